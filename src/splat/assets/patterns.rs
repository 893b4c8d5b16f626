//! Helpers of the procedural assets: hashing, value noise, colour mixing and a few
//! implicit shapes.

use glam::DVec3;

use super::Rgb;

/// A hash of integer lattice coordinates and a salt, uniform in [0, 1).
pub(super) fn hash(i: [i64; 3], salt: u64) -> f64 {
    let mut x = salt.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    for c in i {
        x ^= (c as u64).wrapping_add(0x632B_E59B_D9B4_E019);
        x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
        x ^= x >> 31;
    }
    x = x.wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^= x >> 29;
    (x >> 11) as f64 / (1u64 << 53) as f64
}

/// Three hashes of a cell (a point in the unit cube).
pub(super) fn hash3(i: [i64; 3], salt: u64) -> DVec3 {
    DVec3::new(hash(i, salt), hash(i, salt + 1), hash(i, salt + 2))
}

pub(super) fn cell(p: DVec3, c: f64) -> [i64; 3] {
    let q = (p / c).floor();
    [q.x as i64, q.y as i64, q.z as i64]
}

/// Smooth value noise in [0, 1] with features of size `c`.
pub(super) fn noise(p: DVec3, c: f64, salt: u64) -> f64 {
    let q = p / c;
    let b = q.floor();
    let f = q - b;
    let s = f * f * (DVec3::splat(3.0) - 2.0 * f);
    let mut acc = 0.0;
    for k in 0..8 {
        let o = [(k & 1) as i64, ((k >> 1) & 1) as i64, ((k >> 2) & 1) as i64];
        let w = (if o[0] == 1 { s.x } else { 1.0 - s.x })
            * (if o[1] == 1 { s.y } else { 1.0 - s.y })
            * (if o[2] == 1 { s.z } else { 1.0 - s.z });
        acc += w * hash(
            [b.x as i64 + o[0], b.y as i64 + o[1], b.z as i64 + o[2]],
            salt,
        );
    }
    acc
}

/// Per-point speckle in [−1, 1] on a fine grid `c` (grain of sand, fuzz of a skin).
pub(super) fn speckle(p: DVec3, c: f64, salt: u64) -> f64 {
    2.0 * hash(cell(p, c), salt) - 1.0
}

pub(super) fn mix(a: Rgb, b: Rgb, t: f64) -> Rgb {
    let t = t.clamp(0.0, 1.0) as f32;
    [0, 1, 2].map(|i| a[i] + (b[i] - a[i]) * t)
}

pub(super) fn shade(c: Rgb, f: f64) -> Rgb {
    c.map(|v| (v * f as f32).clamp(0.0, 1.0))
}

pub(super) fn smoothstep(a: f64, b: f64, x: f64) -> f64 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Seeds scattered on a hashed grid: each cell (side `c`) holds, with probability `keep`,
/// one seed centred anywhere in it. Returns the first seed centre among the 27 cells
/// around `p` for which `hit` holds (so seeds up to `c` in size are found whole, and any
/// cut through the solid shows them, not only cuts between cell walls).
pub(super) fn scattered(
    p: DVec3,
    c: f64,
    keep: f64,
    salt: u64,
    hit: impl Fn(DVec3) -> bool,
) -> Option<DVec3> {
    let i0 = cell(p, c);
    for k in 0..27 {
        let i = [
            i0[0] + k % 3 - 1,
            i0[1] + (k / 3) % 3 - 1,
            i0[2] + k / 9 - 1,
        ];
        if hash(i, salt) >= keep {
            continue;
        }
        let lo = DVec3::new(i[0] as f64, i[1] as f64, i[2] as f64) * c;
        let s = lo + c * hash3(i, salt + 7);
        if hit(s) {
            return Some(s);
        }
    }
    None
}

/// Whether `v` (relative to a seed's centre) lies in a teardrop of half length `l` and
/// largest radius `w` along the unit `axis` (blunt end towards +axis).
pub(super) fn teardrop(v: DVec3, axis: DVec3, l: f64, w: f64) -> bool {
    let u = v.dot(axis);
    if u.abs() > l {
        return false;
    }
    let rho = (v - u * axis).length();
    let t = 0.5 * (u / l + 1.0);
    rho <= w * (1.0 - (u / l).powi(2)).sqrt() * (0.45 + 0.55 * t)
}

/// Radial distance below an ellipsoid's surface of a point with normalised radius `r`
/// (the point `p` = r · surface point).
pub(super) fn radial_depth(p: DVec3, r: f64, half: DVec3) -> f64 {
    if r < 1e-9 {
        half.min_element()
    } else {
        (1.0 - r) * p.length() / r
    }
}

/// Signed distance to a box of half extents `b` with edges rounded by `rc`.
pub(super) fn rounded_box(p: DVec3, b: DVec3, rc: f64) -> f64 {
    let q = p.abs() - (b - DVec3::splat(rc));
    q.max(DVec3::ZERO).length() + q.max_element().min(0.0) - rc
}
