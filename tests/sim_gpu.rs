//! The GPU MPM step against the CPU reference step (`splatter::sim::cpu`, f64): the same
//! scenes stepped on both, positions compared. The GPU runs in f32 with a different
//! summation order (a per-node gather in sorted order, like the CPU), so agreement is
//! within f32 round-off grown over the steps, stated per test in units of Δx.

mod common;

use glam::{DMat3, DVec3};
use splatter::gpu::pages::Pages;
use splatter::gpu::GpuContext;
use splatter::sim::cpu::step;
use splatter::sim::gpu::{GpuSim, P2gPath};
use splatter::sim::model::nacc::oracle::Case3Variant;
use splatter::sim::{
    cfl_dt, Boundaries, Condition, DomainWalls, Grid, Material, Particles, PlaneCollider,
    StepParams, Transfer,
};

const G: f64 = 9.8;

fn gpus() -> Vec<GpuContext> {
    splatter::gpu::test_contexts()
}

/// The P2G paths an adapter can run: the gather and the fixed-point scatter always, float
/// atomics where supported.
fn paths(gpu: &GpuContext) -> Vec<P2gPath> {
    let mut list = vec![P2gPath::Gather, P2gPath::Fixed];
    if gpu.features.float32_atomics {
        list.push(P2gPath::Atomic);
    }
    list
}

struct Scene {
    particles: Particles,
    grid_lo: DVec3,
    grid_hi: DVec3,
    dx: f64,
    materials: Vec<Material>,
    params: StepParams,
}

/// Step `scene` `steps` times on the CPU and on the GPU (in `chunks` submissions) and return
/// the largest position difference in units of Δx, and both end states.
fn compare(
    gpu: &GpuContext,
    path: P2gPath,
    scene: &Scene,
    steps: u32,
    chunks: u32,
) -> (f64, Particles, Particles) {
    let pages = GpuSim::pages_for(gpu, scene.particles.len());
    compare_paged(gpu, path, scene, steps, chunks, pages)
}

/// As [`compare`], with the GPU's particle arrays split into `pages`.
fn compare_paged(
    gpu: &GpuContext,
    path: P2gPath,
    scene: &Scene,
    steps: u32,
    chunks: u32,
    pages: Pages,
) -> (f64, Particles, Particles) {
    let mut grid = Grid::new(scene.grid_lo, scene.grid_hi, scene.dx);
    let sim = GpuSim::with_pages(
        gpu,
        &scene.particles,
        &grid,
        &scene.materials,
        &scene.params,
        path,
        pages,
    )
    .unwrap();
    let mut cpu = scene.particles.clone();
    for _ in 0..steps {
        step(&mut cpu, &mut grid, &scene.materials, &scene.params);
    }
    for _ in 0..chunks {
        sim.step(gpu, steps / chunks).unwrap();
    }
    let out = sim.read_particles(gpu, &scene.particles).unwrap();
    let worst = cpu
        .x
        .iter()
        .zip(&out.x)
        .map(|(a, b)| (*a - *b).abs().max_element())
        .fold(0.0, f64::max);
    (worst / scene.dx, cpu, out)
}

fn params(dt: f64, boundaries: Boundaries) -> StepParams {
    StepParams {
        dt,
        gravity: DVec3::new(0.0, -G, 0.0),
        boundaries,
        transfer: Transfer::Apic,
        separation: Default::default(),
        fields: Default::default(),
        actions: Default::default(),
    }
}

/// Free fall on the GPU: no stress, no walls reached; matches the discrete formula
/// x_n = x₀ + n v₀ Δt + g Δt² n(n+1)/2 to f32 round-off, and F stays I.
/// An elastic cube of `material` (ρ = 1000) in the unit box at Δx = 1/24, thrown with
/// velocity `v`, stepped at the CFL Δt under `boundaries`.
fn thrown_cube(material: Material, v: DVec3, boundaries: Boundaries) -> Scene {
    let dx = 1.0 / 24.0;
    let mut particles = Particles::sample_box(
        DVec3::new(0.35, 0.45, 0.35),
        DVec3::new(0.6, 0.7, 0.6),
        dx / 2.0,
        1000.0,
    );
    particles.set_material(0, &material);
    particles.v.iter_mut().for_each(|p| *p = v);
    let dt = cfl_dt(&material, 1000.0, dx, 0.4);
    Scene {
        particles,
        grid_lo: DVec3::ZERO,
        grid_hi: DVec3::ONE,
        dx,
        materials: vec![material],
        params: params(dt, boundaries),
    }
}

