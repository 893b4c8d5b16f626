//! The parameters of one MPM step (docs/method.md §2).

use glam::DVec3;

use super::actions::Actions;
use super::boundary::Boundaries;
use super::fields::Fields;
use super::separation::Separation;

/// How velocity moves between particles and grid (docs/method.md §2, *Transfers*).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Transfer {
    /// APIC/MLS (the default): P2G carries the affine momentum m_p C_p, G2P takes the
    /// interpolated velocity.
    #[default]
    Apic,
    /// A FLIP/PIC blend: P2G carries no affine momentum (C_p still drives the F update),
    /// and G2P sets v_p ← flip · (v_p + Σ w Δv_i) + (1 − flip) · Σ w v_i, with
    /// Δv_i = v_i − Σ w m_p v_p / m_i what the step's forces (stress, gravity, boundary
    /// conditions) changed at node i; positions move with the interpolated velocity.
    /// `flip` in [0, 1]; 0 is PIC.
    FlipPic { flip: f64 },
}

impl Transfer {
    /// Whether P2G carries the affine momentum m_p C_p.
    pub fn apic(self) -> bool {
        self == Transfer::Apic
    }

    /// The FLIP share of the G2P velocity (0 for APIC and PIC).
    pub fn flip(self) -> f64 {
        match self {
            Transfer::Apic => 0.0,
            Transfer::FlipPic { flip } => flip,
        }
    }
}

/// Parameters of one step.
#[derive(Clone, Debug, PartialEq)]
pub struct StepParams {
    pub dt: f64,
    pub gravity: DVec3,
    pub boundaries: Boundaries,
    pub transfer: Transfer,
    pub separation: Separation,
    /// Wind and attractor over the whole simulation (none by default).
    pub fields: Fields,
    /// Timed pushes, holds and drives of regions (none by default).
    pub actions: Actions,
}

impl StepParams {
    /// A drop onto a sticky ground (the domain's floor, walls that let go) with APIC and
    /// one field: the benchmark's and the studies' usual setting.
    pub fn sticky_ground(dt: f64, gravity: DVec3) -> StepParams {
        use super::boundary::{Condition, DomainWalls};
        StepParams {
            dt,
            gravity,
            boundaries: Boundaries {
                walls: DomainWalls::with_ground(Condition::STICKY, Condition::SEPARATE),
                colliders: vec![],
                surface: None,
            },
            transfer: Transfer::Apic,
            separation: Separation::None,
            fields: Default::default(),
            actions: Default::default(),
        }
    }
}

/// What one step saw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepStats {
    /// Particles left out of P2G because their stencil was not on the grid (or their
    /// position not finite).
    pub escaped: usize,
}
