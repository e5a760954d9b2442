//! The water terms of a rigid body (`volume`, `centre_of_buoyancy`, `cda`, `linear_drag`,
//! `ca`, `added_inertia`, `added_mass`, `waterplane_area`, `waterline`, `waterplane_moments`
//! of `[bodies.NAME]`,
//! docs/scenario.md
//! "Rigid bodies"): the library's [`BodyHydro`] (docs/method.md §22), with the names and
//! meanings of MoorDyn's body columns where it has them.

use phstring::body::{BodyHydro, Mat6, Vec3};
use toml::Spanned;

use super::spec::BodySpec;
use super::{ScenarioError, ScenarioFile};
use crate::text::num;

/// The body's water terms as `summary.json` (`components.bodies`) and `phstring check` give
/// them (units of [`BodyHydro`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct BodyWaterComponent {
    /// Displaced volume [m³].
    pub volume: f64,
    /// Centre of buoyancy in body axes relative to the centre of mass [m].
    pub centre_of_buoyancy: Vec<f64>,
    /// Drag coefficient times area `CdA` [m²].
    pub cda: f64,
    /// Linear drag coefficient [N·s/m].
    pub linear_drag: f64,
    /// Added-mass coefficient `Ca` on `ρ_w V`.
    pub ca: f64,
    /// Added moments of inertia about the body axes [kg·m²] (`x`, `y`, `z`).
    pub added_inertia: Vec<f64>,
    /// The full added-mass matrix in body axes (rows of 6 in 3D, of 3 in 2D: `x`, `y`, `θ`;
    /// kg, kg·m, kg·m²), when given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub added_mass: Option<Vec<Vec<f64>>>,
    /// Waterplane area [m²] (0: submerged).
    pub waterplane_area: f64,
    /// The waterline point in body axes relative to the centre of mass [m].
    pub waterline: Vec<f64>,
    /// The waterplane's second moments of area [m⁴]: about `x` and `y` in 3D, one in 2D.
    pub waterplane_moments: Vec<f64>,
}

impl BodyWaterComponent {
    /// The report of `h` in dimension `d` (points with `d` components).
    pub(super) fn of(h: &BodyHydro, d: usize) -> Self {
        Self {
            volume: h.volume,
            centre_of_buoyancy: h.centre_of_buoyancy.as_slice()[..d].to_vec(),
            cda: h.cda,
            linear_drag: h.linear_drag,
            ca: h.ca,
            added_inertia: h.added_inertia.as_slice().to_vec(),
            added_mass: h.added_mass.map(|a| {
                let idx: Vec<usize> = if d == 2 {
                    vec![0, 1, 5]
                } else {
                    (0..6).collect()
                };
                idx.iter()
                    .map(|&r| idx.iter().map(|&c| a[(r, c)]).collect())
                    .collect()
            }),
            waterplane_area: h.waterplane_area,
            waterline: h.waterline.as_slice()[..d].to_vec(),
            waterplane_moments: h.waterplane_moments[..d - 1].to_vec(),
        }
    }
}

/// `v` as a 3-vector (`z = 0` in 2D).
fn embed(v: &[f64]) -> Vec3 {
    Vec3::from_fn(|k, _| v.get(k).copied().unwrap_or(0.0))
}

