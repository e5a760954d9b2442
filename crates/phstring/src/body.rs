//! Rigid bodies in the exact step (docs/method.md §22): a body's definition and state, the
//! Cayley rotation of a step, and the body's step equations with their Jacobian.
//!
//! A body is its centre of mass `x` [m] with velocity `V` [m/s], its orientation `R` (body
//! axes to space, kept as a unit quaternion) and its angular velocity in body axes `Ω`
//! [rad/s]; `J` is the inertia tensor about the centre of mass in body axes and `Π = J Ω`
//! the angular momentum in body axes. Its energy is `½ m |V|² + ½ Ω·JΩ − x·W`, `W` its
//! weight [N].
//!
//! A step's unknowns are `Δx = x_{n+1} − x_n` and the Cayley vector `w`:
//! `R_{n+1} = R_n cay(w)`, `cay(w) = (I − ŵ/2)⁻¹ (I + ŵ/2)`, `w = h Ω_{n+½}` with
//! `Ω_{n+½} = J⁻¹ Π_{n+½}`. A string end at a body point `s` (body axes) is a node whose
//! increment is `Δa = Δx + R_n (cay(w) − I) s`; the node's residual is the force the body
//! must exert on it, so the body feels its negative.
//!
//! Vectors of a body are 3-vectors in 2D as in 3D: in 2D the plane is `z = 0`, a rotation
//! turns about `z`, and only the moment of inertia about `z` (`inertia[(2, 2)]`) counts.

use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};

use crate::boundary::Boundary;
use crate::error::SetupError;
use crate::mesh::Mesh;

mod added_mass;
pub use added_mass::{Mat6, added_mass_about_centre, check_added_mass};

/// A nodal vector in `R^D`.
type Vector<const D: usize> = nalgebra::SVector<f64, D>;

/// A 3-vector of a body [m, m/s, N or N·m].
pub type Vec3 = Vector3<f64>;
/// A 3×3 matrix of a body.
pub type Mat3 = Matrix3<f64>;

/// The state of a rigid body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyState {
    /// Position of the centre of mass [m] (`z = 0` in 2D).
    pub position: Vec3,
    /// Velocity of the centre of mass [m/s].
    pub velocity: Vec3,
    /// Orientation: the rotation from body axes to space axes.
    pub orientation: UnitQuaternion<f64>,
    /// Angular velocity in body axes `Ω` [rad/s] (in 2D about `z` only).
    pub omega: Vec3,
}

impl BodyState {
    /// A body at `position` [m] with `velocity` [m/s], `orientation` and the angular velocity
    /// `omega` [rad/s] given in space axes.
    pub fn new(
        position: Vec3,
        velocity: Vec3,
        orientation: UnitQuaternion<f64>,
        omega: Vec3,
    ) -> Self {
        Self {
            position,
            velocity,
            orientation,
            omega: orientation.inverse_transform_vector(&omega),
        }
    }

    /// A body at rest at `position` [m] with `orientation`.
    pub fn at_rest(position: Vec3, orientation: UnitQuaternion<f64>) -> Self {
        Self {
            position,
            velocity: Vec3::zeros(),
            orientation,
            omega: Vec3::zeros(),
        }
    }

    /// The angular velocity in space axes `R Ω` [rad/s].
    pub fn omega_space(&self) -> Vec3 {
        self.orientation.transform_vector(&self.omega)
    }

    /// The space position [m] of the body point `s` [m] (body axes).
    pub fn point(&self, s: &Vec3) -> Vec3 {
        self.position + self.orientation.transform_vector(s)
    }
}

/// Where a node of a string is fixed to a body.
#[derive(Debug, Clone, PartialEq)]
pub struct Attachment<const D: usize> {
    /// The node (a string end, or any node of the mesh).
    pub node: usize,
    /// The attachment point in body axes [m], relative to the centre of mass.
    pub point: Vector<D>,
}

/// A signal of time [s] with a 3-vector value (a force [N] or a torque [N·m]).
pub type Vec3Fn = std::sync::Arc<dyn Fn(f64) -> Vec3 + Send + Sync>;

/// The wrench port of a body: a force at its centre of mass and a torque, both in space axes,
/// given as functions of time (evaluated at the step's mid time `t_{n+½}`). Its outputs are
/// the body's mid-step velocity and angular velocity; its power enters the balance.
#[derive(Clone)]
pub struct BodyWrench {
    /// Force [N] at the centre of mass, space axes (in 2D its `z` component is ignored).
    pub force: Vec3Fn,
    /// Torque [N·m] about the centre of mass, space axes (in 2D only `z` counts).
    pub torque: Vec3Fn,
}

impl std::fmt::Debug for BodyWrench {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BodyWrench").finish_non_exhaustive()
    }
}

/// A body's pose `(position [m], orientation)` as a function of time [s].
pub type PoseFn = std::sync::Arc<dyn Fn(f64) -> (Vec3, UnitQuaternion<f64>) + Send + Sync>;
/// A body's velocity [m/s] and angular velocity [rad/s] (space axes) as a function of time [s].
pub type TwistFn = std::sync::Arc<dyn Fn(f64) -> (Vec3, Vec3) + Send + Sync>;

/// A prescribed motion of a whole body (a vessel, a crane trolley): its pose and the pose's
/// exact rate. The body's slots are then known; its port's input is the motion, its output
/// the reaction wrench (with the impulse that holds its velocity at `twist`), and its power
/// enters the balance. In 2D the position's `z`, and the rotation about other axes than `z`,
/// must be zero.
#[derive(Clone)]
pub struct BodyMotion {
    /// Pose at time `t`.
    pub pose: PoseFn,
    /// Velocity and angular velocity (space axes) at time `t`: the pose's rate.
    pub twist: TwistFn,
}

impl std::fmt::Debug for BodyMotion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BodyMotion").finish_non_exhaustive()
    }
}

/// A sample of a body's wrench port over the last step.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BodyPortSample {
    /// Force input [N] (space axes; the weight is not included); for a prescribed motion
    /// the reaction force the motion needs (output).
    pub force: Vec3,
    /// Torque input [N·m] (space axes); for a prescribed motion the reaction torque.
    pub torque: Vec3,
    /// Output: the mid-step velocity `Δx/h` [m/s].
    pub velocity: Vec3,
    /// Output: the mid-step angular velocity `R_n w/h` [rad/s], space axes.
    pub omega: Vec3,
    /// Mean power over the step `F·v + τ·ω` [W] (positive into the body).
    pub mean_power: f64,
}

