//! The assets, one function each of a point in object coordinates. `h` is the half extent
//! of the bounding box; colours are display RGB.

use glam::DVec3;

use super::patterns::*;
use super::Rgb;

/// Ellipsoid, long axis x: dark green rind with wavy meridian stripes, a pale inner rind,
/// red flesh, black teardrop seeds in a band halfway to the centre.
pub(super) fn watermelon(p: DVec3, h: DVec3) -> Option<(u16, Rgb)> {
    let r = (p / h).length();
    if r > 1.0 {
        return None;
    }
    let radius = h.y.min(h.z);
    let depth = radial_depth(p, r, h);
    if depth < 0.07 * radius {
        let q = p / h;
        let around = q.z.atan2(q.y);
        let wave = 0.35 * (7.0 * q.x).sin() + 0.15 * (17.0 * q.x + 2.0 * around).sin();
        let stripe = smoothstep(-0.1, 0.35, (9.0 * around + wave * 3.0).sin());
        let light = [0.48, 0.68, 0.26];
        let dark = [0.07, 0.27, 0.07];
        let c = mix(light, dark, stripe);
        return Some((0, shade(c, 1.0 + 0.08 * speckle(p, 0.02 * radius, 1))));
    }
    if depth < 0.12 * radius {
        return Some((
            1,
            mix(
                [0.93, 0.96, 0.78],
                [0.75, 0.9, 0.55],
                smoothstep(0.07, 0.1, depth / radius),
            ),
        ));
    }
    // Seeds: teardrops pointing at the centre, in the band 0.45 < r < 0.72.
    let c = 0.15 * radius;
    let seed = |s: DVec3| {
        (0.45..0.72).contains(&(s / h).length())
            && teardrop(p - s, s.normalize(), 0.38 * c, 0.17 * c)
    };
    if scattered(p, c, 0.9, 11, seed).is_some() {
        return Some((3, [0.05, 0.04, 0.03]));
    }
    let flesh = mix(
        [0.93, 0.2, 0.22],
        [0.98, 0.35, 0.33],
        noise(p, 0.15 * radius, 3),
    );
    Some((2, flesh))
}

/// Rounded cube in one bright colour, a little deeper in tone inside.
pub(super) fn jelly(p: DVec3, h: DVec3) -> Option<(u16, Rgb)> {
    let rc = 0.22 * h.min_element();
    let d = rounded_box(p, h, rc);
    if d > 0.0 {
        return None;
    }
    let t = (-d / (0.5 * h.min_element())).min(1.0);
    Some((0, mix([0.35, 0.95, 0.4], [0.1, 0.65, 0.2], t)))
}

/// The pumpkin's ribbed, dimpled body in normalised coordinates (`q` scaled by the body's
/// half extents); `inset` shrinks it uniformly (0 = the surface).
pub(super) fn pumpkin_body(q: DVec3, inset: f64) -> bool {
    let q = q / (1.0 - inset);
    let phi = q.y.atan2(q.x);
    let groove = (5.0 * phi).cos().abs().powi(6);
    let lobe = 1.0 - 0.09 * groove;
    let rxy = (q.x * q.x + q.y * q.y).sqrt();
    let e2 = 1.0 - (rxy / lobe).powi(2);
    if e2 < 0.0 {
        return false;
    }
    let e = e2.sqrt();
    let dimple = (-(rxy / 0.3).powi(2)).exp();
    q.z <= e - 0.25 * dimple && q.z >= -(e - 0.12 * dimple)
}

