//! Running the `splatter` binary from a test, and reading what it said.
//!
//! Every run removes `RUST_LOG` (so the binary's own filter applies: warnings only),
//! `RUST_BACKTRACE` (so that a panic always prints its `RUST_BACKTRACE` hint, which
//! [`assert_no_panic`] looks for, rather than a backtrace), the test hook
//! `SPLATTER_FAIL_AT_FRAME` (which only the tests that want a crash set) and the render
//! managers' task indices (so that tests run as a Slurm array task behave as anywhere).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// `splatter ARGS` with `cwd` as the current directory, not yet started.
pub fn command(cwd: &Path, args: &[&str]) -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_splatter"));
    cmd.args(args)
        .current_dir(cwd)
        .env_remove("RUST_LOG")
        .env_remove("RUST_BACKTRACE")
        .env_remove("SPLATTER_FAIL_AT_FRAME")
        .env_remove("SLURM_ARRAY_TASK_MIN");
    for var in splatter::farm::TASK_INDEX_VARS {
        cmd.env_remove(var);
    }
    cmd
}

/// Run `splatter ARGS` in `cwd` to its end.
pub fn splatter(cwd: &Path, args: &[&str]) -> Output {
    splatter_env(cwd, args, &[])
}

/// Run `splatter ARGS` in `cwd` with extra environment variables.
pub fn splatter_env(cwd: &Path, args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = command(cwd, args);
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().expect("the splatter binary runs")
}

/// Run `splatter ARGS` in `cwd` and require success.
pub fn splatter_ok(cwd: &Path, args: &[&str]) -> Output {
    let out = splatter(cwd, args);
    expect_success(&out);
    out
}

/// Lines that graphics drivers print on their own, which the binary cannot suppress.
///
/// When wgpu enumerates adapters (every render and `info`), Mesa's GL/EGL stack and lavapipe
/// write straight to the process's stderr: `error: XDG_RUNTIME_DIR is invalid or not set in
/// the environment.` (from the Wayland/EGL platform probe — note it even starts with
/// `error: `), `[ERROR] EGL …` (wgpu-hal's EGL callback, logged through env_logger), `MESA…`
/// diagnostics and `WARNING: lavapipe is not a conformant vulkan implementation…`. They depend
/// on the machine, not on the input, so they are ignored when counting error lines.
pub fn is_driver_noise(line: &str) -> bool {
    line.contains("XDG_RUNTIME_DIR")
        || line.starts_with("[ERROR] EGL")
        || line.starts_with("MESA")
        || line.starts_with("WARNING: lavapipe")
}

/// stderr without driver noise and blank lines.
pub fn stderr_lines(out: &Output) -> Vec<String> {
    String::from_utf8_lossy(&out.stderr)
        .lines()
        .filter(|l| !l.trim().is_empty() && !is_driver_noise(l))
        .map(str::to_string)
        .collect()
}

/// The exit status and both streams, for assertion messages.
pub fn describe(out: &Output) -> String {
    format!(
        "exit status: {:?}\n--- stdout ---\n{}\n--- stderr ---\n{}",
        out.status.code(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// The run did not panic.
pub fn assert_no_panic(out: &Output) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !err.contains("panicked") && !err.contains("RUST_BACKTRACE"),
        "the binary panicked:\n{}",
        describe(out)
    );
}

/// The run succeeded without a panic.
pub fn expect_success(out: &Output) {
    assert_no_panic(out);
    assert!(out.status.success(), "expected success:\n{}", describe(out));
}

/// Non-zero exit by the process itself (not a signal), without a panic.
fn expect_clean_failure(out: &Output) {
    assert_no_panic(out);
    assert!(
        !out.status.success(),
        "expected a non-zero exit:\n{}",
        describe(out)
    );
    assert!(
        out.status.code().is_some(),
        "killed by a signal, not a clean exit:\n{}",
        describe(out)
    );
}

/// The run failed cleanly: non-zero exit, no panic, exactly one (non-noise) stderr line and it
/// starts with `error: `. Returns that line.
pub fn expect_error(out: &Output) -> String {
    expect_clean_failure(out);
    let lines = stderr_lines(out);
    assert_eq!(
        lines.len(),
        1,
        "expected exactly one stderr line:\n{}",
        describe(out)
    );
    let line = lines.into_iter().next().unwrap();
    assert!(
        line.starts_with("error: "),
        "the stderr line should start with `error: `:\n{}",
        describe(out)
    );
    line
}

/// The run failed cleanly after rendering had started: like [`expect_error`], except that the
/// progress lines printed before the failure (`adapter: …`, `scene: …`, `frame 1/1 …`) are
/// allowed. Exactly one line starts with `error: `, and it is the last one. Returns it.
pub fn expect_late_error(out: &Output) -> String {
    expect_clean_failure(out);
    let lines = stderr_lines(out);
    let errors: Vec<&String> = lines.iter().filter(|l| l.starts_with("error: ")).collect();
    assert_eq!(
        errors.len(),
        1,
        "expected exactly one `error: ` line:\n{}",
        describe(out)
    );
    assert_eq!(
        lines.last(),
        Some(errors[0]),
        "the error should be the last line:\n{}",
        describe(out)
    );
    errors[0].clone()
}

/// `line` contains every one of `needles`.
pub fn assert_mentions(line: &str, needles: &[&str]) {
    for n in needles {
        assert!(line.contains(n), "the error should mention {n:?}: {line}");
    }
}

/// A fresh directory to run in.
pub fn workdir() -> tempfile::TempDir {
    tempfile::tempdir().expect("a temporary directory")
}

/// Write a test input `dir/name`.
pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).expect("write a test input");
    path
}

/// The `frame_*.png` names in `dir`, sorted (none if `dir` is missing).
pub fn frames_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.filter_map(|e| e.ok())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .filter(|n| n.starts_with("frame_") && n.ends_with(".png"))
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    names
}
