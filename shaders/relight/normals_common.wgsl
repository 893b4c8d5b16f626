// Shared declarations of the GPU PCA normals (`derive::normals`): a uniform hash grid over
// the recomputed Gaussians, cells about half a neighbourhood radius wide, so that the
// neighbours within the radius lie in the cells up to `reach` away from a Gaussian's own
// (fine cells: the cells searched hug the sphere of the radius more closely). Mirrored by
// `NormalsParams` / `NormalObject` in src/relight/gpu_normals.rs (layout test).
// Comes after shaders/common.wgsl, shaders/render/lighting.wgsl and the sim math
// (`derive::normals::source`).

struct NormalsParams {
    // xyz: grid origin, w: cell size h
    lo_h: vec4<f32>,
    // xyz: cells per axis, w: number of recomputed Gaussians
    dims_count: vec4<u32>,
    // index of the first recomputed Gaussian in the renderer's buffers
    offset: u32,
    // cells to search on each side of a Gaussian's own: ⌈largest radius / h⌉
    reach: u32,
    _pad1: u32,
    _pad2: u32,
}

// Per object: the neighbourhood radius and the surface-layer depth of the refit.
struct NormalObject {
    radius: f32,
    layer: f32,
    _pad0: f32,
    _pad1: f32,
}

@group(0) @binding(0) var<storage, read> params: NormalsParams;

fn normals_cell(p: vec3<f32>) -> vec3<i32> {
    let rel = (p - params.lo_h.xyz) / params.lo_h.w;
    let top = vec3<f32>(params.dims_count.xyz) - 1.0;
    // NaN-safe: select keeps finite values, anything else goes to cell 0.
    let ok = rel == rel;
    return vec3<i32>(clamp(select(vec3<f32>(0.0), floor(rel), ok), vec3<f32>(0.0), top));
}

fn normals_cell_index(c: vec3<i32>) -> u32 {
    let d = params.dims_count.xyz;
    return u32(c.x) + d.x * (u32(c.y) + d.y * u32(c.z));
}

// A Gaussian's centre and object as the neighbourhood search reads them, in cell order
// (normals_points.wgsl): the centre's bits and the object, exact both ways.
fn sorted_point(p: vec3<f32>, object: u32) -> vec4<u32> {
    return vec4<u32>(bitcast<vec3<u32>>(p), object);
}

// Whether cell c can hold a centre within `radius` of p: its box is near enough. Border
// cells also hold the centres outside the grid (normals_cell clamps), so their box is
// open on the outer side.
fn cell_within(c: vec3<i32>, p: vec3<f32>, radius: f32) -> bool {
    let h = params.lo_h.w;
    let top = vec3<i32>(params.dims_count.xyz) - 1;
    let open = vec3<f32>(1e30);
    let lo = select(params.lo_h.xyz + vec3<f32>(c) * h, -open, c <= vec3<i32>(0));
    let hi = select(params.lo_h.xyz + vec3<f32>(c + 1) * h, open, c >= top);
    let gap = max(max(lo - p, p - hi), vec3<f32>(0.0));
    return !(dot(gap, gap) > radius * radius);
}
