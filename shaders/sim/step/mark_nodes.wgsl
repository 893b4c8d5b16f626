// Active nodes (per sorted particle): the first particle of each occupied base cell marks
// the 27 nodes its cell's stencils reach. The P2G gather then skips every other node with
// one load instead of visiting 27 empty cells — most of a grid is empty, and "grids cover
// only what moves" still leaves air around the objects.

@group(0) @binding(1) var<storage, read> cell_keys: array<u32>;
@group(0) @binding(2) var<storage, read_write> node_active: array<u32>;

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = flat_id(wid, nwg, lid);
    if i >= step.num_particles {
        return;
    }
    let key = cell_keys[i];
    if key == no_cell_key() || (i > 0u && cell_keys[i - 1u] == key) {
        return;
    }
    let bc = step.cells - 1u;
    let base = vec3<u32>(key % bc.x, (key / bc.x) % bc.y, key / (bc.x * bc.y));
    let n = step.nodes;
    for (var k = 0u; k < 27u; k++) {
        let node = base + bspline_stencil_offset(k);
        // Every writer stores the same value, so the order of the stores does not matter.
        node_active[node.x + n.x * (node.y + n.y * node.z)] = 1u;
    }
}
