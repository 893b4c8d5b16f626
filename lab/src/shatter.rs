//! The shatter study: `scenes/watermelon_drop_nacc.json` (the paper's watermelon dropped onto a
//! flat table) run at several grid spacings Δx and with both NACC return mappings, each
//! run measured by `--fragments` on its last frame (pieces, largest share, damaged share)
//! and over all frames (the fastest particle against the impact speed, the kinetic plus
//! gravitational energy against its start, non-finite particles). It answers whether the
//! pattern converges, from which Δx pieces appear, and what the continuous mapping changes
//! against the center mapping (docs/notes/watermelon-nacc.md).
//!
//! Fine spacings cost a CPU hours, so the study can also run one quarter of the fruit
//! between two symmetry planes ([`cut_to_quarter`]), and each invocation's runs are merged
//! into the ones already in `shatter.json` ([`merge`]): a long study can be run in parts.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

use splatter::run::{one_line, Event, Input, Run, RunOptions};
use splatter::sim::model::nacc::oracle::ReturnMapping;

/// Grid spacings of the full study (metres), coarse to fine, and of `--quick`.
pub const DX_FULL: [f64; 3] = [0.03, 0.02, 0.015];
pub const DX_QUICK: [f64; 2] = [0.04, 0.03];

/// The return mappings compared.
pub const MAPPINGS: [ReturnMapping; 2] = [ReturnMapping::Continuous, ReturnMapping::Center];

/// One run of the study.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ShatterRun {
    pub dx: f64,
    pub mapping: ReturnMapping,
    /// One quarter of the fruit between two symmetry planes ([`cut_to_quarter`]): the
    /// counts and shares are the quarter's.
    #[serde(default)]
    pub quarter: bool,
    pub particles: usize,
    pub frames: u32,
    /// Last frame: fragments with ≥ 1% of the particles, the largest one's share, the
    /// share with α ≥ 0 (cohesion gone), all fragments.
    pub pieces: usize,
    pub largest_share: f64,
    pub damaged_share: f64,
    pub fragments: usize,
    /// The largest particle speed of any frame after the first, over the drop speed (frame
    /// 0's; the fruit starts a few millimetres above the table, so it is the impact speed).
    pub speed_ratio: f64,
    /// The largest kinetic plus gravitational energy of any frame after the first, over
    /// frame 0's: above 1 the run made energy.
    pub energy_ratio: f64,
    /// The most particles with a non-finite state in any frame.
    pub nonfinite: usize,
    pub wall_s: f64,
}

/// The study as written to `OUT/data/shatter.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ShatterReport {
    pub scene: String,
    pub runs: Vec<ShatterRun>,
}

/// What one invocation of the study runs.
pub struct ShatterPlan<'a> {
    /// Grid spacings, coarse to fine.
    pub dxs: &'a [f64],
    /// Return mappings, a subset of [`MAPPINGS`].
    pub mappings: &'a [ReturnMapping],
    /// 6 frames instead of 24.
    pub quick: bool,
    /// One quarter of the fruit ([`cut_to_quarter`]).
    pub quarter: bool,
}

/// What the study reports while it runs.
pub enum ShatterEvent<'a> {
    /// Frame `frame` of `frames` of the run at `dx` with `mapping` is done.
    Frame {
        dx: f64,
        mapping: ReturnMapping,
        frame: u32,
        frames: u32,
    },
    /// A run is finished and measured.
    Done(&'a ShatterRun),
}

