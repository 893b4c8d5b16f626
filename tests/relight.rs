//! Relighting: PCA normals against analytic normals, the shaded sphere against
//! the Blinn-Phong formula, and shadows against the geometry that casts them. Normals and
//! shading formulas are checked on the CPU (`splatter::relight`); the rendered images come
//! from the GPU renderer on every test adapter.

use glam::{Mat3, Vec3};
use splatter::relight::normals::pca_normals;
use splatter::splat::procedural::{ProceduralSpec, Shape};

fn spec(shape: Shape, spacing: f32) -> ProceduralSpec {
    ProceduralSpec {
        shape,
        spacing,
        color: Some([0.8, 0.8, 0.8]),
        shells: vec![],
        checker: None,
        opacity: 0.95,
        jitter: 0.25,
        seed: 3,
    }
}

fn angle_deg(a: Vec3, b: Vec3) -> f32 {
    a.dot(b).clamp(-1.0, 1.0).acos().to_degrees()
}

fn percentile(v: &mut [f32], q: f32) -> f32 {
    v.sort_by(f32::total_cmp);
    v[((v.len() - 1) as f32 * q).round() as usize]
}

/// Surface Gaussians (within half a spacing of the surface) of a filled, jittered sphere and
/// box: PCA normals (k = 30) against the analytic outward normals — median < 5°, 95th
/// percentile < 20°. On the box, Gaussians within two spacings of an edge, where
/// the analytic normal is not defined, are left out.
#[test]
fn pca_normals_match_analytic_normals_on_a_sphere_and_a_box() {
    let spacing = 0.025;
    let r = 0.4;
    let sphere = spec(Shape::Sphere { radius: r }, spacing)
        .generate()
        .unwrap();
    let n = pca_normals(&sphere.positions, 30);
    let mut errors: Vec<f32> = sphere
        .positions
        .iter()
        .zip(&n)
        .filter(|(p, _)| p.length() > r - 0.5 * spacing)
        .map(|(p, n)| angle_deg(*n, p.normalize()))
        .collect();
    let count = errors.len();
    let (median, p95) = (percentile(&mut errors, 0.5), percentile(&mut errors, 0.95));
    eprintln!("sphere: {count} surface Gaussians, angle error median {median:.2}°, p95 {p95:.2}°");
    assert!(median < 5.0 && p95 < 20.0);

    let half = Vec3::new(0.4, 0.3, 0.2);
    let cube = spec(
        Shape::Box {
            size: (2.0 * half).to_array(),
        },
        spacing,
    )
    .generate()
    .unwrap();
    let n = pca_normals(&cube.positions, 30);
    let mut errors = Vec::new();
    let mut edge = 0;
    for (p, n) in cube.positions.iter().zip(&n) {
        // Distance below each face; the nearest face's normal is the analytic one.
        let below = half - p.abs();
        let axis = below.min_position();
        if below[axis] > 0.5 * spacing {
            continue;
        }
        // Along edges the analytic normal jumps from face to face; leave out the Gaussians
        // within two spacings of a second face (counted and reported).
        let mut others = below;
        others[axis] = f32::INFINITY;
        if others.min_element() < 2.0 * spacing {
            edge += 1;
            continue;
        }
        let mut want = Vec3::ZERO;
        want[axis] = p[axis].signum();
        errors.push(angle_deg(*n, want));
    }
    let count = errors.len();
    let (median, p95) = (percentile(&mut errors, 0.5), percentile(&mut errors, 0.95));
    eprintln!("box: {count} surface Gaussians away from edges ({edge} near edges left out), angle error median {median:.2}°, p95 {p95:.2}°");
    assert!(median < 5.0 && p95 < 20.0);
}

