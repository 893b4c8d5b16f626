//! Selecting what moves and interior filling: `physics.select`,
//! `physics.min_opacity`, `physics.fill` and `scene::fill`.

use std::path::Path;

use glam::{DVec3, Quat, Vec3};
use splatter::scene::fill::{fill, FillInput, InsideTest};
use splatter::scene::simulation::{prepare, PartKind, SimulationSetup};
use splatter::scene::{self, SceneError};
use splatter::splat::ply::{write_ply, PlyFormat};
use splatter::splat::GaussianCloud;

fn scene_text(objects: &str, dx: f64) -> String {
    format!(
        r#"{{
  "output": {{ "width": 32, "height": 24, "frames": 1 }},
  "camera": {{ "fov_y_deg": 40, "path": {{ "type": "orbit", "target": [0.5, 0.5, 0.5], "radius": 2 }} }},
  "simulation": {{ "dx": {dx}, "domain": {{ "lo": [0, 0, 0], "hi": [1, 1, 1] }} }},
  "objects": [{objects}]
}}"#
    )
}

fn setup(text: &str, dir: &Path) -> Result<SimulationSetup, SceneError> {
    let scene = scene::parse(text, "test.json", dir)?;
    let (splats, report) = scene.build_splats()?;
    Ok(prepare(&scene, splats, &report)?.expect("a simulation"))
}

const MATERIAL: &str =
    r#""material": { "model": "fixed_corotated", "E": 1000, "nu": 0.3, "density": 2 }"#;

/// A closed procedural sphere filled at h = Δx/2: particles ≈ volume / h³ and none outside.
#[test]
fn procedural_sphere_fill_matches_volume_and_stays_inside() {
    let (r, dx) = (0.3, 0.02);
    let h = dx / 2.0;
    let obj = format!(
        r#"{{ "procedural": {{ "shape": "sphere", "radius": {r}, "spacing": 0.04, "color": [1, 0, 0] }},
            "transform": {{ "translate": [0.5, 0.5, 0.5] }},
            "physics": {{ {MATERIAL}, "fill": true, "particles": "gaussians" }} }}"#
    );
    let s = setup(&scene_text(&obj, dx), Path::new(".")).unwrap();
    let volume = 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
    let expected = volume / (h * h * h);
    let n = s.particles.len() as f64;
    let rel = (n - expected).abs() / expected;
    println!(
        "procedural sphere: {n} particles, volume/h³ = {expected:.0} ({:+.2}%)",
        100.0 * (n - expected) / expected
    );
    assert!(rel < 0.05, "{n} particles vs {expected:.0}");
    let v: f64 = s.particles.volume0.iter().sum();
    assert!((v - volume).abs() / volume < 0.05, "volume {v} vs {volume}");
    let centre = DVec3::splat(0.5);
    let outside = s
        .particles
        .x
        .iter()
        .filter(|x| x.distance(centre) > r + 1e-6)
        .count();
    assert_eq!(outside, 0, "particles outside the sphere");
    // Splat order: the fill follows the object's Gaussians, all after static_count.
    let kinds: Vec<PartKind> = s.parts.iter().map(|p| p.kind).collect();
    assert_eq!(kinds, [PartKind::Simulated, PartKind::Fill]);
    assert_eq!(s.static_count, 0);
    assert_eq!(s.splats.len(), s.particles.len());
    // Fill Gaussians are isotropic, σ = 0.6 h, and take the object's colour.
    let fill = &s.parts[1];
    let c = s.splats.covariances[fill.start];
    assert!((c[0] - (0.6 * h as f32).powi(2)).abs() < 1e-9 && c[1] == 0.0);
    assert_eq!(
        s.splats.sh[fill.start * 3..fill.start * 3 + 3],
        s.splats.sh[0..3]
    );
}

