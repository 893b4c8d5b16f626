//! The GPU renderer against its CPU reference and against analytic profiles.
//!
//! These tests need a wgpu adapter; on a machine without a GPU, Mesa's lavapipe (Vulkan)
//! or llvmpipe (GL) serves. Set `SPLATTER_TEST_BACKEND=gl` to run them on GL.

use glam::{Mat3, Quat, Vec3};
use splatter::gpu::{Executor, GpuContext};
use splatter::render::cpu;
use splatter::render::splats::sym3_from_mat3;
use splatter::render::{Camera, GpuRenderer, PassSet, Splats};
use splatter::splat::sh;

fn gpus() -> Vec<GpuContext> {
    splatter::gpu::test_contexts()
}

/// `n` random anisotropic Gaussians in the cube [−1, 1]³, random rotations, rest frames
/// and SH (the library's shared synthetic scene).
fn random_splats(n: usize, degree: u32, seed: u64) -> Splats {
    splatter::bench::Synthetic {
        ball: false,
        scale: Some((0.005, 0.08)),
        random_frames: true,
        min_opacity: 0.05,
        rest_sh: 0.4,
        ..splatter::bench::Synthetic::capture_like(n, degree, seed)
    }
    .build()
}

/// SH as the GPU sees them (f16), so the CPU reference evaluates the same coefficients.
fn f16_rounded(mut s: Splats) -> Splats {
    for v in &mut s.sh {
        *v = half::f16::from_f32(*v).to_f32();
    }
    s
}

fn camera(width: u32, height: u32) -> Camera {
    Camera::look_at(
        Vec3::new(2.2, -2.6, 1.4),
        Vec3::ZERO,
        Vec3::Z,
        50f32.to_radians(),
        width,
        height,
    )
}

/// A camera at distance `z` on the −z axis looking at the origin, y up, 40° field of view,
/// `size`×`size` pixels.
fn facing_camera(z: f32, size: u32) -> Camera {
    Camera::look_at(
        Vec3::new(0.0, 0.0, -z),
        Vec3::ZERO,
        Vec3::Y,
        40f32.to_radians(),
        size,
        size,
    )
}

/// One white isotropic Gaussian of standard deviation `sigma` and `opacity` at the origin.
fn white_gaussian(sigma: f32, opacity: f32) -> Splats {
    Splats {
        means: vec![Vec3::ZERO],
        covariances: vec![sym3_from_mat3(Mat3::from_diagonal(Vec3::splat(
            sigma * sigma,
        )))],
        rotations: vec![Quat::IDENTITY],
        opacities: vec![opacity],
        sh_degree: 0,
        sh: sh::rgb_to_dc([1.0, 1.0, 1.0]).to_vec(),
        ..Default::default()
    }
}

#[test]
fn gpu_matches_cpu_reference_on_random_scenes() {
    for gpu in gpus() {
        eprintln!("adapter: {}", gpu.describe());
        let mut renderer = GpuRenderer::new(&gpu);
        for (degree, n, seed, (w, h)) in [
            (0u32, 3000usize, 1u64, (160u32, 120u32)),
            (3, 3000, 2, (173, 97)),
            (1, 500, 3, (64, 64)),
        ] {
            let splats = f16_rounded(random_splats(n, degree, seed));
            let cam = camera(w, h);
            let bg = Vec3::new(0.1, 0.2, 0.3);
            renderer.upload(&gpu, &splats).unwrap();
            let image = renderer.render(&gpu, &cam, bg).unwrap();
            let reference = cpu::render(&splats, &cam, bg);
            let psnr = cpu::psnr(&image.rgba, &reference);
            eprintln!(
                "degree {degree}, {n} Gaussians, {w}×{h}: PSNR {psnr:.1} dB, {:?}",
                image.stats
            );
            assert!(psnr >= 40.0, "degree {degree}: PSNR {psnr:.1} dB < 40 dB");
            assert!(image.stats.visible > 0);
        }
    }
}

