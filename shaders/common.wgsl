// Shared declarations of the render passes. Every struct here is mirrored by a
// `#[repr(C)]` Rust type in `src/render/gpu/layout.rs`; a test checks sizes and offsets.

// One Gaussian as the renderer receives it (world space). 64 bytes.
struct GaussianIn {
    // xyz: mean, w: opacity in (0, 1]
    mean_opacity: vec4<f32>,
    // covariance upper triangle: xx, xy, xz, yy
    cov_a: vec4<f32>,
    // covariance upper triangle: yz, zz, (unused), (unused)
    cov_b: vec4<f32>,
    // rest-frame rotation R_p as a unit quaternion (x, y, z, w)
    rotation: vec4<f32>,
}

// A Gaussian after projection to the screen. 48 bytes.
struct Projected {
    // xy: pixel position of the mean, z: opacity, w: the id pass's id (a whole number,
    // 0 for none; written with IDS only)
    xy_opacity: vec4<f32>,
    // inverse of the 2D covariance: (a, b, c) of [[a, b], [b, c]], w: camera-space depth
    conic: vec4<f32>,
    // rgb: colour from SH, w: the camera-space normal as `normal_code` packs it (written
    // with NORMALS only)
    color: vec4<f32>,
}

// Depth key of a culled Gaussian (project.wgsl): it sorts after every visible one, touches
// no tile and is not shaded.
const CULLED_KEY: u32 = 0xffffffffu;

// Per-frame constants, written once per frame.
struct Frame {
    // world-to-camera rotation, rows 0..2 in xyz (w unused)
    view_row0: vec4<f32>,
    view_row1: vec4<f32>,
    view_row2: vec4<f32>,
    // xyz: camera centre in world space, w: near plane (camera z)
    camera_near: vec4<f32>,
    // fx, fy, cx, cy in pixels
    focal_principal: vec4<f32>,
    // background colour (rgb), w unused
    background: vec4<f32>,
    // tan of half the horizontal / vertical field of view, times 1.3 (the 3DGS clamp)
    lim_x: f32,
    lim_y: f32,
    width: u32,
    height: u32,
    tiles_x: u32,
    tiles_y: u32,
    num_gaussians: u32,
    sh_degree: u32,
    // capacity of the tile-key buffers (entries)
    key_capacity: u32,
    // log2 of the records per page of the per-Gaussian arrays (gpu::pages)
    page_shift: u32,
    _pad1: u32,
    _pad2: u32,
}

// Counters written by the passes and read back with every frame.
struct Stats {
    // Gaussians skipped for NaN/Inf in mean or covariance
    skipped_nonfinite: atomic<u32>,
    // Gaussians skipped because their 2D covariance was not positive definite
    skipped_degenerate: atomic<u32>,
    // Gaussians in front of the camera and on screen
    visible: atomic<u32>,
    // tile intersections wanted this frame (may exceed the key capacity)
    intersections: atomic<u32>,
}

const TILE: u32 = 16u;

// Compositing skips α below this (docs/method.md §7).
const MIN_ALPHA: f32 = 1.0 / 255.0;

// Flattened workgroup index of a 1D dispatch split over x and y (x ≤ 65535).
fn flat_workgroup(wid: vec3<u32>, nwg: vec3<u32>) -> u32 {
    return wid.x + wid.y * nwg.x;
}

// How many standard deviations a Gaussian's footprint spans: 3 (docs/method.md §7), or fewer when
// its α = ω·exp(−r²/2) already falls below MIN_ALPHA inside 3σ, at r = sqrt(2 ln(255 ω)).
// Beyond that compositing skips every pixel, so the image does not change while faint
// Gaussians touch fewer tiles. Mirrors `render::cpu::extent_sigmas`.
fn extent_sigmas(opacity: f32) -> f32 {
    return min(3.0, sqrt(2.0 * log(opacity / MIN_ALPHA)));
}

// dᵀ C d for the conic C = [[a, b], [b, c]] stored as (a, b, c).
fn conic_form(d: vec2<f32>, conic: vec3<f32>) -> f32 {
    return conic.x * d.x * d.x + 2.0 * conic.y * d.x * d.y + conic.z * d.y * d.y;
}

