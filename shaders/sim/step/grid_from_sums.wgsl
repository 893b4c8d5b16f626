// The grid update after the atomic P2G (per node of the active blocks): the scattered
// momentum and mass become velocity and mass (grid_update.wgsl's node_velocity: gravity,
// colliders, walls), written to the grid texture G2P reads (common.wgsl, grid_texel).
// Nodes without mass get zero.

// momentum xyz, mass w (p2g_scatter.wgsl); for a FLIP/PIC blend every node has a second
// vec4, the momentum without the stress and affine terms
@group(0) @binding(1) var<storage, read> grid: array<vec4<f32>>;
// velocity xyz, mass w
@group(0) @binding(4) var grid_velocity: texture_storage_2d<rgba32float, write>;
// xyz: what the step's forces changed, v_i − Σ w m_p v_p / m_i (FLIP/PIC blends only)
@group(0) @binding(16) var grid_velocity_change: texture_storage_2d<rgba32float, write>;
@group(0) @binding(2) var<storage, read> active_blocks: array<u32>;
// [3]: the number of active blocks (compact_blocks.wgsl)
@group(0) @binding(3) var<storage, read> block_args: array<u32, 4>;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    read_consts();
    let slot = wid.x + wid.y * nwg.x;
    if slot >= listed_blocks(block_args[3]) {
        return;
    }
    let bn = block_node(active_blocks[slot], lid);
    if !bn.ok {
        return;
    }
    let carry = consts.flip > 0.0;
    let pm = grid[select(bn.index, 2u * bn.index, carry)];
    var v = vec4<f32>(0.0);
    if pm.w > 0.0 {
        v = vec4<f32>(node_velocity(bn.node, pm.xyz, pm.w), pm.w);
    }
    textureStore(grid_velocity, grid_texel(bn.index), v);
    if carry {
        var dv = vec4<f32>(0.0);
        if pm.w > 0.0 {
            dv = vec4<f32>(v.xyz - grid[2u * bn.index + 1u].xyz / pm.w, 0.0);
        }
        textureStore(grid_velocity_change, grid_texel(bn.index), dv);
    }
}
