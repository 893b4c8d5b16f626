//! `splatter-lab suite`: the simulation, render and end-to-end benchmarks in one run,
//! written as JSON and as a markdown table next to the paper's seconds per frame
//! (docs/method.md §9), with the adapter, the machine's cores and the command line.
//!
//! End to end means what a user waits for: `splatter render SCENE` run as a child process
//! for a few frames (simulation steps, derive, render, PNG writing), timed per frame from
//! the run's `manifest.json`. Scenes can be coarsened (`--scale s` multiplies the grid
//! spacing `dx` and every procedural `spacing` by s, so N drops by about s³) to fit a CPU
//! machine.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use glam::Vec3;
use serde::{Deserialize, Serialize};

use splatter::bench::{sim_paths, synthetic_splats, time_render, time_sim, SimCase};
use splatter::bench::{RenderTiming, SimTiming};
use splatter::gpu::GpuContext;
use splatter::output::manifest::Manifest;
use splatter::render::{Camera, GpuRenderer};
use splatter::run::{one_line, Input, Run, RunOptions};

/// One row of docs/method.md §9's table: what the paper reports for an example.
#[derive(Clone, Copy, Debug)]
pub struct PaperExample {
    /// File stem under `scenes/`.
    pub name: &'static str,
    /// Seconds per rendered frame on the paper's GPU (52 TFLOPS class, Warp).
    pub s_per_frame: f64,
    /// Particle count N.
    pub n: f64,
    pub dx: f64,
    pub dt_step: f64,
    pub dt_frame: f64,
}

/// docs/method.md §9 (the source paper's Table A1, as read there).
pub const PAPER_EXAMPLES: [PaperExample; 8] = [
    ex("watermelon", 3.56, 27e6, 3e-3, 1e-4, 1.0 / 50.0),
    ex("jelly", 0.39, 1e6, 3e-3, 1e-5, 1.0 / 500.0),
    ex("pumpkin", 5.12, 27e6, 3e-3, 1e-4, 1.0 / 50.0),
    ex("kiwi", 1.58, 1e6, 1e-2, 1e-4, 1.0 / 50.0),
    ex("pineapple", 1.16, 1e6, 1e-2, 1e-4, 1.0 / 50.0),
    ex("dragonfruit", 2.27, 1e6, 1e-2, 1e-4, 1.0 / 50.0),
    ex("toast", 3.18, 8e6, 5e-3, 1e-4, 1.0 / 50.0),
    ex("sandcastle", 2.09, 8e6, 1e-2, 1e-4, 1.0 / 50.0),
];

const fn ex(
    name: &'static str,
    s_per_frame: f64,
    n: f64,
    dx: f64,
    dt_step: f64,
    dt_frame: f64,
) -> PaperExample {
    PaperExample {
        name,
        s_per_frame,
        n,
        dx,
        dt_step,
        dt_frame,
    }
}

/// Our own simulated demo scenes, timed after the paper's examples.
pub const EXTRA_SCENES: [&str; 3] = ["fracture", "pillow", "table"];

/// Options of `splatter-lab suite`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SuiteOptions {
    /// Small cases only (no 1M-particle sim or 1M-Gaussian render case), fewer frames.
    pub quick: bool,
    /// Coarsening of the example scenes (1: as shipped).
    pub scale: f64,
    /// Frames rendered per example (frame 0 is the initial state; the timed frames are
    /// 1..frames, each with a full frame of simulation steps).
    pub frames: u32,
    pub width: u32,
    pub height: u32,
    /// Steps timed per simulation case.
    pub sim_steps: u32,
    /// Repeats per render case.
    pub repeat: usize,
    /// Directory holding the example scenes.
    pub scenes: PathBuf,
    /// The end-to-end runs' P2G path by name (`P2gPath::name`); None: as `render` chooses.
    #[serde(default)]
    pub p2g: Option<String>,
}

/// One example's end-to-end result.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EndToEnd {
    pub example: String,
    /// The paper's numbers (None for our own demo scenes).
    pub paper_s_per_frame: Option<f64>,
    pub paper_n: Option<f64>,
    /// "ran", "missing" (no scene file) or "failed".
    pub status: String,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub note: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub run: Option<EndToEndRun>,
}

