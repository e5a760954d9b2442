//! Validation of what is attached to nodes: `[[point_mass]]` and `[[boundary]]` (fixed
//! components, prescribed motions, loads), with the supports of `[[platform]]` (read in
//! `tables.rs`). All refer to nodes by index, name or `"STRING:INDEX"`.

use std::collections::HashMap;
use std::ops::Range;
use std::sync::{Arc, Mutex};

use phstring::{Boundary, FeedbackLoad, Fixed, Motion, NodalLoad, PdLaw, PointMass, Vector};

use super::components::{AXES, ControlComponent, MotionComponent, PointMassComponent};
use super::expr::{Expr, eval_or_record, is_zero};
use super::refs::label;
use super::spec::{BoundarySpec, ControlSpec, FixedSpec, GainSpec};
use super::tables::{ForceTable, Platform, TableMotions, column_text};
use super::{ScenarioError, ScenarioFile, Skeleton};
use crate::text::{clip, num};

/// The validated `[[boundary]]` tables.
pub(super) struct BoundaryParts<const D: usize> {
    /// The conditions, in file order within each kind.
    pub boundary: Boundary<D>,
    /// Force expressions per load (node, component texts, FMU input).
    pub loads: Vec<(usize, Vec<String>, bool)>,
    /// The first failure of an expression during the run.
    pub load_error: Arc<Mutex<Option<String>>>,
    /// The motions, for reports.
    pub motions: Vec<MotionComponent>,
    /// The feedback controls, for reports.
    pub controls: Vec<ControlComponent>,
}

/// What holds one component of a node: fixed or moved by boundary table `k` (by its key
/// `position` or `motion_table`), or moved by platform `k`.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Hold {
    Free,
    Fixed(usize),
    Moved(usize, &'static str),
    Platform(usize),
}

impl Hold {
    /// What moves the component, for messages (`boundary.2.position`, `platform.0`).
    fn mover(self) -> String {
        match self {
            Hold::Moved(j, what) => format!("boundary.{j}.{what}"),
            Hold::Platform(j) => format!("platform.{j}"),
            Hold::Free | Hold::Fixed(_) => String::new(),
        }
    }
}

/// One `[[boundary]]` table, parsed and checked on its own.
struct Entry<const D: usize> {
    node: usize,
    /// The node for messages (`node 5`, `"platform" (node 0)`).
    label: String,
    fixed: [bool; D],
    /// Moved components: (component, expression, span of its text).
    motions: Vec<(usize, Expr, Range<usize>)>,
    /// Components moved by `motion_table`.
    tabled: TableMotions,
    force: Option<Force>,
    /// `force_table`.
    force_table: Option<ForceTable>,
    control: Option<Control<D>>,
    /// `external = true`: the force or the motion is an FMU input.
    external: bool,
}

/// The `control` of a `[[boundary]]` table.
struct Control<const D: usize> {
    kp: Vector<D>,
    kd: Vector<D>,
    /// Reference position expressions (none: zero).
    reference: Option<Vec<Expr>>,
    /// Reference velocity expressions (none: central difference of `reference`, or zero).
    velocity: Option<Vec<Expr>>,
    /// Span of the table.
    span: Range<usize>,
}

/// Half-width [s] of the central difference that gives a control's reference velocity when
/// only its position is given: `v_ref(t) ≈ (r_ref(t + δ) − r_ref(t − δ)) / 2δ` with
/// `δ = REFERENCE_DT · max(1, |t|)`; for `t < δ` the forward difference
/// `(r_ref(t + δ) − r_ref(t)) / δ`, so that the reference is never evaluated before `t = 0`.
/// Truncation error about `(δ/τ)²/6` relative for a reference that varies on the time scale
/// `τ` (2e-7 at τ = 1 ms); rounding about `ε |r_ref| / (δ |v_ref|)`.
pub const REFERENCE_DT: f64 = 1e-6;

/// The `force` of a `[[boundary]]` table.
struct Force {
    /// One expression per component.
    exprs: Vec<Expr>,
    /// Their texts.
    texts: Vec<String>,
    /// Span of the list.
    span: Range<usize>,
    /// Components whose expression is not the literal zero.
    loaded: Vec<bool>,
}

/// The point masses of a scenario, their report entries, and their hydrodynamics (those
/// with `volume`, `cda` or `ca`).
pub(super) type PointMasses<const D: usize> = (
    Vec<PointMass<D>>,
    Vec<PointMassComponent>,
    Vec<phstring::PointHydro>,
);

