// Two-field separation, 2 of 3 (per particle; docs/method.md §4.9 step 2): the damage
// field's gradient at the particle, ∇D_p = Σ_i D_i ∇w_ip (zero off the grid). Mirrors
// `separation::damage_gradient`.

@group(0) @binding(1) var<storage, read> x_mass: array<vec4<f32>>;
// D_i per pool node (damage_field.wgsl)
@group(0) @binding(2) var<storage, read> damage: array<vec2<f32>>;
// xyz: ∇D_p, w: |∇D_p|²
@group(0) @binding(3) var<storage, read_write> damage_gradient: array<vec4<f32>>;

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    read_consts();
    let p = flat_id(wid, nwg, lid);
    if p >= page.count {
        return;
    }
    let st = grid_stencil(x_mass[p].xyz);
    var g = vec3<f32>(0.0);
    if st.ok {
        let blocks = stencil_blocks(vec3<u32>(st.s.base));
        for (var k = 0u; k < 27u; k++) {
            let off = bspline_stencil_offset(k);
            let node = stencil_node(blocks, off);
            if node == NO_SLOT {
                continue;
            }
            g += damage[node].x * bspline_weight_grad(st.s, off, consts.inv_dx);
        }
    }
    damage_gradient[p] = vec4<f32>(g, dot(g, g));
}
