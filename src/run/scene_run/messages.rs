//! What a run says about itself: its lighting and simulation lines, and the error that
//! explains a watchdog's stop.

use super::*;

pub(super) fn describe_lighting(l: &SceneLighting, gaussians: usize) -> String {
    format!(
        "lighting: {} lights, shadows {}, normals of {} Gaussians in {:.2} s",
        l.lights.at(0.0).len(),
        l.setup.shadows.map_or("off".to_string(), |g| format!(
            "{}×{}×{} voxels",
            g.res.x, g.res.y, g.res.z
        )),
        gaussians,
        l.normals_seconds
    )
}

pub(super) fn describe_simulation(
    s: &SimulationSetup,
    p2g: P2gPath,
    deterministic: bool,
) -> String {
    let acting = &s.params.actions;
    let actions = match acting.list.len() {
        0 => String::new(),
        n => format!(
            ", {n} timed action{} on {} particles",
            if n == 1 { "" } else { "s" },
            acting.members.iter().filter(|m| **m != 0).count()
        ),
    };
    format!(
        "simulation: {} particles moving {} Gaussians, {} materials{actions}, grid {}×{}×{} (Δx {}), Δt {:.3e} s, {} steps per frame{}, P2G {}{}",
        s.particles.len(),
        s.binding.len(),
        s.materials.len(),
        s.grid.cells.x,
        s.grid.cells.y,
        s.grid.cells.z,
        s.grid.dx,
        s.params.dt,
        s.steps_per_frame,
        match s.step_rule.cfl_velocity {
            Some(c) => format!(" at first (each frame's Δt follows the motion: cfl_velocity {c})"),
            None => String::new(),
        },
        p2g.name(),
        if deterministic { " (deterministic)" } else { "" }
    )
}

/// The watchdog's stop message: frame, what was counted, the likely cause. Frames
/// already written are complete (each was renamed into place).
pub(super) fn watchdog_message(
    frame: u32,
    w: Watchdog,
    s: &SimulationSetup,
    plan: StepPlan,
    steps_before: u64,
    culprit: Option<(String, f64)>,
) -> String {
    let dt = plan.dt;
    let first = culprit
        .as_ref()
        .map_or(String::new(), |(c, _)| format!("; the first: {c}"));
    // A particle that crossed more than a cell a step did not leave because the domain is
    // small: the step blew up (the CFL condition keeps a particle well under a cell).
    let cells_a_step = culprit.map_or(0.0, |(_, speed)| speed * dt / s.grid.dx);
    let n = plan.steps;
    let steps = match w.first_step {
        // The frame's steps follow the `steps_before` of the frames before it; counted
        // from 1.
        Some(k) => format!(
            "in the {n} steps before frame {frame}, first at step {} (substep {} of {n})",
            steps_before + u64::from(k) + 1,
            k + 1
        ),
        None => format!("in the {n} steps before frame {frame}"),
    };
    if w.nonfinite > 0 {
        format!(
            "simulation stopped: {} particle-steps became NaN/Inf {steps} (Δt {:.3e} s, Δx {}){first}; likely cause: Δt too large for the material's stiffness (lower simulation.dt or simulation.cfl) or a material that inverts (use NACC or fixed_corotated)",
            w.nonfinite, dt, s.grid.dx
        )
    } else if w.fixed_point_range > 0 {
        format!(
            "simulation stopped: {} particle-steps moved faster than the fixed-point P2G's bound of {} cells a step ({:.4e} m/s at Δt {:.3e} s, Δx {}) {steps}; their contributions were not summed; likely cause: Δt far too large for the motion (lower simulation.dt or simulation.cfl)",
            w.fixed_point_range,
            FIXED_POINT_CELLS_PER_STEP,
            FIXED_POINT_CELLS_PER_STEP * s.grid.dx / dt,
            dt,
            s.grid.dx
        )
    } else {
        let (lo, hi) = (s.grid.lo, s.grid.hi());
        let v = |x: DVec3| format!("[{:.3}, {:.3}, {:.3}]", x.x, x.y, x.z);
        let cause = if cells_a_step > 1.0 {
            format!("an instability, not the domain's size: it crossed {cells_a_step:.3e} cells a step (Δt {:.3e} s, Δx {}) where the CFL condition keeps a particle under one; try a smaller simulation.cfl or simulation.dt", dt, s.grid.dx)
        } else {
            "simulation.domain too small for the motion, or Δt too large".to_string()
        };
        format!(
            "simulation stopped: {} particle-steps left the domain {steps} ({} .. {}){first}; likely cause: {cause}",
            w.escaped,
            v(lo),
            v(hi)
        )
    }
}
