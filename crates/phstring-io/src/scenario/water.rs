//! Validation of `[water]`, `[seabed]`, the strings' hydrodynamic keys (`diameter`, `cd`,
//! `cd_axial`, `ca`, `ca_axial` of a material) and the point masses' (`volume`, `cda`,
//! `ca`): the library's [`Water`], [`LineHydro`] and [`PointHydro`] (docs/method.md §21).

use phstring::{
    Bathymetry, Boundary, Current, Friction, LineHydro, PointHydro, Seabed, SeabedSurface, Vector,
    Water,
};
use toml::Spanned;

use super::spec::{MaterialSpec, PointMassSpec, SeabedSpec, WaterSpec};
use super::{ScenarioError, ScenarioFile};
use crate::text::num;

/// Sea water's density [kg/m³], the default of `water.density`.
pub const SEA_WATER_DENSITY: f64 = 1025.0;

/// MoorDyn's default `FricDamp` [N·s/m], the default of `seabed.friction_damping`.
pub const DEFAULT_FRICTION_DAMPING: f64 = 200.0;

impl ScenarioFile {
    /// The hydrodynamic keys of the cross-section `spec` at `prefix` (`material` or
    /// `materials.NAME`): `None` without `diameter` (then `cd`, `cd_axial`, `ca` and
    /// `ca_axial` must be absent too).
    pub(super) fn line_hydro(
        &self,
        prefix: &str,
        spec: &MaterialSpec,
    ) -> Result<Option<LineHydro>, ScenarioError> {
        let key = |k: &str| format!("{prefix}.{k}");
        let coefficients = [
            ("cd", &spec.cd),
            ("cd_axial", &spec.cd_axial),
            ("ca", &spec.ca),
            ("ca_axial", &spec.ca_axial),
        ];
        let Some(d) = &spec.diameter else {
            if let Some((k, Some(v))) = coefficients.iter().find(|(_, v)| v.is_some()) {
                return Err(self.invalid(
                    &key(k),
                    v.span(),
                    "needs the hydrodynamic diameter (`diameter`) of the same material",
                ));
            }
            return Ok(None);
        };
        let diameter = self.positive(&key("diameter"), d)?;
        let [cd, cd_axial, ca, ca_axial] =
            coefficients.map(|(k, v)| self.non_negative(&key(k), v.as_ref()));
        Ok(Some(LineHydro {
            diameter,
            cd: cd?,
            cd_axial: cd_axial?,
            ca: ca?,
            ca_axial: ca_axial?,
        }))
    }

    /// The hydrodynamic keys of point mass `k` at mesh node `node`: `None` when it has none.
    pub(super) fn point_hydro(
        &self,
        k: usize,
        pm: &PointMassSpec,
        node: usize,
    ) -> Result<Option<PointHydro>, ScenarioError> {
        let key = |f: &str| format!("point_mass.{k}.{f}");
        if pm.volume.is_none() && pm.cda.is_none() && pm.ca.is_none() {
            return Ok(None);
        }
        Ok(Some(PointHydro {
            node,
            volume: self.non_negative(&key("volume"), pm.volume.as_ref())?,
            cda: self.non_negative(&key("cda"), pm.cda.as_ref())?,
            ca: self.non_negative(&key("ca"), pm.ca.as_ref())?,
        }))
    }