#[test]
fn gpu_free_fall_matches_the_discrete_formula() {
    for gpu in gpus() {
        let dx = 1.0 / 16.0;
        let mut p = Particles::sample_box(DVec3::splat(0.4), DVec3::splat(0.6), dx / 2.0, 1000.0);
        let v0 = DVec3::new(0.3, 1.0, -0.2);
        p.v.iter_mut().for_each(|v| *v = v0);
        let grid = Grid::new(DVec3::ZERO, DVec3::ONE, dx);
        let (dt, n) = (1e-3, 100u32);
        let sp = params(dt, Boundaries::default());
        let sim =
            GpuSim::new(&gpu, &p, &grid, &[Material::fixed_corotated(1e4, 0.3)], &sp).unwrap();
        sim.step(&gpu, n).unwrap();
        let out = sim.read_particles(&gpu, &p).unwrap();
        let nf = f64::from(n);
        let (mut ex, mut ef) = (0.0f64, 0.0f64);
        for q in 0..p.len() {
            let want = p.x[q] + v0 * (nf * dt) + sp.gravity * (dt * dt * nf * (nf + 1.0) / 2.0);
            ex = ex.max((out.x[q] - want).abs().max_element());
            ef = ef.max(
                (out.f[q] - DMat3::IDENTITY)
                    .to_cols_array()
                    .iter()
                    .fold(0.0f64, |m, v| m.max(v.abs())),
            );
        }
        eprintln!(
            "{}: free fall {n} steps: max |x − formula| {ex:.2e}, max |F − I| {ef:.2e}",
            gpu.describe()
        );
        assert!(ex < 2e-5, "position error {ex}");
        assert!(ef < 1e-5, "F error {ef}");
    }
}

/// An elastic cube (fixed corotated, then Neo-Hookean) dropped on a frictional slope
/// inside separate walls: the GPU follows the CPU reference to within 0.1% of Δx over
/// 150 steps (impact, sliding and wobbling included).
#[test]
fn gpu_elastic_step_matches_the_cpu_reference() {
    for gpu in gpus() {
        for material in [
            Material::fixed_corotated(2e4, 0.3),
            Material::neo_hookean(2e4, 0.3),
        ] {
            let dx = 1.0 / 24.0;
            let slope = PlaneCollider {
                point: DVec3::new(0.5, 0.3, 0.5),
                normal: DVec3::new(0.3, 1.0, 0.0),
                condition: Condition::SLIP.with_friction(0.3),
            };
            let scene = thrown_cube(
                material,
                DVec3::new(0.5, -1.0, 0.2),
                Boundaries {
                    walls: DomainWalls::default(),
                    colliders: vec![slope],
                    surface: None,
                },
            );
            for path in paths(&gpu) {
                let (worst, cpu, _) = compare(&gpu, path, &scene, 150, 3);
                let moved = cpu
                    .x
                    .iter()
                    .zip(&scene.particles.x)
                    .map(|(a, b)| (*a - *b).length())
                    .fold(0.0, f64::max);
                eprintln!(
                "{} ({path:?} P2G): {material:?}: {} particles, 150 steps, moved up to {:.1} Δx; GPU vs CPU max |Δx| = {worst:.2e} Δx",
                gpu.describe(),
                scene.particles.len(),
                moved / dx
            );
                assert!(moved / dx > 2.0, "the scene should move");
                assert!(worst < 1e-3, "GPU and CPU differ by {worst} Δx");
            }
        }
    }
}

