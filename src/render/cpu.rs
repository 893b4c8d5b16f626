//! The CPU reference renderer: the same math as the GPU passes (projection, SH colour,
//! tile rectangles, front-to-back compositing with the same thresholds), written as a plain
//! per-pixel loop over depth-sorted Gaussians. It is the oracle the GPU renderer is tested
//! against, and slow on purpose: clarity over speed.

use glam::{Mat3, Vec2, Vec3};
use rayon::prelude::*;

use super::gpu::layout::{FOV_CLAMP, TILE};
use super::gpu::{PassImages, PassSet};
use super::splats::mat3_from_sym3;
use super::{Camera, Splats};
use crate::splat::sh;

/// A Gaussian projected to the screen.
#[derive(Clone, Copy, Debug)]
pub struct ProjectedGaussian {
    pub index: usize,
    pub depth: f32,
    pub xy: Vec2,
    /// Inverse 2D covariance (a, b, c) of [[a, b], [b, c]].
    pub conic: Vec3,
    pub opacity: f32,
    pub color: Vec3,
    /// The normal pass's normal: the axis of least extent turned towards the camera, in
    /// camera space, quantised as the GPU's (`normal_code`); zero where there is none.
    pub normal: Vec3,
    /// Tile rectangle [min, max).
    pub tile_min: (u32, u32),
    pub tile_max: (u32, u32),
}

/// Compositing skips α below this.
pub const MIN_ALPHA: f32 = 1.0 / 255.0;

/// Standard deviations the screen radius spans: 3 (docs/method.md §7), or the distance at which
/// α = ω·exp(−r²/2) drops below 1/255 when that is nearer, r = sqrt(2 ln(255 ω)). The
/// tiles this leaves out hold only pixels that compositing skips, so images are unchanged.
pub fn extent_sigmas(opacity: f32) -> f32 {
    (2.0 * (opacity / MIN_ALPHA).ln()).sqrt().min(3.0)
}

/// dᵀ C d for the conic C = [[a, b], [b, c]] stored as (a, b, c).
fn conic_form(d: Vec2, conic: Vec3) -> f32 {
    conic.x * d.x * d.x + 2.0 * conic.y * d.x * d.y + conic.z * d.y * d.y
}

/// Smallest dᵀ C d over the segment d0 + t e, t ∈ [0, 1].
fn conic_min_on_segment(d0: Vec2, e: Vec2, conic: Vec3) -> f32 {
    let ce = Vec2::new(conic.x * e.x + conic.y * e.y, conic.y * e.x + conic.z * e.y);
    let t = (-ce.dot(d0) / e.dot(ce)).clamp(0.0, 1.0);
    conic_form(d0 + t * e, conic)
}

/// Does the footprint ellipse dᵀ C d ≤ k² reach the rectangle spanned by the pixel centres
/// of tile (tx, ty)? The mean inside it, or the ellipse crossing one of its edges.
pub fn ellipse_touches_tile(xy: Vec2, conic: Vec3, k2: f32, tx: u32, ty: u32) -> bool {
    let lo = Vec2::new((tx * TILE) as f32, (ty * TILE) as f32) + 0.5;
    let span = (TILE - 1) as f32;
    let hi = lo + span;
    if xy.cmpge(lo).all() && xy.cmple(hi).all() {
        return true;
    }
    let d = lo - xy;
    let m = conic_min_on_segment(d, Vec2::new(span, 0.0), conic)
        .min(conic_min_on_segment(
            d + Vec2::new(0.0, span),
            Vec2::new(span, 0.0),
            conic,
        ))
        .min(
            conic_min_on_segment(d, Vec2::new(0.0, span), conic).min(conic_min_on_segment(
                d + Vec2::new(span, 0.0),
                Vec2::new(0.0, span),
                conic,
            )),
        );
    m <= k2
}

