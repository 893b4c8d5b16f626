//! Which P2G path steps faster on this adapter, where that is a question of the CPU rather
//! than of the driver: on a CPU driver with subgroups of eight, the float-atomic scatter
//! and the gather by subgroups both run, and which one wins depends on what the host CPU
//! charges for lavapipe's per-lane loads and atomics (docs/performance.md). So a run times
//! both on a small block of particles, once per process and adapter, and takes the faster.

use std::sync::Mutex;
use std::time::Instant;

use glam::DVec3;

use super::{GpuSim, P2gPath, SimSetupError};
use crate::gpu::GpuContext;
use crate::sim::model::nacc::oracle::{Case3Variant, NaccParams};
use crate::sim::{cfl_dt, Grid, Material, Particles, StepParams};

/// The two timings of a race, in ms per step of the probe block, and the faster path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct P2gRace {
    pub atomic_ms: f64,
    pub gather_ms: f64,
    /// Wall time of the whole race, building both probes included.
    pub seconds: f64,
}

impl P2gRace {
    /// The faster path; the atomic scatter on a tie (it needs no sort buffers).
    pub fn winner(&self) -> P2gPath {
        if self.gather_ms < self.atomic_ms {
            P2gPath::Gather
        } else {
            P2gPath::Atomic
        }
    }

    /// Whether a run of `particles` on `gpu` with `params` has the choice a race decides:
    /// float atomics, the gather by subgroups, one field (separation needs the gather) and
    /// the particles in one storage binding (the gather needs them there).
    pub fn decides(gpu: &GpuContext, params: &StepParams, particles: usize) -> bool {
        gpu.features.float32_atomics
            && gpu.cpu_subgroups_of_eight()
            && params.separation == crate::sim::Separation::None
            && GpuSim::pages_for(gpu, particles).count == 1
    }

    /// Whether a run that steps `particles` particles `steps` times is long enough to pay
    /// for a race (a second or so on a CPU driver): a few seconds of stepping at least.
    /// Shorter runs take the float atomics unraced.
    pub fn worth_running(particles: usize, steps: u64) -> bool {
        particles as f64 * steps as f64 >= WORTH_PARTICLE_STEPS
    }

    /// The race on `gpu`, run at its first call in this process and remembered per
    /// adapter.
    pub fn on(gpu: &GpuContext) -> Result<P2gRace, SimSetupError> {
        static DONE: Mutex<Vec<(String, P2gRace)>> = Mutex::new(Vec::new());
        let key = gpu.describe();
        let mut done = DONE.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, race)) = done.iter().find(|(k, _)| *k == key) {
            return Ok(*race);
        }
        let race = run(gpu)?;
        done.push((key, race));
        Ok(race)
    }
}

/// Particle-steps from which a run races: about 5–10 s of stepping on lavapipe, against a
/// race of about one second (most of it building the two probes).
const WORTH_PARTICLE_STEPS: f64 = 1e7;

/// Cells along the probe block's side, on a grid of `PROBE_CELLS`³: eight particles a cell
/// (two a cell along each axis, as scenes sample interiors), about 22 000 particles.
const BLOCK_CELLS: u32 = 14;
const PROBE_CELLS: u32 = 32;
/// Rounds of `STEPS` steps per path, taken alternately; each path keeps its fastest round,
/// so a burst of load on a shared machine costs one round, not the verdict.
const ROUNDS: u32 = 3;
const STEPS: u32 = 4;

fn run(gpu: &GpuContext) -> Result<P2gRace, SimSetupError> {
    let start = Instant::now();
    let (particles, grid, material, params) = probe_block();
    let build = |path| GpuSim::with_path(gpu, &particles, &grid, &[material], &params, path);
    let sims = [build(P2gPath::Atomic)?, build(P2gPath::Gather)?];
    let mut best = [f64::INFINITY; 2];
    for sim in &sims {
        sim.step(gpu, 1)?;
        gpu.wait()?;
    }
    for _ in 0..ROUNDS {
        for (sim, best) in sims.iter().zip(&mut best) {
            let start = Instant::now();
            sim.step(gpu, STEPS)?;
            gpu.wait()?;
            let ms = start.elapsed().as_secs_f64() * 1e3 / f64::from(STEPS);
            *best = best.min(ms);
        }
    }
    Ok(P2gRace {
        atomic_ms: best[0],
        gather_ms: best[1],
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// A cube of NACC particles resting on the floor of a unit box.
fn probe_block() -> (Particles, Grid, Material, StepParams) {
    let density = 2.0;
    let material = Material::nacc(
        NaccParams {
            e: 2000.0,
            nu: 0.4,
            alpha0: -0.04,
            beta: 1.0,
            xi: 2.0,
            m_slope: 2.36,
        },
        Case3Variant::Continuous { k: 2.0 },
    );
    let dx = 1.0 / f64::from(PROBE_CELLS);
    let side = f64::from(BLOCK_CELLS) * dx;
    let lo = DVec3::new(0.5 - side / 2.0, 3.0 * dx, 0.5 - side / 2.0);
    let mut particles = Particles::sample_box(lo, lo + DVec3::splat(side), dx / 2.0, density);
    particles.set_material(0, &material);
    let params = StepParams::sticky_ground(
        cfl_dt(&material, density, dx, 0.4).min(1e-4),
        DVec3::new(0.0, -9.8, 0.0),
    );
    let grid = Grid::new(DVec3::ZERO, DVec3::ONE, dx);
    (particles, grid, material, params)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_runs_of_some_seconds_race() {
        // the donut capture dropped as jelly: 1161 particles, 12 frames of 214 steps
        assert!(!P2gRace::worth_running(1161, 12 * 214));
        // a NACC watermelon and a jelly: 8888 particles, 226 steps a frame for 35 frames
        assert!(P2gRace::worth_running(8888, 35 * 226));
    }

    #[test]
    fn the_faster_path_wins_and_a_tie_goes_to_the_atomics() {
        let race = |atomic_ms, gather_ms| P2gRace {
            atomic_ms,
            gather_ms,
            seconds: 1.0,
        };
        assert_eq!(race(19.0, 11.0).winner(), P2gPath::Gather);
        assert_eq!(race(6.0, 30.0).winner(), P2gPath::Atomic);
        assert_eq!(race(7.0, 7.0).winner(), P2gPath::Atomic);
    }
}