/// The default particles: a jittered lattice at h = Δx/2 over the exact solid, whatever the
/// object's own spacing; its volume is the sphere's, no particle strays further than the
/// jitter, and every Gaussian (the object's and the fill's) rides on its nearest particle.
#[test]
fn lattice_particles_cover_the_solid_and_carry_every_gaussian() {
    let (r, dx) = (0.3, 0.02);
    let h = dx / 2.0;
    let volume = 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
    let centre = DVec3::splat(0.5);
    for (spacing, fill) in [(0.04, "false"), (0.005, "false"), (0.04, "true")] {
        let obj = format!(
            r#"{{ "procedural": {{ "shape": "sphere", "radius": {r}, "spacing": {spacing}, "color": [1, 0, 0] }},
                "transform": {{ "translate": [0.5, 0.5, 0.5] }},
                "physics": {{ {MATERIAL}, "fill": {fill} }} }}"#
        );
        let s = setup(&scene_text(&obj, dx), Path::new(".")).unwrap();
        let n = s.particles.len() as f64;
        let expected = volume / (h * h * h);
        println!("lattice, object spacing {spacing}, fill {fill}: {n} particles for {} Gaussians (volume/h³ = {expected:.0})", s.splats.len());
        assert!(
            (n - expected).abs() / expected < 0.03,
            "{n} vs {expected:.0}"
        );
        let v: f64 = s.particles.volume0.iter().sum();
        assert!((v - volume).abs() / volume < 0.03, "volume {v} vs {volume}");
        // Voxel centres inside, moved by at most h/4 per axis.
        let reach = r + 0.25 * h * 3f64.sqrt() + 1e-9;
        assert!(s.particles.x.iter().all(|x| x.distance(centre) <= reach));
        assert_eq!(s.binding.len(), s.splats.len() - s.static_count);
        assert_eq!(s.bodies.len(), 1);
        assert_eq!(s.bodies[0].particles, 0..s.particles.len());
        for (k, (&p, d)) in s.binding.particle.iter().zip(&s.binding.offset).enumerate() {
            let g = s.static_count + k;
            let x = s.splats.means[g].as_dvec3();
            assert!((x - s.particles.x[p as usize] - d.as_dvec3()).length() < 1e-6);
            // The nearest particle is never further than a voxel's diagonal.
            assert!(
                d.length() < 3f32.sqrt() * h as f32,
                "Gaussian {g}: offset {d}"
            );
        }
    }
}

/// A surface-only sphere cloud (tangent disks on a Fibonacci sphere).
fn surface_sphere(centre: Vec3, r: f32, n: usize) -> GaussianCloud {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    let disk = r * (4.0 * std::f32::consts::PI / n as f32).sqrt() * 0.6;
    let mut c = GaussianCloud {
        positions: Vec::new(),
        scales: Vec::new(),
        rotations: Vec::new(),
        opacities: Vec::new(),
        sh_degree: 0,
        sh: Vec::new(),
        normals: Vec::new(),
        ..Default::default()
    };
    for i in 0..n {
        let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
        let rho = (1.0 - z * z).sqrt();
        let phi = golden * i as f32;
        let d = Vec3::new(rho * phi.cos(), rho * phi.sin(), z);
        c.positions.push(centre + r * d);
        c.scales.push(Vec3::new(disk, disk, disk * 0.01));
        c.rotations.push(Quat::from_rotation_arc(Vec3::Z, d));
        c.opacities.push(0.9);
        c.sh.extend_from_slice(&[0.3, (i % 7) as f32 * 0.1, -0.2]);
    }
    c
}

