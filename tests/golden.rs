//! Golden images: small scenes rendered and compared with PNGs under `tests/golden/`, one
//! test per case. A regression guard, not a proof (the proofs are the CPU-reference and
//! analytic tests in `tests/render_gpu.rs`); every case here is also checked against the
//! CPU reference. One case is simulated (`sim_jelly.json`, `--deterministic`), so that the
//! golden frames guard the simulation too.
//!
//! Tolerance: PSNR ≥ 40 dB against the golden image and at most 0.5% of pixels with a
//! channel off by more than 16/255 — loose enough for another GPU's rounding, tight enough
//! to catch a changed convention (a flipped axis, a shifted pixel centre, other SH signs).
//!
//! Regenerate after an intended change, and look at the images before committing them:
//!     SPLATTER_BLESS=1 cargo test --release --test golden

use std::path::{Path, PathBuf};

use glam::{Quat, Vec3};
use splatter::gpu::GpuContext;
use splatter::render::{cpu, GpuRenderer};
use splatter::rng::SplitMix64;
use splatter::run::{Input, Run, RunOptions};
use splatter::scene;
use splatter::splat::{ply, GaussianCloud};

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden")
}

fn blessing() -> bool {
    std::env::var_os("SPLATTER_BLESS").is_some()
}

/// A deterministic SH-degree-3 blob: 600 anisotropic Gaussians whose view-dependent colour
/// is strong, so a wrong SH convention shows. Written on bless if missing (once, however
/// many tests ask).
fn ensure_sh3_ply() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(write_sh3_ply_if_missing);
}

fn write_sh3_ply_if_missing() {
    let path = golden_dir().join("sh3_blob.ply");
    if path.exists() {
        return;
    }
    assert!(
        blessing(),
        "{} is missing: run with SPLATTER_BLESS=1 to create it",
        path.display()
    );
    let mut rng = SplitMix64::new(12345);
    let mut next = move || rng.uniform() as f32;
    let n = 600;
    let mut cloud = GaussianCloud {
        sh_degree: 3,
        ..Default::default()
    };
    while cloud.len() < n {
        let p = Vec3::new(next() * 2.0 - 1.0, next() * 2.0 - 1.0, next() * 2.0 - 1.0) * 0.6;
        if p.length() > 0.6 {
            continue;
        }
        cloud.positions.push(p);
        cloud.scales.push(Vec3::new(
            0.02 + 0.06 * next(),
            0.02 + 0.06 * next(),
            0.01 + 0.02 * next(),
        ));
        let q = Quat::from_xyzw(next() - 0.5, next() - 0.5, next() - 0.5, next() - 0.5).normalize();
        cloud.rotations.push(q);
        cloud.opacities.push(0.5 + 0.5 * next());
        for k in 0..16 {
            for _ in 0..3 {
                let amp = if k == 0 { 1.2 } else { 0.5 };
                cloud.sh.push((next() * 2.0 - 1.0) * amp);
            }
        }
    }
    ply::write_ply(&path, &cloud, ply::PlyFormat::BinaryLittleEndian).unwrap();
}

/// Render frame `frame` of `tests/golden/<name>.json` and compare with `<name>_<frame>.png`.
fn check(name: &str, frame: u32) {
    let gpu = GpuContext::new(None).expect("a wgpu adapter (install mesa-vulkan-drivers)");
    let scene = scene::load(&golden_dir().join(format!("{name}.json"))).unwrap();
    let (splats, _) = scene.build_splats().unwrap();
    let camera = scene.camera_path().unwrap().camera(frame);
    let background = Vec3::from(scene.output.background);
    let mut renderer = GpuRenderer::new(&gpu);
    renderer.upload(&gpu, &splats).unwrap();
    let image = renderer.render(&gpu, &camera, background).unwrap();
    let reference = cpu::render(&splats, &camera, background);
    if let Err(e) = compare(
        name,
        frame,
        image.width,
        image.height,
        &image.rgba,
        &reference,
    ) {
        panic!("{e}");
    }
}

