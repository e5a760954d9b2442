//! Water and seabed (docs/method.md §21): buoyancy and seabed contact as potentials in `Ĥ`,
//! Morison drag in a current, seabed damping and friction as resistances (the current's work
//! is a port), added mass in `M_ρ`.
//!
//! Conventions (those of the mooring tools, e.g. MoorDyn): the vertical axis is the last
//! component (`y` in 2D, `z` in 3D), the free surface is at height 0, water lies below it,
//! and a flat seabed at depth `h` lies at height `−h`. SI units; the hydrodynamic
//! coefficients mean what they mean in MoorDyn (`Cd` on `d·l`, `CdAx` on `π·d·l`, `Ca` and
//! `CaAx` on the displaced mass `ρ_w π d²/4` per length, `kBot` and `cBot` per unit
//! diameter and length of line in contact). Water needs `D ≥ 2`.
//!
//! ## Example: a chain from an anchor on the seabed to a fairlead, in a current
//! Water is attached to a [`crate::Network`] (the scenario layer's path): the water with its
//! current and seabed, then the hydrodynamics of each line (element group) and point.
//! ```
//! use phstring::{Current, Fixed, Friction, LineHydro, MassMatrix, Material, Mesh, Network,
//!                Boundary, Problem, Seabed, Simulation, State, StepParams, Vector, Water};
//! let (n, depth) = (20, 50.0);
//! let mesh = Mesh::uniform_chain(n, 100.0)?;                       // 100 m of chain
//! let initial = State::straight(&mesh, Vector::<3>::new(0.0, 0.0, -depth),
//!                               Vector::<3>::new(80.0, 0.0, -10.0));
//! let net: Network<3, Material> = Problem {
//!     mesh, initial,
//!     material: Material::linear_elastic(1e9),                       // EA [N]
//!     rho_a: 100.0,                                                  // [kg/m]
//!     body_force: Vector::<3>::new(0.0, 0.0, -100.0 * 9.80665),      // its weight [N/m]
//!     mass: MassMatrix::Lumped,
//!     boundary: Boundary { fixed: vec![Fixed::node(0), Fixed::node(n)], loads: vec![],
//!                          motions: vec![], feedback: vec![] },
//!     point_masses: vec![],
//! }.into();
//! let seabed = Seabed::flat(depth, 3e6, 3e5)                          // kBot, cBot
//!     .with_friction(Friction::new(0.5, 0.5 * 200.0)); // μ, μ·FricDamp
//! let water = Water::new(1025.0)
//!     .with_current(Current::Uniform(Vector::<3>::new(0.5, 0.2, 0.0)))
//!     .with_seabed(seabed);
//! let chain = LineHydro { diameter: 0.1, cd: 2.4, cd_axial: 1.15, ca: 1.0, ca_axial: 0.5 };
//! let net = net.with_water(water).with_line_hydro(0, chain);
//! let mut sim = Simulation::new(net, StepParams { h: 0.01, ..Default::default() })?;
//! for _ in 0..20 {
//!     let report = sim.step()?;
//!     assert!(report.relative_balance_error() <= 1e-12);
//!     assert!(report.water.drag_dissipated >= 0.0);
//! }
//! let e = sim.energies();             // in Ĥ: buoyancy −ρ_w g V Φ(z) > 0 below the surface
//! assert!(e.buoyancy > 0.0 && e.seabed >= 0.0);
//! let grounded = sim.system().grounded_length(0, &sim.state().r);    // [m]
//! assert!(grounded >= 0.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::sync::Arc;

use nalgebra::SMatrix;

use crate::bathymetry::{Bathymetry, height_d, horizontal, widen};
use crate::error::SetupError;
use crate::mesh::Mesh;

/// A nodal vector in `R^D` [m, m/s or N].
type Vector<const D: usize> = nalgebra::SVector<f64, D>;

/// What [`build`] needs to know of an element group.
pub(crate) struct GroupInfo<'a> {
    /// A string (only strings take line hydrodynamics).
    pub is_string: bool,
    pub name: &'a str,
    pub elements: std::ops::Range<usize>,
}

/// Standard gravity [m/s²], the default of [`Water::gravity`].
pub const STANDARD_GRAVITY: f64 = 9.80665;

/// Lorentz's factor `8/(3π)` of the equivalent linear drag: `α |v| v` and `(8/3π) α V v`
/// dissipate the same energy over a cycle of `v = V sin ωt`.
const LORENTZ: f64 = 8.0 / (3.0 * std::f64::consts::PI);

/// Default smoothing speed `δ` [m/s] of the drag laws' `|v|` (see [`Water::drag_smoothing`]).
pub const DEFAULT_DRAG_SMOOTHING: f64 = 1e-3;

/// Default penetration [m] over which the seabed damping ramps up (see
/// [`Seabed::damping_ramp`]).
pub const DEFAULT_DAMPING_RAMP: f64 = 1e-3;

/// The current: the water's velocity `u(z)` [m/s] as a function of the height `z` [m].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Current<const D: usize> {
    /// The same velocity [m/s] at every depth (zero: still water).
    Uniform(Vector<D>),
    /// A depth profile: points `(z [m], u [m/s])` with strictly increasing `z`, linear in
    /// between, constant beyond the first and the last point.
    Profile(Vec<(f64, Vector<D>)>),
}

impl<const D: usize> Current<D> {
    /// Still water.
    pub fn still() -> Self {
        Current::Uniform(Vector::zeros())
    }

    /// The velocity `u(z)` [m/s] and its derivative `du/dz` [1/s] at height `z` [m].
    #[inline]
    pub fn at(&self, z: f64) -> (Vector<D>, Vector<D>) {
        match self {
            Current::Uniform(u) => (*u, Vector::zeros()),
            Current::Profile(p) => profile_at(p, z),
        }
    }

    fn is_still(&self) -> bool {
        match self {
            Current::Uniform(u) => u.iter().all(|&x| x == 0.0),
            Current::Profile(p) => p.iter().all(|(_, u)| u.iter().all(|&x| x == 0.0)),
        }
    }
}

/// Linear interpolation in a profile, constant beyond its ends.
fn profile_at<const D: usize>(p: &[(f64, Vector<D>)], z: f64) -> (Vector<D>, Vector<D>) {
    let zero = Vector::zeros();
    let (Some(first), Some(last)) = (p.first(), p.last()) else {
        return (zero, zero);
    };
    if z <= first.0 {
        return (first.1, zero);
    }
    if z >= last.0 {
        return (last.1, zero);
    }
    let k = p.partition_point(|(zk, _)| *zk <= z).clamp(1, p.len() - 1);
    let ((z0, u0), (z1, u1)) = (p[k - 1], p[k]);
    let slope = (u1 - u0) / (z1 - z0);
    (u0 + slope * (z - z0), slope)
}

/// The seabed's surface.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum SeabedSurface<const D: usize> {
    /// Flat and horizontal at height `−depth` [m] (`depth > 0`).
    Flat {
        /// Water depth [m].
        depth: f64,
    },
    /// A plane through `point` [m] with the upward normal `normal` (any length > 0; it is
    /// normalized, and must point upwards: its vertical component > 0).
    Plane {
        /// A point of the plane [m].
        point: Vector<D>,
        /// Normal pointing into the water.
        normal: Vector<D>,
    },
    /// A bathymetry grid: the seabed at height `−depth(x, y)` (a profile `−depth(x)` in 2D),
    /// C¹ between the grid points and continued along its edge tangent beyond them; the
    /// gap is measured along the vertical (docs/method.md §21).
    Grid(Arc<Bathymetry>),
}

/// Regularized Coulomb friction on the seabed (docs/method.md §21, (21.5) and (21.5a)): a
/// resistance against the node's slip `v_t` in the seabed plane, `N` the node's contact
/// force. Isotropic by default: `f = −μ N c_f v_t / √((μ N)² + (c_f |v_t|)²)`, a damper of
/// slope `c_f` at small slip that tends to `μ N` against the slip at large slip. With
/// [`Self::axial`] the slip splits into its part along the line's axis and the part across
/// it, each with its own law (MoorDyn-F's axial and transverse friction); with
/// [`Self::static_scale`] `s ≠ 1` each law's coefficient rises from `μ` at large slip to
/// `s·μ` at small slip (a static peak).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Friction {
    /// Friction coefficient `μ` (MoorDyn's `FrictionCoefficient` or `mu_kT`, the kinetic
    /// one) [–], ≥ 0: isotropic, or across the line's axis when [`Self::axial`] is set.
    pub coefficient: f64,
    /// Slope `c_f` of the friction force at zero slip [N·s/m] per node, > 0. MoorDyn's
    /// low-speed friction is `μ FricDamp |v_t|`: from a MoorDyn deck, `slope = μ · FricDamp`.
    pub slope: f64,
    /// Friction along the line's axis, if it differs from the transverse one (`None`: the
    /// isotropic law with [`Self::coefficient`] and [`Self::slope`]).
    pub axial: Option<AxialFriction>,
    /// Static over kinetic friction `s = μ_s/μ_k` [–], > 0 (MoorDyn's `StatDynFricScale`);
    /// 1 (the default): no static peak.
    pub static_scale: f64,
}

/// Seabed friction along a line's axis (docs/method.md §21 (21.5a)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxialFriction {
    /// Axial kinetic friction coefficient `μ_a` [–], ≥ 0 (MoorDyn-F's `mu_kA`).
    pub coefficient: f64,
    /// Slope `c_a` of the axial friction force at zero slip [N·s/m] per node, > 0 (from a
    /// MoorDyn deck `μ_a · FricDamp`).
    pub slope: f64,
}

impl Friction {
    /// Isotropic friction of coefficient `μ` [–] and zero-slip slope `c_f` [N·s/m] per node,
    /// without a static peak.
    pub fn new(coefficient: f64, slope: f64) -> Self {
        Self {
            coefficient,
            slope,
            axial: None,
            static_scale: 1.0,
        }
    }
    /// The same friction with the axial coefficient `μ_a` [–] and slope `c_a` [N·s/m] along
    /// the line's axis (the other fields then act across it).
    pub fn with_axial(mut self, coefficient: f64, slope: f64) -> Self {
        self.axial = Some(AxialFriction { coefficient, slope });
        self
    }
    /// The same friction with the static peak `s = μ_s/μ_k` [–].
    pub fn with_static_scale(mut self, scale: f64) -> Self {
        self.static_scale = scale;
        self
    }
}

/// A seabed: a penalty contact of stiffness `k·d` per unit length of line, damping of the
/// normal velocity while in contact, and optionally friction.
#[derive(Debug, Clone, PartialEq)]
pub struct Seabed<const D: usize> {
    /// Where the seabed is.
    pub surface: SeabedSurface<D>,
    /// Contact stiffness `k` [Pa/m] (MoorDyn's `kBot`): the force per unit length of a line
    /// of diameter `d` pressed `p` into the seabed is `k d p`.
    pub stiffness: f64,
    /// Contact damping `c` [Pa·s/m] (MoorDyn's `cBot`): the force per unit length is
    /// `−c d v_n` on the normal velocity `v_n` while in contact (ramped, see
    /// [`Self::damping_ramp`]).
    pub damping: f64,
    /// Penetration [m] over which the damping ramps from 0 to full (a C¹ ramp in the deeper
    /// of a step's two end penetrations, so that the damping force is continuous where
    /// contact starts and monotone in the step's increment), > 0.
    pub damping_ramp: f64,
    /// Friction, none by default.
    pub friction: Option<Friction>,
}

