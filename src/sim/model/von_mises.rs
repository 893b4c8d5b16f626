//! Von Mises (J2) plasticity for metal and plasticine (docs/method.md §4.11): the yield
//! surface q = √(3/2) ‖τ̂‖ ≤ σ_y + H ε̄ᴾ with linear isotropic hardening, on St.
//! Venant–Kirchhoff Hencky elasticity, by the radial return in the Hencky strain (exact
//! for this elasticity: the deviatoric stress is 2μ ε̂). WGSL `von_mises_return_map` in
//! `shaders/sim/model/von_mises.wgsl`.

use glam::{DMat3, DVec3};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::{ElasticModel, Example, ParamError, PlasticLaw, PlasticWgsl, PLASTIC_PARAMS};
use crate::sim::model::elasticity::{hencky_strain, Lame, HENCKY_SIGMA_MIN};
use crate::sim::svd::svd3;

/// A von Mises material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VonMises {
    /// Initial yield stress σ_y in Pa (uniaxial).
    pub yield_stress: f64,
    /// Linear hardening modulus H in Pa: σ_y grows by H per unit equivalent plastic strain.
    pub hardening: f64,
}

/// The scene file's von Mises parameters.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct VonMisesSpec {
    /// Yield stress σ_y in Pa (> 0): the uniaxial stress at which the material starts to
    /// flow. Plasticine: 1e3–1e4; soft metal (lead, aluminium): 1e7–1e8.
    pub yield_stress: f64,
    /// Linear hardening modulus H in Pa (≥ 0, default 0: perfectly plastic): the yield
    /// stress after an equivalent plastic strain ε̄ᴾ is σ_y + H ε̄ᴾ.
    #[serde(default)]
    pub hardening: f64,
}

impl VonMises {
    /// The yield stress after equivalent plastic strain `alpha`.
    pub fn yield_stress_at(&self, alpha: f64) -> f64 {
        self.yield_stress + self.hardening * alpha
    }

    /// The radial return of trial Hencky strains `eps`: the projected strains and the
    /// equivalent plastic strain increment Δε̄ᴾ (0 when elastic).
    pub fn project(&self, eps: DVec3, alpha: f64, lame: &Lame) -> (DVec3, f64) {
        let mean = (eps.x + eps.y + eps.z) / 3.0;
        let dev = eps - DVec3::splat(mean);
        let q_trial = 2.0 * lame.mu * (1.5f64).sqrt() * dev.length();
        let excess = q_trial - self.yield_stress_at(alpha);
        if excess <= 0.0 {
            return (eps, 0.0);
        }
        let d_eq = excess / (3.0 * lame.mu + self.hardening);
        let shrink = 1.0 - 3.0 * lame.mu * d_eq / q_trial;
        (DVec3::splat(mean) + dev * shrink, d_eq)
    }
}

impl PlasticLaw for VonMises {
    const NAME: &'static str = "von_mises";
    const ELASTIC: ElasticModel = ElasticModel::StvkHencky;
    const FRACTURES: bool = false;
    const ALPHA: &'static str = "the equivalent plastic strain ε̄ᴾ";
    const ALPHA_IS_LOG_JP: bool = false;
    // params: σ_y, H.
    const WGSL: PlasticWgsl = PlasticWgsl {
        return_map: "return von_mises_return_map(f, alpha, m.mu, m.params[0], m.params[1]);",
        damage: "0.0",
        stress_scale: "1.0",
        kirchhoff: None,
        module: include_str!("../../../shaders/sim/model/von_mises.wgsl"),
    };
    const EXAMPLE: Example = Example {
        params: r#"{"yield_stress": 40.0, "hardening": 200.0}"#,
        alpha: 0.02,
    };
    type Spec = VonMisesSpec;

    fn from_spec(spec: VonMisesSpec, _e: f64, _nu: f64) -> Result<Self, ParamError> {
        let (y, h) = (spec.yield_stress, spec.hardening);
        ParamError::check(
            y.is_finite() && y > 0.0,
            "yield_stress",
            y,
            "a stress in Pa > 0",
        )?;
        ParamError::check(
            h.is_finite() && h >= 0.0,
            "hardening",
            h,
            "a modulus in Pa ≥ 0",
        )?;
        Ok(VonMises {
            yield_stress: y,
            hardening: h,
        })
    }

