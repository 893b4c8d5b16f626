//! Elastic constitutive models (docs/method.md §3): Lamé parameters and Kirchhoff stresses τ(F).
//!
//! The MPM step (docs/method.md §2) needs the Kirchhoff stress τ = P Fᵀ = J σ_Cauchy, which both
//! models here give in closed form. Both are objective (τ(RF) = R τ(F) Rᵀ) and isotropic;
//! their small-strain limit is linear elasticity τ ≈ λ tr(ε) I + 2μ ε.

use glam::{DMat3, DVec3};

use crate::sim::svd::{polar, svd3};

/// Lamé parameters μ (`mu`, shear modulus) and λ (`lambda`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lame {
    pub mu: f64,
    pub lambda: f64,
}

impl Lame {
    /// docs/method.md §3: μ = E / (2(1 + ν)), λ = Eν / ((1 + ν)(1 − 2ν)). Needs −1 < ν < ½.
    pub fn from_young_poisson(e: f64, nu: f64) -> Self {
        Lame {
            mu: e / (2.0 * (1.0 + nu)),
            lambda: e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
        }
    }

    /// Bulk modulus κ = λ + 2μ/3 = E / (3(1 − 2ν)) (docs/method.md §3).
    pub fn kappa(&self) -> f64 {
        self.lambda + 2.0 * self.mu / 3.0
    }

    /// P-wave modulus λ + 2μ, for the CFL sound speed c = sqrt((λ + 2μ)/ρ) (docs/method.md §2).
    pub fn p_wave_modulus(&self) -> f64 {
        self.lambda + 2.0 * self.mu
    }
}

/// Trace of a 3×3 matrix.
pub fn trace(a: DMat3) -> f64 {
    a.x_axis.x + a.y_axis.y + a.z_axis.z
}

/// Deviatoric part `A − tr(A)/3 I`.
pub fn dev(a: DMat3) -> DMat3 {
    a - DMat3::IDENTITY * (trace(a) / 3.0)
}

/// Fixed-corotated Kirchhoff stress (docs/method.md §3): τ = 2μ (F − R) Fᵀ + λ (J − 1) J I, with R
/// the rotation of the polar decomposition (a proper rotation even if det F < 0).
pub fn kirchhoff_fixed_corotated(f: DMat3, lame: &Lame) -> DMat3 {
    let (r, _) = polar(f);
    let j = f.determinant();
    (f - r) * f.transpose() * (2.0 * lame.mu) + DMat3::IDENTITY * (lame.lambda * (j - 1.0) * j)
}

/// Neo-Hookean (Borden form) Kirchhoff stress (docs/method.md §3):
/// τ = μ J^(−2/3) dev(F Fᵀ) + κ/2 (J² − 1) I. Needs J > 0.
pub fn kirchhoff_neo_hookean(f: DMat3, lame: &Lame) -> DMat3 {
    let j = f.determinant();
    let b = f * f.transpose();
    dev(b) * (lame.mu * j.powf(-2.0 / 3.0)) + DMat3::IDENTITY * (0.5 * lame.kappa() * (j * j - 1.0))
}

/// The Hencky (logarithmic) strains ε = ln σ of the singular values σ of F, clamped to
/// σ ≥ [`HENCKY_SIGMA_MIN`] (an inverted or flat F has no logarithm).
pub fn hencky_strain(sigma: DVec3) -> DVec3 {
    let sigma = sigma.max(DVec3::splat(HENCKY_SIGMA_MIN));
    DVec3::new(sigma.x.ln(), sigma.y.ln(), sigma.z.ln())
}

/// Singular values below this are clamped before their logarithm (as NACC's `SIGMA_MIN`).
pub const HENCKY_SIGMA_MIN: f64 = 1e-4;