/// A cube of two materials (its −x half a soft fixed-corotated solid, its +x half a 10×
/// stiffer Neo-Hookean one) dropped on a frictional slope: the GPU follows the CPU
/// reference to within 0.1% of Δx over 150 steps in 3 submissions, so every particle is
/// stepped with its own material (the step passes read material 0 once for all
/// invocations and the others per particle, `particle_material` in `common.wgsl`).
#[test]
fn gpu_step_with_two_materials_matches_the_cpu_reference() {
    for gpu in gpus() {
        let soft = Material::fixed_corotated(2e4, 0.3);
        let stiff = Material::neo_hookean(2e5, 0.3);
        let slope = PlaneCollider {
            point: DVec3::new(0.5, 0.3, 0.5),
            normal: DVec3::new(0.3, 1.0, 0.0),
            condition: Condition::SLIP.with_friction(0.3),
        };
        // Δt from the stiffer material
        let mut scene = thrown_cube(
            stiff,
            DVec3::new(0.5, -1.0, 0.2),
            Boundaries {
                walls: DomainWalls::default(),
                colliders: vec![slope],
                surface: None,
            },
        );
        scene.materials = vec![soft, stiff];
        let p = &mut scene.particles;
        for (m, x) in p.material.iter_mut().zip(&p.x) {
            *m = u32::from(x.x > 0.475);
        }
        let stiff_count = p.material.iter().filter(|m| **m == 1).count();
        assert!(stiff_count > 0 && stiff_count < p.len());
        for path in paths(&gpu) {
            let (worst, _, _) = compare(&gpu, path, &scene, 150, 3);
            eprintln!(
                "{} ({path:?} P2G): two materials, {} particles ({stiff_count} stiff), 150 steps; GPU vs CPU max |Δx| = {worst:.2e} Δx",
                gpu.describe(),
                scene.particles.len()
            );
            assert!(worst < 1e-3, "GPU and CPU differ by {worst} Δx");
        }
    }
}

/// An elastic cube dropped on a captured surface (`SurfaceCollider`: a tilted plane given
/// as its signed distance at the nodes, as `scene::surface` would build it): the GPU
/// follows the CPU reference to within 0.1% of Δx over 150 steps, and the cube slides
/// down the surface without entering it.
#[test]
fn gpu_step_with_a_surface_collider_matches_the_cpu_reference() {
    use splatter::sim::boundary::SurfaceCollider;
    for gpu in gpus() {
        let material = Material::neo_hookean(2e4, 0.3);
        let dx: f64 = 1.0 / 24.0;
        // The surface y = 0.3 + 0.3 (0.5 − x) (a slope), φ its signed distance.
        let n = DVec3::new(0.3, 1.0, 0.0).normalize();
        let point = DVec3::new(0.5, 0.3, 0.5);
        let cells = (1.0 / dx).ceil() as usize;
        let nodes = cells + 1;
        let mut phi = Vec::with_capacity(nodes * nodes * nodes);
        for k in 0..nodes {
            for j in 0..nodes {
                for i in 0..nodes {
                    let x = DVec3::new(i as f64, j as f64, k as f64) * dx;
                    phi.push(((x - point).dot(n)).clamp(-4.0 * dx, 4.0 * dx) as f32);
                }
            }
        }
        let surface = SurfaceCollider {
            phi,
            condition: Condition::SEPARATE.with_friction(0.3),
        };
        let scene = thrown_cube(
            material,
            DVec3::new(0.3, -1.0, 0.0),
            Boundaries {
                walls: DomainWalls::default(),
                colliders: vec![],
                surface: Some(surface),
            },
        );
        for path in paths(&gpu) {
            let (worst, cpu, _) = compare(&gpu, path, &scene, 150, 3);
            let deepest = cpu
                .x
                .iter()
                .map(|x| (*x - point).dot(n))
                .fold(f64::INFINITY, f64::min);
            let slid = cpu.x.iter().map(|x| x.x).sum::<f64>() / cpu.x.len() as f64
                - scene.particles.x.iter().map(|x| x.x).sum::<f64>() / scene.particles.len() as f64;
            eprintln!(
                "{} ({path:?} P2G): surface collider: deepest particle {:.2} Δx from the surface, slid {:.2} Δx along x; GPU vs CPU max |Δx| = {worst:.2e} Δx",
                gpu.describe(),
                deepest / dx,
                slid / dx
            );
            assert!(worst < 1e-3, "GPU and CPU differ by {worst} Δx");
            assert!(
                deepest > -dx,
                "a particle {} Δx inside the surface",
                -deepest / dx
            );
            assert!(
                slid / dx > 1.0,
                "the cube should slide down the slope: {} Δx",
                slid / dx
            );
        }
    }
}

