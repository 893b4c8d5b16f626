//! The CPU reference MPM step (docs/method.md §2), f64 and rayon-parallel: the oracle the f32 GPU
//! step is compared with, and the home of the analytic tests (`tests/sim_cpu.rs`).
//!
//! One [`step`] is docs/method.md §2 verbatim: **P2G** ([`p2g`], MLS-MPM/APIC with quadratic
//! B-splines, affine_p = m_p C_p − Δt V⁰_p (4/Δx²) τ_p), **grid update** ([`grid_update`]:
//! v = p/m, gravity, boundary conditions) and **G2P** ([`g2p`]: v_p, C_p, F ← (I + Δt C) F,
//! x += Δt v, then the material's plasticity: its law's return mapping from the registry
//! (`sim::model`), nothing for a purely elastic material). Velocity is updated before position (symplectic Euler).
//!
//! # P2G without atomics, deterministic
//!
//! P2G is a *sorted gather*: particles are counting-sorted (stable, by particle index) by
//! their stencil's base node, then every grid node sums, in a fixed order, the
//! contributions of the particles whose base lies in the 27 cells that reach it. Each node
//! is written by exactly one task, so the result is bit-for-bit the same on every run and
//! for any number of threads (tested), and the scheme is the atomics-free P2G the GL path
//! of the GPU step can copy.

pub mod textbook;

use glam::{DMat3, DVec3, IVec3, UVec3};
use rayon::prelude::*;

use super::actions::Acting;
use super::boundary::{Boundaries, PlaneCollider};
use super::bspline::Stencil;
use super::fields::Fields;
use super::grid::{FarField, Grid, NO_CELL};
use super::kinematic::{KinematicCollider, RigidPose};
use super::material::Material;
use super::params::{StepParams, StepStats, Transfer};
use super::particles::Particles;
use super::separation::{contact, partition, Separation};

/// Per-particle P2G data, in sorted order.
struct P2gItem {
    w: [DVec3; 3],
    dw: [DVec3; 3],
    fx: DVec3,
    m: f64,
    mv: DVec3,
    affine: DMat3,
    /// Stencil nodes that hold the particle in their far field (`sim::separation`).
    far: u32,
}

/// What P2G sums at one node for one field.
#[derive(Clone, Copy, Default)]
struct NodeSum {
    m: f64,
    p: DVec3,
    /// Σ w m v ([`Grid::carried`]), for a FLIP/PIC blend.
    q: DVec3,
    /// Σ m ∇w, for a two-field contact normal.
    grad: DVec3,
}