impl<const D: usize> Seabed<D> {
    /// A flat seabed at depth `depth` [m] with stiffness `k` [Pa/m] and damping `c` [Pa·s/m],
    /// frictionless, the damping ramp at its default.
    pub fn flat(depth: f64, stiffness: f64, damping: f64) -> Self {
        Self {
            surface: SeabedSurface::Flat { depth },
            stiffness,
            damping,
            damping_ramp: DEFAULT_DAMPING_RAMP,
            friction: None,
        }
    }
    /// A plane seabed through `point` [m] with the upward normal `normal` (normalized), with
    /// stiffness `k` [Pa/m] and damping `c` [Pa·s/m], frictionless, the damping ramp at its
    /// default.
    pub fn plane(point: Vector<D>, normal: Vector<D>, stiffness: f64, damping: f64) -> Self {
        Self {
            surface: SeabedSurface::Plane { point, normal },
            ..Self::flat(1.0, stiffness, damping)
        }
    }
    /// A seabed on the bathymetry grid `grid` (a profile in 2D, a grid in 3D) with
    /// stiffness `k` [Pa/m] and damping `c` [Pa·s/m], frictionless, the damping ramp at its
    /// default.
    pub fn grid(grid: Bathymetry, stiffness: f64, damping: f64) -> Self {
        Self {
            surface: SeabedSurface::Grid(Arc::new(grid)),
            ..Self::flat(1.0, stiffness, damping)
        }
    }
    /// The same seabed with `friction`.
    pub fn with_friction(mut self, friction: Friction) -> Self {
        self.friction = Some(friction);
        self
    }
}

/// Water: density, gravity (for buoyancy), current and seabed. The surface is at height 0.
#[derive(Debug, Clone, PartialEq)]
pub struct Water<const D: usize> {
    /// Density `ρ_w` [kg/m³] (sea water ≈ 1025), > 0.
    pub density: f64,
    /// Gravity `g` [m/s²] of the buoyancy `ρ_w g V`, acting along the vertical axis, > 0.
    /// (The lines' own weight is their body force, set separately.)
    pub gravity: f64,
    /// The current.
    pub current: Current<D>,
    /// The seabed, if any.
    pub seabed: Option<Seabed<D>>,
    /// Smoothing speed `δ` [m/s] of the quadratic drag laws: `|v|` is taken as
    /// `√(|v|² + δ²)`, so that the drag's Jacobian is defined at zero relative speed; > 0.
    pub drag_smoothing: f64,
    /// Velocity amplitude `V` [m/s] of the equivalent linear drag in the linear model
    /// (`linear::damping_blocks`): the quadratic drag `α |v| v` of a harmonic motion of
    /// velocity amplitude `V` dissipates per cycle what the linear drag `(8/3π) α V v` does,
    /// and that damping is added to the drag's derivative at rest. 0 (the default): only the
    /// derivative, which in still water is the negligible `α δ`. ≥ 0. The time step does not
    /// use it.
    pub linear_drag_amplitude: f64,
}

impl<const D: usize> Water<D> {
    /// Still water of density `density` [kg/m³], standard gravity, no seabed.
    pub fn new(density: f64) -> Self {
        Self {
            density,
            gravity: STANDARD_GRAVITY,
            current: Current::still(),
            seabed: None,
            drag_smoothing: DEFAULT_DRAG_SMOOTHING,
            linear_drag_amplitude: 0.0,
        }
    }
    /// The same water with `current`.
    pub fn with_current(mut self, current: Current<D>) -> Self {
        self.current = current;
        self
    }
    /// The same water with `seabed`.
    pub fn with_seabed(mut self, seabed: Seabed<D>) -> Self {
        self.seabed = Some(seabed);
        self
    }
    /// The same water with gravity `g` [m/s²].
    pub fn with_gravity(mut self, g: f64) -> Self {
        self.gravity = g;
        self
    }
}

/// Hydrodynamic parameters of a line (an element group), as in MoorDyn.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LineHydro {
    /// Volume-equivalent diameter `d` [m] (> 0): displaced volume `π d²/4` per unit length,
    /// drag areas, contact width.
    pub diameter: f64,
    /// Transverse drag coefficient `Cd` [–] on the area `d·l`.
    pub cd: f64,
    /// Axial drag coefficient `CdAx` [–] on the area `π·d·l`.
    pub cd_axial: f64,
    /// Transverse added-mass coefficient `Ca` [–].
    pub ca: f64,
    /// Axial added-mass coefficient `CaAx` [–] (see docs/method.md §21: the added mass is
    /// taken isotropic with `Ca`; the axial excess is reported).
    pub ca_axial: f64,
}

/// Hydrodynamic parameters of a point (a point mass, a buoy, a junction), as in MoorDyn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointHydro {
    /// Node index.
    pub node: usize,
    /// Displaced volume [m³] (buoyancy `ρ_w g V`), ≥ 0.
    pub volume: f64,
    /// Drag area times drag coefficient `CdA` [m²]: the drag `½ ρ_w CdA |v_r| v_r`, ≥ 0.
    pub cda: f64,
    /// Added-mass coefficient `Ca` [–] on the displaced mass `ρ_w V`, ≥ 0.
    pub ca: f64,
}

/// The hydrodynamic parameters of a network's lines and points.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Hydrodynamics {
    /// `(group index, parameters)`: lines without an entry feel no water.
    pub lines: Vec<(usize, LineHydro)>,
    /// Points with buoyancy, drag or added mass.
    pub points: Vec<PointHydro>,
}

impl Hydrodynamics {
    /// No hydrodynamic parameters.
    pub fn is_empty(&self) -> bool {
        self.lines.is_empty() && self.points.is_empty()
    }
}

// ---------------------------------------------------------------------------------------
// One-dimensional laws and their discrete gradients.

/// Submerged fraction `φ(z)` of a node of band `b` [m] at height `z` [m]: 1 below `−b/2`,
/// 0 above `b/2`, `1 − S(t)` in between with `S(t) = t²(3 − 2t)`, `t = (z + b/2)/b` (C¹).
pub fn submerged_fraction(z: f64, b: f64) -> f64 {
    1.0 - emerged(z, b).0
}

/// `(S, dS/dz)`: the emerged fraction `1 − φ` and its derivative [1/m].
fn emerged(z: f64, b: f64) -> (f64, f64) {
    let half = 0.5 * b;
    if z <= -half {
        (0.0, 0.0)
    } else if z >= half {
        (1.0, 0.0)
    } else {
        let t = (z + half) / b;
        (t * t * (3.0 - 2.0 * t), 6.0 * t * (1.0 - t) / b)
    }
}

/// `A(z) = ∫_{−∞}^{z} (1 − φ)`: 0 below the band, `z` above it, `b (t³ − t⁴/2)` inside [m].
fn a_int(z: f64, b: f64) -> f64 {
    let half = 0.5 * b;
    if z <= -half {
        0.0
    } else if z >= half {
        z
    } else {
        let t = (z + half) / b;
        b * t * t * t * (1.0 - 0.5 * t)
    }
}

/// The buoyancy potential per unit `ρ_w g V` [m]: `Φ(z) = ∫_0^z φ = z − A(z) + A(0)`,
/// `A(0) = 3b/32`, so that `U = −ρ_w g V Φ(z)`; `Φ = z + 3b/32` fully submerged.
pub fn buoyancy_height(z: f64, b: f64) -> f64 {
    z - a_int(z, b) + 3.0 * b / 32.0
}

/// Divided difference of `A` over the band's piece `[ta, tb]` in `t`: exact, no cancellation.
fn band_quotient(ta: f64, tb: f64) -> f64 {
    (ta * ta + ta * tb + tb * tb) - 0.5 * (ta + tb) * (ta * ta + tb * tb)
}

/// `(q, ∂q/∂z₁)`: the divided difference `(A(z₁) − A(z₀))/(z₁ − z₀)` (the emerged fraction
/// averaged over the step), split at the band's edges into a convex combination of the
/// pieces' closed-form quotients (no cancellation, no switch); `S(z)` at `z₀ = z₁`.
pub(crate) fn emerged_quotient(z0: f64, z1: f64, b: f64) -> (f64, f64) {
    let half = 0.5 * b;
    let (lo, hi) = if z0 <= z1 { (z0, z1) } else { (z1, z0) };
    if hi <= -half {
        // Submerged over the whole step (the common case).
        return (0.0, 0.0);
    }
    let t = |z: f64| ((z + half) / b).clamp(0.0, 1.0);
    // Pieces: below (quotient 0), band, above (quotient 1).
    let below = if lo < -half { hi.min(-half) - lo } else { 0.0 };
    let (bl, bh) = (lo.max(-half), hi.min(half));
    let band = if bh > bl { bh - bl } else { 0.0 };
    let above = if hi > half { hi - lo.max(half) } else { 0.0 };
    let total = below + band + above;
    let single_band = lo > -half && hi < half;
    let q = if total > 0.0 {
        let qb = if band > 0.0 {
            band_quotient(t(bl), t(bh))
        } else {
            0.0
        };
        (band * qb + above) / total
    } else {
        emerged(z0, b).0
    };
    let dq = if single_band {
        let (t0, t1) = (t(z0), t(z1));
        ((2.0 * t1 + t0) - 0.5 * (t1 * t1 + t0 * t0) - (t1 + t0) * t1) / b
    } else if lo <= -half && hi <= -half || lo >= half && hi >= half {
        0.0
    } else if (z1 - z0).abs() > 1e-8 * b {
        (emerged(z1, b).0 - q) / (z1 - z0)
    } else {
        0.5 * emerged(z1, b).1
    };
    (q, dq)
}

/// `(q, ∂q/∂g₁)`: the exact divided difference of `V(g) = ½ k max(0, −g)²` [N] between the
/// gaps `g₀`, `g₁` [m], for a stiffness `k` [N/m]; `V'(g)` at `g₀ = g₁`.
pub(crate) fn contact_quotient(g0: f64, g1: f64, k: f64) -> (f64, f64) {
    match (g0 < 0.0, g1 < 0.0) {
        (false, false) => (0.0, 0.0),
        (true, true) => (0.5 * k * (g0 + g1), 0.5 * k),
        // V₁ − V₀ = −½ k g₀², g₁ − g₀ ≥ −g₀ > 0: the sum of two magnitudes.
        (true, false) => {
            let d = g1 - g0;
            (-0.5 * k * g0 * (g0 / d), 0.5 * k * (g0 / d) * (g0 / d))
        }
        (false, true) => {
            let d = g1 - g0;
            (
                0.5 * k * g1 * (g1 / d),
                0.5 * k * (g1 / d) * ((g1 - 2.0 * g0) / d),
            )
        }
    }
}

/// The contact potential `½ k max(0, −g)²` [J] of a gap `g` [m].
fn contact_energy(g: f64, k: f64) -> f64 {
    if g < 0.0 { 0.5 * k * g * g } else { 0.0 }
}

/// `(ρ, dρ/dp)`: the C¹ ramp `x²(3 − 2x)`, `x = p/δ` clamped to [0, 1], of the seabed damping.
fn ramp(p: f64, delta: f64) -> (f64, f64) {
    if p <= 0.0 {
        (0.0, 0.0)
    } else if p >= delta {
        (1.0, 0.0)
    } else {
        let inv = 1.0 / delta;
        let x = p * inv;
        (x * x * (3.0 - 2.0 * x), 6.0 * x * (1.0 - x) * inv)
    }
}

