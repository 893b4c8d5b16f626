//! Moving kinematic colliders (`splatter::sim::kinematic`): analytic checks on the CPU
//! reference step (material held by a sticky collider moves rigidly with it, a pushed block
//! takes the pusher's speed, a projectile through a jelly leaves it moving with constant
//! momentum and never inside the projectile) and the GPU step against the CPU step with
//! moving, rotating colliders, on every adapter and P2G path.

use glam::{DVec3, Vec3};
use splatter::gpu::GpuContext;
use splatter::sim::cpu::step_at;
use splatter::sim::gpu::{GpuSim, P2gPath};
use splatter::sim::kinematic::{ColliderShape, KinematicCollider, RigidMotion};
use splatter::sim::{
    Boundaries, Condition, DomainWalls, Grid, Material, Particles, StepParams, Transfer,
};

fn params(dt: f64, gravity: DVec3, walls: DomainWalls) -> StepParams {
    StepParams {
        dt,
        gravity,
        boundaries: Boundaries {
            walls,
            colliders: vec![],
            surface: None,
        },
        transfer: Transfer::Apic,
        separation: Default::default(),
        fields: Default::default(),
        actions: Default::default(),
    }
}

/// Straight-line motion from `from` to `to` over `seconds`, turning by `turn_deg`.
fn linear(from: DVec3, to: DVec3, seconds: f32, turn_deg: Vec3) -> RigidMotion {
    RigidMotion::new(
        vec![0.0, seconds],
        vec![from.as_vec3(), to.as_vec3()],
        vec![Vec3::ZERO, turn_deg],
    )
}

fn run_cpu(
    p: &mut Particles,
    grid: &mut Grid,
    m: &[Material],
    sp: &StepParams,
    k: &[KinematicCollider],
    steps: u32,
    start: u32,
) {
    for s in start..start + steps {
        step_at(p, grid, m, sp, k, f64::from(s) * sp.dt);
    }
}

/// A jelly block entirely inside a sticky box collider that moves and turns: every node the
/// block touches gets the rigid velocity, which the quadratic B-splines reproduce exactly,
/// so the particles follow the rigid motion (up to the time integration's O(Δt) drift).
#[test]
fn material_inside_a_sticky_collider_moves_rigidly_with_it() {
    let dx = 1.0 / 32.0;
    let c0 = DVec3::new(0.4, 0.5, 0.5);
    let mut p = Particles::sample_box(c0 - 0.06, c0 + 0.06, dx / 2.0, 1000.0);
    let start = p.x.clone();
    let material = Material::fixed_corotated(1e4, 0.3);
    p.set_material(0, &material);
    let collider = KinematicCollider {
        shape: ColliderShape::Box {
            half: DVec3::splat(0.15),
        },
        centre: DVec3::ZERO,
        margin: 0.0,
        condition: Condition::STICKY,
        motion: linear(
            c0,
            c0 + DVec3::new(0.2, 0.0, 0.0),
            0.5,
            Vec3::new(0.0, 0.0, 40.0),
        ),
    };
    let mut grid = Grid::new(DVec3::ZERO, DVec3::ONE, dx);
    let sp = params(1e-3, DVec3::new(0.0, -9.8, 0.0), DomainWalls::default());
    let k = [collider];
    run_cpu(&mut p, &mut grid, &[material], &sp, &k, 300, 0);
    let pose = k[0].motion.pose(0.3);
    let worst = start
        .iter()
        .zip(&p.x)
        .map(|(x0, x)| (pose.rotation * (*x0 - c0) + pose.position - *x).length())
        .fold(0.0, f64::max);
    eprintln!(
        "rigid carry: 300 steps, max |x − rigid motion| = {:.2e} Δx",
        worst / dx
    );
    assert!(worst < 0.05 * dx, "{worst}");
}

