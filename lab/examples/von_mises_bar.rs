//! A von Mises bar pulled past yield and released, and one pulled to half its yield strain,
//! on the CPU reference step (`splatter_lab::plastic_bar`, docs/notes/metal.md *Metal and
//! plasticine*).
//!
//! `cargo run --release --example von_mises_bar [-- DX [HARDENING_PA]]`
//!
//! Prints, per run, the loading curve (every few samples: phase, gauge strain, mean axial
//! Kirchhoff stress, force, mean α), then the yield point of a bilinear fit against
//! σ_y, σ_y A₀ e^{−σ_y/E} and the slopes against E and E H/(E + H), and the permanent set
//! at zero load and after release against the analytic ε_peak − τ_peak/E.

use anyhow::{Context, Result};
use splatter_lab::plastic_bar::{run, BarResult, BarSpec, Phase};

fn report(name: &str, spec: &BarSpec, r: &BarResult, wall: f64) {
    println!(
        "\n== {name}: {} particles, dx {}, dt {:.3e}, {} steps, {wall:.1} s, healthy {}",
        r.particles, spec.dx, r.dt, r.steps, r.healthy
    );
    println!("phase    | strain    | tau (Pa)  | force (N) | alpha");
    let every = (r.samples.len() / 40).max(1);
    for (i, s) in r.samples.iter().enumerate() {
        let last = i + 1 == r.samples.len();
        let turn = i > 0 && r.samples[i - 1].phase != s.phase;
        if i % every == 0 || last || turn {
            println!(
                "{:8} | {:9.5} | {:9.1} | {:9.4} | {:.5}",
                format!("{:?}", s.phase),
                s.strain,
                s.tau,
                s.force,
                s.alpha
            );
        }
    }
    let (sy, e, a0) = (spec.law.yield_stress, spec.e, spec.area());
    if let Some(f) = r.fit {
        let fy = f.yield_stress * a0 * (-f.yield_strain).exp();
        let fy_exact = sy * a0 * (-sy / e).exp();
        println!(
            "yield stress {:.1} Pa vs sigma_y {sy:.1} ({:+.2}%); yield strain {:.5} vs {:.5}",
            f.yield_stress,
            100.0 * (f.yield_stress / sy - 1.0),
            f.yield_strain,
            sy / e
        );
        println!(
            "yield load {fy:.4} N vs sigma_y A0 exp(-sigma_y/E) {fy_exact:.4} N ({:+.2}%), sigma_y A0 {:.4} N",
            100.0 * (fy / fy_exact - 1.0),
            sy * a0
        );
        println!(
            "elastic slope {:.4e} vs E {e:.4e} ({:+.2}%); hardening slope {:.4e} vs EH/(E+H) {:.4e}",
            f.elastic_slope,
            100.0 * (f.elastic_slope / e - 1.0),
            f.hardening_slope,
            spec.hardening_slope()
        );
    }
    let (ep, tp) = r.peak;
    // The elastic part τ/E springs back; with no gauge particle yielded, all of it.
    let expected = if r.max_alpha > 0.0 { ep - tp / e } else { 0.0 };
    println!(
        "peak strain {ep:.5} at tau {tp:.1} Pa; permanent set: analytic {expected:.3e}, at zero load {}, after release {}; max gauge alpha {:.5}",
        r.set_at_zero_load.map_or("-".into(), |x| format!("{x:.3e}")),
        r.set_after_release.map_or("-".into(), |x| format!("{x:.3e}")),
        r.max_alpha
    );
    let unload: Vec<_> = r
        .samples
        .iter()
        .filter(|s| s.phase == Phase::Unload)
        .collect();
    if let (Some(a), Some(b)) = (unload.first(), unload.last()) {
        println!(
            "unloading slope {:.4e} (vs E {e:.4e})",
            (b.tau - a.tau) / (b.strain - a.strain)
        );
    }
}

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut spec = BarSpec::reference();
    if let Some(dx) = args.first() {
        spec.dx = dx.parse().context("DX")?;
    }
    if let Some(h) = args.get(1) {
        spec.law.hardening = h.parse().context("HARDENING_PA")?;
    }
    let mut below = spec;
    below.peak_strain = 0.5 * spec.yield_strain();
    below.load_transits = spec.load_transits * below.peak_strain / spec.peak_strain;
    for (name, s) in [("past yield", spec), ("below yield", below)] {
        let clock = std::time::Instant::now();
        let r = run(&s);
        report(name, &s, &r, clock.elapsed().as_secs_f64());
    }
    Ok(())
}
