//! The step's constants as the GPU holds them (`SimStep` and its members in
//! `shaders/sim/step/common.wgsl`, `SimMaterial` in `shaders/sim/material.wgsl`), mirrored
//! by `#[repr(C)]` types; `tests::layouts_match_wgsl` checks sizes and offsets with naga.

use bytemuck::{Pod, Zeroable};
use glam::{DMat3, DVec3};

use crate::gpu::GpuError;
use crate::sim::actions::{Effect, MAX_ACTIONS};
use crate::sim::kinematic::{ColliderShape, KinematicCollider, RigidPose};
use crate::sim::model::PLASTIC_PARAMS;
use crate::sim::{Condition, Grid, Material, StepParams};

pub use crate::sim::gpu::codes::{MAX_COLLIDERS, MAX_KINEMATIC, MAX_MATERIALS};

/// A 3×3 matrix as WGSL's `mat3x3<f32>` stores it: three columns padded to vec4.
pub(crate) fn mat3_to_gpu(m: DMat3) -> [[f32; 4]; 3] {
    let m = m.as_mat3();
    [
        m.x_axis.extend(0.0).to_array(),
        m.y_axis.extend(0.0).to_array(),
        m.z_axis.extend(0.0).to_array(),
    ]
}

/// `SimMaterial` of `shaders/sim/material.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuMaterial {
    /// `ElasticModel::code`.
    pub elastic: u32,
    /// `PlasticModel::code`.
    pub plastic: u32,
    pub mu: f32,
    pub lambda: f32,
    pub kappa: f32,
    /// The plastic model's parameters (`PlasticLaw::gpu_params`).
    pub params: [f32; PLASTIC_PARAMS],
}

/// `Condition` of `shaders/sim/step/common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuCondition {
    pub kind: u32,
    pub friction: f32,
    pub _pad: [u32; 2],
}

/// `Collider` of `shaders/sim/step/common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuCollider {
    pub point: [f32; 4],
    pub normal: [f32; 4],
    pub condition: GpuCondition,
}

/// `KinematicCollider` of `shaders/sim/step/common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuKinematic {
    pub shape: u32,
    pub margin: f32,
    pub _pad: [u32; 2],
    pub size: [f32; 4],
    pub centre: [f32; 4],
    pub condition: GpuCondition,
}

/// `KinematicPose` of `shaders/sim/step/common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuPose {
    pub rotation: [[f32; 4]; 3],
    pub position: [f32; 4],
    pub velocity: [f32; 4],
    pub angular_velocity: [f32; 4],
}

impl GpuKinematic {
    pub(crate) fn from_cpu(k: &KinematicCollider) -> Self {
        let size = match k.shape {
            ColliderShape::Sphere { radius } => [radius, 0.0, 0.0],
            ColliderShape::Box { half } => half.to_array(),
            ColliderShape::Cylinder {
                radius,
                half_height,
            } => [radius, half_height, 0.0],
        };
        GpuKinematic {
            shape: k.shape.gpu_code(),
            margin: k.margin as f32,
            _pad: [0; 2],
            size: [size[0] as f32, size[1] as f32, size[2] as f32, 0.0],
            centre: k.centre.as_vec3().extend(0.0).to_array(),
            condition: GpuCondition::from_cpu(&k.condition),
        }
    }
}

impl GpuPose {
    pub(crate) fn from_cpu(p: &RigidPose) -> Self {
        let v4 = |v: DVec3| v.as_vec3().extend(0.0).to_array();
        GpuPose {
            rotation: mat3_to_gpu(p.rotation),
            position: v4(p.position),
            velocity: v4(p.velocity),
            angular_velocity: v4(p.angular_velocity),
        }
    }
}

/// `Action` of `shaders/sim/step/common.wgsl`: what one timed action does over the current
/// substep (`sim::actions::Effect`), rewritten before every substep.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuAction {
    /// A push's Δv, or a move's velocity.
    pub velocity: [f32; 3],
    /// `ACTION_IDLE`, `ACTION_PUSH` or `ACTION_MOVE` (`sim::gpu::codes`).
    pub mode: u32,
    /// A move's displacement.
    pub displacement: [f32; 3],
    pub _pad: u32,
}