    /// `[water]` with `[seabed]`, for gravity `gravity` (`body_force.gravity`, which must
    /// point straight down the vertical axis): `None` without `[water]`.
    pub(super) fn water<const D: usize>(
        &self,
        gravity: Option<Vector<D>>,
    ) -> Result<Option<Water<D>>, ScenarioError> {
        let Some(spec) = &self.scenario.water else {
            if let Some(sb) = &self.scenario.seabed {
                return Err(self.invalid(
                    "seabed",
                    sb.span(),
                    "needs [water] (its depth places a flat seabed)",
                ));
            }
            return Ok(None);
        };
        let w = spec.get_ref();
        if D < 2 {
            return Err(self.invalid(
                "water",
                spec.span(),
                "needs dimension 2 or 3 (the vertical axis is the last one)",
            ));
        }
        let g = self.water_gravity(spec, gravity)?;
        let density = match &w.density {
            Some(d) => self.positive("water.density", d)?,
            None => SEA_WATER_DENSITY,
        };
        let mut water = Water::<D>::new(density)
            .with_gravity(g)
            .with_current(self.current::<D>(w)?);
        if let Some(s) = &w.drag_smoothing {
            water.drag_smoothing = self.positive("water.drag_smoothing", s)?;
        }
        water.linear_drag_amplitude = self.non_negative(
            "water.linear_drag_amplitude",
            w.linear_drag_amplitude.as_ref(),
        )?;
        if let Some(sb) = &self.scenario.seabed {
            water = water.with_seabed(self.seabed::<D>(w, sb)?);
        }
        Ok(Some(water))
    }

    /// Refuses a support held in every component below a flat seabed (by more than 1e-9 of
    /// the depth) at its position `r` [m]: its line would start inside the seabed, and the
    /// contact would push it out with the penalty's force of the whole depth difference (an
    /// anchor 220 m below a seabed given by `--set water.depth=100` ran with 1e10 N). Names
    /// the node and `water.depth`.
    pub(super) fn supports_above_seabed<const D: usize>(
        &self,
        water: &Water<D>,
        boundary: &Boundary<D>,
        r: &[Vector<D>],
    ) -> Result<(), ScenarioError> {
        let Some(SeabedSurface::Flat { depth }) = water.seabed.as_ref().map(|s| &s.surface) else {
            return Ok(());
        };
        let Some(key) = self
            .scenario
            .water
            .as_ref()
            .and_then(|w| w.get_ref().depth.as_ref())
        else {
            return Ok(());
        };
        let deepest = boundary
            .fixed
            .iter()
            .filter(|f| f.components.iter().all(|&c| c))
            .map(|f| (f.node, r[f.node][D - 1]))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        match deepest {
            Some((node, z)) if z < -depth * (1.0 + 1e-9) => Err(self.invalid(
                "water.depth",
                key.span(),
                format!(
                    "= {} m puts the seabed at z = {} m, above the support at mesh node {node} (z = {} m): its line would start inside the seabed",
                    num(*depth),
                    num(-depth),
                    num(z)
                ),
            )),
            _ => Ok(()),
        }
    }

    /// The magnitude [m/s²] of `gravity`, which must point straight down the vertical axis.
    fn water_gravity<const D: usize>(
        &self,
        spec: &Spanned<WaterSpec>,
        gravity: Option<Vector<D>>,
    ) -> Result<f64, ScenarioError> {
        let down = gravity.filter(|g| g[D - 1] < 0.0 && (0..D - 1).all(|i| g[i] == 0.0));
        match down {
            Some(g) => Ok(-g[D - 1]),
            None => {
                let (key, span) = match &self.scenario.body_force.gravity {
                    Some(g) => ("body_force.gravity", g.span()),
                    None => ("water", spec.span()),
                };
                Err(self.invalid(
                    key,
                    span,
                    format!(
                        "[water] needs body_force.gravity pointing straight down the vertical axis, e.g. {}: buoyancy acts against it and the free surface is level",
                        if D == 2 { "[0, -9.81]" } else { "[0, 0, -9.81]" }
                    ),
                ))
            }
        }
    }

    /// `water.current` or `water.current_profile` (still water without either).
    fn current<const D: usize>(&self, w: &WaterSpec) -> Result<Current<D>, ScenarioError> {
        match (&w.current, &w.current_profile) {
            (Some(_), Some(p)) => Err(self.invalid(
                "water.current_profile",
                p.span(),
                "is given with water.current: give one of them",
            )),
            (Some(u), None) => Ok(Current::Uniform(self.vector::<D>("water.current", u)?)),
            (None, Some(p)) => self.current_profile::<D>(p),
            (None, None) => Ok(Current::still()),
        }
    }

