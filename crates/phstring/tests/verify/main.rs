//! Verification of the method against theorems, closed forms and the paper (docs/method.md §13).
//! One module per property or part of the model.

mod accuracy;
mod bathymetry;
mod bodies;
mod bodies_statics;
mod body_feedback;
mod common;
mod damping;
mod elimination;
mod friction;
mod modes;
mod momentum;
mod motion;
mod network;
mod order;
mod paper;
mod point_mass;
mod quotient;
mod real_units;
mod reduction;
mod solvers;
mod statics;
mod water;
mod winch;
mod winch_body;
mod winch_checks;
mod winch_dg4;
mod winch_drum;