impl GpuAction {
    pub(crate) fn from_cpu(e: Option<Effect>) -> Self {
        let v = |v: DVec3| v.as_vec3().to_array();
        let (velocity, displacement) = match e {
            None => (DVec3::ZERO, DVec3::ZERO),
            Some(Effect::Push(dv)) => (dv, DVec3::ZERO),
            Some(Effect::Move {
                velocity,
                displacement,
            }) => (velocity, displacement),
        };
        GpuAction {
            velocity: v(velocity),
            mode: super::super::codes::effect_code(e.as_ref()),
            displacement: v(displacement),
            _pad: 0,
        }
    }
}

/// `SurfaceCondition` of `shaders/sim/step/common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuSurface {
    pub on: u32,
    pub _pad: [u32; 3],
    pub condition: GpuCondition,
}

/// `SimStep` of `shaders/sim/step/common.wgsl`: everything constant over a step.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuStep {
    pub lo: [f32; 3],
    pub dx: f32,
    pub gravity: [f32; 3],
    pub dt: f32,
    pub cells: [u32; 3],
    pub num_particles: u32,
    pub nodes: [u32; 3],
    pub num_colliders: u32,
    pub band: u32,
    pub apic: u32,
    pub num_kinematic: u32,
    /// Blocks the grid pool holds (set by `GpuSim`).
    pub pool_blocks: u32,
    /// The FLIP share of G2P's velocity (`Transfer::flip`; 0: none).
    pub flip: f32,
    /// The fixed-point P2G's units: 2^−`mass_exponent` kg and 2^−`momentum_exponent` kg·m/s
    /// ([`GpuStep::set_fixed_point`]).
    pub mass_exponent: i32,
    pub momentum_exponent: i32,
    /// The speed every particle must stay under for the fixed-point sums to fit (m/s).
    pub speed_bound: f32,
    /// The wind's velocity and drag k (0: no wind), `sim::fields::Wind`.
    pub wind: [f32; 3],
    pub wind_drag: f32,
    /// The attractor's point, acceleration (0: none) and falloff r², `sim::fields::Attractor`.
    pub attractor: [f32; 3],
    pub attractor_strength: f32,
    pub attractor_falloff2: f32,
    /// Timed actions in `actions` (their membership words are a particle buffer).
    pub num_actions: u32,
    pub _fields_pad: [u32; 2],
    pub surface: GpuSurface,
    pub walls: [GpuCondition; 6],
    pub colliders: [GpuCollider; MAX_COLLIDERS],
    pub materials: [GpuMaterial; MAX_MATERIALS],
    pub kinematic: [GpuKinematic; MAX_KINEMATIC],
    /// Rewritten before every substep from [`GpuSim::step`](crate::sim::gpu::GpuSim::step)'s uploaded poses.
    pub poses: [GpuPose; MAX_KINEMATIC],
    /// Last: each action's effect, rewritten before every substep as the poses.
    pub actions: [GpuAction; MAX_ACTIONS],
}

impl GpuCondition {
    pub(crate) fn from_cpu(c: &Condition) -> Self {
        GpuCondition {
            kind: c.kind.gpu_code(),
            friction: c.friction as f32,
            _pad: [0; 2],
        }
    }
}

