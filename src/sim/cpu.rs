//! The CPU reference MPM step (docs/method.md §2), f64 and rayon-parallel: the oracle the f32 GPU
//! step is compared with, and the home of the analytic tests (`tests/sim_cpu.rs`).
//!
//! One [`step`] is docs/method.md §2 verbatim: **P2G** ([`p2g`], MLS-MPM/APIC with quadratic
//! B-splines, affine_p = m_p C_p − Δt V⁰_p (4/Δx²) τ_p), **grid update** ([`grid_update`]:
//! v = p/m, gravity, boundary conditions) and **G2P** ([`g2p`]: v_p, C_p, F ← (I + Δt C) F,
//! x += Δt v, then the material's plasticity: [`return_map`] for NACC, nothing for the
//! elastic models). Velocity is updated before position (symplectic Euler).
//!
//! # Grid
//!
//! A dense grid over the axis-aligned box [lo, hi] with spacing Δx: `cells =
//! ceil((hi − lo)/Δx)` per axis (the far face is rounded up to lo + cells·Δx), nodes
//! 0..=cells, node i at lo + i·Δx. A particle's 3×3×3 stencil lies on the grid exactly
//! when every component of s = (x − lo)/Δx is in [0.5, cells − 0.5); a particle outside
//! that range has *escaped* (it is left out of P2G, moves ballistically in G2P, and
//! [`check`] counts it).
//!
//! # P2G without atomics, deterministic
//!
//! P2G is a *sorted gather*: particles are counting-sorted (stable, by particle index) by
//! their stencil's base node, then every grid node sums, in a fixed order, the
//! contributions of the particles whose base lies in the 27 cells that reach it. Each node
//! is written by exactly one task, so the result is bit-for-bit the same on every run and
//! for any number of threads (tested), and the scheme is the atomics-free P2G the GL path
//! of the GPU step can copy.
//!
//! # Boundary conditions (docs/method.md §2), applied to grid velocities after gravity
//!
//! A condition acts on a node with the unit normal n pointing *out of the obstacle* into
//! the free region; v_n = v·n (< 0: moving into the obstacle), v_t = v − v_n n:
//!
//! - [`BoundaryKind::Sticky`]: v = 0 (friction is irrelevant).
//! - [`BoundaryKind::Slip`]: bilateral; v ← v_t (the normal component is removed whatever
//!   its sign: the material can slide along the surface but not leave it).
//! - [`BoundaryKind::Separate`]: unilateral; v ← v_t only when v_n < 0, untouched when the
//!   node moves away.
//! - Coulomb friction μ (slip and separate): only under compression (v_n < 0, i.e. when the
//!   surface had to push): the tangential speed drops by μ |v_n| and is clamped at 0,
//!   direction kept: v_t ← v_t max(0, 1 − μ|v_n| / |v_t|). Nothing ever writes v = 0 for
//!   slip or separate unless friction stops the node, which is the point of docs/method.md §2's
//!   warning. The impulse a node's normal velocity change stands for is m|v_n|, so the
//!   friction impulse m μ |v_n| is the Coulomb bound μ·(normal impulse) per node and step.
//!
//! **Domain walls** ([`DomainWalls`]): each of the six faces has its own kind and friction.
//! A node gets a face's condition when it lies within the *boundary band* of that face:
//! index i < band on a lower face, i > cells − band on an upper face, band = 3 by default
//! ([`WALL_BAND`]). Why 3: with quadratic B-splines a particle whose stencil touches the
//! outermost node (s ∈ [0.5, 1.5)) then interpolates only from nodes 0, 1, 2; with all
//! three constrained it cannot move further towards the wall, so a wall can never let a
//! particle's stencil leave the grid. (Two cells, the other common choice, leaves node 2
//! free and lets particles creep out.) The material therefore meets a wall about
//! (band − 1)·Δx inside the box face; a sticky face clamps material at the node
//! lo + (band − 1)Δx (exactly, for the far field of a linear displacement: the spline of a
//! coefficient sequence that is 0 up to node c and linear after it is exactly linear for
//! s ≥ c + ½).
//!
//! **Planar colliders** ([`PlaneCollider`]): a half-space {(x − point)·n ≤ 0} with outward
//! unit normal n; every node with (x_i − point)·n ≤ 0 gets the collider's condition.
//! Colliders are applied first, walls last (so the walls' guarantee holds at corners). A
//! node in the band of two faces gets both conditions, one after the other.
//!
//! **Moving colliders** (`sim::kinematic`, [`step_at`]): rigid shapes on a prescribed path,
//! applied after the planar colliders in the collider's frame (relative velocity).

use glam::{DMat3, DVec3, IVec3, UVec3};
use rayon::prelude::*;