/// The GPU image of frame `frame` of case `name` against the CPU reference's (PSNR ≥ 40 dB)
/// and against `<name>_<frame>.png` (the tolerance at the top), or blessed as that file.
/// A mismatch writes the image to `out/golden-failures/`.
fn compare(
    name: &str,
    frame: u32,
    width: u32,
    height: u32,
    rgba: &[u8],
    reference: &[u8],
) -> Result<(), String> {
    let psnr_cpu = cpu::psnr(rgba, reference);
    if psnr_cpu < 40.0 {
        return Err(format!(
            "{name} frame {frame}: GPU vs CPU reference PSNR {psnr_cpu:.1} dB"
        ));
    }
    let file = golden_dir().join(format!("{name}_{frame}.png"));
    if blessing() {
        splatter::output::write_png(&file, width, height, rgba).unwrap();
        eprintln!("blessed {}", file.display());
        return Ok(());
    }
    let golden = image::open(&file)
        .map_err(|e| format!("{}: {e} (SPLATTER_BLESS=1 creates it)", file.display()))?
        .to_rgba8();
    if golden.dimensions() != (width, height) {
        return Err(format!(
            "{name} frame {frame}: size {width}×{height}, golden {:?}",
            golden.dimensions()
        ));
    }
    let golden = golden.into_raw();
    let psnr = cpu::psnr(rgba, &golden);
    let frac = pixels_off(rgba, &golden) as f64 / f64::from(width * height);
    eprintln!("{name} frame {frame}: PSNR {psnr:.1} dB vs golden, {:.3}% pixels off, {psnr_cpu:.1} dB vs CPU", frac * 100.0);
    if psnr < 40.0 || frac > 0.005 {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("out/golden-failures");
        std::fs::create_dir_all(&dir).unwrap();
        let got = dir.join(format!("{name}_{frame}.png"));
        splatter::output::write_png(&got, width, height, rgba).unwrap();
        return Err(format!(
            "{name} frame {frame}: PSNR {psnr:.1} dB, {:.2}% pixels off; rendered image in {}",
            frac * 100.0,
            got.display()
        ));
    }
    Ok(())
}

/// Pixels of two RGBA8 images with an RGB channel more than 16/255 apart.
fn pixels_off(a: &[u8], b: &[u8]) -> usize {
    a.chunks_exact(4)
        .zip(b.chunks_exact(4))
        .filter(|(a, b)| (0..3).any(|c| a[c].abs_diff(b[c]) > 16))
        .count()
}

/// Procedural sphere, box, cylinder and checkered ground, frame 3 of an orbit.
#[test]
fn procedural_frame_3() {
    check("procedural", 3);
}

/// The SH degree-3 PLY, rotated and non-uniformly scaled, seen from a keyframed camera.
#[test]
fn sh3_ply_frame_1() {
    ensure_sh3_ply();
    check("sh3_ply", 1);
}

#[test]
fn sh3_ply_frame_2() {
    ensure_sh3_ply();
    check("sh3_ply", 2);
}

/// Cameras 0 and 1 of an INRIA `cameras.json`.
#[test]
fn inria_cameras_frame_0() {
    check("inria_cameras", 0);
}

#[test]
fn inria_cameras_frame_1() {
    check("inria_cameras", 1);
}

/// The simulation: frames 0..4 of `sim_jelly.json` (an elastic cube thrown down with a
/// spin, bouncing on the ground; a still camera), run as `splatter render --deterministic`
/// does, each frame compared with its golden PNG and with the CPU reference's render of the
/// Gaussians the run drew (`--export-ply`). Frame 3 must differ from frame 0 over a good
/// part of the cube's area, so that the golden frames guard the simulation, not only the
/// renderer. All frames are compared before a failure is reported.
#[test]
fn simulated_jelly_frames_0_to_3() {
    let gpu = GpuContext::new(None).expect("a wgpu adapter (install mesa-vulkan-drivers)");
    let file = golden_dir().join("sim_jelly.json");
    let dir = tempfile::tempdir().unwrap();
    let (out, states) = (dir.path().join("frames"), dir.path().join("states"));
    let run = Run::prepare(RunOptions {
        input: Input::Scene(Some(file)),
        out: Some(out.clone()),
        frames: Some("0..4".into()),
        deterministic: true,
        checkpoint_every: 0,
        export_ply: Some(states.clone()),
        ..RunOptions::default()
    })
    .unwrap();
    let scene = run.scene().clone();
    let path = scene.camera_path().unwrap();
    run.execute(&gpu, &mut |_| {}).unwrap();
    let background = Vec3::from(scene.output.background);
    let mut frames = Vec::new();
    let mut failures = Vec::new();
    for frame in 0..4 {
        let image = image::open(splatter::output::frame_path(&out, frame))
            .unwrap()
            .to_rgba8();
        let (state, _) = splatter::farm::load_state(&states, frame).unwrap();
        let reference = cpu::render(&state, &path.camera(frame), background);
        let (w, h) = image.dimensions();
        if let Err(e) = compare("sim_jelly", frame, w, h, image.as_raw(), &reference) {
            failures.push(e);
        }
        frames.push(image.into_raw());
    }
    let moved = pixels_off(&frames[0], &frames[3]) as f64 / (frames[0].len() / 4) as f64;
    eprintln!(
        "sim_jelly: {:.1}% of the pixels differ by more than 16/255 between frames 0 and 3",
        100.0 * moved
    );
    if moved < 0.03 {
        failures.push(format!(
            "sim_jelly: frame 3 differs from frame 0 in only {:.2}% of the pixels: the cube did not move",
            100.0 * moved
        ));
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
