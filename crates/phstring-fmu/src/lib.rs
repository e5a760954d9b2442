//! FMI 2.0 and 3.0 Co-Simulation export of phstring scenarios (docs/method.md §20).
//!
//! `phstring fmu SCENARIO -o NAME.fmu` packages a scenario with this crate's shared library:
//! [`model::ModelSpec`] lists the FMU's variables (port inputs and outputs, energies, node
//! positions, the parameters `EA`, `ρA`, `h`) and writes `modelDescription.xml`;
//! [`package::write_fmu`] writes the archive; the C functions of FMI 2.0 (`ffi`) and FMI 3.0
//! (`ffi3`), both in the one shared library, run the same `phstring::Simulation` as
//! `phstring run` on the packaged scenario.

pub mod error;
#[allow(unsafe_code)]
pub mod ffi;
#[allow(unsafe_code)]
pub mod ffi3;
mod handles;
pub mod instance;
pub mod model;
pub mod package;