    /// Rows `[z, u…]` of strictly increasing, finite `z` and finite `u`.
    fn current_profile<const D: usize>(
        &self,
        p: &Spanned<Vec<Vec<f64>>>,
    ) -> Result<Current<D>, ScenarioError> {
        let bad = |reason: String| self.invalid("water.current_profile", p.span(), reason);
        let rows = p.get_ref();
        if rows.is_empty() {
            return Err(bad(
                "has no rows: give [z, u_x, …] rows or leave it out".into()
            ));
        }
        let mut points: Vec<(f64, Vector<D>)> = Vec::with_capacity(rows.len());
        for (i, row) in rows.iter().enumerate() {
            if row.len() != D + 1 {
                return Err(bad(format!(
                    "row {i} has {} numbers; each row is [z, then {D} velocity components]",
                    row.len()
                )));
            }
            if let Some(x) = row.iter().find(|x| !x.is_finite()) {
                return Err(bad(format!("row {i} has a non-finite number {}", num(*x))));
            }
            if let Some((z0, _)) = points.last()
                && row[0] <= *z0
            {
                return Err(bad(format!(
                    "row {i}: z = {} is not above the row before ({}): heights must increase",
                    num(row[0]),
                    num(*z0)
                )));
            }
            points.push((row[0], Vector::<D>::from_column_slice(&row[1..])));
        }
        Ok(Current::Profile(points))
    }

    /// `[seabed]`: a plane through `point` (default: `−water.depth` on the vertical axis)
    /// with upward `normal` (default vertical).
    fn seabed<const D: usize>(
        &self,
        w: &WaterSpec,
        sb: &Spanned<SeabedSpec>,
    ) -> Result<Seabed<D>, ScenarioError> {
        let s = sb.get_ref();
        let k = self.positive("seabed.stiffness", &s.stiffness)?;
        let c = self.non_negative("seabed.damping", s.damping.as_ref())?;
        let mut seabed = match (&s.bathymetry, &s.point, &s.normal) {
            (Some(file), _, _) => Seabed::grid(self.bathymetry::<D>(s, file)?, k, c),
            (None, None, None) => {
                let Some(depth) = &w.depth else {
                    return Err(self.invalid(
                        "seabed",
                        sb.span(),
                        "needs water.depth (a flat seabed at −depth) or a point of its plane (seabed.point)",
                    ));
                };
                Seabed::flat(self.positive("water.depth", depth)?, k, c)
            }
            (None, point, normal) => {
                let point = match point {
                    Some(p) => self.vector::<D>("seabed.point", p)?,
                    None => {
                        let depth = w.depth.as_ref().ok_or_else(|| {
                            self.invalid(
                                "seabed",
                                sb.span(),
                                "needs water.depth or seabed.point: a point of its plane",
                            )
                        })?;
                        let mut p = Vector::<D>::zeros();
                        p[D - 1] = -self.positive("water.depth", depth)?;
                        p
                    }
                };
                let normal = match normal {
                    Some(n) => self.upward::<D>(n)?,
                    None => {
                        let mut n = Vector::<D>::zeros();
                        n[D - 1] = 1.0;
                        n
                    }
                };
                Seabed::plane(point, normal, k, c)
            }
        };
        if let Some(r) = &s.damping_ramp {
            seabed.damping_ramp = self.positive("seabed.damping_ramp", r)?;
        }
        let mu = self.non_negative("seabed.friction", s.friction.as_ref())?;
        let axial = match &s.friction_axial {
            Some(a) => Some(self.non_negative("seabed.friction_axial", Some(a))?),
            None => None,
        };
        let scale = match &s.friction_static_scale {
            Some(f) => self.positive("seabed.friction_static_scale", f)?,
            None => 1.0,
        };
        if mu > 0.0 || axial.is_some_and(|a| a > 0.0) {
            let fric_damp = match &s.friction_damping {
                Some(f) => self.positive("seabed.friction_damping", f)?,
                None => DEFAULT_FRICTION_DAMPING,
            };
            // A zero coefficient keeps a positive slope (the law is then off in that
            // direction: its Coulomb level μN is 0).
            let slope = |m: f64| if m > 0.0 { m * fric_damp } else { fric_damp };
            let mut friction = Friction::new(mu, slope(mu)).with_static_scale(scale);
            if let Some(a) = axial {
                friction = friction.with_axial(a, slope(a));
            }
            seabed = seabed.with_friction(friction);
        }
        Ok(seabed)
    }

