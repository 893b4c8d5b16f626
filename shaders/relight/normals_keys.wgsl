// GPU PCA normals, pass 1 (per recomputed Gaussian): its hash-grid cell as a sort key.

@group(0) @binding(1) var<storage, read> gaussians: array<GaussianIn>;
@group(0) @binding(2) var<storage, read_write> keys: array<u32>;
@group(0) @binding(3) var<storage, read_write> values: array<u32>;

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = flat_workgroup(wid, nwg) * 256u + lid;
    if i >= params.dims_count.w {
        return;
    }
    let p = gaussians[params.offset + i].mean_opacity.xyz;
    keys[i] = normals_cell_index(normals_cell(p));
    values[i] = i;
}
