// What both P2G gathers (p2g.wgsl, p2g_broadcast.wgsl) sum at a node, per field, and how
// they finish the node: the grid update (grid_update.wgsl), with two fields the contact of
// the fields first (separation.wgsl). SEPARATION is a constant their Rust types define.
// The bindings below are both passes' own (`step::p2g_gather_bindings`).
// Needs: sim/step/grid_update, sim/step/separation, sim/step/node_gather.

@group(0) @binding(3) var<storage, read> x_mass: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> v_volume: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> affine: array<mat3x3<f32>>;
// xyz: velocity after the grid update, w: mass (common.wgsl, grid_texel)
@group(0) @binding(6) var grid_velocity: texture_storage_2d<rgba32float, write>;
// xyz: what the step's forces changed, v_i − Σ w m_p v_p / m_i (FLIP/PIC blends only)
@group(0) @binding(16) var grid_velocity_change: texture_storage_2d<rgba32float, write>;
// Two-field separation only (step/separation.wgsl): ∇D_p per particle (xyz), the ridge
// gradient per pool node, and the far field per pool node: velocity xyz and mass w, then
// the velocity change (FLIP/PIC blends)
@group(0) @binding(9) var<storage, read> damage_gradient: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read> ridge: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read_write> far_field: array<vec4<f32>>;

// One field's sums at a node: Σ w m, Σ w (m v + affine d), Σ w m v (read with a FLIP/PIC
// blend), and with two fields Σ m ∇w with respect to the node. A struct per field, not an
// array indexed by field: a local array indexed at run time goes to memory on a CPU driver
// (lavapipe).
struct FieldSums {
    m: f32,
    p: vec3<f32>,
    q: vec3<f32>,
    g: vec3<f32>,
}

fn no_sums() -> FieldSums {
    return FieldSums(0.0, vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
}

// Node `node` (pool slot idx) from its fields' sums: velocity and mass into grid_velocity
// (the near field's with two fields, the far field's into far_field), and with `carry`
// each field's velocity change v − Σ w m v / m.
fn finish_node(node: vec3<u32>, idx: u32, near: FieldSums, far: FieldSums, carry: bool) {
    if !SEPARATION {
        let v = node_velocity(node, near.p, near.m);
        textureStore(grid_velocity, grid_texel(idx), vec4<f32>(v, near.m));
        if carry {
            let dv = select(vec3<f32>(0.0), v - near.q / near.m, near.m > 0.0);
            textureStore(grid_velocity_change, grid_texel(idx), vec4<f32>(dv, 0.0));
        }
        return;
    }
    // Two fields: trial velocities, the contact where the node holds both, then each
    // field's boundary conditions (cpu::grid_update_at).
    var v_near = vec3<f32>(0.0);
    var v_far = vec3<f32>(0.0);
    if near.m > 0.0 {
        v_near = trial_velocity(node, near.p, near.m);
    }
    if far.m > 0.0 {
        v_far = trial_velocity(node, far.p, far.m);
    }
    if near.m > 0.0 && far.m > 0.0 {
        let c = field_contact(near.m, v_near, near.g, far.m, v_far, far.g);
        v_near = c.near;
        v_far = c.far;
    }
    var dv_near = vec3<f32>(0.0);
    var dv_far = vec3<f32>(0.0);
    if near.m > 0.0 {
        v_near = constrained_velocity(node, v_near);
        dv_near = v_near - near.q / near.m;
    }
    if far.m > 0.0 {
        v_far = constrained_velocity(node, v_far);
        dv_far = v_far - far.q / far.m;
    }
    textureStore(grid_velocity, grid_texel(idx), vec4<f32>(v_near, near.m));
    far_field[2u * idx] = vec4<f32>(v_far, far.m);
    if carry {
        textureStore(grid_velocity_change, grid_texel(idx), vec4<f32>(dv_near, 0.0));
        far_field[2u * idx + 1u] = vec4<f32>(dv_far, 0.0);
    }
}
