//! Long runs that survive, end to end through the binary: a run killed midway
//! and resumed from its checkpoint gives the frames of an uninterrupted run (byte-identical
//! in deterministic mode); deterministic runs of a fracture scene are byte-identical; the
//! run manifest; checkpoints of another scene or mode refused; buffer limits checked before
//! GPU allocation; I/O errors that name the path and cause; `--video`.
//!
//! The kill is the `SPLATTER_FAIL_AT_FRAME=k` test hook: the process exits at once (status
//! 86) just before frame k, losing frames still queued for writing, as a crash would.
//! Renders are tiny (64×48) so that each run takes about a second on lavapipe.

mod common;

use std::path::Path;
use std::process::Output;

use common::cli::{
    describe, expect_late_error as expect_error, expect_success, frames_in, splatter, splatter_env,
    write,
};
use tempfile::TempDir;

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn bytes(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Frames of `a` and `b` (same names expected) compared byte for byte.
fn assert_same_frames(a: &Path, b: &Path, count: usize) {
    let names = frames_in(a);
    assert_eq!(names.len(), count, "{}: {names:?}", a.display());
    assert_eq!(names, frames_in(b));
    for name in &names {
        assert!(
            bytes(&a.join(name)) == bytes(&b.join(name)),
            "{name} differs between {} and {}",
            a.display(),
            b.display()
        );
    }
}

/// An elastic cube falling onto the ground: `frames` frames at 64×48 (125 particles, 25
/// steps per frame).
fn sim_scene(frames: u32, e: f64) -> String {
    sim_scene_with(frames, e, r#"{ "spacing": 0.03 }"#)
}

/// [`sim_scene`] with the cube's `physics.particles` as given.
fn sim_scene_with(frames: u32, e: f64, particles: &str) -> String {
    format!(
        r#"{{
  "output": {{"width": 64, "height": 48, "frames": {frames}, "fps": 24}},
  "camera": {{"fov_y_deg": 50, "path": {{"type": "orbit", "target": [0.3, 0.3, 0.2], "radius": 1.2, "height": 0.3}}}},
  "simulation": {{"dx": 0.05, "domain": {{"lo": [0, 0, 0], "hi": [0.6, 0.6, 0.6]}}, "ground": {{"kind": "sticky"}}}},
  "objects": [
    {{"name": "cube",
      "procedural": {{"shape": "box", "size": [0.15, 0.15, 0.15], "spacing": 0.03, "color": [0.9, 0.2, 0.2]}},
      "transform": {{"translate": [0.3, 0.3, 0.35]}},
      "physics": {{"material": {{"model": "fixed_corotated", "E": {e}, "nu": 0.3, "density": 2}}, "velocity": [0, 0, -1], "particles": {particles}}}}}
  ]
}}"#
    )
}

fn manifest(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&bytes(&dir.join("manifest.json"))).expect("manifest.json is JSON")
}

/// The acceptance test of checkpoints: kill a deterministic run before frame 5 (checkpoints
/// every 2 frames, so the last one is frame 4), resume it, and compare every frame with an
/// uninterrupted run byte for byte; with Gaussians bound to a particle lattice and with one
/// particle per Gaussian.
#[test]
fn killed_run_resumes_to_the_frames_of_an_uninterrupted_run() {
    for particles in [r#"{ "spacing": 0.03 }"#, r#""gaussians""#] {
        killed_run_resumes(&sim_scene_with(9, 200.0, particles));
    }
}

/// A run killed inside the windows of timed actions (a push on the cube's top from 0.1 s
/// to 0.25 s, a hold of its bottom from 0.15 s; the checkpoint is at frame 4, 0.167 s)
/// resumes to the uninterrupted run's very bytes: the actions follow the step's clock.
#[test]
fn a_run_killed_inside_an_action_window_resumes_to_the_same_frames() {
    let scene = sim_scene(9, 200.0).replace(
        r#""velocity": [0, 0, -1],"#,
        r#""velocity": [0, 0, -1], "actions": [
          {"impulse": {"acceleration": [6, 0, 0]}, "region": {"box": {"lo": [0, 0, 0.36], "hi": [1, 1, 1]}}, "from": 0.1, "to": 0.25},
          {"hold": {}, "region": {"box": {"lo": [0, 0, 0], "hi": [1, 1, 0.34]}}, "from": 0.15}],"#,
    );
    assert!(scene.contains("impulse"), "test setup");
    killed_run_resumes(&scene);
}

