// Two-field separation, 1 of 3 (per node of the active blocks; docs/method.md §4.9 step 2):
// the damage field D_i = Σ w m d / Σ w m, and whether a broken particle (d = 1) reaches
// the node, gathered from the 27 base cells whose stencils reach it as P2G does (fixed
// order, no atomics). Mirrors `separation::damage_field`.

@group(0) @binding(1) var<storage, read> ranges: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read> cell_values: array<u32>;
@group(0) @binding(3) var<storage, read> x_mass: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> alpha: array<f32>;
@group(0) @binding(5) var<storage, read> material: array<u32>;
// per pool node (common.wgsl, node_index): D_i, and 1 where a broken particle reaches it
@group(0) @binding(6) var<storage, read_write> damage: array<vec2<f32>>;
@group(0) @binding(7) var<storage, read> active_blocks: array<u32>;
// [3]: the number of active blocks
@group(0) @binding(8) var<storage, read> block_args: array<u32, 4>;

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
    let node = vec3<i32>(bn.node);
    let bc = vec3<i32>(consts.cells) - 1;
    var md = 0.0;
    var m = 0.0;
    var broken = false;
    for (var oz = 0; oz < 3; oz++) {
        for (var oy = 0; oy < 3; oy++) {
            for (var ox = 0; ox < 3; ox++) {
                let b = node - vec3<i32>(ox, oy, oz);
                if any(b < vec3<i32>(0)) || any(b >= bc) {
                    continue;
                }
                let range = ranges[u32(b.x + bc.x * (b.y + bc.y * b.z))];
                let off = vec3<u32>(u32(ox), u32(oy), u32(oz));
                for (var k = range.x; k < range.y; k++) {
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
        }
    }
    damage[bn.index] = vec2<f32>(select(0.0, md / m, m > 0.0), select(0.0, 1.0, broken));
}
