//! The `splatter` command line. Errors end as one `error: …` line and a non-zero exit.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};

use splatter::gpu::{BackendChoice, GpuContext};
use splatter::output::Progress;
use splatter::run::{Event, FragmentLog, Input, Run, RunOptions};
use splatter::scene;

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
    /// paper example under scenes/ next to the paper's column (docs/method.md §9), written to
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
    /// Also write each rendered frame's Gaussians as SPZ (version 3, gzip; an order of
    /// magnitude smaller than PLY, opened by web viewers): DIR/frame_00000.spz, …
    #[arg(long, value_name = "DIR")]
    export_spz: Option<PathBuf>,
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
    #[arg(long, value_name = "DIR", conflicts_with_all = ["ply", "export_ply", "export_spz"])]
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
            eprintln!("error: {}", splatter::run::one_line(&e));
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        None => render(cli.backend, RunOptions::default()),
        Some(Command::Render(args)) => render(cli.backend, args.into_options()),
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
    fn into_options(self) -> RunOptions {
        let input = match (self.from_states, self.ply) {
            (Some(dir), _) => Input::States {
                scene: self.scene,
                dir,
            },
            (None, Some(file)) => Input::Ply {
                file,
                cameras: self.cameras,
                camera: self.camera,
            },
            (None, None) => Input::Scene(self.scene),
        };
        RunOptions {
            input,
            out: self.out,
            frames: self.frames,
            width: self.width,
            height: self.height,
            quality: self.quality,
            export_ply: self.export_ply,
            export_spz: self.export_spz,
            resume: self.resume,
            deterministic: self.deterministic,
            checkpoint_every: self.checkpoint_every,
            video: self.video,
            fragments: self.fragments,
        }
    }
}

/// `splatter render`: prepare on the CPU, then open the GPU and run, printing the run's
/// notes and a progress bar.
fn render(backend: Option<BackendChoice>, opts: RunOptions) -> Result<()> {
    let fail_at = fail_hook_frame()?;
    let run = Run::prepare(opts)?;
    let gpu = GpuContext::new(backend)?;
    let mut progress: Option<Progress> = None;
    let mut on_event = |event: Event| match event {
        Event::Note(line) => eprintln!("{line}"),
        Event::Frames(frames) => {
            progress = Some(Progress::new(
                u64::from(frames.end - frames.start),
                "render",
            ))
        }
        Event::FrameStart(frame) => {
            if fail_at == Some(frame) {
                eprintln!("SPLATTER_FAIL_AT_FRAME: exiting abruptly before frame {frame}");
                std::process::exit(FAIL_HOOK_EXIT);
            }
        }
        Event::FrameDone { .. } => {
            if let Some(p) = &mut progress {
                p.frame_done();
            }
        }
        Event::FramesWritten => {
            if let Some(p) = &progress {
                p.finish();
            }
        }
    };
    let summary = run.execute(&gpu, &mut on_event)?;
    eprintln!("{}", summary.describe());
    for line in FragmentLog::describe(&summary.fragments) {
        eprintln!("{line}");
    }
    Ok(())
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