/// Runs the study on `scenes/watermelon_drop_nacc.json` under `scenes`.
/// Each whole-fruit run's last frame is kept as `stills/shatter_{mapping}_{dx}.png`, and
/// with both mappings, the two at the finest Δx side by side as
/// `stills/shatter_mappings.png`. Quarter runs keep no still: the rest of the fruit stays
/// in the picture, unsimulated, and would hide the quarter.
pub fn run_shatter(
    gpu: &splatter::gpu::GpuContext,
    (scenes, stills): (&Path, &Path),
    plan: &ShatterPlan,
    on_event: &mut dyn FnMut(ShatterEvent),
) -> Result<ShatterReport> {
    let scene = scenes.join("watermelon_drop_nacc.json");
    let text = std::fs::read_to_string(&scene)
        .with_context(|| format!("cannot read {}", scene.display()))?;
    let mut value: Value = serde_json::from_str(&text)?;
    if plan.dxs.is_empty() || plan.mappings.is_empty() {
        bail!("the shatter study needs at least one grid spacing and one return mapping");
    }
    if plan.quarter {
        cut_to_quarter(&mut value).with_context(|| format!("{}", scene.display()))?;
    }
    let frames = if plan.quick { 6 } else { 24 };
    let mut runs = Vec::new();
    for &dx in plan.dxs {
        for &mapping in plan.mappings {
            let still = (!plan.quarter).then(|| stills.join(format!("shatter_{mapping}_{dx}.png")));
            let mut run = run_one(
                gpu,
                (&scene, &value),
                (dx, mapping),
                frames,
                still.as_deref(),
                on_event,
            )?;
            run.quarter = plan.quarter;
            on_event(ShatterEvent::Done(&run));
            runs.push(run);
        }
    }
    if !plan.quarter && plan.mappings.len() == MAPPINGS.len() {
        let finest = plan.dxs[plan.dxs.len() - 1];
        let pair = MAPPINGS.map(|m| stills.join(format!("shatter_{m}_{finest}.png")));
        side_by_side(&pair, &stills.join("shatter_mappings.png"))?;
    }
    Ok(ShatterReport {
        scene: "scenes/watermelon_drop_nacc.json".into(),
        runs,
    })
}

/// Keeps only one quarter of the fruit in the simulation: the part with x and y at or
/// above its centre's (its `physics.select`), between two slip planes through its centre
/// with normals +x and +y (the table's frictionless `slip` colliders: the velocity across
/// a plane is removed both ways). The fruit is an ellipsoid with its axes along x, y and z
/// and it falls straight down, so these planes are planes of symmetry of the whole drop and
/// the quarter moves as its part of the whole fruit would, at a quarter of the particles.
/// Two things differ: the seeds' layout is only nearly symmetric, and no crack can open
/// along a plane (the quarter's piece count is of cracks elsewhere). The rest of the fruit
/// stays in the scene, static and unsimulated.
pub fn cut_to_quarter(v: &mut Value) -> Result<()> {
    let three = |x: &Value, what: &str| -> Result<[f64; 3]> {
        let a: Option<Vec<f64>> = x
            .as_array()
            .map(|a| a.iter().filter_map(Value::as_f64).collect());
        match a {
            Some(a) if a.len() == 3 => Ok([a[0], a[1], a[2]]),
            _ => bail!("{what}: expected three numbers"),
        }
    };
    let domain_lo = three(&v["simulation"]["domain"]["lo"], "simulation.domain.lo")?;
    let domain_hi = three(&v["simulation"]["domain"]["hi"], "simulation.domain.hi")?;
    let fruit = v["objects"]
        .as_array_mut()
        .and_then(|objects| objects.iter_mut().find(|o| o["name"] == "watermelon"))
        .context("no object named watermelon")?;
    let c = three(
        &fruit["transform"]["translate"],
        "watermelon's transform.translate",
    )?;
    fruit["physics"]["select"] = json!({
        "box": { "lo": [c[0], c[1], domain_lo[2]], "hi": domain_hi }
    });
    let planes = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
        .map(|normal| json!({ "point": c, "normal": normal, "kind": "slip", "friction": 0.0 }));
    match v["simulation"]["colliders"].as_array_mut() {
        Some(colliders) => colliders.extend(planes),
        None => v["simulation"]["colliders"] = Value::Array(planes.to_vec()),
    }
    Ok(())
}