/// Oblate and ribbed by 10 lobes: orange skin darker in the grooves, pale flesh, a hollow
/// cavity with flat seeds along its wall, a green-brown stem in the top dimple.
pub(super) fn pumpkin(p: DVec3, h: DVec3) -> Option<(u16, Rgb)> {
    // The body fills z ∈ [−hz, hz − 0.3 hz]; the stem rises above it to hz.
    let bh = 0.85 * h.z;
    let centre = DVec3::new(0.0, 0.0, -h.z + bh);
    let scale = DVec3::new(h.x, h.y, bh);
    let q = (p - centre) / scale;
    let stem_r = 0.07 * h.x.min(h.y);
    let stem_base = centre.z + 0.55 * bh;
    if p.z > stem_base {
        // The stem leans a little towards +x as it rises.
        let t = (p.z - stem_base) / (h.z - stem_base);
        let axis_x = 0.6 * stem_r * t * t;
        let rho = ((p.x - axis_x).powi(2) + p.y * p.y).sqrt();
        let ridge = 1.0 + 0.12 * (6.0 * p.y.atan2(p.x - axis_x)).cos();
        if rho <= stem_r * ridge * (1.0 - 0.25 * t) && !pumpkin_body(q, 0.0) {
            let c = mix([0.38, 0.42, 0.16], [0.5, 0.42, 0.25], t);
            return Some((3, shade(c, 0.85 + 0.15 * ridge)));
        }
    }
    if !pumpkin_body(q, 0.0) {
        return None;
    }
    if !pumpkin_body(q, 0.07) {
        let phi = q.y.atan2(q.x);
        let groove = (5.0 * phi).cos().abs().powi(3);
        let c = mix([0.96, 0.52, 0.1], [0.62, 0.25, 0.04], groove);
        let c = shade(c, 0.92 + 0.08 * q.z + 0.05 * speckle(p, 0.01 * h.x, 5));
        return Some((0, c));
    }
    if pumpkin_body(q, 0.45) {
        // The cavity: empty but for seeds hanging from its wall.
        // Flat oval seeds (normal along the cell's hashed axis) near the cavity wall.
        let c = 0.12 * h.x.min(h.y);
        let seed = |s: DVec3| {
            let axis = (hash3(cell(s, c), 23) - DVec3::splat(0.5)).normalize_or(DVec3::Z);
            let v = p - s;
            let u = v.dot(axis);
            let rho2 = (v - u * axis).length_squared();
            !pumpkin_body((s - centre) / scale, 0.55)
                && (u / (0.1 * c)).powi(2) + rho2 / (0.3 * c).powi(2) <= 1.0
        };
        return scattered(p, c, 0.7, 21, seed).map(|_| (2, [0.96, 0.9, 0.68]));
    }
    Some((
        1,
        mix(
            [1.0, 0.78, 0.38],
            [0.99, 0.72, 0.32],
            noise(p, 0.04 * h.x, 6),
        ),
    ))
}

/// Ellipsoid, long axis x: fuzzy brown skin, green flesh with pale rays, a cream core and a
/// ring of black seeds around it.
pub(super) fn kiwi(p: DVec3, h: DVec3) -> Option<(u16, Rgb)> {
    let q = p / h;
    let r = q.length();
    if r > 1.0 {
        return None;
    }
    if r > 0.94 {
        let c = shade(
            [0.5, 0.36, 0.2],
            1.0 + 0.18 * speckle(p, 0.004 * h.x.max(h.y), 7),
        );
        return Some((0, c));
    }
    let rho = (q.y * q.y + q.z * q.z).sqrt();
    let around = q.z.atan2(q.y);
    if (q.x / 0.85).powi(2) + (rho / 0.2).powi(2) <= 1.0 {
        return Some((2, [0.96, 0.94, 0.8]));
    }
    // Seeds: one per (angle, length) cell of a ring at ρ ≈ 0.34, elongated radially.
    let n = 30.0;
    let a = around / std::f64::consts::TAU * n;
    let (ia, ix) = (a.floor(), (q.x / 0.06).floor());
    let salt_cell = [ia as i64, ix as i64, 0];
    if hash(salt_cell, 31) < 0.85 && q.x.abs() < 0.8 {
        let jit = hash3(salt_cell, 32);
        let ac = ia + 0.3 + 0.4 * jit.x;
        let xc = (ix + 0.3 + 0.4 * jit.y) * 0.06;
        let rc = 0.3 + 0.08 * jit.z;
        let d_rho = (rho - rc) / 0.07;
        let d_arc = (a - ac) / n * std::f64::consts::TAU * rc / 0.025;
        let d_x = (q.x - xc) / 0.04;
        if d_rho * d_rho + d_arc * d_arc + d_x * d_x <= 1.0 {
            return Some((3, [0.04, 0.03, 0.02]));
        }
    }
    let rays = smoothstep(0.6, 1.0, (around * 40.0 + 3.0 * rho).sin()) * (1.0 - rho);
    let c = mix(
        [0.42, 0.7, 0.12],
        [0.78, 0.88, 0.45],
        0.4 * rays + 0.4 * (1.0 - rho / 0.9),
    );
    Some((1, c))
}

