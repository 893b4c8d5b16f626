//! The materials a particle can have (docs/method.md §3–§4): a registered elastic model,
//! with a registered plastic model (or none) after each F update. Shared by the CPU
//! reference step, the GPU step and the scene setup. The models themselves, and what
//! each plastic model keeps in the particle's hardening state α, are in
//! [`super::model`].

use glam::DMat3;

use super::model::elasticity::Lame;
use super::model::nacc::oracle::{Case3Variant, NaccParams};
use super::model::{ElasticModel, Nacc, Plastic, PlasticLaw, PlasticModel};

/// A material: the elastic model of the stress with its Lamé parameters, and the plastic
/// model after the F update.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    pub elastic: ElasticModel,
    pub lame: Lame,
    pub plastic: Plastic,
}

impl Material {
    /// Fixed corotated from Young's modulus and Poisson ratio.
    pub fn fixed_corotated(e: f64, nu: f64) -> Self {
        Self::elastic(ElasticModel::FixedCorotated, e, nu)
    }

    /// Neo-Hookean (Borden) from Young's modulus and Poisson ratio. Needs det F > 0 (an
    /// inverted F gives NaN, which [`super::cpu::check`] reports).
    pub fn neo_hookean(e: f64, nu: f64) -> Self {
        Self::elastic(ElasticModel::NeoHookean, e, nu)
    }

    /// Any registered elastic model from Young's modulus and Poisson ratio, no plasticity.
    pub fn elastic(model: ElasticModel, e: f64, nu: f64) -> Self {
        Material {
            elastic: model,
            lame: Lame::from_young_poisson(e, nu),
            plastic: Plastic::None,
        }
    }

    /// A registered plastic law on its own elastic model, from Young's modulus and Poisson
    /// ratio.
    pub fn plastic<L: PlasticLaw>(law: L, e: f64, nu: f64) -> Self
    where
        Plastic: From<L>,
    {
        Material {
            elastic: L::ELASTIC,
            lame: Lame::from_young_poisson(e, nu),
            plastic: law.into(),
        }
    }

    /// A plastic model with its parameters, on its law's elastic model (elastic fixed
    /// corotated for no plasticity).
    pub fn with_plastic(plastic: Plastic, e: f64, nu: f64) -> Self {
        Material {
            elastic: plastic
                .model()
                .elastic()
                .unwrap_or(ElasticModel::FixedCorotated),
            lame: Lame::from_young_poisson(e, nu),
            plastic,
        }
    }

    /// NACC (CD-MPM) with its case-3 variant.
    pub fn nacc(params: NaccParams, variant: Case3Variant) -> Self {
        Self::plastic(Nacc { params, variant }, params.e, params.nu)
    }

    /// Lamé parameters of the elastic part.
    pub fn lame(&self) -> Lame {
        self.lame
    }

    /// The elastic model of the stress.
    pub fn elastic_model(&self) -> ElasticModel {
        self.elastic
    }

    /// The plastic model after the F update.
    pub fn plastic_model(&self) -> PlasticModel {
        self.plastic.model()
    }

    /// Whether the material carries a hardening state α.
    pub fn has_hardening_state(&self) -> bool {
        self.plastic_model() != PlasticModel::None
    }

    /// Whether the material breaks into pieces: its α measures damage
    /// ([`super::model::PlasticLaw::FRACTURES`]).
    pub fn fractures(&self) -> bool {
        self.plastic_model().fractures()
    }

    /// Damage d ∈ [0, 1] of a particle with hardening state `alpha` (what
    /// `sim::separation` splits the grid by; 1 counts as damaged in `fragments.csv`).
    pub fn damage(&self, alpha: f64) -> f64 {
        self.plastic.damage(alpha)
    }

    /// P-wave modulus λ + 2μ (CFL sound speed c = sqrt((λ + 2μ)/ρ)).
    pub fn p_wave_modulus(&self) -> f64 {
        self.lame.p_wave_modulus()
    }

    /// α a fresh particle starts with.
    pub fn initial_alpha(&self) -> f64 {
        self.plastic.initial_alpha()
    }

    /// Kirchhoff stress τ(F) at hardening state α (docs/method.md §3): the elastic model's
    /// times the plastic law's hardening factor, or the law's own (a brittle material's
    /// split stress).
    pub fn kirchhoff(&self, f: DMat3, alpha: f64) -> DMat3 {
        self.plastic.kirchhoff(self.elastic, f, alpha, &self.lame)
    }

    /// The plastic step after the F update: the return mapping of the plastic model
    /// (docs/method.md §4), (F, α) unchanged without one. `particle` is the particle's
    /// index in the simulation's particle arrays, which a law whose particles differ keys
    /// them by (a brittle material's strengths).
    pub fn plasticity_at(&self, f_trial: DMat3, alpha: f64, particle: u32) -> (DMat3, f64) {
        self.plastic
            .return_map_at(f_trial, alpha, &self.lame, particle)
    }

    /// The material on a grid of spacing `dx` (a law's size effect).
    pub fn for_grid(&self, dx: f64) -> Material {
        Material {
            plastic: self.plastic.for_grid(dx),
            ..*self
        }
    }
}

/// Δt = CFL · Δx / c with c = sqrt((λ + 2μ)/ρ) (docs/method.md §2; CFL ≈ 0.3–0.6).
pub fn cfl_dt(material: &Material, density: f64, dx: f64, cfl: f64) -> f64 {
    cfl * dx / (material.p_wave_modulus() / density).sqrt()
}
