//! Snow (Stomakhin et al. 2013, docs/method.md §4.12): fixed-corotated elasticity whose
//! Lamé parameters harden with compaction, μ, λ ∝ e^{ξ (1 − Jᴾ)}, and a plasticity that
//! clamps the singular values of the elastic F to [1 − θ_c, 1 + θ_s], moving the rest
//! into the plastic F. WGSL `snow_return_map` in `shaders/sim/model/snow.wgsl`.

use glam::{DMat3, DVec3};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::{ElasticModel, Example, ParamError, PlasticLaw, PlasticWgsl, PLASTIC_PARAMS};
use crate::sim::model::elasticity::Lame;
use crate::sim::svd::svd3;

/// Stomakhin et al.'s snow.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Snow {
    /// Critical compression θ_c: σ below 1 − θ_c is plastic.
    pub critical_compression: f64,
    /// Critical stretch θ_s: σ above 1 + θ_s is plastic.
    pub critical_stretch: f64,
    /// Hardening coefficient ξ.
    pub hardening: f64,
}

/// The scene file's snow parameters (defaults: the paper's reference snow).
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SnowSpec {
    /// Critical compression θ_c in (0, 1), default 0.025: how far the snow compresses
    /// elastically before it compacts.
    #[serde(default = "default_compression")]
    pub critical_compression: f64,
    /// Critical stretch θ_s > 0, default 0.0075: how far it stretches elastically before
    /// it breaks apart.
    #[serde(default = "default_stretch")]
    pub critical_stretch: f64,
    /// Hardening coefficient ξ ≥ 0, default 10: compacted snow stiffens by e^{ξ (1 − Jᴾ)}.
    #[serde(default = "default_hardening")]
    pub hardening: f64,
}

fn default_compression() -> f64 {
    0.025
}

fn default_stretch() -> f64 {
    0.0075
}

fn default_hardening() -> f64 {
    10.0
}

/// Hardening exponents above this are clamped (e^{60} fits f32), for Jᴾ → 0.
const MAX_EXPONENT: f64 = 60.0;

impl PlasticLaw for Snow {
    const NAME: &'static str = "snow";
    const ELASTIC: ElasticModel = ElasticModel::FixedCorotated;
    const FRACTURES: bool = false;
    const ALPHA: &'static str = "log of the plastic volume ratio Jᴾ (compacted < 0)";
    const ALPHA_IS_LOG_JP: bool = true;
    // params: θ_c, θ_s, ξ.
    const WGSL: PlasticWgsl = PlasticWgsl {
        return_map: "return snow_return_map(f, alpha, m.params[0], m.params[1]);",
        damage: "0.0",
        stress_scale: "snow_hardening(m.params[2], alpha)",
        kirchhoff: None,
        module: include_str!("../../../shaders/sim/model/snow.wgsl"),
    };
    const EXAMPLE: Example = Example {
        params: r#"{"critical_compression": 0.025, "critical_stretch": 0.0075, "hardening": 10.0}"#,
        alpha: -0.05,
    };
    type Spec = SnowSpec;

    fn from_spec(spec: SnowSpec, _e: f64, _nu: f64) -> Result<Self, ParamError> {
        let (c, s, xi) = (
            spec.critical_compression,
            spec.critical_stretch,
            spec.hardening,
        );
        ParamError::check(
            c.is_finite() && c > 0.0 && c < 1.0,
            "critical_compression",
            c,
            "θ_c in (0, 1)",
        )?;
        ParamError::check(s.is_finite() && s > 0.0, "critical_stretch", s, "θ_s > 0")?;
        ParamError::check(xi.is_finite() && xi >= 0.0, "hardening", xi, "ξ ≥ 0")?;
        Ok(Snow {
            critical_compression: c,
            critical_stretch: s,
            hardening: xi,
        })
    }