/// Geometry shared by the pineapple's body tests: normalised height, radius and the
/// diamond cell coordinates of its eyes.
struct PineBody {
    qz: f64,
    rho: f64,
    /// Distance from the nearest eye centre in the diamond lattice, in [0, 1].
    eye: f64,
}

impl PineBody {
    fn new(p: DVec3, h: DVec3, centre_z: f64, bh: f64) -> PineBody {
        let qz = (p.z - centre_z) / bh;
        let rho = (p.x * p.x / (h.x * h.x) + p.y * p.y / (h.y * h.y)).sqrt();
        let turns = p.y.atan2(p.x) / std::f64::consts::TAU * 8.0;
        let (u, v) = (turns + qz * 5.0, turns - qz * 5.0);
        // rem_euclid, not fract: fract keeps the sign, which breaks the pattern at u < 0.
        let (du, dv) = (u.rem_euclid(1.0) - 0.5, v.rem_euclid(1.0) - 0.5);
        let eye = (2.0 * du.abs().max(dv.abs())).clamp(0.0, 1.0);
        PineBody { qz, rho, eye }
    }

    /// The barrel's radius at this height, with the eyes bulging out.
    fn radius(&self) -> f64 {
        let barrel = (1.0 - self.qz.abs().powf(2.5)).max(0.0).powf(0.45);
        0.95 * barrel * (1.0 + 0.04 * (1.0 - self.eye))
    }
}

/// A barrel with a diamond pattern of eyes, pale yellow flesh, a fibrous core and a crown
/// of long green leaves.
pub(super) fn pineapple(p: DVec3, h: DVec3) -> Option<(u16, Rgb)> {
    let crown_h = 0.36 * 2.0 * h.z;
    let bh = (2.0 * h.z - crown_h) / 2.0;
    let centre_z = -h.z + bh;
    let b = PineBody::new(p, h, centre_z, bh);
    let radius = b.radius();
    if b.qz.abs() <= 1.0 && b.rho <= radius {
        if b.rho > radius - 0.08 {
            let c = if b.eye < 0.3 {
                mix([0.28, 0.16, 0.05], [0.6, 0.38, 0.1], b.eye / 0.3)
            } else if b.eye < 0.86 {
                [0.9, 0.62, 0.18]
            } else {
                [0.45, 0.38, 0.1]
            };
            return Some((0, shade(c, 1.0 + 0.06 * speckle(p, 0.003, 41))));
        }
        if b.rho < 0.2 {
            let fibre = 0.5 + 0.5 * (p.y.atan2(p.x) * 14.0).sin();
            return Some((2, mix([0.97, 0.93, 0.7], [0.9, 0.85, 0.55], fibre)));
        }
        return Some((1, mix([1.0, 0.9, 0.45], [0.98, 0.82, 0.3], b.rho)));
    }
    crown_leaf(p, h, centre_z + 0.9 * bh)
}

/// The pineapple's crown: 14 straight, tapering, keeled leaves from the top of the body,
/// steeper in the middle.
pub(super) fn crown_leaf(p: DVec3, h: DVec3, base_z: f64) -> Option<(u16, Rgb)> {
    // Leaves rise from the base: nothing far below it (a keeled leaf dips ≤ 0.11 hx).
    if p.z < base_z - 0.2 * h.x {
        return None;
    }
    let base = DVec3::new(0.0, 0.0, base_z);
    let n = 14;
    for i in 0..n {
        let f = i as f64 / (n - 1) as f64;
        let phi = 2.399_963 * i as f64;
        let tilt = 0.15 + 0.85 * f;
        let d = DVec3::new(tilt.sin() * phi.cos(), tilt.sin() * phi.sin(), tilt.cos());
        // Long enough to reach the box top (inner leaves) or its side (outer ones).
        let len = ((h.z - base_z) / d.z.max(1e-3)).min(0.95 * h.x.min(h.y) / tilt.sin().max(1e-3));
        let rel = p - base;
        let t = rel.dot(d) / len;
        if !(0.0..=1.0).contains(&t) {
            continue;
        }
        let side = DVec3::new(-phi.sin(), phi.cos(), 0.0);
        let normal = d.cross(side);
        let lat = rel.dot(side);
        let width = 0.16 * h.x * (1.0 - t).powf(0.8) * (0.5 + 2.0 * t).min(1.0);
        let keel = rel.dot(normal) - 0.35 * lat.abs();
        if lat.abs() <= width && keel.abs() <= 0.05 * h.x {
            let c = mix([0.16, 0.42, 0.14], [0.45, 0.62, 0.28], t);
            return Some((3, shade(c, 1.0 - 0.25 * (lat.abs() / width.max(1e-9)))));
        }
    }
    None
}