/// A NACC sphere (the paper's fruit parameters, ρ = 2) dropped at 3 m/s on a sticky ground.
fn nacc_sphere() -> Scene {
    let dx = 0.02;
    let density = 2.0;
    let material = Material::nacc(common::fruit(), Case3Variant::Continuous { k: 2.0 });
    let mut particles =
        Particles::sample_sphere(DVec3::new(0.2, 0.12, 0.2), 0.06, dx / 2.0, density);
    particles.set_material(0, &material);
    particles
        .v
        .iter_mut()
        .for_each(|v| *v = DVec3::new(0.0, -3.0, 0.0));
    let dt = cfl_dt(&material, density, dx, 0.4);
    let walls = DomainWalls::with_ground(Condition::STICKY, Condition::SEPARATE);
    Scene {
        particles,
        grid_lo: DVec3::ZERO,
        grid_hi: DVec3::splat(0.4),
        dx,
        materials: vec![material],
        params: params(
            dt,
            Boundaries {
                walls,
                colliders: vec![],
                surface: None,
            },
        ),
    }
}

/// A NACC sphere hitting a sticky ground: plasticity on the GPU follows the CPU reference.
/// Tolerances are looser than the elastic ones: near the yield surface an f32 rounding can
/// decide whether a particle yields in this step or the next.
#[test]
fn gpu_nacc_step_matches_the_cpu_reference() {
    for gpu in gpus() {
        let scene = nacc_sphere();
        for path in paths(&gpu) {
            let (worst, cpu, out) = compare(&gpu, path, &scene, 120, 2);
            let yielded = cpu
                .alpha
                .iter()
                .filter(|a| (**a + 0.04).abs() > 1e-3)
                .count();
            let alpha_err = cpu
                .alpha
                .iter()
                .zip(&out.alpha)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            eprintln!(
            "{} ({path:?} P2G): NACC sphere, {} particles, 120 steps: {yielded} yielded; GPU vs CPU max |Δx| = {worst:.2e} Δx, max |Δα| = {alpha_err:.2e}",
            gpu.describe(),
            scene.particles.len()
        );
            assert!(yielded > 0, "the impact should yield some particles");
            assert!(out.x.iter().all(|x| x.is_finite()));
            assert!(worst < 1e-2, "GPU and CPU differ by {worst} Δx");
            assert!(alpha_err < 1e-2, "α differs by {alpha_err}");
        }
    }
}

/// A brittle sphere (Weibull strengths, `sim::model::Brittle`) thrown onto a sticky
/// ground: its damage on the GPU follows the CPU reference, particle by particle, so the
/// strength each particle draws (a hash of its index) and the split stress agree. A
/// particle near its threshold may cross it one step apart in f32, so a few may differ.
#[test]
fn gpu_brittle_step_matches_the_cpu_reference() {
    use splatter::sim::model::Brittle;
    use splatter::sim::model::PlasticLaw;
    let spec =
        serde_json::json!({"strength": 150.0, "weibull_modulus": 6.0, "softening": 0.5, "seed": 4});
    let law = Brittle::from_spec(serde_json::from_value(spec).unwrap(), 2000.0, 0.38).unwrap();
    let material = Material::with_plastic(law.into(), 2000.0, 0.38);
    let mut scene = nacc_sphere();
    scene.particles.set_material(0, &material);
    scene
        .particles
        .v
        .iter_mut()
        .for_each(|v| *v = DVec3::new(0.0, -6.0, 0.0));
    scene.materials = vec![material];
    for gpu in gpus() {
        for path in paths(&gpu) {
            let (worst, cpu, out) = compare(&gpu, path, &scene, 120, 2);
            let damaged = cpu.alpha.iter().filter(|&&d| d > 0.0).count();
            let broken = cpu.alpha.iter().filter(|&&d| d == 1.0).count();
            let differ = cpu
                .alpha
                .iter()
                .zip(&out.alpha)
                .filter(|(a, b)| (*a - *b).abs() > 0.05)
                .count();
            eprintln!(
                "{} ({path:?} P2G): brittle sphere, {} particles, 120 steps: {damaged} damaged, {broken} broken; GPU vs CPU max |Δx| = {worst:.2e} Δx, {differ} with |Δd| > 0.05",
                gpu.describe(),
                scene.particles.len()
            );
            assert!(
                damaged > 20 && broken > 5 && damaged < cpu.len() / 2,
                "the impact should damage part of the sphere ({damaged}, {broken} broken)"
            );
            assert!(out.x.iter().all(|x| x.is_finite()));
            assert!(worst < 1e-2, "GPU and CPU differ by {worst} Δx");
            assert!(
                differ * 100 <= damaged,
                "{differ} particles' damage differs"
            );
        }
    }
}

