//! The `splatter` command line. Errors end as one `error: …` line and a non-zero exit.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use glam::{DVec3, Vec3};

use splatter::checkpoint::{self, checkpoint_path, Checkpoint};
use splatter::gpu::{BackendChoice, GpuContext};
use splatter::limits;
use splatter::output::manifest::{manifest_path, FrameTiming, Manifest, ManifestWriter, Settings};
use splatter::output::{frame_path, FrameWriter, Progress};
use splatter::relight::gpu_normals::GpuNormals;
use splatter::render::GpuRenderer;
use splatter::scene::kinematic::KinematicObject;
use splatter::scene::simulation::{PartKind, SimulationSetup};
use splatter::scene::{self, BuildReport, CameraPath, Scene};
use splatter::sim::cpu::Material;
use splatter::sim::derive::{Derive, RigidDerive};
use splatter::sim::gpu::{GpuSim, P2gPath, Watchdog};
use splatter::study::fragments::{fragment_sizes, FragmentSummary, PIECE_SHARE};

#[derive(Parser)]
#[command(
    name = "splatter",
    version,
    about = "Simulate and render 3D Gaussian Splatting scenes to PNG frames."
)]
struct Cli {
    /// Force a graphics API instead of choosing the best adapter.
    #[arg(long, global = true, value_enum)]
    backend: Option<BackendChoice>,
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene file (or, with --ply, a PLY file) to DIR/frame_00000.png, …
    /// Without a scene and without --ply, renders the embedded default scene.
    Render(Box<RenderArgs>),
    /// List the GPU adapters, their optional features and limits.
    Info,
    /// Print the JSON Schema of scene files.
    Schema,
    /// Print the embedded default scene (a starting point for your own).
    DefaultScene,
    /// Benchmarks (see docs/performance.md).
    Bench {
        #[command(subcommand)]
        what: BenchWhat,
    },
}

