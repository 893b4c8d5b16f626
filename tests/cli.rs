//! The `splatter` binary end to end: bad input ends as exactly one `error: …` line on stderr
//! and a non-zero exit, never a panic; the message names what is wrong. Plus a few positive
//! runs (the smallest render, `schema`, `info`, `default-scene`).
//!
//! Every run happens in its own temporary directory (the binary's current directory), so
//! default output folders (`out/<name>`) never land in the source tree. Renders are tiny
//! (64×48, one frame): on a machine without a GPU they run on lavapipe, a CPU Vulkan driver.

mod common;

use std::path::{Path, PathBuf};

use common::cli::*;
use glam::{Quat, Vec3};
use splatter::splat::ply::{write_ply, PlyFormat};
use splatter::splat::GaussianCloud;

// ---------------------------------------------------------------------------------------------
// Inputs
// ---------------------------------------------------------------------------------------------

/// A small procedural sphere (about 500 Gaussians at this spacing).
const SPHERE: &str = r#"{"procedural": {"shape": "sphere", "radius": 0.5, "spacing": 0.1, "color": [0.9, 0.2, 0.1]}}"#;

/// A scene `width`×48 with `frames` frames, an orbit camera with field of view `fov` (JSON
/// text) and the given `objects` (a JSON array).
fn scene_json(width: i64, frames: u32, fov: &str, objects: &str) -> String {
    format!(
        r#"{{
  "output": {{"width": {width}, "height": 48, "frames": {frames}}},
  "camera": {{"fov_y_deg": {fov}, "path": {{"type": "orbit", "target": [0, 0, 0], "radius": 3, "height": 1}}}},
  "objects": {objects}
}}
"#
    )
}

/// The smallest useful scene: one frame of a small sphere.
fn tiny_scene() -> String {
    scene_json(64, 1, "50", &format!("[{SPHERE}]"))
}

/// A scene whose only object is the sphere with `transform`.
fn sphere_with_transform(transform: &str) -> String {
    let inner = SPHERE.strip_suffix('}').expect("SPHERE is a JSON object");
    let object = format!(r#"{inner}, "transform": {transform}}}"#);
    scene_json(64, 1, "50", &format!("[{object}]"))
}

/// A tiny valid Gaussian cloud (SH degree 0), `n` Gaussians on a line.
fn tiny_cloud(n: usize) -> GaussianCloud {
    let mut c = GaussianCloud::default();
    for i in 0..n {
        let t = i as f32 / n.max(1) as f32 - 0.5;
        c.positions.push(Vec3::new(t, 0.2 * t, -0.1 * t));
        c.scales.push(Vec3::splat(0.05));
        c.rotations.push(Quat::IDENTITY);
        c.opacities.push(0.8);
        c.sh.extend([0.5, 0.1, -0.2]);
    }
    c
}

/// Write a valid binary PLY of `n` Gaussians at `dir/name`.
fn write_tiny_ply(dir: &Path, name: &str, n: usize) -> PathBuf {
    let path = dir.join(name);
    write_ply(&path, &tiny_cloud(n), PlyFormat::BinaryLittleEndian).expect("write_ply");
    path
}

/// The header of an ASCII 3DGS PLY with `n` vertices and the given properties (all floats).
fn ascii_header(n: usize, properties: &[&str]) -> String {
    let mut h = format!("ply\nformat ascii 1.0\nelement vertex {n}\n");
    for p in properties {
        h.push_str(&format!("property float {p}\n"));
    }
    h.push_str("end_header\n");
    h
}

/// Every 3DGS property of an SH degree 0 PLY, in the usual order.
const PROPERTIES: [&str; 14] = [
    "x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1", "scale_2",
    "rot_0", "rot_1", "rot_2", "rot_3",
];

/// An INRIA 3DGS `cameras.json` with two cameras looking at the origin along +y / −x.
const CAMERAS_JSON: &str = r#"[
  {"id": 0, "img_name": "a", "width": 64, "height": 48,
   "position": [0, -3, 0],
   "rotation": [[1, 0, 0], [0, 0, 1], [0, -1, 0]],
   "fx": 60, "fy": 60},
  {"id": 1, "img_name": "b", "width": 64, "height": 48,
   "position": [3, 0, 0],
   "rotation": [[0, 0, -1], [1, 0, 0], [0, -1, 0]],
   "fx": 60, "fy": 60}
]
"#;

/// Files in `dir` (names only), sorted; the run manifest (`manifest.json`, or
/// `manifest_A-B.json` for a part of the frames, which every render writes) left out.
fn list(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| !(n.starts_with("manifest") && n.ends_with(".json")))
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}

// ---------------------------------------------------------------------------------------------
// Missing and broken input files
// ---------------------------------------------------------------------------------------------

#[test]
fn missing_scene_file() {
    let dir = workdir();
    let out = splatter(dir.path(), &["render", "no_such_scene.json"]);
    let line = expect_error(&out);
    assert_mentions(&line, &["no_such_scene.json"]);
    // The OS reason should be stated once, not repeated by the error chain.
    let reason = "No such file or directory";
    assert_eq!(
        line.matches(reason).count(),
        1,
        "the OS error should appear exactly once: {line}"
    );
}

#[test]
fn missing_ply_file() {
    let dir = workdir();
    let out = splatter(
        dir.path(),
        &["render", "--ply", "nope.ply", "--out", "frames"],
    );
    let line = expect_error(&out);
    assert_mentions(&line, &["nope.ply"]);
    assert!(
        !dir.path().join("frames").exists(),
        "no output folder on error"
    );
}

#[test]
fn truncated_binary_ply() {
    let dir = workdir();
    let ply = write_tiny_ply(dir.path(), "cut.ply", 16);
    let len = std::fs::metadata(&ply).unwrap().len();
    // Cut the body in the middle of a vertex (each vertex is 17 floats = 68 bytes here).
    let file = std::fs::OpenOptions::new().write(true).open(&ply).unwrap();
    file.set_len(len - 100).unwrap();
    drop(file);
    let out = splatter(
        dir.path(),
        &[
            "render", "--ply", "cut.ply", "--out", "frames", "--frames", "0..1", "--width", "64",
            "--height", "48",
        ],
    );
    let line = expect_error(&out);
    assert_mentions(&line, &["cut.ply", "truncated", "16"]);
}

#[test]
fn ply_without_opacity() {
    let dir = workdir();
    let props: Vec<&str> = PROPERTIES
        .iter()
        .copied()
        .filter(|p| *p != "opacity")
        .collect();
    let mut text = ascii_header(2, &props);
    text.push_str("0 0 0 0.5 0.5 0.5 -3 -3 -3 1 0 0 0\n");
    text.push_str("0.1 0 0 0.5 0.5 0.5 -3 -3 -3 1 0 0 0\n");
    write(dir.path(), "no_opacity.ply", &text);
    let out = splatter(
        dir.path(),
        &[
            "render",
            "--ply",
            "no_opacity.ply",
            "--out",
            "frames",
            "--frames",
            "0..1",
            "--width",
            "64",
            "--height",
            "48",
        ],
    );
    let line = expect_error(&out);
    assert_mentions(&line, &["no_opacity.ply", "opacity"]);
}

#[test]
fn nan_in_ply_is_skipped_with_a_warning() {
    let dir = workdir();
    let mut text = ascii_header(5, &PROPERTIES);
    text.push_str("0 0 0 0.5 0.5 0.5 2 -3 -3 -3 1 0 0 0\n");
    text.push_str("nan 0 0 0.5 0.5 0.5 2 -3 -3 -3 1 0 0 0\n");
    text.push_str("0.3 0 0 0.5 0.5 0.5 2 -3 -3 -3 1 0 0 0\n");
    text.push_str("0 0.3 0 0.5 0.5 0.5 nan -3 -3 -3 1 0 0 0\n");
    text.push_str("0 0 0.3 0.5 0.5 0.5 2 -3 -3 -3 1 0 0 0\n");
    write(dir.path(), "holes.ply", &text);
    let out = splatter(
        dir.path(),
        &[
            "render",
            "--ply",
            "holes.ply",
            "--out",
            "frames",
            "--frames",
            "0..1",
            "--width",
            "64",
            "--height",
            "48",
        ],
    );
    expect_success(&out);
    let warning = stderr_lines(&out)
        .into_iter()
        .find(|l| l.contains("skipped"))
        .unwrap_or_else(|| panic!("no warning about skipped Gaussians:\n{}", describe(&out)));
    assert_mentions(&warning, &["holes.ply", "2 Gaussians"]);
    assert!(
        !stderr_lines(&out).iter().any(|l| l.starts_with("error: ")),
        "a successful run prints no error line:\n{}",
        describe(&out)
    );
    assert_eq!(list(&dir.path().join("frames")), ["frame_00000.png"]);
}

// ---------------------------------------------------------------------------------------------
// Scene values out of range
// ---------------------------------------------------------------------------------------------

