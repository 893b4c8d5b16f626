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
    // xy: pixel position of the mean, z: opacity, w: unused
    xy_opacity: vec4<f32>,
    // inverse of the 2D covariance: (a, b, c) of [[a, b], [b, c]], w unused
    conic: vec4<f32>,
    // rgb: colour from SH, w unused
    color: vec4<f32>,
}

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
    _pad0: u32,
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

// Compositing skips α below this (SPEC §7).
const MIN_ALPHA: f32 = 1.0 / 255.0;

// Flattened workgroup index of a 1D dispatch split over x and y (x ≤ 65535).
fn flat_workgroup(wid: vec3<u32>, nwg: vec3<u32>) -> u32 {
    return wid.x + wid.y * nwg.x;
}