/// Ovoid magenta body with flame-like bracts (pink, green at the tips) in a spiral, white
/// flesh with small black seeds.
pub(super) fn dragonfruit(p: DVec3, h: DVec3) -> Option<(u16, Rgb)> {
    let bh = DVec3::new(0.74 * h.x, 0.74 * h.y, 0.8 * h.z);
    let centre = DVec3::new(0.0, 0.0, -0.2 * h.z);
    let q = (p - centre) / bh;
    let r = q.length();
    if r <= 1.0 {
        if r > 0.93 {
            let c = shade([0.9, 0.12, 0.45], 1.0 + 0.06 * speckle(p, 0.004, 51));
            return Some((0, c));
        }
        let c = 0.07 * bh.x;
        let seed = |s: DVec3| (p - s).length() <= 0.18 * c && ((s - centre) / bh).length() < 0.88;
        if scattered(p, c, 0.6, 53, seed).is_some() {
            return Some((3, [0.03, 0.03, 0.03]));
        }
        return Some((2, [0.97, 0.96, 0.93]));
    }
    bract(p, h, centre, bh)
}

/// One of the dragonfruit's bracts: a flat tongue leaving the surface upwards and
/// outwards, magenta at the base, green at the tip.
pub(super) fn bract(p: DVec3, h: DVec3, centre: DVec3, bh: DVec3) -> Option<(u16, Rgb)> {
    let n = 22;
    for i in 0..n {
        let f = (i as f64 + 0.5) / n as f64;
        let phi = 2.399_963 * i as f64;
        // Base on the surface at height qz, from low on the body to near the top.
        let qz = -0.75 + 1.55 * f;
        let ring = (1.0 - qz * qz).sqrt();
        let out = DVec3::new(ring * phi.cos(), ring * phi.sin(), qz);
        let base = centre + out * bh * 0.96;
        let normal = (out / bh).normalize();
        let up = (DVec3::Z - normal * normal.z).normalize_or(DVec3::X);
        let d = (up * 0.75 + normal * 0.66).normalize();
        let len = 0.5 * bh.x;
        let rel = p - base;
        let t = rel.dot(d) / len;
        if !(0.0..=1.0).contains(&t) {
            continue;
        }
        let side = d.cross(normal).normalize();
        let flat = d.cross(side);
        let width = 0.28 * len * (1.0 - t).powf(0.7);
        if rel.dot(side).abs() <= width && rel.dot(flat).abs() <= 0.07 * bh.x {
            let c = mix(
                [0.92, 0.16, 0.5],
                [0.5, 0.72, 0.2],
                smoothstep(0.45, 0.9, t),
            );
            return Some((1, c));
        }
    }
    let _ = h;
    None
}

/// Whether (a, b) (normalised in the slice's plane) is inside the bread slice outline,
/// shrunk by `ia`, `ib`: a rounded rectangle below and a wider dome on top.
pub(super) fn slice_outline(a: f64, b: f64, ia: f64, ib: f64) -> bool {
    let rect = DVec3::new(a, b + 0.35, 0.0);
    let in_rect = rounded_box(rect, DVec3::new(0.86 - ia, 0.65 - ib, 1.0), 0.12) <= 0.0;
    let dome = (a / (1.0 - ia)).powi(2) + ((b - 0.3) / (0.7 - ib)).powi(2) <= 1.0;
    in_rect || dome
}

/// A slice of bread lying flat (thickness along z): brown crust around the outline, light
/// crumb with pores on the faces and inside.
pub(super) fn toast(p: DVec3, h: DVec3) -> Option<(u16, Rgb)> {
    let (a, b) = (p.x / h.x, p.y / h.y);
    if !slice_outline(a, b, 0.0, 0.0) {
        return None;
    }
    let crust = 0.06 * h.x.min(h.y);
    if !slice_outline(a, b, crust / h.x, crust / h.y) {
        let c = shade([0.62, 0.36, 0.13], 1.0 + 0.1 * speckle(p, 0.002, 61));
        return Some((0, c));
    }
    // Pores: holes, with a darker rim.
    let c = 0.07 * h.x.min(h.y);
    let pore = |s: DVec3| (p - s).length() <= 0.4 * c;
    if let Some(s) = scattered(p, c, 0.25, 63, pore) {
        if (p - s).length() <= 0.28 * c {
            return None;
        }
        return Some((1, [0.86, 0.74, 0.52]));
    }
    let c = mix(
        [0.98, 0.92, 0.76],
        [0.93, 0.83, 0.6],
        noise(p, 0.02 * h.x, 65),
    );
    Some((1, c))
}

