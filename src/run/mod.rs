//! A run: a scene (or a capture, or a folder of per-frame states) rendered to frames.
//!
//! [`Run::prepare`] does the CPU part (load and build the scene, choose the frames, check
//! the output options); [`Run::execute`] sets up the GPU work and runs the frames:
//!
//! ```text
//! simulation setup → (resume: manifest, checkpoint) → upload, lighting, simulation, derive
//! for frame: step (re-run on pool overflow) → watchdog → [checkpoint] → [fragments]
//!            → derive → [export] → render → writer → manifest
//! writer.finish → manifest complete → [video]
//! ```
//!
//! Progress is reported as [`Event`]s: the command line prints them; tests and the bench
//! suite may ignore them.

mod fragments;
mod from_states;
mod input;
pub mod preview;
mod scene_run;

pub use fragments::{FragmentLog, ObjectFragments};

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Result};

use crate::farm::Chunk;
use crate::frames::FrameSet;
use crate::gpu::GpuContext;
use crate::output::manifest::{ChunkSettings, FrameTiming, Manifest, ManifestWriter, Settings};
use crate::output::passes::Pass;
use crate::output::Pixels;
use crate::output::{frame_path, FrameWriter};
use crate::render::gpu::{FrameTimings, RenderedImage};
use crate::render::Splats;
use crate::scene::cameras::export::FrameCamera;
use crate::scene::quality::Quality;
use crate::scene::{BuildReport, CameraPath, Scene};

/// Where a run's Gaussians come from.
#[derive(Clone, Debug, PartialEq)]
pub enum Input {
    /// A scene file, or the embedded default scene (`None`).
    Scene(Option<PathBuf>),
    /// A quick look at a capture: an orbit framing its bounds, stood upright (on `up`, a
    /// signed axis name, else the estimate), or a camera of an INRIA `cameras.json` (index
    /// `camera`, default 0).
    Ply {
        file: PathBuf,
        cameras: Option<PathBuf>,
        /// A nerfstudio training run's `dataparser_transforms.json`, mapping a
        /// `camera_path.json` in `cameras` back into the capture's frame.
        dataparser: Option<PathBuf>,
        camera: Option<usize>,
        up: Option<String>,
    },
    /// A scene given as JSON text (the Python package's `Scene.from_dict`): `name` names it
    /// in messages, relative paths in it resolve against `base_dir`.
    Text {
        text: String,
        name: String,
        base_dir: PathBuf,
    },
    /// Render-only: each frame's Gaussians from `dir/frame_NNNNN.ply` (as written by
    /// `--export-ply`); the scene gives the camera path and output settings.
    States {
        scene: Option<PathBuf>,
        dir: PathBuf,
    },
}

/// What to run and how: the library form of `splatter render`'s options.
#[derive(Clone, Debug)]
pub struct RunOptions {
    pub input: Input,
    /// Output directory (overrides the scene's `output.dir`).
    pub out: Option<PathBuf>,
    /// Frames to render: `A..B` (B exclusive), `A..`, `..B`, `A`, or a list of inclusive
    /// ranges `1-3,5,7-20:2` (see [`FrameSet::parse`]).
    pub frames: Option<String>,
    /// Render only this farm task's chunk of those frames.
    pub chunk: Option<Chunk>,
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub quality: Quality,
    /// Also write each frame's Gaussians as a 3DGS PLY into this directory.
    pub export_ply: Option<PathBuf>,
    /// Also write each frame's Gaussians as SPZ (version 3) into this directory.
    pub export_spz: Option<PathBuf>,
    /// Also write each frame's Gaussians as GLB (KHR_gaussian_splatting) into this directory.
    pub export_glb: Option<PathBuf>,
    /// Also write each frame's MPM particles as a PLY point cloud into this directory.
    pub export_particles: Option<PathBuf>,
    /// Passes written beside the colour frames (`OUT/alpha/`, `OUT/depth/`).
    pub passes: Vec<crate::output::passes::Pass>,
    /// Also write the rendered frames' cameras into this directory, as an INRIA
    /// `cameras.json` and a nerfstudio `camera_path.json` (`scene::cameras::export`).
    pub export_cameras: Option<PathBuf>,
    /// Skip frames already written and restart the simulation from the checkpoint.
    pub resume: bool,
    /// Sum P2G in a fixed order: bit-identical frames on the same adapter.
    pub deterministic: bool,
    /// Run P2G on this path instead of the one chosen for the adapter and scene.
    pub p2g: Option<crate::sim::gpu::P2gPath>,
    /// Save the simulation state every N frames (0: never).
    pub checkpoint_every: u32,
    /// Assemble the frames into this video with ffmpeg.
    pub video: Option<PathBuf>,
    /// Count the pieces of every simulated object per frame (`OUT/fragments.csv`).
    pub fragments: bool,
}

