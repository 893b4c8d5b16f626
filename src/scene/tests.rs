use super::*;

fn minimal(camera: &str) -> String {
    format!(r#"{{"output": {{"width": 64, "height": 48, "frames": 4}}, "camera": {camera}}}"#)
}

#[test]
fn parse_error_message_has_no_serde_position_suffix() {
    let err = parse("{\n  \"outputs\": 1\n}", "x.json", Path::new(".")).unwrap_err();
    let s = err.to_string();
    assert!(s.starts_with("x.json:2:"), "{s}");
    assert!(!s.contains("at line"), "{s}");
}

#[test]
fn defaults_are_filled_in() {
    let s = parse(
        &minimal(r#"{"fov_y_deg": 40, "path": {"type": "orbit", "radius": 2}}"#),
        "scenes/a.json",
        Path::new("scenes"),
    )
    .unwrap();
    assert_eq!(s.output.fps, 24.0);
    assert_eq!(s.output.background, [0.0; 3]);
    assert_eq!(s.camera.near, 0.01);
    assert_eq!(s.camera.up, [0.0, 0.0, 1.0]);
    assert_eq!(s.output_dir(), Path::new("out/a"));
    let PathSpec::Orbit(o) = &s.camera.path else {
        panic!()
    };
    assert_eq!(o.turns, 1.0);
    assert_eq!(o.target, [0.0; 3]);
}

#[test]
fn half_given_focal_lengths_are_rejected() {
    let err = parse(
        &minimal(r#"{"fx": 100, "path": {"type": "orbit", "radius": 2}}"#),
        "a.json",
        Path::new("."),
    )
    .unwrap_err();
    assert!(err.to_string().contains("camera.fy"), "{err}");
}

#[test]
fn scale_accepts_number_or_triple() {
    let t: TransformSpec = serde_json::from_str(r#"{"scale": 2}"#).unwrap();
    assert_eq!(t.scale.as_vec3(), Vec3::splat(2.0));
    let t: TransformSpec = serde_json::from_str(r#"{"scale": [1, 2, 3]}"#).unwrap();
    assert_eq!(t.scale.as_vec3(), Vec3::new(1.0, 2.0, 3.0));
    let e = serde_json::from_str::<TransformSpec>(r#"{"scale": "big"}"#).unwrap_err();
    assert!(
        e.to_string().contains("a number or an array of 3 numbers"),
        "{e}"
    );
}

#[test]
fn euler_rotation_is_x_then_y_then_z() {
    let t = TransformSpec {
        rotate_deg: [90.0, 0.0, 90.0],
        ..Default::default()
    };
    // +y →(Rx 90°) +z →(Rz 90°) +z
    let v = t.rotation() * Vec3::Y;
    assert!((v - Vec3::Z).length() < 1e-6, "{v}");
    // +z →(Rx 90°) −y →(Rz 90°) +x
    let v = t.rotation() * Vec3::Z;
    assert!((v - Vec3::X).length() < 1e-6, "{v}");
}

#[test]
fn overrides_keep_aspect_and_rescale_focal() {
    let mut s = parse(
        &minimal(r#"{"fx": 50, "fy": 60, "path": {"type": "orbit", "radius": 2}}"#),
        "a.json",
        Path::new("."),
    )
    .unwrap();
    s.with_overrides(Some("elsewhere".into()), Some(128), None)
        .unwrap();
    assert_eq!((s.output.width, s.output.height), (128, 96));
    assert_eq!((s.camera.fx, s.camera.fy), (Some(100.0), Some(120.0)));
    assert_eq!(s.output_dir(), Path::new("elsewhere"));
    assert!(s.with_overrides(None, Some(0), Some(10)).is_err());
}

#[test]
fn one_line_joins_lines() {
    assert_eq!(one_line("a\n  b\n\nc\n"), "a; b; c");
}
