//! The scene file: parsing, validation, camera paths, object transforms.

use std::path::{Path, PathBuf};

use glam::{Mat3, Quat, Vec3};
use splatter::render::camera::Camera;
use splatter::render::splats::mat3_from_sym3;
use splatter::render::Splats;
use splatter::scene::{self, CameraPath, Scene, SceneError, TransformSpec};
use splatter::splat::GaussianCloud;

/// A scene with the given `camera` object and no objects.
fn with_camera(camera: &str) -> String {
    format!(r#"{{"output": {{"width": 64, "height": 48, "frames": 10}}, "camera": {camera}}}"#)
}

fn parse(text: &str) -> Result<Scene, SceneError> {
    scene::parse(text, "test.json", Path::new("."))
}

fn parse_in(text: &str, dir: &Path) -> Result<Scene, SceneError> {
    scene::parse(text, "test.json", dir)
}

fn expect_invalid(text: &str, field: &str) -> String {
    match parse(text) {
        Err(e @ SceneError::Invalid { .. }) => {
            let s = e.to_string();
            assert!(s.contains(field), "error should name {field}: {s}");
            assert!(
                s.starts_with("test.json: "),
                "error should name the file: {s}"
            );
            assert!(!s.contains('\n'), "one line: {s}");
            s
        }
        other => panic!("expected an Invalid error naming {field}, got {other:?}"),
    }
}

fn assert_close(a: Vec3, b: Vec3, tol: f32, what: &str) {
    assert!((a - b).length() <= tol, "{what}: {a} vs {b}");
}

fn assert_orthonormal(r: Mat3, what: &str) {
    let err = (r.transpose() * r - Mat3::IDENTITY)
        .to_cols_array()
        .iter()
        .fold(0.0f32, |m, x| m.max(x.abs()));
    assert!(err < 1e-5, "{what}: not orthonormal ({err}): {r:?}");
    assert!(
        (r.determinant() - 1.0).abs() < 1e-5,
        "{what}: det {}",
        r.determinant()
    );
}

/// Pixel coordinates of a world point.
fn project(c: &Camera, p: Vec3) -> (f32, f32, f32) {
    let q = c.world_to_camera() * (p - c.position);
    let (cx, cy) = c.principal_point();
    (c.fx * q.x / q.z + cx, c.fy * q.y / q.z + cy, q.z)
}

// ---------------------------------------------------------------------------------------------
// Parsing and validation
// ---------------------------------------------------------------------------------------------

#[test]
fn unknown_keys_are_rejected_with_line_and_column() {
    let text = "{\n  \"output\": {\"width\": 64, \"height\": 48, \"frames\": 1},\n  \"camera\": {\n    \"fovy\": 40,\n    \"path\": {\"type\": \"orbit\", \"radius\": 2}\n  }\n}\n";
    let err = parse(text).unwrap_err();
    let SceneError::Parse {
        line,
        column,
        ref message,
        ..
    } = err
    else {
        panic!("{err:?}")
    };
    assert_eq!(line, 4, "{err}");
    assert!(column > 0);
    assert!(message.contains("unknown field `fovy`"), "{message}");
    assert!(
        message.contains("fov_y_deg"),
        "lists the expected keys: {message}"
    );
    let s = err.to_string();
    assert!(s.starts_with("test.json:4:"), "{s}");
    assert!(!s.contains('\n'));

    // Top level and inside the path too.
    let err = parse(&with_camera(
        r#"{"fov_y_deg": 40, "path": {"type": "orbit", "radius": 2}}, "extra": 1"#,
    ))
    .unwrap_err();
    assert!(
        matches!(err, SceneError::Parse { .. }) && err.to_string().contains("extra"),
        "{err}"
    );
    let err = parse(&with_camera(
        r#"{"fov_y_deg": 40, "path": {"type": "orbit", "radius": 2, "radiuss": 3}}"#,
    ))
    .unwrap_err();
    assert!(err.to_string().contains("radiuss"), "{err}");
    let err = parse(&with_camera(
        r#"{"fov_y_deg": 40, "path": {"type": "spiral", "radius": 2}}"#,
    ))
    .unwrap_err();
    assert!(err.to_string().contains("spiral"), "{err}");
}

#[test]
fn malformed_json_reports_position() {
    let err = parse("{\n  \"output\": {\"width\": 64,,}\n}").unwrap_err();
    let SceneError::Parse { line, .. } = err else {
        panic!("{err:?}")
    };
    assert_eq!(line, 2);
}

#[test]
fn fov_out_of_range_is_rejected() {
    for fov in ["0", "-10", "180", "200", "1e39"] {
        let s = expect_invalid(
            &with_camera(&format!(
                r#"{{"fov_y_deg": {fov}, "path": {{"type": "orbit", "radius": 2}}}}"#
            )),
            "camera.fov_y_deg",
        );
        assert!(s.contains("(0, 180)"), "{s}");
    }
}

#[test]
fn zero_image_size_is_rejected() {
    let camera = r#"{"fov_y_deg": 40, "path": {"type": "orbit", "radius": 2}}"#;
    let s = expect_invalid(
        &format!(r#"{{"output": {{"width": 0, "height": 48, "frames": 1}}, "camera": {camera}}}"#),
        "output.width",
    );
    assert!(s.contains("= 0"), "{s}");
    expect_invalid(
        &format!(r#"{{"output": {{"width": 64, "height": 0, "frames": 1}}, "camera": {camera}}}"#),
        "output.height",
    );
    expect_invalid(
        &format!(
            r#"{{"output": {{"width": 64, "height": 20000, "frames": 1}}, "camera": {camera}}}"#
        ),
        "output.height",
    );
    expect_invalid(
        &format!(r#"{{"output": {{"width": 64, "height": 48, "frames": 0}}, "camera": {camera}}}"#),
        "output.frames",
    );
    expect_invalid(
        &format!(
            r#"{{"output": {{"width": 64, "height": 48, "frames": 1, "fps": 0}}, "camera": {camera}}}"#
        ),
        "output.fps",
    );
    expect_invalid(
        &format!(
            r#"{{"output": {{"width": 64, "height": 48, "frames": 1, "background": [0, 2, 0]}}, "camera": {camera}}}"#
        ),
        "output.background",
    );
    // A negative size is a type error from the parser.
    let err = parse(&format!(
        r#"{{"output": {{"width": -5, "height": 48, "frames": 1}}, "camera": {camera}}}"#
    ))
    .unwrap_err();
    assert!(matches!(err, SceneError::Parse { .. }), "{err}");
}

#[test]
fn fov_and_fx_together_are_rejected() {
    let s = expect_invalid(
        &with_camera(
            r#"{"fov_y_deg": 40, "fx": 50, "fy": 50, "path": {"type": "orbit", "radius": 2}}"#,
        ),
        "camera.fov_y_deg",
    );
    assert!(s.contains("not both"), "{s}");
    expect_invalid(
        &with_camera(r#"{"path": {"type": "orbit", "radius": 2}}"#),
        "camera",
    );
    expect_invalid(
        &with_camera(r#"{"fx": -1, "fy": 50, "path": {"type": "orbit", "radius": 2}}"#),
        "camera.fx",
    );
}

#[test]
fn other_camera_fields_are_checked() {
    expect_invalid(
        &with_camera(r#"{"fov_y_deg": 40, "near": 0, "path": {"type": "orbit", "radius": 2}}"#),
        "camera.near",
    );
    expect_invalid(
        &with_camera(
            r#"{"fov_y_deg": 40, "up": [0, 0, 0], "path": {"type": "orbit", "radius": 2}}"#,
        ),
        "camera.up",
    );
    expect_invalid(
        &with_camera(r#"{"fov_y_deg": 40, "path": {"type": "orbit", "radius": 0}}"#),
        "camera.path.radius",
    );
    expect_invalid(
        &with_camera(
            r#"{"fov_y_deg": 40, "path": {"type": "orbit", "radius": 1, "target": [0, 1e39, 0]}}"#,
        ),
        "camera.path.target",
    );
}

#[test]
fn keyframe_problems_are_named() {
    let kf = |keys: &str| {
        with_camera(&format!(
            r#"{{"fov_y_deg": 40, "path": {{"type": "keyframes", "keyframes": [{keys}]}}}}"#
        ))
    };
    expect_invalid(&kf(""), "camera.path.keyframes");
    let s = expect_invalid(
        &kf(
            r#"{"time": 0, "position": [1, 0, 0], "look_at": [0, 0, 0]}, {"time": 0, "position": [2, 0, 0], "look_at": [0, 0, 0]}"#,
        ),
        "camera.path.keyframes[1].time",
    );
    assert!(s.contains("strictly increase"), "{s}");
    expect_invalid(
        &kf(r#"{"time": 0, "position": [1, 0, 0]}"#),
        "camera.path.keyframes[0]",
    );
    expect_invalid(
        &kf(
            r#"{"time": 0, "position": [1, 0, 0], "look_at": [0, 0, 0], "rotation": [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}"#,
        ),
        "camera.path.keyframes[0].rotation",
    );
    expect_invalid(
        &kf(r#"{"time": 0, "position": [1, 0, 0], "rotation": [[2, 0, 0], [0, 1, 0], [0, 0, 1]]}"#),
        "rotation",
    );
    // A reflection is not a rotation.
    expect_invalid(
        &kf(
            r#"{"time": 0, "position": [1, 0, 0], "rotation": [[-1, 0, 0], [0, 1, 0], [0, 0, 1]]}"#,
        ),
        "rotation",
    );
    expect_invalid(
        &kf(r#"{"time": 0, "position": [1, 0, 0], "look_at": [1, 0, 0]}"#),
        "look_at",
    );
}

#[test]
fn object_problems_are_named() {
    let obj = |o: &str| {
        format!(
            r#"{{"output": {{"width": 64, "height": 48, "frames": 1}},
                "camera": {{"fov_y_deg": 40, "path": {{"type": "orbit", "radius": 2}}}},
                "objects": [{o}]}}"#
        )
    };
    expect_invalid(&obj(r#"{"name": "nothing"}"#), "objects[0]");
    let s = expect_invalid(&obj(r#"{"ply": "does/not/exist.ply"}"#), "objects[0].ply");
    assert!(s.contains("not found"), "{s}");
    expect_invalid(
        &obj(
            r#"{"ply": "a.ply", "procedural": {"shape": "sphere", "radius": 1, "spacing": 0.1, "color": [1, 1, 1]}}"#,
        ),
        "objects[0].procedural",
    );
    let good =
        r#""procedural": {"shape": "sphere", "radius": 1, "spacing": 0.1, "color": [1, 1, 1]}"#;
    expect_invalid(
        &obj(&format!(r#"{{{good}, "transform": {{"scale": 0}}}}"#)),
        "objects[0].transform.scale",
    );
    expect_invalid(
        &obj(&format!(
            r#"{{{good}, "transform": {{"scale": [1, -1, 1]}}}}"#
        )),
        "objects[0].transform.scale",
    );
    let err = parse(&obj(&format!(
        r#"{{{good}, "transform": {{"scale": "x"}}}}"#
    )))
    .unwrap_err();
    assert!(
        err.to_string()
            .contains("a number or an array of 3 numbers"),
        "{err}"
    );
    let err = parse(&obj(&format!(r#"{{{good}, "colour": [1, 0, 0]}}"#))).unwrap_err();
    assert!(err.to_string().contains("colour"), "{err}");
}

#[test]
fn procedural_problems_carry_the_object_path() {
    let text = r#"{"output": {"width": 64, "height": 48, "frames": 1},
        "camera": {"fov_y_deg": 40, "path": {"type": "orbit", "radius": 2}},
        "objects": [{"procedural": {"shape": "sphere", "radius": -1, "spacing": 0.1, "color": [1, 1, 1]}}]}"#;
    let s = expect_invalid(text, "objects[0].procedural");
    assert!(s.contains("-1"), "{s}");
}

#[test]
fn default_scene_parses_and_validates() {
    let s = scene::default_scene();
    s.validate().unwrap();
    assert_eq!(
        (s.output.width, s.output.height, s.frame_count()),
        (640, 360, 24)
    );
    assert_eq!(s.output_dir(), Path::new("out/default"));
    assert!(s.objects.len() >= 4);
    // A dynamic scene under moving lights: something breaks, something wobbles.
    assert!(s.simulation.is_some() && s.lighting.is_some());
    assert_eq!(s.objects.iter().filter(|o| o.physics.is_some()).count(), 2);
    let path = s.camera_path().unwrap();
    for f in 0..s.frame_count() {
        let c = path.camera(f);
        assert_eq!((c.width, c.height), (640, 360));
        assert_orthonormal(c.rotation, "default scene camera");
    }
    // Round trip through serde.
    let text = serde_json::to_string(&s).unwrap();
    let again = parse(&text).unwrap();
    assert_eq!(again.objects.len(), s.objects.len());
}

#[test]
fn default_scene_builds_a_modest_number_of_gaussians() {
    let s = scene::default_scene();
    let (splats, report) = s.build_splats().unwrap();
    assert_eq!(splats.len(), report.total_gaussians());
    assert_eq!(report.objects.len(), s.objects.len());
    assert!(
        (10_000..=200_000).contains(&splats.len()),
        "{} Gaussians",
        splats.len()
    );
    assert!(report.warnings().is_empty());
    assert_eq!(report.objects[2].name, "watermelon");
}

#[test]
fn demo_scenes_load() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "json") {
            let s = scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(s.base_dir, dir);
            s.camera_path().unwrap_or_else(|e| panic!("{e}"));
            n += 1;
        }
    }
    assert!(n >= 2, "default.json and keyframes.json");
    let s = scene::load(&dir.join("keyframes.json")).unwrap();
    assert_eq!(s.name, "keyframes");
    assert_eq!(s.output_dir(), Path::new("out/keyframes"));
}

#[test]
fn load_reports_missing_file() {
    let err = scene::load(Path::new("no/such/scene.json")).unwrap_err();
    assert!(matches!(err, SceneError::Io { .. }));
    assert!(err.to_string().contains("no/such/scene.json"), "{err}");
}

#[test]
fn schema_is_an_object_with_properties() {
    let v = scene::schema();
    let props = v
        .get("properties")
        .and_then(|p| p.as_object())
        .expect("properties");
    for key in ["output", "camera", "objects"] {
        assert!(props.contains_key(key), "{key}");
    }
    assert!(!props.contains_key("base_dir"));
    let text = serde_json::to_string(&v).unwrap();
    for word in [
        "fov_y_deg",
        "keyframes",
        "cameras_json",
        "rotate_deg",
        "orbit",
    ] {
        assert!(text.contains(word), "schema mentions {word}");
    }
}

#[test]
fn overrides_are_validated() {
    let mut s = scene::default_scene();
    s.with_overrides(Some(PathBuf::from("/tmp/x")), Some(320), None)
        .unwrap();
    assert_eq!((s.output.width, s.output.height), (320, 180));
    assert_eq!(s.output_dir(), Path::new("/tmp/x"));
    assert_eq!(s.camera_path().unwrap().camera(0).width, 320);
    let err = s.with_overrides(None, Some(0), Some(0)).unwrap_err();
    assert!(err.to_string().contains("output.width"), "{err}");
}

// ---------------------------------------------------------------------------------------------
// Camera paths
// ---------------------------------------------------------------------------------------------

#[test]
fn orbit_always_looks_at_the_target() {
    let s = parse(&with_camera(
        r#"{"fov_y_deg": 50, "path": {"type": "orbit", "target": [1, 2, 0.5], "radius": 3, "height": 1, "start_deg": 30, "turns": 1.5}}"#,
    ))
    .unwrap();
    let path = s.camera_path().unwrap();
    let target = Vec3::new(1.0, 2.0, 0.5);
    for f in 0..10 {
        let c = path.camera(f);
        assert_orthonormal(c.rotation, "orbit");
        let (u, v, z) = project(&c, target);
        assert!(z > 0.0);
        assert!(
            (u - 32.0).abs() < 1e-3 && (v - 24.0).abs() < 1e-3,
            "frame {f}: target at ({u}, {v})"
        );
        let d = c.position - target;
        assert!((d.z - 1.0).abs() < 1e-5, "height");
        assert!((d.truncate().length() - 3.0).abs() < 1e-5, "radius");
        // Image up (−y) points toward world up.
        assert!((-c.rotation.y_axis).z > 0.0);
        // Focal length from the vertical field of view.
        assert!((c.fy - 24.0 / 25f32.to_radians().tan()).abs() < 1e-3 && c.fx == c.fy);
    }
    // Frame 0 at start_deg (measured from +x toward +y).
    let d0 = path.camera(0).position - target;
    assert!((d0.y.atan2(d0.x).to_degrees() - 30.0).abs() < 1e-3);
}

fn keyframe_scene(keys: &str, fps: u32, frames: u32) -> Scene {
    parse(&format!(
        r#"{{"output": {{"width": 64, "height": 48, "frames": {frames}, "fps": {fps}}},
            "camera": {{"fov_y_deg": 40, "path": {{"type": "keyframes", "keyframes": [{keys}]}}}}}}"#
    ))
    .unwrap()
}

const LOOK_AT_KEYS: &str = r#"
    {"time": 0.0, "position": [4, 0, 1], "look_at": [0, 0, 0]},
    {"time": 1.0, "position": [0, 3, 2], "look_at": [0.5, 0, 0]},
    {"time": 2.5, "position": [-3, 0, 1], "look_at": [0, 0.5, 0.2]},
    {"time": 3.0, "position": [-2, -2, 0.5], "look_at": [0, 0, 0]}"#;

const ROTATION_KEYS: &str = r#"
    {"time": 0.0, "position": [0, -4, 0], "rotation": [[1, 0, 0], [0, 0, 1], [0, -1, 0]]},
    {"time": 1.0, "position": [4, 0, 0], "look_at": [0, 0, 0]},
    {"time": 2.5, "position": [0, 4, 1], "rotation": [[-1, 0, 0], [0, 0, -1], [0, -1, 0]]},
    {"time": 3.0, "position": [-4, 0, 0], "look_at": [0, 0, 0]}"#;

#[test]
fn keyframes_are_hit_exactly_at_their_times() {
    for keys in [LOOK_AT_KEYS, ROTATION_KEYS] {
        let s = keyframe_scene(keys, 100, 301);
        let path = s.camera_path().unwrap();
        let scene::PathSpec::Keyframes(k) = &s.camera.path else {
            panic!()
        };
        for key in &k.keyframes {
            let frame = (key.time * 100.0).round() as u32;
            let c = path.camera(frame);
            assert_eq!(
                c.position,
                Vec3::from_array(key.position),
                "position at t = {}",
                key.time
            );
            if let Some(t) = key.look_at {
                let (u, v, z) = project(&c, Vec3::from_array(t));
                assert!(
                    z > 0.0 && (u - 32.0).abs() < 1e-3 && (v - 24.0).abs() < 1e-3,
                    "looks at its target"
                );
            }
            if let Some(rows) = key.rotation {
                let r = Mat3::from_cols_array_2d(&rows).transpose();
                let diff = (c.rotation - r)
                    .to_cols_array()
                    .iter()
                    .fold(0.0f32, |m, x| m.max(x.abs()));
                assert!(
                    diff < 1e-5,
                    "rotation at t = {}: {:?} vs {r:?}",
                    key.time,
                    c.rotation
                );
            }
        }
        // Before the first and after the last keyframe the end poses hold.
        let first = &k.keyframes[0];
        let last = k.keyframes.last().unwrap();
        assert_eq!(
            path.camera_at_time(-1.0).position,
            Vec3::from_array(first.position)
        );
        assert_eq!(path.camera(300).position, Vec3::from_array(last.position));
        assert_eq!(
            path.camera(10_000).position,
            Vec3::from_array(last.position)
        );
    }
}

#[test]
fn keyframe_path_is_c1_at_interior_keyframes() {
    let s = keyframe_scene(LOOK_AT_KEYS, 24, 72);
    let path = s.camera_path().unwrap();
    let h = 1e-3f32;
    let pos = |t: f32| path.camera_at_time(t).position;
    let fwd = |t: f32| path.camera_at_time(t).rotation.z_axis;
    for t in [1.0f32, 2.5] {
        let before = (pos(t) - pos(t - h)) / h;
        let after = (pos(t + h) - pos(t)) / h;
        assert!(before.length() > 0.5, "moving at {t}");
        assert!(
            (before - after).length() < 0.02 * before.length().max(1.0),
            "velocity jumps at t = {t}: {before} vs {after}"
        );
        // The viewing direction turns smoothly too (look-at targets are splined as well).
        let wb = (fwd(t) - fwd(t - h)) / h;
        let wa = (fwd(t + h) - fwd(t)) / h;
        assert!(
            (wb - wa).length() < 0.02 * wb.length().max(1.0),
            "angular velocity jumps at t = {t}: {wb} vs {wa}"
        );
    }
    // Continuity elsewhere: no jumps between consecutive samples.
    let mut prev = pos(0.0);
    for i in 1..=3000 {
        let p = pos(i as f32 * 1e-3);
        assert!((p - prev).length() < 0.02, "jump at {}", i as f32 * 1e-3);
        prev = p;
    }
}

#[test]
fn slerped_orientations_are_orthonormal() {
    let s = keyframe_scene(ROTATION_KEYS, 24, 72);
    let path = s.camera_path().unwrap();
    let mut prev: Option<Quat> = None;
    for i in 0..=600 {
        let c = path.camera_at_time(i as f32 * 0.005);
        assert_orthonormal(c.rotation, "slerp");
        let q = Quat::from_mat3(&c.rotation);
        if let Some(p) = prev {
            assert!(p.angle_between(q) < 0.05, "orientation jumps at step {i}");
        }
        prev = Some(q);
    }
}

#[test]
fn single_keyframe_is_a_still_camera() {
    let s = keyframe_scene(
        r#"{"time": 0.5, "position": [1, 2, 3], "look_at": [0, 0, 0]}"#,
        24,
        5,
    );
    let path = s.camera_path().unwrap();
    let c0 = path.camera(0);
    for f in 1..5 {
        assert_eq!(path.camera(f), c0);
    }
    assert_eq!(c0.position, Vec3::new(1.0, 2.0, 3.0));
}

const TWO_CAMERAS: &str = r#"[
  {"id": 0, "img_name": "00000", "width": 800, "height": 600,
   "position": [1.0, 2.0, 3.0],
   "rotation": [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]],
   "fx": 1000.0, "fy": 900.0},
  {"id": 1, "img_name": "00001", "width": 800, "height": 600,
   "position": [-1.0, 0.5, 2.0],
   "rotation": [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
   "fx": 1200.0, "fy": 1100.0}
]"#;

fn rows(c: &Camera) -> [[f32; 3]; 3] {
    c.rotation.transpose().to_cols_array_2d()
}

#[test]
fn cameras_json_is_read_as_is_with_focal_rescaled() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("cameras.json");
    std::fs::write(&file, TWO_CAMERAS).unwrap();

    let cams = scene::from_cameras_json(&file, None, None).unwrap();
    assert_eq!(cams.len(), 2);
    assert_eq!(cams[0].position, Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(
        rows(&cams[0]),
        [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]]
    );
    assert_eq!(
        rows(&cams[1]),
        [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    );
    assert_eq!(
        (cams[0].width, cams[0].height, cams[0].fx, cams[0].fy),
        (800, 600, 1000.0, 900.0)
    );

    let cams = scene::from_cameras_json(&file, Some(400), Some(200)).unwrap();
    assert_eq!(
        (cams[0].width, cams[0].height, cams[0].fx, cams[0].fy),
        (400, 200, 500.0, 300.0)
    );
    assert_eq!(cams[1].position, Vec3::new(-1.0, 0.5, 2.0));
    // Only a width: the height keeps the aspect ratio.
    let cams = scene::from_cameras_json(&file, Some(400), None).unwrap();
    assert_eq!(
        (cams[1].width, cams[1].height, cams[1].fx, cams[1].fy),
        (400, 300, 600.0, 550.0)
    );

    // Through a scene, mode "each".
    let text = r#"{"output": {"width": 200, "height": 150, "frames": 2},
        "camera": {"path": {"type": "cameras_json", "file": "cameras.json", "mode": "each"}}}"#;
    let s = parse_in(text, dir.path()).unwrap();
    let path = s.camera_path().unwrap();
    let (c0, c1) = (path.camera(0), path.camera(1));
    assert_eq!(
        (c0.position, c0.fx, c0.fy, c0.width),
        (Vec3::new(1.0, 2.0, 3.0), 250.0, 225.0, 200)
    );
    assert_eq!(
        rows(&c1),
        [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    );
    assert_eq!((c1.fx, c1.fy), (300.0, 275.0));

    // Explicit intrinsics win over the file's.
    let text = r#"{"output": {"width": 200, "height": 150, "frames": 2},
        "camera": {"fx": 77, "fy": 88, "path": {"type": "cameras_json", "file": "cameras.json"}}}"#;
    let c = parse_in(text, dir.path())
        .unwrap()
        .camera_path()
        .unwrap()
        .camera(1);
    assert_eq!(
        (c.fx, c.fy, c.position),
        (77.0, 88.0, Vec3::new(-1.0, 0.5, 2.0))
    );
}

#[test]
fn cameras_json_smooth_mode_spreads_cameras_over_the_frames() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("cams.json"), TWO_CAMERAS).unwrap();
    let text = r#"{"output": {"width": 200, "height": 150, "frames": 11},
        "camera": {"path": {"type": "cameras_json", "file": "cams.json", "mode": "smooth"}}}"#;
    let path = parse_in(text, dir.path()).unwrap().camera_path().unwrap();
    assert_eq!(path.camera(0).position, Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(path.camera(10).position, Vec3::new(-1.0, 0.5, 2.0));
    let mid = path.camera(5);
    assert_close(mid.position, Vec3::new(0.0, 1.25, 2.5), 1e-5, "halfway");
    assert_orthonormal(mid.rotation, "smooth");
    assert!(
        (mid.fx - 275.0).abs() < 1e-3,
        "focal interpolated: {}",
        mid.fx
    );
}

#[test]
fn missing_cameras_json_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let text = r#"{"output": {"width": 200, "height": 150, "frames": 2},
        "camera": {"path": {"type": "cameras_json", "file": "nope/cameras.json"}}}"#;
    let err = parse_in(text, dir.path()).unwrap_err();
    let s = err.to_string();
    assert!(
        s.contains("camera.path.file")
            && s.contains("nope/cameras.json")
            && s.contains("not found"),
        "{s}"
    );

    let err = scene::from_cameras_json(&dir.path().join("missing.json"), None, None).unwrap_err();
    assert!(matches!(err, SceneError::Io { .. }), "{err}");

    // A malformed file names itself, with line and column.
    let bad = dir.path().join("bad.json");
    std::fs::write(&bad, "[\n {\"width\": 10}\n]").unwrap();
    let err = scene::from_cameras_json(&bad, None, None).unwrap_err();
    let SceneError::Parse {
        ref origin, line, ..
    } = err
    else {
        panic!("{err:?}")
    };
    assert!(origin.ends_with("bad.json") && line == 2, "{err}");
}

#[test]
fn each_mode_with_too_few_cameras_is_rejected() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("cameras.json"), TWO_CAMERAS).unwrap();
    let text = r#"{"output": {"width": 200, "height": 150, "frames": 3},
        "camera": {"path": {"type": "cameras_json", "file": "cameras.json", "mode": "each"}}}"#;
    let s = parse_in(text, dir.path()).unwrap();
    let err = s.camera_path().unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("output.frames") && msg.contains("at most 2"),
        "{msg}"
    );
}

#[test]
fn still_and_orbit_framing() {
    let c = Camera::look_at(Vec3::new(0.0, -3.0, 1.0), Vec3::ZERO, Vec3::Z, 0.8, 64, 48);
    let path = CameraPath::still(c);
    assert_eq!(path.camera(0), c);
    assert_eq!(path.camera(99), c);

    let bounds = (Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, 1.0, 2.0));
    let path = scene::CameraPath::orbit_framing(bounds, Vec3::Z, 45.0, 64, 48, 8);
    assert_eq!(path.frames(), 8);
    for f in 0..8 {
        let c = path.camera(f);
        let (u, v, _) = project(&c, Vec3::new(0.0, 0.0, 1.0));
        assert!((u - 32.0).abs() < 1e-3 && (v - 24.0).abs() < 1e-3);
        assert!(c.position.z > 1.0, "slightly above the centre");
    }
}

// ---------------------------------------------------------------------------------------------
// Objects
// ---------------------------------------------------------------------------------------------

fn two_gaussians() -> GaussianCloud {
    GaussianCloud {
        positions: vec![Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 2.0, -1.0)],
        scales: vec![Vec3::new(0.1, 0.2, 0.3), Vec3::splat(0.05)],
        rotations: vec![Quat::from_rotation_y(0.4), Quat::IDENTITY],
        opacities: vec![0.5, 0.9],
        sh_degree: 0,
        sh: vec![0.1, 0.2, 0.3, 0.4, 0.5, 0.6],
        normals: vec![],
        ..Default::default()
    }
}

