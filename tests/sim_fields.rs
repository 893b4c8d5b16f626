//! The force fields (`simulation.fields`, docs/method.md §2.5) against their analytic
//! answers, on the f64 CPU reference step and the GPU step on every P2G path.

use glam::DVec3;
use splatter::gpu::GpuContext;
use splatter::sim::cpu::{step, step_at};
use splatter::sim::gpu::{GpuSim, P2gPath};
use splatter::sim::{
    Attractor, Boundaries, Fields, Grid, Gusts, Material, Particles, StepParams, Transfer, Wind,
};

const DX: f64 = 1.0 / 24.0;
const DT: f64 = 1e-3;

/// A block of stiff elastic particles at rest in the middle of a unit domain, far from its
/// walls, in zero gravity.
fn block() -> (Particles, Grid, Vec<Material>) {
    let mut p = Particles::sample_box(DVec3::splat(0.4), DVec3::splat(0.55), DX / 2.0, 1000.0);
    let material = Material::fixed_corotated(1e4, 0.3);
    p.set_material(0, &material);
    (p, Grid::new(DVec3::ZERO, DVec3::ONE, DX), vec![material])
}

fn params(fields: Fields) -> StepParams {
    StepParams {
        dt: DT,
        gravity: DVec3::ZERO,
        boundaries: Boundaries::default(),
        transfer: Transfer::Apic,
        separation: Default::default(),
        fields,
        actions: Default::default(),
    }
}

fn paths(gpu: &GpuContext) -> Vec<P2gPath> {
    let mut list = vec![P2gPath::Gather, P2gPath::Fixed];
    if gpu.features.float32_atomics {
        list.push(P2gPath::Atomic);
    }
    list
}

/// Largest |v − want| over the particles, relative to |want|.
fn worst_relative(v: &[DVec3], want: DVec3) -> f64 {
    v.iter().map(|v| (*v - want).length()).fold(0.0, f64::max) / want.length()
}

/// A body at rest in a wind w with drag k moves with the grid's uniform velocity, which
/// the exact exponential update takes to w (1 − e^{−k t}): within 1e-6 of it on the
/// f64 reference, and within f32 rounding on the GPU.
#[test]
fn wind_brings_a_body_to_its_speed_at_the_drag_rate() {
    let wind = Wind {
        velocity: DVec3::new(0.5, 0.0, 0.2),
        drag: 4.0,
        gusts: None,
    };
    let sp = params(Fields {
        wind: Some(wind),
        attractor: None,
    });
    let n = 200u32;
    let want = wind.velocity * (1.0 - (-wind.drag * DT * f64::from(n)).exp());
    let (p0, mut grid, materials) = block();
    let mut cpu = p0.clone();
    for _ in 0..n {
        step(&mut cpu, &mut grid, &materials, &sp);
    }
    let cpu_err = worst_relative(&cpu.v, want);
    eprintln!(
        "wind, CPU: |v| {:.6} m/s, want {:.6}, relative error {cpu_err:.1e}",
        cpu.v[0].length(),
        want.length()
    );
    assert!(cpu_err < 1e-6, "CPU: relative error {cpu_err}");
    for gpu in splatter::gpu::test_contexts() {
        for path in paths(&gpu) {
            let sim = GpuSim::with_path(&gpu, &p0, &grid, &materials, &sp, path).unwrap();
            sim.step(&gpu, n).unwrap();
            let out = sim.read_particles(&gpu, &p0).unwrap();
            let err = worst_relative(&out.v, want);
            eprintln!(
                "wind, {} {path:?}: relative error {err:.1e}",
                gpu.describe()
            );
            assert!(err < 1e-4, "{path:?}: relative error {err}");
        }
    }
}

