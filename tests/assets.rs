//! Region labels (PLY round trip, shells of the basic shapes, merging in `Splats`) and the
//! procedural assets (`splat::assets`): each fits its bounds, inside test and volume
//! estimate, and its regions sit where they should.

use std::path::Path;
use std::time::Instant;

use glam::{DVec3, Quat, Vec3};
use splatter::render::splats::Splats;
use splatter::scene::simulation::{prepare, PartKind};
use splatter::scene::{self, SceneError};
use splatter::splat::assets::Kind;
use splatter::splat::ply::{read_ply_bytes, write_ply_bytes, PlyError, PlyFormat};
use splatter::splat::procedural::{ProceduralSpec, Shape, Shell};
use splatter::splat::{GaussianCloud, NO_LABEL};

/// A small cloud labelled `rind`, `flesh`, `seeds` in turn, with a fourth name `spare`
/// that no Gaussian uses (it must survive the round trip too).
fn labelled_cloud(n: usize) -> GaussianCloud {
    GaussianCloud {
        positions: (0..n).map(|i| Vec3::new(i as f32, 0.5, -1.0)).collect(),
        scales: vec![Vec3::splat(0.1); n],
        rotations: vec![Quat::IDENTITY; n],
        opacities: vec![0.5; n],
        sh_degree: 0,
        sh: vec![0.25; 3 * n],
        labels: (0..n).map(|i| [0, 1, 2][i % 3]).collect(),
        label_names: ["rind", "flesh", "seeds", "spare"]
            .map(String::from)
            .to_vec(),
        ..Default::default()
    }
}

#[test]
fn ply_labels_round_trip_with_names() {
    let cloud = labelled_cloud(10);
    for format in [PlyFormat::BinaryLittleEndian, PlyFormat::Ascii] {
        let bytes = write_ply_bytes(&cloud, format, "mem.ply").unwrap();
        let (back, _) = read_ply_bytes(&bytes, "mem.ply").unwrap();
        assert_eq!(back.label_names, cloud.label_names, "{format:?}");
        assert_eq!(back.labels, cloud.labels, "{format:?}");
        assert_eq!(back.positions, cloud.positions);
        assert_eq!(back.label_name(4), Some("flesh"));
    }
}

#[test]
fn ply_without_labels_has_none() {
    let mut cloud = labelled_cloud(4);
    cloud.labels.clear();
    cloud.label_names.clear();
    let bytes = write_ply_bytes(&cloud, PlyFormat::BinaryLittleEndian, "m").unwrap();
    assert!(!String::from_utf8_lossy(&bytes[..400]).contains("label"));
    let (back, _) = read_ply_bytes(&bytes, "m").unwrap();
    assert!(back.labels.is_empty() && back.label_names.is_empty());
}

/// An ASCII PLY with an integer `segment` property and no name comments.
fn segment_ply(values: &[&str]) -> Vec<u8> {
    let mut s = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n\
         property float f_dc_0\nproperty float f_dc_1\nproperty float f_dc_2\n\
         property float opacity\nproperty float scale_0\nproperty float scale_1\n\
         property float scale_2\nproperty float rot_0\nproperty float rot_1\n\
         property float rot_2\nproperty float rot_3\nproperty int segment\nend_header\n",
        values.len()
    );
    for (i, v) in values.iter().enumerate() {
        s.push_str(&format!("{i} 0 0 0.1 0.2 0.3 0 -2 -2 -2 1 0 0 0 {v}\n"));
    }
    s.into_bytes()
}

#[test]
fn ply_segment_numbers_become_names() {
    let (c, _) = read_ply_bytes(&segment_ply(&["7", "-1", "7", "3"]), "seg.ply").unwrap();
    assert_eq!(c.label_names, ["-1", "3", "7"]);
    let names: Vec<_> = (0..4).map(|i| c.label_name(i).unwrap()).collect();
    assert_eq!(names, ["7", "-1", "7", "3"]);
    c.check_consistent().unwrap();
}

#[test]
fn ply_fractional_label_is_refused() {
    let err = read_ply_bytes(&segment_ply(&["1", "2.5"]), "seg.ply").unwrap_err();
    assert!(matches!(err, PlyError::Invalid { .. }), "{err}");
    let msg = err.to_string();
    assert!(msg.contains("2.5") && msg.contains("label"), "{msg}");
}