/// A single isotropic Gaussian facing the camera renders as
/// α(r) = ω exp(−r² / (2 s²)) with s² = (f σ / z)² + 0.3 (the dilation), over black.
#[test]
fn isotropic_gaussian_has_the_analytic_profile() {
    for gpu in gpus() {
        eprintln!("adapter: {}", gpu.describe());
        let mut renderer = GpuRenderer::new(&gpu);
        let sigma = 0.05f32;
        let z = 2.0f32;
        let opacity = 0.8f32;
        let splats = white_gaussian(sigma, opacity);
        // 64×64 so the mean is at pixel (32, 32).
        let cam = facing_camera(z, 64);
        renderer.upload(&gpu, &splats).unwrap();
        let image = renderer.render(&gpu, &cam, Vec3::ZERO).unwrap();
        let s2 = (cam.fx * sigma / z).powi(2) + 0.3;
        let mut worst = 0.0f32;
        for y in 0..64u32 {
            for x in 0..64u32 {
                let dx = x as f32 + 0.5 - 32.0;
                let dy = y as f32 + 0.5 - 32.0;
                let mut a = opacity * (-(dx * dx + dy * dy) / (2.0 * s2)).exp();
                if a < 1.0 / 255.0 {
                    a = 0.0;
                }
                let got = f32::from(image.rgba[((y * 64 + x) * 4) as usize]) / 255.0;
                worst = worst.max((got - a).abs());
            }
        }
        eprintln!(
            "σ on screen {:.2} px, worst difference {worst:.4}",
            s2.sqrt()
        );
        assert!(worst <= 1.5 / 255.0, "worst difference {worst}");
    }
}

/// The passes of that Gaussian (docs/method.md §7.7), on the GPU and the CPU reference:
/// the alpha pass's α is the analytic profile (within 1.5/255, as the colour), its straight
/// colour the Gaussian's own (white, up to the frame's rounding over α), and the depth pass the centre's
/// camera-space depth z there (within 2e-5 relative: f32 sums) and +∞ where nothing was drawn. The
/// colour frame is the same bytes with the passes on as off.
#[test]
fn the_passes_of_a_single_gaussian_are_analytic() {
    let (sigma, z, opacity) = (0.05f32, 2.0f32, 0.8f32);
    let splats = white_gaussian(sigma, opacity);
    let cam = facing_camera(z, 64);
    let bg = Vec3::new(0.2, 0.3, 0.4);
    let s2 = (cam.fx * sigma / z).powi(2) + 0.3;
    let check = |passes: &splatter::render::PassImages, what: &str| {
        let (mut worst_alpha, mut worst_depth, mut drawn) = (0.0f32, 0.0f32, 0);
        for y in 0..64u32 {
            for x in 0..64u32 {
                let (dx, dy) = (x as f32 + 0.5 - 32.0, y as f32 + 0.5 - 32.0);
                let mut a = opacity * (-(dx * dx + dy * dy) / (2.0 * s2)).exp();
                if a < 1.0 / 255.0 {
                    a = 0.0;
                }
                let i = (y * 64 + x) as usize;
                let px = &passes.alpha[4 * i..4 * i + 4];
                worst_alpha = worst_alpha.max((f32::from(px[3]) / 255.0 - a).abs());
                let depth = passes.depth[i];
                if a > 0.0 {
                    drawn += 1;
                    // The straight colour reproduces the frame at the 8-bit α: white up
                    // to the frame's rounding divided by α.
                    let a8 = f32::from(px[3]) / 255.0;
                    let levels = (1.0 / a8.max(1.0 / 255.0)).ceil() as u8;
                    for c in &px[..3] {
                        assert!(
                            *c >= 255 - levels,
                            "{what}: straight colour {px:?} at ({x}, {y})"
                        );
                    }
                    worst_depth = worst_depth.max((depth / z - 1.0).abs());
                } else if px[3] == 0 {
                    assert_eq!(
                        depth,
                        f32::INFINITY,
                        "{what}: depth where nothing was drawn"
                    );
                }
            }
        }
        eprintln!("{what}: {drawn} pixels drawn, α within {worst_alpha:.4}, depth within {worst_depth:.1e}");
        assert!(drawn > 100, "{what}");
        assert!(worst_alpha <= 1.5 / 255.0, "{what}: α off by {worst_alpha}");
        assert!(worst_depth <= 2e-5, "{what}: depth off by {worst_depth}");
    };
    let (cpu_rgba, cpu_passes) =
        cpu::render_with_passes(&splats, &cam, bg, PassSet::ALPHA_DEPTH, &[]);
    assert_eq!(cpu_rgba, cpu::render(&splats, &cam, bg));
    check(&cpu_passes.unwrap(), "CPU reference");
    for gpu in gpus() {
        let mut renderer = GpuRenderer::new(&gpu);
        renderer.upload(&gpu, &splats).unwrap();
        let plain = renderer.render(&gpu, &cam, bg).unwrap();
        assert!(plain.passes.is_none());
        renderer.set_passes(&gpu, PassSet::ALPHA_DEPTH);
        let image = renderer.render(&gpu, &cam, bg).unwrap();
        assert_eq!(
            image.rgba, plain.rgba,
            "the frame changed with the passes on"
        );
        check(image.passes.as_ref().unwrap(), &gpu.describe());
    }
}

