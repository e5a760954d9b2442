//! Validation of a network: `[materials.NAME]`, `[[node]]`, `[[string]]` and `[[spring]]`,
//! assembled with [`phstring::NetworkBuilder`]. Mesh numbering: the `[[node]]`s in file
//! order, then the interior nodes of each string in file order, then the fixed ends of the
//! springs with `to_point` in file order.

use std::collections::{BTreeMap, HashMap};
use std::ops::Range;

use phstring::{Material, NetworkBuilder, StoredEnergy, StringSpec, Vector};
use toml::Spanned;

use super::components::{Components, NamedNode, SpringComponent, StringComponent, StringLayout};
use super::material::{CrossSection, Longest};
use super::overrides::line_col;
use super::refs::{Along, Nodes, known, label};
use super::settings::BodyForce;
use super::single::MAX_ELEMENTS;
use super::spec::SpringSpec;
use super::{Frame, ScenarioError, ScenarioFile, Skeleton};
use crate::text::{clip, num, nums};

/// Most `[[node]]` tables.
pub const MAX_NAMED_NODES: usize = 100_000;
/// Most `[[string]]` tables.
pub const MAX_STRINGS: usize = 100_000;
/// Most `[[spring]]` tables.
pub const MAX_SPRINGS: usize = 100_000;
/// Most entries in one string's `path`.
pub const MAX_PATH: usize = 100_000;
/// Longest name of a node, material, string or spring [bytes].
pub const MAX_NAME_BYTES: usize = 64;