/// `(ρ, ∂ρ/∂g₁)` of the seabed damping's [`ramp`] over `delta` [m] at the deeper end's
/// penetration `max(−g₀, −g₁)` of a step with gaps `g₀`, `g₁` [m] (docs/method.md §21): its
/// force is then monotone in the step's normal increment.
fn deeper_ramp(g0: f64, g1: f64, delta: f64) -> (f64, f64) {
    if g1 < g0 {
        let (rho, drho) = ramp(-g1, delta);
        (rho, -drho)
    } else {
        (ramp(-g0, delta).0, 0.0)
    }
}

// ---------------------------------------------------------------------------------------
// The validated model the step evaluates.

/// The seabed as the step sees it: the plane `n·(r − p) = 0` with unit normal `n`, or, with
/// `grid`, the height field `z = b(x)` of a bathymetry grid (then `n` and `p` are unused).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Bed<const D: usize> {
    pub n: Vector<D>,
    pub p: Vector<D>,
    pub grid: Option<Arc<Bathymetry>>,
    pub ramp: f64,
    pub friction: Option<Friction>,
}

impl<const D: usize> Bed<D> {
    /// The signed gap [m] (negative: penetration): `n·(r − p)` for a plane, `z − b(x)` (along
    /// the vertical) for a grid.
    #[inline]
    pub fn gap(&self, r: &Vector<D>) -> f64 {
        match &self.grid {
            None => self.n.dot(&(r - self.p)),
            Some(g) => r[D - 1] - height_d::<D>(g, r).0,
        }
    }

    /// `∇g` at `r` (the plane's `n`; `e_z − ∇b` for a grid) and, for a grid, `∇²g = −∇²b`.
    #[inline]
    pub fn gap_gradient(&self, r: &Vector<D>) -> (Vector<D>, Option<Block<D>>) {
        match &self.grid {
            None => (self.n, None),
            Some(g) => {
                let (_, gb, hb) = height_d::<D>(g, r);
                (up::<D>() - gb, Some(-hb))
            }
        }
    }

    /// The exact discrete gradient `∇̄g` of the gap from `r0` to `r1` (`∇̄g·(r1 − r0) =
    /// g(r1) − g(r0)`) and, for a grid, its derivative by `r1` (docs/method.md §21).
    #[inline]
    pub fn gap_quotient(&self, r0: &Vector<D>, r1: &Vector<D>) -> (Vector<D>, Option<Block<D>>) {
        match &self.grid {
            None => (self.n, None),
            Some(g) => {
                let (gb, jb) = g.mean_gradient(horizontal(r0), horizontal(r1));
                let (gb, jb) = widen::<D>(gb, jb);
                (up::<D>() - gb, Some(-jb))
            }
        }
    }

    /// The unit upward normal at `r` and, for a grid, its derivative by `r`.
    #[inline]
    pub fn normal_at(&self, r: &Vector<D>) -> (Vector<D>, Option<Block<D>>) {
        match self.gap_gradient(r) {
            (n, None) => (n, None),
            (grad, Some(hess)) => {
                let len = grad.norm();
                let n = grad / len;
                let dn = (Block::<D>::identity() - n * n.transpose()) * hess / len;
                (n, Some(dn))
            }
        }
    }

    /// Whether the seabed is the level plane `z = p_z` (normal `e_z`, no grid) with isotropic
    /// friction or none, where the step's contact terms are formed by component.
    #[inline]
    pub fn is_level(&self) -> bool {
        self.grid.is_none()
            && self.n == up::<D>()
            && self.friction.is_none_or(|f| f.axial.is_none())
    }

    /// Whether the seabed holds a line along axis `k` (the vertical, or an axis along which
    /// the seabed slopes).
    pub fn holds(&self, k: usize) -> bool {
        match &self.grid {
            None => self.n[k] != 0.0,
            Some(g) => k == D - 1 || g.slopes_along(k),
        }
    }
}

/// The unit vector up the vertical axis.
fn up<const D: usize>() -> Vector<D> {
    let mut e = Vector::<D>::zeros();
    e[D - 1] = 1.0;
    e
}

/// A node that water acts on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct WetNode {
    pub node: usize,
    /// `ρ_w g V` [N]: the buoyancy fully submerged.
    pub buoyancy: f64,
    /// Surface band [m] (the largest diameter at the node).
    pub band: f64,
    /// Contact stiffness `k d L` [N/m] and damping `c d L` [N·s/m] (`d L = Σ ½ l_e d_e`).
    pub stiffness: f64,
    pub damping: f64,
    /// Point drag `½ ρ_w CdA` [kg/m].
    pub drag: f64,
    /// The nodes whose chord at the step's start is the node's axis for axial friction:
    /// its neighbours along its line (itself at a line's end); `(node, node)` off a line.
    pub axis: (usize, usize),
}

/// An element that drag acts on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct WetElement {
    pub e: usize,
    /// `½ ρ_w Cd d l` [kg/m] and `½ ρ_w CdAx π d l` [kg/m].
    pub normal: f64,
    pub axial: f64,
    /// Surface band [m] (the diameter).
    pub band: f64,
    /// Added mass the isotropic model gives to axial motion beyond `CaAx`,
    /// `ρ_w π d²/4 (Ca − CaAx) l` [kg].
    pub axial_excess: f64,
}

/// Water, seabed and the lines' and points' hydrodynamics, validated and lumped to nodes and
/// elements.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct WaterModel<const D: usize> {
    pub rho: f64,
    pub current: Current<D>,
    pub still: bool,
    pub delta: f64,
    /// [`Water::linear_drag_amplitude`] [m/s].
    pub amplitude: f64,
    pub bed: Option<Bed<D>>,
    /// Sorted by node.
    pub nodes: Vec<WetNode>,
    /// Sorted by element.
    pub elements: Vec<WetElement>,
}

/// What the water does in a step [J]; each share is reported separately.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct WaterWork {
    /// Energy dissipated by drag relative to the water, `−h f·v_r ≥ 0`.
    pub drag_dissipated: f64,
    /// Work of the current through the drag, `h f·u` (either sign): a port.
    pub current_supplied: f64,
    /// Energy dissipated by the seabed's damping, ≥ 0.
    pub seabed_dissipated: f64,
    /// Energy dissipated by seabed friction, ≥ 0.
    pub friction_dissipated: f64,
}

impl WaterWork {
    /// Whether every share is zero (a run without water).
    pub fn is_zero(&self) -> bool {
        *self == Self::default()
    }
    /// Everything dissipated [J].
    pub fn dissipated(&self) -> f64 {
        self.drag_dissipated + self.seabed_dissipated + self.friction_dissipated
    }
    /// The sum of the magnitudes of the shares [J] (the energy scale of their rounding).
    pub fn magnitude(&self) -> f64 {
        self.drag_dissipated.abs()
            + self.current_supplied.abs()
            + self.seabed_dissipated.abs()
            + self.friction_dissipated.abs()
    }
    /// Adds `other` share by share.
    pub fn add(&mut self, other: &WaterWork) {
        self.drag_dissipated += other.drag_dissipated;
        self.current_supplied += other.current_supplied;
        self.seabed_dissipated += other.seabed_dissipated;
        self.friction_dissipated += other.friction_dissipated;
    }
}

/// Contact state of a node on the seabed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeContact {
    /// Node index.
    pub node: usize,
    /// The node is below the seabed's surface (penetration > 0).
    pub grounded: bool,
    /// Penetration [m] (≥ 0): normal to a plane, along the vertical into a grid's seabed.
    pub penetration: f64,
    /// Contact force [N] on the node, along the seabed's normal (`k d L p`; on a grid
    /// `k d L p |∇g|`, `|∇g| = √(1 + |∇b|²)`).
    pub force: f64,
}

/// The seabed contact of wet node `w` (of nonzero stiffness) at positions `r` [m].
fn node_contact<const D: usize>(bed: &Bed<D>, w: &WetNode, r: &[Vector<D>]) -> NodeContact {
    let p = (-bed.gap(&r[w.node])).max(0.0);
    // |∇g| = 1 on a plane; on a grid the vertical gap's gradient is longer.
    let stretch = match &bed.grid {
        None => 1.0,
        Some(_) if p > 0.0 => bed.gap_gradient(&r[w.node]).0.norm(),
        Some(_) => 1.0,
    };
    NodeContact {
        node: w.node,
        grounded: p > 0.0,
        penetration: p,
        force: w.stiffness * p * stretch,
    }
}

/// Checks `value` against `0 ≤ value < ∞` (or `> 0` with `positive`).
fn check_value(
    what: &'static str,
    index: Option<usize>,
    value: f64,
    positive: bool,
) -> Result<(), SetupError> {
    let ok = value.is_finite() && if positive { value > 0.0 } else { value >= 0.0 };
    if ok {
        Ok(())
    } else {
        Err(SetupError::WaterParameter {
            what,
            index,
            value,
            range: if positive {
                "0 < value < infinity"
            } else {
                "0 <= value < infinity"
            },
        })
    }
}

fn check_vector<const D: usize>(
    what: &'static str,
    index: Option<usize>,
    v: &Vector<D>,
) -> Result<(), SetupError> {
    match v.iter().find(|x| !x.is_finite()) {
        Some(&value) => Err(SetupError::WaterParameter {
            what,
            index,
            value,
            range: "finite",
        }),
        None => Ok(()),
    }
}

/// Checks the water's own parameters and returns its seabed as a plane.
fn check_water<const D: usize>(w: &Water<D>) -> Result<Option<Bed<D>>, SetupError> {
    check_value("water density [kg/m^3]", None, w.density, true)?;
    check_value("gravity [m/s^2]", None, w.gravity, true)?;
    check_value("drag smoothing speed [m/s]", None, w.drag_smoothing, true)?;
    check_value(
        "equivalent linear drag amplitude [m/s]",
        None,
        w.linear_drag_amplitude,
        false,
    )?;
    match &w.current {
        Current::Uniform(u) => check_vector("current velocity [m/s]", None, u)?,
        Current::Profile(p) => {
            for (k, (z, u)) in p.iter().enumerate() {
                check_vector("current velocity [m/s] of profile point", Some(k), u)?;
                let prev = if k > 0 { p[k - 1].0 } else { f64::NEG_INFINITY };
                if !(z.is_finite() && *z > prev) {
                    return Err(SetupError::WaterParameter {
                        what: "current profile height [m] of point",
                        index: Some(k),
                        value: *z,
                        range: "finite and above the previous point's",
                    });
                }
            }
        }
    }
    let Some(sb) = &w.seabed else {
        return Ok(None);
    };
    check_value("seabed stiffness kBot [Pa/m]", None, sb.stiffness, false)?;
    check_value("seabed damping cBot [Pa s/m]", None, sb.damping, false)?;
    check_value("seabed damping ramp [m]", None, sb.damping_ramp, true)?;
    if let Some(f) = &sb.friction {
        check_value("seabed friction coefficient", None, f.coefficient, false)?;
        check_value(
            "seabed friction slope (mu FricDamp) [N s/m]",
            None,
            f.slope,
            true,
        )?;
        if let Some(ax) = &f.axial {
            check_value(
                "seabed axial friction coefficient",
                None,
                ax.coefficient,
                false,
            )?;
            check_value(
                "seabed axial friction slope (mu_a FricDamp) [N s/m]",
                None,
                ax.slope,
                true,
            )?;
        }
        check_value(
            "seabed static friction scale (mu_s/mu_k)",
            None,
            f.static_scale,
            true,
        )?;
    }
    let up = up::<D>();
    let mut grid = None;
    let (n, p) = match &sb.surface {
        &SeabedSurface::Flat { depth } => {
            check_value("water depth [m]", None, depth, true)?;
            (up, -up * depth)
        }
        SeabedSurface::Grid(g) => {
            if g.is_profile() != (D == 2) {
                return Err(SetupError::WaterParameter {
                    what: "number of horizontal axes of the bathymetry grid",
                    index: None,
                    value: if g.is_profile() { 1.0 } else { 2.0 },
                    range: "the dimension's: a profile along x in 2D, a grid over x and y in 3D",
                });
            }
            grid = Some(Arc::clone(g));
            (up, Vector::zeros())
        }
        &SeabedSurface::Plane { point, normal } => {
            check_vector("seabed plane point [m]", None, &point)?;
            check_vector("seabed plane normal", None, &normal)?;
            let len = normal.norm();
            if !(len > 0.0 && len.is_finite() && normal[D - 1] > 0.0) {
                return Err(SetupError::WaterParameter {
                    what: "vertical component of the seabed plane's normal",
                    index: None,
                    value: normal[D - 1],
                    range: "> 0 (the normal points up, into the water)",
                });
            }
            (normal / len, point)
        }
    };
    Ok(Some(Bed {
        n,
        p,
        grid,
        ramp: sb.damping_ramp,
        friction: sb.friction,
    }))
}

