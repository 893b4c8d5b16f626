// P2G, part 1 (per particle): the particle's base cell as a sort key, and its affine
// momentum term affine_p = m_p C_p − Δt V⁰_p (4/Δx²) τ(F_p) (docs/method.md §2 step 1,
// common.wgsl's affine_term), computed once here rather than 27 times in the gather.
// Mirrors the item building in `cpu::p2g`. Only the first step of a submission runs it:
// G2P leaves both for the next step (g2p.wgsl).

@group(0) @binding(1) var<storage, read> x_mass: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> v_volume: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> deformation: array<mat3x3<f32>>;
@group(0) @binding(4) var<storage, read> affine_velocity: array<mat3x3<f32>>;
@group(0) @binding(5) var<storage, read> material: array<u32>;
@group(0) @binding(6) var<storage, read_write> cell_keys: array<u32>;
@group(0) @binding(7) var<storage, read_write> cell_values: array<u32>;
@group(0) @binding(8) var<storage, read_write> affine: array<mat3x3<f32>>;
@group(0) @binding(9) var<storage, read> alpha: array<f32>;

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    read_consts();
    let p = flat_id(wid, nwg, lid);
    if p >= page.count {
        return;
    }
    cell_values[p] = page.base + p;
    let xm = x_mass[p];
    cell_keys[p] = cell_key(xm.xyz);
    affine[p] = affine_term(particle_material(material[p]), deformation[p], alpha[p],
                            affine_velocity[p], xm.w, v_volume[p].w);
}