/// What the water does to a body (docs/method.md §22), with the network's water (density,
/// gravity, current): the body is taken as fully submerged.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BodyHydro {
    /// Displaced volume [m³] (≥ 0): the buoyancy `ρ_w g V` acts upwards (`z` in 3D, `y` in
    /// 2D) at the centre of buoyancy; its potential is in `Ĥ`.
    pub volume: f64,
    /// Centre of buoyancy in body axes [m], relative to the centre of mass.
    pub centre_of_buoyancy: Vec3,
    /// Drag area `C_d A` [m²] (≥ 0) of the quadratic drag `−½ ρ_w C_d A |v_r| v_r` at the
    /// centre of mass, `v_r` its velocity relative to the current there (MoorDyn's body `CdA`).
    pub cda: f64,
    /// Linear drag coefficient [N·s/m] (≥ 0): the force `−c v_r`.
    pub linear_drag: f64,
    /// Added-mass coefficient `C_a` (≥ 0): the translational added mass `C_a ρ_w V` [kg],
    /// the same in every direction.
    pub ca: f64,
    /// Added moments of inertia about the body axes [kg·m²] (≥ 0), added to the inertia's
    /// diagonal.
    pub added_inertia: Vec3,
    /// The full added-mass matrix `A` in body axes about the centre of mass (translation x,
    /// y, z, then rotation about x, y, z; kg, kg·m, kg·m²), symmetric positive semi-definite,
    /// constant in body axes: the kinetic energy is `½ ξ·(M_RB + A) ξ` with `ξ = (Rᵀ V, Ω)`.
    /// In 2D only its `(x, y, θ_z)` entries (rows and columns 0, 1, 5) count. Not together
    /// with `ca` or `added_inertia` (both must be 0). `None`: no matrix.
    pub added_mass: Option<Mat6>,
    /// Waterplane area `A_w` [m²] (≥ 0) of a floater: the displaced volume is
    /// `V − A_w z_w` with `z_w` the height of the waterline point above the free surface
    /// (`z = 0`), so that besides `ρ_w g V` the heave restoring force `−ρ_w g A_w z_w` acts at
    /// that point, with the potential `½ ρ_w g A_w z_w²` in `Ĥ`. 0: a submerged body.
    pub waterplane_area: f64,
    /// The waterline point in body axes [m] (where `z_w` is measured and the restoring force
    /// acts): the centroid of the waterplane.
    pub waterline: Vec3,
    /// The waterplane's second moments of area about the body's `x` and `y` axes through the
    /// waterline point [m⁴] (≥ 0; in 2D only the first counts, about the out-of-plane axis):
    /// the roll and pitch restoring `ρ_w g I` [N·m/rad] of a floater, beyond the buoyancy's
    /// own (its centre of buoyancy above or below the centre of mass). The area is then
    /// carried at four points of the waterplane (two in 2D) with these moments, each with
    /// its share of the heave term's potential, so the heave restoring is unchanged. Zero:
    /// the heave term alone; without a waterplane area they do nothing.
    pub waterplane_moments: [f64; 2],
}

/// A rigid body of a network.
#[derive(Debug, Clone)]
pub struct RigidBody<const D: usize> {
    /// Name for messages and outputs.
    pub name: String,
    /// Mass [kg] (> 0).
    pub mass: f64,
    /// Inertia tensor about the centre of mass in body axes [kg·m²] (symmetric positive
    /// definite; in 2D only `inertia[(2, 2)]`, the moment about `z`, is used).
    pub inertia: Mat3,
    /// Weight (gravity force) on the body [N], usually `m g`; its potential `−x·W` is in `Ĥ`.
    pub weight: Vector<D>,
    /// The nodes fixed to the body.
    pub attachments: Vec<Attachment<D>>,
    /// Initial state (its angular momentum with the inertia above).
    pub initial: BodyState,
    /// The wrench port's inputs; `None`: no port.
    pub wrench: Option<BodyWrench>,
    /// The water's action (needs the network's water); `None`: none.
    pub hydro: Option<BodyHydro>,
    /// A prescribed motion; `None`: the body moves freely.
    pub motion: Option<BodyMotion>,
    /// A feedback law on the wrench port (PD on the pose, damping injection; docs/method.md
    /// §22), applied besides the port's force and torque signals; `None`: none.
    pub feedback: Option<crate::body_feedback::BodyFeedback>,
}

/// The waterplane points of a floater with heave stiffness `k = ρ_w g A_w` [N/m] (`up` the
/// vertical unit vector): the waterline point alone, or, with second moments, points about it
/// along the body's `x` and `y` axes (two each in 3D, two along `x` in 2D) sharing `k`, placed
/// so that `Σ k_i s_i s_iᵀ` has the moments `ρ_w g I` (their centroid stays the waterline point).
fn waterplane_points<const D: usize>(
    k: f64,
    hydro: &BodyHydro,
    up: Vec3,
) -> Vec<(f64, Vec3, Vec3)> {
    let centre = embed_point::<D>(&hydro.waterline);
    let area = hydro.waterplane_area;
    let [i_x, i_y] = hydro.waterplane_moments;
    if D == 2 {
        if i_x <= 0.0 {
            return vec![(k, centre, up)];
        }
        // Two halves at ±d along x: A d² = I.
        let d = (i_x / area).sqrt();
        return [-d, d]
            .iter()
            .map(|&x| (0.5 * k, centre + Vec3::new(x, 0.0, 0.0), up))
            .collect();
    }
    if i_x <= 0.0 && i_y <= 0.0 {
        return vec![(k, centre, up)];
    }
    // Four quarters at ±d_x along x and ±d_y along y: A d²/2 = I about the other axis.
    let (dx, dy) = ((2.0 * i_y / area).sqrt(), (2.0 * i_x / area).sqrt());
    [
        Vec3::new(dx, 0.0, 0.0),
        Vec3::new(-dx, 0.0, 0.0),
        Vec3::new(0.0, dy, 0.0),
        Vec3::new(0.0, -dy, 0.0),
    ]
    .iter()
    .map(|off| (0.25 * k, centre + off, up))
    .collect()
}

/// `3×3` skew matrix `â` with `â b = a × b`.
pub fn skew(a: &Vec3) -> Mat3 {
    Mat3::new(0.0, -a.z, a.y, a.z, 0.0, -a.x, -a.y, a.x, 0.0)
}

/// The Cayley rotation `cay(w) = (I − ŵ/2)⁻¹(I + ŵ/2)`: a rotation by `2 atan(|w|/2)` about `w`.
pub fn cayley(w: &Vec3) -> Mat3 {
    let wh = skew(w);
    Mat3::identity() + (wh + wh * wh * 0.5) * (4.0 / (4.0 + w.norm_squared()))
}

/// The unit quaternion of [`cayley`]`(w)`.
pub fn cayley_quaternion(w: &Vec3) -> UnitQuaternion<f64> {
    UnitQuaternion::new_normalize(Quaternion::new(1.0, 0.5 * w.x, 0.5 * w.y, 0.5 * w.z))
}

/// The rotation of one step of a body: `R_n`, `cay(w)` and `(I − ŵ/2)⁻¹`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Turn {
    /// `R_n`.
    pub rot: Mat3,
    /// `cay(w)`.
    pub cay: Mat3,
    /// `(I − ŵ/2)⁻¹`.
    pub inv_half: Mat3,
}