/// Render `scene` (written as `name`, with `extra` arguments) and expect a clean error;
/// returns the error line.
fn render_scene_error(name: &str, scene: &str, extra: &[&str]) -> String {
    let dir = workdir();
    write(dir.path(), name, scene);
    let mut args = vec!["render", name, "--out", "frames"];
    args.extend_from_slice(extra);
    let out = splatter(dir.path(), &args);
    expect_error(&out)
}

#[test]
fn fragments_of_a_scene_that_simulates_nothing() {
    let line = render_scene_error("still.json", &tiny_scene(), &["--fragments"]);
    assert_mentions(&line, &["--fragments", "still.json", "physics"]);
}

#[test]
fn particles_of_a_scene_that_simulates_nothing() {
    let line = render_scene_error(
        "still.json",
        &tiny_scene(),
        &["--export-particles", "particles"],
    );
    assert_mentions(&line, &["--export-particles", "physics"]);
}

#[test]
fn zero_transform_scale() {
    let line = render_scene_error(
        "zero_scale.json",
        &sphere_with_transform(r#"{"scale": 0}"#),
        &[],
    );
    assert_mentions(
        &line,
        &["zero_scale.json", "objects[0].transform.scale", "= 0"],
    );
}

#[test]
fn negative_transform_scale() {
    let line = render_scene_error(
        "neg_scale.json",
        &sphere_with_transform(r#"{"scale": -1}"#),
        &[],
    );
    assert_mentions(
        &line,
        &["neg_scale.json", "objects[0].transform.scale", "-1"],
    );
}

#[test]
fn zero_per_axis_transform_scale() {
    let line = render_scene_error(
        "axis_scale.json",
        &sphere_with_transform(r#"{"scale": [1, 0, 1]}"#),
        &[],
    );
    assert_mentions(
        &line,
        &[
            "axis_scale.json",
            "objects[0].transform.scale",
            "[1.0, 0.0, 1.0]",
        ],
    );
}

#[test]
fn procedural_sphere_radius_zero() {
    let object =
        r#"{"procedural": {"shape": "sphere", "radius": 0, "spacing": 0.1, "color": [1, 1, 1]}}"#;
    let line = render_scene_error(
        "flat_ball.json",
        &scene_json(64, 1, "50", &format!("[{object}]")),
        &[],
    );
    assert_mentions(
        &line,
        &["flat_ball.json", "objects[0].procedural.radius", "0"],
    );
}

#[test]
fn unknown_key_in_scene() {
    let scene = r#"{
  "output": {"width": 64, "height": 48, "frames": 1},
  "camera": {"fovy": 50, "path": {"type": "orbit", "radius": 3}},
  "objects": []
}
"#;
    let line = render_scene_error("typo.json", scene, &[]);
    assert_mentions(&line, &["fovy", "unknown field"]);
    // `error: typo.json:LINE:COLUMN: …`
    let rest = line
        .strip_prefix("error: typo.json:")
        .unwrap_or_else(|| panic!("expected `error: typo.json:LINE:COLUMN: …`: {line}"));
    let mut parts = rest.splitn(3, ':');
    let l: usize = parts.next().unwrap().parse().expect("a line number");
    let c: usize = parts.next().unwrap().parse().expect("a column number");
    // Where `"fovy"` is in the file (1-based line and columns of its quotes).
    let (key_line, text) = scene
        .lines()
        .enumerate()
        .find(|(_, t)| t.contains("\"fovy\""))
        .unwrap();
    let first = text.find("\"fovy\"").unwrap() + 1;
    let last = first + "\"fovy\"".len() - 1;
    assert_eq!(l, key_line + 1, "line of `fovy`: {line}");
    assert!(
        (first..=last + 1).contains(&c),
        "column {c} should point at `fovy` (columns {first}..={last}): {line}"
    );
}

#[test]
fn fov_zero() {
    let line = render_scene_error(
        "fov0.json",
        &scene_json(64, 1, "0", &format!("[{SPHERE}]")),
        &[],
    );
    assert_mentions(&line, &["fov0.json", "camera.fov_y_deg", "= 0"]);
}

#[test]
fn fov_negative() {
    let line = render_scene_error(
        "fovneg.json",
        &scene_json(64, 1, "-10", &format!("[{SPHERE}]")),
        &[],
    );
    assert_mentions(&line, &["fovneg.json", "camera.fov_y_deg", "-10"]);
}

#[test]
fn zero_width_in_scene() {
    let line = render_scene_error(
        "narrow.json",
        &scene_json(0, 1, "50", &format!("[{SPHERE}]")),
        &[],
    );
    assert_mentions(&line, &["narrow.json", "output.width", "= 0"]);
}

#[test]
fn zero_width_on_command_line() {
    let line = render_scene_error("ok.json", &tiny_scene(), &["--width", "0"]);
    // The 0 came from the command line, not from ok.json: the message should say so.
    assert_mentions(&line, &["--width", "0"]);
}

#[test]
fn zero_width_on_command_line_with_ply() {
    let dir = workdir();
    write_tiny_ply(dir.path(), "tiny.ply", 8);
    let out = splatter(
        dir.path(),
        &[
            "render", "--ply", "tiny.ply", "--out", "frames", "--width", "0", "--height", "48",
        ],
    );
    let line = expect_error(&out);
    assert_mentions(&line, &["--width", "0"]);
}

// ---------------------------------------------------------------------------------------------
// Command-line values out of range
// ---------------------------------------------------------------------------------------------

#[test]
fn up_axis_not_an_axis() {
    let dir = workdir();
    write_tiny_ply(dir.path(), "tiny.ply", 8);
    let out = splatter(
        dir.path(),
        &[
            "render", "--ply", "tiny.ply", "--up", "sideways", "--out", "frames",
        ],
    );
    let line = expect_error(&out);
    assert_mentions(&line, &["--up", "sideways", "+x", "-z"]);
}

#[test]
fn inspect_cameras_missing_or_malformed() {
    let dir = workdir();
    write_tiny_ply(dir.path(), "tiny.ply", 8);
    let out = splatter(
        dir.path(),
        &["inspect", "tiny.ply", "--cameras", "nope.json"],
    );
    let line = expect_error(&out);
    assert_mentions(&line, &["nope.json"]);
    write(dir.path(), "bad.json", r#"[{"width": 64}]"#);
    let out = splatter(
        dir.path(),
        &["inspect", "tiny.ply", "--cameras", "bad.json"],
    );
    let line = expect_error(&out);
    assert_mentions(&line, &["bad.json", "height"]);
}

/// A `cameras.json` next to a capture that is not an INRIA cameras file (another tool's of
/// that name) is left unused, in one warning line, rather than failing the inspection.
#[test]
fn unreadable_cameras_json_next_to_a_capture_is_not_used() {
    let dir = workdir();
    write_tiny_ply(dir.path(), "tiny.ply", 8);
    write(dir.path(), "cameras.json", r#"{"frames": []}"#);
    let out = splatter_ok(dir.path(), &["inspect", "tiny.ply"]);
    let lines: Vec<String> = stderr_lines(&out)
        .into_iter()
        .filter(|l| l.contains("was not used"))
        .collect();
    assert_eq!(lines.len(), 1, "{}", describe(&out));
    assert_mentions(&lines[0], &["tiny.ply", "cameras.json"]);
}

#[test]
fn scene_up_cameras_missing_or_on_a_procedural_object() {
    let dir = workdir();
    write_tiny_ply(dir.path(), "tiny.ply", 8);
    let object = r#"{"ply": "tiny.ply", "transform": {"up": {"auto": {"cameras": "nope.json"}}}}"#;
    write(
        dir.path(),
        "s.json",
        &scene_json(64, 1, "50", &format!("[{object}]")),
    );
    let line = expect_error(&splatter(dir.path(), &["render", "s.json"]));
    assert_mentions(
        &line,
        &[
            "s.json",
            "objects[0].transform.up.auto.cameras",
            "nope.json",
        ],
    );

    write(dir.path(), "cameras.json", CAMERAS_JSON);
    write(
        dir.path(),
        "p.json",
        &sphere_with_transform(r#"{"up": {"auto": {"cameras": "cameras.json"}}}"#),
    );
    let line = expect_error(&splatter(dir.path(), &["render", "p.json"]));
    assert_mentions(
        &line,
        &["objects[0].transform.up.auto.cameras", "procedural"],
    );

    write(
        dir.path(),
        "k.json",
        &sphere_with_transform(r#"{"up": {"auto": {"camera": "cameras.json"}}}"#),
    );
    let line = expect_error(&splatter(dir.path(), &["render", "k.json"]));
    assert_mentions(&line, &["k.json", "up"]);
}

#[test]
fn camera_index_out_of_range() {
    let dir = workdir();
    write_tiny_ply(dir.path(), "tiny.ply", 8);
    write(dir.path(), "cameras.json", CAMERAS_JSON);
    let out = splatter(
        dir.path(),
        &[
            "render",
            "--ply",
            "tiny.ply",
            "--cameras",
            "cameras.json",
            "--camera",
            "5",
            "--out",
            "frames",
        ],
    );
    let line = expect_error(&out);
    assert_mentions(&line, &["--camera 5", "cameras.json", "2 cameras"]);
}

#[test]
fn frames_out_of_range() {
    let line = render_scene_error(
        "two.json",
        &scene_json(64, 2, "50", &format!("[{SPHERE}]")),
        &["--frames", "5..99"],
    );
    assert_mentions(&line, &["--frames", "5..99", "2 frames"]);
}

#[test]
fn frames_not_a_number() {
    let line = render_scene_error(
        "two_b.json",
        &scene_json(64, 2, "50", &format!("[{SPHERE}]")),
        &["--frames", "x..1"],
    );
    assert_mentions(&line, &["--frames", "x"]);
}

// ---------------------------------------------------------------------------------------------
// Unwritable output
// ---------------------------------------------------------------------------------------------

#[test]
fn output_dir_in_proc() {
    let dir = workdir();
    write(dir.path(), "ok.json", &tiny_scene());
    let out = splatter(
        dir.path(),
        &["render", "ok.json", "--out", "/proc/splatter-forbidden"],
    );
    let line = expect_error(&out);
    assert_mentions(&line, &["/proc/splatter-forbidden"]);
}

#[test]
fn output_dir_under_a_regular_file() {
    let dir = workdir();
    write(dir.path(), "ok.json", &tiny_scene());
    write(dir.path(), "plain.txt", "not a folder\n");
    let out = splatter(
        dir.path(),
        &["render", "ok.json", "--out", "plain.txt/frames"],
    );
    let line = expect_error(&out);
    assert_mentions(&line, &["plain.txt/frames"]);
    assert_eq!(
        std::fs::read_to_string(dir.path().join("plain.txt")).unwrap(),
        "not a folder\n"
    );
}

#[test]
fn output_dir_is_a_regular_file() {
    let dir = workdir();
    write(dir.path(), "ok.json", &tiny_scene());
    write(dir.path(), "plain.txt", "not a folder\n");
    let out = splatter(dir.path(), &["render", "ok.json", "--out", "plain.txt"]);
    let line = expect_error(&out);
    assert_mentions(&line, &["plain.txt"]);
}

/// The frame cannot be written (its name is taken by a folder): the error comes from the PNG
/// writer thread, after the GPU has started.
#[test]
fn frame_path_taken_by_a_directory() {
    let dir = workdir();
    write(dir.path(), "ok.json", &tiny_scene());
    let frames = dir.path().join("frames");
    std::fs::create_dir_all(frames.join("frame_00000.png").join("occupied")).unwrap();
    let out = splatter(dir.path(), &["render", "ok.json", "--out", "frames"]);
    let line = expect_late_error(&out);
    assert_mentions(&line, &["frame_00000.png"]);
    assert_eq!(
        line.matches("Is a directory").count(),
        1,
        "the OS error should appear exactly once: {line}"
    );
    assert_eq!(
        list(&frames),
        ["frame_00000.png"],
        "no temporary file left behind"
    );
    assert!(frames.join("frame_00000.png").join("occupied").is_dir());
}

// ---------------------------------------------------------------------------------------------
// Positive runs
// ---------------------------------------------------------------------------------------------

#[test]
fn smallest_scene_renders_one_frame() {
    let dir = workdir();
    write(dir.path(), "tiny.json", &tiny_scene());
    let out = splatter(dir.path(), &["render", "tiny.json", "--out", "frames"]);
    expect_success(&out);
    let frames = dir.path().join("frames");
    // Exactly the frame: no `.frame_00000.png.tmp` or other leftovers.
    assert_eq!(list(&frames), ["frame_00000.png"], "{}", describe(&out));
    let img = image::open(frames.join("frame_00000.png"))
        .expect("a readable PNG")
        .to_rgb8();
    assert_eq!(img.dimensions(), (64, 48));
    // The sphere is in view: some pixel is not the (black) background.
    assert!(
        img.pixels().any(|p| p.0 != [0, 0, 0]),
        "the frame is all background"
    );
}

#[test]
fn scene_output_dir_defaults_to_out_slash_name() {
    let dir = workdir();
    write(dir.path(), "tiny.json", &tiny_scene());
    let out = splatter(dir.path(), &["render", "tiny.json"]);
    expect_success(&out);
    assert_eq!(list(&dir.path().join("out/tiny")), ["frame_00000.png"]);
}

#[test]
fn camera_from_cameras_json_renders() {
    let dir = workdir();
    write_tiny_ply(dir.path(), "tiny.ply", 8);
    write(dir.path(), "cameras.json", CAMERAS_JSON);
    let out = splatter(
        dir.path(),
        &[
            "render",
            "--ply",
            "tiny.ply",
            "--cameras",
            "cameras.json",
            "--camera",
            "1",
            "--out",
            "frames",
        ],
    );
    expect_success(&out);
    let frames = dir.path().join("frames");
    assert_eq!(list(&frames), ["frame_00000.png"], "{}", describe(&out));
    let img = image::open(frames.join("frame_00000.png"))
        .unwrap()
        .to_rgb8();
    assert_eq!(img.dimensions(), (64, 48), "the size of the file's camera");
}

/// A scene whose camera path is a `cameras.json` and whose capture is transformed says, in
/// one warning line, that the training views will not line up (the cameras are in the
/// capture's own frame); the untransformed capture renders without it.
#[test]
fn cameras_json_path_with_a_transformed_capture_warns() {
    let dir = workdir();
    write_tiny_ply(dir.path(), "tiny.ply", 8);
    write(dir.path(), "cameras.json", CAMERAS_JSON);
    let scene = |transform: &str| {
        format!(
            r#"{{"output": {{"width": 64, "height": 48, "frames": 1}},
                "camera": {{"path": {{"type": "cameras_json", "file": "cameras.json"}}}},
                "objects": [{{"name": "capture", "ply": "tiny.ply"{transform}}}]}}"#
        )
    };
    let warnings = |out: &std::process::Output| -> Vec<String> {
        stderr_lines(out)
            .into_iter()
            .filter(|l| l.contains("training views will not line up"))
            .collect()
    };
    write(
        dir.path(),
        "moved.json",
        &scene(r#", "transform": {"up": "-y"}"#),
    );
    let out = splatter(dir.path(), &["render", "moved.json", "--out", "a"]);
    expect_success(&out);
    let lines = warnings(&out);
    assert_eq!(lines.len(), 1, "{}", describe(&out));
    assert_mentions(&lines[0], &["moved.json", "\"capture\"", "cameras.json"]);

    write(dir.path(), "own.json", &scene(""));
    let out = splatter(dir.path(), &["render", "own.json", "--out", "b"]);
    expect_success(&out);
    assert!(warnings(&out).is_empty(), "{}", describe(&out));
}

/// Channel `name` of an OpenEXR file's first layer, read by the `exr` crate: the layer's
/// size and the channel's values, row-major.
fn exr_channel(path: &Path, name: &str) -> ((usize, usize), Vec<f32>) {
    let exr = exr::prelude::read_first_flat_layer_from_file(path)
        .unwrap_or_else(|e| panic!("{} is no OpenEXR file: {e}", path.display()));
    let layer = &exr.layer_data;
    let channel = layer
        .channel_data
        .list
        .iter()
        .find(|c| c.name.to_string() == name)
        .unwrap_or_else(|| panic!("{}: no channel {name}", path.display()));
    (
        (layer.size.0, layer.size.1),
        channel.sample_data.values_as_f32().collect(),
    )
}

/// `--passes normal,id` on a lit sphere (its normals the relighting's PCA normals) and an
/// unlit one (its Gaussians' least axes): OUT/normal/frame_00000.exr (channels R, G, B,
/// read back by the exr crate) holds unit camera-space normals that face the camera and
/// point outwards (left of the lit ball's centre x < 0, above it y < 0: camera y is down),
/// (0, 0, 0) where nothing was drawn; OUT/id/frame_00000.png is a 16-bit grey PNG whose
/// ids the manifest's `ids` table names, one per object, 0 exactly where no normal is.
#[test]
fn normal_and_id_passes_name_what_each_pixel_shows() {
    let dir = workdir();
    let scene = r#"{
  "output": {"width": 96, "height": 64, "frames": 1},
  "camera": {"fov_y_deg": 40, "path": {"type": "orbit", "target": [0.4, 0, 0], "radius": 3.5, "height": 0}},
  "objects": [
    {"name": "lit ball", "procedural": {"shape": "sphere", "radius": 0.45, "spacing": 0.06, "color": [0.9, 0.2, 0.1]}},
    {"name": "other", "procedural": {"shape": "sphere", "radius": 0.3, "spacing": 0.06, "color": [0.2, 0.9, 0.1]},
     "transform": {"translate": [0, 0.9, 0]}}
  ],
  "lighting": {"ambient": [0.5, 0.5, 0.5], "lights": [{"position": [3, 1, 2]}], "shadows": {"enabled": false}}
}"#;
    write(dir.path(), "lit.json", scene);
    let out = splatter(
        dir.path(),
        &["render", "lit.json", "--out", "o", "--passes", "normal,id"],
    );
    expect_success(&out);
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("o/manifest.json")).unwrap())
            .unwrap();
    let table = manifest["settings"]["ids"]
        .as_array()
        .expect("the ids table");
    let names: Vec<(u64, &str)> = table
        .iter()
        .map(|e| (e["id"].as_u64().unwrap(), e["object"].as_str().unwrap()))
        .collect();
    assert_eq!(names, [(1, "lit ball"), (2, "other")]);
    let ids = image::open(dir.path().join("o/id/frame_00000.png")).unwrap();
    assert_eq!(ids.color(), image::ColorType::L16);
    let ids = ids.to_luma16();
    let normal = dir.path().join("o/normal/frame_00000.exr");
    let channel = |name: &str| exr_channel(&normal, name).1;
    let (nx, ny, nz) = (channel("R"), channel("G"), channel("B"));
    let (w, h) = (96usize, 64usize);
    let mut count = [0usize; 3];
    let (mut lit, mut sum_x) = (Vec::new(), [0.0f32; 2]);
    for i in 0..w * h {
        let n = [nx[i], ny[i], nz[i]];
        let id = ids.as_raw()[i];
        count[usize::from(id.min(2))] += 1;
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        if id == 0 {
            assert_eq!(len, 0.0, "a normal where nothing was drawn, pixel {i}");
            continue;
        }
        assert!((len - 1.0).abs() < 1e-3, "normal {n:?} at pixel {i}");
        assert!(n[2] < 0.1, "normal {n:?} at pixel {i} faces away");
        if id == 1 {
            lit.push((i % w, i / w, n));
        }
    }
    // the lit ball's pixels: left of its centre column, the normals point left; above its
    // centre row, up (−y)
    let cx = lit.iter().map(|p| p.0 as f32).sum::<f32>() / lit.len() as f32;
    let cy = lit.iter().map(|p| p.1 as f32).sum::<f32>() / lit.len() as f32;
    let mut sum_y = [0.0f32; 2];
    for (x, y, n) in &lit {
        sum_x[usize::from(*x as f32 > cx)] += n[0];
        sum_y[usize::from(*y as f32 > cy)] += n[1];
    }
    eprintln!("pixels (none, lit ball, other) {count:?}; Σ n.x left/right {sum_x:?}, Σ n.y above/below {sum_y:?}");
    assert!(count.iter().all(|c| *c > 100), "{count:?}");
    assert!(sum_x[0] < 0.0 && sum_x[1] > 0.0, "n.x left/right {sum_x:?}");
    assert!(
        sum_y[0] < 0.0 && sum_y[1] > 0.0,
        "n.y above/below {sum_y:?}"
    );
}

/// `--passes alpha,depth` writes OUT/alpha/frame_00000.png (RGBA: the frame is its
/// straight colour over the background, within 1/255) and OUT/depth/frame_00000.exr (one
/// float channel `Z`, read back by the exr crate: the camera distance's range where the
/// sphere is, +∞ around it); a bad pass name is one error line; resuming the finished run
/// finds the passes written.
#[test]
fn passes_are_written_beside_the_frames() {
    let dir = workdir();
    write(dir.path(), "tiny.json", &tiny_scene());
    let out = splatter(
        dir.path(),
        &[
            "render",
            "tiny.json",
            "--out",
            "o",
            "--passes",
            "alpha,depth",
        ],
    );
    expect_success(&out);
    let frame = image::open(dir.path().join("o/frame_00000.png"))
        .unwrap()
        .to_rgb8();
    let alpha = image::open(dir.path().join("o/alpha/frame_00000.png")).unwrap();
    assert_eq!(alpha.color(), image::ColorType::Rgba8);
    let alpha = alpha.to_rgba8();
    let (mut worst, mut covered) = (0.0f32, 0);
    for (f, a) in frame.pixels().zip(alpha.pixels()) {
        let al = f32::from(a[3]) / 255.0;
        covered += usize::from(a[3] > 0);
        // the default background is black
        for c in 0..3 {
            let over = f32::from(a[c]) / 255.0 * al;
            worst = worst.max((over - f32::from(f[c]) / 255.0).abs() * 255.0);
        }
    }
    assert!(worst <= 1.0, "composited alpha pass off by {worst}/255");
    assert!(
        covered > 100 && covered < 64 * 48,
        "{covered} pixels covered"
    );
    let (size, values) = exr_channel(&dir.path().join("o/depth/frame_00000.exr"), "Z");
    assert_eq!(size, (64, 48));
    let (mut lo, mut hi, mut infinite) = (f32::INFINITY, 0.0f32, 0);
    for (v, a) in values.iter().zip(alpha.pixels()) {
        if a[3] == 0 && !v.is_finite() {
            infinite += 1;
        } else if v.is_finite() {
            lo = lo.min(*v);
            hi = hi.max(*v);
        }
    }
    // The orbit camera is √(3² + 1²) = 3.16 from the centre of the sphere of radius 0.5.
    eprintln!("depth {lo:.3} .. {hi:.3}, {infinite} pixels at +inf");
    assert!(lo > 2.5 && hi < 3.8 && lo < hi, "depth {lo} .. {hi}");
    assert!(infinite > 100);
    let again = splatter(
        dir.path(),
        &[
            "render",
            "tiny.json",
            "--out",
            "o",
            "--passes",
            "alpha,depth",
            "--resume",
        ],
    );
    expect_success(&again);
    assert!(
        String::from_utf8_lossy(&again.stderr).contains("all written already"),
        "{}",
        describe(&again)
    );
    let bad = splatter(
        dir.path(),
        &["render", "tiny.json", "--passes", "alpha,normals"],
    );
    assert!(!bad.status.success());
    assert!(
        String::from_utf8_lossy(&bad.stderr).contains("normals"),
        "{}",
        describe(&bad)
    );
}

#[test]
fn schema_is_json_with_properties() {
    let dir = workdir();
    let out = splatter(dir.path(), &["schema"]);
    expect_success(&out);
    let v: serde_json::Value =
        serde_json::from_slice(&out.stdout).expect("`splatter schema` prints JSON");
    let props = v
        .get("properties")
        .and_then(|p| p.as_object())
        .expect("the schema has `properties`");
    for key in ["output", "camera", "objects"] {
        assert!(props.contains_key(key), "schema properties lack {key}: {v}");
    }
    // The simulation's fields and timed actions, with their parts.
    let defs = &v["$defs"];
    let has = |def: &str, keys: &[&str]| {
        for key in keys {
            assert!(
                defs[def]["properties"].get(*key).is_some(),
                "schema {def} lacks {key}"
            );
        }
    };
    has("SimulationSpec", &["fields"]);
    has("PhysicsSpec", &["actions"]);
    has(
        "ActionSpec",
        &["impulse", "hold", "drive", "region", "from", "to"],
    );
    has("ImpulseSpec", &["acceleration", "force"]);
    has("DriveSpec", &["velocity", "path"]);
}

/// `splatter info` lists the adapters, best first, four lines each (name, device type and
/// backend; driver; optional features; key limits), and the one marked chosen is the one a
/// run opens, with the features and limits it has. CI always has lavapipe, so the test asks
/// for an adapter: the no-adapter message (which also contains "adapter") fails it.
#[test]
fn info_names_an_adapter() {
    let dir = workdir();
    let out = splatter(dir.path(), &["info"]);
    expect_success(&out);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        !stdout.contains("no GPU adapter found"),
        "CI has lavapipe, so `info` should list it:\n{}",
        describe(&out)
    );
    let lines: Vec<&str> = stdout.lines().collect();
    assert!(
        !lines.is_empty() && lines.len().is_multiple_of(4),
        "four lines per adapter:\n{}",
        describe(&out)
    );
    // Block i: `adapter i: NAME (DEVICE TYPE, BACKEND)` (`  <- chosen` on the first),
    // `  driver: …`, `  features: …`, `  limits: …`.
    let mut chosen = None;
    for (i, block) in lines.chunks(4).enumerate() {
        let head = block[0]
            .strip_prefix(&format!("adapter {i}: "))
            .unwrap_or_else(|| panic!("adapter line {i}: {}", block[0]));
        let (description, is_chosen) = match head.strip_suffix("  <- chosen") {
            Some(d) => (d, true),
            None => (head, false),
        };
        assert_eq!(
            is_chosen,
            i == 0,
            "only the first adapter is chosen: {head}"
        );
        let (name, kind) = description
            .rsplit_once(" (")
            .unwrap_or_else(|| panic!("`NAME (TYPE, BACKEND)`: {description}"));
        let (device_type, backend) = kind
            .strip_suffix(')')
            .and_then(|k| k.split_once(", "))
            .unwrap_or_else(|| panic!("`(TYPE, BACKEND)`: {description}"));
        assert!(!name.trim().is_empty(), "an adapter name: {description}");
        assert!(
            ["DiscreteGpu", "IntegratedGpu", "VirtualGpu", "Cpu", "Other"].contains(&device_type),
            "a wgpu device type: {description}"
        );
        assert!(
            ["Vulkan", "Metal", "Dx12", "Gl", "BrowserWebGpu"].contains(&backend),
            "a wgpu backend: {description}"
        );
        assert!(block[1].starts_with("  driver: "), "{}", block[1]);
        let features = info_fields(
            block[2],
            "  features: ",
            &["f32 atomics", "subgroups", "timestamps"],
        );
        assert!(
            features.iter().all(|f| f == "yes" || f == "no"),
            "{}",
            block[2]
        );
        let limits = info_fields(
            block[3],
            "  limits: ",
            &[
                "storage binding",
                "buffer",
                "workgroup storage",
                "invocations/workgroup",
                "workgroups/dimension",
            ],
        );
        let limits: Vec<u64> = limits
            .iter()
            .zip(["MiB", "MiB", "KiB", "", ""])
            .map(|(v, unit)| {
                let n = v.strip_suffix(unit).unwrap_or(v).trim();
                n.parse()
                    .unwrap_or_else(|_| panic!("a number of {unit}: {v:?} in {}", block[3]))
            })
            .collect();
        assert!(limits.iter().all(|&n| n > 0), "{}", block[3]);
        if i == 0 {
            chosen = Some((description.to_string(), features, limits));
        }
    }
    // The chosen adapter is the one a run opens, with its features and limits.
    let gpu = splatter::gpu::GpuContext::new(None).expect("an adapter");
    let (description, features, limits) = chosen.unwrap();
    assert_eq!(description, gpu.describe());
    let yes = |b: bool| if b { "yes" } else { "no" };
    let f = gpu.features;
    assert_eq!(
        features,
        [yes(f.float32_atomics), yes(f.subgroups), yes(f.timestamps)]
    );
    let l = &gpu.limits;
    assert_eq!(
        limits,
        [
            l.max_storage_buffer_binding_size >> 20,
            l.max_buffer_size >> 20,
            u64::from(l.max_compute_workgroup_storage_size >> 10),
            u64::from(l.max_compute_invocations_per_workgroup),
            u64::from(l.max_compute_workgroups_per_dimension),
        ]
    );
}

/// `line` is `prefix` then `NAME VALUE` pairs separated by `, `, with these names in this
/// order; returns the values.
fn info_fields(line: &str, prefix: &str, names: &[&str]) -> Vec<String> {
    let rest = line
        .strip_prefix(prefix)
        .unwrap_or_else(|| panic!("{prefix:?}: {line}"));
    let parts: Vec<&str> = rest.split(", ").collect();
    assert_eq!(parts.len(), names.len(), "{line}");
    parts
        .iter()
        .zip(names)
        .map(|(part, name)| {
            part.strip_prefix(&format!("{name} "))
                .unwrap_or_else(|| panic!("{name:?} in {line}"))
                .to_string()
        })
        .collect()
}

#[test]
fn default_scene_is_json() {
    let dir = workdir();
    let out = splatter(dir.path(), &["default-scene"]);
    expect_success(&out);
    let v: serde_json::Value =
        serde_json::from_slice(&out.stdout).expect("`splatter default-scene` prints JSON");
    assert!(
        v.get("output").is_some() && v.get("camera").is_some(),
        "{v}"
    );
    assert!(
        v["objects"].as_array().is_some_and(|a| !a.is_empty()),
        "the default scene has objects: {v}"
    );
}

/// A backend that this machine does not have (Metal or DX12 on Linux) gives the
/// "no adapter" message, which says what to install.
#[test]
fn missing_backend_says_what_to_install() {
    if cfg!(any(target_os = "macos", target_os = "windows")) {
        return;
    }
    let dir = workdir();
    write(dir.path(), "ok.json", &tiny_scene());
    for backend in ["metal", "dx12"] {
        let out = splatter(
            dir.path(),
            &["--backend", backend, "render", "ok.json", "--out", "frames"],
        );
        let line = expect_error(&out);
        assert_mentions(&line, &["no GPU adapter", "mesa-vulkan-drivers"]);
    }
}

/// `--p2g PATH` runs the simulation's P2G on the path named (the log says which), each
/// path gives a run; float atomics with --deterministic, and an unknown path, are refused.
#[test]
fn p2g_path_can_be_forced() {
    let dir = workdir();
    write(dir.path(), "sim.json", &sim_scene(2, "", 200.0));
    for path in ["gather", "atomic", "fixed"] {
        let out = splatter(
            dir.path(),
            &["render", "sim.json", "--out", path, "--p2g", path],
        );
        expect_success(&out);
        let err = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(err.contains(&format!("P2G {path}")), "{path}: {err}");
    }
    let line = expect_error(&splatter(
        dir.path(),
        &[
            "render",
            "sim.json",
            "--out",
            "x",
            "--p2g",
            "atomic",
            "--deterministic",
        ],
    ));
    assert_mentions(&line, &["--p2g atomic", "--deterministic"]);
    let out = splatter(
        dir.path(),
        &["render", "sim.json", "--out", "y", "--p2g", "scatter"],
    );
    assert!(!out.status.success());
    assert_no_panic(&out);
}

/// A small simulated scene: a fixed-corotated cube falling in a box, `frames` frames at
/// 64×48; `dt` and `e` let a test provoke the watchdog.
fn sim_scene(frames: u32, dt: &str, e: f64) -> String {
    format!(
        r#"{{
  "output": {{"width": 64, "height": 48, "frames": {frames}, "fps": 24}},
  "camera": {{"fov_y_deg": 50, "path": {{"type": "orbit", "target": [0.3, 0.3, 0.2], "radius": 1.2, "height": 0.3}}}},
  "simulation": {{"dx": 0.05, {dt} "domain": {{"lo": [0, 0, 0], "hi": [0.6, 0.6, 0.6]}}, "ground": {{"kind": "sticky"}}}},
  "objects": [
    {{"name": "cube",
      "procedural": {{"shape": "box", "size": [0.15, 0.15, 0.15], "spacing": 0.03, "color": [0.9, 0.2, 0.2]}},
      "transform": {{"translate": [0.3, 0.3, 0.35]}},
      "physics": {{"material": {{"model": "fixed_corotated", "E": {e}, "nu": 0.3, "density": 2}}, "velocity": [0, 0, -1]}}}}
  ]
}}"#
    )
}

