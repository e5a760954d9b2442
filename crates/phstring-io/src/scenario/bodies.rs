//! Rigid bodies of a network (`[bodies.NAME]`, docs/scenario.md "Rigid bodies"): mass,
//! inertia, initial pose and motion, attachment points and the optional wrench port. Each
//! point is a mesh node named `"BODY.POINT"`, created after the `[[node]]`s (bodies and their
//! points in file order) at the point's initial position and moving with the body; strings
//! and springs reach it by that name. A body point cannot be a support, a moving support or a
//! feedback port (the body alone moves it).

use std::collections::{BTreeMap, HashMap, HashSet};
use std::ops::Range;
use std::sync::{Arc, Mutex};

use nalgebra::{Rotation3, UnitQuaternion};
use phstring::body::{Mat3, Vec3};
use phstring::{Attachment, BodyState, BodyWrench, Material, NetworkBuilder, RigidBody, Vector};
use toml::Spanned;

use super::body_motion::MotionSource;
use super::body_water::BodyWaterComponent;
use super::components::{BodyComponent, BodyPointComponent, Components, NamedNode};
use super::expr::{Expr, eval_or_record_at};
use super::refs::Nodes;
use super::spec::{BodySpec, WrenchSpec};
use super::{ScenarioError, ScenarioFile};
use crate::text::{clip, num, nums};

/// How far [–] the two smaller principal moments of a body's inertia may add up below the
/// largest (`I₁ + I₂ ≥ I₃`, equal for a flat body) before it is refused: moments typed to a
/// few digits miss equality by about that much.
const INERTIA_SLACK: f64 = 0.02;

/// A validated body (its wrench port is attached by [`ScenarioFile::body_wrenches`], which
/// needs the run's record of expression failures).
pub(super) struct BodyDraft<const D: usize> {
    /// The body, without its wrench port yet.
    pub body: RigidBody<D>,
    /// Per attachment (in the order of `body.attachments`): the node's initial position [m]
    /// and velocity [m/s], and its name `"BODY.POINT"`.
    pub starts: Vec<(Vector<D>, Vector<D>, String)>,
    /// Its prescribed motion, attached by [`ScenarioFile::body_wrenches`] with the run's
    /// record of expression failures.
    pub motion: Option<MotionSource>,
    /// Its feedback law, attached by [`ScenarioFile::body_wrenches`] with the run's record
    /// of expression failures.
    pub feedback: Option<super::body_feedback::FeedbackSource>,
}

/// `v` as a 3-vector (`z = 0` in 2D).
fn embed<const D: usize>(v: &Vector<D>) -> Vec3 {
    Vec3::from_fn(|k, _| if k < D { v[k] } else { 0.0 })
}

/// The first `D` components of `v`.
fn project<const D: usize>(v: &Vec3) -> Vector<D> {
    Vector::<D>::from_fn(|k, _| v[k.min(2)])
}

/// Entries of `map` in the order they appear in the file (by span), names breaking ties.
fn file_order<T>(map: &BTreeMap<String, Spanned<T>>) -> Vec<(&str, &Spanned<T>)> {
    let mut list: Vec<(&str, &Spanned<T>)> = map.iter().map(|(k, v)| (k.as_str(), v)).collect();
    list.sort_by_key(|(_, v)| v.span().start);
    list
}