/// What a step does to an attachment point `s`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PointStep {
    /// `R_n (cay(w) − I) s` [m]: the point's increment less the centre's.
    pub moved: Vec3,
    /// `s̄ = ½ (I + cay(w)) s` [m], body axes.
    pub mean: Vec3,
    /// `∂(moved)/∂w = −R_n (I − ŵ/2)⁻¹ [s̄×]` [m].
    pub dw: Mat3,
}

impl Turn {
    /// The turn by `w` from orientation `q`.
    pub fn new(q: &UnitQuaternion<f64>, w: &Vec3) -> Self {
        let a = w * 0.5;
        let ah = skew(&a);
        Self {
            rot: *q.to_rotation_matrix().matrix(),
            cay: cayley(w),
            inv_half: Mat3::identity() + (ah + ah * ah) / (1.0 + a.norm_squared()),
        }
    }

    /// The step of the body point `s` (body axes).
    pub fn point(&self, s: &Vec3) -> PointStep {
        let turned = self.cay * s;
        let mean = (s + turned) * 0.5;
        PointStep {
            moved: self.rot * (turned - s),
            mean,
            dw: -(self.rot * self.inv_half * skew(&mean)),
        }
    }
}

/// A body's constants in the form the step uses.
#[derive(Debug, Clone)]
pub(crate) struct BodyModel {
    pub mass: f64,
    /// Inertia used by the step (in 2D `J_zz I`).
    pub inertia: Mat3,
    pub weight: Vec3,
    /// `(node, point in body axes)`.
    pub attachments: Vec<(usize, Vec3)>,
    /// Per attachment, an increment [m] (space axes) its node makes over the current step
    /// beside the body's motion at its point: a winch drum on the body paying out, whose drum
    /// node slides along its path from the drum point (docs/method.md §23, "A drum on a rigid
    /// body"). Empty, or zero for an attachment, where the nodes only move with the body.
    /// Set for every attempt at a step before its solve (the winches' prescribe), zero
    /// between steps; an evaluation outside a step's solve (an error estimate) must set it
    /// first.
    pub offset: Vec<Vec3>,
    /// The wrench port's inputs.
    pub wrench: Option<BodyWrench>,
    /// The body's own mass [kg] (`mass` has the added mass too).
    pub dry_mass: f64,
    /// The body's own inertia tensor about its centre of mass in body axes [kg·m²], as
    /// given (`inertia` has the added inertia too, and in 2D only its `z` moment).
    pub dry_inertia: Mat3,
    /// The buoyancy force [N] (space axes) and its point (body axes).
    pub buoyancy: Option<(Vec3, Vec3)>,
    /// Drag at the centre of mass: linear [N·s/m], quadratic `½ ρ_w C_d A` [kg/m], and the
    /// smoothing speed `δ` [m/s] of `|v_r|`.
    pub drag: Option<(f64, f64, f64)>,
    /// Heave (and roll and pitch) restoring: per waterplane point its stiffness
    /// `ρ_w g A_i` [N/m], the point (body axes) and the vertical unit vector; empty without
    /// a waterplane.
    pub waterplane: Vec<(f64, Vec3, Vec3)>,
    /// The prescribed motion.
    pub motion: Option<BodyMotion>,
    /// The feedback law on the wrench port (in 2D with the out-of-plane gains zeroed).
    pub feedback: Option<crate::body_feedback::BodyFeedback>,
    /// The total mass matrix `𝕄 = M_RB + A` [kg, kg·m, kg·m²] (body axes, about the centre of
    /// mass) of a body whose added mass is not isotropic in translation or couples translation
    /// and rotation: its step takes the Kirchhoff form (`mass` and `inertia` are then only its
    /// scales: the mean translational mass and the rotation block). `None`: `mass`, `inertia`.
    pub kirchhoff: Option<Mat6>,
}

/// The row of an attachment node that a body's equations need: its residual `R_k` [N] and
/// its diagonal Jacobian block `∂R_k/∂Δ_k` [N/m], both in space axes.
#[derive(Debug, Clone, Copy)]
pub(crate) struct NodeRow {
    pub res: Vec3,
    pub diag: Mat3,
}

/// A body's step equations: the residual rows (force [N], then torque [N·m]) and, when asked,
/// their Jacobian against `(Δx, w)`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct BodyRows {
    pub force: Vec3,
    pub torque: Vec3,
    /// `[[∂force/∂Δx, ∂force/∂w], [∂torque/∂Δx, ∂torque/∂w]]`.
    pub jac: [[Mat3; 2]; 2],
}

/// `v` in 3D: `(x, y, 0)` in 2D.
pub(crate) fn embed<const D: usize>(v: &Vector<D>) -> Vec3 {
    let mut out = Vec3::zeros();
    for k in 0..D.min(3) {
        out[k] = v[k];
    }
    out
}

/// A body point in the plane of a `D`-dimensional network (`z = 0` in 2D).
fn embed_point<const D: usize>(p: &Vec3) -> Vec3 {
    if D == 2 { Vec3::new(p.x, p.y, 0.0) } else { *p }
}

/// The first `D` components of `v`.
pub(crate) fn project<const D: usize>(v: &Vec3) -> Vector<D> {
    Vector::<D>::from_fn(|k, _| if k < 3 { v[k] } else { 0.0 })
}

impl BodyModel {
    /// The wrench port's force [N] and torque [N·m] at time `t` [s] (in 2D in the plane: the
    /// force's `z` and the torque's `x`, `y` are dropped); zero without a port.
    pub fn wrench_at<const D: usize>(&self, t: f64) -> (Vec3, Vec3) {
        match &self.wrench {
            None => (Vec3::zeros(), Vec3::zeros()),
            Some(w) => {
                let (f, tau) = ((w.force)(t), (w.torque)(t));
                if D == 2 {
                    (Vec3::new(f.x, f.y, 0.0), Vec3::new(0.0, 0.0, tau.z))
                } else {
                    (f, tau)
                }
            }
        }
    }

