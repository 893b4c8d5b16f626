//! Timed actions on regions of the simulated material (docs/method.md §2.6): a push (an
//! acceleration over a time window, a poke or a kick), a hold (the region pinned) and a
//! drive (the region moved at a velocity or along a keyframed path). Each action acts on
//! the particles of its region, chosen once when the scene is built ([`Actions::members`],
//! one bit per action), during its window [from, to).
//!
//! They act in G2P, after the particle has taken its velocity from the grid, the same on
//! the CPU reference ([`super::cpu::g2p`]) and the GPU (`shaders/sim/step/g2p.wgsl`), so
//! every P2G path sees them alike: the next P2G carries what they set onto the grid, where
//! the stresses pass it on to the rest of the body. Over a step [t, t + Δt] an action
//! takes only the part of the step inside its window, Δt' = |[t, t + Δt] ∩ [from, to)|:
//!
//! - a push adds a Δt' to v_p, so a window delivers exactly a (to − from) per unit mass;
//! - a hold or a drive moves the particle rigidly by the path's displacement over the step,
//!   d = P(t + Δt) − P(t) with P clamped to the window (0 for a hold, u Δt' at a velocity u):
//!   x_p ← x_p + d (instead of the grid's velocity), v_p ← d / Δt and C_p ← 0, so F_p is
//!   kept (the region moves rigidly) and its displacements add up to exactly
//!   P(to) − P(from).
//!
//! Actions apply in list order; a hold or drive replaces what came before it.

use std::sync::Arc;

use glam::{DMat3, DVec3, Vec3};

use crate::spline::KeyedPoint;

/// Actions a simulation may have: one bit each in a particle's membership word, and the
/// GPU step's table.
pub const MAX_ACTIONS: usize = 8;

/// What an action does to its region.
#[derive(Clone, Debug, PartialEq)]
pub enum ActionKind {
    /// dv/dt = a during the window (a force F on a region of mass M is a = F / M).
    Impulse { acceleration: DVec3 },
    /// The region pinned where it is: v = 0, x and F kept.
    Hold,
    /// The region moved rigidly.
    Drive(Drive),
}

/// How a driven region moves.
#[derive(Clone, Debug, PartialEq)]
pub enum Drive {
    /// At a constant velocity (m/s).
    Velocity(DVec3),
    /// By the displacement of a keyframed point on the scene's C¹ Hermite spline (held
    /// before its first key and after its last).
    Path(Path),
}

/// A keyframed point: the region moves by P(t) − P(from).
#[derive(Clone, Debug, PartialEq)]
pub struct Path(KeyedPoint);

impl Path {
    /// Keys at strictly increasing `times` (seconds) with their `positions`.
    pub fn new(times: Vec<f32>, positions: Vec<Vec3>) -> Path {
        let n = times.len();
        Path(KeyedPoint::new(times, positions, vec![Vec3::ZERO; n]))
    }

    /// P(t).
    pub fn at(&self, t: f64) -> DVec3 {
        self.0.at(t as f32).0.as_dvec3()
    }
}

/// One action: what it does, during [from, to) seconds.
#[derive(Clone, Debug, PartialEq)]
pub struct Action {
    pub kind: ActionKind,
    pub from: f64,
    /// `f64::INFINITY`: to the end of the run.
    pub to: f64,
}

/// What an action does to a particle over one step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Effect {
    /// v_p += Δv.
    Push(DVec3),
    /// x_p += displacement, v_p = velocity, C_p = 0.
    Move {
        velocity: DVec3,
        displacement: DVec3,
    },
}

impl Action {
    /// Δt': the part of the step [t, t + Δt] inside the window.
    pub fn overlap(&self, t: f64, dt: f64) -> f64 {
        ((t + dt).min(self.to) - t.max(self.from)).max(0.0)
    }

    /// What the action does over the step [t, t + Δt]; `None` outside its window.
    pub fn effect(&self, t: f64, dt: f64) -> Option<Effect> {
        let inside = self.overlap(t, dt);
        if inside <= 0.0 {
            return None;
        }
        let displacement = match &self.kind {
            ActionKind::Impulse { acceleration } => {
                return Some(Effect::Push(*acceleration * inside))
            }
            ActionKind::Hold => DVec3::ZERO,
            ActionKind::Drive(Drive::Velocity(u)) => *u * inside,
            ActionKind::Drive(Drive::Path(p)) => {
                let clamp = |s: f64| s.clamp(self.from, self.to);
                p.at(clamp(t + dt)) - p.at(clamp(t))
            }
        };
        Some(Effect::Move {
            velocity: displacement / dt,
            displacement,
        })
    }
}