/// Checks a line's parameters (`group` for messages).
fn check_line(group: usize, h: &LineHydro) -> Result<(), SetupError> {
    check_value("line diameter [m] of group", Some(group), h.diameter, true)?;
    check_value("line Cd of group", Some(group), h.cd, false)?;
    check_value("line CdAx of group", Some(group), h.cd_axial, false)?;
    check_value("line Ca of group", Some(group), h.ca, false)?;
    check_value("line CaAx of group", Some(group), h.ca_axial, false)
}

/// Checks a point's parameters (`k` its index, `n` the number of nodes).
fn check_point(k: usize, p: &PointHydro, n: usize) -> Result<(), SetupError> {
    if p.node >= n {
        return Err(SetupError::NodeOutOfRange {
            what: "point hydrodynamics",
            node: p.node,
            n_nodes: n,
        });
    }
    check_value("point volume [m^3]", Some(k), p.volume, false)?;
    check_value("point CdA [m^2]", Some(k), p.cda, false)?;
    check_value("point Ca", Some(k), p.ca, false)
}

/// The sums a node's wet data is lumped from: displaced volume [m³], the largest diameter
/// [m], `Σ ½ l_e d_e` [m²] and the points' drag `½ ρ_w CdA` [kg/m].
type NodeSums = (f64, f64, f64, f64);

/// The cross-section `π d²/4` [m²] of a line.
fn area_of(h: &LineHydro) -> f64 {
    0.25 * std::f64::consts::PI * h.diameter * h.diameter
}

/// Adds half of a line element of reference length `l` [m] to its node's sums.
fn add_line(nd: &mut NodeSums, l: f64, h: &LineHydro) {
    nd.0 += 0.5 * l * area_of(h);
    nd.1 = nd.1.max(h.diameter);
    nd.2 += 0.5 * l * h.diameter;
}

/// Adds point `p` to its node's sums (water density `rho` [kg/m³]).
fn add_point(nd: &mut NodeSums, p: &PointHydro, rho: f64) {
    nd.0 += p.volume;
    if nd.1 == 0.0 {
        // A point alone: the band is its volume's sphere diameter.
        nd.1 = (6.0 * p.volume / std::f64::consts::PI).cbrt();
    }
    nd.3 += 0.5 * rho * p.cda;
}

/// The drag data of line element `e` of reference length `l` [m].
fn wet_element(e: usize, l: f64, h: &LineHydro, rho: f64) -> WetElement {
    WetElement {
        e,
        normal: 0.5 * rho * h.cd * h.diameter * l,
        axial: 0.5 * rho * h.cd_axial * std::f64::consts::PI * h.diameter * l,
        band: h.diameter,
        axial_excess: rho * area_of(h) * (h.ca - h.ca_axial) * l,
    }
}

/// Node `i`'s wet data from its sums and its neighbours along its line (`None`: water does
/// nothing to it).
fn wet_node<const D: usize>(
    water: &Water<D>,
    i: usize,
    &(v, band, dl, drag): &NodeSums,
    (prev, next): (Option<usize>, Option<usize>),
) -> Option<WetNode> {
    if !(v > 0.0 || dl > 0.0 || drag > 0.0) {
        return None;
    }
    let (kb, cb) = water
        .seabed
        .as_ref()
        .map_or((0.0, 0.0), |s| (s.stiffness, s.damping));
    Some(WetNode {
        node: i,
        buoyancy: water.density * water.gravity * v,
        band: if band > 0.0 { band } else { 1e-3 },
        stiffness: kb * dl,
        damping: cb * dl,
        drag,
        axis: (prev.unwrap_or(i), next.unwrap_or(i)),
    })
}

/// The validated model, and the added masses: per group `ρ_w π d²/4 Ca` [kg/m] to add to
/// `ρA`, per node `ρ_w V Ca` [kg] to add as point masses.
pub(crate) type Built<const D: usize> = (WaterModel<D>, Vec<f64>, Vec<(usize, f64)>);