/// Rotating the cloud rotates the normals with it (no dependence on the axes).
#[test]
fn pca_normals_rotate_with_the_object() {
    let sphere = spec(Shape::Sphere { radius: 0.3 }, 0.03)
        .generate()
        .unwrap();
    let rot = Mat3::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1);
    let moved: Vec<Vec3> = sphere.positions.iter().map(|p| rot * *p).collect();
    let a = pca_normals(&sphere.positions, 30);
    let b = pca_normals(&moved, 30);
    let worst = a
        .iter()
        .zip(&b)
        .zip(&sphere.positions)
        .filter(|(_, p)| p.length() > 0.27)
        .map(|((a, b), _)| angle_deg(rot * *a, *b))
        .fold(0.0f32, f32::max);
    assert!(worst < 0.5, "worst {worst}°");
}

// ------------------------------------------------------------------------------------------
// Rendered images (GPU)
// ------------------------------------------------------------------------------------------

use splatter::derive::normals::{spacing_of, GpuNormals, RecomputedObject};
use splatter::relight::shadow::VolumeGrid;
use splatter::relight::{blinn_phong, oct_encode, PointLight, ShadingParams};
use splatter::render::gpu::lighting::LightingSetup;
use splatter::render::{Camera, GpuRenderer, Splats};

fn gpus() -> Vec<splatter::gpu::GpuContext> {
    splatter::gpu::test_contexts()
}

/// Splats of procedural objects, with PCA normals per object and one material.
fn lit_scene(objects: &[(ProceduralSpec, Vec3)]) -> (Splats, Vec<[u32; 2]>) {
    let mut splats = Splats::default();
    let mut shading = Vec::new();
    for (spec, at) in objects {
        let cloud = spec.generate().unwrap();
        let s = Splats::from_cloud(&cloud, Mat3::IDENTITY, *at);
        let normals = pca_normals(&s.means, 30);
        shading.extend(normals.iter().map(|n| [oct_encode(*n), 0]));
        splats.append(s);
    }
    (splats, shading)
}

fn luminance(img: &[u8], w: u32, x: u32, y: u32) -> f32 {
    let i = 4 * (y * w + x) as usize;
    (f32::from(img[i]) + f32::from(img[i + 1]) + f32::from(img[i + 2])) / (3.0 * 255.0)
}

/// Where the camera ray through the centre of pixel (x, y) meets the sphere |p − c| = r
/// (the nearer hit), if it does.
fn ray_sphere(cam: &Camera, x: u32, y: u32, c: Vec3, r: f32) -> Option<Vec3> {
    let (cx, cy) = cam.principal_point();
    let d = (cam.rotation
        * Vec3::new(
            (x as f32 + 0.5 - cx) / cam.fx,
            (y as f32 + 0.5 - cy) / cam.fy,
            1.0,
        ))
    .normalize();
    let o = cam.position - c;
    let b = o.dot(d);
    let disc = b * b - (o.length_squared() - r * r);
    (disc >= 0.0).then(|| cam.position + d * (-b - disc.sqrt()))
}

