//! The `splatter` command line. Errors end as one `error: …` line and a non-zero exit.

use std::path::Path;
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Parser;

use splatter::gpu::{BackendChoice, GpuContext};
use splatter::output::Progress;
use splatter::run::{Event, FragmentLog, Run, RunOptions};
use splatter::scene;

mod cli;

use cli::{BenchWhat, Cli, Command};

fn main() -> ExitCode {
    splatter::run::init_logging();
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", splatter::run::one_line(&e));
            ExitCode::FAILURE
        }
    }
}

// Over 80 lines on purpose: the command line's dispatch, one short arm per command.
fn run(cli: Cli) -> Result<()> {
    match cli.command {
        None => render(cli.backend, RunOptions::default()),
        Some(Command::Render(args)) => render(cli.backend, args.into_options()?),
        Some(Command::Inspect {
            file,
            support_height,
            preview,
            cameras,
        }) => inspect(
            cli.backend,
            &file,
            support_height,
            cameras.as_deref(),
            preview.as_deref(),
        ),
        Some(Command::Fragments { files, link }) => fragments(&files, link),
        Some(Command::Convert {
            input,
            output,
            spz_version,
        }) => convert(&input, &output, spz_version),
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
                    separation,
                    particles,
                },
        }) => {
            let gpu = GpuContext::new(cli.backend)?;
            let out = &mut std::io::stdout();
            match particles {
                Some(n) => splatter::bench::sim_scale_bench(&gpu, n, steps.max(1), out),
                None => {
                    let what = splatter::bench::SimBench {
                        steps: steps.max(1),
                        quick,
                        per_pass,
                        separation,
                    };
                    splatter::bench::sim_bench(&gpu, what, out).map(|_| ())
                }
            }
        }
        Some(Command::Bench {
            what:
                BenchWhat::Render {
                    repeat,
                    quick,
                    per_pass,
                    gaussians,
                },
        }) => {
            let gpu = GpuContext::new(cli.backend)?;
            if let Some(n) = gaussians {
                return splatter::bench::render_scale_bench(
                    &gpu,
                    n,
                    repeat.max(1),
                    &mut std::io::stdout(),
                );
            }
            splatter::bench::render_bench(
                &gpu,
                repeat.max(1),
                quick,
                per_pass,
                &mut std::io::stdout(),
            )
        }
        Some(Command::Bench {
            what: BenchWhat::Read { files, repeat },
        }) => splatter::bench::read_bench(&files, repeat.max(1), &mut std::io::stdout()),
        Some(Command::Bench {
            what: BenchWhat::Suite { args },
        }) => forward_to_lab(cli.backend, "suite", &args),
        Some(Command::Bench {
            what: BenchWhat::Accuracy { args },
        }) => forward_to_lab(cli.backend, "accuracy", &args),
    }
}

/// `bench suite` and `bench accuracy` live in the lab now (`splatter-lab`, built next to
/// this binary by `cargo build --release`): run it with the same arguments, so scripts
/// written for the old commands keep working, and exit as it does.
fn forward_to_lab(backend: Option<BackendChoice>, command: &str, args: &[String]) -> Result<()> {
    let lab = std::env::current_exe()?
        .with_file_name(format!("splatter-lab{}", std::env::consts::EXE_SUFFIX));
    if !lab.is_file() {
        anyhow::bail!(
            "`splatter bench {command}` moved to the lab: run `splatter-lab {command}` ({} not found; `cargo build --release` builds it next to splatter)",
            lab.display()
        );
    }
    let mut cmd = std::process::Command::new(&lab);
    if let Some(b) = backend {
        use clap::ValueEnum;
        let name = b.to_possible_value().map(|v| v.get_name().to_string());
        cmd.args(["--backend", &name.unwrap_or_default()]);
    }
    let status = cmd
        .arg(command)
        .args(args)
        .status()
        .with_context(|| format!("cannot run {}", lab.display()))?;
    std::process::exit(status.code().unwrap_or(1));
}

/// `splatter inspect`: the report (warnings on stderr), and with `--preview` an overview
/// image.
fn inspect(
    backend: Option<BackendChoice>,
    file: &Path,
    support_height: f32,
    cameras: Option<&Path>,
    preview: Option<&Path>,
) -> Result<()> {
    let (cloud, found, report) =
        splatter::run::preview::inspect_file(file, support_height, cameras)?;
    println!("{report}");
    for w in found.warnings(&file.display().to_string()) {
        log::warn!("{w}");
    }
    if let Some(png) = preview {
        let gpu = GpuContext::new(backend)?;
        splatter::run::preview::write(&gpu, &cloud, &found.inspection, png)?;
        println!("preview:       {}", png.display());
    }
    Ok(())
}

/// `splatter convert`: one line naming what was read and written.
fn convert(input: &Path, output: &Path, spz_version: u32) -> Result<()> {
    use splatter::splat::spz::SpzVersion;
    let spz = if spz_version == 4 {
        SpzVersion::V4
    } else {
        SpzVersion::V3
    };
    let done = splatter::splat::convert::convert(input, output, spz)?;
    println!("{} → {}: {done}", input.display(), output.display());
    Ok(())
}

/// `splatter render`: prepare on the CPU, then open the GPU and run, printing the run's
/// notes and a progress bar.
fn render(backend: Option<BackendChoice>, opts: RunOptions) -> Result<()> {
    let fail_at = fail_hook_frame()?;
    let run = Run::prepare(opts)?;
    if let Some(why) = run.idle() {
        // A farm task with no frames: done, without a GPU.
        eprintln!("{why}");
        return Ok(());
    }
    let gpu = GpuContext::new(backend)?;
    let mut progress: Option<Progress> = None;
    let mut on_event = |event: Event| match event {
        Event::Note(line) => eprintln!("{line}"),
        Event::Frames(frames) => progress = Some(Progress::new(frames.len() as u64, "render")),
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

/// `splatter fragments`: the pieces of each file's particles, per object.
fn fragments(files: &[std::path::PathBuf], link: Option<f64>) -> Result<()> {
    use splatter::fragments::PIECE_SHARE;
    if let Some(l) = link {
        anyhow::ensure!(
            l.is_finite() && l > 0.0,
            "--link {l}: expected a positive distance"
        );
    }
    for path in files {
        let file = splatter::output::particles::read(path)?;
        let Some(link) = link.or(file.dx) else {
            anyhow::bail!(
                "{}: no `comment dx` in its header to take the link distance from; give --link",
                path.display()
            );
        };
        for p in file.pieces(link) {
            let s = &p.summary;
            let which = p.object.map(|o| format!(" object {o}")).unwrap_or_default();
            let damaged = p
                .damaged_share
                .map(|d| format!(", {:.1}% broken through", 100.0 * d))
                .unwrap_or_default();
            println!(
                "{}{which}: {} particles, {} piece(s) with ≥ {:.0}% (largest {:.1}%), {} particles of debris, {} fragments in all (link {link}){damaged}",
                path.display(),
                s.particles,
                s.pieces,
                PIECE_SHARE * 100.0,
                s.largest_share * 100.0,
                s.debris,
                s.fragments,
            );
        }
    }
    Ok(())
}