/// Measured numbers of an example that ran.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EndToEndRun {
    pub particles: usize,
    pub gaussians: usize,
    pub steps_per_frame: u32,
    pub dt: f64,
    pub frames_timed: u32,
    /// Mean over the timed frames of the simulation part (steps + watchdog read).
    pub sim_s_per_frame: f64,
    /// Mean over the timed frames of derive, render and readback.
    pub render_s_per_frame: f64,
    /// sim + render.
    pub s_per_frame: f64,
    /// Whole child process, setup and PNG writing included, over all frames.
    pub wall_s: f64,
    /// The P2G path the run took (its manifest's).
    #[serde(default)]
    pub p2g: Option<String>,
}

/// Everything `splatter-lab suite` measured.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SuiteReport {
    pub command: String,
    pub adapter: String,
    pub cores: usize,
    /// /proc/loadavg (1, 5, 15 min) when the suite started: timings on a shared machine
    /// mean little without it.
    #[serde(default)]
    pub load_average: Option<[f64; 3]>,
    pub commit: String,
    pub options_quick: bool,
    pub options_scale: f64,
    pub sim: Vec<SimTiming>,
    pub render: Vec<RenderCase>,
    pub end_to_end: Vec<EndToEnd>,
}

/// A render case and its timing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RenderCase {
    pub gaussians: usize,
    pub width: u32,
    pub height: u32,
    pub timing: RenderTiming,
}

/// Runs the suite and writes `OUT/bench_suite.json` and `OUT/bench_suite.md`.
pub fn run_suite(
    gpu: &GpuContext,
    opts: &SuiteOptions,
    out_dir: &Path,
    log: &mut dyn Write,
) -> Result<SuiteReport> {
    writeln!(log, "adapter: {}", gpu.describe())?;
    let load_average = load_average();
    let sim = sim_cases(gpu, opts, log)?;
    let render = render_cases(gpu, opts, log)?;
    let mut end_to_end = Vec::new();
    let paper = PAPER_EXAMPLES.iter().map(|e| (e.name, Some(e)));
    let extra = EXTRA_SCENES.iter().map(|name| (*name, None));
    for (name, example) in paper.chain(extra) {
        let row = end_to_end_example(gpu, name, example, opts);
        writeln!(log, "end to end {name}: {}", summary(&row))?;
        end_to_end.push(row);
    }
    let report = SuiteReport {
        command: std::env::args().collect::<Vec<_>>().join(" "),
        adapter: gpu.describe(),
        cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
        load_average,
        commit: git_commit(),
        options_quick: opts.quick,
        options_scale: opts.scale,
        sim,
        render,
        end_to_end,
    };
    std::fs::create_dir_all(out_dir)?;
    let json = out_dir.join("bench_suite.json");
    std::fs::write(&json, serde_json::to_string_pretty(&report)? + "\n")?;
    std::fs::write(out_dir.join("bench_suite.md"), markdown(&report))?;
    writeln!(log, "wrote {} and bench_suite.md", json.display())?;
    Ok(report)
}

fn summary(row: &EndToEnd) -> String {
    match &row.run {
        Some(r) => format!(
            "{:.3} s/frame ({} particles, {} steps/frame)",
            r.s_per_frame, r.particles, r.steps_per_frame
        ),
        None => format!("{} {}", row.status, row.note.clone().unwrap_or_default()),
    }
}

fn sim_cases(gpu: &GpuContext, opts: &SuiteOptions, log: &mut dyn Write) -> Result<Vec<SimTiming>> {
    let mut cases = vec![(20_000usize, 64u32)];
    if !opts.quick {
        cases.push((1_000_000, 128));
    }
    let mut rows = Vec::new();
    for (n, cells) in cases {
        let case = SimCase::new(n, cells);
        for path in sim_paths(gpu) {
            let (_, t) = time_sim(gpu, &case, path, opts.sim_steps)?;
            writeln!(
                log,
                "sim {n} {cells}³ {}: {:.2} ms/step",
                t.p2g, t.ms_per_step
            )?;
            rows.push(t);
        }
    }
    Ok(rows)
}

