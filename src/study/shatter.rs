//! The shatter study: `scenes/watermelon_drop.json` (the paper's watermelon dropped onto a
//! flat table) run at several grid spacings Δx and with both NACC return mappings, each
//! run measured by `--fragments` on its last frame (pieces, largest share, damaged share)
//! and over all frames (the fastest particle against the impact speed, the kinetic plus
//! gravitational energy against its start, non-finite particles). It answers whether the
//! pattern converges, from which Δx pieces appear, and what the continuous mapping changes
//! against the center mapping (docs/accuracy.md).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};

use crate::run::{one_line, Input, Run, RunOptions};

/// Grid spacings of the full study (metres), coarse to fine, and of `--quick`.
pub const DX_FULL: [f64; 3] = [0.03, 0.02, 0.015];
pub const DX_QUICK: [f64; 2] = [0.04, 0.03];

/// The return mappings compared.
pub const MAPPINGS: [&str; 2] = ["continuous", "center"];

/// One run of the study.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ShatterRun {
    pub dx: f64,
    pub mapping: String,
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

/// Runs the study on `scenes/watermelon_drop.json` under `scenes`.
/// Each run's last frame is kept as `stills/shatter_{mapping}_{dx}.png`, and the two
/// mappings at the finest Δx side by side as `stills/shatter_mappings.png`.
pub fn run_shatter(
    gpu: &crate::gpu::GpuContext,
    (scenes, stills): (&Path, &Path),
    dxs: &[f64],
    quick: bool,
    on_run: &mut dyn FnMut(&ShatterRun),
) -> Result<ShatterReport> {
    let scene = scenes.join("watermelon_drop.json");
    let text = std::fs::read_to_string(&scene)
        .with_context(|| format!("cannot read {}", scene.display()))?;
    let value: serde_json::Value = serde_json::from_str(&text)?;
    if dxs.is_empty() {
        bail!("the shatter study needs at least one grid spacing");
    }
    let frames = if quick { 6 } else { 24 };
    let mut runs = Vec::new();
    for &dx in dxs {
        for mapping in MAPPINGS {
            let still = stills.join(format!("shatter_{mapping}_{dx}.png"));
            let run = run_one(gpu, (&scene, &value), dx, mapping, frames, &still)?;
            on_run(&run);
            runs.push(run);
        }
    }
    let finest = dxs[dxs.len() - 1];
    let pair = MAPPINGS.map(|m| stills.join(format!("shatter_{m}_{finest}.png")));
    side_by_side(&pair, &stills.join("shatter_mappings.png"))?;
    Ok(ShatterReport {
        scene: "scenes/watermelon_drop.json".into(),
        runs,
    })
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
    gpu: &crate::gpu::GpuContext,
    (scene, value): (&Path, &serde_json::Value),
    dx: f64,
    mapping: &str,
    frames: u32,
    still: &Path,
) -> Result<ShatterRun> {
    let tmp = std::env::temp_dir().join(format!("splatter-shatter-{}", std::process::id()));
    std::fs::create_dir_all(&tmp)?;
    let mut v = value.clone();
    v["simulation"]["dx"] = dx.into();
    set_mapping(&mut v, mapping);
    let base = scene.parent().unwrap_or(Path::new("."));
    super::suite::prepare_scene(&mut v, 1.0, base);
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
        .and_then(|run| run.execute(gpu, &mut |_| {}))
        .map_err(|e| anyhow::anyhow!("watermelon_drop at dx {dx} ({mapping}): {}", one_line(&e)))?;
    let wall_s = start.elapsed().as_secs_f64();
    let rows = read_rows(&out.join("fragments.csv"))?;
    let last = out.join(format!("frame_{:05}.png", frames - 1));
    std::fs::copy(&last, still).with_context(|| format!("cannot keep {}", last.display()))?;
    let _ = std::fs::remove_dir_all(&tmp);
    summarise(&rows, dx, mapping, frames, wall_s)
}

/// Every NACC material of the scene gets `mapping`.
fn set_mapping(v: &mut serde_json::Value, mapping: &str) {
    match v {
        serde_json::Value::Object(map) => {
            if map.get("model").and_then(|m| m.as_str()) == Some("nacc") {
                map.insert("return_mapping".into(), mapping.into());
            }
            map.values_mut().for_each(|x| set_mapping(x, mapping));
        }
        serde_json::Value::Array(items) => items.iter_mut().for_each(|x| set_mapping(x, mapping)),
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

fn summarise(rows: &[Row], dx: f64, mapping: &str, frames: u32, wall_s: f64) -> Result<ShatterRun> {
    let (Some(first), Some(last)) = (rows.first(), rows.last()) else {
        bail!("fragments.csv has no watermelon rows");
    };
    let later = &rows[1..];
    let speed_max = later.iter().map(|r| r.speed_max).fold(0.0, f64::max);
    let energy_max = later.iter().map(|r| r.energy).fold(f64::MIN, f64::max);
    Ok(ShatterRun {
        dx,
        mapping: mapping.into(),
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
        let run = summarise(&rows, 0.02, "center", 3, 1.0).unwrap();
        assert_eq!((run.particles, run.pieces, run.fragments), (100, 2, 3));
        assert_eq!((run.largest_share, run.damaged_share), (0.6, 0.25));
        assert_eq!(run.speed_ratio, 9.0 / 8.0);
        assert_eq!(run.energy_ratio, 44.0 / 40.0);
        assert_eq!(run.nonfinite, 1);
    }

    #[test]
    fn the_mapping_is_set_on_every_nacc_material_only() {
        let mut v: serde_json::Value = serde_json::json!({
            "objects": [{ "physics": {
                "material": { "model": "nacc", "return_mapping": "continuous" },
                "regions": [{ "material": { "model": "nacc" } },
                            { "material": { "model": "neo_hookean" } }]
            }}]
        });
        set_mapping(&mut v, "center");
        let m = &v["objects"][0]["physics"];
        assert_eq!(m["material"]["return_mapping"], "center");
        assert_eq!(m["regions"][0]["material"]["return_mapping"], "center");
        assert!(m["regions"][1]["material"].get("return_mapping").is_none());
    }
}
