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

/// What a frame's failed steps left to say: the watchdog of the last run, its steps, how
/// often Δt was halved on the way, and the particles it names (described).
pub(super) struct Failure {
    pub frame: u32,
    pub watchdog: Watchdog,
    /// The steps of the last run (after any halvings).
    pub plan: StepPlan,
    pub halvings: u32,
    /// Steps taken before this frame's.
    pub steps_before: u64,
    /// The first non-finite or escaped particle, and its speed.
    pub culprit: Option<(String, f64)>,
    /// The first particle whose step inverted its deformation, described ("the same
    /// particle" when it is the culprit).
    pub inverted: Option<String>,
}

/// "in the N steps before frame F, first at step S (substep k of N)".
fn steps_before_frame(frame: u32, plan: StepPlan, steps_before: u64, first: Option<u32>) -> String {
    let n = plan.steps;
    match first {
        // The frame's steps follow the `steps_before` of the frames before it; counted
        // from 1.
        Some(k) => format!(
            "in the {n} steps before frame {frame}, first at step {} (substep {} of {n})",
            steps_before + u64::from(k) + 1,
            k + 1
        ),
        None => format!("in the {n} steps before frame {frame}"),
    }
}

/// What came before a failure when steps inverted a particle's deformation: often the
/// origin (a wall stopping a particle within its stencil, or a stiffened state ringing),
/// seen steps before the NaN or the escape it leads to.
fn inversion_clause(f: &Failure) -> String {
    let w = &f.watchdog;
    let Some(particle) = &f.inverted else {
        return String::new();
    };
    format!(
        "; it began with {} particle-steps that inverted their deformation (det(I + Δt ∇v) ≤ 0: the step too long for the velocity gradient there) {}, by {particle}",
        w.inverted,
        steps_before_frame(f.frame, f.plan, f.steps_before, w.inverted_first_step)
    )
}

/// "; the frame ran again at Δt/2 … Δt/2ʰ and still failed", when it did.
fn halved(halvings: u32) -> String {
    match halvings {
        0 => String::new(),
        1 => "; the frame ran again at Δt/2 and still failed".to_string(),
        h => format!(
            "; the frame ran again at Δt/2 … Δt/{} and still failed",
            1u64 << h
        ),
    }
}

/// The watchdog's stop message: frame, what was counted, where it began, the likely cause.
/// Frames already written are complete (each was renamed into place).
pub(super) fn watchdog_message(f: &Failure, s: &SimulationSetup) -> String {
    let w = f.watchdog;
    let dt = f.plan.dt;
    let first = f
        .culprit
        .as_ref()
        .map_or(String::new(), |(c, _)| format!("; the first: {c}"));
    // A particle that crossed more than a cell a step did not leave because the domain is
    // small: the step blew up (the CFL condition keeps a particle well under a cell).
    let cells_a_step = f
        .culprit
        .as_ref()
        .map_or(0.0, |(_, speed)| speed * dt / s.grid.dx);
    let steps = steps_before_frame(f.frame, f.plan, f.steps_before, w.first_step);
    let began = inversion_clause(f) + &halved(f.halvings);
    let smaller = if s.step_rule.cfl_velocity.is_some() {
        "simulation.cfl_velocity or simulation.cfl"
    } else {
        "simulation.dt (or leave dt out, so that the step follows the motion)"
    };
    if w.nonfinite > 0 {
        format!(
            "simulation stopped: {} particle-steps became NaN/Inf {steps} (Δt {:.3e} s, Δx {}){first}{began}; likely cause: Δt too large for the material's stiffness (try a smaller {smaller}) or a material that inverts (use NACC or fixed_corotated)",
            w.nonfinite, dt, s.grid.dx
        )
    } else if w.fixed_point_range > 0 {
        format!(
            "simulation stopped: {} particle-steps moved faster than the fixed-point P2G's bound of {} cells a step ({:.4e} m/s at Δt {:.3e} s, Δx {}) {steps}; their contributions were not summed{began}; likely cause: Δt far too large for the motion (try a smaller {smaller})",
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
            format!("an instability, not the domain's size: it crossed {cells_a_step:.3e} cells a step (Δt {:.3e} s, Δx {}) where the CFL condition keeps a particle under one; try a smaller {smaller}", dt, s.grid.dx)
        } else {
            "simulation.domain too small for the motion, or Δt too large".to_string()
        };
        format!(
            "simulation stopped: {} particle-steps left the domain {steps} ({} .. {}){first}{began}; likely cause: {cause}",
            w.escaped,
            v(lo),
            v(hi)
        )
    }
}

/// The warning, once a run, when steps inverted a particle's deformation and the run went
/// on: a scene's own `dt`, or a frame still inverting at the smallest halved step.
pub(super) fn inversion_warning(
    frame: u32,
    w: &Watchdog,
    plan: StepPlan,
    steps_before: u64,
    particle: &str,
    s: &SimulationSetup,
) -> String {
    let fix = if s.step_rule.cfl_velocity.is_some() {
        "a smaller simulation.cfl_velocity or simulation.cfl"
    } else {
        "a smaller simulation.dt, or no dt (the step then follows the motion and is halved where it inverts)"
    };
    format!(
        "{} particle-steps inverted their deformation (det(I + Δt ∇v) ≤ 0) {} (Δt {:.3e} s), first by {particle}: the step is too long for the velocity gradient there, and the material near it may blow up or show step artifacts; try {fix} (reported once a run)",
        w.inverted,
        steps_before_frame(frame, plan, steps_before, w.inverted_first_step),
        plan.dt
    )
}
