//! Time discretization: discrete gradient (DG) and implicit midpoint (MP) (docs/method.md §5,
//! §7, §8; paper eqs. (33)–(36)).
//!
//! Both schemes solve, per step, for the position increment `Δ = r_{n+1} − r_n`; velocities
//! and strains are eliminated exactly: `v_{n+1} = 2Δ/h − v_n` and
//! `C_{e,n+1} = C_{e,n} + (r'_{n+1} + r'_n)·(r'_{n+1} − r'_n)` (paper Remark 5). The
//! remaining momentum balance, divided by `h`, is the Newton residual [N]:
//!
//! `R(Δ) = M_ρ (v_{n+1} − v_n)/h − F_b + K(r_{n+½}) S̄ − F_N(t_{n+½})`,
//!
//! plus, with dissipation and feedback (docs/method.md §18), the Kelvin–Voigt stress
//! `η ΔC/h` in `S̄`, the drag `c M_c Δ/h`, the dashpots `c (Δ_b − Δ_a)/h` and the feedback
//! forces `−F(t_{n+½}, r_{n+½}, Δ/h)`.

use nalgebra::SMatrix;

use crate::linsolve::BlockJacobian;
use crate::material::StoredEnergy;
use crate::newton::NewtonProblem;
use crate::system::{Damping, Law, MassMatrix, PhSystem, Vector, element_mass};
use crate::water::{ElementMotion, WaterModel, WaterWork, WetElement};

/// The part of a residual evaluation that one element group takes.
struct ElementKernel {
    mass: MassMatrix,
    rho_a: f64,
    /// Elements of the group to evaluate.
    els: std::ops::Range<usize>,
    /// Whether all rows are evaluated.
    full: bool,
    /// Rows evaluated when not `full`.
    nodes: std::ops::Range<usize>,
    /// The group's dissipation.
    damping: Damping,
}

/// Where an element loop adds its terms: the residual, the Jacobian (if wanted), the squares
/// of its force and strain scales, and the water's work.
type ElementOut<'a, const D: usize> = (
    &'a mut [Vector<D>],
    Option<&'a mut BlockJacobian<D>>,
    (&'a mut f64, &'a mut f64),
    &'a mut WaterWork,
);

/// Time-stepping scheme: how the stress `S̄` of a step is formed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Scheme {
    /// Discrete gradient: `S̄ = 2 (W(C₁) − W(C₀))/(C₁ − C₀)` (Greenspan); exact energy balance.
    #[default]
    DiscreteGradient,
    /// Implicit midpoint: `S̄ = 2 W'((C₀ + C₁)/2)`.
    Midpoint,
    /// Fourth order: the triple-jump composition of three discrete-gradient sub-steps
    /// `γ₁h, γ₂h, γ₁h` with `γ₁ = 1/(2 − 2^{1/3})`, `γ₂ = 1 − 2γ₁` (docs/method.md §19). Each
    /// sub-step balances energy exactly, so the step does.
    DiscreteGradient4,
}

/// The triple-jump weights `[γ₁, γ₂, γ₁]` (`γ₁ = 1/(2 − 2^{1/3})`, `γ₂ = 1 − 2γ₁ < 0`).
pub fn triple_jump() -> [f64; 3] {
    let g1 = 1.0 / (2.0 - 2f64.cbrt());
    [g1, 1.0 - 2.0 * g1, g1]
}

/// A node's damped seabed contact as the backward sub-step of `dg4` sees it
/// (docs/method.md §19, "Stiff damping and the backward sub-step"): the range of masses
/// `[m_lo, m_hi]` [kg] its normal motion can have (the mass-matrix row `Σ (m_d ∓ |m_o|)`
/// plus point masses: neighbours moving against it, with it), the contact damping
/// `c = c_bed d L` [N·s/m] and stiffness `k = k_bed d L` [N/m] in full contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct DampedContact {
    /// Smallest effective mass [kg].
    pub mass_lo: f64,
    /// Largest effective mass [kg].
    pub mass_hi: f64,
    /// Contact damping [N·s/m].
    pub damping: f64,
    /// Contact stiffness [N/m].
    pub stiffness: f64,
}

/// The damped seabed contacts of `sys`: one per wet node whose contact has damping.
pub(crate) fn damped_contacts<const D: usize, M: StoredEnergy>(
    sys: &PhSystem<D, M>,
) -> Vec<DampedContact> {
    let Some(w) = sys.water.as_deref() else {
        return Vec::new();
    };
    if w.bed.is_none() {
        return Vec::new();
    }
    let mut mass = vec![(0.0, 0.0); sys.mesh.n_nodes()];
    for (g, _, [a, b], l) in sys.each_element() {
        let (md, mo) = element_mass(g.mass, g.rho_a, l);
        for i in [a, b] {
            mass[i].0 += md - mo.abs();
            mass[i].1 += md + mo.abs();
        }
    }
    for &(i, m) in &sys.point_mass {
        mass[i].0 += m;
        mass[i].1 += m;
    }
    w.nodes
        .iter()
        .filter(|n| n.damping > 0.0 && n.stiffness > 0.0)
        .map(|n| DampedContact {
            mass_lo: mass[n.node].0,
            mass_hi: mass[n.node].1,
            damping: n.damping,
            stiffness: n.stiffness,
        })
        .collect()
}

/// Most triple jumps [`compositions`] splits a `dg4` step into.
pub(crate) const MAX_COMPOSITIONS: usize = 64;

/// The number `n` of triple jumps (19.1) of step `h/n` that a `dg4` step of `h` [s] is made
/// of (docs/method.md §19, eq. (19.4)): the smallest `n` for which the backward sub-step
/// `s = |γ₂| h/n` keeps the Newton pivot `(2m − c s + k s²)/s²` of every damped contact and
/// every mass `m` in its range at least half the mass term `2m/s²` away from zero,
/// `|2m − c s + k s²| ≥ m`: that is, no mass in `(q/3, q)`, `q = c s − k s²`. Where the pivot
/// is zero the backward sub-step (whose damping counts negatively) is singular and the
/// composition amplifies the contact's motion without bound. 1 without damped contacts;
/// at most [`MAX_COMPOSITIONS`].
pub(crate) fn compositions(contacts: &[DampedContact], h: f64) -> usize {
    let g2 = triple_jump()[1].abs();
    let clear = |n: usize| {
        let s = g2 * h.abs() / n as f64;
        contacts.iter().all(|c| {
            let q = c.damping * s - c.stiffness * s * s;
            c.mass_lo >= q || 3.0 * c.mass_hi <= q
        })
    };
    (1..MAX_COMPOSITIONS)
        .find(|&n| clear(n))
        .unwrap_or(MAX_COMPOSITIONS)
}

impl Scheme {
    /// `(S̄/2, ∂(S̄/2)/∂C₁)` for an element going from strain `c0` to `c1`.
    #[inline]
    pub fn half_stress<M: StoredEnergy>(self, material: &M, c0: f64, c1: f64) -> (f64, f64) {
        match self {
            Scheme::DiscreteGradient | Scheme::DiscreteGradient4 => material.quotient(c0, c1),
            Scheme::Midpoint => {
                let m = 0.5 * (c0 + c1);
                (material.dw(m), 0.5 * material.d2w(m))
            }
        }
    }
    /// Short name: `dg`, `mp` or `dg4`.
    pub fn name(self) -> &'static str {
        match self {
            Scheme::DiscreteGradient => "dg",
            Scheme::Midpoint => "mp",
            Scheme::DiscreteGradient4 => "dg4",
        }
    }
    /// Order of accuracy in `h`: 2, or 4 for [`Scheme::DiscreteGradient4`].
    pub fn order(self) -> u32 {
        match self {
            Scheme::DiscreteGradient4 => 4,
            _ => 2,
        }
    }
}