/// The alpha pass composited over the background gives the colour frame: on a random
/// scene of 3000 Gaussians whose colours lie in [0, 1], every channel within 1/255, on the
/// GPU and the CPU reference; and the GPU's depth pass agrees with the reference's.
#[test]
fn the_alpha_pass_composited_over_the_background_is_the_frame() {
    let splats = f16_rounded(random_splats(3000, 0, 7));
    let cam = camera(160, 120);
    let bg = Vec3::new(0.1, 0.6, 0.3);
    let composite_error = |rgba: &[u8], alpha: &[u8]| {
        let mut worst = 0.0f32;
        for (f, a) in rgba.chunks_exact(4).zip(alpha.chunks_exact(4)) {
            let alpha = f32::from(a[3]) / 255.0;
            for c in 0..3 {
                let straight = f32::from(a[c]) / 255.0;
                let over = straight * alpha + bg[c] * (1.0 - alpha);
                worst = worst.max((over - f32::from(f[c]) / 255.0).abs());
            }
        }
        worst * 255.0
    };
    let (cpu_rgba, cpu_passes) =
        cpu::render_with_passes(&splats, &cam, bg, PassSet::ALPHA_DEPTH, &[]);
    let cpu_passes = cpu_passes.unwrap();
    let e = composite_error(&cpu_rgba, &cpu_passes.alpha);
    eprintln!("CPU reference: composited within {e:.2}/255");
    assert!(e <= 1.0, "CPU: {e}/255");
    for gpu in gpus() {
        let mut renderer = GpuRenderer::new(&gpu);
        renderer.set_passes(&gpu, PassSet::ALPHA_DEPTH);
        renderer.upload(&gpu, &splats).unwrap();
        let image = renderer.render(&gpu, &cam, bg).unwrap();
        let passes = image.passes.unwrap();
        let e = composite_error(&image.rgba, &passes.alpha);
        let depth_off = passes
            .depth
            .iter()
            .zip(&cpu_passes.depth)
            .filter(|(a, b)| a.is_finite() && b.is_finite())
            .map(|(a, b)| (a / b - 1.0).abs())
            .fold(0.0f32, f32::max);
        let agree = passes
            .depth
            .iter()
            .zip(&cpu_passes.depth)
            .filter(|(a, b)| a.is_finite() == b.is_finite())
            .count();
        eprintln!(
            "{}: composited within {e:.2}/255; depth against the reference within {depth_off:.1e} relative, drawn alike at {agree} of {} pixels",
            gpu.describe(),
            passes.depth.len()
        );
        assert!(e <= 1.0, "{}: {e}/255", gpu.describe());
        assert!(agree as f64 >= 0.999 * passes.depth.len() as f64);
        assert!(depth_off < 1e-4, "{}: depth {depth_off}", gpu.describe());
    }
}

