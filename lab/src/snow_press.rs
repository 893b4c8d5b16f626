//! Snow packed under load (`sim::model::Snow`) on the CPU reference step (f64): a block
//! in a frictionless box (the domain's separating walls, which the block fills wall to
//! wall) pressed by a plate that comes down at a constant speed — confined (uniaxial)
//! compaction, docs/notes/snow.md *Snow: a snowball on impact and under load*. Used by
//! `examples/snow_press.rs`.
//!
//! The plate is the grid nodes at or above its height: their vertical velocity is the
//! plate's, their horizontal one is left free (a frictionless plate). Measured per sample:
//! the compression 1 − H/H₀ (H the plate's height above the floor), the block's density
//! ratio ρ/ρ₀ = Σ V⁰ / Σ V⁰ J with J = det F_E · Jᴾ (F_E the particle's F, Jᴾ = e^α), which
//! mass conservation in a confined box fixes at H₀/H, its plastic part 1/Jᴾ (mean and
//! largest), and the pressure on the plate, the mean vertical Kirchhoff stress
//! −Σ τ_zz V⁰ / (A H) (the force through a horizontal slice, averaged over the height,
//! over the box's section A).
//!
//! Snow stiffens by e^{ξ (1 − Jᴾ)} as it packs, and the sound speed with the square root of
//! that, so Δt is recomputed every step from the stiffest particle (the scene file's Δt is
//! fixed at the start: docs/notes/snow.md).

use glam::DVec3;

use crate::driven::driven_step;
use splatter::sim::model::{PlasticLaw, Snow};
use splatter::sim::{
    cfl_dt, Boundaries, Condition, DomainWalls, Grid, Material, Particles, StepParams, Transfer,
};

/// The block and the press.
#[derive(Clone, Copy, Debug)]
pub struct PressSpec {
    /// Side of the cubic block, m.
    pub size: f64,
    pub dx: f64,
    pub ppc_axis: u32,
    pub e: f64,
    pub nu: f64,
    pub density: f64,
    pub law: Snow,
    /// Final compression 1 − H/H₀.
    pub compression: f64,
    /// Plate speed, m/s.
    pub speed: f64,
    pub cfl: f64,
}

impl PressSpec {
    /// Stomakhin et al.'s reference snow (E 1.4e5, ν 0.2, ρ 400, θ_c 0.025, θ_s 0.0075,
    /// ξ 10) in an 8 cm cube at Δx 0.01 (2³ particles per cell), pressed to 40% at 0.2 m/s
    /// (the block's wave transit is 4 ms, the press 160 ms).
    pub fn reference() -> Self {
        PressSpec {
            size: 0.08,
            dx: 0.01,
            ppc_axis: 2,
            e: 1.4e5,
            nu: 0.2,
            density: 400.0,
            law: Snow {
                critical_compression: 0.025,
                critical_stretch: 0.0075,
                hardening: 10.0,
            },
            compression: 0.4,
            speed: 0.2,
            cfl: 0.3,
        }
    }
}

/// One sample.
#[derive(Clone, Copy, Debug)]
pub struct PressSample {
    pub t: f64,
    /// 1 − H/H₀.
    pub compression: f64,
    /// Σ V⁰ / Σ V⁰ J.
    pub density_ratio: f64,
    /// H₀/H with H from the plate's first node: the nodes move, not the plate, so the
    /// material meets the plate at the first node at or above it (as it meets the floor at
    /// the floor's band's last node); what mass conservation gives for ρ/ρ₀.
    pub confined_ratio: f64,
    /// The same from the particles: the rest distance between the mean heights of the
    /// top and bottom lattice layers over the current one.
    pub layer_ratio: f64,
    /// Mean and largest 1/Jᴾ.
    pub plastic_mean: f64,
    pub plastic_max: f64,
    /// Mean vertical pressure, Pa.
    pub pressure: f64,
    /// The step's Δt.
    pub dt: f64,
}

/// What a press measured.
#[derive(Clone, Debug)]
pub struct PressResult {
    pub samples: Vec<PressSample>,
    pub particles: usize,
    pub steps: usize,
    pub healthy: bool,
}