impl RunOptions {
    /// The per-frame Gaussian exports asked for: (directory, format).
    pub fn exports(&self) -> impl Iterator<Item = (&Path, crate::output::export::Export)> {
        use crate::output::export::Export;
        [
            (self.export_ply.as_deref(), Export::Ply),
            (self.export_spz.as_deref(), Export::Spz),
            (self.export_glb.as_deref(), Export::Glb),
        ]
        .into_iter()
        .filter_map(|(d, f)| d.map(|d| (d, f)))
    }
}

impl Default for RunOptions {
    /// The embedded default scene as written.
    fn default() -> Self {
        RunOptions {
            input: Input::Scene(None),
            out: None,
            frames: None,
            chunk: None,
            width: None,
            height: None,
            quality: Quality::Standard,
            export_ply: None,
            export_spz: None,
            export_glb: None,
            export_particles: None,
            export_cameras: None,
            passes: Vec::new(),
            resume: false,
            deterministic: false,
            p2g: None,
            checkpoint_every: 10,
            video: None,
            fragments: false,
        }
    }
}

/// What a run reports as it goes.
#[derive(Clone, Debug, PartialEq)]
pub enum Event {
    /// A line for the user (the adapter, the scene's size, resume decisions, …).
    Note(String),
    /// The frame loop starts: `frames` is what will be rendered or skipped.
    Frames(FrameSet),
    /// Frame `frame` is about to be simulated (or loaded) and rendered.
    FrameStart(u32),
    /// Frame `frame` is rendered (queued for writing), or was already written (`skipped`,
    /// with `--resume`).
    FrameDone { frame: u32, skipped: bool },
    /// Every frame is on disk.
    FramesWritten,
}

/// What a finished run did.
#[derive(Clone, Debug, Default)]
pub struct Summary {
    pub rendered: u32,
    /// Wall time of the frame loop and of the whole run, in seconds.
    pub render_seconds: f64,
    pub total_seconds: f64,
    /// GPU render + readback, summed over the rendered frames, in milliseconds.
    pub gpu_ms: f64,
    pub png_workers: usize,
    pub manifest: PathBuf,
    /// `--fragments`: each simulated object's pieces at the last rendered frame.
    pub fragments: Vec<ObjectFragments>,
}

impl Summary {
    /// The closing line of `splatter render`.
    pub fn describe(&self) -> String {
        let n = f64::from(self.rendered.max(1));
        format!(
            "done: {} frames rendered in {:.2} s ({:.3} s/frame; GPU render+readback {:.1} ms/frame; {} PNG worker thread(s)); total {:.2} s with scene build",
            self.rendered,
            self.render_seconds,
            self.render_seconds / n,
            self.gpu_ms / n,
            self.png_workers,
            self.total_seconds
        )
    }
}

/// A prepared run: the scene loaded and built on the CPU, nothing on the GPU yet.
pub struct Run {
    job: Job,
    source: Source,
}

enum Source {
    Built {
        splats: Splats,
        report: BuildReport,
    },
    States(PathBuf),
    /// Nothing to render, and why (a farm task past the last chunk).
    Idle(String),
}

