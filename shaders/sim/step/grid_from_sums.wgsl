// The grid update after an atomic P2G (per node of the active blocks): the scattered
// momentum and mass become velocity and mass (grid_update.wgsl's node_velocity: gravity,
// colliders, walls), written to the grid texture G2P reads (common.wgsl, grid_texel).
// Nodes without mass get zero. FIXED_POINT (a constant GridFromSums defines) says which
// scatter wrote the sums: p2g_fixed.wgsl's word pairs, or p2g_scatter.wgsl's floats.

// Per node, for a FLIP/PIC blend twice: momentum xyz and mass w (the second time the
// momentum without the stress and affine terms) — one vec4 of f32 bits (p2g_scatter.wgsl),
// or two vec4 of (low, high) word pairs (p2g_fixed.wgsl).
@group(0) @binding(1) var<storage, read> grid: array<vec4<u32>>;
// velocity xyz, mass w
@group(0) @binding(4) var grid_velocity: texture_storage_2d<rgba32float, write>;
// xyz: what the step's forces changed, v_i − Σ w m_p v_p / m_i (FLIP/PIC blends only)
@group(0) @binding(16) var grid_velocity_change: texture_storage_2d<rgba32float, write>;
@group(0) @binding(2) var<storage, read> active_blocks: array<u32>;
// [3]: the number of active blocks (compact_blocks.wgsl)
@group(0) @binding(3) var<storage, read> block_args: array<u32, BLOCK_ARGS>;

// A 64-bit two's-complement sum of units of 1/scale (a power of two), as f32.
fn fixed_value(w: vec2<u32>, unit: f32) -> f32 {
    return (f32(bitcast<i32>(w.y)) * TWO_TO_32 + f32(w.x)) * unit;
}

// Sum vector j (0, or 1 for a FLIP/PIC blend's second) of pool node `index`, of `per_node`.
fn node_sums(index: u32, j: u32, per_node: u32) -> vec4<f32> {
    let k = per_node * index + j;
    if !FIXED_POINT {
        return bitcast<vec4<f32>>(grid[k]);
    }
    let a = grid[2u * k];
    let b = grid[2u * k + 1u];
    let unit = power_of_two(-step.momentum_exponent);
    return vec4<f32>(fixed_value(a.xy, unit), fixed_value(a.zw, unit), fixed_value(b.xy, unit),
                     fixed_value(b.zw, power_of_two(-step.mass_exponent)));
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    read_consts();
    let slot = wid.x + wid.y * nwg.x;
    if slot >= listed_blocks(block_args[BLOCK_ARG_BLOCKS]) {
        return;
    }
    let bn = block_node(active_blocks[slot], lid);
    if !bn.ok {
        return;
    }
    let carry = consts.flip > 0.0;
    let per_node = select(1u, 2u, carry);
    let pm = node_sums(bn.index, 0u, per_node);
    var v = vec4<f32>(0.0);
    if pm.w > 0.0 {
        v = vec4<f32>(node_velocity(bn.node, pm.xyz, pm.w), pm.w);
    }
    textureStore(grid_velocity, grid_texel(bn.index), v);
    if carry {
        var dv = vec4<f32>(0.0);
        if pm.w > 0.0 {
            dv = vec4<f32>(v.xyz - node_sums(bn.index, 1u, per_node).xyz / pm.w, 0.0);
        }
        textureStore(grid_velocity_change, grid_texel(bn.index), dv);
    }
}
