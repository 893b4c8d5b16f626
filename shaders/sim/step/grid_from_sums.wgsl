// The grid update after the atomic P2G (per node), in place: the scattered momentum and
// mass become velocity and mass (grid_update.wgsl's node_velocity: gravity, colliders,
// walls). Nodes without mass are left at the zeros the step started from — no particle
// stencil reaches them — so empty grid costs one load per node.

// in: momentum xyz, mass w (p2g_scatter.wgsl); out: velocity xyz, mass w
@group(0) @binding(1) var<storage, read_write> grid: array<vec4<f32>>;

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let idx = flat_id(wid, nwg, lid);
    let n = step.nodes;
    if idx >= n.x * n.y * n.z {
        return;
    }
    let pm = grid[idx];
    if pm.w <= 0.0 {
        return;
    }
    let i = vec3<u32>(idx % n.x, (idx / n.x) % n.y, idx / (n.x * n.y));
    grid[idx] = vec4<f32>(node_velocity(i, pm.xyz, pm.w), pm.w);
}
