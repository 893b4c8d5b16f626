// Two-field separation (docs/method.md §4.9, `sim::separation`): what its passes
// (damage_field, damage_gradient, ridge), P2G and G2P share. With separation (P2G's and
// G2P's SEPARATION constant),
// a node holds the particles across the damage ridge from the one that set its ridge
// gradient g_i (∇D_p · g_i < 0) in a second, far field: P2G sums them there, the grid
// update makes both fields' velocities meet at a frictionless contact, and G2P reads each
// particle's own field.
// Needs: sim/step/common.

// Whether a particle of damage gradient `gradient` is in the far field of a node whose
// ridge gradient is `ridge`.
fn in_far_field(gradient: vec3<f32>, ridge: vec3<f32>) -> bool {
    return dot(gradient, ridge) < 0.0;
}

fn unit_or_zero(v: vec3<f32>) -> vec3<f32> {
    let len = length(v);
    return select(vec3<f32>(0.0), v / len, len > 0.0);
}

struct FieldVelocities {
    near: vec3<f32>,
    far: vec3<f32>,
}

// The contact of a node's near field (mass, velocity, mass gradient) with its far field
// (`separation::contact`): where they approach along n ∝ n̂_near − n̂_far, the normal part
// of each one's velocity relative to their centre of mass is removed; separating fields
// keep their velocities; where n is undefined they move as one.
fn field_contact(m_near: f32, v_near: vec3<f32>, g_near: vec3<f32>,
                 m_far: f32, v_far: vec3<f32>, g_far: vec3<f32>) -> FieldVelocities {
    let v_cm = (m_near * v_near + m_far * v_far) / (m_near + m_far);
    let n_raw = unit_or_zero(g_near) - unit_or_zero(g_far);
    let len = length(n_raw);
    var out: FieldVelocities;
    if !(len > 1e-6) {
        out.near = v_cm;
        out.far = v_cm;
        return out;
    }
    let n = n_raw / len;
    if dot(v_near - v_far, n) >= 0.0 {
        out.near = v_near;
        out.far = v_far;
        return out;
    }
    out.near = v_near - n * dot(v_near - v_cm, n);
    out.far = v_far - n * dot(v_far - v_cm, n);
    return out;
}
