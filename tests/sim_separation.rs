//! Two-field separation (`splatter::sim::separation`, docs/method.md §4.9) on the CPU
//! reference step: a crack that opens stays open, momentum is conserved, and where nothing
//! is damaged the step is the one-field step. Run with `--nocapture` for the figures.

use glam::DVec3;
use splatter::sim::cpu::{check, step};
use splatter::sim::gpu::{GpuSim, P2gPath};
use splatter::sim::{
    cfl_dt, Boundaries, Case3Variant, Condition, DomainWalls, Grid, Material, NaccParams,
    Particles, Separation, StepParams, Transfer,
};

const NACC: NaccParams = NaccParams {
    e: 2000.0,
    nu: 0.38,
    alpha0: -0.04,
    beta: 1.0,
    xi: 2.0,
    m_slope: 2.36,
};

fn nacc() -> Material {
    Material::nacc(NACC, Case3Variant::Continuous { k: 2.0 })
}

fn params(dt: f64, separation: Separation, transfer: Transfer) -> StepParams {
    StepParams {
        dt,
        gravity: DVec3::ZERO,
        boundaries: Boundaries {
            walls: DomainWalls::uniform(Condition::SEPARATE),
            colliders: vec![],
            surface: None,
        },
        transfer,
        separation,
        fields: Default::default(),
        actions: Default::default(),
    }
}

const DX: f64 = 0.05;
/// Width of the bar's damaged layer.
const CRACK: f64 = 2.0 * DX;

/// A NACC bar along x over [0.25, 0.75], its halves moving apart at ±`speed` and a layer of
/// fully damaged particles (α = 0, no cohesion left) `crack` wide across its middle.
fn pulled_bar(speed: f64, crack: f64) -> Particles {
    let mut p = Particles::sample_box(
        DVec3::new(0.25, 0.35, 0.35),
        DVec3::new(0.75, 0.65, 0.65),
        DX / 2.0,
        1.0,
    );
    p.set_material(0, &nacc());
    for q in 0..p.len() {
        let side = (p.x[q].x - 0.5).signum();
        p.v[q] = DVec3::X * (side * speed);
        if (p.x[q].x - 0.5).abs() < crack / 2.0 {
            p.alpha[q] = 0.0;
        }
    }
    p
}

/// The mean x velocity of the bar's intact particles (those that started with α₀) on
/// either side of the crack.
fn half_speeds(p: &Particles, start: &Particles) -> (f64, f64) {
    let mean = |left: bool| {
        let sel: Vec<usize> = (0..p.len())
            .filter(|&q| start.alpha[q] < 0.0 && ((start.x[q].x < 0.5) == left))
            .collect();
        sel.iter().map(|&q| p.v[q].x).sum::<f64>() / sel.len() as f64
    };
    (mean(true), mean(false))
}

fn run_bar(separation: Separation, transfer: Transfer, steps: usize) -> (Particles, DVec3) {
    run_bar_at(0.5, separation, transfer, steps)
}

/// [`pulled_bar`] at `speed` (negative: pushed together), run for `steps`; the particles
/// and the momentum's drift.
fn run_bar_at(
    speed: f64,
    separation: Separation,
    transfer: Transfer,
    steps: usize,
) -> (Particles, DVec3) {
    let mut p = pulled_bar(speed, CRACK);
    let mut g = Grid::new(DVec3::ZERO, DVec3::ONE, DX);
    let sp = params(cfl_dt(&nacc(), 1.0, DX, 0.4), separation, transfer);
    let p0 = p.momentum();
    for n in 1..=steps {
        step(&mut p, &mut g, &[nacc()], &sp);
        if let Some(msg) = check(&p, &g, sp.dt).message(n as u64) {
            panic!("{msg}");
        }
    }
    let drift = p.momentum() - p0;
    (p, drift)
}

