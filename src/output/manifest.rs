//! `OUT_DIR/manifest.json`: what a run was (scene hash, program version, adapter,
//! settings) and how it went (per-frame timings, status), rewritten atomically as frames
//! complete, so that a render farm or a person can tell what a folder of frames is.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

use super::{write_atomically, OutputError};

/// `OUT_DIR/manifest.json` for a run of all `scene_frames` frames; for a part,
/// `OUT_DIR/manifest_A-B.json` (frames A..B), so that the jobs of a render farm writing
/// into one folder each keep their own.
pub fn manifest_path(dir: &Path, frames: std::ops::Range<u32>, scene_frames: u32) -> PathBuf {
    if frames.start == 0 && frames.end == scene_frames {
        dir.join("manifest.json")
    } else {
        dir.join(format!(
            "manifest_{:05}-{:05}.json",
            frames.start, frames.end
        ))
    }
}

/// Bumped when fields change meaning.
pub const MANIFEST_FORMAT: u32 = 1;

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    pub width: u32,
    pub height: u32,
    pub fps: f32,
    /// The half-open frame range of this run (`--frames`).
    pub frames: [u32; 2],
    /// Frames in the scene.
    pub scene_frames: u32,
    pub deterministic: bool,
    pub gaussians: usize,
    /// Simulated runs: particles, the P2G path, steps per frame and Δt.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub particles: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub p2g: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub steps_per_frame: Option<u32>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub dt: Option<f64>,
    /// Frames between checkpoints (0: none).
    pub checkpoint_every: u32,
    /// `--resume`: the checkpoint's frame this run continued from.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub resumed_from: Option<u32>,
    /// `--from-states DIR`.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub from_states: Option<PathBuf>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub export_ply: Option<PathBuf>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub export_spz: Option<PathBuf>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub export_glb: Option<PathBuf>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub export_particles: Option<PathBuf>,
}

/// One rendered frame's timings (wall clock on the rendering thread, milliseconds).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FrameTiming {
    /// The simulation steps leading to this frame, with the watchdog readback.
    pub simulate_ms: f64,
    /// Loading the frame's state (`--from-states`).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub load_ms: Option<f64>,
    /// Derive, render passes and image readback.
    pub render_ms: f64,
    /// GPU render and readback as the renderer measured them.
    pub gpu_ms: f64,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Started, not finished (a run killed midway stays so).
    Running,
    /// Every frame of the range written.
    Complete,
    /// Stopped by an error (see `error`).
    Failed,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    pub format: u32,
    pub program: String,
    pub version: String,
    /// The scene file (or `<default>`, `--ply FILE`).
    pub scene: String,
    /// [`crate::checkpoint::scene_hash`], 16 hex digits.
    pub scene_hash: String,
    pub adapter: String,
    pub settings: Settings,
    pub status: Status,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub error: Option<String>,
    /// Seconds since the run started.
    pub elapsed_s: f64,
    /// Frames rendered, by index (a map, so that a resumed run keeps the entries of the
    /// frames it skipped).
    pub frames: BTreeMap<u32, FrameTiming>,
}

impl Manifest {
    pub fn new(scene: String, scene_hash: u64, adapter: String, settings: Settings) -> Self {
        Manifest {
            format: MANIFEST_FORMAT,
            program: "splatter".into(),
            version: crate::PROGRAM_VERSION.into(),
            scene,
            scene_hash: format!("{scene_hash:016x}"),
            adapter,
            settings,
            status: Status::Running,
            error: None,
            elapsed_s: 0.0,
            frames: BTreeMap::new(),
        }
    }

    /// Read a manifest (for `--resume`); `None` when there is none or it does not parse.
    pub fn read(path: &Path) -> Option<Manifest> {
        let text = std::fs::read_to_string(path).ok()?;
        serde_json::from_str(&text).ok()
    }

    pub fn to_json(&self) -> String {
        let mut s = serde_json::to_string_pretty(self).expect("a manifest serialises");
        s.push('\n');
        s
    }
}

/// Keeps `manifest.json` up to date without rewriting it for every frame of a fast run: at
/// most every `interval`, and whenever [`write_now`](Self::write_now) is called.
pub struct ManifestWriter {
    pub manifest: Manifest,
    path: PathBuf,
    started: Instant,
    last: Option<Instant>,
    interval: Duration,
}

impl ManifestWriter {
    pub fn new(path: PathBuf, manifest: Manifest, started: Instant) -> Self {
        ManifestWriter {
            manifest,
            path,
            started,
            last: None,
            interval: Duration::from_millis(500),
        }
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Record frame `frame`'s timings; writes the file if the last write is old enough.
    pub fn frame_done(&mut self, frame: u32, timing: FrameTiming) -> Result<(), OutputError> {
        self.manifest.frames.insert(frame, timing);
        if self.last.is_none_or(|t| t.elapsed() >= self.interval) {
            self.write_now()?;
        }
        Ok(())
    }

    /// Write the manifest now (atomically).
    pub fn write_now(&mut self) -> Result<(), OutputError> {
        self.manifest.elapsed_s = self.started.elapsed().as_secs_f64();
        self.last = Some(Instant::now());
        write_atomically(&self.path, self.manifest.to_json().as_bytes())
    }

    /// Mark the run finished (complete, or failed with `error`) and write.
    pub fn finish(&mut self, error: Option<String>) -> Result<(), OutputError> {
        self.manifest.status = if error.is_some() {
            Status::Failed
        } else {
            Status::Complete
        };
        self.manifest.error = error;
        self.write_now()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn manifest_round_trips_and_is_written_atomically() {
        let dir = tempfile::tempdir().unwrap();
        let settings = Settings {
            width: 64,
            height: 48,
            frames: [0, 3],
            deterministic: true,
            ..Default::default()
        };
        let m = Manifest::new("s.json".into(), 0xabc, "llvmpipe".into(), settings);
        let path = manifest_path(dir.path(), 0..3, 3);
        assert!(path.ends_with("manifest.json"));
        assert!(manifest_path(dir.path(), 1..3, 3).ends_with("manifest_00001-00003.json"));
        let mut w = ManifestWriter::new(path, m, Instant::now());
        w.frame_done(
            0,
            FrameTiming {
                simulate_ms: 1.5,
                render_ms: 2.0,
                ..Default::default()
            },
        )
        .unwrap();
        let back = Manifest::read(w.path()).unwrap();
        assert_eq!(back.status, Status::Running);
        assert_eq!(back.scene_hash, "0000000000000abc");
        assert_eq!(back.frames[&0].render_ms, 2.0);
        w.finish(Some("disk full".into())).unwrap();
        let back = Manifest::read(w.path()).unwrap();
        assert_eq!(back.status, Status::Failed);
        assert_eq!(back.error.as_deref(), Some("disk full"));
        assert_eq!(back, w.manifest);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }
}