#[test]
fn shells_are_labelled_outermost_first() {
    let spec = ProceduralSpec {
        shape: Shape::Sphere { radius: 1.0 },
        spacing: 0.1,
        color: Some([0.5; 3]),
        shells: vec![
            Shell {
                depth: 0.2,
                color: [1.0, 0.0, 0.0],
            },
            Shell {
                depth: 0.2,
                color: [0.0, 1.0, 0.0],
            },
        ],
        checker: None,
        opacity: 0.9,
        jitter: 0.25,
        seed: 1,
    };
    let c = spec.generate().unwrap();
    c.check_consistent().unwrap();
    assert_eq!(c.label_names, ["shell0", "shell1", "core"]);
    for i in 0..c.len() {
        let depth = 1.0 - c.positions[i].length();
        let want = if depth < 0.2 {
            "shell0"
        } else if depth < 0.4 {
            "shell1"
        } else {
            "core"
        };
        assert_eq!(c.label_name(i), Some(want), "depth {depth}");
    }
}

#[test]
fn appending_splats_merges_label_names() {
    let a = labelled_cloud(3);
    let mut b = labelled_cloud(3);
    b.label_names = ["seeds", "core", "rind"].map(String::from).to_vec();
    let plain = GaussianCloud {
        labels: Vec::new(),
        label_names: Vec::new(),
        ..labelled_cloud(2)
    };
    let mut s = Splats::from_cloud(&plain, glam::Mat3::IDENTITY, Vec3::ZERO);
    s.append(Splats::from_cloud(&a, glam::Mat3::IDENTITY, Vec3::ZERO));
    s.append(Splats::from_cloud(&b, glam::Mat3::IDENTITY, Vec3::ZERO));
    s.append(Splats::from_cloud(&plain, glam::Mat3::IDENTITY, Vec3::ZERO));
    assert_eq!(s.labels.len(), s.len());
    let names: Vec<_> = (0..s.len()).map(|i| s.label_name(i)).collect();
    let want = [
        None,
        None,
        Some("rind"),
        Some("flesh"),
        Some("seeds"),
        Some("seeds"),
        Some("core"),
        Some("rind"),
        None,
        None,
    ];
    assert_eq!(names, want);
    assert_eq!(s.labels[0], NO_LABEL);
}

/// The scene-file form of an asset, parsed as a scene would.
fn asset_spec(kind: Kind, extra: &str) -> ProceduralSpec {
    let json = format!(
        r#"{{"shape": "{}", "spacing": 1, {extra} "seed": 7}}"#,
        kind.name()
    );
    serde_json::from_str(&json).unwrap_or_else(|e| panic!("{json}: {e}"))
}

/// An asset at its default size with `per_axis` lattice cells along its longest side.
fn default_asset(kind: Kind, per_axis: f32) -> ProceduralSpec {
    let mut spec = asset_spec(kind, "");
    spec.spacing = kind.default_size().iter().cloned().fold(0.0, f32::max) / per_axis;
    spec
}

/// Every asset: a count within its estimate (and not far below), every Gaussian inside
/// the bounds and the exact inside test, labels named by the asset's regions, each region
/// present, and each Gaussian labelled and coloured as the region function says there.
#[test]
fn every_asset_fits_its_bounds_inside_test_and_estimate() {
    for kind in Kind::ALL {
        let spec = default_asset(kind, 48.0);
        let t0 = Instant::now();
        let cloud = spec.generate().unwrap();
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        cloud.check_consistent().unwrap();
        let n = cloud.len();
        let estimate = spec.estimated_count();
        println!(
            "{:<12} {n:>7} Gaussians (estimate {estimate:>7.0}, {:.0} %), {ms:.1} ms",
            kind.name(),
            100.0 * n as f64 / estimate
        );
        assert!(n as f64 <= estimate, "{kind:?}: {n} > estimate {estimate}");
        assert!(
            n as f64 >= 0.25 * estimate,
            "{kind:?}: {n} ≪ estimate {estimate}"
        );
        let (lo, hi) = spec.bounds();
        let names: Vec<&str> = cloud.label_names.iter().map(String::as_str).collect();
        assert_eq!(names, kind.regions(), "{kind:?}");
        let mut seen = vec![0usize; names.len()];
        let mut colour_misses = 0;
        for (i, x) in cloud.positions.iter().enumerate() {
            let p = x.as_dvec3().to_array();
            assert!(
                (0..3).all(|a| p[a] >= lo[a] - 1e-6 && p[a] <= hi[a] + 1e-6),
                "{kind:?}: {x} outside the bounds"
            );
            let (label, rgb) = spec
                .region_at(p)
                .unwrap_or_else(|| panic!("{kind:?}: Gaussian {i} at {x} outside the solid"));
            assert!(spec.contains(p));
            assert_eq!(cloud.labels[i], label, "{kind:?} at {x}");
            // Patterns are hashed on fine cells, so rounding the position to f32 may
            // move a Gaussian into the next cell: compare with a tolerance, count misses.
            let dc = splatter::splat::sh::rgb_to_dc(rgb);
            let close = (0..3).all(|c| (cloud.sh_of(i)[c] - dc[c]).abs() < 1e-3);
            colour_misses += usize::from(!close);
            seen[usize::from(label)] += 1;
        }
        for (r, count) in seen.iter().enumerate() {
            assert!(*count > 0, "{kind:?}: no Gaussian in region {}", names[r]);
        }
        assert!(
            colour_misses * 200 <= n,
            "{kind:?}: {colour_misses} colours differ"
        );
    }
}