use super::bspline::Stencil;
use super::elasticity::{kirchhoff, ElasticModel, Lame};
use super::kinematic::{KinematicCollider, RigidPose};
use super::nacc::{return_map, Case3Variant, NaccParams};

/// Default width, in cells, of the band of nodes next to each domain face that gets the
/// face's wall condition (see the module docs for why 3).
pub const WALL_BAND: u32 = 3;

/// A material: an elastic model, or NACC plasticity on top of Neo-Hookean (docs/method.md §3–§4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// τ = 2μ (F − R) Fᵀ + λ (J − 1) J I; no plasticity.
    FixedCorotated { lame: Lame },
    /// Borden Neo-Hookean τ = μ J^(−2/3) dev(F Fᵀ) + κ/2 (J² − 1) I; no plasticity. Needs
    /// det F > 0 (an inverted F gives NaN, which [`check`] reports).
    NeoHookean { lame: Lame },
    /// Neo-Hookean stress with the NACC return mapping and hardening after each F update.
    Nacc {
        params: NaccParams,
        variant: Case3Variant,
    },
}

impl Material {
    /// Fixed corotated from Young's modulus and Poisson ratio.
    pub fn fixed_corotated(e: f64, nu: f64) -> Self {
        Material::FixedCorotated {
            lame: Lame::from_young_poisson(e, nu),
        }
    }

    /// Neo-Hookean (Borden) from Young's modulus and Poisson ratio.
    pub fn neo_hookean(e: f64, nu: f64) -> Self {
        Material::NeoHookean {
            lame: Lame::from_young_poisson(e, nu),
        }
    }

    /// Lamé parameters of the elastic part.
    pub fn lame(&self) -> Lame {
        match self {
            Material::FixedCorotated { lame } | Material::NeoHookean { lame } => *lame,
            Material::Nacc { params, .. } => params.lame(),
        }
    }

    /// P-wave modulus λ + 2μ (CFL sound speed c = sqrt((λ + 2μ)/ρ)).
    pub fn p_wave_modulus(&self) -> f64 {
        self.lame().p_wave_modulus()
    }

    /// α a fresh particle starts with: α₀ for NACC, 0 otherwise (unused there).
    pub fn initial_alpha(&self) -> f64 {
        match self {
            Material::Nacc { params, .. } => params.alpha0,
            _ => 0.0,
        }
    }

    /// Kirchhoff stress τ(F) (docs/method.md §3).
    pub fn kirchhoff(&self, f: DMat3) -> DMat3 {
        match self {
            Material::FixedCorotated { lame } => kirchhoff(ElasticModel::FixedCorotated, f, lame),
            Material::NeoHookean { lame } => kirchhoff(ElasticModel::NeoHookean, f, lame),
            Material::Nacc { params, .. } => kirchhoff(ElasticModel::NeoHookean, f, &params.lame()),
        }
    }

    /// The plastic step after the F update: (F, α) unchanged for the elastic models, the
    /// NACC return mapping (docs/method.md §4) otherwise.
    pub fn plasticity(&self, f_trial: DMat3, alpha: f64) -> (DMat3, f64) {
        match self {
            Material::Nacc { params, variant } => {
                let r = return_map(f_trial, alpha, params, *variant);
                (r.f, r.alpha)
            }
            _ => (f_trial, alpha),
        }
    }
}

/// Δt = CFL · Δx / c with c = sqrt((λ + 2μ)/ρ) (docs/method.md §2; CFL ≈ 0.3–0.6).
pub fn cfl_dt(material: &Material, density: f64, dx: f64, cfl: f64) -> f64 {
    cfl * dx / (material.p_wave_modulus() / density).sqrt()
}

/// Particles as a structure of arrays (docs/method.md §1, the simulated part).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Particles {
    /// Positions x_p.
    pub x: Vec<DVec3>,
    /// Velocities v_p.
    pub v: Vec<DVec3>,
    /// Deformation gradients F_p (the elastic part F_E for NACC).
    pub f: Vec<DMat3>,
    /// APIC affine velocity matrices C_p (the velocity gradient of the last G2P).
    pub c: Vec<DMat3>,
    /// NACC hardening state α_p.
    pub alpha: Vec<f64>,
    /// Masses m_p.
    pub mass: Vec<f64>,
    /// Rest volumes V⁰_p.
    pub volume0: Vec<f64>,
    /// Index into the step's material slice.
    pub material: Vec<u32>,
}

