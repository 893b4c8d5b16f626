//! Relighting (docs/method.md §8): per-Gaussian normals and Blinn-Phong shading under moving point
//! lights with shadows. The method and its choices are in `docs/relighting.md`.
//!
//! This module holds the CPU side: the shading model ([`blinn_phong`], the twin of
//! `shaders/render/lighting.wgsl`), PCA normals ([`normals`]), the shadow volume's CPU
//! reference ([`shadow`]) and the normal packing shared with the GPU ([`oct_encode`]). The
//! GPU passes live in `src/render/gpu/lighting.rs`.

pub mod normals;
pub mod shadow;

use glam::{Vec2, Vec3};

/// Per-object shading weights of the Blinn-Phong model; the defaults are the paper's public
/// code's (ambient 0.8, diffuse 0.4, specular 0.1, shininess 32).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingParams {
    pub ambient: f32,
    pub diffuse: f32,
    pub specular: f32,
    pub shininess: f32,
}

impl Default for ShadingParams {
    fn default() -> Self {
        ShadingParams {
            ambient: 0.8,
            diffuse: 0.4,
            specular: 0.1,
            shininess: 32.0,
        }
    }
}

/// A point light at one instant: `radiance` is its colour times its intensity (I_L,m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    pub position: Vec3,
    pub radiance: Vec3,
}

/// The most point lights a frame may have (`MAX_LIGHTS` in `shaders/render/lighting.wgsl`).
pub const MAX_LIGHTS: usize = 8;

/// Blinn-Phong of one Gaussian (docs/method.md §8, the paper's eq. A20) with per-object weights:
///
///   L = k_a c0 ⊙ I_a + Σ_m T_m (c0 ⊙ I_L,m) (k_d D_m + k_s S_m) / r_m²,
///   D_m = max(n·l_m, 0),  S_m = max(n·h_m, 0)^shininess,  h_m = normalize(l_m + v),
///
/// with c0 the Gaussian's own colour, p its centre, n its unit normal, v the unit direction
/// from p to the eye, l_m the unit direction from p to light m at distance r_m, T_m ∈ [0, 1]
/// the light's visibility from p (`visibility[m]`, 1 when shorter than `lights`).
#[allow(clippy::too_many_arguments)] // the formula's own inputs, named as in docs/method.md §8
pub fn blinn_phong(
    c0: Vec3,
    p: Vec3,
    n: Vec3,
    eye: Vec3,
    ambient: Vec3,
    lights: &[PointLight],
    visibility: &[f32],
    w: &ShadingParams,
) -> Vec3 {
    let v = (eye - p).normalize_or_zero();
    // Two-sided, as the shade pass: a normal facing away from the eye is flipped.
    let n = if n.dot(v) < 0.0 { -n } else { n };
    let mut out = w.ambient * c0 * ambient;
    for (m, light) in lights.iter().enumerate() {
        let to_light = light.position - p;
        let r2 = to_light.length_squared().max(1e-12);
        let l = to_light / r2.sqrt();
        let h = (l + v).normalize_or_zero();
        let d = n.dot(l).max(0.0);
        let s = n.dot(h).max(0.0).powf(w.shininess);
        let t = visibility.get(m).copied().unwrap_or(1.0);
        out += t * c0 * light.radiance * (w.diffuse * d + w.specular * s) / r2;
    }
    out
}

/// The packed value of "no normal" (both halves −32768, which [`oct_encode`] never makes).
pub const NO_NORMAL: u32 = 0x8000_8000;

/// A unit normal packed into one u32: octahedral map onto [−1, 1]², two 16-bit snorms
/// (x in the low half). Angular error below 0.05°. A zero or non-finite vector packs to
/// [`NO_NORMAL`].
pub fn oct_encode(n: Vec3) -> u32 {
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    if !l1.is_finite() || l1 <= 0.0 {
        return NO_NORMAL;
    }
    let p = Vec2::new(n.x, n.y) / l1;
    let e = if n.z < 0.0 {
        (Vec2::ONE - Vec2::new(p.y.abs(), p.x.abs())) * Vec2::new(sign(p.x), sign(p.y))
    } else {
        p
    };
    let q = |x: f32| ((x.clamp(-1.0, 1.0) * 32767.0).round() as i32 as u32) & 0xffff;
    q(e.x) | (q(e.y) << 16)
}

