//! Winches: a string paid out from, or hauled in onto, a drum at its first node
//! (docs/method.md §23).
//!
//! A winch owns the first elements of one string (one element group whose elements run in
//! a chain along its path). The elements still on the drum are *parked*: outside the group's
//! range, so that they carry no mass, weight or stress, with their nodes held at the drum
//! point. The first element off the drum, the *drum element*, has a variable reference
//! length; every other element of the string keeps the string's element length `L`. When
//! the drum element's length leaves `[L/2, 3L/2]`, one element is brought off the drum
//! (paying out) or put back on it (hauling in), so the string's node identities never
//! change. This module holds the plain data and the state transfers; the step that books
//! their energy is in the simulation.

use crate::body::{BodyState, Vec3, project};
use crate::error::SetupError;
use crate::mesh::Mesh;
use nalgebra::SVector;
use std::ops::Range;
use std::sync::Arc;

/// A drum on a rigid body: the body's index, the index of the body's attachment that holds
/// the drum node, and the drum point in body axes [m].
pub(crate) type BodyDrum = (usize, usize, Vec3);

/// A winch's paid-out length [m] as a function of time `t` [s]: the length paid out since
/// `t = 0` (negative: hauled in), 0 at `t = 0`.
pub type PayoutFn = Arc<dyn Fn(f64) -> f64 + Send + Sync>;

/// A moving drum's position [m] (`x, y, z`; `z` unused in 2D) as a function of time `t`
/// [s], at the drum node's position at `t = 0`.
pub type DrumFn = Arc<dyn Fn(f64) -> [f64; 3] + Send + Sync>;

/// A drum's motor force [N] at the rope (the motor torque over the drum radius) as a function
/// of time `t` [s]; positive hauls in.
pub type DrumForceFn = Arc<dyn Fn(f64) -> f64 + Send + Sync>;

/// A winch drum whose payout is a state of the system rather than prescribed (docs/method.md
/// §23.6): the payout `p` moves by the rope's pull against the drum's inertia, its motor, its
/// damping and its brake, all inside the exact step. With `force = T_ref(t)` and a damping
/// `d`, it is a tension controller: at steady state the drum pays out at `(T − T_ref)/d`, a
/// proportional law of the payout speed on the tension error; `derivative_time` adds a
/// derivative part on the tension's rate.
#[derive(Clone)]
pub struct WinchDrum {
    /// The drum's inertia at the rope, `J/R²` [kg] (`J` the drum's and the motor's moment of
    /// inertia [kg·m²], `R` the drum radius [m]); its kinetic energy `½ (J/R²) ṗ²` is part of
    /// `Ĥ`. May be 0.
    pub inertia: f64,
    /// The motor's pull at the rope [N] as a function of time (hauling in positive): the
    /// target tension of a tension controller, or a motor torque over the drum radius. It is
    /// a port: its power is `−f ṗ`.
    pub force: DrumForceFn,
    /// Damping of the payout speed [N·s/m] (`≥ 0`): the force `−d ṗ` on the payout, a
    /// resistance.
    pub damping: f64,
    /// A brake: the largest force it holds [N] and the slip speed [m/s] of its smoothed
    /// Coulomb law `−F_b ṗ/√(ṗ² + s²)` (a resistance: the brake holds a pull `T < F_b` with a
    /// creep of about `s T/√(F_b² − T²)` and slips above it).
    pub brake: Option<(f64, f64)>,
    /// The derivative time `τ` [s] of the tension controller (`≥ 0`, finite; 0: no
    /// derivative part): the motor adds the pull `−τ dT/dt` to `force`, so that at zero
    /// inertia the drum pays out at `λ d ṗ = (T − T_ref) + τ dT/dt` (`T` the rope's pull at
    /// the drum; gains `1/d` and `τ/d`). `dT/dt` is taken inside the step between the mid
    /// times of the previous accepted step and this one (docs/method.md §23.6); off on a
    /// run's first step. Not with `dg4` (refused by name).
    pub derivative_time: f64,
}

