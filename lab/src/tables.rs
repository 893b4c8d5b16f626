//! Markdown tables and PNG charts of the convergence study and the stability atlas, made
//! from the reports as read back from their JSON files.

use std::path::Path;

use anyhow::Result;
use plotters::prelude::SeriesLabelPosition;
use plotters::style::RGBColor;

use crate::atlas::{AtlasReport, Class};
use crate::chart::{cell_map, lines, loglog, Cell, Series};
use crate::convergence::{ConvRun, ConvergenceReport};
use crate::fit::pareto_front;
use crate::shatter::{ShatterReport, ShatterRun};

fn opt(v: Option<f64>) -> String {
    v.map_or("–".into(), |x| format!("{x:.4e}"))
}

/// One row per run, then the fitted orders.
pub fn convergence_markdown(r: &ConvergenceReport) -> String {
    let mut s = String::from(
        "| case | sweep | Δx | Δt | CFL | ppc | particles | steps | measured | known | error | s/frame | outcome |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n",
    );
    for run in &r.runs {
        s += &format!(
            "| {} | {} | {:.4} | {:.3e} | {} | {} | {} | {} | {} | {} | {} | {:.3} | {:?} |\n",
            run.case,
            run.sweep,
            run.dx,
            run.dt,
            run.cfl,
            run.ppc,
            run.particles,
            run.steps,
            opt(run.measured),
            opt(run.exact),
            run.error.map_or("–".into(), |e| format!("{e:.3e}")),
            run.s_per_frame,
            run.outcome
        );
    }
    s += "\n| case | order (log-log fit of error against Δx) | points |\n|---|---:|---:|\n";
    for o in &r.orders {
        s += &format!("| {} | {:.2} | {} |\n", o.case, o.order, o.points);
    }
    s
}

fn cases(runs: &[ConvRun]) -> Vec<String> {
    let mut c: Vec<String> = runs.iter().map(|r| r.case.clone()).collect();
    c.dedup();
    c
}

/// convergence_dx.png (error against Δx with the fitted power laws) and
/// convergence_pareto.png (error against cost, Pareto front per case).
pub fn convergence_charts(r: &ConvergenceReport, dir: &Path) -> Result<()> {
    let mut dx_series = Vec::new();
    let mut cost_series = Vec::new();
    for (i, case) in cases(&r.runs).iter().enumerate() {
        let ok: Vec<&ConvRun> = r
            .runs
            .iter()
            .filter(|x| &x.case == case && x.error.is_some())
            .collect();
        let dx_pts: Vec<(f64, f64)> = ok
            .iter()
            .filter(|x| x.sweep == "dx")
            .map(|x| (x.dx, x.error.unwrap_or(0.0)))
            .collect();
        let fit = r.orders.iter().find(|o| &o.case == case);
        let label = match fit {
            Some(o) => format!("{case}: order {:.2}", o.order),
            None => case.clone(),
        };
        dx_series.push(Series {
            label,
            points: dx_pts.clone(),
            line: false,
            markers: true,
            color: i,
        });
        if let Some(o) = fit {
            let fitted = dx_pts
                .iter()
                .map(|(h, _)| (*h, o.constant * h.powf(o.order)))
                .collect();
            dx_series.push(Series {
                label: format!("{case}: fit C·Δx^{:.2}", o.order),
                points: fitted,
                line: true,
                markers: false,
                color: i,
            });
        }
        let cost: Vec<f64> = ok.iter().map(|x| x.s_per_frame).collect();
        let err: Vec<f64> = ok.iter().map(|x| x.error.unwrap_or(0.0)).collect();
        cost_series.push(Series {
            label: format!("{case} (all sweeps)"),
            points: cost.iter().copied().zip(err.iter().copied()).collect(),
            line: false,
            markers: true,
            color: i,
        });
        cost_series.push(Series {
            label: format!("{case}: Pareto front"),
            points: pareto_front(&cost, &err)
                .into_iter()
                .map(|k| (cost[k], err[k]))
                .collect(),
            line: true,
            markers: false,
            color: i,
        });
    }
    loglog(
        &dir.join("convergence_dx.png"),
        (
            "Error against grid spacing (CPU reference step, f64)",
            "Δx (m)",
            "relative error",
        ),
        &dx_series,
        SeriesLabelPosition::LowerRight,
    )?;
    loglog(
        &dir.join("convergence_pareto.png"),
        (
            "Error against cost (2-core CPU, s per 1/50 s frame)",
            "wall seconds per simulated frame",
            "relative error",
        ),
        &cost_series,
        SeriesLabelPosition::UpperRight,
    )
}

