//! The `splatter` command line. Errors end as one `error: …` line and a non-zero exit.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use glam::Vec3;

use splatter::gpu::{BackendChoice, GpuContext};
use splatter::output::{frame_path, FrameWriter, Progress};
use splatter::render::GpuRenderer;
use splatter::scene::simulation::SimulationSetup;
use splatter::scene::{self, BuildReport, CameraPath, Scene};
use splatter::sim::derive::Derive;
use splatter::sim::gpu::{GpuSim, Watchdog};

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
    Render(RenderArgs),
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
        Some(Command::Render(args)) => render(cli.backend, args),
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
    }
}

impl RenderArgs {
    fn default_scene() -> RenderArgs {
        RenderArgs {
            export_ply: None,
            scene: None,
            out: None,
            frames: None,
            width: None,
            height: None,
            ply: None,
            cameras: None,
            camera: None,
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
    let started = Instant::now();
    let (scene, path, splats, report) = prepare(&args)?;
    let frames = frame_range(args.frames.as_deref(), scene.frame_count())?;
    let setup = scene::simulation::prepare(&scene, splats.clone(), &report)?;
    let splats = setup.as_ref().map_or(splats, |s| s.splats.clone());
    let dir = scene.output_dir();
    std::fs::create_dir_all(&dir)
        .with_context(|| format!("cannot create the output directory {}", dir.display()))?;

    let gpu = GpuContext::new(backend)?;
    eprintln!("adapter: {}", gpu.describe());
    eprintln!(
        "scene: {} Gaussians, {}×{}, frames {}..{} → {}",
        splats.len(),
        scene.output.width,
        scene.output.height,
        frames.start,
        frames.end,
        dir.display()
    );
    let mut renderer = GpuRenderer::new(&gpu);
    renderer.upload(&gpu, &splats)?;
    let background = Vec3::from(scene.output.background);
    let sim = match &setup {
        Some(s) => {
            for w in &s.warnings {
                log::warn!("{w}");
            }
            eprintln!(
                "simulation: {} particles, {} materials, grid {}×{}×{} (Δx {}), Δt {:.3e} s, {} steps per frame",
                s.particles.len(),
                s.materials.len(),
                s.grid.cells.x,
                s.grid.cells.y,
                s.grid.cells.z,
                s.grid.dx,
                s.params.dt,
                s.steps_per_frame
            );
            let gpu_sim = GpuSim::new(&gpu, &s.particles, &s.grid, &s.materials, &s.params)?;
            let derive = Derive::new(&gpu, &gpu_sim, &renderer, &s.splats, s.static_count as u32)?;
            Some((gpu_sim, derive, s))
        }
        None => None,
    };

    if let Some(dir) = &args.export_ply {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create the PLY export directory {}", dir.display()))?;
    }
    let rotator = args
        .export_ply
        .as_ref()
        .map(|_| splatter::splat::sh::ShRotator::new());
    let workers = FrameWriter::default_workers();
    let mut writer = FrameWriter::new(workers, 2 * workers);
    let mut progress = Progress::new(u64::from(frames.end - frames.start), "render");
    let render_start = Instant::now();
    let mut gpu_ms = 0.0;
    // Frame f shows the state after f · steps_per_frame steps; a range that starts later
    // simulates the frames before it without rendering them.
    let first = if sim.is_some() { 0 } else { frames.start };
    for frame in first..frames.end {
        if let Some((gpu_sim, derive, s)) = &sim {
            if frame > 0 {
                gpu_sim.step(&gpu, s.steps_per_frame)?;
            }
            let w = gpu_sim.take_watchdog(&gpu)?;
            if w.nonfinite > 0 || w.escaped > 0 {
                bail!("{}", watchdog_message(frame, w, s));
            }
            if frame < frames.start {
                continue;
            }
            derive.run(&gpu)?;
        }
        if let (Some(dir), Some(rotator)) = (&args.export_ply, &rotator) {
            let gaussians = renderer.read_gaussians(&gpu)?;
            splatter::output::export::export_frame(dir, frame, &gaussians, &splats, rotator)?;
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
        progress.frame_done();
    }
    let encode = writer.finish()?;
    progress.finish();
    let n = f64::from(frames.end - frames.start);
    let wall = render_start.elapsed().as_secs_f64();
    eprintln!(
        "done: {} frames in {:.2} s ({:.3} s/frame; GPU render+readback {:.1} ms/frame, PNG encoding {:.1} ms/frame on {} worker thread(s)); total {:.2} s with scene build",
        n,
        wall,
        wall / n,
        gpu_ms / n,
        encode.as_secs_f64() * 1e3 / n,
        workers,
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
