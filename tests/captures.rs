//! Real captures as users bring them: the up axis and support `inspect` estimates, the
//! upright, framed quick look of `render --ply`, the capture seen from its own training
//! cameras (in its own frame), `up` in scene files, and the fill of an open capture. Data: tests/data/captures (subsets of a real plant capture) and
//! tests/data/formats (a subset of the Mip-Splatting donut); see their READMEs.

mod common;

use std::path::{Path, PathBuf};

use common::cli::{assert_mentions, describe, splatter_ok, stderr_lines, workdir};
use glam::{Mat3, Quat, Vec3};
use splatter::render::camera::{look_at_rotation, DEFAULT_NEAR};
use splatter::render::{cpu, Camera, Splats};
use splatter::run::{Input, Run, RunOptions};
use splatter::sim::time_step::StepPlan;
use splatter::splat::formats::read_splats;
use splatter::splat::inspect::{
    cameras_up, inspect, inspect_with_cameras, robust_bounds, UpEvidence,
};
use splatter::splat::ply::{write_ply, PlyFormat};
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
            dataparser: None,
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
            .step_frame(
                &gpu,
                StepPlan {
                    dt: setup.params.dt,
                    steps: k,
                },
                done as f64 * setup.params.dt,
                0,
            )
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
            dataparser: None,
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

// ---------------------------------------------------------------------------------------------
// Up from the capture's cameras, and a warning when up is a guess
// ---------------------------------------------------------------------------------------------

/// Cameras posed round the plant as a phone video would be (its author does not distribute
/// the training cameras; how they were placed: tests/data/captures/make_cameras.py).
const PLANT_CAMERAS: &str = "captures/plant_cameras.json";

/// A half turn about x: the plant's −y up becomes +y (a proper rotation, not a mirror).
const FLIP: Mat3 = Mat3::from_cols(Vec3::X, Vec3::NEG_Y, Vec3::NEG_Z);

/// The plant in its own frame (−y up), or turned by [`FLIP`] into a +y-up file.
fn plant(flipped: bool) -> GaussianCloud {
    let (mut cloud, _) = read_splats(&data(PLANT)).unwrap();
    if flipped {
        assert_eq!(
            cloud.sh_degree, 0,
            "higher SH degrees would need rotating too"
        );
        let q = Quat::from_mat3(&FLIP);
        for p in cloud.positions.iter_mut().chain(cloud.normals.iter_mut()) {
            *p = FLIP * *p;
        }
        for r in &mut cloud.rotations {
            *r = q * *r;
        }
    }
    cloud
}

/// The plant's cameras (camera-to-world, OpenCV axes) as the fixture holds them, or turned by
/// [`FLIP`] with the plant.
fn plant_cameras_json(flipped: bool) -> String {
    let text = std::fs::read_to_string(data(PLANT_CAMERAS)).unwrap();
    let mut cams: Vec<serde_json::Value> = serde_json::from_str(&text).unwrap();
    if flipped {
        let turn = |v: &serde_json::Value| -> [f32; 3] {
            let a: [f32; 3] = serde_json::from_value(v.clone()).unwrap();
            (FLIP * Vec3::from_array(a)).to_array()
        };
        for c in &mut cams {
            c["position"] = serde_json::json!(turn(&c["position"]));
            // R' = FLIP · R: each column turned; by rows, rows 1 and 2 negated.
            let rows: [[f32; 3]; 3] = serde_json::from_value(c["rotation"].clone()).unwrap();
            let r = Mat3::from_cols_array_2d(&rows).transpose();
            let turned = (FLIP * r).transpose().to_cols_array_2d();
            c["rotation"] = serde_json::json!(turned);
        }
    }
    serde_json::to_string(&cams).unwrap()
}

/// The true up of the plant's file: −y as captured, +y flipped.
fn true_up(flipped: bool) -> Vec3 {
    if flipped {
        FLIP * -Vec3::Y
    } else {
        -Vec3::Y
    }
}

/// The camera-to-world rotations of a cameras.json text.
fn rotations(json: &str) -> Vec<Mat3> {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("cameras.json");
    std::fs::write(&file, json).unwrap();
    splatter::scene::from_cameras_json(&file, None, None)
        .unwrap()
        .iter()
        .map(|c| c.rotation)
        .collect()
}

