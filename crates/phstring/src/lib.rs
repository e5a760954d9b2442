//! # phstring — port-Hamiltonian strings with exact energy behaviour
//!
//! Structure-preserving simulation of geometrically exact strings and cables (no bending
//! stiffness) in 1D, 2D and 3D, after Kinon, Thoma, Betsch and Kotyczka, "Port-Hamiltonian
//! formulation and structure-preserving discretization of hyperelastic strings". The
//! numerics follow `docs/method.md` in the repository, section by section:
//!
//! * **Model** (§2–§3): state `(r, v, C)` with strain `C = r'·r'`, stored energy `W(C)`
//!   ([`material`]), stress `S = 2W'(C)`, Hamiltonian `H = ∫ ½ρA v·v + W(C) − r·b ds`.
//!   Boundary ports: force in / velocity out at loaded nodes, velocity in / reaction force
//!   out at fixed nodes ([`boundary`]).
//! * **Space** (§4): mixed finite elements — linear `r`, `v` per node, constant `C`, `S` per
//!   element; consistent mass matrix ([`system`]).
//! * **Time** (§5–§11): the energy-consistent discrete-gradient scheme (Greenspan quotient,
//!   evaluated without cancellation) and the implicit midpoint rule ([`integrator`]), solved
//!   by Newton's method on the positions alone ([`newton`]) with an O(N) block-tridiagonal
//!   or a sparse LU linear solve ([`linsolve`]).
//! * **Water** (§21, [`water`]): buoyancy and seabed contact as potentials, Morison drag in a
//!   current, seabed damping and friction, added mass; the balance stays exact with each
//!   mechanism's share reported.
//!
//! What it is for: simulations whose energy balance `Ĥ_{n+1} − Ĥ_n = h û·ŷ` must hold to
//! round-off, ports for coupling and control. What it is not for: bending, torsion,
//! contact between lines (not modelled).
//!
//! ## Conventions
//! * SI units: m, s, kg, N, J. `EA` [N], `ρA` [kg/m], body force `b` [N/m] per unit
//!   reference length, nodal forces [N].
//! * Dimension `D ∈ {1, 2, 3}` is a const generic; nodal vectors are `SVector<f64, D>`.
//! * Degrees of freedom are ordered node by node, components `x, y, z` within a node.
//! * Element `e = [a, b]` runs from node `a` (at smaller `s`) to node `b`;
//!   `r'_e = (r_b − r_a)/l_e`. The internal force `K(r)S` adds `−S_e r'_e` to node `a` and
//!   `+S_e r'_e` to node `b`; it enters the momentum balance with a minus sign.
//! * Port power `û·ŷ` is positive when energy flows into the string.
//! * Times: step `n` goes from `t_n = n h` to `t_{n+1}`; loads are evaluated at
//!   `t_{n+½}`.
//!
//! ## Example: the paper's string pendulum (docs/method.md §12)
//! ```
//! use phstring::{Boundary, Fixed, MassMatrix, Material, Mesh, NodalLoad, Problem,
//!                Scheme, Simulation, State, StepParams, Vector};
//! use std::f64::consts::{FRAC_1_SQRT_2, PI};
//!
//! let n_el = 30;
//! let mesh = Mesh::uniform_chain(n_el, 1.0)?;                       // L = 1 m
//! let end = Vector::<2>::new(FRAC_1_SQRT_2, -FRAC_1_SQRT_2);
//! let initial = State::straight(&mesh, Vector::zeros(), end);        // C₀ = 1, v₀ = 0
//! let load = NodalLoad::new(n_el, |t: f64| {                        // F_N at s = L
//!     let a = if t <= 0.2 { (PI * t / 0.2).sin() } else { 0.0 };
//!     Vector::<2>::new(a, a)                                         // ρA = 1
//! });
//! let problem = Problem {
//!     mesh, initial,
//!     material: Material::hyperelastic(20.0),                        // EA = 20 N
//!     rho_a: 1.0,
//!     body_force: Vector::<2>::new(0.0, -9.81),                      // −g ρA e_y
//!     mass: MassMatrix::Consistent,
//!     boundary: Boundary { fixed: vec![Fixed::node(0)], loads: vec![load], motions: vec![], feedback: vec![] },
//!     point_masses: vec![],                                          // none here
//! };
//! let params = StepParams { h: 0.01, scheme: Scheme::DiscreteGradient, ..Default::default() };
//! let mut sim = Simulation::new(problem, params)?;
//! assert!((sim.energies().hamiltonian() - (-3.468359)).abs() < 1e-6);
//! sim.run_until(1.0, &mut ())?;
//! assert!((sim.energies().hamiltonian() - (-3.403762)).abs() < 1e-6);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod accuracy;
pub mod assembly;
pub mod bathymetry;
pub mod benchmarks;
pub mod body;
pub mod body_feedback;
mod body_step;
pub mod boundary;
pub mod catenary;
pub mod dimension;
pub mod eigen;
pub mod error;
pub mod inputs;
pub mod integrator;
pub mod linear;
pub mod linsolve;
pub mod material;
pub mod mesh;
pub mod modes;
pub mod network;
pub mod newton;
pub mod observe;
pub mod signal;
pub mod simulation;
pub mod statics;
pub mod system;
#[cfg(any(test, feature = "testing"))]
pub mod testing;
pub mod water;
pub mod winch;
mod winch_cut;
mod winch_step;

pub use bathymetry::Bathymetry;
pub use body::{
    Attachment, BodyHydro, BodyMotion, BodyPortSample, BodyState, BodyWrench, Mat6, RigidBody,
    added_mass_about_centre, check_added_mass,
};
pub use body_feedback::{BodyFeedback, FeedbackTarget};
pub use boundary::{
    Boundary, FeedbackLoad, Fixed, ForceFn, Motion, NodalLoad, PathFn, PdLaw, PortKind, PortLaw,
    PortSample, PositionFn, PositionRamp, RateFn,
};
pub use dimension::ByDim;
pub use error::{LinearSolveError, Num, SetupError, StepError};
pub use inputs::InputError;
pub use integrator::Scheme;
pub use linsolve::{BlockJacobian, LinearSolver, SolverKind};
pub use material::{
    Hyperelastic, LinearElastic, LinearSpring, Material, StVenantKirchhoff, StoredEnergy,
};
pub use mesh::Mesh;
pub use network::{NetworkBuilder, StringSpec};
pub use newton::{NewtonParams, NewtonStats};
pub use observe::{
    Observer, RunSummary, Settle, SettleWatch, Settled, StepReport, fastest_node, nan_max,
};
pub use signal::{PlatformPath, PlatformState, SampleError, Sampled};
pub use simulation::{
    Checkpoint, CheckpointFit, FlatCheckpoint, Predictor, Simulation, StepControl, StepParams,
    WinchSample, estimated_memory_bytes, estimated_seconds_per_iteration,
    estimated_seconds_per_step,
};
pub use system::{
    Damping, ElementGroup, Energies, Law, MassMatrix, Network, PhSystem, PointMass, Problem, State,
    Vector,
};
pub use water::{
    AxialFriction, Current, Friction, Hydrodynamics, LineHydro, NodeContact, PointHydro, Seabed,
    SeabedSurface, Water, WaterWork,
};
pub use winch::{DrumFn, DrumForceFn, PayoutFn, Winch, WinchDrum, WinchState};
