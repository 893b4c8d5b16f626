//! Render farms (`docs/farm.md`): a simulated run exports its per-frame states with
//! `--export-ply`; `--from-states` renders any frame range from them without simulating.
//! A two-machine split, reproduced here with two processes running at the same time into
//! one folder, gives frames byte-identical to a single process rendering every frame.
//! Render managers' frame lists (`--frames 1-3,5,7-20:2`) and array tasks (`--chunk N`
//! with `--task-index` or `SLURM_ARRAY_TASK_ID`) write exactly their frames.

mod common;

use std::process::Stdio;

use common::cli::{
    assert_mentions, command, describe, expect_error, expect_success, frames_in, splatter as run,
    splatter_env, stderr_lines,
};
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
    // A simulated run of a set with gaps simulates every frame up to its last but writes
    // only the frames listed, identical to the full run's.
    expect_success(&run(
        d,
        &[
            "render",
            "scene.json",
            "--out",
            "gaps",
            "--frames",
            "1,4-5",
            "--deterministic",
        ],
    ));
    let gaps = frames_in(&d.join("gaps"));
    assert_eq!(
        gaps,
        ["frame_00001.png", "frame_00004.png", "frame_00005.png"]
    );
    for name in &gaps {
        let x = std::fs::read(d.join("sim").join(name)).unwrap();
        let y = std::fs::read(d.join("gaps").join(name)).unwrap();
        assert!(x == y, "{name}: the run of 1,4-5 differs from the full run");
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

/// A static scene of 21 frames (an orbit round a checker slab and a box), 32×24.
const SCENE_21: &str = r#"{
  "output": {"width": 32, "height": 24, "frames": 21, "fps": 12, "background": [0.1, 0.1, 0.15]},
  "camera": {"fov_y_deg": 50, "path": {"type": "orbit", "target": [0.3, 0.3, 0.1], "radius": 1.2, "height": 0.3, "turns": 0.5}},
  "objects": [
    {"name": "ground",
     "procedural": {"shape": "slab", "size": [0.8, 0.8], "thickness": 0.04, "spacing": 0.05, "color": [0.6, 0.6, 0.6],
                    "checker": {"period": 0.1, "colors": [[0.85, 0.85, 0.85], [0.3, 0.3, 0.35]]}},
     "transform": {"translate": [0.3, 0.3, 0.06]}},
    {"name": "box",
     "procedural": {"shape": "box", "size": [0.15, 0.15, 0.15], "spacing": 0.04, "color": [0.2, 0.8, 0.3]},
     "transform": {"translate": [0.3, 0.3, 0.2]}}
  ]
}"#;

/// A folder with `scene.json` (21 frames) and `states/frame_00000.ply` … `frame_00020.ply`:
/// frame 0's exported state copied to every frame, which is all `--from-states` needs
/// (the camera still moves, so the frames differ).
fn states_of_21_frames() -> TempDir {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    std::fs::write(d.join("scene.json"), SCENE_21).unwrap();
    expect_success(&run(
        d,
        &[
            "render",
            "scene.json",
            "--frames",
            "0",
            "--export-ply",
            "states",
            "--out",
            "first",
        ],
    ));
    for f in 1..21 {
        std::fs::copy(
            d.join("states/frame_00000.ply"),
            d.join(format!("states/frame_{f:05}.ply")),
        )
        .unwrap();
    }
    dir
}

/// `render scene.json --from-states states --out OUT ARGS…` with `env`.
fn render_states(
    d: &std::path::Path,
    out: &str,
    args: &[&str],
    env: &[(&str, &str)],
) -> std::process::Output {
    let mut all = vec![
        "render",
        "scene.json",
        "--from-states",
        "states",
        "--out",
        out,
    ];
    all.extend_from_slice(args);
    splatter_env(d, &all, env)
}

/// The one manifest in `dir`: its name and content.
fn only_manifest(dir: &std::path::Path) -> (String, serde_json::Value) {
    let found: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("manifest"))
        .collect();
    assert_eq!(found.len(), 1, "{found:?}");
    let m = serde_json::from_slice(&std::fs::read(dir.join(&found[0])).unwrap()).unwrap();
    (found[0].clone(), m)
}

fn names(frames: &[u32]) -> Vec<String> {
    frames.iter().map(|f| format!("frame_{f:05}.png")).collect()
}

