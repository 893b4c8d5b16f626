//! Single-point tests of the NACC return mapping (docs/method.md §4), on the
//! f64 oracle in `splatter::sim`. Each test prints the numbers
//! it measured (`cargo test --release --test sim_math -- --nocapture`).

use glam::{DMat3, DQuat, DVec3};
use splatter::rng::SplitMix64;
use splatter::sim::model::nacc::oracle::{
    j_from_pressure, principal_state, project_center, project_closest_point, project_continuous,
    project_pq, return_map, Case3Variant, NaccParams, ReturnCase, YieldEllipse, SIGMA_MIN,
};
use splatter::sim::svd::svd3;

mod common;
use common::{fruit, paper_materials as materials, VARIANTS};

fn random_rotation(r: &mut SplitMix64) -> DMat3 {
    let v = DVec3::new(r.uniform(), r.uniform(), r.uniform()) - 0.5;
    DMat3::from_quat(DQuat::from_xyzw(v.x, v.y, v.z, r.uniform() - 0.5).normalize())
}

/// A trial F with principal stretches in [0.6, 1.5] (compression, tension and shear).
fn random_trial(r: &mut SplitMix64) -> DMat3 {
    let s = DVec3::new(r.uniform(), r.uniform(), r.uniform()) * 0.9 + 0.6;
    random_rotation(r) * DMat3::from_diagonal(s) * random_rotation(r).transpose()
}

/// (p, q) of an elastic gradient, evaluated from scratch (SVD, σ clamp, docs/method.md §4 formulas).
fn evaluate_pq(f: DMat3, params: &NaccParams) -> (f64, f64) {
    let sigma = svd3(f).sigma.max(DVec3::splat(SIGMA_MIN));
    let st = principal_state(sigma, params.kappa(), params.mu());
    (st.p, st.q)
}

fn variant_name(v: Case3Variant) -> String {
    match v {
        Case3Variant::Center => "center".into(),
        Case3Variant::Continuous { k } => format!("continuous{{k={k}}}"),
        Case3Variant::ClosestPoint => "closest_point".into(),
    }
}

/// (a) Elastic trial states (y_tr ≤ 0) come back bit for bit, α unchanged.
#[test]
fn elastic_trial_states_are_unchanged() {
    let mut r = SplitMix64::new(31);
    let mut elastic = 0;
    for params in materials() {
        for v in VARIANTS {
            for _ in 0..2000 {
                let f = random_trial(&mut r);
                let alpha = -0.6 + 0.8 * r.uniform();
                let out = return_map(f, alpha, &params, v);
                let (p, q) = evaluate_pq(f, &params);
                let y = params.ellipse(alpha).y(p, q);
                assert_eq!(out.case == ReturnCase::Elastic, y <= 0.0);
                if out.case == ReturnCase::Elastic {
                    elastic += 1;
                    assert_eq!(out.f, f);
                    assert_eq!(out.alpha, alpha);
                    assert_eq!((out.p, out.q), (out.p_trial, out.q_trial));
                }
            }
        }
    }
    println!("(a) {elastic} elastic trial states of 60000 returned unchanged");
    assert!(elastic > 5000);
}