/// With Δt following the motion closely (`cfl_velocity` 0.02: the falling cube's speed
/// sets the step, and its stop on the ground changes it) the step count differs from
/// frame to frame, and a killed run still resumes to the uninterrupted run's very bytes:
/// the checkpoint holds the speed the next frame's Δt is chosen from.
#[test]
fn a_run_whose_step_count_varies_resumes_to_the_same_frames() {
    let scene = sim_scene_with(9, 200.0, r#"{ "spacing": 0.03 }"#).replace(
        r#""ground": {"kind": "sticky"}}"#,
        r#""ground": {"kind": "sticky"}, "cfl_velocity": 0.02}"#,
    );
    assert!(scene.contains("cfl_velocity"), "test setup");
    let dir = killed_run_resumes(&scene);
    let m = manifest(&dir.path().join("full"));
    let steps: Vec<u64> = (1..9)
        .map(|f| m["frames"][f.to_string()]["steps"].as_u64().expect("steps"))
        .collect();
    let mut distinct = steps.clone();
    distinct.sort_unstable();
    distinct.dedup();
    assert!(distinct.len() >= 3, "steps per frame {steps:?}");
}

/// Kill a deterministic run of `scene` before frame 5, resume it and compare; the
/// directory holds `full` (uninterrupted) and `part` (killed and resumed).
fn killed_run_resumes(scene: &str) -> TempDir {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    write(d, "sim.json", scene);
    let common = [
        "render",
        "sim.json",
        "--deterministic",
        "--checkpoint-every",
        "2",
    ];
    let with = |out: &str, extra: &[&'static str]| -> Vec<String> {
        let mut a: Vec<String> = common.iter().map(|s| s.to_string()).collect();
        a.extend(["--out".to_string(), out.to_string()]);
        a.extend(extra.iter().map(|s| s.to_string()));
        a
    };
    let run = |args: &[String], env: &[(&str, &str)]| {
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        splatter_env(d, &a, env)
    };

    expect_success(&run(&with("full", &[]), &[]));

    let killed = run(&with("part", &[]), &[("SPLATTER_FAIL_AT_FRAME", "5")]);
    assert_eq!(killed.status.code(), Some(86), "{}", describe(&killed));
    let written = frames_in(&d.join("part"));
    assert!(
        written.len() <= 5 && written.len() >= 4,
        "frames 0..4 written (4 maybe still queued): {written:?}"
    );
    assert!(d.join("part/checkpoint.bin").is_file());
    assert_eq!(manifest(&d.join("part"))["status"], "running");

    let resumed = run(&with("part", &["--resume"]), &[]);
    expect_success(&resumed);
    assert!(
        stderr(&resumed).contains("continuing from the checkpoint at frame 4"),
        "{}",
        describe(&resumed)
    );
    assert_same_frames(&d.join("full"), &d.join("part"), 9);
    let m = manifest(&d.join("part"));
    assert_eq!(m["status"], "complete");
    assert_eq!(m["settings"]["resumed_from"], 4);
    // The killed run's entries up to its last checkpoint (the manifest is rewritten at
    // each checkpoint; between them at most every 0.5 s) and the resumed run's.
    let recorded = m["frames"].as_object().unwrap();
    for f in [0, 1, 2, 3, 5, 6, 7, 8] {
        assert!(recorded.contains_key(&f.to_string()), "frame {f} in {m}");
    }

    // Resuming a finished run renders nothing and changes nothing.
    let again = run(&with("part", &["--resume"]), &[]);
    expect_success(&again);
    assert!(
        stderr(&again).contains("all written already"),
        "{}",
        describe(&again)
    );
    assert_same_frames(&d.join("full"), &d.join("part"), 9);
    dir
}

