//! Drucker–Prager plasticity for sand (Klár et al. 2016, docs/method.md §4.10): the yield
//! cone ‖τ̂‖ + α_dp tr(τ − p_apex I) ≤ 0 on St. Venant–Kirchhoff Hencky elasticity, with
//! the return mapping in the Hencky strain ε = ln σ. WGSL `drucker_prager_return_map` in
//! `shaders/sim/models/drucker_prager.wgsl`.

use glam::{DMat3, DVec3};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::{ElasticModel, ParamError, PlasticLaw, PlasticWgsl, PLASTIC_PARAMS};
use crate::sim::elasticity::{hencky_strain, Lame, HENCKY_SIGMA_MIN};
use crate::sim::svd::svd3;

/// A Drucker–Prager material: the cone's slope and its apex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DruckerPrager {
    /// Friction angle φ in radians.
    pub friction_angle: f64,
    /// Cohesion c in Pa (0: dry sand, no tension at all).
    pub cohesion: f64,
}

/// The scene file's Drucker–Prager parameters.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DruckerPragerSpec {
    /// Friction angle φ in degrees, in (0, 90): dry sand 30–40. A pile's angle of repose
    /// lies near it.
    pub friction_angle: f64,
    /// Cohesion c in Pa (≥ 0, default 0): the tension the material holds is c cot φ in
    /// mean stress. Damp sand: a few hundred Pa.
    #[serde(default)]
    pub cohesion: f64,
}

impl DruckerPrager {
    /// The cone's slope α_dp = √(2/3) · 2 sin φ / (3 − sin φ) (the Mohr–Coulomb cone's
    /// compressive meridian, as Klár et al.).
    pub fn alpha_dp(&self) -> f64 {
        let s = self.friction_angle.sin();
        (2.0f64 / 3.0).sqrt() * 2.0 * s / (3.0 - s)
    }

    /// tr ε at the cone's apex: the mean stress c cot φ over the bulk modulus κ.
    pub fn apex_strain(&self, lame: &Lame) -> f64 {
        self.cohesion / self.friction_angle.tan() / lame.kappa()
    }

    /// The projected Hencky strains of the trial strains `eps`, and whether they moved.
    pub fn project(&self, eps: DVec3, lame: &Lame) -> (DVec3, bool) {
        let apex = self.apex_strain(lame);
        let tr = eps.x + eps.y + eps.z;
        let shifted = tr - apex;
        if shifted >= 0.0 {
            // Pulled apart past the apex: no stress left but the apex's.
            return (DVec3::splat(apex / 3.0), true);
        }
        let dev = eps - DVec3::splat(tr / 3.0);
        let dev_norm = dev.length();
        let kappa3 = 3.0 * lame.lambda + 2.0 * lame.mu;
        let dgamma = dev_norm + kappa3 / (2.0 * lame.mu) * shifted * self.alpha_dp();
        if dgamma <= 0.0 {
            return (eps, false);
        }
        (eps - dev * (dgamma / dev_norm), true)
    }
}

impl PlasticLaw for DruckerPrager {
    const NAME: &'static str = "drucker_prager";
    const ELASTIC: ElasticModel = ElasticModel::StvkHencky;
    const FRACTURES: bool = false;
    const ALPHA: &'static str = "log of the plastic volume ratio Jᴾ (dilation > 0)";
    // params: α_dp, the apex's tr ε.
    const WGSL: PlasticWgsl = PlasticWgsl {
        return_map:
            "return drucker_prager_return_map(f, alpha, m.mu, m.lambda, m.params[0], m.params[1]);",
        damage: "0.0",
        stress_scale: "1.0",
        module: include_str!("../../../shaders/sim/models/drucker_prager.wgsl"),
    };
    type Spec = DruckerPragerSpec;

    fn from_spec(spec: DruckerPragerSpec, _e: f64, _nu: f64) -> Result<Self, ParamError> {
        let phi = spec.friction_angle;
        ParamError::check(
            phi.is_finite() && phi > 0.0 && phi < 90.0,
            "friction_angle",
            phi,
            "an angle in degrees in (0, 90)",
        )?;
        let c = spec.cohesion;
        ParamError::check(
            c.is_finite() && c >= 0.0,
            "cohesion",
            c,
            "a cohesion in Pa ≥ 0",
        )?;
        Ok(DruckerPrager {
            friction_angle: phi.to_radians(),
            cohesion: c,
        })
    }

    /// F = U exp(ε_new) Vᵀ; α gains the plastic volume change tr ε_trial − tr ε_new.
    fn return_map(&self, f_trial: DMat3, alpha: f64, lame: &Lame) -> (DMat3, f64) {
        let s = svd3(f_trial);
        let eps = hencky_strain(s.sigma);
        let (eps_new, moved) = self.project(eps, lame);
        if !moved && s.sigma.min_element() >= HENCKY_SIGMA_MIN {
            return (f_trial, alpha);
        }
        let sigma = DVec3::new(eps_new.x.exp(), eps_new.y.exp(), eps_new.z.exp());
        let f = s.u * DMat3::from_diagonal(sigma) * s.v.transpose();
        let plastic = (eps.x + eps.y + eps.z) - (eps_new.x + eps_new.y + eps_new.z);
        (f, alpha + plastic)
    }

    fn gpu_params(&self, lame: &Lame) -> [f32; PLASTIC_PARAMS] {
        let apex = self.apex_strain(lame);
        [
            self.alpha_dp() as f32,
            apex as f32,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
        ]
    }
}
