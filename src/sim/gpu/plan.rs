//! What a simulation asks of the adapter before its [`GpuSim`](super::GpuSim) is built, decided in one
//! place: which P2G path it steps on (forced, deterministic, raced or the best the adapter
//! has), and whether the buffers that path needs fit the adapter, with errors that say
//! what to reduce. A run asks [`SimPlan::choose`] and reaches into nothing else.

use glam::{DVec3, UVec3};

use super::{P2gPath, P2gRace, SimSetupError};
use crate::gpu::limits::{check_gpu, Fit, LimitError, Need};
use crate::gpu::GpuContext;
use crate::sim::StepParams;

/// Advice of a need that more particles than the adapter holds would exceed.
pub const FEWER_PARTICLES: &str = "simulate fewer particles (a larger physics.particles spacing, smaller or fewer objects with physics) or use a GPU with larger buffers";
/// Advice of a need that a grid too large for the adapter would exceed.
pub const SMALLER_GRID: &str =
    "use a coarser or smaller grid (a larger simulation.dx, or a smaller simulation.domain)";

/// Why a simulation cannot be planned on this adapter.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    #[error("--p2g atomic sums with float atomics, whose order varies: it cannot be --deterministic (use --p2g fixed or gather)")]
    AtomicNotDeterministic,
    #[error("simulation: a grid of {:.0}×{:.0}×{:.0} nodes (domain / dx) has more nodes than the 2^32 the simulation indexes; {SMALLER_GRID}", .0.x, .0.y, .0.z)]
    TooManyNodes(DVec3),
    #[error(transparent)]
    Limit(#[from] LimitError),
    #[error(transparent)]
    Setup(#[from] SimSetupError),
}

/// A simulation as the plan sees it.
#[derive(Clone, Copy, Debug)]
pub struct SimRequest<'a> {
    pub params: &'a StepParams,
    pub particles: usize,
    /// Grid cells per axis ([`crate::sim::Grid::cells`]).
    pub cells: UVec3,
    /// Steps the run will take, at least (a race is run only when they pay for it).
    pub steps: u64,
    /// A path the user forced (`--p2g`).
    pub forced: Option<P2gPath>,
    /// Bit-identical frames asked for (`--deterministic`).
    pub deterministic: bool,
}

/// The plan: the P2G path (its buffers checked against the adapter), and the race that
/// chose it if one ran.
#[derive(Clone, Copy, Debug)]
pub struct SimPlan {
    pub p2g: P2gPath,
    pub race: Option<P2gRace>,
}

impl SimPlan {
    /// Refuses options that contradict each other, before anything is built: a forced
    /// float-atomic path cannot give bit-identical frames.
    pub fn check_options(forced: Option<P2gPath>, deterministic: bool) -> Result<(), PlanError> {
        if forced == Some(P2gPath::Atomic) && deterministic {
            return Err(PlanError::AtomicNotDeterministic);
        }
        Ok(())
    }

    /// Refuses a grid the step cannot hold, before the simulation's setup builds it: its
    /// nodes are indexed with 32 bits, and what the step keeps per block, per cell (the
    /// gather path, which two-field separation runs on) and per node (a captured
    /// surface's distance) must fit the adapter. `cells` may be fractional (domain / Δx).
    pub fn check_grid(
        gpu: &GpuContext,
        cells: DVec3,
        separation: bool,
        surface: bool,
    ) -> Result<(), PlanError> {
        let cells = (cells - 1e-9).ceil().max(DVec3::ONE);
        let nodes = cells + 1.0;
        if !nodes.is_finite() || nodes.element_product() >= f64::from(u32::MAX) {
            return Err(PlanError::TooManyNodes(nodes));
        }
        check_gpu(gpu, &sim_needs(0, cells.as_uvec3(), separation, surface))?;
        Ok(())
    }

