//! The winch drums' part of a step (docs/method.md §23.6): each drum's payout increment is
//! an unknown of the Newton vector (a slot after the nodes and the rigid bodies' slots), the
//! drum node's increment follows from it, and the drum's row balances the rope's pull against
//! its inertia, motor, damping and brake.
//!
//! A drum's slot holds `(Δp, 0, …)`: the components after the first are placeholders whose
//! rows are `u = 0`.

use crate::body::{BodyState, Mat3, Turn, Vec3, embed};
use crate::body_step::{rotation_slot, unknowns};
use crate::linsolve::{Block, BlockJacobian};
use crate::system::{PhSystem, Vector};
use crate::winch::WinchDrum;

/// One drum's data for a step, fixed before the Newton solve.
#[derive(Debug, Clone, Copy)]
pub(crate) struct DrumStep<const D: usize> {
    /// The winch's index.
    pub winch: usize,
    /// Its slot's index among the slots (after the nodes).
    pub slot: usize,
    /// The drum node and the drum element's other node.
    pub node: usize,
    pub other: usize,
    /// The drum element.
    pub element: usize,
    /// The drum node's increment at `Δp = 0` [m] (the drum's own motion; 0 for a drum on a
    /// rigid body, whose motion the body's slots give).
    pub base: Vector<D>,
    /// A drum on a rigid body: the body and the drum point in body axes [m] (docs/method.md
    /// §23.7); the drum node is the body's attached node, its slide `λ t̂ Δp` added.
    pub body: Option<(usize, Vec3)>,
    /// The drum node's increment per metre paid out, `λ t̂` [m/m].
    pub axis: Vector<D>,
    /// The stretch `λ` of the path: the rope passes over the drum at `λ ṗ`.
    pub stretch: f64,
    /// The payout speed at the step's start [m/s].
    pub speed: f64,
    /// The drum's inertia per unit payout, `λ² J/R²` [kg].
    pub inertia: f64,
    /// The motor's pull per unit payout at the mid time, `λ f(t_{n+½})` [N] (hauling in
    /// positive).
    pub force: f64,
    /// The derivative part's gain `τ/Δt` (dimensionless): the drum's derivative time `τ` [s]
    /// over the time between the previous accepted step's mid time and this step's,
    /// `Δt = (h_{n−1} + h)/2`; 0 when the drum has none or no previous pull is known.
    pub derivative: f64,
    /// The previous accepted step's pull per unit payout, `λ T_{n−½}` [N] (0 with
    /// `derivative` 0).
    pub pull_before: f64,
}

impl<const D: usize> DrumStep<D> {
    /// The motor's pull per unit payout [N] (hauling in positive) with the drum node's
    /// residual along the path `along = λ t̂·R_d` [N] (the rope's pull `λ T = −along`): the
    /// motor's `λ f` plus the derivative part's `−λ τ (T_{n+½} − T_{n−½})/Δt =
    /// (τ/Δt)(along + λ T_{n−½})` (docs/method.md §23.6). Without a derivative part it is
    /// `λ f` itself, untouched by `along`.
    pub fn drive(&self, along: f64) -> f64 {
        if self.derivative > 0.0 {
            self.force + self.derivative * (along + self.pull_before)
        } else {
            self.force
        }
    }

    /// The payout speed [m/s] at the end of a step of `h` [s] that paid out `dp` [m]: the
    /// midpoint rule's `2Δp/h − ṗₙ`, or for a drum without inertia, which has no speed of its
    /// own, the step's mean `Δp/h` (the midpoint value would alternate about it).
    pub fn speed_after(&self, dp: f64, h: f64) -> f64 {
        let u = dp / h;
        if self.inertia > 0.0 {
            2.0 * u - self.speed
        } else {
            u
        }
    }
}

/// The drum of winch `k` of `sys` (a winch with a drum).
fn drum_of<const D: usize, M>(sys: &PhSystem<D, M>, k: usize) -> &WinchDrum {
    match &sys.winches[k].drum {
        Some((d, _)) => d,
        None => unreachable!("a drum step belongs to a winch with a drum"),
    }
}

