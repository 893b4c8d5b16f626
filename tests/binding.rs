//! Gaussians bound to particles (docs/method.md §6.1): bound Gaussians follow a prescribed
//! rigid motion and a uniform stretch exactly (to f32 round-off) on the GPU, and with one
//! Gaussian on each particle the bound run renders the frames of the Gaussians-as-particles
//! run.

mod common;

use std::path::Path;

use glam::{DMat3, DQuat, DVec3, Mat3, Quat, Vec3};
use splatter::derive::{Binding, Derive};
use splatter::gpu::GpuContext;
use splatter::render::splats::{mat3_from_sym3, sym3_from_mat3};
use splatter::render::{GpuRenderer, Splats};
use splatter::rng::SplitMix64;
use splatter::sim::gpu::GpuSim;
use splatter::sim::{Boundaries, Grid, Material, Particles, StepParams, Transfer};

/// Particles on a lattice of spacing `h` over [0.3, 0.7]³ and 2000 anisotropic Gaussians
/// scattered over the same box, each bound to its nearest particle.
fn bound_cloud(h: f64) -> (Particles, Splats, Binding) {
    let mut particles = Particles::new();
    let n = (0.4 / h).round() as usize;
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                let x = DVec3::splat(0.3) + (DVec3::new(i as f64, j as f64, k as f64) + 0.5) * h;
                particles.push(x, DVec3::ZERO, 1e-3, 1e-6, 0, 0.0);
            }
        }
    }
    let mut rng = SplitMix64::new(11);
    let mut r = move || rng.range(-1.0, 1.0);
    let mut splats = Splats {
        sh_degree: 0,
        ..Default::default()
    };
    for _ in 0..2000 {
        splats
            .means
            .push(Vec3::splat(0.5) + 0.2 * Vec3::new(r(), r(), r()));
        let q = Quat::from_xyzw(r(), r(), r(), r()).normalize();
        let m = Mat3::from_quat(q) * Mat3::from_diagonal(Vec3::new(0.004, 0.002, 0.0005));
        splats.covariances.push(sym3_from_mat3(m * m.transpose()));
        splats
            .rotations
            .push(Quat::from_xyzw(r(), r(), r(), r()).normalize());
        splats.opacities.push(0.8);
        splats.sh.extend([r(), r(), r()]);
    }
    let binding = Binding::nearest(&splats.means, &particles.x, 0, h);
    (particles, splats, binding)
}

/// The derive pass of `binding` after every particle moved by x ↦ `f` (x − c) + c + `b`
/// (its deformation gradient set to `f`); the largest error of the bound Gaussians' means
/// against the same map applied to their rest means (relative to the box's size), of their
/// covariances against F A Fᵀ (relative to its largest entry), and of their rotations
/// (1 − |q·q'| against polar(F) ∘ R⁰).
fn follow(gpu: &GpuContext, f: DMat3, b: DVec3) -> (f64, f64, f64) {
    let (mut particles, splats, binding) = bound_cloud(0.05);
    let c = DVec3::splat(0.5);
    let map = |x: DVec3| f * (x - c) + c + b;
    for p in 0..particles.len() {
        particles.x[p] = map(particles.x[p]);
        particles.f[p] = f;
    }
    let grid = Grid::new(DVec3::ZERO, DVec3::ONE, 1.0 / 16.0);
    let params = StepParams {
        dt: 1e-4,
        gravity: DVec3::ZERO,
        boundaries: Boundaries::default(),
        transfer: Transfer::Apic,
        separation: Default::default(),
        fields: Default::default(),
        actions: Default::default(),
    };
    let material = [Material::fixed_corotated(1e3, 0.3)];
    let sim = GpuSim::new(gpu, &particles, &grid, &material, &params).unwrap();
    let mut renderer = GpuRenderer::new(gpu);
    renderer.upload(gpu, &splats).unwrap();
    Derive::new(gpu, &sim, &renderer, &splats, 0, &binding)
        .unwrap()
        .run(gpu)
        .unwrap();
    let out = renderer.read_gaussians(gpu).unwrap();
    let (r, _) = splatter::sim::svd::polar(f);
    let (mut mean_err, mut cov_err, mut rot_err) = (0.0f64, 0.0f64, 0.0f64);
    for (g, got) in out.iter().enumerate() {
        let x = DVec3::from_array(got.mean_opacity.map(f64::from)[..3].try_into().unwrap());
        mean_err = mean_err.max((x - map(splats.means[g].as_dvec3())).length() / 0.4);
        let a = mat3_from_sym3(splats.covariances[g]).as_dmat3();
        let want = f * a * f.transpose();
        let have = mat3_from_sym3([
            got.cov_a[0],
            got.cov_a[1],
            got.cov_a[2],
            got.cov_a[3],
            got.cov_b[0],
            got.cov_b[1],
        ])
        .as_dmat3();
        let largest = want
            .to_cols_array()
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let diff = (have - want).to_cols_array();
        cov_err = cov_err.max(diff.iter().fold(0.0f64, |m, v| m.max(v.abs())) / largest);
        let q = DQuat::from_array(got.rotation.map(f64::from));
        let want = (DQuat::from_mat3(&r) * splats.rotations[g].as_dquat()).normalize();
        rot_err = rot_err.max(1.0 - q.dot(want).abs());
    }
    (mean_err, cov_err, rot_err)
}

