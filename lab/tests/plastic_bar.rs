//! Von Mises plasticity in a bar pulled past yield on the CPU reference step
//! (`splatter_lab::plastic_bar`; the full-size figures are in docs/notes/metal.md, *Metal and
//! plasticine*). A coarse bar (Δx 0.01, 4 cells across) keeps the test short: the
//! loading is a uniform stretch, so the answer does not depend on Δx (at Δx 0.005 and 0.01
//! the fitted yield stress is within 0.01% of σ_y, the elastic slope within 0.2% of E).
//!
//! Tolerances: yield stress 1% and elastic slope 1% (ten times the grips' 0.1–0.2% effect
//! on the slope), hardening slope E H/(E + H) 2%, permanent set at zero load 2% of the
//! analytic ε_peak − τ_peak/E; below yield no particle of the gauge may yield and the bar
//! must return to within 10⁻⁴ of its length (0.2% of the peak strain there).

use splatter_lab::plastic_bar::{run, BarSpec};

fn coarse() -> BarSpec {
    BarSpec {
        dx: 0.01,
        load_transits: 6.0,
        release_transits: 0.0,
        ..BarSpec::reference()
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a / b - 1.0).abs()
}

#[test]
fn bar_past_yield_yields_at_sigma_y_and_keeps_its_set() {
    let spec = coarse();
    let r = run(&spec);
    assert!(r.healthy);
    let fit = r.fit.expect("the peak is past 2 yield strains");
    let sy = spec.law.yield_stress;
    assert!(
        rel(fit.yield_stress, sy) < 0.01,
        "yield stress {} vs σ_y {sy}",
        fit.yield_stress
    );
    assert!(
        rel(fit.elastic_slope, spec.e) < 0.01,
        "elastic slope {} vs E {}",
        fit.elastic_slope,
        spec.e
    );
    assert!(
        rel(fit.hardening_slope, spec.hardening_slope()) < 0.02,
        "hardening slope {} vs EH/(E+H) {}",
        fit.hardening_slope,
        spec.hardening_slope()
    );
    let (ep, tp) = r.peak;
    let expected = ep - tp / spec.e;
    let set = r.set_at_zero_load.expect("unloading reaches zero stress");
    assert!(
        (set - expected).abs() < 0.02 * expected,
        "permanent set {set} vs ε_peak − τ_peak/E = {expected}"
    );
}

#[test]
fn bar_below_yield_returns_to_its_length() {
    let mut spec = coarse();
    spec.peak_strain = 0.5 * spec.yield_strain();
    spec.load_transits = 2.0;
    spec.reverse_transits = 2.0;
    let r = run(&spec);
    assert!(r.healthy);
    assert!(r.peak.0 < spec.yield_strain(), "peak {}", r.peak.0);
    assert_eq!(r.max_alpha, 0.0);
    let set = r.set_at_zero_load.expect("unloading reaches zero stress");
    assert!(set.abs() < 1e-4, "permanent set {set}");
}