impl Run {
    /// Load and build the scene, check the options, choose the frames (CPU only, so that
    /// a bad scene file is reported before a GPU is opened).
    pub fn prepare(opts: RunOptions) -> Result<Run> {
        let started = Instant::now();
        let ffmpeg = match &opts.video {
            Some(v) => Some(crate::output::video::preflight(v)?),
            None => None,
        };
        input::check_image_size(&opts)?;
        let (scene, path, frames, source) = match &opts.input {
            Input::States { scene, dir } => {
                let (scene, path) = input::load_scene(scene.as_deref(), &opts)?;
                let (frames, idle) = task_frames(&opts, scene.frame_count())?;
                let source = unless_idle(idle, || {
                    crate::farm::check_states(dir, &frames)?;
                    Ok(Source::States(dir.clone()))
                })?;
                (scene, path, frames, source)
            }
            Input::Scene(_) | Input::Text { .. } => {
                let (scene, path) = input::load_scene_input(&opts.input, &opts)?;
                let (frames, idle) = task_frames(&opts, scene.frame_count())?;
                // A task with nothing to render does not build the scene (captures can
                // take long to read).
                let source = unless_idle(idle, || {
                    let (splats, report) = input::build_splats(&scene)?;
                    Ok(Source::Built { splats, report })
                })?;
                (scene, path, frames, source)
            }
            Input::Ply {
                file,
                cameras,
                dataparser,
                camera,
                up,
            } => {
                let (scene, path, splats, report) = input::quick_look(
                    &opts,
                    file,
                    (cameras.as_deref(), dataparser.as_deref()),
                    *camera,
                    up.as_deref(),
                )?;
                let (frames, idle) = task_frames(&opts, scene.frame_count())?;
                let source = unless_idle(idle, || Ok(Source::Built { splats, report }))?;
                (scene, path, frames, source)
            }
        };
        if opts.video.is_some() && !frames.is_empty() && frames.as_range().is_none() {
            bail!(
                "--video reads the frames as one numbered sequence, and frames {frames} have gaps; render them, then assemble the video over a range without gaps (e.g. the whole scene with --resume --video)"
            );
        }
        let job = Job {
            opts,
            started,
            ffmpeg,
            scene,
            path,
            frames,
        };
        Ok(Run { job, source })
    }

    /// The scene as prepared (quality and overrides applied).
    pub fn scene(&self) -> &Scene {
        &self.job.scene
    }

    /// The frames this run renders (none for an idle farm task).
    pub fn frames(&self) -> &FrameSet {
        &self.job.frames
    }

    /// Why this run renders nothing (a farm task past the last chunk); `execute` then
    /// only reports it, and a caller need not open a GPU.
    pub fn idle(&self) -> Option<&str> {
        match &self.source {
            Source::Idle(why) => Some(why),
            _ => None,
        }
    }

    /// The camera of every frame.
    pub fn camera_path(&self) -> &CameraPath {
        &self.job.path
    }

    /// The scene's Gaussians as placed in the world (None for `--from-states`, which
    /// loads them per frame).
    pub fn splats(&self) -> Option<&Splats> {
        match &self.source {
            Source::Built { splats, .. } => Some(splats),
            Source::States(_) | Source::Idle(_) => None,
        }
    }

    /// Run every frame on `gpu`, reporting progress to `on_event`.
    pub fn execute(self, gpu: &GpuContext, on_event: &mut dyn FnMut(Event)) -> Result<Summary> {
        let Run { job, source } = self;
        if let (Some(dir), false) = (&job.opts.export_cameras, matches!(source, Source::Idle(_))) {
            let frames: Vec<FrameCamera> = job
                .frames
                .iter()
                .map(|frame| FrameCamera {
                    frame,
                    camera: job.path.camera(frame),
                })
                .collect();
            crate::scene::cameras::export::write(dir, &frames, job.path.fps()).map_err(|e| {
                anyhow::anyhow!("cannot write the cameras into {}: {e}", dir.display())
            })?;
            on_event(Event::Note(format!(
                "cameras of {} frames: {} and {}",
                frames.len(),
                dir.join("cameras.json").display(),
                dir.join("camera_path.json").display()
            )));
        }
        match source {
            Source::Built { splats, report } => {
                scene_run::execute(job, splats, report, gpu, on_event)
            }
            Source::States(dir) => from_states::execute(job, &dir, gpu, on_event),
            Source::Idle(why) => {
                on_event(Event::Note(why));
                Ok(Summary::default())
            }
        }
    }
}

/// [`Source::Idle`] when `idle` gives a reason, else the source `make` prepares.
fn unless_idle(idle: Option<String>, make: impl FnOnce() -> Result<Source>) -> Result<Source> {
    match idle {
        Some(why) => Ok(Source::Idle(why)),
        None => make(),
    }
}

