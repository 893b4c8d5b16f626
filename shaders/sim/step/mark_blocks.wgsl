// Active blocks, gather path (per sorted particle): the first particle of each occupied base
// cell flags the blocks (common.wgsl) holding the 27 nodes its cell's stencils reach.

@group(0) @binding(1) var<storage, read> cell_keys: array<u32>;
@group(0) @binding(2) var<storage, read_write> block_flags: array<u32>;

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    read_consts();
    let i = flat_id(wid, nwg, lid);
    if i >= consts.num_particles {
        return;
    }
    let key = cell_keys[i];
    if key == no_cell_key() || (i > 0u && cell_keys[i - 1u] == key) {
        return;
    }
    let bc = consts.cells - 1u;
    let base = vec3<u32>(key % bc.x, (key / bc.x) % bc.y, key / (bc.x * bc.y));
    let lo = stencil_block_lo(base);
    let hi = stencil_block_hi(base);
    for (var z = lo.z; z <= hi.z; z++) {
        for (var y = lo.y; y <= hi.y; y++) {
            for (var x = lo.x; x <= hi.x; x++) {
                // Every writer stores the same value, so the order does not matter.
                block_flags[block_index(vec3<u32>(x, y, z))] = 1u;
            }
        }
    }
}