impl Particles {
    /// No particles.
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// True when there are no particles.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Adds a particle at rest state F = I, C = 0.
    pub fn push(&mut self, x: DVec3, v: DVec3, mass: f64, volume0: f64, material: u32, alpha: f64) {
        self.x.push(x);
        self.v.push(v);
        self.f.push(DMat3::IDENTITY);
        self.c.push(DMat3::ZERO);
        self.alpha.push(alpha);
        self.mass.push(mass);
        self.volume0.push(volume0);
        self.material.push(material);
    }

    /// Appends all particles of `other`.
    pub fn append(&mut self, other: &Particles) {
        self.x.extend_from_slice(&other.x);
        self.v.extend_from_slice(&other.v);
        self.f.extend_from_slice(&other.f);
        self.c.extend_from_slice(&other.c);
        self.alpha.extend_from_slice(&other.alpha);
        self.mass.extend_from_slice(&other.mass);
        self.volume0.extend_from_slice(&other.volume0);
        self.material.extend_from_slice(&other.material);
    }

    /// Keeps the particles whose position satisfies `keep`, in order.
    pub fn retain_positions(&mut self, keep: impl Fn(DVec3) -> bool) {
        let idx: Vec<usize> = (0..self.len()).filter(|&p| keep(self.x[p])).collect();
        fn pick<T: Copy>(v: &[T], idx: &[usize]) -> Vec<T> {
            idx.iter().map(|&i| v[i]).collect()
        }
        self.x = pick(&self.x, &idx);
        self.v = pick(&self.v, &idx);
        self.f = pick(&self.f, &idx);
        self.c = pick(&self.c, &idx);
        self.alpha = pick(&self.alpha, &idx);
        self.mass = pick(&self.mass, &idx);
        self.volume0 = pick(&self.volume0, &idx);
        self.material = pick(&self.material, &idx);
    }

    /// A regular lattice filling the box [lo, hi]: round((hi − lo)/spacing) points per axis
    /// at lo + (i + ½)·spacing, each with V⁰ = spacing³ and m = ρ V⁰, at rest, material 0,
    /// α = 0. spacing = Δx/2 gives the typical 2³ particles per cell.
    pub fn sample_box(lo: DVec3, hi: DVec3, spacing: f64, density: f64) -> Self {
        let n = ((hi - lo) / spacing).round().max(DVec3::ZERO).as_uvec3();
        let vol = spacing * spacing * spacing;
        let mut out = Particles::new();
        for k in 0..n.z {
            for j in 0..n.y {
                for i in 0..n.x {
                    let x = lo + (UVec3::new(i, j, k).as_dvec3() + 0.5) * spacing;
                    out.push(x, DVec3::ZERO, density * vol, vol, 0, 0.0);
                }
            }
        }
        out
    }

    /// The lattice points of [`Particles::sample_box`] (origin `center − radius`) that lie
    /// strictly inside the ball.
    pub fn sample_sphere(center: DVec3, radius: f64, spacing: f64, density: f64) -> Self {
        let r = DVec3::splat(radius);
        let mut out = Self::sample_box(center - r, center + r, spacing, density);
        out.retain_positions(|x| (x - center).length_squared() < radius * radius);
        out
    }

    /// Sets every particle's material index to `index` and α to `material`'s initial α.
    pub fn set_material(&mut self, index: u32, material: &Material) {
        self.material.iter_mut().for_each(|m| *m = index);
        let a0 = material.initial_alpha();
        self.alpha.iter_mut().for_each(|a| *a = a0);
    }

    /// Σ m_p.
    pub fn total_mass(&self) -> f64 {
        self.mass.iter().sum()
    }

    /// Σ m_p v_p.
    pub fn momentum(&self) -> DVec3 {
        self.mass.iter().zip(&self.v).map(|(m, v)| *m * *v).sum()
    }

    /// Mass-weighted mean position.
    pub fn center_of_mass(&self) -> DVec3 {
        self.mass
            .iter()
            .zip(&self.x)
            .map(|(m, x)| *m * *x)
            .sum::<DVec3>()
            / self.total_mass()
    }

    /// Angular momentum about `origin`. With `apic`, each particle also carries the spin
    /// of its affine field, m_p (Δx²/4) axial(C_p) with axial(A) = (A_zy − A_yz,
    /// A_xz − A_zx, A_yx − A_xy): exactly what P2G puts on the grid (Σ w d × C d =
    /// (Δx²/4) axial(C) since Σ w d dᵀ = Δx²/4 I), so APIC transfers conserve this sum.
    pub fn angular_momentum(&self, origin: DVec3, dx: f64, apic: bool) -> DVec3 {
        let spin = if apic { 0.25 * dx * dx } else { 0.0 };
        (0..self.len())
            .map(|p| {
                let m = self.mass[p];
                (self.x[p] - origin).cross(self.v[p]) * m + axial(self.c[p]) * (m * spin)
            })
            .sum()
    }
}

