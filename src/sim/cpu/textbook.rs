//! The MPM step as a textbook writes it: mpm88's shape in f64 and three dimensions. One
//! field, APIC transfers with quadratic B-splines (docs/method.md §2), one fixed-corotated
//! material (§3), gravity, and frictionless walls that let go (`separate`) on the
//! [`WALL_BAND`](crate::sim::WALL_BAND) nodes next to each face. No plasticity, no
//! colliders, no sorting: three loops to read before the reference step ([`super::step`]),
//! which computes the same thing with every option and a deterministic order, and is tested
//! equal to it (`tests/sim_cpu.rs`).

use glam::{DMat3, DVec3, IVec3, UVec3};

use crate::sim::model::elasticity::Lame;
use crate::sim::svd::polar;
use crate::sim::Particles;

/// The grid and the constants of the textbook step.
#[derive(Clone, Copy, Debug)]
pub struct Textbook {
    /// Position of node 0 and the node spacing Δx.
    pub lo: DVec3,
    pub dx: f64,
    /// Cells per axis (nodes = cells + 1).
    pub cells: UVec3,
    pub dt: f64,
    pub gravity: DVec3,
    pub lame: Lame,
    /// Nodes within this many of a face get its wall.
    pub band: u32,
}

/// Quadratic B-spline weights of the three nodes from the base node, per axis, at the
/// offset `fx` ∈ [0.5, 1.5) of the particle from its base node (in cells).
fn weights(fx: DVec3) -> [DVec3; 3] {
    let sq = |v: DVec3| v * v;
    [0.5 * sq(1.5 - fx), 0.75 - sq(fx - 1.0), 0.5 * sq(fx - 0.5)]
}

/// The 27 nodes of the stencil: offset from the base node and weight.
fn stencil(w: &[DVec3; 3]) -> impl Iterator<Item = (IVec3, f64)> + '_ {
    (0..27).map(move |k| {
        let o = IVec3::new(k % 3, (k / 3) % 3, k / 9);
        (o, w[o.x as usize].x * w[o.y as usize].y * w[o.z as usize].z)
    })
}

/// One step: P2G, grid update, G2P. Every particle's stencil must lie on the grid.
pub fn step(p: &mut Particles, t: &Textbook) {
    let nodes = t.cells + 1;
    let node = |i: IVec3| (i.x + nodes.x as i32 * (i.y + nodes.y as i32 * i.z)) as usize;
    let count = (nodes.x * nodes.y * nodes.z) as usize;
    let (inv_dx, dt) = (1.0 / t.dx, t.dt);
    let mut mass = vec![0.0; count];
    let mut momentum = vec![DVec3::ZERO; count];

    // P2G: mass and momentum, with the stress folded into the affine term.
    for q in 0..p.len() {
        let xp = (p.x[q] - t.lo) * inv_dx;
        let base = (xp - 0.5).floor();
        let fx = xp - base;
        let f = p.f[q];
        let (r, _) = polar(f);
        let j = f.determinant();
        let tau = 2.0 * t.lame.mu * (f - r) * f.transpose()
            + DMat3::IDENTITY * (t.lame.lambda * (j - 1.0) * j);
        let affine = p.c[q] * p.mass[q] - tau * (dt * p.volume0[q] * 4.0 * inv_dx * inv_dx);
        for (o, w) in stencil(&weights(fx)) {
            let dpos = (o.as_dvec3() - fx) * t.dx;
            let i = node(base.as_ivec3() + o);
            mass[i] += w * p.mass[q];
            momentum[i] += w * (p.v[q] * p.mass[q] + affine * dpos);
        }
    }

    // Grid update: velocity, gravity, walls that stop motion into them.
    let mut velocity = vec![DVec3::ZERO; count];
    for (i, v) in velocity.iter_mut().enumerate() {
        if mass[i] <= 0.0 {
            continue;
        }
        *v = momentum[i] / mass[i] + t.gravity * dt;
        let at = UVec3::new(
            i as u32 % nodes.x,
            (i as u32 / nodes.x) % nodes.y,
            i as u32 / (nodes.x * nodes.y),
        );
        for a in 0..3 {
            if (at[a] < t.band && v[a] < 0.0) || (at[a] + t.band > t.cells[a] && v[a] > 0.0) {
                v[a] = 0.0;
            }
        }
    }

    // G2P: velocity and its gradient back, then move and deform.
    for q in 0..p.len() {
        let xp = (p.x[q] - t.lo) * inv_dx;
        let base = (xp - 0.5).floor();
        let fx = xp - base;
        let (mut v, mut c) = (DVec3::ZERO, DMat3::ZERO);
        for (o, w) in stencil(&weights(fx)) {
            let dpos = (o.as_dvec3() - fx) * t.dx;
            let vi = velocity[node(base.as_ivec3() + o)];
            v += w * vi;
            c += DMat3::from_cols(vi * dpos.x, vi * dpos.y, vi * dpos.z)
                * (4.0 * inv_dx * inv_dx * w);
        }
        p.v[q] = v;
        p.c[q] = c;
        p.x[q] += dt * v;
        p.f[q] = (DMat3::IDENTITY + dt * c) * p.f[q];
    }
}
