//! What the step's watchdog counts and the GPU reads back between frames (`flags` of
//! the step passes): non-finite and escaped particles, the sparse grid's need and overflow,
//! the fixed-point P2G's range, and steps that inverted a particle's deformation.

/// What the watchdog counted (particle-steps, summed over the steps since the last read).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Watchdog {
    pub nonfinite: u32,
    pub escaped: u32,
    /// The first of those steps in which a particle was counted, 0-based from the last read.
    pub first_step: Option<u32>,
    /// The most blocks of 4³ nodes active in one of those steps (the sparse grid's need).
    pub active_blocks_max: u32,
    /// Active blocks that found the grid pool full (their nodes were skipped: the steps are
    /// wrong; grow the pool, [`super::GpuSim::fit_pool`]).
    pub pool_overflow: u32,
    /// Particles past the fixed-point P2G's speed bound (`GpuStep::speed_bound`; they added
    /// nothing to the grid: the steps are wrong).
    pub fixed_point_range: u32,
    /// The largest particle speed of those steps (m/s; finite particles only).
    pub speed_max: f32,
    /// The lowest index of a particle counted as non-finite or escaped.
    pub first_particle: Option<u32>,
    /// Particle-steps whose deformation increment I + Δt C inverted (det ≤ 0). The flow
    /// of a velocity field never inverts matter, so the step was too long for the velocity
    /// gradient there; the law's return mapping then starts from a clamped, flattened F.
    pub inverted: u32,
    /// The first of those steps that counted an inversion, 0-based from the last read.
    pub inverted_first_step: Option<u32>,
    /// The lowest index of a particle counted as inverted.
    pub inverted_first_particle: Option<u32>,
}

impl Watchdog {
    /// Whether a step counted a particle that makes the run wrong (the pool's overflow,
    /// which a re-run with a larger pool repairs, aside).
    pub fn failed(&self) -> bool {
        self.nonfinite > 0 || self.escaped > 0 || self.fixed_point_range > 0
    }

    /// Whether the steps show that Δt was too long for what they met: a step that
    /// inverted a particle's deformation, NaN, or a particle past the fixed-point P2G's
    /// speed bound. Running the same steps at a shorter Δt can repair these; an escape
    /// alone (a domain too small for the motion) it cannot.
    pub fn step_too_long(&self) -> bool {
        self.inverted > 0 || self.nonfinite > 0 || self.fixed_point_range > 0
    }
}