impl GpuMaterial {
    /// The GPU record of `m`: its registered models' codes and parameters.
    pub fn from_material(m: &Material) -> Self {
        let lame = m.lame();
        GpuMaterial {
            elastic: m.elastic_model().code(),
            plastic: m.plastic_model().code(),
            mu: lame.mu as f32,
            lambda: lame.lambda as f32,
            kappa: lame.kappa() as f32,
            params: m.plastic.gpu_params(&lame),
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum SimSetupError {
    #[error("{0} materials given; the GPU step supports at most {MAX_MATERIALS}")]
    TooManyMaterials(usize),
    #[error("{0} colliders given; the GPU step supports at most {MAX_COLLIDERS}")]
    TooManyColliders(usize),
    #[error("{0} moving colliders given; the GPU step supports at most {MAX_KINEMATIC}")]
    TooManyKinematic(usize),
    #[error("{0} timed actions given; the GPU step supports at most {MAX_ACTIONS}")]
    TooManyActions(usize),
    #[error("the timed actions name {members} particles' members, the simulation has {particles}")]
    ActionMembers { members: usize, particles: usize },
    #[error("the simulation's particles reach {needed} blocks of 4³ grid nodes at the start, more than the {limit} this adapter's grid pool holds (its grid texture, 64 blocks per row of the largest 2D texture, and its sums, one storage binding): use a coarser grid (a larger simulation.dx)")]
    PoolAtLimit { needed: u32, limit: u32 },
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

impl GpuStep {
    pub fn new(
        grid: &Grid,
        materials: &[Material],
        params: &StepParams,
        num_particles: u32,
    ) -> Result<GpuStep, SimSetupError> {
        if materials.len() > MAX_MATERIALS {
            return Err(SimSetupError::TooManyMaterials(materials.len()));
        }
        let actions = &params.actions;
        if actions.list.len() > MAX_ACTIONS {
            return Err(SimSetupError::TooManyActions(actions.list.len()));
        }
        if !actions.is_empty() && actions.members.len() != num_particles as usize {
            return Err(SimSetupError::ActionMembers {
                members: actions.members.len(),
                particles: num_particles as usize,
            });
        }
        let colliders = &params.boundaries.colliders;
        if colliders.len() > MAX_COLLIDERS {
            return Err(SimSetupError::TooManyColliders(colliders.len()));
        }
        let mut step = GpuStep {
            lo: grid.lo.as_vec3().to_array(),
            dx: grid.dx as f32,
            gravity: params.gravity.as_vec3().to_array(),
            dt: params.dt as f32,
            cells: grid.cells.to_array(),
            num_particles,
            nodes: grid.nodes().to_array(),
            num_colliders: colliders.len() as u32,
            band: params.boundaries.walls.band,
            apic: u32::from(params.transfer.apic()),
            num_kinematic: 0,
            pool_blocks: 0,
            flip: params.transfer.flip() as f32,
            mass_exponent: 0,
            momentum_exponent: 0,
            speed_bound: 0.0,
            wind: [0.0; 3],
            wind_drag: 0.0,
            attractor: [0.0; 3],
            attractor_strength: 0.0,
            attractor_falloff2: 0.0,
            num_actions: params.actions.list.len() as u32,
            _fields_pad: [0; 2],
            surface: match &params.boundaries.surface {
                Some(s) => GpuSurface {
                    on: 1,
                    _pad: [0; 3],
                    condition: GpuCondition::from_cpu(&s.condition),
                },
                None => GpuSurface::default(),
            },
            walls: params
                .boundaries
                .walls
                .faces
                .map(|c| GpuCondition::from_cpu(&c)),
            colliders: [GpuCollider::default(); MAX_COLLIDERS],
            materials: [GpuMaterial::default(); MAX_MATERIALS],
            kinematic: [GpuKinematic::default(); MAX_KINEMATIC],
            poses: [GpuPose::default(); MAX_KINEMATIC],
            actions: [GpuAction::default(); MAX_ACTIONS],
        };
        for (slot, c) in step.colliders.iter_mut().zip(colliders) {
            let n = c.normal.normalize();
            *slot = GpuCollider {
                point: [c.point.x as f32, c.point.y as f32, c.point.z as f32, 0.0],
                normal: [n.x as f32, n.y as f32, n.z as f32, 0.0],
                condition: GpuCondition::from_cpu(&c.condition),
            };
        }
        for (slot, m) in step.materials.iter_mut().zip(materials) {
            *slot = GpuMaterial::from_material(m);
        }
        if let Some(w) = &params.fields.wind {
            step.wind = w.velocity.as_vec3().to_array();
            step.wind_drag = w.drag as f32;
        }
        if let Some(a) = &params.fields.attractor {
            step.attractor = a.point.as_vec3().to_array();
            step.attractor_strength = a.strength as f32;
            step.attractor_falloff2 = (a.falloff * a.falloff) as f32;
        }
        Ok(step)
    }
}

/// How many cells a step a particle may cross before the fixed-point P2G refuses it: eight
/// times what the CFL condition allows at all, so only a run that has already failed
/// reaches it.
pub const FIXED_POINT_CELLS_PER_STEP: f64 = 8.0;

/// The most units a fixed-point sum may hold: 2^62, a factor of two under the 64-bit word
/// pair's range.
const FIXED_POINT_SUM_LOG2: f64 = 62.0;

/// The most units one particle's contribution may hold: 2^32, so that adding it to a sum
/// changes the high word only through the low word's carry (an integer atomic less, most
/// of the time).
const FIXED_POINT_PART_LOG2: f64 = 32.0;

impl GpuStep {
    /// The units of the fixed-point P2G (`p2g_fixed.wgsl`) for particles of `total_mass`
    /// whose heaviest is `max_mass`: the largest powers of two under which one particle's
    /// contribution stays under 2^32 units and every sum under 2^62. A node's mass sums
    /// w_ip m_p ≤ m_p over particles, so it is at most the total mass M; each momentum
    /// component sums w_ip |m_p v_p + a_p d_ip| ≤ w_ip m_p V for particles under the speed
    /// bound V (the scatter counts and skips the others), so it is at most M V.
    pub fn set_fixed_point(&mut self, total_mass: f64, max_mass: f64) {
        let speed_bound = FIXED_POINT_CELLS_PER_STEP * f64::from(self.dx) / f64::from(self.dt);
        self.speed_bound = speed_bound as f32;
        self.mass_exponent = fixed_point_exponent(max_mass, total_mass);
        self.momentum_exponent =
            fixed_point_exponent(max_mass * speed_bound, total_mass * speed_bound);
    }
}

/// The largest e with part · 2^e ≤ 2^32 and sum · 2^e ≤ 2^62, kept where f32 can scale by
/// it (a massless set of particles gets the top, which nothing is scaled by).
fn fixed_point_exponent(part: f64, sum: f64) -> i32 {
    let e = (FIXED_POINT_PART_LOG2 - part.log2()).min(FIXED_POINT_SUM_LOG2 - sum.log2());
    if e.is_nan() {
        return 0;
    }
    e.floor().clamp(-100.0, 100.0) as i32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::layout_check::assert_layout;

    #[test]
    fn fixed_point_units_keep_a_part_under_2_32_and_a_sum_under_2_62() {
        let mut step = GpuStep::zeroed();
        step.dx = 0.01;
        step.dt = 1e-4;
        // 1e6 particles of 1e-3 kg: the part bounds the exponent.
        step.set_fixed_point(1e3, 1e-3);
        let speed = 8.0 * 0.01 / 1e-4;
        assert!((f64::from(step.speed_bound) - speed).abs() < 1e-3);
        let scaled = |x: f64, e: i32| x * 2f64.powi(e);
        for (part, sum, e) in [
            (1e-3, 1e3, step.mass_exponent),
            (1e-3 * speed, 1e3 * speed, step.momentum_exponent),
        ] {
            assert!(scaled(part, e) <= 2f64.powi(32) && scaled(part, e) > 2f64.powi(31));
            assert!(scaled(sum, e) <= 2f64.powi(62));
        }
        // 2^40 particles: the sum bounds it.
        step.set_fixed_point(2f64.powi(40), 1.0);
        assert_eq!(step.mass_exponent, 22);
        // No particles: nothing to scale.
        step.set_fixed_point(0.0, 0.0);
        assert_eq!(step.mass_exponent, 100);
    }

    #[test]
    fn layouts_match_wgsl() {
        let src = super::super::source("");
        assert_layout!(
            &src,
            GpuMaterial,
            "SimMaterial",
            [elastic, plastic, mu, lambda, kappa, params]
        );
        assert_layout!(&src, GpuCondition, "Condition", [kind, friction]);
        assert_layout!(&src, GpuSurface, "SurfaceCondition", [on, condition]);
        assert_layout!(&src, GpuCollider, "Collider", [point, normal, condition]);
        assert_layout!(
            &src,
            GpuStep,
            "SimStep",
            [
                lo,
                dx,
                gravity,
                dt,
                cells,
                num_particles,
                nodes,
                num_colliders,
                band,
                apic,
                num_kinematic,
                pool_blocks,
                flip,
                mass_exponent,
                momentum_exponent,
                speed_bound,
                wind,
                wind_drag,
                attractor,
                attractor_strength,
                attractor_falloff2,
                num_actions,
                surface,
                walls,
                colliders,
                materials,
                kinematic,
                poses,
                actions
            ]
        );
        assert_layout!(&src, GpuAction, "Action", [velocity, mode, displacement]);
        assert_layout!(
            &src,
            GpuKinematic,
            "KinematicCollider",
            [shape, margin, size, centre, condition]
        );
        assert_layout!(
            &src,
            GpuPose,
            "KinematicPose",
            [rotation, position, velocity, angular_velocity]
        );
    }
}