    /// Checks body `index` of a network of `n_nodes` nodes and forms its model.
    pub fn new<const D: usize>(
        index: usize,
        body: &RigidBody<D>,
        n_nodes: usize,
        water: Option<&crate::water::Water<D>>,
    ) -> Result<Self, SetupError> {
        let fail = |problem: String| SetupError::Body {
            index,
            name: body.name.clone(),
            problem,
        };
        if D < 2 {
            return Err(fail("rigid bodies need a 2D or 3D network".into()));
        }
        if !(body.mass > 0.0 && body.mass.is_finite()) {
            return Err(fail(format!(
                "mass must be positive and finite, got {} kg",
                body.mass
            )));
        }
        let (hydro, water) = match (&body.hydro, water) {
            (None, _) => (BodyHydro::default(), None),
            (Some(h), Some(w)) => (*h, Some(w)),
            (Some(_), None) => {
                return Err(fail("its hydrodynamics need the network's water".into()));
            }
        };
        for (what, v) in [
            ("volume [m³]", hydro.volume),
            ("drag area CdA [m²]", hydro.cda),
            ("linear drag [N·s/m]", hydro.linear_drag),
            ("added-mass coefficient Ca", hydro.ca),
            ("added inertia x [kg·m²]", hydro.added_inertia.x),
            ("added inertia y [kg·m²]", hydro.added_inertia.y),
            ("added inertia z [kg·m²]", hydro.added_inertia.z),
            ("waterplane area [m²]", hydro.waterplane_area),
            ("waterplane moment x [m⁴]", hydro.waterplane_moments[0]),
            ("waterplane moment y [m⁴]", hydro.waterplane_moments[1]),
        ] {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(fail(format!("{what} must be ≥ 0 and finite, got {v}")));
            }
        }
        if !hydro.centre_of_buoyancy.iter().all(|x| x.is_finite())
            || !hydro.waterline.iter().all(|x| x.is_finite())
        {
            return Err(fail(
                "centre of buoyancy or waterline point is not finite".into(),
            ));
        }
        let rho = water.map_or(0.0, |w| w.density);
        let (added_mass, added, kirchhoff) =
            added::<D>(&hydro, body.mass, &body.inertia, rho).map_err(&fail)?;
        let inertia = if D == 2 {
            Mat3::identity() * (body.inertia[(2, 2)] + added[(2, 2)])
        } else {
            body.inertia + added
        };
        let symmetric = (inertia - inertia.transpose()).abs().max() <= 1e-12 * inertia.abs().max();
        let positive = inertia.iter().all(|x| x.is_finite())
            && symmetric
            && inertia.symmetric_eigenvalues().iter().all(|&l| l > 0.0);
        if !positive {
            return Err(fail(format!(
                "inertia must be symmetric positive definite{}, got {:?} kg·m²",
                if D == 2 {
                    " (in 2D its z moment > 0)"
                } else {
                    ""
                },
                inertia.as_slice()
            )));
        }
        if let Some((gain, value)) = body.feedback.as_ref().and_then(|f| f.bad_gain()) {
            return Err(fail(format!(
                "feedback gain {gain} must be ≥ 0 and finite, got {value}"
            )));
        }
        let st = &body.initial;
        let finite = |v: &Vec3| v.iter().all(|x| x.is_finite());
        if !(finite(&st.position)
            && finite(&st.velocity)
            && finite(&st.omega)
            && st.orientation.coords.iter().all(|x| x.is_finite()))
        {
            return Err(fail("initial state is not finite".into()));
        }
        let q = st.orientation.quaternion();
        if D == 2 && (st.position.z != 0.0 || st.velocity.z != 0.0 || q.i != 0.0 || q.j != 0.0) {
            return Err(fail(
                "a 2D body moves in the plane z = 0 and turns about z only".into(),
            ));
        }
        let mut attachments = Vec::with_capacity(body.attachments.len());
        for a in &body.attachments {
            if a.node >= n_nodes {
                return Err(fail(format!(
                    "attachment node {} is not in the mesh (nodes 0..={})",
                    a.node,
                    n_nodes.saturating_sub(1)
                )));
            }
            if !a.point.iter().all(|x| x.is_finite()) {
                return Err(fail(format!(
                    "attachment point of node {} is not finite",
                    a.node
                )));
            }
            attachments.push((a.node, embed(&a.point)));
        }
        let weight = embed(&body.weight);
        if !finite(&weight) {
            return Err(fail("weight is not finite".into()));
        }
        let up = Vec3::from_fn(|k, _| if k + 1 == D { 1.0 } else { 0.0 });
        let buoyancy = water.filter(|_| hydro.volume > 0.0).map(|w| {
            (
                up * (w.density * w.gravity * hydro.volume),
                embed_point::<D>(&hydro.centre_of_buoyancy),
            )
        });
        let drag = water
            .filter(|_| hydro.cda > 0.0 || hydro.linear_drag > 0.0)
            .map(|w| (hydro.linear_drag, 0.5 * rho * hydro.cda, w.drag_smoothing));
        let waterplane = water
            .filter(|_| hydro.waterplane_area > 0.0)
            .map_or_else(Vec::new, |w| {
                let k = w.density * w.gravity * hydro.waterplane_area;
                waterplane_points::<D>(k, &hydro, up)
            });
        Ok(Self {
            mass: body.mass + added_mass,
            inertia,
            weight,
            attachments,
            offset: Vec::new(),
            wrench: body.wrench.clone(),
            dry_mass: body.mass,
            dry_inertia: body.inertia,
            buoyancy,
            drag,
            waterplane,
            motion: body.motion.clone(),
            feedback: body
                .feedback
                .as_ref()
                .map(|f| if D == 2 { f.planar() } else { f.clone() }),
            kirchhoff,
        })
    }

    /// Kinetic energy `½ m |V|² + ½ Π·J⁻¹Π` [J]; in the Kirchhoff form `½ ξ·𝕄ξ`,
    /// `ξ = (Rᵀ V, Ω)`.
    pub fn kinetic(&self, st: &BodyState) -> f64 {
        if let Some(mm) = &self.kirchhoff {
            let (u, om) = added_mass::body_velocity(st);
            let (p, pi) = added_mass::momenta(mm, st);
            return 0.5 * (u.dot(&p) + om.dot(&pi));
        }
        0.5 * self.mass * st.velocity.norm_squared()
            + 0.5 * st.omega.dot(&(self.inertia * st.omega))
    }

    /// Potential of the weight `−x·W` [J].
    pub fn potential(&self, st: &BodyState) -> f64 {
        -st.position.dot(&self.weight)
    }

    /// The buoyancy's potential `−F_b·(x + R s_b)` and the waterplane's `½ k z_w²` [J].
    pub fn buoyancy_potential(&self, st: &BodyState) -> f64 {
        let point = self.buoyancy.map_or(0.0, |(f, s)| -f.dot(&st.point(&s)));
        let plane: f64 = self
            .waterplane
            .iter()
            .map(|(k, s, up)| {
                let z = st.point(s).dot(up);
                0.5 * k * z * z
            })
            .sum();
        point + plane
    }

    /// The waterplane's restoring point over a step from `st` whose point moves by `moved`
    /// beyond the centre's `dx`: the row `R = −F` that asks the body for its negative, with
    /// `F = −k z̄ e_z` at the mean height `z̄` (the exact discrete gradient of `½ k z²`), and
    /// `∂R/∂Δa = ½ k e_z e_zᵀ`, for waterplane point `i` of [`Self::waterplane`].
    pub fn waterplane_row(&self, i: usize, st: &BodyState, dx: &Vec3, moved: &Vec3) -> NodeRow {
        let (k, s, up) = self.waterplane[i];
        let z0 = st.point(&s).dot(&up);
        let z_mean = z0 + 0.5 * (dx + moved).dot(&up);
        NodeRow {
            res: up * (k * z_mean),
            diag: up * up.transpose() * (0.5 * k),
        }
    }

    /// The drag at the centre of mass over a step of `h` [s] with increment `dx` [m], in a
    /// current `u` [m/s] with vertical derivative `du_dz` [1/s] (`up` the vertical unit vector)
    /// at the mid-step position: the force [N] at the mid-step relative velocity
    /// `v_r = Δx/h − u`, its derivative by `Δx`, and the work split (dissipated
    /// `h (c + c_q|v_r|)|v_r|² ≥ 0` [J], supplied by the current `h F·u` [J]). Zero without drag.
    pub fn drag_step(
        &self,
        h: f64,
        dx: &Vec3,
        (u, du_dz, up): (&Vec3, &Vec3, &Vec3),
    ) -> (Vec3, Mat3, f64, f64) {
        let Some((lin, quad, delta)) = self.drag else {
            return (Vec3::zeros(), Mat3::zeros(), 0.0, 0.0);
        };
        let vr = dx / h - u;
        let speed = (vr.norm_squared() + delta * delta).sqrt();
        let c = lin + quad * speed;
        let force = -vr * c;
        // ∂v_r/∂Δx = I/h − ½ (du/dz) upᵀ (the current at the mid height).
        let dvr = Mat3::identity() / h - du_dz * up.transpose() * 0.5;
        let dforce = -(Mat3::identity() * c + vr * vr.transpose() * (quad / speed)) * dvr;
        (force, dforce, h * c * vr.norm_squared(), h * force.dot(u))
    }

    /// The radius of gyration `√(tr J / m)` [m] (> 0 for a valid body): the length that
    /// turns the body's torque row into a force in Newton's norm.
    pub fn gyration(&self) -> f64 {
        (self.inertia.trace() / self.mass).sqrt()
    }

    /// Angular momentum about the centre of mass in body axes `Π = J Ω` [kg·m²/s]; in the
    /// Kirchhoff form the rotation rows of `𝕄 ξ` (the Kirchhoff angular impulse).
    pub fn momentum(&self, st: &BodyState) -> Vec3 {
        match &self.kirchhoff {
            Some(mm) => added_mass::momenta(mm, st).1,
            None => self.inertia * st.omega,
        }
    }

    /// The mass matrix at rest in the orientation `rot` (`R₀`) on the centre's displacement
    /// (space axes) and the Cayley vector `w` (body axes), blocks
    /// `[[R₀ 𝕄_tt R₀ᵀ, R₀ 𝕄_tr], [𝕄_rt R₀ᵀ, 𝕄_rr]]` [kg, kg·m, kg·m²]: `[[m I, 0], [0, J]]`
    /// without an added-mass matrix (the kinetic energy `½ ξ·𝕄ξ` with `ξ = (R₀ᵀ ẋ, ẇ)`).
    pub fn rest_mass(&self, rot: &Mat3) -> [[Mat3; 2]; 2] {
        match &self.kirchhoff {
            Some(mm) => {
                let [[tt, tr], [rt, rr]] = added_mass::blocks(mm);
                let rt_t = rot.transpose();
                [[rot * tt * rt_t, rot * tr], [rt * rt_t, rr]]
            }
            None => [
                [Mat3::identity() * self.mass, Mat3::zeros()],
                [Mat3::zeros(), self.inertia],
            ],
        }
    }

    /// Linear momentum in space axes `m V` [kg·m/s]; in the Kirchhoff form `R P`, `P` the
    /// translation rows of `𝕄 ξ` (the Kirchhoff impulse).
    pub fn linear_momentum(&self, st: &BodyState) -> Vec3 {
        match &self.kirchhoff {
            Some(mm) => st
                .orientation
                .transform_vector(&added_mass::momenta(mm, st).0),
            None => st.velocity * self.mass,
        }
    }

    /// The state after a step of size `h` [s] with increment `dx` [m] and Cayley vector `w`.
    pub fn advance(&self, st: &BodyState, h: f64, dx: &Vec3, w: &Vec3) -> BodyState {
        let inv_h = 1.0 / h;
        // Renormalized: the unit product's norm would random-walk at round-off.
        let orientation = UnitQuaternion::new_normalize(
            st.orientation.into_inner() * cayley_quaternion(w).into_inner(),
        );
        let velocity = match &self.kirchhoff {
            // The body-axes velocity's midpoint rule (docs/method.md eq. (22.8)).
            Some(_) => {
                let turn = Turn::new(&st.orientation, w);
                added_mass::next_velocity(st, h, (&turn, &orientation), dx, w)
            }
            None => dx * (2.0 * inv_h) - st.velocity,
        };
        BodyState {
            position: st.position + dx,
            velocity,
            orientation,
            omega: w * (2.0 * inv_h) - st.omega,
        }
    }

    /// The inertia part of the step rows (force [N] in space axes, torque [N·m] in the body
    /// axes of `R_n`) for a step of `h` [s] from `st` with unknowns `dx` [m], `w` and its turn
    /// `turn`, and their Jacobian: `m (V_{n+1} − V_n)/h` and
    /// `(Π_{n+1} − Π_n)/h + Ω_{n+½} × Π_{n+½}`, or the Kirchhoff form (docs/method.md
    /// eq. (22.9)).
    pub fn inertia_rows(
        &self,
        st: &BodyState,
        h: f64,
        (dx, w): (&Vec3, &Vec3),
        turn: &Turn,
    ) -> (Vec3, Vec3, [[Mat3; 2]; 2]) {
        if let Some(mm) = &self.kirchhoff {
            return added_mass::inertia_rows(mm, st, h, (dx, w), turn);
        }
        let inv_h = 1.0 / h;
        let f = (dx * inv_h - st.velocity) * (2.0 * inv_h * self.mass);
        let pm = self.inertia * w * inv_h;
        let t = (pm - self.momentum(st)) * (2.0 * inv_h) + (w * inv_h).cross(&pm);
        let mut jac = [[Mat3::zeros(); 2]; 2];
        jac[0][0] = Mat3::identity() * (2.0 * inv_h * inv_h * self.mass);
        jac[1][1] = self.inertia * (2.0 * inv_h * inv_h)
            + (skew(w) * self.inertia - skew(&(self.inertia * w))) * (inv_h * inv_h);
        (f, t, jac)
    }

    /// The step equations of a step of size `h` [s] from `st` with unknowns `dx` [m], `w`,
    /// the turn `turn` of `w`, the attachment rows `rows` with their point steps `points`
    /// (same order as `attachments`), the applied force `force` [N] (weight included) and the
    /// applied torque `torque` [N·m] in space axes; `dw_rows[k]` receives `∂torque/∂R_k`
    /// (`∂force/∂R_k` is the identity).
    #[allow(clippy::too_many_arguments)]
    pub fn rows(
        &self,
        st: &BodyState,
        h: f64,
        (dx, w): (&Vec3, &Vec3),
        turn: &Turn,
        rows: &[NodeRow],
        points: &[PointStep],
        (force, torque): (&Vec3, &Vec3),
        dw_rows: &mut [Mat3],
    ) -> BodyRows {
        let eye = Mat3::identity();
        let rt = turn.rot.transpose();
        // Force: m (V_{n+1} − V_n)/h − F + Σ R_k.
        let (f_in, t_in, mut jac) = self.inertia_rows(st, h, (dx, w), turn);
        let mut f = f_in - force;
        // τ̃ = Σ s̄_k × (R_nᵀ(−R_k)) + R_nᵀ τ: the torque in body axes.
        let mut tau = rt * torque;
        for (row, p) in rows.iter().zip(points) {
            f += row.res;
            tau -= p.mean.cross(&(rt * row.res));
        }
        // Torque: (Π_{n+1} − Π_n)/h + Ω×Π_{n+½} − (I − ½ŵ) τ̃.
        let half = eye - skew(w) * 0.5;
        let t = t_in - half * tau;
        jac[1][1] -= skew(&tau) * 0.5;
        for (k, (row, p)) in rows.iter().zip(points).enumerate() {
            // ∂torque/∂R_k = (I − ½ŵ) [s̄×] R_nᵀ.
            let wk = half * skew(&p.mean) * rt;
            dw_rows[k] = wk;
            let da = [eye, p.dw];
            for (c, dc) in da.iter().enumerate() {
                let jd = row.diag * dc;
                jac[0][c] += jd;
                jac[1][c] += wk * jd;
            }
            // s̄_k depends on w: ∂τ̃/∂w ∋ ½ [g_k×] R_nᵀ ∂(moved)/∂w, g_k = R_nᵀ R_k.
            let g = rt * row.res;
            jac[1][1] -= half * skew(&g) * rt * p.dw * 0.5;
        }
        BodyRows {
            force: f,
            torque: t,
            jac,
        }
    }
}

