//! The parameters of one MPM step (docs/method.md §2).

use glam::DVec3;

use super::boundary::Boundaries;

/// Particle-to-grid transfer of the affine field.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Transfer {
    /// APIC/MLS (docs/method.md §2's default): m_p C_p is transferred.
    #[default]
    Apic,
    /// PIC: C_p still drives the F update but is not transferred (for comparison only).
    Pic,
}

/// Parameters of one step.
#[derive(Clone, Debug, PartialEq)]
pub struct StepParams {
    pub dt: f64,
    pub gravity: DVec3,
    pub boundaries: Boundaries,
    pub transfer: Transfer,
}

/// What one step saw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepStats {
    /// Particles left out of P2G because their stencil was not on the grid (or their
    /// position not finite).
    pub escaped: usize,
}