fn render_cases(
    gpu: &GpuContext,
    opts: &SuiteOptions,
    log: &mut dyn Write,
) -> Result<Vec<RenderCase>> {
    let mut cases = vec![(100_000usize, 640u32, 360u32), (100_000, 1920, 1080)];
    if !opts.quick {
        cases.push((1_000_000, 1920, 1080));
    }
    let mut renderer = GpuRenderer::new(gpu);
    let mut last_n = 0;
    let mut rows = Vec::new();
    for (n, w, h) in cases {
        if n != last_n {
            renderer.upload(gpu, &synthetic_splats(n, 3, 7))?;
            last_n = n;
        }
        // The same view as `bench render`.
        let camera = Camera::look_at(
            Vec3::new(0.0, -2.6, 0.9),
            Vec3::ZERO,
            Vec3::Z,
            50f32.to_radians(),
            w,
            h,
        );
        let timing = time_render(gpu, &mut renderer, &camera, opts.repeat)?;
        writeln!(log, "render {n} {w}x{h}: {:.1} ms", timing.render_ms)?;
        rows.push(RenderCase {
            gaussians: n,
            width: w,
            height: h,
            timing,
        });
    }
    Ok(rows)
}

/// Runs one scene end to end, or says why not.
fn end_to_end_example(
    gpu: &GpuContext,
    name: &str,
    example: Option<&PaperExample>,
    opts: &SuiteOptions,
) -> EndToEnd {
    let scene = opts.scenes.join(format!("{name}.json"));
    let mut row = EndToEnd {
        example: name.to_string(),
        paper_s_per_frame: example.map(|e| e.s_per_frame),
        paper_n: example.map(|e| e.n),
        status: "missing".into(),
        note: None,
        run: None,
    };
    if !scene.exists() {
        row.note = Some(format!("no {}", scene.display()));
        return row;
    }
    match run_render(gpu, &scene, opts) {
        Ok(run) => {
            row.status = "ran".into();
            row.run = Some(run);
        }
        Err(e) => {
            row.status = "failed".into();
            let msg = format!("{e:#}");
            row.note = Some(msg.split_whitespace().collect::<Vec<_>>().join(" "));
        }
    }
    row
}

/// A run of `scene` (coarsened by `opts.scale`), frames 0..opts.frames, through the
/// library's [`Run`], then the per-frame timings from its manifest.
fn run_render(gpu: &GpuContext, scene: &Path, opts: &SuiteOptions) -> Result<EndToEndRun> {
    let tmp = std::env::temp_dir().join(format!("splatter-suite-{}", std::process::id()));
    std::fs::create_dir_all(&tmp)?;
    let scene_file = tmp.join("scene.json");
    let text = std::fs::read_to_string(scene)
        .with_context(|| format!("cannot read {}", scene.display()))?;
    let mut value: serde_json::Value = serde_json::from_str(&text)?;
    let base = scene.parent().unwrap_or(Path::new("."));
    prepare_scene(&mut value, opts.scale, base);
    std::fs::write(&scene_file, serde_json::to_string(&value)?)?;
    let frames_dir = tmp.join("frames");
    let _ = std::fs::remove_dir_all(&frames_dir);
    let run_opts = RunOptions {
        input: Input::Scene(Some(scene_file)),
        out: Some(frames_dir.clone()),
        frames: Some(format!("0..{}", opts.frames)),
        width: Some(opts.width),
        height: Some(opts.height),
        checkpoint_every: 0,
        p2g: opts
            .p2g
            .as_deref()
            .and_then(splatter::sim::gpu::P2gPath::from_name),
        ..RunOptions::default()
    };
    let start = Instant::now();
    let result = Run::prepare(run_opts)
        .and_then(|run| run.execute(gpu, &mut |_| {}))
        .map_err(|e| anyhow::anyhow!("render failed: {}", one_line(&e)))
        .and_then(|_| read_manifest(&frames_dir, start.elapsed().as_secs_f64()));
    let _ = std::fs::remove_dir_all(&tmp);
    result
}