/// Rows: sweep and value; columns: the mappings; cells: class, energy ratio, speed
/// ratio, near-tip q/b. Then the tip probe.
pub fn atlas_markdown(r: &AtlasReport) -> String {
    let (rows, cols) = atlas_axes(r);
    let mut s = format!(
        "| sweep | {} |\n|---|{}\n",
        cols.join(" | "),
        "---|".repeat(cols.len())
    );
    for (sweep, value) in &rows {
        s += &format!("| {sweep} = {value} |");
        for c in &cols {
            match find(r, sweep, *value, c) {
                Some(x) => {
                    s += &format!(
                        " {}: E {:.3}, v {:.2}; tip {}, q/b {:.2}, top {:.1}%, v {:.2} |",
                        x.class.name(),
                        x.energy_ratio,
                        x.speed_ratio,
                        x.near_tip_returns,
                        x.near_tip_q_over_b,
                        100.0 * x.near_tip_towards_top,
                        x.near_tip_speed_ratio
                    )
                }
                None => s += " |",
            }
        }
        s.push('\n');
    }
    s += "\n| mapping | q_tr/b | (p/p0, q/b) at p_tr = p0(1 − ε) | at p0(1 + ε) | jump |\n|---|---:|---|---|---:|\n";
    for p in &r.probes {
        s += &format!(
            "| {} | {} | ({:.3}, {:.3}) | ({:.3}, {:.3}) | {:.3} |\n",
            p.variant, p.q_trial_over_b, p.inside.0, p.inside.1, p.outside.0, p.outside.1, p.jump
        );
    }
    s
}

fn atlas_axes(r: &AtlasReport) -> (Vec<(String, f64)>, Vec<String>) {
    let mut rows: Vec<(String, f64)> = Vec::new();
    let mut cols: Vec<String> = Vec::new();
    for x in &r.runs {
        if !rows.iter().any(|(s, v)| *s == x.sweep && *v == x.value) {
            rows.push((x.sweep.clone(), x.value));
        }
        if !cols.contains(&x.variant) {
            cols.push(x.variant.clone());
        }
    }
    (rows, cols)
}

fn find<'a>(
    r: &'a AtlasReport,
    sweep: &str,
    value: f64,
    variant: &str,
) -> Option<&'a crate::atlas::AtlasRun> {
    r.runs
        .iter()
        .find(|x| x.sweep == sweep && x.value == value && x.variant == variant)
}

const CLASSES: [Class; 5] = [
    Class::Stable,
    Class::TipArtifact,
    Class::Artifact,
    Class::EnergyBlowUp,
    Class::Nan,
];

fn class_index(c: Class) -> usize {
    CLASSES.iter().position(|k| *k == c).unwrap_or(0)
}

/// atlas.png: the map of classes, each cell annotated with energy ratio / speed ratio /
/// near-tip q/b.
pub fn atlas_chart(r: &AtlasReport, path: &Path) -> Result<()> {
    let (rows, cols) = atlas_axes(r);
    let cells: Vec<Vec<Cell>> = rows
        .iter()
        .map(|(sweep, value)| {
            cols.iter()
                .map(|c| match find(r, sweep, *value, c) {
                    Some(x) => Cell {
                        class: class_index(x.class),
                        text: format!(
                            "{:.2} {:.2} {:.0}%",
                            x.energy_ratio,
                            x.speed_ratio,
                            100.0 * x.near_tip_towards_top
                        ),
                    },
                    None => Cell {
                        class: 0,
                        text: String::new(),
                    },
                })
                .collect()
        })
        .collect();
    let row_labels: Vec<String> = rows
        .iter()
        .map(|(s, v)| match s.as_str() {
            "cfl" => format!("Δt = {v} Δx/c"),
            "E" => format!("E = {v} Pa"),
            "nu" => format!("ν = {v}"),
            "alpha0" => format!("α₀ = {v}"),
            _ => format!("impact {v} m/s"),
        })
        .collect();
    let classes: Vec<(&str, RGBColor)> = CLASSES
        .iter()
        .zip([
            RGBColor(190, 230, 190),
            RGBColor(250, 240, 150),
            RGBColor(250, 200, 120),
            RGBColor(240, 150, 120),
            RGBColor(200, 200, 200),
        ])
        .map(|(c, col)| (c.name(), col))
        .collect();
    cell_map(
        path,
        "Stability atlas, NACC sphere impact. Cell: max E/E0, max |v|/v_ref, % of near-tip returns sent to the top",
        &row_labels,
        &cols,
        &cells,
        &classes,
    )
}

