// Pass 1 of the renderer: project every Gaussian (docs/method.md §7).
// Per Gaussian: view-space mean, 2D covariance Σ' = J W Σ Wᵀ Jᵀ + 0.3 I, its inverse (the
// conic), the screen radius from 3 standard deviations (less for faint Gaussians, see
// `extent_sigmas`), the rectangle of 16×16 tiles it
// touches, its SH colour, and its depth key for the global depth sort.
// Mirrors `render::cpu::project_gaussian`.

@group(0) @binding(0) var<uniform> frame: Frame;
// The page's windows of the Gaussians, their SH and their projections (indexed locally);
// the rectangles and depth keys cover all Gaussians (indexed by page.base + local).
@group(0) @binding(1) var<storage, read> gaussians: array<GaussianIn>;
@group(0) @binding(2) var<storage, read> sh_words: array<u32>;
@group(0) @binding(3) var<storage, read_write> projected: array<Projected>;
// Packed tile rectangle: min.x | min.y << 16 and max.x | max.y << 16 (max exclusive).
@group(0) @binding(4) var<storage, read_write> tile_rects: array<vec2<u32>>;
@group(0) @binding(5) var<storage, read_write> depth_keys: array<u32>;
@group(0) @binding(6) var<storage, read_write> depth_order: array<u32>;
@group(0) @binding(7) var<storage, read_write> stats: Stats;
@group(0) @binding(8) var<storage, read> page: PageRange;
// The id pass's id of every Gaussian, two 16-bit ids a word (low half first), indexed by
// page.base + local; read with IDS only.
@group(0) @binding(9) var<storage, read> ids: array<u32>;


fn rotate_by_conjugate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    // Rotate v by q⁻¹ (q unit, xyzw): v + 2 w (v × u) + 2 u × (u × v)... with u = -q.xyz.
    let u = -q.xyz;
    let t = 2.0 * cross(u, v);
    return v + q.w * t + cross(u, t);
}

// The axis of least extent of the covariance (upper triangle xx, xy, xz, yy / yz, zz),
// the normal of a flat Gaussian: the eigenvector of its smallest eigenvalue, from the
// eigenvalues in closed form (the trigonometric solution of the characteristic cubic) and
// the largest cross product of two rows of Σ − λ I. (0, 0, 0) when the two smallest
// eigenvalues lie within LEAST_AXIS_GAP of the trace of each other (a sphere or a
// needle: no axis stands out, and the closed form would pick one by rounding). Mirrors
// `render::cpu::least_axis` (which takes the Jacobi eigenvectors instead).
const LEAST_AXIS_GAP: f32 = 0.01;

fn least_axis(cov_a: vec4<f32>, cov_b: vec4<f32>) -> vec3<f32> {
    let trace = cov_a.x + cov_a.w + cov_b.y;
    if !(trace > 0.0) {
        return vec3<f32>(0.0);
    }
    // Scaled to unit trace, so that tiny Gaussians lose no precision.
    let a = cov_a / trace;
    let b = cov_b / trace;
    let off = a.y * a.y + a.z * a.z + b.x * b.x;
    let q = 1.0 / 3.0;
    let d = vec3<f32>(a.x, a.w, b.y) - q;
    let p = sqrt((dot(d, d) + 2.0 * off) / 6.0);
    if p < 0.1 * LEAST_AXIS_GAP {
        return vec3<f32>(0.0);
    }
    let r0 = vec3<f32>(d.x, a.y, a.z) / p;
    let r1 = vec3<f32>(a.y, d.y, b.x) / p;
    let r2 = vec3<f32>(a.z, b.x, d.z) / p;
    let half_det = 0.5 * dot(r0, cross(r1, r2));
    let phi = acos(clamp(half_det, -1.0, 1.0)) / 3.0;
    let lambda = q + 2.0 * p * cos(phi + 2.0943951);
    let middle = 1.0 - (q + 2.0 * p * cos(phi)) - lambda;
    if middle - lambda < LEAST_AXIS_GAP {
        return vec3<f32>(0.0);
    }
    let s0 = vec3<f32>(a.x - lambda, a.y, a.z);
    let s1 = vec3<f32>(a.y, a.w - lambda, b.x);
    let s2 = vec3<f32>(a.z, b.x, b.y - lambda);
    let c01 = cross(s0, s1);
    let c02 = cross(s0, s2);
    let c12 = cross(s1, s2);
    var best = c01;
    if dot(c02, c02) > dot(best, best) {
        best = c02;
    }
    if dot(c12, c12) > dot(best, best) {
        best = c12;
    }
    let len2 = dot(best, best);
    if !(len2 > 1e-12) {
        return vec3<f32>(0.0);
    }
    return best * inverseSqrt(len2);
}

// The id of Gaussian g (IDS).
fn gaussian_id(g: u32) -> f32 {
    return f32((ids[g / 2u] >> (16u * (g % 2u))) & 0xffffu);
}

fn cull(g: u32) {
    tile_rects[g] = vec2<u32>(0u, 0u);
    depth_keys[g] = CULLED_KEY;
    depth_order[g] = g;
}