/// A PLY sphere made of surface Gaussians only gets a solid interior: on a cut through the
/// centre, every point inside (minus a margin) has a particle within two spacings.
#[test]
fn surface_only_ply_sphere_fills_without_holes() {
    let dir = tempfile::tempdir().unwrap();
    let (r, dx) = (0.3f32, 0.02);
    let h = dx / 2.0;
    let cloud = surface_sphere(Vec3::splat(0.5), r, 20_000);
    write_ply(
        &dir.path().join("shell.ply"),
        &cloud,
        PlyFormat::BinaryLittleEndian,
    )
    .unwrap();
    let obj = format!(r#"{{ "ply": "shell.ply", "physics": {{ {MATERIAL}, "fill": true }} }}"#);
    let s = setup(&scene_text(&obj, dx), dir.path()).unwrap();
    let added = s.particles.len() - cloud.len();
    let expected = 4.0 / 3.0 * std::f64::consts::PI * f64::from(r).powi(3) / (h * h * h);
    println!(
        "surface sphere: {} surface + {added} fill particles (volume/h³ = {expected:.0}); warnings {:?}",
        cloud.len(),
        s.warnings
    );
    assert!(added as f64 > 0.8 * expected && (added as f64) < 1.05 * expected);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    // Every fill particle lies inside the sphere (with the surface band's width to spare).
    let centre = DVec3::splat(0.5);
    let r = f64::from(r);
    assert!(s
        .particles
        .x
        .iter()
        .all(|x| x.distance(centre) < r + 2.0 * h));
    // The cut z = 0.5 (and a slanted one): no hole larger than two spacings.
    let near: Vec<DVec3> = s.particles.x.clone();
    let mut worst: f64 = 0.0;
    let mut checked = 0;
    let step = h / 2.0;
    let m = (r / step) as i64;
    for (tilt, axis) in [
        (0.0, DVec3::X),
        (0.7, DVec3::new(1.0, 1.0, 0.0).normalize()),
    ] {
        let rot = glam::DQuat::from_axis_angle(axis, tilt);
        for i in -m..=m {
            for j in -m..=m {
                let local = DVec3::new(i as f64 * step, j as f64 * step, 0.0);
                if local.length() > r - 2.0 * h {
                    continue;
                }
                let p = centre + rot * local;
                let d = near
                    .iter()
                    .map(|x| x.distance_squared(p))
                    .fold(f64::INFINITY, f64::min)
                    .sqrt();
                worst = worst.max(d);
                checked += 1;
            }
        }
    }
    println!(
        "cut: {checked} points, farthest particle {:.3} spacings",
        worst / h
    );
    assert!(worst <= 2.0 * h, "a hole: {} spacings", worst / h);
}

/// A sphere with three caps missing, facing +x, +y and +z (a capture with openings seen
/// along every axis): where the rays of all three axes pass an opening, parity has no vote
/// it can trust and leaves the voxel empty, with a warning that names the closing mode;
/// the closing mode bridges the opening and fills the volume, and nothing outside the
/// sphere.
#[test]
fn open_capture_fills_with_the_closing_mode() {
    let (r, h) = (0.3f64, 0.01f64);
    let centre = Vec3::splat(0.5);
    let mut cloud = surface_sphere(centre, r as f32, 20_000);
    // Cut away the caps beyond 0.8 r: openings of radius 0.6 r.
    let keep: Vec<usize> = (0..cloud.len())
        .filter(|&i| (cloud.positions[i] - centre).max_element() < 0.8 * r as f32)
        .collect();
    cloud.positions = keep.iter().map(|&i| cloud.positions[i]).collect();
    cloud.scales = keep.iter().map(|&i| cloud.scales[i]).collect();
    cloud.rotations = keep.iter().map(|&i| cloud.rotations[i]).collect();
    cloud.opacities = keep.iter().map(|&i| cloud.opacities[i]).collect();
    let covariances: Vec<_> = (0..cloud.len())
        .map(|i| splatter::render::splats::sym3_from_mat3(cloud.covariance(i)))
        .collect();
    let everywhere = |_: DVec3| true;
    let run = |inside| {
        fill(&FillInput {
            means: &cloud.positions,
            covariances: &covariances,
            opacities: &cloud.opacities,
            spacing: h,
            inside,
            region: &everywhere,
        })
        .unwrap()
    };
    let volume = 4.0 / 3.0 * std::f64::consts::PI * r.powi(3) / h.powi(3);
    let parity = run(InsideTest::Parity);
    // Each opening is 2·0.6·r = 0.36 wide: a closing radius of 0.2 bridges it.
    let closing = run(InsideTest::Closing { radius: 20 });
    println!(
        "open sphere: parity {} fill points, closing {} (volume/h³ = {volume:.0}); parity warnings {:?}",
        parity.points.len(),
        closing.points.len(),
        parity.warnings
    );
    assert!(
        parity.warnings.iter().any(|w| w.contains("\"closing\"")),
        "{:?}",
        parity.warnings
    );
    assert!((closing.points.len() as f64) > 0.75 * volume);
    assert!((closing.points.len() as f64) < volume);
    assert!(closing.points.len() > parity.points.len() + (0.15 * volume) as usize);
    let c = centre.as_dvec3();
    assert!(closing.points.iter().all(|p| p.distance(c) < r + 2.0 * h));
}

/// An open surface (a hemisphere) and degenerate covariances: no panic, a warning naming
/// what was odd, bounded counts.
#[test]
fn adversarial_input_warns_and_stays_bounded() {
    let mut cloud = surface_sphere(Vec3::ZERO, 1.0, 4000);
    let keep: Vec<usize> = (0..cloud.len())
        .filter(|&i| cloud.positions[i].z > 0.0)
        .collect();
    let means: Vec<Vec3> = keep.iter().map(|&i| cloud.positions[i]).collect();
    let mut covs: Vec<[f32; 6]> = keep
        .iter()
        .map(|&i| {
            let m = glam::Mat3::from_quat(cloud.rotations[i])
                * glam::Mat3::from_diagonal(cloud.scales[i]);
            let s = m * m.transpose();
            [
                s.x_axis.x, s.y_axis.x, s.z_axis.x, s.y_axis.y, s.z_axis.y, s.z_axis.z,
            ]
        })
        .collect();
    // Degenerate: NaN, negative definite, huge.
    covs[0] = [f32::NAN; 6];
    covs[1] = [-1.0, 0.0, 0.0, -1.0, 0.0, -1.0];
    covs[2] = [1e30, 0.0, 0.0, 1e30, 0.0, 1e30];
    cloud.opacities.truncate(means.len());
    let opac = vec![0.9f32; means.len()];
    let all = |_: DVec3| true;
    let f = fill(&FillInput {
        means: &means,
        covariances: &covs,
        opacities: &opac,
        spacing: 0.05,
        inside: InsideTest::Parity,
        region: &all,
    })
    .unwrap();
    println!("{:?}\n{:?}", f.stats, f.warnings);
    let text = f.warnings.join("\n");
    assert!(
        text.contains("2 Gaussians with a degenerate covariance"),
        "{text}"
    );
    assert!(text.contains("1 Gaussians wider than"), "{text}");
    assert!(text.contains("surface looks open"), "{text}");
    let voxels: usize = f.stats.dims.iter().product();
    assert!(f.points.len() <= voxels);
    assert_eq!(f.volumes.len(), means.len());

    // Non-finite means and a single point: no panic.
    let means = vec![Vec3::NAN, Vec3::splat(0.2)];
    let covs = vec![[0.0f32; 6]; 2];
    let f = fill(&FillInput {
        means: &means,
        covariances: &covs,
        opacities: &[0.5, 0.5],
        spacing: 0.05,
        inside: InsideTest::Parity,
        region: &all,
    })
    .unwrap();
    assert!(f.points.is_empty());
    assert!(f.warnings.iter().any(|w| w.contains("non-finite position")));
    assert!(f.warnings.iter().any(|w| w.contains("no interior found")));

    // A grid beyond the voxel limit is an error, not an allocation.
    let means = vec![Vec3::ZERO, Vec3::splat(1000.0)];
    let err = fill(&FillInput {
        means: &means,
        covariances: &covs,
        opacities: &[0.5, 0.5],
        spacing: 0.01,
        inside: InsideTest::Parity,
        region: &all,
    })
    .unwrap_err();
    assert!(err.to_string().contains("voxels"), "{err}");
}

/// `select` and `min_opacity`: the selected Gaussians move, the rest of the object is
/// static and comes first.
#[test]
fn selection_splits_an_object_into_static_and_simulated() {
    let dir = tempfile::tempdir().unwrap();
    let mut cloud = surface_sphere(Vec3::splat(0.5), 0.2, 2000);
    for (i, o) in cloud.opacities.iter_mut().enumerate() {
        *o = if i % 4 == 0 { 0.02 } else { 0.9 };
    }
    write_ply(
        &dir.path().join("s.ply"),
        &cloud,
        PlyFormat::BinaryLittleEndian,
    )
    .unwrap();
    let ground = r#"{ "procedural": { "shape": "box", "size": [0.2, 0.2, 0.2], "spacing": 0.05, "color": [0, 1, 0] },
                      "transform": { "translate": [0.5, 0.5, 0.2] } }"#;
    let obj = format!(
        r#"{{ "ply": "s.ply", "physics": {{ {MATERIAL}, "select": {{ "box": {{ "lo": [0, 0, 0.5], "hi": [1, 1, 1] }} }}, "min_opacity": 0.05, "particles": "gaussians" }} }}, {ground}"#
    );
    let s = setup(&scene_text(&obj, 0.02), dir.path()).unwrap();
    let moving = (0..cloud.len())
        .filter(|&i| cloud.positions[i].z >= 0.5 && cloud.opacities[i] >= 0.05)
        .count();
    assert_eq!(s.particles.len(), moving);
    assert_eq!(s.splats.len(), cloud.len() + 64); // the box: 4³ Gaussians
    assert_eq!(s.static_count, cloud.len() - moving + 64);
    let runs: Vec<(usize, PartKind, usize)> =
        s.parts.iter().map(|p| (p.object, p.kind, p.len)).collect();
    assert_eq!(
        runs,
        [
            (0, PartKind::Static, cloud.len() - moving),
            (1, PartKind::Static, 64),
            (0, PartKind::Simulated, moving)
        ]
    );
    assert!(s.particles.x.iter().all(|x| x.z >= 0.5));
    // The same with a sphere: everything within 0.1 of the top pole.
    let obj = format!(
        r#"{{ "ply": "s.ply", "physics": {{ {MATERIAL}, "select": {{ "sphere": {{ "center": [0.5, 0.5, 0.7], "radius": 0.1 }} }}, "particles": "gaussians" }} }}"#
    );
    let s = setup(&scene_text(&obj, 0.02), dir.path()).unwrap();
    let moving = (0..cloud.len())
        .filter(|&i| {
            cloud.positions[i]
                .as_dvec3()
                .distance(DVec3::new(0.5, 0.5, 0.7))
                <= 0.1
        })
        .count();
    assert!(moving > 0 && moving < cloud.len() / 4);
    assert_eq!(s.particles.len(), moving);
}