/// A block resting on a frictionless ground, pushed by a sticky box moving at u: once in
/// contact the block moves at u, and no particle enters the pusher by more than a cell.
#[test]
fn a_pushed_block_moves_with_the_pusher() {
    let dx = 1.0 / 32.0;
    let material = Material::fixed_corotated(2e4, 0.3);
    let mut p = Particles::sample_box(
        DVec3::new(0.4, 3.0 * dx, 0.4),
        DVec3::new(0.55, 3.0 * dx + 0.1, 0.6),
        dx / 2.0,
        1000.0,
    );
    p.set_material(0, &material);
    let u = 0.5;
    let half = DVec3::new(0.05, 0.1, 0.15);
    let from = DVec3::new(0.3, 3.0 * dx + 0.1, 0.5);
    let pusher = KinematicCollider {
        shape: ColliderShape::Box { half },
        centre: DVec3::ZERO,
        margin: 0.0,
        condition: Condition::STICKY,
        motion: linear(from, from + DVec3::new(u, 0.0, 0.0), 1.0, Vec3::ZERO),
    };
    let mut grid = Grid::new(DVec3::ZERO, DVec3::ONE, dx);
    let walls = DomainWalls::with_ground(Condition::SLIP, Condition::SEPARATE);
    let sp = params(5e-4, DVec3::new(0.0, -9.8, 0.0), walls);
    let k = [pusher];
    // Contact after (0.4 − 0.35)/u = 0.1 s; run to 0.4 s.
    run_cpu(&mut p, &mut grid, &[material], &sp, &k, 800, 0);
    let v = p.momentum() / p.total_mass();
    let pose = k[0].motion.pose(0.4);
    let depth =
        p.x.iter()
            .map(|x| -k[0].distance(&pose, *x))
            .fold(f64::MIN, f64::max);
    eprintln!(
        "pushed block: velocity {v:.4} (pusher {u}), deepest particle {:.2} Δx inside",
        depth / dx
    );
    assert!((v.x - u).abs() < 0.05 * u, "{v}");
    assert!(v.z.abs() < 0.01 * u, "{v}");
    assert!(depth < dx, "a particle is {depth} inside the pusher");
}

/// A fast sphere strikes a floating jelly slab (no gravity, no walls reached) and pulls back:
/// the jelly is pushed along the shot, no particle is ever inside the projectile by more
/// than a cell, and once the projectile has let go the jelly's momentum is constant.
#[test]
fn a_projectile_strikes_a_jelly() {
    let dx = 1.0 / 32.0;
    let material = Material::fixed_corotated(3e3, 0.3);
    let mut p = Particles::sample_box(
        DVec3::new(0.35, 0.35, 0.45),
        DVec3::new(0.65, 0.65, 0.6),
        dx / 2.0,
        1000.0,
    );
    p.set_material(0, &material);
    // 4 m/s in, to 0.05 deep, and back out at 4 m/s.
    let shot = KinematicCollider {
        shape: ColliderShape::Sphere { radius: 0.05 },
        centre: DVec3::ZERO,
        margin: 0.0,
        condition: Condition::SEPARATE,
        motion: RigidMotion::new(
            vec![0.0, 0.05, 0.1],
            vec![
                Vec3::new(0.5, 0.5, 0.3),
                Vec3::new(0.5, 0.5, 0.5),
                Vec3::new(0.5, 0.5, 0.3),
            ],
            vec![Vec3::ZERO; 3],
        ),
    };
    let mut grid = Grid::new(DVec3::ZERO, DVec3::ONE, dx);
    let sp = params(2.5e-4, DVec3::ZERO, DomainWalls::default());
    let k = [shot];
    let mut deepest = f64::MIN;
    let mut steps = 0;
    for _ in 0..12 {
        run_cpu(&mut p, &mut grid, &[material], &sp, &k, 50, steps);
        steps += 50;
        let pose = k[0].motion.pose(f64::from(steps) * sp.dt);
        let d =
            p.x.iter()
                .map(|x| -k[0].distance(&pose, *x))
                .fold(f64::MIN, f64::max);
        deepest = deepest.max(d);
    }
    let m1 = p.momentum();
    run_cpu(&mut p, &mut grid, &[material], &sp, &k, 200, steps);
    let m2 = p.momentum();
    eprintln!(
        "projectile: jelly momentum {m1:.5} → {m2:.5} after the shot; deepest particle {:.2} Δx inside",
        deepest / dx
    );
    assert!(m1.z > 0.0 && m1.z > 100.0 * m1.truncate().length(), "{m1}");
    assert!((m2 - m1).length() < 1e-9 * m1.length(), "{m1} vs {m2}");
    assert!(
        deepest < dx,
        "a particle is {deepest} inside the projectile"
    );
}