/// (b) + (h) Every plastic return lands on the yield surface of p0(α_start), for all
/// variants: the returned (p, q) to round-off, and the reconstructed F_new re-evaluated from
/// scratch (h) to ~ε κ (p = κ/2 (1 − J²) cannot be better: with α ≥ 0, p0 = 1e-5 κ). Also: α_new − α = ln(J_tr / det F_new), p_new ∈ [−βp0, p0], 0 ≤ q_new ≤ q_tr.
/// For contrast it measures the drift of the reference code's trace-keeping b̄ (docs/method.md §4).
#[test]
fn plastic_returns_land_on_the_yield_surface() {
    let mut r = SplitMix64::new(32);
    for v in VARIANTS {
        let (mut worst_y, mut worst_rebuilt, mut worst_pq, mut worst_alpha) =
            (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        let (mut worst_trace_keeping, mut cases) = (0.0f64, [0usize; 4]);
        for params in materials() {
            let (kappa, mu) = (params.kappa(), params.mu());
            for _ in 0..4000 {
                let f = random_trial(&mut r);
                let alpha = -0.6 + 0.8 * r.uniform();
                let out = return_map(f, alpha, &params, v);
                cases[out.case as usize] += 1;
                if out.case == ReturnCase::Elastic {
                    continue;
                }
                let ell = params.ellipse(alpha);
                let scale = ell.scale();
                worst_y = worst_y.max(ell.y(out.p, out.q).abs() / scale);
                assert!(
                    out.p >= -ell.beta * ell.p0 * (1.0 + 1e-12) && out.p <= ell.p0 * (1.0 + 1e-12)
                );
                assert!(out.q >= 0.0 && out.q <= out.q_trial * (1.0 + 1e-12));
                // (h) the new F reproduces (p_new, q_new).
                let (p2, q2) = evaluate_pq(out.f, &params);
                worst_rebuilt = worst_rebuilt.max(distance_to_surface(&ell, p2, q2) / kappa);
                let pq_err = ((p2 - out.p).abs()).max((q2 - out.q).abs()) / kappa;
                worst_pq = worst_pq.max(pq_err);
                // Hardening α ← α + ln(J_tr / J_new).
                let j_tr = out_trial_j(f);
                let want = alpha + (j_tr / out.f.determinant()).ln();
                worst_alpha = worst_alpha.max((out.alpha - want).abs());
                // The trace-keeping alternative: b̄_new = s_new/μ + mean(b̄_tr).
                let tk = trace_keeping_f(f, &out, kappa, mu);
                let (p3, q3) = evaluate_pq(tk, &params);
                if out.case == ReturnCase::Interior {
                    let drift = distance_to_surface(&ell, p3, q3) / kappa;
                    worst_trace_keeping = worst_trace_keeping.max(drift);
                }
            }
        }
        println!(
            "(b,h) {:18} cases [elastic, upper tip, lower tip, interior] = {cases:?}: \
             |y(p_new,q_new)|/M²a² ≤ {worst_y:.1e}; rebuilt F: distance to surface ≤ \
             {worst_rebuilt:.1e}·κ, |Δp|,|Δq| ≤ {worst_pq:.1e}·κ; α error ≤ {worst_alpha:.1e}; \
             case 3 with a trace-keeping b̄ would be up to {worst_trace_keeping:.1e}·κ off the surface",
            variant_name(v)
        );
        assert!(
            cases[1] > 100 && cases[2] > 100 && cases[3] > 100,
            "{cases:?}"
        );
        assert!(worst_y < 1e-12, "{worst_y:e}");
        assert!(worst_rebuilt < 1e-13, "{worst_rebuilt:e}");
        assert!(worst_pq < 1e-13, "{worst_pq:e}");
        assert!(worst_alpha < 1e-12, "{worst_alpha:e}");
        assert!(worst_trace_keeping > 1e3 * worst_rebuilt.max(1e-15));
    }
}

/// First-order distance of (p, q) from the surface, |y| / ‖∇y‖ (exact on the surface; the
/// natural measure here because p = κ/2 (1 − J²) carries an absolute error ~ε κ).
fn distance_to_surface(ell: &YieldEllipse, p: f64, q: f64) -> f64 {
    let m2 = ell.m_slope * ell.m_slope;
    let grad = (2.0 * m2 * (p - ell.center())).hypot(2.0 * (1.0 + 2.0 * ell.beta) * q);
    ell.y(p, q).abs() / grad.max(1e-300)
}

/// J of the clamped trial stretches, as the return mapping sees it.
fn out_trial_j(f: DMat3) -> f64 {
    let s = svd3(f).sigma.max(DVec3::splat(SIGMA_MIN));
    s.x * s.y * s.z
}

/// F_new as the reference code would build it: b̄ keeps the trial trace instead of det = 1.
fn trace_keeping_f(f: DMat3, out: &splatter::sim::PlasticReturn, kappa: f64, mu: f64) -> DMat3 {
    let svd = svd3(f);
    let trial = principal_state(svd.sigma.max(DVec3::splat(SIGMA_MIN)), kappa, mu);
    let ratio = if trial.q > 0.0 { out.q / trial.q } else { 0.0 };
    let mean = (trial.b_bar.x + trial.b_bar.y + trial.b_bar.z) / 3.0;
    let b = trial.s * (ratio / mu) + DVec3::splat(mean);
    let sigma =
        DVec3::new(b.x.sqrt(), b.y.sqrt(), b.z.sqrt()) * j_from_pressure(out.p, kappa).cbrt();
    svd.u * DMat3::from_diagonal(sigma) * svd.v.transpose()
}

/// (c) Isotropic compression, 0.1 % volume per step down to J = 0.6: every plastic step
/// lands on the upper tip (p = p0(α_start), q = 0) and lowers α (p0 grows); because p0 is
/// taken from the α at the start of the step, hardening overshoots a little and some steps
/// in between are elastic (a staircase around the path). J_E · exp(α − α₀) = J_total holds
/// to round-off, and α follows the continuum hardening path κ/2 (1 − J_E²) = p0(α),
/// J_E = J_total e^(α₀ − α), to within one step's hardening.
#[test]
fn isotropic_compression_follows_the_hardening_path() {
    let params = fruit();
    let step = (0.999f64).cbrt();
    let (mut f, mut alpha, mut j_total) = (DMat3::IDENTITY, params.alpha0, 1.0f64);
    let (mut first_yield, mut plastic_steps, mut worst_lag) = (None, 0, 0.0f64);
    let mut n = 0;
    while j_total > 0.6 {
        n += 1;
        j_total *= 0.999;
        let p0_start = params.p0(alpha);
        let out = return_map(f * step, alpha, &params, Case3Variant::Center);
        if out.case != ReturnCase::Elastic {
            first_yield.get_or_insert((n, j_total));
            assert_eq!(out.case, ReturnCase::UpperTip, "step {n}");
            assert!((out.p - p0_start).abs() < 1e-12 * p0_start && out.q == 0.0);
            assert!(
                out.alpha < alpha && params.p0(out.alpha) > p0_start,
                "step {n}"
            );
            plastic_steps += 1;
        }
        let invariant = out.f.determinant() * (out.alpha - params.alpha0).exp();
        assert!((invariant / j_total - 1.0).abs() < 1e-11, "step {n}");
        (f, alpha) = (out.f, out.alpha);
        if first_yield.is_some() {
            worst_lag = worst_lag.max((alpha - hardening_path(&params, j_total)).abs());
        }
    }
    let (n_yield, j_yield) = first_yield.expect("never yielded");
    let want_j_yield = j_from_pressure(params.p0(params.alpha0), params.kappa());
    let alpha_path = hardening_path(&params, j_total);
    println!(
        "(c) first yield at step {n_yield}, J = {j_yield:.5} (predicted J_E(p0(α₀)) = \
         {want_j_yield:.5}); {plastic_steps} of the next {} steps plastic; at J = {j_total:.4}: \
         α = {alpha:.6}, continuum path α = {alpha_path:.6} (largest lag on the way \
         {worst_lag:.1e}); p0 grew from {:.2} to {:.2} (κ = {:.1})",
        n - n_yield + 1,
        params.p0(params.alpha0),
        params.p0(alpha),
        params.kappa()
    );
    assert!((j_yield / want_j_yield - 1.0).abs() < 2e-3);
    assert!(worst_lag < 3e-3, "{worst_lag}");
}

/// α on the continuum isotropic hardening path at total volume ratio J: the root of
/// κ/2 (1 − J_E²) = p0(α) with J_E = J e^(α₀ − α) (bisection).
fn hardening_path(params: &NaccParams, j_total: f64) -> f64 {
    let residual = |a: f64| {
        let je = j_total * (params.alpha0 - a).exp();
        0.5 * params.kappa() * (1.0 - je * je) - params.p0(a)
    };
    let (mut lo, mut hi) = (-5.0, params.alpha0);
    if residual(hi) <= 0.0 {
        return params.alpha0; // not yet yielding
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if residual(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

/// (d) Isotropic tension, 0.1 % volume per step: it yields at the lower tip, α rises and
/// crosses 0 (softening runs away within a few steps: fracture), after which p0 sits at the
/// floor κ ε₀ and the stress is p = −β κ ε₀.
#[test]
fn isotropic_tension_loses_cohesion() {
    let params = fruit();
    let step = (1.001f64).cbrt();
    let (mut f, mut alpha, mut j_total) = (DMat3::IDENTITY, params.alpha0, 1.0f64);
    let (mut first_yield, mut crossed) = (None, None);
    let mut p_before = 0.0;
    for n in 1..=600 {
        j_total *= 1.001;
        let out = return_map(
            f * step,
            alpha,
            &params,
            Case3Variant::Continuous { k: 2.0 },
        );
        if out.case != ReturnCase::Elastic {
            first_yield.get_or_insert((n, j_total, out.p));
            assert_eq!(out.case, ReturnCase::LowerTip, "step {n}");
            assert!(out.alpha > alpha, "step {n}");
        }
        if crossed.is_none() && out.alpha >= 0.0 {
            crossed = Some((n, j_total));
            p_before = out.p;
        } else if crossed.is_some() {
            let floor = params.kappa() * splatter::sim::model::nacc::oracle::EPS0;
            assert_eq!(params.p0(alpha), floor);
            assert!(
                (out.p + params.beta * floor).abs() < 1e-12 * floor,
                "step {n}"
            );
        }
        (f, alpha) = (out.f, out.alpha);
    }
    let (n_yield, j_yield, p_yield) = first_yield.expect("never yielded");
    let (n_cross, j_cross) = crossed.expect("α never crossed 0");
    let floor = params.kappa() * splatter::sim::model::nacc::oracle::EPS0;
    println!(
        "(d) first yield at step {n_yield} (J = {j_yield:.5}, p = {p_yield:.2}); α ≥ 0 at step \
         {n_cross} (J = {j_cross:.5}, last cohesive p = {p_before:.3}); afterwards p = −βκε₀ = \
         {:.4}, p0 = κε₀ = {floor:.4}; final α = {alpha:.4}",
        -params.beta * floor
    );
    assert!(n_cross - n_yield < 50);
}

/// (e) Shear at fixed pressure (simple shear F = J^(1/3) (I + γ e_x e_yᵀ), det = J): the
/// first plastic state, found by bisection on γ, has q = M sqrt((p + βp0)(p0 − p)/(1 + 2β)).
#[test]
fn shear_at_fixed_pressure_first_yields_on_the_ellipse() {
    for params in materials() {
        let alpha = params.alpha0;
        let ell = params.ellipse(alpha);
        let lo_p = -ell.beta * ell.p0;
        let mut worst: f64 = 0.0;
        for frac in [0.05, 0.25, 0.5, 0.75, 0.95] {
            let p = lo_p + frac * (ell.p0 - lo_p);
            if p > 0.49 * params.kappa() {
                continue; // p ≥ κ/2 needs J ≤ 0: this cap is out of reach
            }
            let jc = j_from_pressure(p, params.kappa()).cbrt();
            let trial = |g: f64| {
                let shear = DMat3::from_cols(DVec3::X, DVec3::new(g, 1.0, 0.0), DVec3::Z);
                return_map(shear * jc, alpha, &params, Case3Variant::Center)
            };
            let (mut lo, mut hi) = (0.0, 10.0);
            assert_eq!(trial(lo).case, ReturnCase::Elastic);
            assert_eq!(trial(hi).case, ReturnCase::Interior);
            for _ in 0..100 {
                let mid = 0.5 * (lo + hi);
                if trial(mid).case == ReturnCase::Elastic {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let out = trial(hi);
            let want = params.m_slope
                * ((p + ell.beta * ell.p0) * (ell.p0 - p) / (1.0 + 2.0 * ell.beta)).sqrt();
            let err = (out.q_trial - want).abs() / ell.half_height();
            assert!((out.p_trial - p).abs() < 1e-9 * ell.p0, "p drifted");
            assert!(err < 1e-9, "p = {p}: q = {} vs {want}", out.q_trial);
            worst = worst.max(err);
        }
        println!(
            "(e) E = {}, β = {}: first-yield q matches M sqrt((p+βp0)(p0−p)/(1+2β)) to {worst:.1e}·b \
             at 5 pressures",
            params.e, params.beta
        );
    }
}

/// Largest distance between consecutive results of a sweep of p_tr over [from, to].
fn largest_jump(map: impl Fn(f64) -> (f64, f64), from: f64, to: f64, h: f64) -> f64 {
    let n = ((to - from) / h).round() as usize;
    let points: Vec<(f64, f64)> = (0..=n).map(|i| map(from + (i as f64 + 0.5) * h)).collect();
    points
        .windows(2)
        .map(|w| (w[1].0 - w[0].0).hypot(w[1].1 - w[0].1))
        .fold(0.0, f64::max)
}

/// (f) Continuity at the tips: sweep p_tr across p0 (and across −βp0) at q_tr = 1000 p0 with
/// steps h·p0, h = 1e-2, 1e-3, 1e-4. `continuous` jumps shrink with h (like sqrt(h));
/// `center` keeps a jump equal to the distance from (p0, 0) to the ellipse top,
/// sqrt(a² + b²), a = (1 + β)p0/2, b = M a / sqrt(1 + 2β), up to O(a/q_tr).
#[test]
fn continuity_across_the_tips() {
    let params = fruit();
    let ell = params.ellipse(params.alpha0);
    let (p0, a, b) = (ell.p0, ell.half_width(), ell.half_height());
    let q_tr = 1000.0 * p0;
    let top_distance = a.hypot(b);
    // Centre mapping just left of the tip, closed form: t = M a / sqrt((1+2β) q² + M² a²).
    let m = ell.m_slope;
    let t = m * a / ((1.0 + 2.0 * ell.beta) * q_tr * q_tr + m * m * a * a).sqrt();
    let finite_q_jump = (a - t * a).hypot(t * q_tr);
    println!(
        "(f) p0 = {p0:.3}, q_tr = 1000 p0; predicted center jump: asymptotic sqrt(a²+b²) = \
         {:.5} p0, at this q_tr {:.5} p0",
        top_distance / p0,
        finite_q_jump / p0
    );
    let hs = [1e-2, 1e-3, 1e-4];
    for v in VARIANTS {
        let map = |p: f64| {
            let (pn, qn, _) = project_pq(&ell, p, q_tr, v);
            (pn, qn)
        };
        let right: Vec<f64> = hs
            .iter()
            .map(|h| largest_jump(map, p0 * 0.95, p0 * 1.05, h * p0) / p0)
            .collect();
        let tip = -ell.beta * p0;
        let left: Vec<f64> = hs
            .iter()
            .map(|h| largest_jump(map, tip - 0.05 * p0, tip + 0.05 * p0, h * p0) / p0)
            .collect();
        println!(
            "(f) {:18} largest jump / p0 for h = 1e-2, 1e-3, 1e-4: right tip {:.5?}, left tip {:.5?}",
            variant_name(v),
            right,
            left
        );
        match v {
            Case3Variant::Continuous { .. } => {
                for jumps in [&right, &left] {
                    assert!(
                        jumps[1] < jumps[0] / 2.0 && jumps[2] < jumps[1] / 2.0,
                        "{jumps:?}"
                    );
                }
                assert!(right[2] < 0.1 * top_distance / p0);
            }
            Case3Variant::Center => {
                // The samples nearest the tip sit h/2 on either side of it.
                for (jump, h) in right.iter().zip(hs) {
                    assert!((jump - finite_q_jump / p0).abs() < h, "{jump}");
                    assert!((jump * p0 / top_distance - 1.0).abs() < 1e-2 + h);
                }
            }
            Case3Variant::ClosestPoint => {}
        }
    }
}

/// k → ∞ recovers `center` (docs/method.md §4).
#[test]
fn continuous_with_huge_k_is_center() {
    let ell = fruit().ellipse(-0.2);
    for i in 1..100 {
        let p = -ell.beta * ell.p0 + (1.0 + ell.beta) * ell.p0 * i as f64 / 100.0;
        let q = 3.0 * ell.half_height();
        let (c, k) = (
            project_center(&ell, p, q),
            project_continuous(&ell, p, q, 1e6),
        );
        assert!((c.0 - k.0).abs() < 1e-9 * ell.p0 && (c.1 - k.1).abs() < 1e-9 * ell.p0);
    }
}

/// (g) `closest_point` is the closest point: on the surface, no point of a 200 000-point
/// sampling of the ellipse is closer, and the return is along the normal (Δγ ≥ 0).
#[test]
fn closest_point_is_closest() {
    let mut r = SplitMix64::new(37);
    let mut worst_gain: f64 = 0.0;
    for params in materials() {
        let ell: YieldEllipse = params.ellipse(-0.3 * r.uniform());
        let (pc, a, b) = (ell.center(), ell.half_width(), ell.half_height());
        let samples: Vec<(f64, f64)> = (0..=200_000)
            .map(|i| {
                let th = std::f64::consts::PI * i as f64 / 200_000.0;
                (pc + a * th.cos(), b * th.sin())
            })
            .collect();
        for _ in 0..100 {
            let p_tr = pc + a * (2.4 * r.uniform() - 1.2);
            let q_tr = b * (0.2 + 3.0 * r.uniform());
            if ell.y(p_tr, q_tr) <= 0.0 {
                continue;
            }
            let (p, q) = project_closest_point(&ell, p_tr, q_tr);
            assert!(ell.y(p, q).abs() < 1e-12 * ell.scale());
            let d = (p - p_tr).hypot(q - q_tr);
            let best = samples
                .iter()
                .map(|s| (s.0 - p_tr).hypot(s.1 - q_tr))
                .fold(f64::INFINITY, f64::min);
            assert!(d <= best * (1.0 + 1e-12), "{d} > {best}");
            worst_gain = worst_gain.max((d - best) / a);
            // Normal return: (p_tr − p, q_tr − q) = Δγ ∇y with Δγ ≥ 0.
            let grad = DVec3::new(
                params.m_slope.powi(2) * 2.0 * (p - pc),
                2.0 * (1.0 + 2.0 * ell.beta) * q,
                0.0,
            );
            let diff = DVec3::new(p_tr - p, q_tr - q, 0.0);
            assert!(grad.cross(diff).length() < 1e-9 * grad.length() * diff.length());
            assert!(grad.dot(diff) > 0.0);
        }
    }
    println!("(g) closest_point never farther than the best of 200k samples (max excess {worst_gain:.1e}·a)");
}