/// `select: {"label": [...]}` on a capture's segments: exactly the Gaussians of the named
/// segments move, named by number or by string.
#[test]
fn a_label_selection_moves_the_segments_it_names() {
    let dir = tempfile::tempdir().unwrap();
    let mut cloud = surface_sphere(Vec3::splat(0.5), 0.2, 2000);
    // Segment 7 on top, segment 3 below: as a segmentation tool writes them.
    cloud.labels = cloud
        .positions
        .iter()
        .map(|p| u16::from(p.z >= 0.5))
        .collect();
    cloud.label_names = vec!["3".into(), "7".into()];
    write_ply(
        &dir.path().join("s.ply"),
        &cloud,
        PlyFormat::BinaryLittleEndian,
    )
    .unwrap();
    let top = cloud.positions.iter().filter(|p| p.z >= 0.5).count();
    assert!(top > 500 && top < 1500, "{top}");
    // `inspect` lists them, for the user to choose from.
    let report = splatter::splat::inspect::inspect(&cloud).to_string();
    let listed = format!("labels:        3 ({}), 7 ({top})", cloud.len() - top);
    assert!(report.contains(&listed), "{report}");
    // (selection, Gaussians that move, whether they are all above z = 0.5 or all below)
    for (select, moving, above) in [
        ("[7]", top, Some(true)),
        (r#"["7"]"#, top, Some(true)),
        (r#"[3, "7"]"#, cloud.len(), None),
        ("[3]", cloud.len() - top, Some(false)),
    ] {
        let obj = format!(
            r#"{{ "ply": "s.ply", "physics": {{ {MATERIAL}, "select": {{ "label": {select} }}, "particles": "gaussians" }} }}"#
        );
        let s = setup(&scene_text(&obj, 0.02), dir.path()).unwrap();
        assert_eq!(s.particles.len(), moving, "{select}");
        assert_eq!(s.static_count, cloud.len() - moving, "{select}");
        if let Some(above) = above {
            assert!(
                s.particles.x.iter().all(|x| (x.z >= 0.5) == above),
                "{select}"
            );
        }
    }
    // A segment the capture lacks is named with those it has.
    let obj = format!(
        r#"{{ "ply": "s.ply", "physics": {{ {MATERIAL}, "select": {{ "label": [9] }} }} }}"#
    );
    let err = setup(&scene_text(&obj, 0.02), dir.path())
        .err()
        .expect("an unknown segment")
        .to_string();
    assert!(
        err.contains("objects[0].physics.select.label") && err.contains("labels: 3, 7"),
        "{err}"
    );
}

/// `label_property` names the PLY property the segments come from: another than the
/// default `label`/`segment`, and an error naming the file's properties when it lacks it.
#[test]
fn label_property_names_where_a_capture_keeps_its_segments() {
    let dir = tempfile::tempdir().unwrap();
    let cloud = surface_sphere(Vec3::splat(0.5), 0.2, 2000);
    // An ASCII 3DGS PLY with two integer properties: `segment` splits by x, `instance_id`
    // by z, so the two selections below differ.
    let mut ply = format!("ply\nformat ascii 1.0\nelement vertex {}\n", cloud.len());
    for p in [
        "x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1", "scale_2",
        "rot_0", "rot_1", "rot_2", "rot_3",
    ] {
        ply += &format!("property float {p}\n");
    }
    ply += "property int segment\nproperty uchar instance_id\nend_header\n";
    for p in &cloud.positions {
        ply += &format!(
            "{} {} {} 0.5 0.5 0.5 2 -4 -4 -4 1 0 0 0 {} {}\n",
            p.x,
            p.y,
            p.z,
            i32::from(p.x >= 0.5),
            u8::from(p.z >= 0.5) + 4
        );
    }
    std::fs::write(dir.path().join("s.ply"), ply).unwrap();
    let run = |extra: &str| {
        let obj = format!(
            r#"{{ "ply": "s.ply", {extra} "physics": {{ {MATERIAL}, "select": {{ "label": [5] }}, "particles": "gaussians" }} }}"#
        );
        setup(&scene_text(&obj, 0.02), dir.path()).map(|s| s.particles)
    };
    let top = run(r#""label_property": "instance_id","#).unwrap();
    assert_eq!(
        top.len(),
        cloud.positions.iter().filter(|p| p.z >= 0.5).count()
    );
    assert!(top.x.iter().all(|x| x.z >= 0.5));
    // By default the labels are `segment`'s (0 and 1): there is no segment 5.
    let err = match run("") {
        Ok(_) => panic!("no segment 5, accepted"),
        Err(e) => e.to_string(),
    };
    assert!(err.contains("labels: 0, 1"), "{err}");
    let err = match run(r#""label_property": "instance","#) {
        Ok(_) => panic!("no such property, accepted"),
        Err(e) => e.to_string(),
    };
    assert!(
        err.contains("no scalar vertex property `instance`")
            && err.contains("segment, instance_id"),
        "{err}"
    );
}

/// On a procedural asset the selected regions bound the solid: the lattice of the rind
/// alone and that of every other region together are the lattice of the whole melon,
/// split exactly.
#[test]
fn a_label_selection_of_an_asset_fills_only_its_regions() {
    let dir = tempfile::tempdir().unwrap();
    let particles = |select: &str| {
        let obj = format!(
            r#"{{ "procedural": {{ "shape": "watermelon", "size": [0.4, 0.3, 0.3], "spacing": 0.02 }},
                 "transform": {{ "translate": [0.5, 0.5, 0.5] }},
                 "physics": {{ {MATERIAL} {select} }} }}"#
        );
        let s = setup(&scene_text(&obj, 0.04), dir.path()).unwrap();
        (s.particles.len(), s.static_count)
    };
    let (whole, none_static) = particles("");
    let (rind, rind_static) = particles(r#", "select": { "label": ["rind"] }"#);
    let (rest, _) = particles(r#", "select": { "label": ["white_rind", "flesh", "seeds"] }"#);
    assert_eq!(none_static, 0);
    assert!(
        rind > 0 && rest > 0 && rind < whole,
        "{rind} {rest} {whole}"
    );
    assert_eq!(rind + rest, whole);
    assert!(rind_static > 0);
}

/// Scene-file errors name the field.
#[test]
fn bad_select_fill_and_particles_name_the_field() {
    let dir = tempfile::tempdir().unwrap();
    let proc = r#""procedural": { "shape": "sphere", "radius": 0.1, "spacing": 0.03, "color": [1, 0, 0] }, "transform": { "translate": [0.5, 0.5, 0.5] }"#;
    let cases = [
        (
            r#""select": { "box": { "lo": [1, 0, 0], "hi": [0, 1, 1] } }"#,
            "objects[0].physics.select.box",
        ),
        (
            r#""select": { "sphere": { "center": [0, 0, 0], "radius": -1 } }"#,
            "objects[0].physics.select.sphere.radius",
        ),
        (
            r#""select": { "sphere": { "center": [0, 0, 0], "radius": 0.01 } }"#,
            "objects[0].physics.select",
        ),
        (
            r#""select": { "label": [] }"#,
            "objects[0].physics.select.label",
        ),
        (
            r#""select": { "label": ["rind"] }"#,
            "objects[0].physics.select.label",
        ),
        (
            r#""select": { "label": [1.5] }"#,
            "expected a label: a name (\"rind\") or a capture's integer segment id",
        ),
        (r#""min_opacity": 1.5"#, "objects[0].physics.min_opacity"),
        (
            r#""fill": { "spacing": 0.5 }"#,
            "objects[0].physics.fill.spacing",
        ),
        (
            r#""fill": { "spacing": 0.0001 }"#,
            "objects[0].physics.fill.spacing",
        ),
        (
            r#""fill": { "spcing": 0.01 }"#,
            "physics.fill: unknown field `spcing`",
        ),
        (r#""fill": "yes""#, "physics.fill: expected true, false"),
        (
            r#""particles": { "spacing": 0.5 }"#,
            "objects[0].physics.particles.spacing",
        ),
        (
            r#""particles": { "spacing": 0.01, "jitter": 2 }"#,
            "objects[0].physics.particles.jitter",
        ),
        (
            r#""particles": "each""#,
            r#"physics.particles: expected "gaussians" or {"spacing": h}"#,
        ),
        (
            r#""particles": { "spaceing": 0.01 }"#,
            "physics.particles: unknown field `spaceing`",
        ),
    ];
    for (extra, field) in cases {
        let obj = format!(r#"{{ {proc}, "physics": {{ {MATERIAL}, {extra} }} }}"#);
        let err = match setup(&scene_text(&obj, 0.02), dir.path()) {
            Ok(_) => panic!("{extra}: accepted"),
            Err(e) => e.to_string(),
        };
        assert!(err.contains(field), "{extra}: {err}");
        assert!(!err.contains('\n'), "{err}");
    }
    // `fill: false` is no fill.
    let obj = format!(r#"{{ {proc}, "physics": {{ {MATERIAL}, "fill": false }} }}"#);
    let s = setup(&scene_text(&obj, 0.02), dir.path()).unwrap();
    assert!(s.parts.iter().all(|p| p.kind != PartKind::Fill));
}