    /// `seabed.bathymetry`: the grid read from its file (relative to the scenario file's
    /// folder), without `point` or `normal`.
    fn bathymetry<const D: usize>(
        &self,
        s: &SeabedSpec,
        file: &Spanned<String>,
    ) -> Result<Bathymetry, ScenarioError> {
        if let Some(p) = s.point.as_ref().or(s.normal.as_ref()) {
            let key = if s.point.is_some() {
                "seabed.point"
            } else {
                "seabed.normal"
            };
            return Err(self.invalid(
                key,
                p.span(),
                "is given with seabed.bathymetry: a seabed is a plane or a grid, not both",
            ));
        }
        let dir = self.path.parent().unwrap_or(std::path::Path::new(""));
        super::bathymetry::read(&dir.join(file.get_ref()), D)
            .map_err(|reason| self.invalid("seabed.bathymetry", file.span(), reason))
    }

    /// `seabed.normal`: finite, not zero, pointing up (positive vertical component).
    fn upward<const D: usize>(&self, n: &Spanned<Vec<f64>>) -> Result<Vector<D>, ScenarioError> {
        let v = self.vector::<D>("seabed.normal", n)?;
        if v[D - 1].partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(self.invalid(
                "seabed.normal",
                n.span(),
                "must point up into the water (a positive vertical component)",
            ));
        }
        Ok(v)
    }
}

#[cfg(test)]
mod tests {
    /// The friction keys: `friction_axial` and `friction_static_scale` build the library's
    /// axial friction (slope `μ_a · friction_damping`) and static scale; without them the
    /// friction is isotropic with scale 1; a scale ≤ 0 is refused naming the key and place.
    #[test]
    fn friction_keys_build_axial_friction_and_the_static_scale() {
        let dir = crate::test_util::temp_dir("friction", "keys");
        let scenario = |seabed: &str| {
            let text = format!(
                "dimension = 3\n[geometry]\nstart = [0.0, 0.0, -100.0]\nend = [100.0, 0.0, -100.0]\n[mesh]\nelements = 10\n\
                 [material]\nlaw = \"linear_elastic\"\nea = 6.0e8\nrho_a = 113.0\ndiameter = 0.1368\n\
                 [body_force]\ngravity = [0.0, 0.0, -9.81]\n[water]\ndepth = 100.0\n[seabed]\nstiffness = 3.0e6\n{seabed}\n\
                 [[boundary]]\nnode = 0\nfixed = true\n[time]\nh = 0.01\nend = 0.1\n"
            );
            let path = dir.join("s.toml");
            std::fs::write(&path, text).unwrap();
            crate::scenario::load(&path, &[]).unwrap()
        };
        let friction = |seabed: &str| {
            let v = scenario(seabed).validate::<3>().unwrap();
            v.problem.water.unwrap().seabed.unwrap().friction.unwrap()
        };
        let f = friction(
            "friction = 0.6\nfriction_damping = 150.0\nfriction_axial = 0.3\nfriction_static_scale = 1.4",
        );
        assert_eq!(
            (f.coefficient, f.slope, f.static_scale),
            (0.6, 0.6 * 150.0, 1.4)
        );
        let a = f.axial.unwrap();
        assert_eq!((a.coefficient, a.slope), (0.3, 0.3 * 150.0));
        let f = friction("friction = 0.6");
        assert_eq!((f.axial, f.static_scale, f.slope), (None, 1.0, 0.6 * 200.0));
        let e = scenario("friction = 0.6\nfriction_static_scale = 0.0")
            .check()
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("s.toml:")
                && e.contains("seabed.friction_static_scale")
                && e.contains("got 0"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