/// Element kinematics of a step from the increments: `(r'_{n+½}, r'_{n+1} − r'_n, ΔC)`.
#[inline]
pub(crate) fn element_step<const D: usize>(
    r0a: &Vector<D>,
    r0b: &Vector<D>,
    xa: &Vector<D>,
    xb: &Vector<D>,
    l: f64,
) -> (Vector<D>, Vector<D>, f64) {
    let inv_l = 1.0 / l;
    let dr = (xb - xa) * inv_l;
    let rpm = (r0b - r0a) * inv_l + dr * 0.5;
    let dc = 2.0 * rpm.dot(&dr);
    (rpm, dr, dc)
}

/// A strain outside the material's domain, met while evaluating the step residual.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrainError {
    /// Element index.
    pub element: usize,
    /// Strain value.
    pub c: f64,
}

/// The step equations of one time step, as a Newton problem in `Δ`.
pub(crate) struct StepEquations<'a, const D: usize, M> {
    pub sys: &'a PhSystem<D, M>,
    pub scheme: Scheme,
    pub h: f64,
    pub r0: &'a [Vector<D>],
    pub v0: &'a [Vector<D>],
    pub c0: &'a [f64],
    /// Mid time `t_{n+½}` [s] (feedback laws are evaluated there).
    pub t_mid: f64,
    /// `F_b + F_N(t_{n+½})` per node [N].
    pub f_ext: &'a [Vector<D>],
    /// Reaction forces at the constrained components [N] (output).
    pub reaction: &'a mut [Vector<D>],
    /// Force scale of the step, measured at the first full evaluation [N] (output; see
    /// [`NewtonProblem::force_scale`]).
    pub scale: f64,
    /// Strain scale of the step, measured at the first full evaluation [N] (output; see
    /// [`NewtonProblem::strain_scale`]).
    pub strain_scale: f64,
    /// Measure the scales in the next full evaluation (then cleared): they are taken once
    /// per solve, at the predictor, where they cost nothing in the Newton iterations.
    pub measure: bool,
    /// The rigid bodies' states at the step's start (docs/method.md §22).
    pub bodies: &'a [crate::body::BodyState],
    /// Per body, its wrench port's force [N] and torque [N·m] at `t_mid` (empty: none).
    pub wrenches: &'a [(crate::body::Vec3, crate::body::Vec3)],
    /// Per body, its feedback law's reference at `t_mid` (empty or `None`: no law).
    pub targets: &'a [Option<crate::body_feedback::FeedbackTarget>],
    /// The winch drums' data for the step (docs/method.md §23.6; empty: none).
    pub drums: &'a [crate::winch_step::DrumStep<D>],
    /// With bodies: the nodes' increments with the attached nodes' filled in (workspace).
    pub(crate) nodes_x: Vec<Vector<D>>,
    /// With bodies: the buffers of their rows (workspace).
    pub(crate) body_scratch: crate::body_step::BodyScratch,
    /// What the water did over the step at the increment of the last evaluation when that
    /// was a full one (`None` after a partial or failed one): the Newton solve ends on an
    /// evaluation at its result, so the step's [`Self::water_work`] is at hand.
    work: Option<WaterWork>,
}

impl<'a, const D: usize, M> StepEquations<'a, D, M> {
    /// The equations of a step of size `h` [s] from `state` with mid time `t_mid` [s] and
    /// external forces `f_ext` [N] (`F_b + F_N(t_mid)` per node); reactions go to `reaction`.
    /// The scales are measured at the first full evaluation.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        sys: &'a PhSystem<D, M>,
        scheme: Scheme,
        h: f64,
        state: &'a crate::system::State<D>,
        t_mid: f64,
        f_ext: &'a [Vector<D>],
        reaction: &'a mut [Vector<D>],
    ) -> Self {
        Self {
            sys,
            scheme,
            h,
            r0: &state.r,
            v0: &state.v,
            c0: &state.c,
            t_mid,
            f_ext,
            reaction,
            scale: 0.0,
            strain_scale: 0.0,
            measure: true,
            bodies: &state.bodies,
            wrenches: &[],
            targets: &[],
            drums: &[],
            nodes_x: Vec::new(),
            body_scratch: Default::default(),
            work: None,
        }
    }
}

impl<const D: usize, M: StoredEnergy> NewtonProblem<D> for StepEquations<'_, D, M> {
    type Error = StrainError;

    fn evaluate(
        &mut self,
        x: &[Vector<D>],
        res: &mut [Vector<D>],
        jac: Option<&mut BlockJacobian<D>>,
    ) -> Result<(), StrainError> {
        self.evaluate_nodes(x, res, jac, 0..x.len())
    }

    fn chain(&self) -> bool {
        self.sys.mesh.is_chain() && self.sys.bodies.is_empty() && self.drums.is_empty()
    }

    fn force_scale(&self) -> f64 {
        self.scale
    }

    fn strain_scale(&self) -> f64 {
        self.strain_scale
    }

    fn evaluate_nodes(
        &mut self,
        x: &[Vector<D>],
        res: &mut [Vector<D>],
        jac: Option<&mut BlockJacobian<D>>,
        nodes: std::ops::Range<usize>,
    ) -> Result<(), StrainError> {
        if !(self.sys.bodies.is_empty() && self.drums.is_empty()) {
            return self.evaluate_with_bodies(x, res, jac);
        }
        // Two instances, so that the Newton iterations run a loop without the scale sums.
        if self.measure && nodes.start == 0 && nodes.end >= x.len() {
            self.evaluate_range::<true>(x, res, jac, nodes, None)
        } else {
            self.evaluate_range::<false>(x, res, jac, nodes, None)
        }
    }
}

impl<const D: usize, M: StoredEnergy> StepEquations<'_, D, M> {
    /// The full evaluation with rigid bodies or winch drums: `x` holds the nodes' increments,
    /// then the bodies' and the drums' slots; the attached nodes' and the drum nodes'
    /// increments follow from the slots.
    fn evaluate_with_bodies(
        &mut self,
        x: &[Vector<D>],
        res: &mut [Vector<D>],
        jac: Option<&mut BlockJacobian<D>>,
    ) -> Result<(), StrainError> {
        let n = self.sys.mesh.n_nodes();
        let mut xt = std::mem::take(&mut self.nodes_x);
        xt.clear();
        xt.extend_from_slice(&x[..n]);
        crate::body_step::fill_attachments(self.sys, self.bodies, &x[n..], &mut xt);
        crate::winch_step::fill_drums(self.drums, &x[n..], &mut xt);
        let mut scratch = std::mem::take(&mut self.body_scratch);
        let mut step = crate::body_step::BodyStep {
            states: self.bodies,
            h: self.h,
            slots: &x[n..],
            wrenches: self.wrenches,
            targets: self.targets,
            scratch: &mut scratch,
        };
        let out = if self.measure {
            self.evaluate_range::<true>(&xt, res, jac, 0..n, Some(&mut step))
        } else {
            self.evaluate_range::<false>(&xt, res, jac, 0..n, Some(&mut step))
        };
        self.nodes_x = xt;
        self.body_scratch = scratch;
        out
    }
}