/// The release's FLIP/PIC blend (FLIP share 0.7) on the GPU: the elastic cube on the
/// frictional slope and the NACC sphere on the sticky ground follow the CPU reference to
/// the bounds of their APIC tests (positions), and the particle velocities, which the
/// blend sets from the grid's velocity changes, to the same share of the speeds.
#[test]
fn gpu_flip_pic_blend_matches_the_cpu_reference() {
    let blend = Transfer::FlipPic { flip: 0.7 };
    let slope = PlaneCollider {
        point: DVec3::new(0.5, 0.3, 0.5),
        normal: DVec3::new(0.3, 1.0, 0.0),
        condition: Condition::SLIP.with_friction(0.3),
    };
    let mut cube = thrown_cube(
        Material::fixed_corotated(2e4, 0.3),
        DVec3::new(0.5, -1.0, 0.2),
        Boundaries {
            walls: DomainWalls::default(),
            colliders: vec![slope],
            surface: None,
        },
    );
    cube.params.transfer = blend;
    let mut sphere = nacc_sphere();
    sphere.params.transfer = blend;
    for gpu in gpus() {
        for (name, scene, steps, bound) in [
            ("cube", &cube, 150, 1e-3),
            ("NACC sphere", &sphere, 120, 1e-2),
        ] {
            for path in paths(&gpu) {
                let (worst, cpu, out) = compare(&gpu, path, scene, steps, 3);
                let speed = cpu.v.iter().map(|v| v.length()).fold(0.0, f64::max);
                let dv = cpu
                    .v
                    .iter()
                    .zip(&out.v)
                    .map(|(a, b)| (*a - *b).length())
                    .fold(0.0, f64::max);
                eprintln!(
                    "{} ({path:?} P2G): {name}, FLIP 0.7, {steps} steps: GPU vs CPU max |Δx| = {worst:.2e} Δx, max |Δv| = {:.2e} of the top speed",
                    gpu.describe(),
                    dv / speed
                );
                assert!(worst < bound, "{name}: GPU and CPU differ by {worst} Δx");
                assert!(
                    dv / speed < bound * 10.0,
                    "{name}: velocities differ by {dv}"
                );
            }
        }
    }
}

/// The node passes visit only the blocks of 4³ nodes that some particle's stencil reaches:
/// the GPU's list after a step holds exactly the blocks counted here on the CPU from the
/// particles' stencils at the start of that step, including blocks that stick out of a
/// grid whose node count is not a multiple of 4.
#[test]
fn gpu_active_blocks_are_the_blocks_the_stencils_reach() {
    for gpu in gpus() {
        let dx = 1.0 / 32.0; // 33 nodes per axis: 9 blocks, the last one mostly outside
        let grid = Grid::new(DVec3::ZERO, DVec3::ONE, dx);
        let mut p = Particles::sample_box(
            DVec3::new(0.2, 0.3, 0.25),
            DVec3::new(0.35, 0.4, 0.5),
            dx / 2.0,
            1000.0,
        );
        // A second cluster against the far corner, in the partial blocks.
        p.append(&Particles::sample_box(
            DVec3::splat(0.9),
            DVec3::splat(0.95),
            dx / 2.0,
            1000.0,
        ));
        let nodes = grid.nodes();
        let per_axis = (nodes + 3) / 4;
        let mut want = std::collections::BTreeSet::new();
        for x in &p.x {
            let base = grid.stencil(*x).expect("inside the grid").base.as_uvec3();
            let (lo, hi) = (base / 4, (base + 2) / 4);
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        want.insert(x + per_axis.x * (y + per_axis.y * z));
                    }
                }
            }
        }
        let sp = params(1e-4, Boundaries::default());
        for path in paths(&gpu) {
            let sim = GpuSim::with_path(
                &gpu,
                &p,
                &grid,
                &[Material::fixed_corotated(1e4, 0.3)],
                &sp,
                path,
            )
            .unwrap();
            sim.step(&gpu, 1).unwrap();
            let active = sim.active_blocks(&gpu).unwrap();
            eprintln!(
                "{} ({path:?} P2G): {} active blocks of {}",
                gpu.describe(),
                active.len(),
                sim.blocks()
            );
            assert_eq!(sim.blocks(), per_axis.element_product());
            assert_eq!(active, want.iter().copied().collect::<Vec<u32>>());
        }
    }
}

