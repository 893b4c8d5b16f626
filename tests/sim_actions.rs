//! The timed actions (`physics.actions`, docs/method.md §2.6) against their known answers,
//! on the f64 CPU reference step and the GPU step on every P2G path: an impulse delivers
//! exactly its momentum during its window and none outside it; a held region stays where
//! it was; a driven region follows its path.

use std::sync::Arc;

use glam::{DVec3, Vec3};
use splatter::gpu::GpuContext;
use splatter::sim::actions::Path;
use splatter::sim::cpu::step_at;
use splatter::sim::gpu::{GpuSim, P2gPath};
use splatter::sim::{
    Action, ActionKind, Actions, Boundaries, Drive, Grid, Material, Particles, StepParams, Transfer,
};

const DX: f64 = 1.0 / 24.0;
const DT: f64 = 1e-3;

/// A block of soft elastic particles at rest in the middle of a unit domain, far from its
/// walls (which are left at their defaults: nothing reaches them).
fn block() -> (Particles, Grid, Vec<Material>) {
    let mut p = Particles::sample_box(DVec3::splat(0.35), DVec3::splat(0.6), DX / 2.0, 1000.0);
    let material = Material::fixed_corotated(2e4, 0.3);
    p.set_material(0, &material);
    (p, Grid::new(DVec3::ZERO, DVec3::ONE, DX), vec![material])
}

/// `actions` on the particles `inside` picks (one bit per action, all on the same region).
fn params(
    p: &Particles,
    gravity: DVec3,
    list: Vec<Action>,
    inside: impl Fn(DVec3) -> bool,
) -> StepParams {
    let all = (1u32 << list.len()) - 1;
    let members: Arc<[u32]> =
        p.x.iter()
            .map(|x| if inside(*x) { all } else { 0 })
            .collect();
    StepParams {
        dt: DT,
        gravity,
        boundaries: Boundaries::default(),
        transfer: Transfer::Apic,
        separation: Default::default(),
        fields: Default::default(),
        actions: Actions { list, members },
    }
}

fn paths(gpu: &GpuContext) -> Vec<P2gPath> {
    let mut list = vec![P2gPath::Gather, P2gPath::Fixed];
    if gpu.features.float32_atomics {
        list.push(P2gPath::Atomic);
    }
    list
}

/// `steps` CPU steps from time `t`, returning the new time.
fn run_cpu(
    p: &mut Particles,
    grid: &mut Grid,
    m: &[Material],
    sp: &StepParams,
    t: f64,
    steps: u32,
) -> f64 {
    let mut t = t;
    for _ in 0..steps {
        step_at(p, grid, m, sp, &[], t);
        t += DT;
    }
    t
}

/// The GPU state after each of `chunks` calls of `steps` substeps, from time 0.
fn run_gpu(
    gpu: &GpuContext,
    path: P2gPath,
    p0: &Particles,
    grid: &Grid,
    m: &[Material],
    sp: &StepParams,
    chunks: &[u32],
) -> Vec<Particles> {
    let sim = GpuSim::with_path(gpu, p0, grid, m, sp, path).unwrap();
    chunks
        .iter()
        .map(|&n| {
            sim.step(gpu, n).unwrap();
            sim.read_particles(gpu, p0).unwrap()
        })
        .collect()
}