impl ScenarioFile {
    /// The water terms of the body at `key` (`spec`): `None` when it has none. They need
    /// `[water]`; a centre of buoyancy needs a volume, `ca` a volume, a waterline a waterplane
    /// area.
    pub(super) fn body_hydro<const D: usize>(
        &self,
        key: &str,
        spec: &BodySpec,
    ) -> Result<Option<BodyHydro>, ScenarioError> {
        let k = |f: &str| format!("{key}.{f}");
        let scalars = [
            ("volume", &spec.volume),
            ("cda", &spec.cda),
            ("linear_drag", &spec.linear_drag),
            ("ca", &spec.ca),
            ("waterplane_area", &spec.waterplane_area),
        ];
        let vectors = [
            ("centre_of_buoyancy", &spec.centre_of_buoyancy),
            ("added_inertia", &spec.added_inertia),
            ("waterline", &spec.waterline),
        ];
        let first = scalars
            .iter()
            .filter_map(|(f, v)| v.as_ref().map(|v| (*f, v.span())))
            .chain(
                vectors
                    .iter()
                    .filter_map(|(f, v)| v.as_ref().map(|v| (*f, v.span()))),
            )
            .chain(spec.added_mass.as_ref().map(|v| ("added_mass", v.span())))
            .chain(
                spec.waterplane_moments
                    .as_ref()
                    .map(|v| ("waterplane_moments", v.span())),
            )
            .min_by_key(|(_, span)| span.start);
        let Some((f, span)) = first else {
            return Ok(None);
        };
        if self.scenario.water.is_none() {
            return Err(self.invalid(
                &k(f),
                span,
                "is a water term of a rigid body, but the scenario has no [water] table: add [water] (density, current) or remove the body's water keys",
            ));
        }
        let [volume, cda, linear_drag, ca, waterplane_area] =
            scalars.map(|(f, v)| self.non_negative(&k(f), v.as_ref()));
        let h = BodyHydro {
            volume: volume?,
            centre_of_buoyancy: self
                .body_axes_point::<D>(&k("centre_of_buoyancy"), spec.centre_of_buoyancy.as_ref())?,
            cda: cda?,
            linear_drag: linear_drag?,
            ca: ca?,
            added_inertia: self
                .added_inertia::<D>(&k("added_inertia"), spec.added_inertia.as_ref())?,
            added_mass: self.added_mass::<D>(&k("added_mass"), spec)?,
            waterplane_area: waterplane_area?,
            waterline: self.body_axes_point::<D>(&k("waterline"), spec.waterline.as_ref())?,
            waterplane_moments: self.waterplane_moments::<D>(
                &k("waterplane_moments"),
                spec.waterplane_moments.as_ref(),
            )?,
        };
        let needs = [
            (
                "centre_of_buoyancy",
                &spec.centre_of_buoyancy,
                h.volume,
                "volume",
            ),
            (
                "waterline",
                &spec.waterline,
                h.waterplane_area,
                "waterplane_area",
            ),
            (
                "waterplane_moments",
                &spec.waterplane_moments,
                h.waterplane_area,
                "waterplane_area",
            ),
        ];
        for (f, v, base, what) in needs {
            if let Some(v) = v
                && base == 0.0
            {
                return Err(self.invalid(
                    &k(f),
                    v.span(),
                    format!("needs a positive `{what}` of the same body (it is 0)"),
                ));
            }
        }
        if let Some(c) = &spec.ca
            && h.volume == 0.0
            && h.ca > 0.0
        {
            return Err(self.invalid(
                &k("ca"),
                c.span(),
                format!(
                    "= {} is a coefficient on the displaced mass ρ_w V, but the body's `volume` is 0: give the volume",
                    num(h.ca)
                ),
            ));
        }
        Ok(Some(h))
    }