fn paths(gpu: &GpuContext) -> Vec<P2gPath> {
    let mut list = vec![P2gPath::Gather, P2gPath::Fixed];
    if gpu.features.float32_atomics {
        list.push(P2gPath::Atomic);
    }
    list
}

/// A jelly on a frictional ground, hit by a turning sticky box and a slipping cylinder that
/// moves along a curved path: the GPU (poses uploaded per substep, set in two calls) follows
/// the CPU reference.
#[test]
fn gpu_kinematic_step_matches_the_cpu_reference() {
    let dx = 1.0 / 24.0;
    let material = Material::fixed_corotated(1e4, 0.3);
    let mut particles = Particles::sample_box(
        DVec3::new(0.35, 3.0 * dx, 0.35),
        DVec3::new(0.6, 3.0 * dx + 0.15, 0.6),
        dx / 2.0,
        1000.0,
    );
    particles.set_material(0, &material);
    let blade = KinematicCollider {
        shape: ColliderShape::Box {
            half: DVec3::new(0.1, 0.01, 0.08),
        },
        centre: DVec3::new(0.0, 0.02, 0.0),
        margin: 0.5 * dx,
        condition: Condition::STICKY,
        motion: linear(
            DVec3::new(0.47, 0.35, 0.47),
            DVec3::new(0.47, 0.1, 0.47),
            0.1,
            Vec3::new(0.0, 30.0, 0.0),
        ),
    };
    let roller = KinematicCollider {
        shape: ColliderShape::Cylinder {
            radius: 0.05,
            half_height: 0.2,
        },
        centre: DVec3::ZERO,
        margin: 0.0,
        condition: Condition::SLIP.with_friction(0.3),
        motion: RigidMotion::new(
            vec![0.0, 0.05, 0.1],
            vec![
                Vec3::new(0.2, 0.15, 0.47),
                Vec3::new(0.32, 0.12, 0.5),
                Vec3::new(0.4, 0.15, 0.45),
            ],
            vec![
                Vec3::ZERO,
                Vec3::new(0.0, 0.0, 45.0),
                Vec3::new(10.0, 0.0, 90.0),
            ],
        ),
    };
    let k = [blade, roller];
    let walls = DomainWalls::with_ground(Condition::SLIP.with_friction(0.2), Condition::SEPARATE);
    let sp = params(4e-4, DVec3::new(0.0, -9.8, 0.0), walls);
    let steps = 200;
    let mut cpu = particles.clone();
    let mut grid = Grid::new(DVec3::ZERO, DVec3::splat(0.8), dx);
    run_cpu(&mut cpu, &mut grid, &[material], &sp, &k, steps, 0);
    let moved = cpu
        .x
        .iter()
        .zip(&particles.x)
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max);
    for gpu in splatter::gpu::test_contexts() {
        for path in paths(&gpu) {
            let mut sim =
                GpuSim::with_path(&gpu, &particles, &grid, &[material], &sp, path).unwrap();
            sim.set_kinematic(&gpu, &k).unwrap();
            sim.step(&gpu, steps / 2).unwrap();
            sim.step(&gpu, steps / 2).unwrap();
            let out = sim.read_particles(&gpu, &particles).unwrap();
            let worst = cpu
                .x
                .iter()
                .zip(&out.x)
                .map(|(a, b)| (*a - *b).abs().max_element())
                .fold(0.0, f64::max);
            eprintln!(
                "{} ({path:?} P2G): {} particles, {steps} steps, two moving colliders, moved up to {:.1} Δx; GPU vs CPU max |Δx| = {:.2e} Δx",
                gpu.describe(),
                particles.len(),
                moved / dx,
                worst / dx
            );
            assert!(moved / dx > 1.0, "the colliders should move the jelly");
            assert!(worst / dx < 1e-2, "GPU and CPU differ by {} Δx", worst / dx);
        }
    }
}