    /// The path for `req` on `gpu`, in this order: the forced one; with `deterministic`,
    /// the fastest deterministic one ([`P2gPath::deterministic_for`]); where the adapter
    /// leaves the choice to a race and the run is long enough to pay for it, the race's
    /// winner ([`P2gRace`]); else the best path that runs its parameters. Then the
    /// buffers of that path, checked.
    pub fn choose(gpu: &GpuContext, req: &SimRequest) -> Result<SimPlan, PlanError> {
        Self::check_options(req.forced, req.deterministic)?;
        let gather_fits = gather_fits(gpu, req);
        let mut race = None;
        let p2g = if let Some(path) = req.forced {
            path
        } else if req.deterministic {
            P2gPath::deterministic_for(gpu, req.params, req.particles, gather_fits)
        } else if P2gRace::decides(gpu, req.params, req.particles)
            && P2gRace::worth_running(req.particles, req.steps)
            && gather_fits
        {
            let r = P2gRace::on(gpu)?;
            race = Some(r);
            r.winner()
        } else {
            P2gPath::for_params(gpu, req.params)
        };
        let surface = req.params.boundaries.surface.is_some();
        let needs = sim_needs(req.particles, req.cells, p2g == P2gPath::Gather, surface);
        check_gpu(gpu, &needs)?;
        Ok(SimPlan { p2g, race })
    }
}

/// Whether the gather path's buffers fit the adapter: it indexes every base cell of the
/// grid, where the scatters hold only the blocks the particles reach.
fn gather_fits(gpu: &GpuContext, req: &SimRequest) -> bool {
    let surface = req.params.boundaries.surface.is_some();
    check_gpu(gpu, &sim_needs(req.particles, req.cells, true, surface)).is_ok()
}

impl P2gRace {
    /// One line for the run's log: both times and the path taken.
    pub fn describe(&self) -> String {
        format!(
            "P2G on this adapter: float atomics {:.1} ms, gather by subgroups {:.1} ms a step of a probe block (timed in {:.1} s); taking {}",
            self.atomic_ms,
            self.gather_ms,
            self.seconds,
            self.winner().name()
        )
    }
}

/// The simulation's largest buffers for `particles` particles on a grid of `cells` cells
/// per axis ([`Grid::cells`](crate::sim::Grid)), on the gather P2G path when `gather`. The
/// grid's nodes live in a pool of the blocks the particles reach (`GpuSim`), grown as they
/// move and capped where it stops fitting (`GpuSim::max_pool_blocks`), so the whole grid
/// needs only its block tables, 4 bytes a block of 4³ nodes; the gather path also indexes
/// every cell (its runs of sorted particles) and binds the particle arrays whole; a
/// captured surface collider (`surface`) samples its distance at every node.
pub fn sim_needs(particles: usize, cells: UVec3, gather: bool, surface: bool) -> Vec<Need> {
    let n = particles as u64;
    let nodes = cells.to_array().map(|c| u64::from(c) + 1);
    let blocks: u64 = nodes.iter().map(|n| n.div_ceil(4)).product();
    let node_count: u64 = nodes.iter().product();
    let mut needs = vec![
        Need {
            what: if gather {
                format!("the stress-affine terms of {n} particles, which the gather P2G path (two-field separation) binds whole")
            } else {
                format!("the deformation gradients of {n} particles")
            },
            bytes: n * 48,
            advice: FEWER_PARTICLES,
            fit: if gather { Fit::Binding } else { Fit::Buffer },
        },
        Need {
            what: format!(
                "the block table of a grid of {}×{}×{} nodes",
                cells.x + 1,
                cells.y + 1,
                cells.z + 1
            ),
            bytes: blocks * 4,
            advice: SMALLER_GRID,
            fit: Fit::Binding,
        },
    ];
    if surface {
        needs.push(Need {
            what: format!("the captured surface's distance at {node_count} grid nodes"),
            bytes: node_count * 4,
            advice: SMALLER_GRID,
            fit: Fit::Binding,
        });
    }
    if gather {
        needs.push(Need {
            what: format!(
                "the cell ranges of {} grid cells (gather P2G path)",
                crate::sim::gpu::gather_range_entries(cells) - 1
            ),
            bytes: crate::sim::gpu::gather_range_entries(cells) * 8,
            advice: SMALLER_GRID,
            fit: Fit::Binding,
        });
    }
    needs
}