/// St. Venant–Kirchhoff on the Hencky strain (docs/method.md §3), the elasticity under
/// Drucker–Prager and von Mises plasticity: τ = U (2μ ε + λ tr(ε) I) Uᵀ with ε = ln σ.
/// Linear in the logarithmic strain, so the return mappings stay radial in it.
pub fn kirchhoff_stvk_hencky(f: DMat3, lame: &Lame) -> DMat3 {
    let s = svd3(f);
    let (u, eps) = (s.u, hencky_strain(s.sigma));
    let tr = eps.x + eps.y + eps.z;
    let t = eps * (2.0 * lame.mu) + DVec3::splat(lame.lambda * tr);
    u * DMat3::from_diagonal(t) * u.transpose()
}

/// St. Venant–Kirchhoff Hencky strain energy density μ ‖ε‖² + λ/2 (tr ε)².
pub fn energy_stvk_hencky(f: DMat3, lame: &Lame) -> f64 {
    let eps = hencky_strain(svd3(f).sigma);
    let tr = eps.x + eps.y + eps.z;
    lame.mu * eps.length_squared() + 0.5 * lame.lambda * tr * tr
}

/// Fixed-corotated strain energy density μ Σ(σᵢ − 1)² + λ/2 (J − 1)².
pub fn energy_fixed_corotated(f: DMat3, lame: &Lame) -> f64 {
    let j = f.determinant();
    let d = svd3(f).sigma - DVec3::ONE;
    lame.mu * d.length_squared() + 0.5 * lame.lambda * (j - 1.0) * (j - 1.0)
}

