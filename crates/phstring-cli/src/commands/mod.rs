//! The `phstring` commands, one module each with its arguments and the function that runs
//! it, and [`common`], what several of them share.

pub mod check;
pub mod common;
pub mod fmu;
pub mod linearize;
pub mod modes;
pub mod mooring;
pub mod paper;
pub mod run;
pub mod statics;
pub mod sweep;