#[derive(Subcommand)]
enum BenchWhat {
    /// Nanoseconds per particle-step of the GPU MPM step (NACC): 20k particles on a 64³
    /// grid and 1M particles on a 128³ grid.
    Sim {
        /// Steps timed per case (after one warm-up step).
        #[arg(long, default_value_t = 20)]
        steps: u32,
        /// Only the 20k case.
        #[arg(long)]
        quick: bool,
        /// Also break each case down by pass (each pass run alone and waited for).
        #[arg(long)]
        per_pass: bool,
    },
    /// Milliseconds per frame of the renderer: render passes, readback, PNG encoding.
    Render {
        /// Repetitions per case (the median is reported).
        #[arg(long, default_value_t = 5)]
        repeat: usize,
        /// Only the small cases (100k Gaussians), for a quick check.
        #[arg(long)]
        quick: bool,
        /// Also break each case down by pass (one extra frame, each pass waited for).
        #[arg(long)]
        per_pass: bool,
    },
    /// The sim, render and end-to-end benchmarks in one run: seconds per frame of each
    /// paper example under scenes/ next to the paper's column (SPEC §9), written to
    /// OUT/data/bench_suite.{json,md} (docs/performance.md).
    Suite(Box<SuiteArgs>),
    /// Convergence study and stability atlas on the CPU reference step: JSON and tables
    /// in OUT/data/, charts in OUT/images/ (docs/accuracy.md).
    Accuracy {
        /// Output root (data/ and images/ go under it).
        #[arg(long, default_value = "docs")]
        out: PathBuf,
        /// Which part to run.
        #[arg(long, value_enum, default_value = "all")]
        only: AccuracyPart,
        /// Tiny sweeps (a smoke run; the numbers are not the documented ones).
        #[arg(long)]
        quick: bool,
        /// Simulate nothing: redraw the tables and charts from OUT/data/*.json.
        #[arg(long)]
        redraw: bool,
    },
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum AccuracyPart {
    All,
    Convergence,
    Atlas,
}

#[derive(clap::Args)]
struct SuiteArgs {
    /// Output root (the JSON and the table go to OUT/data/).
    #[arg(long, default_value = "docs")]
    out: PathBuf,
    /// Small cases only and 3 frames per example (a CPU machine).
    #[arg(long)]
    quick: bool,
    /// Coarsen each example scene by this factor (dx and spacings × s: N / s³).
    #[arg(long, default_value_t = 1.0)]
    scale: f64,
    /// Frames per example (frame 0 plus frames-1 timed frames); default 4, 3 with --quick.
    #[arg(long)]
    frames: Option<u32>,
    /// Image size of the end-to-end runs.
    #[arg(long, default_value_t = 480)]
    width: u32,
    #[arg(long, default_value_t = 360)]
    height: u32,
    /// Directory of the example scenes.
    #[arg(long, default_value = "scenes")]
    scenes: PathBuf,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// Scene file (JSON). See docs/scene-format.md.
    scene: Option<PathBuf>,
    /// Output directory (overrides the scene's `output.dir`).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Frames to render: `A..B` (B exclusive), `A..`, `..B` or a single frame `A`.
    #[arg(long)]
    frames: Option<String>,
    /// Image width in pixels (overrides the scene's).
    #[arg(long)]
    width: Option<u32>,
    /// Image height in pixels (overrides the scene's).
    #[arg(long)]
    height: Option<u32>,
    /// Resolution in space and on screen: `draft` (twice as coarse), `standard` (the
    /// scene as written) or `high` (twice as fine: 8× the particles, twice the image
    /// size; meant for a GPU). --width/--height still win for the image size.
    #[arg(long, value_enum, default_value_t = scene::quality::Quality::Standard)]
    quality: scene::quality::Quality,
    /// Also write each rendered frame's Gaussians (deformed, SH rotated into the world
    /// frame) as a standard 3DGS PLY: DIR/frame_00000.ply, …
    #[arg(long, value_name = "DIR")]
    export_ply: Option<PathBuf>,
    /// Quick look at a 3DGS PLY file without a scene file: an orbit framing its bounds.
    #[arg(long, conflicts_with = "scene")]
    ply: Option<PathBuf>,
    /// With --ply: an INRIA 3DGS cameras.json to take the camera from.
    #[arg(long, requires = "ply")]
    cameras: Option<PathBuf>,
    /// With --cameras: index of the camera in cameras.json (default 0).
    #[arg(long, requires = "cameras")]
    camera: Option<usize>,
    /// Continue a killed or failed run in the same output directory: frames already
    /// written are skipped, and a simulation restarts from OUT_DIR/checkpoint.bin (a
    /// checkpoint of another scene, mode or program version is refused).
    #[arg(long)]
    resume: bool,
    /// Bit-identical frames for the same input on the same adapter: the simulation sums
    /// P2G in a fixed order (sorted gather) instead of with float atomics.
    #[arg(long)]
    deterministic: bool,
    /// Save the simulation state to OUT_DIR/checkpoint.bin every N frames (0: never).
    #[arg(long, value_name = "N", default_value_t = 10)]
    checkpoint_every: u32,
    /// Render-only: take each frame's Gaussians from DIR/frame_NNNNN.ply (as written by
    /// --export-ply) instead of building and simulating the scene; the scene gives the
    /// camera path and output settings. For splitting frame ranges over machines.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["ply", "export_ply"])]
    from_states: Option<PathBuf>,
    /// After rendering, assemble the frames into a video with ffmpeg (which must be on
    /// the PATH; checked before rendering starts).
    #[arg(long, value_name = "FILE")]
    video: Option<PathBuf>,
    /// Count the pieces each simulated object has broken into, every rendered frame:
    /// particles closer than Δx are linked, linked particles form a fragment
    /// (OUT_DIR/fragments.csv; the last frame's counts are printed).
    #[arg(long, conflicts_with_all = ["ply", "from_states"])]
    fragments: bool,
}

fn main() -> ExitCode {
    env_logger::Builder::from_env(
        env_logger::Env::default()
            .default_filter_or("warn,wgpu_core=error,wgpu_hal=error,naga=error"),
    )
    .format_timestamp(None)
    .format_target(false)
    .init();
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", one_line(&e));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes on one line, leaving out a cause whose text the message already
/// carries (our error types print their source, as wgpu's and io's errors are terse).
fn one_line(e: &anyhow::Error) -> String {
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

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        None => render(cli.backend, RenderArgs::default_scene()),
        Some(Command::Render(args)) => render(cli.backend, *args),
        Some(Command::Info) => {
            print!("{}", splatter::gpu::info_report(cli.backend));
            Ok(())
        }
        Some(Command::Schema) => {
            println!("{}", serde_json::to_string_pretty(&scene::schema())?);
            Ok(())
        }
        Some(Command::DefaultScene) => {
            print!("{}", scene::DEFAULT_SCENE_JSON);
            Ok(())
        }
        Some(Command::Bench {
            what:
                BenchWhat::Sim {
                    steps,
                    quick,
                    per_pass,
                },
        }) => {
            let gpu = GpuContext::new(cli.backend)?;
            splatter::bench::sim_bench(&gpu, steps.max(1), quick, per_pass, &mut std::io::stdout())
        }
        Some(Command::Bench {
            what:
                BenchWhat::Render {
                    repeat,
                    quick,
                    per_pass,
                },
        }) => {
            let gpu = GpuContext::new(cli.backend)?;
            splatter::bench::render_bench(
                &gpu,
                repeat.max(1),
                quick,
                per_pass,
                &mut std::io::stdout(),
            )
        }
        Some(Command::Bench {
            what: BenchWhat::Suite(args),
        }) => bench_suite(cli.backend, &args),
        Some(Command::Bench {
            what:
                BenchWhat::Accuracy {
                    out,
                    only,
                    quick,
                    redraw,
                },
        }) => {
            use splatter::study::Part;
            if quick && !redraw && out == Path::new("docs") {
                // The smoke sweeps would overwrite the documented numbers.
                bail!("--quick runs smoke-sized sweeps: give an --out other than docs");
            }
            let part = match only {
                AccuracyPart::All => Part::All,
                AccuracyPart::Convergence => Part::Convergence,
                AccuracyPart::Atlas => Part::Atlas,
            };
            splatter::study::run_accuracy(part, quick, redraw, &out, &mut std::io::stderr())
        }
    }
}

fn bench_suite(backend: Option<BackendChoice>, args: &SuiteArgs) -> Result<()> {
    if !(args.scale > 0.0 && args.scale.is_finite()) {
        bail!("--scale {}: expected a positive factor", args.scale);
    }
    let gpu = GpuContext::new(backend)?;
    let opts = splatter::study::suite::SuiteOptions {
        quick: args.quick,
        scale: args.scale,
        frames: args.frames.unwrap_or(if args.quick { 3 } else { 4 }).max(2),
        width: args.width,
        height: args.height,
        sim_steps: 20,
        repeat: if args.quick { 3 } else { 5 },
        scenes: args.scenes.clone(),
    };
    let out = args.out.join("data");
    splatter::study::suite::run_suite(&gpu, &opts, &out, &mut std::io::stderr())?;
    Ok(())
}

impl RenderArgs {
    fn default_scene() -> RenderArgs {
        RenderArgs {
            export_ply: None,
            fragments: false,
            scene: None,
            out: None,
            frames: None,
            width: None,
            height: None,
            ply: None,
            cameras: None,
            camera: None,
            resume: false,
            deterministic: false,
            checkpoint_every: 10,
            from_states: None,
            video: None,
            quality: scene::quality::Quality::Standard,
        }
    }
}

/// The watchdog's stop message: frame, what was counted, the likely cause. Frames
/// already written are complete (each was renamed into place).
fn watchdog_message(frame: u32, w: Watchdog, s: &SimulationSetup) -> String {
    let n = s.steps_per_frame;
    let steps = match w.first_step {
        // Frame f shows the state after f·n steps: the batch read before it ran steps
        // (f − 1)·n + 1 ..= f·n, counted from 1.
        Some(k) => format!(
            "in the {n} steps before frame {frame}, first at step {} (substep {} of {n})",
            u64::from(frame.saturating_sub(1)) * u64::from(n) + u64::from(k) + 1,
            k + 1
        ),
        None => format!("in the {n} steps before frame {frame}"),
    };
    if w.nonfinite > 0 {
        format!(
            "simulation stopped: {} particle-steps became NaN/Inf {steps} (Δt {:.3e} s, Δx {}); likely cause: Δt too large for the material's stiffness (lower simulation.dt or simulation.cfl) or a material that inverts (use NACC or fixed_corotated)",
            w.nonfinite, s.params.dt, s.grid.dx
        )
    } else {
        let (lo, hi) = (s.grid.lo, s.grid.hi());
        let v = |x: glam::DVec3| format!("[{:.3}, {:.3}, {:.3}]", x.x, x.y, x.z);
        format!(
            "simulation stopped: {} particle-steps left the domain {steps} ({} .. {}); likely cause: simulation.domain too small for the motion, or Δt too large",
            w.escaped,
            v(lo),
            v(hi)
        )
    }
}

/// Parse `A..B`, `A..`, `..B` or `A` against `count` frames into a half-open range.
fn frame_range(spec: Option<&str>, count: u32) -> Result<std::ops::Range<u32>> {
    let Some(spec) = spec else {
        return Ok(0..count);
    };
    let num = |s: &str, default: u32| -> Result<u32> {
        if s.trim().is_empty() {
            Ok(default)
        } else {
            s.trim()
                .parse()
                .with_context(|| format!("--frames {spec:?}: {s:?} is not a frame number"))
        }
    };
    let range = match spec.split_once("..") {
        Some((a, b)) => num(a, 0)?..num(b, count)?,
        None => {
            let a = num(spec, 0)?;
            a..a.saturating_add(1)
        }
    };
    if range.start >= range.end || range.end > count {
        bail!("--frames {spec:?}: expected a non-empty range within 0..{count} (the scene has {count} frames)");
    }
    Ok(range)
}

/// The scene, its camera path and the frames to render, from the command line.
fn prepare(
    args: &RenderArgs,
) -> Result<(Scene, CameraPath, splatter::render::Splats, BuildReport)> {
    for (flag, value) in [("--width", args.width), ("--height", args.height)] {
        if let Some(v) = value {
            if !(1..=scene::MAX_IMAGE_SIZE).contains(&v) {
                bail!(
                    "{flag} {v}: expected an image size in pixels in 1..={}",
                    scene::MAX_IMAGE_SIZE
                );
            }
        }
    }
    if let Some(ply) = &args.ply {
        return prepare_quick_look(args, ply);
    }
    let mut scene = match &args.scene {
        Some(path) => scene::load(path)?,
        None => scene::default_scene(),
    };
    scene.apply_quality(args.quality);
    scene.with_overrides(args.out.clone(), args.width, args.height)?;
    let path = scene.camera_path()?;
    let (splats, report) = scene.build_splats()?;
    for w in report.warnings() {
        log::warn!("{w}");
    }
    Ok((scene, path, splats, report))
}

fn prepare_quick_look(
    args: &RenderArgs,
    ply: &std::path::Path,
) -> Result<(Scene, CameraPath, splatter::render::Splats, BuildReport)> {
    let text = format!(
        r#"{{"output": {{"width": {w}, "height": {h}, "frames": 60}},
            "camera": {{"fov_y_deg": 50, "path": {{"type": "orbit", "target": [0, 0, 0], "radius": 1}}}},
            "objects": [{{"ply": {p}}}]}}"#,
        w = args.width.unwrap_or(1280),
        h = args.height.unwrap_or(720),
        p = serde_json::to_string(&ply.to_string_lossy())?,
    );
    let stem = ply
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "ply".into());
    let mut scene = scene::parse(
        &text,
        &format!("--ply {}", ply.display()),
        std::path::Path::new("."),
    )?;
    scene.name = stem;
    scene.with_overrides(args.out.clone(), None, None)?;
    let (splats, report) = scene.build_splats()?;
    for w in report.warnings() {
        log::warn!("{w}");
    }
    let path = match &args.cameras {
        Some(file) => {
            let cameras = scene::from_cameras_json(file, args.width, args.height)?;
            let index = args.camera.unwrap_or(0);
            let Some(camera) = cameras.get(index) else {
                bail!(
                    "--camera {index}: {} has {} cameras (valid: 0..{})",
                    file.display(),
                    cameras.len(),
                    cameras.len()
                );
            };
            scene.output.frames = 1;
            scene.output.width = camera.width;
            scene.output.height = camera.height;
            CameraPath::still(*camera)
        }
        None => {
            let bounds = splats.means.iter().fold(
                (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                |(lo, hi), p| (lo.min(*p), hi.max(*p)),
            );
            let (w, h) = (scene.output.width, scene.output.height);
            CameraPath::orbit_framing(bounds, Vec3::Z, 50.0, w, h, scene.output.frames)
        }
    };
    Ok((scene, path, splats, report))
}