impl ScenarioFile {
    /// The bodies of a network, each checked, their points added to the mesh as nodes named
    /// `"BODY.POINT"` (after the `[[node]]`s), to `nodes` and to `components`; `gravity`
    /// [m/s²] gives their weights.
    pub(super) fn body_points<'s, const D: usize>(
        &'s self,
        b: &mut NetworkBuilder<D, Material>,
        nodes: &mut Nodes<'s>,
        components: &mut Components,
        gravity: Vector<D>,
    ) -> Result<Vec<BodyDraft<D>>, ScenarioError> {
        let mut drafts = Vec::new();
        for (name, spec) in file_order(&self.scenario.bodies) {
            let key = format!("bodies.{}", clip(name));
            self.checked_name(&key, name, spec.span())?;
            if D < 2 {
                return Err(self.invalid(
                    &key,
                    spec.span(),
                    format!("is a rigid body, but the scenario has dimension {D}: bodies need dimension 2 or 3"),
                ));
            }
            let spec = spec.get_ref();
            let (mut body, omega, motion) = self.body::<D>(&key, name, spec, gravity)?;
            let feedback = self.feedback_of::<D>(&key, spec, &body, motion.is_some())?;
            let (report, starts, points) = self.points(&key, spec, &mut body, &omega, b)?;
            for (p, &(_, node, _)) in starts.iter().zip(&points) {
                components.nodes.push(NamedNode {
                    name: p.2.clone(),
                    node,
                    position: p.0.as_slice().to_vec(),
                });
            }
            nodes.add_body(name, points.iter().map(|&(p, n, _)| (p, n)).collect());
            let mut component = body_component(&body, spec, report);
            component.motion = motion.as_ref().map_or_else(Vec::new, MotionSource::texts);
            component.feedback = feedback.as_ref().map_or_else(Vec::new, |f| f.texts());
            components.bodies.push(component);
            drafts.push(BodyDraft {
                body,
                starts,
                motion,
                feedback,
            });
        }
        nodes.n_nodes = b.n_nodes();
        Ok(drafts)
    }

    /// The feedback of body `body` (at `key`, `spec`), refused beside a prescribed motion
    /// (`moved`); `None` without `feedback`.
    fn feedback_of<const D: usize>(
        &self,
        key: &str,
        spec: &BodySpec,
        body: &RigidBody<D>,
        moved: bool,
    ) -> Result<Option<super::body_feedback::FeedbackSource>, ScenarioError> {
        let Some(f) = &spec.feedback else {
            return Ok(None);
        };
        if moved {
            return Err(self.invalid(
                &format!("{key}.feedback"),
                f.span(),
                "is given, but the body has a prescribed motion, which takes no feedback law (its port is the motion): remove `feedback`",
            ));
        }
        let turns = if D == 2 { 1 } else { 3 };
        let angles = self.turn_vector(
            &format!("{key}.orientation"),
            spec.orientation.as_ref(),
            turns,
        )?;
        let pose = (&body.initial.position, &angles);
        self.body_feedback_source::<D>(key, f, pose, self.first_mid_time())
            .map(Some)
    }

    /// Body `name` (at `key`) without its points: mass, weight, inertia, water terms and
    /// initial state (a prescribed motion's at `t = 0`); also its initial angular velocity in
    /// space axes [rad/s] and its prescribed motion.
    fn body<const D: usize>(
        &self,
        key: &str,
        name: &str,
        spec: &BodySpec,
        gravity: Vector<D>,
    ) -> Result<(RigidBody<D>, Vec3, Option<MotionSource>), ScenarioError> {
        let k = |f: &str| format!("{key}.{f}");
        let mass = self.positive(&k("mass"), &spec.mass)?;
        let weight = gravity * mass;
        let w = super::rounding::length(&weight);
        if w.is_nan() || w > super::material::MAX_NODAL_FORCE {
            return Err(self.invalid(
                &k("mass"),
                spec.mass.span(),
                format!(
                    "= {} kg: its weight under body_force.gravity is {} N, above {:.0e} N (forces this large overflow the residual, which squares them)",
                    num(mass),
                    num(w),
                    super::material::MAX_NODAL_FORCE
                ),
            ));
        }
        let inertia = self.inertia::<D>(&k("inertia"), &spec.inertia)?;
        let position = embed(&self.vector::<D>(&k("position"), &spec.position)?);
        let velocity = match &spec.velocity {
            Some(v) => embed(&self.vector::<D>(&k("velocity"), v)?),
            None => Vec3::zeros(),
        };
        let turns = if D == 2 { 1 } else { 3 };
        let angles = self.turn_vector(&k("orientation"), spec.orientation.as_ref(), turns)?;
        let rates = self.turn_vector(
            &k("angular_velocity"),
            spec.angular_velocity.as_ref(),
            turns,
        )?;
        let deg = std::f64::consts::PI / 180.0;
        let rot = phstring::signal::rotation(angles.x * deg, angles.y * deg, angles.z * deg);
        let orientation =
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(rot));
        let hydro = self.body_hydro::<D>(key, spec)?;
        let motion = self.body_motion_source::<D>(key, spec, self.first_mid_time())?;
        let (initial, rates) = match &motion {
            None => (
                BodyState::new(position, velocity, orientation, rates),
                rates,
            ),
            Some(m) => {
                let (x, q, v, w) = self.motion_start::<D>(key, spec, m, &position, &orientation)?;
                (BodyState::new(x, v, q, w), w)
            }
        };
        let body = RigidBody {
            name: name.to_string(),
            mass,
            inertia,
            weight,
            attachments: Vec::new(),
            initial,
            wrench: None,
            hydro,
            motion: None,
            feedback: None,
        };
        Ok((body, rates, motion))
    }

    /// `bodies.NAME.inertia` (`key`): the principal moments `[Ixx, Iyy, Izz]` or the entries
    /// `[Ixx, Iyy, Izz, Ixy, Ixz, Iyz]` [kg·m²]; in 3D positive definite with principal
    /// moments `I₁ + I₂ ≥ I₃` (within [`INERTIA_SLACK`]), in 2D `Izz > 0` and no negative
    /// moment.
    fn inertia<const D: usize>(
        &self,
        key: &str,
        v: &Spanned<Vec<f64>>,
    ) -> Result<Mat3, ScenarioError> {
        let x = v.get_ref();
        let bad = |reason: String| self.invalid(key, v.span(), reason);
        if x.len() != 3 && x.len() != 6 {
            return Err(bad(format!(
                "has {} numbers: give the principal moments [Ixx, Iyy, Izz] or the tensor's entries [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] (kg·m², body axes)",
                x.len()
            )));
        }
        if let Some(c) = x.iter().find(|c| !c.is_finite()) {
            return Err(bad(format!("has a non-finite entry {}", num(*c))));
        }
        let off = |i: usize| x.get(i).copied().unwrap_or(0.0);
        let j = Mat3::new(
            x[0],
            off(3),
            off(4),
            off(3),
            x[1],
            off(5),
            off(4),
            off(5),
            x[2],
        );
        if D == 2 {
            if x[2] <= 0.0 {
                return Err(bad(format!(
                    "has Izz = {} kg·m²: a body in 2D turns about z, so its moment about z must be positive",
                    num(x[2])
                )));
            }
            if x[0] < 0.0 || x[1] < 0.0 {
                return Err(bad(format!(
                    "= {} kg·m² has a negative moment: a moment of inertia is never negative (in 2D only Izz is used)",
                    nums(x)
                )));
            }
            return Ok(j);
        }
        let moments = j.symmetric_eigenvalues();
        let mut m: Vec<f64> = moments.iter().copied().collect();
        m.sort_by(f64::total_cmp);
        if !moments.iter().all(|&l| l > 0.0) {
            return Err(bad(format!(
                "= {} kg·m² is not positive definite (principal moments {} kg·m²): every moment of inertia must be positive",
                nums(x),
                nums(&m)
            )));
        }
        // I₁ + I₂ ≥ I₃ for every mass distribution (equality for a flat one: a thin ring's
        // moments typed to two digits, 0.31, 0.31 and 0.63, miss it by 1.6 %).
        if m[0] + m[1] < m[2] * (1.0 - INERTIA_SLACK) {
            return Err(bad(format!(
                "= {} kg·m² has the principal moments {} kg·m², whose two smaller add up to less than the largest (by more than 2 %): no body has them (I₁ + I₂ ≥ I₃)",
                nums(x),
                nums(&m)
            )));
        }
        Ok(j)
    }

    /// An orientation [deg] or angular velocity [rad/s] at `key` with `n` components (3 in
    /// 3D, 1 in 2D: about `z`), as a 3-vector; zero when absent.
    pub(super) fn turn_vector(
        &self,
        key: &str,
        v: Option<&Spanned<Vec<f64>>>,
        n: usize,
    ) -> Result<Vec3, ScenarioError> {
        let Some(v) = v else { return Ok(Vec3::zeros()) };
        let x = v.get_ref();
        if x.len() != n {
            let what = if n == 1 {
                "1 component in 2D (about z)"
            } else {
                "3 components in 3D"
            };
            return Err(self.invalid(key, v.span(), format!("must have {what}, got {}", x.len())));
        }
        if let Some(c) = x.iter().find(|c| !c.is_finite()) {
            return Err(self.invalid(
                key,
                v.span(),
                format!("has a non-finite component {}", num(*c)),
            ));
        }
        Ok(if n == 1 {
            Vec3::new(0.0, 0.0, x[0])
        } else {
            Vec3::new(x[0], x[1], x[2])
        })
    }

    /// The points of the body at `key` (`spec`), each a new node of `b` at its initial
    /// position moving with the body (`omega` [rad/s] in space axes), added to the body's
    /// attachments. Returns their reports, their starts and `(name, node, span)`.
    #[allow(clippy::type_complexity)] // three parallel lists, each used once by the caller
    fn points<'s, const D: usize>(
        &'s self,
        key: &str,
        spec: &'s BodySpec,
        body: &mut RigidBody<D>,
        omega: &Vec3,
        b: &mut NetworkBuilder<D, Material>,
    ) -> Result<
        (
            Vec<BodyPointComponent>,
            Vec<(Vector<D>, Vector<D>, String)>,
            Vec<(&'s str, usize, Range<usize>)>,
        ),
        ScenarioError,
    > {
        let list = file_order(spec.points.get_ref());
        if list.is_empty() {
            return Err(self.invalid(
                &format!("{key}.points"),
                spec.points.span(),
                "is empty: a body needs at least one point for a string or spring to attach to",
            ));
        }
        let st = body.initial;
        let (mut report, mut starts, mut out) = (Vec::new(), Vec::new(), Vec::new());
        for (p, v) in list {
            let pkey = format!("{key}.points.{}", clip(p));
            self.checked_name(&pkey, p, v.span())?;
            let s = self.vector::<D>(&pkey, v)?;
            let arm = st.orientation.transform_vector(&embed(&s));
            let r = project::<D>(&(st.position + arm));
            let vel = project::<D>(&(st.velocity + omega.cross(&arm)));
            let node = b.node(r);
            let name = format!("{}.{p}", body.name);
            body.attachments.push(Attachment { node, point: s });
            report.push(BodyPointComponent {
                name: name.clone(),
                node,
                point: s.as_slice().to_vec(),
                position: r.as_slice().to_vec(),
                attached: Vec::new(),
            });
            starts.push((r, vel, name));
            out.push((p, node, v.span()));
        }
        Ok((report, starts, out))
    }

    /// Refuses a body point (its mesh node in `points`) that is on no string's path and at no
    /// spring's end (`used`), and fills in what attaches to each point in `components`.
    pub(super) fn body_points_used(
        &self,
        components: &mut Components,
        used: &[bool],
    ) -> Result<(), ScenarioError> {
        let strings: Vec<(String, Vec<usize>)> = components
            .strings
            .iter()
            .map(|st| (st.name.clone(), st.path_nodes.clone()))
            .collect();
        let springs: Vec<(String, [usize; 2])> = components
            .springs
            .iter()
            .map(|sp| (sp.name.clone(), sp.nodes))
            .collect();
        for body in &mut components.bodies {
            for p in &mut body.points {
                if !used.get(p.node).copied().unwrap_or(true) {
                    let point = p.name.rsplit_once('.').map_or("", |(_, q)| q);
                    let span =
                        self.scenario.bodies.get(&body.name).and_then(|s| {
                            s.get_ref().points.get_ref().get(point).map(|v| v.span())
                        });
                    return Err(self.invalid(
                        &format!("bodies.{}.points.{}", clip(&body.name), clip(point)),
                        span.unwrap_or(0..0),
                        format!(
                            "(\"{}\", node {}) is on no string's path and at no spring's end: every body point must hold one (remove it, or attach a string to it)",
                            clip(&p.name),
                            p.node
                        ),
                    ));
                }
                p.attached = strings
                    .iter()
                    .filter(|(_, path)| path.contains(&p.node))
                    .map(|(n, _)| format!("string {n}"))
                    .chain(
                        springs
                            .iter()
                            .filter(|(_, ends)| ends.contains(&p.node))
                            .map(|(n, _)| format!("spring {n}")),
                    )
                    .collect();
            }
        }
        Ok(())
    }

    /// Refuses a `[[boundary]]` table that fixes, moves or controls a body point, and a
    /// platform that moves one (`held`: the mesh nodes that the boundary conditions fix, move
    /// or control; `body_nodes`: each body point's node and name).
    pub(super) fn bodies_not_held(
        &self,
        nodes: &Nodes,
        held: &HashSet<usize>,
        body_nodes: &HashMap<usize, String>,
    ) -> Result<(), ScenarioError> {
        let refuse = |key: String, span: Range<usize>, node: usize, what: &str| {
            let name = body_nodes.get(&node).map_or("", String::as_str);
            Err(self.invalid(
                &key,
                span,
                format!(
                    "is body point \"{}\" (node {node}), which its body alone moves: it cannot also be {what} (a force load is allowed; it acts on the body)",
                    clip(name)
                ),
            ))
        };
        for (k, b) in self.scenario.boundary.iter().enumerate() {
            let holds = b.fixed.is_some()
                || b.position.is_some()
                || b.motion_table.is_some()
                || b.control.is_some();
            if !holds {
                continue;
            }
            let key = format!("boundary.{k}.node");
            let node = self.resolve(&key, &b.node, nodes)?;
            if body_nodes.contains_key(&node) && held.contains(&node) {
                return refuse(key, b.node.span(), node, "fixed, moved or controlled");
            }
        }
        for (k, p) in self.scenario.platform.iter().enumerate() {
            for (i, r) in p.nodes.get_ref().iter().enumerate() {
                let key = format!("platform.{k}.nodes.{i}");
                let node = self.resolve(&key, r, nodes)?;
                if body_nodes.contains_key(&node) {
                    return refuse(key, r.span(), node, "moved by a platform");
                }
            }
        }
        Ok(())
    }

    /// Attaches the wrench ports of `[bodies.NAME] wrench` to `drafts` (in the order of
    /// [`Self::body_points`]); a failing expression during the run is recorded in `slot`.
    pub(super) fn body_wrenches<const D: usize>(
        &self,
        drafts: &mut [BodyDraft<D>],
        slot: &Arc<Mutex<Option<String>>>,
    ) -> Result<(), ScenarioError> {
        let t_check = self.first_mid_time();
        for ((name, spec), draft) in file_order(&self.scenario.bodies).into_iter().zip(drafts) {
            if let Some(m) = &draft.motion {
                draft.body.motion = Some(m.motion::<D>(slot));
            }
            if let Some(f) = &draft.feedback {
                draft.body.feedback = Some(f.law::<D>(slot));
            }
            let Some(w) = &spec.get_ref().wrench else {
                continue;
            };
            let key = format!("bodies.{}.wrench", clip(name));
            let WrenchSpec { force, torque, .. } = w.get_ref();
            let turns = if D == 2 { 1 } else { 3 };
            let force = self.wrench_exprs(&format!("{key}.force"), force.as_ref(), D, t_check)?;
            let torque =
                self.wrench_exprs(&format!("{key}.torque"), torque.as_ref(), turns, t_check)?;
            // In 2D a torque's one expression is about z (component 2).
            let signal = |exprs: Vec<Expr>, what: String, first: usize| {
                let slot = slot.clone();
                Arc::new(move |t: f64| {
                    let mut v = Vec3::zeros();
                    for (i, e) in exprs.iter().enumerate() {
                        v[first + i] = eval_or_record_at(e, &slot, &what, first + i, t);
                    }
                    v
                }) as phstring::body::Vec3Fn
            };
            draft.body.wrench = Some(BodyWrench {
                force: signal(force, format!("{key}.force"), 0),
                torque: signal(torque, format!("{key}.torque"), 3 - turns),
            });
        }
        Ok(())
    }

    /// The `n` expressions of `t` at `key` (none given: no expressions, the signal is zero),
    /// each valid at `t_check` [s].
    pub(super) fn wrench_exprs(
        &self,
        key: &str,
        list: Option<&Spanned<Vec<Spanned<String>>>>,
        n: usize,
        t_check: f64,
    ) -> Result<Vec<Expr>, ScenarioError> {
        let Some(list) = list else {
            return Ok(Vec::new());
        };
        if list.get_ref().len() != n {
            return Err(self.invalid(
                key,
                list.span(),
                format!("must have {n} expressions, got {}", list.get_ref().len()),
            ));
        }
        list.get_ref()
            .iter()
            .enumerate()
            .map(|(i, e)| {
                Expr::new(e.get_ref(), t_check)
                    .map_err(|m| self.invalid(&format!("{key}.{i}"), e.span(), m))
            })
            .collect()
    }
}