impl ScenarioFile {
    /// Refuses `node` (given at `key`) if it is the fixed point of a spring with `to_point`:
    /// that node is held in every component, so a condition or a mass there would do nothing
    /// (or move the "fixed" point).
    pub(super) fn not_an_anchor<const D: usize>(
        &self,
        key: &str,
        span: Range<usize>,
        node: usize,
        sk: &Skeleton<D>,
    ) -> Result<(), ScenarioError> {
        let anchor_of = sk
            .components
            .springs
            .iter()
            .find(|sp| sp.to_point.is_some() && sp.nodes[1] == node);
        match anchor_of {
            Some(sp) => Err(self.invalid(
                key,
                span,
                format!(
                    "is node {node}, the fixed point of spring \"{}\" (to_point): it is held in every component, so nothing can be attached to, fixed, moved or loaded there",
                    clip(&sp.name)
                ),
            )),
            None => Ok(()),
        }
    }

    /// `[[point_mass]]`: a node, a positive mass and its finite weight `kg · gravity`.
    pub(super) fn point_masses<const D: usize>(
        &self,
        sk: &Skeleton<D>,
        gravity: Vector<D>,
    ) -> Result<PointMasses<D>, ScenarioError> {
        let list = &self.scenario.point_mass;
        let mut masses = Vec::with_capacity(list.len());
        let mut report = Vec::with_capacity(list.len());
        let mut hydro = Vec::new();
        for (k, pm) in list.iter().enumerate() {
            let key = |f: &str| format!("point_mass.{k}.{f}");
            let node = self.resolve(&key("node"), &pm.node, &sk.nodes)?;
            self.not_an_anchor(&key("node"), pm.node.span(), node, sk)?;
            let kg = self.positive(&key("kg"), &pm.kg)?;
            let weight = gravity * kg;
            if !weight.iter().all(|w| w.is_finite()) {
                return Err(self.invalid(
                    &key("kg"),
                    pm.kg.span(),
                    format!(
                        "= {}: its weight under body_force.gravity overflows",
                        num(kg)
                    ),
                ));
            }
            let w = super::rounding::length(&weight);
            if w > super::material::MAX_NODAL_FORCE {
                return Err(self.invalid(
                    &key("kg"),
                    pm.kg.span(),
                    format!(
                        "= {}: its weight under body_force.gravity at {} is {} N, above {:.0e} N: nodal forces this large overflow the force residual, which squares them",
                        num(kg),
                        label(pm.node.get_ref(), node),
                        num(w),
                        super::material::MAX_NODAL_FORCE
                    ),
                ));
            }
            masses.push(PointMass {
                node,
                mass: kg,
                weight,
            });
            hydro.extend(self.point_hydro(k, pm, node)?);
            report.push(PointMassComponent {
                node,
                kg,
                weight: weight.as_slice().to_vec(),
            });
        }
        Ok((masses, report, hydro))
    }

    /// Refuses a `position` (at `key`) whose every expression is `""`: it prescribes nothing.
    fn prescribes_a_component(
        &self,
        key: &str,
        p: &toml::Spanned<Vec<toml::Spanned<String>>>,
    ) -> Result<(), ScenarioError> {
        if p.get_ref().iter().all(|t| t.get_ref().trim().is_empty()) {
            return Err(self.invalid(
                key,
                p.span(),
                "prescribes nothing: every expression is \"\" (free); give the position of at least one component (\"\" for the free ones), or remove the key",
            ));
        }
        Ok(())
    }

