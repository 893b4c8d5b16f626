// GPU PCA normals, pass 3 (per recomputed Gaussian, after sorting by cell): the covariance
// of the same object's centres within the object's radius, its smallest-eigenvalue axis
// (svd3 of the symmetric covariance), oriented along p − centroid when that offset is
// clear and otherwise like the normal already there (the derive pass's transported one),
// then refit on the neighbours no deeper than `layer` below the tangent plane (the
// surface layer of a filled object). The twin of `relight::normals::pca_normals`, with a
// radius instead of the k nearest.

@group(0) @binding(1) var<storage, read> ranges: array<vec2<u32>>;
// The recomputed Gaussians in cell order, and their centres and objects in that order
// (normals_points.wgsl).
@group(0) @binding(2) var<storage, read> sorted_values: array<u32>;
@group(0) @binding(3) var<storage, read> points: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> objects: array<NormalObject>;
@group(0) @binding(5) var<storage, read_write> shading: array<vec2<u32>>;

struct Moments {
    n: f32,
    s1: vec3<f32>,
    // upper triangle of Σ d dᵀ: xx, xy, xz / yy, yz, zz
    s2a: vec3<f32>,
    s2b: vec3<f32>,
}

// Moments of the neighbours d = q − p within `radius` (same object), keeping only those
// with d·axis > −layer when `axis` is non-zero.
fn moments(p: vec3<f32>, obj: u32, radius: f32, axis: vec3<f32>, layer: f32) -> Moments {
    var m: Moments;
    m.n = 0.0;
    m.s1 = vec3<f32>(0.0);
    m.s2a = vec3<f32>(0.0);
    m.s2b = vec3<f32>(0.0);
    let c = normals_cell(p);
    let d = vec3<i32>(params.dims_count.xyz);
    let r2 = radius * radius;
    let keep_layer = any(axis != vec3<f32>(0.0));
    let reach = i32(params.reach);
    for (var dz = -reach; dz <= reach; dz++) {
        for (var dy = -reach; dy <= reach; dy++) {
            for (var dx = -reach; dx <= reach; dx++) {
                let cc = c + vec3<i32>(dx, dy, dz);
                if any(cc < vec3<i32>(0)) || any(cc >= d) || !cell_within(cc, p, radius) {
                    continue;
                }
                let range = ranges[normals_cell_index(cc)];
                for (var k = range.x; k < range.y; k++) {
                    let e = points[k];
                    if e.w != obj {
                        continue;
                    }
                    let q = bitcast<vec3<f32>>(e.xyz) - p;
                    if dot(q, q) > r2 || (keep_layer && dot(q, axis) <= -layer) {
                        continue;
                    }
                    m.n += 1.0;
                    m.s1 += q;
                    m.s2a += q.x * q;
                    m.s2b += vec3<f32>(q.y * q.y, q.y * q.z, q.z * q.z);
                }
            }
        }
    }
    return m;
}

// The smallest-variance axis of the moments (unoriented), or zero when degenerate.
fn pca_axis(m: Moments, radius: f32) -> vec3<f32> {
    let mean = m.s1 / m.n;
    let xx = m.s2a.x / m.n - mean.x * mean.x;
    let xy = m.s2a.y / m.n - mean.x * mean.y;
    let xz = m.s2a.z / m.n - mean.x * mean.z;
    let yy = m.s2b.x / m.n - mean.y * mean.y;
    let yz = m.s2b.y / m.n - mean.y * mean.z;
    let zz = m.s2b.z / m.n - mean.z * mean.z;
    let cov = mat3x3<f32>(vec3<f32>(xx, xy, xz), vec3<f32>(xy, yy, yz), vec3<f32>(xz, yz, zz));
    let s = svd3(cov);
    // σ descending; a line (two vanishing σ) has no normal.
    if !(abs(s.sigma.y) > 1e-6 * radius * radius) {
        return vec3<f32>(0.0);
    }
    return normalize(s.v[2]);
}

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    // In cell order, so that the lanes of a SIMD vector search the same cells: their loops
    // run alike instead of each waiting for the longest.
    let k = flat_workgroup(wid, nwg) * 256u + lid;
    if k >= params.dims_count.w {
        return;
    }
    let g = params.offset + sorted_values[k];
    let e = points[k];
    let p = bitcast<vec3<f32>>(e.xyz);
    let obj = e.w;
    let o = objects[obj];
    let first = moments(p, obj, o.radius, vec3<f32>(0.0), 0.0);
    if first.n < 4.0 {
        return; // too few neighbours: keep the transported normal
    }
    var n = pca_axis(first, o.radius);
    if all(n == vec3<f32>(0.0)) {
        return;
    }
    let outward = -first.s1 / first.n; // p − centroid
    var hint = outward;
    if length(outward) <= 0.1 * o.radius {
        hint = oct_decode(shading[g].x);
    }
    if dot(n, hint) < 0.0 {
        n = -n;
    }
    let layer = moments(p, obj, o.radius, n, o.layer);
    if layer.n >= 6.0 {
        let m = pca_axis(layer, o.radius);
        if any(m != vec3<f32>(0.0)) {
            n = select(m, -m, dot(m, n) < 0.0);
        }
    }
    shading[g].x = oct_encode(n);
}
