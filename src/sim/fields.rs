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
/// 1 − e^{−kt}.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wind {
    /// w (m/s).
    pub velocity: DVec3,
    /// k (1/s): the rate at which the material takes the wind's velocity.
    pub drag: f64,
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
    /// A node's velocity `v` at `x` after the fields over `dt`: the attractor's
    /// acceleration, then the wind's drag.
    pub fn apply(&self, v: DVec3, x: DVec3, dt: f64) -> DVec3 {
        let mut v = v;
        if let Some(a) = &self.attractor {
            v += a.acceleration(x) * dt;
        }
        if let Some(w) = &self.wind {
            v = w.velocity + (v - w.velocity) * (-w.drag * dt).exp();
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
        };
        let fields = Fields {
            wind: Some(wind),
            attractor: None,
        };
        // Ten steps of 0.01 s equal one of 0.1 s: the exact exponential.
        let mut v = DVec3::ZERO;
        for _ in 0..10 {
            v = fields.apply(v, DVec3::ZERO, 0.01);
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
}