    /// `boundary.{k}` on its own: node, `position` (each expression valid and starting at
    /// the node), `fixed` components, `force` expressions.
    fn boundary_entry<const D: usize>(
        &self,
        k: usize,
        sk: &Skeleton<D>,
        t_check: f64,
    ) -> Result<Entry<D>, ScenarioError> {
        let b = &self.scenario.boundary[k];
        let key = |f: &str| format!("boundary.{k}.{f}");
        let node = self.resolve(&key("node"), &b.node, &sk.nodes)?;
        self.not_an_anchor(&key("node"), b.node.span(), node, sk)?;
        let label = label(b.node.get_ref(), node);
        if b.fixed.is_none()
            && b.force.is_none()
            && b.position.is_none()
            && b.control.is_none()
            && b.motion_table.is_none()
            && b.force_table.is_none()
        {
            return Err(self.invalid(
                &key("node"),
                b.node.span(),
                "has neither `fixed`, `force`, `position`, `motion_table`, `force_table` nor `control`",
            ));
        }
        let motions = self.entry_motions(k, b, sk.position(node), &label, t_check)?;
        let tabled = self.entry_motion_table(k, b, sk.position(node), &label)?;
        let force_table = self.entry_force_table::<D>(k, b)?;
        let fixed = self.entry_fixed::<D>(k, b)?;
        let force = self.entry_force::<D>(k, b, t_check)?;
        let control = match &b.control {
            None => None,
            Some(c) => Some(self.control::<D>(k, c.get_ref(), c.span(), t_check)?),
        };
        let external = self.entry_external(k, b)?;
        Ok(Entry {
            node,
            label,
            fixed,
            motions,
            tabled,
            force,
            force_table,
            control,
            external,
        })
    }

    /// The moved components of `boundary.{k}.position` (table `b`): each expression valid and
    /// at the node's `start` position [m] (called `label`) at `t = 0`.
    fn entry_motions<const D: usize>(
        &self,
        k: usize,
        b: &BoundarySpec,
        start: Vector<D>,
        label: &str,
        t_check: f64,
    ) -> Result<Vec<(usize, Expr, Range<usize>)>, ScenarioError> {
        let key = |f: &str| format!("boundary.{k}.{f}");
        let mut motions = Vec::new();
        if let Some(p) = &b.position {
            let texts = p.get_ref();
            if texts.len() != D {
                return Err(self.invalid(
                    &key("position"),
                    p.span(),
                    format!(
                        "must have {D} expressions (dimension = {D}; \"\" for a free component), got {}",
                        texts.len()
                    ),
                ));
            }
            self.prescribes_a_component(&key("position"), p)?;
            for (i, txt) in texts.iter().enumerate() {
                if txt.get_ref().trim().is_empty() {
                    continue;
                }
                let ckey = format!("boundary.{k}.position.{i}");
                let e = Expr::new(txt.get_ref(), t_check)
                    .map_err(|m| self.invalid(&ckey, txt.span(), m))?;
                let at_zero = e
                    .eval(0.0)
                    .map_err(|m| self.invalid(&ckey, txt.span(), m))?;
                let start = start[i];
                // NaN (an expression undefined at 0) fails too.
                let starts_there = (at_zero - start).abs() <= 1e-9 * start.abs().max(1.0);
                if !starts_there {
                    return Err(self.invalid(
                        &ckey,
                        txt.span(),
                        format!(
                            "component {} is at {} m at t = 0, but {label} starts at {} m: the expression gives the absolute position",
                            AXES[i],
                            num(at_zero),
                            num(start)
                        ),
                    ));
                }
                motions.push((i, e, txt.span()));
            }
        }
        Ok(motions)
    }

    /// The fixed components of `boundary.{k}.fixed` (table `b`): all, a mask, or a list of
    /// component names.
    fn entry_fixed<const D: usize>(
        &self,
        k: usize,
        b: &BoundarySpec,
    ) -> Result<[bool; D], ScenarioError> {
        let key = |f: &str| format!("boundary.{k}.{f}");
        let mut fixed = [false; D];
        if let Some(f) = &b.fixed {
            match f.get_ref() {
                FixedSpec::All(v) => fixed = [*v; D],
                FixedSpec::Mask(flags) => {
                    if flags.len() != D {
                        return Err(self.invalid(
                            &key("fixed"),
                            f.span(),
                            format!("must have {D} flags (dimension = {D}), got {}", flags.len()),
                        ));
                    }
                    fixed.copy_from_slice(flags);
                }
                FixedSpec::Components(list) => {
                    for name in list {
                        let Some(i) = AXES[..D].iter().position(|a| a == name) else {
                            return Err(self.invalid(
                                &key("fixed"),
                                f.span(),
                                format!(
                                    "component \"{}\" is not one of x, y, z up to dimension {D}",
                                    clip(name)
                                ),
                            ));
                        };
                        fixed[i] = true;
                    }
                }
            }
        }
        Ok(fixed)
    }