/// A grey sphere lit by one point light from +x: the rendered image follows the analytic
/// Blinn-Phong shading of a sphere (pixel by pixel, away from the silhouette), its +x half
/// is brighter than its −x half, and its brightest spot is where the formula puts it.
/// Shadows are on: a convex object must not shadow its own lit side.
#[test]
fn a_lit_sphere_is_shaded_as_the_formula_says() {
    let r = 0.5;
    let (splats, shading) = lit_scene(&[(spec(Shape::Sphere { radius: r }, 0.02), Vec3::ZERO)]);
    let grey = 0.6;
    let ambient = Vec3::splat(0.2);
    let light = PointLight {
        position: Vec3::new(2.0, 0.5, 1.5),
        radiance: Vec3::splat(4.0),
    };
    let w = ShadingParams::default();
    let (width, height) = (96u32, 96u32);
    let cam = Camera::look_at(
        Vec3::new(0.0, 0.0, 3.0),
        Vec3::ZERO,
        Vec3::Y,
        30f32.to_radians(),
        width,
        height,
    );
    // The analytic image of the shaded sphere surface.
    let shade = |p: Vec3| {
        let n = p.normalize();
        blinn_phong(
            Vec3::splat(grey),
            p,
            n,
            cam.position,
            ambient,
            &[light],
            &[1.0],
            &w,
        )
        .x
    };
    for gpu in gpus() {
        let mut renderer = GpuRenderer::new(&gpu);
        let mut s = splats.clone();
        for c in s.sh.chunks_mut(3) {
            // Every Gaussian grey: c0 = 0.5 + C0 · dc.
            c.fill((grey - 0.5) / splatter::splat::sh::C0);
        }
        renderer.upload(&gpu, &s).unwrap();
        renderer
            .set_lighting(
                &gpu,
                &LightingSetup {
                    ambient,
                    materials: vec![w],
                    shading: shading.clone(),
                    shadows: Some(VolumeGrid::covering(
                        Vec3::splat(-0.6),
                        Vec3::splat(0.6),
                        48,
                    )),
                    max_lights: 1,
                },
            )
            .unwrap();
        renderer.set_lights(&[light]);
        let img = renderer.render(&gpu, &cam, Vec3::ZERO).unwrap();
        let (mut right, mut left, mut nr, mut nl) = (0.0, 0.0, 0, 0);
        let (mut err_sum, mut err_n, mut worst) = (0.0f32, 0, 0.0f32);
        let (mut best, mut best_px) = (0.0f32, (0u32, 0u32));
        let (mut want_best, mut want_px) = (0.0f32, (0u32, 0u32));
        for y in 0..height {
            for x in 0..width {
                let Some(p) = ray_sphere(&cam, x, y, Vec3::ZERO, r) else {
                    continue;
                };
                let got = luminance(&img.rgba, width, x, y);
                if x >= width / 2 {
                    right += got;
                    nr += 1;
                } else {
                    left += got;
                    nl += 1;
                }
                // Away from the silhouette (where splats thin out): compare to the formula.
                if p.normalize().dot((cam.position - p).normalize()) > 0.5 {
                    let want = shade(p).min(1.0);
                    let e = (got - want).abs();
                    err_sum += e;
                    err_n += 1;
                    worst = worst.max(e);
                    if want > want_best {
                        (want_best, want_px) = (want, (x, y));
                    }
                    if got > best {
                        (best, best_px) = (got, (x, y));
                    }
                }
            }
        }
        let (right, left) = (right / nr as f32, left / nl as f32);
        let mean_err = err_sum / err_n as f32;
        let dist = ((best_px.0 as f32 - want_px.0 as f32).powi(2)
            + (best_px.1 as f32 - want_px.1 as f32).powi(2))
        .sqrt();
        let sphere_px = cam.fx * r / 3.0;
        eprintln!(
            "{}: +x half {right:.3}, −x half {left:.3}; vs formula: mean |Δ| {mean_err:.3}, worst {worst:.3} over {err_n} pixels; brightest at {best_px:?} ({best:.3}), formula {want_px:?} ({want_best:.3}): {dist:.1} px of a {sphere_px:.0} px radius",
            gpu.describe()
        );
        assert!(right > 1.3 * left, "the lit half is brighter");
        assert!(mean_err < 0.04, "mean error {mean_err}");
        assert!(dist < 0.15 * sphere_px, "brightest spot {dist} px off");
    }
}