#[test]
fn a_frame_list_renders_exactly_its_frames() {
    let dir = states_of_21_frames();
    let d = dir.path();
    let out = render_states(d, "list", &["--frames", "1-3,5,7-20:2"], &[]);
    expect_success(&out);
    assert_eq!(
        frames_in(&d.join("list")),
        names(&[1, 2, 3, 5, 7, 9, 11, 13, 15, 17, 19])
    );
    // Its manifest is named by the span and the set, and lists the frames.
    let (name, m) = only_manifest(&d.join("list"));
    assert!(name.starts_with("manifest_00001-00020_"), "{name}");
    assert_eq!(m["status"], "complete");
    assert_eq!(m["settings"]["frame_list"], "1-3,5-19:2");
    assert_eq!(m["settings"]["frames"], serde_json::json!([1, 20]));
    assert_eq!(m["frames"].as_object().unwrap().len(), 11);

    // The same frames as a render of all of them, byte for byte.
    expect_success(&render_states(d, "all", &[], &[]));
    for name in frames_in(&d.join("list")) {
        let x = std::fs::read(d.join("all").join(&name)).unwrap();
        let y = std::fs::read(d.join("list").join(&name)).unwrap();
        assert!(
            x == y,
            "{name}: the list's frame differs from the full render's"
        );
    }
}

#[test]
fn an_array_task_renders_its_chunk() {
    let dir = states_of_21_frames();
    let d = dir.path();
    let list = ["--frames", "1-3,5,7-20:2", "--chunk", "4"];
    let slurm = [("SLURM_ARRAY_TASK_ID", "1")];

    // Chunk 1 of 4 frames of the sorted set 1,2,3,5 | 7,9,11,13 | 15,17,19.
    expect_success(&render_states(d, "slurm", &list, &slurm));
    assert_eq!(frames_in(&d.join("slurm")), names(&[7, 9, 11, 13]));
    let (name, m) = only_manifest(&d.join("slurm"));
    assert!(name.starts_with("manifest_00007-00014_"), "{name}");
    assert_eq!(
        m["settings"]["chunk"],
        serde_json::json!({"size": 4, "index": 1, "index_from": "SLURM_ARRAY_TASK_ID"})
    );

    // --task-index wins over the environment; the last chunk is clamped to the set.
    let flag = [&list[..], &["--task-index", "2"]].concat();
    expect_success(&render_states(d, "flag", &flag, &slurm));
    assert_eq!(frames_in(&d.join("flag")), names(&[15, 17, 19]));

    // A Kubernetes Indexed Job's pod.
    let k8s = [("JOB_COMPLETION_INDEX", "0")];
    expect_success(&render_states(d, "k8s", &list, &k8s));
    assert_eq!(frames_in(&d.join("k8s")), names(&[1, 2, 3, 5]));

    // A task past the last chunk renders nothing, says so, and succeeds.
    let out = render_states(d, "idle", &list, &[("SLURM_ARRAY_TASK_ID", "3")]);
    expect_success(&out);
    let said = stderr_lines(&out).join("\n");
    assert_mentions(
        &said,
        &["task 3", "nothing to render", "3 chunks, tasks 0-2"],
    );
    assert!(!d.join("idle").exists(), "an idle task writes nothing");

    // Without an index, --chunk is refused.
    let line = expect_error(&render_states(d, "none", &list, &[]));
    assert_mentions(&line, &["--chunk 4", "no task index", "--task-index"]);
}

#[test]
fn a_frame_list_outside_the_scene_is_one_error_line() {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    std::fs::write(d.join("scene.json"), SCENE_21).unwrap();
    std::fs::create_dir(d.join("states")).unwrap();
    let line = expect_error(&render_states(d, "o", &["--frames", "1-3,5,7-40:2"], &[]));
    assert_mentions(
        &line,
        &[
            "--frames \"1-3,5,7-40:2\"",
            "frame 39",
            "7-40:2",
            "expected 0-20 (21 frames)",
        ],
    );
    let line = expect_error(&render_states(d, "o", &["--frames", "5-1"], &[]));
    assert_mentions(&line, &["5-1", "backwards"]);
    assert!(frames_in(&d.join("o")).is_empty());
}

/// `docs/jobs/run_openjd_local.sh`: the Open Job Description template run by the `openjd`
/// CLI (simulate, then render tasks given frame lists with gaps), its frames exactly the
/// listed ones and byte-identical to one process rendering them. It needs openjd-cli
/// (`pip install openjd-cli`; `OPENJD` names the program when it is not `openjd` on the
/// PATH), which CI does not install: without it the test says so and passes.
#[test]
fn the_openjd_template_gives_a_single_runs_frames() {
    let openjd = std::env::var("OPENJD").unwrap_or_else(|_| "openjd".into());
    if std::process::Command::new(&openjd)
        .arg("--version")
        .output()
        .is_err()
    {
        eprintln!("skipped: no `{openjd}` program (pip install openjd-cli, or set OPENJD)");
        return;
    }
    let dir = TempDir::new().unwrap();
    let script = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/jobs/run_openjd_local.sh");
    let out = std::process::Command::new(script)
        .arg(dir.path().join("work"))
        .env("SPLATTER", env!("CARGO_BIN_EXE_splatter"))
        .env("OPENJD", &openjd)
        .output()
        .expect("the script runs");
    assert!(out.status.success(), "{}", describe(&out));
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(said.contains("OK: 10 frames"), "{said}");
}