/// Whether `p` is in a crenellated cylinder tower (axis `at`, radius `r`, from z = `z0` to
/// `z1`, 8 merlons around the top ring).
pub(super) fn tower(p: DVec3, at: [f64; 2], r: f64, z0: f64, z1: f64) -> bool {
    let (dx, dy) = (p.x - at[0], p.y - at[1]);
    let rho = (dx * dx + dy * dy).sqrt();
    if rho > r || p.z < z0 || p.z > z1 {
        return false;
    }
    let merlon_h = 0.18 * r;
    if p.z < z1 - merlon_h {
        return true;
    }
    rho > 0.65 * r && (8.0 * dy.atan2(dx)).cos() > 0.0
}

/// A square base with four crenellated corner towers, crenellated walls between them and
/// a taller central keep; sand-coloured with grain, darker (wetter) at the bottom.
pub(super) fn sandcastle(p: DVec3, h: DVec3) -> Option<(u16, Rgb)> {
    let height = 2.0 * h.z;
    let z = |f: f64| -h.z + f * height;
    let base_top = z(0.18);
    let taper = 1.0 - 0.08 * ((p.z + h.z) / (base_top + h.z)).clamp(0.0, 1.0);
    let in_base = p.z <= base_top && p.x.abs() <= h.x * taper && p.y.abs() <= h.y * taper;
    let m = h.x.min(h.y);
    let corner = [0.7 * h.x, 0.7 * h.y];
    let towers = [[1.0, 1.0], [-1.0, 1.0], [1.0, -1.0], [-1.0, -1.0]]
        .iter()
        .any(|s| {
            tower(
                p,
                [s[0] * corner[0], s[1] * corner[1]],
                0.26 * m,
                base_top,
                z(0.8),
            )
        });
    let keep = tower(p, [0.0, 0.0], 0.28 * m, base_top, h.z);
    // Walls along the four sides between the towers, notched on top.
    let wall_top = z(0.55);
    let notched = p.z < wall_top - 0.05 * height || (p.x + p.y).rem_euclid(0.12 * m) < 0.06 * m;
    let on_side = (p.x.abs() - corner[0]).abs() <= 0.06 * m && p.y.abs() <= corner[1]
        || (p.y.abs() - corner[1]).abs() <= 0.06 * m && p.x.abs() <= corner[0];
    let wall = on_side && p.z > base_top && p.z <= wall_top && notched;
    if !(in_base || towers || keep || wall) {
        return None;
    }
    let grain = 1.0 + 0.09 * speckle(p, 0.003, 71) + 0.05 * (noise(p, 0.05 * m, 72) - 0.5);
    let wet = smoothstep(0.12, 0.0, (p.z + h.z) / height);
    let c = mix([0.88, 0.76, 0.53], [0.66, 0.53, 0.36], wet);
    Some((0, shade(c, grain)))
}

/// A puffy cushion: thickness falls to a thin seam at the edge; fabric on the outside with
/// a fine weave, white stuffing inside, darker piping along the seam.
pub(super) fn pillow(p: DVec3, h: DVec3) -> Option<(u16, Rgb)> {
    let (a, b) = (p.x / h.x, p.y / h.y);
    let puff = ((1.0 - a.powi(4)).max(0.0) * (1.0 - b.powi(4)).max(0.0)).sqrt();
    let seam = 0.1;
    let half_t = h.z * puff.max(seam);
    if p.z.abs() > half_t {
        return None;
    }
    if a.abs().max(b.abs()) > 0.95 {
        return Some((2, [0.3, 0.35, 0.55]));
    }
    if half_t - p.z.abs() < 0.15 * h.z {
        let weave = 0.04 * ((p.x * 700.0).sin() * (p.y * 700.0).sin()).signum();
        let c = shade([0.7, 0.78, 0.92], 1.0 + weave - 0.1 * (1.0 - puff));
        return Some((0, c));
    }
    Some((1, [0.97, 0.97, 0.95]))
}