impl std::fmt::Debug for WinchDrum {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("WinchDrum")
            .field("inertia", &self.inertia)
            .field("damping", &self.damping)
            .field("brake", &self.brake)
            .field("derivative_time", &self.derivative_time)
            .finish_non_exhaustive()
    }
}

impl WinchDrum {
    /// The resistance's force on the payout [N] (opposing it) at the mid-step payout speed
    /// `u` [m/s], and its derivative in `u` [N·s/m]: damping and brake.
    pub fn resistance(&self, u: f64) -> (f64, f64) {
        let (mut f, mut df) = (self.damping * u, self.damping);
        if let Some((hold, slip)) = self.brake {
            let root = (u * u + slip * slip).sqrt();
            f += hold * u / root;
            df += hold * slip * slip / (root * root * root);
        }
        (f, df)
    }
}

/// A winch at the first node of a string (the drum), paying the string out or hauling it
/// in as a prescribed payout of time, or with a drum of its own (`drum`).
#[derive(Clone)]
pub struct Winch {
    /// Name for outputs and messages.
    pub name: String,
    /// The element group (a string) it pays out. Its elements run in a chain along its path,
    /// all of one reference length `L` (to 1e-6); the path's first node is the drum.
    pub group: usize,
    /// How many of the group's first elements start on the drum (parked: their nodes at
    /// the drum point): the cable the drum can pay out beyond the starting length is
    /// `reserve · L` [m] (plus half an element).
    pub reserve: usize,
    /// The paid-out length [m] since `t = 0` as a function of `t` [s] (negative: hauled
    /// in). It must be 0 at `t = 0`.
    pub payout: PayoutFn,
    /// The drum's position as a function of time (a crane's trolley); `None`: the drum stays
    /// at the first node's initial position.
    pub drum_motion: Option<DrumFn>,
    /// A drum with dynamics (inertia, motor, damping, brake); `None`: the payout follows
    /// `payout`, which is then unused with a drum.
    pub drum: Option<WinchDrum>,
}

impl std::fmt::Debug for Winch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Winch")
            .field("name", &self.name)
            .field("group", &self.group)
            .field("reserve", &self.reserve)
            .finish_non_exhaustive()
    }
}

/// The state of one winch: which element of its string is the drum element, the straight
/// path its first node (the drum node) follows since the last cut, and the energy the winch
/// has supplied so far.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct WinchState {
    /// Index of the drum element within the string (0 = its first element): the elements
    /// before it are on the drum.
    pub drum: usize,
    /// Where the drum node was at the last cut [m], relative to the drum point then (`x, y,
    /// z`; `z` unused in 2D).
    pub origin: [f64; 3],
    /// The unit direction out of the drum along which the drum node moves (`x, y, z`).
    pub direction: [f64; 3],
    /// The stretch `λ` of the drum element at the last cut: the drum node moves `λ` metres
    /// per metre paid out.
    pub stretch: f64,
    /// The payout [m] at the last cut.
    pub payout_cut: f64,
    /// The reference length [m] between the drum node and the drum point at the last cut
    /// (the cable in the model that is still on the drum, drawn straight behind it).
    pub behind_cut: f64,
    /// The payout [m] the state was brought to.
    pub payout: f64,
    /// Energy [J] the winch has supplied to the system since `t = 0` (negative: taken).
    pub energy: f64,
    /// The payout speed `ṗ` [m/s] at the state (a drum's state; with a prescribed payout, 0).
    #[cfg_attr(feature = "serde", serde(default))]
    pub speed: f64,
    /// Energy [J] the drum's damping and brake have dissipated since `t = 0` (≥ 0).
    #[cfg_attr(feature = "serde", serde(default))]
    pub dissipated: f64,
    /// Energy [J] the drum's motor has supplied since `t = 0` (negative: taken), part of
    /// `energy`.
    #[cfg_attr(feature = "serde", serde(default))]
    pub motor: f64,
    /// The rope's pull at the drum [N] over the last accepted step, `T_{n−½} = −t̂·R_d` at
    /// its mid time (the drum's reaction along the rope), for the derivative part of a drum
    /// with a derivative time (0 otherwise).
    #[cfg_attr(feature = "serde", serde(default))]
    pub pull: f64,
    /// The size [s] of the step `pull` was taken over; 0 while no pull is known (before a
    /// run's first step, or without a derivative time): the derivative part is off then.
    #[cfg_attr(feature = "serde", serde(default))]
    pub pull_step: f64,
}