/// A rigid motion (a rotation about the box's centre and a translation): every bound
/// Gaussian lands where the motion takes its rest mean, turned by R, to f32 round-off.
#[test]
fn bound_gaussians_follow_a_rigid_motion_exactly() {
    let r = DMat3::from_quat(DQuat::from_axis_angle(
        DVec3::new(1.0, 2.0, -0.5).normalize(),
        1.1,
    ));
    for gpu in splatter::gpu::test_contexts() {
        let (mean, cov, rot) = follow(&gpu, r, DVec3::new(0.05, -0.02, 0.08));
        eprintln!(
            "{}: rigid motion: mean {mean:.1e}, covariance {cov:.1e}, rotation {rot:.1e}",
            gpu.describe()
        );
        // f32 has 6e-8 relative round-off; a few operations each.
        assert!(mean < 1e-6, "mean error {mean}");
        assert!(cov < 2e-6, "covariance error {cov}");
        assert!(rot < 1e-6, "rotation error {rot}");
    }
}

/// A uniform stretch by 1.6 (and, as any affine map is followed as exactly, a shear):
/// means and covariances follow F to f32 round-off, and the SH frame does not turn.
#[test]
fn bound_gaussians_follow_a_uniform_stretch_exactly() {
    let shear = DMat3::from_cols(
        DVec3::new(1.2, 0.1, 0.0),
        DVec3::new(0.3, 0.9, 0.05),
        DVec3::new(-0.1, 0.2, 1.1),
    );
    for gpu in splatter::gpu::test_contexts() {
        for (name, f) in [
            ("stretch", DMat3::from_diagonal(DVec3::splat(1.6))),
            ("shear", shear),
        ] {
            let (mean, cov, rot) = follow(&gpu, f, DVec3::ZERO);
            eprintln!(
                "{}: {name}: mean {mean:.1e}, covariance {cov:.1e}, rotation {rot:.1e}",
                gpu.describe()
            );
            assert!(mean < 1e-6, "{name}: mean error {mean}");
            assert!(cov < 2e-6, "{name}: covariance error {cov}");
            assert!(rot < 1e-6, "{name}: rotation error {rot}");
        }
    }
}

/// A jelly cube dropped on a sticky ground whose Gaussians sit on the lattice the particles
/// would take (a box of unjittered Gaussians at spacing h, particles at spacing h without
/// jitter), `particles` as given.
fn cube_scene(dir: &Path, particles: &str) -> std::path::PathBuf {
    let text = format!(
        r#"{{ "output": {{ "width": 96, "height": 72, "frames": 8, "fps": 24, "dir": "{out}" }},
          "camera": {{ "fov_y_deg": 40, "path": {{ "type": "orbit", "target": [0.5, 0.5, 0.3], "radius": 1.0, "height": 0.4 }} }},
          "simulation": {{ "dx": 0.04, "domain": {{ "lo": [0, 0, 0], "hi": [1, 1, 1] }},
                           "ground": {{ "kind": "sticky" }} }},
          "objects": [ {{ "procedural": {{ "shape": "box", "size": [0.2, 0.2, 0.2], "spacing": 0.02,
                                         "jitter": 0, "color": [0.9, 0.4, 0.2] }},
                         "transform": {{ "translate": [0.5, 0.5, 0.3] }},
                         "physics": {{ "material": {{ "model": "neo_hookean", "E": 2000, "nu": 0.3, "density": 10 }},
                                       "velocity": [0, 0, -1.5], "angular_velocity": [2, 0, 0],
                                       "particles": {particles} }} }} ] }}"#,
        out = dir.join(format!("out_{}", particles.len())).display()
    );
    let path = dir.join(format!("cube_{}.json", particles.len()));
    std::fs::write(&path, text).unwrap();
    path
}

/// One Gaussian on each particle: with `--deterministic` the lattice mode renders the
/// frames of the Gaussians-as-particles mode to within one level in a handful of channels.
/// The lattice's voxel centres (f64) round to the Gaussians' f32 means, so both runs step
/// the same particles in the same order, and every Gaussian is bound to the particle at its
/// mean with a zero offset; their volumes and spin velocities are computed apart (the
/// lattice cell against the Gaussian's share) and can differ in the last bit of an f32,
/// which the impact can carry into one level of a pixel.
#[test]
fn one_gaussian_per_particle_renders_as_the_gaussians_mode() {
    let dir = tempfile::tempdir().unwrap();
    let mut frames = Vec::new();
    for particles in [r#""gaussians""#, r#"{ "spacing": 0.02, "jitter": 0 }"#] {
        let scene = cube_scene(dir.path(), particles);
        let out = dir.path().join(format!("out_{}", particles.len()));
        common::cli::splatter_ok(
            dir.path(),
            &["render", scene.to_str().unwrap(), "--deterministic"],
        );
        let manifest: serde_json::Value =
            serde_json::from_slice(&std::fs::read(out.join("manifest.json")).unwrap()).unwrap();
        assert_eq!(manifest["settings"]["particles"], 1000, "{particles}");
        assert_eq!(manifest["settings"]["gaussians"], 1000, "{particles}");
        let mut images = Vec::new();
        for f in [0, 4, 7] {
            images.push(
                image::open(out.join(format!("frame_{f:05}.png")))
                    .unwrap()
                    .to_rgb8(),
            );
        }
        frames.push(images);
    }
    for (k, (a, b)) in frames[0].iter().zip(&frames[1]).enumerate() {
        let diff = a
            .as_raw()
            .iter()
            .zip(b.as_raw())
            .map(|(x, y)| x.abs_diff(*y))
            .max()
            .unwrap();
        let changed = a
            .as_raw()
            .iter()
            .zip(b.as_raw())
            .filter(|(x, y)| x != y)
            .count();
        eprintln!(
            "frame {}: largest difference {diff} levels, {changed} channels differ",
            [0, 4, 7][k]
        );
        assert!(
            diff <= 1 && changed <= a.as_raw().len() / 1000,
            "frame {}: {diff} levels apart in {changed} channels",
            [0, 4, 7][k]
        );
    }
}
