//! Validation of a cross-section: `[material]` of a single string, or one
//! `[materials.NAME]` of a network (same keys).

use phstring::{Damping, MassMatrix, Material};

use super::spec::MaterialSpec;
use super::{ScenarioError, ScenarioFile};
use crate::text::clip;

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
        })
    }
}