/// A free elastic body in zero gravity, its lower half given an acceleration a during a
/// window whose ends fall inside steps: its momentum stays 0 before the window, gains
/// exactly M_region a (to − from) over it (within 1e-6 on the reference, f32 rounding on
/// the GPU) and nothing after it; a force F gives F (to − from) whatever the mass.
#[test]
fn an_impulse_delivers_its_momentum_within_its_window() {
    let (p0, mut grid, m) = block();
    let below = |x: DVec3| x.z < 0.475;
    let (from, to) = (0.0105, 0.0305);
    let a = DVec3::new(2.0, -1.0, 0.5);
    let sp = params(
        &p0,
        DVec3::ZERO,
        vec![Action {
            kind: ActionKind::Impulse { acceleration: a },
            from,
            to,
        }],
        below,
    );
    let region_mass = sp.actions.region_mass(0, &p0.mass);
    assert!(region_mass > 0.3 * p0.total_mass() && region_mass < 0.7 * p0.total_mass());
    let want = a * region_mass * (to - from);
    let mut p = p0.clone();
    let t = run_cpu(&mut p, &mut grid, &m, &sp, 0.0, 10);
    let before = p.momentum();
    let t = run_cpu(&mut p, &mut grid, &m, &sp, t, 22);
    let during = p.momentum();
    run_cpu(&mut p, &mut grid, &m, &sp, t, 18);
    let after = p.momentum();
    let rel = |v: DVec3| v.length() / want.length();
    eprintln!(
        "impulse, CPU: before {:.1e}, gained {:.3e} of {:.3e} (relative error {:.1e}), after the window {:.1e}",
        rel(before),
        during.length(),
        want.length(),
        rel(during - want),
        rel(after - during)
    );
    assert!(rel(before) < 1e-12, "momentum before the window {before}");
    assert!(rel(during - want) < 1e-6, "gained {during}, want {want}");
    assert!(
        rel(after - during) < 1e-12,
        "momentum changed after the window"
    );
    // The body moved as the momentum says: its centre's velocity is P / M.
    let v_cm = after / p.total_mass();
    assert!(v_cm.length() > 0.01, "{v_cm}");

    for gpu in splatter::gpu::test_contexts() {
        for path in paths(&gpu) {
            let out = run_gpu(&gpu, path, &p0, &grid, &m, &sp, &[10, 22, 18]);
            let (before, during, after) = (out[0].momentum(), out[1].momentum(), out[2].momentum());
            eprintln!(
                "impulse, {} {path:?}: before {:.1e}, relative error {:.1e}, after the window {:.1e}",
                gpu.describe(),
                rel(before),
                rel(during - want),
                rel(after - during)
            );
            assert!(rel(before) < 1e-5, "{path:?}: before {before}");
            assert!(
                rel(during - want) < 1e-4,
                "{path:?}: gained {during}, want {want}"
            );
            assert!(rel(after - during) < 1e-4, "{path:?}: after {after}");
        }
    }
}

/// A held region stays where it was during its window (within 1e-6; the step writes
/// x + 0) and keeps its shape (F unchanged) while the rest of the body sags under gravity, and falls once the window ends.
#[test]
fn a_held_region_stays_while_the_rest_sags() {
    let (p0, mut grid, m) = block();
    let top = |x: DVec3| x.z > 0.55;
    let g = DVec3::new(0.0, 0.0, -9.8);
    let sp = params(
        &p0,
        g,
        vec![Action {
            kind: ActionKind::Hold,
            from: 0.0,
            to: 0.04,
        }],
        top,
    );
    let held: Vec<usize> = (0..p0.len()).filter(|&q| top(p0.x[q])).collect();
    let free: Vec<usize> = (0..p0.len()).filter(|&q| p0.x[q].z < 0.4).collect();
    let drift = |p: &Particles, set: &[usize]| {
        set.iter()
            .map(|&q| (p.x[q] - p0.x[q]).length())
            .fold(0.0, f64::max)
    };
    let sag =
        |p: &Particles| free.iter().map(|&q| p0.x[q].z - p.x[q].z).sum::<f64>() / free.len() as f64;
    // The held region keeps its shape: F stays what it was (I).
    let strain = |p: &Particles| {
        held.iter()
            .map(|&q| {
                (p.f[q] - glam::DMat3::IDENTITY)
                    .abs()
                    .to_cols_array()
                    .into_iter()
                    .fold(0.0, f64::max)
            })
            .fold(0.0, f64::max)
    };
    let check = |during: &Particles, after: &Particles, what: &str| {
        let (d, s) = (drift(during, &held), sag(during));
        assert!(
            strain(during) < 1e-6,
            "{what}: the held region deformed, |F − I| {}",
            strain(during)
        );
        eprintln!("hold, {what}: held region moved {d:.1e}, the bottom sagged {s:.2e}, after release {:.2e}", drift(after, &held));
        assert!(d < 1e-6, "{what}: held particles moved {d}");
        assert!(s > 1e-4, "{what}: the free part did not sag ({s})");
        assert!(
            drift(after, &held) > 1e-4,
            "{what}: still held after the window"
        );
    };
    let mut p = p0.clone();
    let t = run_cpu(&mut p, &mut grid, &m, &sp, 0.0, 40);
    let during = p.clone();
    run_cpu(&mut p, &mut grid, &m, &sp, t, 30);
    check(&during, &p, "CPU");
    for gpu in splatter::gpu::test_contexts() {
        for path in paths(&gpu) {
            let out = run_gpu(&gpu, path, &p0, &grid, &m, &sp, &[40, 30]);
            check(&out[0], &out[1], &format!("{} {path:?}", gpu.describe()));
        }
    }
}

