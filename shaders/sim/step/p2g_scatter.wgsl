// P2G with float atomics (per particle; docs/method.md §2 step 1), for adapters with
// SHADER_FLOAT32_ATOMIC: each particle adds w_ip m_p and w_ip (m_p v_p + affine_p d_ip) to
// its 27 nodes. Faster than the gather where atomics are native, but the order of the
// additions — and so the last bits of the sums — varies from run to run; the gather path
// (p2g.wgsl) is the deterministic one. Mirrors `cpu::p2g`.

@group(0) @binding(1) var<storage, read> x_mass: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> v_volume: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> affine: array<mat3x3<f32>>;
// The grid pool (common.wgsl, node_index), 4 floats per node: momentum x, y, z, mass —
// and for a FLIP/PIC blend 4 more: Σ w m_p v_p (the momentum without the stress and
// affine terms), 0; cleared before every step; grid_from_sums.wgsl turns the sums into
// velocities in the grid texture (common.wgsl, grid_texel).
// The blocks were flagged and given slots before (mark_particles.wgsl, compact_blocks.wgsl).
@group(0) @binding(4) var<storage, read_write> grid_sum: array<atomic<f32>>;

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    read_consts();
    let p = flat_id(wid, nwg, lid);
    if p >= page.count {
        return;
    }
    let xm = x_mass[p];
    let st = grid_stencil(xm.xyz);
    if !st.ok {
        return;
    }
    let s = st.s;
    let base = vec3<u32>(s.base);
    let blocks = stencil_blocks(base);
    let mv = xm.w * v_volume[p].xyz;
    let a = affine[p];
    let carry = consts.flip > 0.0;
    let stride = select(4u, 8u, carry);
    for (var k = 0u; k < 27u; k++) {
        let off = bspline_stencil_offset(k);
        let node = stencil_node(blocks, off);
        if node == NO_SLOT {
            continue;
        }
        let idx = stride * node;
        let w = bspline_weight(s, off);
        let mom = w * (mv + a * bspline_offset(s, off, consts.dx));
        atomicAdd(&grid_sum[idx], mom.x);
        atomicAdd(&grid_sum[idx + 1u], mom.y);
        atomicAdd(&grid_sum[idx + 2u], mom.z);
        atomicAdd(&grid_sum[idx + 3u], w * xm.w);
        if carry {
            atomicAdd(&grid_sum[idx + 4u], w * mv.x);
            atomicAdd(&grid_sum[idx + 5u], w * mv.y);
            atomicAdd(&grid_sum[idx + 6u], w * mv.z);
        }
    }
}