/// A body's added mass from `hydro`, for a body of mass `m` [kg] and inertia `j` [kg·m²]
/// (body axes) in water of density `rho` [kg/m³]: the added mass on its translation [kg], its
/// added inertia [kg·m²] (body axes; in 2D its `z` moment) and, for an added-mass matrix that
/// is not isotropic in translation or couples translation and rotation, the body's total mass
/// matrix of the Kirchhoff form (the first two are then its scales: the mean of the
/// translational diagonal, the rotation block).
fn added<const D: usize>(
    hydro: &BodyHydro,
    m: f64,
    j: &Mat3,
    rho: f64,
) -> Result<(f64, Mat3, Option<Mat6>), String> {
    let Some(a) = hydro.added_mass else {
        let ai = Mat3::from_diagonal(&hydro.added_inertia);
        return Ok((hydro.ca * rho * hydro.volume, ai, None));
    };
    if hydro.ca != 0.0 || hydro.added_inertia != Vec3::zeros() {
        return Err(format!(
            "an added-mass matrix is not taken together with Ca ({}) or added inertia ({:?} \
             kg·m²): give them in the matrix",
            hydro.ca,
            hydro.added_inertia.as_slice()
        ));
    }
    let idx: Vec<usize> = if D == 2 {
        added_mass::PLANE.to_vec()
    } else {
        (0..6).collect()
    };
    let n = idx.len();
    check_added_mass(&nalgebra::DMatrix::from_fn(n, n, |r, c| {
        a[(idx[r], idx[c])]
    }))?;
    Ok(added_mass::total::<D>(&a, m, j))
}