/// The damping's and brake's force per unit payout (opposing it) at the mid-step payout
/// speed `u` [m/s] of drum step `d`, and its derivative in `u`: the drum's law at the rope's
/// speed over the drum, `λ u`.
fn resistance<const D: usize, M>(sys: &PhSystem<D, M>, d: &DrumStep<D>, u: f64) -> (f64, f64) {
    let (f, df) = drum_of(sys, d.winch).resistance(d.stretch * u);
    (d.stretch * f, d.stretch * d.stretch * df)
}

/// Writes the drum nodes' increments `base + axis Δp` into `x` from the slots `slots` (on a
/// rigid body, adds the slide `axis Δp` to the body's increment of the node, which `x` has).
pub(crate) fn fill_drums<const D: usize>(
    drums: &[DrumStep<D>],
    slots: &[Vector<D>],
    x: &mut [Vector<D>],
) {
    for d in drums {
        let slide = d.axis * slots[d.slot][0];
        x[d.node] = match d.body {
            Some(_) => x[d.node] + slide,
            None => d.base + slide,
        };
    }
}

/// The drums' rows into `res[n..]` (their own slots) and, with `jac`, their blocks; reads
/// each drum node's row and diagonal block before they are masked. Returns the squares of
/// the drums' own force terms (force scale).
///
/// Row: `g = m_d (2/h)(Δp/h − ṗ_n) + λ t̂·R_d + f + f_r(Δp/h)`, with `R_d` the drum node's
/// residual (the rope's pull on the drum is `−λ t̂·R_d`), `f` the motor's pull with its
/// derivative part ([`DrumStep::drive`]) and `f_r` the damping and brake. The derivative
/// part scales the pull's derivatives by `1 + τ/Δt`.
pub(crate) fn terms<const D: usize, M>(
    sys: &PhSystem<D, M>,
    drums: &[DrumStep<D>],
    (h, bodies): (f64, &[BodyState]),
    slots: &[Vector<D>],
    res: &mut [Vector<D>],
    mut jac: Option<&mut BlockJacobian<D>>,
) -> f64 {
    let n = sys.mesh.n_nodes();
    let inv_h = 1.0 / h;
    let mut scale2 = 0.0;
    for d in drums {
        let dp = slots[d.slot][0];
        let u = dp * inv_h;
        let (f_r, df_r) = resistance(sys, d, u);
        let inertia = d.inertia * 2.0 * inv_h * (u - d.speed);
        let pull = d.axis.dot(&res[d.node]);
        let drive = d.drive(pull);
        let mut row = Vector::<D>::zeros();
        row[0] = inertia + pull + drive + f_r;
        res[n + d.slot] = row;
        let mi = d.inertia * 2.0 * inv_h;
        // The derivative part's two pulls, which cancel to its own (0 without one).
        let (fd, fd_before) = (d.derivative * pull, d.derivative * d.pull_before);
        scale2 += mi * mi * (u * u + d.speed * d.speed)
            + d.force * d.force
            + f_r * f_r
            + fd * fd
            + fd_before * fd_before;
        let Some(j) = jac.as_deref_mut() else {
            continue;
        };
        let slots_n = j.border.slots;
        // The pull's derivatives, with the derivative part's share (1 without one).
        let gain = 1.0 + d.derivative;
        let mut own = Block::<D>::identity();
        own[(0, 0)] = d.inertia * 2.0 * inv_h * inv_h
            + gain * d.axis.dot(&(j.diag[d.node] * d.axis))
            + df_r * inv_h;
        j.border.own[d.slot * slots_n + d.slot] = own;
        if let Some((b, s)) = d.body {
            let model = &sys.bodies[b];
            let free_body = model.motion.is_none();
            body_blocks(
                d,
                (b, &s, free_body, gain),
                (&bodies[b], slots, model.gyration()),
                j,
            );
        }
        let free = sys.free[d.other];
        if !free.iter().any(|&f| f) {
            continue;
        }
        // The drum element's blocks: ∂R_d/∂x_o and ∂R_o/∂x_d (the drum node is its first).
        let (d_o, o_d) = (j.off[d.element][0], j.off[d.element][1]);
        let along = d.axis.transpose() * d_o * gain;
        let across = o_d * d.axis;
        let mut row_blk = Block::<D>::zeros();
        let mut col_blk = Block::<D>::zeros();
        for k in 0..D {
            if free[k] {
                row_blk[(0, k)] = along[k];
                col_blk[(k, 0)] = across[k];
            }
        }
        j.border.links.push((d.other, d.slot, row_blk, col_blk));
    }
    scale2
}

