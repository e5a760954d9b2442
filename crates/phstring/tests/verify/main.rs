//! Verification of the method against theorems, closed forms and the paper (docs/method.md §13).
//! Issue 2's acceptance list, one module each.

mod common;
mod elimination;
mod momentum;
mod modes;
mod motion;
mod network;
mod order;
mod paper;
mod point_mass;
mod quotient;
mod reduction;
mod real_units;
mod solvers;
mod statics;