// Smallest dᵀ C d over the segment d0 + t e, t in [0, 1] (a 1D quadratic in t).
fn conic_min_on_segment(d0: vec2<f32>, e: vec2<f32>, conic: vec3<f32>) -> f32 {
    let ce = vec2<f32>(conic.x * e.x + conic.y * e.y, conic.y * e.x + conic.z * e.y);
    let t = clamp(-dot(ce, d0) / dot(e, ce), 0.0, 1.0);
    return conic_form(d0 + t * e, conic);
}

// Does the ellipse dᵀ C d ≤ k² around `xy` reach a pixel centre of the square of pixel
// centres from `lo` to `lo + span`? Either the mean lies inside it, or the ellipse crosses
// one of its four edges. Squares that only the ellipse's bounding square reaches are left
// out (a large share for elongated, deformed Gaussians).
fn ellipse_touches_square(xy: vec2<f32>, conic: vec3<f32>, k2: f32, lo: vec2<f32>, span: f32) -> bool {
    let hi = lo + span;
    if all(xy >= lo) && all(xy <= hi) {
        return true;
    }
    let d = lo - xy;
    let m = min(
        min(conic_min_on_segment(d, vec2<f32>(span, 0.0), conic),
            conic_min_on_segment(d + vec2<f32>(0.0, span), vec2<f32>(span, 0.0), conic)),
        min(conic_min_on_segment(d, vec2<f32>(0.0, span), conic),
            conic_min_on_segment(d + vec2<f32>(span, 0.0), vec2<f32>(0.0, span), conic)));
    return m <= k2;
}

// Does the ellipse reach a pixel centre of tile `tile`? Mirrors
// `render::cpu::ellipse_touches_tile`.
fn ellipse_touches_tile(xy: vec2<f32>, conic: vec3<f32>, k2: f32, tile: vec2<u32>) -> bool {
    return ellipse_touches_square(xy, conic, k2, vec2<f32>(tile * TILE) + 0.5, f32(TILE - 1u));
}

// The Gaussians one dispatch of a per-Gaussian pass covers. Per-Gaussian arrays may exceed
// one storage binding (gpu::pages): such a pass is dispatched once per page, over windows of
// the arrays that start at Gaussian `base`, and runs for the local indices 0..count.
struct PageRange {
    base: u32,
    count: u32,
}

// Steps of each octahedral coordinate of `normal_code`.
const NORMAL_STEPS: f32 = 4095.0;

// A unit normal as a whole number that an f32 holds exactly (so it can ride in a spare
// float of `Projected`): the octahedral map onto [−1, 1]², each coordinate quantised to
// 12 bits, 1 + u·4096 + v. 0 is no normal (a zero or non-finite vector). Mirrors
// `render::cpu::normal_code`.
fn normal_code(n: vec3<f32>) -> f32 {
    let l1 = abs(n.x) + abs(n.y) + abs(n.z);
    if !(l1 > 0.0) || (bitcast<u32>(l1) & 0x7f800000u) == 0x7f800000u {
        return 0.0;
    }
    var e = n.xy / l1;
    if n.z < 0.0 {
        let sgn = select(vec2<f32>(-1.0), vec2<f32>(1.0), e >= vec2<f32>(0.0));
        e = (vec2<f32>(1.0) - abs(e.yx)) * sgn;
    }
    let q = floor((clamp(e, vec2<f32>(-1.0), vec2<f32>(1.0)) * 0.5 + 0.5) * NORMAL_STEPS + 0.5);
    return 1.0 + q.x * 4096.0 + q.y;
}

// The unit normal of a `normal_code`, (0, 0, 0) for code 0.
fn normal_from_code(code: f32) -> vec3<f32> {
    if code < 1.0 {
        return vec3<f32>(0.0);
    }
    let c = u32(code) - 1u;
    let e = vec2<f32>(f32(c / 4096u), f32(c % 4096u)) / NORMAL_STEPS * 2.0 - 1.0;
    let z = 1.0 - abs(e.x) - abs(e.y);
    let t = max(-z, 0.0);
    let sgn = select(vec2<f32>(-1.0), vec2<f32>(1.0), e >= vec2<f32>(0.0));
    return normalize(vec3<f32>(e - sgn * t, z));
}