/// Degree 1, only the z-basis coefficient of red set: seen along a view direction d the red
/// channel is 0.5 + C1 · d_z · c (docs/method.md §7), while green, with only a DC term, stays 0.5.
/// Red / green × 0.5 removes the Gaussian's α from the comparison.
/// A flat Gaussian (a disc, scales 0.5, 0.35 and 0.01) whose axis of least extent is a
/// known direction d, and the normal pass at every pixel it covers: the camera-space
/// direction of d turned towards the camera, W·(±d), analytic, within 2e-3 (the normal
/// rides in 12 bits an octahedral coordinate), on the CPU reference (Jacobi eigenvectors)
/// and the GPU (the cubic's closed form); (0, 0, 0) where nothing was drawn.
#[test]
fn the_normal_pass_of_a_flat_gaussian_is_its_axis() {
    let cam = camera(96, 96);
    let bg = Vec3::ZERO;
    // its normal (local z) turned by 40° about x, then 25° about z
    let rotation = Quat::from_rotation_z(0.44) * Quat::from_rotation_x(0.7);
    let r = Mat3::from_quat(rotation);
    let cov = r * Mat3::from_diagonal(Vec3::new(0.5, 0.35, 0.01).powf(2.0)) * r.transpose();
    let mut splats = white_gaussian(1.0, 0.9);
    splats.covariances[0] = sym3_from_mat3(cov);
    let d = rotation * Vec3::Z;
    let d = if d.dot(cam.position) < 0.0 { -d } else { d };
    let expected = cam.world_to_camera() * d;
    assert!(expected.z < 0.0, "a facing normal points at the camera");
    let list: Vec<_> = cpu::project_gaussian(&splats, 0, &cam)
        .into_iter()
        .collect();
    let check = |normal: &[[f32; 3]], what: &str| {
        let (mut worst, mut covered) = (0.0f32, 0);
        for y in 0..96u32 {
            for x in 0..96u32 {
                let n = Vec3::from(normal[(y * 96 + x) as usize]);
                if cpu::composite_pixel(&list, x, y).alpha() > 0.0 {
                    covered += 1;
                    worst = worst.max((n - expected).abs().max_element());
                } else {
                    assert_eq!(n, Vec3::ZERO, "{what}: a normal where nothing was drawn");
                }
            }
        }
        eprintln!("{what}: {covered} pixels drawn, normal within {worst:.1e} of {expected}");
        assert!((500..9000).contains(&covered), "{what}: {covered}");
        assert!(worst <= 2e-3, "{what}: normal off by {worst}");
    };
    let set = PassSet {
        normal: true,
        ..PassSet::default()
    };
    let (_, cpu_passes) = cpu::render_with_passes(&splats, &cam, bg, set, &[]);
    check(&cpu_passes.unwrap().normal.unwrap(), "CPU reference");
    for gpu in gpus() {
        let mut renderer = GpuRenderer::new(&gpu);
        renderer.set_passes(&gpu, set);
        renderer.upload(&gpu, &splats).unwrap();
        let image = renderer.render(&gpu, &cam, bg).unwrap();
        check(&image.passes.unwrap().normal.unwrap(), &gpu.describe());
    }
}

/// The id pass on two overlapping Gaussians of ids 3 and 7, the nearer one fainter
/// (ω 0.3 against 0.9): at each pixel the id of the larger analytic weight (w_near =
/// α_near, w_far = α_far (1 − α_near)), 0 where nothing was drawn, on the CPU reference
/// and the GPU; pixels within 1e-3 of a tie are left out.
#[test]
fn the_id_pass_shows_the_largest_weight() {
    let cam = facing_camera(2.0, 64);
    let bg = Vec3::ZERO;
    let mut near = white_gaussian(0.06, 0.3);
    let mut far = white_gaussian(0.05, 0.9);
    near.means[0] = Vec3::new(0.02, 0.0, -0.1);
    far.means[0] = Vec3::new(-0.05, 0.01, 0.1);
    let mut splats = far.clone();
    splats.append(near.clone());
    let ids = [7u16, 3];
    let alpha = |g: &Splats, x: u32, y: u32| {
        let p = cpu::project_gaussian(g, 0, &cam).unwrap();
        let d = p.xy - glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
        let power = -0.5 * (p.conic.x * d.x * d.x + p.conic.z * d.y * d.y) - p.conic.y * d.x * d.y;
        let a = (p.opacity * power.exp()).min(0.99);
        if a < 1.0 / 255.0 {
            0.0
        } else {
            a
        }
    };
    let check = |got: &[u16], what: &str| {
        let (mut checked, mut each) = (0, [0usize; 3]);
        for y in 0..64u32 {
            for x in 0..64u32 {
                let (a_near, a_far) = (alpha(&near, x, y), alpha(&far, x, y));
                let (w_near, w_far) = (a_near, a_far * (1.0 - a_near));
                if w_near.max(w_far) > 0.0 && (w_near - w_far).abs() < 1e-3 {
                    continue;
                }
                let want = if w_near.max(w_far) == 0.0 {
                    0
                } else if w_near > w_far {
                    3
                } else {
                    7
                };
                let g = got[(y * 64 + x) as usize];
                assert_eq!(
                    g, want,
                    "{what}: id at ({x}, {y}), weights {w_near} near, {w_far} far"
                );
                checked += 1;
                each[[0, 3, 7].iter().position(|v| *v == want).unwrap()] += 1;
            }
        }
        eprintln!("{what}: {checked} pixels, (none, near, far) = {each:?}");
        assert!(each.iter().all(|n| *n > 50), "{what}: {each:?}");
    };
    let set = PassSet {
        id: true,
        ..PassSet::default()
    };
    let (_, cpu_passes) = cpu::render_with_passes(&splats, &cam, bg, set, &ids);
    check(&cpu_passes.unwrap().id.unwrap(), "CPU reference");
    for gpu in gpus() {
        let mut renderer = GpuRenderer::new(&gpu);
        renderer.set_passes(&gpu, set);
        renderer.upload(&gpu, &splats).unwrap();
        renderer.set_ids(&gpu, &ids).unwrap();
        let image = renderer.render(&gpu, &cam, bg).unwrap();
        check(&image.passes.unwrap().id.unwrap(), &gpu.describe());
    }
}