impl WinchState {
    /// The reference length [m] between the drum node and the drum point at `payout`.
    pub fn behind(&self, payout: f64) -> f64 {
        self.behind_cut - (payout - self.payout_cut)
    }
}

/// A winch as the system keeps it: its string's elements and nodes, the string's element
/// length, the drum point and the string's body force.
#[derive(Clone)]
pub(crate) struct WinchModel<const D: usize> {
    /// Name for outputs and messages.
    pub name: String,
    /// Its element group.
    pub group: usize,
    /// The group's elements, parked ones included.
    pub elements: Range<usize>,
    /// The string's nodes along its path: element `elements.start + j` is
    /// `[nodes[j], nodes[j + 1]]`.
    pub nodes: Vec<usize>,
    /// The string's element length `L` [m].
    pub l: f64,
    /// The drum point at `t = 0` [m].
    pub drum_point: SVector<f64, D>,
    /// The drum's motion; `None`: it stays at `drum_point`.
    pub drum_motion: Option<DrumFn>,
    /// The string's body force per unit reference length [N/m].
    pub body_force: SVector<f64, D>,
    /// The payout function.
    pub payout: PayoutFn,
    /// The drum's dynamics and its slot in the Newton vector (after the nodes); `None`: the
    /// payout is prescribed.
    pub drum: Option<(WinchDrum, usize)>,
    /// A drum on a rigid body: the body, the body's attachment that holds the drum node, and
    /// the drum point in body axes [m]; the drum point moves with the body, the path stays in
    /// space axes. `None`: a drum of space (`drum_point`, `drum_motion`).
    pub body: Option<BodyDrum>,
}

/// Where a winch's drum point is at one instant [m] and its velocity [m/s].
#[derive(Debug, Clone, Copy)]
pub(crate) struct DrumFrame<const D: usize> {
    /// The drum point [m].
    pub point: SVector<f64, D>,
    /// The drum point's velocity [m/s].
    pub velocity: SVector<f64, D>,
}

impl<const D: usize> std::fmt::Debug for WinchModel<D> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("WinchModel")
            .field("name", &self.name)
            .field("group", &self.group)
            .field("elements", &self.elements)
            .field("l", &self.l)
            .finish_non_exhaustive()
    }
}

/// Why a winch cannot follow its payout.
#[derive(Debug, Clone, PartialEq)]
pub enum WinchLimit {
    /// The payout function is not finite.
    NotFinite(f64),
    /// The payout asks for more cable than the drum holds.
    Empty {
        /// The payout asked for [m].
        payout: f64,
        /// The most the drum can pay out [m].
        capacity: f64,
    },
    /// The payout hauls in more than the string has off the drum (half an element stays).
    HauledIn {
        /// The payout asked for [m].
        payout: f64,
        /// The least payout the string allows [m].
        least: f64,
    },
}

impl std::fmt::Display for WinchLimit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NotFinite(p) => write!(f, "its payout is not finite ({p})"),
            Self::Empty { payout, capacity } => write!(
                f,
                "its payout {payout} m is more than the drum holds ({capacity} m: give the winch a larger reserve)"
            ),
            Self::HauledIn { payout, least } => write!(
                f,
                "its payout {payout} m hauls in more than the string has off the drum (the least payout is {least} m: half an element stays off the drum)"
            ),
        }
    }
}

/// The first `D` components of `a`.
fn vec_of<const D: usize>(a: &[f64; 3]) -> SVector<f64, D> {
    SVector::<f64, D>::from_fn(|k, _| a[k])
}