/// Checks a body's prescribed motion against its initial state `st` (pose and rate at
/// `t = 0`, within 1e-9 of their scale) and refuses a wrench port beside it.
fn check_motion<const D: usize>(
    fail: &dyn Fn(String) -> SetupError,
    body: &RigidBody<D>,
    st: &BodyState,
) -> Result<(), SetupError> {
    let Some(m) = &body.motion else {
        return Ok(());
    };
    if body.feedback.is_some() {
        return Err(fail(
            "a body with a prescribed motion takes no feedback law (its port is the motion)".into(),
        ));
    }
    if body.wrench.is_some() {
        return Err(fail(
            "a body with a prescribed motion takes no wrench port (its port is the motion)".into(),
        ));
    }
    let ((x, q), (v, omega)) = ((m.pose)(0.0), (m.twist)(0.0));
    let off = (x - st.position).norm() + q.angle_to(&st.orientation) * (1.0 + x.norm());
    let slip = (v - st.velocity).norm() + (omega - st.omega_space()).norm() * (1.0 + x.norm());
    let scale = 1.0 + st.position.norm() + st.velocity.norm() + st.omega.norm();
    if !(off <= 1e-9 * scale && slip <= 1e-9 * scale) {
        return Err(fail(format!(
            "its prescribed motion does not start at its initial state: pose {off:e}, rate \
             {slip:e} off at t = 0"
        )));
    }
    Ok(())
}

/// A network's bodies in the form the system keeps them.
#[derive(Debug, Clone, Default)]
pub(crate) struct Rigid {
    pub models: Vec<BodyModel>,
    pub names: Vec<String>,
    /// Per body and attachment: `(element, other node, the attached node is its first)`.
    pub links: Vec<Vec<Vec<(usize, usize, bool)>>>,
    /// Per node, the body and attachment it is fixed to (empty without bodies).
    pub attached: Vec<Option<(usize, usize)>>,
    /// The bodies' initial states.
    pub states: Vec<BodyState>,
}

/// Checks the bodies of a network with nodes at `r` [m] moving at `v` [m/s] and forms their
/// models; the attached nodes' components become non-free (`free`): the bodies move them.
#[allow(clippy::too_many_arguments)]
pub(crate) fn attach_bodies<const D: usize>(
    bodies: &[RigidBody<D>],
    mesh: &Mesh,
    boundary: &Boundary<D>,
    water: Option<&crate::water::Water<D>>,
    free: &mut [[bool; D]],
    r: &[Vector<D>],
    v: &[Vector<D>],
) -> Result<Rigid, SetupError> {
    let mut out = Rigid::default();
    if bodies.is_empty() {
        return Ok(out);
    }
    let n = mesh.n_nodes();
    out.attached = vec![None; n];
    let mut ported = vec![false; n];
    for i in boundary.fixed.iter().map(|f| f.node) {
        ported[i] |= i < n;
    }
    for i in boundary.motions.iter().map(|m| m.node) {
        ported[i.min(n - 1)] |= i < n;
    }
    for i in boundary.feedback.iter().map(|f| f.node) {
        ported[i.min(n - 1)] |= i < n;
    }
    for (b, body) in bodies.iter().enumerate() {
        let model = BodyModel::new(b, body, n, water)?;
        let fail = |problem: String| SetupError::Body {
            index: b,
            name: body.name.clone(),
            problem,
        };
        let mut st = body.initial;
        if D == 2 {
            // A plane body spins about z only.
            st.omega = Vec3::new(0.0, 0.0, st.omega.z);
        }
        let omega = st.omega_space();
        let mut links = Vec::with_capacity(model.attachments.len());
        for (k, &(node, s)) in model.attachments.iter().enumerate() {
            if let Some((other, _)) = out.attached[node] {
                return Err(fail(format!(
                    "node {node} is already fixed to body {other}: a node is fixed to one body"
                )));
            }
            if ported[node] {
                return Err(fail(format!(
                    "node {node} is a support, a moving support or a feedback port: a node fixed \
                     to a body is moved by the body alone"
                )));
            }
            check_point(&fail, node, &s, &st, omega, (&r[node], &v[node]))?;
            out.attached[node] = Some((b, k));
            free[node] = [false; D];
            let at: Vec<(usize, usize, bool)> = mesh
                .elements()
                .iter()
                .enumerate()
                .filter_map(|(e, &[a, c])| {
                    (a == node)
                        .then_some((e, c, true))
                        .or((c == node).then_some((e, a, false)))
                })
                .collect();
            links.push(at);
        }
        check_motion::<D>(&fail, body, &st)?;
        out.states.push(st);
        out.models.push(model);
        out.names.push(body.name.clone());
        out.links.push(links);
    }
    Ok(out)
}

