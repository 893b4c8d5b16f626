// G2P (per particle, docs/method.md §2 step 3): v_pic = Σ w v_i, C_p = (4/Δx²) Σ w v_i d_ipᵀ,
// F ← (I + Δt C) F, x += Δt v_pic, then the material's plasticity (its law's return mapping,
// docs/method.md §4). The particle keeps v_pic, or with a FLIP/PIC blend
// flip · (v_p + Σ w Δv_i) + (1 − flip) · v_pic. The timed actions (ACTIONS, a constant G2p
// defines; sim::actions) then push, hold or drive their particles, before F takes C. A
// particle whose stencil is off the grid moves ballistically. Mirrors `cpu::g2p`.

@group(0) @binding(1) var<storage, read_write> x_mass: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> v_volume: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> deformation: array<mat3x3<f32>>;
@group(0) @binding(4) var<storage, read_write> affine_velocity: array<mat3x3<f32>>;
@group(0) @binding(5) var<storage, read_write> alpha: array<f32>;
// Per particle: its material's index, and above MATERIAL_BITS, bit k set when
// step.actions[k] acts on it (read only with ACTIONS).
@group(0) @binding(6) var<storage, read> material: array<u32>;
// The grid's nodes after the grid update: velocity xyz, mass w (common.wgsl, grid_texel).
@group(0) @binding(7) var grid_velocity: texture_2d<f32>;
// What the step's forces changed at each node, Δv_i (read only with a FLIP/PIC blend).
@group(0) @binding(16) var grid_velocity_change: texture_2d<f32>;
// The watchdog's counters (docs/method.md §2.3), one word per WATCH_* slot (their meanings
// at sim::gpu::codes::WatchSlot). Read and cleared once per frame.
@group(0) @binding(8) var<storage, read_write> flags: array<atomic<u32>, WATCH_SLOTS>;
// What prepare.wgsl would compute for the next step, so that only the first step of a
// submission runs it: the affine term (common.wgsl, affine_term), and on the gather path
// (NEXT_KEYS, a constant G2p defines) the base-cell sort key and the particle's index.
@group(0) @binding(9) var<storage, read_write> affine: array<mat3x3<f32>>;
@group(0) @binding(17) var<storage, read_write> cell_keys: array<u32>;
@group(0) @binding(18) var<storage, read_write> cell_values: array<u32>;

// Two-field separation only (step/separation.wgsl): ∇D_p per particle, the ridge gradient
// per pool node, and the far field (velocity xyz, mass w; then the velocity change) per
// pool node, written by p2g.wgsl.
@group(0) @binding(10) var<storage, read> damage_gradient: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read> ridge: array<vec4<f32>>;
@group(0) @binding(12) var<storage, read> far_field: array<vec4<f32>>;

// The next step's sort key and value of particle p at x (as prepare.wgsl).
fn leave_key(p: u32, x: vec3<f32>) {
    if NEXT_KEYS {
        cell_values[p] = page.base + p;
        cell_keys[p] = cell_key(x);
    }
}

// Counts particle p in `slot` (WATCH_NONFINITE or WATCH_ESCAPED); the bitwise NOTs keep
// the lowest particle and the earliest step under atomicMax.
fn count_failure(slot: u32, p: u32) {
    atomicAdd(&flags[slot], 1u);
    atomicMax(&flags[WATCH_FIRST_PARTICLE], ~(page.base + p));
    // compact_blocks.wgsl has already counted this step
    atomicMax(&flags[WATCH_FIRST_STEP], ~(atomicLoad(&flags[WATCH_STEP]) - 1u));
}

// Counts particle p's step as inverting its deformation (det(I + Δt C) ≤ 0), keeping the
// lowest particle and the earliest step as count_failure does. Rare, so the atomics cost
// nothing in a healthy step.
fn count_inversion(p: u32) {
    atomicAdd(&flags[WATCH_INVERTED], 1u);
    atomicMax(&flags[WATCH_INVERTED_FIRST_PARTICLE], ~(page.base + p));
    atomicMax(&flags[WATCH_INVERTED_FIRST_STEP], ~(atomicLoad(&flags[WATCH_STEP]) - 1u));
}