/// Project Gaussian `i` (docs/method.md §7); `None` when culled or degenerate.
pub fn project_gaussian(splats: &Splats, i: usize, camera: &Camera) -> Option<ProjectedGaussian> {
    let mean = splats.means[i];
    let opacity = splats.opacities[i];
    let w = camera.world_to_camera();
    let t = w * (mean - camera.position);
    if !mean.is_finite() || t.z < camera.near || opacity < MIN_ALPHA {
        return None;
    }
    let (tan_x, tan_y) = camera.tan_half_fov();
    let (lim_x, lim_y) = (FOV_CLAMP * tan_x, FOV_CLAMP * tan_y);
    let (fx, fy) = (camera.fx, camera.fy);
    let tz = t.z;
    let tx = (t.x / tz).clamp(-lim_x, lim_x) * tz;
    let ty = (t.y / tz).clamp(-lim_y, lim_y) * tz;
    let j0 = Vec3::new(fx / tz, 0.0, -fx * tx / (tz * tz));
    let j1 = Vec3::new(0.0, fy / tz, -fy * ty / (tz * tz));
    // Rows of T = J W, as column vectors Wᵀ j_i.
    let wt: Mat3 = w.transpose();
    let t0 = wt * j0;
    let t1 = wt * j1;
    let sigma = mat3_from_sym3(splats.covariances[i]);
    let a = t0.dot(sigma * t0) + 0.3;
    let b = t0.dot(sigma * t1);
    let c = t1.dot(sigma * t1) + 0.3;
    let det = a * c - b * b;
    if !det.is_finite() || det <= 0.0 {
        return None;
    }
    let conic = Vec3::new(c / det, -b / det, a / det);
    let mid = 0.5 * (a + c);
    let lambda1 = mid + (mid * mid - det).max(0.1).sqrt();
    let radius = (extent_sigmas(opacity) * lambda1.sqrt()).ceil();
    let (cx, cy) = camera.principal_point();
    let xy = Vec2::new(fx * t.x / tz + cx, fy * t.y / tz + cy);
    let tiles = Vec2::new(
        camera.width.div_ceil(TILE) as f32,
        camera.height.div_ceil(TILE) as f32,
    );
    let tile = TILE as f32;
    let rmin = ((xy - radius) / tile).floor().clamp(Vec2::ZERO, tiles);
    let rmax = ((xy + radius + (tile - 1.0)) / tile)
        .floor()
        .clamp(Vec2::ZERO, tiles);
    if !(rmax.x > rmin.x && rmax.y > rmin.y) {
        return None;
    }
    let dir = (mean - camera.position).normalize();
    let local = splats.rotations[i].conjugate() * dir;
    let stride = splats.sh_stride();
    let color = sh::eval(
        splats.sh_degree,
        &splats.sh[i * stride..(i + 1) * stride],
        local,
    );
    let axis = least_axis(splats.covariances[i]);
    let facing = if axis.dot(camera.position - mean) < 0.0 {
        -axis
    } else {
        axis
    };
    Some(ProjectedGaussian {
        index: i,
        depth: tz,
        xy,
        conic,
        opacity,
        color,
        normal: normal_from_code(normal_code(w * facing)),
        tile_min: (rmin.x as u32, rmin.y as u32),
        tile_max: (rmax.x as u32, rmax.y as u32),
    })
}

/// How far apart, as a share of the trace, the two smallest eigenvalues of a covariance
/// must lie for [`least_axis`] to name an axis (the GPU's too): closer, the Gaussian is a
/// sphere or a needle, and no axis stands out.
pub const LEAST_AXIS_GAP: f64 = 0.01;

/// The axis of least extent of a covariance (the eigenvector of its smallest eigenvalue,
/// by Jacobi rotations: `project.wgsl` solves the cubic instead), the normal of a flat
/// Gaussian; zero where no axis stands out ([`LEAST_AXIS_GAP`]).
pub fn least_axis(cov: super::splats::Sym3) -> Vec3 {
    let sigma = mat3_from_sym3(cov);
    let trace = sigma.x_axis.x + sigma.y_axis.y + sigma.z_axis.z;
    if trace.is_nan() || trace <= 0.0 || !trace.is_finite() {
        return Vec3::ZERO;
    }
    let (lambda, v) = crate::sim::svd::symmetric_eigen(sigma.as_dmat3() / f64::from(trace));
    // λ sorted descending: the last two are the smallest.
    if lambda.y - lambda.z < LEAST_AXIS_GAP {
        return Vec3::ZERO;
    }
    v.z_axis.as_vec3().normalize()
}