impl<const D: usize, M: StoredEnergy> StepEquations<'_, D, M> {
    /// The energy `D_n ≥ 0` [J] that the dissipation takes out in a step with increment `x`
    /// (docs/method.md §18): `Σ_e l_e η ΔC_e²/(2h)` (Kelvin–Voigt), `Δᵀ M_c Δ / h` (drag, with
    /// the group's mass-matrix pattern) and `c |Δ_b − Δ_a|²/h` (dashpots). Each term is a
    /// sum of squares with non-negative coefficients, so the computed value is ≥ 0 exactly for
    /// `h > 0` (a backward `dg4` sub-step has `h < 0` and gives energy back).
    pub(crate) fn dissipated(&self, x: &[Vector<D>]) -> f64 {
        let sys = self.sys;
        let inv_h = 1.0 / self.h;
        let mut total = 0.0;
        for grp in sys.groups.iter().filter(|g| !g.damping.is_none()) {
            let d = grp.damping;
            for e in grp.elements.clone() {
                let [a, b] = sys.mesh.elements()[e];
                let l = sys.mesh.lengths()[e];
                if d.kelvin_voigt != 0.0 {
                    let dc = element_step(&self.r0[a], &self.r0[b], &x[a], &x[b], l).2;
                    total += 0.5 * d.kelvin_voigt * l * dc * dc * inv_h;
                }
                if d.drag != 0.0 {
                    // Δᵀ [[cd, co], [co, cd]] Δ = (cd − co)(|Δ_a|² + |Δ_b|²) + co |Δ_a + Δ_b|².
                    let (cd, co) = element_mass(grp.mass, d.drag, l);
                    let q = (cd - co) * (x[a].norm_squared() + x[b].norm_squared())
                        + co * (x[a] + x[b]).norm_squared();
                    total += q * inv_h;
                }
                if d.dashpot != 0.0 {
                    total += d.dashpot * (x[b] - x[a]).norm_squared() * inv_h;
                }
            }
        }
        total
    }

    /// What the water does over a step with increment `x` (docs/method.md §21): drag,
    /// the current's work, seabed damping and friction, each computed as a sum of products
    /// of non-negative factors where it is a dissipation (≥ 0 exactly for `h > 0`). Taken
    /// from the last evaluation when that was a full one at `x` (the end of a Newton solve).
    pub(crate) fn water_work(&self, x: &[Vector<D>]) -> WaterWork {
        let mut work = match self.work {
            Some(work) => {
                debug_assert_eq!(work, self.water_work_at(x), "last evaluation not at x");
                work
            }
            None => self.water_work_at(x),
        };
        // The rigid bodies' drag (docs/method.md §22), after the lines' and nodes' terms.
        if !self.sys.bodies.is_empty() {
            let n = self.sys.mesh.n_nodes();
            let (d, s) = crate::body_step::drag_work(self.sys, self.bodies, self.h, &x[n..]);
            work.drag_dissipated += d;
            work.current_supplied += s;
        }
        work
    }

    /// [`Self::water_work`] computed at `x`: the elements' drag, then the nodes' terms, each
    /// as an evaluation sums them (so that the two agree to the last bit).
    fn water_work_at(&self, x: &[Vector<D>]) -> WaterWork {
        let mut work = WaterWork::default();
        let Some(w) = self.sys.water.as_deref() else {
            return work;
        };
        let mesh = &self.sys.mesh;
        for el in &w.elements {
            let [a, b] = mesh.elements()[el.e];
            let l = mesh.lengths()[el.e];
            let (r0, xs) = ((&self.r0[a], &self.r0[b]), (&x[a], &x[b]));
            let rpm = element_step(r0.0, r0.1, xs.0, xs.1, l).0;
            let m = ElementMotion::with_tangent(rpm, r0, xs, 1.0 / l, self.h);
            work.add(&w.drag(el, &m, self.h, false).2);
        }
        for node in &w.nodes {
            let i = node.node;
            let axis = w.node_axis(node, self.r0);
            work.add(&w.node_step(node, &self.r0[i], &x[i], &axis, self.h).work);
        }
        work
    }

    /// The water's terms (docs/method.md §21) of the rows of `nodes` (elements `els` for the
    /// drag), added to `res` and `jac`, and their work to `work` (the elements' first);
    /// returns the squares of their forces (force scale).
    #[allow(clippy::too_many_arguments)]
    fn water_terms<const MEASURE: bool>(
        &self,
        w: &WaterModel<D>,
        x: &[Vector<D>],
        res: &mut [Vector<D>],
        mut jac: Option<&mut BlockJacobian<D>>,
        nodes: std::ops::Range<usize>,
        els: std::ops::Range<usize>,
        work: &mut WaterWork,
    ) -> f64 {
        let mut scale2 = 0.0;
        let mut node_work = WaterWork::default();
        for node in w.nodes_in(nodes.clone()) {
            let i = node.node;
            if let Some(b) = w.resting_buoyancy(node, &self.r0[i], &x[i]) {
                // [`WaterModel::node_step`]'s terms then, without adding its zeros.
                res[i][D - 1] -= b;
                if MEASURE {
                    scale2 += b * b;
                }
                continue;
            }
            let axis = w.node_axis(node, self.r0);
            let st = w.node_step(node, &self.r0[i], &x[i], &axis, self.h);
            res[i] += st.res;
            node_work.add(&st.work);
            if MEASURE {
                scale2 += st.res.norm_squared();
            }
            if let Some(j) = jac.as_deref_mut() {
                j.diag[i] += st.jac;
            }
        }
        let want = jac.is_some();
        for el in w.elements_in(els) {
            let [a, b] = self.sys.mesh.elements()[el.e];
            let l = self.sys.mesh.lengths()[el.e];
            let (r0, xs) = ((&self.r0[a], &self.r0[b]), (&x[a], &x[b]));
            let rpm = element_step(r0.0, r0.1, xs.0, xs.1, l).0;
            let m = ElementMotion::with_tangent(rpm, r0, xs, 1.0 / l, self.h);
            let (f, [ja, jb], drag_work) = w.drag(el, &m, self.h, want);
            work.add(&drag_work);
            let half = f * 0.5;
            let (in_a, in_b) = (nodes.contains(&a), nodes.contains(&b));
            if in_a {
                res[a] -= half;
            }
            if in_b {
                res[b] -= half;
            }
            if MEASURE {
                scale2 += 2.0 * half.norm_squared();
            }
            if let Some(j) = jac.as_deref_mut() {
                // Rows a and b alike: ∂/∂x_a = ja, ∂/∂x_b = jb.
                if in_a {
                    j.diag[a] += ja;
                }
                if in_b {
                    j.diag[b] += jb;
                }
                j.off[el.e][0] += jb;
                j.off[el.e][1] += ja;
            }
        }
        work.add(&node_work);
        scale2
    }

    /// [`NewtonProblem::evaluate_nodes`]; with `MEASURE` (a full range only) also the force
    /// and strain scales.
    fn evaluate_range<const MEASURE: bool>(
        &mut self,
        x: &[Vector<D>],
        res: &mut [Vector<D>],
        mut jac: Option<&mut BlockJacobian<D>>,
        nodes: std::ops::Range<usize>,
        bodies: Option<&mut crate::body_step::BodyStep<'_, D>>,
    ) -> Result<(), StrainError> {
        let sys = self.sys;
        let n_el = sys.mesh.n_elements();
        let full = nodes.start == 0 && nodes.end >= x.len();
        debug_assert!(full || sys.mesh.is_chain(), "node ranges need a chain mesh");
        // Elements touching the node range (chain numbering when not the full range).
        let els = if full {
            0..n_el
        } else {
            nodes.start.saturating_sub(1)..nodes.end.min(n_el)
        };
        for (r, f) in res[nodes.clone()]
            .iter_mut()
            .zip(&self.f_ext[nodes.clone()])
        {
            *r = -f;
        }
        // Force scale (docs/method.md §9, eq. (9.2)): squares of the magnitudes of every force term of
        // the residual, summed over the full evaluation.
        let mut strain2 = 0.0;
        self.work = None;
        let mut work = WaterWork::default();
        let mut scale2 = if MEASURE {
            self.f_ext.iter().map(|f| f.norm_squared()).sum::<f64>()
        } else {
            0.0
        };
        if let Some(j) = jac.as_deref_mut() {
            if full {
                j.clear();
            } else {
                j.diag[nodes.clone()].iter_mut().for_each(|b| b.fill(0.0));
            }
        }
        // The drag of a line's elements goes with their other terms in the element loop (one
        // pass over the elements) when each group is all wet or all dry, as line
        // hydrodynamics, given per group, make it.
        let water = sys.water.as_deref();
        let fused = water.is_some_and(|w| {
            sys.groups.iter().all(|g| {
                let n = w.elements_in(g.elements.clone()).len();
                n == 0 || n == g.elements.len()
            })
        });
        for grp in &sys.groups {
            // This group's part of the elements touching the range.
            let sub = grp.elements.start.max(els.start)..grp.elements.end.min(els.end);
            if sub.is_empty() {
                continue;
            }
            let drag = water
                .filter(|_| fused)
                .map(|w| (w, w.elements_in(sub.clone())))
                .filter(|(_, wet)| !wet.is_empty());
            let k = ElementKernel {
                mass: grp.mass,
                rho_a: grp.rho_a,
                els: sub,
                full,
                nodes: nodes.clone(),
                damping: grp.damping,
            };
            let jac = jac.as_deref_mut();
            let out = (&mut *res, jac, (&mut scale2, &mut strain2), &mut work);
            match (&grp.law, drag) {
                (Law::String(m), Some(d)) => {
                    self.elements::<_, MEASURE, true>(m, k, Some(d), x, out)?
                }
                (Law::String(m), None) => self.elements::<_, MEASURE, false>(m, k, None, x, out)?,
                (Law::Spring(sp), _) => self.elements::<_, MEASURE, false>(sp, k, None, x, out)?,
            }
        }
        if let Some(w) = water {
            // The element loop has taken the drag when fused.
            let drag_els = if fused { 0..0 } else { els.clone() };
            let j = jac.as_deref_mut();
            let s2 = self.water_terms::<MEASURE>(w, x, res, j, nodes.clone(), drag_els, &mut work);
            if MEASURE {
                scale2 += s2;
            }
            // The step's water work, when this evaluation is a full one.
            self.work = full.then_some(work);
        }
        self.port_and_mass_terms::<MEASURE>(x, res, jac.as_deref_mut(), &nodes, &mut scale2);
        // Rigid bodies: their rows take the attached nodes' rows before those are masked.
        if let Some(step) = bodies {
            let mut s2 = step.terms(sys, res, jac.as_deref_mut());
            // Winch drums: their rows take the drum nodes' rows likewise.
            if !self.drums.is_empty() {
                let j = jac.as_deref_mut();
                s2 += crate::winch_step::terms(
                    sys,
                    self.drums,
                    (self.h, step.states),
                    step.slots,
                    res,
                    j,
                );
            }
            if MEASURE {
                scale2 += s2;
            }
        }
        // Dirichlet components: the residual there is the reaction force; the equation is
        // replaced by Δ_k = 0.
        for &i in sys.constrained.iter().filter(|i| nodes.contains(i)) {
            let free = &sys.free[i];
            for k in 0..D {
                if !free[k] {
                    self.reaction[i][k] = res[i][k];
                    res[i][k] = 0.0;
                }
            }
        }
        if let Some(j) = jac {
            mask_constrained(sys, j, &nodes, &els);
        }
        if MEASURE {
            self.scale = scale2.sqrt();
            self.strain_scale = strain2.sqrt();
            self.measure = false;
        }
        Ok(())
    }

    /// The feedback ports' forces and the point masses' inertia on the rows of `nodes`, added
    /// to `res` and `jac`; with `MEASURE` the squares of their force terms are added to
    /// `scale2`, term by term.
    fn port_and_mass_terms<const MEASURE: bool>(
        &self,
        x: &[Vector<D>],
        res: &mut [Vector<D>],
        mut jac: Option<&mut BlockJacobian<D>>,
        nodes: &std::ops::Range<usize>,
        scale2: &mut f64,
    ) {
        let sys = self.sys;
        let h = self.h;
        let (inv_h, mass_scale) = (1.0 / h, 2.0 / (h * h));
        let eye = SMatrix::<f64, D, D>::identity();
        // Feedback ports: the force F(t_{n+½}, r_{n+½}, Δ/h) is an input, so −F in the residual.
        for fb in sys
            .boundary
            .feedback
            .iter()
            .filter(|f| nodes.contains(&f.node))
        {
            let i = fb.node;
            let (rm, y) = (self.r0[i] + x[i] * 0.5, x[i] * inv_h);
            let f = fb.law.force(self.t_mid, &rm, &y);
            res[i] -= f;
            if let Some(j) = jac.as_deref_mut() {
                let (dr, dy) = fb.law.jacobian(self.t_mid, &rm, &y);
                j.diag[i] -= dr * 0.5 + dy * inv_h;
            }
            if MEASURE {
                *scale2 += f.norm_squared();
            }
        }
        // Point masses: inertia m (v_{n+1} − v_n)/h at their nodes.
        for &(i, m) in sys.point_mass.iter().filter(|(i, _)| nodes.contains(i)) {
            let w = (x[i] * inv_h - self.v0[i]) * (2.0 * inv_h);
            res[i] += w * m;
            if let Some(j) = jac.as_deref_mut() {
                j.diag[i] += eye * (mass_scale * m);
            }
            if MEASURE {
                let mm = 2.0 * inv_h * m;
                *scale2 +=
                    mm * mm * (x[i].norm_squared() * (inv_h * inv_h) + self.v0[i].norm_squared());
            }
        }
    }

    /// The inertia and internal-force terms of the elements `k.els` of one group with law
    /// `law` (rows of `k.nodes` only unless `k.full`); with `MEASURE` also their force and
    /// strain scales, added to `scale2` and `strain2`. With `WET`, also the water's drag on
    /// them, `drag` (the model and the group's wet elements `k.els`, in order).
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn elements<L: StoredEnergy, const MEASURE: bool, const WET: bool>(
        &self,
        law: &L,
        k: ElementKernel,
        drag: Option<(&WaterModel<D>, &[WetElement])>,
        x: &[Vector<D>],
        (res, mut jac, (scale2, strain2), work): ElementOut<'_, D>,
    ) -> Result<(), StrainError> {
        let sys = self.sys;
        let h = self.h;
        let (inv_h, mass_scale) = (1.0 / h, 2.0 / (h * h));
        let (els, full, nodes) = (k.els.clone(), k.full, k.nodes.clone());
        let eye = SMatrix::<f64, D, D>::identity();
        // Kelvin–Voigt: η/(2h) [N], the change of S̄/2 per unit ΔC.
        let kv = 0.5 * k.damping.kelvin_voigt * inv_h;
        let lossy = k.damping.drag != 0.0 || k.damping.dashpot != 0.0;
        for (e, (&[a, b], &l)) in sys.mesh.elements()[els.clone()]
            .iter()
            .zip(&sys.mesh.lengths()[els.clone()])
            .enumerate()
        {
            let e = e + els.start;
            // Rows outside a partial range are left alone.
            let (in_a, in_b) = (full || a >= nodes.start, full || b < nodes.end);
            let (md, mo) = element_mass(k.mass, k.rho_a, l);
            // Inertia: M_ρ (v_{n+1} − v_n)/h with v_{n+1} − v_n = 2 (Δ/h − v_n).
            let wa = (x[a] * inv_h - self.v0[a]) * (2.0 * inv_h);
            let wb = (x[b] * inv_h - self.v0[b]) * (2.0 * inv_h);
            // Internal force K(r_{n+½}) S̄.
            let (rpm, dr, dc) = element_step(&self.r0[a], &self.r0[b], &x[a], &x[b], l);
            let c0 = self.c0[e];
            let c1 = c0 + dc;
            if !law.admissible(c1) {
                return Err(StrainError { element: e, c: c1 });
            }
            let (mut q, mut dq) = self.scheme.half_stress(law, c0, c1);
            if kv != 0.0 {
                // Kelvin–Voigt: S̄ gains η ΔC/h, so S̄/2 gains η ΔC/(2h).
                q += kv * dc;
                dq += kv;
            }
            let f = rpm * (2.0 * q);
            // The water's drag on the element (docs/method.md §21), with its mid-step tangent.
            let wet = match drag {
                Some((w, wet)) if WET => {
                    let (r0, xs) = ((&self.r0[a], &self.r0[b]), (&x[a], &x[b]));
                    let m = ElementMotion::with_tangent(rpm, r0, xs, 1.0 / l, h);
                    Some(w.drag(&wet[e - els.start], &m, h, jac.is_some()))
                }
                _ => None,
            };
            if MEASURE {
                // Inertia terms (2/h²) m Δ and (2/h) m v_n at both nodes; the internal
                // force on both nodes.
                let m = (2.0 * inv_h) * (md + mo.abs());
                let motion = (x[a].norm_squared() + x[b].norm_squared()) * (inv_h * inv_h)
                    + self.v0[a].norm_squared()
                    + self.v0[b].norm_squared();
                let rpm2 = rpm.norm_squared();
                *scale2 += m * m * motion + 8.0 * q * q * rpm2;
                let kk = dq * c1.abs().max(c0.abs());
                *strain2 += 8.0 * kk * kk * rpm2;
            }
            if in_a {
                res[a] += wa * md + wb * mo;
                res[a] -= f;
            }
            if in_b {
                res[b] += wb * md + wa * mo;
                res[b] += f;
            }
            if let Some((fw, _, drag_work)) = &wet {
                work.add(drag_work);
                // Half of the drag on each node.
                let half = fw * 0.5;
                if in_a {
                    res[a] -= half;
                }
                if in_b {
                    res[b] -= half;
                }
                if MEASURE {
                    *scale2 += 2.0 * half.norm_squared();
                }
            }
            // Drag c M_c Δ/h and dashpot c (Δ_b − Δ_a)/h: `(rd, ro)` are their diagonal and
            // coupling coefficients per unit velocity [N·s/m].
            let (rd, ro) = if lossy {
                let (cd, co) = element_mass(k.mass, k.damping.drag, l);
                (cd + k.damping.dashpot, co - k.damping.dashpot)
            } else {
                (0.0, 0.0)
            };
            if lossy {
                let (ua, ub) = (x[a] * inv_h, x[b] * inv_h);
                if in_a {
                    res[a] += ua * rd + ub * ro;
                }
                if in_b {
                    res[b] += ub * rd + ua * ro;
                }
                if MEASURE {
                    let m = rd.abs() + ro.abs();
                    *scale2 += m * m * (ua.norm_squared() + ub.norm_squared());
                }
            }
            if let Some(j) = jac.as_deref_mut() {
                // ∂f/∂r'_{n+1} = q I + 4 ∂q/∂C₁ r'_{n+½} r'_{n+1}ᵀ.
                let rp1 = rpm + dr * 0.5;
                let g = (eye * q + rpm * rp1.transpose() * (4.0 * dq)) * (1.0 / l);
                let diag = g + eye * (mass_scale * md + inv_h * rd);
                let off = eye * (mass_scale * mo + inv_h * ro) - g;
                // Rows a and b alike: the drag's ∂/∂x_a = ja, ∂/∂x_b = jb.
                let (da, db, offs) = match &wet {
                    Some((_, [ja, jb], _)) => (diag + ja, diag + jb, [off + jb, off + ja]),
                    None => (diag, diag, [off, off]),
                };
                if in_a {
                    j.diag[a] += da;
                }
                if in_b {
                    j.diag[b] += db;
                }
                j.off[e] = offs;
            }
        }
        Ok(())
    }
}

