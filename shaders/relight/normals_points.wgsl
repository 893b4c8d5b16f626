// GPU PCA normals, pass 2 (per recomputed Gaussian in cell order, after the sort): copy its
// centre and object next to its neighbours', so that the neighbourhood search of
// normals_pca.wgsl reads one record per candidate instead of following the sorted index
// to the Gaussian and to its object (three dependent loads per candidate, each a gather on
// a CPU driver).

@group(0) @binding(1) var<storage, read> gaussians: array<GaussianIn>;
@group(0) @binding(2) var<storage, read> sorted_values: array<u32>;
@group(0) @binding(3) var<storage, read> object_of: array<u32>;
@group(0) @binding(4) var<storage, read_write> points: array<vec4<u32>>;

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let k = flat_workgroup(wid, nwg) * 256u + lid;
    if k >= params.dims_count.w {
        return;
    }
    let j = sorted_values[k];
    points[k] = sorted_point(gaussians[params.offset + j].mean_opacity.xyz, object_of[j]);
}
