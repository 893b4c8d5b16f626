//! Golden images: small scenes rendered and compared with PNGs under `tests/golden/`.
//! A regression guard, not a proof (the proofs are the CPU-reference and analytic tests in
//! `tests/render_gpu.rs`); every case here is also checked against the CPU reference.
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
use splatter::scene;
use splatter::splat::{ply, GaussianCloud};

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden")
}

fn blessing() -> bool {
    std::env::var_os("SPLATTER_BLESS").is_some()
}

/// A deterministic SH-degree-3 blob: 600 anisotropic Gaussians whose view-dependent colour
/// is strong, so a wrong SH convention shows. Written on bless if missing.
fn ensure_sh3_ply() {
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
fn check(gpu: &GpuContext, name: &str, frame: u32) {
    let scene = scene::load(&golden_dir().join(format!("{name}.json"))).unwrap();
    let (splats, _) = scene.build_splats().unwrap();
    let camera = scene.camera_path().unwrap().camera(frame);
    let background = Vec3::from(scene.output.background);
    let mut renderer = GpuRenderer::new(gpu);
    renderer.upload(gpu, &splats).unwrap();
    let image = renderer.render(gpu, &camera, background).unwrap();

    let reference = cpu::render(&splats, &camera, background);
    let psnr_cpu = cpu::psnr(&image.rgba, &reference);
    assert!(
        psnr_cpu >= 40.0,
        "{name} frame {frame}: GPU vs CPU reference PSNR {psnr_cpu:.1} dB"
    );

    let file = golden_dir().join(format!("{name}_{frame}.png"));
    if blessing() {
        splatter::output::write_png(&file, image.width, image.height, &image.rgba).unwrap();
        eprintln!("blessed {}", file.display());
        return;
    }
    let golden = image::open(&file)
        .unwrap_or_else(|e| panic!("{}: {e} (SPLATTER_BLESS=1 creates it)", file.display()))
        .to_rgba8();
    assert_eq!(
        golden.dimensions(),
        (image.width, image.height),
        "{name}: size changed"
    );
    let golden = golden.into_raw();
    let psnr = cpu::psnr(&image.rgba, &golden);
    let off = image
        .rgba
        .chunks_exact(4)
        .zip(golden.chunks_exact(4))
        .filter(|(a, b)| (0..3).any(|c| a[c].abs_diff(b[c]) > 16))
        .count();
    let frac = off as f64 / f64::from(image.width * image.height);
    eprintln!("{name} frame {frame}: PSNR {psnr:.1} dB vs golden, {:.3}% pixels off, {psnr_cpu:.1} dB vs CPU", frac * 100.0);
    if psnr < 40.0 || frac > 0.005 {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("out/golden-failures");
        std::fs::create_dir_all(&dir).unwrap();
        let got = dir.join(format!("{name}_{frame}.png"));
        splatter::output::write_png(&got, image.width, image.height, &image.rgba).unwrap();
        panic!(
            "{name} frame {frame}: PSNR {psnr:.1} dB, {:.2}% pixels off; rendered image in {}",
            frac * 100.0,
            got.display()
        );
    }
}

#[test]
fn golden_images() {
    ensure_sh3_ply();
    let gpu = GpuContext::new(None).expect("a wgpu adapter (install mesa-vulkan-drivers)");
    check(&gpu, "procedural", 3);
    check(&gpu, "sh3_ply", 1);
    check(&gpu, "sh3_ply", 2);
    check(&gpu, "inria_cameras", 0);
    check(&gpu, "inria_cameras", 1);
}