    /// The force of `boundary.{k}.force` (table `b`), if any: `D` valid expressions [N].
    fn entry_force<const D: usize>(
        &self,
        k: usize,
        b: &BoundarySpec,
        t_check: f64,
    ) -> Result<Option<Force>, ScenarioError> {
        let key = |f: &str| format!("boundary.{k}.{f}");
        Ok(match &b.force {
            None => None,
            Some(f) => {
                let texts = f.get_ref();
                if texts.len() != D {
                    return Err(self.invalid(
                        &key("force"),
                        f.span(),
                        format!(
                            "must have {D} expressions (dimension = {D}), got {}",
                            texts.len()
                        ),
                    ));
                }
                let mut exprs = Vec::with_capacity(D);
                for txt in texts {
                    exprs.push(
                        Expr::new(txt, t_check)
                            .map_err(|m| self.invalid(&key("force"), f.span(), m))?,
                    );
                }
                let loaded = texts.iter().map(|t| !is_zero(t)).collect();
                Some(Force {
                    exprs,
                    texts: texts.clone(),
                    span: f.span(),
                    loaded,
                })
            }
        })
    }

    /// Whether `boundary.{k}.external` (table `b`) marks its force or motion as an FMU input:
    /// only for a table with exactly one of them.
    fn entry_external(&self, k: usize, b: &BoundarySpec) -> Result<bool, ScenarioError> {
        let key = |f: &str| format!("boundary.{k}.{f}");
        Ok(match &b.external {
            Some(x) if *x.get_ref() => {
                if b.motion_table.is_some() || b.force_table.is_some() {
                    return Err(self.invalid(
                        &key("external"),
                        x.span(),
                        "marks an FMU input, which the FMU's master sets, but this table takes its values from a table file (`motion_table` or `force_table`): remove one of them",
                    ));
                }
                if b.force.is_none() && b.position.is_none() {
                    return Err(self.invalid(
                        &key("external"),
                        x.span(),
                        "marks a force or position port as an FMU input, but this table has neither `force` nor `position`",
                    ));
                }
                if b.force.is_some() && b.position.is_some() {
                    return Err(self.invalid(
                        &key("external"),
                        x.span(),
                        "is ambiguous: this table has both `force` and `position`; split it into two tables and mark the one that is an input",
                    ));
                }
                true
            }
            _ => false,
        })
    }

    /// The PD law of `boundary.{k}.control`; expression failures during the run become NaN
    /// (the step fails) and are recorded in `errors`.
    fn pd_law<const D: usize>(
        &self,
        k: usize,
        c: Control<D>,
        errors: &Arc<Mutex<Option<String>>>,
    ) -> PdLaw<D> {
        let reference = c.reference.map(Arc::new);
        let position = {
            let (reference, errors) = (reference.clone(), errors.clone());
            move |t: f64| match &reference {
                None => Vector::<D>::zeros(),
                Some(x) => Vector::<D>::from_fn(|i, _| {
                    eval_or_record(&x[i], &errors, "control.reference", k, i, t)
                }),
            }
        };
        let velocity: Arc<dyn Fn(f64) -> Vector<D> + Send + Sync> = match c.velocity {
            Some(v) => {
                let errors = errors.clone();
                Arc::new(move |t| {
                    Vector::<D>::from_fn(|i, _| {
                        eval_or_record(&v[i], &errors, "control.reference_velocity", k, i, t)
                    })
                })
            }
            None if reference.is_some() => {
                let position = position.clone();
                Arc::new(move |t: f64| {
                    let dt = REFERENCE_DT * t.abs().max(1.0);
                    if t < dt {
                        (position(t + dt) - position(t)) / dt
                    } else {
                        (position(t + dt) - position(t - dt)) / (2.0 * dt)
                    }
                })
            }
            None => Arc::new(|_| Vector::<D>::zeros()),
        };
        PdLaw {
            kp: c.kp,
            kd: c.kd,
            r_ref: Arc::new(position),
            v_ref: velocity,
        }
    }