/// A simulation's actions and which particles each acts on.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Actions {
    /// At most [`MAX_ACTIONS`].
    pub list: Vec<Action>,
    /// Per particle, bit k set when action k acts on it (empty without actions).
    pub members: Arc<[u32]>,
}

impl Actions {
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// What the actions do over the step [t, t + Δt].
    pub fn at(&self, t: f64, dt: f64) -> Acting<'_> {
        Acting {
            effects: self.list.iter().map(|a| a.effect(t, dt)).collect(),
            members: &self.members,
        }
    }

    /// Σ m_p over the particles of action `k`.
    pub fn region_mass(&self, k: usize, mass: &[f64]) -> f64 {
        self.members
            .iter()
            .zip(mass)
            .filter(|(m, _)| *m >> k & 1 == 1)
            .map(|(_, m)| *m)
            .sum()
    }
}

/// The actions over one step: each one's effect (`None` outside its window) and the
/// particles' membership words.
pub struct Acting<'a> {
    pub effects: Vec<Option<Effect>>,
    pub members: &'a [u32],
}

impl Acting<'_> {
    /// No actions.
    pub fn none() -> Acting<'static> {
        Acting {
            effects: Vec::new(),
            members: &[],
        }
    }

    /// The effects on particle `p`, in list order: its G2P velocity `v`, affine velocity
    /// `c` and new position `x`, having started the step at `x0`.
    pub fn apply(&self, p: usize, x0: DVec3, v: &mut DVec3, c: &mut DMat3, x: &mut DVec3) {
        let members = self.members.get(p).copied().unwrap_or(0);
        for (k, e) in self.effects.iter().enumerate() {
            if members >> k & 1 == 0 {
                continue;
            }
            match e {
                None => {}
                Some(Effect::Push(dv)) => *v += *dv,
                Some(Effect::Move {
                    velocity,
                    displacement,
                }) => {
                    *v = *velocity;
                    *c = DMat3::ZERO;
                    *x = x0 + *displacement;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn action(kind: ActionKind) -> Action {
        Action {
            kind,
            from: 0.25,
            to: 0.5,
        }
    }

    /// Steps that straddle the window take only their share: a push's Δv over any
    /// stepping adds up to a (to − from), and a drive's displacements to P(to) − P(from).
    #[test]
    fn windows_are_taken_exactly_by_any_stepping() {
        let a = DVec3::new(1.0, -2.0, 0.5);
        let push = action(ActionKind::Impulse { acceleration: a });
        let path = Path::new(
            vec![0.0, 0.3, 1.0],
            vec![
                Vec3::ZERO,
                Vec3::new(0.2, 0.1, 0.0),
                Vec3::new(0.5, 0.0, 0.3),
            ],
        );
        let drive = action(ActionKind::Drive(Drive::Path(path.clone())));
        for dt in [0.03, 0.07, 0.1] {
            let (mut dv, mut d) = (DVec3::ZERO, DVec3::ZERO);
            let mut t = 0.0;
            while t < 1.0 {
                if let Some(Effect::Push(x)) = push.effect(t, dt) {
                    dv += x;
                }
                if let Some(Effect::Move { displacement, .. }) = drive.effect(t, dt) {
                    d += displacement;
                }
                t += dt;
            }
            assert!((dv - a * 0.25).length() < 1e-12, "Δt {dt}: {dv}");
            let want = path.at(0.5) - path.at(0.25);
            assert!((d - want).length() < 1e-6, "Δt {dt}: {d} vs {want}");
        }
        assert_eq!(push.effect(0.0, 0.25), None);
        assert_eq!(push.effect(0.5, 0.1), None);
    }

    /// A hold keeps x where the step started whatever the grid said, zeroes v and C; a
    /// push only adds; a particle outside the action's bits is untouched.
    #[test]
    fn a_hold_pins_and_a_push_adds() {
        let hold = action(ActionKind::Hold).effect(0.3, 0.01);
        let push = Some(Effect::Push(DVec3::X));
        let x0 = DVec3::new(0.1, 0.2, 0.3);
        let run = |members: u32, effects: &[Option<Effect>]| {
            let (mut v, mut c, mut x) = (DVec3::Y, DMat3::IDENTITY, x0 + DVec3::Y * 0.01);
            let acting = Acting {
                effects: effects.to_vec(),
                members: &[members],
            };
            acting.apply(0, x0, &mut v, &mut c, &mut x);
            (v, c, x)
        };
        assert_eq!(run(0b01, &[hold, push]), (DVec3::ZERO, DMat3::ZERO, x0));
        assert_eq!(run(0b11, &[hold, push]), (DVec3::X, DMat3::ZERO, x0));
        assert_eq!(run(0b10, &[hold, push]).0, DVec3::Y + DVec3::X);
        assert_eq!(run(0b00, &[hold, push]).2, x0 + DVec3::Y * 0.01);
    }
}
