//! Drucker–Prager plasticity for sand (Klár et al. 2016, docs/method.md §4.10): the yield
//! cone ‖τ̂‖ + α_dp tr(τ − p_apex I) ≤ 0 on St. Venant–Kirchhoff Hencky elasticity, with
//! the return mapping in the Hencky strain ε = ln σ. WGSL `drucker_prager_return_map` in
//! `shaders/sim/model/drucker_prager.wgsl`.

use glam::{DMat3, DVec3};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::{ElasticModel, Example, ParamError, PlasticLaw, PlasticWgsl, PLASTIC_PARAMS};
use crate::sim::model::elasticity::{hencky_strain, Lame, HENCKY_SIGMA_MIN};
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
    const ALPHA_IS_LOG_JP: bool = true;
    // params: α_dp, the apex's tr ε.
    const WGSL: PlasticWgsl = PlasticWgsl {
        return_map:
            "return drucker_prager_return_map(f, alpha, m.mu, m.lambda, m.params[0], m.params[1]);",
        damage: "0.0",
        stress_scale: "1.0",
        kirchhoff: None,
        module: include_str!("../../../shaders/sim/model/drucker_prager.wgsl"),
    };
    const EXAMPLE: Example = Example {
        params: r#"{"friction_angle": 35.0, "cohesion": 20.0}"#,
        alpha: 0.0,
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn lame() -> Lame {
        Lame::from_young_poisson(1e5, 0.3)
    }

    fn sand(phi_deg: f64, cohesion: f64) -> DruckerPrager {
        DruckerPrager {
            friction_angle: phi_deg.to_radians(),
            cohesion,
        }
    }

    /// y(ε) = ‖ε̂‖ + (3κ/2μ) α_dp (tr ε − tr ε_apex): the cone in strain, ≤ 0 inside.
    fn cone(dp: &DruckerPrager, eps: DVec3, l: &Lame) -> f64 {
        let tr = eps.x + eps.y + eps.z;
        let dev = eps - DVec3::splat(tr / 3.0);
        dev.length() + (3.0 * l.kappa()) / (2.0 * l.mu) * dp.alpha_dp() * (tr - dp.apex_strain(l))
    }

    /// The cone's slope is Mohr–Coulomb's: α_dp = √(2/3)·2 sin φ/(3 − sin φ), so at 30°
    /// α_dp = √(2/3)·0.4.
    #[test]
    fn slope_and_apex() {
        let dp = sand(30.0, 0.0);
        assert!((dp.alpha_dp() - (2.0f64 / 3.0).sqrt() * 0.4).abs() < 1e-14);
        assert_eq!(dp.apex_strain(&lame()), 0.0);
        // Cohesion c moves the apex to the mean stress c cot φ.
        let l = lame();
        let c = sand(30.0, 100.0).apex_strain(&l) * l.kappa();
        assert!((c - 100.0 / 30f64.to_radians().tan()).abs() < 1e-9);
    }

    /// Inside the cone nothing changes; outside, the return lands on the cone (y = 0),
    /// keeps tr ε (a purely deviatoric return: the flow rule is non-associated, no
    /// dilation), keeps the direction of ε̂, and F keeps its rotations; a stretched state
    /// goes to the apex; α gains exactly the plastic volume change.
    #[test]
    fn return_lands_on_the_cone_and_keeps_the_volume() {
        let l = lame();
        let mut r = SplitMix64::new(7);
        let (mut inside, mut sheared, mut apex) = (0, 0, 0);
        for dp in [sand(20.0, 0.0), sand(35.0, 0.0), sand(35.0, 50.0)] {
            for _ in 0..3000 {
                let eps = (DVec3::new(r.uniform(), r.uniform(), r.uniform()) - 0.5) * 0.1;
                let u = r.rotation();
                let v = r.rotation();
                let sigma = DVec3::new(eps.x.exp(), eps.y.exp(), eps.z.exp());
                let f = u * DMat3::from_diagonal(sigma) * v.transpose();
                let (f_new, alpha) = dp.return_map(f, 0.25, &l);
                let eps_new = hencky_strain(svd3(f_new).sigma);
                let tr = eps.x + eps.y + eps.z;
                let tr_new = eps_new.x + eps_new.y + eps_new.z;
                if cone(&dp, eps, &l) <= 0.0 {
                    inside += 1;
                    assert_eq!((f_new, alpha), (f, 0.25));
                } else if tr > dp.apex_strain(&l) {
                    apex += 1;
                    let want = DVec3::splat(dp.apex_strain(&l) / 3.0);
                    assert!((eps_new - want).abs().max_element() < 1e-9, "{eps_new}");
                } else {
                    sheared += 1;
                    assert!(cone(&dp, eps_new, &l).abs() < 1e-9, "not on the cone");
                    assert!((tr_new - tr).abs() < 1e-9, "tr ε changed");
                    // Same principal frame: F_new F⁻¹ is symmetric positive in F's
                    // left frame, i.e. F_new = U diag(σ') Vᵀ with the same U, V.
                    let back = u.transpose() * f_new * v;
                    let off = back
                        - DMat3::from_diagonal(DVec3::new(
                            back.x_axis.x,
                            back.y_axis.y,
                            back.z_axis.z,
                        ));
                    assert!(off.to_cols_array().iter().all(|x| x.abs() < 1e-9));
                }
                assert!((alpha - 0.25 - (tr - tr_new)).abs() < 1e-9);
            }
        }
        assert!(
            inside > 500 && sheared > 500 && apex > 500,
            "{inside} {sheared} {apex}"
        );
    }

    /// A larger friction angle holds more shear: the set of strains inside the cone grows
    /// with φ.
    #[test]
    fn larger_friction_angle_yields_less() {
        let l = lame();
        let mut r = SplitMix64::new(8);
        let strains: Vec<DVec3> = (0..4000)
            .map(|_| (DVec3::new(r.uniform(), r.uniform(), r.uniform()) - 0.5) * 0.05 - 0.01)
            .collect();
        let elastic = |phi: f64| {
            let dp = sand(phi, 0.0);
            strains.iter().filter(|&&e| !dp.project(e, &l).1).count()
        };
        let counts: Vec<usize> = [10.0, 20.0, 30.0, 40.0].map(elastic).to_vec();
        assert!(counts.windows(2).all(|w| w[0] < w[1]), "{counts:?}");
    }
}
