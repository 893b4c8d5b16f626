//! One frame of simulation: its substeps, re-run with a larger sparse-grid pool when they
//! overflowed it, so that results never depend on the pool's size, and re-run at half the
//! step when they were too long for what they met (docs/method.md §2.3).

use super::gpu::{GpuSim, Watchdog};
use super::time_step::StepPlan;
use crate::gpu::{GpuContext, GpuError};

#[derive(Debug, thiserror::Error)]
pub enum FrameError {
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error("{overflow} block(s) overflowed a sparse-grid pool that holds every block of the domain (an internal error; please report it)")]
    PoolHoldsDomain { overflow: u32 },
    #[error("the simulation's moving region reached {needed} blocks of 4³ grid nodes, more than the {limit} this adapter's grid pool holds (its grid texture, 64 blocks per row of the largest 2D texture, and its sums, one storage binding): use a coarser grid (a larger simulation.dx)")]
    PoolAtLimit { needed: u32, limit: u32 },
}

/// What running a frame's substeps took.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameSteps {
    /// The watchdog of the run that counted (the last one).
    pub watchdog: Watchdog,
    /// How often the frame was run again after its steps overflowed the pool.
    pub reruns: u32,
    /// The steps that counted: the plan's, or twice as many per halving.
    pub plan: StepPlan,
    /// How often Δt was halved because a run's steps were too long
    /// ([`Watchdog::step_too_long`]).
    pub halvings: u32,
}

impl GpuSim {
    /// Run `plan.steps` substeps of `plan.dt` from `start` seconds (the moving colliders'
    /// clock). The particle state is first copied aside on the GPU when a re-run may be
    /// needed, and the frame runs again from that copy:
    /// - when the steps overflowed the sparse grid's pool (the moving region grew more
    ///   than the pool's headroom within the frame): the pool is grown to twice what the
    ///   watchdog counted and the same steps run again;
    /// - when the steps were too long for what they met ([`Watchdog::step_too_long`]: an
    ///   inverted step, NaN), up to `max_halvings` times: Δt is halved (twice the steps)
    ///   and the frame runs again. A step rule that follows the motion chooses Δt before a
    ///   frame from the speed of the last one; this catches what happens within the frame.
    ///
    /// The pool is not fitted for the next frame here: callers do that with
    /// [`GpuSim::fit_pool`] once they have looked at the watchdog.
    pub fn step_frame(
        &mut self,
        gpu: &GpuContext,
        plan: StepPlan,
        start: f64,
        max_halvings: u32,
    ) -> Result<FrameSteps, FrameError> {
        let mut done = FrameSteps {
            plan,
            ..FrameSteps::default()
        };
        let mut saved = false;
        loop {
            // A pool at the adapter's limit cannot grow: its overflow is an error.
            let can_grow = self.pool_can_overflow() && !self.pool_at_limit();
            let can_halve = done.halvings < max_halvings;
            if !saved && (can_grow || can_halve) {
                self.save_state(gpu)?;
                saved = true;
            }
            self.set_dt(gpu, done.plan.dt)?;
            self.set_time(start);
            self.step(gpu, done.plan.steps)?;
            let watchdog = self.take_watchdog(gpu)?;
            done.watchdog = watchdog;
            if watchdog.pool_overflow > 0 {
                if !can_grow {
                    return Err(if self.pool_can_overflow() {
                        FrameError::PoolAtLimit {
                            needed: watchdog.active_blocks_max,
                            limit: self.pool_blocks(),
                        }
                    } else {
                        FrameError::PoolHoldsDomain {
                            overflow: watchdog.pool_overflow,
                        }
                    });
                }
                log::info!(
                    "the sparse grid's pool of {} blocks overflowed by {}; growing it and running the frame again",
                    self.pool_blocks(),
                    watchdog.pool_overflow
                );
                self.restore_state(gpu)?;
                // The watchdog counts every active block, also those left out: grow to
                // twice that.
                self.fit_pool(gpu, &watchdog)?;
                done.reruns += 1;
            } else if watchdog.step_too_long() && can_halve {
                log::info!(
                    "{}; running the frame again at Δt {:.3e} s",
                    too_long(&watchdog, done.plan),
                    done.plan.dt / 2.0
                );
                self.restore_state(gpu)?;
                done.plan = done.plan.halved();
                done.halvings += 1;
            } else {
                return Ok(done);
            }
        }
    }
}

/// What made a frame's steps too long, for the log.
fn too_long(w: &Watchdog, plan: StepPlan) -> String {
    let at = |step: Option<u32>| {
        step.map_or(String::new(), |k| {
            format!(", first at substep {} of {}", k + 1, plan.steps)
        })
    };
    if w.inverted > 0 {
        format!(
            "{} particle-steps inverted their deformation at Δt {:.3e} s{}",
            w.inverted,
            plan.dt,
            at(w.inverted_first_step)
        )
    } else {
        format!(
            "{} particle-steps became NaN/Inf or outran the fixed-point P2G at Δt {:.3e} s{}",
            w.nonfinite + w.fixed_point_range,
            plan.dt,
            at(w.first_step)
        )
    }
}