/// axial(A) = (A_zy − A_yz, A_xz − A_zx, A_yx − A_xy) (twice the axial vector of A's skew
/// part; for A = skew(ω), i.e. A r = ω × r, it is 2ω).
pub fn axial(a: DMat3) -> DVec3 {
    // glam: a.col(c)[r] is row r, column c.
    DVec3::new(
        a.y_axis.z - a.z_axis.y,
        a.z_axis.x - a.x_axis.z,
        a.x_axis.y - a.y_axis.x,
    )
}

/// How a boundary treats the grid velocity of a node it covers (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoundaryKind {
    /// v = 0.
    Sticky,
    /// Remove the normal component (bilateral); friction on the tangential part.
    Slip,
    /// Remove the normal component only when it points into the obstacle (unilateral);
    /// friction on the tangential part.
    Separate,
}

/// One boundary condition: a kind and a Coulomb friction coefficient μ ≥ 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Condition {
    pub kind: BoundaryKind,
    pub friction: f64,
}

impl Condition {
    pub const STICKY: Condition = Condition {
        kind: BoundaryKind::Sticky,
        friction: 0.0,
    };
    pub const SLIP: Condition = Condition {
        kind: BoundaryKind::Slip,
        friction: 0.0,
    };
    pub const SEPARATE: Condition = Condition {
        kind: BoundaryKind::Separate,
        friction: 0.0,
    };

    /// The same kind with friction μ.
    pub fn with_friction(self, mu: f64) -> Self {
        Condition {
            friction: mu,
            ..self
        }
    }

    /// The velocity after the condition, for a node whose obstacle has outward unit normal
    /// `n` (module docs).
    pub fn apply(&self, v: DVec3, n: DVec3) -> DVec3 {
        let vn = v.dot(n);
        match self.kind {
            BoundaryKind::Sticky => DVec3::ZERO,
            BoundaryKind::Separate if vn >= 0.0 => v,
            BoundaryKind::Slip | BoundaryKind::Separate => {
                let vt = v - vn * n;
                if vn < 0.0 && self.friction > 0.0 {
                    let speed = vt.length();
                    let drop = -self.friction * vn;
                    if speed <= drop {
                        DVec3::ZERO
                    } else {
                        vt * (1.0 - drop / speed)
                    }
                } else {
                    vt
                }
            }
        }
    }
}

/// Conditions on the six faces of the grid box, in the order −x, +x, −y, +y, −z, +z, and
/// the band width (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DomainWalls {
    pub faces: [Condition; 6],
    pub band: u32,
}

impl DomainWalls {
    /// The same condition on every face, band [`WALL_BAND`].
    pub fn uniform(c: Condition) -> Self {
        DomainWalls {
            faces: [c; 6],
            band: WALL_BAND,
        }
    }

    /// `rest` on every face and `ground` on −y (y up).
    pub fn with_ground(ground: Condition, rest: Condition) -> Self {
        let mut w = Self::uniform(rest);
        w.faces[2] = ground;
        w
    }
}

impl Default for DomainWalls {
    /// Separate (unilateral, frictionless) walls, band [`WALL_BAND`].
    fn default() -> Self {
        Self::uniform(Condition::SEPARATE)
    }
}

/// A planar collider: the solid half-space {(x − point)·normal ≤ 0}; `normal` points out of
/// the solid (it is normalised when applied).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaneCollider {
    pub point: DVec3,
    pub normal: DVec3,
    pub condition: Condition,
}

/// Every boundary of a step.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Boundaries {
    pub walls: DomainWalls,
    pub colliders: Vec<PlaneCollider>,
}

/// Particle-to-grid transfer of the affine field.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Transfer {
    /// APIC/MLS (docs/method.md §2's default): m_p C_p is transferred.
    #[default]
    Apic,
    /// PIC: C_p still drives the F update but is not transferred (for comparison only).
    Pic,
}

/// Parameters of one step.
#[derive(Clone, Debug, PartialEq)]
pub struct StepParams {
    pub dt: f64,
    pub gravity: DVec3,
    pub boundaries: Boundaries,
    pub transfer: Transfer,
}

/// What one step saw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepStats {
    /// Particles left out of P2G because their stencil was not on the grid (or their
    /// position not finite).
    pub escaped: usize,
}

/// A dense MPM grid (module docs). `mass` and `momentum` hold the last P2G's sums,
/// `velocity` the last grid update's result.
#[derive(Clone, Debug)]
pub struct Grid {
    /// Position of node 0.
    pub lo: DVec3,
    /// Node spacing Δx.
    pub dx: f64,
    /// Cells per axis (nodes = cells + 1).
    pub cells: UVec3,
    pub mass: Vec<f64>,
    pub momentum: Vec<DVec3>,
    pub velocity: Vec<DVec3>,
    /// Counting-sort scratch of the sorted gather (reused between steps).
    cell_start: Vec<u32>,
    order: Vec<u32>,
}