/// Without --deterministic the GPU sums P2G with float atomics where it can, whose order
/// varies; a resumed run then agrees with an uninterrupted one only up to that noise:
/// stated tolerance, at most 1% of the channel values off by more than 8/255 (measured: a
/// few pixels along the cube's edges by a few levels).
#[test]
fn resumed_run_without_deterministic_mode_is_within_tolerance() {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    write(d, "sim.json", &sim_scene(7, 200.0));
    let args = |out: &'static str, resume: bool| {
        let mut a = vec![
            "render",
            "sim.json",
            "--checkpoint-every",
            "3",
            "--out",
            out,
        ];
        if resume {
            a.push("--resume");
        }
        a
    };
    expect_success(&splatter(d, &args("full", false)));
    let killed = splatter_env(d, &args("part", false), &[("SPLATTER_FAIL_AT_FRAME", "4")]);
    assert_eq!(killed.status.code(), Some(86), "{}", describe(&killed));
    expect_success(&splatter(d, &args("part", true)));
    for name in frames_in(&d.join("full")) {
        let a = image::open(d.join("full").join(&name)).unwrap().to_rgb8();
        let b = image::open(d.join("part").join(&name)).unwrap().to_rgb8();
        let off = a
            .as_raw()
            .iter()
            .zip(b.as_raw())
            .filter(|(x, y)| x.abs_diff(**y) > 8)
            .count();
        assert!(
            off * 100 <= a.as_raw().len(),
            "{name}: {off} of {} channel values differ by more than 8/255",
            a.as_raw().len()
        );
    }
    assert_eq!(frames_in(&d.join("part")).len(), 7);
}

/// A checkpoint of another scene, of the other mode, or damaged, is refused with a message
/// naming the file and what to do; so is a folder whose manifest names another scene.
#[test]
fn resume_refuses_foreign_or_damaged_checkpoints() {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    write(d, "a.json", &sim_scene(6, 200.0));
    write(d, "b.json", &sim_scene(6, 300.0));
    let killed = splatter_env(
        d,
        &[
            "render",
            "a.json",
            "--out",
            "o",
            "--checkpoint-every",
            "2",
            "--deterministic",
        ],
        &[("SPLATTER_FAIL_AT_FRAME", "3")],
    );
    assert_eq!(killed.status.code(), Some(86), "{}", describe(&killed));

    let line = expect_error(&splatter(
        d,
        &[
            "render",
            "b.json",
            "--out",
            "o",
            "--resume",
            "--deterministic",
        ],
    ));
    assert!(
        line.contains("manifest.json") && line.contains("different scene"),
        "{line}"
    );

    std::fs::remove_file(d.join("o/manifest.json")).unwrap();
    let line = expect_error(&splatter(
        d,
        &[
            "render",
            "b.json",
            "--out",
            "o",
            "--resume",
            "--deterministic",
        ],
    ));
    assert!(
        line.contains("checkpoint.bin") && line.contains("different scene"),
        "{line}"
    );

    let line = expect_error(&splatter(
        d,
        &["render", "a.json", "--out", "o", "--resume"],
    ));
    assert!(
        line.contains("checkpoint.bin") && line.contains("--deterministic"),
        "{line}"
    );

    let cp = d.join("o/checkpoint.bin");
    let full = bytes(&cp);
    std::fs::write(&cp, &full[..full.len() - 10]).unwrap();
    let line = expect_error(&splatter(
        d,
        &[
            "render",
            "a.json",
            "--out",
            "o",
            "--resume",
            "--deterministic",
        ],
    ));
    assert!(
        line.contains("checkpoint.bin") && line.contains("truncated"),
        "{line}"
    );

    let mut other_version = full.clone();
    other_version[12..17].copy_from_slice(b"0.0.1");
    std::fs::write(&cp, &other_version).unwrap();
    let line = expect_error(&splatter(
        d,
        &[
            "render",
            "a.json",
            "--out",
            "o",
            "--resume",
            "--deterministic",
        ],
    ));
    assert!(
        line.contains("splatter 0.0.1") && line.contains("without --resume"),
        "{line}"
    );

    // Without --resume the run starts over and replaces the checkpoint.
    expect_success(&splatter(
        d,
        &[
            "render",
            "a.json",
            "--out",
            "o",
            "--checkpoint-every",
            "2",
            "--deterministic",
        ],
    ));
    assert_eq!(frames_in(&d.join("o")).len(), 6);
    assert_ne!(bytes(&cp), other_version);
}

/// Two deterministic runs of the fracture scene (NACC, 4224 particles moving 33k Gaussians)
/// give byte-identical frames on the same adapter, on whichever deterministic path it takes.
#[test]
fn deterministic_fracture_runs_are_byte_identical() {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fracture.json");
    let scene = scene.to_str().unwrap();
    for out in ["a", "b"] {
        let o = splatter(
            d,
            &[
                "render",
                scene,
                "--out",
                out,
                "--width",
                "64",
                "--height",
                "48",
                "--frames",
                "0..4",
                "--deterministic",
            ],
        );
        expect_success(&o);
        // The fixed-point scatter, or on CPU drivers the gather by subgroups.
        let err = stderr(&o);
        assert!(
            err.contains("P2G fixed (deterministic)") || err.contains("P2G gather (deterministic)"),
            "{}",
            describe(&o)
        );
    }
    assert_same_frames(&d.join("a"), &d.join("b"), 4);
    let (f0, f3) = (
        bytes(&d.join("a/frame_00000.png")),
        bytes(&d.join("a/frame_00003.png")),
    );
    assert_ne!(f0, f3, "the sphere moves");
}