/// A blob between a point light and a ground slab: the slab darkens where the rays from it
/// to the light pass through the blob, and nowhere else (each pixel of the slab compared
/// with the same render without shadows); moving the light to the other side moves the
/// shadow with it.
#[test]
fn a_blob_shadows_the_slab_where_the_geometry_says() {
    let blob_c = Vec3::new(0.0, 0.0, 0.45);
    let blob_r = 0.2;
    let slab = ProceduralSpec {
        shape: Shape::Slab {
            size: [2.4, 2.4],
            thickness: 0.06,
        },
        ..spec(Shape::Sphere { radius: 1.0 }, 0.03)
    };
    let (splats, shading) = lit_scene(&[
        (slab, Vec3::ZERO),
        (spec(Shape::Sphere { radius: blob_r }, 0.02), blob_c),
    ]);
    let (width, height) = (96u32, 96u32);
    let cam = Camera::look_at(
        Vec3::new(0.0, 0.0, 4.0),
        Vec3::ZERO,
        Vec3::Y,
        34f32.to_radians(),
        width,
        height,
    );
    let grid = VolumeGrid::covering(
        Vec3::new(-1.25, -1.25, -0.1),
        Vec3::new(1.25, 1.25, 0.7),
        64,
    );
    for gpu in gpus() {
        for light_x in [1.0f32, -1.0] {
            let light = PointLight {
                position: Vec3::new(light_x, 0.0, 1.5),
                radiance: Vec3::splat(2.0),
            };
            let mut images = Vec::new();
            for shadows in [None, Some(grid)] {
                let mut renderer = GpuRenderer::new(&gpu);
                renderer.upload(&gpu, &splats).unwrap();
                renderer
                    .set_lighting(
                        &gpu,
                        &LightingSetup {
                            ambient: Vec3::splat(0.1),
                            materials: vec![ShadingParams::default()],
                            shading: shading.clone(),
                            shadows,
                            max_lights: 1,
                        },
                    )
                    .unwrap();
                renderer.set_lights(&[light]);
                images.push(renderer.render(&gpu, &cam, Vec3::ZERO).unwrap().rgba);
            }
            // Classify slab pixels by where the ray from the slab point to the light passes
            // the blob's centre (in blob radii); skip pixels that see the blob itself.
            let (mut inside, mut ni, mut outside_min, mut no) = (0.0f32, 0, f32::MAX, 0);
            let mut dark_centroid = Vec3::ZERO;
            for y in 0..height {
                for x in 0..width {
                    if ray_sphere(&cam, x, y, blob_c, blob_r * 1.3).is_some() {
                        continue;
                    }
                    let Some(p) = ray_plane(&cam, x, y) else {
                        continue;
                    };
                    if p.x.abs() > 1.1 || p.y.abs() > 1.1 {
                        continue;
                    }
                    let d = (light.position - p).normalize();
                    let miss = (blob_c - p).cross(d).length() / blob_r;
                    let lit = luminance(&images[0], width, x, y);
                    if lit < 0.05 {
                        continue; // too dark to measure a ratio (facing away)
                    }
                    let ratio = luminance(&images[1], width, x, y) / lit;
                    if miss < 0.7 {
                        inside += ratio;
                        ni += 1;
                        dark_centroid += p;
                    } else if miss > 1.6 {
                        outside_min = outside_min.min(ratio);
                        no += 1;
                    }
                }
            }
            let inside = inside / ni as f32;
            let centroid = dark_centroid / ni as f32;
            // The shadow's centre: the blob's centre projected from the light onto z = 0.
            let t = light.position.z / (light.position.z - blob_c.z);
            let want = light.position + (blob_c - light.position) * t;
            eprintln!(
                "{}: light x = {light_x}: {ni} pixels inside the predicted shadow, mean brightness ratio {inside:.3}; {no} pixels well outside, lowest ratio {outside_min:.3}; shadow centre predicted ({:.2}, {:.2})",
                gpu.describe(),
                want.x,
                want.y,
            );
            assert!(ni > 20 && no > 1000, "test setup: {ni} / {no} pixels");
            assert!(inside < 0.5, "the shadow darkens the slab: ratio {inside}");
            assert!(
                outside_min > 0.9,
                "no shadow elsewhere: ratio {outside_min}"
            );
            assert!((centroid.x - want.x).abs() < 0.15, "{centroid} vs {want}");
        }
    }
}

