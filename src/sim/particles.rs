//! The particle state every part of the simulation shares (docs/method.md §1).

use glam::{DMat3, DVec3, UVec3};

use super::material::Material;

/// Particles as a structure of arrays (docs/method.md §1, the simulated part).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Particles {
    /// Positions x_p.
    pub x: Vec<DVec3>,
    /// Velocities v_p.
    pub v: Vec<DVec3>,
    /// Deformation gradients F_p (the elastic part F_E for NACC).
    pub f: Vec<DMat3>,
    /// APIC affine velocity matrices C_p (the velocity gradient of the last G2P).
    pub c: Vec<DMat3>,
    /// NACC hardening state α_p.
    pub alpha: Vec<f64>,
    /// Masses m_p.
    pub mass: Vec<f64>,
    /// Rest volumes V⁰_p.
    pub volume0: Vec<f64>,
    /// Index into the step's material slice.
    pub material: Vec<u32>,
}

impl Particles {
    /// No particles.
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// The largest particle speed |v_p| (0 without particles).
    pub fn max_speed(&self) -> f64 {
        self.v.iter().map(|v| v.length()).fold(0.0, f64::max)
    }

    /// True when there are no particles.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Adds a particle at rest state F = I, C = 0.
    pub fn push(&mut self, x: DVec3, v: DVec3, mass: f64, volume0: f64, material: u32, alpha: f64) {
        self.x.push(x);
        self.v.push(v);
        self.f.push(DMat3::IDENTITY);
        self.c.push(DMat3::ZERO);
        self.alpha.push(alpha);
        self.mass.push(mass);
        self.volume0.push(volume0);
        self.material.push(material);
    }

    /// Appends all particles of `other`.
    pub fn append(&mut self, other: &Particles) {
        self.x.extend_from_slice(&other.x);
        self.v.extend_from_slice(&other.v);
        self.f.extend_from_slice(&other.f);
        self.c.extend_from_slice(&other.c);
        self.alpha.extend_from_slice(&other.alpha);
        self.mass.extend_from_slice(&other.mass);
        self.volume0.extend_from_slice(&other.volume0);
        self.material.extend_from_slice(&other.material);
    }

    /// Keeps the particles whose position satisfies `keep`, in order.
    pub fn retain_positions(&mut self, keep: impl Fn(DVec3) -> bool) {
        let idx: Vec<usize> = (0..self.len()).filter(|&p| keep(self.x[p])).collect();
        fn pick<T: Copy>(v: &[T], idx: &[usize]) -> Vec<T> {
            idx.iter().map(|&i| v[i]).collect()
        }
        self.x = pick(&self.x, &idx);
        self.v = pick(&self.v, &idx);
        self.f = pick(&self.f, &idx);
        self.c = pick(&self.c, &idx);
        self.alpha = pick(&self.alpha, &idx);
        self.mass = pick(&self.mass, &idx);
        self.volume0 = pick(&self.volume0, &idx);
        self.material = pick(&self.material, &idx);
    }

    /// A regular lattice filling the box [lo, hi]: round((hi − lo)/spacing) points per axis
    /// at lo + (i + ½)·spacing, each with V⁰ = spacing³ and m = ρ V⁰, at rest, material 0,
    /// α = 0. spacing = Δx/2 gives the typical 2³ particles per cell.
    pub fn sample_box(lo: DVec3, hi: DVec3, spacing: f64, density: f64) -> Self {
        let n = ((hi - lo) / spacing).round().max(DVec3::ZERO).as_uvec3();
        let vol = spacing * spacing * spacing;
        let mut out = Particles::new();
        for k in 0..n.z {
            for j in 0..n.y {
                for i in 0..n.x {
                    let x = lo + (UVec3::new(i, j, k).as_dvec3() + 0.5) * spacing;
                    out.push(x, DVec3::ZERO, density * vol, vol, 0, 0.0);
                }
            }
        }
        out
    }

    /// The lattice points of [`Particles::sample_box`] (origin `center − radius`) that lie
    /// strictly inside the ball.
    pub fn sample_sphere(center: DVec3, radius: f64, spacing: f64, density: f64) -> Self {
        let r = DVec3::splat(radius);
        let mut out = Self::sample_box(center - r, center + r, spacing, density);
        out.retain_positions(|x| (x - center).length_squared() < radius * radius);
        out
    }

    /// Sets every particle's material index to `index` and α to `material`'s initial α.
    pub fn set_material(&mut self, index: u32, material: &Material) {
        self.material.iter_mut().for_each(|m| *m = index);
        let a0 = material.initial_alpha();
        self.alpha.iter_mut().for_each(|a| *a = a0);
    }

    /// Σ m_p.
    pub fn total_mass(&self) -> f64 {
        self.mass.iter().sum()
    }

    /// Σ m_p v_p.
    pub fn momentum(&self) -> DVec3 {
        self.mass.iter().zip(&self.v).map(|(m, v)| *m * *v).sum()
    }

    /// Mass-weighted mean position.
    pub fn center_of_mass(&self) -> DVec3 {
        self.mass
            .iter()
            .zip(&self.x)
            .map(|(m, x)| *m * *x)
            .sum::<DVec3>()
            / self.total_mass()
    }

    /// Angular momentum about `origin`. With `apic`, each particle also carries the spin
    /// of its affine field, m_p (Δx²/4) axial(C_p) with axial(A) = (A_zy − A_yz,
    /// A_xz − A_zx, A_yx − A_xy): exactly what P2G puts on the grid (Σ w d × C d =
    /// (Δx²/4) axial(C) since Σ w d dᵀ = Δx²/4 I), so APIC transfers conserve this sum.
    pub fn angular_momentum(&self, origin: DVec3, dx: f64, apic: bool) -> DVec3 {
        let spin = if apic { 0.25 * dx * dx } else { 0.0 };
        (0..self.len())
            .map(|p| {
                let m = self.mass[p];
                (self.x[p] - origin).cross(self.v[p]) * m + axial(self.c[p]) * (m * spin)
            })
            .sum()
    }
}

/// axial(A) = (A_zy − A_yz, A_xz − A_zx, A_yx − A_xy) (twice the axial vector of A's skew
/// part; for A = skew(ω), i.e. A r = ω × r, it is 2ω).
pub fn axial(a: DMat3) -> DVec3 {
    // glam: a.col(c)[r] is row r, column c.
    DVec3::new(
        a.y_axis.z - a.z_axis.y,
        a.z_axis.x - a.x_axis.z,
        a.x_axis.y - a.y_axis.x,
    )
}
