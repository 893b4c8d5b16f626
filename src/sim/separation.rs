//! Cracks that stay open: two velocity fields per grid node, split by the damage field's
//! gradient (DFG partitioning; Homel & Herbold 2017, the separation CD-MPM uses,
//! docs/method.md §4.9).
//!
//! With one velocity per node, the material on both sides of a crack narrower than the
//! stencil shares its nodes' velocities, so the two sides move together and the crack heals
//! at any resolution a CPU affords. Here every node may carry a second field:
//!
//! 1. **Damage** d_p ∈ [0, 1] of each particle ([`Material::damage`]: for NACC the share of
//!    its cohesion the hardening state has lost, 0 for elastic materials).
//! 2. **Damage field** D_i = Σ_p w_ip m_p d_p / Σ_p w_ip m_p on the nodes, and its gradient at
//!    each particle, ∇D_p = Σ_i D_i ∇w_ip.
//! 3. **Node gradient** g_i: the ∇D_p of largest norm among the particles whose stencil
//!    reaches node i (ties: the lowest particle index), where a broken particle (d_p =
//!    [`BROKEN`]) reaches the node; none elsewhere.
//! 4. **Fields**: particle p belongs to node i's far field when ∇D_p · g_i < 0 (it lies on
//!    the other side of the damage ridge than the particle that set g_i), to its near
//!    field otherwise. P2G, the grid update and G2P then run per field ([`super::cpu`]):
//!    a particle's stress, mass and momentum reach only its own field, and it reads only
//!    its own field's velocities back, so the two sides of a crack stop pushing and
//!    pulling each other through the grid.
//! 5. **Contact** ([`contact`]): where a node holds both fields and they approach each other
//!    along the contact normal, the normal part of their relative velocity is removed about
//!    the centre-of-mass velocity (frictionless). Separating fields are left alone: that is
//!    the crack opening. The exchange is an equal and opposite impulse, so the node's
//!    momentum is unchanged.
//!
//! Where nothing is damaged every particle is in the near field and the step is the
//! one-field step exactly (tested).

use glam::{DVec3, IVec3};
use rayon::prelude::*;

use super::bspline::stencil_offsets;
use super::grid::Grid;
use super::material::Material;
use super::particles::Particles;

/// How the grid keeps the pieces of a fractured body apart (docs/method.md §4.9).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Separation {
    /// One velocity field per node (the plain MPM grid).
    #[default]
    None,
    /// Two fields per node, split by the damage field's gradient (module docs).
    DamageGradient,
}

/// Damage of a particle that holds no tension any more (NACC: α ≥ 0). A node splits its
/// particles into two fields only where such a particle reaches it: the partition must not
/// open a crack the material has not made, and a node that only partly damaged material
/// reaches still holds together.
pub const BROKEN: f64 = 1.0;

/// Which of a particle's 27 stencil nodes (bit ox + 3·oy + 9·oz) hold it in their far
/// field, per particle; all zero where nothing is damaged.
pub fn partition(particles: &Particles, grid: &Grid, materials: &[Material]) -> Vec<u32> {
    let n = particles.len();
    let Some((field, gradient)) = damage_gradients(particles, grid, materials) else {
        return vec![0; n];
    };
    let ridge = node_gradients(particles, grid, &field, &gradient);
    (0..n)
        .into_par_iter()
        .map(|p| {
            let Some(st) = grid.stencil(particles.x[p]) else {
                return 0;
            };
            let mut far = 0u32;
            for (bit, off) in stencil_offsets().enumerate() {
                let g = ridge[node_index(grid, st.node(off))];
                if gradient[p].dot(g) < 0.0 {
                    far |= 1 << bit;
                }
            }
            far
        })
        .collect()
}

/// ∇D_p of every particle (docs/method.md §4.9 step 2), with the damage field it comes
/// from; None where nothing is damaged.
fn damage_gradients(
    particles: &Particles,
    grid: &Grid,
    materials: &[Material],
) -> Option<(DamageField, Vec<DVec3>)> {
    let damage: Vec<f64> = (0..particles.len())
        .into_par_iter()
        .map(|p| materials[particles.material[p] as usize].damage(particles.alpha[p]))
        .collect();
    if damage.iter().all(|&d| d == 0.0) {
        return None;
    }
    let field = damage_field(particles, grid, &damage);
    let gradient = particles
        .x
        .par_iter()
        .map(|x| damage_gradient(*x, grid, &field))
        .collect();
    Some((field, gradient))
}

/// ∇D_p of every particle (zero where nothing is damaged): what the GPU's
/// `damage_gradient.wgsl` computes, for tests against it.
pub fn particle_damage_gradients(
    particles: &Particles,
    grid: &Grid,
    materials: &[Material],
) -> Vec<DVec3> {
    damage_gradients(particles, grid, materials)
        .map_or_else(|| vec![DVec3::ZERO; particles.len()], |(_, g)| g)
}

fn node_index(grid: &Grid, node: IVec3) -> usize {
    grid.index(node.as_uvec3())
}