/// Per-frame means of the frames after 0 (frame 0 runs no steps).
fn read_manifest(dir: &Path, wall_s: f64) -> Result<EndToEndRun> {
    let file = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("manifest"))
        })
        .context("the render wrote no manifest")?;
    let m = Manifest::read(&file).context("unreadable manifest")?;
    let timed: Vec<_> = m.frames.iter().filter(|(f, _)| **f > 0).collect();
    let n = timed.len().max(1) as f64;
    let sim = timed.iter().map(|(_, t)| t.simulate_ms).sum::<f64>() / n / 1e3;
    let render = timed.iter().map(|(_, t)| t.render_ms).sum::<f64>() / n / 1e3;
    Ok(EndToEndRun {
        p2g: m.settings.p2g.clone(),
        particles: m.settings.particles.unwrap_or(0),
        gaussians: m.settings.gaussians,
        steps_per_frame: m.settings.steps_per_frame.unwrap_or(0),
        dt: m.settings.dt.unwrap_or(0.0),
        frames_timed: timed.len() as u32,
        sim_s_per_frame: sim,
        render_s_per_frame: render,
        s_per_frame: sim + render,
        wall_s,
    })
}

/// Coarsens a scene by `scale` (the simulation's `dx` and every `spacing` times `scale`)
/// and makes relative file paths absolute against `base`, so that the copy can live
/// elsewhere.
pub fn prepare_scene(value: &mut serde_json::Value, scale: f64, base: &Path) {
    use serde_json::Value;
    match value {
        Value::Object(map) => {
            for (key, v) in map.iter_mut() {
                match v {
                    Value::Number(n) if scale != 1.0 && (key == "spacing" || key == "dx") => {
                        if let Some(x) = n.as_f64() {
                            *v = Value::from(x * scale);
                        }
                    }
                    Value::String(s) if base.join(s.as_str()).is_file() => {
                        *v = Value::from(base.join(s.as_str()).to_string_lossy().into_owned());
                    }
                    _ => prepare_scene(v, scale, base),
                }
            }
        }
        Value::Array(items) => items.iter_mut().for_each(|v| prepare_scene(v, scale, base)),
        _ => {}
    }
}

fn load_average() -> Option<[f64; 3]> {
    let text = std::fs::read_to_string("/proc/loadavg").ok()?;
    let v: Vec<f64> = text
        .split_whitespace()
        .take(3)
        .filter_map(|x| x.parse().ok())
        .collect();
    (v.len() == 3).then(|| [v[0], v[1], v[2]])
}