/// Every pass at once on a random scene, the GPU against the CPU reference: the colour
/// frame unchanged by the passes, normals within 3e-3 wherever both drew one (a few
/// quantisation steps of the packed normal), and the same id at all but a few pixels
/// (near-ties of two weights may go either way in f32).
#[test]
fn all_passes_agree_with_the_reference_on_random_scenes() {
    let splats = f16_rounded(random_splats(2000, 1, 11));
    let ids: Vec<u16> = (0..splats.len()).map(|i| (i % 5000) as u16 + 1).collect();
    let cam = camera(128, 96);
    let bg = Vec3::new(0.1, 0.2, 0.3);
    let (_, cpu_passes) = cpu::render_with_passes(&splats, &cam, bg, PassSet::ALL, &ids);
    let cpu_passes = cpu_passes.unwrap();
    for gpu in gpus() {
        let mut renderer = GpuRenderer::new(&gpu);
        renderer.upload(&gpu, &splats).unwrap();
        let plain = renderer.render(&gpu, &cam, bg).unwrap();
        renderer.set_passes(&gpu, PassSet::ALL);
        renderer.set_ids(&gpu, &ids).unwrap();
        let image = renderer.render(&gpu, &cam, bg).unwrap();
        assert_eq!(
            image.rgba, plain.rgba,
            "the frame changed with every pass on"
        );
        let p = image.passes.unwrap();
        let (normal, id) = (p.normal.unwrap(), p.id.unwrap());
        let cpu_normal = cpu_passes.normal.as_ref().unwrap();
        let mut off: Vec<f32> = normal
            .iter()
            .zip(cpu_normal)
            .map(|(a, b)| (Vec3::from(*a), Vec3::from(*b)))
            .filter(|(a, b)| *a != Vec3::ZERO && *b != Vec3::ZERO)
            .map(|(a, b)| (a - b).length())
            .collect();
        off.sort_by(f32::total_cmp);
        let both = off.len();
        let worst = off.last().copied().unwrap_or(0.0);
        let same = id
            .iter()
            .zip(cpu_passes.id.as_ref().unwrap())
            .filter(|(a, b)| a == b)
            .count();
        let n = id.len();
        eprintln!(
            "{}: normals within {worst:.1e} at {both} pixels; ids alike at {same} of {n}",
            gpu.describe()
        );
        assert!(both > n / 3, "{both} of {n}");
        assert!(worst <= 3e-3, "normals off by {worst}");
        assert!(
            same as f64 >= 0.995 * n as f64,
            "ids alike at {same} of {n}"
        );
    }
}

