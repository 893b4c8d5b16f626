//! `OUT_DIR/manifest.json`: what a run was (scene hash, program version, adapter,
//! settings) and how it went (per-frame timings, status), rewritten atomically as frames
//! complete, so that a render farm or a person can tell what a folder of frames is.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

use super::{write_atomically, OutputError};
use crate::frames::FrameSet;

/// `OUT_DIR/manifest.json` for a run of all `scene_frames` frames; for a part,
/// `OUT_DIR/manifest_A-B.json` (frames A..B, B exclusive), so that the jobs of a render
/// farm writing into one folder each keep their own. A set with gaps is named by its span
/// and a hash of its frames, `manifest_A-B_HHHHHHHH.json`: two sets can share a span
/// (`0-9:3` and `0,9`), and a farm's tasks render different sets.
pub fn manifest_path(dir: &Path, frames: &FrameSet, scene_frames: u32) -> PathBuf {
    let span = frames.span();
    match frames.as_range() {
        Some(r) if r == (0..scene_frames) => dir.join("manifest.json"),
        Some(_) => dir.join(format!("manifest_{:05}-{:05}.json", span.start, span.end)),
        None => dir.join(format!(
            "manifest_{:05}-{:05}_{:08x}.json",
            span.start,
            span.end,
            frames_hash(frames)
        )),
    }
}

/// FNV-1a 32 of the frames' numbers: stable across builds and platforms, unlike std's
/// hasher, so a re-run of a task finds its own manifest again.
fn frames_hash(frames: &FrameSet) -> u32 {
    let mut h: u32 = 0x811c_9dc5;
    for b in frames.iter().flat_map(u32::to_le_bytes) {
        h = (h ^ u32::from(b)).wrapping_mul(0x0100_0193);
    }
    h
}

/// Bumped when fields change meaning: 2 when `settings.frames` became the span of a frame
/// set that may have gaps (then listed in `settings.frame_list`).
pub const MANIFEST_FORMAT: u32 = 2;

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    pub width: u32,
    pub height: u32,
    pub fps: f32,
    /// The frames of this run (`--frames`, `--chunk`) as a half-open range: its first
    /// frame and one past its last. With `frame_list`, only the frames listed there.
    pub frames: [u32; 2],
    /// The frames rendered, when they have gaps (`--frames 1-3,5,7-20:2`), in the render
    /// managers' syntax (inclusive ranges, `:step`).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub frame_list: Option<String>,
    /// `--chunk`: this task's share of the frames.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub chunk: Option<ChunkSettings>,
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
    /// The id pass's table (`--passes id`): what each id of `id/frame_N.png` shows.
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub ids: Vec<crate::output::passes::IdEntry>,
}

/// A farm task's chunk: `size` frames a chunk, the task's 0-based `index`, and where that
/// index came from (`--task-index`, `SLURM_ARRAY_TASK_ID`, `JOB_COMPLETION_INDEX`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ChunkSettings {
    pub size: u32,
    pub index: u32,
    pub index_from: String,
}

/// One rendered frame's timings (wall clock on the rendering thread, milliseconds).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FrameTiming {
    /// The simulation steps leading to this frame, with the watchdog readback.
    pub simulate_ms: f64,
    /// How many steps led to this frame (its Δt is the frame's length over them; it
    /// follows the motion unless the scene sets `dt`); absent without a simulation.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub steps: Option<u32>,
    /// How often this frame's steps were too long (a particle's step inverted it, or NaN)
    /// and the frame ran again at half the step; absent when none were.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub halvings: Option<u32>,
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
    fn sets_with_gaps_get_their_own_manifest_names() {
        let name = |spec: &str| {
            let set = FrameSet::parse(Some(spec), 20).unwrap();
            let path = manifest_path(Path::new("o"), &set, 20);
            path.file_name().unwrap().to_string_lossy().into_owned()
        };
        assert_eq!(name("0-19"), "manifest.json");
        assert_eq!(name("4-7"), "manifest_00004-00008.json");
        let (a, b) = (name("0-9:3"), name("0,9"));
        assert!(
            a.starts_with("manifest_00000-00010_") && a.ends_with(".json"),
            "{a}"
        );
        assert!(b.starts_with("manifest_00000-00010_"), "{b}");
        assert_ne!(a, b, "two sets with one span");
        assert_eq!(a, name("0,3,6,9"), "the same set, the same name");
        assert_eq!(a.len(), "manifest_00000-00010_12345678.json".len());
    }

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
        let path = manifest_path(dir.path(), &FrameSet::from(0..3), 3);
        assert!(path.ends_with("manifest.json"));
        let part = manifest_path(dir.path(), &FrameSet::from(1..3), 3);
        assert!(part.ends_with("manifest_00001-00003.json"));
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
