//! Validation of a cross-section: `[material]` of a single string, or one
//! `[materials.NAME]` of a network (same keys).

use std::ops::Range;

use phstring::{Damping, MassMatrix, Material};

use super::settings::BodyForce;
use super::spec::MaterialSpec;
use super::{ScenarioError, ScenarioFile};
use crate::text::{clip, num};

/// Largest weight of one string element (`|b| ℓ`) or point mass [N], and largest drag
/// coefficient of one element (`c ℓ`) [N·s/m]: the Newton residual's force scale sums
/// squared nodal forces, which overflow near 1e154 (to a message about infinite or NaN
/// forces, without a key, at setup or at the first step).
pub const MAX_NODAL_FORCE: f64 = 1e150;

/// The longest element of a string, for [`ScenarioFile::element_scales`].
pub(super) struct Longest {
    /// The string in messages: `string "s0" (string.0)` or `the string`.
    pub owner: String,
    /// Its reference length ℓ [m].
    pub l: f64,
    /// What sets ℓ, in words (e.g. `span 1 of its path / elements / prestretch`).
    pub from: String,
    /// The key blamed when ℓ is the large factor: key, span and `"= value "` (or empty).
    pub key: (String, Range<usize>, String),
}

/// A validated cross-section: law, `ρA` and mass matrix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct CrossSection {
    /// Stored-energy law with its `EA` [N].
    pub material: Material,
    /// Mass per unit reference length [kg/m].
    pub rho_a: f64,
    /// Mass matrix variant.
    pub mass: MassMatrix,
    /// Kelvin–Voigt viscosity and drag.
    pub damping: Damping,
    /// Hydrodynamic diameter and coefficients (with `diameter`), for `[water]`.
    pub hydro: Option<phstring::LineHydro>,
}

/// `consistent` or `lumped`.
pub(super) fn mass_name(mass: MassMatrix) -> &'static str {
    match mass {
        MassMatrix::Consistent => "consistent",
        MassMatrix::Lumped => "lumped",
    }
}

impl ScenarioFile {
    /// The cross-section `spec`, whose keys are named `{prefix}.ea`, … (`material` or
    /// `materials.NAME`).
    pub(super) fn cross_section(
        &self,
        prefix: &str,
        spec: &MaterialSpec,
    ) -> Result<CrossSection, ScenarioError> {
        let key = |k: &str| format!("{prefix}.{k}");
        let ea = self.positive(&key("ea"), &spec.ea)?;
        let rho_a = self.positive(&key("rho_a"), &spec.rho_a)?;
        let law = spec.law.get_ref();
        let material = Material::from_name(law, ea).ok_or_else(|| {
            self.invalid(
                &key("law"),
                spec.law.span(),
                format!(
                    "must be hyperelastic, linear_elastic, st_venant_kirchhoff, tension_only_linear or tension_only_hyperelastic, got \"{}\"",
                    clip(law)
                ),
            )
        })?;
        let mass = match spec.mass.get_ref().as_str() {
            "consistent" => MassMatrix::Consistent,
            "lumped" => MassMatrix::Lumped,
            other => {
                return Err(self.invalid(
                    &key("mass"),
                    spec.mass.span(),
                    format!("must be consistent or lumped, got \"{}\"", clip(other)),
                ));
            }
        };
        let damping = Damping {
            kelvin_voigt: self.non_negative(&key("kelvin_voigt"), spec.kelvin_voigt.as_ref())?,
            drag: self.non_negative(&key("drag"), spec.drag.as_ref())?,
            dashpot: 0.0,
        };
        Ok(CrossSection {
            material,
            rho_a,
            mass,
            damping,
            hydro: self.line_hydro(prefix, spec)?,
        })
    }
}

impl ScenarioFile {
    /// Refuses a string whose longest element has a weight `|b| ℓ` or a drag coefficient
    /// `c ℓ` above [`MAX_NODAL_FORCE`], naming the key that makes it so large: the
    /// material's (`mat_key`, its table `mat_spec`) `rho_a` or `drag`,
    /// `body_force.per_length`, or what sets ℓ.
    pub(super) fn element_scales<const D: usize>(
        &self,
        mat_key: &str,
        mat_spec: Option<&MaterialSpec>,
        cs: &CrossSection,
        body: &BodyForce<D>,
        longest: Longest,
    ) -> Result<(), ScenarioError> {
        let (owner, l) = (&longest.owner, longest.l);
        let why = "nodal forces this large overflow the force residual, which squares them";
        let (gravity, per_length) = (
            cs.rho_a * super::rounding::length(&body.g()),
            body.per_length.map_or(0.0, |p| super::rounding::length(&p)),
        );
        let weight = gravity + per_length;
        // NaN is refused too.
        if (weight * l).is_nan() || weight * l > MAX_NODAL_FORCE {
            let (key, at, value) = if l >= weight {
                longest.key.clone()
            } else if per_length > gravity {
                let given = self.scenario.body_force.per_length.as_ref();
                let span = given.map_or(0..0, |p| p.span());
                ("body_force.per_length".to_string(), span, String::new())
            } else {
                let span = mat_spec.map_or(0..0, |m| m.rho_a.span());
                let value = format!("= {} ", num(cs.rho_a));
                (format!("{mat_key}.rho_a"), span, value)
            };
            return Err(self.invalid(
                &key,
                at,
                format!(
                    "{value}gives the elements of {owner} the weight {} N each: the body force {} N/m ({mat_key}.rho_a = {} kg/m times body_force.gravity, plus body_force.per_length) times the reference element length {} m ({}), above {MAX_NODAL_FORCE:.0e} N: {why}",
                    num(weight * l),
                    num(weight),
                    num(cs.rho_a),
                    num(l),
                    longest.from
                ),
            ));
        }
        let drag = cs.damping.drag;
        if (drag * l).is_nan() || drag * l > MAX_NODAL_FORCE {
            let span = mat_spec
                .and_then(|m| m.drag.as_ref())
                .map_or(0..0, |d| d.span());
            return Err(self.invalid(
                &format!("{mat_key}.drag"),
                span,
                format!(
                    "= {} N·s/m² gives the elements of {owner}, of reference length up to {} m, the drag coefficient {} N·s/m each, above {MAX_NODAL_FORCE:.0e} N·s/m: {why}",
                    num(drag),
                    num(l),
                    num(drag * l)
                ),
            ));
        }
        Ok(())
    }
}
