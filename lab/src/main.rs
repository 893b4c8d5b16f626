//! `splatter-lab`: the project's own measurements (see the library's docs). Each command
//! writes where docs/performance.md and docs/accuracy.md say their figures come from.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Result};
use clap::{Parser, Subcommand, ValueEnum};
use splatter::gpu::{BackendChoice, GpuContext};
use splatter::sim::gpu::P2gPath;
use splatter::sim::model::nacc::oracle::ReturnMapping;
use splatter_lab::peer::Peer;
use splatter_lab::{AccuracyOptions, Part};

#[derive(Parser)]
#[command(
    name = "splatter-lab",
    version,
    about = "splatter's lab: studies, the paper-examples suite, peers"
)]
struct Cli {
    /// wgpu backend (default: the best the machine has).
    #[arg(long, global = true, value_enum)]
    backend: Option<BackendChoice>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// The sim, render and end-to-end benchmarks in one run: seconds per frame of each
    /// paper example under scenes/ next to the paper's column (docs/method.md §9), written to
    /// OUT/data/bench_suite.{json,md} (docs/performance.md).
    Suite(Box<SuiteArgs>),
    /// Convergence study, stability atlas and shatter study: JSON and tables in OUT/data/,
    /// charts in OUT/images/ (docs/accuracy.md).
    Accuracy(Box<AccuracyArgs>),
    /// The 20k-particle cases of `splatter bench sim --quick`, then the fixed-corotated one
    /// stepped by a peer in the same run, and the ratios (docs/performance.md).
    Peer {
        /// taichi: `benches/peers/taichi_mpm.py`, needs `pip install taichi==1.7.4`;
        /// slosh: `benches/peers/slosh/`, built beforehand as its README says.
        #[arg(value_enum)]
        peer: Peer,
        /// Steps timed per case (after one warm-up step).
        #[arg(long, default_value_t = 20)]
        steps: u32,
        /// Also break each case down by pass.
        #[arg(long)]
        per_pass: bool,
    },
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
    /// Run the end-to-end examples' P2G on this path (as `splatter render --p2g`), e.g. to
    /// reproduce a failure on every path.
    #[arg(long, value_name = "PATH", value_enum)]
    p2g: Option<P2gArg>,
}

#[derive(clap::Args)]
struct AccuracyArgs {
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
    /// Grid spacings of the shatter study instead of its default ones (metres,
    /// comma-separated, coarse to fine; finer than 0.01 is meant for a GPU).
    #[arg(long, value_delimiter = ',')]
    shatter_dx: Option<Vec<f64>>,
    /// Return mappings of the shatter study (comma-separated; default both).
    #[arg(long, value_delimiter = ',', value_parser = return_mapping)]
    shatter_mapping: Option<Vec<ReturnMapping>>,
    /// Simulate one quarter of the fruit between two symmetry planes through its
    /// centre: a quarter of the particles, so a CPU reaches finer spacings (no stills).
    #[arg(long)]
    shatter_quarter: bool,
    /// Directory of the shipped scenes (the shatter study runs watermelon_drop_nacc.json).
    #[arg(long, default_value = "scenes")]
    scenes: PathBuf,
}

#[derive(Clone, Copy, ValueEnum)]
enum AccuracyPart {
    All,
    Convergence,
    Atlas,
    /// The flat watermelon drop at several Δx, both return mappings.
    Shatter,
}

/// A P2G path by name (as the product's `--p2g`).
#[derive(Clone, Copy, ValueEnum)]
enum P2gArg {
    Gather,
    Atomic,
    Fixed,
}

impl P2gArg {
    fn path(self) -> P2gPath {
        match self {
            P2gArg::Gather => P2gPath::Gather,
            P2gArg::Atomic => P2gPath::Atomic,
            P2gArg::Fixed => P2gPath::Fixed,
        }
    }
}

/// A return mapping by its scene-file name (`sim::model::nacc::oracle::ReturnMapping`).
fn return_mapping(name: &str) -> Result<ReturnMapping, String> {
    ReturnMapping::from_name(name).ok_or_else(|| {
        let names: Vec<_> = ReturnMapping::ALL.iter().map(|m| m.name()).collect();
        format!("expected one of {}", names.join(", "))
    })
}

