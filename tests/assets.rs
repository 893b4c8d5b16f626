//! Region labels (PLY round trip, shells of the basic shapes, merging in `Splats`) and the
//! procedural assets (`splat::assets`): each fits its bounds, inside test and volume
//! estimate, and its regions sit where they should.

use glam::{Quat, Vec3};
use splatter::render::splats::Splats;
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
        color: [0.5; 3],
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
