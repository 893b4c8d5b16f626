//! Real captures as users bring them: the up axis and support `inspect` estimates, the
//! upright, framed quick look of `render --ply`, `up` in scene files, and the fill of an
//! open capture. Data: tests/data/captures (a subset of the shared plant capture) and
//! tests/data/formats (a subset of the Mip-Splatting donut); see their READMEs.

use std::path::{Path, PathBuf};

use glam::Vec3;
use splatter::run::{Input, Run, RunOptions};
use splatter::splat::formats::read_splats;
use splatter::splat::inspect::{inspect, robust_bounds, UpEvidence};

fn data(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(path)
}

const PLANT: &str = "captures/plant_14k.spz";
const DONUT: &str = "formats/donut_4k.ply";

/// The plant is −y up (its README says so); the donut's icing faces +z.
#[test]
fn inspect_finds_the_up_axis_of_both_captures() {
    for (file, up) in [(PLANT, -Vec3::Y), (DONUT, Vec3::Z)] {
        let (cloud, _) = read_splats(&data(file)).unwrap();
        let found = inspect(&cloud);
        println!("{file}:\n{found}\n");
        assert_eq!(found.up, up, "{file}: {:?}", found.evidence);
        assert_eq!(found.floaters, 0, "{file}");
        // The support lies at the bottom of the robust core along up.
        let (lo, hi) = found.upright_robust_bounds();
        let t = found.placement(0.0);
        assert!(
            (lo.z + t.z).abs() < 0.05 * (hi.z - lo.z),
            "{file}: support at z = 0"
        );
    }
    // The donut's up comes from its seen top, the plant's only from the convention.
    let (donut, _) = read_splats(&data(DONUT)).unwrap();
    assert!(matches!(
        inspect(&donut).evidence,
        UpEvidence::SeenTop { .. }
    ));
}

/// A capture with a table under it: the support plane decides, and its height is the
/// table's, whatever frame the capture came in.
#[test]
fn a_support_plane_sets_up_and_height() {
    let (mut cloud, _) = read_splats(&data(DONUT)).unwrap();
    // A dense slab of Gaussians at z = −0.02 under the donut, as a table capture would be,
    // then the whole capture turned so that its up is −y (as in COLMAP frames).
    let n = 6000;
    let mut rng = splatter::rng::SplitMix64::new(7);
    for _ in 0..n {
        cloud
            .positions
            .push(Vec3::new(rng.range(-0.2, 0.2), rng.range(-0.2, 0.2), -0.02));
        cloud.scales.push(Vec3::new(0.004, 0.004, 0.0004));
        cloud.rotations.push(glam::Quat::IDENTITY);
        cloud.opacities.push(0.9);
        cloud.sh.extend([0.5, 0.5, 0.5]);
    }
    let turn = glam::Mat3::from_rotation_x(std::f32::consts::FRAC_PI_2);
    for p in &mut cloud.positions {
        *p = turn * *p;
    }
    let found = inspect(&cloud);
    println!("{found}");
    assert!(
        matches!(found.evidence, UpEvidence::SupportPlane { .. }),
        "{:?}",
        found.evidence
    );
    assert!(found.up.distance(-Vec3::Y) < 1e-6, "{:?}", found.up);
    // The table top: at y = 0.02 after the turn, so at height −0.02 along −y.
    assert!((found.support + 0.02).abs() < 0.003, "{}", found.support);
}

fn quick_look(file: &str) -> Run {
    Run::prepare(RunOptions {
        input: Input::Ply {
            file: data(file),
            cameras: None,
            camera: None,
        },
        out: Some(std::env::temp_dir().join("splatter-quick-look-test")),
        width: Some(320),
        height: Some(180),
        ..RunOptions::default()
    })
    .unwrap()
}