#[test]
fn transform_is_rotation_times_scale_plus_translation() {
    let t: TransformSpec =
        serde_json::from_str(r#"{"translate": [1, 2, 3], "rotate_deg": [0, 0, 90], "scale": 2}"#)
            .unwrap();
    let (m, tr) = t.affine();
    let cloud = two_gaussians();
    let s = Splats::from_cloud(&cloud, m, tr);
    // (1, 0, 0) → scaled (2, 0, 0) → rotated 90° about z (0, 2, 0) → moved (1, 4, 3).
    assert_close(s.means[0], Vec3::new(1.0, 4.0, 3.0), 1e-5, "mean");
    for i in 0..2 {
        let a = cloud.covariance(i);
        let c = mat3_from_sym3(s.covariances[i]);
        // Uniform scale 2: covariance × 4 and rotated.
        let expected = t.rotation() * (a * 4.0) * t.rotation().transpose();
        let diff = (c - expected)
            .to_cols_array()
            .iter()
            .fold(0.0f32, |m, x| m.max(x.abs()));
        assert!(diff < 1e-5, "{c:?} vs {expected:?}");
        assert!(
            (c.determinant() - a.determinant() * 64.0).abs()
                < 1e-6 * (1.0 + a.determinant() * 64.0)
        );
    }
}

#[test]
fn build_splats_applies_each_objects_transform() {
    let text = r#"{"output": {"width": 64, "height": 48, "frames": 1},
        "camera": {"fov_y_deg": 40, "path": {"type": "orbit", "radius": 2}},
        "objects": [
          {"name": "plain", "procedural": {"shape": "sphere", "radius": 0.3, "spacing": 0.05, "color": [1, 0, 0], "seed": 7}},
          {"procedural": {"shape": "sphere", "radius": 0.3, "spacing": 0.05, "color": [1, 0, 0], "seed": 7},
           "transform": {"translate": [5, 0, 1], "scale": 3}}
        ]}"#;
    let s = parse(text).unwrap();
    let (splats, report) = s.build_splats().unwrap();
    assert_eq!(report.objects.len(), 2);
    assert_eq!(report.objects[0].name, "plain");
    assert_eq!(report.objects[1].name, "sphere 1");
    let n = report.objects[0].gaussians;
    assert!(n > 0);
    assert_eq!(report.objects[1].gaussians, n);
    assert_eq!(splats.len(), 2 * n);
    for i in 0..n {
        let (a, b) = (splats.means[i], splats.means[n + i]);
        assert_close(
            b,
            a * 3.0 + Vec3::new(5.0, 0.0, 1.0),
            1e-4,
            "mean moved and scaled",
        );
        for k in 0..6 {
            let (ca, cb) = (splats.covariances[i][k], splats.covariances[n + i][k]);
            assert!(
                (cb - 9.0 * ca).abs() <= 1e-6 + 1e-4 * ca.abs(),
                "covariance × scale²: {cb} vs 9·{ca}"
            );
        }
        assert_eq!(splats.opacities[i], splats.opacities[n + i]);
    }
}

#[test]
fn ply_errors_name_the_object() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("broken.ply"), "this is not a ply file\n").unwrap();
    let text = r#"{"output": {"width": 64, "height": 48, "frames": 1},
        "camera": {"fov_y_deg": 40, "path": {"type": "orbit", "radius": 2}},
        "objects": [{"ply": "broken.ply"}]}"#;
    let s = parse_in(text, dir.path()).unwrap();
    let err = s.build_splats().unwrap_err();
    let msg = err.to_string();
    assert!(
        matches!(err, SceneError::Object { index: 0, .. }),
        "{err:?}"
    );
    assert!(
        msg.contains("objects[0] (broken.ply)") && !msg.contains('\n'),
        "{msg}"
    );
}

#[test]
fn a_schema_reference_for_editors_is_accepted() {
    let text = splatter::scene::DEFAULT_SCENE_JSON.replacen(
        '{',
        "{\n  \"$schema\": \"./scene.schema.json\",",
        1,
    );
    let scene =
        splatter::scene::parse(&text, "with-schema.json", std::path::Path::new(".")).unwrap();
    assert_eq!(scene.schema_ref.as_deref(), Some("./scene.schema.json"));
}
