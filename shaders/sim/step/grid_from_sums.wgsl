// The grid update after the atomic P2G (per node of the active blocks), in place: the
// scattered momentum and mass become velocity and mass (grid_update.wgsl's node_velocity:
// gravity, colliders, walls). Nodes without mass keep the zeros the step started from.

// in: momentum xyz, mass w (p2g_scatter.wgsl); out: velocity xyz, mass w
@group(0) @binding(1) var<storage, read_write> grid: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> active_blocks: array<u32>;
// [3]: the number of active blocks (compact_blocks.wgsl)
@group(0) @binding(3) var<storage, read> block_args: array<u32, 4>;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let slot = wid.x + wid.y * nwg.x;
    if slot >= listed_blocks(block_args[3]) {
        return;
    }
    let bn = block_node(active_blocks[slot], lid);
    if !bn.ok {
        return;
    }
    let pm = grid[bn.index];
    if pm.w <= 0.0 {
        return;
    }
    grid[bn.index] = vec4<f32>(node_velocity(bn.node, pm.xyz, pm.w), pm.w);
}