/// `render --ply`: the capture stands upright (its up is the world's +z, which the orbit
/// circles) and its robust bounds fill at least a third of the frame height in every
/// frame of the orbit.
#[test]
fn quick_look_is_upright_and_framed() {
    for (file, tall) in [(PLANT, true), (DONUT, false)] {
        let run = quick_look(file);
        let splats = run.splats().unwrap();
        let (lo, hi) = robust_bounds(&splats.means);
        let size = hi - lo;
        println!("{file}: upright robust size {size:?}");
        if tall {
            assert!(
                size.z > 1.5 * size.x.max(size.y),
                "the plant stands: {size:?}"
            );
        } else {
            assert!(
                size.z < 0.6 * size.x.min(size.y),
                "the donut lies flat: {size:?}"
            );
        }
        let path = run.camera_path();
        for frame in [0, 15, 30, 45] {
            let cam = path.camera(frame);
            let mut ys = Vec::new();
            for c in 0..8 {
                let p = Vec3::new(
                    if c & 1 == 0 { lo.x } else { hi.x },
                    if c & 2 == 0 { lo.y } else { hi.y },
                    if c & 4 == 0 { lo.z } else { hi.z },
                );
                let q = cam.world_to_camera() * (p - cam.position);
                assert!(q.z > 0.0, "in front of the camera");
                ys.push(cam.height as f32 * 0.5 + cam.fy * q.y / q.z);
            }
            let span = ys.iter().copied().fold(f32::NEG_INFINITY, f32::max)
                - ys.iter().copied().fold(f32::INFINITY, f32::min);
            println!(
                "  frame {frame}: robust box spans {span:.0} of {} px",
                cam.height
            );
            assert!(
                span >= cam.height as f32 / 3.0,
                "{file} frame {frame}: {span} px"
            );
            assert!(
                span <= cam.height as f32 * 1.05,
                "{file} frame {frame}: cut off"
            );
            // Upright: the world's +z points up the image (image y down).
            let up = cam.world_to_camera() * Vec3::Z;
            assert!(up.y < -0.8, "{file} frame {frame}: camera up {up:?}");
        }
    }
}

/// The scene of the drop tests: the plant, stood upright by `up: auto` and lifted so its
/// support is at z = `lift`, above a 10 cm slab whose top is z = 0.1 and which is declared a
/// collider (or not, to see that the collider is what stops it: the ground is then the
/// domain's floor at z = −0.2).
fn drop_scene(collider: bool) -> String {
    let (cloud, _) = read_splats(&data(PLANT)).unwrap();
    let found = inspect(&cloud);
    let lift = 0.16;
    let t = found.placement(lift);
    let collider = if collider {
        r#", "collider": { "kind": "separate", "friction": 0.8 }"#
    } else {
        ""
    };
    format!(
        r#"{{
  "output": {{ "width": 32, "height": 24, "frames": 1 }},
  "camera": {{ "fov_y_deg": 40, "path": {{ "type": "orbit", "target": [0, 0, 0.4], "radius": 3 }} }},
  "simulation": {{
    "dx": 0.04, "domain": {{ "lo": [-0.4, -0.4, -0.2], "hi": [0.4, 0.4, 1.2] }},
    "walls": {{ "kind": "separate" }}, "ground": {{ "kind": "separate", "friction": 0.8 }}
  }},
  "objects": [
    {{ "name": "slab",
       "procedural": {{ "shape": "box", "size": [0.7, 0.7, 0.1], "spacing": 0.01, "color": [0.5, 0.5, 0.5] }},
       "transform": {{ "translate": [0, 0, 0.05] }}{collider} }},
    {{ "name": "plant", "ply": "{ply}",
       "transform": {{ "up": "auto", "translate": [{x}, {y}, {z}] }},
       "physics": {{ "material": {{ "model": "neo_hookean", "E": 1000000, "nu": 0.3, "density": 400 }} }} }}
  ]
}}"#,
        ply = data(PLANT).display(),
        x = t.x,
        y = t.y,
        z = t.z,
    )
}

