//! Real spherical harmonics as used by 3DGS (docs/method.md §5, §7).
//!
//! The basis and its constants are those of the 3DGS reference implementation, so that
//! trained captures render with the colours they were trained with. Colour is
//! `max(0, 0.5 + Σ_k Y_k(d) · c_k)` with d the unit view direction in the Gaussian's rest
//! frame. The same formulas live in `shaders/sh.wgsl`; keep the two in step.

use glam::Vec3;

pub const C0: f32 = 0.282_094_79;
pub const C1: f32 = 0.488_602_5;
pub const C2: [f32; 5] = [
    1.092_548_4,
    -1.092_548_4,
    0.315_391_57,
    -1.092_548_4,
    0.546_274_2,
];
pub const C3: [f32; 7] = [
    -0.590_043_6,
    2.890_611_4,
    -0.457_045_8,
    0.373_176_34,
    -0.457_045_8,
    1.445_305_7,
    -0.590_043_6,
];

/// Convert an RGB colour in [0, 1] to the DC coefficient that renders as it.
pub fn rgb_to_dc(rgb: [f32; 3]) -> [f32; 3] {
    rgb.map(|c| (c - 0.5) / C0)
}

/// Basis values Y_k(d), k < (degree + 1)², for a unit direction `d`.
pub fn basis(degree: u32, d: Vec3) -> [f32; 16] {
    let mut y = [0.0; 16];
    y[0] = C0;
    if degree == 0 {
        return y;
    }
    let (x, yy, z) = (d.x, d.y, d.z);
    y[1] = -C1 * yy;
    y[2] = C1 * z;
    y[3] = -C1 * x;
    if degree == 1 {
        return y;
    }
    let (xx, y2, zz) = (x * x, yy * yy, z * z);
    let (xy, yz, xz) = (x * yy, yy * z, x * z);
    y[4] = C2[0] * xy;
    y[5] = C2[1] * yz;
    y[6] = C2[2] * (2.0 * zz - xx - y2);
    y[7] = C2[3] * xz;
    y[8] = C2[4] * (xx - y2);
    if degree == 2 {
        return y;
    }
    y[9] = C3[0] * yy * (3.0 * xx - y2);
    y[10] = C3[1] * xy * z;
    y[11] = C3[2] * yy * (4.0 * zz - xx - y2);
    y[12] = C3[3] * z * (2.0 * zz - 3.0 * xx - 3.0 * y2);
    y[13] = C3[4] * x * (4.0 * zz - xx - y2);
    y[14] = C3[5] * z * (xx - y2);
    y[15] = C3[6] * x * (xx - 3.0 * y2);
    y
}

/// Colour of SH coefficients `coeffs` (coefficient-major, `[k * 3 + c]`) seen along the unit
/// rest-frame direction `d`: max(0, 0.5 + Σ Y_k(d) c_k).
pub fn eval(degree: u32, coeffs: &[f32], d: Vec3) -> Vec3 {
    let y = basis(degree, d);
    let k_count = super::sh_coeff_count(degree);
    let mut rgb = Vec3::splat(0.5);
    for (k, yk) in y.iter().enumerate().take(k_count) {
        rgb += *yk * Vec3::new(coeffs[k * 3], coeffs[k * 3 + 1], coeffs[k * 3 + 2]);
    }
    rgb.max(Vec3::ZERO)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dc_round_trips_a_colour() {
        let dc = rgb_to_dc([0.2, 0.5, 0.9]);
        let c = eval(0, &dc, Vec3::X);
        assert!((c - Vec3::new(0.2, 0.5, 0.9)).abs().max_element() < 1e-6);
    }

    #[test]
    fn degree_one_follows_the_view_direction() {
        // Only the z-coefficient (k = 2) of red is set: colour = 0.5 + C1 * z * c.
        let mut coeffs = [0.0f32; 12];
        coeffs[2 * 3] = 0.5;
        for z in [-1.0f32, -0.3, 0.0, 0.7, 1.0] {
            let d = Vec3::new((1.0 - z * z).sqrt(), 0.0, z);
            let c = eval(1, &coeffs, d);
            assert!((c.x - (0.5 + C1 * z * 0.5).max(0.0)).abs() < 1e-6);
        }
    }
}

/// Rotating SH coefficients into the world frame: given coefficients `c` that are evaluated
/// along the rest-frame direction Rᵀd (as the renderer does with a Gaussian's rest-frame
/// rotation R), return c' with eval(c', d) = eval(c, Rᵀd) for every d — what a standard
/// 3DGS viewer, which has no per-Gaussian frame, needs.
///
/// Each band l transforms by a (2l+1)² matrix D_l with Y_l(Rᵀd) = D_l Y_l(d), and c'_l =
/// D_lᵀ c_l. D_l is found numerically: Y_l at K fixed, well-spread directions d_k and at
/// Rᵀd_k, D_l = [Y_l(Rᵀd_k)] · pinv([Y_l(d_k)]) (exact, since the band is closed under
/// rotation; the pseudo-inverse is computed once).
pub struct ShRotator {
    dirs: Vec<glam::DVec3>,
    /// Per band l = 1..=3: pinv of the (2l+1) × K matrix [Y_l(d_k)], as K × (2l+1).
    pinv: [Vec<f64>; 3],
}

const ROT_DIRS: usize = 16;

fn band_range(l: usize) -> std::ops::Range<usize> {
    l * l..(l + 1) * (l + 1)
}