/// The plant as captured (−y up) and flipped (+y up): with its cameras, up is the true up
/// (the mean of the cameras' ups within a few degrees of it, snapped to the axis); without
/// them, no evidence decides, the convention's −y is marked a guess and a warning says so
/// (the guess is wrong for the flipped file).
#[test]
fn the_cameras_give_the_plant_s_up_in_either_frame() {
    for flipped in [false, true] {
        let cloud = plant(flipped);
        let truth = true_up(flipped);
        let cameras = cameras_up(&rotations(&plant_cameras_json(flipped))).unwrap();
        let angle = cameras.up.angle_between(truth).to_degrees();
        println!(
            "flipped {flipped}: mean up of {} cameras {:.4?}, {angle:.2}° from the true up; spread {:.1}°, agreement {:.3}",
            cameras.count, cameras.up, cameras.spread_deg, cameras.agreement
        );
        assert!(angle < 5.0, "{angle}° from {truth}");
        let found = inspect_with_cameras(&cloud, Some(cameras));
        assert_eq!(found.up, truth, "{:?}", found.evidence);
        assert!(matches!(
            found.evidence,
            UpEvidence::Cameras { count: 24, .. }
        ));
        assert!(found.guess_warning("plant").is_none());

        let alone = inspect(&cloud);
        println!("  without cameras: {}", alone.up_text());
        assert!(alone.is_guess(), "{:?}", alone.evidence);
        assert_eq!(alone.up, -Vec3::Y, "the convention");
        let warning = alone.guess_warning("plant").unwrap();
        assert!(
            warning.contains("--up") && warning.contains("cameras"),
            "{warning}"
        );
    }
}

/// The upright-and-framed quick look of the plant, with its cameras.json next to it or
/// none, and `up` given or not.
fn quick_look_at(dir: &Path, flipped: bool, cameras: bool, up: Option<&str>) -> Run {
    let file = dir.join("plant.ply");
    write_ply(&file, &plant(flipped), PlyFormat::BinaryLittleEndian).unwrap();
    let json = dir.join("cameras.json");
    if cameras {
        std::fs::write(&json, plant_cameras_json(flipped)).unwrap();
    } else if json.exists() {
        std::fs::remove_file(&json).unwrap();
    }
    Run::prepare(RunOptions {
        input: Input::Ply {
            file,
            cameras: None,
            dataparser: None,
            camera: None,
            up: up.map(str::to_string),
        },
        out: Some(dir.join("out")),
        width: Some(320),
        height: Some(180),
        ..RunOptions::default()
    })
    .unwrap()
}

/// Heights (world z) of the plant's leaves and of the rest (the pot and soil) in a run's
/// Gaussians, as means: the leaves are the Gaussians whose colour is clearly green.
fn leaves_and_pot(run: &Run) -> (f32, f32) {
    let splats = run.splats().unwrap();
    let (mut leaves, mut pot) = (Vec::new(), Vec::new());
    for (i, m) in splats.means.iter().enumerate() {
        if splats.opacities[i] < 0.1 {
            continue;
        }
        let rgb =
            Vec3::from_slice(&splats.sh[3 * i..3 * i + 3]) * splatter::splat::codec::SH_C0 + 0.5;
        let green = rgb.y > 1.1 * rgb.x && rgb.y > 1.1 * rgb.z;
        if green { &mut leaves } else { &mut pot }.push(m.z);
    }
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
    (mean(&leaves), mean(&pot))
}

/// The cameras' mean height (world z) in a quick look, against the plant's robust centre:
/// positive when they look down on it.
fn cameras_above(run: &Run, flipped: bool) -> f32 {
    let (m, t) = run.scene().objects[0].transform.affine();
    let cams: Vec<serde_json::Value> = serde_json::from_str(&plant_cameras_json(flipped)).unwrap();
    let mean: Vec3 = cams
        .iter()
        .map(|c| {
            let p: [f32; 3] = serde_json::from_value(c["position"].clone()).unwrap();
            m * Vec3::from_array(p) + t
        })
        .sum::<Vec3>()
        / cams.len() as f32;
    let (lo, hi) = robust_bounds(&run.splats().unwrap().means);
    mean.z - 0.5 * (lo.z + hi.z)
}

