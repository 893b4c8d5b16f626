//! Brittle damage (docs/method.md §4.13): tension-driven damage that softens a particle
//! from its strength to nothing, never heals, and degrades the St. Venant–Kirchhoff
//! Hencky energy with the volumetric–deviatoric split of Borden et al. (2012), so that
//! broken material still carries pressure. Each particle has its own strength, drawn from
//! a Weibull distribution by a hash of its index and the material's seed, so cracks
//! nucleate at weak spots and run through them, and a run is reproducible. WGSL
//! `brittle_return_map` and `brittle_kirchhoff` in `shaders/sim/model/brittle.wgsl`.
//!
//! The law, per particle with Hencky strains ε = ln σ of F = U diag(σ) Vᵀ:
//!
//! - effective (undamaged) principal stresses s_i = 2μ (ε_i − tr ε/3) + κ tr ε;
//! - driving ratio y = max(max_i s_i, 0) / σ_c,p (tension only);
//! - damage d ← max(d, D(y)), D(y) = 1 − e^{−(y − 1)/s} / y for y > 1, else 0; the
//!   softening ratio s sets how far past the peak a particle still carries load (in
//!   uniaxial tension the stress is σ_c e^{−(y − 1)/s} after the peak);
//! - stress τ = U diag(g 2μ ε̂_i + h κ tr ε) Uᵀ with g = 1 − d on the deviatoric part and
//!   h = g in tension (tr ε > 0) but 1 in compression;
//! - compaction: a volumetric compression past θ (ln J < ln(1 − θ)) is plastic, so an
//!   impact crushes the material it compresses instead of storing its energy to spring
//!   back (the fruit's cells burst; NACC's cap does the same);
//! - a particle with d ≥ [`BROKEN`] is rubble: d = 1, and F keeps only its rotation and
//!   a compression of at most θ (F = J^{1/3} U Vᵀ with 1 − θ ≤ J ≤ 1): a crack's particles
//!   neither pull nor stretch their Gaussians into streaks.

use glam::{DMat3, DVec3};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::{ElasticModel, Example, ParamError, PlasticLaw, PlasticWgsl, PLASTIC_PARAMS};
use crate::sim::model::elasticity::{hencky_strain, Lame};
use crate::sim::svd::svd3;

/// Damage at which a particle counts as broken through (rubble).
pub const BROKEN: f64 = 0.99;

/// A brittle material: its strength distribution and softening.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Brittle {
    /// Mean tensile strength σ̄ (Pa) at the reference spacing.
    pub strength: f64,
    /// Weibull modulus m; `None`: every particle has strength σ̄.
    pub weibull_modulus: Option<f64>,
    /// Softening ratio s > 0.
    pub softening: f64,
    /// Seed of the strength draw.
    pub seed: u32,
    /// The largest volumetric compression θ held elastically (past it, compaction).
    pub compaction: f64,
    /// Grid spacing at which σ̄ is the mean strength; `None`: no size effect.
    pub reference_dx: Option<f64>,
    /// The size effect's factor on every strength at the simulation's spacing
    /// (`(reference_dx / dx)^{3/m}`, set by [`PlasticLaw::for_grid`]; 1 before).
    pub size_factor: f64,
}

/// The scene file's brittle parameters.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BrittleSpec {
    /// Mean tensile strength σ̄ in Pa (> 0): the largest principal stress a particle of
    /// average strength carries before it starts to break. The shipped watermelon's flesh:
    /// 160 Pa, 0.16 of its Young's modulus (`scenes/watermelon_drop.json`).
    pub strength: f64,
    /// Weibull modulus m (> 0; absent: every particle has strength σ̄): each particle's
    /// strength is drawn from a Weibull distribution of mean σ̄; a smaller m spreads the
    /// strengths wider (glass and ceramics 5–15).
    #[serde(default)]
    pub weibull_modulus: Option<f64>,
    /// Softening ratio s (> 0, default 1): after its peak a particle's stress in uniaxial
    /// tension falls as e^{−(y − 1)/s}, y the effective stress over the strength; smaller is
    /// more brittle.
    #[serde(default = "default_softening")]
    pub softening: f64,
    /// Seed of the strength draw (default 0): the same seed, the same weak spots.
    #[serde(default)]
    pub seed: u32,
    /// The largest volumetric compression θ in (0, 1) the material holds elastically
    /// (default 0.1): it carries a pressure up to about κθ and compacts (crushes) beyond
    /// it, so an impact's energy goes into the crushed zone instead of a rebound.
    #[serde(default = "default_compaction")]
    pub compaction: f64,
    /// Spacing Δx in m at which `strength` is the mean (> 0; needs `weibull_modulus`): on
    /// another grid every strength is scaled by (reference_dx / Δx)^{3/m}, Weibull's size
    /// effect (smaller samples are stronger). Absent: the same strengths at every Δx.
    #[serde(default)]
    pub reference_dx: Option<f64>,
}

