//! The lab: what the project measures about itself, kept out of the product. The
//! paper-examples suite ([`suite`]), the accuracy studies — the convergence study
//! ([`convergence`]), the stability atlas ([`atlas`]), the shatter study ([`shatter`]) —
//! and the peers' drivers ([`peer`]), run by the `splatter-lab` binary. Studies write JSON
//! (`OUT/data/`), markdown tables next to it and PNG charts (`OUT/images/`); the charts and
//! tables are drawn from the JSON as written and read back, so their numbers are the
//! JSON's.

pub mod atlas;
pub mod chart;
pub mod convergence;
pub mod driven;
pub mod fit;
pub mod peer;
pub mod plastic_bar;
pub mod runner;
pub mod shatter;
pub mod snow_press;
pub mod suite;
pub mod table_a1;
pub mod tables;

use std::io::Write;
use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use serde::{de::DeserializeOwned, Serialize};

/// What `splatter-lab accuracy` runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    All,
    Convergence,
    Atlas,
    Shatter,
}

impl Part {
    fn runs(self, part: Part) -> bool {
        self == Part::All || self == part
    }
}

/// What `splatter-lab accuracy` is given: the part, the sizes, and for the shatter study the
/// adapter and the directory of the shipped scenes.
pub struct AccuracyOptions<'a> {
    pub part: Part,
    pub quick: bool,
    pub redraw: bool,
    pub gpu: Option<&'a splatter::gpu::GpuContext>,
    pub scenes: &'a Path,
    /// The shatter study's grid spacings, if not its defaults.
    pub shatter_dx: Option<&'a [f64]>,
    /// The shatter study's return mappings, if not both.
    pub shatter_mappings: Option<&'a [splatter::sim::model::nacc::oracle::ReturnMapping]>,
    /// The shatter study simulates one quarter of the fruit (`shatter::cut_to_quarter`).
    pub shatter_quarter: bool,
}