/// The frames of `--frames`, and with `--chunk` this task's share of them; when the task
/// has no share, an empty set and the reason.
fn task_frames(opts: &RunOptions, count: u32) -> Result<(FrameSet, Option<String>)> {
    let set = FrameSet::parse(opts.frames.as_deref(), count)?;
    let Some(c) = &opts.chunk else {
        return Ok((set, None));
    };
    if let Some(w) = &c.warning {
        log::warn!("{w}");
    }
    if let Some(part) = set.chunk(c.size, c.index) {
        return Ok((part, None));
    }
    // Arrays are often sized generously (a fixed 0-99, or one task per frame before the
    // chunk size was raised): a task past the end has nothing to do, which is not a
    // failure the farm should retry.
    let tasks = match set.chunk_count(c.size) {
        1 => "1 chunk, task 0".to_string(),
        n => format!("{n} chunks, tasks 0-{}", n - 1),
    };
    Ok((
        FrameSet::default(),
        Some(format!(
            "--chunk {}: task {} (from {}) has nothing to render: the {} frames {set} make {tasks}",
            c.size,
            c.index,
            c.index_from,
            set.len(),
        )),
    ))
}

/// The parts of a prepared run both input modes use.
struct Job {
    opts: RunOptions,
    started: Instant,
    ffmpeg: Option<PathBuf>,
    scene: Scene,
    path: CameraPath,
    frames: FrameSet,
}

impl Job {
    /// The manifest's record of the frames: their span, the list when it has gaps, the
    /// chunk.
    fn frame_settings(&self) -> Settings {
        let span = self.frames.span();
        Settings {
            frames: [span.start, span.end],
            frame_list: self
                .frames
                .as_range()
                .is_none()
                .then(|| self.frames.to_string()),
            chunk: self.opts.chunk.as_ref().map(|c| ChunkSettings {
                size: c.size,
                index: c.index,
                index_from: c.index_from.to_string(),
            }),
            scene_frames: self.scene.frame_count(),
            ..Default::default()
        }
    }

    /// How the manifest names the input.
    fn input_name(&self) -> String {
        match &self.opts.input {
            Input::Scene(Some(p)) | Input::States { scene: Some(p), .. } => p.display().to_string(),
            Input::Ply { file, .. } => format!("--ply {}", file.display()),
            Input::Scene(None) | Input::States { scene: None, .. } => "<default scene>".into(),
            Input::Text { name, .. } => name.clone(),
        }
    }

    /// A frame counts as done for `--resume` when its PNG (and each export's file: PLY,
    /// SPZ, GLB, particles, passes) exists: both are written to a temporary name and renamed, so existing means
    /// complete.
    fn frame_done(&self, dir: &Path, frame: u32) -> bool {
        frame_path(dir, frame).is_file()
            && self
                .opts
                .exports()
                .all(|(d, format)| crate::output::export::frame_file(d, frame, format).is_file())
            && self
                .opts
                .export_particles
                .as_deref()
                .is_none_or(|d| crate::output::particles::frame_particles_path(d, frame).is_file())
            && self
                .opts
                .passes
                .iter()
                .all(|p| p.frame_file(dir, frame).is_file())
    }

    /// The manifest of this run; with `--resume`, the frame timings of an earlier run of
    /// the same scene are kept.
    fn manifest(
        &self,
        path: PathBuf,
        hash: u64,
        gpu: &GpuContext,
        settings: Settings,
    ) -> ManifestWriter {
        let mut m = Manifest::new(self.input_name(), hash, gpu.describe(), settings);
        if self.opts.resume {
            if let Some(old) = Manifest::read(&path) {
                if old.scene_hash == m.scene_hash {
                    m.frames = old.frames;
                }
            }
        }
        ManifestWriter::new(path, m, self.started)
    }

    /// After the frame loop: wait for the writer, record the outcome in the manifest,
    /// assemble the video, and sum up.
    fn finish(
        &self,
        result: Result<()>,
        sink: Sink,
        fragments: Vec<ObjectFragments>,
        on_event: &mut dyn FnMut(Event),
    ) -> Result<Summary> {
        let Sink {
            dir,
            passes: _,
            writer,
            mut manifest,
            rendered,
            gpu_ms,
            workers,
            loop_started,
        } = sink;
        let result = result.and_then(|()| writer.finish().map(|_| ()).map_err(Into::into));
        on_event(Event::FramesWritten);
        if let Err(e) = result {
            // The run's error is what matters; a manifest that cannot be written (a full
            // disk) must not hide it.
            let _ = manifest.finish(Some(one_line(&e)));
            return Err(e);
        }
        if let (Some(ffmpeg), Some(video)) = (&self.ffmpeg, &self.opts.video) {
            on_event(Event::Note(format!("video: {} (ffmpeg)", video.display())));
            let fps = self.scene.output.fps;
            // Checked in `prepare`: a video's frames have no gaps.
            let frames = self.frames.span();
            if let Err(e) = crate::output::video::assemble(ffmpeg, &dir, frames, fps, video) {
                let e = anyhow::Error::from(e);
                let _ = manifest.finish(Some(one_line(&e)));
                return Err(e);
            }
        }
        manifest.finish(None)?;
        Ok(Summary {
            rendered,
            render_seconds: loop_started.elapsed().as_secs_f64(),
            total_seconds: self.started.elapsed().as_secs_f64(),
            gpu_ms,
            png_workers: workers,
            manifest: manifest.path().to_path_buf(),
            fragments,
        })
    }
}