/// One row per run of the shatter study, finest Δx last.
pub fn shatter_markdown(r: &ShatterReport) -> String {
    let mut s = format!(
        "`{}`, last frame of each run (`--fragments`: pieces hold ≥ 1% of the particles; \
         fruit `quarter`: one quarter between two symmetry planes, its own counts and shares).\n\n\
         | Δx (m) | mapping | fruit | particles | pieces | largest | damaged | fragments | max speed / drop speed | max energy / start | non-finite | wall s |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|\n",
        r.scene
    );
    for x in &r.runs {
        s += &format!(
            "| {} | {} | {} | {} | {} | {:.1}% | {:.1}% | {} | {:.2} | {:.3} | {} | {:.0} |\n",
            x.dx,
            x.mapping,
            if x.quarter { "quarter" } else { "whole" },
            x.particles,
            x.pieces,
            100.0 * x.largest_share,
            100.0 * x.damaged_share,
            x.fragments,
            x.speed_ratio,
            x.energy_ratio,
            x.nonfinite,
            x.wall_s
        );
    }
    s
}

/// What the shatter chart plots of a run.
type Measure = fn(&ShatterRun) -> f64;

/// Pieces, largest share and damaged share against Δx, one colour per mapping and measure:
/// the whole fruit's runs joined by lines, a quarter's as markers of the same colour.
pub fn shatter_chart(r: &ShatterReport, path: &Path) -> Result<()> {
    let measures: [(&str, Measure); 3] = [
        ("pieces", |x| x.pieces as f64),
        ("largest share", |x| x.largest_share),
        ("damaged share", |x| x.damaged_share),
    ];
    let mut series = Vec::new();
    for quarter in [false, true] {
        for (m, mapping) in crate::shatter::MAPPINGS.iter().enumerate() {
            let runs: Vec<&ShatterRun> = r
                .runs
                .iter()
                .filter(|x| x.mapping == *mapping && x.quarter == quarter)
                .collect();
            if runs.is_empty() {
                continue;
            }
            for (k, (name, f)) in measures.iter().enumerate() {
                series.push(Series {
                    label: format!(
                        "{name} ({mapping}{})",
                        if quarter { ", quarter" } else { "" }
                    ),
                    points: runs.iter().map(|x| (x.dx, f(x))).collect(),
                    line: !quarter,
                    markers: true,
                    color: 3 * m + k,
                });
            }
        }
    }
    lines(
        path,
        (
            "Watermelon dropped on a table: last frame against grid spacing",
            "Δx (m)",
            "pieces / share",
        ),
        &series,
        SeriesLabelPosition::UpperLeft,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atlas::{AtlasRun, TipProbe};
    use crate::runner::Outcome;

    /// The atlas table shows each run's class and numbers as stored in the JSON.
    #[test]
    fn atlas_table_agrees_with_json() {
        let run = AtlasRun {
            sweep: "E".into(),
            value: 2000.0,
            variant: "center".into(),
            e: 2000.0,
            nu: 0.4,
            speed: 8.0,
            cfl: 0.4,
            dt: 1e-4,
            steps: 300,
            outcome: Outcome::Finished,
            energy_ratio: 1.0123,
            speed_ratio: 1.234,
            near_tip_returns: 42,
            upper_tip_returns: 7,
            near_tip_q_over_b: 0.876,
            near_tip_towards_top: 0.25,
            near_tip_speed_ratio: 1.1,
            tip_speed_outliers: 0,
            alpha0: -0.04,
            class: Class::Stable,
            wall_s: 1.0,
        };
        let report = AtlasReport {
            runs: vec![run],
            probes: vec![TipProbe {
                variant: "center".into(),
                q_trial_over_b: 3.0,
                inside: (0.0, 0.99),
                outside: (1.0, 0.0),
                jump: 1.41,
                epsilon: 1e-3,
            }],
        };
        let back: AtlasReport =
            serde_json::from_str(&serde_json::to_string(&report).unwrap()).unwrap();
        let md = atlas_markdown(&back);
        assert!(
            md.contains(
                "| E = 2000 | stable: E 1.012, v 1.23; tip 42, q/b 0.88, top 25.0%, v 1.10 |"
            ),
            "{md}"
        );
        assert!(md.contains("| center | 3 | (0.000, 0.990) | (1.000, 0.000) | 1.410 |"));
    }
}