fn render(backend: Option<BackendChoice>, args: RenderArgs) -> Result<()> {
    if args.from_states.is_some() {
        return render_from_states(backend, args);
    }
    let started = Instant::now();
    let ffmpeg = video_preflight(&args)?;
    let (scene, path, splats, report) = prepare(&args)?;
    let frames = frame_range(args.frames.as_deref(), scene.frame_count())?;
    let gpu = GpuContext::new(backend)?;
    let (width, height) = (scene.output.width, scene.output.height);
    let simulated = scene.objects.iter().any(|o| o.physics.is_some());
    if let (Some(spec), true) = (&scene.simulation, simulated) {
        // The grid's GPU size before the simulation setup allocates it on the CPU.
        let (lo, hi) = (DVec3::from(spec.domain.lo), DVec3::from(spec.domain.hi));
        let cells = ((hi - lo) / spec.dx - 1e-9).ceil().max(DVec3::ONE);
        if cells.is_finite() && cells.max_element() < f64::from(u32::MAX) {
            limits::check_gpu(&gpu, &limits::sim_needs(0, cells.as_uvec3()))?;
        }
    }
    let setup = scene::simulation::prepare(&scene, splats.clone(), &report)?;
    if args.fragments && setup.is_none() {
        let name = args
            .scene
            .as_ref()
            .map_or("the default scene".into(), |p| p.display().to_string());
        bail!("--fragments counts the pieces of simulated objects, and {name} simulates none (no object has `physics`)");
    }
    let hash = checkpoint::scene_hash(&scene, &splats, setup.as_ref());
    let splats = setup.as_ref().map_or(splats, |s| s.splats.clone());
    let dir = scene.output_dir();
    std::fs::create_dir_all(&dir)
        .with_context(|| format!("cannot create the output directory {}", dir.display()))?;
    if let Some(dir) = &args.export_ply {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create the PLY export directory {}", dir.display()))?;
    }
    eprintln!("adapter: {}", gpu.describe());
    let manifest_file = manifest_path(&dir, frames.clone(), scene.frame_count());
    let mut needs = limits::render_needs(splats.len(), width, height);
    if let Some(s) = &setup {
        needs.extend(limits::sim_needs(s.particles.len(), s.grid.cells));
    }
    limits::check_gpu(&gpu, &needs)?;
    if args.resume {
        check_manifest_for_resume(&manifest_file, hash)?;
    }
    let done = |frame: u32| frame_done(&dir, args.export_ply.as_deref(), frame);
    let first_missing = if args.resume {
        frames.clone().find(|f| !done(*f))
    } else {
        Some(frames.start)
    };
    let path_p2g = if args.deterministic {
        P2gPath::Gather
    } else {
        P2gPath::best(&gpu)
    };
    // A checkpoint helps only if it is not past the first frame still to render.
    let checkpoint_file = checkpoint_path(&dir);
    let resume_state = match (&setup, first_missing) {
        (Some(s), Some(missing)) if args.resume && checkpoint_file.exists() => {
            let cp = Checkpoint::load(&checkpoint_file)?;
            cp.check_matches(
                &checkpoint_file,
                hash,
                args.deterministic,
                s.particles.len(),
                s.steps_per_frame,
            )?;
            if cp.frame <= missing {
                Some(cp)
            } else {
                eprintln!(
                    "resume: the checkpoint is at frame {}, after frame {missing} which is missing; simulating from frame 0",
                    cp.frame
                );
                None
            }
        }
        _ => None,
    };
    if args.resume {
        match (first_missing, &resume_state) {
            (None, _) => eprintln!(
                "resume: frames {}..{} are all written already",
                frames.start, frames.end
            ),
            (Some(m), Some(cp)) => eprintln!(
                "resume: continuing from the checkpoint at frame {} (first missing frame {m})",
                cp.frame
            ),
            (Some(m), None) => eprintln!("resume: first missing frame {m}"),
        }
    }
    eprintln!(
        "scene: {} Gaussians, {}×{}, frames {}..{} → {}",
        splats.len(),
        width,
        height,
        frames.start,
        frames.end,
        dir.display()
    );
    let mut renderer = GpuRenderer::new(&gpu);
    renderer.upload(&gpu, &splats)?;
    // Relighting before the derive pass is built: derive moves the simulated normals.
    let lighting = scene::lighting::prepare(
        &scene,
        &splats,
        &report,
        setup.as_ref().map(|s| s.parts.as_slice()),
        setup
            .as_ref()
            .map(|s| (s.grid.lo.as_vec3(), s.grid.hi().as_vec3())),
    )?;
    if let Some(l) = &lighting {
        eprintln!(
            "lighting: {} lights, shadows {}, normals of {} Gaussians in {:.2} s",
            l.lights.at(0.0).len(),
            l.setup.shadows.map_or("off".to_string(), |g| format!(
                "{}×{}×{} voxels",
                g.res.x, g.res.y, g.res.z
            )),
            splats.len(),
            l.normals_seconds
        );
        renderer.set_lighting(&gpu, &l.setup)?;
    }
    let mut sim = match &setup {
        Some(s) => {
            for w in &s.warnings {
                log::warn!("{w}");
            }
            eprintln!(
                "simulation: {} particles, {} materials, grid {}×{}×{} (Δx {}), Δt {:.3e} s, {} steps per frame, P2G {}{}",
                s.particles.len(),
                s.materials.len(),
                s.grid.cells.x,
                s.grid.cells.y,
                s.grid.cells.z,
                s.grid.dx,
                s.params.dt,
                s.steps_per_frame,
                p2g_name(path_p2g),
                if args.deterministic { " (deterministic)" } else { "" }
            );
            let restored;
            let start = match &resume_state {
                Some(cp) => {
                    restored = cp.to_particles(&s.particles);
                    &restored
                }
                None => &s.particles,
            };
            let mut gpu_sim =
                GpuSim::with_path(&gpu, start, &s.grid, &s.materials, &s.params, path_p2g)?;
            let colliders: Vec<_> = s.kinematic.iter().map(|k| k.collider.clone()).collect();
            gpu_sim.set_kinematic(&gpu, &colliders)?;
            let derive = Derive::new(&gpu, &gpu_sim, &renderer, &s.splats, s.static_count as u32)?;
            Some((gpu_sim, derive, s))
        }
        None => None,
    };
    // Kinematic objects' Gaussians, moved rigidly along their paths every frame.
    let rigid = match &setup {
        Some(s) => kinematic_parts(&gpu, &renderer, s)?,
        None => Vec::new(),
    };
    // Simulated objects whose normals are recomputed every frame, on the GPU.
    let gpu_normals = match (&lighting, &setup) {
        (Some(l), Some(s)) if !l.recompute.is_empty() => Some(GpuNormals::new(
            &gpu,
            &renderer,
            &l.recomputed_objects(&splats),
            s.grid.lo.as_vec3(),
            s.grid.hi().as_vec3(),
        )?),
        _ => None,
    };

    let settings = Settings {
        width,
        height,
        fps: scene.output.fps,
        frames: [frames.start, frames.end],
        scene_frames: scene.frame_count(),
        deterministic: args.deterministic,
        gaussians: splats.len(),
        particles: setup.as_ref().map(|s| s.particles.len()),
        p2g: setup.as_ref().map(|_| p2g_name(path_p2g).to_string()),
        steps_per_frame: setup.as_ref().map(|s| s.steps_per_frame),
        dt: setup.as_ref().map(|s| s.params.dt),
        checkpoint_every: if setup.is_some() {
            args.checkpoint_every
        } else {
            0
        },
        resumed_from: resume_state.as_ref().map(|cp| cp.frame),
        from_states: None,
        export_ply: args.export_ply.clone(),
    };
    let mut manifest = new_manifest(&args, manifest_file, hash, &gpu, settings, started);
    manifest.write_now()?;

    let rotator = args
        .export_ply
        .as_ref()
        .map(|_| splatter::splat::sh::ShRotator::new());
    let workers = FrameWriter::default_workers();
    let mut writer = FrameWriter::new(workers, 2 * workers);
    let mut progress = Progress::new(u64::from(frames.end - frames.start), "render");
    let render_start = Instant::now();
    let mut gpu_ms = 0.0;
    let mut rendered = 0u32;
    let background = Vec3::from(scene.output.background);
    let fail_at = fail_hook_frame()?;
    let sim_first = resume_state.as_ref().map_or(0, |cp| cp.frame);
    let mut fragment_log = match args.fragments {
        true => Some(FragmentLog::create(
            &dir.join("fragments.csv"),
            args.resume,
        )?),
        false => None,
    };
    let mut run_frames = || -> Result<()> {
        let Some(_) = first_missing else {
            return Ok(());
        };
        // Frame f shows the state after f · steps_per_frame steps; a range that starts
        // later simulates the frames before it without rendering them.
        let first = if sim.is_some() {
            sim_first
        } else {
            frames.start
        };
        for frame in first..frames.end {
            if fail_at == Some(frame) {
                eprintln!("SPLATTER_FAIL_AT_FRAME: exiting abruptly before frame {frame}");
                std::process::exit(FAIL_HOOK_EXIT);
            }
            let t0 = Instant::now();
            let mut timing = FrameTiming::default();
            if let Some((gpu_sim, derive, s)) = &mut sim {
                let w = if frame > sim_first {
                    simulate_frame(&gpu, gpu_sim, frame, s)?
                } else {
                    gpu_sim.take_watchdog(&gpu)?
                };
                // Sparse grid: room for the active region to double before the next read.
                gpu_sim.fit_pool(&gpu, &w)?;
                if w.nonfinite > 0 || w.escaped > 0 {
                    bail!("{}", watchdog_message(frame, w, s));
                }
                if args.checkpoint_every > 0
                    && frame > sim_first
                    && frame % args.checkpoint_every == 0
                {
                    // Frames before this one reach the disk first, so a crash after the
                    // checkpoint never loses a frame that resuming from it would skip.
                    writer.flush()?;
                    let state = gpu_sim.read_particles(&gpu, &s.particles)?;
                    Checkpoint::from_particles(
                        &state,
                        hash,
                        args.deterministic,
                        frame,
                        s.steps_per_frame,
                    )
                    .save(&checkpoint_file)?;
                    manifest.write_now()?;
                }
                timing.simulate_ms = t0.elapsed().as_secs_f64() * 1e3;
                if frame < frames.start {
                    continue;
                }
                if args.resume && done(frame) {
                    progress.frame_done();
                    continue;
                }
                if let Some(log) = &mut fragment_log {
                    let state = gpu_sim.read_particles(&gpu, &s.particles)?;
                    log.record(frame, &state, s, &scene)?;
                }
                derive.run(&gpu)?;
                let seconds = f64::from(frame) / f64::from(scene.output.fps);
                for (k, r) in &rigid {
                    let (a, b) = k.rest_to_world(seconds);
                    r.run(&gpu, a, b)?;
                }
            } else if args.resume && done(frame) {
                progress.frame_done();
                continue;
            }
            let t1 = Instant::now();
            if let (Some(dir), Some(rotator)) = (&args.export_ply, &rotator) {
                let gaussians = renderer.read_gaussians(&gpu)?;
                splatter::output::export::export_frame(dir, frame, &gaussians, &splats, rotator)?;
            }
            if let Some(l) = &lighting {
                renderer.set_lights(&l.lights.at(frame as f32 / scene.output.fps));
            }
            if let Some(n) = &gpu_normals {
                // Normals in the deformed configuration (new fracture faces included).
                n.run(&gpu)?;
            }
            let camera = path.camera(frame);
            let (image, timings) = renderer.render_timed(&gpu, &camera, background)?;
            gpu_ms += timings.render_ms + timings.readback_ms;
            writer.submit(
                frame_path(&dir, frame),
                image.width,
                image.height,
                image.rgba,
            )?;
            timing.render_ms = t1.elapsed().as_secs_f64() * 1e3;
            timing.gpu_ms = timings.render_ms + timings.readback_ms;
            manifest.frame_done(frame, timing)?;
            rendered += 1;
            progress.frame_done();
        }
        Ok(())
    };
    let result = run_frames();
    finish_run(
        result,
        writer,
        &progress,
        &mut manifest,
        ffmpeg,
        &args,
        &dir,
        frames,
        scene.output.fps,
    )?;
    report_done(rendered, render_start, gpu_ms, workers, started);
    if let Some(log) = &fragment_log {
        log.print_last();
    }
    Ok(())
}