/// The watchdog counts a particle that turns non-finite or leaves the grid once per step,
/// names the first step that counted since the last read and the particle, keeps the
/// largest speed, and starts over after a read.
#[test]
fn gpu_watchdog_counts_and_names_the_first_step() {
    for gpu in gpus() {
        let dx = 1.0 / 16.0;
        let grid = Grid::new(DVec3::ZERO, DVec3::ONE, dx);
        let mut p = Particles::sample_box(DVec3::splat(0.4), DVec3::splat(0.6), dx / 2.0, 1000.0);
        let sp = params(1e-4, Boundaries::default());
        let material = [Material::fixed_corotated(1e4, 0.3)];
        for path in paths(&gpu) {
            let sim = GpuSim::with_path(&gpu, &p, &grid, &material, &sp, path).unwrap();
            sim.step(&gpu, 4).unwrap();
            let quiet = sim.take_watchdog(&gpu).unwrap();
            assert_eq!(
                (quiet.nonfinite, quiet.escaped, quiet.first_step),
                (0, 0, None)
            );
            assert_eq!(quiet.first_particle, None);
            // Four steps of 1e-4 s from rest: at most g · 4e-4 s.
            assert!(quiet.speed_max < 0.01, "{path:?}: {}", quiet.speed_max);
        }
        // A lone particle thrown at 1000 m/s leaves the grid in step 0 (it is still inside
        // during that step) and is counted from step 1 on: 4 of 5 steps, first step 1. After
        // a read, the count and the first step start over.
        let n = p.len();
        p.append(&Particles::sample_box(
            DVec3::splat(0.75),
            DVec3::splat(0.75 + dx / 4.0),
            dx / 2.0,
            1000.0,
        ));
        assert_eq!(p.len(), n + 1, "test setup: one lone particle");
        p.v[n] = DVec3::new(1000.0, 0.0, 0.0);
        let sp = params(1e-3, Boundaries::default());
        // The fixed-point scatter instead counts it in step 0, past its bound of 8 cells a
        // step (500 m/s here) while still on the grid, and leaves it out of the grid: G2P
        // then finds no mass there and stops it, so it never leaves.
        for path in paths(&gpu) {
            let sim = GpuSim::with_path(&gpu, &p, &grid, &material, &sp, path).unwrap();
            sim.step(&gpu, 5).unwrap();
            let w = sim.take_watchdog(&gpu).unwrap();
            let counted = (w.escaped, w.fixed_point_range, w.first_step);
            if path != P2gPath::Fixed {
                // It moved at 1000 m/s in step 0, the only step it was on the grid.
                assert_eq!(w.first_particle, Some(n as u32), "{path:?}");
                assert!(
                    (w.speed_max - 1000.0).abs() < 1.0,
                    "{path:?}: {}",
                    w.speed_max
                );
            }
            let again = || {
                sim.step(&gpu, 2).unwrap();
                let w = sim.take_watchdog(&gpu).unwrap();
                (w.escaped, w.fixed_point_range, w.first_step)
            };
            if path == P2gPath::Fixed {
                assert_eq!(counted, (0, 1, Some(0)), "{path:?}");
                assert_eq!(again(), (0, 0, None), "{path:?}");
            } else {
                assert_eq!(counted, (4, 0, Some(1)), "{path:?}");
                assert_eq!(again(), (2, 0, Some(0)), "{path:?}");
            }
        }
    }
}