/// manifest.json names the scene hash, program, adapter, settings and per-frame timings.
#[test]
fn manifest_describes_the_run() {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    write(d, "sim.json", &sim_scene(3, 200.0));
    let o = splatter(d, &["render", "sim.json", "--out", "o", "--deterministic"]);
    expect_success(&o);
    let m = manifest(&d.join("o"));
    assert_eq!(m["status"], "complete");
    assert_eq!(m["program"], "splatter");
    assert_eq!(m["version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(m["scene_hash"].as_str().unwrap().len(), 16);
    assert!(!m["adapter"].as_str().unwrap().is_empty());
    let s = &m["settings"];
    assert_eq!(
        (s["width"].clone(), s["height"].clone()),
        (64.into(), 48.into())
    );
    assert_eq!(s["deterministic"], true);
    // A deterministic path (the fixed-point scatter, or the gather on CPU drivers), the
    // one the log names.
    let p2g = s["p2g"].as_str().unwrap();
    assert!(p2g == "fixed" || p2g == "gather", "{p2g}");
    assert!(
        stderr(&o).contains(&format!("P2G {p2g} (deterministic)")),
        "{}",
        describe(&o)
    );
    assert_eq!(s["steps_per_frame"], 25);
    assert_eq!(s["particles"], 125);
    let frames = m["frames"].as_object().unwrap();
    assert_eq!(frames.len(), 3);
    assert!(frames["1"]["simulate_ms"].as_f64().unwrap() > 0.0);
    assert!(frames["1"]["render_ms"].as_f64().unwrap() > 0.0);

    // The same scene rendered at another size has another hash.
    expect_success(&splatter(
        d,
        &["render", "sim.json", "--out", "p", "--width", "32"],
    ));
    assert_ne!(manifest(&d.join("p"))["scene_hash"], m["scene_hash"]);
}

/// Sizes past the adapter's buffer limits stop the run before any GPU allocation, saying
/// what to reduce.
#[test]
fn sizes_past_the_buffer_limits_are_refused_up_front() {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    write(d, "sim.json", &sim_scene(2, 200.0));
    let line = expect_error(&splatter(
        d,
        &[
            "render", "sim.json", "--out", "o", "--width", "16384", "--height", "16384",
        ],
    ));
    assert!(
        line.contains("16384×16384 image") && line.contains("--width"),
        "{line}"
    );
    assert!(frames_in(&d.join("o")).is_empty());

    // A grid of 380³ nodes (the domain and the walls' padding): the scatter paths hold its
    // nodes in a pool of the blocks the particles reach, so it runs; the gather path
    // (two-field separation) indexes every one of its 54M base cells, past lavapipe's
    // 128 MiB binding.
    let fine = sim_scene_with(2, 200.0, r#"{ "spacing": 0.0016 }"#)
        .replace("\"dx\": 0.05", "\"dx\": 0.0016")
        .replace("[0.15, 0.15, 0.15]", "[0.03, 0.03, 0.03]");
    write(d, "fine.json", &fine);
    expect_success(&splatter(
        d,
        &["render", "fine.json", "--out", "fine", "--frames", "0"],
    ));
    // --deterministic too: where the gather would not fit, it takes the fixed-point scatter
    // (on CPU drivers it would otherwise take the gather by subgroups).
    let o = splatter(
        d,
        &[
            "render",
            "fine.json",
            "--out",
            "fine_det",
            "--frames",
            "0",
            "--deterministic",
        ],
    );
    expect_success(&o);
    assert!(
        stderr(&o).contains("P2G fixed (deterministic)"),
        "{}",
        stderr(&o)
    );
    write(
        d,
        "fine_gather.json",
        &fine.replace(
            "\"ground\"",
            "\"separation\": \"damage_gradient\", \"ground\"",
        ),
    );
    let line = expect_error(&splatter(d, &["render", "fine_gather.json", "--out", "o"]));
    assert!(
        line.contains("cell ranges of 54010152 grid cells") && line.contains("simulation.dx"),
        "{line}"
    );
}

/// A checkpoint that cannot be written (its path taken by a directory, as good as a full
/// disk for the writer) stops the run with the path and the cause; frames written before
/// are complete PNGs and no temporary file is left that looks like a frame.
#[test]
fn a_failed_checkpoint_write_names_the_path_and_cause() {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    write(d, "sim.json", &sim_scene(5, 200.0));
    std::fs::create_dir_all(d.join("o/checkpoint.bin/x")).unwrap();
    let line = expect_error(&splatter(
        d,
        &[
            "render",
            "sim.json",
            "--out",
            "o",
            "--checkpoint-every",
            "2",
        ],
    ));
    assert!(
        line.contains("o/checkpoint.bin") && line.contains("cannot write"),
        "{line}"
    );
    assert!(
        line.to_lowercase().contains("directory"),
        "the cause: {line}"
    );
    let written = frames_in(&d.join("o"));
    assert_eq!(written, ["frame_00000.png", "frame_00001.png"]);
    for name in written {
        image::open(d.join("o").join(name)).expect("a complete PNG");
    }
    assert_eq!(manifest(&d.join("o"))["status"], "failed");
}

/// `--video` without ffmpeg on the PATH stops before rendering, saying what to install;
/// with an ffmpeg on the PATH (here a stand-in script that records its arguments and
/// writes the file) it is called once after the frames are written.
#[test]
fn video_needs_ffmpeg_and_gets_the_frames() {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    write(d, "sim.json", &sim_scene(3, 200.0));
    let empty = d.join("empty-bin");
    std::fs::create_dir_all(&empty).unwrap();
    let path = std::env::join_paths([&empty]).unwrap();
    let out = splatter_env(
        d,
        &["render", "sim.json", "--out", "o", "--video", "o.mp4"],
        &[("PATH", path.to_str().unwrap())],
    );
    let line = expect_error(&out);
    assert!(
        line.contains("ffmpeg was not found on the PATH") && line.contains("o.mp4"),
        "{line}"
    );
    assert!(
        frames_in(&d.join("o")).is_empty(),
        "checked before rendering"
    );

    let line = expect_error(&splatter(
        d,
        &["render", "sim.json", "--out", "o", "--video", "o.png"],
    ));
    assert!(line.contains("video extension"), "{line}");

    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let bin = d.join("bin");
        std::fs::create_dir_all(&bin).unwrap();
        let fake = bin.join("ffmpeg");
        // Records its arguments, checks the first frame exists, writes the last argument.
        std::fs::write(
            &fake,
            "#!/bin/sh\necho \"$@\" > \"$(dirname \"$0\")/args.txt\"\nfor a; do last=\"$a\"; done\n[ -f o/frame_00000.png ] && [ -f o/frame_00002.png ] || exit 3\necho video > \"$last\"\n",
        )
        .unwrap();
        std::fs::set_permissions(&fake, std::fs::Permissions::from_mode(0o755)).unwrap();
        let path = format!(
            "{}:{}",
            bin.display(),
            std::env::var("PATH").unwrap_or_default()
        );
        let out = splatter_env(
            d,
            &["render", "sim.json", "--out", "o", "--video", "o.mp4"],
            &[("PATH", &path)],
        );
        expect_success(&out);
        let args = String::from_utf8(bytes(&bin.join("args.txt"))).unwrap();
        assert!(
            args.contains("-framerate 24 -start_number 0 -i o/frame_%05d.png -frames:v 3"),
            "{args}"
        );
        assert!(
            args.contains("-pix_fmt yuv420p") && args.trim_end().ends_with("o.mp4"),
            "{args}"
        );
        assert_eq!(bytes(&d.join("o.mp4")), b"video\n");

        // An ffmpeg that fails is reported with its status, and the manifest says so.
        std::fs::write(&fake, "#!/bin/sh\necho 'Unknown encoder' >&2\nexit 1\n").unwrap();
        let line = expect_error(&splatter_env(
            d,
            &["render", "sim.json", "--out", "o", "--video", "o.mp4"],
            &[("PATH", &path)],
        ));
        assert!(
            line.contains("ffmpeg failed") && line.contains("Unknown encoder"),
            "{line}"
        );
        assert_eq!(manifest(&d.join("o"))["status"], "failed");
    }
}

/// Lone particles of a cohesionless NACC material (α₀ 6), thrown up at 65–100 m/s into a
/// separating ceiling at Δx 0.006, each alone on its stencil (3 cells apart or more): the
/// splash of a 40 m/s impact at a finer resolution, as the dragonfruit's blow-up began
/// (docs/notes/stability.md). At the wave bound's Δt (4.7e-5 s; 0.5–0.8 cells a step) the
/// wall, which stops the nodes above a particle but not those below, compresses it by more
/// than its size in one step: its deformation increment I + Δt C inverts, the return
/// mapping starts from a clamped F, the hardening reads that as a 10⁴-fold compaction
/// (α −0.4 → −13.5, p₀ ~ 10⁷ κ), and the particle, now elastic whatever it meets, rings on
/// its own stencil until it leaves the domain at 10³ m/s. The positions and speeds are
/// those of a sweep in which each of them blew up on the gather path.
fn splash_scene(step: &str) -> String {
    let cases = [
        (80.0, 0.0, -0.04),
        (80.0, 0.0, 6.0),
        (80.0, 0.6, 6.0),
        (100.0, 0.3, -0.04),
        (100.0, 0.3, 6.0),
        (100.0, 0.6, -0.04),
        (100.0, 0.6, 6.0),
        (65.0, 0.0, 6.0),
    ];
    let objects: Vec<String> = cases
        .iter()
        .enumerate()
        .map(|(i, (v, phase, alpha0))| {
            // 5 cells apart, on nodes in x and y; `phase` cells above a node in z.
            let x = 0.03 * (1 + i % 4) as f64;
            let y = 0.03 * (1 + i / 4) as f64;
            let z = 0.03 + phase * 0.006;
            format!(
                r#"{{"name": "drop {i}",
      "procedural": {{"shape": "sphere", "radius": 0.002, "spacing": 0.001, "color": [0.9, 0.2, 0.2]}},
      "transform": {{"translate": [{x}, {y}, {z}]}},
      "physics": {{"material": {{"model": "nacc", "E": 2000, "nu": 0.42, "density": 2, "alpha0": {alpha0}, "beta": 1, "xi": 2, "M": 2.36}},
                  "fill": true, "velocity": [0, 0, {v}]}}}}"#
            )
        })
        .collect();
    format!(
        r#"{{
  "output": {{"width": 32, "height": 24, "frames": 3, "fps": 24}},
  "camera": {{"fov_y_deg": 40, "path": {{"type": "orbit", "target": [0.075, 0.045, 0.03], "radius": 0.3, "height": 0.05}}}},
  "simulation": {{"dx": 0.006, "domain": {{"lo": [0, 0, 0], "hi": [0.15, 0.09, 0.06]}},
                 "walls": {{"kind": "separate"}}, "ground": {{"kind": "sticky"}}, {step}}},
  "objects": [
    {}
  ]
}}"#,
        objects.join(",\n    ")
    )
}