/// A CSV field: quoted (with doubled quotes) when it holds a comma, quote or line break.
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Vertical extent of a body (z from its 1st to its 99th percentile, so that a few
/// thrown-off particles do not count): how far a slumping heap has sunk.
fn height_extent(points: &[glam::DVec3]) -> f64 {
    if points.is_empty() {
        return 0.0;
    }
    let mut z: Vec<f64> = points.iter().map(|p| p.z).collect();
    z.sort_unstable_by(f64::total_cmp);
    let at = |q: f64| z[((z.len() - 1) as f64 * q).round() as usize];
    at(0.99) - at(0.01)
}

/// `--fragments`: per rendered frame and simulated object, how many pieces its particles
/// form (`splatter::study::fragments`), appended to a CSV as the frames go.
struct FragmentLog {
    file: std::io::BufWriter<std::fs::File>,
    last: Vec<(String, u32, FragmentSummary)>,
}

impl FragmentLog {
    /// With `resume`, rows of an earlier run of the same output directory are kept and the
    /// resumed frames appended after them.
    fn create(path: &Path, resume: bool) -> Result<Self> {
        let append = resume && path.is_file();
        let file = std::fs::OpenOptions::new()
            .create(true)
            .append(append)
            .write(true)
            .truncate(!append)
            .open(path)
            .with_context(|| format!("--fragments: cannot create {}", path.display()))?;
        let mut file = std::io::BufWriter::new(file);
        if !append {
            writeln!(
                file,
                "frame,object,particles,pieces,largest_share,debris,fragments,damaged_share,height"
            )?;
        }
        Ok(Self {
            file,
            last: Vec::new(),
        })
    }

    fn record(
        &mut self,
        frame: u32,
        state: &splatter::sim::cpu::Particles,
        s: &SimulationSetup,
        scene: &scene::Scene,
    ) -> Result<()> {
        self.last.clear();
        let mut objects: Vec<usize> = s
            .parts
            .iter()
            .filter(|p| p.kind != PartKind::Static)
            .map(|p| p.object)
            .collect();
        objects.dedup();
        for object in objects {
            // The object's particles: its simulated parts, in particle order.
            let particles: Vec<usize> = s
                .parts
                .iter()
                .filter(|p| p.object == object && p.kind != PartKind::Static)
                .flat_map(|p| p.start - s.static_count..p.start - s.static_count + p.len)
                .collect();
            let points: Vec<glam::DVec3> = particles.iter().map(|&i| state.x[i]).collect();
            let damaged = particles
                .iter()
                .filter(|&&i| {
                    matches!(
                        s.materials[state.material[i] as usize],
                        Material::Nacc { .. }
                    ) && state.alpha[i] >= 0.0
                })
                .count();
            let height = height_extent(&points);
            let sizes = fragment_sizes(&points, s.grid.dx);
            let summary = FragmentSummary::new(&sizes, PIECE_SHARE);
            let name = scene.objects[object]
                .name
                .clone()
                .unwrap_or_else(|| format!("objects[{object}]"));
            let name = csv_field(&name);
            writeln!(
                self.file,
                "{frame},{name},{},{},{:.4},{},{},{:.4},{height:.4}",
                summary.particles,
                summary.pieces,
                summary.largest_share,
                summary.debris,
                summary.fragments,
                damaged as f64 / summary.particles.max(1) as f64
            )?;
            self.last.push((name, frame, summary));
        }
        self.file.flush()?;
        Ok(())
    }

    fn print_last(&self) {
        for (name, frame, s) in &self.last {
            eprintln!(
                "fragments: {name} at frame {frame}: {} piece(s) with ≥ {:.0}% of its {} particles (largest {:.1}%), {} particles of debris, {} fragments in all",
                s.pieces,
                PIECE_SHARE * 100.0,
                s.particles,
                s.largest_share * 100.0,
                s.debris,
                s.fragments
            );
        }
    }
}

/// A rigid derive pass for every run of a kinematic object's Gaussians (`scene::kinematic`).
fn kinematic_parts<'a>(
    gpu: &GpuContext,
    renderer: &GpuRenderer,
    s: &'a SimulationSetup,
) -> Result<Vec<(&'a KinematicObject, RigidDerive)>> {
    let mut out = Vec::new();
    for k in &s.kinematic {
        for part in s.parts.iter().filter(|p| p.object == k.object) {
            let r = RigidDerive::new(gpu, renderer, &s.splats, part.start as u32, part.len as u32)?;
            out.push((k, r));
        }
    }
    Ok(out)
}

