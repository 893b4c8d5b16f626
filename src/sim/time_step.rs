//! The time step of each frame (docs/method.md §2.3). Two bounds hold for an explicit MPM
//! step: the materials' fastest elastic wave must not cross a cell in a step (the CFL
//! bound, Δt_c = cfl · Δx / c, fixed by the scene), and neither must the material itself:
//! a particle moving at v crosses v Δt / Δx cells a step, and where an impact stops it
//! against a boundary the velocity jumps by v across a cell, so F changes by about that
//! fraction in one step. The second bound, Δt ≤ cfl_velocity · Δx / v_max, follows the
//! motion. v_max is not known before a frame's steps run, so a frame takes the largest
//! speed the previous frame's steps saw (the watchdog's) plus what gravity adds over a
//! frame, and its Δt is the frame's length over a whole number of equal steps.
//!
//! What a frame meets within its steps the rule cannot see in advance: a splash that
//! reaches a wall faster than the last frame moved, or a state that the law's hardening has
//! made stiffer than the materials' c. The watchdog sees its sign, a step that inverted a
//! particle's deformation (det(I + Δt C) ≤ 0) or NaN, and the frame runs again from its
//! start at half the step, up to [`MAX_HALVINGS`] times (`sim::frame`).

/// A frame's step count may not grow past the wave bound's by more than this: a speed that
/// would need more steps is an instability, not motion (a blown-up particle reads as
/// 10⁶ m/s), and the run stops instead of crawling.
pub const MAX_SHRINK: f64 = 64.0;

/// A frame whose steps were too long runs again at half the step at most this many times
/// (down to Δt/16 of its plan).
pub const MAX_HALVINGS: u32 = 4;

/// At most this many steps a frame.
const MAX_STEPS: f64 = 1e7;

/// How a frame's Δt is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepRule {
    /// A frame's length in seconds.
    pub frame: f64,
    /// The largest Δt: the CFL bound of the materials' waves, or the scene's `dt`.
    pub dt_max: f64,
    /// The fraction of a cell the fastest particle may cross in a step; `None`: Δt stays
    /// `dt_max` (a scene that sets `dt`).
    pub cfl_velocity: Option<f64>,
    pub dx: f64,
    /// |g| in m/s²: what gravity adds to a speed over a frame is part of the bound.
    pub gravity: f64,
}

/// A frame's steps: Δt and how many fill the frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepPlan {
    pub dt: f64,
    pub steps: u32,
}

impl StepPlan {
    /// The same frame in twice as many steps of half the length.
    pub fn halved(self) -> StepPlan {
        StepPlan {
            dt: self.dt / 2.0,
            steps: self.steps.saturating_mul(2),
        }
    }
}

/// A speed that would need a step more than [`MAX_SHRINK`] times under the wave bound.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("a particle moved at {speed:.4e} m/s, which would need Δt {needed:.3e} s, more than {MAX_SHRINK} times under the CFL bound {dt_max:.3e} s: the simulation blew up")]
pub struct TooFast {
    pub speed: f64,
    pub needed: f64,
    pub dt_max: f64,
}

/// Where a run's steps stand after a frame: what the next frame's Δt is chosen from, and
/// the count that names a step in messages. A checkpoint holds it, so that a resumed run
/// takes the very steps the uninterrupted one took.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Clock {
    /// The largest particle speed of the last frame's steps (at the start: of the
    /// particles' initial velocities), m/s.
    pub speed: f64,
    /// Steps taken since frame 0.
    pub steps_done: u64,
}

impl StepRule {
    /// How often a frame may halve its step when the steps were too long: never with a
    /// scene's own `dt` (the user's step is kept as written).
    pub fn max_halvings(&self) -> u32 {
        if self.cfl_velocity.is_some() {
            MAX_HALVINGS
        } else {
            0
        }
    }

    /// The steps of a frame after one whose particles moved at most `speed` (m/s).
    pub fn frame_steps(&self, speed: f64) -> Result<StepPlan, TooFast> {
        let mut dt = self.dt_max;
        if let Some(c) = self.cfl_velocity {
            let v = speed + self.gravity * self.frame;
            let needed = c * self.dx / v;
            if needed * MAX_SHRINK < self.dt_max {
                return Err(TooFast {
                    speed,
                    needed,
                    dt_max: self.dt_max,
                });
            }
            dt = dt.min(needed);
        }
        let steps = (self.frame / dt).ceil().clamp(1.0, MAX_STEPS);
        Ok(StepPlan {
            dt: self.frame / steps,
            steps: steps as u32,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rule(cfl_velocity: Option<f64>) -> StepRule {
        StepRule {
            frame: 1.0 / 24.0,
            dt_max: 1e-4,
            cfl_velocity,
            dx: 0.01,
            gravity: 9.8,
        }
    }

    /// Slow motion keeps the wave bound; fast motion shrinks Δt so that the fastest
    /// particle crosses at most cfl_velocity of a cell a step; either way a whole number
    /// of equal steps fills the frame.
    #[test]
    fn the_step_follows_the_motion() {
        let r = rule(Some(0.2));
        let slow = r.frame_steps(0.0).unwrap();
        assert_eq!(slow.steps, (r.frame / 1e-4).ceil() as u32);
        for speed in [0.0, 5.0, 40.0, 300.0] {
            let s = r.frame_steps(speed).unwrap();
            assert!((s.dt * f64::from(s.steps) - r.frame).abs() < 1e-15);
            assert!(s.dt <= r.dt_max);
            let v = speed + r.gravity * r.frame;
            assert!(v * s.dt / r.dx <= 0.2 + 1e-12, "{speed} m/s: {s:?}");
        }
        let fast = r.frame_steps(40.0).unwrap();
        assert!(fast.steps > slow.steps, "{fast:?} against {slow:?}");
        // Fixed: the scene's dt whatever the speed.
        assert_eq!(rule(None).frame_steps(300.0).unwrap(), slow);
    }

    /// A blown-up particle's speed stops the run rather than asking for millions of steps.
    #[test]
    fn a_blown_up_speed_is_refused() {
        let r = rule(Some(0.2));
        let err = r.frame_steps(2.3e6).unwrap_err();
        assert_eq!(err.speed, 2.3e6);
        assert!(err.to_string().contains("blew up"), "{err}");
        // The edge: just inside MAX_SHRINK is still a step.
        let v = 0.2 * r.dx * MAX_SHRINK / r.dt_max * 0.99 - r.gravity * r.frame;
        assert!(r.frame_steps(v).is_ok());
    }
}
