// Two-field separation, 1 of 3 (per node of the active blocks; docs/method.md §4.9 step 2):
// the damage field D_i = Σ w m d / Σ w m, and whether a broken particle (d = 1) reaches
// the node, gathered from the 27 base cells whose stencils reach it as P2G does
// (node_gather.wgsl: fixed order, no atomics). Mirrors `separation::damage_field`.

@group(0) @binding(3) var<storage, read> x_mass: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> alpha: array<f32>;
@group(0) @binding(5) var<storage, read> material: array<u32>;
// per pool node (common.wgsl, node_index): D_i, and 1 where a broken particle reaches it
@group(0) @binding(6) var<storage, read_write> damage: array<vec2<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    read_consts();
    let bn = gathering_node(wid, nwg, lid);
    if !bn.ok {
        return;
    }
    var md = 0.0;
    var m = 0.0;
    var broken = false;
    for (var n = 0u; n < 27u; n++) {
        let off = bspline_stencil_offset(n);
        let run = reaching_run(bn.node, off);
        for (var k = run.x; k < run.y; k++) {
            let p = cell_values[k];
            let xm = x_mass[p];
            let s = bspline_stencil(xm.xyz - consts.lo, consts.inv_dx);
            let wm = bspline_weight(s, off) * xm.w;
            let d = material_damage(particle_material(material[p]), alpha[p]);
            md += wm * d;
            m += wm;
            broken = broken || d >= 1.0;
        }
    }
    damage[bn.index] = vec2<f32>(select(0.0, md / m, m > 0.0), select(0.0, 1.0, broken));
}