/// Head above feet: the quick look stands the plant with its leaves above its pot and its
/// cameras above it, whichever way up its file is, when its cameras.json lies next to it
/// (said in a note) or `--up` names the axis; without either the flipped plant stands on
/// its head, and the run warns that its up is a guess.
#[test]
fn quick_look_stands_the_plant_leaves_up_from_its_cameras() {
    let dir = tempfile::tempdir().unwrap();
    for flipped in [false, true] {
        let run = quick_look_at(dir.path(), flipped, true, None);
        let (leaves, pot) = leaves_and_pot(&run);
        let above = cameras_above(&run, flipped);
        println!("flipped {flipped}, cameras: leaves at z {leaves:.3}, pot at {pot:.3}; cameras {above:.3} above the centre");
        assert!(
            leaves > pot + 0.1,
            "upside down: leaves {leaves}, pot {pot}"
        );
        assert!(above > 0.2, "the cameras should look down on it: {above}");
        let scene = run.scene();
        assert!(scene.up_warnings.is_empty(), "{:?}", scene.up_warnings);
        assert_eq!(scene.up_notes.len(), 1, "{:?}", scene.up_notes);
        assert!(
            scene.up_notes[0].contains("found next to the capture"),
            "{}",
            scene.up_notes[0]
        );
    }
    let guessed = quick_look_at(dir.path(), true, false, None);
    let (leaves, pot) = leaves_and_pot(&guessed);
    println!("flipped, no cameras: leaves at z {leaves:.3}, pot at {pot:.3}");
    assert!(
        leaves < pot,
        "the convention's guess is wrong for a +y-up file"
    );
    let warnings = &guessed.scene().up_warnings;
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(warnings[0].contains("is a guess"), "{}", warnings[0]);

    let given = quick_look_at(dir.path(), true, false, Some("+y"));
    let (leaves, pot) = leaves_and_pot(&given);
    println!("flipped, --up +y: leaves at z {leaves:.3}, pot at {pot:.3}");
    assert!(leaves > pot + 0.1, "--up +y: leaves {leaves}, pot {pot}");
    assert!(given.scene().up_warnings.is_empty());
}

/// A GLB stands on glTF's +y without cameras and without a guess: the plant written as a
/// GLB (its −y up turned into glTF's +y, as splat-transform turns a PLY) stands leaves up
/// in the quick look, and the note says the up came from the glTF frame.
#[test]
fn quick_look_stands_a_glb_on_gltf_s_up() {
    use splatter::splat::formats::{write_splats, SourceFrame, WriteFormat};
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("plant.glb");
    write_splats(&file, &plant(false), WriteFormat::Glb(SourceFrame::Capture)).unwrap();
    let run = Run::prepare(RunOptions {
        input: Input::Ply {
            file,
            cameras: None,
            dataparser: None,
            camera: None,
            up: None,
        },
        out: Some(dir.path().join("out")),
        width: Some(320),
        height: Some(180),
        ..RunOptions::default()
    })
    .unwrap();
    let (leaves, pot) = leaves_and_pot(&run);
    println!("plant.glb: leaves at z {leaves:.3}, pot at {pot:.3}");
    assert!(
        leaves > pot + 0.1,
        "upside down: leaves {leaves}, pot {pot}"
    );
    let scene = run.scene();
    assert!(scene.up_warnings.is_empty(), "{:?}", scene.up_warnings);
    assert_eq!(scene.up_notes.len(), 1, "{:?}", scene.up_notes);
    assert!(
        scene.up_notes[0].contains("glTF frame"),
        "{}",
        scene.up_notes[0]
    );
}

/// A scene names the capture's cameras (`{"auto": {"cameras": FILE}}`, any file name): the
/// flipped plant is turned by its +y, and the note names the file.
#[test]
fn a_scene_takes_up_from_the_cameras_it_names() {
    let dir = tempfile::tempdir().unwrap();
    write_ply(
        &dir.path().join("plant.ply"),
        &plant(true),
        PlyFormat::BinaryLittleEndian,
    )
    .unwrap();
    std::fs::write(dir.path().join("views.json"), plant_cameras_json(true)).unwrap();
    let text = r#"{"output": {"width": 32, "height": 24, "frames": 1},
        "camera": {"fov_y_deg": 40, "path": {"type": "orbit", "target": [0, 0, 0], "radius": 3}},
        "objects": [{"ply": "plant.ply", "transform": {"up": {"auto": {"cameras": "views.json"}}}}]}"#;
    let scene = splatter::scene::parse(text, "scene.json", dir.path()).unwrap();
    let turned = scene.objects[0].transform.rotation() * Vec3::Y;
    println!("{:?}; +y turned to {turned:?}", scene.up_notes);
    assert!(turned.distance(Vec3::Z) < 1e-5, "{turned:?}");
    assert!(scene.up_warnings.is_empty(), "{:?}", scene.up_warnings);
    assert!(
        scene.up_notes.len() == 1 && scene.up_notes[0].contains("views.json"),
        "{:?}",
        scene.up_notes
    );
}

/// The flipped (+y-up) plant written to `dir/plant.ply`, its cameras to `dir/views.json`.
fn flipped_plant_in(dir: &Path) {
    write_ply(
        &dir.join("plant.ply"),
        &plant(true),
        PlyFormat::BinaryLittleEndian,
    )
    .unwrap();
    std::fs::write(dir.join("views.json"), plant_cameras_json(true)).unwrap();
}

/// stderr lines that say up is a guess.
fn guess_lines(out: &std::process::Output) -> Vec<String> {
    stderr_lines(out)
        .into_iter()
        .filter(|l| l.contains("is a guess"))
        .collect()
}