/// `v` as three components (`z = 0` in 2D).
fn arr_of<const D: usize>(v: &SVector<f64, D>) -> [f64; 3] {
    let mut a = [0.0; 3];
    for k in 0..D {
        a[k] = v[k];
    }
    a
}

impl<const D: usize> WinchModel<D> {
    /// The drum element's mesh index in `ws`.
    pub fn drum_element(&self, ws: &WinchState) -> usize {
        self.elements.start + ws.drum
    }

    /// The drum node of `ws`.
    pub fn drum_node(&self, ws: &WinchState) -> usize {
        self.nodes[ws.drum]
    }

    /// The string's reference length off the drum [m] at `payout` (the part beyond the
    /// drum point).
    pub fn length_off(&self, ws: &WinchState, payout: f64) -> f64 {
        (self.elements.len() - ws.drum) as f64 * self.l - ws.behind(payout)
    }

    /// The unstretched arc length [m] of the string's node `j` (along its path, 0 = the
    /// first parked node) from the drum point in `ws`: `(j − drum) L − b`, `b` the reference
    /// length between the drum node and the drum point. For the last node it is
    /// [`Self::length_off`] at the state's payout, in the same arithmetic.
    pub fn arc_length(&self, ws: &WinchState, j: usize) -> f64 {
        (j as f64 - ws.drum as f64) * self.l - ws.behind(ws.payout)
    }

    /// Checks that the winch in `ws` can follow the payout `payout` [m] without running
    /// out of parked elements or hauling in all but half an element.
    pub fn check(&self, ws: &WinchState, payout: f64) -> Result<(), WinchLimit> {
        if !payout.is_finite() {
            return Err(WinchLimit::NotFinite(payout));
        }
        let capacity = ws.payout_cut + ws.behind_cut + ws.drum as f64 * self.l;
        if payout > capacity {
            return Err(WinchLimit::Empty { payout, capacity });
        }
        let least = payout - self.length_off(ws, payout) + 0.5 * self.l;
        if payout < least {
            return Err(WinchLimit::HauledIn { payout, least });
        }
        Ok(())
    }

    /// The drum point [m] and its velocity [m/s] at time `t` [s] (a central difference).
    pub fn drum_at(&self, t: f64) -> (SVector<f64, D>, SVector<f64, D>) {
        match &self.drum_motion {
            None => (self.drum_point, SVector::zeros()),
            Some(m) => {
                let dt = 1e-6 * t.abs().max(1.0);
                let (a, b) = (vec_of::<D>(&m(t - dt)), vec_of::<D>(&m(t + dt)));
                (vec_of::<D>(&m(t)), (b - a) / (2.0 * dt))
            }
        }
    }

    /// The drum at time `t` [s] with the rigid bodies in `bodies` (a drum on a body moves
    /// with it).
    pub fn frame(&self, t: f64, bodies: &[BodyState]) -> DrumFrame<D> {
        let Some((b, _, s)) = self.body else {
            let (point, velocity) = self.drum_at(t);
            return DrumFrame { point, velocity };
        };
        let st = &bodies[b];
        let arm = st.orientation.transform_vector(&s);
        DrumFrame {
            point: project(&(st.position + arm)),
            velocity: project(&(st.velocity + st.omega_space().cross(&arm))),
        }
    }

    /// The drum node's position [m] and velocity [m/s] at time `t` [s] on the path of `ws`:
    /// `X(t) + origin + direction λ (p(t) − p_cut)`, `X` the drum point, the velocity from
    /// central differences of `X` and `p` (on a rigid body `X` is its point, moving with it).
    pub fn path(
        &self,
        ws: &WinchState,
        t: f64,
        bodies: &[BodyState],
    ) -> (SVector<f64, D>, SVector<f64, D>) {
        let (p, rate) = self.payout_at(ws, t);
        self.path_at(ws, &self.frame(t, bodies), (p, rate))
    }