/// A region driven along a keyframed path moves by P(t) − P(from) (within Δx/100: mid-window
/// and at its end, where a step straddles it), carrying the rest of the body with it
/// through the stresses.
#[test]
fn a_driven_region_follows_its_path() {
    let (p0, mut grid, m) = block();
    let top = |x: DVec3| x.z > 0.55;
    let path = Path::new(
        vec![0.0, 0.02, 0.04],
        vec![
            Vec3::ZERO,
            Vec3::new(0.05, 0.02, 0.0),
            Vec3::new(0.06, 0.0, 0.03),
        ],
    );
    let (from, to) = (0.0045, 0.0355);
    let sp = params(
        &p0,
        DVec3::ZERO,
        vec![Action {
            kind: ActionKind::Drive(Drive::Path(path.clone())),
            from,
            to,
        }],
        top,
    );
    let driven: Vec<usize> = (0..p0.len()).filter(|&q| top(p0.x[q])).collect();
    let off_path = |p: &Particles, t: f64| {
        let want = path.at(t.min(to)) - path.at(from);
        driven
            .iter()
            .map(|&q| (p.x[q] - p0.x[q] - want).length())
            .fold(0.0, f64::max)
    };
    // The mean x displacement of the particles not driven.
    let rest_moved = |p: &Particles| {
        let rest: Vec<usize> = (0..p0.len()).filter(|&q| !top(p0.x[q])).collect();
        rest.iter().map(|&q| p.x[q].x - p0.x[q].x).sum::<f64>() / rest.len() as f64
    };
    let check = |mid: &Particles, end: &Particles, what: &str| {
        let (e_mid, e_end) = (off_path(mid, 0.02), off_path(end, 0.036));
        eprintln!(
            "drive, {what}: off the path by {e_mid:.1e} at 0.02 s, {e_end:.1e} at the window's end; the rest followed by {:.2e}",
            rest_moved(end)
        );
        assert!(
            e_mid < DX / 100.0 && e_end < DX / 100.0,
            "{what}: {e_mid}, {e_end}"
        );
        assert!(rest_moved(end) > 1e-3, "{what}: the rest did not follow");
    };
    let mut p = p0.clone();
    let t = run_cpu(&mut p, &mut grid, &m, &sp, 0.0, 20);
    let mid = p.clone();
    run_cpu(&mut p, &mut grid, &m, &sp, t, 16);
    check(&mid, &p, "CPU");
    for gpu in splatter::gpu::test_contexts() {
        for path in paths(&gpu) {
            let out = run_gpu(&gpu, path, &p0, &grid, &m, &sp, &[20, 16]);
            check(&out[0], &out[1], &format!("{} {path:?}", gpu.describe()));
        }
    }
}