/// The runs of `earlier` that `new` does not repeat (same Δx, mapping and fruit), with
/// `new`'s runs: the whole fruit first, then by Δx coarse to fine, `continuous` before
/// `center`.
pub fn merge(earlier: ShatterReport, new: ShatterReport) -> ShatterReport {
    let same = |a: &ShatterRun, b: &ShatterRun| {
        a.dx == b.dx && a.mapping == b.mapping && a.quarter == b.quarter
    };
    let mut runs: Vec<ShatterRun> = earlier
        .runs
        .into_iter()
        .filter(|old| !new.runs.iter().any(|n| same(old, n)))
        .collect();
    runs.extend(new.runs);
    let order = |m: &ReturnMapping| {
        MAPPINGS
            .iter()
            .position(|x| x == m)
            .unwrap_or(MAPPINGS.len())
    };
    runs.sort_by(|a, b| {
        a.quarter
            .cmp(&b.quarter)
            .then(b.dx.total_cmp(&a.dx))
            .then(order(&a.mapping).cmp(&order(&b.mapping)))
    });
    ShatterReport {
        scene: new.scene,
        runs,
    }
}

/// Two images of one size next to each other.
fn side_by_side(pair: &[PathBuf; 2], out: &Path) -> Result<()> {
    let [a, b] = pair.clone().map(|p| image::open(&p).map(|i| i.to_rgb8()));
    let (a, b) = (a?, b?);
    let mut joined = image::RgbImage::new(a.width() + b.width(), a.height().max(b.height()));
    image::imageops::replace(&mut joined, &a, 0, 0);
    image::imageops::replace(&mut joined, &b, i64::from(a.width()), 0);
    joined.save(out)?;
    Ok(())
}

fn run_one(
    gpu: &splatter::gpu::GpuContext,
    (scene, value): (&Path, &Value),
    (dx, mapping): (f64, ReturnMapping),
    frames: u32,
    still: Option<&Path>,
    on_event: &mut dyn FnMut(ShatterEvent),
) -> Result<ShatterRun> {
    let tmp = std::env::temp_dir().join(format!("splatter-shatter-{}", std::process::id()));
    std::fs::create_dir_all(&tmp)?;
    let mut v = value.clone();
    v["simulation"]["dx"] = dx.into();
    set_mapping(&mut v, mapping);
    let base = scene.parent().unwrap_or(Path::new("."));
    crate::suite::prepare_scene(&mut v, 1.0, base);
    let scene_file = tmp.join("scene.json");
    std::fs::write(&scene_file, serde_json::to_string(&v)?)?;
    let out: PathBuf = tmp.join("frames");
    let _ = std::fs::remove_dir_all(&out);
    let opts = RunOptions {
        input: Input::Scene(Some(scene_file)),
        out: Some(out.clone()),
        frames: Some(format!("0..{frames}")),
        width: Some(360),
        height: Some(240),
        checkpoint_every: 0,
        fragments: true,
        ..RunOptions::default()
    };
    let start = Instant::now();
    Run::prepare(opts)
        .and_then(|run| {
            run.execute(gpu, &mut |event| {
                if let Event::FrameDone { frame, .. } = event {
                    on_event(ShatterEvent::Frame {
                        dx,
                        mapping,
                        frame,
                        frames,
                    });
                }
            })
        })
        .map_err(|e| anyhow::anyhow!("watermelon_drop at dx {dx} ({mapping}): {}", one_line(&e)))?;
    let wall_s = start.elapsed().as_secs_f64();
    let rows = read_rows(&out.join("fragments.csv"))?;
    if let Some(still) = still {
        let last = out.join(format!("frame_{:05}.png", frames - 1));
        std::fs::copy(&last, still).with_context(|| format!("cannot keep {}", last.display()))?;
    }
    let _ = std::fs::remove_dir_all(&tmp);
    summarise(&rows, dx, mapping, frames, wall_s)
}

/// Every NACC material of the scene gets `mapping`.
fn set_mapping(v: &mut Value, mapping: ReturnMapping) {
    match v {
        Value::Object(map) => {
            if map.get("model").and_then(|m| m.as_str()) == Some("nacc") {
                map.insert("return_mapping".into(), mapping.name().into());
            }
            map.values_mut().for_each(|x| set_mapping(x, mapping));
        }
        Value::Array(items) => items.iter_mut().for_each(|x| set_mapping(x, mapping)),
        _ => {}
    }
}

/// The watermelon's rows of a `fragments.csv`, by column name.
struct Row {
    particles: usize,
    pieces: usize,
    largest_share: f64,
    fragments: usize,
    damaged_share: f64,
    speed_max: f64,
    energy: f64,
    nonfinite: usize,
}