fn basis_f64(d: glam::DVec3) -> [f64; 16] {
    basis(3, d.as_vec3().normalize()).map(f64::from)
}

impl Default for ShRotator {
    fn default() -> Self {
        Self::new()
    }
}

impl ShRotator {
    pub fn new() -> ShRotator {
        // A Fibonacci sphere: well spread, deterministic.
        let dirs: Vec<glam::DVec3> = (0..ROT_DIRS)
            .map(|k| {
                let z = 1.0 - (2.0 * k as f64 + 1.0) / ROT_DIRS as f64;
                let r = (1.0 - z * z).sqrt();
                let phi = k as f64 * std::f64::consts::PI * (3.0 - 5f64.sqrt());
                glam::DVec3::new(r * phi.cos(), r * phi.sin(), z)
            })
            .collect();
        let ys: Vec<[f64; 16]> = dirs.iter().map(|d| basis_f64(*d)).collect();
        let pinv = [1, 2, 3].map(|l| {
            let r = band_range(l);
            let n = r.len();
            // A: n × K. pinv = Aᵀ (A Aᵀ)⁻¹ (K × n).
            let mut aat = vec![0.0; n * n];
            for y in &ys {
                for i in 0..n {
                    for j in 0..n {
                        aat[i * n + j] += y[r.start + i] * y[r.start + j];
                    }
                }
            }
            let inv = invert(&aat, n);
            let mut p = vec![0.0; ROT_DIRS * n];
            for (k, y) in ys.iter().enumerate() {
                for j in 0..n {
                    p[k * n + j] = (0..n).map(|i| y[r.start + i] * inv[i * n + j]).sum();
                }
            }
            p
        });
        ShRotator { dirs, pinv }
    }

    /// World-frame coefficients of `coeffs` (coefficient-major `[k * 3 + c]`, degree
    /// `degree`) for a Gaussian whose rest frame is rotated by `r`.
    pub fn to_world(&self, degree: u32, coeffs: &[f32], r: glam::DQuat) -> Vec<f32> {
        let mut out = coeffs.to_vec();
        let rt = r.conjugate();
        let rotated: Vec<[f64; 16]> = self.dirs.iter().map(|d| basis_f64(rt * *d)).collect();
        for l in 1..=degree as usize {
            let range = band_range(l);
            let n = range.len();
            // D = [Y_l(Rᵀ d_k)] (n × K) · pinv (K × n).
            let mut dmat = vec![0.0; n * n];
            for (k, y) in rotated.iter().enumerate() {
                for i in 0..n {
                    for j in 0..n {
                        dmat[i * n + j] += y[range.start + i] * self.pinv[l - 1][k * n + j];
                    }
                }
            }
            for c in 0..3 {
                for j in 0..n {
                    // c'_j = Σ_i D_ij c_i
                    let v: f64 = (0..n)
                        .map(|i| dmat[i * n + j] * f64::from(coeffs[(range.start + i) * 3 + c]))
                        .sum();
                    out[(range.start + j) * 3 + c] = v as f32;
                }
            }
        }
        out
    }
}

/// Inverse of a small symmetric positive definite n × n matrix (Gauss-Jordan).
fn invert(a: &[f64], n: usize) -> Vec<f64> {
    let mut m = a.to_vec();
    let mut inv: Vec<f64> = (0..n * n)
        .map(|i| if i / n == i % n { 1.0 } else { 0.0 })
        .collect();
    for col in 0..n {
        let piv = (col..n)
            .max_by(|x, y| m[x * n + col].abs().total_cmp(&m[y * n + col].abs()))
            .unwrap_or(col);
        for j in 0..n {
            m.swap(col * n + j, piv * n + j);
            inv.swap(col * n + j, piv * n + j);
        }
        let d = m[col * n + col];
        for j in 0..n {
            m[col * n + j] /= d;
            inv[col * n + j] /= d;
        }
        for row in 0..n {
            if row != col {
                let f = m[row * n + col];
                for j in 0..n {
                    m[row * n + j] -= f * m[col * n + j];
                    inv[row * n + j] -= f * inv[col * n + j];
                }
            }
        }
    }
    inv
}

#[cfg(test)]
mod rotation_tests {
    use super::*;
    use glam::{DQuat, DVec3};

    #[test]
    fn rotated_coefficients_evaluate_like_the_rest_frame() {
        let rot = ShRotator::new();
        let mut rng = crate::rng::SplitMix64::new(9);
        for _ in 0..50 {
            let r = DQuat::from_xyzw(
                rng.uniform() - 0.5,
                rng.uniform() - 0.5,
                rng.uniform() - 0.5,
                rng.uniform() - 0.5,
            )
            .normalize();
            let c: Vec<f32> = (0..48).map(|_| rng.range(-1.0, 1.0)).collect();
            let world = rot.to_world(3, &c, r);
            for _ in 0..20 {
                let d = DVec3::new(
                    rng.uniform() - 0.5,
                    rng.uniform() - 0.5,
                    rng.uniform() - 0.5,
                )
                .normalize();
                let rest = eval(3, &c, (r.conjugate() * d).as_vec3());
                let got = eval(3, &world, d.as_vec3());
                // Compare before the clamp at 0: both are max(0, ·) of equal values.
                assert!((rest - got).abs().max_element() < 2e-4, "{rest} vs {got}");
            }
        }
    }
}