fn default_softening() -> f64 {
    1.0
}

fn default_compaction() -> f64 {
    0.1
}

/// lowbias32 (Wellons' integer hash): a particle's index and seed to 32 well-mixed bits.
pub fn hash32(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^ (x >> 16)
}

/// The key the seed adds to every index: 24 bits, so that the GPU record carries it
/// exactly as an f32.
pub fn seed_key(seed: u32) -> u32 {
    hash32(seed ^ 0x9e37_79b9) >> 8
}

/// A uniform draw in (0, 1) for particle `particle`: 23 bits plus a half, exact in f32.
pub fn uniform_draw(particle: u32, key: u32) -> f64 {
    let k = hash32(particle ^ key) >> 9;
    (f64::from(k) + 0.5) / f64::from(1u32 << 23)
}

/// D(y): the damage at driving ratio y.
pub fn damage_at(y: f64, softening: f64) -> f64 {
    if y <= 1.0 {
        0.0
    } else {
        1.0 - (-(y - 1.0) / softening).exp() / y
    }
}

impl Brittle {
    /// The Weibull scale σ₀ = σ̄ / Γ(1 + 1/m) (times the size factor): the strengths' mean
    /// is then σ̄.
    pub fn weibull_scale(&self) -> f64 {
        let mean_factor = match self.weibull_modulus {
            Some(m) => libm::tgamma(1.0 + 1.0 / m),
            None => 1.0,
        };
        self.strength * self.size_factor / mean_factor
    }

    /// Particle `particle`'s strength σ_c,p = σ₀ (−ln u)^{1/m}.
    pub fn strength_of(&self, particle: u32) -> f64 {
        match self.weibull_modulus {
            None => self.weibull_scale(),
            Some(m) => {
                let u = uniform_draw(particle, seed_key(self.seed));
                self.weibull_scale() * (-u.ln()).powf(1.0 / m)
            }
        }
    }

    /// The effective principal stresses s_i = 2μ ε̂_i + κ tr ε of the Hencky strains `eps`.
    pub fn effective_stresses(eps: DVec3, lame: &Lame) -> DVec3 {
        let tr = eps.x + eps.y + eps.z;
        (eps - DVec3::splat(tr / 3.0)) * (2.0 * lame.mu) + DVec3::splat(lame.kappa() * tr)
    }

    /// The degraded principal stresses at damage `d`.
    pub fn degraded_stresses(eps: DVec3, d: f64, lame: &Lame) -> DVec3 {
        let tr = eps.x + eps.y + eps.z;
        let g = 1.0 - d;
        let h = if tr > 0.0 { g } else { 1.0 };
        (eps - DVec3::splat(tr / 3.0)) * (2.0 * lame.mu * g) + DVec3::splat(h * lame.kappa() * tr)
    }

    /// Stored energy density ψ = g μ ‖ε̂‖² + h κ/2 (tr ε)² at damage `d`.
    pub fn energy(f: DMat3, d: f64, lame: &Lame) -> f64 {
        let eps = hencky_strain(svd3(f).sigma);
        let tr = eps.x + eps.y + eps.z;
        let g = 1.0 - d;
        let h = if tr > 0.0 { g } else { 1.0 };
        let dev = eps - DVec3::splat(tr / 3.0);
        g * lame.mu * dev.length_squared() + h * 0.5 * lame.kappa() * tr * tr
    }
}

