//! The ground's compliance along the path: the normal and tangential densities of the [`GroundPatchConfig`]
//! strips over the default ones of [`ContactConfig`].

use crate::config::{ContactConfig, GroundConfig, GroundPatchConfig};

/// Normal stiffness and damping densities of the ground at a place.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalDensities {
    /// Stiffness density `k`, N/m³.
    pub stiffness: f64,
    /// Damping density `b`, N·s/m³.
    pub damping: f64,
}

/// Tangential (stick-spring) stiffness and damping densities of the ground at a place.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TangentialDensities {
    /// Stiffness density, N/m³.
    pub stiffness: f64,
    /// Damping density, N·s/m³.
    pub damping: f64,
}

/// Where on the ground which densities hold: the validated patches (non-overlapping strips along world x)
/// and the default elsewhere.
#[derive(Clone, Debug, PartialEq)]
pub struct GroundCompliance {
    default: NormalDensities,
    default_tangential: TangentialDensities,
    patches: Vec<GroundPatchConfig>,
}

impl GroundCompliance {
    /// The compliance of a validated configuration ([`crate::SimConfig::validate`]).
    pub fn from_config(ground: &GroundConfig, contact: &ContactConfig) -> Self {
        Self {
            default: NormalDensities {
                stiffness: contact.normal_stiffness,
                damping: contact.normal_damping,
            },
            default_tangential: TangentialDensities {
                stiffness: contact.tangential_stiffness,
                damping: contact.tangential_damping,
            },
            patches: ground.patches.clone(),
        }
    }

    /// The patch with `x_min ≤ x < x_max`, if any.
    fn patch_at(&self, x: f64) -> Option<&GroundPatchConfig> {
        self.patches.iter().find(|p| p.x_min <= x && x < p.x_max)
    }

    /// The normal densities at world abscissa `x` (m): those of the patch with `x_min ≤ x < x_max`, else the
    /// default.
    pub fn at(&self, x: f64) -> NormalDensities {
        self.densities_at(x).0
    }

    /// The normal and tangential densities at world abscissa `x` (m): those of the patch with
    /// `x_min ≤ x < x_max` (its tangential ones when given, else the default tangential ones), else the
    /// defaults.
    pub fn densities_at(&self, x: f64) -> (NormalDensities, TangentialDensities) {
        let Some(p) = self.patch_at(x) else {
            return (self.default, self.default_tangential);
        };
        let normal = NormalDensities {
            stiffness: p.normal_stiffness,
            damping: p.normal_damping,
        };
        let tangential = TangentialDensities {
            stiffness: p
                .tangential_stiffness
                .unwrap_or(self.default_tangential.stiffness),
            damping: p
                .tangential_damping
                .unwrap_or(self.default_tangential.damping),
        };
        (normal, tangential)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_patch_holds_on_its_half_open_strip_and_the_default_elsewhere() {
        let ground = GroundConfig {
            patches: vec![GroundPatchConfig {
                x_min: 0.5,
                x_max: 1.0,
                normal_stiffness: 8e5,
                normal_damping: 1e3,
                tangential_stiffness: None,
                tangential_damping: Some(2e3),
            }],
            ..GroundConfig::default()
        };
        let contact = ContactConfig::default();
        let c = GroundCompliance::from_config(&ground, &contact);
        let soft = NormalDensities {
            stiffness: 8e5,
            damping: 1e3,
        };
        let default = NormalDensities {
            stiffness: contact.normal_stiffness,
            damping: contact.normal_damping,
        };
        assert_eq!(c.at(0.5), soft);
        assert_eq!(c.at(0.99), soft);
        assert_eq!(c.at(1.0), default);
        assert_eq!(c.at(0.4999), default);
        let default_tangential = TangentialDensities {
            stiffness: contact.tangential_stiffness,
            damping: contact.tangential_damping,
        };
        // The patch's tangential damping, the floor's tangential stiffness (not given on the patch).
        let patch_tangential = TangentialDensities {
            stiffness: contact.tangential_stiffness,
            damping: 2e3,
        };
        assert_eq!(c.densities_at(0.7), (soft, patch_tangential));
        assert_eq!(c.densities_at(1.0), (default, default_tangential));
    }
}