/// Validates `water` and `hydro` for the groups of `mesh` and lumps them to nodes and
/// elements (docs/method.md §21).
pub(crate) fn build<const D: usize>(
    water: &Water<D>,
    hydro: &Hydrodynamics,
    mesh: &Mesh,
    groups: &[GroupInfo<'_>],
) -> Result<Built<D>, SetupError> {
    if D < 2 {
        return Err(SetupError::WaterDimension { dimension: D });
    }
    let bed = check_water(water)?;
    let n = mesh.n_nodes();
    let rho = water.density;
    let mut node = vec![(0.0f64, 0.0f64, 0.0f64, 0.0f64); n]; // (V, band, d L, drag)
    // Each node's neighbours along a wet line, for its axis.
    let (mut prev, mut next) = (vec![None; n], vec![None; n]);
    let mut added_rho_a = vec![0.0; groups.len()];
    let mut elements = Vec::new();
    let mut seen = vec![false; groups.len()];
    for &(gi, h) in &hydro.lines {
        let Some(grp) = groups.get(gi) else {
            return Err(SetupError::NodeOutOfRange {
                what: "line hydrodynamics (element group)",
                node: gi,
                n_nodes: groups.len(),
            });
        };
        if !grp.is_string || std::mem::replace(&mut seen[gi], true) {
            return Err(SetupError::HydroGroup {
                group: gi,
                name: grp.name.to_string(),
            });
        }
        check_line(gi, &h)?;
        added_rho_a[gi] = rho * area_of(&h) * h.ca;
        for e in grp.elements.clone() {
            let l = mesh.lengths()[e];
            let [a, b] = mesh.elements()[e];
            prev[b].get_or_insert(a);
            next[a].get_or_insert(b);
            for i in mesh.elements()[e] {
                add_line(&mut node[i], l, &h);
            }
            elements.push(wet_element(e, l, &h, rho));
        }
    }
    elements.sort_by_key(|w| w.e);
    let mut added_point = Vec::new();
    for (k, p) in hydro.points.iter().enumerate() {
        check_point(k, p, n)?;
        add_point(&mut node[p.node], p, rho);
        if p.ca * p.volume > 0.0 {
            added_point.push((p.node, rho * p.volume * p.ca));
        }
    }
    let nodes = node
        .iter()
        .enumerate()
        .filter_map(|(i, sums)| wet_node(water, i, sums, (prev[i], next[i])))
        .collect();
    let model = WaterModel {
        rho,
        still: water.current.is_still(),
        current: water.current.clone(),
        delta: water.drag_smoothing,
        amplitude: water.linear_drag_amplitude,
        bed,
        nodes,
        elements,
    };
    Ok((model, added_rho_a, added_point))
}

// ---------------------------------------------------------------------------------------
// Evaluation: the potentials, and the step's forces, Jacobian blocks and work.

/// Block type of the Jacobian.
pub(crate) type Block<const D: usize> = SMatrix<f64, D, D>;

impl<const D: usize> WaterModel<D> {
    /// `(buoyancy, contact)` potentials [J] of node `w` at `r`, and their magnitudes.
    #[inline]
    pub fn node_energies(&self, w: &WetNode, r: &Vector<D>) -> (f64, f64) {
        let u = -w.buoyancy * buoyancy_height(r[D - 1], w.band);
        let c = match &self.bed {
            Some(bed) if w.stiffness > 0.0 => contact_energy(bed.gap(r), w.stiffness),
            _ => 0.0,
        };
        (u, c)
    }

    /// The wet nodes in `nodes` (a sorted range).
    pub fn nodes_in(&self, nodes: std::ops::Range<usize>) -> &[WetNode] {
        let lo = self.nodes.partition_point(|w| w.node < nodes.start);
        let hi = self.nodes.partition_point(|w| w.node < nodes.end);
        &self.nodes[lo..hi]
    }

    /// The axis of wet node `w` at the positions `r` [m] for axial friction: the chord
    /// between its neighbours along its line (not normalized); zero when the seabed has no
    /// axial friction or the node is on no line.
    #[inline]
    pub fn node_axis(&self, w: &WetNode, r: &[Vector<D>]) -> Vector<D> {
        let axial = self
            .bed
            .as_ref()
            .is_some_and(|b| b.friction.is_some_and(|f| f.axial.is_some()));
        if axial && w.stiffness > 0.0 {
            r[w.axis.1] - r[w.axis.0]
        } else {
            Vector::zeros()
        }
    }

    /// Room for a wet entry at every node and element of `mesh`, so that
    /// [`Self::relump_string`] never allocates.
    pub(crate) fn reserve_all(&mut self, mesh: &Mesh) {
        self.nodes.reserve(mesh.n_nodes() - self.nodes.len());
        self.elements
            .reserve(mesh.n_elements() - self.elements.len());
    }

    /// Lumps the water again, as [`build`] lumps it, at the nodes `nodes` and the elements
    /// `elements` of the string of group `group` after its active elements became `active`
    /// (a winch's cut, docs/method.md §23): `elements` must hold every element that meets a
    /// node in `nodes`, and no other group's element may meet them. Adds, replaces or
    /// removes their entries in place.
    pub(crate) fn relump_string(
        &mut self,
        (water, hydro): (&Water<D>, &Hydrodynamics),
        mesh: &Mesh,
        (group, active): (usize, &std::ops::Range<usize>),
        (elements, nodes): (std::ops::Range<usize>, &[usize]),
    ) {
        let line = hydro
            .lines
            .iter()
            .find(|(g, _)| *g == group)
            .map(|(_, h)| h);
        let wet = |e: usize| line.filter(|_| active.contains(&e));
        for e in elements.clone() {
            let at = self.elements.binary_search_by_key(&e, |w| w.e);
            match (wet(e), at) {
                (Some(h), Ok(k)) => {
                    self.elements[k] = wet_element(e, mesh.lengths()[e], h, water.density)
                }
                (Some(h), Err(k)) => self
                    .elements
                    .insert(k, wet_element(e, mesh.lengths()[e], h, water.density)),
                (None, Ok(k)) => {
                    self.elements.remove(k);
                }
                (None, Err(_)) => {}
            }
        }
        for &i in nodes {
            let mut sums = (0.0, 0.0, 0.0, 0.0);
            let (mut prev, mut next) = (None, None);
            for e in elements.clone() {
                let (Some(h), [a, b]) = (wet(e), mesh.elements()[e]) else {
                    continue;
                };
                if b == i {
                    prev.get_or_insert(a);
                }
                if a == i {
                    next.get_or_insert(b);
                }
                if a == i || b == i {
                    add_line(&mut sums, mesh.lengths()[e], h);
                }
            }
            for p in hydro.points.iter().filter(|p| p.node == i) {
                add_point(&mut sums, p, water.density);
            }
            let at = self.nodes.binary_search_by_key(&i, |w| w.node);
            match (wet_node(water, i, &sums, (prev, next)), at) {
                (Some(w), Ok(k)) => self.nodes[k] = w,
                (Some(w), Err(k)) => self.nodes.insert(k, w),
                (None, Ok(k)) => {
                    self.nodes.remove(k);
                }
                (None, Err(_)) => {}
            }
        }
    }

    /// The wet elements in `els` (a sorted range).
    pub fn elements_in(&self, els: std::ops::Range<usize>) -> &[WetElement] {
        let lo = self.elements.partition_point(|w| w.e < els.start);
        let hi = self.elements.partition_point(|w| w.e < els.end);
        &self.elements[lo..hi]
    }
}

impl<const D: usize> WaterModel<D> {
    /// The buoyancy [N] of wet node `w` when that is all the water does to it over the step
    /// from `r0` by `x` [m] (the common case: no point drag, below the surface band and off
    /// the seabed at both ends of the step), else `None`: then [`Self::node_step`]'s force is
    /// `−buoyancy e_z`, with a zero Jacobian block and no work.
    #[inline(always)]
    pub fn resting_buoyancy(&self, w: &WetNode, r0: &Vector<D>, x: &Vector<D>) -> Option<f64> {
        let r1 = r0 + x;
        let zi = D - 1;
        let submerged = r0[zi].max(r1[zi]) <= -0.5 * w.band;
        let off_bed = match &self.bed {
            Some(bed) if w.stiffness > 0.0 => bed.gap(r0) >= 0.0 && bed.gap(&r1) >= 0.0,
            _ => true,
        };
        (w.drag == 0.0 && (submerged || w.buoyancy == 0.0) && off_bed).then_some(w.buoyancy)
    }
}

/// The step's force on a wet node from the node's start `r0` and increment `x` over a step
/// of `h` [s]: the residual term (`+∂Ĥ/∂r` of buoyancy and contact, minus the resistive and
/// drag forces) [N], its Jacobian block, and the node's work in the step.
pub(crate) struct NodeStep<const D: usize> {
    pub res: Vector<D>,
    pub jac: Block<D>,
    pub work: WaterWork,
}

impl<const D: usize> WaterModel<D> {
    /// The step terms of node `w` (docs/method.md §21), `axis` the node's axis at the step's
    /// start for axial friction ([`Self::node_axis`]; zero: none).
    #[inline(always)]
    pub fn node_step(
        &self,
        w: &WetNode,
        r0: &Vector<D>,
        x: &Vector<D>,
        axis: &Vector<D>,
        h: f64,
    ) -> NodeStep<D> {
        let inv_h = 1.0 / h;
        let mut res = Vector::<D>::zeros();
        let mut jac = Block::<D>::zeros();
        let mut work = WaterWork::default();
        let zi = D - 1;
        let r1 = r0 + x;
        // Buoyancy: the exact quotient of U(z) = −ρ g V Φ(z), Φ' = 1 − S.
        // Submerged over the whole step (the common case): the full buoyancy, no derivative.
        if w.buoyancy > 0.0 && r0[zi].max(r1[zi]) <= -0.5 * w.band {
            res[zi] -= w.buoyancy;
        } else if w.buoyancy > 0.0 {
            let (qa, dqa) = emerged_quotient(r0[zi], r1[zi], w.band);
            res[zi] -= w.buoyancy * (1.0 - qa);
            jac[(zi, zi)] += w.buoyancy * dqa;
        }
        if let Some(bed) = self.bed.as_ref().filter(|_| w.stiffness > 0.0) {
            let out = (&mut res, &mut jac, &mut work);
            self.contact_step(bed, w, r0, &r1, x, axis, inv_h, out);
        }
        if w.drag > 0.0 {
            // Point drag ½ ρ CdA |v_r|_δ v_r at the mid-step velocity, in water only.
            let zm = r0[zi] + 0.5 * x[zi];
            let (u, du) = self.current.at(zm);
            let (em, dem) = emerged(zm, w.band);
            let phi = 1.0 - em;
            let vr = x * inv_h - u;
            let s = (vr.norm_squared() + self.delta * self.delta).sqrt();
            let f = vr * (-phi * w.drag * s);
            res -= f;
            let g = (Block::<D>::identity() * s + vr * vr.transpose() / s) * (w.drag * phi);
            let mut dvr = Block::<D>::identity() * inv_h;
            for k in 0..D {
                dvr[(k, zi)] -= 0.5 * du[k];
            }
            jac += g * dvr;
            // ∂φ/∂x_z = −½ dS/dz.
            for k in 0..D {
                jac[(k, zi)] -= 0.5 * w.drag * s * vr[k] * dem;
            }
            work.drag_dissipated += h * phi * w.drag * s * vr.norm_squared();
            work.current_supplied += h * f.dot(&u);
        }
        NodeStep { res, jac, work }
    }

    /// Contact (the quotient of the penalty potential), the ramped normal damping and the
    /// friction of node `w`, along the seabed's normal at the mid-step position
    /// (docs/method.md §21).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn contact_step(
        &self,
        bed: &Bed<D>,
        w: &WetNode,
        r0: &Vector<D>,
        r1: &Vector<D>,
        x: &Vector<D>,
        axis: &Vector<D>,
        inv_h: f64,
        (res, jac, work): (&mut Vector<D>, &mut Block<D>, &mut WaterWork),
    ) {
        if bed.is_level() {
            return Self::level_contact_step(bed, w, r0, r1, x, inv_h, (res, jac, work));
        }
        let (g0, g1) = (bed.gap(r0), bed.gap(r1));
        if g0 >= 0.0 && g1 >= 0.0 {
            // Off the seabed at both ends of the step: no contact, no damping, no friction.
            return;
        }
        let (q, dq) = contact_quotient(g0, g1, w.stiffness);
        // The quotient in the gap times the gap's exact discrete gradient (21.4).
        let (dg, ddg) = bed.gap_quotient(r0, r1);
        let grad1 = bed.gap_gradient(r1).0;
        *res += dg * q;
        *jac += dg * grad1.transpose() * dq;
        if let Some(ddg) = ddg {
            *jac += ddg * q;
        }
        let pm = (-0.5 * (g0 + g1)).max(0.0);
        // The normal at the mid-step position; on a grid it turns with the node,
        // ∂n/∂x = ½ ∂n/∂r.
        let (n, dn) = match &bed.grid {
            // A plane's normal, without the call.
            None => (bed.n, None),
            Some(_) => bed.normal_at(&(r0 + x * 0.5)),
        };
        let dn = dn.map(|d| d * 0.5);
        let xn = n.dot(x);
        // ∂(n·x)/∂x.
        let dxn = match &dn {
            None => n.transpose(),
            Some(d) => n.transpose() + x.transpose() * d,
        };
        if w.damping > 0.0 {
            let (rho, drho) = deeper_ramp(g0, g1, bed.ramp);
            let c = w.damping * rho;
            *res += n * (c * xn * inv_h);
            *jac += n * (dxn * (c * inv_h));
            if drho != 0.0 {
                // ∂g₁/∂x = ∇g(r₁)ᵀ.
                *jac += n * (grad1.transpose() * (w.damping * xn * inv_h * drho));
            }
            if let Some(d) = &dn {
                *jac += d * (c * xn * inv_h);
            }
            work.seabed_dissipated += c * xn * xn * inv_h;
        }
        if pm <= 0.0 {
            return;
        }
        if let Some(fr) = &bed.friction {
            let slip = Slip {
                n: &n,
                dn: dn.as_ref(),
                xn,
                dxn: &dxn,
                grad1: &grad1,
                stiffness: w.stiffness,
                pm,
            };
            slip.friction(fr, x, axis, inv_h, (res, jac, work));
        }
    }
}

impl<const D: usize> WaterModel<D> {
    /// [`Self::contact_step`] on a level seabed with isotropic friction ([`Bed::is_level`]):
    /// the same terms with `n = e_z`, formed by component. The gap is `z − p_z`, the slip
    /// the increment's horizontal part.
    #[inline(always)]
    fn level_contact_step(
        bed: &Bed<D>,
        w: &WetNode,
        r0: &Vector<D>,
        r1: &Vector<D>,
        x: &Vector<D>,
        inv_h: f64,
        (res, jac, work): (&mut Vector<D>, &mut Block<D>, &mut WaterWork),
    ) {
        let zi = D - 1;
        let (g0, g1) = (r0[zi] - bed.p[zi], r1[zi] - bed.p[zi]);
        if g0 >= 0.0 && g1 >= 0.0 {
            return;
        }
        let (q, dq) = contact_quotient(g0, g1, w.stiffness);
        res[zi] += q;
        jac[(zi, zi)] += dq;
        let xn = x[zi];
        if w.damping > 0.0 {
            // ∂g₁/∂x_z = 1.
            let (rho, drho) = deeper_ramp(g0, g1, bed.ramp);
            let c = w.damping * rho;
            res[zi] += c * xn * inv_h;
            jac[(zi, zi)] += c * inv_h + w.damping * xn * inv_h * drho;
            work.seabed_dissipated += c * xn * xn * inv_h;
        }
        let pm = (-0.5 * (g0 + g1)).max(0.0);
        if pm <= 0.0 {
            return;
        }
        let Some(fr) = &bed.friction else {
            return;
        };
        let a = fr.coefficient * w.stiffness * pm;
        if a <= 0.0 {
            return;
        }
        let mut v = x * inv_h;
        v[zi] = 0.0;
        let law = slip_law(fr.slope, a, fr.static_scale, &v);
        *res += v * law.coef;
        // ∂(coef v)/∂x: the horizontal columns of dv/h; the vertical column from the
        // Coulomb level, ∂a/∂x_z = −½ μ k.
        for col in 0..zi {
            for row in 0..D {
                jac[(row, col)] += law.dv[(row, col)] * inv_h;
            }
        }
        let dz = law.da * (-0.5 * fr.coefficient * w.stiffness);
        for row in 0..D {
            jac[(row, zi)] += v[row] * dz;
        }
        work.friction_dissipated += (1.0 / inv_h) * law.coef * v.norm_squared();
    }
}

/// Below this length of the axis's part in the seabed plane (relative to the axis), a node's
/// friction is the transverse law in every direction (a line standing on the seabed).
const AXIS_IN_PLANE_MIN: f64 = 1e-9;

/// Normalized slip `x_S` [–] about which the static peak's excess decays (docs/method.md
/// §21 (21.5b)): the coefficient is `μ (1 + (s − 1) exp(−(x/x_S)⁴))` at the normalized slip
/// `x = c_f |v|/(μ N)`, so that it stays within 2 % of `s μ` at the peak and is `μ` above
/// `x ≈ 2 x_S`.
pub const STATIC_PEAK_SLIP: f64 = 20.0;

/// The friction's derivative by the slip at zero slip [N·s/m] in the seabed plane of normal
/// `n`: `s c_f (I − nnᵀ)`, or with axial friction and an `axis` in the plane,
/// `s (c_a t tᵀ + c_f (I − nnᵀ − t tᵀ))`, `t` the axis's unit part in the plane.
fn friction_slope<const D: usize>(fr: &Friction, n: &Vector<D>, axis: &Vector<D>) -> Block<D> {
    let p = Block::<D>::identity() - n * n.transpose();
    let s = fr.static_scale;
    let a = p * axis;
    let la = a.norm();
    match fr.axial {
        Some(ax) if la > AXIS_IN_PLANE_MIN * axis.norm() => {
            let tt = a * a.transpose() / (la * la);
            (tt * ax.slope + (p - tt) * fr.slope) * s
        }
        _ => p * (fr.slope * s),
    }
}