/// Where rendered frames go: PNGs through the writer threads, timings into the manifest,
/// and the counts the summary reports.
struct Sink {
    dir: PathBuf,
    /// The passes written beside each frame.
    passes: Vec<Pass>,
    writer: FrameWriter,
    manifest: ManifestWriter,
    rendered: u32,
    gpu_ms: f64,
    workers: usize,
    loop_started: Instant,
}

impl Sink {
    fn new(dir: PathBuf, passes: &[Pass], manifest: ManifestWriter) -> Sink {
        let workers = FrameWriter::default_workers();
        Sink {
            dir,
            passes: passes.to_vec(),
            writer: FrameWriter::new(workers, 2 * workers),
            manifest,
            rendered: 0,
            gpu_ms: 0.0,
            workers,
            loop_started: Instant::now(),
        }
    }

    /// Queue frame `frame`'s PNG and record its timings (GPU time from `gpu`).
    fn submit(
        &mut self,
        frame: u32,
        image: RenderedImage,
        gpu: &FrameTimings,
        mut timing: FrameTiming,
    ) -> Result<()> {
        let gpu_ms = gpu.render_ms + gpu.readback_ms;
        self.gpu_ms += gpu_ms;
        timing.gpu_ms = gpu_ms;
        let path = frame_path(&self.dir, frame);
        let RenderedImage {
            width: w,
            height: h,
            rgba,
            passes,
            ..
        } = image;
        self.writer.submit(path, w, h, rgba)?;
        if let Some(p) = passes {
            for pass in &self.passes {
                let file = pass.frame_file(&self.dir, frame);
                let pixels = match pass {
                    Pass::Alpha => Pixels::Rgba(p.alpha.clone()),
                    Pass::Depth => Pixels::Depth(p.depth.clone()),
                    Pass::Normal => Pixels::Normal(p.normal.clone().unwrap_or_default()),
                    Pass::Id => Pixels::Id(p.id.clone().unwrap_or_default()),
                };
                self.writer.submit_pixels(file, w, h, pixels)?;
            }
        }
        self.manifest.frame_done(frame, timing)?;
        self.rendered += 1;
        Ok(())
    }
}

/// `--resume` into a folder whose manifest names another scene is refused (its frames
/// would be mixed with this scene's).
fn check_manifest_for_resume(path: &Path, hash: u64) -> Result<()> {
    if let Some(m) = Manifest::read(path) {
        let ours = format!("{hash:016x}");
        if m.scene_hash != ours {
            bail!(
                "--resume: {} is the manifest of a run of a different scene (scene hash {}, this run {ours}): the scene file, a file it loads, or --width/--height changed since; render into another --out, or run without --resume to start over",
                path.display(),
                m.scene_hash
            );
        }
    }
    Ok(())
}

/// The command lines' logging: warnings and errors on stderr without timestamps, wgpu's
/// and naga's own chatter only when it is an error (`RUST_LOG` overrides).
pub fn init_logging() {
    env_logger::Builder::from_env(
        env_logger::Env::default()
            .default_filter_or("warn,wgpu_core=error,wgpu_hal=error,naga=error"),
    )
    .format_timestamp(None)
    .format_target(false)
    .init();
}

/// The error and its causes on one line, leaving out a cause whose text the message already
/// carries (our error types print their source, as wgpu's and io's errors are terse).
pub fn one_line(e: &anyhow::Error) -> String {
    let mut msg = e.to_string();
    for cause in e.chain().skip(1) {
        let text = cause.to_string();
        if !msg.contains(&text) {
            msg.push_str(": ");
            msg.push_str(&text);
        }
    }
    msg.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The output directory, created.
fn create_dir(dir: &Path, what: &str) -> Result<()> {
    use anyhow::Context;
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create the {what} {}", dir.display()))
}
