//! The lab binary's refusals: one `error:` line, a non-zero exit, no panic.

use std::process::{Command, Output};

fn lab(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_splatter-lab"));
    cmd.args(args);
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().expect("the splatter-lab binary runs")
}

/// The one stderr line of a clean failure.
fn error_line(out: &Output) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "expected a failure:\n{stderr}");
    assert!(!stderr.contains("panicked"), "a panic:\n{stderr}");
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "expected one stderr line:\n{stderr}");
    assert!(lines[0].starts_with("error: "), "{stderr}");
    lines[0].to_string()
}

/// A peer that is not built is one error line saying how to get it, before any of our own
/// cases runs (which would take minutes).
#[test]
fn a_missing_peer_is_refused_before_the_benchmark_runs() {
    let out = lab(
        &["peer", "slosh"],
        &[("SLOSH_PEER", "/nonexistent/slosh-peer")],
    );
    let line = error_line(&out);
    for needle in ["peer slosh", "/nonexistent/slosh-peer", "SLOSH_PEER"] {
        assert!(line.contains(needle), "should mention {needle:?}: {line}");
    }
    // Refused up front: not even the table's header was printed.
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(!stdout.contains("ms/step"), "{stdout}");
}

/// Smoke sweeps must not overwrite the documented numbers under docs/.
#[test]
fn quick_sweeps_into_docs_are_refused() {
    let line = error_line(&lab(&["accuracy", "--quick"], &[]));
    assert!(line.contains("--out"), "{line}");
}