/// Particle arrays split into pages (as past one storage binding, `gpu::pages`): with pages
/// of 256 particles, the atomic path steps the NACC sphere as it does in one page, to the
/// CPU reference's bound; the gather path, which sorts all particles at once, refuses pages.
#[test]
fn gpu_step_over_pages_matches_the_cpu_reference() {
    let scene = nacc_sphere();
    let n = scene.particles.len();
    let pages = Pages::with_size(n as u32, 256);
    assert!(pages.count >= 4, "{n} particles in {} pages", pages.count);
    for gpu in gpus() {
        let grid = Grid::new(scene.grid_lo, scene.grid_hi, scene.dx);
        let refused = GpuSim::with_pages(
            &gpu,
            &scene.particles,
            &grid,
            &scene.materials,
            &scene.params,
            P2gPath::Gather,
            pages,
        );
        let message = refused
            .err()
            .expect("the gather path refuses pages")
            .to_string();
        assert!(message.contains("fixed-point or atomic path"), "{message}");
        for path in paths(&gpu).into_iter().filter(|p| *p != P2gPath::Gather) {
            let (worst, cpu, out) = compare_paged(&gpu, path, &scene, 120, 2, pages);
            let moved = cpu
                .x
                .iter()
                .zip(&out.x)
                .zip(&scene.particles.x)
                .filter(|((_, g), x0)| (**g - **x0).length() > 1e-3 * scene.dx)
                .count();
            eprintln!(
                "{} ({path:?}): {n} particles in {} pages of {}, 120 steps: GPU vs CPU max |Δx| = {worst:.2e} Δx; {moved} moved",
                gpu.describe(),
                pages.count,
                pages.size
            );
            assert_eq!(moved, n, "every page's particles move");
            assert!(worst < 1e-2, "GPU and CPU differ by {worst} Δx");
        }
    }
}

/// Both deterministic paths end two runs of the NACC sphere's impact in the same bits, in
/// every particle's position, velocity, F and α: the fixed-point scatter sums in integers,
/// whose addition is associative (many particles add to each node from several threads, in
/// an order that differs between runs), and the gather sums each node in the sorted order.
#[test]
fn gpu_deterministic_paths_end_two_runs_in_the_same_bits() {
    let scene = nacc_sphere();
    for gpu in gpus() {
        for path in [P2gPath::Fixed, P2gPath::Gather] {
            let run = || {
                let grid = Grid::new(scene.grid_lo, scene.grid_hi, scene.dx);
                let sim = GpuSim::with_path(
                    &gpu,
                    &scene.particles,
                    &grid,
                    &scene.materials,
                    &scene.params,
                    path,
                )
                .unwrap();
                sim.step(&gpu, 60).unwrap();
                sim.step(&gpu, 60).unwrap();
                sim.read_particles(&gpu, &scene.particles).unwrap()
            };
            let (a, b) = (run(), run());
            let bits = |p: &Particles| -> Vec<u64> {
                let mut v: Vec<f64> = Vec::new();
                for i in 0..p.len() {
                    v.extend(p.x[i].to_array());
                    v.extend(p.v[i].to_array());
                    v.extend(p.f[i].to_cols_array());
                    v.push(p.alpha[i]);
                }
                v.iter().map(|x| x.to_bits()).collect()
            };
            let differ = bits(&a)
                .iter()
                .zip(bits(&b))
                .filter(|(x, y)| **x != *y)
                .count();
            eprintln!(
                "{}: {} P2G, NACC sphere, 120 steps twice: {differ} values differ",
                gpu.describe(),
                path.name()
            );
            assert_eq!(differ, 0, "two runs of the {} path differ", path.name());
        }
    }
}

/// A particle whose affine term reaches past the fixed-point bound (here a velocity
/// gradient of 1e6 /s, at rest) is counted in the step it happens, named as the first
/// step, and adds nothing: the other particles fall exactly as in a run without it.
#[test]
fn gpu_fixed_point_range_is_counted_not_summed() {
    for gpu in gpus() {
        let dx = 1.0 / 16.0;
        let grid = Grid::new(DVec3::ZERO, DVec3::ONE, dx);
        let body = Particles::sample_box(DVec3::splat(0.3), DVec3::splat(0.4), dx / 2.0, 1000.0);
        let mut with_outlier = body.clone();
        with_outlier.append(&Particles::sample_box(
            DVec3::splat(0.7),
            DVec3::splat(0.7 + dx / 4.0),
            dx / 2.0,
            1000.0,
        ));
        let n = body.len();
        with_outlier.c[n] = DMat3::from_diagonal(DVec3::splat(1e6));
        let sp = params(1e-3, Boundaries::default());
        let material = [Material::fixed_corotated(1e4, 0.3)];
        let run = |p: &Particles| {
            let sim = GpuSim::with_path(&gpu, p, &grid, &material, &sp, P2gPath::Fixed).unwrap();
            sim.step(&gpu, 3).unwrap();
            let w = sim.take_watchdog(&gpu).unwrap();
            (w, sim.read_particles(&gpu, p).unwrap())
        };
        let (quiet, alone) = run(&body);
        assert_eq!((quiet.fixed_point_range, quiet.first_step), (0, None));
        let (w, out) = run(&with_outlier);
        assert_eq!(
            (w.fixed_point_range, w.first_step, w.nonfinite, w.escaped),
            (1, Some(0), 0, 0),
            "{w:?}"
        );
        assert_eq!(&out.x[..n], &alone.x[..], "the outlier added to the grid");
    }
}