/// The halves of a bar cut by a damaged layer two cells wide fly apart at their own speed
/// with two fields (each half a free rigid body: its velocity is kept to round-off), and
/// momentum is conserved; with one field the nodes the halves share hold them together
/// and slow them. 300 steps at CFL 0.4: each half moves one cell.
#[test]
fn a_crack_stays_open_with_two_fields() {
    let steps = 300;
    for transfer in [Transfer::Apic, Transfer::FlipPic { flip: 0.7 }] {
        let (two, drift) = run_bar(Separation::DamageGradient, transfer, steps);
        let start = pulled_bar(0.5, CRACK);
        let (l, r) = half_speeds(&two, &start);
        let (one, _) = run_bar(Separation::None, transfer, steps);
        let (l1, r1) = half_speeds(&one, &start);
        let total = two.total_mass() * 0.5;
        println!(
            "{transfer:?}: halves' speed with two fields {l:.6} / {r:.6}, with one {l1:.4} / \
             {r1:.4} (start ∓0.5); momentum drift {:.1e} of {total:.3}",
            drift.length()
        );
        assert!(drift.length() < 1e-12 * total, "momentum drift {drift}");
        assert!((l + 0.5).abs() < 1e-9 && (r - 0.5).abs() < 1e-9, "{l} {r}");
        assert!(
            r1 < 0.45 && l1 > -0.45,
            "one field did not hold the halves: {l1} {r1}"
        );
    }
}

/// The same bar's halves pushed into each other through the damaged layer: the fields meet
/// at the contact, which stops their approach with equal and opposite impulses (momentum
/// kept to round-off), so the halves slow down and no particle passes to the other side
/// (without the contact, 288 do).
#[test]
fn fields_that_meet_push_each_other_apart() {
    let steps = 300;
    let (two, drift) = run_bar_at(-0.5, Separation::DamageGradient, Transfer::Apic, steps);
    let start = pulled_bar(-0.5, CRACK);
    let (l, r) = half_speeds(&two, &start);
    let total = two.total_mass() * 0.5;
    // Particles that crossed the middle: those that started on the other side.
    let crossed = (0..two.len())
        .filter(|&q| (two.x[q].x - 0.5).signum() != (start.x[q].x - 0.5).signum())
        .count();
    println!(
        "pushed together: halves' speed {l:.4} / {r:.4} (start ±0.5), {crossed} particles \
         crossed the middle, momentum drift {:.1e}",
        drift.length()
    );
    assert!(drift.length() < 1e-12 * total, "momentum drift {drift}");
    assert!(l < 0.3 && r > -0.3, "the halves were not stopped: {l} {r}");
    assert_eq!(crossed, 0, "particles passed through the contact");
}

/// Where no particle has broken, the two-field step is the one-field step bit for bit:
/// the pulled bar with its layer half damaged (d = ½, a damage gradient but no crack).
#[test]
fn without_a_broken_particle_two_fields_are_one() {
    let run = |separation| {
        let mut p = pulled_bar(0.5, CRACK);
        for a in &mut p.alpha {
            if *a == 0.0 {
                *a = NACC.alpha0 / 2.0;
            }
        }
        let mut g = Grid::new(DVec3::ZERO, DVec3::ONE, DX);
        let sp = params(cfl_dt(&nacc(), 1.0, DX, 0.4), separation, Transfer::Apic);
        for _ in 0..200 {
            step(&mut p, &mut g, &[nacc()], &sp);
        }
        p
    };
    let (one, two) = (run(Separation::None), run(Separation::DamageGradient));
    let damage: Vec<f64> = two.alpha.iter().map(|&a| nacc().damage(a)).collect();
    let partial = damage.iter().filter(|&&d| d > 0.0 && d < 1.0).count();
    let broken = damage.iter().filter(|&&d| d >= 1.0).count();
    println!("partly damaged {partial}, broken {broken} of {}", two.len());
    assert!(
        partial > 0 && broken == 0,
        "partial {partial} broken {broken}"
    );
    assert_eq!(one, two);
}

