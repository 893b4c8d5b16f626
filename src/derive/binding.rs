//! Gaussians bound to particles (docs/method.md §6.1): when an object's particles are a
//! lattice rather than its Gaussians, each Gaussian is bound at rest to its nearest
//! particle p and keeps the offset X_g − X_p. Every frame the derive pass moves it by that
//! particle's local affine motion,
//!
//!   x_g = x_p + F_p (X_g − X_p),   Σ_g = F_p A_g F_pᵀ,   R_g = polar(F_p) R⁰_g,
//!
//! which is exact for any motion that is affine over the particle's neighbourhood (a rigid
//! motion, a uniform stretch). One particle per Gaussian rather than a smooth blend of
//! several: a blend pulls a Gaussian whose neighbours end up in two fragments across the
//! crack between them, the nearest particle carries it off with its own fragment. Eight
//! bytes of state per Gaussian would do (index and a half-precision offset); the GPU record
//! is 16 (offset as three f32, index as bits), which keeps x_g to f32 round-off.
//!
//! With one particle per Gaussian ("gaussians"), the binding is the identity with zero
//! offsets, and the same pass gives x_g = x_p bit for bit.

use std::collections::HashMap;

use glam::{DMat3, DVec3, IVec3, Vec3};
use rayon::prelude::*;

/// Which particle moves each Gaussian of a run of Gaussians, and its rest offset from it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Binding {
    /// Index of the particle (in the simulation's particle order).
    pub particle: Vec<u32>,
    /// X_g − X_p at rest.
    pub offset: Vec<Vec3>,
}

impl Binding {
    /// Gaussian k moved by particle `first + k`, from its position: one particle per
    /// Gaussian.
    pub fn identity(first: u32, count: usize) -> Binding {
        Binding {
            particle: (0..count as u32).map(|k| first + k).collect(),
            offset: vec![Vec3::ZERO; count],
        }
    }

    /// Each of `means` bound to its nearest point of `particles` (ties: the lower index),
    /// numbered from `first`; `spacing` is the particles' typical spacing (the search
    /// grid's cell).
    pub fn nearest(means: &[Vec3], particles: &[DVec3], first: u32, spacing: f64) -> Binding {
        assert!(
            spacing > 0.0,
            "binding: the particle spacing must be positive"
        );
        if particles.is_empty() {
            return Binding::default();
        }
        let cell = |p: DVec3| (p / spacing).floor().as_ivec3();
        let mut cells: HashMap<IVec3, Vec<u32>> = HashMap::new();
        for (i, &p) in particles.iter().enumerate() {
            cells.entry(cell(p)).or_default().push(i as u32);
        }
        // The farthest ring worth searching: beyond the particles' own extent.
        let (lo, hi) = particles
            .iter()
            .fold((IVec3::MAX, IVec3::MIN), |(lo, hi), &p| {
                (lo.min(cell(p)), hi.max(cell(p)))
            });
        let (particle, offset) = means
            .par_iter()
            .map(|m| {
                let x = m.as_dvec3();
                let c = cell(x);
                let reach = (c - lo).abs().max((hi - c).abs()).max_element() + 1;
                let mut best = (f64::INFINITY, u32::MAX);
                for r in 0..=reach {
                    // Every point in a ring r cells out is at least (r − 1)·spacing away.
                    if best.0.sqrt() < f64::from((r - 1).max(0)) * spacing {
                        break;
                    }
                    for d in ring(r) {
                        for &j in cells.get(&(c + d)).map_or(&[][..], |v| v.as_slice()) {
                            let d2 = x.distance_squared(particles[j as usize]);
                            if (d2, j) < best {
                                best = (d2, j);
                            }
                        }
                    }
                }
                let j = best.1;
                (first + j, (x - particles[j as usize]).as_vec3())
            })
            .unzip();
        Binding { particle, offset }
    }

    pub fn len(&self) -> usize {
        self.particle.len()
    }

    pub fn is_empty(&self) -> bool {
        self.particle.is_empty()
    }

    pub fn append(&mut self, other: Binding) {
        self.particle.extend(other.particle);
        self.offset.extend(other.offset);
    }
}

/// The cells on the surface of the cube of half-width `r` about the origin.
fn ring(r: i32) -> impl Iterator<Item = IVec3> {
    (-r..=r).flat_map(move |x| {
        (-r..=r).flat_map(move |y| {
            (-r..=r)
                .map(move |z| IVec3::new(x, y, z))
                .filter(move |d| d.abs().max_element() == r)
        })
    })
}

/// Where a bound Gaussian is: x_p + F_p (X_g − X_p) (the f64 twin of the derive pass).
pub fn bound_mean(x_p: DVec3, f_p: DMat3, offset: DVec3) -> DVec3 {
    x_p + f_p * offset
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    #[test]
    fn nearest_matches_a_brute_force_search() {
        let mut r = SplitMix64::new(3);
        let mut v = || DVec3::new(r.uniform(), r.uniform(), r.uniform());
        let particles: Vec<DVec3> = (0..400).map(|_| v()).collect();
        // Means inside the cloud and far outside it (the search has to widen).
        let means: Vec<Vec3> = (0..300)
            .map(|k| (v() * if k % 10 == 0 { 4.0 } else { 1.0 }).as_vec3())
            .collect();
        let b = Binding::nearest(&means, &particles, 7, 0.1);
        for (k, m) in means.iter().enumerate() {
            let x = m.as_dvec3();
            let best = (0..particles.len())
                .min_by(|&a, &b| {
                    x.distance_squared(particles[a])
                        .total_cmp(&x.distance_squared(particles[b]))
                })
                .unwrap();
            assert_eq!(b.particle[k], 7 + best as u32, "mean {k}");
            let o = (x - particles[best]).as_vec3();
            assert_eq!(b.offset[k], o);
        }
    }

    #[test]
    fn gaussians_on_their_particles_bind_as_the_identity() {
        let particles: Vec<DVec3> = (0..50)
            .map(|k| {
                DVec3::new(f64::from(k) * 0.013, 0.2, -0.1)
                    .as_vec3()
                    .as_dvec3()
            })
            .collect();
        let means: Vec<Vec3> = particles.iter().map(|p| p.as_vec3()).collect();
        assert_eq!(
            Binding::nearest(&means, &particles, 3, 0.01),
            Binding::identity(3, 50)
        );
    }
}