/// The report of `body` (with its points `points`) for `check` and `summary.json`.
fn body_component<const D: usize>(
    body: &RigidBody<D>,
    spec: &BodySpec,
    points: Vec<BodyPointComponent>,
) -> BodyComponent {
    let texts = |l: Option<&Spanned<Vec<Spanned<String>>>>| {
        l.map_or_else(Vec::new, |l| {
            l.get_ref().iter().map(|t| t.get_ref().clone()).collect()
        })
    };
    let wrench = spec.wrench.as_ref().map(|w| w.get_ref());
    BodyComponent {
        name: body.name.clone(),
        mass: body.mass,
        weight: body.weight.as_slice().to_vec(),
        inertia: [0, 1, 2].map(|i| [0, 1, 2].map(|j| body.inertia[(i, j)])),
        position: body.initial.position.as_slice()[..D].to_vec(),
        orientation: spec.orientation.as_ref().map_or_else(
            || vec![0.0; if D == 2 { 1 } else { 3 }],
            |o| o.get_ref().clone(),
        ),
        points,
        wrench_force: texts(wrench.and_then(|w| w.force.as_ref())),
        wrench_torque: texts(wrench.and_then(|w| w.torque.as_ref())),
        wrench_external: wrench
            .and_then(|w| w.external.as_ref())
            .is_some_and(|x| *x.get_ref()),
        water: body.hydro.as_ref().map(|h| BodyWaterComponent::of(h, D)),
        motion: Vec::new(),
        feedback: Vec::new(),
    }
}

