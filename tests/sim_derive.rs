//! Deforming the Gaussians on the GPU (docs/method.md §6): the derive pass against its f64 twin, and a
//! jelly cube simulated, derived and rendered without a CPU round trip, checked against the
//! CPU reference renderer fed with the CPU-derived Gaussians.

use glam::{DMat3, DQuat, DVec3, Mat3, Quat, Vec3};
use splatter::derive::{derive_gaussian, derive_normal, rest_covariance, Binding, Derive};
use splatter::gpu::buffers::copy_out;
use splatter::gpu::GpuContext;
use splatter::relight::{oct_decode, oct_encode, ShadingParams};
use splatter::render::gpu::layout::GaussianIn;
use splatter::render::gpu::lighting::LightingSetup;
use splatter::render::splats::{mat3_from_sym3, sym3_from_mat3};
use splatter::render::{cpu, Camera, GpuRenderer, Splats};
use splatter::rng::SplitMix64;
use splatter::sim::gpu::GpuSim;
use splatter::sim::{
    Boundaries, Condition, DomainWalls, Grid, Material, Particles, StepParams, Transfer,
};
use splatter::splat::procedural::ProceduralSpec;

fn read_gaussians(gpu: &GpuContext, renderer: &GpuRenderer, n: usize) -> Vec<GaussianIn> {
    let buffer = renderer.gaussian_buffer().unwrap();
    let bytes = copy_out(gpu, buffer).unwrap();
    bytemuck::pod_collect_to_vec(&bytes[..n * std::mem::size_of::<GaussianIn>()])
}

/// Particles at the Gaussians `offset..` of `splats`, density ρ, rest volume `volume` each.
fn particles_for(splats: &Splats, offset: usize, density: f64, volume: f64) -> Particles {
    let mut p = Particles::new();
    for m in &splats.means[offset..] {
        p.push(m.as_dvec3(), DVec3::ZERO, density * volume, volume, 0, 0.0);
    }
    p
}

/// Give every particle a random deformation (rotation times I + `amount`·random, det > 0),
/// upload them to a simulation and `splats` to a renderer, and run the derive pass for the
/// Gaussians from `offset` on: the shared setup of the derive tests.
fn deform_and_derive(
    gpu: &GpuContext,
    splats: &Splats,
    particles: &mut Particles,
    offset: usize,
    amount: f64,
    r: &mut impl FnMut() -> f32,
) -> GpuRenderer {
    deform_and_derive_lit(gpu, splats, particles, offset, amount, r, None)
}