    /// F = U exp(ε_new) Vᵀ (volume kept: the return is deviatoric); α gains Δε̄ᴾ.
    fn return_map(&self, f_trial: DMat3, alpha: f64, lame: &Lame) -> (DMat3, f64) {
        let s = svd3(f_trial);
        let eps = hencky_strain(s.sigma);
        let (eps_new, d_eq) = self.project(eps, alpha, lame);
        if d_eq == 0.0 && s.sigma.min_element() >= HENCKY_SIGMA_MIN {
            return (f_trial, alpha);
        }
        let sigma = DVec3::new(eps_new.x.exp(), eps_new.y.exp(), eps_new.z.exp());
        (
            s.u * DMat3::from_diagonal(sigma) * s.v.transpose(),
            alpha + d_eq,
        )
    }

    fn gpu_params(&self, _lame: &Lame) -> [f32; PLASTIC_PARAMS] {
        [
            self.yield_stress as f32,
            self.hardening as f32,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn lame() -> Lame {
        Lame::from_young_poisson(1e6, 0.3)
    }

    fn q_of(eps: DVec3, l: &Lame) -> f64 {
        let dev = eps - DVec3::splat((eps.x + eps.y + eps.z) / 3.0);
        2.0 * l.mu * 1.5f64.sqrt() * dev.length()
    }

    /// Below the yield surface nothing changes; above it the return lands on the hardened
    /// surface q = σ_y + H (α + Δε̄ᴾ), keeps the volume (tr ε) and the direction of ε̂,
    /// and Δε̄ᴾ = (q_trial − σ_y(α))/(3μ + H) (the consistency condition of linear
    /// hardening).
    #[test]
    fn radial_return_is_consistent() {
        let l = lame();
        let mut r = SplitMix64::new(11);
        let vm = VonMises {
            yield_stress: 5e3,
            hardening: 2e5,
        };
        let (mut elastic, mut plastic) = (0, 0);
        for _ in 0..4000 {
            let eps = (DVec3::new(r.uniform(), r.uniform(), r.uniform()) - 0.5) * 0.02;
            let alpha = r.uniform() * 0.01;
            let (eps_new, d_eq) = vm.project(eps, alpha, &l);
            let q_trial = q_of(eps, &l);
            if q_trial <= vm.yield_stress_at(alpha) {
                elastic += 1;
                assert_eq!((eps_new, d_eq), (eps, 0.0));
                continue;
            }
            plastic += 1;
            let want = (q_trial - vm.yield_stress_at(alpha)) / (3.0 * l.mu + vm.hardening);
            assert!((d_eq - want).abs() < 1e-12);
            let q = q_of(eps_new, &l);
            assert!(
                (q - vm.yield_stress_at(alpha + d_eq)).abs() < 1e-6 * q,
                "{q}"
            );
            let tr = |e: DVec3| e.x + e.y + e.z;
            assert!((tr(eps_new) - tr(eps)).abs() < 1e-14);
            let dir = |e: DVec3| {
                let d = e - DVec3::splat(tr(e) / 3.0);
                d / d.length()
            };
            assert!((dir(eps_new) - dir(eps)).length() < 1e-9);
        }
        assert!(elastic > 500 && plastic > 500, "{elastic} {plastic}");
    }

    /// Uniaxial tension in the oracle: a bar stretched by λ₁ with the lateral strains that
    /// keep the lateral stress 0 (solved by bisection) yields when the axial stress reaches
    /// σ_y, and beyond it the axial stress follows σ_y + H ε̄ᴾ with ε̄ᴾ the axial plastic
    /// strain (ε̄ᴾ = |Δε_axial| in uniaxial plastic flow).
    #[test]
    fn uniaxial_tension_yields_at_the_yield_stress() {
        let l = lame();
        let vm = VonMises {
            yield_stress: 5e3,
            hardening: 0.0,
        };
        // Axial stress at axial strain e with lateral strain t (elastic trial).
        let stress = |e: f64, t: f64| {
            let eps = DVec3::new(e, t, t);
            let (eps_new, _) = vm.project(eps, 0.0, &l);
            let tr = eps_new.x + eps_new.y + eps_new.z;
            let tau = eps_new * (2.0 * l.mu) + DVec3::splat(l.lambda * tr);
            (tau.x, tau.y)
        };
        let lateral_free = |e: f64| {
            let (mut lo, mut hi) = (-e, e);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if stress(e, mid).1 > 0.0 {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            stress(e, 0.5 * (lo + hi)).0
        };
        let e_young = 1e6;
        // Elastic: σ = E ε below ε_y = σ_y / E; flat at σ_y above (perfect plasticity).
        let below = lateral_free(0.5 * 5e3 / e_young);
        assert!((below - 2.5e3).abs() < 1e-6 * 2.5e3, "{below}");
        for e in [2.0, 5.0, 20.0] {
            let above = lateral_free(e * 5e3 / e_young);
            assert!((above - 5e3).abs() < 1e-6 * 5e3, "ε = {e} ε_y: {above}");
        }
    }
}