    /// `boundary.{k}.control`: gains at least 0 (not both all zero), `reference` with `kp`,
    /// expressions valid.
    fn control<const D: usize>(
        &self,
        k: usize,
        c: &ControlSpec,
        span: Range<usize>,
        t_check: f64,
    ) -> Result<Control<D>, ScenarioError> {
        let key = |f: &str| format!("boundary.{k}.control.{f}");
        let gain =
            |name: &str, g: &Option<toml::Spanned<GainSpec>>| -> Result<Vector<D>, ScenarioError> {
                let Some(g) = g else {
                    return Ok(Vector::zeros());
                };
                let v = match g.get_ref() {
                    GainSpec::One(x) => Vector::<D>::from_element(*x),
                    GainSpec::Each(list) if list.len() == D => Vector::<D>::from_column_slice(list),
                    GainSpec::Each(list) => {
                        return Err(self.invalid(
                            &key(name),
                            g.span(),
                            format!(
                                "must be one number or {D} (dimension = {D}), got {}",
                                list.len()
                            ),
                        ));
                    }
                };
                if let Some(x) = v.iter().find(|x| !(**x >= 0.0 && x.is_finite())) {
                    return Err(self.invalid(
                        &key(name),
                        g.span(),
                        format!("must be at least 0 and finite, got {}", num(*x)),
                    ));
                }
                Ok(v)
            };
        let kp = gain("kp", &c.kp)?;
        let kd = gain("kd", &c.kd)?;
        if kp.iter().chain(kd.iter()).all(|&x| x == 0.0) {
            return Err(self.invalid(
                &format!("boundary.{k}.control"),
                span,
                "has no gain: give `kp` [N/m] (with `reference`) and/or `kd` [N s/m]",
            ));
        }
        let exprs = |name: &str,
                     list: &Option<toml::Spanned<Vec<toml::Spanned<String>>>>|
         -> Result<Option<Vec<Expr>>, ScenarioError> {
            let Some(list) = list else { return Ok(None) };
            let texts = list.get_ref();
            if texts.len() != D {
                return Err(self.invalid(
                    &key(name),
                    list.span(),
                    format!(
                        "must have {D} expressions (dimension = {D}), got {}",
                        texts.len()
                    ),
                ));
            }
            texts
                .iter()
                .enumerate()
                .map(|(i, t)| {
                    Expr::new(t.get_ref(), t_check)
                        .map_err(|m| self.invalid(&format!("{}.{i}", key(name)), t.span(), m))
                })
                .collect::<Result<Vec<_>, _>>()
                .map(Some)
        };
        let reference = exprs("reference", &c.reference)?;
        let velocity = exprs("reference_velocity", &c.reference_velocity)?;
        if let Some(v) = &c.reference_velocity
            && kd.iter().all(|&x| x == 0.0)
        {
            return Err(self.invalid(
                &key("reference_velocity"),
                v.span(),
                "has no effect without `kd` (it enters only as kd (y - v_ref))",
            ));
        }
        if reference.is_none() && kp.iter().any(|&x| x != 0.0) {
            return Err(self.invalid(
                &key("kp"),
                c.kp.as_ref().map_or(span.clone(), |g| g.span()),
                "needs `reference`: the position [m] the node is pulled to, one expression of t per component",
            ));
        }
        Ok(Control {
            kp,
            kd,
            reference,
            velocity,
            span,
        })
    }

    /// `[[boundary]]`: each table on its own, then across tables: a component is fixed,
    /// moved by one motion, or loaded, never two of these.
    pub(super) fn boundary<const D: usize>(
        &self,
        sk: &Skeleton<D>,
        t_check: f64,
    ) -> Result<BoundaryParts<D>, ScenarioError> {
        let entries = (0..self.scenario.boundary.len())
            .map(|k| self.boundary_entry::<D>(k, sk, t_check))
            .collect::<Result<Vec<_>, _>>()?;
        let platforms = self.platforms(sk)?;
        let held = self.holds(&entries, &platforms)?;
        self.loads_on_free_components(&entries, &held)?;
        self.controls_on_free_components(&entries, &held)?;
        Ok(self.boundary_parts(entries, platforms))
    }