/// `splatter inspect` on the +y-up plant: without cameras it prints the convention's −y as
/// a guess and one warning line naming the ways to decide; with `--cameras`, or a
/// cameras.json next to the capture (said in the report), up is +y and nothing is warned.
#[test]
fn inspect_takes_up_from_the_cameras_and_warns_on_a_guess() {
    let dir = workdir();
    flipped_plant_in(dir.path());
    let out = splatter_ok(dir.path(), &["inspect", "plant.ply"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("up:            \"-y\", from the camera convention's -y, a guess"),
        "{}",
        describe(&out)
    );
    let lines = stderr_lines(&out);
    assert_eq!(lines.len(), 1, "{}", describe(&out));
    println!("{}", lines[0]);
    assert_mentions(
        &lines[0],
        &[
            "plant.ply",
            "is a guess",
            "--up AXIS",
            "\"up\": \"+y\"",
            "--cameras",
        ],
    );

    let out = splatter_ok(
        dir.path(),
        &["inspect", "plant.ply", "--cameras", "views.json"],
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    println!("{stdout}");
    assert!(
        stdout.contains("cameras:       views.json (24 cameras)\n"),
        "{stdout}"
    );
    assert!(
        stdout.contains("up:            \"+y\", from the mean up of 24 cameras"),
        "{stdout}"
    );
    assert!(stderr_lines(&out).is_empty(), "{}", describe(&out));

    std::fs::copy(
        dir.path().join("views.json"),
        dir.path().join("cameras.json"),
    )
    .unwrap();
    let out = splatter_ok(dir.path(), &["inspect", "plant.ply"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("(24 cameras, found next to the capture)"),
        "{stdout}"
    );
    assert!(stdout.contains("up:            \"+y\""), "{stdout}");
    assert!(stderr_lines(&out).is_empty(), "{}", describe(&out));
}

/// `render --ply` on the +y-up plant warns that its up is a guess; `--up +y` decides it and
/// the warning goes; a cameras.json next to the capture decides it too, said in a note.
#[test]
fn render_ply_up_overrides_the_guess() {
    let dir = workdir();
    flipped_plant_in(dir.path());
    let args = |out: &'static str| {
        vec![
            "render",
            "--ply",
            "plant.ply",
            "--out",
            out,
            "--frames",
            "0..1",
            "--width",
            "64",
            "--height",
            "48",
        ]
    };
    let out = splatter_ok(dir.path(), &args("a"));
    assert_eq!(guess_lines(&out).len(), 1, "{}", describe(&out));

    let out = splatter_ok(dir.path(), &[args("b"), vec!["--up", "+y"]].concat());
    assert!(guess_lines(&out).is_empty(), "{}", describe(&out));

    std::fs::copy(
        dir.path().join("views.json"),
        dir.path().join("cameras.json"),
    )
    .unwrap();
    let out = splatter_ok(dir.path(), &args("c"));
    assert!(guess_lines(&out).is_empty(), "{}", describe(&out));
    let note = stderr_lines(&out)
        .into_iter()
        .find(|l| l.contains("found next to the capture"))
        .unwrap_or_else(|| panic!("no note on the cameras:\n{}", describe(&out)));
    assert_mentions(&note, &["up \"+y\"", "24 cameras", "cameras.json"]);
}

/// `inspect --preview` marks a guess in the image: the plant (−y up) with and without its
/// cameras is stood up the same way, and the two previews differ only in the band of the
/// label that says up is a guess.
#[test]
fn inspect_preview_marks_a_guess() {
    let dir = workdir();
    std::fs::copy(data(PLANT), dir.path().join("plant.spz")).unwrap();
    std::fs::copy(data(PLANT_CAMERAS), dir.path().join("views.json")).unwrap();
    splatter_ok(
        dir.path(),
        &["inspect", "plant.spz", "--preview", "guess.png"],
    );
    splatter_ok(
        dir.path(),
        &[
            "inspect",
            "plant.spz",
            "--cameras",
            "views.json",
            "--preview",
            "decided.png",
        ],
    );
    let read = |name: &str| image::open(dir.path().join(name)).unwrap().to_rgb8();
    let (guess, decided) = (read("guess.png"), read("decided.png"));
    let rows: Vec<u32> = guess
        .enumerate_pixels()
        .filter(|(x, y, p)| decided.get_pixel(*x, *y) != *p)
        .map(|(_, y, _)| y)
        .collect();
    let (top, bottom) = (rows.iter().min(), rows.iter().max());
    println!("{} pixels differ, rows {top:?}..={bottom:?}", rows.len());
    assert!(rows.len() > 200, "no mark of the guess");
    assert!(
        rows.iter().all(|y| (30..70).contains(y)),
        "rows {top:?}..={bottom:?}"
    );
}