/// The nodal damage field and where it may split the grid.
struct DamageField {
    /// D_i = Σ w m d / Σ w m (0 where no particle reaches).
    d: Vec<f64>,
    /// Whether a broken particle reaches node i.
    broken: Vec<bool>,
}

/// The damage field of `damage` on the grid.
fn damage_field(particles: &Particles, grid: &Grid, damage: &[f64]) -> DamageField {
    let mut md = vec![0.0; grid.node_count()];
    let mut m = vec![0.0; grid.node_count()];
    let mut broken = vec![false; grid.node_count()];
    for ((x, mass), &d) in particles.x.iter().zip(&particles.mass).zip(damage) {
        let Some(st) = grid.stencil(*x) else {
            continue;
        };
        for off in stencil_offsets() {
            let i = node_index(grid, st.node(off));
            let wm = st.weight(off) * mass;
            md[i] += wm * d;
            m[i] += wm;
            broken[i] |= d >= BROKEN;
        }
    }
    let d = md
        .iter()
        .zip(&m)
        .map(|(&a, &b)| if b > 0.0 { a / b } else { 0.0 })
        .collect();
    DamageField { d, broken }
}

/// ∇D at a particle: Σ_i D_i ∇w_ip (zero off the grid).
fn damage_gradient(x: DVec3, grid: &Grid, field: &DamageField) -> DVec3 {
    let Some(st) = grid.stencil(x) else {
        return DVec3::ZERO;
    };
    stencil_offsets()
        .map(|off| field.d[node_index(grid, st.node(off))] * st.weight_grad(off, grid.dx))
        .sum()
}

/// g_i of every node (module docs, step 3): the largest particle gradient reaching a node
/// a broken particle reaches, zero elsewhere.
fn node_gradients(
    particles: &Particles,
    grid: &Grid,
    field: &DamageField,
    gradient: &[DVec3],
) -> Vec<DVec3> {
    let mut best = vec![(0.0f64, DVec3::ZERO); grid.node_count()];
    // Ascending particle order with a strict comparison: ties keep the lowest index.
    for (x, &g) in particles.x.iter().zip(gradient) {
        let Some(st) = grid.stencil(*x) else {
            continue;
        };
        let norm2 = g.length_squared();
        for off in stencil_offsets() {
            let i = node_index(grid, st.node(off));
            if field.broken[i] && norm2 > best[i].0 {
                best[i] = (norm2, g);
            }
        }
    }
    best.into_iter().map(|(_, g)| g).collect()
}

/// Below this length of n̂_near − n̂_far the contact normal is undefined (the two fields'
/// mass gradients point the same way, or vanish); the WGSL twin uses the same bound.
pub const NORMAL_MIN: f64 = 1e-6;

/// One node's contact between its near field (mass `m_near`, velocity `v_near`, mass
/// gradient `grad_near`) and its far field: returns the two velocities after it (module
/// docs, step 5). The contact normal n points from the far field into the near one,
/// n ∝ ∇m_near/|∇m_near| − ∇m_far/|∇m_far|; the fields approach when (v_near − v_far)·n < 0.
/// Where n is undefined (|n̂_near − n̂_far| ≤ [`NORMAL_MIN`]), the fields move as one.
pub fn contact(
    (m_near, v_near, grad_near): (f64, DVec3, DVec3),
    (m_far, v_far, grad_far): (f64, DVec3, DVec3),
) -> (DVec3, DVec3) {
    let v_cm = (v_near * m_near + v_far * m_far) / (m_near + m_far);
    let n = grad_near.normalize_or_zero() - grad_far.normalize_or_zero();
    // Also catches a NaN length.
    if n.length().partial_cmp(&NORMAL_MIN) != Some(std::cmp::Ordering::Greater) {
        return (v_cm, v_cm);
    }
    let n = n.normalize();
    if (v_near - v_far).dot(n) >= 0.0 {
        return (v_near, v_far);
    }
    (
        v_near - n * (v_near - v_cm).dot(n),
        v_far - n * (v_far - v_cm).dot(n),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contact_conserves_momentum_and_stops_the_approach() {
        let (ma, mb) = (2.0, 0.5);
        let (va, vb) = (DVec3::new(-1.0, 0.3, 0.0), DVec3::new(2.0, -0.1, 0.5));
        // Near field to the right (mass grows with x), far field to the left: n = +x.
        let (ga, gb) = (DVec3::X, -DVec3::X * 3.0);
        let (a, b) = contact((ma, va, ga), (mb, vb, gb));
        let before = va * ma + vb * mb;
        assert!((a * ma + b * mb - before).length() < 1e-15);
        // Normal relative velocity removed, tangential parts kept.
        assert!((a - b).x.abs() < 1e-15);
        assert_eq!((a.y, a.z, b.y, b.z), (va.y, va.z, vb.y, vb.z));
        // Moving apart: untouched.
        let (a, b) = contact((ma, vb, ga), (mb, va, gb));
        assert_eq!((a, b), (vb, va));
    }
}
