//! One step of the CPU reference (f64) with some grid nodes driven: P2G, the grid update,
//! then the driven nodes' velocities set (a grip pulling a bar, a plate pressing a block),
//! then G2P. The loading of the studies that deform a specimen at a prescribed speed.

use splatter::sim::actions::Acting;
use splatter::sim::cpu::{check, g2p, grid_update, p2g};
use splatter::sim::{Grid, Material, Particles, StepParams};

/// Step `p` by `params.dt` on `grid`, `drive` setting the driven nodes' velocities after
/// the grid update (gravity and the boundaries as `params` says). Whether every particle
/// stayed finite and on the grid.
pub fn driven_step(
    p: &mut Particles,
    grid: &mut Grid,
    materials: &[Material],
    params: &StepParams,
    drive: impl FnOnce(&mut Grid),
) -> bool {
    let dt = params.dt;
    p2g(p, grid, materials, dt, params.transfer, params.separation);
    grid_update(grid, dt, params.gravity, &params.boundaries);
    drive(grid);
    g2p(
        p,
        grid,
        materials,
        dt,
        params.gravity,
        params.transfer,
        &Acting::none(),
    );
    let h = check(p, grid, dt);
    h.non_finite == 0 && h.outside == 0
}
