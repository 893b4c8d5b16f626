//! One frame of simulation: its substeps, re-run with a larger sparse-grid pool when they
//! overflowed it, so that results never depend on the pool's size.

use super::gpu::{GpuSim, Watchdog};
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
}

impl GpuSim {
    /// Run `steps` substeps from `start` seconds (the moving colliders' clock). While the
    /// pool can overflow, the particle state is first copied aside on the GPU; when the
    /// steps did overflow it (the moving region grew more than the pool's headroom within
    /// the frame), the pool is grown to twice what the watchdog counted and the frame runs
    /// again from that copy. The pool is not fitted for the next frame here: callers do
    /// that with [`GpuSim::fit_pool`] once they have looked at the watchdog.
    pub fn step_frame(
        &mut self,
        gpu: &GpuContext,
        steps: u32,
        start: f64,
    ) -> Result<FrameSteps, FrameError> {
        let mut reruns = 0;
        loop {
            // A pool at the adapter's limit cannot grow: its overflow is an error, so there
            // is no state to save for a re-run.
            let retry = self.pool_can_overflow() && !self.pool_at_limit();
            if retry {
                self.save_state(gpu)?;
            }
            self.set_time(start);
            self.step(gpu, steps)?;
            let watchdog = self.take_watchdog(gpu)?;
            if watchdog.pool_overflow == 0 {
                return Ok(FrameSteps { watchdog, reruns });
            }
            if !retry {
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
            // The watchdog counts every active block, also those left out: grow to twice that.
            self.fit_pool(gpu, &watchdog)?;
            reruns += 1;
        }
    }
}