/// Replaces the Jacobian's rows and columns of the constrained components of `nodes` (and of
/// the elements `els` touching them) by the unit vector: their equations are `Δ_k` = known.
fn mask_constrained<const D: usize, M>(
    sys: &PhSystem<D, M>,
    j: &mut BlockJacobian<D>,
    nodes: &std::ops::Range<usize>,
    els: &std::ops::Range<usize>,
) {
    let mask = |blk: &mut SMatrix<f64, D, D>, row: &[bool; D], col: &[bool; D]| {
        for k in 0..D {
            for m in 0..D {
                if !row[k] || !col[m] {
                    blk[(k, m)] = 0.0;
                }
            }
        }
    };
    for &i in sys.constrained.iter().filter(|i| nodes.contains(i)) {
        let fi = &sys.free[i];
        mask(&mut j.diag[i], fi, fi);
        for k in 0..D {
            if !fi[k] {
                j.diag[i][(k, k)] = 1.0;
            }
        }
    }
    for &e in sys.constrained_elements.iter().filter(|e| els.contains(e)) {
        let [a, b] = sys.mesh.elements()[e];
        let (fa, fb) = (&sys.free[a], &sys.free[b]);
        mask(&mut j.off[e][0], fa, fb);
        mask(&mut j.off[e][1], fb, fa);
    }
}

