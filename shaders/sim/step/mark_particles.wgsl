// Active blocks, atomic path (per particle): flag the blocks (common.wgsl) holding the 27
// nodes of the particle's stencil, so that compact_blocks.wgsl can give them pool slots
// before p2g_scatter.wgsl adds to them. Redundant stores of the same value, in any order.

@group(0) @binding(1) var<storage, read> x_mass: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> block_flags: array<u32>;

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    read_consts();
    let p = flat_id(wid, nwg, lid);
    if p >= page.count {
        return;
    }
    let st = grid_stencil(x_mass[p].xyz);
    if !st.ok {
        return;
    }
    let base = vec3<u32>(st.s.base);
    let lo = stencil_block_lo(base);
    let hi = stencil_block_hi(base);
    for (var z = lo.z; z <= hi.z; z++) {
        for (var y = lo.y; y <= hi.y; y++) {
            for (var x = lo.x; x <= hi.x; x++) {
                block_flags[block_index(vec3<u32>(x, y, z))] = 1u;
            }
        }
    }
}