// The largest speed of the frame: most particles only read it, so that the one word is
// not written by every particle of every step.
fn record_speed(speed: f32) {
    let bits = bitcast<u32>(speed);
    if bits > atomicLoad(&flags[WATCH_SPEED_MAX]) {
        atomicMax(&flags[WATCH_SPEED_MAX], bits);
    }
}

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    read_consts();
    let p = flat_id(wid, nwg, lid);
    if p >= page.count {
        return;
    }
    let xm = x_mass[p];
    let vv = v_volume[p];
    let st = grid_stencil(xm.xyz);
    if !st.ok {
        if sim_is_finite3(xm.xyz) {
            count_failure(WATCH_ESCAPED, p);
        } else {
            count_failure(WATCH_NONFINITE, p);
        }
        let v = vv.xyz + consts.gravity * consts.dt;
        v_volume[p] = vec4<f32>(v, vv.w);
        let x = xm.xyz + v * consts.dt;
        x_mass[p] = vec4<f32>(x, xm.w);
        affine[p] = affine_term(particle_material(material[p]), deformation[p], alpha[p],
                                affine_velocity[p], xm.w, vv.w);
        leave_key(p, x);
        return;
    }
    let s = st.s;
    let base = vec3<u32>(s.base);
    let blocks = stencil_blocks(base);
    let flip = consts.flip;
    // SEPARATION: a constant G2p defines (two-field separation compiled in or out)
    let two = SEPARATION;
    var gradient = vec3<f32>(0.0);
    if two {
        gradient = damage_gradient[p].xyz;
    }
    var vp = vec3<f32>(0.0);
    var dv = vec3<f32>(0.0);
    var b = mat3x3<f32>(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    for (var k = 0u; k < 27u; k++) {
        let off = bspline_stencil_offset(k);
        let node = stencil_node(blocks, off);
        let texel = grid_texel(node);
        // the field of this node that holds the particle
        let far = two && node != NO_SLOT && in_far_field(gradient, ridge[node].xyz);
        var vi = textureLoad(grid_velocity, texel, 0).xyz;
        if far {
            vi = far_field[2u * node].xyz;
        }
        let w = bspline_weight(s, off);
        let d = bspline_offset(s, off, consts.dx);
        vp += w * vi;
        b += mat3x3<f32>(vi * (w * d.x), vi * (w * d.y), vi * (w * d.z));
        if flip > 0.0 {
            if far {
                dv += w * far_field[2u * node + 1u].xyz;
            } else {
                dv += w * textureLoad(grid_velocity_change, texel, 0).xyz;
            }
        }
    }
    var c = b * (4.0 / (consts.dx * consts.dx));
    var v_new = vp;
    if flip > 0.0 {
        v_new = flip * (vv.xyz + dv) + (1.0 - flip) * vp;
    }
    var x = xm.xyz + vp * consts.dt;
    if ACTIONS {
        let members = material[p] >> MATERIAL_BITS;
        for (var k = 0u; k < step.num_actions; k++) {
            let a = step.actions[k];
            if (members >> k & 1u) == 0u || a.mode == ACTION_IDLE {
                continue;
            }
            if a.mode == ACTION_PUSH {
                v_new += a.velocity;
            } else {
                v_new = a.velocity;
                c = mat3x3<f32>(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
                x = xm.xyz + a.displacement;
            }
        }
    }
    // The step's deformation increment. The flow of a velocity field never inverts matter:
    // det ≤ 0 means Δt was too long for this particle's velocity gradient (a wall stopping
    // it within its stencil, or its own stress ringing on its stencil), and the law's
    // return mapping would start from a clamped, flattened F. The frame is then run again
    // with a shorter step (sim::frame).
    let increment = SIM_IDENTITY3 + c * consts.dt;
    if determinant(increment) <= 0.0 {
        count_inversion(p);
    }
    let f_trial = increment * deformation[p];
    v_volume[p] = vec4<f32>(v_new, vv.w);
    affine_velocity[p] = c;
    x_mass[p] = vec4<f32>(x, xm.w);
    leave_key(p, x);
    let m = particle_material(material[p]);
    let plastic = material_plasticity(m, f_trial, alpha[p], page.base + p);
    let f_new = plastic.f;
    alpha[p] = plastic.alpha;
    deformation[p] = f_new;
    affine[p] = affine_term(m, f_new, plastic.alpha, c, xm.w, vv.w);
    if !(sim_is_finite3(v_new) && sim_is_finite_mat3(f_new)) {
        count_failure(WATCH_NONFINITE, p);
    } else {
        record_speed(length(v_new));
    }
}