#[cfg(test)]
mod tests {
    //! `W'`, `W''`, `∂q/∂C₁` and the assembled Newton Jacobian against central
    //! finite differences, on random states, d = 1, 2, 3, all laws, both schemes.

    use super::*;

    /// A chain node on a damped seabed (226 kg/m with added mass over 16.7 m: m = 3770 kg,
    /// c = c_bed d L = 9e5 N·s/m, k = 9e6 N/m). The backward sub-step's pivot
    /// `2m − c s + k s²` vanishes at `s* = (c − √(c² − 8mk))/2k = 9.23 ms`, that is at
    /// `h* = s*/|γ₂| = 5.42 ms`; a step there, and at 4 and 5 ms, is split until the pivot is
    /// at least `m` (two or three triple jumps), a step well beyond it is not, and without a
    /// damped contact nothing is split.
    #[test]
    fn dg4_splits_a_step_whose_backward_sub_step_is_near_a_contacts_singular_step() {
        let contact = DampedContact {
            mass_lo: 3770.0,
            mass_hi: 3770.0,
            damping: 9.0e5,
            stiffness: 9.0e6,
        };
        let (m, c, k) = (contact.mass_lo, contact.damping, contact.stiffness);
        let g2 = triple_jump()[1].abs();
        let pivot = |h: f64, n: usize| {
            let s = g2 * h / n as f64;
            (2.0 * m - c * s + k * s * s) / m
        };
        let s_star = (c - (c * c - 8.0 * m * k).sqrt()) / (2.0 * k);
        let h_star = s_star / g2;
        assert!((h_star - 5.4215e-3).abs() < 1e-7, "h* = {h_star}");
        assert!(pivot(h_star, 1).abs() < 1e-12);
        for (h, n) in [
            (1e-3, 1),
            (4e-3, 2),
            (5e-3, 2),
            (h_star, 3),
            (1e-2, 1),
            (2e-2, 1),
        ] {
            assert_eq!(compositions(&[contact], h), n, "h = {h}");
            assert!(pivot(h, n).abs() >= 1.0, "h = {h}: pivot {}", pivot(h, n));
            if n > 1 {
                assert!(pivot(h, n - 1).abs() < 1.0, "h = {h}");
            }
        }
        // Pivots / m: 1.03 at 5 ms with two jumps (0.141 with one), −1.37 at 10 ms.
        assert!((pivot(5e-3, 2) - 1.0272).abs() < 1e-4);
        assert!((pivot(5e-3, 1) - 0.1409).abs() < 1e-4);
        assert!((pivot(1e-2, 1) + 1.3722).abs() < 1e-4);
        assert_eq!(compositions(&[], 5e-3), 1);
        // A consistent mass row: every mass between m/3 (neighbours against the node) and m
        // must clear the band `(q/3, q)`: at 5 ms that takes 7 jumps (q = 1081 kg ≤ m/3 =
        // 1257 kg; 1259 kg with 6), at 10 ms one (q = 12 714 kg ≥ 3m).
        let consistent = DampedContact {
            mass_lo: m / 3.0,
            ..contact
        };
        assert_eq!(compositions(&[consistent], 5e-3), 7);
        assert_eq!(compositions(&[consistent], 1e-2), 1);
    }
    use crate::boundary::{Boundary, Fixed};
    use crate::material::Material;
    use crate::mesh::Mesh;
    use crate::system::{MassMatrix, Problem, State};
    use proptest::prelude::*;