/// The P2G race times both paths on its probe block (finite, positive times, the faster
/// path named), once per process and adapter: a second call returns the first's verdict.
#[test]
fn p2g_race_times_both_paths_once_and_names_the_faster() {
    use splatter::sim::gpu::P2gRace;
    for gpu in gpus().iter().filter(|g| g.features.float32_atomics) {
        let race = P2gRace::on(gpu).unwrap();
        for ms in [race.atomic_ms, race.gather_ms] {
            assert!(ms.is_finite() && ms > 0.0, "{race:?}");
        }
        let faster = if race.gather_ms < race.atomic_ms {
            P2gPath::Gather
        } else {
            P2gPath::Atomic
        };
        assert_eq!(race.winner(), faster, "{race:?}");
        assert_eq!(P2gRace::on(gpu).unwrap(), race, "raced twice");
    }
}

/// The plan takes a forced path as given, never the float atomics for a deterministic
/// run, the gather for two-field separation, and the race's winner only where the race
/// decides and the run is long enough to pay for it; it refuses a forced atomic path with
/// --deterministic, a grid past 2³² nodes and one whose block table exceeds the adapter.
#[test]
fn the_sim_plan_picks_one_path_and_refuses_what_cannot_run() {
    use splatter::bench::SimCase;
    use splatter::sim::gpu::{P2gRace, PlanError, SimPlan, SimRequest};
    use splatter::sim::Separation;
    let case = SimCase::new(2_000, 16);
    let mut separated = case.params.clone();
    separated.separation = Separation::DamageGradient;
    for gpu in gpus() {
        let ask = |params, forced, deterministic, steps| {
            SimPlan::choose(
                &gpu,
                &SimRequest {
                    params,
                    particles: case.particles.len(),
                    cells: case.grid.cells,
                    steps,
                    forced,
                    deterministic,
                },
            )
        };
        for path in P2gPath::ALL {
            if path == P2gPath::Atomic && !gpu.features.float32_atomics {
                continue;
            }
            let plan = ask(&case.params, Some(path), false, 1).unwrap();
            assert_eq!((plan.p2g, plan.race), (path, None));
        }
        let deterministic = ask(&case.params, None, true, u64::MAX).unwrap();
        assert_ne!(deterministic.p2g, P2gPath::Atomic);
        assert!(deterministic.race.is_none());
        assert_eq!(
            ask(&separated, None, false, u64::MAX).unwrap().p2g,
            P2gPath::Gather
        );
        // A short run is not raced; a long one is where the adapter leaves the choice open.
        assert!(ask(&case.params, None, false, 1).unwrap().race.is_none());
        let long = ask(&case.params, None, false, u64::MAX).unwrap();
        let decides = P2gRace::decides(&gpu, &case.params, case.particles.len());
        assert_eq!(long.race.is_some(), decides, "{}", gpu.describe());
        if let Some(race) = long.race {
            assert_eq!(long.p2g, race.winner());
        }
        assert!(matches!(
            ask(&case.params, Some(P2gPath::Atomic), true, 1),
            Err(PlanError::AtomicNotDeterministic)
        ));
        let too_many = SimPlan::check_grid(&gpu, DVec3::splat(2000.0), false, false);
        assert!(
            matches!(too_many, Err(PlanError::TooManyNodes(_))),
            "{too_many:?}"
        );
        let too_wide = SimPlan::check_grid(&gpu, DVec3::new(1600.0, 1600.0, 1600.0), true, false);
        assert!(matches!(too_wide, Err(PlanError::Limit(_))), "{too_wide:?}");
        SimPlan::check_grid(&gpu, DVec3::splat(64.0), true, true).unwrap();
    }
}