/// P2G (docs/method.md §2 step 1) into `grid.mass` and `grid.momentum`, by the sorted gather of the
/// module docs; with two-field `separation` also into `grid.far`, each particle into the
/// field each node holds it in (`sim::separation::partition`). Returns how many particles
/// were left out (stencil off the grid).
// Over 80 lines on purpose: the counting sort, the ordered gather and the two-field split
// share one sorted order; kept whole, it reads beside the GPU passes it mirrors.
pub fn p2g(
    particles: &Particles,
    grid: &mut Grid,
    materials: &[Material],
    dt: f64,
    transfer: Transfer,
    separation: Separation,
) -> usize {
    grid.size_fields();
    let n = particles.len();
    let dx = grid.dx;
    let inv_d = 4.0 / (dx * dx);
    let two_field = separation != Separation::None;
    let sides = if two_field {
        partition(particles, grid, materials)
    } else {
        Vec::new()
    };
    // Base cells: base ∈ [0, cells − 2] per axis.
    let bc = grid.cells - 1;
    let ncell = (bc.x as usize) * (bc.y as usize) * (bc.z as usize);
    let g = &*grid;
    let keys: Vec<u32> = (0..n)
        .into_par_iter()
        .map(|p| match g.stencil(particles.x[p]) {
            Some(st) => {
                let b = st.base.as_uvec3();
                b.x + bc.x * (b.y + bc.y * b.z)
            }
            None => NO_CELL,
        })
        .collect();

    // Stable counting sort by base cell.
    let mut start = std::mem::take(&mut grid.cell_start);
    start.clear();
    start.resize(ncell + 1, 0);
    for &k in &keys {
        if k != NO_CELL {
            start[k as usize + 1] += 1;
        }
    }
    for c in 0..ncell {
        start[c + 1] += start[c];
    }
    let sorted = start[ncell] as usize;
    let escaped = n - sorted;
    let mut order = std::mem::take(&mut grid.order);
    order.clear();
    order.resize(sorted, 0);
    {
        let mut fill = start.clone();
        for (p, &k) in keys.iter().enumerate() {
            if k != NO_CELL {
                order[fill[k as usize] as usize] = p as u32;
                fill[k as usize] += 1;
            }
        }
    }

    let apic = transfer.apic();
    let items: Vec<P2gItem> = order
        .par_iter()
        .map(|&p| {
            let p = p as usize;
            let st = Stencil::new(particles.x[p] - grid.lo, dx);
            let m = particles.mass[p];
            let mat = &materials[particles.material[p] as usize];
            let tau = mat.kirchhoff(particles.f[p], particles.alpha[p]);
            let mut affine = tau * (-dt * particles.volume0[p] * inv_d);
            if apic {
                affine += particles.c[p] * m;
            }
            P2gItem {
                w: st.w,
                dw: st.dw,
                fx: st.fx,
                m,
                mv: particles.v[p] * m,
                affine,
                far: if two_field { sides[p] } else { 0 },
            }
        })
        .collect();

    let nodes = grid.nodes().as_ivec3();
    let bci = bc.as_ivec3();
    let (start_ref, items_ref) = (&start, &items);
    let carry = transfer.flip() > 0.0;
    // The near and far fields' sums at node `idx`.
    let gather = |idx: usize| -> [NodeSum; 2] {
        let node = IVec3::new(
            idx as i32 % nodes.x,
            (idx as i32 / nodes.x) % nodes.y,
            idx as i32 / (nodes.x * nodes.y),
        );
        let mut sum = [NodeSum::default(); 2];
        for oz in 0..3 {
            let bz = node.z - oz;
            if bz < 0 || bz >= bci.z {
                continue;
            }
            for oy in 0..3 {
                let by = node.y - oy;
                if by < 0 || by >= bci.y {
                    continue;
                }
                for ox in 0..3 {
                    let bx = node.x - ox;
                    if bx < 0 || bx >= bci.x {
                        continue;
                    }
                    let cell = (bx + bci.x * (by + bci.y * bz)) as usize;
                    let off = DVec3::new(ox as f64, oy as f64, oz as f64);
                    let bit = ox + 3 * oy + 9 * oz;
                    let (s, e) = (start_ref[cell] as usize, start_ref[cell + 1] as usize);
                    for it in &items_ref[s..e] {
                        let (a, b, c) = (ox as usize, oy as usize, oz as usize);
                        let w = it.w[a].x * it.w[b].y * it.w[c].z;
                        let d = (off - it.fx) * dx;
                        let f = &mut sum[(it.far >> bit & 1) as usize];
                        f.m += w * it.m;
                        f.p += (it.mv + it.affine * d) * w;
                        if carry {
                            f.q += it.mv * w;
                        }
                        if two_field {
                            let dw = DVec3::new(
                                it.dw[a].x * it.w[b].y * it.w[c].z,
                                it.w[a].x * it.dw[b].y * it.w[c].z,
                                it.w[a].x * it.w[b].y * it.dw[c].z,
                            );
                            // ∇ of the node's mass with respect to the node's position: the
                            // stencil's dw is with respect to the particle's, so negated.
                            f.grad -= dw * (it.m / dx);
                        }
                    }
                }
            }
        }
        sum
    };
    if two_field {
        let sums: Vec<[NodeSum; 2]> = (0..grid.node_count()).into_par_iter().map(gather).collect();
        let far = &mut grid.far;
        far.resize(sums.len());
        for (i, [near_sum, far_sum]) in sums.into_iter().enumerate() {
            (grid.mass[i], grid.momentum[i], grid.carried[i]) =
                (near_sum.m, near_sum.p, near_sum.q);
            far.near_mass_gradient[i] = near_sum.grad;
            (far.mass[i], far.momentum[i], far.carried[i]) = (far_sum.m, far_sum.p, far_sum.q);
            far.mass_gradient[i] = far_sum.grad;
        }
        far.sides = sides;
    } else {
        grid.far = FarField::default();
        grid.mass
            .par_iter_mut()
            .zip(grid.momentum.par_iter_mut())
            .zip(grid.carried.par_iter_mut())
            .enumerate()
            .for_each(|(idx, ((m_out, p_out), q_out))| {
                let [s, _] = gather(idx);
                (*m_out, *p_out, *q_out) = (s.m, s.p, s.q);
            });
    }
    grid.cell_start = start;
    grid.order = order;
    escaped
}