    /// The payout [m] and its rate [m/s] at time `t` [s]: the prescribed payout's (a central
    /// difference), or with a drum its state's.
    pub fn payout_at(&self, ws: &WinchState, t: f64) -> (f64, f64) {
        if self.drum.is_some() {
            return (ws.payout, ws.speed);
        }
        let dt = 1e-6 * t.abs().max(1.0);
        let rate = ((self.payout)(t + dt) - (self.payout)(t - dt)) / (2.0 * dt);
        ((self.payout)(t), rate)
    }

    /// The drum node's position [m] and velocity [m/s] on the path of `ws` with the drum at
    /// `frame`, payout `p` [m] and payout rate `rate` [m/s].
    pub fn path_at(
        &self,
        ws: &WinchState,
        frame: &DrumFrame<D>,
        (p, rate): (f64, f64),
    ) -> (SVector<f64, D>, SVector<f64, D>) {
        let axis = self.axis(ws);
        (
            frame.point + vec_of::<D>(&ws.origin) + axis * (p - ws.payout_cut),
            frame.velocity + axis * rate,
        )
    }

    /// How far the drum node moves per metre paid out on the path of `ws`: `λ t̂` [m/m].
    pub fn axis(&self, ws: &WinchState) -> SVector<f64, D> {
        vec_of::<D>(&ws.direction) * ws.stretch
    }

    /// Sets the drum node's path in `ws` along its element in the state `(r, c)` (its
    /// direction and stretch there), from the drum node's position: how a run starts from a
    /// state that is not the layout's (an equilibrium), so that the first element that comes
    /// off the drum continues the string's own direction.
    pub fn align(
        &self,
        ws: &mut WinchState,
        r: &[SVector<f64, D>],
        c: &[f64],
        frame: &DrumFrame<D>,
    ) {
        let (a, b) = (self.nodes[ws.drum], self.nodes[ws.drum + 1]);
        let behind = ws.behind(ws.payout);
        self.new_path(ws, (r[a], r[b]), (c[self.drum_element(ws)], behind), frame);
    }

    /// Starts a new path for the drum node at its position `r` with the direction and
    /// stretch of the drum element (whose other node is at `r_next`, strain `c`), from the
    /// drum point of `frame`.
    fn new_path(
        &self,
        ws: &mut WinchState,
        (r, r_next): (SVector<f64, D>, SVector<f64, D>),
        (c, behind): (f64, f64),
        frame: &DrumFrame<D>,
    ) {
        let chord = r_next - r;
        let n = chord.norm();
        let dir = if n > 0.0 {
            chord / n
        } else {
            vec_of::<D>(&ws.direction)
        };
        ws.origin = arr_of(&(r - frame.point));
        ws.direction = arr_of(&dir);
        ws.stretch = c.max(0.0).sqrt();
        ws.payout_cut = ws.payout;
        ws.behind_cut = behind;
    }

    /// The drum element (index along the string) after [`Self::cut`] brings `ws` to
    /// `payout` [m]: the drum node leaves the band `[−ε, L − ε]` of its distance behind the
    /// drum point, `ε = 1e-9 L`, one element at a time (a payout brought back to where a cut
    /// left the drum node, `b = L` up to rounding, puts the element back, so that paying out
    /// and hauling in the same length returns the mesh it started from).
    pub fn drum_after(&self, ws: &WinchState, payout: f64) -> usize {
        let (l, last) = (self.l, self.elements.len() - 1);
        let eps = 1e-9 * l;
        let (mut behind, mut drum) = (ws.behind(payout), ws.drum);
        while behind < -eps && drum > 0 {
            behind += l;
            drum -= 1;
        }
        while behind > l - eps && drum < last {
            behind -= l;
            drum += 1;
        }
        drum
    }