/// One direction of the friction law (21.5)/(21.5b) at the slip `v` [m/s]: the force is
/// `−coef v` [N]; `dv` is `∂(coef v)/∂v` [N·s/m] and `da` the factor of `v` in
/// `∂(coef v)/∂a` [s/m], `a = μ N` the Coulomb level [N].
pub(crate) struct SlipLaw<const D: usize> {
    pub coef: f64,
    pub dv: Block<D>,
    pub da: f64,
}

/// The regularized Coulomb law (21.5) with zero-slip slope `c` [N·s/m] and Coulomb level
/// `a = μ N > 0` [N], times the static peak (21.5b) of scale `s` (`s = 1`: none), at the slip
/// `v` [m/s]: `coef = c φ(x) (1 + (s − 1) G(x))`, `φ = 1/√(1 + x²)`, `x = c|v|/a`,
/// `G = exp(−(x/x_S)⁴)`. Smooth in `v` (a function of `|v|²`), `coef > 0`.
#[inline(always)]
pub(crate) fn slip_law<const D: usize>(c: f64, a: f64, s: f64, v: &Vector<D>) -> SlipLaw<D> {
    let v2 = v.norm_squared();
    let root = (a * a + c * c * v2).sqrt();
    let coef = c * a / root;
    let r3 = root * root * root;
    let dv = (Block::<D>::identity() / root - v * v.transpose() * (c * c / r3)) * (c * a);
    let da = c * c * c * v2 / r3;
    if s == 1.0 {
        return SlipLaw { coef, dv, da };
    }
    // m = 1 + (s − 1) G(q), q = x² = c²|v|²/a², G = exp(−(q/x_S²)²).
    let xs2 = STATIC_PEAK_SLIP * STATIC_PEAK_SLIP;
    let q = c * c * v2 / (a * a);
    let qs = q / xs2;
    let g = (-qs * qs).exp();
    let m = 1.0 + (s - 1.0) * g;
    let dm_dq = -2.0 * (s - 1.0) * g * qs / xs2;
    // ∂q/∂v = 2 c² v/a², ∂q/∂a = −2 q/a.
    let dm_dv = v * (dm_dq * 2.0 * c * c / (a * a));
    let dm_da = -2.0 * dm_dq * q / a;
    SlipLaw {
        coef: coef * m,
        dv: dv * m + v * dm_dv.transpose() * coef,
        da: da * m + coef * dm_da,
    }
}

/// The seabed plane at a node in contact, for its friction: the mid-step normal `n` and its
/// derivative by the increment `dn` (a grid), `n·x` and its derivative, `∇g(r₁)`, the
/// node's contact stiffness `k_i` [N/m] and mid-step penetration `p_m` [m].
struct Slip<'a, const D: usize> {
    n: &'a Vector<D>,
    dn: Option<&'a Block<D>>,
    xn: f64,
    dxn: &'a nalgebra::SMatrix<f64, 1, D>,
    grad1: &'a Vector<D>,
    stiffness: f64,
    pm: f64,
}

impl<const D: usize> Slip<'_, D> {
    /// The friction (21.5), (21.5a), (21.5b) of the increment `x`, the axis `axis` of the node
    /// at the step's start (zero: none), added to the residual, Jacobian and work.
    #[inline(always)]
    fn friction(
        &self,
        fr: &Friction,
        x: &Vector<D>,
        axis: &Vector<D>,
        inv_h: f64,
        (res, jac, work): (&mut Vector<D>, &mut Block<D>, &mut WaterWork),
    ) {
        let n = self.n;
        // h v_t and ∂(h v_t)/∂x: (I − nnᵀ) on a plane.
        let xt = x - n * self.xn;
        let mut pt = Block::<D>::identity() - n * self.dxn;
        if let Some(d) = self.dn {
            pt -= d * self.xn;
        }
        let s = fr.static_scale;
        let along = fr.axial.and_then(|ax| {
            let a = axis - n * n.dot(axis);
            let la = a.norm();
            (la > AXIS_IN_PLANE_MIN * axis.norm()).then_some((ax, a / la, la))
        });
        let Some((ax, t, la)) = along else {
            self.direction(
                fr.coefficient,
                fr.slope,
                s,
                &xt,
                &pt,
                inv_h,
                (res, jac, work),
            );
            return;
        };
        // The slip along the axis t (in the seabed plane), h v_a = t tᵀ h v_t, and across it.
        let ta = t.dot(&xt);
        let xa = t * ta;
        let mut pa = t * t.transpose() * pt;
        if let Some(d) = self.dn {
            // t = P a₀/|P a₀| turns with n: ∂(P a₀)/∂x = −d (n·a₀) − n (a₀ᵀ d).
            let a0 = axis;
            let dpa = -(d * n.dot(a0)) - n * (a0.transpose() * d);
            let dt = (Block::<D>::identity() - t * t.transpose()) * dpa / la;
            pa += dt * ta + t * (xt.transpose() * dt);
        }
        let (xc, pc) = (xt - xa, pt - pa);
        self.direction(
            ax.coefficient,
            ax.slope,
            s,
            &xa,
            &pa,
            inv_h,
            (res, jac, work),
        );
        self.direction(
            fr.coefficient,
            fr.slope,
            s,
            &xc,
            &pc,
            inv_h,
            (res, jac, work),
        );
    }

    /// One direction's law: `μ`, zero-slip slope `c`, static scale `s`, the slip times `h`
    /// and its derivative by the increment.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn direction(
        &self,
        mu: f64,
        c: f64,
        s: f64,
        hv: &Vector<D>,
        dhv: &Block<D>,
        inv_h: f64,
        (res, jac, work): (&mut Vector<D>, &mut Block<D>, &mut WaterWork),
    ) {
        let a = mu * self.stiffness * self.pm;
        if a <= 0.0 {
            return;
        }
        let v = hv * inv_h;
        let law = slip_law(c, a, s, &v);
        *res += v * law.coef;
        *jac += law.dv * dhv * inv_h;
        // ∂a/∂x = −½ μ k ∇g(r₁)ᵀ (the mid-step penetration).
        let da = -0.5 * mu * self.stiffness;
        *jac += v * self.grad1.transpose() * (law.da * da);
        let h = 1.0 / inv_h;
        work.friction_dissipated += h * law.coef * v.norm_squared();
    }
}

/// An element's mid-step motion as its drag sees it: the tangent `r'_{n+½}` [–], the
/// velocity `(Δ_a + Δ_b)/2h` [m/s], the height of its mid-point `z_{n+½}` [m] and `1/l`
/// [1/m].
pub(crate) struct ElementMotion<const D: usize> {
    pub rpm: Vector<D>,
    pub ve: Vector<D>,
    pub zm: f64,
    pub inv_l: f64,
}

impl<const D: usize> ElementMotion<D> {
    /// The motion of element `[a, b]` of reference length `l` [m] from its nodes' starts
    /// `r0` [m] and increments `x` [m] over a step of `h` [s].
    #[inline(always)]
    pub fn new(r0: (&Vector<D>, &Vector<D>), x: (&Vector<D>, &Vector<D>), l: f64, h: f64) -> Self {
        let inv_l = 1.0 / l;
        Self::with_tangent((r0.1 - r0.0 + (x.1 - x.0) * 0.5) * inv_l, r0, x, inv_l, h)
    }

    /// [`Self::new`] with the mid-step tangent `rpm` the element loop has already formed.
    #[inline(always)]
    pub fn with_tangent(
        rpm: Vector<D>,
        r0: (&Vector<D>, &Vector<D>),
        x: (&Vector<D>, &Vector<D>),
        inv_l: f64,
        h: f64,
    ) -> Self {
        let zi = D - 1;
        Self {
            rpm,
            ve: (x.0 + x.1) * (0.5 * (1.0 / h)),
            zm: 0.5 * (r0.0[zi] + r0.1[zi]) + 0.25 * (x.0[zi] + x.1[zi]),
            inv_l,
        }
    }
}

impl<const D: usize> WaterModel<D> {
    /// `(force F [N] on the element, its Jacobian blocks by x_a and x_b, work)` of the drag on
    /// wet element `w` = `[a, b]` of reference length `l`: Morison's law at the element's
    /// mid-step velocity `(Δ_a + Δ_b)/2h` relative to the current at the mid-step mid-point,
    /// split along the mid-step tangent; half of `F` acts on each node. The blocks are those
    /// of the residual rows (`−½ F` on each node).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub fn element_drag(
        &self,
        w: &WetElement,
        r0: (&Vector<D>, &Vector<D>),
        x: (&Vector<D>, &Vector<D>),
        l: f64,
        h: f64,
        want_jac: bool,
    ) -> (Vector<D>, [Block<D>; 2], WaterWork) {
        self.drag(w, &ElementMotion::new(r0, x, l, h), h, want_jac)
    }

    /// [`Self::element_drag`] of the element's motion `m` over a step of `h` [s].
    #[inline(always)]
    pub fn drag(
        &self,
        w: &WetElement,
        m: &ElementMotion<D>,
        h: f64,
        want_jac: bool,
    ) -> (Vector<D>, [Block<D>; 2], WaterWork) {
        let inv_h = 1.0 / h;
        let zi = D - 1;
        let (rpm, zm, inv_l) = (&m.rpm, m.zm, m.inv_l);
        let (u, du) = if self.still {
            (Vector::zeros(), Vector::zeros())
        } else {
            self.current.at(zm)
        };
        let (em, dem) = emerged(zm, w.band);
        let phi = 1.0 - em;
        let vr = m.ve - u;
        // The tangent t = p/|p| only enters through p pᵀ/|p|² and (p·v_r)/|p|²: no root.
        let l2 = rpm.norm_squared();
        let inv_l2 = if l2 > 0.0 { 1.0 / l2 } else { 0.0 };
        let ap = rpm.dot(&vr);
        let vrt = rpm * (ap * inv_l2);
        let vrn = vr - vrt;
        let d2 = self.delta * self.delta;
        let a2 = ap * ap * inv_l2;
        let (sn, st) = ((vrn.norm_squared() + d2).sqrt(), (a2 + d2).sqrt());
        let bvec = vrn * (w.normal * sn) + vrt * (w.axial * st);
        let f = bvec * -phi;
        let work = WaterWork {
            drag_dissipated: h
                * phi
                * (w.normal * sn * vrn.norm_squared() + w.axial * st * vrt.norm_squared()),
            current_supplied: h * f.dot(&u),
            ..Default::default()
        };
        if !want_jac {
            return (f, [Block::zeros(); 2], work);
        }
        // With P = I − t tᵀ, a = t·v_r, v_rn = P v_r, v_rt = a t (so v_rnᵀ t = 0):
        // ∂B/∂v_r = wN (sn P + v_rn v_rnᵀ/sn) + wA (st + a²/st) t tᵀ, and the tangent's part
        // ∂B/∂t · ∂t/∂r' = (1/|r'|) [(wA st − wN sn)(a P + t v_rnᵀ) + wA a²/st t v_rnᵀ
        //                            − wN a/sn v_rn v_rnᵀ].
        // Entrywise, with a |p| = p·v_r: ∂B/∂v_r = α I + β t tᵀ + γ v_rn v_rnᵀ and the
        // tangent's part (1/|r'|) [c a I − c a t tᵀ + (c + wA a²/st) t v_rnᵀ − (wN a/sn) v_rn v_rnᵀ].
        let inv_sn = 1.0 / sn;
        let aa = w.axial * a2 / st;
        let (alpha, gamma) = (w.normal * sn, w.normal * inv_sn);
        let beta = w.axial * st + aa - alpha;
        // Zero when the element has no length (p = 0, inv_l2 = 0).
        let c = w.axial * st - alpha;
        let (s0, s1) = (0.25 * phi * inv_h, 0.25 * phi * inv_l * inv_l2);
        // The ½ h⁻¹ ∂B/∂v_r part K₀ and the tangent's part K₁ (rows −½ B): ∂/∂x_a = K₀ − K₁,
        // ∂/∂x_b = K₀ + K₁, each a multiple of I plus rank-one terms p (·)ᵀ and v_rn (·)ᵀ,
        // with p pᵀ/|p|² = p (p/|p|²)ᵀ.
        let (k0i, k0p, k0n) = (s0 * alpha, s0 * beta, s0 * gamma);
        let (k1i, k1v, k1n) = (s1 * c * ap, s1 * (c + aa), s1 * gamma * ap);
        let pu = rpm * inv_l2;
        let (pa, pb) = (pu * (k0p + k1i) - vrn * k1v, pu * (k0p - k1i) + vrn * k1v);
        let (na, nb) = (vrn * (k0n + k1n), vrn * (k0n - k1n));
        let eye = Block::<D>::identity();
        let mut ja = eye * (k0i - k1i) + rpm * pa.transpose() + vrn * na.transpose();
        let mut jb = eye * (k0i + k1i) + rpm * pb.transpose() + vrn * nb.transpose();
        // ∂v_r/∂x = ½h⁻¹ I − ¼ (du/dz) e_zᵀ; ∂φ/∂x_z = −¼ dS/dz, times ½ of −(−B) on each row.
        if dem != 0.0 || du.iter().any(|&d| d != 0.0) {
            let gv = Block::<D>::identity() * alpha
                + rpm * rpm.transpose() * (beta * inv_l2)
                + vrn * vrn.transpose() * gamma;
            let gdu = gv * du * (-0.125 * phi);
            for k in 0..D {
                let col = gdu[k] - 0.125 * dem * bvec[k];
                ja[(k, zi)] += col;
                jb[(k, zi)] += col;
            }
        }
        (f, [ja, jb], work)
    }
}

