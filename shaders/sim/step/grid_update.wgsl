// Grid update (SPEC §2 step 2), as functions called by the P2G gather right after a node's
// mass and momentum are summed (one pass over the nodes instead of two): v_i = p_i / m_i
// where m_i > 0, v_i += Δt g, then the planar colliders and the domain walls (nodes within
// `band` of a face). Slip and separate keep the tangential velocity, less Coulomb friction
// — never v = 0 (SPEC §2). Mirrors `cpu::grid_update` and `cpu::Condition::apply`.

fn apply_condition(c: Condition, v: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let vn = dot(v, n);
    if c.kind == BOUNDARY_STICKY {
        return vec3<f32>(0.0);
    }
    if c.kind == BOUNDARY_SEPARATE && vn >= 0.0 {
        return v;
    }
    let vt = v - vn * n;
    if vn < 0.0 && c.friction > 0.0 {
        let speed = length(vt);
        let drop = -c.friction * vn;
        if speed <= drop {
            return vec3<f32>(0.0);
        }
        return vt * (1.0 - drop / speed);
    }
    return vt;
}

// Velocity of node i from its momentum and mass (0 where there is no mass).
fn node_velocity(i: vec3<u32>, momentum: vec3<f32>, mass: f32) -> vec3<f32> {
    if mass <= 0.0 {
        return vec3<f32>(0.0);
    }
    let x = step.lo + vec3<f32>(i) * step.dx;
    var v = momentum / mass + step.gravity * step.dt;
    for (var k = 0u; k < step.num_colliders; k++) {
        let c = step.colliders[k];
        if dot(x - c.point.xyz, c.normal.xyz) <= 0.0 {
            v = apply_condition(c.condition, v, c.normal.xyz);
        }
    }
    for (var axis = 0u; axis < 3u; axis++) {
        var e = vec3<f32>(0.0);
        e[axis] = 1.0;
        if i[axis] < step.band {
            v = apply_condition(step.walls[2u * axis], v, e);
        }
        if i[axis] + step.band > step.cells[axis] {
            v = apply_condition(step.walls[2u * axis + 1u], v, -e);
        }
    }
    return v;
}