/// Grid update (docs/method.md §2 step 2): v_i = p_i/m_i where m_i > 0 (0 elsewhere), v_i += Δt g,
/// then the colliders and the domain walls (module docs).
pub fn grid_update(grid: &mut Grid, dt: f64, gravity: DVec3, boundaries: &Boundaries) {
    grid_update_at(grid, dt, gravity, &Fields::default(), boundaries, &[], 0.0);
}

/// [`grid_update`] with the simulation's force fields (after gravity, [`Fields::apply`]) and
/// moving colliders (`sim::kinematic`) at their pose at `time` seconds, applied after the
/// planar colliders and before the walls.
// Over 80 lines on purpose: one node's conditions in their order (colliders, moving colliders,
// surface, walls), for one and for two fields.
pub fn grid_update_at(
    grid: &mut Grid,
    dt: f64,
    gravity: DVec3,
    fields: &Fields,
    boundaries: &Boundaries,
    kinematic: &[KinematicCollider],
    time: f64,
) {
    let poses: Vec<RigidPose> = kinematic.iter().map(|k| k.motion.pose(time)).collect();
    let cells = grid.cells;
    let (lo, dx, nodes) = (grid.lo, grid.dx, grid.nodes());
    let walls = boundaries.walls;
    let colliders: Vec<PlaneCollider> = boundaries
        .colliders
        .iter()
        .map(|c| PlaneCollider {
            normal: c.normal.normalize(),
            ..*c
        })
        .collect();
    let band = walls.band;
    // The boundary conditions at node `i` (position `x`) on a velocity.
    let constrain = |i: UVec3, x: DVec3, mut v: DVec3| {
        for c in &colliders {
            if (x - c.point).dot(c.normal) <= 0.0 {
                v = c.condition.apply(v, c.normal);
            }
        }
        for (k, pose) in kinematic.iter().zip(&poses) {
            v = k.apply(pose, x, v);
        }
        if let Some(s) = &boundaries.surface {
            v = s.apply(nodes.to_array(), i.to_array(), v);
        }
        for axis in 0..3 {
            let e = DVec3::AXES[axis];
            if i[axis] < band {
                v = walls.faces[2 * axis].apply(v, e);
            }
            if i[axis] + band > cells[axis] {
                v = walls.faces[2 * axis + 1].apply(v, -e);
            }
        }
        v
    };
    let node_of = |idx: usize| {
        let (nx, ny) = (nodes.x as usize, nodes.y as usize);
        UVec3::new(
            (idx % nx) as u32,
            ((idx / nx) % ny) as u32,
            (idx / (nx * ny)) as u32,
        )
    };
    let trial = |m: f64, p: DVec3, x: DVec3| fields.apply(p / m + gravity * dt, x, dt, time);
    if grid.far.mass.is_empty() {
        grid.velocity
            .par_iter_mut()
            .zip(grid.mass.par_iter().zip(grid.momentum.par_iter()))
            .enumerate()
            .for_each(|(idx, (v_out, (&m, &p)))| {
                *v_out = if m > 0.0 {
                    let i = node_of(idx);
                    let x = lo + i.as_dvec3() * dx;
                    constrain(i, x, trial(m, p, x))
                } else {
                    DVec3::ZERO
                };
            });
        return;
    }
    // Two fields (sim::separation): both fields' trial velocities, their contact where a
    // node holds both, then each field's boundary conditions.
    let far = &mut grid.far;
    let (mass, momentum) = (&grid.mass, &grid.momentum);
    grid.velocity
        .par_iter_mut()
        .zip(far.velocity.par_iter_mut())
        .enumerate()
        .for_each(|(idx, (v_near, v_far))| {
            let (m_near, m_far) = (mass[idx], far.mass[idx]);
            let i = node_of(idx);
            let x = lo + i.as_dvec3() * dx;
            let mut near = (m_near > 0.0).then(|| trial(m_near, momentum[idx], x));
            let mut other = (m_far > 0.0).then(|| trial(m_far, far.momentum[idx], x));
            if let (Some(a), Some(b)) = (near, other) {
                let (a, b) = contact(
                    (m_near, a, far.near_mass_gradient[idx]),
                    (m_far, b, far.mass_gradient[idx]),
                );
                (near, other) = (Some(a), Some(b));
            }
            *v_near = near.map_or(DVec3::ZERO, |v| constrain(i, x, v));
            *v_far = other.map_or(DVec3::ZERO, |v| constrain(i, x, v));
        });
}