    fn laws() -> [Material; 5] {
        [
            Material::hyperelastic(20.0),
            Material::linear_elastic(13.0),
            Material::st_venant_kirchhoff(7.0),
            Material::tension_only_linear(11.0),
            Material::tension_only_hyperelastic(17.0),
        ]
    }

    /// Central difference of `f` at `x` with step `eps`.
    fn fd(f: impl Fn(f64) -> f64, x: f64, eps: f64) -> f64 {
        (f(x + eps) - f(x - eps)) / (2.0 * eps)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn material_derivatives_match_finite_differences(c in 0.3f64..3.0, dc in -0.25f64..0.25) {
            for m in laws() {
                let eps = 1e-6;
                let d1 = fd(|x| m.w(x), c, eps);
                prop_assert!((m.dw(c) - d1).abs() <= 1e-7 * (1.0 + d1.abs()), "{m:?} W' at {c}");
                let d2 = fd(|x| m.dw(x), c, eps);
                prop_assert!((m.d2w(c) - d2).abs() <= 1e-7 * (1.0 + d2.abs()), "{m:?} W'' at {c}");
                let c1 = c + dc;
                let dq = fd(|x| m.quotient(c, x).0, c1, eps);
                let got = m.quotient(c, c1).1;
                prop_assert!((got - dq).abs() <= 1e-7 * (1.0 + dq.abs()), "{m:?} dq/dC1 at ({c}, {c1}): {got} vs {dq}");
            }
        }
    }

    /// A nonlinear feedback law for the Jacobian checks:
    /// `F = −k (|r|² r + t y + (y·y) y)`.
    struct Cubic {
        k: f64,
    }

    impl<const D: usize> crate::boundary::PortLaw<D> for Cubic {
        fn force(&self, t: f64, r: &Vector<D>, y: &Vector<D>) -> Vector<D> {
            -(r * r.norm_squared() + y * t + y * y.norm_squared()) * self.k
        }
        fn jacobian(
            &self,
            t: f64,
            r: &Vector<D>,
            y: &Vector<D>,
        ) -> (SMatrix<f64, D, D>, SMatrix<f64, D, D>) {
            let eye = SMatrix::<f64, D, D>::identity();
            (
                -(eye * r.norm_squared() + r * r.transpose() * 2.0) * self.k,
                -(eye * (t + y.norm_squared()) + y * y.transpose() * 2.0) * self.k,
            )
        }
    }

    /// Random chain state in `D` dimensions with positive strains; node 0 fixed in all
    /// components and node 1 in the first, to exercise the Dirichlet masking.
    fn check_jacobian<const D: usize>(seed: &[f64], scheme: Scheme, material: Material) {
        let n_el = 5;
        let mut it = seed.iter().copied().cycle();
        let mut next = move || it.next().unwrap();
        let mesh = Mesh::uniform_chain(n_el, 1.0).unwrap();
        let r: Vec<Vector<D>> = (0..=n_el)
            .map(|i| {
                let mut x = Vector::<D>::from_fn(|_, _| 0.05 * next());
                x[0] += 0.2 * i as f64;
                x
            })
            .collect();
        let v: Vec<Vector<D>> = (0..=n_el).map(|_| Vector::from_fn(|_, _| next())).collect();
        let mut fixed1 = [false; D];
        fixed1[0] = true;
        let problem = Problem {
            point_masses: Vec::new(),
            initial: State::consistent(&mesh, r, v),
            mesh,
            material,
            rho_a: 1.3,
            body_force: Vector::from_fn(|_, _| 0.5),
            mass: MassMatrix::Consistent,
            boundary: Boundary {
                motions: vec![],
                feedback: vec![],
                fixed: vec![
                    Fixed::node(0),
                    Fixed {
                        node: 1,
                        components: fixed1,
                    },
                ],
                loads: vec![],
            },
        };
        let mut net: crate::system::Network<D, Material> = problem.into();
        // Kelvin–Voigt and drag of random size (zero in about a quarter of the cases), and a
        // nonlinear feedback law at the last node.
        let coef = |x: f64| (x - 0.5).max(0.0) * 4.0;
        net.groups[0].damping = crate::system::Damping {
            kelvin_voigt: coef(next()),
            drag: coef(next()),
            dashpot: 0.0,
        };
        net.boundary
            .feedback
            // Node 2 lies inside the partial range checked below.
            .push(crate::boundary::FeedbackLoad::new(2, Cubic { k: next() }));
        let (sys, state) = PhSystem::new(net).unwrap();
        let kink = matches!(
            material,
            Material::TensionOnlyLinear(_) | Material::TensionOnlyHyperelastic(_)
        ) && scheme == Scheme::Midpoint;
        check_system_jacobian(&sys, &state, &mut next, scheme, kink);
    }