#[test]
fn degree_one_colour_follows_the_view_direction() {
    for gpu in gpus() {
        eprintln!("adapter: {}", gpu.describe());
        let mut renderer = GpuRenderer::new(&gpu);
        let c = 0.6f32;
        let mut coeffs = vec![0.0f32; 12];
        coeffs[2] = -0.5 / sh::C0; // blue 0; red and green DC 0 → 0.5
        coeffs[2 * 3] = c; // red, basis Y_2 = C1 · z
        let splats = Splats {
            means: vec![Vec3::ZERO],
            covariances: vec![sym3_from_mat3(Mat3::from_diagonal(Vec3::splat(0.3 * 0.3)))],
            rotations: vec![Quat::IDENTITY],
            opacities: vec![0.99],
            sh_degree: 1,
            sh: coeffs,
            ..Default::default()
        };
        renderer.upload(&gpu, &splats).unwrap();
        for angle in [-80.0f32, -30.0, 0.0, 45.0, 85.0] {
            // Camera on a circle in the x-z plane; view direction d = (mean − camera)/|…|.
            let a = angle.to_radians();
            let eye = -3.0 * Vec3::new(a.cos(), 0.0, a.sin());
            let cam = Camera::look_at(eye, Vec3::ZERO, Vec3::Y, 40f32.to_radians(), 32, 32);
            let image = renderer.render(&gpu, &cam, Vec3::ZERO).unwrap();
            let d = (Vec3::ZERO - eye).normalize();
            let expected = 0.5 + c * sh::C1 * d.z;
            let centre = ((16 * 32 + 16) * 4) as usize;
            let (red, green) = (
                f32::from(image.rgba[centre]),
                f32::from(image.rgba[centre + 1]),
            );
            let got = red / green * 0.5;
            eprintln!(
                "angle {angle}: d_z {:.3}, colour {got:.3}, expected {expected:.3}",
                d.z
            );
            assert!(
                (got - expected).abs() <= 0.01,
                "angle {angle}: got {got}, expected {expected}"
            );
            assert!(image.rgba[centre + 2] <= 1, "blue stays 0");
        }
    }
}

/// NaN/Inf and degenerate Gaussians are skipped and counted; a Gaussian stretched far past
/// the screen is drawn (its tile rectangle is clamped to the screen), and one whose
/// projected covariance overflows f32 is skipped as degenerate. The frame still renders.
#[test]
fn nan_degenerate_and_huge_gaussians_are_guarded() {
    for gpu in gpus() {
        eprintln!("adapter: {}", gpu.describe());
        let mut renderer = GpuRenderer::new(&gpu);
        let mut splats = random_splats(200, 0, 9);
        splats.means[3] = Vec3::new(f32::NAN, 0.0, 0.0);
        splats.covariances[7][0] = f32::INFINITY;
        splats.rotations[8] = Quat::from_xyzw(f32::NAN, 0.0, 0.0, 1.0);
        splats.covariances[11] = [-1.0, 0.0, 0.0, -1.0, 0.0, -1.0];
        splats.covariances[12] = [1e36, 0.0, 0.0, 1e36, 0.0, 1e36];
        splats.covariances[13] = [1e4, 0.0, 0.0, 1e4, 0.0, 1e4];
        splats.opacities[13] = 0.5;
        renderer.upload(&gpu, &splats).unwrap();
        let cam = camera(64, 64);
        let image = renderer.render(&gpu, &cam, Vec3::ZERO).unwrap();
        assert_eq!(image.stats.skipped_nonfinite, 3);
        assert_eq!(image.stats.skipped_degenerate, 2);
        // The huge Gaussian covers every tile: at least 16 pairs (4×4 tiles) come from it.
        let tiles = 16;
        assert!(image.stats.intersections >= tiles, "{:?}", image.stats);
        // And it matches the CPU reference, which guards the same way.
        let reference = cpu::render(&f16_rounded(splats), &cam, Vec3::ZERO);
        assert!(cpu::psnr(&image.rgba, &reference) >= 40.0);
    }
}

#[test]
fn empty_scene_renders_the_background() {
    for gpu in gpus() {
        eprintln!("adapter: {}", gpu.describe());
        let mut renderer = GpuRenderer::new(&gpu);
        renderer.upload(&gpu, &Splats::default()).unwrap();
        let image = renderer
            .render(&gpu, &camera(40, 30), Vec3::new(1.0, 0.0, 0.0))
            .unwrap();
        assert!(image.rgba.chunks(4).all(|p| p == [255, 0, 0, 255]));
    }
}