/// Simulate `seconds` and return the particles' positions, and the setup.
fn drop(
    collider: bool,
    seconds: f64,
) -> (
    Vec<glam::DVec3>,
    splatter::scene::simulation::SimulationSetup,
) {
    use splatter::gpu::GpuContext;
    use splatter::sim::gpu::GpuSim;
    let scene = splatter::scene::parse(&drop_scene(collider), "drop.json", Path::new("/")).unwrap();
    let (splats, report) = scene.build_splats().unwrap();
    let setup = splatter::scene::simulation::prepare(&scene, splats, &report)
        .unwrap()
        .unwrap();
    let gpu = GpuContext::new(None).unwrap();
    let mut sim = GpuSim::new(
        &gpu,
        &setup.particles,
        &setup.grid,
        &setup.materials,
        &setup.params,
    )
    .unwrap();
    let steps = (seconds / setup.params.dt).ceil() as u32;
    let mut done = 0;
    while done < steps {
        let k = (steps - done).min(100);
        let frame = sim
            .step_frame(&gpu, k, done as f64 * setup.params.dt)
            .unwrap();
        sim.fit_pool(&gpu, &frame.watchdog).unwrap();
        done += k;
    }
    let out = sim.read_particles(&gpu, &setup.particles).unwrap();
    (out.x, setup)
}

/// The plant, stood up by `up: auto`, dropped onto a slab declared a collider comes to rest
/// on it: no particle more than Δx below the slab's top (z = 0.1), the pot's base on it, and
/// the plant still upright (its height kept). Without `collider` the same plant falls
/// through the slab to the floor, so the collider is what holds it.
#[test]
fn plant_dropped_on_a_captured_slab_rests_on_it() {
    let (x, setup) = drop(true, 0.3);
    let dx = setup.grid.dx;
    let lowest = x.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
    println!(
        "{} particles, dt {:.2e}: lowest z {lowest:.4} (slab top 0.1, Δx {dx})",
        x.len(),
        setup.params.dt
    );
    assert!(
        lowest >= 0.1 - dx,
        "a particle at z = {lowest} sank below the slab"
    );
    assert!(
        lowest <= 0.1 + 1.5 * dx,
        "the plant should have landed: lowest z = {lowest}"
    );
    // Upright: what started in the top half (the leaves) is still well above what
    // started in the bottom half (the pot), and the plant has not slid or tipped sideways.
    // (It sags: a jelly plant simulated from its surface Gaussians at Δx = 4 cm.)
    let x0 = &setup.particles.x;
    let mid = 0.5
        * (x0.iter().map(|p| p.z).fold(f64::INFINITY, f64::min)
            + x0.iter().map(|p| p.z).fold(f64::NEG_INFINITY, f64::max));
    let mean = |pick: &dyn Fn(usize) -> bool| {
        let v: Vec<glam::DVec3> = (0..x.len()).filter(|&i| pick(i)).map(|i| x[i]).collect();
        v.iter().sum::<glam::DVec3>() / v.len() as f64
    };
    let (upper, lower) = (mean(&|i| x0[i].z > mid), mean(&|i| x0[i].z <= mid));
    let c0 = x0.iter().sum::<glam::DVec3>() / x0.len() as f64;
    let c1 = x.iter().sum::<glam::DVec3>() / x.len() as f64;
    println!(
        "upper half at z {:.3}, lower half at z {:.3}; centre moved {:.3} sideways",
        upper.z,
        lower.z,
        (c1 - c0).truncate().length()
    );
    assert!(
        upper.z - lower.z > 0.2,
        "the plant should stand: {upper:?} over {lower:?}"
    );
    assert!(
        (upper - lower).truncate().length() < 0.5 * (upper.z - lower.z),
        "tipped: {upper:?} over {lower:?}"
    );
    assert!((c1 - c0).truncate().length() < 0.05, "slid sideways");

    let (x, _) = drop(false, 0.2);
    let lowest = x.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
    println!("without the collider: lowest z {lowest:.4}");
    assert!(
        lowest < 0.1 - dx,
        "without the collider the plant falls through: {lowest}"
    );
}