/// The exit status of the `SPLATTER_FAIL_AT_FRAME` test hook.
const FAIL_HOOK_EXIT: i32 = 86;

/// Test hook: `SPLATTER_FAIL_AT_FRAME=k` makes a render exit abruptly (status 86, frames in
/// the writer queue lost, no cleanup) just before frame k, as a crash or `kill -9` would.
/// Used by the resume tests; see docs/testing.md.
fn fail_hook_frame() -> Result<Option<u32>> {
    match std::env::var("SPLATTER_FAIL_AT_FRAME") {
        Ok(v) => Ok(Some(v.trim().parse().with_context(|| {
            format!("SPLATTER_FAIL_AT_FRAME={v:?}: expected a frame number")
        })?)),
        Err(_) => Ok(None),
    }
}

fn p2g_name(path: P2gPath) -> &'static str {
    match path {
        P2gPath::Gather => "gather",
        P2gPath::Atomic => "atomic",
    }
}

/// A frame counts as done for `--resume` when its PNG (and, with --export-ply, its PLY)
/// exists: both are written to a temporary name and renamed, so existing means complete.
fn frame_done(dir: &Path, export_ply: Option<&Path>, frame: u32) -> bool {
    frame_path(dir, frame).is_file()
        && export_ply.is_none_or(|d| splatter::output::export::frame_ply_path(d, frame).is_file())
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

fn new_manifest(
    args: &RenderArgs,
    path: PathBuf,
    hash: u64,
    gpu: &GpuContext,
    settings: Settings,
    started: Instant,
) -> ManifestWriter {
    let scene_name = match (&args.scene, &args.ply) {
        (Some(p), _) => p.display().to_string(),
        (None, Some(p)) => format!("--ply {}", p.display()),
        (None, None) => "<default scene>".into(),
    };
    let mut m = Manifest::new(scene_name, hash, gpu.describe(), settings);
    if args.resume {
        // Keep the timings of the frames an earlier run of the same scene rendered.
        if let Some(old) = Manifest::read(&path) {
            if old.scene_hash == m.scene_hash {
                m.frames = old.frames;
            }
        }
    }
    ManifestWriter::new(path, m, started)
}

/// `--video`: a plausible name and ffmpeg on the PATH, before any rendering.
fn video_preflight(args: &RenderArgs) -> Result<Option<PathBuf>> {
    match &args.video {
        Some(v) => Ok(Some(splatter::output::video::preflight(v)?)),
        None => Ok(None),
    }
}

/// After the frame loop: wait for the writer, record the outcome in the manifest, and
/// assemble the video.
#[allow(clippy::too_many_arguments)]
fn finish_run(
    result: Result<()>,
    writer: FrameWriter,
    progress: &Progress,
    manifest: &mut ManifestWriter,
    ffmpeg: Option<PathBuf>,
    args: &RenderArgs,
    dir: &Path,
    frames: std::ops::Range<u32>,
    fps: f32,
) -> Result<()> {
    let result = result.and_then(|()| writer.finish().map(|_| ()).map_err(Into::into));
    progress.finish();
    if let Err(e) = result {
        // The run's error is what matters; a manifest that cannot be written (a full
        // disk) must not hide it.
        let _ = manifest.finish(Some(one_line(&e)));
        return Err(e);
    }
    if let (Some(ffmpeg), Some(video)) = (ffmpeg, &args.video) {
        eprintln!("video: {} (ffmpeg)", video.display());
        if let Err(e) = splatter::output::video::assemble(&ffmpeg, dir, frames, fps, video) {
            let e = anyhow::Error::from(e);
            let _ = manifest.finish(Some(one_line(&e)));
            return Err(e);
        }
    }
    manifest.finish(None)?;
    Ok(())
}

fn report_done(
    rendered: u32,
    render_start: Instant,
    gpu_ms: f64,
    workers: usize,
    started: Instant,
) {
    let n = f64::from(rendered.max(1));
    let wall = render_start.elapsed().as_secs_f64();
    eprintln!(
        "done: {} frames rendered in {:.2} s ({:.3} s/frame; GPU render+readback {:.1} ms/frame; {} PNG worker thread(s)); total {:.2} s with scene build",
        rendered,
        wall,
        wall / n,
        gpu_ms / n,
        workers,
        started.elapsed().as_secs_f64()
    );
}

/// One frame's substeps. While the sparse grid's pool can overflow, the particle state is
/// copied aside first (on the GPU); when the steps did overflow it — the moving region grew
/// more than the pool's headroom within the frame — the frame is run again from that copy
/// with a larger pool, so results never depend on the pool's size.
fn simulate_frame(
    gpu: &GpuContext,
    gpu_sim: &mut GpuSim,
    frame: u32,
    s: &SimulationSetup,
) -> Result<Watchdog> {
    // The moving colliders' clock: this frame's steps start at frame − 1.
    let start = f64::from(frame - 1) * f64::from(s.steps_per_frame) * s.params.dt;
    loop {
        let retry = gpu_sim.pool_can_overflow();
        if retry {
            gpu_sim.save_state(gpu)?;
        }
        gpu_sim.set_time(start);
        gpu_sim.step(gpu, s.steps_per_frame)?;
        let w = gpu_sim.take_watchdog(gpu)?;
        if w.pool_overflow == 0 {
            return Ok(w);
        }
        if !retry {
            bail!(
                "frame {frame}: {} block(s) overflowed a sparse-grid pool that holds every block of the domain (an internal error; please report it)",
                w.pool_overflow
            );
        }
        log::info!(
            "frame {frame}: the sparse grid's pool of {} blocks overflowed by {}; growing it and running the frame again",
            gpu_sim.pool_blocks(),
            w.pool_overflow
        );
        gpu_sim.restore_state(gpu)?;
        // The watchdog counts every active block, also those left out: grow to twice that.
        gpu_sim.fit_pool(gpu, &w)?;
    }
}

/// `--from-states DIR`: each frame's Gaussians from DIR/frame_NNNNN.ply, rendered with the
/// scene's camera and output settings; no build, no simulation.
fn render_from_states(backend: Option<BackendChoice>, args: RenderArgs) -> Result<()> {
    let started = Instant::now();
    let states = args.from_states.clone().expect("--from-states given");
    let ffmpeg = video_preflight(&args)?;
    for (flag, value) in [("--width", args.width), ("--height", args.height)] {
        if let Some(v) = value {
            if !(1..=scene::MAX_IMAGE_SIZE).contains(&v) {
                bail!(
                    "{flag} {v}: expected an image size in pixels in 1..={}",
                    scene::MAX_IMAGE_SIZE
                );
            }
        }
    }
    let mut scene = match &args.scene {
        Some(path) => scene::load(path)?,
        None => scene::default_scene(),
    };
    scene.apply_quality(args.quality);
    scene.with_overrides(args.out.clone(), args.width, args.height)?;
    let path = scene.camera_path()?;
    let frames = frame_range(args.frames.as_deref(), scene.frame_count())?;
    splatter::farm::check_states(&states, frames.clone())?;
    // The scene's settings only: its objects come from the states.
    let hash = checkpoint::scene_hash(&scene, &splatter::render::Splats::default(), None);
    let dir = scene.output_dir();
    std::fs::create_dir_all(&dir)
        .with_context(|| format!("cannot create the output directory {}", dir.display()))?;
    let gpu = GpuContext::new(backend)?;
    eprintln!("adapter: {}", gpu.describe());
    let manifest_file = manifest_path(&dir, frames.clone(), scene.frame_count());
    let (width, height) = (scene.output.width, scene.output.height);
    limits::check_gpu(&gpu, &limits::render_needs(0, width, height))?;
    if args.resume {
        check_manifest_for_resume(&manifest_file, hash)?;
    }
    eprintln!(
        "states: {}, {}×{}, frames {}..{} → {}",
        states.display(),
        width,
        height,
        frames.start,
        frames.end,
        dir.display()
    );
    let settings = Settings {
        width,
        height,
        fps: scene.output.fps,
        frames: [frames.start, frames.end],
        scene_frames: scene.frame_count(),
        deterministic: args.deterministic,
        from_states: Some(states.clone()),
        ..Default::default()
    };
    let mut manifest = new_manifest(&args, manifest_file, hash, &gpu, settings, started);
    manifest.write_now()?;
    let mut renderer = GpuRenderer::new(&gpu);
    let background = Vec3::from(scene.output.background);
    let workers = FrameWriter::default_workers();
    let mut writer = FrameWriter::new(workers, 2 * workers);
    let mut progress = Progress::new(u64::from(frames.end - frames.start), "render");
    let render_start = Instant::now();
    let (mut gpu_ms, mut rendered) = (0.0, 0u32);
    let fail_at = fail_hook_frame()?;
    let mut run_frames = || -> Result<()> {
        for frame in frames.clone() {
            if fail_at == Some(frame) {
                eprintln!("SPLATTER_FAIL_AT_FRAME: exiting abruptly before frame {frame}");
                std::process::exit(FAIL_HOOK_EXIT);
            }
            if args.resume && frame_done(&dir, None, frame) {
                progress.frame_done();
                continue;
            }
            let t0 = Instant::now();
            let (splats, skipped) = splatter::farm::load_state(&states, frame)?;
            if skipped > 0 {
                log::warn!("frame {frame}: {skipped} NaN or degenerate Gaussians in its state were skipped");
            }
            limits::check_gpu(&gpu, &limits::render_needs(splats.len(), width, height))?;
            renderer.upload(&gpu, &splats)?;
            if let Some(l) = scene::lighting::prepare_state(&scene, &splats)? {
                renderer.set_lighting(&gpu, &l.setup)?;
                renderer.set_lights(&l.lights.at(frame as f32 / scene.output.fps));
            }
            let load_ms = t0.elapsed().as_secs_f64() * 1e3;
            let t1 = Instant::now();
            let (image, timings) = renderer.render_timed(&gpu, &path.camera(frame), background)?;
            gpu_ms += timings.render_ms + timings.readback_ms;
            writer.submit(
                frame_path(&dir, frame),
                image.width,
                image.height,
                image.rgba,
            )?;
            manifest.frame_done(
                frame,
                FrameTiming {
                    simulate_ms: 0.0,
                    load_ms: Some(load_ms),
                    render_ms: t1.elapsed().as_secs_f64() * 1e3,
                    gpu_ms: timings.render_ms + timings.readback_ms,
                },
            )?;
            rendered += 1;
            progress.frame_done();
        }
        Ok(())
    };
    let result = run_frames();
    finish_run(
        result,
        writer,
        &progress,
        &mut manifest,
        ffmpeg,
        &args,
        &dir,
        frames,
        scene.output.fps,
    )?;
    report_done(rendered, render_start, gpu_ms, workers, started);
    Ok(())
}