/// Runs the study parts and writes OUT/data/{convergence,atlas,shatter}.{json,md},
/// OUT/data/table_a1.md and OUT/images/{convergence_dx,convergence_pareto,atlas,shatter}.png.
/// With `redraw`, nothing is simulated: the tables and charts are made again from the JSON
/// files already there.
pub fn run_accuracy(opts: &AccuracyOptions, out: &Path, log: &mut dyn Write) -> Result<()> {
    let (part, quick) = (opts.part, opts.quick);
    let data = out.join("data");
    let images = out.join("images");
    std::fs::create_dir_all(&data)?;
    std::fs::create_dir_all(&images)?;
    std::fs::write(
        data.join("table_a1.md"),
        table_a1::markdown(&table_a1::cfl_rows()),
    )?;
    if opts.redraw {
        return redraw_from_json(part, out);
    }
    let started = Instant::now();
    if part.runs(Part::Convergence) {
        let report = convergence::run_convergence(convergence::ConvOptions { quick }, &mut |r| {
            let _ = writeln!(
                log,
                "{} {} dx {:.4} dt {:.2e} ppc {}: error {:?}, {:.1} s ({:?})",
                r.case, r.sweep, r.dx, r.dt, r.ppc, r.error, r.wall_s, r.outcome
            );
        });
        let report: convergence::ConvergenceReport =
            round_trip(&report, &data.join("convergence.json"))?;
        std::fs::write(
            data.join("convergence.md"),
            tables::convergence_markdown(&report),
        )?;
        tables::convergence_charts(&report, &images)?;
        for o in &report.orders {
            writeln!(
                log,
                "order {}: {:.2} ({} points)",
                o.case, o.order, o.points
            )?;
        }
    }
    if part.runs(Part::Atlas) {
        let report = atlas::run_atlas(quick, &mut |r| {
            let _ = writeln!(
                log,
                "atlas {} {} {}: {} (E ratio {:.3}, speed ratio {:.2}, near tip {}, q/b {:.2}) {:.1} s",
                r.sweep,
                r.value,
                r.variant,
                r.class.name(),
                r.energy_ratio,
                r.speed_ratio,
                r.near_tip_returns,
                r.near_tip_q_over_b,
                r.wall_s
            );
        });
        let report: atlas::AtlasReport = round_trip(&report, &data.join("atlas.json"))?;
        std::fs::write(data.join("atlas.md"), tables::atlas_markdown(&report))?;
        tables::atlas_chart(&report, &images.join("atlas.png"))?;
    }
    if part.runs(Part::Shatter) {
        let gpu = opts
            .gpu
            .ok_or_else(|| anyhow::anyhow!("the shatter study needs an adapter"))?;
        let dxs = opts.shatter_dx.unwrap_or(if quick {
            &shatter::DX_QUICK
        } else {
            &shatter::DX_FULL
        });
        let plan = shatter::ShatterPlan {
            dxs,
            mappings: opts.shatter_mappings.unwrap_or(&shatter::MAPPINGS),
            quick,
            quarter: opts.shatter_quarter,
        };
        let fruit = if plan.quarter { " quarter" } else { "" };
        let report = shatter::run_shatter(gpu, (opts.scenes, &images), &plan, &mut |event| {
            let _ = match event {
                shatter::ShatterEvent::Frame {
                    dx,
                    mapping,
                    frame,
                    frames,
                } => writeln!(
                    log,
                    "shatter dx {dx} {mapping}{fruit}: frame {}/{frames} ({:.0} s)",
                    frame + 1,
                    started.elapsed().as_secs_f64()
                ),
                shatter::ShatterEvent::Done(r) => writeln!(
                    log,
                    "shatter dx {} {}{fruit}: {} pieces, largest {:.1}%, damaged {:.1}%, speed ratio {:.2}, energy ratio {:.3}, non-finite {}, {:.0} s",
                    r.dx,
                    r.mapping,
                    r.pieces,
                    100.0 * r.largest_share,
                    100.0 * r.damaged_share,
                    r.speed_ratio,
                    r.energy_ratio,
                    r.nonfinite,
                    r.wall_s
                ),
            };
        })?;
        // Runs made earlier into the same file stay unless this invocation repeated them.
        let earlier = std::fs::read_to_string(data.join("shatter.json"))
            .ok()
            .and_then(|text| serde_json::from_str::<shatter::ShatterReport>(&text).ok());
        let report = match earlier {
            Some(earlier) => {
                let merged = shatter::merge(earlier, report);
                writeln!(
                    log,
                    "shatter: {} runs in {} (with the earlier ones it did not repeat)",
                    merged.runs.len(),
                    data.join("shatter.json").display()
                )?;
                merged
            }
            None => report,
        };
        let report: shatter::ShatterReport = round_trip(&report, &data.join("shatter.json"))?;
        std::fs::write(data.join("shatter.md"), tables::shatter_markdown(&report))?;
        tables::shatter_chart(&report, &images.join("shatter.png"))?;
    }
    writeln!(
        log,
        "wrote {} and {} in {:.0} s",
        data.display(),
        images.display(),
        started.elapsed().as_secs_f64()
    )?;
    Ok(())
}

fn redraw_from_json(part: Part, out: &Path) -> Result<()> {
    let (data, images) = (out.join("data"), out.join("images"));
    std::fs::create_dir_all(&images)?;
    if part.runs(Part::Convergence) {
        let text = std::fs::read_to_string(data.join("convergence.json"))?;
        let report: convergence::ConvergenceReport = serde_json::from_str(&text)?;
        std::fs::write(
            data.join("convergence.md"),
            tables::convergence_markdown(&report),
        )?;
        tables::convergence_charts(&report, &images)?;
    }
    if part.runs(Part::Atlas) {
        let text = std::fs::read_to_string(data.join("atlas.json"))?;
        let report: atlas::AtlasReport = serde_json::from_str(&text)?;
        std::fs::write(data.join("atlas.md"), tables::atlas_markdown(&report))?;
        tables::atlas_chart(&report, &images.join("atlas.png"))?;
    }
    if part.runs(Part::Shatter) {
        let text = std::fs::read_to_string(data.join("shatter.json"))?;
        let report: shatter::ShatterReport = serde_json::from_str(&text)?;
        std::fs::write(data.join("shatter.md"), tables::shatter_markdown(&report))?;
        tables::shatter_chart(&report, &images.join("shatter.png"))?;
    }
    Ok(())
}

/// Writes `value` as pretty JSON and returns what reading the file back gives: the
/// tables and charts are made from that, so they show the file's numbers.
fn round_trip<T: Serialize + DeserializeOwned>(value: &T, path: &Path) -> Result<T> {
    std::fs::write(path, serde_json::to_string_pretty(value)? + "\n")?;
    Ok(serde_json::from_str(&std::fs::read_to_string(path)?)?)
}