/// The GPU step (gather path, f32) against the CPU reference on the pulled bar (FLIP 0.7)
/// and the pushed one (APIC), on every test adapter: positions within 1e-3 Δx after 300
/// steps, and the pulled halves still fly apart at their own speed. The atomic path, which
/// has one field, refuses separation with a message naming the gather path.
#[test]
fn gpu_two_fields_match_the_cpu_reference() {
    for gpu in splatter::gpu::test_contexts() {
        for (speed, transfer) in [
            (0.5, Transfer::FlipPic { flip: 0.7 }),
            (-0.5, Transfer::Apic),
        ] {
            let start = pulled_bar(speed, CRACK);
            let mut grid = Grid::new(DVec3::ZERO, DVec3::ONE, DX);
            let sp = params(
                cfl_dt(&nacc(), 1.0, DX, 0.4),
                Separation::DamageGradient,
                transfer,
            );
            let sim = GpuSim::new(&gpu, &start, &grid, &[nacc()], &sp).unwrap();
            assert_eq!(sim.path(), P2gPath::Gather);
            let steps = 300;
            sim.step(&gpu, steps).unwrap();
            let out = sim.read_particles(&gpu, &start).unwrap();
            let mut cpu = start.clone();
            for _ in 0..steps {
                step(&mut cpu, &mut grid, &[nacc()], &sp);
            }
            let worst = cpu
                .x
                .iter()
                .zip(&out.x)
                .map(|(a, b)| (*a - *b).abs().max_element())
                .fold(0.0, f64::max)
                / DX;
            let (l, r) = half_speeds(&out, &start);
            println!(
                "{}: speed {speed} {transfer:?}: GPU against CPU {worst:.2e} Δx, GPU halves \
                 {l:.5} / {r:.5}",
                gpu.describe()
            );
            assert!(worst < 1e-3, "{worst} Δx");
            if speed > 0.0 {
                assert!(
                    (l + speed).abs() < 1e-4 && (r - speed).abs() < 1e-4,
                    "{l} {r}"
                );
            }
            if gpu.features.float32_atomics {
                let refused =
                    GpuSim::with_path(&gpu, &start, &grid, &[nacc()], &sp, P2gPath::Atomic);
                let msg = refused.err().map(|e| e.to_string()).unwrap_or_default();
                assert!(msg.contains("gather"), "{msg}");
            }
        }
    }
}

/// The GPU's ∇D_p (from its damage field, `damage_field` then `damage_gradient`) against the
/// CPU reference's, on every test adapter: the pulled bar after 40 steps, from the state
/// at the last step's start. The field's shape sets which particles go to a far field.
#[test]
fn gpu_damage_gradients_match_the_cpu_reference() {
    for gpu in splatter::gpu::test_contexts() {
        let start = pulled_bar(0.5, CRACK);
        let grid = Grid::new(DVec3::ZERO, DVec3::ONE, DX);
        let sp = params(
            cfl_dt(&nacc(), 1.0, DX, 0.4),
            Separation::DamageGradient,
            Transfer::Apic,
        );
        let sim = GpuSim::new(&gpu, &start, &grid, &[nacc()], &sp).unwrap();
        sim.step(&gpu, 39).unwrap();
        let before = sim.read_particles(&gpu, &start).unwrap();
        sim.step(&gpu, 1).unwrap();
        let on_gpu = sim.read_damage_gradients(&gpu).unwrap();
        let on_cpu =
            splatter::sim::separation::particle_damage_gradients(&before, &grid, &[nacc()]);
        let top = on_cpu.iter().map(|g| g.length()).fold(0.0, f64::max);
        let worst = on_cpu
            .iter()
            .zip(&on_gpu)
            .map(|(a, b)| (*a - *b).length())
            .fold(0.0, f64::max);
        println!(
            "{}: ∇D_p of {} particles, largest {top:.3e}: GPU against CPU {worst:.2e}",
            gpu.describe(),
            start.len()
        );
        assert!(top > 1.0, "the crack should have a damage gradient: {top}");
        assert!(worst < 1e-4 * top, "{worst} of {top}");
    }
}
