//! Real captures as users bring them: the up axis and support `inspect` estimates, the
//! upright, framed quick look of `render --ply`, the capture seen from its own training
//! cameras (in its own frame), `up` in scene files, and the fill of an open capture. Data: tests/data/captures (subsets of a real plant capture) and
//! tests/data/formats (a subset of the Mip-Splatting donut); see their READMEs.

use std::path::{Path, PathBuf};

use glam::{Mat3, Quat, Vec3};
use splatter::render::camera::{look_at_rotation, DEFAULT_NEAR};
use splatter::render::{cpu, Camera, Splats};
use splatter::run::{Input, Run, RunOptions};
use splatter::splat::formats::read_splats;
use splatter::splat::inspect::{inspect, robust_bounds, UpEvidence};
use splatter::splat::GaussianCloud;

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
            up: None,
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

// ---------------------------------------------------------------------------------------------
// A capture seen from its own training cameras
// ---------------------------------------------------------------------------------------------

/// A `cameras.json` holding one camera of `width`×`height` looking at the centre of
/// `cloud`'s robust bounds from a direction off every axis, rolled (its image up is no
/// axis either), in the capture's own frame; and that camera built here, independently of
/// the reader.
fn off_axis_camera(cloud: &GaussianCloud, width: u32, height: u32) -> (String, Camera) {
    let (lo, hi) = robust_bounds(&cloud.positions);
    let centre = 0.5 * (lo + hi);
    let distance = 1.1 * (hi - lo).length();
    let eye = centre + distance * Vec3::new(0.62, -0.41, 0.67).normalize();
    let rotation = look_at_rotation(eye, centre, Vec3::new(0.35, -1.0, 0.25));
    let focal = 0.9 * height as f32;
    let rows: Vec<[f32; 3]> = (0..3).map(|i| rotation.row(i).to_array()).collect();
    let json = serde_json::json!([{
        "id": 0, "img_name": "view_0", "width": width, "height": height,
        "position": eye.to_array(), "rotation": rows, "fx": focal, "fy": focal,
    }]);
    let camera = Camera {
        position: eye,
        rotation,
        fx: focal,
        fy: focal,
        width,
        height,
        near: DEFAULT_NEAR,
    };
    (json.to_string(), camera)
}

/// Frame 0 of `opts`, rendered on the test adapter (RGBA), with the run's background.
fn render_frame(opts: RunOptions) -> (Vec<u8>, Vec3) {
    let out = opts.out.clone().unwrap();
    let run = Run::prepare(opts).unwrap();
    let background = Vec3::from(run.scene().output.background);
    let gpu = splatter::gpu::GpuContext::new(None).expect("a wgpu adapter");
    run.execute(&gpu, &mut |_| {}).unwrap();
    let image = image::open(out.join("frame_00000.png")).unwrap().to_rgba8();
    (image.into_raw(), background)
}

/// The CPU reference renderer's image of `cloud` as it is in its file (no transform).
fn reference_image(cloud: &GaussianCloud, m: Mat3, camera: &Camera, background: Vec3) -> Vec<u8> {
    cpu::render(
        &Splats::from_cloud(cloud, m, Vec3::ZERO),
        camera,
        background,
    )
}

/// The CPU reference of the capture stood upright (its up turned to +z, as the orbit quick
/// look does) scores low against its own-frame image from this camera: the plant is not
/// symmetric under that quarter turn, so a test against the own-frame image can tell the
/// two apart.
fn assert_the_frame_matters(cloud: &GaussianCloud, camera: &Camera, own: &[u8]) {
    let upright = Mat3::from_quat(Quat::from_rotation_arc(inspect(cloud).up, Vec3::Z));
    let turned = reference_image(cloud, upright, camera, Vec3::ZERO);
    let psnr = cpu::psnr(&turned, own);
    println!("the capture stood upright against its own frame: {psnr:.1} dB");
    assert!(
        psnr < 25.0,
        "the view cannot tell the frames apart: {psnr:.1} dB"
    );
}

/// `render --ply F --cameras cameras.json`: the capture is drawn in its own frame, the one
/// its training cameras were posed in, so the image is the CPU reference's of the
/// untransformed Gaussians from that camera (PSNR ≥ 40 dB, the golden images' bound for
/// GPU against CPU).
#[test]
fn quick_look_from_a_training_camera_draws_the_capture_in_its_own_frame() {
    let dir = tempfile::tempdir().unwrap();
    let (cloud, _) = read_splats(&data(PLANT)).unwrap();
    let (json, camera) = off_axis_camera(&cloud, 160, 120);
    let cameras = dir.path().join("cameras.json");
    std::fs::write(&cameras, json).unwrap();
    let (image, background) = render_frame(RunOptions {
        input: Input::Ply {
            file: data(PLANT),
            cameras: Some(cameras),
            camera: Some(0),
            up: None,
        },
        out: Some(dir.path().join("frames")),
        ..RunOptions::default()
    });
    let reference = reference_image(&cloud, Mat3::IDENTITY, &camera, background);
    assert_the_frame_matters(&cloud, &camera, &reference);
    let psnr = cpu::psnr(&image, &reference);
    println!("--ply --cameras against the CPU reference in the capture's frame: {psnr:.1} dB");
    assert!(psnr >= 40.0, "{psnr:.1} dB against the CPU reference");
}

/// A scene file with the capture untransformed and a `cameras_json` camera path renders
/// the same view (the scene's frame is the capture's).
#[test]
fn scene_with_a_cameras_json_path_draws_the_capture_in_its_own_frame() {
    let dir = tempfile::tempdir().unwrap();
    let (cloud, _) = read_splats(&data(PLANT)).unwrap();
    let (json, camera) = off_axis_camera(&cloud, 160, 120);
    std::fs::write(dir.path().join("cameras.json"), json).unwrap();
    let scene = serde_json::json!({
        "output": {"width": 160, "height": 120, "frames": 1},
        "camera": {"path": {"type": "cameras_json", "file": "cameras.json"}},
        "objects": [{"ply": data(PLANT)}],
    });
    let file = dir.path().join("scene.json");
    std::fs::write(&file, scene.to_string()).unwrap();
    let (image, background) = render_frame(RunOptions {
        input: Input::Scene(Some(file)),
        out: Some(dir.path().join("frames")),
        ..RunOptions::default()
    });
    let reference = reference_image(&cloud, Mat3::IDENTITY, &camera, background);
    let psnr = cpu::psnr(&image, &reference);
    println!("scene with cameras_json against the CPU reference: {psnr:.1} dB");
    assert!(psnr >= 40.0, "{psnr:.1} dB against the CPU reference");
}
