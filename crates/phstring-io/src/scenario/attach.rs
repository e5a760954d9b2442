//! Validation of what is attached to nodes: `[[point_mass]]` and `[[boundary]]` (fixed
//! components, prescribed motions, loads). Both refer to nodes by index, name or
//! `"STRING:INDEX"`.

use std::collections::HashMap;
use std::ops::Range;
use std::sync::{Arc, Mutex};

use phstring::{Boundary, Fixed, Motion, NodalLoad, PointMass, Vector};

use super::components::{AXES, MotionComponent, PointMassComponent};
use super::expr::{Expr, eval_or_record, is_zero};
use super::refs::label;
use super::spec::FixedSpec;
use super::{ScenarioError, ScenarioFile, Skeleton};
use crate::text::{clip, num};

/// The validated `[[boundary]]` tables.
pub(super) struct BoundaryParts<const D: usize> {
    /// The conditions, in file order within each kind.
    pub boundary: Boundary<D>,
    /// Force expressions per load (node, component texts).
    pub loads: Vec<(usize, Vec<String>)>,
    /// The first failure of an expression during the run.
    pub load_error: Arc<Mutex<Option<String>>>,
    /// The motions, for reports.
    pub motions: Vec<MotionComponent>,
}

/// What holds one component of a node: fixed or moved by boundary table `k`.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Hold {
    Free,
    Fixed(usize),
    Moved(usize),
}

/// One `[[boundary]]` table, parsed and checked on its own.
struct Entry<const D: usize> {
    node: usize,
    /// The node for messages (`node 5`, `"platform" (node 0)`).
    label: String,
    fixed: [bool; D],
    /// Moved components: (component, expression, span of its text).
    motions: Vec<(usize, Expr, Range<usize>)>,
    force: Option<Force>,
}

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

impl ScenarioFile {
    /// Refuses `node` (given at `key`) if it is the fixed point of a spring with `to_point`:
    /// that node is held in every component, so a condition or a mass there would do nothing
    /// (or move the "fixed" point).
    fn not_an_anchor<const D: usize>(
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
    ) -> Result<(Vec<PointMass<D>>, Vec<PointMassComponent>), ScenarioError> {
        let list = &self.scenario.point_mass;
        let mut masses = Vec::with_capacity(list.len());
        let mut report = Vec::with_capacity(list.len());
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
            masses.push(PointMass {
                node,
                mass: kg,
                weight,
            });
            report.push(PointMassComponent {
                node,
                kg,
                weight: weight.as_slice().to_vec(),
            });
        }
        Ok((masses, report))
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
        if b.fixed.is_none() && b.force.is_none() && b.position.is_none() {
            return Err(self.invalid(
                &key("node"),
                b.node.span(),
                "has neither `fixed`, `force` nor `position`",
            ));
        }
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
            let start = sk.position(node);
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
        let force = match &b.force {
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
        };
        Ok(Entry {
            node,
            label,
            fixed,
            motions,
            force,
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
        for (k, e) in entries.iter().enumerate() {
            for (i, _, span) in &e.motions {
                let h = held.entry(e.node).or_insert([Hold::Free; D]);
                let ckey = format!("boundary.{k}.position.{i}");
                let axis = AXES[*i];
                match h[*i] {
                    Hold::Free => h[*i] = Hold::Moved(k),
                    Hold::Fixed(_) => {
                        return Err(self.invalid(
                            &ckey,
                            span.clone(),
                            format!(
                                "{} is also fixed in component {axis} (give \"\" there, or drop it from `fixed`)",
                                e.label
                            ),
                        ));
                    }
                    Hold::Moved(j) => {
                        return Err(self.invalid(
                            &ckey,
                            span.clone(),
                            format!(
                                "{} already follows boundary.{j}.position in component {axis}: a component has one prescribed position",
                                e.label
                            ),
                        ));
                    }
                }
            }
        }
        for (k, e) in entries.iter().enumerate() {
            let Some(Force { span, loaded, .. }) = &e.force else {
                continue;
            };
            let h = held.get(&e.node).copied().unwrap_or([Hold::Free; D]);
            for i in (0..D).filter(|&i| loaded[i]) {
                let axis = AXES[i];
                let how = match h[i] {
                    Hold::Free => continue,
                    Hold::Fixed(_) => format!("is fixed in component {axis}"),
                    Hold::Moved(j) => {
                        format!(
                            "has a prescribed position (boundary.{j}.position) in component {axis}"
                        )
                    }
                };
                // `node 3 is fixed …` keeps the wording of single-string messages.
                return Err(self.invalid(
                    &format!("boundary.{k}.force"),
                    span.clone(),
                    format!(
                        "{} {how} and cannot also be loaded in it (give \"0\" there)",
                        e.label
                    ),
                ));
            }
        }
        let load_error: Arc<Mutex<Option<String>>> = Arc::default();
        let mut boundary = Boundary::<D>::default();
        let mut loads = Vec::new();
        let mut motions = Vec::new();
        for (k, e) in entries.into_iter().enumerate() {
            let texts = self.scenario.boundary[k].position.as_ref();
            for (i, expr, _) in e.motions {
                motions.push(MotionComponent {
                    node: e.node,
                    component: AXES[i],
                    position: texts.map_or_else(String::new, |t| t.get_ref()[i].get_ref().clone()),
                });
                let errors = load_error.clone();
                boundary.motions.push(Motion::new(e.node, i, move |t| {
                    eval_or_record(&expr, &errors, "position", k, i, t)
                }));
            }
            if e.fixed.iter().any(|&c| c) {
                boundary.fixed.push(Fixed {
                    node: e.node,
                    components: e.fixed,
                });
            }
            if let Some(Force { exprs, texts, .. }) = e.force {
                loads.push((e.node, texts));
                let exprs = Arc::new(exprs);
                let errors = load_error.clone();
                boundary.loads.push(NodalLoad::new(e.node, move |t| {
                    Vector::<D>::from_fn(|i, _| {
                        eval_or_record(&exprs[i], &errors, "force", k, i, t)
                    })
                }));
            }
        }
        Ok(BoundaryParts {
            boundary,
            loads,
            load_error,
            motions,
        })
    }
}
