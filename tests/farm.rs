//! Render farms (`docs/farm.md`): a simulated run exports its per-frame states with
//! `--export-ply`; `--from-states` renders any frame range from them without simulating.
//! A two-machine split, reproduced here with two processes running at the same time into
//! one folder, gives frames byte-identical to a single process rendering every frame.

mod common;

use std::process::Stdio;

use common::cli::{command, expect_success, frames_in, splatter as run};
use splatter::render::cpu::psnr;
use tempfile::TempDir;

/// A jelly cube on a static checker slab (static and simulated Gaussians), 6 frames.
const SCENE: &str = r#"{
  "output": {"width": 64, "height": 48, "frames": 6, "fps": 12, "background": [0.1, 0.1, 0.15]},
  "camera": {"fov_y_deg": 50, "path": {"type": "orbit", "target": [0.3, 0.3, 0.2], "radius": 1.2, "height": 0.3, "turns": 0.2}},
  "simulation": {"dx": 0.05, "domain": {"lo": [0, 0, 0], "hi": [0.6, 0.6, 0.6]}, "ground": {"kind": "sticky"}},
  "objects": [
    {"name": "ground",
     "procedural": {"shape": "slab", "size": [0.8, 0.8], "thickness": 0.04, "spacing": 0.04, "color": [0.6, 0.6, 0.6],
                    "checker": {"period": 0.1, "colors": [[0.85, 0.85, 0.85], [0.3, 0.3, 0.35]]}},
     "transform": {"translate": [0.3, 0.3, 0.06]}},
    {"name": "cube",
     "procedural": {"shape": "box", "size": [0.15, 0.15, 0.15], "spacing": 0.03, "color": [0.2, 0.8, 0.3]},
     "transform": {"translate": [0.3, 0.3, 0.35], "rotate_deg": [20, 10, 0]},
     "physics": {"material": {"model": "fixed_corotated", "E": 300, "nu": 0.3, "density": 2}, "velocity": [0, 0, -1.5]}}
  ]
}"#;

#[test]
fn a_split_over_two_processes_equals_a_single_run() {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    std::fs::write(d.join("scene.json"), SCENE).unwrap();

    // Simulate once, exporting the states (the "simulation machine").
    expect_success(&run(
        d,
        &[
            "render",
            "scene.json",
            "--out",
            "sim",
            "--export-ply",
            "states",
            "--deterministic",
        ],
    ));

    // One process renders every frame from the states.
    expect_success(&run(
        d,
        &[
            "render",
            "scene.json",
            "--from-states",
            "states",
            "--out",
            "single",
        ],
    ));

    // Two "machines": two processes at the same time, one folder, half the frames each.
    let spawn = |range: &str| {
        command(
            d,
            &[
                "render",
                "scene.json",
                "--from-states",
                "states",
                "--frames",
                range,
                "--out",
                "split",
            ],
        )
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn")
    };
    let (a, b) = (spawn("0..3"), spawn("3..6"));
    expect_success(&a.wait_with_output().unwrap());
    expect_success(&b.wait_with_output().unwrap());

    let names = frames_in(&d.join("single"));
    assert_eq!(names.len(), 6);
    assert_eq!(frames_in(&d.join("split")), names);
    for name in &names {
        let x = std::fs::read(d.join("single").join(name)).unwrap();
        let y = std::fs::read(d.join("split").join(name)).unwrap();
        assert!(x == y, "{name}: the split differs from the single run");
    }
    // Each job kept its own manifest; the single run has the whole-range one.
    assert!(d.join("split/manifest_00000-00003.json").is_file());
    assert!(d.join("split/manifest_00003-00006.json").is_file());
    let m: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("single/manifest.json")).unwrap()).unwrap();
    assert_eq!(m["status"], "complete");
    assert_eq!(m["settings"]["from_states"], "states");
    assert!(m["frames"]["2"]["load_ms"].as_f64().unwrap() > 0.0);

    // The states reproduce the simulated run's frames up to the export's rounding
    // (covariance → scale + rotation, SH rotated into the world frame): PSNR ≥ 35 dB.
    for name in &names {
        let a = image::open(d.join("sim").join(name)).unwrap().to_rgb8();
        let b = image::open(d.join("single").join(name)).unwrap().to_rgb8();
        let p = psnr(a.as_raw(), b.as_raw());
        eprintln!("{name}: states vs simulated run {p:.1} dB");
        assert!(
            p >= 35.0,
            "{name}: PSNR {p:.1} dB against the simulated run"
        );
    }
    let first = std::fs::read(d.join("single/frame_00000.png")).unwrap();
    let last = std::fs::read(d.join("single/frame_00005.png")).unwrap();
    assert_ne!(first, last, "the frames differ (camera and cube move)");
}

#[test]
fn missing_states_are_reported_before_rendering() {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    std::fs::write(d.join("scene.json"), SCENE).unwrap();
    std::fs::create_dir_all(d.join("states")).unwrap();
    let out = run(
        d,
        &[
            "render",
            "scene.json",
            "--from-states",
            "states",
            "--frames",
            "2..5",
            "--out",
            "o",
        ],
    );
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains("3 of the 3 frame states") && err.contains("frame_00002.ply"),
        "{err}"
    );
    assert!(frames_in(&d.join("o")).is_empty());

    // A state that is not a PLY names the file.
    std::fs::write(d.join("states/frame_00000.ply"), b"not a ply").unwrap();
    let out = run(
        d,
        &[
            "render",
            "scene.json",
            "--from-states",
            "states",
            "--frames",
            "0",
            "--out",
            "o",
        ],
    );
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("states/frame_00000.ply") && !err.contains("panicked"),
        "{err}"
    );
}