/// Runs the press (module docs).
pub fn run(spec: &PressSpec) -> PressResult {
    let dx = spec.dx;
    let band = f64::from(splatter::sim::WALL_BAND - 1);
    // Walls meet material (band − 1)Δx inside the box faces: the block fills that box.
    let lo_m = band * dx;
    let side = ((spec.size / dx).round() + 2.0 * band) * dx;
    let top0 = lo_m + spec.size;
    let hi = DVec3::new(side, side, top0 + 4.0 * dx);
    let mut grid = Grid::new(DVec3::ZERO, hi, dx);
    let mut p = Particles::sample_box(
        DVec3::splat(lo_m),
        DVec3::new(side - lo_m, side - lo_m, top0),
        dx / f64::from(spec.ppc_axis),
        spec.density,
    );
    let mat = Material::plastic(spec.law, spec.e, spec.nu);
    let materials = [mat];
    let z_rest: Vec<f64> = p.x.iter().map(|x| x.z).collect();
    let (z_min, z_max) = z_rest
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &z| (a.min(z), b.max(z)));
    let half = 0.25 * dx / f64::from(spec.ppc_axis);
    let bottom: Vec<usize> = (0..p.len()).filter(|&q| z_rest[q] < z_min + half).collect();
    let top: Vec<usize> = (0..p.len()).filter(|&q| z_rest[q] > z_max - half).collect();
    let mean_z = |p: &Particles, idx: &[usize]| {
        idx.iter().map(|&q| p.x[q].z).sum::<f64>() / idx.len() as f64
    };
    let mut params = StepParams {
        dt: 0.0,
        gravity: DVec3::ZERO,
        boundaries: Boundaries {
            walls: DomainWalls::uniform(Condition::SEPARATE),
            colliders: vec![],
            surface: None,
        },
        transfer: Transfer::Apic,
        separation: Default::default(),
        fields: Default::default(),
        actions: Default::default(),
    };
    let area = (side - 2.0 * lo_m).powi(2);
    let dt0 = cfl_dt(&mat, spec.density, dx, spec.cfl);
    let t_end = spec.compression * spec.size / spec.speed;
    let (mut t, mut steps) = (0.0, 0usize);
    let mut samples = Vec::new();
    let mut healthy = true;
    let every = (t_end / 200.0).max(dt0);
    let mut next_sample = 0.0;
    // The plate starts at rest on the block and reaches its speed over 5% of the press.
    let ramp = 0.05 * t_end;
    let travel = |t: f64| {
        let s = if t < ramp {
            0.5 * t * t / ramp
        } else {
            t - 0.5 * ramp
        };
        spec.speed * s
    };
    let lo_z = grid.lo.z;
    let plate_node = |z: f64| ((z - lo_z) / dx - 1e-9).ceil() * dx + lo_z;
    while t < t_end + 0.5 * ramp {
        let stiff = p
            .alpha
            .iter()
            .map(|&a| spec.law.stress_scale(a))
            .fold(1.0, f64::max);
        let dt = dt0 / stiff.sqrt();
        params.dt = dt;
        let speed = spec.speed * (t / ramp).min(1.0);
        let plate = top0 - travel(t);
        // The plate: the nodes at or above it move down at its speed.
        let press = |grid: &mut Grid| {
            let nodes = grid.nodes();
            for (idx, v) in grid.velocity.iter_mut().enumerate() {
                let k = idx / (nodes.x as usize * nodes.y as usize);
                if grid.mass[idx] > 0.0 && grid.lo.z + k as f64 * dx >= plate - 1e-9 * dx {
                    v.z = -speed;
                }
            }
        };
        let ok = driven_step(&mut p, &mut grid, &materials, &params, press);
        t += dt;
        steps += 1;
        if !ok {
            healthy = false;
            break;
        }
        if t >= next_sample {
            next_sample += every;
            let height = top0 - travel(t) - lo_m;
            let (mut v0, mut v, mut tzz, mut inv_jp, mut max_inv) = (0.0, 0.0, 0.0, 0.0, 1.0f64);
            for q in 0..p.len() {
                let jp = p.alpha[q].exp();
                v0 += p.volume0[q];
                v += p.volume0[q] * p.f[q].determinant() * jp;
                tzz += mat.kirchhoff(p.f[q], p.alpha[q]).z_axis.z * p.volume0[q];
                inv_jp += 1.0 / jp;
                max_inv = max_inv.max(1.0 / jp);
            }
            samples.push(PressSample {
                t,
                compression: 1.0 - height / spec.size,
                density_ratio: v0 / v,
                confined_ratio: spec.size / (plate_node(top0 - travel(t)) - lo_m),
                layer_ratio: (z_max - z_min) / (mean_z(&p, &top) - mean_z(&p, &bottom)),
                plastic_mean: inv_jp / p.len() as f64,
                plastic_max: max_inv,
                pressure: -tzz / (area * height),
                dt,
            });
        }
    }
    PressResult {
        samples,
        particles: p.len(),
        steps,
        healthy,
    }
}