/// The shadow passes march only the voxels that some visible Gaussian's lookup reads
/// (`shadow_mark.wgsl`): every such voxel, for each of two lights, holds the transmittance
/// of the CPU reference march (`relight::shadow`, over the CPU-splatted volume), so no
/// lookup reads a voxel that was left out; and the voxels marched are a fraction of the
/// volume.
#[test]
fn every_voxel_a_shadow_lookup_reads_is_marched() {
    use splatter::relight::oct_decode;
    use splatter::relight::shadow::{splat, transmittance};
    let (splats, shading) = lit_scene(&[
        (
            ProceduralSpec {
                shape: Shape::Slab {
                    size: [1.6, 1.6],
                    thickness: 0.06,
                },
                ..spec(Shape::Sphere { radius: 1.0 }, 0.04)
            },
            Vec3::ZERO,
        ),
        (
            spec(Shape::Sphere { radius: 0.2 }, 0.03),
            Vec3::new(0.1, 0.0, 0.4),
        ),
    ]);
    let cam = Camera::look_at(
        Vec3::new(0.3, -2.5, 2.0),
        Vec3::ZERO,
        Vec3::Z,
        45f32.to_radians(),
        80,
        60,
    );
    let grid = VolumeGrid::covering(Vec3::new(-0.9, -0.9, -0.1), Vec3::new(0.9, 0.9, 0.7), 40);
    let lights = [
        PointLight {
            position: Vec3::new(0.8, 0.2, 1.4),
            radiance: Vec3::splat(2.0),
        },
        PointLight {
            position: Vec3::new(-0.7, -0.5, 1.0),
            radiance: Vec3::splat(1.0),
        },
    ];
    let depth = splat(&grid, &splats.means, &splats.covariances, &splats.opacities);
    let voxels = grid.voxels();
    // The voxels the shade pass reads: every Gaussian is in front of the camera and opaque
    // enough to be drawn, so each one with a normal looks up each light (shadow_lookup).
    let mut read = vec![false; voxels * lights.len()];
    for (i, p) in splats.means.iter().enumerate() {
        let n = oct_decode(shading[i][0]);
        if n == Vec3::ZERO {
            continue;
        }
        let n = if n.dot(cam.position - *p) < 0.0 {
            -n
        } else {
            n
        };
        for (k, light) in lights.iter().enumerate() {
            let l = (light.position - *p).normalize();
            let x = (*p + l * (2.0 * grid.h) + n * (1.5 * grid.h) - grid.lo) / grid.h - 0.5;
            let hi = grid.res.as_vec3() - 1.0;
            if x.cmplt(Vec3::ZERO).any() || x.cmpgt(hi).any() {
                continue;
            }
            let lo = x.floor().min(hi - 1.0).as_uvec3();
            for c in 0..8u32 {
                let v = lo + glam::UVec3::new(c & 1, (c >> 1) & 1, c >> 2);
                read[k * voxels + (v.x + grid.res.x * (v.y + grid.res.y * v.z)) as usize] = true;
            }
        }
    }
    let wanted = read.iter().filter(|r| **r).count();
    assert!(wanted > 100, "the scene's lookups read {wanted} voxels");
    for gpu in gpus() {
        let mut renderer = GpuRenderer::new(&gpu);
        renderer.upload(&gpu, &splats).unwrap();
        renderer
            .set_lighting(
                &gpu,
                &LightingSetup {
                    ambient: Vec3::splat(0.2),
                    materials: vec![ShadingParams::default()],
                    shading: shading.clone(),
                    shadows: Some(grid),
                    max_lights: lights.len(),
                },
            )
            .unwrap();
        renderer.set_lights(&lights);
        renderer.render(&gpu, &cam, Vec3::ZERO).unwrap();
        let t = renderer.read_transmittance(&gpu).unwrap().unwrap();
        let mut worst = 0.0f32;
        let mut shadowed = 0;
        for (index, _) in read.iter().enumerate().filter(|(_, r)| **r) {
            let (k, v) = (index / voxels, index % voxels);
            let cell = glam::UVec3::new(
                v as u32 % grid.res.x,
                (v as u32 / grid.res.x) % grid.res.y,
                v as u32 / (grid.res.x * grid.res.y),
            );
            let centre = grid.lo + (cell.as_vec3() + 0.5) * grid.h;
            let want = transmittance(&grid, &depth, centre, lights[k].position);
            worst = worst.max((t[index] - want).abs());
            shadowed += usize::from(want < 0.5);
        }
        eprintln!(
            "{}: {wanted} of {} voxel-lights read and marched ({shadowed} in shadow); worst |T − T_cpu| = {worst:.2e}",
            gpu.info.name,
            voxels * lights.len()
        );
        assert!(
            worst < 1e-3,
            "a looked-up voxel's transmittance is off by {worst}"
        );
        assert!(shadowed > 10, "the blob shadows some of the voxels read");
        assert!(
            wanted * 4 < voxels * lights.len(),
            "a fraction of the volume is read"
        );
    }
}