    /// Brings `ws` to `payout` [m] after a step and cuts where the drum node has left its
    /// band: out past the drum point (paying out), an element comes off the drum, its new
    /// drum node `L λ` behind the old one on the path, with the old strain; more than an
    /// element behind the drum point (hauling in), the drum element goes onto the drum (its
    /// first node parked at the drum point at rest) and the next node becomes the drum
    /// node, on a new path along its element. A new drum node moves with the payout rate
    /// `rate` [m/s] along its path.
    pub fn cut(
        &self,
        ws: &mut WinchState,
        (frame, payout, rate): (&DrumFrame<D>, f64, f64),
        (r, v, c): (&mut [SVector<f64, D>], &mut [SVector<f64, D>], &mut [f64]),
    ) {
        let to = self.drum_after(ws, payout);
        ws.payout = payout;
        let l = self.l;
        let (drum, drum_v) = (frame.point, frame.velocity);
        let along = |ws: &WinchState| drum_v + vec_of::<D>(&ws.direction) * (ws.stretch * rate);
        while ws.drum > to {
            let (a, b) = (self.nodes[ws.drum - 1], self.nodes[ws.drum]);
            let e = self.drum_element(ws);
            // The new element has the drum element's strain, and its chord fits it,
            // continuing the drum element's chord (so that the string has no kink at the
            // old drum node, which is free from now on).
            let chord = r[self.nodes[ws.drum + 1]] - r[b];
            let n = chord.norm();
            let dir = if n > 0.0 {
                chord / n
            } else {
                vec_of::<D>(&ws.direction)
            };
            r[a] = r[b] - dir * (c[e].max(0.0).sqrt() * l);
            c[e - 1] = c[e];
            let behind = ws.behind(payout) + l;
            ws.drum -= 1;
            self.new_path(ws, (r[a], r[b]), (c[e - 1], behind), frame);
            v[a] = along(ws);
        }
        while ws.drum < to {
            let (a, b, n) = (
                self.nodes[ws.drum],
                self.nodes[ws.drum + 1],
                self.nodes[ws.drum + 2],
            );
            let e = self.drum_element(ws);
            let behind = ws.behind(payout) - l;
            r[a] = drum;
            v[a] = SVector::zeros();
            c[e] = 0.0;
            ws.drum += 1;
            self.new_path(ws, (r[b], r[n]), (c[e + 1], behind), frame);
            v[b] = along(ws);
        }
    }

    /// Puts `ws` into the system's data: the group's range (the drum element first), which
    /// nodes are held (those on the drum and the drum node) and the body forces of the
    /// string's nodes. Returns whether the set of held nodes changed (then the constrained
    /// sets need rebuilding). Without `always`, nothing is done where the drum element has
    /// not changed.
    pub fn place(
        &self,
        ws: &WinchState,
        mesh: &Mesh,
        range: &mut Range<usize>,
        f_body: &mut [SVector<f64, D>],
        free: &mut [[bool; D]],
        always: bool,
    ) -> bool {
        let first = self.elements.start + ws.drum;
        let moved = range.start != first;
        if !(moved || always) {
            return false;
        }
        let all = 0..self.elements.len();
        self.place_nodes(ws, mesh, range, (f_body, free), all);
        true
    }

    /// [`Self::place`] of `ws` (always), its held flags and body forces set only at the
    /// string's nodes `nodes` (indices along the string, not its last): where a cut moved
    /// the drum element, the nodes between the old and the new drum nodes.
    pub fn place_nodes(
        &self,
        ws: &WinchState,
        mesh: &Mesh,
        range: &mut Range<usize>,
        (f_body, free): (&mut [SVector<f64, D>], &mut [[bool; D]]),
        nodes: Range<usize>,
    ) {
        *range = self.elements.start + ws.drum..self.elements.end;
        let n_el = self.elements.len();
        let lengths = mesh.lengths();
        let half = |j: usize| -> SVector<f64, D> {
            if j >= ws.drum && j < n_el {
                self.body_force * (0.5 * lengths[self.elements.start + j])
            } else {
                SVector::zeros()
            }
        };
        for j in nodes {
            let i = self.nodes[j];
            let before = if j > 0 { half(j - 1) } else { SVector::zeros() };
            f_body[i] = before + half(j);
            free[i] = [j > ws.drum; D];
        }
    }
}

