//! Boundary conditions (docs/method.md §2), applied to grid velocities after gravity.
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
//! **Moving colliders** (`sim::kinematic`, [`step_at`](crate::sim::cpu::step_at)): rigid shapes on a prescribed path,
//! applied after the planar colliders in the collider's frame (relative velocity).
//!
//! **A surface collider** ([`SurfaceCollider`]): a static captured surface (a table, the
//! floor) as a signed distance φ sampled at every grid node (negative inside,
//! `scene::surface` builds it from the Gaussians' density). A node with φ ≤ 0 gets its
//! condition, with the outward normal ∇φ/|∇φ| from central differences of the nodes
//! around it (one-sided at the grid's faces); where ∇φ vanishes (deep inside) the node is
//! held (v = 0). Applied after the moving colliders, before the walls.

use glam::DVec3;

/// Default width, in cells, of the band of nodes next to each domain face that gets the
/// face's wall condition (see the module docs for why 3).
pub const WALL_BAND: u32 = 3;

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

/// A static surface as a signed distance at the grid nodes (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceCollider {
    /// φ at node (i, j, k), index i + nx (j + ny k) over the grid's nodes; scene units.
    pub phi: Vec<f32>,
    pub condition: Condition,
}

impl SurfaceCollider {
    /// φ at node `i` of a grid with `nodes` nodes per axis, clamped to the grid.
    pub fn phi_at(&self, nodes: [u32; 3], i: [i64; 3]) -> f32 {
        let c = |a: usize| i[a].clamp(0, i64::from(nodes[a]) - 1) as usize;
        let (nx, ny) = (nodes[0] as usize, nodes[1] as usize);
        self.phi[c(0) + nx * (c(1) + ny * c(2))]
    }

    /// The velocity of node `i` after the condition (unchanged outside).
    pub fn apply(&self, nodes: [u32; 3], i: [u32; 3], v: DVec3) -> DVec3 {
        let at = |d: [i64; 3]| self.phi_at(nodes, [0, 1, 2].map(|a| i64::from(i[a]) + d[a]));
        if at([0, 0, 0]) > 0.0 {
            return v;
        }
        let g = DVec3::new(
            f64::from(at([1, 0, 0]) - at([-1, 0, 0])),
            f64::from(at([0, 1, 0]) - at([0, -1, 0])),
            f64::from(at([0, 0, 1]) - at([0, 0, -1])),
        );
        match g.try_normalize() {
            Some(n) => self.condition.apply(v, n),
            None => DVec3::ZERO,
        }
    }
}

/// Every boundary of a step.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Boundaries {
    pub walls: DomainWalls,
    pub colliders: Vec<PlaneCollider>,
    /// A captured static surface, if the scene declares one.
    pub surface: Option<SurfaceCollider>,
}