/// Key of a particle outside the grid in the sort.
const NO_CELL: u32 = u32::MAX;

impl Grid {
    /// A grid over [lo, hi] with spacing `dx`: cells = ceil((hi − lo)/dx) per axis (a
    /// relative 1e-9 slack keeps an exact multiple from rounding up). Needs ≥ 3 cells per
    /// axis.
    pub fn new(lo: DVec3, hi: DVec3, dx: f64) -> Self {
        let cells = ((hi - lo) / dx - 1e-9).ceil().max(DVec3::ONE).as_uvec3();
        assert!(
            cells.min_element() >= 3,
            "a grid needs at least 3 cells per axis, got {cells}"
        );
        let n = cells + 1;
        let count = (n.x as usize) * (n.y as usize) * (n.z as usize);
        assert!(count < u32::MAX as usize, "grid too large");
        Grid {
            lo,
            dx,
            cells,
            mass: vec![0.0; count],
            momentum: vec![DVec3::ZERO; count],
            velocity: vec![DVec3::ZERO; count],
            cell_start: Vec::new(),
            order: Vec::new(),
        }
    }

    /// Nodes per axis (cells + 1).
    pub fn nodes(&self) -> UVec3 {
        self.cells + 1
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.mass.len()
    }

    /// The far corner lo + cells·Δx.
    pub fn hi(&self) -> DVec3 {
        self.lo + self.cells.as_dvec3() * self.dx
    }

    /// Linear index of node (i, j, k), x fastest.
    pub fn index(&self, i: UVec3) -> usize {
        let n = self.nodes();
        (i.x as usize) + (n.x as usize) * ((i.y as usize) + (n.y as usize) * (i.z as usize))
    }

    /// (i, j, k) of a linear index.
    pub fn node_of(&self, idx: usize) -> UVec3 {
        let n = self.nodes();
        let (nx, ny) = (n.x as usize, n.y as usize);
        UVec3::new(
            (idx % nx) as u32,
            ((idx / nx) % ny) as u32,
            (idx / (nx * ny)) as u32,
        )
    }

    /// World position lo + i·Δx of node i.
    pub fn node_position(&self, i: UVec3) -> DVec3 {
        self.lo + i.as_dvec3() * self.dx
    }

    /// The stencil of a particle at `x`, relative to node 0, or None when its 3×3×3 nodes
    /// are not all on the grid (or `x` is not finite).
    pub fn stencil(&self, x: DVec3) -> Option<Stencil> {
        if !x.is_finite() {
            return None;
        }
        let s = (x - self.lo) / self.dx;
        let top = self.cells.as_dvec3() - 0.5;
        if s.cmplt(DVec3::splat(0.5)).any() || s.cmpge(top).any() {
            return None;
        }
        let st = Stencil::new(x - self.lo, self.dx);
        // Guard round-off at the range ends.
        let ok =
            st.base.cmpge(IVec3::ZERO).all() && (st.base + 2).cmple(self.cells.as_ivec3()).all();
        ok.then_some(st)
    }

    /// Σ m_i.
    pub fn total_mass(&self) -> f64 {
        self.mass.iter().sum()
    }

    /// Σ p_i (the P2G momentum).
    pub fn total_momentum(&self) -> DVec3 {
        self.momentum.iter().sum()
    }

    /// Σ (x_i − origin) × p_i (the P2G momentum).
    pub fn angular_momentum(&self, origin: DVec3) -> DVec3 {
        (0..self.node_count())
            .map(|i| (self.node_position(self.node_of(i)) - origin).cross(self.momentum[i]))
            .sum()
    }
}

/// Per-particle P2G data, in sorted order.
struct P2gItem {
    w: [DVec3; 3],
    fx: DVec3,
    m: f64,
    mv: DVec3,
    affine: DMat3,
}