impl ScenarioFile {
    /// Checks the bodies `drafts` against the boundary conditions `parts` (no body point is
    /// fixed, moved or controlled) and attaches their wrench ports, whose expression failures
    /// go to the record the loads share.
    pub(super) fn checked_bodies<const D: usize>(
        &self,
        nodes: &Nodes,
        parts: &super::attach::BoundaryParts<D>,
        drafts: &mut [BodyDraft<D>],
    ) -> Result<(), ScenarioError> {
        if drafts.is_empty() {
            return Ok(());
        }
        let body_nodes: HashMap<usize, String> = drafts
            .iter()
            .flat_map(|d| {
                d.body
                    .attachments
                    .iter()
                    .zip(&d.starts)
                    .map(|(a, s)| (a.node, s.2.clone()))
            })
            .collect();
        let b = &parts.boundary;
        let held: HashSet<usize> = b
            .fixed
            .iter()
            .filter(|f| f.components.iter().any(|&c| c))
            .map(|f| f.node)
            .chain(b.motions.iter().map(|m| m.node))
            .chain(b.feedback.iter().map(|f| f.node))
            .collect();
        self.bodies_not_held(nodes, &held, &body_nodes)?;
        self.body_wrenches(drafts, &parts.load_error)
    }
}

/// Adds the bodies of `drafts` to `problem`, with each body point's node moving at the
/// body's velocity there; returns the points' `(node, position [m], velocity [m/s], name)`.
pub(super) fn with_bodies<const D: usize>(
    problem: &mut phstring::Network<D, Material>,
    drafts: Vec<BodyDraft<D>>,
) -> Vec<(usize, Vector<D>, Vector<D>, String)> {
    let mut starts = Vec::new();
    for d in drafts {
        for (a, (r, v, name)) in d.body.attachments.iter().zip(d.starts) {
            if let Some(node_v) = problem.initial.v.get_mut(a.node) {
                *node_v = v;
            }
            starts.push((a.node, r, v, name));
        }
        problem.bodies.push(d.body);
    }
    starts
}