/// As [`deform_and_derive`], with relighting set up first (`shading`: packed rest normal and
/// material per Gaussian) so that the derive pass also transports normals.
fn deform_and_derive_lit(
    gpu: &GpuContext,
    splats: &Splats,
    particles: &mut Particles,
    offset: usize,
    amount: f64,
    r: &mut impl FnMut() -> f32,
    shading: Option<Vec<[u32; 2]>>,
) -> GpuRenderer {
    for f in &mut particles.f {
        *f =
            DMat3::from_quat(DQuat::from_xyzw(r().into(), r().into(), r().into(), 1.0).normalize())
                * (DMat3::IDENTITY
                    + DMat3::from_cols_array(&[0.0; 9].map(|_| amount * f64::from(r()))));
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
    let sim = GpuSim::new(
        gpu,
        particles,
        &grid,
        &[Material::fixed_corotated(1e3, 0.3)],
        &params,
    )
    .unwrap();
    let mut renderer = GpuRenderer::new(gpu);
    renderer.upload(gpu, splats).unwrap();
    if let Some(shading) = shading {
        renderer
            .set_lighting(
                gpu,
                &LightingSetup {
                    ambient: Vec3::ONE,
                    materials: vec![ShadingParams::default()],
                    shading,
                    shadows: None,
                    max_lights: 1,
                },
            )
            .unwrap();
    }
    Derive::new(
        gpu,
        &sim,
        &renderer,
        splats,
        offset as u32,
        &Binding::identity(0, particles.len()),
    )
    .unwrap()
    .run(gpu)
    .unwrap();
    renderer
}

#[test]
fn derive_matches_its_f64_twin() {
    for gpu in splatter::gpu::test_contexts() {
        let mut rng = SplitMix64::new(5);
        let mut r = move || rng.range(-1.0, 1.0);
        let n = 500;
        let offset = 100;
        let mut splats = Splats {
            sh_degree: 0,
            ..Default::default()
        };
        for _ in 0..n {
            splats
                .means
                .push(Vec3::new(r(), r(), r()) * 0.3 + Vec3::splat(0.5));
            let q = Quat::from_xyzw(r(), r(), r(), r()).normalize();
            let m = Mat3::from_quat(q)
                * Mat3::from_diagonal(Vec3::new(0.01, 0.02, 0.005) * (1.5 + r()));
            splats.covariances.push(sym3_from_mat3(m * m.transpose()));
            splats
                .rotations
                .push(Quat::from_xyzw(r(), r(), r(), r()).normalize());
            splats.opacities.push(0.5 + 0.4 * r());
            splats.sh.extend([r(), r(), r()]);
        }
        let mut particles = particles_for(&splats, offset, 1000.0, 1e-6);
        let renderer = deform_and_derive(&gpu, &splats, &mut particles, offset, 0.3, &mut r);
        let out = read_gaussians(&gpu, &renderer, n);
        let (mut cov_err, mut rot_err) = (0.0f64, 0.0f64);
        for (p, g) in out.iter().enumerate().skip(offset) {
            let i = p - offset;
            let r0 = splats.rotations[p].as_dquat();
            let (x, cov, rot) = derive_gaussian(
                particles.x[i],
                particles.f[i],
                rest_covariance(&splats, p),
                r0,
            );
            assert!(
                (DVec3::new(
                    g.mean_opacity[0].into(),
                    g.mean_opacity[1].into(),
                    g.mean_opacity[2].into()
                ) - x)
                    .length()
                    < 1e-6
            );
            assert_eq!(g.mean_opacity[3], splats.opacities[p]);
            let got = mat3_from_sym3([
                g.cov_a[0], g.cov_a[1], g.cov_a[2], g.cov_a[3], g.cov_b[0], g.cov_b[1],
            ])
            .as_dmat3();
            let scale = cov
                .to_cols_array()
                .iter()
                .fold(0.0f64, |m, v| m.max(v.abs()));
            cov_err = cov_err.max(
                (got - cov)
                    .to_cols_array()
                    .iter()
                    .fold(0.0f64, |m, v| m.max(v.abs()))
                    / scale,
            );
            let q = DQuat::from_xyzw(
                g.rotation[0].into(),
                g.rotation[1].into(),
                g.rotation[2].into(),
                g.rotation[3].into(),
            );
            rot_err = rot_err.max(1.0 - q.dot(rot).abs());
        }
        // Static Gaussians are untouched.
        for (p, g) in out.iter().enumerate().take(offset) {
            assert_eq!(g.mean_opacity[0], splats.means[p].x);
        }
        eprintln!(
            "{}: derive: covariance rel. error {cov_err:.1e}, rotation 1 − |q·q'| {rot_err:.1e}",
            gpu.describe()
        );
        assert!(cov_err < 1e-5, "covariance error {cov_err}");
        assert!(rot_err < 1e-6, "rotation error {rot_err}");
    }
}

/// A jelly cube of Gaussians dropped on a sticky ground: stepped, derived and rendered on
/// the GPU with no readback in between; the image equals the CPU reference renderer's
/// image of the CPU-derived Gaussians (read back once at the end), and the cube has moved
/// down the screen.
#[test]
fn jelly_cube_is_simulated_derived_and_rendered_on_the_gpu() {
    let gpu = GpuContext::new(None).unwrap();
    let spec: ProceduralSpec = serde_json::from_str(
        r#"{"shape": "box", "size": [0.2, 0.2, 0.2], "spacing": 0.02, "color": [0.9, 0.3, 0.2], "seed": 3}"#,
    )
    .unwrap();
    let cloud = spec.generate().unwrap();
    let splats = Splats::from_cloud(&cloud, Mat3::IDENTITY, Vec3::new(0.5, 0.5, 0.5));
    let density = 1000.0;
    let mut particles = particles_for(&splats, 0, density, 0.02f64.powi(3));
    let material = Material::fixed_corotated(3e4, 0.3);
    particles.set_material(0, &material);
    particles
        .v
        .iter_mut()
        .for_each(|v| *v = DVec3::new(0.0, 0.0, -1.0));
    let grid = Grid::new(DVec3::ZERO, DVec3::ONE, 1.0 / 32.0);
    let params = StepParams {
        dt: 2e-4,
        gravity: DVec3::new(0.0, 0.0, -9.8),
        boundaries: Boundaries {
            walls: DomainWalls::uniform(Condition::SEPARATE),
            colliders: vec![],
            surface: None,
        },
        transfer: Transfer::Apic,
        separation: Default::default(),
        fields: Default::default(),
        actions: Default::default(),
    };
    let sim = GpuSim::new(&gpu, &particles, &grid, &[material], &params).unwrap();
    let mut renderer = GpuRenderer::new(&gpu);
    renderer.upload(&gpu, &splats).unwrap();
    let derive = Derive::new(
        &gpu,
        &sim,
        &renderer,
        &splats,
        0,
        &Binding::identity(0, particles.len()),
    )
    .unwrap();
    let cam = Camera::look_at(
        Vec3::new(0.5, -1.2, 0.4),
        Vec3::new(0.5, 0.5, 0.3),
        Vec3::Z,
        40f32.to_radians(),
        96,
        96,
    );
    let before = renderer.render(&gpu, &cam, Vec3::ZERO).unwrap();
    sim.step(&gpu, 1500).unwrap();
    derive.run(&gpu).unwrap();
    let after = renderer.render(&gpu, &cam, Vec3::ZERO).unwrap();

    // The reference: read the particles back once, derive on the CPU, render on the CPU.
    let state = sim.read_particles(&gpu, &particles).unwrap();
    let mut reference = splats.clone();
    for p in 0..state.len() {
        let (x, cov, rot) = derive_gaussian(
            state.x[p],
            state.f[p],
            rest_covariance(&splats, p),
            splats.rotations[p].as_dquat(),
        );
        reference.means[p] = x.as_vec3();
        reference.covariances[p] = sym3_from_mat3(cov.as_mat3());
        reference.rotations[p] = rot.as_quat();
    }
    for v in &mut reference.sh {
        *v = half::f16::from_f32(*v).to_f32();
    }
    let psnr = cpu::psnr(&after.rgba, &cpu::render(&reference, &cam, Vec3::ZERO));
    let centroid_y = |rgba: &[u8]| {
        let (mut sum, mut count) = (0.0, 0.0);
        for (i, px) in rgba.chunks(4).enumerate() {
            let lum = f64::from(px[0]);
            sum += lum * (i / 96) as f64;
            count += lum;
        }
        sum / count
    };
    let (y0, y1) = (centroid_y(&before.rgba), centroid_y(&after.rgba));
    let drop = state.x.iter().map(|x| x.z).sum::<f64>() / state.len() as f64 - 0.5;
    eprintln!(
        "{} particles, 1500 steps: centre of mass moved {drop:.3} in z; image centroid row {y0:.1} → {y1:.1}; GPU frame vs CPU reference of the derived state: {psnr:.1} dB",
        state.len()
    );
    assert!(drop < -0.2, "the cube should have fallen: {drop}");
    assert!(
        y1 > y0 + 5.0,
        "the cube should move down the image: {y0} → {y1}"
    );
    assert!(psnr >= 40.0, "PSNR {psnr}");
}

/// `--export-ply`: the exported cloud (covariances folded into scale and rotation, SH rotated
/// into the world frame) renders like the deformed state it came from, in a renderer that
/// knows nothing of rest frames. SH degree 3, random rest frames and random deformations.
#[test]
fn exported_ply_renders_like_the_deformed_state() {
    use splatter::output::export::{frame_ply_path, world_cloud};
    use splatter::splat::ply::{read_ply, write_ply, PlyFormat};
    use splatter::splat::sh::ShRotator;

    let gpu = GpuContext::new(None).unwrap();
    let mut rng = SplitMix64::new(17);
    let mut r = move || rng.range(-1.0, 1.0);
    let n = 400;
    let mut splats = Splats {
        sh_degree: 3,
        ..Default::default()
    };
    for _ in 0..n {
        splats
            .means
            .push(Vec3::new(r(), r(), r()) * 0.25 + Vec3::splat(0.5));
        let q = Quat::from_xyzw(r(), r(), r(), r()).normalize();
        let m = Mat3::from_quat(q) * Mat3::from_diagonal(Vec3::new(0.03, 0.02, 0.01) * (1.5 + r()));
        splats.covariances.push(sym3_from_mat3(m * m.transpose()));
        splats
            .rotations
            .push(Quat::from_xyzw(r(), r(), r(), r()).normalize());
        splats.opacities.push(0.6 + 0.3 * r());
        for k in 0..48 {
            splats.sh.push(if k < 3 { r() } else { 0.4 * r() });
        }
    }
    let mut particles = particles_for(&splats, 0, 1000.0, 1e-6);
    let mut renderer = deform_and_derive(&gpu, &splats, &mut particles, 0, 0.25, &mut r);
    let cam = Camera::look_at(
        Vec3::new(1.6, -0.9, 1.1),
        Vec3::splat(0.5),
        Vec3::Z,
        40f32.to_radians(),
        128,
        96,
    );
    let deformed = renderer.render(&gpu, &cam, Vec3::ZERO).unwrap();

    let dir = tempfile::tempdir().unwrap();
    let path = frame_ply_path(dir.path(), 0);
    let cloud = world_cloud(
        &renderer.read_gaussians(&gpu).unwrap(),
        &splats,
        &ShRotator::new(),
    );
    write_ply(&path, &cloud, PlyFormat::BinaryLittleEndian).unwrap();
    let (back, _) = read_ply(&path).unwrap();
    let mut plain = GpuRenderer::new(&gpu);
    plain
        .upload(&gpu, &Splats::from_cloud(&back, Mat3::IDENTITY, Vec3::ZERO))
        .unwrap();
    let exported = plain.render(&gpu, &cam, Vec3::ZERO).unwrap();
    let psnr = cpu::psnr(&deformed.rgba, &exported.rgba);
    // Without the SH rotation the same check gives a visibly different image.
    let mut unrotated = back.clone();
    unrotated.sh = splats.sh.clone();
    plain
        .upload(
            &gpu,
            &Splats::from_cloud(&unrotated, Mat3::IDENTITY, Vec3::ZERO),
        )
        .unwrap();
    let wrong = cpu::psnr(
        &deformed.rgba,
        &plain.render(&gpu, &cam, Vec3::ZERO).unwrap().rgba,
    );
    eprintln!("exported PLY vs deformed state: {psnr:.1} dB (with SH left in the rest frame: {wrong:.1} dB)");
    assert!(psnr >= 40.0, "PSNR {psnr}");
    assert!(
        wrong < psnr - 5.0,
        "the SH rotation should matter: {wrong} vs {psnr}"
    );
}

/// With relighting on, the derive pass also moves each simulated Gaussian's normal as a
/// covector, n = F⁻ᵀ n₀ (normalised): checked against the f64 twin `derive_normal` for
/// random deformations; static Gaussians keep their normals.
#[test]
fn derive_transports_normals_with_the_inverse_transpose() {
    for gpu in splatter::gpu::test_contexts() {
        let mut rng = SplitMix64::new(9);
        let mut r = move || rng.range(-1.0, 1.0);
        let (n, offset) = (300, 50);
        let mut splats = Splats {
            sh_degree: 0,
            ..Default::default()
        };
        let mut shading = Vec::new();
        for _ in 0..n {
            splats
                .means
                .push(Vec3::new(r(), r(), r()) * 0.3 + Vec3::splat(0.5));
            splats.covariances.push([1e-4, 0.0, 0.0, 1e-4, 0.0, 1e-4]);
            splats.rotations.push(Quat::IDENTITY);
            splats.opacities.push(0.9);
            splats.sh.extend([0.0, 0.0, 0.0]);
            shading.push([oct_encode(Vec3::new(r(), r(), r()).normalize()), 0]);
        }
        let mut particles = particles_for(&splats, offset, 1000.0, 1e-6);
        let renderer = deform_and_derive_lit(
            &gpu,
            &splats,
            &mut particles,
            offset,
            0.3,
            &mut r,
            Some(shading.clone()),
        );
        let buffer = renderer.shading_buffer().unwrap();
        let got: Vec<[u32; 2]> = bytemuck::pod_collect_to_vec(&copy_out(&gpu, buffer).unwrap());
        let mut worst = 0.0f64;
        for p in 0..n {
            if p < offset {
                assert_eq!(got[p], shading[p], "static Gaussians keep their normals");
                continue;
            }
            let n0 = oct_decode(shading[p][0]).as_dvec3();
            let want = derive_normal(particles.f[p - offset], n0);
            let have = oct_decode(got[p][0]).as_dvec3();
            worst = worst.max(have.dot(want).clamp(-1.0, 1.0).acos().to_degrees());
        }
        eprintln!(
            "{}: transported normals within {worst:.3}° of F⁻ᵀ n₀",
            gpu.describe()
        );
        assert!(worst < 0.1, "worst {worst}°");
    }
}