/// Checks that a node at `r` [m] moving at `v` [m/s] sits at the body point `s` (body axes)
/// of a body in state `st` turning at `omega` [rad/s] (space axes) and moves with it; `fail`
/// forms the error.
fn check_point<const D: usize>(
    fail: &dyn Fn(String) -> SetupError,
    node: usize,
    s: &Vec3,
    st: &BodyState,
    omega: Vec3,
    (r, v): (&Vector<D>, &Vector<D>),
) -> Result<(), SetupError> {
    let arm = st.orientation.transform_vector(s);
    let off = (embed(r) - st.position - arm).norm();
    let scale = 1.0 + st.position.norm() + s.norm();
    if off.is_nan() || off > 1e-9 * scale {
        return Err(fail(format!(
            "node {node} is {off:e} m from its attachment point {:?} (body axes): the node \
             must start at the point",
            s.as_slice()
        )));
    }
    let slip = (embed(v) - st.velocity - omega.cross(&arm)).norm();
    let vscale = 1.0 + st.velocity.norm() + omega.norm() * s.norm();
    if slip.is_nan() || slip > 1e-9 * vscale {
        return Err(fail(format!(
            "node {node} moves {slip:e} m/s off its attachment point's velocity: the node \
             must start with the body's motion"
        )));
    }
    Ok(())
}