/// A simulated scene renders frame by frame, and what it renders is the simulated state:
/// the cube's exported Gaussians fall between frames 1 and 2 (it starts at 1 m/s downwards
/// under gravity, its bottom well above the ground), and the frames show it. The state is
/// read, not the images alone: the orbit camera moves every frame, so two images would
/// differ with the simulation frozen. The same with the FLIP/PIC blend, which carries a
/// free fall exactly too, and with two-field separation (its passes run; nothing breaks).
#[test]
fn simulated_scene_renders_moving_frames() {
    simulated_cube_falls("");
    simulated_cube_falls(r#""transfer": {"flip": 0.7},"#);
    simulated_cube_falls(r#""separation": "damage_gradient","#);
}

fn simulated_cube_falls(transfer: &str) {
    let dir = workdir();
    write(dir.path(), "sim.json", &sim_scene(3, transfer, 200.0));
    let out = splatter(
        dir.path(),
        &[
            "render",
            "sim.json",
            "--out",
            "frames",
            "--frames",
            "1..3",
            "--export-ply",
            "states",
            "--export-particles",
            "particles",
        ],
    );
    expect_success(&out);
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("simulation: "),
        "{}",
        describe(&out)
    );
    assert_eq!(
        list(&dir.path().join("frames")),
        ["frame_00001.png", "frame_00002.png"]
    );
    let mean_z = |frame: &str| {
        let path = dir.path().join("states").join(frame);
        let (cloud, _) = splatter::splat::formats::read_splats(&path).unwrap();
        cloud.positions.iter().map(|p| f64::from(p.z)).sum::<f64>() / cloud.len() as f64
    };
    // Free fall over one frame (1/24 s) from v = −1 m/s at t = 1/24 s: the centre drops
    // v·Δt + g·t·Δt + g·Δt²/2 = 0.0417 + 0.0170 + 0.0085 = 0.067.
    let drop = mean_z("frame_00001.ply") - mean_z("frame_00002.ply");
    assert!(
        (drop - 0.067).abs() < 0.01,
        "{transfer}: the cube's centre should fall 0.067 between frames 1 and 2, fell {drop}"
    );
    // The particle files: the same free fall, of the particles' centre of mass.
    let particles = |frame: &str| {
        let path = dir.path().join("particles").join(frame);
        splatter::output::particles::read(&path).unwrap()
    };
    let (a, b) = (particles("frame_00001.ply"), particles("frame_00002.ply"));
    assert_eq!(a.x.len(), b.x.len());
    assert!(!a.x.is_empty() && a.dx.is_some_and(|dx| dx > 0.0));
    let centre_z = |f: &splatter::output::particles::ParticleFile| {
        f.x.iter().map(|p| p.z).sum::<f64>() / f.x.len() as f64
    };
    let drop = centre_z(&a) - centre_z(&b);
    assert!(
        (drop - 0.067).abs() < 1e-3,
        "{transfer}: the particles' centre should fall 0.067 between frames 1 and 2, fell {drop}"
    );
}

/// `splatter fragments` on a point cloud of known pieces: two blocks of 10×10×10 points
/// (spacing 0.01) 0.05 apart and one stray point far away count as 2 pieces, 1 particle of
/// debris and 3 fragments with the link 0.015; with a link of 0.1 they are one block and
/// the stray point.
#[test]
fn fragments_counts_the_pieces_of_a_point_cloud() {
    let dir = workdir();
    let mut ply = String::new();
    let mut points = Vec::new();
    for block in [0.0, 0.14] {
        for i in 0..1000 {
            let (x, y, z) = (i % 10, (i / 10) % 10, i / 100);
            points.push([block + x as f64 * 0.01, y as f64 * 0.01, z as f64 * 0.01]);
        }
    }
    points.push([5.0, 5.0, 5.0]);
    ply.push_str(&format!(
        "ply\nformat ascii 1.0\ncomment dx 0.015\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
        points.len()
    ));
    for p in &points {
        ply.push_str(&format!("{} {} {}\n", p[0], p[1], p[2]));
    }
    write(dir.path(), "points.ply", &ply);
    let out = splatter(dir.path(), &["fragments", "points.ply"]);
    expect_success(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("2001 particles, 2 piece(s)")
            && text.contains("1 particles of debris, 3 fragments"),
        "{text}"
    );
    let out = splatter(dir.path(), &["fragments", "points.ply", "--link", "0.1"]);
    expect_success(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("1 piece(s)") && text.contains("2 fragments"),
        "{text}"
    );
    let line = expect_error(&splatter(dir.path(), &["fragments", "missing.ply"]));
    assert_mentions(&line, &["missing.ply"]);
}

/// `simulation.transfer` out of range or misspelt: one error line naming the field and
/// what it takes.
#[test]
fn bad_transfer_is_reported() {
    let line = render_scene_error(
        "flip.json",
        &sim_scene(1, r#""transfer": {"flip": 1.5},"#, 200.0),
        &[],
    );
    assert_mentions(
        &line,
        &["flip.json", "simulation.transfer.flip", "1.5", "[0, 1]"],
    );
    let line = render_scene_error(
        "pic.json",
        &sim_scene(1, r#""transfer": "pic","#, 200.0),
        &[],
    );
    assert_mentions(&line, &["pic.json", "transfer", "\"apic\"", "flip"]);
}

/// `simulation.separation` misspelt: one error line naming the value and the choices.
#[test]
fn bad_separation_is_reported() {
    let line = render_scene_error(
        "dfg.json",
        &sim_scene(1, r#""separation": "dfg","#, 200.0),
        &[],
    );
    assert_mentions(&line, &["dfg.json", "separation", "dfg", "damage_gradient"]);
}

/// `simulation.fields` with a bad value, a second wind or an unknown field: one error
/// line naming the field and what it takes.
#[test]
fn bad_fields_are_reported() {
    let wind = |drag: &str| {
        format!(r#""fields": [{{"wind": {{"velocity": [1, 0, 0], "drag": {drag}}}}}],"#)
    };
    let line = render_scene_error("drag.json", &sim_scene(1, &wind("0"), 200.0), &[]);
    assert_mentions(
        &line,
        &["drag.json", "simulation.fields[0].wind.drag", "0", "> 0"],
    );
    let two = r#""fields": [{"wind": {"velocity": [1, 0, 0], "drag": 2}}, {"wind": {"velocity": [0, 1, 0], "drag": 2}}],"#;
    let line = render_scene_error("two.json", &sim_scene(1, two, 200.0), &[]);
    assert_mentions(
        &line,
        &["two.json", "simulation.fields[1].wind", "at most one wind"],
    );
    let falloff =
        r#""fields": [{"attractor": {"point": [0, 0, 0], "strength": 1, "falloff": -1}}],"#;
    let line = render_scene_error("falloff.json", &sim_scene(1, falloff, 200.0), &[]);
    assert_mentions(
        &line,
        &[
            "falloff.json",
            "simulation.fields[0].attractor.falloff",
            "-1",
        ],
    );
    let calm = r#""fields": [{"wind": {"velocity": [1, 0, 0], "drag": 2, "gusts": {"strength": 0.5, "period": 0}}}],"#;
    let line = render_scene_error("calm.json", &sim_scene(1, calm, 200.0), &[]);
    assert_mentions(
        &line,
        &["calm.json", "simulation.fields[0].wind.gusts.period", "> 0"],
    );
    let gale = r#""fields": [{"gale": {}}],"#;
    let line = render_scene_error("gale.json", &sim_scene(1, gale, 200.0), &[]);
    assert_mentions(&line, &["gale.json", "gale", "wind", "attractor"]);
}

/// Bad timed actions: each bad value is one error line naming the file, the field, the
/// value and what was expected, and nothing is rendered.
#[test]
fn bad_actions_are_reported() {
    let with = |actions: &str| {
        sim_scene(1, "", 200.0).replace(
            r#""velocity": [0, 0, -1]}"#,
            &format!(r#""velocity": [0, 0, -1], "actions": [{actions}]}}"#),
        )
    };
    assert!(with("{}").contains(r#""actions": [{}]"#), "test setup");
    let cases: [(&str, &[&str]); 4] = [
        (
            r#"{"hold": {}, "from": 0.2, "to": 0.1}"#,
            &[
                "window.json",
                "objects[0].physics.actions[0].to",
                "0.1",
                "after `from`",
            ],
        ),
        (
            r#"{"impulse": {"acceleration": [0, 0, "up"]}}"#,
            &["window.json", "\"up\"", "expected f64"],
        ),
        (
            r#"{"hold": {}, "region": {"sphere": {"center": [0, 0, 0], "radius": 0.01}}}"#,
            &[
                "window.json",
                "objects[0].physics.actions[0].region",
                "none of the object's particles",
            ],
        ),
        (
            r#"{"drive": {"velocity": [0, 0, 1], "path": [{"time": 0, "position": [0, 0, 0]}]}}"#,
            &[
                "window.json",
                "objects[0].physics.actions[0].drive",
                "exactly one of",
            ],
        ),
    ];
    for (actions, words) in cases {
        let line = render_scene_error("window.json", &with(actions), &[]);
        assert_mentions(&line, words);
    }
}

/// A step far above the CFL bound: a warning names the suggested Δt, then the watchdog
/// stops the run with one error line naming the frame and the likely cause; frames written
/// before stay complete.
#[test]
fn watchdog_stops_an_unstable_simulation() {
    let dir = workdir();
    write(dir.path(), "bad.json", &sim_scene(6, r#""dt": 0.02,"#, 1e6));
    let out = splatter(dir.path(), &["render", "bad.json", "--out", "frames"]);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        stderr.contains("exceeds the CFL bound"),
        "{}",
        describe(&out)
    );
    let line = expect_late_error(&out);
    assert_mentions(
        &line,
        &[
            "simulation stopped",
            "before frame",
            "first at step",
            "Δt",
            "the first: particle",
            "objects[0]",
            "m/s",
            "an instability",
        ],
    );
    for name in list(&dir.path().join("frames")) {
        assert!(
            name.starts_with("frame_") && name.ends_with(".png"),
            "no partial file: {name}"
        );
        image::open(dir.path().join("frames").join(&name))
            .expect("every written frame is a complete PNG");
    }
}

/// `physics` without a `simulation` block, and bad material values, are named.
#[test]
fn bad_simulation_input_is_named() {
    let dir = workdir();
    let no_block = sim_scene(1, "", 200.0).replace(
        r#""simulation": {"dx": 0.05,  "domain": {"lo": [0, 0, 0], "hi": [0.6, 0.6, 0.6]}, "ground": {"kind": "sticky"}},"#,
        "",
    );
    assert!(!no_block.contains("\"simulation\""), "test setup");
    write(dir.path(), "a.json", &no_block);
    let line = expect_error(&splatter(dir.path(), &["render", "a.json", "--out", "f"]));
    assert_mentions(&line, &["objects[0].physics", "simulation"]);
    write(dir.path(), "b.json", &sim_scene(1, "", -5.0));
    let line = expect_error(&splatter(dir.path(), &["render", "b.json", "--out", "f"]));
    assert_mentions(&line, &["objects[0].physics.material.E", "-5"]);
    write(
        dir.path(),
        "c.json",
        &sim_scene(1, r#""cfl_velocity": 0,"#, 200.0),
    );
    let line = expect_error(&splatter(dir.path(), &["render", "c.json", "--out", "f"]));
    assert_mentions(&line, &["simulation.cfl_velocity", "0", "(0, 1]"]);
}

/// `--export-ply DIR`, `--export-spz DIR` and `--export-glb DIR` write one standard 3DGS
/// PLY, one SPZ and one GLB per rendered frame, readable back, with the simulated object
/// moved between frames, the same Gaussians in all three (within SPZ's quantisation; the
/// GLB turned from the z-up world into glTF's y-up frame) and the region labels in all.
#[test]
fn export_ply_spz_and_glb_write_a_cloud_per_frame() {
    let dir = workdir();
    write(dir.path(), "sim.json", &sim_scene(2, "", 200.0));
    let out = splatter(
        dir.path(),
        &[
            "render",
            "sim.json",
            "--out",
            "frames",
            "--export-ply",
            "plys",
            "--export-spz",
            "spzs",
            "--export-glb",
            "glbs",
        ],
    );
    expect_success(&out);
    assert_eq!(
        list(&dir.path().join("plys")),
        ["frame_00000.ply", "frame_00001.ply"]
    );
    assert_eq!(
        list(&dir.path().join("spzs")),
        ["frame_00000.spz", "frame_00001.spz"]
    );
    let read = |sub: &str, name: &str| {
        splatter::splat::formats::read_splats(&dir.path().join(sub).join(name))
            .unwrap()
            .0
    };
    let (a, b) = (
        read("plys", "frame_00000.ply"),
        read("plys", "frame_00001.ply"),
    );
    assert_eq!(a.len(), b.len());
    assert_ne!(
        a.positions, b.positions,
        "the cube should move between the exported frames"
    );
    let s = read("spzs", "frame_00001.spz");
    assert_eq!(s.len(), b.len());
    let worst = s
        .positions
        .iter()
        .zip(&b.positions)
        .map(|(p, q)| p.distance(*q))
        .fold(0.0f32, f32::max);
    assert!(
        worst < 2.2e-4,
        "SPZ positions within 12 fractional bits: {worst}"
    );
    assert_eq!(s.labels, b.labels);
    assert_eq!(s.label_names, b.label_names);
    let size = |sub: &str, name: &str| {
        std::fs::metadata(dir.path().join(sub).join(name))
            .unwrap()
            .len()
    };
    println!(
        "frame 1: PLY {} bytes, SPZ {} bytes; labels {:?}",
        size("plys", "frame_00001.ply"),
        size("spzs", "frame_00001.spz"),
        s.label_names
    );
    assert!(size("spzs", "frame_00001.spz") * 5 < size("plys", "frame_00001.ply"));

    assert_eq!(
        list(&dir.path().join("glbs")),
        ["frame_00000.glb", "frame_00001.glb"]
    );
    // Read back, a GLB is held in a PLY's frame (glTF's +y up is -y): the world's z up
    // went to glTF's +y, so the world's (x, y, z) reads back as (-x, -z, -y).
    let g = read("glbs", "frame_00001.glb");
    assert_eq!(g.len(), b.len());
    for (p, q) in g.positions.iter().zip(&b.positions) {
        assert_eq!(*p, Vec3::new(-q.x, -q.z, -q.y));
    }
    let turn = Quat::from_mat3(&glam::Mat3::from_cols(-Vec3::X, -Vec3::Z, -Vec3::Y));
    for (r, q) in g.rotations.iter().zip(&b.rotations) {
        assert!(r.dot(turn * *q).abs() > 1.0 - 1e-5, "{r} vs {q}");
    }
    // The PLY keeps log-scales and logit opacities (a rounding from the linear values the
    // GLB keeps as they are).
    for (s, t) in g.scales.iter().zip(&b.scales) {
        assert!((*s / *t - 1.0).abs().max_element() < 1e-6, "{s} vs {t}");
    }
    for (o, p) in g.opacities.iter().zip(&b.opacities) {
        assert!((o - p).abs() < 1e-6, "{o} vs {p}");
    }
    assert_eq!(g.labels, b.labels);
    assert_eq!(g.label_names, b.label_names);
    let up = splatter::splat::formats::read_splats(&dir.path().join("glbs/frame_00001.glb"))
        .unwrap()
        .1
        .up;
    assert_eq!(up.map(|u| u.axis), Some("-y"), "glTF's up, declared");
}

/// Damaged and unsupported splat files (the messages docs/formats.md quotes): one `error:`
/// line each, naming the file, the format
/// it looks like and what is wrong (`inspect` reads them as `render --ply` and scenes do).
#[test]
fn damaged_splat_files_get_one_error_line_each() {
    let dir = workdir();
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/formats");
    let read = |name: &str| std::fs::read(fixtures.join(name)).unwrap();
    let put = |name: &str, bytes: &[u8]| std::fs::write(dir.path().join(name), bytes).unwrap();

    // A truncated SPZ (the gzip stream cut in the middle of its data).
    let v3 = read("donut_4k.v3.spz");
    put("truncated.spz", &v3[..v3.len() / 2]);
    // A corrupt gzip stream: bytes of the deflate data overwritten.
    let mut corrupt = v3.clone();
    for b in &mut corrupt[40..80] {
        *b = 0xff;
    }
    put("corrupt.spz", &corrupt);
    // An unknown SPZ version: a version-4 header saying 7.
    let mut v7 = read("donut_4k.v4.spz");
    v7[4] = 7;
    put("version7.spz", &v7);
    // A .splat whose size is not a multiple of 32 bytes.
    let splat = read("donut_4k.splat");
    put("odd.splat", &splat[..1000]);
    // A SOG folder with an image missing.
    let sog = dir.path().join("missing_sog");
    std::fs::create_dir(&sog).unwrap();
    for f in [
        "meta.json",
        "means_l.webp",
        "quats.webp",
        "scales.webp",
        "sh0.webp",
    ] {
        std::fs::copy(fixtures.join("donut_4k_sog").join(f), sog.join(f)).unwrap();
    }
    // A compressed.ply whose chunk count does not match its vertices.
    let cply = read("donut_4k.compressed.ply");
    let text = String::from_utf8_lossy(&cply[..600]).into_owned();
    let at = text.find("element chunk 17").unwrap();
    let mut bad = cply.clone();
    bad[at..at + 16].copy_from_slice(b"element chunk 16");
    put("chunks.compressed.ply", &bad);

    for (file, needles) in [
        (
            "truncated.spz",
            &["truncated.spz", "SPZ", "gzip stream"][..],
        ),
        (
            "corrupt.spz",
            &["corrupt.spz", "damaged SPZ", "gzip stream"][..],
        ),
        (
            "version7.spz",
            &["version7.spz", "SPZ version 7", "versions 1 to 4"][..],
        ),
        ("odd.splat", &["odd.splat", ".splat", "32-byte records"][..]),
        ("missing_sog", &["missing_sog", "SOG", "means_u.webp"][..]),
        (
            "chunks.compressed.ply",
            &[
                "chunks.compressed.ply",
                "compressed PLY",
                "16 chunks for 4148 vertices",
            ][..],
        ),
    ] {
        let line = expect_error(&splatter(dir.path(), &["inspect", file]));
        println!("{line}");
        assert_mentions(&line, needles);
    }
}

// ---------------------------------------------------------------------------------------------
// convert, and glTF / GLB input
// ---------------------------------------------------------------------------------------------

/// A cloud with everything a format may keep or lose: SH degree 3, unit quaternions in all
/// directions, opacities over (0, 1), colours within SPZ's DC range and region labels.
fn rich_cloud(n: usize) -> GaussianCloud {
    let wave = |i: usize, k: usize| ((i * 7 + k * 13) as f32 * 0.37).sin();
    let mut c = GaussianCloud {
        sh_degree: 3,
        label_names: vec!["flesh".into(), "rind".into(), "seeds".into()],
        ..Default::default()
    };
    for i in 0..n {
        c.positions
            .push(Vec3::new(wave(i, 0), wave(i, 1), wave(i, 2)) * 0.4);
        c.scales
            .push(Vec3::new(0.01, 0.02, 0.03) * (1.5 + wave(i, 3)));
        c.rotations
            .push(Quat::from_xyzw(wave(i, 4), wave(i, 5), wave(i, 6), wave(i, 7)).normalize());
        c.opacities.push(0.5 + 0.45 * wave(i, 8));
        c.sh.extend((0..48).map(|k| if k < 3 { 2.0 } else { 0.4 } * wave(i, 9 + k)));
        c.labels.push((i % 3) as u16);
    }
    c
}

/// Per-field largest errors of `b` against `a` (same order): position, relative scale,
/// opacity, DC, rest SH, rotation (1 - |q·q'|).
fn field_errors(a: &GaussianCloud, b: &GaussianCloud) -> [f32; 6] {
    assert_eq!(a.len(), b.len(), "count");
    let mut e = [0.0f32; 6];
    for i in 0..a.len() {
        let (sa, sb) = (a.sh_of(i), b.sh_of(i));
        let got = [
            (a.positions[i] - b.positions[i]).abs().max_element(),
            (b.scales[i] / a.scales[i] - 1.0).abs().max_element(),
            (a.opacities[i] - b.opacities[i]).abs(),
            (0..3).map(|k| (sa[k] - sb[k]).abs()).fold(0.0, f32::max),
            (3..48).map(|k| (sa[k] - sb[k]).abs()).fold(0.0, f32::max),
            1.0 - a.rotations[i].dot(b.rotations[i]).abs(),
        ];
        for (w, g) in e.iter_mut().zip(got) {
            *w = w.max(g);
        }
    }
    e
}

/// `splatter convert` PLY → GLB → PLY and PLY → SPZ → PLY: one summary line each (counts
/// and formats), the Gaussians back within each format's precision (GLB: float32 as the
/// PLY, so to rounding; SPZ: its quantisation), the order and the labels kept.
#[test]
fn convert_round_trips_through_glb_and_spz() {
    let dir = workdir();
    let source = rich_cloud(500);
    write_ply(
        &dir.path().join("in.ply"),
        &source,
        PlyFormat::BinaryLittleEndian,
    )
    .unwrap();
    let read = |name: &str| {
        splatter::splat::formats::read_splats(&dir.path().join(name))
            .unwrap()
            .0
    };
    let reference = read("in.ply");
    // position, relative scale, opacity, DC, rest SH, 1 - |q·q'|
    for (via, limits, format) in [
        ("glb", [0.0, 1e-6, 1e-6, 0.0, 0.0, 1e-6], "glTF GLB"),
        (
            "spz",
            [2.5e-4, 0.033, 0.0021, 0.014, 0.07, 1e-4],
            "SPZ version 3",
        ),
    ] {
        let mid = format!("mid.{via}");
        let back = format!("back_{via}.ply");
        for (from, to) in [("in.ply", mid.as_str()), (mid.as_str(), back.as_str())] {
            let out = splatter(dir.path(), &["convert", from, to]);
            expect_success(&out);
            let line = String::from_utf8_lossy(&out.stdout).trim().to_string();
            println!("{line}");
            assert_eq!(line.lines().count(), 1, "one summary line: {line}");
            assert_mentions(&line, &[from, to, "500 Gaussians (SH degree 3)", format]);
        }
        let e = field_errors(&reference, &read(&back));
        println!("PLY → {via} → PLY: {e:?}");
        for ((name, got), limit) in ["position", "scale", "opacity", "DC", "SH", "rotation"]
            .iter()
            .zip(e)
            .zip(limits)
        {
            assert!(got <= limit, "via {via}: {name} error {got} above {limit}");
        }
        let back = read(&back);
        assert_eq!(back.labels, reference.labels, "via {via}: labels");
        assert_eq!(back.label_names, reference.label_names, "via {via}: names");
    }
}

/// An output extension we do not write, and an input that is not there: one error line,
/// nothing written.
#[test]
fn convert_refuses_what_it_cannot_write() {
    let dir = workdir();
    write_tiny_ply(dir.path(), "in.ply", 10);
    for (out, needles) in [
        (
            "out.sog",
            &["out.sog", "SOG is read, not written", ".glb"][..],
        ),
        ("out.gltf", &["out.gltf", ".glb only"][..]),
        (
            "out.compressed.ply",
            &["out.compressed.ply", "compressed PLY"][..],
        ),
        (
            "out.obj",
            &["out.obj", ".obj", ".ply", ".spz", ".splat", ".glb"][..],
        ),
    ] {
        let line = expect_error(&splatter(dir.path(), &["convert", "in.ply", out]));
        assert_mentions(&line, needles);
        assert!(!dir.path().join(out).exists(), "{out} written");
    }
    let line = expect_error(&splatter(dir.path(), &["convert", "none.ply", "out.glb"]));
    assert_mentions(&line, &["none.ply"]);
    assert!(!dir.path().join("out.glb").exists());
}

/// The GLB fixture (splat-transform's) with its JSON edited by `edit`.
fn edited_glb(edit: impl FnOnce(&mut serde_json::Value)) -> Vec<u8> {
    let fixture =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/formats/donut_300_sh3.glb");
    let glb = std::fs::read(fixture).unwrap();
    let len = |at: usize| u32::from_le_bytes(glb[at..at + 4].try_into().unwrap()) as usize;
    let json_len = len(12);
    let mut json: serde_json::Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    edit(&mut json);
    let mut text = serde_json::to_vec(&json).unwrap();
    text.resize(text.len().next_multiple_of(4), b' ');
    let bin = &glb[20 + json_len..];
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((20 + text.len() + bin.len()) as u32).to_le_bytes());
    out.extend((text.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(text);
    out.extend(bin);
    out
}

/// The accessor index of attribute `name` in the fixture's primitive.
fn attribute(json: &serde_json::Value, name: &str) -> usize {
    json["meshes"][0]["primitives"][0]["attributes"][name]
        .as_u64()
        .unwrap() as usize
}

/// Bad glTF files: one `error:` line each, naming the file, the format and what is wrong
/// (the field, its value and what was expected), from `inspect` as from every reader.
#[test]
fn damaged_glb_files_get_one_error_line_each() {
    let dir = workdir();
    let put = |name: &str, bytes: &[u8]| std::fs::write(dir.path().join(name), bytes).unwrap();
    let good = edited_glb(|_| {});
    put("truncated.glb", &good[..good.len() / 2]);
    put(
        "mesh.glb",
        &edited_glb(|j| {
            let p = &mut j["meshes"][0]["primitives"][0];
            p.as_object_mut().unwrap().remove("extensions");
            p["mode"] = 4.into();
            j["extensionsUsed"] = serde_json::json!([]);
        }),
    );
    put(
        "vec4_scale.glb",
        &edited_glb(|j| {
            let a = attribute(j, "KHR_gaussian_splatting:SCALE");
            j["accessors"][a]["type"] = "VEC4".into();
        }),
    );
    put(
        "byte_rotation.glb",
        &edited_glb(|j| {
            let a = attribute(j, "KHR_gaussian_splatting:ROTATION");
            j["accessors"][a]["componentType"] = 5121.into();
            j["accessors"][a]["normalized"] = true.into();
        }),
    );
    put(
        "count.glb",
        &edited_glb(|j| {
            let a = attribute(j, "KHR_gaussian_splatting:OPACITY");
            j["accessors"][a]["count"] = 299.into();
        }),
    );
    put(
        "partial_sh.glb",
        &edited_glb(|j| {
            let attrs = j["meshes"][0]["primitives"][0]["attributes"]
                .as_object_mut()
                .unwrap();
            attrs.remove("KHR_gaussian_splatting:SH_DEGREE_2_COEF_3");
        }),
    );
    put(
        "gltf.gltf",
        br#"{"asset": {"version": "2.0"}, "buffers": [{"uri": "missing.bin", "byteLength": 4}]}"#,
    );
    for (file, needles) in [
        (
            "truncated.glb",
            &["truncated.glb", "damaged glTF", "truncated", "76532 bytes"][..],
        ),
        (
            "mesh.glb",
            &[
                "mesh.glb",
                "glTF",
                "without KHR_gaussian_splatting",
                "extensionsUsed: none",
            ][..],
        ),
        (
            "vec4_scale.glb",
            &[
                "vec4_scale.glb",
                "KHR_gaussian_splatting:SCALE",
                "type VEC4, expected VEC3",
            ][..],
        ),
        (
            "byte_rotation.glb",
            &[
                "byte_rotation.glb",
                "KHR_gaussian_splatting:ROTATION",
                "componentType 5121 (unsigned byte normalized)",
                "expected float, signed byte normalized, signed short normalized",
            ][..],
        ),
        (
            "count.glb",
            &[
                "count.glb",
                "KHR_gaussian_splatting:OPACITY",
                "299 elements, POSITION has 300",
            ][..],
        ),
        (
            "partial_sh.glb",
            &[
                "partial_sh.glb",
                "SH degree 2 is partly defined",
                "4 of its 5",
            ][..],
        ),
        ("gltf.gltf", &["gltf.gltf", "buffer 0", "missing.bin"][..]),
    ] {
        let line = expect_error(&splatter(dir.path(), &["inspect", file]));
        println!("{line}");
        assert_mentions(&line, needles);
    }
}

/// The old `bench suite` and `bench accuracy` run the lab's commands with the same
/// arguments (scripts written for them keep working): the lab's own refusal comes back as
/// one error line and a non-zero exit.
#[test]
fn bench_accuracy_and_suite_forward_to_the_lab() {
    let dir = tempfile::tempdir().unwrap();
    let line = expect_error(&splatter(dir.path(), &["bench", "accuracy", "--quick"]));
    assert_mentions(&line, &["--quick", "--out"]);
    let line = expect_error(&splatter(dir.path(), &["bench", "suite", "--scale=0"]));
    assert_mentions(&line, &["--scale 0", "positive"]);
}

/// `bench sim --separation` steps the NACC case with two fields: its passes include the
/// damage field, on the gather path.
#[test]
fn bench_sim_with_separation_runs_the_separation_passes() {
    let dir = tempfile::tempdir().unwrap();
    let out = splatter(
        dir.path(),
        &[
            "bench",
            "sim",
            "--quick",
            "--steps",
            "2",
            "--per-pass",
            "--separation",
        ],
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    assert!(stdout.contains("nacc, two fields  gather"), "{stdout}");
    assert!(stdout.contains("damage field"), "{stdout}");
    assert!(!stdout.contains("fixed_corotated"), "{stdout}");
}