// ---------------------------------------------------------------------------------------
// Statics: the same forces at rest (v = 0).

impl<const D: usize> WaterModel<D> {
    /// At rest at `r`: the potential part of node `w`'s residual (`+∂Ĥ/∂r` of buoyancy,
    /// scaled by the load factor `lambda`, and of contact) [N], and its stiffness block
    /// [N/m] (symmetric; ⪰ 0 on a plane, with the curvature term `k g ∇²g` on a grid),
    /// docs/method.md §21.
    pub fn static_potential(
        &self,
        w: &WetNode,
        r: &Vector<D>,
        lambda: f64,
    ) -> (Vector<D>, Block<D>) {
        let zi = D - 1;
        let mut res = Vector::<D>::zeros();
        let mut jac = Block::<D>::zeros();
        if w.buoyancy > 0.0 {
            let (s, ds) = emerged(r[zi], w.band);
            res[zi] -= lambda * w.buoyancy * (1.0 - s);
            jac[(zi, zi)] += lambda * w.buoyancy * ds;
        }
        if let Some(bed) = &self.bed {
            let g = bed.gap(r);
            if w.stiffness > 0.0 && g < 0.0 {
                let (grad, hess) = bed.gap_gradient(r);
                res += grad * (w.stiffness * g);
                jac += grad * grad.transpose() * w.stiffness;
                if let Some(hess) = hess {
                    jac += hess * (w.stiffness * g);
                }
            }
        }
        (res, jac)
    }

    /// At rest at `r`: the residual term of node `w`'s point drag in the current (`−f` with
    /// `v_r = −u(z)`) [N] and its derivative by `r` [N/m].
    pub fn static_point_drag(&self, w: &WetNode, r: &Vector<D>) -> (Vector<D>, Block<D>) {
        let drag_only = WetNode {
            buoyancy: 0.0,
            stiffness: 0.0,
            damping: 0.0,
            ..*w
        };
        // A step of infinite length from r with no increment has v = 0; the increment enters
        // the mid-step height with weight ½, so the derivative by r is twice that by x.
        let zero = Vector::zeros();
        let st = self.node_step(&drag_only, r, &zero, &zero, f64::INFINITY);
        (st.res, st.jac * 2.0)
    }

    /// At rest at `r_a`, `r_b`: the drag force `F` [N] on element `w` in the current (half on
    /// each node) and the derivative of the residual rows (`−½ F`) by `r_a` and `r_b` [N/m].
    pub fn static_element_drag(
        &self,
        w: &WetElement,
        r: (&Vector<D>, &Vector<D>),
        l: f64,
        want_jac: bool,
    ) -> (Vector<D>, [Block<D>; 2]) {
        let zero = Vector::<D>::zeros();
        // As in `static_point_drag`: no velocity, and positions enter with weight ½.
        let (f, [ja, jb], _) = self.element_drag(w, r, (&zero, &zero), l, f64::INFINITY, want_jac);
        (f, [ja * 2.0, jb * 2.0])
    }

    /// At rest at the positions `r` [m]: the derivative of node `w`'s resistive forces by its
    /// velocity [N·s/m] (symmetric, ⪰ 0), the node's block of the damping matrix `R_v`: the
    /// point drag's derivative in the current (with the equivalent linear drag of
    /// [`Water::linear_drag_amplitude`]), the seabed damping in contact (ramped by the
    /// penetration), and the friction's slope at zero slip in the seabed plane (times the
    /// static scale; along and across the node's axis with axial friction).
    pub fn node_damping(&self, w: &WetNode, rs: &[Vector<D>]) -> Block<D> {
        let eye = Block::<D>::identity();
        let r = &rs[w.node];
        let mut c = Block::<D>::zeros();
        if w.drag > 0.0 {
            let (u, _) = self.current.at(r[D - 1]);
            let phi = 1.0 - emerged(r[D - 1], w.band).0;
            let s = (u.norm_squared() + self.delta * self.delta).sqrt();
            let eq = LORENTZ * self.amplitude;
            c += (eye * (s + eq) + u * u.transpose() / s) * (w.drag * phi);
        }
        if let Some(bed) = self.bed.as_ref().filter(|_| w.stiffness > 0.0) {
            let p = -bed.gap(r);
            if p > 0.0 {
                let nn = bed.n * bed.n.transpose();
                c += nn * (w.damping * ramp(p, bed.ramp).0);
                if let Some(fr) = &bed.friction {
                    c += friction_slope(fr, &bed.n, &self.node_axis(w, rs));
                }
            }
        }
        c
    }

    /// At rest at `r_a`, `r_b`: the derivative of element `w`'s drag force by the element's
    /// mean velocity, negated [N·s/m] (symmetric, ⪰ 0): Morison's law at `v_r = −u` split
    /// along the tangent, plus the equivalent linear drag of
    /// [`Water::linear_drag_amplitude`]. Each of the element's four node blocks of `R_v`
    /// carries a quarter of it.
    pub fn element_damping(&self, w: &WetElement, r: (&Vector<D>, &Vector<D>)) -> Block<D> {
        let zi = D - 1;
        let zm = 0.5 * (r.0[zi] + r.1[zi]);
        let (u, _) = self.current.at(zm);
        let phi = 1.0 - emerged(zm, w.band).0;
        let chord = r.1 - r.0;
        let len = chord.norm();
        let t = if len > 0.0 { chord / len } else { chord };
        let vr = -u;
        let a = t.dot(&vr);
        let vrn = vr - t * a;
        let d2 = self.delta * self.delta;
        let (sn, st) = ((vrn.norm_squared() + d2).sqrt(), (a * a + d2).sqrt());
        let (tt, eq) = (t * t.transpose(), LORENTZ * self.amplitude);
        let pn = Block::<D>::identity() - tt;
        (pn * (w.normal * (sn + eq))
            + vrn * vrn.transpose() * (w.normal / sn)
            + tt * (w.axial * (st + eq + a * a / st)))
            * phi
    }

    /// The stiffness of the potentials (buoyancy, contact) of every wet node at `r`, added to
    /// the diagonal blocks `diag` [N/m].
    pub fn add_potential_stiffness(&self, r: &[Vector<D>], diag: &mut [Block<D>]) {
        for w in &self.nodes {
            diag[w.node] += self.static_potential(w, &r[w.node], 1.0).1;
        }
    }

    /// Contact of every wet node at `r` with the seabed (none without seabed).
    pub fn contacts(&self, r: &[Vector<D>]) -> Vec<NodeContact> {
        let Some(bed) = &self.bed else {
            return Vec::new();
        };
        self.nodes
            .iter()
            .filter(|w| w.stiffness > 0.0)
            .map(|w| node_contact(bed, w, r))
            .collect()
    }

    /// The seabed contact of mesh node `node` at positions `r` [m] (see [`Self::contacts`]);
    /// `None` if the node cannot touch the seabed or there is none.
    pub fn contact(&self, node: usize, r: &[Vector<D>]) -> Option<NodeContact> {
        let bed = self.bed.as_ref()?;
        let w = self.nodes_in(node..node + 1).first()?;
        (w.stiffness > 0.0).then(|| node_contact(bed, w, r))
    }
}