/// The same spec gives the same cloud; another size scales the asset.
#[test]
fn assets_are_deterministic_and_scale_with_size() {
    let a = default_asset(Kind::Pumpkin, 24.0).generate().unwrap();
    let b = default_asset(Kind::Pumpkin, 24.0).generate().unwrap();
    assert_eq!(a, b);
    let mut big = default_asset(Kind::Pumpkin, 24.0);
    big.shape = serde_json::from_str(r#"{"shape": "pumpkin", "size": [0.6, 0.6, 0.48]}"#).unwrap();
    big.spacing *= 2.0;
    let c = big.generate().unwrap();
    let rel = (c.len() as f64 - a.len() as f64).abs() / a.len() as f64;
    assert!(rel < 0.05, "{} vs {}", c.len(), a.len());
    assert_eq!(
        big.bounds().1,
        [0.3, 0.3, 0.24].map(|v: f64| v as f32 as f64)
    );
}

/// The watermelon's layers: rind outermost (a Gaussian whose point 0.9 rind depths further
/// out along its ray from the centre is outside the fruit is rind), white rind next, and
/// every seed surrounded by flesh or seeds.
#[test]
fn watermelon_layers_are_ordered_and_seeds_sit_in_flesh() {
    let spec = default_asset(Kind::Watermelon, 96.0);
    let cloud = spec.generate().unwrap();
    let radius = 0.11; // the smaller half extent of the default size
    let rind = 0.07 * radius;
    let id = |name: &str| cloud.label_id(name).unwrap();
    let (rind_id, white, flesh, seeds) = (id("rind"), id("white_rind"), id("flesh"), id("seeds"));
    let mut counts = [0usize; 4];
    for (i, x) in cloud.positions.iter().enumerate() {
        let p = x.as_dvec3();
        let l = cloud.labels[i];
        counts[usize::from(l)] += 1;
        let out = |d: f64| spec.contains((p + p.normalize() * d).to_array());
        if !out(0.9 * rind) {
            assert_eq!(l, rind_id, "near the surface at {p}");
        }
        if l == flesh || l == seeds {
            assert!(
                out(0.11 * radius),
                "flesh/seeds too close to the surface at {p}"
            );
        }
        if l == white {
            assert!(out(0.9 * rind) && !out(0.13 * radius), "white rind at {p}");
        }
        if l == seeds {
            for d in DVec3::AXES.iter().flat_map(|a| [*a, -*a]) {
                let q = p + d * 0.1 * radius;
                let around = spec.region_at(q.to_array()).map(|r| r.0);
                assert!(
                    around == Some(flesh) || around == Some(seeds),
                    "seed at {p}: {around:?} at {q}"
                );
            }
        }
    }
    println!("watermelon regions (rind, white, flesh, seeds): {counts:?}");
    assert!(counts[usize::from(seeds)] >= 50, "{counts:?}");
}

/// Interior fill of a simulated asset takes the region at each fill point: a watermelon's
/// fill is flesh and seeds (and white rind near the surface), never the rind colour of its
/// nearest surface Gaussian; labels follow into `SimulationSetup::part_labels`.
#[test]
fn asset_fill_takes_the_region_inside() {
    let text = r#"{
  "output": { "width": 32, "height": 24, "frames": 1 },
  "camera": { "fov_y_deg": 40, "path": { "type": "orbit", "target": [0.5, 0.5, 0.5], "radius": 2 } },
  "simulation": { "dx": 0.02, "domain": { "lo": [0, 0, 0], "hi": [1, 1, 1] } },
  "objects": [{ "procedural": { "shape": "watermelon", "spacing": 0.02 },
                "transform": { "translate": [0.5, 0.5, 0.5], "rotate_deg": [0, 0, 30] },
                "physics": { "material": { "model": "fixed_corotated", "E": 1000, "nu": 0.3, "density": 2 },
                             "fill": true } }]
}"#;
    let scene = scene::parse(text, "test.json", Path::new(".")).unwrap();
    let (splats, report) = scene.build_splats().unwrap();
    let s = prepare(&scene, splats, &report).unwrap().unwrap();
    let fill = s.parts.iter().find(|p| p.kind == PartKind::Fill).unwrap();
    assert!(fill.len > 100, "{} fill particles", fill.len);
    let mut tally = std::collections::BTreeMap::new();
    for (j, label) in s.part_labels(fill).enumerate() {
        let label = label.expect("labelled");
        *tally.entry(label).or_insert(0usize) += 1;
        if label == "flesh" {
            let g = fill.start + j;
            let red = s.splats.sh[g * s.splats.sh_stride()];
            let green = s.splats.sh[g * s.splats.sh_stride() + 1];
            assert!(red > green, "flesh fill Gaussian {g} is not red");
        }
    }
    println!("fill regions: {tally:?}");
    assert!(
        tally.get("flesh").copied().unwrap_or(0) > fill.len / 2,
        "{tally:?}"
    );
    let surface = s
        .parts
        .iter()
        .find(|p| p.kind == PartKind::Simulated)
        .unwrap();
    assert!(s.part_labels(surface).any(|l| l == Some("rind")));
}