/// A unit normal as a whole number an f32 holds exactly: the octahedral map onto [−1, 1]²,
/// 12 bits a coordinate, 1 + u·4096 + v; 0 for a zero or non-finite vector. The GPU packs
/// the normal pass's normals so (`normal_code` in `shaders/common.wgsl`).
pub fn normal_code(n: Vec3) -> f32 {
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    if l1.is_nan() || l1 <= 0.0 || !l1.is_finite() {
        return 0.0;
    }
    let mut e = Vec2::new(n.x, n.y) / l1;
    if n.z < 0.0 {
        let sgn = Vec2::new(
            if e.x >= 0.0 { 1.0 } else { -1.0 },
            if e.y >= 0.0 { 1.0 } else { -1.0 },
        );
        e = (Vec2::ONE - Vec2::new(e.y.abs(), e.x.abs())) * sgn;
    }
    let q = ((e.clamp(Vec2::NEG_ONE, Vec2::ONE) * 0.5 + 0.5) * 4095.0 + 0.5).floor();
    1.0 + q.x * 4096.0 + q.y
}

/// The unit normal of a [`normal_code`]; zero for 0.
pub fn normal_from_code(code: f32) -> Vec3 {
    if code < 1.0 {
        return Vec3::ZERO;
    }
    let c = code as u32 - 1;
    let e = Vec2::new((c / 4096) as f32, (c % 4096) as f32) / 4095.0 * 2.0 - 1.0;
    let z = 1.0 - e.x.abs() - e.y.abs();
    let t = (-z).max(0.0);
    let sgn = Vec2::new(
        if e.x >= 0.0 { 1.0 } else { -1.0 },
        if e.y >= 0.0 { 1.0 } else { -1.0 },
    );
    let xy = e - sgn * t;
    Vec3::new(xy.x, xy.y, z).normalize()
}

/// Render to RGBA8 (alpha 255), row-major.
pub fn render(splats: &Splats, camera: &Camera, background: Vec3) -> Vec<u8> {
    render_with_passes(splats, camera, background, PassSet::default(), &[]).0
}

/// [`render`], and the `passes` of the same compositing (as the GPU rasteriser's,
/// `shaders/render/rasterize.wgsl`); `ids` holds each Gaussian's id for the id pass (empty:
/// all 0).
pub fn render_with_passes(
    splats: &Splats,
    camera: &Camera,
    background: Vec3,
    passes: PassSet,
    ids: &[u16],
) -> (Vec<u8>, Option<PassImages>) {
    let list = sorted_projections(splats, camera);
    let (w, h) = (camera.width, camera.height);
    let pixels: Vec<Composite> = (0..w * h)
        .into_par_iter()
        .map(|i| composite_pixel(&list, i % w, i / w))
        .collect();
    let rgba = pixels
        .iter()
        .flat_map(|p| {
            let c = (p.sum + p.t * background).clamp(Vec3::ZERO, Vec3::ONE);
            [to_u8(c.x), to_u8(c.y), to_u8(c.z), 255]
        })
        .collect();
    let id_of = |p: &Composite| p.best.map_or(0, |i| ids.get(i).copied().unwrap_or(0));
    let set = passes;
    let passes = set.any().then(|| PassImages {
        normal: set
            .normal
            .then(|| pixels.iter().map(|p| p.normal().to_array()).collect()),
        id: set.id.then(|| pixels.iter().map(id_of).collect()),
        alpha: pixels
            .iter()
            .flat_map(|p| {
                let (c, a) = p.straight_over(background);
                [to_u8(c.x), to_u8(c.y), to_u8(c.z), a]
            })
            .collect(),
        depth: pixels.iter().map(Composite::depth).collect(),
    });
    (rgba, passes)
}

/// What front-to-back compositing leaves at a pixel: the premultiplied colour sum Σ w_i c_i,
/// the transmittance T, the depth sum Σ w_i z_i and normal sum Σ w_i n_i (w_i = α_i T_i),
/// and the Gaussian with the largest w_i (the first of equals).
#[derive(Clone, Copy, Debug)]
pub struct Composite {
    pub sum: Vec3,
    pub t: f32,
    pub depth_sum: f32,
    pub normal_sum: Vec3,
    pub best: Option<usize>,
}

impl Composite {
    /// α = 1 − T.
    pub fn alpha(&self) -> f32 {
        1.0 - self.t
    }