fn read_rows(path: &Path) -> Result<Vec<Row>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines
        .next()
        .context("empty fragments.csv")?
        .split(',')
        .collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .with_context(|| format!("fragments.csv has no column {name}"))
    };
    let cols = [
        "object",
        "particles",
        "pieces",
        "largest_share",
        "fragments",
        "damaged_share",
        "speed_max",
        "energy",
        "nonfinite",
    ]
    .map(col);
    let mut at = [0usize; 9];
    for (a, c) in at.iter_mut().zip(cols) {
        *a = c?;
    }
    let mut rows = Vec::new();
    for line in lines {
        let f: Vec<&str> = line.split(',').collect();
        if f.get(at[0]) != Some(&"watermelon") {
            continue;
        }
        let num = |k: usize| -> Result<f64> {
            f.get(at[k])
                .and_then(|s| s.parse().ok())
                .with_context(|| format!("fragments.csv: bad row {line}"))
        };
        rows.push(Row {
            particles: num(1)? as usize,
            pieces: num(2)? as usize,
            largest_share: num(3)?,
            fragments: num(4)? as usize,
            damaged_share: num(5)?,
            speed_max: num(6)?,
            energy: num(7)?,
            nonfinite: num(8)? as usize,
        });
    }
    Ok(rows)
}