/// Bad asset parameters are refused naming the field, in the scene's terms.
#[test]
fn bad_asset_parameters_name_the_field() {
    let scene_with = |procedural: &str| {
        format!(
            r#"{{ "output": {{ "width": 32, "height": 24, "frames": 1 }},
  "camera": {{ "fov_y_deg": 40, "path": {{ "type": "orbit", "target": [0, 0, 0], "radius": 2 }} }},
  "objects": [{{ "procedural": {procedural} }}] }}"#
        )
    };
    let cases = [
        (
            r#"{"shape": "pumpkin", "size": [0.3, -1, 0.2], "spacing": 0.01}"#,
            "objects[0].procedural.size",
        ),
        (
            r#"{"shape": "kiwi", "size": [0.3, 0.2, 0.2], "spacing": 0}"#,
            "objects[0].procedural.spacing",
        ),
        (
            r#"{"shape": "jelly", "spacing": 0.01, "color": [2, 0, 0]}"#,
            "objects[0].procedural.color",
        ),
        (
            r#"{"shape": "watermelon", "spacing": 0.01, "shells": [{"depth": 0.01, "color": [1, 0, 0]}]}"#,
            "objects[0].procedural.shells",
        ),
        (
            r#"{"shape": "sphere", "radius": 0.2, "spacing": 0.01}"#,
            "objects[0].procedural.color",
        ),
    ];
    for (procedural, field) in cases {
        let err = scene::parse(&scene_with(procedural), "s.json", Path::new("."))
            .err()
            .unwrap_or_else(|| panic!("{procedural} accepted"));
        let msg = err.to_string();
        assert!(msg.contains(field), "{procedural}: {msg}");
        assert!(matches!(err, SceneError::Invalid { .. }), "{msg}");
    }
    // A field the asset does not have is refused by name.
    let err = scene::parse(
        &scene_with(r#"{"shape": "table", "radius": 1, "spacing": 0.01}"#),
        "s.json",
        Path::new("."),
    )
    .err()
    .unwrap();
    assert!(err.to_string().contains("radius"), "{err}");
}

/// A scene's `color` repaints the asset's first region only.
#[test]
fn color_repaints_the_first_region() {
    let spec = asset_spec(Kind::Watermelon, r#""color": [0, 0, 1], "#);
    let mut spec = spec;
    spec.spacing = 0.01;
    let cloud = spec.generate().unwrap();
    let blue = splatter::splat::sh::rgb_to_dc([0.0, 0.0, 1.0]);
    for i in 0..cloud.len() {
        let is_blue = cloud.sh_of(i)[..3] == blue;
        assert_eq!(is_blue, cloud.label_name(i) == Some("rind"), "Gaussian {i}");
    }
}

/// An asset's depth below its surface (used by `physics.regions` shells): on the ball,
/// within 25 % above the exact r − |p| (26 escape directions) and never below it.
#[test]
fn asset_depth_approximates_the_distance_to_the_surface() {
    let spec = asset_spec(Kind::Projectile, r#""size": [0.2, 0.2, 0.2], "#);
    for i in 0..200 {
        let f = |k: u32| ((i * 7919 + k * 104_729) % 1000) as f64 / 1000.0 - 0.5;
        let p = DVec3::new(f(1), f(2), f(3)) * 0.2;
        let exact = 0.1 - p.length();
        let d = spec.depth(p.to_array());
        if exact <= 0.0 {
            assert_eq!(d, 0.0, "outside at {p}");
        } else {
            assert!(
                d >= exact - 1e-5 && d <= 1.25 * exact + 1e-5,
                "{d} vs {exact} at {p}"
            );
        }
    }
}
