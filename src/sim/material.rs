//! The materials a particle can have (docs/method.md §3–§4): an elastic model, or NACC
//! plasticity on top of Neo-Hookean. Shared by the CPU reference step, the GPU step and
//! the scene setup.

use glam::DMat3;

use super::elasticity::Lame;
use super::models::{ElasticModel, PlasticModel};
use super::nacc::{return_map, Case3Variant, NaccParams};

/// A material: an elastic model, or NACC plasticity on top of Neo-Hookean (docs/method.md §3–§4).
/// The models themselves are registered in [`super::models`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// An elastic model without plasticity. Neo-Hookean needs det F > 0 (an inverted F
    /// gives NaN, which [`super::cpu::check`] reports).
    Elastic { model: ElasticModel, lame: Lame },
    /// Neo-Hookean stress with the NACC return mapping and hardening after each F update.
    Nacc {
        params: NaccParams,
        variant: Case3Variant,
    },
}

impl Material {
    /// Fixed corotated from Young's modulus and Poisson ratio.
    pub fn fixed_corotated(e: f64, nu: f64) -> Self {
        Self::elastic(ElasticModel::FixedCorotated, e, nu)
    }

    /// Neo-Hookean (Borden) from Young's modulus and Poisson ratio.
    pub fn neo_hookean(e: f64, nu: f64) -> Self {
        Self::elastic(ElasticModel::NeoHookean, e, nu)
    }

    /// Any registered elastic model from Young's modulus and Poisson ratio.
    pub fn elastic(model: ElasticModel, e: f64, nu: f64) -> Self {
        Material::Elastic {
            model,
            lame: Lame::from_young_poisson(e, nu),
        }
    }

    /// Lamé parameters of the elastic part.
    pub fn lame(&self) -> Lame {
        match self {
            Material::Elastic { lame, .. } => *lame,
            Material::Nacc { params, .. } => params.lame(),
        }
    }

    /// The elastic model of the stress.
    pub fn elastic_model(&self) -> ElasticModel {
        match self {
            Material::Elastic { model, .. } => *model,
            Material::Nacc { .. } => ElasticModel::NeoHookean,
        }
    }

    /// The plastic model after the F update.
    pub fn plastic_model(&self) -> PlasticModel {
        match self {
            Material::Elastic { .. } => PlasticModel::None,
            Material::Nacc { .. } => PlasticModel::Nacc,
        }
    }

    /// Whether the material carries a hardening state α (whose α ≥ 0 counts as damaged).
    pub fn has_hardening_state(&self) -> bool {
        self.plastic_model() != PlasticModel::None
    }

    /// Damage d ∈ [0, 1] of a particle with hardening state `alpha` (what `sim::separation`
    /// splits the grid by): for NACC the share of the initial cohesion −α₀ that α has lost,
    /// clamp((α − α₀)/(−α₀), 0, 1), so 0 when fresh or compacted and 1 at α ≥ 0, where the
    /// material holds no tension (1 everywhere for a material that starts without
    /// cohesion, α₀ ≥ 0); 0 for the elastic models.
    pub fn damage(&self, alpha: f64) -> f64 {
        match self {
            Material::Nacc { params, .. } if params.alpha0 < 0.0 => {
                ((alpha - params.alpha0) / -params.alpha0).clamp(0.0, 1.0)
            }
            Material::Nacc { .. } => 1.0,
            Material::Elastic { .. } => 0.0,
        }
    }

    /// P-wave modulus λ + 2μ (CFL sound speed c = sqrt((λ + 2μ)/ρ)).
    pub fn p_wave_modulus(&self) -> f64 {
        self.lame().p_wave_modulus()
    }

    /// α a fresh particle starts with: α₀ for NACC, 0 otherwise (unused there).
    pub fn initial_alpha(&self) -> f64 {
        match self {
            Material::Nacc { params, .. } => params.alpha0,
            _ => 0.0,
        }
    }

    /// Kirchhoff stress τ(F) (docs/method.md §3).
    pub fn kirchhoff(&self, f: DMat3) -> DMat3 {
        self.elastic_model().kirchhoff(f, &self.lame())
    }

    /// The plastic step after the F update: (F, α) unchanged for the elastic models, the
    /// NACC return mapping (docs/method.md §4) otherwise.
    pub fn plasticity(&self, f_trial: DMat3, alpha: f64) -> (DMat3, f64) {
        match self {
            Material::Nacc { params, variant } => {
                let r = return_map(f_trial, alpha, params, *variant);
                (r.f, r.alpha)
            }
            _ => (f_trial, alpha),
        }
    }
}

/// Δt = CFL · Δx / c with c = sqrt((λ + 2μ)/ρ) (docs/method.md §2; CFL ≈ 0.3–0.6).
pub fn cfl_dt(material: &Material, density: f64, dx: f64, cfl: f64) -> f64 {
    cfl * dx / (material.p_wave_modulus() / density).sqrt()
}