/// A frame whose steps invert a particle's deformation runs again at half the step
/// (`sim::frame`): the splash of [`splash_scene`] at the wave bound's step (cfl_velocity 1:
/// the speeds alone would allow it) survives, frame 1 in more steps than planned and with
/// no inversion left. With the same step fixed by a scene `dt` (kept as written) it stops,
/// and the message names where it began: the inverted steps, their first step and
/// particle, and what to change.
#[test]
fn a_splash_whose_steps_invert_at_a_wall_is_run_again_at_a_shorter_step() {
    let dir = TempDir::new().unwrap();
    let d = dir.path();
    let run =
        |scene: &str, out: &str| splatter(d, &["render", scene, "--out", out, "--deterministic"]);
    write(d, "follow.json", &splash_scene(r#""cfl_velocity": 1"#));
    let o = run("follow.json", "follow");
    expect_success(&o);
    assert!(
        !stderr(&o).contains("inverted their deformation"),
        "an inversion was left:\n{}",
        stderr(&o)
    );
    let m = manifest(&d.join("follow"));
    let planned = (1.0 / 24.0 / 4.746e-5_f64).ceil() as u64;
    let frame = &m["frames"]["1"];
    let halvings = frame["halvings"].as_u64().unwrap_or(0);
    let steps = frame["steps"].as_u64().expect("steps");
    assert!(
        halvings >= 1 && steps == planned << halvings,
        "frame 1: {steps} steps, {halvings} halvings of the wave bound's {planned}"
    );

    write(d, "fixed.json", &splash_scene(r#""dt": 4.75e-5"#));
    let line = expect_error(&run("fixed.json", "fixed"));
    for part in [
        "inverted their deformation",
        "first at step",
        "of objects[",
        "(nacc)",
        "simulation.dt",
    ] {
        assert!(line.contains(part), "no {part:?} in: {line}");
    }
}