/// Neo-Hookean (docs/method.md §3) strain energy density
/// μ/2 (tr(J^(−2/3) F Fᵀ) − 3) + κ/2 ((J² − 1)/2 − ln J).
pub fn energy_neo_hookean(f: DMat3, lame: &Lame) -> f64 {
    let j = f.determinant();
    let tr_b = trace(f * f.transpose());
    0.5 * lame.mu * (j.powf(-2.0 / 3.0) * tr_b - 3.0)
        + 0.5 * lame.kappa() * (0.5 * (j * j - 1.0) - j.ln())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;
    use crate::sim::model::ElasticModel;
    use glam::DQuat;

    fn max_abs(m: DMat3) -> f64 {
        m.to_cols_array().iter().fold(0.0, |a, x| a.max(x.abs()))
    }

    fn random_matrix(r: &mut SplitMix64, amp: f64) -> DMat3 {
        DMat3::from_cols_array(&[0.0; 9].map(|_: f64| amp * (2.0 * r.uniform() - 1.0)))
    }

    fn random_rotation(r: &mut SplitMix64) -> DMat3 {
        let v = DVec3::new(r.uniform(), r.uniform(), r.uniform()) - 0.5;
        DMat3::from_quat(DQuat::from_xyzw(v.x, v.y, v.z, r.uniform() - 0.5).normalize())
    }

    fn lame() -> Lame {
        Lame::from_young_poisson(2000.0, 0.38)
    }

    #[test]
    fn lame_parameters() {
        let l = Lame::from_young_poisson(1000.0, 0.25);
        assert!((l.mu - 400.0).abs() < 1e-12 && (l.lambda - 400.0).abs() < 1e-12);
        let l = lame();
        assert!((l.kappa() - 2000.0 / (3.0 * (1.0 - 2.0 * 0.38))).abs() < 1e-9);
    }

    /// τ(I) = 0 and τ(R) = 0 for random rotations, both models.
    #[test]
    fn stress_free_at_rest_and_under_rotation() {
        let mut r = SplitMix64::new(21);
        let l = lame();
        for &m in ElasticModel::ALL {
            assert!(max_abs(m.kirchhoff(DMat3::IDENTITY, &l)) < 1e-12);
            for _ in 0..1000 {
                let tau = m.kirchhoff(random_rotation(&mut r), &l);
                assert!(max_abs(tau) < 1e-9 * l.kappa(), "{m:?}: {tau}");
            }
        }
    }

    /// τ is symmetric and objective: τ(QF) = Q τ(F) Qᵀ.
    #[test]
    fn stress_symmetric_and_objective() {
        let mut r = SplitMix64::new(22);
        let l = lame();
        for &m in ElasticModel::ALL {
            for _ in 0..2000 {
                let f = DMat3::IDENTITY + random_matrix(&mut r, 0.4);
                let tau = m.kirchhoff(f, &l);
                let scale = max_abs(tau).max(1.0);
                assert!(max_abs(tau - tau.transpose()) < 1e-12 * scale);
                let q = random_rotation(&mut r);
                let rotated = m.kirchhoff(q * f, &l);
                assert!(max_abs(rotated - q * tau * q.transpose()) < 1e-11 * scale);
            }
        }
    }

    /// Small strain: dτ/dF at I along H equals λ tr(ε) I + 2μ ε with ε = sym(H) (central
    /// finite differences, step 1e-5; any skew part of H must not contribute).
    #[test]
    fn small_strain_limit_is_linear_elasticity() {
        let mut r = SplitMix64::new(23);
        let l = lame();
        let h = 1e-5;
        let mut worst = 0.0f64;
        for &m in ElasticModel::ALL {
            for _ in 0..500 {
                let dir = random_matrix(&mut r, 1.0);
                let eps = (dir + dir.transpose()) * 0.5;
                let linear = DMat3::IDENTITY * (l.lambda * trace(eps)) + eps * (2.0 * l.mu);
                let plus = m.kirchhoff(DMat3::IDENTITY + dir * h, &l);
                let minus = m.kirchhoff(DMat3::IDENTITY - dir * h, &l);
                let fd = (plus - minus) * (0.5 / h);
                let rel = max_abs(fd - linear) / max_abs(linear);
                worst = worst.max(rel);
                assert!(rel < 1e-6, "{m:?}: {fd} vs {linear}");
            }
        }
        println!("small-strain limit: worst relative deviation {worst:e}");
    }

    /// Neo-Hookean under pure dilation F = J^(1/3) I: τ = κ/2 (J² − 1) I exactly, i.e.
    /// pressure p = −tr(τ)/3 = κ/2 (1 − J²) (docs/method.md §4's p).
    #[test]
    fn neo_hookean_dilation_pressure() {
        let l = lame();
        for j in [0.3, 0.8, 0.99, 1.0, 1.01, 1.5, 3.0] {
            let tau = kirchhoff_neo_hookean(DMat3::IDENTITY * f64::cbrt(j), &l);
            let want = 0.5 * l.kappa() * (j * j - 1.0);
            let err = max_abs(tau - DMat3::IDENTITY * want);
            assert!(err < 1e-12 * l.kappa(), "J = {j}: {tau} vs {want}");
        }
    }

    /// τ = (∂ψ/∂F) Fᵀ with ∂ψ/∂F by central finite differences of the energy.
    #[test]
    fn stress_is_energy_derivative() {
        let mut r = SplitMix64::new(24);
        let l = lame();
        let h = 1e-6;
        for &m in ElasticModel::ALL {
            for _ in 0..300 {
                let f = DMat3::IDENTITY + random_matrix(&mut r, 0.3);
                let mut p = DMat3::ZERO;
                for k in 0..9 {
                    let mut e = [0.0; 9];
                    e[k] = h;
                    let d = DMat3::from_cols_array(&e);
                    let dpsi = m.energy_density(f + d, &l) - m.energy_density(f - d, &l);
                    let mut cols = p.to_cols_array();
                    cols[k] = dpsi / (2.0 * h);
                    p = DMat3::from_cols_array(&cols);
                }
                let tau = m.kirchhoff(f, &l);
                let err = max_abs(p * f.transpose() - tau) / max_abs(tau).max(1.0);
                assert!(err < 1e-6, "{m:?}: {} vs {tau}", p * f.transpose());
            }
        }
    }
}
