// Grid update (docs/method.md §2 step 2), as functions called by the P2G gather right after a node's
// mass and momentum are summed (one pass over the nodes instead of two): v_i = p_i / m_i
// where m_i > 0, v_i += Δt g, then the planar colliders, the moving (kinematic) colliders at
// this substep's pose, the captured surface and the domain walls (nodes within `band` of a face). Slip and separate keep the tangential velocity, less Coulomb friction
// — never v = 0 (docs/method.md §2). Mirrors `cpu::grid_update` and `cpu::Condition::apply`.
// Needs: sim/step/common.

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

// Signed distance of p (relative to the shape's centre) and the outward unit normal of the
// nearest surface point (mirrors `kinematic::ColliderShape::distance`).
struct ShapeDistance {
    d: f32,
    n: vec3<f32>,
}

fn shape_distance(k: KinematicCollider, p: vec3<f32>) -> ShapeDistance {
    var out: ShapeDistance;
    if k.shape == SHAPE_SPHERE {
        let len = length(p);
        out.d = len - k.size.x;
        out.n = select(vec3<f32>(0.0, 0.0, 1.0), p / len, len > 0.0);
        return out;
    }
    if k.shape == SHAPE_BOX {
        let q = abs(p) - k.size.xyz;
        let sgn = select(vec3<f32>(1.0), vec3<f32>(-1.0), p < vec3<f32>(0.0));
        let o = max(q, vec3<f32>(0.0));
        if dot(o, o) > 0.0 {
            out.d = length(o);
            out.n = normalize(o * sgn);
            return out;
        }
        // Inside: the nearest face.
        var axis = 2u;
        if q.x >= q.y && q.x >= q.z {
            axis = 0u;
        } else if q.y >= q.z {
            axis = 1u;
        }
        out.d = q[axis];
        out.n = vec3<f32>(0.0);
        out.n[axis] = sgn[axis];
        return out;
    }
    let r = length(p.xy);
    let radial = select(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(p.xy / r, 0.0), r > 0.0);
    let axial = vec3<f32>(0.0, 0.0, select(1.0, -1.0, p.z < 0.0));
    let qr = r - k.size.x;
    let qz = abs(p.z) - k.size.y;
    if qr > 0.0 || qz > 0.0 {
        let a = max(qr, 0.0);
        let b = max(qz, 0.0);
        out.d = sqrt(a * a + b * b);
        out.n = (radial * a + axial * b) / out.d;
    } else if qr > qz {
        out.d = qr;
        out.n = radial;
    } else {
        out.d = qz;
        out.n = axial;
    }
    return out;
}

// Moving collider k on the node at x with velocity v: the condition on the velocity
// relative to the rigid motion there, v_c = v_lin + ω × (x − c) (sticky: v = v_c).
fn apply_kinematic(k: u32, x: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    let c = step.kinematic[k];
    let pose = step.poses[k];
    let rel = x - pose.position.xyz;
    let sd = shape_distance(c, transpose(pose.rotation) * rel - c.centre.xyz);
    if sd.d > c.margin {
        return v;
    }
    let vc = pose.velocity.xyz + cross(pose.angular_velocity.xyz, rel);
    return vc + apply_condition(c.condition, v - vc, pose.rotation * sd.n);
}

// φ of the captured surface at every node (a single 0 when there is none); only the passes
// that update the grid use it.
@group(0) @binding(14) var<storage, read> surface: array<f32>;

// φ at node i + d, clamped to the grid (mirrors `SurfaceCollider::phi_at`).
fn surface_phi(i: vec3<u32>, d: vec3<i32>) -> f32 {
    let c = vec3<u32>(clamp(vec3<i32>(i) + d, vec3<i32>(0), vec3<i32>(consts.nodes) - 1));
    return surface[c.x + consts.nodes.x * (c.y + consts.nodes.y * c.z)];
}

// The surface collider on node i (mirrors `SurfaceCollider::apply`): inside (φ ≤ 0) the
// condition with the normal ∇φ/|∇φ|, held where the gradient vanishes.
fn apply_surface(i: vec3<u32>, v: vec3<f32>) -> vec3<f32> {
    if surface_phi(i, vec3<i32>(0)) > 0.0 {
        return v;
    }
    let g = vec3<f32>(
        surface_phi(i, vec3<i32>(1, 0, 0)) - surface_phi(i, vec3<i32>(-1, 0, 0)),
        surface_phi(i, vec3<i32>(0, 1, 0)) - surface_phi(i, vec3<i32>(0, -1, 0)),
        surface_phi(i, vec3<i32>(0, 0, 1)) - surface_phi(i, vec3<i32>(0, 0, -1)),
    );
    let len = length(g);
    if len <= 0.0 {
        return vec3<f32>(0.0);
    }
    return apply_condition(step.surface.condition, v, g / len);
}

// Velocity of node i from its momentum and mass (0 where there is no mass).
fn node_velocity(i: vec3<u32>, momentum: vec3<f32>, mass: f32) -> vec3<f32> {
    if mass <= 0.0 {
        return vec3<f32>(0.0);
    }
    return constrained_velocity(i, trial_velocity(i, momentum, mass));
}

// p/m + Δt g, then the force fields: node i's velocity before the boundary conditions.
fn trial_velocity(i: vec3<u32>, momentum: vec3<f32>, mass: f32) -> vec3<f32> {
    return sim_fields(i, momentum / mass + consts.gravity * consts.dt);
}

// The wind and the attractor on velocity v at node i (sim::fields::Fields::apply): the
// attractor's acceleration a r² / (r² + d²) towards p, then v ← w + (v − w) e^{−kΔt}.
// Without fields (k = 0, a = 0) v is returned as it came.
fn sim_fields(i: vec3<u32>, v_in: vec3<f32>) -> vec3<f32> {
    var v = v_in;
    if step.attractor_strength != 0.0 {
        let d = step.attractor - (consts.lo + vec3<f32>(i) * consts.dx);
        let d2 = dot(d, d);
        if d2 > 1e-24 {
            let r2 = step.attractor_falloff2;
            v += d * (step.attractor_strength * r2 / ((r2 + d2) * sqrt(d2))) * consts.dt;
        }
    }
    if step.wind_drag > 0.0 {
        v = step.wind + (v - step.wind) * exp(-step.wind_drag * consts.dt);
    }
    return v;
}

// Velocity `v_in` of node i after the colliders, the moving colliders, the captured
// surface and the walls, in that order (docs/method.md §2).
fn constrained_velocity(i: vec3<u32>, v_in: vec3<f32>) -> vec3<f32> {
    let x = consts.lo + vec3<f32>(i) * consts.dx;
    var v = v_in;
    for (var k = 0u; k < step.num_colliders; k++) {
        let c = step.colliders[k];
        if dot(x - c.point.xyz, c.normal.xyz) <= 0.0 {
            v = apply_condition(c.condition, v, c.normal.xyz);
        }
    }
    for (var k = 0u; k < step.num_kinematic; k++) {
        v = apply_kinematic(k, x, v);
    }
    if step.surface.on != 0u {
        v = apply_surface(i, v);
    }
    for (var axis = 0u; axis < 3u; axis++) {
        var e = vec3<f32>(0.0);
        e[axis] = 1.0;
        if i[axis] < step.band {
            v = apply_condition(step.walls[2u * axis], v, e);
        }
        if i[axis] + step.band > consts.cells[axis] {
            v = apply_condition(step.walls[2u * axis + 1u], v, -e);
        }
    }
    return v;
}