    /// The Newton Jacobian of `sys` at a random increment from `state` against central
    /// differences; with `kink`, states within 1e-4 of C = 1 at the midpoint are skipped.
    fn check_system_jacobian<const D: usize>(
        sys: &PhSystem<D, Material>,
        state: &State<D>,
        next: &mut impl FnMut() -> f64,
        scheme: Scheme,
        kink: bool,
    ) {
        let h = 0.05;
        let x: Vec<Vector<D>> = state
            .v
            .iter()
            .map(|v| v * h + Vector::from_fn(|_, _| 0.01 * next()))
            .collect();
        // The midpoint rule evaluates `W''` at `(C₀ + C₁)/2`; for a tension-only law that jumps
        // at C = 1, where a central difference is no derivative: such states are skipped.
        if kink {
            let near = sys
                .mesh
                .elements()
                .iter()
                .zip(sys.mesh.lengths())
                .zip(&state.c)
                .any(|((&[a, b], &l), &c0)| {
                    let dc = element_step(&state.r[a], &state.r[b], &x[a], &x[b], l).2;
                    (c0 + 0.5 * dc - 1.0).abs() < 1e-4
                });
            if near {
                return;
            }
        }
        let mut reaction = vec![Vector::<D>::zeros(); x.len()];
        let f_ext = sys.f_body.clone();
        let mut eqs = StepEquations {
            sys,
            scheme,
            h,
            r0: &state.r,
            v0: &state.v,
            c0: &state.c,
            t_mid: 0.3,
            f_ext: &f_ext,
            reaction: &mut reaction,
            scale: 0.0,
            strain_scale: 0.0,
            measure: true,
            bodies: &state.bodies,
            wrenches: &[],
            targets: &[],
            drums: &[],
            nodes_x: Vec::new(),
            body_scratch: Default::default(),
            work: None,
        };
        let n = x.len();
        let mut res = vec![Vector::<D>::zeros(); n];
        let mut jac = BlockJacobian::<D>::zeros(sys.mesh());
        eqs.evaluate(&x, &mut res, Some(&mut jac)).unwrap();
        // A node range (used by nonlinear elimination on chains) gives the same rows and blocks,
        // whatever the buffers held before, and writes nothing else.
        let range = if sys.mesh.is_chain() { 1..4 } else { 0..0 };
        // Finite, so that an accumulation into a row outside the range shows.
        const SENTINEL: f64 = 12345.0;
        let mut res_r = vec![Vector::<D>::from_element(SENTINEL); n];
        let mut jac_r = jac.clone();
        jac_r.diag.iter_mut().for_each(|b| b.fill(SENTINEL));
        jac_r
            .off
            .iter_mut()
            .for_each(|b| b.iter_mut().for_each(|b| b.fill(SENTINEL)));
        if !range.is_empty() {
            eqs.evaluate_nodes(&x, &mut res_r, Some(&mut jac_r), range.clone())
                .unwrap();
        }
        for i in (0..n).filter(|_| !range.is_empty()) {
            if range.contains(&i) {
                assert_eq!(res_r[i], res[i], "residual row {i}");
                assert_eq!(jac_r.diag[i], jac.diag[i], "diagonal block {i}");
            } else {
                // Left as it was.
                assert!(
                    res_r[i].iter().all(|&v| v == SENTINEL),
                    "row {i} was written"
                );
                assert!(
                    jac_r.diag[i].iter().all(|&v| v == SENTINEL),
                    "block {i} was written"
                );
            }
        }
        for e in range.start..range.end.saturating_sub(1) {
            assert_eq!(jac_r.off[e], jac.off[e], "coupling blocks of element {e}");
        }
        // Dense Jacobian from the blocks.
        let dense = |i: usize, k: usize, j: usize, m: usize| -> f64 {
            let mut v = 0.0;
            if i == j {
                v += jac.diag[i][(k, m)];
            }
            for (e, &[a, b]) in sys.mesh().elements().iter().enumerate() {
                if a == i && b == j {
                    v += jac.off[e][0][(k, m)];
                }
                if b == i && a == j {
                    v += jac.off[e][1][(k, m)];
                }
            }
            v
        };
        // Central differences: truncation O(eps² R''') and rounding ~ε|R|/eps. Near the
        // seabed contact's and the static friction's sharp bends the truncation at 1e-7 was
        // up to 3.4e-6 of the scale (falling 100-fold per 10-fold smaller step: the
        // Jacobian was right); at 1e-8 rounding stays near 1e-8 |R|, well below 1e-6.
        let eps = 1e-8;
        let mut scale = 0.0_f64;
        let mut worst = 0.0_f64;
        for j in 0..n {
            for m in 0..D {
                let (mut xp, mut xm) = (x.clone(), x.clone());
                xp[j][m] += eps;
                xm[j][m] -= eps;
                let (mut rp, mut rm) = (res.clone(), res.clone());
                eqs.evaluate(&xp, &mut rp, None).unwrap();
                eqs.evaluate(&xm, &mut rm, None).unwrap();
                for i in 0..n {
                    for k in 0..D {
                        let mut num = (rp[i][k] - rm[i][k]) / (2.0 * eps);
                        if !sys.free[i][k] || !sys.free[j][m] {
                            // Replaced equation Δ_k = 0: identity on the diagonal.
                            num = if i == j && k == m && !sys.free[i][k] {
                                1.0
                            } else {
                                0.0
                            };
                        }
                        scale = scale.max(num.abs());
                        worst = worst.max((dense(i, k, j, m) - num).abs());
                    }
                }
            }
        }
        assert!(
            worst <= 1e-6 * scale,
            "D = {D}, {scheme:?}, {:?}: Jacobian error {worst:e} (scale {scale:e})",
            sys.groups.iter().map(|g| g.law).collect::<Vec<_>>()
        );
    }

    /// A random network in `D` dimensions: three strings of different laws and mass kinds
    /// meeting at a junction, a spring of positive rest length between two strings, a
    /// zero-rest-length spring to a fixed point, a point mass, a prescribed motion and a
    /// partly fixed node.
    fn check_network_jacobian<const D: usize>(seed: &[f64], scheme: Scheme) {
        use crate::boundary::Motion;
        use crate::network::{NetworkBuilder, StringSpec};
        use crate::system::PointMass;
        let mut it = seed.iter().copied().cycle();
        let mut next = move || it.next().unwrap();
        let mut b = NetworkBuilder::<D, Material>::new();
        let mut point = |b: &mut NetworkBuilder<D, Material>, k: usize| {
            let mut x = Vector::<D>::from_fn(|_, _| 0.1 * next());
            x[k.min(D - 1)] += 1.0 + k as f64;
            b.node(x)
        };
        let junction = point(&mut b, 0);
        let ends: Vec<usize> = (1..4).map(|k| point(&mut b, k)).collect();
        let laws = [
            Material::hyperelastic(20.0),
            Material::st_venant_kirchhoff(9.0),
            Material::linear_elastic(13.0),
        ];
        for (k, (&e, law)) in ends.iter().zip(laws).enumerate() {
            let spec = StringSpec {
                name: format!("s{k}"),
                material: law,
                rho_a: 0.7 + 0.3 * k as f64,
                mass: if k == 1 {
                    MassMatrix::Lumped
                } else {
                    MassMatrix::Consistent
                },
                body_force: Vector::from_fn(|_, _| 0.2),
                prestretch: 1.1,
            };
            b.string(spec, &[e, junction], 3).unwrap();
        }
        let (m0, m1) = (b.group_nodes(0).unwrap()[1], b.group_nodes(1).unwrap()[2]);
        b.spring("link", m0, m1, 5.0, 0.3).unwrap();
        b.spring_to_point("tie", junction, Vector::from_fn(|_, _| 0.5), 3.0, 0.0)
            .unwrap();
        // A pure dashpot (stiffness 0) from the junction to a fixed point, a dashpot across
        // the link spring, Kelvin–Voigt and drag on the strings.
        let pure = b
            .spring_to_point("damper", ends[2], Vector::from_fn(|_, _| -0.5), 0.0, 0.0)
            .unwrap();
        let dash = |c: f64| crate::system::Damping {
            dashpot: c,
            ..Default::default()
        };
        b.set_damping(pure, dash(0.5 + next().abs())).unwrap();
        b.set_damping(3, dash(next().abs())).unwrap();
        for g in 0..3 {
            let d = crate::system::Damping {
                kelvin_voigt: next().abs() * 2.0,
                drag: next().abs(),
                dashpot: 0.0,
            };
            b.set_damping(g, d).unwrap();
        }
        let mut net = b
            .build(
                Boundary {
                    fixed: vec![Fixed::node(ends[0]), {
                        let mut c = [false; D];
                        c[0] = true;
                        Fixed {
                            node: ends[1],
                            components: c,
                        }
                    }],
                    loads: vec![],
                    motions: vec![],
                    feedback: vec![],
                },
                vec![PointMass {
                    node: junction,
                    mass: 2.0,
                    weight: Vector::from_fn(|_, _| -1.0),
                }],
            )
            .unwrap();
        let x0 = net.initial.r[ends[2]][D - 1];
        net.boundary
            .motions
            .push(Motion::new(ends[2], D - 1, move |t| x0 + 0.1 * t));
        for v in &mut net.initial.v {
            *v = Vector::from_fn(|_, _| next());
        }
        net.boundary
            .feedback
            .push(crate::boundary::FeedbackLoad::new(
                junction,
                Cubic { k: next().abs() },
            ));
        let (rr, kp, kd) = (next(), next().abs(), next().abs());
        net.boundary
            .feedback
            .push(crate::boundary::FeedbackLoad::new(
                ends[2],
                crate::boundary::PdLaw::tracking(
                    kp,
                    kd,
                    move |t| Vector::from_element(rr + t),
                    |_| Vector::from_element(1.0),
                ),
            ));
        let (sys, state) = PhSystem::new(net).unwrap();
        check_system_jacobian(&sys, &state, &mut next, scheme, false);
    }