    /// The straight (not premultiplied) colour and the 8-bit α of the alpha pass: the
    /// colour that over `background` at that α gives back the frame's 8-bit colour, so that
    /// compositing the pass reproduces the frame within 1/255 (it is Σ w_i c_i / α up to
    /// that rounding, and the frame's own colour where α = 1; black where α rounds to 0).
    pub fn straight_over(&self, background: Vec3) -> (Vec3, u8) {
        let a = to_u8(self.alpha());
        let a8 = f32::from(a) / 255.0;
        if a == 0 {
            return (Vec3::ZERO, 0);
        }
        let frame = (self.sum + self.t * background).clamp(Vec3::ZERO, Vec3::ONE);
        let levels = Vec3::new(
            f32::from(to_u8(frame.x)),
            f32::from(to_u8(frame.y)),
            f32::from(to_u8(frame.z)),
        ) / 255.0;
        (
            ((levels - (1.0 - a8) * background) / a8).clamp(Vec3::ZERO, Vec3::ONE),
            a,
        )
    }

    /// The direction of Σ w_i n_i, zero where there is none.
    pub fn normal(&self) -> Vec3 {
        self.normal_sum.normalize_or_zero()
    }

    /// The alpha-weighted mean depth Σ w_i z_i / α, +∞ where α = 0.
    pub fn depth(&self) -> f32 {
        let a = self.alpha();
        if a > 0.0 {
            self.depth_sum / a
        } else {
            f32::INFINITY
        }
    }
}

/// The Gaussians `camera` sees, front to back.
fn sorted_projections(splats: &Splats, camera: &Camera) -> Vec<ProjectedGaussian> {
    let mut list: Vec<ProjectedGaussian> = (0..splats.len())
        .into_par_iter()
        .filter_map(|i| project_gaussian(splats, i, camera))
        .collect();
    // Same order as the GPU: by depth, ties by index (the radix sort is stable).
    list.sort_by(|a, b| {
        a.depth
            .to_bits()
            .cmp(&b.depth.to_bits())
            .then(a.index.cmp(&b.index))
    });
    list
}

/// Front-to-back compositing of one pixel (docs/method.md §7) over `background`.
pub fn shade_pixel(list: &[ProjectedGaussian], x: u32, y: u32, background: Vec3) -> Vec3 {
    let p = composite_pixel(list, x, y);
    (p.sum + p.t * background).clamp(Vec3::ZERO, Vec3::ONE)
}

/// Front-to-back compositing of one pixel (docs/method.md §7): its sums and transmittance.
pub fn composite_pixel(list: &[ProjectedGaussian], x: u32, y: u32) -> Composite {
    let (tx, ty) = (x / TILE, y / TILE);
    let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
    let mut t = 1.0f32;
    let mut rgb = Vec3::ZERO;
    let mut depth_sum = 0.0f32;
    let mut normal_sum = Vec3::ZERO;
    let (mut best, mut best_w) = (None, 0.0f32);
    for g in list {
        if tx < g.tile_min.0 || tx >= g.tile_max.0 || ty < g.tile_min.1 || ty >= g.tile_max.1 {
            continue;
        }
        let k = extent_sigmas(g.opacity);
        if !ellipse_touches_tile(g.xy, g.conic, k * k, tx, ty) {
            continue;
        }
        let d = g.xy - centre;
        let power = -0.5 * (g.conic.x * d.x * d.x + g.conic.z * d.y * d.y) - g.conic.y * d.x * d.y;
        if power > 0.0 {
            continue;
        }
        let alpha = (g.opacity * power.exp()).min(0.99);
        if alpha < MIN_ALPHA {
            continue;
        }
        let next_t = t * (1.0 - alpha);
        if next_t < 1e-4 {
            break;
        }
        let w = alpha * t;
        rgb += g.color * w;
        depth_sum += g.depth * w;
        normal_sum += g.normal * w;
        if w > best_w {
            (best, best_w) = (Some(g.index), w);
        }
        t = next_t;
    }
    Composite {
        sum: rgb,
        t,
        depth_sum,
        normal_sum,
        best,
    }
}

/// The rounding of WGSL's `pack4x8unorm`: round(clamp(c, 0, 1) × 255).
pub fn to_u8(c: f32) -> u8 {
    (c.clamp(0.0, 1.0) * 255.0 + 0.5).floor() as u8
}

/// Peak signal-to-noise ratio in dB of two RGBA8 images (RGB channels only).
pub fn psnr(a: &[u8], b: &[u8]) -> f64 {
    assert_eq!(a.len(), b.len(), "images differ in size");
    let (mut se, mut n) = (0.0f64, 0usize);
    for (pa, pb) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
        for c in 0..3 {
            let d = f64::from(pa[c]) - f64::from(pb[c]);
            se += d * d;
            n += 1;
        }
    }
    let mse = se / n.max(1) as f64;
    if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (255.0f64 * 255.0 / mse).log10()
    }
}