fn main() -> ExitCode {
    splatter::run::init_logging();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Suite(args) => suite(cli.backend, &args),
        Command::Accuracy(args) => accuracy(cli.backend, &args),
        Command::Peer {
            peer,
            steps,
            per_pass,
        } => peer_ratio(cli.backend, peer, steps.max(1), per_pass),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", splatter::run::one_line(&e));
            ExitCode::FAILURE
        }
    }
}

fn suite(backend: Option<BackendChoice>, args: &SuiteArgs) -> Result<()> {
    if !(args.scale > 0.0 && args.scale.is_finite()) {
        bail!("--scale {}: expected a positive factor", args.scale);
    }
    let gpu = GpuContext::new(backend)?;
    let opts = splatter_lab::suite::SuiteOptions {
        quick: args.quick,
        scale: args.scale,
        frames: args.frames.unwrap_or(if args.quick { 3 } else { 4 }).max(2),
        width: args.width,
        height: args.height,
        sim_steps: 20,
        repeat: if args.quick { 3 } else { 5 },
        scenes: args.scenes.clone(),
        p2g: args.p2g.map(|p| p.path().name().to_string()),
    };
    let out = args.out.join("data");
    splatter_lab::suite::run_suite(&gpu, &opts, &out, &mut std::io::stderr())?;
    Ok(())
}

fn accuracy(backend: Option<BackendChoice>, args: &AccuracyArgs) -> Result<()> {
    if args.quick && !args.redraw && args.out == Path::new("docs") {
        // The smoke sweeps would overwrite the documented numbers.
        bail!("--quick runs smoke-sized sweeps: give an --out other than docs");
    }
    if let Some(bad) = args
        .shatter_dx
        .iter()
        .flatten()
        .find(|dx| !(**dx > 0.0 && dx.is_finite()))
    {
        bail!("--shatter-dx {bad}: expected positive grid spacings in metres");
    }
    // In the study's order, each once.
    let shatter_mappings: Option<Vec<ReturnMapping>> =
        args.shatter_mapping.as_ref().map(|chosen| {
            splatter_lab::shatter::MAPPINGS
                .into_iter()
                .filter(|m| chosen.contains(m))
                .collect()
        });
    let part = match args.only {
        AccuracyPart::All => Part::All,
        AccuracyPart::Convergence => Part::Convergence,
        AccuracyPart::Atlas => Part::Atlas,
        AccuracyPart::Shatter => Part::Shatter,
    };
    let simulates_on_gpu = !args.redraw && matches!(part, Part::All | Part::Shatter);
    let gpu = simulates_on_gpu
        .then(|| GpuContext::new(backend))
        .transpose()?;
    let opts = AccuracyOptions {
        part,
        quick: args.quick,
        redraw: args.redraw,
        gpu: gpu.as_ref(),
        scenes: &args.scenes,
        shatter_dx: args.shatter_dx.as_deref(),
        shatter_mappings: shatter_mappings.as_deref(),
        shatter_quarter: args.shatter_quarter,
    };
    splatter_lab::run_accuracy(&opts, &args.out, &mut std::io::stderr())
}

/// Our 20k cases first (as `splatter bench sim --quick`), then the peer's fixed-corotated
/// case, in one run on one machine, and the ratios.
fn peer_ratio(
    backend: Option<BackendChoice>,
    peer: Peer,
    steps: u32,
    per_pass: bool,
) -> Result<()> {
    use splatter::bench::{SimBench, SimCase, SimModel};
    peer.check()?;
    let gpu = GpuContext::new(backend)?;
    let out = &mut std::io::stdout();
    let what = SimBench {
        steps,
        quick: true,
        per_pass,
        separation: false,
    };
    let ours = splatter::bench::sim_bench(&gpu, what, out)?;
    let case = SimCase::with_model(20_000, 64, SimModel::FixedCorotated);
    let run = peer.run(&case, steps)?;
    println!("peer: {}: {:.2} ms/step", run.line, run.ms);
    for pass in &run.passes {
        println!("peer {pass}");
    }
    for (model, t) in &ours {
        println!(
            "peer ratio: splatter {} {} / {} fixed_corotated = {:.2}",
            model.name(),
            t.p2g,
            peer.name(),
            t.ms_per_step / run.ms
        );
    }
    Ok(())
}
