//! Real spherical harmonics as used by 3DGS (SPEC §5, §7).
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