/// Checks the winches of a network and returns their models with their starting states:
/// each winch's group a string whose elements run in a chain of one reference length, its
/// first `reserve` elements (and no more than all but one) at the drum point, no other
/// element, support, load or port at its nodes but the last, and the payout 0 at `t = 0`.
/// `body_force` and `is_string` are the groups' body forces and kinds; `claimed(i)` tells
/// whether node `i` carries a support, load, port, point mass, water point or body; `on_body[k]` is winch
/// `k`'s drum on a rigid body (body, attachment, drum point in body axes), whose nodes on the
/// drum move with the drum point instead of starting at rest.
pub(crate) fn attach<const D: usize>(
    winches: &[Winch],
    mesh: &Mesh,
    groups: &[(Range<usize>, SVector<f64, D>, bool)],
    (r, v): (&[SVector<f64, D>], &[SVector<f64, D>]),
    claimed: impl Fn(usize) -> bool,
    on_body: &[Option<BodyDrum>],
) -> Result<Vec<(WinchModel<D>, WinchState)>, SetupError> {
    let problem = |k: usize, w: &Winch, problem: String| SetupError::Winch {
        index: k,
        name: w.name.clone(),
        problem,
    };
    let mut degree = vec![0usize; mesh.n_nodes()];
    for &[a, b] in mesh.elements() {
        degree[a] += 1;
        degree[b] += 1;
    }
    let mut used = vec![false; groups.len()];
    let mut out = Vec::with_capacity(winches.len());
    let mut n_drums = 0;
    for (k, w) in winches.iter().enumerate() {
        let Some((range, body_force, is_string)) = groups.get(w.group) else {
            return Err(problem(
                k,
                w,
                format!("its string (group {}) does not exist", w.group),
            ));
        };
        if !is_string {
            return Err(problem(k, w, "its group is a spring, not a string".into()));
        }
        if std::mem::replace(&mut used[w.group], true) {
            return Err(problem(
                k,
                w,
                "another winch already pays out its string".into(),
            ));
        }
        let els = &mesh.elements()[range.clone()];
        let mut nodes = vec![els[0][0]];
        for (j, &[a, b]) in els.iter().enumerate() {
            if a != nodes[j] {
                return Err(problem(
                    k,
                    w,
                    format!(
                        "its string's element {j} does not start where element {} ends",
                        j.saturating_sub(1)
                    ),
                ));
            }
            nodes.push(b);
        }
        let l = mesh.lengths()[range.start];
        if let Some(j) = (0..els.len()).find(|&j| {
            let lj = mesh.lengths()[range.start + j];
            (lj - l).abs() > 1e-6 * l
        }) {
            return Err(problem(
                k,
                w,
                format!(
                    "its string's elements must share one reference length, but element {j} has {} m and the first {l} m",
                    mesh.lengths()[range.start + j]
                ),
            ));
        }
        if w.reserve >= els.len() {
            return Err(problem(
                k,
                w,
                format!(
                    "its reserve of {} elements leaves none of the string's {} off the drum",
                    w.reserve,
                    els.len()
                ),
            ));
        }
        let drum_point = r[nodes[0]];
        let body = on_body.get(k).copied().flatten();
        let drum_v = if body.is_some() {
            v[nodes[0]]
        } else {
            SVector::zeros()
        };
        check_start(w, &nodes, (r, v), (drum_point, drum_v)).map_err(|p| problem(k, w, p))?;
        let last = nodes.len() - 1;
        for (j, &i) in nodes[..last].iter().enumerate() {
            let own = if j == 0 { 1 } else { 2 };
            if degree[i] != own || claimed(i) {
                return Err(problem(
                    k,
                    w,
                    format!(
                        "node {j} of its string (mesh node {i}) carries something else (an element of another string, a support, a load, a port, a point mass, a water point or a body): only the string's last node may"
                    ),
                ));
            }
        }
        let dn = nodes[w.reserve];
        let chord = r[nodes[w.reserve + 1]] - r[dn];
        let stretch = chord.norm() / l;
        let state = WinchState {
            drum: w.reserve,
            origin: [0.0; 3],
            direction: arr_of(&(chord / chord.norm())),
            stretch,
            payout_cut: 0.0,
            behind_cut: 0.0,
            payout: 0.0,
            energy: 0.0,
            speed: 0.0,
            dissipated: 0.0,
            motor: 0.0,
            pull: 0.0,
            pull_step: 0.0,
        };
        let drum = match &w.drum {
            None => None,
            Some(d) => {
                check_drum(d).map_err(|p| problem(k, w, p))?;
                Some((d.clone(), n_drums))
            }
        };
        n_drums += usize::from(drum.is_some());
        let model = WinchModel {
            name: w.name.clone(),
            group: w.group,
            elements: range.clone(),
            nodes,
            l,
            drum_point,
            body_force: *body_force,
            payout: w.payout.clone(),
            drum_motion: w.drum_motion.clone(),
            drum,
            body,
        };
        out.push((model, state));
    }
    Ok(out)
}

