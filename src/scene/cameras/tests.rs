use std::path::Path;

use glam::{Mat3, Vec3};

use super::*;

/// A COLMAP text model whose one image is rotated a quarter turn about the world's z: the
/// quaternion (cos 45°, 0, 0, sin 45°) is R_wc, so the camera's x axis in the world is
/// R_wcᵀ x = −y... and its centre −R_wcᵀ t. Comments, a blank 2D-points line and a
/// SIMPLE_PINHOLE camera (one focal length) are read as COLMAP writes them.
#[test]
fn a_colmap_text_model_gives_centre_axes_and_focal() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("cameras.txt"),
        "# Camera list\n# CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n3 SIMPLE_PINHOLE 640 480 500 320 240\n",
    )
    .unwrap();
    let h = std::f64::consts::FRAC_1_SQRT_2;
    std::fs::write(
        d.join("images.txt"),
        format!(
            "# Image list\n7 {h} 0 0 {h} 1 2 3 3 b.png\n\n5 1 0 0 0 0 0 0 3 a.png\n1.0 2.0 -1\n"
        ),
    )
    .unwrap();
    let file = read_any(&d.join("images.txt")).unwrap();
    let names: Vec<&str> = file.cameras.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["a.png", "b.png"], "name order");
    let c = &file.cameras[1];
    // R_wc rotates world x to camera y: the camera's x axis is the world's −y.
    assert!(
        c.rotation
            .x_axis
            .abs_diff_eq(Vec3::new(0.0, -1.0, 0.0), 1e-6),
        "{}",
        c.rotation
    );
    assert!(c.rotation.z_axis.abs_diff_eq(Vec3::Z, 1e-6));
    // centre = −R_wcᵀ t with t = (1, 2, 3): R_wcᵀ (1, 2, 3) = (2, −1, 3).
    assert!(
        c.position.abs_diff_eq(Vec3::new(-2.0, 1.0, -3.0), 1e-6),
        "{}",
        c.position
    );
    assert_eq!((c.fx, c.fy, c.width, c.height), (500.0, 500.0, 640, 480));
    assert!(file.warnings.is_empty(), "{:?}", file.warnings);
    assert_eq!(CameraFormat::of(d).unwrap(), CameraFormat::Colmap);
    assert!(colmap::model_dir(&d.join("cameras.txt")).is_some());
    assert!(colmap::model_dir(Path::new("/nonexistent/cameras.txt")).is_none());
}

/// Distortion and an off-centre principal point are ignored with a warning each, once per
/// camera.
#[test]
fn colmap_distortion_is_ignored_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("cameras.txt"),
        "1 OPENCV 100 80 90 91 60 40 0.1 0.01 0 0\n",
    )
    .unwrap();
    std::fs::write(
        d.join("images.txt"),
        "1 1 0 0 0 0 0 0 1 a.png\n\n2 1 0 0 0 0 0 1 1 b.png\n\n",
    )
    .unwrap();
    let file = read_any(d).unwrap();
    assert_eq!(file.cameras.len(), 2);
    assert_eq!((file.cameras[0].fx, file.cameras[0].fy), (90.0, 91.0));
    assert_eq!(file.warnings.len(), 2, "{:?}", file.warnings);
    assert!(file.warnings[0].contains("OPENCV") && file.warnings[0].contains("ignored"));
    assert!(file.warnings[1].contains("principal point"));
}

/// OpenGL ↔ OpenCV camera axes: y and z turn round, x stays; twice is nothing.
#[test]
fn gl_and_cv_axes_differ_by_a_half_turn_about_x() {
    let r = Mat3::from_rotation_y(0.3) * Mat3::from_rotation_x(-0.7);
    let cv = flip_gl_cv(r);
    assert_eq!(cv.x_axis, r.x_axis);
    assert_eq!(cv.y_axis, -r.y_axis);
    assert_eq!(cv.z_axis, -r.z_axis);
    assert_eq!(flip_gl_cv(cv), r);
    assert!((cv.determinant() - 1.0).abs() < 1e-6);
}

/// Missing sizes follow each camera's aspect ratio; focal lengths scale with the size.
#[test]
fn cameras_at_an_output_size_keep_their_field_of_view() {
    let c = FileCamera {
        name: String::new(),
        position: Vec3::ZERO,
        rotation: Mat3::IDENTITY,
        fx: 1000.0,
        fy: 1000.0,
        width: 1920,
        height: 1080,
    };
    let at = |w, h| at_size("t", std::slice::from_ref(&c), w, h).unwrap()[0];
    let half = at(Some(960), None);
    assert_eq!(
        (half.width, half.height, half.fx, half.fy),
        (960, 540, 500.0, 500.0)
    );
    assert_eq!(at(None, Some(108)).width, 192);
    assert_eq!(at(None, None).fx, 1000.0);
    assert!(at_size("t", &[c], Some(0), None).is_err());
}