    /// What holds each component of the nodes that have conditions: fixed by its first
    /// table, else moved by one motion or platform (a component both fixed and moved, or
    /// moved twice, is refused).
    fn holds<const D: usize>(
        &self,
        entries: &[Entry<D>],
        platforms: &[Platform],
    ) -> Result<HashMap<usize, [Hold; D]>, ScenarioError> {
        // What holds each component, for the nodes that have conditions.
        let mut held: HashMap<usize, [Hold; D]> = HashMap::new();
        for (k, e) in entries.iter().enumerate() {
            let h = held.entry(e.node).or_insert([Hold::Free; D]);
            for i in 0..D {
                if e.fixed[i] && h[i] == Hold::Free {
                    h[i] = Hold::Fixed(k);
                }
            }
        }
        let table_span = |k: usize| {
            let b = &self.scenario.boundary[k];
            b.motion_table.as_ref().map_or(0..0, |f| f.span())
        };
        for (k, e) in entries.iter().enumerate() {
            let by_expr = e.motions.iter().map(|(i, _, span)| {
                let key = format!("boundary.{k}.position.{i}");
                (*i, key, span.clone(), Hold::Moved(k, "position"))
            });
            let by_table = e.tabled.iter().map(|(i, _)| {
                let key = format!("boundary.{k}.motion_table");
                (*i, key, table_span(k), Hold::Moved(k, "motion_table"))
            });
            for (i, key, span, how) in by_expr.chain(by_table) {
                self.hold_moved(&mut held, e.node, i, how, (&key, span), &e.label)?;
            }
        }
        for (k, p) in platforms.iter().enumerate() {
            for (i, (node, _, label, span)) in p.nodes.iter().enumerate() {
                let key = format!("platform.{k}.nodes.{i}");
                for c in 0..D {
                    let how = Hold::Platform(k);
                    self.hold_moved(&mut held, *node, c, how, (&key, span.clone()), label)?;
                }
            }
        }
        Ok(held)
    }

    /// Marks component `i` of `node` (called `label`) as moved by `how`, given at `at` (key
    /// and span); refused if it is already fixed or moved.
    fn hold_moved<const D: usize>(
        &self,
        held: &mut HashMap<usize, [Hold; D]>,
        node: usize,
        i: usize,
        how: Hold,
        at: (&str, Range<usize>),
        label: &str,
    ) -> Result<(), ScenarioError> {
        let h = held.entry(node).or_insert([Hold::Free; D]);
        let axis = AXES[i];
        let (key, span) = at;
        match h[i] {
            Hold::Free => {
                h[i] = how;
                Ok(())
            }
            Hold::Fixed(j) => Err(self.invalid(
                key,
                span,
                format!(
                    "{label} is also fixed in component {axis} (by boundary.{j}.fixed; give \"\" there, or drop it from `fixed`)"
                ),
            )),
            other => Err(self.invalid(
                key,
                span,
                format!(
                    "{label} already follows {} in component {axis}: a component has one prescribed position",
                    other.mover()
                ),
            )),
        }
    }

