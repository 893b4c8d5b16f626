//! Force fields over the whole simulation (docs/method.md §2.5): a wind that drags the
//! material towards its velocity and an attractor that pulls it towards a point. Both
//! act on the grid's node velocities after gravity and before the boundary conditions,
//! the same on the CPU reference ([`super::cpu::grid_update_at`]) and the GPU
//! (`shaders/sim/step/grid_update.wgsl`, `sim_fields`).

use glam::DVec3;

/// The fields of a simulation (none by default).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Fields {
    pub wind: Option<Wind>,
    pub attractor: Option<Attractor>,
}

/// A wind of velocity w: dv/dt = k (w − v), integrated exactly over a step,
/// v ← w + (v − w) e^{−kΔt}, so any drag is stable and a body at rest reaches w as
/// 1 − e^{−kt}. With gusts, w varies in time: [`Wind::velocity_at`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wind {
    /// The mean w (m/s).
    pub velocity: DVec3,
    /// k (1/s): the rate at which the material takes the wind's velocity.
    pub drag: f64,
    pub gusts: Option<Gusts>,
}

/// Gusts: the wind's velocity w(t) = w (1 + s n(t / T)), n a smooth noise in [−1, 1] with
/// one random value per period T (seeded), eased between them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gusts {
    /// s: the gusts' share of the mean wind (0.5: from half to one and a half times it).
    pub strength: f64,
    /// T (s): the time between the noise's values.
    pub period: f64,
    pub seed: u32,
}

impl Gusts {
    /// n(u) in [−1, 1]: the values at the integers ⌊u⌋ and ⌊u⌋ + 1 (hashed with the seed),
    /// eased by 3f² − 2f³ (f = u − ⌊u⌋), so n and dn/du are continuous.
    pub fn noise(&self, u: f64) -> f64 {
        let k = u.floor();
        let f = u - k;
        let at = |j: f64| {
            let bits =
                crate::rng::SplitMix64::new((j as i64 as u64) ^ (u64::from(self.seed) << 40))
                    .next_u64();
            (bits >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let e = f * f * (3.0 - 2.0 * f);
        at(k) * (1.0 - e) + at(k + 1.0) * e
    }
}

impl Wind {
    /// w(t): the mean velocity, scaled by the gusts at `time` seconds.
    pub fn velocity_at(&self, time: f64) -> DVec3 {
        match &self.gusts {
            None => self.velocity,
            Some(g) => self.velocity * (1.0 + g.strength * g.noise(time / g.period)),
        }
    }

    /// Whether w changes in time (the GPU then takes it per substep).
    pub fn varies(&self) -> bool {
        self.gusts.is_some_and(|g| g.strength != 0.0)
    }
}

/// An attractor at p: an acceleration of `strength` towards p (away when negative) at
/// distance d, scaled by r² / (r² + d²), r the falloff.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Attractor {
    /// p (m).
    pub point: DVec3,
    /// Acceleration towards p at p's side (m/s²; negative repels).
    pub strength: f64,
    /// r (m): the distance at which the acceleration has halved.
    pub falloff: f64,
}

impl Attractor {
    /// The acceleration at `x`.
    pub fn acceleration(&self, x: DVec3) -> DVec3 {
        let d = self.point - x;
        let d2 = d.length_squared();
        if d2 <= 1e-24 {
            return DVec3::ZERO;
        }
        let r2 = self.falloff * self.falloff;
        d * (self.strength * r2 / ((r2 + d2) * d2.sqrt()))
    }
}

impl Fields {
    /// A node's velocity `v` at `x` after the fields over the step of `dt` that starts at
    /// `time`: the attractor's acceleration, then the wind's drag towards w(time).
    pub fn apply(&self, v: DVec3, x: DVec3, dt: f64, time: f64) -> DVec3 {
        let mut v = v;
        if let Some(a) = &self.attractor {
            v += a.acceleration(x) * dt;
        }
        if let Some(w) = &self.wind {
            let wt = w.velocity_at(time);
            v = wt + (v - wt) * (-w.drag * dt).exp();
        }
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wind_relaxes_exactly_and_the_attractor_halves_at_its_falloff() {
        let wind = Wind {
            velocity: DVec3::new(2.0, 0.0, 0.0),
            drag: 3.0,
            gusts: None,
        };
        let fields = Fields {
            wind: Some(wind),
            attractor: None,
        };
        // Ten steps of 0.01 s equal one of 0.1 s: the exact exponential.
        let mut v = DVec3::ZERO;
        for _ in 0..10 {
            v = fields.apply(v, DVec3::ZERO, 0.01, 0.0);
        }
        let exact = 2.0 * (1.0 - (-0.3f64).exp());
        assert!((v.x - exact).abs() < 1e-12, "{} vs {exact}", v.x);
        let a = Attractor {
            point: DVec3::new(0.0, 0.0, 1.0),
            strength: 4.0,
            falloff: 0.5,
        };
        let near = a.acceleration(DVec3::new(0.0, 0.0, 1.0 - 1e-6));
        let at_r = a.acceleration(DVec3::new(0.0, 0.0, 0.5));
        assert!((near.z - 4.0).abs() < 1e-9 && near.x == 0.0);
        assert!((at_r.z - 2.0).abs() < 1e-12, "{at_r}");
        assert_eq!(a.acceleration(a.point), DVec3::ZERO);
    }

    #[test]
    fn gusts_stay_in_their_band_and_vary_smoothly() {
        let g = Gusts {
            strength: 0.5,
            period: 0.4,
            seed: 7,
        };
        let wind = Wind {
            velocity: DVec3::new(2.0, 0.0, 0.0),
            drag: 1.0,
            gusts: Some(g),
        };
        let speeds: Vec<f64> = (0..4000)
            .map(|i| wind.velocity_at(f64::from(i) * 1e-3).x)
            .collect();
        let (lo, hi) = speeds
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &s| (a.min(s), b.max(s)));
        assert!(lo >= 1.0 - 1e-12 && hi <= 3.0 + 1e-12, "{lo}..{hi}");
        assert!(hi - lo > 0.5, "gusts that barely vary: {lo}..{hi}");
        // Continuous: no jump between neighbouring milliseconds bigger than the ease allows
        // (|dn/du| ≤ 1.5 · 2 over a period of 0.4 s: 0.0075 per ms at s 0.5, w 2).
        let jump = speeds
            .windows(2)
            .map(|p| (p[1] - p[0]).abs())
            .fold(0.0, f64::max);
        assert!(jump < 0.0076, "jump {jump}");
        let other = Gusts { seed: 8, ..g };
        assert_ne!(g.noise(3.3), other.noise(3.3));
        assert_eq!(g.noise(3.3), g.noise(3.3));
    }
}
