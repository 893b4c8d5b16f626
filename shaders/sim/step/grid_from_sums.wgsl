// The grid update after the atomic P2G (per node): velocity, gravity, colliders and walls
// from the scattered sums (grid_update.wgsl's node_velocity, as in the gather path).

// momentum xyz, mass w (written by p2g_scatter.wgsl)
@group(0) @binding(1) var<storage, read> grid_sum: array<vec4<f32>>;
// velocity xyz, mass w
@group(0) @binding(2) var<storage, read_write> grid: array<vec4<f32>>;

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let idx = flat_id(wid, nwg, lid);
    let n = step.nodes;
    if idx >= n.x * n.y * n.z {
        return;
    }
    let pm = grid_sum[idx];
    let i = vec3<u32>(idx % n.x, (idx / n.x) % n.y, idx / (n.x * n.y));
    grid[idx] = vec4<f32>(node_velocity(i, pm.xyz, pm.w), pm.w);
}