    /// Refuses a force on a component that is fixed or moved (`held`).
    fn loads_on_free_components<const D: usize>(
        &self,
        entries: &[Entry<D>],
        held: &HashMap<usize, [Hold; D]>,
    ) -> Result<(), ScenarioError> {
        for (k, e) in entries.iter().enumerate() {
            let (key, span, loaded) = match (&e.force, &e.force_table) {
                (Some(Force { span, loaded, .. }), _) => ("force", span, loaded),
                (None, Some(ForceTable { span, loaded, .. })) => ("force_table", span, loaded),
                (None, None) => continue,
            };
            let h = held.get(&e.node).copied().unwrap_or([Hold::Free; D]);
            for i in (0..D).filter(|&i| loaded[i]) {
                let axis = AXES[i];
                let how = match h[i] {
                    Hold::Free => continue,
                    Hold::Fixed(_) => format!("is fixed in component {axis}"),
                    moved => format!(
                        "has a prescribed position ({}) in component {axis}",
                        moved.mover()
                    ),
                };
                // `node 3 is fixed …` keeps the wording of single-string messages.
                return Err(self.invalid(
                    &format!("boundary.{k}.{key}"),
                    span.clone(),
                    format!(
                        "{} {how} and cannot also be loaded in it (give \"0\" there)",
                        e.label
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Refuses a control with a gain on a component that is fixed or moved (`held`).
    fn controls_on_free_components<const D: usize>(
        &self,
        entries: &[Entry<D>],
        held: &HashMap<usize, [Hold; D]>,
    ) -> Result<(), ScenarioError> {
        for (k, e) in entries.iter().enumerate() {
            let Some(c) = &e.control else { continue };
            let h = held.get(&e.node).copied().unwrap_or([Hold::Free; D]);
            for i in (0..D).filter(|&i| c.kp[i] != 0.0 || c.kd[i] != 0.0) {
                let axis = AXES[i];
                let how = match h[i] {
                    Hold::Free => continue,
                    Hold::Fixed(_) => format!("is fixed in component {axis}"),
                    moved => format!(
                        "has a prescribed position ({}) in component {axis}",
                        moved.mover()
                    ),
                };
                return Err(self.invalid(
                    &format!("boundary.{k}.control"),
                    c.span.clone(),
                    format!(
                        "{} {how}, where a control can do nothing (give gain 0 there)",
                        e.label
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The boundary conditions, loads, motions and controls of the checked `entries` and
    /// the motions of the `platforms` (after those of the entries), with the record of
    /// expression failures during a run that they share.
    fn boundary_parts<const D: usize>(
        &self,
        entries: Vec<Entry<D>>,
        platforms: Vec<Platform>,
    ) -> BoundaryParts<D> {
        let load_error: Arc<Mutex<Option<String>>> = Arc::default();
        let mut boundary = Boundary::<D>::default();
        let mut controls = Vec::new();
        let mut loads = Vec::new();
        let mut motions = Vec::new();
        for (k, e) in entries.into_iter().enumerate() {
            let texts = self.scenario.boundary[k].position.as_ref();
            for (i, expr, _) in e.motions {
                motions.push(MotionComponent {
                    node: e.node,
                    component: AXES[i],
                    position: texts.map_or_else(String::new, |t| t.get_ref()[i].get_ref().clone()),
                    external: e.external,
                });
                let errors = load_error.clone();
                boundary.motions.push(Motion::new(e.node, i, move |t| {
                    eval_or_record(&expr, &errors, "position", k, i, t)
                }));
            }
            let table = self.scenario.boundary[k].motion_table.as_ref();
            // The file's column of component i (1-based, the time first): `motion_columns`
            // (validated) or the i-th after the time.
            let columns = self.scenario.boundary[k].motion_columns.as_ref();
            for (i, signal) in e.tabled {
                let file = table.map_or("", |f| f.get_ref().as_str());
                let column = columns
                    .and_then(|c| c.get_ref().get(i).copied())
                    .and_then(|c| usize::try_from(c).ok())
                    .unwrap_or(i + 2);
                motions.push(MotionComponent {
                    node: e.node,
                    component: AXES[i],
                    position: column_text(file, column - 1, AXES[i]),
                    external: false,
                });
                boundary.motions.push(Motion::sampled(e.node, i, signal));
            }
            if e.fixed.iter().any(|&c| c) {
                boundary.fixed.push(Fixed {
                    node: e.node,
                    components: e.fixed,
                });
            }
            if let Some(Force { exprs, texts, .. }) = e.force {
                loads.push((e.node, texts, e.external));
                let exprs = Arc::new(exprs);
                let errors = load_error.clone();
                boundary.loads.push(NodalLoad::new(e.node, move |t| {
                    Vector::<D>::from_fn(|i, _| {
                        eval_or_record(&exprs[i], &errors, "force", k, i, t)
                    })
                }));
            }
            if let Some(ForceTable { signals, texts, .. }) = e.force_table {
                loads.push((e.node, texts, false));
                boundary.loads.push(NodalLoad::new(e.node, move |t| {
                    Vector::<D>::from_fn(|i, _| signals[i].value(t))
                }));
            }
            if let Some(c) = e.control {
                let spec = self.scenario.boundary[k].control.as_ref();
                let texts = |l: Option<&toml::Spanned<Vec<toml::Spanned<String>>>>| {
                    l.map_or_else(Vec::new, |l| {
                        l.get_ref().iter().map(|t| t.get_ref().clone()).collect()
                    })
                };
                controls.push(ControlComponent {
                    node: e.node,
                    kp: c.kp.as_slice().to_vec(),
                    kd: c.kd.as_slice().to_vec(),
                    reference: texts(spec.and_then(|s| s.get_ref().reference.as_ref())),
                    reference_velocity: texts(
                        spec.and_then(|s| s.get_ref().reference_velocity.as_ref()),
                    ),
                });
                boundary
                    .feedback
                    .push(FeedbackLoad::new(e.node, self.pd_law(k, c, &load_error)));
            }
        }
        for p in platforms {
            for (node, _, _, _) in &p.nodes {
                motions.extend(AXES[..D].iter().map(|&component| MotionComponent {
                    node: *node,
                    component,
                    position: format!("platform table {}", clip(&p.file)),
                    external: false,
                }));
            }
            boundary.motions.extend(p.motions());
        }
        BoundaryParts {
            boundary,
            loads,
            load_error,
            motions,
            controls,
        }
    }
}