fn all_finite4(v: vec4<f32>) -> bool {
    // Test the exponent bits: float comparisons with NaN may be optimised away by drivers
    // that assume finite math (seen on llvmpipe's GL).
    let exponent = bitcast<vec4<u32>>(v) & vec4<u32>(0x7f800000u);
    return all(exponent != vec4<u32>(0x7f800000u));
}

fn is_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let local = flat_workgroup(wid, nwg) * 256u + lid;
    if local >= page.count {
        return;
    }
    let g = page.base + local;
    let gin = gaussians[local];
    if !(all_finite4(gin.mean_opacity) && all_finite4(gin.cov_a) && all_finite4(gin.cov_b) && all_finite4(gin.rotation)) {
        atomicAdd(&stats.skipped_nonfinite, 1u);
        cull(g);
        return;
    }
    let mean = gin.mean_opacity.xyz;
    let opacity = gin.mean_opacity.w;
    let cam = frame.camera_near.xyz;
    let w = mat3x3<f32>(frame.view_row0.xyz, frame.view_row1.xyz, frame.view_row2.xyz); // rows as columns: w = Wᵀ
    let t = (mean - cam) * w; // row-vector product = W (mean - cam)
    if t.z < frame.camera_near.w || opacity < MIN_ALPHA {  // fainter than the compositing threshold everywhere
        cull(g);
        return;
    }

    // Perspective Jacobian at the (clamped) mean, as in the 3DGS reference.
    let fx = frame.focal_principal.x;
    let fy = frame.focal_principal.y;
    let tz = t.z;
    let tx = clamp(t.x / tz, -frame.lim_x, frame.lim_x) * tz;
    let ty = clamp(t.y / tz, -frame.lim_y, frame.lim_y) * tz;
    // Rows of J (3rd row is zero).
    let j0 = vec3<f32>(fx / tz, 0.0, -fx * tx / (tz * tz));
    let j1 = vec3<f32>(0.0, fy / tz, -fy * ty / (tz * tz));
    // Rows of T = J W: row_i(T) = row_i(J) W = W ᵀ row_i(J) = w * row_i(J)... as vectors:
    let t0 = w * j0;
    let t1 = w * j1;
    let sigma = mat3x3<f32>(
        vec3<f32>(gin.cov_a.x, gin.cov_a.y, gin.cov_a.z),
        vec3<f32>(gin.cov_a.y, gin.cov_a.w, gin.cov_b.x),
        vec3<f32>(gin.cov_a.z, gin.cov_b.x, gin.cov_b.y));
    let s0 = sigma * t0;
    let s1 = sigma * t1;
    let a = dot(t0, s0) + 0.3;
    let b = dot(t0, s1);
    let c = dot(t1, s1) + 0.3;
    let det = a * c - b * b;
    if !(det > 0.0) || !is_finite(det) {
        atomicAdd(&stats.skipped_degenerate, 1u);
        cull(g);
        return;
    }
    let conic = vec3<f32>(c / det, -b / det, a / det);
    let mid = 0.5 * (a + c);
    let lambda1 = mid + sqrt(max(0.1, mid * mid - det));
    let radius = ceil(extent_sigmas(opacity) * sqrt(lambda1));
    let px = fx * t.x / tz + frame.focal_principal.z;
    let py = fy * t.y / tz + frame.focal_principal.w;
    if !(is_finite(px) && is_finite(py) && is_finite(radius)) {
        atomicAdd(&stats.skipped_degenerate, 1u);
        cull(g);
        return;
    }
    // Tile rectangle [min, max) clamped to the grid; computed in f32 so that a huge radius
    // cannot overflow an integer.
    let grid = vec2<f32>(f32(frame.tiles_x), f32(frame.tiles_y));
    let rmin = clamp(floor((vec2<f32>(px, py) - radius) / f32(TILE)), vec2<f32>(0.0), grid);
    let rmax = clamp(floor((vec2<f32>(px, py) + radius + f32(TILE - 1u)) / f32(TILE)), vec2<f32>(0.0), grid);
    let mn = vec2<u32>(rmin);
    let mx = vec2<u32>(rmax);
    if mx.x <= mn.x || mx.y <= mn.y {
        cull(g);
        return;
    }
    atomicAdd(&stats.visible, 1u);
    tile_rects[g] = vec2<u32>(mn.x | (mn.y << 16u), mx.x | (mx.y << 16u));
    // Positive f32 depths sort correctly as their bit patterns.
    depth_keys[g] = bitcast<u32>(tz);
    depth_order[g] = g;

    let dir = normalize(mean - cam);
    let color = sh_color(local, frame.sh_degree, rotate_by_conjugate(gin.rotation, dir));
    // conic.w: the camera-space depth, for the depth pass (rasterize.wgsl, PASSES); with
    // NORMALS color.w: the least axis turned towards the camera, in camera space (the
    // shade pass puts the shading normal there instead where the Gaussian has one); with
    // IDS xy_opacity.w: the Gaussian's id.
    var id = 0.0;
    if IDS {
        id = gaussian_id(g);
    }
    var normal = 0.0;
    if NORMALS {
        let axis = least_axis(gin.cov_a, gin.cov_b);
        normal = normal_code(select(axis, -axis, dot(axis, cam - mean) < 0.0) * w);
    }
    projected[local] = Projected(vec4<f32>(px, py, opacity, id), vec4<f32>(conic, tz), vec4<f32>(color, normal));
}