impl PlasticLaw for Brittle {
    const NAME: &'static str = "brittle";
    const ELASTIC: ElasticModel = ElasticModel::StvkHencky;
    const FRACTURES: bool = true;
    const ALPHA: &'static str = "damage d ∈ [0, 1] (1: broken through)";
    const ALPHA_IS_LOG_JP: bool = false;
    // params: σ₀ (Weibull scale with the size factor), 1/m (0: uniform), s, the seed's key
    // (an integer below 2²⁴), ln(1 − θ) (the compaction's floor on ln J).
    const WGSL: PlasticWgsl = PlasticWgsl {
        return_map: "return brittle_return_map(f, alpha, particle, m.mu, m.kappa, m.params[0], \
                     m.params[1], m.params[2], u32(m.params[3]), m.params[4]);",
        damage: "clamp(alpha, 0.0, 1.0)",
        stress_scale: "1.0",
        kirchhoff: Some("brittle_kirchhoff(f, alpha, m.mu, m.kappa)"),
        module: include_str!("../../../shaders/sim/model/brittle.wgsl"),
    };
    const EXAMPLE: Example = Example {
        params: r#"{"strength": 300.0, "weibull_modulus": 6.0, "softening": 0.5, "seed": 9}"#,
        alpha: 0.0,
    };
    type Spec = BrittleSpec;

    fn from_spec(spec: BrittleSpec, _e: f64, _nu: f64) -> Result<Self, ParamError> {
        let s = spec.strength;
        ParamError::check(
            s.is_finite() && s > 0.0,
            "strength",
            s,
            "a tensile strength in Pa > 0",
        )?;
        if let Some(m) = spec.weibull_modulus {
            ParamError::check(
                m.is_finite() && m > 0.0,
                "weibull_modulus",
                m,
                "a Weibull modulus > 0 (or leave it out for one strength)",
            )?;
        }
        let soft = spec.softening;
        ParamError::check(
            soft.is_finite() && soft > 0.0,
            "softening",
            soft,
            "a softening ratio > 0",
        )?;
        let theta = spec.compaction;
        ParamError::check(
            theta.is_finite() && theta > 0.0 && theta < 1.0,
            "compaction",
            theta,
            "a volumetric compression θ in (0, 1)",
        )?;
        if let Some(h) = spec.reference_dx {
            ParamError::check(
                h.is_finite() && h > 0.0,
                "reference_dx",
                h,
                "a grid spacing in m > 0",
            )?;
            if spec.weibull_modulus.is_none() {
                return Err(ParamError::new(
                    "reference_dx",
                    h,
                    "a weibull_modulus beside it (the size effect is Weibull's)",
                ));
            }
        }
        Ok(Brittle {
            strength: s,
            weibull_modulus: spec.weibull_modulus,
            softening: soft,
            seed: spec.seed,
            compaction: theta,
            reference_dx: spec.reference_dx,
            size_factor: 1.0,
        })
    }

    fn return_map(&self, f_trial: DMat3, alpha: f64, lame: &Lame) -> (DMat3, f64) {
        self.return_map_at(f_trial, alpha, lame, 0)
    }

    /// d ← max(d, D(y)); a compression past θ compacts (ε loses (tr ε − ln(1 − θ))/3 per
    /// axis); past [`BROKEN`], rubble: d = 1, F = J^{1/3} U Vᵀ with ln J = tr ε clamped to
    /// [ln(1 − θ), 0].
    fn return_map_at(
        &self,
        f_trial: DMat3,
        alpha: f64,
        lame: &Lame,
        particle: u32,
    ) -> (DMat3, f64) {
        let s = svd3(f_trial);
        let eps = hencky_strain(s.sigma);
        let peak = Self::effective_stresses(eps, lame).max_element().max(0.0);
        let y = peak / self.strength_of(particle);
        let d = alpha.max(damage_at(y, self.softening)).clamp(0.0, 1.0);
        let tr = eps.x + eps.y + eps.z;
        let ln_j_min = (1.0 - self.compaction).ln();
        if d >= BROKEN {
            let ln_j = tr.clamp(ln_j_min, 0.0);
            return (s.u * s.v.transpose() * (ln_j / 3.0).exp(), 1.0);
        }
        if tr >= ln_j_min {
            return (f_trial, d);
        }
        let eps_new = eps - DVec3::splat((tr - ln_j_min) / 3.0);
        let sigma = DVec3::new(eps_new.x.exp(), eps_new.y.exp(), eps_new.z.exp());
        (s.u * DMat3::from_diagonal(sigma) * s.v.transpose(), d)
    }

    fn damage(&self, alpha: f64) -> f64 {
        alpha.clamp(0.0, 1.0)
    }

