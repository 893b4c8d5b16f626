//! The background grid of the MPM step (docs/method.md §2).
//!
//! A dense grid over the axis-aligned box [lo, hi] with spacing Δx: `cells =
//! ceil((hi − lo)/Δx)` per axis (the far face is rounded up to lo + cells·Δx), nodes
//! 0..=cells, node i at lo + i·Δx. A particle's 3×3×3 stencil lies on the grid exactly
//! when every component of s = (x − lo)/Δx is in [0.5, cells − 0.5); a particle outside
//! that range has *escaped* (it is left out of P2G, moves ballistically in G2P, and
//! [`super::cpu::check`] counts it).

use glam::{DVec3, IVec3, UVec3};

use super::bspline::Stencil;

/// A dense MPM grid (module docs). `mass` and `momentum` hold the last P2G's sums,
/// `velocity` the last grid update's result; the CPU step's first P2G sizes them
/// ([`Grid::size_fields`]), so a grid that only describes the GPU step's domain (box,
/// spacing, cells) holds no per-node memory.
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
    /// Σ w_ip m_p v_p: the momentum the particles brought, without the step's stress and
    /// affine terms; what a FLIP/PIC blend's G2P measures the grid's change against
    /// (summed only for such a blend).
    pub carried: Vec<DVec3>,
    pub velocity: Vec<DVec3>,
    /// The second velocity field of a two-field step (`sim::separation`); empty otherwise.
    pub far: FarField,
    /// Counting-sort scratch of the sorted gather (reused between steps).
    pub(crate) cell_start: Vec<u32>,
    pub(crate) order: Vec<u32>,
}

/// A two-field step's far field (`sim::separation`): per node, the sums and velocity of the
/// particles it holds on the far side of a crack (as [`Grid`]'s fields are the near
/// side's), and both fields' mass gradients Σ m_p ∇w_ip, from which the contact normal
/// comes. Sized by the first two-field P2G.
#[derive(Clone, Debug, Default)]
pub struct FarField {
    pub mass: Vec<f64>,
    pub momentum: Vec<DVec3>,
    pub carried: Vec<DVec3>,
    pub velocity: Vec<DVec3>,
    pub mass_gradient: Vec<DVec3>,
    /// The near field's mass gradient.
    pub near_mass_gradient: Vec<DVec3>,
    /// Per particle: the stencil nodes holding it in their far field (bit ox + 3·oy + 9·oz,
    /// `separation::partition`), from the last P2G, for G2P.
    pub sides: Vec<u32>,
}

impl FarField {
    /// Sized for `nodes` nodes, sums cleared.
    pub(crate) fn resize(&mut self, nodes: usize) {
        self.mass.resize(nodes, 0.0);
        for v in [
            &mut self.momentum,
            &mut self.carried,
            &mut self.velocity,
            &mut self.mass_gradient,
            &mut self.near_mass_gradient,
        ] {
            v.resize(nodes, DVec3::ZERO);
        }
    }
}

/// Key of a particle outside the grid in the sort.
pub(crate) const NO_CELL: u32 = u32::MAX;

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
            mass: Vec::new(),
            momentum: Vec::new(),
            carried: Vec::new(),
            velocity: Vec::new(),
            far: FarField::default(),
            cell_start: Vec::new(),
            order: Vec::new(),
        }
    }

    /// One entry per node in each of the near field's arrays (kept when already sized).
    pub(crate) fn size_fields(&mut self) {
        let n = self.node_count();
        self.mass.resize(n, 0.0);
        for v in [&mut self.momentum, &mut self.carried, &mut self.velocity] {
            v.resize(n, DVec3::ZERO);
        }
    }

    /// Nodes per axis (cells + 1).
    pub fn nodes(&self) -> UVec3 {
        self.cells + 1
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        let n = self.nodes();
        (n.x as usize) * (n.y as usize) * (n.z as usize)
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