/// Inverse of [`oct_encode`] (`oct_decode` in `shaders/render/lighting.wgsl`).
pub fn oct_decode(bits: u32) -> Vec3 {
    if bits == NO_NORMAL {
        return Vec3::ZERO;
    }
    let s = |h: u32| (f32::from(h as u16 as i16) / 32767.0).max(-1.0);
    let e = Vec2::new(s(bits & 0xffff), s(bits >> 16));
    let z = 1.0 - e.x.abs() - e.y.abs();
    let t = (-z).max(0.0);
    let xy = e - Vec2::new(sign(e.x), sign(e.y)) * t;
    Vec3::new(xy.x, xy.y, z).normalize()
}

fn sign(x: f32) -> f32 {
    if x >= 0.0 {
        1.0
    } else {
        -1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn octahedral_packing_round_trips_within_five_hundredths_of_a_degree() {
        let mut rng = crate::rng::SplitMix64::new(7);
        let mut worst = 0.0f32;
        for i in 0..20_000 {
            let n = if i < 6 {
                [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z][i]
            } else {
                Vec3::new(
                    rng.uniform() as f32 - 0.5,
                    rng.uniform() as f32 - 0.5,
                    rng.uniform() as f32 - 0.5,
                )
                .normalize()
            };
            let back = oct_decode(oct_encode(n));
            worst = worst.max(n.dot(back).clamp(-1.0, 1.0).acos().to_degrees());
        }
        assert!(worst < 0.05, "worst angle {worst}°");
        assert_eq!(oct_encode(Vec3::ZERO), NO_NORMAL);
        assert_eq!(oct_decode(NO_NORMAL), Vec3::ZERO);
    }

    #[test]
    fn blinn_phong_follows_the_formula_for_one_light() {
        let w = ShadingParams::default();
        let c0 = Vec3::new(0.5, 0.4, 0.2);
        let light = PointLight {
            position: Vec3::new(0.0, 0.0, 2.0),
            radiance: Vec3::splat(4.0),
        };
        // Light, eye and normal along +z: D = S = 1, r = 2.
        let out = blinn_phong(
            c0,
            Vec3::ZERO,
            Vec3::Z,
            Vec3::new(0.0, 0.0, 5.0),
            Vec3::ONE,
            &[light],
            &[1.0],
            &w,
        );
        let want = c0 * 0.8 + c0 * 4.0 * (0.4 + 0.1) / 4.0;
        assert!((out - want).abs().max_element() < 1e-6, "{out} vs {want}");
        // In full shadow only the ambient term is left.
        let dark = blinn_phong(
            c0,
            Vec3::ZERO,
            Vec3::Z,
            Vec3::new(0.0, 0.0, 5.0),
            Vec3::ONE,
            &[light],
            &[0.0],
            &w,
        );
        assert!((dark - c0 * 0.8).abs().max_element() < 1e-6);
        // A light behind the surface (as seen from the eye) adds nothing, and a normal
        // pointing away from the eye is flipped toward it (two-sided).
        let behind = PointLight {
            position: Vec3::new(0.0, 0.0, -2.0),
            ..light
        };
        let away = blinn_phong(
            c0,
            Vec3::ZERO,
            Vec3::Z,
            Vec3::new(0.0, 0.0, 5.0),
            Vec3::ONE,
            &[behind],
            &[1.0],
            &w,
        );
        let flipped = blinn_phong(
            c0,
            Vec3::ZERO,
            -Vec3::Z,
            Vec3::new(0.0, 0.0, 5.0),
            Vec3::ONE,
            &[light],
            &[1.0],
            &w,
        );
        assert!((flipped - out).abs().max_element() < 1e-6);
        assert!((away - c0 * 0.8).abs().max_element() < 1e-6);
    }
}