const KNIFE_SCENE: &str = r#"{
  "output": { "width": 64, "height": 48, "fps": 24, "frames": 3 },
  "camera": { "fov_y_deg": 40, "path": { "type": "orbit", "target": [0.3, 0.3, 0.1], "radius": 1.0, "height": 0.4 } },
  "simulation": {
    "dx": 0.03,
    "domain": { "lo": [0, 0, 0], "hi": [0.6, 0.6, 0.6] },
    "ground": { "kind": "separate", "friction": 0.4 }
  },
  "objects": [
    {
      "name": "jelly",
      "procedural": { "shape": "box", "size": [0.18, 0.18, 0.1], "spacing": 0.015, "color": [0.2, 0.8, 0.3] },
      "transform": { "translate": [0.3, 0.3, 0.14] },
      "physics": { "material": { "model": "fixed_corotated", "E": 500, "nu": 0.3, "density": 2 } }
    },
    {
      "name": "blade",
      "procedural": { "shape": "box", "size": [0.2, 0.01, 0.08], "spacing": 0.005, "color": [0.8, 0.8, 0.85] },
      "transform": { "translate": [0.3, 0.3, 0.4], "rotate_deg": [0, 0, 10] },
      "kinematic": {
        "keyframes": [
          { "time": 0, "position": [0.3, 0.3, 0.4], "rotate_deg": [0, 0, 10] },
          { "time": 0.1, "position": [0.3, 0.3, 0.1], "rotate_deg": [0, 20, 10] }
        ],
        "kind": "slip", "friction": 0.2, "margin": 0.015
      }
    }
  ]
}"#;

/// A scene's kinematic object: its collider is the procedural box (scaled, at the object's
/// pose), and its Gaussians are rendered moved by the path's rigid motion (means, and
/// covariances turned with it), on the GPU.
#[test]
fn a_kinematic_object_in_a_scene_moves_its_gaussians_rigidly() {
    use splatter::derive::RigidDerive;
    use splatter::render::GpuRenderer;
    use splatter::scene::simulation::{prepare, PartKind};
    let scene =
        splatter::scene::parse(KNIFE_SCENE, "knife.json", std::path::Path::new(".")).unwrap();
    let (splats, report) = scene.build_splats().unwrap();
    let setup = prepare(&scene, splats, &report).unwrap().unwrap();
    assert_eq!(setup.kinematic.len(), 1);
    let k = &setup.kinematic[0];
    assert_eq!(k.object, 1);
    let ColliderShape::Box { half } = k.collider.shape else {
        panic!("{:?}", k.collider.shape)
    };
    assert!(
        (half - DVec3::new(0.1, 0.005, 0.04)).length() < 1e-7,
        "{half}"
    );
    let part = setup
        .parts
        .iter()
        .find(|p| p.object == 1)
        .expect("the blade's Gaussians");
    assert_eq!(part.kind, PartKind::Static);
    // At t = 0 the path starts at the transform: nothing moves.
    let (a0, b0) = k.rest_to_world(0.0);
    assert!(
        (a0 - glam::DMat3::IDENTITY).abs_diff_eq(glam::DMat3::ZERO, 1e-6) && b0.length() < 1e-6
    );
    let gpu = GpuContext::new(None).unwrap();
    let mut renderer = GpuRenderer::new(&gpu);
    renderer.upload(&gpu, &setup.splats).unwrap();
    let rigid = RigidDerive::new(
        &gpu,
        &renderer,
        &setup.splats,
        part.start as u32,
        part.len as u32,
    )
    .unwrap();
    let (a, b) = k.rest_to_world(0.05);
    rigid.run(&gpu, a, b).unwrap();
    let out = renderer.read_gaussians(&gpu).unwrap();
    let mut worst = (0.0f64, 0.0f64);
    for (g, out) in out.iter().enumerate().skip(part.start).take(part.len) {
        let want = a * setup.splats.means[g].as_dvec3() + b;
        let got = DVec3::from_slice(&out.mean_opacity.map(f64::from)[..3]);
        worst.0 = worst.0.max((want - got).length());
        let c = splatter::derive::rest_covariance(&setup.splats, g);
        let want_c = a * c * a.transpose();
        let [xx, xy, xz, yy] = out.cov_a.map(f64::from);
        let err = (want_c.x_axis - DVec3::new(xx, xy, xz)).length() + (want_c.y_axis.y - yy).abs();
        worst.1 = worst
            .1
            .max(err / c.x_axis.x.max(c.y_axis.y).max(c.z_axis.z));
    }
    eprintln!(
        "{}: rigid blade, {} Gaussians: max |mean − path| {:.1e}, covariance {:.1e} relative",
        gpu.describe(),
        part.len,
        worst.0,
        worst.1
    );
    assert!(worst.0 < 1e-6 && worst.1 < 1e-5, "{worst:?}");
}