/// G2P (docs/method.md §2 step 3): v_pic = Σ w v_i, C_p = (4/Δx²) Σ w v_i d_ipᵀ,
/// F ← (I + Δt C) F, x += Δt v_pic, then the material's plasticity. The particle's velocity
/// is v_pic, or with a FLIP/PIC blend flip · (v_p + Σ w Δv_i) + (1 − flip) · v_pic, where
/// Δv_i = v_i − q_i/m_i, q_i = Σ w m_p v_p ([`Grid::carried`]), is what the step's forces
/// changed at node i. A particle whose stencil
/// is off the grid moves ballistically (v += Δt g, x += Δt v; F, C, α unchanged). The
/// step's timed actions (`acting`, [`super::actions`]) then push, hold or drive their
/// particles, before F takes C.
// Over 80 lines on purpose: the CPU twin of one GPU pass: transfer, FLIP blend, deformation
// and plasticity per particle.
pub fn g2p(
    particles: &mut Particles,
    grid: &Grid,
    materials: &[Material],
    dt: f64,
    gravity: DVec3,
    transfer: Transfer,
    acting: &Acting,
) {
    let flip = transfer.flip();
    // Δv_i: the node's velocity after the grid update against the particles' own, before
    // the stress, gravity and boundary conditions changed it.
    let velocity_change = |i: usize, far: bool| {
        let (m, v, q) = if far {
            (grid.far.mass[i], grid.far.velocity[i], grid.far.carried[i])
        } else {
            (grid.mass[i], grid.velocity[i], grid.carried[i])
        };
        if m > 0.0 {
            v - q / m
        } else {
            DVec3::ZERO
        }
    };
    // With two fields, each particle reads the field each node holds it in.
    let sides = &grid.far.sides;
    let velocity = |i: usize, far: bool| {
        if far {
            grid.far.velocity[i]
        } else {
            grid.velocity[i]
        }
    };
    let dx = grid.dx;
    let inv_d = 4.0 / (dx * dx);
    let Particles {
        x,
        v,
        f,
        c,
        alpha,
        material,
        ..
    } = particles;
    (
        x.par_iter_mut(),
        v.par_iter_mut(),
        f.par_iter_mut(),
        c.par_iter_mut(),
        alpha.par_iter_mut(),
        material.par_iter(),
    )
        .into_par_iter()
        .enumerate()
        .for_each(|(p, (x, v, f, c, alpha, mat))| {
            let far_sides = sides.get(p).copied().unwrap_or(0);
            let Some(st) = grid.stencil(*x) else {
                *v += gravity * dt;
                *x += *v * dt;
                return;
            };
            let base = st.base.as_uvec3();
            let mut vp = DVec3::ZERO;
            let mut dv = DVec3::ZERO;
            let mut b = DMat3::ZERO;
            for oz in 0..3u32 {
                for oy in 0..3u32 {
                    let wyz = st.w[oy as usize].y * st.w[oz as usize].z;
                    let row = grid.index(base + UVec3::new(0, oy, oz));
                    for ox in 0..3u32 {
                        let w = st.w[ox as usize].x * wyz;
                        let far = far_sides >> (ox + 3 * oy + 9 * oz) & 1 == 1;
                        let vi = velocity(row + ox as usize, far);
                        let d = (DVec3::new(ox as f64, oy as f64, oz as f64) - st.fx) * dx;
                        vp += vi * w;
                        if flip > 0.0 {
                            dv += velocity_change(row + ox as usize, far) * w;
                        }
                        b += DMat3::from_cols(vi * (w * d.x), vi * (w * d.y), vi * (w * d.z));
                    }
                }
            }
            let mut cp = b * inv_d;
            let mut v_new = if flip > 0.0 {
                (*v + dv) * flip + vp * (1.0 - flip)
            } else {
                vp
            };
            let x0 = *x;
            *x += vp * dt;
            acting.apply(p, x0, &mut v_new, &mut cp, x);
            *v = v_new;
            *c = cp;
            let f_trial = (DMat3::IDENTITY + cp * dt) * *f;
            let (f_new, a_new) = materials[*mat as usize].plasticity_at(f_trial, *alpha, p as u32);
            *f = f_new;
            *alpha = a_new;
        });
}