#[cfg(test)]
mod tests {
    //! The one-dimensional quotients against their defining differences.

    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]
        /// `q (z₁ − z₀) = A(z₁) − A(z₀)` to rounding, across the band's edges, and `q → S`
        /// as the heights meet; the derivative against a central difference.
        #[test]
        fn emerged_quotient_is_the_divided_difference(z0 in -1.5f64..1.5, dz in -1.0f64..1.0, b in 0.05f64..1.0) {
            let z1 = z0 + dz;
            let (q, dq) = emerged_quotient(z0, z1, b);
            let exact = a_int(z1, b) - a_int(z0, b);
            prop_assert!((q * (z1 - z0) - exact).abs() <= 8.0 * f64::EPSILON * (z0.abs() + z1.abs() + b));
            prop_assert!((0.0..=1.0).contains(&q));
            let (qs, _) = emerged_quotient(z0, z0, b);
            prop_assert_eq!(qs, emerged(z0, b).0);
            let eps = 1e-7;
            let fd = (emerged_quotient(z0, z1 + eps, b).0 - emerged_quotient(z0, z1 - eps, b).0) / (2.0 * eps);
            // Skip central differences that straddle a band edge (A''' jumps there).
            let near_edge = ((z1.abs() - 0.5 * b).abs()) < 1e-5;
            prop_assert!(near_edge || (dq - fd).abs() <= 1e-6 * (1.0 + 1.0 / b), "dq {dq} fd {fd}");
        }

        /// The contact quotient: `q (g₁ − g₀) = V(g₁) − V(g₀)` and its derivative.
        #[test]
        fn contact_quotient_is_the_divided_difference(g0 in -0.1f64..0.1, dg in -0.1f64..0.1) {
            let (k, g1) = (3.0e6, g0 + dg);
            let (q, dq) = contact_quotient(g0, g1, k);
            let exact = contact_energy(g1, k) - contact_energy(g0, k);
            let scale = contact_energy(-g0.abs(), k) + contact_energy(-g1.abs(), k);
            prop_assert!((q * (g1 - g0) - exact).abs() <= 8.0 * f64::EPSILON * scale);
            let eps = 1e-9;
            let fd = (contact_quotient(g0, g1 + eps, k).0 - contact_quotient(g0, g1 - eps, k).0) / (2.0 * eps);
            prop_assert!(g1.abs() < 1e-8 || (dq - fd).abs() <= 1e-5 * k, "dq {dq} fd {fd}");
        }
    }

    /// A node of 2 m of 0.1 m chain pressed `p` into a flat seabed, or one of the bumpy grid
    /// (the normal turning), with the friction `fr` and no damping, buoyancy or drag.
    fn friction_node(fr: Friction, grid: bool) -> (WaterModel<3>, WetNode) {
        let g = grid.then(|| {
            let xs = vec![-3.0, -1.0, 0.5, 2.0, 4.0];
            let ys = vec![-2.0, 0.0, 3.0];
            let d = ys
                .iter()
                .flat_map(|&y| {
                    // 50 m deep below the test's node at (0.3, −0.2), sloping about it.
                    xs.iter().map(move |&x: &f64| {
                        50.0 + 0.05 * (x.sin() - 0.3f64.sin()) + 0.02 * (y + 0.2)
                    })
                })
                .collect();
            Arc::new(Bathymetry::grid(xs, ys, d).unwrap())
        });
        let model = WaterModel {
            rho: 1025.0,
            current: Current::still(),
            still: true,
            delta: DEFAULT_DRAG_SMOOTHING,
            amplitude: 0.0,
            bed: Some(Bed {
                n: up::<3>(),
                p: Vector::<3>::new(0.0, 0.0, -50.0),
                grid: g,
                ramp: DEFAULT_DAMPING_RAMP,
                friction: Some(fr),
            }),
            nodes: vec![],
            elements: vec![],
        };
        let node = WetNode {
            node: 0,
            buoyancy: 0.0,
            band: 0.1,
            stiffness: 3e6 * 0.1 * 2.0,
            damping: 0.0,
            drag: 0.0,
            axis: (0, 0),
        };
        (model, node)
    }

    /// The seabed damping, ramped in over the first millimetre of penetration, adds to a
    /// node's step equation a term monotone in its normal increment, so that contact and
    /// damping together cannot give a step two solutions: a node 0.2–0.8 mm into a level
    /// seabed, with a spar line's contact stiffness and damping per node (45 m of 0.09 m
    /// line, kBot 3e6 Pa/m, cBot 3e5 Pa·s/m), rising or sinking up to 3 mm in a 20 ms step.
    /// With the ramp on the mid-step penetration this fails: the node 0.5 mm in, rising
    /// about 0.47 mm, meets a force that falls as it rises further.
    #[test]
    fn seabed_damping_is_monotone_in_the_normal_increment() {
        let (mut model, mut node) = friction_node(Friction::new(0.6, 1e5), false);
        if let Some(bed) = model.bed.as_mut() {
            bed.friction = None;
        }
        node.stiffness = 3e6 * 0.09 * 45.0;
        node.damping = 3e5 * 0.09 * 45.0;
        let (h, axis) = (0.02, Vector::<3>::zeros());
        for p0 in [2e-4, 5e-4, 8e-4] {
            let r0 = Vector::<3>::new(0.3, -0.2, -50.0 - p0);
            let mut last = f64::NEG_INFINITY;
            for k in -3000..=3000 {
                let x = Vector::<3>::new(0.0, 0.0, f64::from(k) * 1e-6);
                let f = model.node_step(&node, &r0, &x, &axis, h).res[2];
                assert!(
                    f >= last,
                    "p0 = {p0} m, x_z = {} m: {f} N after {last} N",
                    x[2]
                );
                last = f;
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]
        /// The friction (21.5)–(21.5b) is a resistance at every state: over any step its
        /// dissipation `h Σ c φ |v|²` is ≥ 0 and is exactly the work `−f·Δ` of its force (the
        /// friction's residual term times the increment, to rounding), isotropic or split
        /// along any axis, with and without the static peak, the slip ranging over the peak's
        /// region and beyond (normalized slip 1e-3 … 1e3).
        #[test]
        fn friction_dissipates_its_work(
            vx in -1.0f64..1.0, vy in -1.0f64..1.0, vz in -0.2f64..0.2, speed in -3.0f64..3.0,
            ax in -1.0f64..1.0, ay in -1.0f64..1.0, az in -1.0f64..1.0,
            mu_a in 0.0f64..1.0, scale in 0.5f64..3.0, pick in 0usize..4, grid in proptest::bool::ANY,
        ) {
            let mut fr = Friction::new(0.6, 1e5);
            if pick & 1 == 1 {
                fr = fr.with_axial(mu_a, mu_a.max(1e-3) * 2e5);
            }
            if pick & 2 == 2 {
                fr = fr.with_static_scale(scale);
            }
            let (with, node) = friction_node(fr, grid);
            let mut without = with.clone();
            without.bed.as_mut().unwrap().friction = None;
            let h = 0.01;
            // 5 mm in, then the slip: |v| from 1e-3 to 1e3 times μN/c (μN ≈ 1800 N).
            let r0 = Vector::<3>::new(0.3, -0.2, -50.005);
            let dir = Vector::<3>::new(vx, vy, vz);
            let x = dir * (h * 1.8e-2 * 10f64.powf(speed) / dir.norm().max(1e-3));
            let axis = Vector::<3>::new(ax, ay, az);
            let a = with.node_step(&node, &r0, &x, &axis, h);
            let b = without.node_step(&node, &r0, &x, &axis, h);
            let d = a.work.friction_dissipated;
            // The friction force is the difference of two residuals that both hold the contact
            // force (about 3 kN here), so its rounding scales with theirs, not with it: at a
            // slow slip the friction work is 1e-9 J while the residuals' work is 1e-3 J.
            let work = (a.res - b.res).dot(&x);
            let rounding = (a.res.norm() + b.res.norm()) * x.norm();
            prop_assert!(d >= 0.0, "dissipation {d:e}");
            prop_assert!((d - work).abs() <= 1e-13 * (d.abs() + rounding), "D {d:e} against -f·Δ {work:e}");
        }
    }

    /// The law's force over `μN` (21.5b) peaks at `s` less the regularization: the largest
    /// value over the slip is within 2 % below `s` for `s` from 1.2 to 3, and the coefficient
    /// is `s c_f` at zero slip and `μ` (the kinetic one) at large slip.
    #[test]
    fn static_peak_reaches_s_mu_n_and_falls_to_mu_n() {
        for s in [1.2, 1.5, 2.0, 3.0] {
            let (c, a) = (1.0, 1.0);
            let psi = |x: f64| slip_law::<1>(c, a, s, &Vector::<1>::new(x)).coef * x;
            let peak = (1..=100_000)
                .map(|k| psi(k as f64 * 1e-3))
                .fold(0.0, f64::max);
            assert!(peak < s && peak >= 0.98 * s, "s = {s}: peak {peak}");
            assert!((slip_law::<1>(c, a, s, &Vector::<1>::new(0.0)).coef - s).abs() <= 1e-15);
            assert!((psi(200.0) - 1.0).abs() <= 2e-5, "s = {s}: {}", psi(200.0));
        }
    }

    /// Momentum (docs/method.md §21): over every step the change of `Σ M_ρ v` equals the
    /// impulse of gravity, the water's forces (buoyancy, seabed, drag, friction) and the
    /// support's reaction, to the Newton residual left at the free components.
    #[test]
    fn momentum_changes_by_the_impulse_of_the_external_forces() {
        use crate::{Boundary, Fixed, MassMatrix, Material, Mesh, Problem, Simulation, State};
        let (n, l) = (12, 4.0);
        let mesh = Mesh::uniform_chain(n, l * n as f64).unwrap();
        let r: Vec<Vector<3>> = (0..=n)
            .map(|i| Vector::<3>::new(3.5 * i as f64, 0.2 * i as f64, -40.0 + 3.0 * i as f64))
            .collect();
        let problem = Problem {
            initial: State::at_rest(&mesh, r),
            mesh,
            material: Material::linear_elastic(1e9),
            rho_a: 120.0,
            body_force: Vector::<3>::new(0.0, 0.0, -120.0 * STANDARD_GRAVITY),
            mass: MassMatrix::Consistent,
            boundary: Boundary {
                fixed: vec![Fixed::node(0)],
                loads: vec![],
                motions: vec![],
                feedback: vec![],
            },
            point_masses: vec![],
        };
        let seabed = Seabed::flat(40.0, 3e6, 3e5).with_friction(Friction::new(0.6, 500.0));
        let water = Water::new(1025.0)
            .with_current(Current::Uniform(Vector::<3>::new(0.8, -0.3, 0.0)))
            .with_seabed(seabed);
        let line = LineHydro {
            diameter: 0.12,
            cd: 1.2,
            cd_axial: 0.4,
            ca: 1.0,
            ca_axial: 1.0,
        };
        let net = crate::Network::from(problem)
            .with_water(water)
            .with_line_hydro(0, line)
            .with_point_hydro(PointHydro {
                node: n,
                volume: 0.5,
                cda: 0.8,
                ca: 0.5,
            });
        let params = crate::StepParams {
            h: 0.02,
            ..Default::default()
        };
        let mut sim = Simulation::new(net, params).unwrap();
        let mut worst = 0.0f64;
        for _ in 0..200 {
            let before = sim.state().clone();
            let p0 = sim.system().linear_momentum(&before);
            let rep = sim.step().unwrap();
            let sys = sim.system();
            let w = sys.water.as_deref().unwrap();
            let x: Vec<Vector<3>> = sim
                .state()
                .r
                .iter()
                .zip(&before.r)
                .map(|(a, b)| a - b)
                .collect();
            // The water's residual terms, summed over the nodes.
            let mut water_res = Vector::<3>::zeros();
            for node in &w.nodes {
                let axis = w.node_axis(node, &before.r);
                water_res += w
                    .node_step(node, &before.r[node.node], &x[node.node], &axis, rep.h)
                    .res;
            }
            for el in &w.elements {
                let [a, b] = sys.mesh.elements()[el.e];
                let l = sys.mesh.lengths()[el.e];
                let (f, _, _) = w.element_drag(
                    el,
                    (&before.r[a], &before.r[b]),
                    (&x[a], &x[b]),
                    l,
                    rep.h,
                    false,
                );
                water_res -= f;
            }
            let gravity: Vector<3> = sys.body_force_vector().iter().sum();
            let supports: Vector<3> = sim.ports().iter().map(|p| p.output).sum();
            let impulse = (gravity - water_res + supports) * rep.h;
            let dp = sys.linear_momentum(sim.state()) - p0;
            let left = rep.h * ((n + 1) as f64 * 3.0).sqrt() * rep.residual;
            let scale = rep.h * (gravity.norm() + water_res.norm() + supports.norm());
            let err = (dp - impulse).norm();
            assert!(
                err <= left + 1e-12 * scale,
                "step {}: {err:e} vs {left:e}",
                rep.step
            );
            worst = worst.max(err / scale);
        }
        println!("momentum: worst relative defect {worst:e}");
        assert!(worst <= 1e-9, "worst {worst:e}");
    }

    /// Fully submerged, the buoyancy is the constant `ρ_w g V` upwards; above the band, none.
    #[test]
    fn buoyancy_potential_far_from_the_surface() {
        let b = 0.2;
        assert_eq!(buoyancy_height(-5.0, b) - buoyancy_height(-7.0, b), 2.0);
        assert_eq!(buoyancy_height(3.0, b), buoyancy_height(1.0, b));
        assert_eq!(emerged_quotient(-5.0, -7.0, b), (0.0, 0.0));
        assert_eq!(emerged_quotient(3.0, 1.0, b), (1.0, 0.0));
        // Φ(0) = 0 by definition.
        assert!(buoyancy_height(0.0, b).abs() <= f64::EPSILON);
    }
}