/// Where a name was first given: table kind, index and span.
type FirstUse = (&'static str, usize, Range<usize>);

/// A string as built: its group, the elements parked on a winch's drum before it, its
/// first interior node and its winch.
struct BuiltString {
    group: usize,
    parked: usize,
    first_interior: usize,
    winch: Option<super::winch::WinchString>,
}

/// What building the strings gives besides the mesh: the strings' hydrodynamics and the
/// strings that winches pay out.
struct StringsBuilt {
    hydro: Vec<(usize, phstring::LineHydro)>,
    winches: Vec<super::winch::WinchString>,
}

impl ScenarioFile {
    /// `name` (the value of `key`) if it is a valid name: 1 to [`MAX_NAME_BYTES`] ASCII
    /// letters, digits, `_` and `-`, starting with a letter or `_` (so that it cannot be
    /// mistaken for an index, and `:` can separate a string's name from a node index).
    pub(super) fn checked_name<'a>(
        &self,
        key: &str,
        name: &'a str,
        span: Range<usize>,
    ) -> Result<&'a str, ScenarioError> {
        let ok = name.len() <= MAX_NAME_BYTES
            && name
                .chars()
                .next()
                .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
        if ok {
            Ok(name)
        } else {
            Err(self.invalid(
                key,
                span,
                format!(
                    "= \"{}\" is not a valid name: use 1 to {MAX_NAME_BYTES} ASCII letters, digits, `_` and `-`, starting with a letter or `_`",
                    clip(name)
                ),
            ))
        }
    }

    /// Records `name` (the value of `key`, table `kind` number `k`) in `seen`, or says
    /// where it was given first.
    fn unique_name<'s>(
        &self,
        seen: &mut HashMap<&'s str, FirstUse>,
        key: &str,
        name: &'s Spanned<String>,
        kind: &'static str,
        k: usize,
    ) -> Result<&'s str, ScenarioError> {
        let n = self.checked_name(key, name.get_ref(), name.span())?;
        if let Some((kind0, k0, span0)) = seen.get(n) {
            let (line, _) = line_col(self.text(), span0.start);
            return Err(self.invalid(
                key,
                name.span(),
                format!(
                    "= \"{n}\" is already the name of {kind0}.{k0} (line {line}); names must differ"
                ),
            ));
        }
        seen.insert(n, (kind, k, name.span()));
        Ok(n)
    }

    /// Refuses more than `max` tables `kind` (`count` given).
    fn at_most(&self, kind: &str, count: usize, max: usize) -> Result<(), ScenarioError> {
        if count > max {
            return Err(self.invalid(
                kind,
                0..0,
                format!("has {count} tables; at most {max} are allowed"),
            ));
        }
        Ok(())
    }

    /// `[materials.NAME]`: every cross-section, by name.
    fn materials(&self) -> Result<BTreeMap<&str, CrossSection>, ScenarioError> {
        let mut out = BTreeMap::new();
        for (name, spec) in &self.scenario.materials {
            // The name is user text of any length: the key in messages is clipped.
            let key = format!("materials.{}", clip(name));
            self.checked_name(&key, name, spec.span())?;
            out.insert(name.as_str(), self.cross_section(&key, spec.get_ref())?);
        }
        Ok(out)
    }

    /// `[[node]]`: unique names, finite positions; they become mesh nodes 0, 1, ….
    fn named_nodes<'s, const D: usize>(
        &'s self,
        b: &mut NetworkBuilder<D, Material>,
        nodes: &mut Nodes<'s>,
        components: &mut Components,
    ) -> Result<(), ScenarioError> {
        let list = &self.scenario.node;
        self.at_most("node", list.len(), MAX_NAMED_NODES)?;
        let mut seen = HashMap::new();
        for (k, spec) in list.iter().enumerate() {
            let spec = spec.get_ref();
            let name =
                self.unique_name(&mut seen, &format!("node.{k}.name"), &spec.name, "node", k)?;
            let r = self.vector::<D>(&format!("node.{k}.position"), &spec.position)?;
            let i = b.node(r);
            nodes.add_named(name, i);
            components.nodes.push(NamedNode {
                name: name.to_string(),
                node: i,
                position: r.as_slice().to_vec(),
            });
        }
        nodes.n_nodes = b.n_nodes();
        Ok(())
    }

    /// `[[string]]`: each runs straight along its path (`[[node]]`s and nodes of the strings
    /// above it), `elements` per span, with a `[materials.NAME]` cross-section. Returns the
    /// `(element group, hydrodynamics)` of the strings whose material has a `diameter`.
    #[allow(clippy::too_many_arguments)] // the network's parts, each needed once
    fn strings<'s, const D: usize>(
        &'s self,
        b: &mut NetworkBuilder<D, Material>,
        nodes: &mut Nodes<'s>,
        materials: &BTreeMap<&str, CrossSection>,
        body: &BodyForce<D>,
        components: &mut Components,
        names: &mut HashMap<&'s str, FirstUse>,
        used: &mut [bool],
    ) -> Result<StringsBuilt, ScenarioError> {
        let list = &self.scenario.string;
        self.at_most("string", list.len(), MAX_STRINGS)?;
        let mut total = 0usize;
        let mut hydro = Vec::new();
        let mut winches = Vec::new();
        for (k, spec) in list.iter().enumerate() {
            let spec = spec.get_ref();
            let key = |f: &str| format!("string.{k}.{f}");
            let name = self.unique_name(names, &key("name"), &spec.name, "string", k)?;
            let entries = spec.path.get_ref();
            if entries.len() < 2 || entries.len() > MAX_PATH {
                return Err(self.invalid(
                    &key("path"),
                    spec.path.span(),
                    format!(
                        "has {} nodes; a string's path has 2 to {MAX_PATH}",
                        entries.len()
                    ),
                ));
            }
            let per_span = *spec.elements.get_ref();
            let spans = entries.len() - 1;
            let count = usize::try_from(per_span)
                .ok()
                .filter(|&n| n >= 1)
                .and_then(|n| n.checked_mul(spans))
                .filter(|&n| n <= MAX_ELEMENTS - total);
            let Some(count) = count else {
                return Err(self.invalid(
                    &key("elements"),
                    spec.elements.span(),
                    if per_span < 1 {
                        format!("must be at least 1 (elements per span), got {per_span}")
                    } else {
                        format!(
                            "= {per_span} per span over {spans} spans is too many: the strings and springs may have at most {MAX_ELEMENTS:.0e} elements in all ({total} before this string)"
                        )
                    },
                ));
            };
            let per_span = per_span as usize;
            let material_name = spec.material.get_ref();
            let cs = *materials.get(material_name.as_str()).ok_or_else(|| {
                let names: Vec<&str> = materials.keys().copied().collect();
                self.invalid(
                    &key("material"),
                    spec.material.span(),
                    if names.is_empty() {
                        format!(
                            "names material \"{}\", but the scenario has no [materials.NAME] tables",
                            clip(material_name)
                        )
                    } else {
                        format!(
                            "names material \"{}\", which is not a [materials.NAME] table (known: {})",
                            clip(material_name),
                            known(&names, material_name)
                        )
                    },
                )
            })?;
            let prestretch = match &spec.prestretch {
                Some(p) => {
                    let x = self.positive(&key("prestretch"), p)?;
                    if !cs.material.admissible(x * x) {
                        return Err(self.invalid(
                            &key("prestretch"),
                            p.span(),
                            format!(
                                "= {} gives the strain C = {} outside the domain of {}",
                                num(x),
                                num(x * x),
                                cs.material.name()
                            ),
                        ));
                    }
                    x
                }
                None => 1.0,
            };
            let path = self.string_path(k, spec.path.get_ref(), nodes, b, per_span, prestretch)?;
            for &p in &path {
                if let Some(u) = used.get_mut(p) {
                    *u = true;
                }
            }
            let body_force = body.on_string(cs.rho_a);
            self.string_scales(k, spec, &path, b, &cs, body)?;
            let (material, rho_a, mass) = (cs.material, cs.rho_a, cs.mass);
            let name_owned = name.to_string();
            let string_spec = StringSpec {
                name: name_owned,
                material,
                rho_a,
                mass,
                body_force,
                prestretch,
            };
            let built = self.build_string(
                k,
                b,
                (&path, per_span, prestretch),
                string_spec,
                total + count,
            )?;
            winches.extend(built.winch);
            let (g, first_interior, first_element) =
                (built.group, built.first_interior, total + built.parked);
            total += built.parked;
            b.set_damping(g, cs.damping)
                .map_err(|e| self.invalid(&format!("string.{k}"), 0..0, e.to_string()))?;
            if let Some(h) = cs.hydro {
                hydro.push((g, h));
            }
            total += count;
            let along = Along {
                path,
                per_span,
                first_interior,
            };
            let layout = StringLayout {
                elements: [first_element, total],
                nodes: along.len(),
                path_nodes: along.path.clone(),
                elements_per_span: per_span,
                interior_nodes: [along.interior().start, along.interior().end],
            };
            components.strings.push(StringComponent::new(
                name.to_string(),
                layout,
                material_name.clone(),
                &cs,
                body_force.as_slice(),
            ));
            nodes.add_string(name, along);
            nodes.n_nodes = b.n_nodes();
        }
        Ok(StringsBuilt { hydro, winches })
    }

    /// Builds string `k` (`spec`) along `path` in `b`, on its winch's drum if one pays it
    /// out (`before` elements come before the drum's).
    fn build_string<const D: usize>(
        &self,
        k: usize,
        b: &mut NetworkBuilder<D, Material>,
        (path, per_span, prestretch): (&[usize], usize, f64),
        spec: StringSpec<D, Material>,
        before: usize,
    ) -> Result<BuiltString, ScenarioError> {
        // A winch's reserve: elements parked on its drum before the string's own.
        let reserve = self.winch_reserve(&spec.name, (path, b), per_span, prestretch, before)?;
        let parked = reserve.map_or(0, |r| r.1);
        let first_interior = b.n_nodes() + parked;
        let built = match reserve {
            Some((_, r)) => b.string_on_drum(spec, path, per_span, r),
            None => b.string(spec, path, per_span),
        };
        let group = built.map_err(|e| self.invalid(&format!("string.{k}"), 0..0, e.to_string()))?;
        Ok(BuiltString {
            group,
            parked,
            first_interior,
            winch: reserve.map(|(winch, reserve)| super::winch::WinchString {
                winch,
                group,
                reserve,
            }),
        })
    }

    /// The winch of string `name` (path `path` in `b`) and the elements parked on its drum,
    /// if a winch pays it out; `before` elements come before them.
    fn winch_reserve<const D: usize>(
        &self,
        name: &str,
        (path, b): (&[usize], &NetworkBuilder<D, Material>),
        per_span: usize,
        prestretch: f64,
        before: usize,
    ) -> Result<Option<(usize, usize)>, ScenarioError> {
        let Some((w, ws)) = self.winch_of(name) else {
            return Ok(None);
        };
        let (a, c) = (b.position(path[0]), b.position(path[1]));
        let span = a.zip(c).map_or(0.0, |(a, c)| (c - a).norm());
        let l = span / per_span as f64 / prestretch;
        let reserve = self.reserve_elements(w, ws, l)?;
        if reserve > MAX_ELEMENTS - before {
            return Err(self.invalid(
                &format!("winch.{w}.reserve"),
                ws.reserve.as_ref().map_or(0..0, |r| r.span()),
                format!("asks for {reserve} elements on the drum: the strings and springs may have at most {MAX_ELEMENTS:.0e} elements in all"),
            ));
        }
        Ok(Some((w, reserve)))
    }

    /// The mesh nodes of `string.{k}.path`: each resolved, consecutive ones different and
    /// apart, every span's length and reference element length finite and positive.
    fn string_path<const D: usize>(
        &self,
        k: usize,
        entries: &[Spanned<super::refs::NodeRef>],
        nodes: &Nodes,
        b: &NetworkBuilder<D, Material>,
        per_span: usize,
        prestretch: f64,
    ) -> Result<Vec<usize>, ScenarioError> {
        let mut path: Vec<usize> = Vec::with_capacity(entries.len());
        for (i, entry) in entries.iter().enumerate() {
            let key = format!("string.{k}.path.{i}");
            let node = self.resolve(&key, entry, nodes)?;
            if let Some(&prev) = path.last() {
                let here = label(entry.get_ref(), node);
                if prev == node {
                    return Err(self.invalid(
                        &key,
                        entry.span(),
                        format!(
                            "is {here} again: consecutive nodes of a path must differ (a span needs two ends)"
                        ),
                    ));
                }
                let (ra, rb) = (
                    b.position(prev).unwrap_or_else(Vector::zeros),
                    b.position(node).unwrap_or_else(Vector::zeros),
                );
                let length = super::rounding::length(&(rb - ra));
                let element = length / per_span as f64;
                let l = element / prestretch;
                let problem = if ra == rb {
                    Some(format!(
                        "is {here}, at the same position {} m as the path's previous node: the span between them has zero length",
                        nums(rb.as_slice())
                    ))
                } else if !length.is_finite() {
                    Some(format!(
                        "is {here}: the length of the span to it overflows (the coordinates are too large)"
                    ))
                } else if element * element < f64::MIN_POSITIVE {
                    Some(format!(
                        "is {here}, {} m from the path's previous node: the span's elements ({per_span} of {} m) are too short for floating point, their squared length (in the strain C) underflows below {:.1e} m²; elements must be longer than {:.1e} m",
                        num(length),
                        num(element),
                        f64::MIN_POSITIVE,
                        f64::MIN_POSITIVE.sqrt()
                    ))
                } else if !(l > 0.0 && l.is_finite()) {
                    Some(format!(
                        "is {here}: the span to it has the length {} m, which gives the reference element length {} m (elements and prestretch)",
                        num(length),
                        num(l)
                    ))
                } else {
                    None
                };
                if let Some(reason) = problem {
                    return Err(self.invalid(&key, entry.span(), reason));
                }
            }
            path.push(node);
        }
        Ok(path)
    }

    /// Refuses a string whose longest element is too heavy or has too much drag
    /// ([`ScenarioFile::element_scales`]).
    fn string_scales<const D: usize>(
        &self,
        k: usize,
        spec: &super::spec::StringPathSpec,
        path: &[usize],
        b: &NetworkBuilder<D, Material>,
        cs: &CrossSection,
        body: &BodyForce<D>,
    ) -> Result<(), ScenarioError> {
        let per_span = *spec.elements.get_ref() as f64;
        let prestretch = spec.prestretch.as_ref().map_or(1.0, |p| *p.get_ref());
        // The longest span: (its index in the path, the reference element length).
        let (span, l) = path
            .windows(2)
            .enumerate()
            .map(|(i, w)| {
                let at = |n| b.position(n).unwrap_or_else(Vector::zeros);
                let d = super::rounding::length(&(at(w[1]) - at(w[0])));
                (i + 1, d / per_span / prestretch)
            })
            .fold((1, 0.0), |m, x| if x.1 > m.1 { x } else { m });
        let material = spec.material.get_ref();
        // What sets ℓ: the prestretch if it lengthens the elements, else the span.
        let key = match &spec.prestretch {
            Some(p) if prestretch < 1.0 => (
                format!("string.{k}.prestretch"),
                p.span(),
                format!("= {} ", num(prestretch)),
            ),
            _ => (
                format!("string.{k}.path.{span}"),
                spec.path.get_ref()[span].span(),
                String::new(),
            ),
        };
        let longest = Longest {
            owner: format!("string \"{}\" (string.{k})", clip(spec.name.get_ref())),
            l,
            from: format!("span {span} of its path / elements / prestretch"),
            key,
        };
        let mat_spec = self.scenario.materials.get(material).map(|m| m.get_ref());
        let mat_key = format!("materials.{}", clip(material));
        self.element_scales(&mat_key, mat_spec, cs, body, longest)
    }

    /// `[[spring]]`: between two different nodes, or from one node to a fixed point
    /// (`to_point`, which becomes a new fixed node).
    #[allow(clippy::too_many_arguments)] // the network's parts, each needed once
    fn springs<'s, const D: usize>(
        &'s self,
        b: &mut NetworkBuilder<D, Material>,
        nodes: &mut Nodes<'s>,
        components: &mut Components,
        names: &mut HashMap<&'s str, FirstUse>,
        used: &mut [bool],
        first_element: usize,
    ) -> Result<(), ScenarioError> {
        let list = &self.scenario.spring;
        self.at_most("spring", list.len(), MAX_SPRINGS)?;
        if first_element + list.len() > MAX_ELEMENTS {
            return Err(self.invalid(
                "spring",
                0..0,
                format!(
                    "has {} springs after {first_element} string elements: at most {MAX_ELEMENTS:.0e} elements are allowed in all",
                    list.len()
                ),
            ));
        }
        for (k, spec) in list.iter().enumerate() {
            let spec = spec.get_ref();
            let key = |f: &str| format!("spring.{k}.{f}");
            let name = self.unique_name(names, &key("name"), &spec.name, "spring", k)?;
            let (stiffness, rest, damping) = self.spring_law(k, spec)?;
            let (a, ends, to_point) = self.spring_ends::<D>(k, spec, b, nodes)?;
            let built = match to_point {
                None => b.spring(name, a, ends[1], stiffness, rest),
                Some(p) => b.spring_to_point(name, a, p, stiffness, rest),
            };
            let g = built.map_err(|e| self.invalid(&format!("spring.{k}"), 0..0, e.to_string()))?;
            let dashpot = phstring::Damping {
                dashpot: damping,
                ..phstring::Damping::NONE
            };
            b.set_damping(g, dashpot)
                .map_err(|e| self.invalid(&format!("spring.{k}"), 0..0, e.to_string()))?;
            let b_end = b.n_nodes() - 1;
            let nodes_of = [a, if to_point.is_some() { b_end } else { ends[1] }];
            for &n in &nodes_of {
                if let Some(u) = used.get_mut(n) {
                    *u = true;
                }
            }
            components.springs.push(SpringComponent {
                name: name.to_string(),
                element: first_element + k,
                nodes: nodes_of,
                k: stiffness,
                rest,
                to_point: to_point.map(|p| p.as_slice().to_vec()),
                damping,
            });
        }
        // Spring indices count in the strings' mesh (a spring's fixed point is not a node
        // another spring can be meant to reach by `-1`); later references see every node.
        nodes.n_nodes = b.n_nodes();
        Ok(())
    }

    /// The law of `spring.{k}` (`spec`): its stiffness [N/m] (0 only for a pure dashpot),
    /// rest length [m] and damping [N s/m].
    fn spring_law(&self, k: usize, spec: &SpringSpec) -> Result<(f64, f64, f64), ScenarioError> {
        let key = |f: &str| format!("spring.{k}.{f}");
        let damping = self.non_negative(&key("damping"), spec.damping.as_ref())?;
        // A spring of stiffness 0 is a pure dashpot.
        let stiffness = if damping > 0.0 {
            self.non_negative(&key("k"), Some(&spec.k))?
        } else {
            let k = *spec.k.get_ref();
            if k == 0.0 {
                return Err(self.invalid(
                    &key("k"),
                    spec.k.span(),
                    "= 0: a spring of stiffness 0 does nothing; give `damping` [N s/m] for a pure dashpot",
                ));
            }
            self.positive(&key("k"), &spec.k)?
        };
        let rest = *spec.rest.get_ref();
        if stiffness == 0.0 && rest != 0.0 {
            return Err(self.invalid(
                &key("rest"),
                spec.rest.span(),
                format!(
                    "= {}: a pure dashpot (k = 0) has no rest length; give rest = 0",
                    num(rest)
                ),
            ));
        }
        if !(rest >= 0.0 && rest.is_finite()) {
            return Err(self.invalid(
                &key("rest"),
                spec.rest.span(),
                format!("must be at least 0 and finite, got {}", num(rest)),
            ));
        }
        Ok((stiffness, rest, damping))
    }

    /// The ends of `spring.{k}` (`spec`): its first node, the nodes resolved from
    /// `between`, and its fixed point [m] if it has `to_point`; refused: two equal nodes, a
    /// wrong count, an initial length that overflows or is zero with a positive rest length.
    fn spring_ends<const D: usize>(
        &self,
        k: usize,
        spec: &SpringSpec,
        b: &NetworkBuilder<D, Material>,
        nodes: &Nodes<'_>,
    ) -> Result<(usize, Vec<usize>, Option<Vector<D>>), ScenarioError> {
        let key = |f: &str| format!("spring.{k}.{f}");
        let rest = *spec.rest.get_ref();
        let between = spec.between.get_ref();
        let mut ends = Vec::with_capacity(2);
        for (i, r) in between.iter().enumerate().take(2) {
            ends.push(self.resolve(&format!("spring.{k}.between.{i}"), r, nodes)?);
        }
        let a = ends.first().copied().unwrap_or(0);
        let ra = b.position(a).unwrap_or_else(Vector::zeros);
        let (other, to_point) = match (between.len(), &spec.to_point) {
            (2, None) => {
                if ends[1] == a {
                    return Err(self.invalid(
                        &key("between.1"),
                        between[1].span(),
                        format!(
                            "is the same node as between.0 ({}): a spring joins two different nodes",
                            label(between[0].get_ref(), a)
                        ),
                    ));
                }
                (b.position(ends[1]).unwrap_or_else(Vector::zeros), None)
            }
            (2, Some(p)) => {
                return Err(self.invalid(
                    &key("to_point"),
                    p.span(),
                    "must not be given with two nodes in `between` (a spring to a fixed point names one node)",
                ));
            }
            (1, Some(p)) => {
                let p = self.vector::<D>(&key("to_point"), p)?;
                (p, Some(p))
            }
            (1, None) => {
                return Err(self.invalid(
                    &key("between"),
                    spec.between.span(),
                    "names one node: give a second one, or `to_point` for a spring to a fixed point",
                ));
            }
            (n, _) => {
                return Err(self.invalid(
                    &key("between"),
                    spec.between.span(),
                    format!("must name two nodes (or one, with `to_point`), got {n}"),
                ));
            }
        };
        let c = (other - ra).norm_squared();
        if !c.is_finite() {
            return Err(self.invalid(
                &key("between"),
                spec.between.span(),
                "the spring's initial length overflows (the coordinates are too large)",
            ));
        }
        if c == 0.0 && rest > 0.0 {
            return Err(self.invalid(
                &key("rest"),
                spec.rest.span(),
                format!(
                    "= {} but the spring's ends start at the same point, where the direction of its force is undefined (use rest = 0 or move an end)",
                    num(rest)
                ),
            ));
        }
        Ok((a, ends, to_point))
    }

    /// A network: `[materials.NAME]`, `[[node]]`, `[[string]]`, `[[spring]]`; every
    /// `[[node]]` must belong to a string or a spring.
    pub(super) fn network<'s, const D: usize>(
        &'s self,
        body: &BodyForce<D>,
    ) -> Result<Skeleton<'s, D>, ScenarioError> {
        let s = &self.scenario;
        let materials = self.materials()?;
        let mut b = NetworkBuilder::<D, Material>::new();
        let mut nodes = Nodes::network(
            s.string
                .iter()
                .map(|st| st.get_ref().name.get_ref().as_str())
                .collect(),
        );
        let mut components = Components::default();
        self.named_nodes(&mut b, &mut nodes, &mut components)?;
        let bodies = self.body_points(&mut b, &mut nodes, &mut components, body.g())?;
        let mut used = vec![false; b.n_nodes()];
        let mut names = HashMap::new();
        let StringsBuilt { hydro, winches } = self.strings(
            &mut b,
            &mut nodes,
            &materials,
            body,
            &mut components,
            &mut names,
            &mut used,
        )?;
        nodes.partial = false;
        let first_spring = components.strings.last().map_or(0, |st| st.elements[1]);
        self.springs(
            &mut b,
            &mut nodes,
            &mut components,
            &mut names,
            &mut used,
            first_spring,
        )?;
        if let Some(k) = used.iter().take(s.node.len()).position(|u| !u) {
            let spec = s.node[k].get_ref();
            return Err(self.invalid(
                &format!("node.{k}.name"),
                spec.name.span(),
                format!(
                    "= \"{}\" is on no string's path and at no spring's end: every [[node]] must belong to one (remove it, or attach it)",
                    clip(spec.name.get_ref())
                ),
            ));
        }
        self.body_points_used(&mut components, &used)?;
        // Nodes that no string touches (only springs, which are massless); a body carries
        // its points.
        let mut massless = vec![true; b.n_nodes()];
        for p in components.bodies.iter().flat_map(|bd| &bd.points) {
            massless[p.node] = false;
        }
        for st in &components.strings {
            for &p in &st.path_nodes {
                massless[p] = false;
            }
            for i in st.interior_nodes[0]..st.interior_nodes[1] {
                massless[i] = false;
            }
        }
        Ok(Skeleton {
            frame: Frame::Network(b),
            nodes,
            components,
            massless,
            single_damping: phstring::Damping::NONE,
            hydro,
            bodies,
            winches,
        })
    }

    /// Refuses a network node that only springs hold (they are massless), unless a point
    /// mass gives it inertia or all its components are fixed or moved; names the first
    /// spring at the node.
    pub(super) fn check_spring_nodes<const D: usize>(
        &self,
        sk: &Skeleton<D>,
        boundary: &phstring::Boundary<D>,
        point_masses: &[phstring::PointMass<D>],
    ) -> Result<(), ScenarioError> {
        if !sk.massless.iter().any(|&m| m) {
            return Ok(());
        }
        let mut held = vec![[false; D]; sk.massless.len()];
        for f in &boundary.fixed {
            for (h, &c) in held[f.node].iter_mut().zip(&f.components) {
                *h |= c;
            }
        }
        for m in &boundary.motions {
            held[m.node][m.component] = true;
        }
        // The fixed ends of springs with `to_point` (fixed when the network is built).
        for sp in sk
            .components
            .springs
            .iter()
            .filter(|sp| sp.to_point.is_some())
        {
            held[sp.nodes[1]] = [true; D];
        }
        let mut has_mass = vec![false; sk.massless.len()];
        for pm in point_masses {
            has_mass[pm.node] = true;
        }
        for (k, sp) in sk.components.springs.iter().enumerate() {
            for (j, &n) in sp.nodes.iter().enumerate() {
                if !sk.massless[n] || has_mass[n] || held[n].iter().all(|&h| h) {
                    continue;
                }
                let spec = self.scenario.spring[k].get_ref();
                let Some(r) = spec.between.get_ref().get(j) else {
                    continue;
                };
                return Err(self.invalid(
                    &format!("spring.{k}.between.{j}"),
                    r.span(),
                    format!(
                        "is {}, which only springs hold: springs are massless, so give the node a [[point_mass]] or fix it",
                        label(r.get_ref(), n)
                    ),
                ));
            }
        }
        Ok(())
    }
}