/// The blocks between the row and slot of drum `d` on rigid body `b` (drum point `s`, body
/// axes) and the body's rows and slots: the drum node moves with the body's `(Δx, w)` and
/// slides with `Δp`, so the drum's row depends on the body's slots through the node's
/// residual `R_d`, `∂R_d/∂(Δx, w) = K_d [I, ∂(moved)/∂w]`, and the body's rows on `Δp`,
/// `∂R_d/∂Δp = K_d λ t̂` (force row; the torque row, scaled by `1/r_g`, through its arm),
/// unless its motion is prescribed (`free_body` false: its rows are `δu = 0`). The drum's row
/// takes the pull's derivatives times `gain`, `1 + τ/Δt` with a derivative part.
fn body_blocks<const D: usize>(
    d: &DrumStep<D>,
    (b, s, free_body, gain): (usize, &Vec3, bool, f64),
    (st, slots, gyration): (&BodyState, &[Vector<D>], f64),
    j: &mut BlockJacobian<D>,
) {
    let n_slots = j.border.slots;
    let (_, w) = unknowns(slots, b);
    let turn = Turn::new(&st.orientation, &w);
    let p = turn.point(s);
    let k = crate::body_step::embed_block(&j.diag[d.node]);
    let axis = embed(&d.axis);
    // The drum's row against the body's slots.
    let along = k.transpose() * axis * gain;
    let mut by_dx = Block::<D>::zeros();
    let mut by_w = Block::<D>::zeros();
    let along_w = p.dw.transpose() * along;
    let (dx_row, w_row) = (
        crate::body::project::<D>(&along),
        rotation_slot::<D>(&along_w),
    );
    for c in 0..D {
        by_dx[(0, c)] = dx_row[c];
        by_w[(0, c)] = w_row[c];
    }
    j.border.own[d.slot * n_slots + 2 * b] += by_dx;
    j.border.own[d.slot * n_slots + 2 * b + 1] += by_w;
    if !free_body {
        return;
    }
    // The body's rows against the drum's slot.
    let pull = k * axis;
    let half = Mat3::identity() - crate::body::skew(&w) * 0.5;
    let turned = half * crate::body::skew(&p.mean) * turn.rot.transpose() * pull / gyration;
    let (f_col, t_col) = (
        crate::body::project::<D>(&pull),
        rotation_slot::<D>(&turned),
    );
    let mut f_blk = Block::<D>::zeros();
    let mut t_blk = Block::<D>::zeros();
    for r in 0..D {
        f_blk[(r, 0)] = f_col[r];
        t_blk[(r, 0)] = t_col[r];
    }
    j.border.own[2 * b * n_slots + d.slot] += f_blk;
    j.border.own[(2 * b + 1) * n_slots + d.slot] += t_blk;
}

/// The drum's share of a solved step with payout increment `dp` [m] over `h` [s] and the drum
/// node's residual (its reaction) `reaction` [N]: the energy the winch supplies (the reaction's
/// work over the drum's own motion, `R·base`, and the motor's, `−f Δp`) and the energy the
/// damping and brake dissipate, `f_r(Δp/h) Δp ≥ 0` [J]; and the motor's part of the supply,
/// `−f Δp` [J], `f` with its derivative part at the converged reaction ([`DrumStep::drive`]).
pub(crate) fn shares<const D: usize, M>(
    sys: &PhSystem<D, M>,
    d: &DrumStep<D>,
    dp: f64,
    h: f64,
    reaction: &Vector<D>,
) -> (f64, f64, f64) {
    let (f_r, _) = resistance(sys, d, dp / h);
    let motor = -d.drive(d.axis.dot(reaction)) * dp;
    (reaction.dot(&d.base) + motor, f_r * dp, motor)
}
