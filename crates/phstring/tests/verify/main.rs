//! Verification of the method against theorems, closed forms and the paper (METHOD §3–4).
//! Issue 2's acceptance list, one module each.

mod common;
mod elimination;
mod momentum;
mod order;
mod paper;
mod quotient;
mod solvers;