    /// τ = U diag(g 2μ ε̂_i + h κ tr ε) Uᵀ (the split of the module doc).
    fn kirchhoff(&self, _elastic: ElasticModel, f: DMat3, alpha: f64, lame: &Lame) -> DMat3 {
        let s = svd3(f);
        let t = Self::degraded_stresses(hencky_strain(s.sigma), alpha.clamp(0.0, 1.0), lame);
        s.u * DMat3::from_diagonal(t) * s.u.transpose()
    }

    fn for_grid(&self, dx: f64) -> Self {
        let size_factor = match (self.reference_dx, self.weibull_modulus) {
            (Some(h), Some(m)) => (h / dx).powf(3.0 / m),
            _ => 1.0,
        };
        Brittle {
            size_factor,
            ..*self
        }
    }

    fn gpu_params(&self, _lame: &Lame) -> [f32; PLASTIC_PARAMS] {
        let inv_m = self.weibull_modulus.map_or(0.0, |m| 1.0 / m);
        [
            self.weibull_scale() as f32,
            inv_m as f32,
            self.softening as f32,
            seed_key(self.seed) as f32,
            (1.0 - self.compaction).ln() as f32,
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
        Lame::from_young_poisson(1000.0, 0.35)
    }

    fn uniform(strength: f64, softening: f64) -> Brittle {
        Brittle {
            strength,
            weibull_modulus: None,
            softening,
            seed: 0,
            compaction: 0.05,
            reference_dx: None,
            size_factor: 1.0,
        }
    }

    fn diag(eps: DVec3) -> DMat3 {
        DMat3::from_diagonal(DVec3::new(eps.x.exp(), eps.y.exp(), eps.z.exp()))
    }

    /// Pulls a bar along x in uniaxial stress (the lateral strain solved each increment so
    /// that the lateral stress of the damaged material is zero): the axial stress peaks at
    /// σ_c within 5%, then softens to nothing; d rises monotonically inside [0, 1].
    fn pull(law: &Brittle, l: &Lame, steps: usize, max_strain: f64) -> (f64, f64, Vec<f64>) {
        let (mut d, mut peak, mut last) = (0.0, 0.0f64, 0.0);
        let mut ds = Vec::new();
        for k in 1..=steps {
            let e1 = max_strain * k as f64 / steps as f64;
            // Lateral strain with zero lateral stress at the current damage (bisection).
            let lateral = |e2: f64| Brittle::degraded_stresses(DVec3::new(e1, e2, e2), d, l).y;
            let (mut lo, mut hi) = (-e1, e1);
            for _ in 0..100 {
                let mid = 0.5 * (lo + hi);
                if lateral(mid) > 0.0 {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            let eps = DVec3::new(e1, lo, lo);
            let (_, d_new) = law.return_map(diag(eps), d, l);
            d = d_new;
            ds.push(d);
            let tau = Brittle::degraded_stresses(eps, d, l).x;
            peak = peak.max(tau);
            last = tau;
        }
        (peak, last, ds)
    }

    #[test]
    fn uniaxial_tension_breaks_at_the_strength() {
        let l = lame();
        for (sigma_c, soft) in [(100.0, 1.0), (50.0, 0.3), (200.0, 2.0)] {
            let law = uniform(sigma_c, soft);
            let (peak, last, ds) = pull(&law, &l, 4000, 2.0);
            assert!(
                (peak - sigma_c).abs() < 0.05 * sigma_c,
                "σ_c {sigma_c}: peak {peak}"
            );
            assert!(
                last < 0.02 * sigma_c,
                "σ_c {sigma_c}: still {last} at the end"
            );
            assert!(ds.windows(2).all(|w| w[1] >= w[0]), "d not monotone");
            assert!(ds.iter().all(|d| (0.0..=1.0).contains(d)));
            assert_eq!(*ds.last().unwrap(), 1.0, "never broke through");
        }
    }

    /// Compression gives no damage: uniaxial (lateral stress free, solved as in `pull`)
    /// and confined (lateral strain zero) to 3σ_c, and hydrostatic.
    #[test]
    fn compression_to_three_times_the_strength_does_not_damage() {
        let l = lame();
        let law = uniform(100.0, 1.0);
        let e_mod = 1000.0;
        let e1 = -3.0 * 100.0 / e_mod * 1.2;
        let nu = 0.35;
        for eps in [
            DVec3::new(e1, -nu * e1, -nu * e1),
            DVec3::new(e1, 0.0, 0.0),
            DVec3::splat(e1),
        ] {
            let axial = Brittle::effective_stresses(eps, &l).x;
            assert!(axial < -2.9 * 100.0, "setup: {axial}");
            let mut d = 0.0;
            for k in 1..=100 {
                let (_, dn) = law.return_map(diag(eps * (k as f64 / 100.0)), d, &l);
                d = dn;
            }
            assert_eq!(d, 0.0, "{eps}: damaged {d}");
        }
    }

    /// ψ(F, d) never grows with d at any F, compression keeps its full pressure, and
    /// the stress is ∂ψ/∂F Fᵀ of that energy (finite differences).
    #[test]
    fn damage_only_releases_energy_and_keeps_pressure() {
        let l = lame();
        let mut r = SplitMix64::new(5);
        for _ in 0..2000 {
            let eps = (DVec3::new(r.uniform(), r.uniform(), r.uniform()) - 0.5) * 0.4;
            let f = r.rotation() * diag(eps) * r.rotation();
            let mut prev = f64::INFINITY;
            for k in 0..=10 {
                let psi = Brittle::energy(f, k as f64 / 10.0, &l);
                assert!(psi <= prev + 1e-12, "ψ grew with d at {eps}");
                prev = psi;
            }
            let tr = eps.x + eps.y + eps.z;
            if tr < 0.0 {
                let full = Brittle::degraded_stresses(eps, 1.0, &l);
                let mean = (full.x + full.y + full.z) / 3.0;
                assert!((mean - l.kappa() * tr).abs() < 1e-9, "pressure lost");
            }
        }
        // τ = (∂ψ/∂F) Fᵀ at a damaged state, by central differences.
        let law = uniform(100.0, 1.0);
        for d in [0.0, 0.4, 0.9] {
            let f = r.rotation() * diag(DVec3::new(0.08, -0.03, 0.02));
            let tau = law.kirchhoff(ElasticModel::StvkHencky, f, d, &l);
            let h = 1e-6;
            let mut p = DMat3::ZERO;
            for c in 0..3 {
                for row in 0..3 {
                    let mut e = DMat3::ZERO;
                    e.col_mut(c)[row] = h;
                    let g =
                        (Brittle::energy(f + e, d, &l) - Brittle::energy(f - e, d, &l)) / (2.0 * h);
                    p.col_mut(c)[row] = g;
                }
            }
            let want = p * f.transpose();
            let err = (tau - want)
                .to_cols_array()
                .iter()
                .fold(0.0f64, |a, x| a.max(x.abs()));
            assert!(err < 1e-4 * 100.0, "d {d}: τ off by {err}");
        }
    }

    /// A broken particle is rubble: d = 1, no tension, no shear, its compression kept up
    /// to θ (compacted beyond), its rotation kept.
    #[test]
    fn broken_particles_keep_rotation_and_compression_only() {
        let l = lame();
        let law = uniform(10.0, 0.2);
        let mut r = SplitMix64::new(6);
        for _ in 0..200 {
            let (u, v) = (r.rotation(), r.rotation());
            let eps = (DVec3::new(r.uniform(), r.uniform(), r.uniform()) - 0.3) * 0.5;
            let f = u * diag(eps) * v.transpose();
            let (f_new, d) = law.return_map(f, 1.0, &l);
            assert_eq!(d, 1.0);
            let j = f_new.determinant();
            let tr = eps.x + eps.y + eps.z;
            let ln_j = tr.clamp(0.95f64.ln(), 0.0);
            assert!((j - ln_j.exp()).abs() < 1e-9, "J {j} for tr ε {tr}");
            let tau = law.kirchhoff(ElasticModel::StvkHencky, f_new, d, &l);
            let want = l.kappa() * ln_j;
            let off = tau - DMat3::IDENTITY * want;
            assert!(off.to_cols_array().iter().all(|x| x.abs() < 1e-8), "{tau}");
            // The rotation is polar(F)'s: F_new = J^{1/3} U Vᵀ.
            let rot = f_new * (1.0 / j.cbrt());
            assert!((rot - u * v.transpose())
                .to_cols_array()
                .iter()
                .all(|x| x.abs() < 1e-9));
        }
    }

    /// An intact particle compressed past θ compacts: ln J lands on ln(1 − θ), its
    /// deviatoric strain and frame are kept, its damage too; less compression is elastic.
    #[test]
    fn compression_past_theta_compacts() {
        let l = lame();
        let law = uniform(1e6, 1.0);
        let floor = 0.95f64.ln();
        let mut r = SplitMix64::new(8);
        let (mut compacted, mut elastic) = (0, 0);
        for _ in 0..500 {
            let (u, v) = (r.rotation(), r.rotation());
            let eps = (DVec3::new(r.uniform(), r.uniform(), r.uniform()) - 0.7) * 0.3;
            let f = u * diag(eps) * v.transpose();
            let (f_new, d) = law.return_map(f, 0.25, &l);
            assert_eq!(d, 0.25);
            let tr = eps.x + eps.y + eps.z;
            if tr >= floor {
                elastic += 1;
                assert_eq!(f_new, f);
                continue;
            }
            compacted += 1;
            assert!((f_new.determinant().ln() - floor).abs() < 1e-9);
            let back = u.transpose() * f_new * v;
            let got = DVec3::new(back.x_axis.x, back.y_axis.y, back.z_axis.z);
            let eps_new = DVec3::new(got.x.ln(), got.y.ln(), got.z.ln());
            let dev = |e: DVec3| e - DVec3::splat((e.x + e.y + e.z) / 3.0);
            assert!((dev(eps_new) - dev(eps)).abs().max_element() < 1e-9);
        }
        assert!(compacted > 100 && elastic > 50, "{compacted} {elastic}");
    }

    /// The strengths have the Weibull distribution asked for: mean σ̄, the CDF's median at
    /// σ₀ (ln 2)^{1/m}, reproducible by seed and different across seeds; the size effect
    /// scales every strength by (h/Δx)^{3/m}.
    #[test]
    fn strengths_are_weibull_and_seeded() {
        let law = Brittle {
            strength: 100.0,
            weibull_modulus: Some(6.0),
            softening: 1.0,
            seed: 3,
            compaction: 0.05,
            reference_dx: Some(0.02),
            size_factor: 1.0,
        };
        let n = 200_000u32;
        let draws: Vec<f64> = (0..n).map(|p| law.strength_of(p)).collect();
        let mean = draws.iter().sum::<f64>() / f64::from(n);
        assert!((mean - 100.0).abs() < 0.3, "mean {mean}");
        let median_want = law.weibull_scale() * 2f64.ln().powf(1.0 / 6.0);
        let below = draws.iter().filter(|&&s| s < median_want).count();
        assert!((below as f64 / f64::from(n) - 0.5).abs() < 0.005, "{below}");
        assert_eq!(law.strength_of(17), law.strength_of(17));
        let other = Brittle { seed: 4, ..law };
        let same = (0..1000)
            .filter(|&p| other.strength_of(p) == law.strength_of(p))
            .count();
        assert!(same < 5, "seed does not change the draw ({same})");
        let finer = law.for_grid(0.01);
        let ratio = finer.strength_of(17) / law.strength_of(17);
        assert!((ratio - 2f64.powf(0.5)).abs() < 1e-12, "{ratio}");
        assert_eq!(uniform(50.0, 1.0).for_grid(0.01).strength_of(5), 50.0);
    }

    #[test]
    fn bad_parameters_name_the_field() {
        let spec = |json: &str| serde_json::from_str::<BrittleSpec>(json).unwrap();
        let err = Brittle::from_spec(spec(r#"{"strength": -1}"#), 1e3, 0.3).unwrap_err();
        assert_eq!(err.field, "strength");
        let err =
            Brittle::from_spec(spec(r#"{"strength": 1, "softening": 0}"#), 1e3, 0.3).unwrap_err();
        assert_eq!(err.field, "softening");
        let err = Brittle::from_spec(spec(r#"{"strength": 1, "reference_dx": 0.01}"#), 1e3, 0.3)
            .unwrap_err();
        assert_eq!(err.field, "reference_dx");
        let err =
            Brittle::from_spec(spec(r#"{"strength": 1, "compaction": 1}"#), 1e3, 0.3).unwrap_err();
        assert_eq!(err.field, "compaction");
        assert!(
            Brittle::from_spec(spec(r#"{"strength": 1, "weibull_modulus": 0}"#), 1e3, 0.3).is_err()
        );
    }
}