    /// A random chain in water (`D ≥ 2`): crossing the surface band, partly in the seabed
    /// (flat, a plane or a grid; stiffness, ramped damping, friction), in a sheared current, with drag, added mass and
    /// a buoyant point with drag in the surface band; node 0 fixed.
    fn check_water_jacobian<const D: usize>(seed: &[f64], scheme: Scheme) {
        use crate::water::{Current, Friction, LineHydro, PointHydro, Seabed, Water};
        let n_el = 7;
        let mut it = seed.iter().copied().cycle();
        let mut next = move || it.next().unwrap();
        let mesh = Mesh::uniform_chain(n_el, 1.0).unwrap();
        // Heights from above the surface band down into the seabed at −2 m.
        let z = [0.6, 0.1, -0.15, -1.0, -1.97, -2.0, -2.03, -2.08];
        let r: Vec<Vector<D>> = (0..=n_el)
            .map(|i| {
                let mut x = Vector::<D>::from_fn(|_, _| 0.02 * next());
                x[0] += 0.9 * i as f64;
                x[D - 1] += z[i];
                x
            })
            .collect();
        let v: Vec<Vector<D>> = (0..=n_el).map(|_| Vector::from_fn(|_, _| next())).collect();
        let problem = Problem {
            point_masses: Vec::new(),
            initial: State::consistent(&mesh, r, v),
            mesh,
            material: Material::linear_elastic(40.0),
            rho_a: 1.3,
            body_force: Vector::from_fn(|k, _| if k == D - 1 { -3.0 } else { 0.0 }),
            mass: MassMatrix::Consistent,
            boundary: Boundary {
                motions: vec![],
                feedback: vec![],
                fixed: vec![Fixed::node(0)],
                loads: vec![],
            },
        };
        let (u0, u1) = (
            Vector::<D>::from_fn(|k, _| 0.3 + 0.1 * k as f64),
            Vector::<D>::from_fn(|k, _| 1.0 - 0.4 * k as f64),
        );
        // Flat at −2 m, a slightly inclined plane through (0, …, −2), or a bumpy bathymetry
        // grid about −2 m (uneven spacing, nodes between and beyond its points).
        let k = 150.0 * (1.0 + 0.5 * next());
        let pick = next();
        let base = if pick > 0.3 {
            Seabed::flat(2.0, k, 4.0)
        } else if pick > -0.3 {
            let xs = vec![-0.5, 0.7, 1.5, 2.6, 3.1, 4.4, 5.0];
            let ys = if D == 3 {
                vec![-0.4, 0.1, 0.5]
            } else {
                Vec::new()
            };
            let depth = |x: f64, y: f64| 2.0 + 0.05 * (2.0 * x).sin() - 0.03 * x + 0.08 * y;
            let d = ys
                .iter()
                .copied()
                .chain((D == 2).then_some(0.0))
                .flat_map(|y| xs.iter().map(move |&x| depth(x, y)))
                .collect();
            Seabed::grid(crate::Bathymetry::grid(xs, ys, d).unwrap(), k, 4.0)
        } else {
            let up = |i: usize, tilt: f64| {
                if i == D - 1 {
                    1.0
                } else {
                    tilt * (i as f64 + 1.0)
                }
            };
            let normal = Vector::<D>::from_fn(|i, _| up(i, 0.04));
            let point = Vector::<D>::from_fn(|i, _| -2.0 * up(i, 0.0));
            Seabed::plane(point, normal, k, 4.0)
        };
        // Isotropic, or axial friction along the nodes' axes; with or without a static
        // peak; the slope small (a damper) or large (saturated, over the peak's decay).
        let mut friction = Friction::new(0.6, (2.0 + next()) * 10f64.powf(1.5 + 1.5 * next()));
        if next() > 0.0 {
            friction = friction.with_axial(0.25, (1.5 + next()) * 10f64.powf(1.5 + 1.5 * next()));
        }
        if next() > -0.3 {
            friction = friction.with_static_scale(1.5 + next());
        }
        let mut seabed = base.with_friction(friction);
        seabed.damping_ramp = 0.05;
        let mut water = Water::new(1.1)
            .with_current(Current::Profile(vec![(-1.5, u0), (0.0, u1)]))
            .with_seabed(seabed);
        water.drag_smoothing = 0.2;
        let net = crate::system::Network::from(problem)
            .with_water(water)
            .with_line_hydro(
                0,
                LineHydro {
                    diameter: 0.4,
                    cd: 1.2,
                    cd_axial: 0.4,
                    ca: 0.8,
                    ca_axial: 0.2,
                },
            )
            .with_point_hydro(PointHydro {
                // In the surface band, where the submerged fraction varies.
                node: 2,
                volume: 0.05,
                cda: 0.7,
                ca: 0.5,
            });
        let (sys, state) = PhSystem::new(net).unwrap();
        check_system_jacobian(&sys, &state, &mut next, scheme, false);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        #[test]
        fn water_jacobian_matches_finite_differences(seed in proptest::collection::vec(-1.0f64..1.0, 37..80)) {
            for scheme in [Scheme::DiscreteGradient, Scheme::Midpoint] {
                check_water_jacobian::<2>(&seed, scheme);
                check_water_jacobian::<3>(&seed, scheme);
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(16))]
        #[test]
        fn network_jacobian_matches_finite_differences(seed in proptest::collection::vec(-1.0f64..1.0, 37..80)) {
            for scheme in [Scheme::DiscreteGradient, Scheme::Midpoint] {
                check_network_jacobian::<1>(&seed, scheme);
                check_network_jacobian::<2>(&seed, scheme);
                check_network_jacobian::<3>(&seed, scheme);
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(16))]
        #[test]
        fn newton_jacobian_matches_finite_differences(seed in proptest::collection::vec(-1.0f64..1.0, 37..80)) {
            for scheme in [Scheme::DiscreteGradient, Scheme::Midpoint] {
                for material in laws() {
                    check_jacobian::<1>(&seed, scheme, material);
                    check_jacobian::<2>(&seed, scheme, material);
                    check_jacobian::<3>(&seed, scheme, material);
                }
            }
        }
    }
}

#[cfg(test)]
mod body_tests;