/// More tile pairs than the first guess of capacity: the renderer grows its buffers and
/// renders the frame again, with the same result as the CPU reference.
#[test]
fn tile_pair_buffers_grow_when_a_frame_needs_more() {
    for gpu in gpus() {
        eprintln!("adapter: {}", gpu.describe());
        let mut renderer = GpuRenderer::new(&gpu);
        // 2000 Gaussians of 0.3 units seen from ~3.4 units at 256×256: each touches dozens of
        // tiles, ≈ 10⁵ pairs, above the initial capacity of max(8 N, 65536).
        let mut splats = random_splats(2000, 0, 21);
        for c in &mut splats.covariances {
            *c = sym3_from_mat3(Mat3::from_diagonal(Vec3::splat(0.3 * 0.3)));
        }
        let splats = f16_rounded(splats);
        renderer.upload(&gpu, &splats).unwrap();
        let cam = camera(256, 256);
        let image = renderer.render(&gpu, &cam, Vec3::ZERO).unwrap();
        assert!(image.stats.intersections > 65536, "{:?}", image.stats);
        assert_eq!(image.dropped_intersections, 0);
        let psnr = cpu::psnr(&image.rgba, &cpu::render(&splats, &cam, Vec3::ZERO));
        assert!(psnr >= 40.0, "PSNR {psnr:.1} dB");
    }
}

/// Past the pair limit the farthest Gaussians are dropped: with room for exactly the
/// nearest Gaussian's 16 tiles, the image is that Gaussian alone.
#[test]
fn pairs_past_the_limit_drop_the_farthest_gaussians() {
    for gpu in gpus() {
        eprintln!("adapter: {}", gpu.describe());
        let mut renderer = GpuRenderer::new(&gpu);
        let cam = Camera::look_at(
            Vec3::new(0.0, 0.0, -3.0),
            Vec3::ZERO,
            Vec3::Y,
            40f32.to_radians(),
            64,
            64,
        );
        let mut splats = f16_rounded(random_splats(300, 0, 5));
        // Gaussian 0: nearest to the camera and large enough to touch all 4×4 tiles.
        splats.means[0] = Vec3::new(0.0, 0.0, -1.5);
        splats.covariances[0] = sym3_from_mat3(Mat3::from_diagonal(Vec3::splat(0.5 * 0.5)));
        for m in &mut splats.means[1..] {
            m.z = m.z.abs() + 0.1; // all others behind it
        }
        renderer.upload(&gpu, &splats).unwrap();
        renderer.limit_tile_pairs(16);
        let image = renderer.render(&gpu, &cam, Vec3::ZERO).unwrap();
        assert!(image.dropped_intersections > 0);
        assert_eq!(image.dropped_intersections, image.stats.intersections - 16);
        let nearest = Splats {
            means: vec![splats.means[0]],
            covariances: vec![splats.covariances[0]],
            rotations: vec![splats.rotations[0]],
            opacities: vec![splats.opacities[0]],
            sh_degree: 0,
            sh: splats.sh[..3].to_vec(),
            ..Default::default()
        };
        let psnr = cpu::psnr(&image.rgba, &cpu::render(&nearest, &cam, Vec3::ZERO));
        assert!(
            psnr >= 40.0,
            "PSNR {psnr:.1} dB against the nearest Gaussian alone"
        );
    }
}

/// Gaussians split into pages (as past one storage binding, `gpu::pages`): projected page by
/// page and read back from every page by the tile keys and the rasteriser, 1,000 Gaussians
/// in 8 pages of 128 render the same image, bit for bit, as in one page; lighting, which reads
/// one page, refuses them with a message.
#[test]
fn gaussians_over_pages_render_as_in_one_page() {
    for gpu in gpus() {
        let cam = camera(96, 64);
        let splats = random_splats(1000, 3, 11);
        let mut one = GpuRenderer::new(&gpu);
        one.upload(&gpu, &splats).unwrap();
        let want = one.render(&gpu, &cam, Vec3::ZERO).unwrap();
        let mut paged = GpuRenderer::new(&gpu);
        paged.limit_page_size(128);
        paged.upload(&gpu, &splats).unwrap();
        let got = paged.render(&gpu, &cam, Vec3::ZERO).unwrap();
        let differ = want
            .rgba
            .iter()
            .zip(&got.rgba)
            .filter(|(a, b)| a != b)
            .count();
        eprintln!(
            "{}: {} visible, {} tile pairs; 8 pages of 128: {differ} channels differ",
            gpu.describe(),
            got.stats.visible,
            got.stats.intersections
        );
        assert!(want.stats.visible > 500, "{:?}", want.stats);
        assert_eq!(want.stats, got.stats);
        assert_eq!(differ, 0);
        let setup = splatter::render::gpu::lighting::LightingSetup {
            ambient: Vec3::ONE,
            materials: vec![],
            shading: vec![],
            shadows: None,
            max_lights: 1,
        };
        let refused = paged.set_lighting(&gpu, &setup).expect_err("refused");
        assert!(refused.to_string().contains("page"), "{refused}");
    }
}