/// Where the camera ray through pixel (x, y) meets the plane z = 0.
fn ray_plane(cam: &Camera, x: u32, y: u32) -> Option<Vec3> {
    let (cx, cy) = cam.principal_point();
    let d = cam.rotation
        * Vec3::new(
            (x as f32 + 0.5 - cx) / cam.fx,
            (y as f32 + 0.5 - cy) / cam.fy,
            1.0,
        );
    let t = -cam.position.z / d.z;
    (t > 0.0).then(|| cam.position + d * t)
}

/// A cube of Gaussians split in two by the simulation: its halves are thrown apart at
/// ±1 m/s and it breaks along a weak layer (five lattice layers of cohesionless NACC, wider
/// than an MPM stencil, between stiff elastic halves). On the two new faces, normals recomputed by PCA in the deformed
/// configuration are within 20° of the face normal (median), while the normals
/// transported with F⁻ᵀ from the interior are not — the measurement behind
/// `lighting.simulated_normals = "recompute"`.
#[test]
fn new_faces_of_a_split_cube_get_face_normals_when_recomputed() {
    use splatter::derive::Derive;
    use splatter::relight::oct_decode;
    use splatter::sim::gpu::GpuSim;
    use splatter::sim::model::nacc::oracle::{Case3Variant, NaccParams};
    use splatter::sim::{Boundaries, Grid, Material, Particles, StepParams, Transfer};

    let spacing = 0.02;
    let half = 0.2;
    let cube = spec(
        Shape::Box {
            size: [2.0 * half; 3],
        },
        spacing,
    )
    .generate()
    .unwrap();
    let centre = Vec3::splat(1.0);
    let splats = Splats::from_cloud(&cube, Mat3::IDENTITY, centre);
    let rest_normals = pca_normals(&splats.means, 30);
    let shading: Vec<[u32; 2]> = rest_normals.iter().map(|n| [oct_encode(*n), 0]).collect();
    let weak = |x: f32| (x - centre.x).abs() < 2.5 * spacing;
    let mut particles = Particles::new();
    let volume = f64::from(spacing).powi(3);
    for m in &splats.means {
        let side = if m.x < centre.x { -1.0 } else { 1.0 };
        particles.push(
            m.as_dvec3(),
            glam::DVec3::new(side, 0.0, 0.0),
            1000.0 * volume,
            volume,
            u32::from(weak(m.x)),
            0.0,
        );
    }
    let materials = [
        Material::fixed_corotated(2e4, 0.3),
        Material::nacc(
            NaccParams {
                e: 2e4,
                nu: 0.3,
                alpha0: -0.001,
                beta: 0.1,
                xi: 0.0,
                m_slope: 1.0,
            },
            Case3Variant::Continuous { k: 2.0 },
        ),
    ];
    let grid = Grid::new(glam::DVec3::ZERO, glam::DVec3::splat(2.0), 1.0 / 32.0);
    let params = StepParams {
        dt: 2e-4,
        gravity: glam::DVec3::ZERO,
        boundaries: Boundaries::default(),
        transfer: Transfer::Apic,
        separation: Default::default(),
        fields: Default::default(),
        actions: Default::default(),
    };
    for gpu in gpus() {
        let sim = GpuSim::new(&gpu, &particles, &grid, &materials, &params).unwrap();
        let mut renderer = GpuRenderer::new(&gpu);
        renderer.upload(&gpu, &splats).unwrap();
        renderer
            .set_lighting(
                &gpu,
                &LightingSetup {
                    ambient: Vec3::ONE,
                    materials: vec![ShadingParams::default()],
                    shading: shading.clone(),
                    shadows: None,
                    max_lights: 1,
                },
            )
            .unwrap();
        let derive = Derive::new(
            &gpu,
            &sim,
            &renderer,
            &splats,
            0,
            &splatter::derive::Binding::identity(0, splats.len()),
        )
        .unwrap();
        sim.step(&gpu, 1000).unwrap();
        derive.run(&gpu).unwrap();
        let means: Vec<Vec3> = renderer
            .read_gaussians(&gpu)
            .unwrap()
            .iter()
            .map(|g| Vec3::new(g.mean_opacity[0], g.mean_opacity[1], g.mean_opacity[2]))
            .collect();
        let transported = read_shading(&gpu, &renderer);
        let recomputed = pca_normals(&means, 30);
        // The same on the GPU, in place of the transported normals.
        let gpu_normals = GpuNormals::new(
            &gpu,
            &renderer,
            &[RecomputedObject {
                range: 0..means.len(),
                spacing: spacing_of(&splats.means),
            }],
            Vec3::ZERO,
            Vec3::splat(2.0),
        )
        .unwrap();
        gpu_normals.run(&gpu).unwrap();
        let on_gpu = read_shading(&gpu, &renderer);

        // Each half's inner end: the innermost of its Gaussians (weak layer included).
        let left_max = (0..means.len())
            .filter(|&i| splats.means[i].x < centre.x)
            .map(|i| means[i].x)
            .fold(f32::MIN, f32::max);
        let right_min = (0..means.len())
            .filter(|&i| splats.means[i].x >= centre.x)
            .map(|i| means[i].x)
            .fold(f32::MAX, f32::min);
        let gap = right_min - left_max;
        let mut hist = vec![0usize; 40];
        for m in &means {
            let b = ((m.x - 0.4) / 0.03).floor();
            if (0.0..40.0).contains(&b) {
                hist[b as usize] += 1;
            }
        }
        let (mut rec, mut tra, mut gpu_rec) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..means.len() {
            let left = splats.means[i].x < centre.x;
            let on_face = if left {
                means[i].x > left_max - spacing
            } else {
                means[i].x < right_min + spacing
            };
            let inner = (splats.means[i].y - centre.y).abs() < half - 2.0 * spacing
                && (splats.means[i].z - centre.z).abs() < half - 2.0 * spacing;
            if !(on_face && inner) {
                continue;
            }
            let want = if left { Vec3::X } else { -Vec3::X };
            rec.push(angle_deg(recomputed[i], want));
            tra.push(angle_deg(oct_decode(transported[i][0]), want));
            gpu_rec.push(angle_deg(oct_decode(on_gpu[i][0]), want));
        }
        let count = rec.len();
        let (rec_median, tra_median) = (percentile(&mut rec, 0.5), percentile(&mut tra, 0.5));
        let gpu_median = percentile(&mut gpu_rec, 0.5);
        eprintln!(
            "{}: gap {gap:.3} m (x histogram from 0.4 by 0.03: {hist:?}); {count} Gaussians on the new faces: recomputed normals median {rec_median:.1}° (CPU), {gpu_median:.1}° (GPU), transported {tra_median:.1}°",
            gpu.describe()
        );
        // More than two cells apart (debris included): the fragments share no grid nodes.
        assert!(gap > 2.0 / 32.0, "the cube split (gap {gap})");
        assert!(count > 50, "test setup: {count} face Gaussians");
        assert!(rec_median < 20.0, "recomputed median {rec_median}°");
        assert!(
            gpu_median < 20.0,
            "recomputed on the GPU: median {gpu_median}°"
        );
        assert!(tra_median > 45.0, "transport keeps the interior's normals");
    }
}