fn summarise(
    rows: &[Row],
    dx: f64,
    mapping: ReturnMapping,
    frames: u32,
    wall_s: f64,
) -> Result<ShatterRun> {
    let (Some(first), Some(last)) = (rows.first(), rows.last()) else {
        bail!("fragments.csv has no watermelon rows");
    };
    let later = &rows[1..];
    let speed_max = later.iter().map(|r| r.speed_max).fold(0.0, f64::max);
    let energy_max = later.iter().map(|r| r.energy).fold(f64::MIN, f64::max);
    Ok(ShatterRun {
        dx,
        mapping,
        quarter: false,
        particles: first.particles,
        frames,
        pieces: last.pieces,
        largest_share: last.largest_share,
        damaged_share: last.damaged_share,
        fragments: last.fragments,
        speed_ratio: speed_max / first.speed_max,
        energy_ratio: energy_max / first.energy,
        nonfinite: rows.iter().map(|r| r.nonfinite).max().unwrap_or(0),
        wall_s,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const CSV: &str = "frame,object,particles,pieces,largest_share,debris,fragments,damaged_share,height,gaussians,gaussian_largest_share,stretch,astray,speed_max,energy,nonfinite\n\
        0,watermelon,100,1,1.0000,0,1,0.0000,0.2,10,1.0,1.0,0,8.0,40.0,0\n\
        0,table,5,1,1.0000,0,1,0.0000,0.0,1,1.0,1.0,0,0.0,0.0,0\n\
        1,watermelon,100,3,0.4000,2,5,0.3000,0.1,10,0.4,1.2,0,9.0,44.0,1\n\
        2,watermelon,100,2,0.6000,1,3,0.2500,0.1,10,0.6,1.1,0,2.0,10.0,0\n";

    #[test]
    fn a_run_is_summarised_from_its_last_frame_and_its_worst_frames() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("fragments.csv");
        std::fs::write(&path, CSV).unwrap();
        let rows = read_rows(&path).unwrap();
        assert_eq!(rows.len(), 3, "the table's rows are left out");
        let run = summarise(&rows, 0.02, ReturnMapping::Center, 3, 1.0).unwrap();
        assert_eq!((run.particles, run.pieces, run.fragments), (100, 2, 3));
        assert_eq!((run.largest_share, run.damaged_share), (0.6, 0.25));
        assert_eq!(run.speed_ratio, 9.0 / 8.0);
        assert_eq!(run.energy_ratio, 44.0 / 40.0);
        assert_eq!(run.nonfinite, 1);
    }

    #[test]
    fn the_mapping_is_set_on_every_nacc_material_only() {
        let mut v: Value = json!({
            "objects": [{ "physics": {
                "material": { "model": "nacc", "return_mapping": "continuous" },
                "regions": [{ "material": { "model": "nacc" } },
                            { "material": { "model": "neo_hookean" } }]
            }}]
        });
        set_mapping(&mut v, ReturnMapping::Center);
        let m = &v["objects"][0]["physics"];
        assert_eq!(m["material"]["return_mapping"], "center");
        assert_eq!(m["regions"][0]["material"]["return_mapping"], "center");
        assert!(m["regions"][1]["material"].get("return_mapping").is_none());
    }

    /// The quarter is selected and walled at the fruit's centre, by slip planes facing
    /// into it, and the table's collider stays.
    #[test]
    fn a_quarter_is_the_fruit_above_its_centre_between_two_slip_planes() {
        let mut v = json!({
            "simulation": {
                "domain": { "lo": [0, 0, -0.1], "hi": [0.6, 0.6, 0.45] },
                "colliders": [{ "point": [0.3, 0.3, 0.06], "normal": [0, 0, 1], "kind": "separate" }]
            },
            "objects": [
                { "name": "table" },
                { "name": "watermelon", "transform": { "translate": [0.3, 0.25, 0.166] },
                  "physics": { "fill": true } }
            ]
        });
        cut_to_quarter(&mut v).unwrap();
        let fruit = &v["objects"][1]["physics"];
        assert_eq!(fruit["select"]["box"]["lo"], json!([0.3, 0.25, -0.1]));
        assert_eq!(fruit["select"]["box"]["hi"], json!([0.6, 0.6, 0.45]));
        assert_eq!(fruit["fill"], true);
        let colliders = v["simulation"]["colliders"].as_array().unwrap();
        assert_eq!(colliders.len(), 3);
        for (c, normal) in colliders[1..]
            .iter()
            .zip([json!([1.0, 0.0, 0.0]), json!([0.0, 1.0, 0.0])])
        {
            assert_eq!(c["point"], json!([0.3, 0.25, 0.166]));
            assert_eq!(c["normal"], normal);
            assert_eq!(
                (c["kind"].as_str(), c["friction"].as_f64()),
                (Some("slip"), Some(0.0))
            );
        }
        let mut no_fruit = json!({ "simulation": { "domain": { "lo": [0, 0, 0], "hi": [1, 1, 1] } },
                                   "objects": [{ "name": "table" }] });
        let e = cut_to_quarter(&mut no_fruit).unwrap_err().to_string();
        assert!(e.contains("watermelon"), "{e}");
    }

    /// A new run replaces the earlier one of the same Δx, mapping and fruit; the others
    /// stay, whole fruit first, coarse to fine, continuous before center.
    #[test]
    fn new_runs_replace_their_earlier_twins_and_keep_the_rest() {
        let run = |dx: f64, mapping: &str, quarter: bool, wall_s: f64| ShatterRun {
            dx,
            mapping: ReturnMapping::from_name(mapping).unwrap(),
            quarter,
            particles: 1,
            frames: 24,
            pieces: 1,
            largest_share: 1.0,
            damaged_share: 0.1,
            fragments: 1,
            speed_ratio: 0.3,
            energy_ratio: 0.1,
            nonfinite: 0,
            wall_s,
        };
        let report = |runs| ShatterReport {
            scene: "s".into(),
            runs,
        };
        let earlier = report(vec![
            run(0.02, "continuous", false, 1.0),
            run(0.02, "center", false, 1.0),
            run(0.01, "continuous", false, 1.0),
            run(0.01, "continuous", true, 1.0),
        ]);
        let new = report(vec![
            run(0.005, "continuous", true, 2.0),
            run(0.01, "continuous", true, 2.0),
            run(0.02, "center", false, 2.0),
        ]);
        let merged = merge(earlier, new);
        let got: Vec<(f64, &str, bool, f64)> = merged
            .runs
            .iter()
            .map(|r| (r.dx, r.mapping.name(), r.quarter, r.wall_s))
            .collect();
        assert_eq!(
            got,
            [
                (0.02, "continuous", false, 1.0),
                (0.02, "center", false, 2.0),
                (0.01, "continuous", false, 1.0),
                (0.01, "continuous", true, 2.0),
                (0.005, "continuous", true, 2.0),
            ]
        );
    }
}