/// The rasteriser has a workgroup shape and the sorts a method per kind of adapter
/// (`Executor`: block radix sort or chunk counting sort); both give the same image on this
/// adapter, on an image whose size leaves partial tiles and partial pixel columns.
#[test]
fn both_workgroup_shapes_render_the_same_image() {
    for gpu in gpus() {
        let cam = camera(101, 70);
        let splats = random_splats(3000, 3, 5);
        let mut images = Vec::new();
        for executor in [Executor::Gpu, Executor::Cpu] {
            let mut renderer = GpuRenderer::with_executor(&gpu, executor);
            renderer.upload(&gpu, &splats).unwrap();
            images.push(renderer.render(&gpu, &cam, Vec3::splat(0.2)).unwrap());
        }
        let differ = images[0]
            .rgba
            .iter()
            .zip(&images[1].rgba)
            .filter(|(a, b)| a != b)
            .count();
        eprintln!(
            "{}: {} visible, {} tile pairs; GPU and CPU shapes: {differ} channels differ",
            gpu.describe(),
            images[0].stats.visible,
            images[0].stats.intersections
        );
        assert!(images[0].stats.visible > 1500, "{:?}", images[0].stats);
        assert_eq!(images[0].stats, images[1].stats);
        assert_eq!(differ, 0);
    }
}

/// Opaque Gaussians a few pixels wide, scattered so that block edges cut through their
/// faint tails: the rasteriser walks, per 8×8 block, only the Gaussians that can reach one
/// of its pixels, and must still composite every pixel whose α reaches 1/255, out to
/// α = 1/255 itself (beyond 3σ for opaque ones). The CPU reference has no blocks.
#[test]
fn block_masks_keep_every_pixel_a_gaussian_reaches() {
    for gpu in gpus() {
        let mut renderer = GpuRenderer::new(&gpu);
        let mut seed = 0x2545_f491_u32;
        let mut uniform = move || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1u32 << 24) as f32
        };
        let n = 60;
        let mut splats = Splats {
            sh_degree: 0,
            ..Default::default()
        };
        for _ in 0..n {
            let mean = Vec3::new(uniform() - 0.5, uniform() - 0.5, 0.5 * uniform()) * 0.7;
            let (sx, sy) = (0.01 + 0.03 * uniform(), 0.01 + 0.03 * uniform());
            let axes = Mat3::from_diagonal(Vec3::new(sx * sx, sy * sy, 1e-4));
            let turn = Mat3::from_rotation_z(std::f32::consts::PI * uniform());
            splats.means.push(mean);
            splats
                .covariances
                .push(sym3_from_mat3(turn * axes * turn.transpose()));
            splats.rotations.push(Quat::IDENTITY);
            splats.opacities.push(0.9 + 0.1 * uniform());
            let rgb = [0.3 + 0.7 * uniform(), 0.3 + 0.7 * uniform(), 1.0];
            splats.sh.extend(sh::rgb_to_dc(rgb));
        }
        let splats = f16_rounded(splats);
        let cam = facing_camera(2.0, 128);
        renderer.upload(&gpu, &splats).unwrap();
        let image = renderer.render(&gpu, &cam, Vec3::ZERO).unwrap();
        let reference = cpu::render(&splats, &cam, Vec3::ZERO);
        let worst = image
            .rgba
            .iter()
            .zip(&reference)
            .map(|(a, b)| a.abs_diff(*b))
            .max()
            .unwrap();
        eprintln!("{}: worst channel difference {worst}/255", gpu.describe());
        assert_eq!(image.stats.visible, n as u32, "{:?}", image.stats);
        assert!(worst <= 1, "worst channel difference {worst}/255");
    }
}
