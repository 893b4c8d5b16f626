//! Running the CPU reference step (`sim::cpu`, f64) for the studies: a timed loop that
//! stops at the first NaN/Inf or escaped particle instead of panicking, so that a sweep
//! can record an unstable run as data.

use std::time::Instant;

use glam::DVec3;

use splatter::sim::cpu::{check, step};
use splatter::sim::{Grid, Material, Particles, StepParams};

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Outcome {
    /// All steps ran with finite state and every particle on the grid.
    Finished,
    /// A particle became NaN/Inf at this step (1-based).
    NonFinite(usize),
    /// A particle left the grid at this step.
    Escaped(usize),
}

/// What a timed run measured.
#[derive(Clone, Copy, Debug)]
pub struct RunStats {
    pub outcome: Outcome,
    pub steps: usize,
    pub wall_s: f64,
}

/// Runs up to `steps` steps; `gravity(t)` gives the gravity at the step's end time and
/// `each(n, t, particles)` is called after each healthy step. The watchdog check runs
/// every step (its cost is in `wall_s`, as it would be in a real run's per-frame read).
pub fn simulate(
    particles: &mut Particles,
    grid: &mut Grid,
    materials: &[Material],
    params: &StepParams,
    steps: usize,
    gravity: impl Fn(f64) -> DVec3,
    mut each: impl FnMut(usize, f64, &Particles),
) -> RunStats {
    let mut sp = params.clone();
    let start = Instant::now();
    let mut outcome = Outcome::Finished;
    for n in 1..=steps {
        let t = n as f64 * sp.dt;
        sp.gravity = gravity(t);
        step(particles, grid, materials, &sp);
        let h = check(particles, grid, sp.dt);
        if h.non_finite > 0 {
            outcome = Outcome::NonFinite(n);
            break;
        }
        if h.outside > 0 {
            outcome = Outcome::Escaped(n);
            break;
        }
        each(n, t, particles);
    }
    RunStats {
        outcome,
        steps,
        wall_s: start.elapsed().as_secs_f64(),
    }
}

/// The paper's frame (Δt_frame = 1/50 s, docs/method.md §9): costs are reported per such frame of
/// simulated time.
pub const FRAME_S: f64 = 1.0 / 50.0;

/// Wall seconds per simulated frame of [`FRAME_S`].
pub fn seconds_per_frame(stats: &RunStats, dt: f64) -> f64 {
    stats.wall_s / (stats.steps as f64 * dt) * FRAME_S
}