/// Checks a drum's constants: a finite inertia, damping and derivative time `≥ 0`, a brake's
/// holding force `≥ 0` and slip speed `> 0`, the motor force finite at `t = 0`.
fn check_drum(d: &WinchDrum) -> Result<(), String> {
    let bad = |what: &str, v: f64| Err(format!("its drum's {what} is {v}"));
    if !(d.inertia.is_finite() && d.inertia >= 0.0) {
        return bad("inertia (J/R², kg; must be ≥ 0)", d.inertia);
    }
    if !(d.damping.is_finite() && d.damping >= 0.0) {
        return bad("damping (N·s/m; must be ≥ 0)", d.damping);
    }
    if !(d.derivative_time.is_finite() && d.derivative_time >= 0.0) {
        return bad("derivative time (s; must be ≥ 0)", d.derivative_time);
    }
    if let Some((hold, slip)) = d.brake {
        if !(hold.is_finite() && hold >= 0.0) {
            return bad("brake holding force (N; must be ≥ 0)", hold);
        }
        if !(slip.is_finite() && slip > 0.0) {
            return bad("brake slip speed (m/s; must be > 0)", slip);
        }
    }
    let f0 = (d.force)(0.0);
    if !f0.is_finite() {
        return bad("motor force at t = 0 (N)", f0);
    }
    Ok(())
}

/// Checks how winch `w` starts on its string's `nodes`: its reserve's nodes at the drum point
/// `drum_point` and at rest, the payout 0 at `t = 0`, a drum motion starting at the drum.
fn check_start<const D: usize>(
    w: &Winch,
    nodes: &[usize],
    (r, v): (&[SVector<f64, D>], &[SVector<f64, D>]),
    (drum_point, drum_v): (SVector<f64, D>, SVector<f64, D>),
) -> Result<(), String> {
    if let Some(j) = (1..=w.reserve).find(|&j| r[nodes[j]] != drum_point) {
        return Err(format!(
            "node {j} of its string is on the drum (within the reserve) but not at the drum point"
        ));
    }
    if let Some(j) = (0..=w.reserve).find(|&j| v[nodes[j]] != drum_v) {
        return Err(format!(
            "node {j} of its string is on the drum but does not start with the drum point's velocity {:?} m/s",
            drum_v.as_slice()
        ));
    }
    let p0 = if w.drum.is_some() {
        0.0
    } else {
        (w.payout)(0.0)
    };
    if p0 != 0.0 {
        return Err(format!("its payout at t = 0 is {p0} m, not 0"));
    }
    if let Some(m) = &w.drum_motion {
        let x0 = vec_of::<D>(&m(0.0));
        if (x0 - drum_point).norm() > 1e-9 * drum_point.norm().max(1.0) {
            return Err(format!(
                "its drum motion starts at {:?} m, not at its drum node {:?} m",
                x0.as_slice(),
                drum_point.as_slice()
            ));
        }
    }
    Ok(())
}
