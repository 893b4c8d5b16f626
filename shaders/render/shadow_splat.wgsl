// Shadows, pass 1 (per Gaussian): splat every Gaussian's optical mass into the shadow
// volume (docs/relighting.md). A Gaussian of opacity ω blocks τ = −ln(1 − ω) of optical
// depth where a ray crosses its middle, over a cross-section 2π σ₁σ₂ (its two largest
// standard deviations): optical mass τ·2πσ₁σ₂, spread over the 8 voxels around its mean
// with trilinear weights. A voxel stores optical depth per voxel length (mass / h²) in
// DEPTH_UNITs. Mirrors `relight::shadow::ShadowVolume::splat`.

@group(0) @binding(0) var<storage, read> lights: Lights;
@group(0) @binding(1) var<storage, read> gaussians: array<GaussianIn>;
@group(0) @binding(2) var<storage, read_write> depth: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read> count: array<u32>;

// The product of the two largest eigenvalues of a symmetric 3×3 (its "area²"), from the
// characteristic polynomial: λ₁λ₂ + λ₁λ₃ + λ₂λ₃ = c2 and λ₃ ≥ 0 small, so λ₁λ₂ ≈ c2 − λ₃
// (λ₁ + λ₂); with λ₃ = det / c2 as the estimate of the smallest (exact when λ₃ ≪ λ₂).
fn top_two_product(a: vec4<f32>, b: vec4<f32>) -> f32 {
    let xx = a.x; let xy = a.y; let xz = a.z; let yy = a.w; let yz = b.x; let zz = b.y;
    let tr = xx + yy + zz;
    let c2 = xx * yy - xy * xy + xx * zz - xz * xz + yy * zz - yz * yz;
    let det = xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz);
    if !(c2 > 0.0) {
        return 0.0;
    }
    let l3 = max(det / c2, 0.0);
    return max(c2 - l3 * (tr - l3), 0.0);
}

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let g = flat_workgroup(wid, nwg) * 256u + lid;
    if g >= count[0] {
        return;
    }
    let gin = gaussians[g];
    let opacity = min(gin.mean_opacity.w, 0.99);
    let h = lights.volume_lo_h.w;
    let res = lights.volume_res.xyz;
    let rel = (gin.mean_opacity.xyz - lights.volume_lo_h.xyz) / h - 0.5;
    if !(opacity > 0.0) || any(rel < vec3<f32>(0.0)) || any(rel >= vec3<f32>(res - 1u)) {
        return; // transparent, non-finite, or outside the volume
    }
    let area = 6.2831853 * sqrt(top_two_product(gin.cov_a, gin.cov_b));
    let per_length = -log(1.0 - opacity) * area / (h * h) / DEPTH_UNIT;
    if !(per_length > 0.0) || per_length > 1e9 {
        return;
    }
    let base = vec3<u32>(floor(rel));
    let f = rel - floor(rel);
    for (var k = 0u; k < 8u; k++) {
        let o = vec3<u32>(k & 1u, (k >> 1u) & 1u, k >> 2u);
        let w = select(1.0 - f, f, o == vec3<u32>(1u));
        let add = u32(round(per_length * w.x * w.y * w.z));
        if add > 0u {
            atomicAdd(&depth[voxel_index(base + o, res)], add);
        }
    }
}