    /// σ clamped to [1 − θ_c, 1 + θ_s]; α = ln Jᴾ gains ln(J_trial / J_new).
    fn return_map(&self, f_trial: DMat3, alpha: f64, _lame: &Lame) -> (DMat3, f64) {
        let s = svd3(f_trial);
        let lo = 1.0 - self.critical_compression;
        let hi = 1.0 + self.critical_stretch;
        let sigma = s.sigma.clamp(DVec3::splat(lo), DVec3::splat(hi));
        if sigma == s.sigma {
            return (f_trial, alpha);
        }
        // An inverted trial (σ₃ < 0) has no logarithm: count it at the clamp's floor.
        let floor = DVec3::splat(1e-4);
        let gained = (s.sigma.max(floor) / sigma)
            .to_array()
            .iter()
            .map(|r| r.ln())
            .sum::<f64>();
        (
            s.u * DMat3::from_diagonal(sigma) * s.v.transpose(),
            alpha + gained,
        )
    }

    /// e^{ξ (1 − Jᴾ)}, Jᴾ = e^α, the exponent clamped at 60.
    fn stress_scale(&self, alpha: f64) -> f64 {
        (self.hardening * (1.0 - alpha.exp()))
            .min(MAX_EXPONENT)
            .exp()
    }

    fn gpu_params(&self, _lame: &Lame) -> [f32; PLASTIC_PARAMS] {
        [
            self.critical_compression as f32,
            self.critical_stretch as f32,
            self.hardening as f32,
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
    use glam::DQuat;

    fn snow() -> Snow {
        Snow {
            critical_compression: 0.025,
            critical_stretch: 0.0075,
            hardening: 10.0,
        }
    }

    /// The returned singular values lie in [1 − θ_c, 1 + θ_s], equal the trial ones there
    /// (F unchanged), and the total volume is kept: J_E·Jᴾ before and after agree, i.e. α
    /// = ln Jᴾ gains exactly ln(J_trial/J_new).
    #[test]
    fn clamp_keeps_the_total_volume() {
        let s = snow();
        let l = Lame::from_young_poisson(1.4e5, 0.2);
        let mut r = SplitMix64::new(3);
        let (mut inside, mut clamped) = (0, 0);
        for _ in 0..4000 {
            let v = DVec3::new(r.uniform(), r.uniform(), r.uniform()) - 0.5;
            let q =
                DMat3::from_quat(DQuat::from_xyzw(v.x, v.y, v.z, r.uniform() - 0.5).normalize());
            let sigma = DVec3::new(r.uniform(), r.uniform(), r.uniform()) * 0.06 + 0.97;
            let f = q * DMat3::from_diagonal(sigma);
            let alpha = -0.1 * r.uniform();
            let (f_new, alpha_new) = s.return_map(f, alpha, &l);
            let sv = svd3(f_new).sigma;
            assert!(sv.min_element() >= 1.0 - 0.025 - 1e-12 && sv.max_element() <= 1.0075 + 1e-12);
            let total = |f: DMat3, a: f64| f.determinant().ln() + a;
            assert!((total(f_new, alpha_new) - total(f, alpha)).abs() < 1e-12);
            if sigma.cmpge(DVec3::splat(0.975)).all() && sigma.cmple(DVec3::splat(1.0075)).all() {
                inside += 1;
                assert_eq!((f_new, alpha_new), (f, alpha));
            } else {
                clamped += 1;
            }
        }
        assert!(inside > 200 && clamped > 200, "{inside} {clamped}");
    }

    /// Compacted snow (Jᴾ < 1) stiffens by e^{ξ(1 − Jᴾ)}, loosened snow softens; fresh snow
    /// has its own Lamé parameters.
    #[test]
    fn hardening_factor() {
        let s = snow();
        assert_eq!(s.stress_scale(0.0), 1.0);
        let jp: f64 = 0.9;
        assert!((s.stress_scale(jp.ln()) - 1.0f64.exp()).abs() < 1e-12);
        assert!(s.stress_scale(0.1) < 1.0);
        // Total loss of volume leaves a finite factor.
        assert!(s.stress_scale(-1e3).is_finite());
    }
}
