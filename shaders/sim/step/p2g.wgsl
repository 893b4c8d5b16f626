// P2G, part 2, and the grid update (per node of the active blocks): gather m_i = Σ w_ip m_p and
// p_i = Σ w_ip (m_p v_p + affine_p d_ip) over the particles of the 27 base cells whose
// stencils reach node i (docs/method.md §2 step 1), then the node's velocity (grid_update.wgsl,
// docs/method.md §2 step 2). Particles are sorted by base cell, so no atomics are needed: the sum has
// a fixed order and the result is the same on every run and every backend. Mirrors
// `cpu::p2g` followed by `cpu::grid_update`. Its bindings and the node's finish are in
// p2g_sums.wgsl.

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    read_consts();
    let bn = gathering_node(wid, nwg, lid);
    if !bn.ok {
        return;
    }
    let idx = bn.index;
    let node = bn.node;
    let carry = consts.flip > 0.0;
    // SEPARATION: a constant P2gGather defines (two-field separation compiled in or out)
    let two = SEPARATION;
    var ridge_i = vec3<f32>(0.0);
    if two {
        ridge_i = ridge[idx].xyz;
    }
    // the near field's sums (the only field without separation) and the far field's
    var near = no_sums();
    var far = no_sums();
    for (var n = 0u; n < 27u; n++) {
        let off = bspline_stencil_offset(n);
        let run = reaching_run(node, off);
        for (var k = run.x; k < run.y; k++) {
            let p = cell_values[k];
            let xm = x_mass[p];
            let s = bspline_stencil(xm.xyz - consts.lo, consts.inv_dx);
            let w = bspline_weight(s, off);
            let d = bspline_offset(s, off, consts.dx);
            let mv = xm.w * v_volume[p].xyz;
            let mom = w * (mv + affine[p] * d);
            if two {
                // ∇w with respect to the node is minus that with respect to x_p
                let gm = -xm.w * bspline_weight_grad(s, off, consts.inv_dx);
                if in_far_field(damage_gradient[p].xyz, ridge_i) {
                    far.m += w * xm.w;
                    far.p += mom;
                    far.q += w * mv;
                    far.g += gm;
                    continue;
                }
                near.g += gm;
            }
            near.m += w * xm.w;
            near.p += mom;
            if carry {
                near.q += w * mv;
            }
        }
    }
    finish_node(node, idx, near, far, carry);
}