/// P2G (docs/method.md §2 step 1) into `grid.mass` and `grid.momentum`, by the sorted gather of the
/// module docs. Returns how many particles were left out (stencil off the grid).
pub fn p2g(
    particles: &Particles,
    grid: &mut Grid,
    materials: &[Material],
    dt: f64,
    transfer: Transfer,
) -> usize {
    let n = particles.len();
    let dx = grid.dx;
    let inv_d = 4.0 / (dx * dx);
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

    let apic = transfer == Transfer::Apic;
    let items: Vec<P2gItem> = order
        .par_iter()
        .map(|&p| {
            let p = p as usize;
            let st = Stencil::new(particles.x[p] - grid.lo, dx);
            let m = particles.mass[p];
            let mat = &materials[particles.material[p] as usize];
            let tau = mat.kirchhoff(particles.f[p]);
            let mut affine = tau * (-dt * particles.volume0[p] * inv_d);
            if apic {
                affine += particles.c[p] * m;
            }
            P2gItem {
                w: st.w,
                fx: st.fx,
                m,
                mv: particles.v[p] * m,
                affine,
            }
        })
        .collect();

    let nodes = grid.nodes().as_ivec3();
    let bci = bc.as_ivec3();
    let (start_ref, items_ref) = (&start, &items);
    grid.mass
        .par_iter_mut()
        .zip(grid.momentum.par_iter_mut())
        .enumerate()
        .for_each(|(idx, (m_out, p_out))| {
            let node = IVec3::new(
                (idx % nodes.x as usize) as i32,
                ((idx / nodes.x as usize) % nodes.y as usize) as i32,
                (idx / (nodes.x as usize * nodes.y as usize)) as i32,
            );
            let (mut msum, mut psum) = (0.0, DVec3::ZERO);
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
                        let (s, e) = (start_ref[cell] as usize, start_ref[cell + 1] as usize);
                        for it in &items_ref[s..e] {
                            let w = it.w[ox as usize].x * it.w[oy as usize].y * it.w[oz as usize].z;
                            let d = (off - it.fx) * dx;
                            msum += w * it.m;
                            psum += (it.mv + it.affine * d) * w;
                        }
                    }
                }
            }
            *m_out = msum;
            *p_out = psum;
        });
    grid.cell_start = start;
    grid.order = order;
    escaped
}

/// Grid update (docs/method.md §2 step 2): v_i = p_i/m_i where m_i > 0 (0 elsewhere), v_i += Δt g,
/// then the colliders and the domain walls (module docs).
pub fn grid_update(grid: &mut Grid, dt: f64, gravity: DVec3, boundaries: &Boundaries) {
    grid_update_at(grid, dt, gravity, boundaries, &[], 0.0);
}