/// One explicit MPM step (docs/method.md §2): [`p2g`], [`grid_update`], [`g2p`].
pub fn step(
    particles: &mut Particles,
    grid: &mut Grid,
    materials: &[Material],
    params: &StepParams,
) -> StepStats {
    step_at(particles, grid, materials, params, &[], 0.0)
}

/// [`step`] starting at `time` seconds, with moving colliders at their pose at that time
/// ([`grid_update_at`]).
pub fn step_at(
    particles: &mut Particles,
    grid: &mut Grid,
    materials: &[Material],
    params: &StepParams,
    kinematic: &[KinematicCollider],
    time: f64,
) -> StepStats {
    let escaped = p2g(
        particles,
        grid,
        materials,
        params.dt,
        params.transfer,
        params.separation,
    );
    let (dt, g) = (params.dt, params.gravity);
    grid_update_at(
        grid,
        dt,
        g,
        &params.fields,
        &params.boundaries,
        kinematic,
        time,
    );
    g2p(
        particles,
        grid,
        materials,
        params.dt,
        params.gravity,
        params.transfer,
        &params.actions.at(time, dt),
    );
    StepStats { escaped }
}

/// The watchdog's CPU twin: what [`check`] found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Health {
    /// Particles with a NaN/Inf in x, v, F, C or α.
    pub non_finite: usize,
    /// Finite particles whose stencil is not on the grid (left the domain).
    pub outside: usize,
    /// Finite particles with |v| Δt ≥ Δx (docs/method.md §2's velocity CFL bound).
    pub too_fast: usize,
    /// Lowest index of a non-finite particle.
    pub first_non_finite: Option<usize>,
    /// Lowest index of an outside particle.
    pub first_outside: Option<usize>,
}

impl Health {
    /// No NaN/Inf and nothing outside (a fast particle alone is a warning).
    pub fn is_ok(&self) -> bool {
        self.non_finite == 0 && self.outside == 0
    }

    /// The stop message for step `step`, naming the count and the likely cause, or None.
    pub fn message(&self, step: u64) -> Option<String> {
        if self.non_finite > 0 {
            Some(format!(
                "step {step}: {} particle(s) have NaN/Inf state (first: #{}); likely cause: Δt \
                 too large for the stiffness (CFL), or an inverted element (det F ≤ 0) in a \
                 Neo-Hookean material",
                self.non_finite,
                self.first_non_finite.unwrap_or(0)
            ))
        } else if self.outside > 0 {
            Some(format!(
                "step {step}: {} particle(s) left the simulation domain (first: #{}); likely \
                 cause: domain too small, or velocities too large for Δt{}",
                self.outside,
                self.first_outside.unwrap_or(0),
                if self.too_fast > 0 {
                    format!(" ({} particle(s) move ≥ Δx per step)", self.too_fast)
                } else {
                    String::new()
                }
            ))
        } else {
            None
        }
    }
}

/// Counts non-finite particles, particles outside the grid and particles faster than
/// Δx/Δt (see [`Health`]).
pub fn check(particles: &Particles, grid: &Grid, dt: f64) -> Health {
    let limit2 = (grid.dx / dt).powi(2);
    (0..particles.len())
        .into_par_iter()
        .map(|p| {
            let finite = particles.x[p].is_finite()
                && particles.v[p].is_finite()
                && particles.f[p].is_finite()
                && particles.c[p].is_finite()
                && particles.alpha[p].is_finite();
            let mut h = Health::default();
            if !finite {
                h.non_finite = 1;
                h.first_non_finite = Some(p);
            } else {
                if grid.stencil(particles.x[p]).is_none() {
                    h.outside = 1;
                    h.first_outside = Some(p);
                }
                if particles.v[p].length_squared() >= limit2 {
                    h.too_fast = 1;
                }
            }
            h
        })
        .reduce(Health::default, |a, b| Health {
            non_finite: a.non_finite + b.non_finite,
            outside: a.outside + b.outside,
            too_fast: a.too_fast + b.too_fast,
            first_non_finite: min_opt(a.first_non_finite, b.first_non_finite),
            first_outside: min_opt(a.first_outside, b.first_outside),
        })
}

fn min_opt(a: Option<usize>, b: Option<usize>) -> Option<usize> {
    match (a, b) {
        (Some(x), Some(y)) => Some(x.min(y)),
        (x, None) => x,
        (None, y) => y,
    }
}

#[cfg(test)]
mod tests;