/// A thin sheet (the whole box) in red-and-white gingham.
pub(super) fn cloth(p: DVec3, h: DVec3) -> Option<(u16, Rgb)> {
    let period = 0.2 * h.x.max(h.y);
    let sx = (p.x / period).rem_euclid(1.0) < 0.5;
    let sy = (p.y / period).rem_euclid(1.0) < 0.5;
    let c = match (sx, sy) {
        (true, true) => [0.72, 0.1, 0.12],
        (true, false) | (false, true) => [0.9, 0.55, 0.55],
        (false, false) => [0.96, 0.94, 0.9],
    };
    Some((0, c))
}

/// A table: a top with rounded corners on four square legs; wood with grain along x on
/// the top and along z on the legs.
pub(super) fn table(p: DVec3, h: DVec3) -> Option<(u16, Rgb)> {
    let top_t = 0.1 * h.z;
    let wood = [0.62, 0.4, 0.22];
    if p.z >= h.z - 2.0 * top_t {
        let centre = DVec3::new(0.0, 0.0, h.z - top_t);
        let rc = 0.05 * h.x.min(h.y);
        if rounded_box(p - centre, DVec3::new(h.x, h.y, top_t), rc.min(0.9 * top_t)) > 0.0 {
            return None;
        }
        let grain = (p.y * 120.0 / h.y.max(0.1) + 3.0 * noise(p, 0.1 * h.x, 81)).sin();
        return Some((0, shade(wood, 1.0 + 0.1 * grain)));
    }
    let leg = 0.07 * h.x.min(h.y);
    let (lx, ly) = (h.x - 1.5 * leg, h.y - 1.5 * leg);
    let in_leg = (p.x.abs() - lx).abs() <= leg && (p.y.abs() - ly).abs() <= leg;
    if !in_leg {
        return None;
    }
    let grain = (p.x * 500.0 + 2.0 * noise(p, 0.05 * h.z, 83)).sin();
    Some((1, shade(wood, 0.9 + 0.08 * grain)))
}

/// A kitchen knife along x: a dark handle with two rivets, a thin steel blade whose edge
/// curves up to the tip at the spine.
pub(super) fn knife(p: DVec3, h: DVec3) -> Option<(u16, Rgb)> {
    let length = 2.0 * h.x;
    let blade_start = -h.x + 0.38 * length;
    if p.x < blade_start {
        // Handle: an elliptic cross-section in y–z, hanging from the spine line.
        let hh = 0.3 * h.z;
        let zc = h.z - 1.2 * hh;
        let u = (p.x - (-h.x)) / (blade_start + h.x);
        let round = 1.0 - (2.0 * u - 1.0).powi(8);
        if (p.y / h.y).powi(2) + ((p.z - zc) / hh).powi(2) > round {
            return None;
        }
        let rivet = [0.3, 0.7].iter().any(|f| {
            let x = -h.x + f * (blade_start + h.x);
            ((p.x - x).powi(2) + (p.z - zc).powi(2)).sqrt() < 0.35 * hh
        });
        let c = if rivet {
            [0.8, 0.8, 0.78]
        } else {
            [0.16, 0.1, 0.07]
        };
        return Some((1, c));
    }
    let t = (p.x - blade_start) / (h.x - blade_start);
    let edge = -h.z + 2.0 * h.z * t.powi(4);
    if p.z < edge || p.z > h.z {
        return None;
    }
    // Thickest at the spine, thinning to the edge (a lattice layer at y = 0 always fits).
    let f = (p.z - edge) / (h.z - edge).max(1e-12);
    if p.y.abs() > 0.3 * h.y * (0.2 + 0.8 * f) {
        return None;
    }
    let c = mix(
        [0.93, 0.94, 0.96],
        [0.7, 0.72, 0.76],
        smoothstep(0.0, 0.3, f),
    );
    Some((0, c))
}

/// A ball (an ellipsoid for unequal sizes): red with a white band around its equator.
pub(super) fn projectile(p: DVec3, h: DVec3) -> Option<(u16, Rgb)> {
    let q = p / h;
    if q.length() > 1.0 {
        return None;
    }
    let c = if q.z.abs() < 0.12 {
        [0.95, 0.95, 0.92]
    } else {
        [0.85, 0.12, 0.08]
    };
    Some((0, c))
}