/// An attractor r² / (r² + d²) · a towards p: over one step each particle gains
/// Δt · a(x) within the B-spline interpolation's error (under 1% for a falloff of many
/// cells), on the reference and on the GPU.
#[test]
fn the_attractor_pulls_at_its_strength() {
    let attractor = Attractor {
        point: DVec3::new(0.9, 0.5, 0.5),
        strength: 3.0,
        falloff: 0.3,
    };
    let sp = params(Fields {
        wind: None,
        attractor: Some(attractor),
    });
    let (p0, mut grid, materials) = block();
    let mut cpu = p0.clone();
    step(&mut cpu, &mut grid, &materials, &sp);
    let check = |v: &[DVec3], tol: f64, what: &str| {
        let worst = (0..p0.len())
            .map(|q| {
                let want = attractor.acceleration(p0.x[q]) * DT;
                (v[q] - want).length() / want.length()
            })
            .fold(0.0, f64::max);
        eprintln!("attractor, {what}: worst relative error {worst:.1e}");
        assert!(worst < tol, "{what}: relative error {worst}");
    };
    check(&cpu.v, 1e-2, "CPU");
    for gpu in splatter::gpu::test_contexts() {
        for path in paths(&gpu) {
            let sim = GpuSim::with_path(&gpu, &p0, &grid, &materials, &sp, path).unwrap();
            sim.step(&gpu, 1).unwrap();
            let out = sim.read_particles(&gpu, &p0).unwrap();
            check(&out.v, 1e-2, &format!("{} {path:?}", gpu.describe()));
            let apart = (0..p0.len())
                .map(|q| (out.v[q] - cpu.v[q]).length() / cpu.v[q].length())
                .fold(0.0, f64::max);
            assert!(apart < 1e-4, "{path:?}: {apart} from the CPU reference");
        }
    }
}

/// A gusty wind: the body follows v ← w(t) + (v − w(t)) e^{−kΔt} with w(t) the gusts'
/// velocity at each step's start, computed here apart from the step: within 1e-9 on the
/// f64 reference (stepped with its time) and within f32 rounding on the GPU, which takes
/// w(t) per substep. The gusts move the answer far more than those tolerances.
#[test]
fn a_gusty_wind_is_followed_step_by_step() {
    let wind = Wind {
        velocity: DVec3::new(1.0, 0.5, 0.0),
        drag: 10.0,
        gusts: Some(Gusts {
            strength: 0.6,
            period: 0.05,
            seed: 3,
        }),
    };
    let sp = params(Fields {
        wind: Some(wind),
        attractor: None,
    });
    let n = 300u32;
    let (mut want, mut steady) = (DVec3::ZERO, DVec3::ZERO);
    let decay = (-wind.drag * DT).exp();
    for s in 0..n {
        let w = wind.velocity_at(f64::from(s) * DT);
        want = w + (want - w) * decay;
        steady = wind.velocity + (steady - wind.velocity) * decay;
    }
    let gust_effect = (want - steady).length() / want.length();
    assert!(gust_effect > 1e-2, "gusts change too little: {gust_effect}");
    let (p0, mut grid, materials) = block();
    let mut cpu = p0.clone();
    for s in 0..n {
        step_at(&mut cpu, &mut grid, &materials, &sp, &[], f64::from(s) * DT);
    }
    let cpu_err = worst_relative(&cpu.v, want);
    eprintln!("gusts: effect {gust_effect:.1e}; CPU relative error {cpu_err:.1e}");
    assert!(cpu_err < 1e-9, "CPU: relative error {cpu_err}");
    for gpu in splatter::gpu::test_contexts() {
        for path in paths(&gpu) {
            let sim = GpuSim::with_path(&gpu, &p0, &grid, &materials, &sp, path).unwrap();
            // In two calls, as frames are: the second starts at the first's end time.
            sim.step(&gpu, n / 2).unwrap();
            sim.step(&gpu, n - n / 2).unwrap();
            let out = sim.read_particles(&gpu, &p0).unwrap();
            let err = worst_relative(&out.v, want);
            eprintln!(
                "gusts, {} {path:?}: relative error {err:.1e}",
                gpu.describe()
            );
            assert!(err < 1e-4, "{path:?}: relative error {err}");
        }
    }
}
