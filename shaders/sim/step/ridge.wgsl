// Two-field separation, 3 of 3 (per node of the active blocks; docs/method.md §4.9 step 3):
// the node's ridge gradient g_i, the ∇D_p of largest norm among the particles whose
// stencils reach it (ties: the lowest particle index, so the result does not depend on the
// visiting order), where a broken particle reaches the node; zero elsewhere. P2G and G2P
// put a particle in the node's far field when ∇D_p · g_i < 0. Mirrors
// `separation::node_gradients`.

// y: 1 where a broken particle reaches the node (damage_field.wgsl)
@group(0) @binding(3) var<storage, read> damage: array<vec2<f32>>;
// xyz: ∇D_p, w: |∇D_p|² (damage_gradient.wgsl)
@group(0) @binding(4) var<storage, read> damage_gradient: array<vec4<f32>>;
// xyz: g_i per pool node
@group(0) @binding(5) var<storage, read_write> ridge: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    read_consts();
    let bn = gathering_node(wid, nwg, lid);
    if !bn.ok {
        return;
    }
    var best = vec4<f32>(0.0);
    var best_p = 0xffffffffu;
    if damage[bn.index].y > 0.0 {
        for (var n = 0u; n < 27u; n++) {
            let run = reaching_run(bn.node, bspline_stencil_offset(n));
            for (var k = run.x; k < run.y; k++) {
                let p = cell_values[k];
                let g = damage_gradient[p];
                if g.w > best.w || (g.w == best.w && g.w > 0.0 && p < best_p) {
                    best = g;
                    best_p = p;
                }
            }
        }
    }
    ridge[bn.index] = vec4<f32>(best.xyz, 0.0);
}