    /// `waterplane_moments` at `key`: `D − 1` numbers, each ≥ 0 and finite (`[I_x, I_y]` in
    /// 3D, `[I]` in 2D, stored as the first); zero when absent.
    fn waterplane_moments<const D: usize>(
        &self,
        key: &str,
        v: Option<&Spanned<Vec<f64>>>,
    ) -> Result<[f64; 2], ScenarioError> {
        let Some(v) = v else {
            return Ok([0.0, 0.0]);
        };
        let m = v.get_ref();
        if m.len() != D - 1 || m.iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
            let what = if D == 2 {
                "[I], the second moment of the waterline about the out-of-plane axis"
            } else {
                "[I_x, I_y], the waterplane's second moments about the body's x and y axes"
            };
            return Err(self.invalid(
                key,
                v.span(),
                format!("must be {what} [m⁴], each ≥ 0 and finite, got {:?}", m),
            ));
        }
        Ok([m[0], m.get(1).copied().unwrap_or(0.0)])
    }

    /// A point in body axes at `key` (`d` finite components), as a 3-vector; zero when absent.
    fn body_axes_point<const D: usize>(
        &self,
        key: &str,
        v: Option<&Spanned<Vec<f64>>>,
    ) -> Result<Vec3, ScenarioError> {
        match v {
            None => Ok(Vec3::zeros()),
            Some(v) => Ok(embed(self.vector::<D>(key, v)?.as_slice())),
        }
    }

    /// `added_mass` at `key` of body `spec`: a 6×6 matrix in 3D, the 3×3 `(x, y, θ)` in 2D
    /// placed at rows and columns 0, 1, 5 of the library's 6×6, checked by
    /// [`phstring::check_added_mass`] (finite, symmetric, positive semi-definite), and not
    /// beside `ca` or `added_inertia`; `None` when absent.
    fn added_mass<const D: usize>(
        &self,
        key: &str,
        spec: &BodySpec,
    ) -> Result<Option<Mat6>, ScenarioError> {
        let Some(v) = &spec.added_mass else {
            return Ok(None);
        };
        let rows = v.get_ref();
        let n = if D == 2 { 3 } else { 6 };
        if rows.len() != n || rows.iter().any(|r| r.len() != n) {
            let shape: Vec<String> = rows.iter().map(|r| r.len().to_string()).collect();
            return Err(self.invalid(
                key,
                v.span(),
                format!(
                    "must be {n} rows of {n} in dimension {D} ({}), got {} rows of [{}]",
                    if D == 2 {
                        "x, y, θ; kg, kg·m, kg·m²"
                    } else {
                        "translation x, y, z, then rotation about x, y, z; kg, kg·m, kg·m²"
                    },
                    rows.len(),
                    shape.join(", ")
                ),
            ));
        }
        let a = nalgebra::DMatrix::from_fn(n, n, |r, c| rows[r][c]);
        phstring::check_added_mass(&a).map_err(|e| self.invalid(key, v.span(), e))?;
        let beside = [
            ("ca", spec.ca.is_some()),
            ("added_inertia", spec.added_inertia.is_some()),
        ];
        if let Some((f, _)) = beside.into_iter().find(|(_, given)| *given) {
            return Err(self.invalid(
                key,
                v.span(),
                format!(
                    "is given beside `{f}` of the same body: give the whole added mass in the \
                     matrix (the translational `Ca ρ_w V` on its first diagonal entries, the \
                     added inertia on the rotational ones)"
                ),
            ));
        }
        let idx: Vec<usize> = if D == 2 {
            vec![0, 1, 5]
        } else {
            (0..6).collect()
        };
        let mut m = Mat6::zeros();
        for (r, &ir) in idx.iter().enumerate() {
            for (c, &ic) in idx.iter().enumerate() {
                m[(ir, ic)] = a[(r, c)];
            }
        }
        Ok(Some(m))
    }

    /// `added_inertia` at `key`: 3 moments about the body axes in 3D, the one about `z` in
    /// 2D [kg·m²], each ≥ 0 and finite; zero when absent.
    fn added_inertia<const D: usize>(
        &self,
        key: &str,
        v: Option<&Spanned<Vec<f64>>>,
    ) -> Result<Vec3, ScenarioError> {
        let Some(v) = v else { return Ok(Vec3::zeros()) };
        let x = v.get_ref();
        let n = if D == 2 { 1 } else { 3 };
        if x.len() != n {
            return Err(self.invalid(
                key,
                v.span(),
                format!(
                    "must have {n} moment{} in dimension {D} (kg·m², about the body axes{}), got {}",
                    if n == 1 { "" } else { "s" },
                    if n == 1 { "; in 2D about z" } else { "" },
                    x.len()
                ),
            ));
        }
        if let Some(c) = x.iter().find(|c| !(**c >= 0.0 && c.is_finite())) {
            return Err(self.invalid(
                key,
                v.span(),
                format!(
                    "has the moment {} kg·m²: each must be at least 0 and finite",
                    num(*c)
                ),
            ));
        }
        Ok(if n == 1 {
            Vec3::new(0.0, 0.0, x[0])
        } else {
            Vec3::new(x[0], x[1], x[2])
        })
    }
}