/// Checks that the bodies' states `states` (one per body of `models`, named `names`) carry
/// their attached nodes: each such node of positions `r` [m] and velocities `v` [m/s] at its
/// body point and moving with it (a state handed to a simulation, e.g. an equilibrium's). A
/// winch's drum node on a body (`drum(node)`) slides along its path from the body point: the
/// winch checks it.
pub(crate) fn check_attached<const D: usize>(
    models: &[BodyModel],
    names: &[String],
    states: &[BodyState],
    (r, v): (&[Vector<D>], &[Vector<D>]),
    drum: impl Fn(usize) -> bool,
) -> Result<(), SetupError> {
    for (b, ((model, name), st)) in models.iter().zip(names).zip(states).enumerate() {
        let fail = |problem: String| SetupError::Body {
            index: b,
            name: name.clone(),
            problem,
        };
        let omega = st.omega_space();
        for (node, s) in &model.attachments {
            let (Some(rn), Some(vn)) = (r.get(*node), v.get(*node)) else {
                return Err(fail(format!("attachment node {node} is not in the state")));
            };
            if !drum(*node) {
                check_point(&fail, *node, s, st, omega, (rn, vn))?;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    //! The body's step equations against finite differences, and a free body stepped alone:
    //! exact energy and angular momentum, the symmetric top's precession, the
    //! intermediate-axis flip.

    use super::*;
    use nalgebra::{SMatrix, SVector};

    /// A body of 2 t, a 2 m × 1 m × 0.5 m box (principal moments 208, 708, 833 kg·m²), in
    /// gravity.
    pub(super) fn box_body() -> BodyModel {
        let inertia = Mat3::from_diagonal(&Vec3::new(208.3, 708.3, 833.3));
        BodyModel {
            mass: 2000.0,
            inertia,
            weight: Vec3::new(0.0, 0.0, -2000.0 * 9.81),
            attachments: vec![],
            offset: Vec::new(),
            wrench: None,
            dry_mass: 2000.0,
            dry_inertia: inertia,
            buoyancy: None,
            drag: None,
            waterplane: Vec::new(),
            motion: None,
            feedback: None,
            kirchhoff: None,
        }
    }

    /// An attachment at body point `s` whose node residual is `R_k = K Δa_k + r`.
    pub(super) type Spring = (Vec3, Mat3, Vec3);

    /// The body's rows at `u = (Δx, w)` with attachments `springs` and a space torque
    /// `torque` [N·m].
    pub(super) fn rows_at(
        body: &BodyModel,
        st: &BodyState,
        h: f64,
        u: &SVector<f64, 6>,
        springs: &[Spring],
        torque: &Vec3,
    ) -> (SVector<f64, 6>, SMatrix<f64, 6, 6>) {
        let dx = Vec3::new(u[0], u[1], u[2]);
        let w = Vec3::new(u[3], u[4], u[5]);
        let turn = Turn::new(&st.orientation, &w);
        let points: Vec<PointStep> = springs.iter().map(|(s, _, _)| turn.point(s)).collect();
        let rows: Vec<NodeRow> = springs
            .iter()
            .zip(&points)
            .map(|((_, k, r), p)| NodeRow {
                res: k * (dx + p.moved) + r,
                diag: *k,
            })
            .collect();
        let mut dw = vec![Mat3::zeros(); springs.len()];
        let applied = (&body.weight, torque);
        let out = body.rows(st, h, (&dx, &w), &turn, &rows, &points, applied, &mut dw);
        let mut res = SVector::<f64, 6>::zeros();
        res.fixed_rows_mut::<3>(0).copy_from(&out.force);
        res.fixed_rows_mut::<3>(3).copy_from(&out.torque);
        let mut jac = SMatrix::<f64, 6, 6>::zeros();
        for r in 0..2 {
            for c in 0..2 {
                jac.fixed_view_mut::<3, 3>(3 * r, 3 * c)
                    .copy_from(&out.jac[r][c]);
            }
        }
        (res, jac)
    }

    pub(super) fn spinning(omega: Vec3) -> BodyState {
        let q = UnitQuaternion::from_euler_angles(0.3, -0.7, 1.1);
        let (x, v) = (Vec3::new(1.0, 2.0, -3.0), Vec3::new(0.5, -0.2, 0.1));
        BodyState::new(x, v, q, omega)
    }

    /// The springs and torque of the Jacobian checks: two points at `arms` (body axes) on
    /// anisotropic springs with forces, and a torque [N·m].
    pub(super) fn jacobian_loads(arms: [Vec3; 2]) -> ([Spring; 2], Vec3) {
        let k1 = Mat3::new(3e5, 1e4, 0.0, 2e4, 2e5, -1e4, 0.0, 3e4, 4e5);
        let springs = [
            (arms[0], k1, Vec3::new(-1e4, 2e3, 5e4)),
            (arms[1], Mat3::identity() * 1e5, Vec3::new(3e3, -4e4, 1e4)),
        ];
        (springs, Vec3::new(300.0, -200.0, 100.0))
    }

    /// Asserts that the Jacobian of `body`'s step rows from `st` over `h` [s] at the slots
    /// `u` (with `springs` and `torque`) equals their central differences, column by column.
    pub(super) fn assert_rows_jacobian(
        body: &BodyModel,
        st: &BodyState,
        h: f64,
        u: &SVector<f64, 6>,
        (springs, torque): (&[Spring], &Vec3),
    ) {
        let (_, jac) = rows_at(body, st, h, u, springs, torque);
        let eps = 1e-6;
        for c in 0..6 {
            let (mut up, mut dn) = (*u, *u);
            up[c] += eps;
            dn[c] -= eps;
            let fd = (rows_at(body, st, h, &up, springs, torque).0
                - rows_at(body, st, h, &dn, springs, torque).0)
                / (2.0 * eps);
            let err = (fd - jac.column(c)).norm();
            // Central differences: truncation O(eps²), rounding ~ε|R|/eps ≈ 1e-10·1e6.
            assert!(
                err <= 1e-5 * fd.norm().max(1.0),
                "column {c}: fd {fd} vs {}",
                jac.column(c)
            );
        }
    }

    #[test]
    fn body_jacobian_matches_finite_differences() {
        let body = box_body();
        let st = spinning(Vec3::new(0.4, -1.3, 0.8));
        let (springs, torque) =
            jacobian_loads([Vec3::new(1.0, 0.5, -0.25), Vec3::new(-1.0, -0.5, 0.25)]);
        let u = SVector::<f64, 6>::from_column_slice(&[0.004, -0.002, 0.001, 0.05, -0.08, 0.03]);
        assert_rows_jacobian(&body, &st, 0.01, &u, (&springs, &torque));
    }

    /// Steps a free body (no attachments, no torque) by `h` [s]: Newton on `(Δx, w)` to a
    /// residual of 1e-13 of the momenta's rate `(m|V| + |Π|)/h` (and the weight), then one
    /// more iteration, which takes the residual to round-off (the balances hold to the
    /// residual).
    pub(super) fn step_free(body: &BodyModel, st: &BodyState, h: f64) -> BodyState {
        let mut u = SVector::<f64, 6>::zeros();
        u.fixed_rows_mut::<3>(0).copy_from(&(st.velocity * h));
        u.fixed_rows_mut::<3>(3).copy_from(&(st.omega * h));
        let zero = Vec3::zeros();
        let scale =
            (body.mass * st.velocity.norm() + body.momentum(st).norm()) / h + body.weight.norm();
        for _ in 0..30 {
            let (res, jac) = rows_at(body, st, h, &u, &[], &zero);
            let converged = res.norm() <= 1e-13 * scale;
            u -= jac.lu().solve(&res).unwrap();
            if converged {
                let dx = Vec3::new(u[0], u[1], u[2]);
                let w = Vec3::new(u[3], u[4], u[5]);
                return body.advance(st, h, &dx, &w);
            }
        }
        panic!("no convergence");
    }

    pub(super) fn angular_momentum(body: &BodyModel, st: &BodyState) -> Vec3 {
        let orbital = st.position.cross(&body.linear_momentum(st));
        orbital + st.orientation.transform_vector(&body.momentum(st))
    }

    /// A torque-free symmetric top (moments 400, 400, 833 kg·m², 2 t, no weight) over 1e5
    /// steps of 1 ms: its figure axis precesses about the angular momentum `L` at
    /// `|L|/I₁` (closed form), energy and `L` stay constant to round-off (measured: energy
    /// within 1e-12, `L` drifts 2.4e-12 relative, 2.4e-17 per step).
    #[test]
    fn symmetric_top_precesses_at_the_closed_form_rate() {
        let inertia = Mat3::from_diagonal(&Vec3::new(400.0, 400.0, 833.0));
        let body = BodyModel {
            inertia,
            weight: Vec3::zeros(),
            ..box_body()
        };
        let mut st = BodyState::new(
            Vec3::zeros(),
            Vec3::new(0.3, 0.0, -0.1),
            UnitQuaternion::identity(),
            Vec3::new(0.8, 0.0, 2.5),
        );
        let (l0, e0) = (angular_momentum(&body, &st), body.kinetic(&st));
        let axis = l0.normalize();
        // The figure axis's angle about L, unwrapped.
        let angle = |st: &BodyState| {
            let e3 = st.orientation.transform_vector(&Vec3::z());
            let p = e3 - axis * axis.dot(&e3);
            let u = Vec3::x().cross(&axis).normalize();
            let v = axis.cross(&u);
            p.dot(&v).atan2(p.dot(&u))
        };
        let (h, n) = (1e-3, 100_000);
        let (mut turned, mut last) = (0.0, angle(&st));
        let (mut de, mut dl) = (0.0f64, 0.0f64);
        for _ in 0..n {
            st = step_free(&body, &st, h);
            let a = angle(&st);
            let d = (a - last + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI)
                - std::f64::consts::PI;
            turned += d;
            last = a;
            de = de.max((body.kinetic(&st) - e0).abs() / e0);
            dl = dl.max((angular_momentum(&body, &st) - l0).norm() / l0.norm());
        }
        let exact = l0.norm() / 400.0 * (h * n as f64);
        // Second-order scheme: relative error ~ (h |L|/I₁)² ≈ 4e-6 at most.
        assert!(
            (turned / exact - 1.0).abs() < 1e-5,
            "precession {turned} vs {exact}"
        );
        // Round-off: less than one ulp of drift per step on average (1e5 ε = 2.2e-11).
        let ulp_per_step = n as f64 * f64::EPSILON;
        assert!(de < ulp_per_step, "energy drift {de}");
        assert!(dl < ulp_per_step, "angular momentum drift {dl}");
    }

    /// The intermediate-axis (Dzhanibekov) flip: a spin about the middle axis of the box
    /// (2 rad/s, perturbed by 1e-3 rad/s) reverses within 60 s, and the energy stays constant
    /// through the flip.
    #[test]
    fn intermediate_axis_flips_with_constant_energy() {
        let body = BodyModel {
            weight: Vec3::zeros(),
            ..box_body()
        };
        let omega = Vec3::new(1e-3, 2.0, 1e-3);
        let mut st = BodyState::new(
            Vec3::zeros(),
            Vec3::zeros(),
            UnitQuaternion::identity(),
            omega,
        );
        let e0 = body.kinetic(&st);
        let (h, mut flipped, mut de) = (2e-3, false, 0.0f64);
        for _ in 0..30_000 {
            st = step_free(&body, &st, h);
            flipped |= st.omega.y < -1.9;
            de = de.max((body.kinetic(&st) - e0).abs() / e0);
        }
        assert!(flipped, "no flip: Ω = {}", st.omega);
        assert!(de < 1e-12, "energy drift {de}");
    }
}