/// The renderer's shading records (packed normal, material), read back.
fn read_shading(gpu: &splatter::gpu::GpuContext, renderer: &GpuRenderer) -> Vec<[u32; 2]> {
    let buffer = renderer.shading_buffer().unwrap();
    bytemuck::pod_collect_to_vec(&splatter::gpu::buffers::copy_out(gpu, buffer).unwrap())
}

/// The GPU's PCA normals (a radius instead of the k nearest, same refit) against the
/// analytic normals of a filled sphere and box: the same bars as the CPU's (median < 5°,
/// 95th percentile < 20°), starting from no normal at all.
#[test]
fn gpu_pca_normals_match_analytic_normals() {
    use splatter::relight::{oct_decode, NO_NORMAL};
    let spacing = 0.025;
    let r = 0.4;
    let half = Vec3::new(0.4, 0.3, 0.2);
    let sphere = spec(Shape::Sphere { radius: r }, spacing)
        .generate()
        .unwrap();
    let cube = spec(
        Shape::Box {
            size: (2.0 * half).to_array(),
        },
        spacing,
    )
    .generate()
    .unwrap();
    for gpu in gpus() {
        for (name, cloud) in [("sphere", &sphere), ("box", &cube)] {
            let splats = Splats::from_cloud(cloud, Mat3::IDENTITY, Vec3::ZERO);
            let mut renderer = GpuRenderer::new(&gpu);
            renderer.upload(&gpu, &splats).unwrap();
            renderer
                .set_lighting(
                    &gpu,
                    &LightingSetup {
                        ambient: Vec3::ONE,
                        materials: vec![ShadingParams::default()],
                        shading: vec![[NO_NORMAL, 0]; splats.len()],
                        shadows: None,
                        max_lights: 1,
                    },
                )
                .unwrap();
            GpuNormals::new(
                &gpu,
                &renderer,
                &[RecomputedObject {
                    range: 0..splats.len(),
                    spacing: spacing_of(&splats.means),
                }],
                Vec3::splat(-0.5),
                Vec3::splat(0.5),
            )
            .unwrap()
            .run(&gpu)
            .unwrap();
            let got = read_shading(&gpu, &renderer);
            let mut errors = Vec::new();
            for (p, rec) in splats.means.iter().zip(&got) {
                let want = if name == "sphere" {
                    if p.length() <= r - 0.5 * spacing {
                        continue;
                    }
                    p.normalize()
                } else {
                    let below = half - p.abs();
                    let axis = below.min_position();
                    let mut others = below;
                    others[axis] = f32::INFINITY;
                    if below[axis] > 0.5 * spacing || others.min_element() < 2.0 * spacing {
                        continue;
                    }
                    let mut w = Vec3::ZERO;
                    w[axis] = p[axis].signum();
                    w
                };
                errors.push(angle_deg(oct_decode(rec[0]), want));
            }
            let count = errors.len();
            let (median, p95) = (percentile(&mut errors, 0.5), percentile(&mut errors, 0.95));
            eprintln!(
                "{}: GPU normals, {name}: {count} surface Gaussians, median {median:.2}°, p95 {p95:.2}°",
                gpu.describe()
            );
            assert!(median < 5.0 && p95 < 20.0, "{name}");
        }
    }
}