/// [`grid_update`] with moving colliders (`sim::kinematic`) at their pose at `time`
/// seconds, applied after the planar colliders and before the walls.
pub fn grid_update_at(
    grid: &mut Grid,
    dt: f64,
    gravity: DVec3,
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
    grid.velocity
        .par_iter_mut()
        .zip(grid.mass.par_iter().zip(grid.momentum.par_iter()))
        .enumerate()
        .for_each(|(idx, (v_out, (&m, &p)))| {
            if m <= 0.0 {
                *v_out = DVec3::ZERO;
                return;
            }
            let (nx, ny) = (nodes.x as usize, nodes.y as usize);
            let i = UVec3::new(
                (idx % nx) as u32,
                ((idx / nx) % ny) as u32,
                (idx / (nx * ny)) as u32,
            );
            let x = lo + i.as_dvec3() * dx;
            let mut v = p / m + gravity * dt;
            for c in &colliders {
                if (x - c.point).dot(c.normal) <= 0.0 {
                    v = c.condition.apply(v, c.normal);
                }
            }
            for (k, pose) in kinematic.iter().zip(&poses) {
                v = k.apply(pose, x, v);
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
            *v_out = v;
        });
}

/// G2P (docs/method.md §2 step 3): v_p = Σ w v_i, C_p = (4/Δx²) Σ w v_i d_ipᵀ, F ← (I + Δt C) F,
/// x += Δt v_p, then the material's plasticity. A particle whose stencil is off the grid
/// moves ballistically (v += Δt g, x += Δt v; F, C, α unchanged).
pub fn g2p(
    particles: &mut Particles,
    grid: &Grid,
    materials: &[Material],
    dt: f64,
    gravity: DVec3,
) {
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
        .for_each(|(x, v, f, c, alpha, mat)| {
            let Some(st) = grid.stencil(*x) else {
                *v += gravity * dt;
                *x += *v * dt;
                return;
            };
            let base = st.base.as_uvec3();
            let mut vp = DVec3::ZERO;
            let mut b = DMat3::ZERO;
            for oz in 0..3u32 {
                for oy in 0..3u32 {
                    let wyz = st.w[oy as usize].y * st.w[oz as usize].z;
                    let row = grid.index(base + UVec3::new(0, oy, oz));
                    for ox in 0..3u32 {
                        let w = st.w[ox as usize].x * wyz;
                        let vi = grid.velocity[row + ox as usize];
                        let d = (DVec3::new(ox as f64, oy as f64, oz as f64) - st.fx) * dx;
                        vp += vi * w;
                        b += DMat3::from_cols(vi * (w * d.x), vi * (w * d.y), vi * (w * d.z));
                    }
                }
            }
            let cp = b * inv_d;
            let f_trial = (DMat3::IDENTITY + cp * dt) * *f;
            *v = vp;
            *c = cp;
            *x += vp * dt;
            let (f_new, a_new) = materials[*mat as usize].plasticity(f_trial, *alpha);
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
    let escaped = p2g(particles, grid, materials, params.dt, params.transfer);
    let (dt, g) = (params.dt, params.gravity);
    grid_update_at(grid, dt, g, &params.boundaries, kinematic, time);
    g2p(particles, grid, materials, params.dt, params.gravity);
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
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn rand_vec(r: &mut SplitMix64) -> DVec3 {
        DVec3::new(r.uniform(), r.uniform(), r.uniform()) * 2.0 - 1.0
    }

    #[test]
    fn conditions() {
        let n = DVec3::Y;
        let v = DVec3::new(2.0, -1.0, 0.0);
        assert_eq!(Condition::STICKY.apply(v, n), DVec3::ZERO);
        assert_eq!(Condition::SLIP.apply(v, n), DVec3::new(2.0, 0.0, 0.0));
        assert_eq!(Condition::SEPARATE.apply(v, n), DVec3::new(2.0, 0.0, 0.0));
        // Leaving: slip is bilateral, separate lets go.
        let up = DVec3::new(2.0, 1.0, 0.0);
        assert_eq!(Condition::SLIP.apply(up, n), DVec3::new(2.0, 0.0, 0.0));
        assert_eq!(Condition::SEPARATE.apply(up, n), up);
        // Friction: |v_t| 2 → 2 − 0.5·1, never v = 0 unless friction stops it.
        let fr = Condition::SEPARATE.with_friction(0.5);
        assert!((fr.apply(v, n) - DVec3::new(1.5, 0.0, 0.0)).length() < 1e-15);
        assert_eq!(
            Condition::SEPARATE.with_friction(3.0).apply(v, n),
            DVec3::ZERO
        );
        assert_eq!(fr.apply(up, n), up);
        assert!(
            (Condition::SLIP.with_friction(0.5).apply(up, n) - DVec3::X * 2.0).length() < 1e-15
        );
    }

    #[test]
    fn grid_layout() {
        let g = Grid::new(DVec3::ZERO, DVec3::new(1.0, 0.5, 0.25), 1.0 / 32.0);
        assert_eq!(g.cells, UVec3::new(32, 16, 8));
        for idx in [0, 5, 33, 1000, g.node_count() - 1] {
            assert_eq!(g.index(g.node_of(idx)), idx);
        }
        assert!(g.stencil(DVec3::splat(0.5 / 32.0)).is_some());
        assert!(g.stencil(DVec3::splat(0.49 / 32.0)).is_none());
        assert!(g.stencil(DVec3::new(1.0 - 0.51 / 32.0, 0.2, 0.1)).is_some());
        assert!(g.stencil(DVec3::new(1.0 - 0.5 / 32.0, 0.2, 0.1)).is_none());
        assert!(g.stencil(DVec3::NAN).is_none());
    }

    #[test]
    fn sampling_and_cfl() {
        let p = Particles::sample_box(DVec3::ZERO, DVec3::new(0.1, 0.2, 0.3), 0.05, 1000.0);
        assert_eq!(p.len(), 2 * 4 * 6);
        assert!((p.total_mass() - 1000.0 * 0.1 * 0.2 * 0.3).abs() < 1e-12);
        let s = Particles::sample_sphere(DVec3::ZERO, 1.0, 0.05, 1.0);
        let vol = s.volume0.iter().sum::<f64>();
        assert!(
            (vol / (4.0 / 3.0 * std::f64::consts::PI) - 1.0).abs() < 0.01,
            "{vol}"
        );
        let m = Material::fixed_corotated(1.0, 0.0);
        assert!((cfl_dt(&m, 1.0, 0.1, 0.5) - 0.05).abs() < 1e-15);
    }

    #[test]
    fn check_counts() {
        let g = Grid::new(DVec3::ZERO, DVec3::ONE, 0.1);
        let mut p = Particles::sample_box(DVec3::splat(0.4), DVec3::splat(0.6), 0.05, 1.0);
        assert!(check(&p, &g, 1e-3).is_ok());
        p.x[3] = DVec3::new(0.5, 0.5, 1.2);
        p.x[5] = DVec3::new(0.5, -0.1, 0.5);
        p.f[7].x_axis.y = f64::NAN;
        p.v[1] = DVec3::X * 200.0;
        let h = check(&p, &g, 1e-3);
        assert_eq!((h.non_finite, h.outside, h.too_fast), (1, 2, 1));
        assert_eq!((h.first_non_finite, h.first_outside), (Some(7), Some(3)));
        assert!(h.message(12).unwrap().contains("step 12"));
    }

    /// A band of 3 keeps particles on the grid: a block thrown at each wall kind at
    /// 0.9 Δx/Δt (the velocity CFL limit) for 60 steps never leaves it; a sticky wall stops
    /// it, slip and separate keep its tangential velocity.
    #[test]
    fn walls_keep_particles_on_the_grid() {
        let dx = 0.1;
        let dt = 1e-3;
        let mats = [Material::fixed_corotated(10.0, 0.3)];
        for cond in [Condition::STICKY, Condition::SLIP, Condition::SEPARATE] {
            let mut g = Grid::new(DVec3::ZERO, DVec3::ONE, dx);
            let mut p =
                Particles::sample_box(DVec3::new(0.4, 0.4, 0.4), DVec3::splat(0.6), dx / 2.0, 1.0);
            let v0 = DVec3::new(-0.9 * dx / dt, 0.02 * dx / dt, 0.0);
            p.v.iter_mut().for_each(|v| *v = v0);
            let params = StepParams {
                dt,
                gravity: DVec3::ZERO,
                boundaries: Boundaries {
                    walls: DomainWalls::uniform(cond),
                    colliders: vec![],
                },
                transfer: Transfer::Apic,
            };
            for _ in 0..60 {
                assert_eq!(step(&mut p, &mut g, &mats, &params).escaped, 0);
                assert!(check(&p, &g, dt).is_ok(), "{cond:?}");
            }
            let xmin = p.x.iter().map(|x| x.x).fold(f64::MAX, f64::min);
            assert!(xmin >= 0.5 * dx, "{cond:?}: {xmin}");
            let vy = p.momentum().y / p.total_mass();
            match cond.kind {
                BoundaryKind::Sticky => {
                    assert!(p.momentum().length() < 0.5 * v0.length() * p.total_mass())
                }
                _ => assert!(vy > 0.0, "{cond:?}: tangential velocity lost"),
            }
        }
    }

    /// The sorted gather equals a plain sequential scatter, and the step is bit-identical
    /// for 1 and 3 threads.
    #[test]
    fn gather_matches_scatter_and_is_deterministic() {
        let mut r = SplitMix64::new(5);
        let dx = 0.1;
        let mut g = Grid::new(DVec3::ZERO, DVec3::ONE, dx);
        let mats = [
            Material::fixed_corotated(1e3, 0.3),
            Material::neo_hookean(2e3, 0.2),
        ];
        let mut p = Particles::new();
        for i in 0..500 {
            let x = DVec3::splat(0.5) + rand_vec(&mut r) * 0.3;
            p.push(x, rand_vec(&mut r), 0.5 + r.uniform(), 1e-3, i % 2, 0.0);
            p.c[i as usize] =
                DMat3::from_cols(rand_vec(&mut r), rand_vec(&mut r), rand_vec(&mut r));
            p.f[i as usize] +=
                DMat3::from_cols(rand_vec(&mut r), rand_vec(&mut r), rand_vec(&mut r)) * 0.1;
        }
        let dt = 1e-3;
        p2g(&p, &mut g, &mats, dt, Transfer::Apic);
        let mut m_ref = vec![0.0; g.node_count()];
        let mut p_ref = vec![DVec3::ZERO; g.node_count()];
        for q in 0..p.len() {
            let st = g.stencil(p.x[q]).unwrap();
            let tau = mats[p.material[q] as usize].kirchhoff(p.f[q]);
            let a = p.c[q] * p.mass[q] - tau * (dt * p.volume0[q] * 4.0 / (dx * dx));
            for o in crate::sim::bspline::stencil_offsets() {
                let i = g.index(st.node(o).as_uvec3());
                let w = st.weight(o);
                m_ref[i] += w * p.mass[q];
                p_ref[i] += (p.v[q] * p.mass[q] + a * st.offset(o, dx)) * w;
            }
        }
        for i in 0..g.node_count() {
            assert!((g.mass[i] - m_ref[i]).abs() < 1e-12);
            assert!((g.momentum[i] - p_ref[i]).length() < 1e-10);
        }
        let params = StepParams {
            dt,
            gravity: DVec3::new(0.0, -9.8, 0.0),
            boundaries: Boundaries::default(),
            transfer: Transfer::Apic,
        };
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let (mut q, mut gg) = (p.clone(), g.clone());
                for _ in 0..5 {
                    step(&mut q, &mut gg, &mats, &params);
                }
                q
            })
        };
        assert_eq!(run(1), run(3));
    }
}