fn git_commit() -> String {
    std::process::Command::new("git")
        .args(["rev-parse", "--short", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|| "unknown".into())
}

/// The report as markdown: header lines, then the end-to-end table next to the paper's
/// column, then the simulation and render tables. Every number comes from `r` with a
/// fixed format (`tests` check the table against the JSON).
pub fn markdown(r: &SuiteReport) -> String {
    let mut s = String::new();
    let load = r.load_average.map_or("unknown".into(), |l| {
        format!("{:.2} {:.2} {:.2}", l[0], l[1], l[2])
    });
    s += &format!(
        "Adapter: {}; {} CPU cores (load average at the start {load}); commit `{}`; command `{}`.\n\n",
        r.adapter, r.cores, r.commit, r.command
    );
    s += "| example | paper s/frame | paper N | status | particles | steps/frame | sim s/frame | render s/frame | s/frame |\n";
    s += "|---|---:|---:|---|---:|---:|---:|---:|---:|\n";
    for e in &r.end_to_end {
        let cells = match &e.run {
            Some(run) => format!(
                "{} | {} | {:.3} | {:.3} | {:.3}",
                run.particles,
                run.steps_per_frame,
                run.sim_s_per_frame,
                run.render_s_per_frame,
                run.s_per_frame
            ),
            None => format!(
                "{} | | | |",
                e.note.as_deref().unwrap_or("").replace('|', "/")
            ),
        };
        s += &format!(
            "| {} | {} | {} | {} | {} |\n",
            e.example,
            e.paper_s_per_frame
                .map_or("–".into(), |v| format!("{v:.2}")),
            e.paper_n.map_or("–".into(), si),
            e.status,
            cells
        );
    }
    s += "\n| particles | grid | P2G | ms/step | ns/particle-step | GPU bytes/particle |\n";
    s += "|---:|---:|---|---:|---:|---:|\n";
    for t in &r.sim {
        s += &format!(
            "| {} | {}³ | {} | {:.2} | {:.1} | {:.0} |\n",
            t.particles,
            t.cells,
            t.p2g,
            t.ms_per_step,
            t.ns_per_particle_step,
            t.gpu_bytes as f64 / t.particles.max(1) as f64
        );
    }
    s += "\n| Gaussians | resolution | render ms | readback ms | png ms | tile pairs |\n";
    s += "|---:|---:|---:|---:|---:|---:|\n";
    for c in &r.render {
        s += &format!(
            "| {} | {}×{} | {:.1} | {:.2} | {:.2} | {} |\n",
            c.gaussians,
            c.width,
            c.height,
            c.timing.render_ms,
            c.timing.readback_ms,
            c.timing.png_ms,
            c.timing.tile_pairs
        );
    }
    s
}

/// 27e6 → "27M", 1e6 → "1M".
fn si(n: f64) -> String {
    if n >= 1e6 {
        format!("{}M", n / 1e6)
    } else {
        format!("{n}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report() -> SuiteReport {
        SuiteReport {
            command: "splatter-lab suite".into(),
            adapter: "test".into(),
            cores: 2,
            load_average: Some([1.0, 2.0, 3.0]),
            commit: "abc".into(),
            options_quick: true,
            options_scale: 1.0,
            sim: vec![SimTiming {
                particles: 19683,
                cells: 64,
                p2g: "atomic".into(),
                steps: 20,
                ms_per_step: 17.25,
                ns_per_particle_step: 876.4,
                gpu_bytes: 10_373_000,
            }],
            render: vec![],
            end_to_end: vec![
                EndToEnd {
                    example: "jelly".into(),
                    paper_s_per_frame: Some(0.39),
                    paper_n: Some(1e6),
                    status: "ran".into(),
                    note: None,
                    run: Some(EndToEndRun {
                        particles: 1234,
                        gaussians: 5000,
                        steps_per_frame: 40,
                        dt: 1e-3,
                        frames_timed: 3,
                        sim_s_per_frame: 0.1234,
                        render_s_per_frame: 0.0456,
                        s_per_frame: 0.169,
                        wall_s: 2.0,
                        p2g: Some("gather".into()),
                    }),
                },
                EndToEnd {
                    example: "kiwi".into(),
                    paper_s_per_frame: Some(1.58),
                    paper_n: Some(1e6),
                    status: "missing".into(),
                    note: Some("no scenes/kiwi.json".into()),
                    run: None,
                },
            ],
        }
    }

    /// The table is made from the JSON's numbers: a round trip through JSON gives the
    /// same table, and each row carries its example's numbers.
    #[test]
    fn table_agrees_with_json() {
        let r = report();
        let back: SuiteReport = serde_json::from_str(&serde_json::to_string(&r).unwrap()).unwrap();
        assert_eq!(back, r);
        let md = markdown(&back);
        assert_eq!(md, markdown(&r));
        assert!(md.contains("| jelly | 0.39 | 1M | ran | 1234 | 40 | 0.123 | 0.046 | 0.169 |"));
        assert!(md.contains("| kiwi | 1.58 | 1M | missing | no scenes/kiwi.json | | | |"));
        assert!(md.contains("| 19683 | 64³ | atomic | 17.25 | 876.4 | 527 |"));
    }

    /// Coarsening touches `dx` and `spacing` only; relative paths to existing files
    /// become absolute.
    #[test]
    fn scene_scaling() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("a.ply"), b"x").unwrap();
        let mut v: serde_json::Value = serde_json::from_str(
            r#"{"simulation": {"dx": 0.02, "cfl": 0.4}, "objects": [{"ply": "a.ply",
                "procedural": {"spacing": 0.01, "radius": 0.1}}, {"name": "b.ply"}]}"#,
        )
        .unwrap();
        prepare_scene(&mut v, 2.0, dir.path());
        assert_eq!(v["simulation"]["dx"], 0.04);
        assert_eq!(v["simulation"]["cfl"], 0.4);
        assert_eq!(v["objects"][0]["procedural"]["spacing"], 0.02);
        assert_eq!(v["objects"][0]["procedural"]["radius"], 0.1);
        let ply = v["objects"][0]["ply"].as_str().unwrap();
        assert!(Path::new(ply).is_absolute());
        assert_eq!(v["objects"][1]["name"], "b.ply");
    }
}
