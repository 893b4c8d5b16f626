//! Stability atlas: a NACC sphere thrown onto a sticky ground (the paper's fruit
//! parameters), swept one parameter at a time around a baseline — Δt relative to the CFL
//! limit, Young's modulus E, Poisson ratio ν → 0.5, impact speed — for each case-3 return
//! mapping (`center`, `continuous` k = 1, 2, 4, `closest_point`), on the CPU reference
//! step (f64). Each run is classified by the rules of [`classify`].
//!
//! Right-tip instrumentation: after every step the trial state of each particle is
//! rebuilt (F_tr = (I + Δt C) F_old from the step's new C and the F and α before the
//! step, exactly what G2P fed the return map) and mapped again with `nacc::return_map` to
//! learn its case. A return is *near the right tip* when it is case 3 (interior) with
//! (p_tr − p_c)/L_p > 0.9, i.e. the trial pressure is in the last 10% of the ellipse's
//! half width before p0 — where `center` sends the state towards the ellipse's top and
//! `continuous` towards the tip.

use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

use crate::runner::{simulate, Outcome};
use splatter::sim::model::nacc::oracle::{project_pq, ReturnCase};
use splatter::sim::ElasticModel;
use splatter::sim::{cfl_dt, Grid, Material, Particles, StepParams};
use splatter::sim::{return_map, Case3Variant, NaccParams};

/// Trial pressure fraction (p_tr − p_c)/L_p above which a case-3 return is "near the
/// right tip".
pub const NEAR_TIP: f64 = 0.9;

/// Classification thresholds (see [`classify`]).
pub const ENERGY_BLOWUP: f64 = 1.5;
pub const ENERGY_ARTIFACT: f64 = 1.05;
/// Stable baseline runs reach up to ~1.7 v_ref: material jets sideways at the contact
/// (physical for near-incompressible impacts), so an outlier is twice the fastest speed
/// the fall can give.
pub const SPEED_OUTLIER: f64 = 2.0;

/// A near-tip return with q_new above this fraction of the half height b left the arc of
/// the ellipse next to the tip: for (p_tr − p_c)/L_p > 0.9 the surface's own q is at most
/// sqrt(1 − 0.9²) b = 0.436 b, so a return above 0.5 b went towards the top.
pub const TOWARDS_TOP: f64 = 0.5;

/// Fraction of near-tip returns sent towards the top above which a run is a tip artifact.
pub const TIP_ARTIFACT: f64 = 0.1;

/// The atlas's run classes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Class {
    Stable,
    /// Dynamically fine, but more than TIP_ARTIFACT of the near-tip returns were sent
    /// towards the ellipse's top: the mapping's discontinuity at the right tip at work.
    TipArtifact,
    Nan,
    EnergyBlowUp,
    Artifact,
}

impl Class {
    pub fn name(self) -> &'static str {
        match self {
            Class::Stable => "stable",
            Class::TipArtifact => "tip artifact",
            Class::Nan => "NaN/escape",
            Class::EnergyBlowUp => "energy blow-up",
            Class::Artifact => "artifact",
        }
    }
}

/// What one run measured.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AtlasRun {
    /// "cfl", "E", "nu", "speed", "alpha0".
    pub sweep: String,
    pub value: f64,
    pub variant: String,
    pub e: f64,
    pub nu: f64,
    pub speed: f64,
    /// Δt / (Δx/c).
    pub cfl: f64,
    pub dt: f64,
    pub steps: usize,
    pub outcome: Outcome,
    /// max over t of E(t)/E(0), E = kinetic + gravitational (above the ground) + elastic.
    pub energy_ratio: f64,
    /// max over t and particles of |v_p| / v_ref, v_ref = sqrt(v₀² + 2 g h₀) (the fastest
    /// speed the fall can give).
    pub speed_ratio: f64,
    /// Returns near the right tip (particle-steps), and tip-case (p_tr > p0) returns.
    pub near_tip_returns: u64,
    pub upper_tip_returns: u64,
    /// Mean q_new / b over the near-tip returns (b: the ellipse's half height): `center`
    /// heads for the top (q ≈ b), a continuous mapping for the tip (q → 0).
    pub near_tip_q_over_b: f64,
    /// Fraction of the near-tip returns with q_new > TOWARDS_TOP · b (sent towards the
    /// ellipse's top rather than to the nearby arc: `center`'s discontinuity at work).
    pub near_tip_towards_top: f64,
    /// max |v_p| / v_ref over the particles at the steps they were returned near the tip.
    pub near_tip_speed_ratio: f64,
    /// Particle-steps of particles returned near the tip in that step and moving faster
    /// than SPEED_OUTLIER·v_ref.
    pub tip_speed_outliers: u64,
    pub alpha0: f64,
    pub class: Class,
    pub wall_s: f64,
}

/// The return-map level probe of the right tip: mapped (p, q)/p0 just inside and just
/// outside p0 at a large trial q, per variant.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TipProbe {
    pub variant: String,
    /// Trial q in units of the half height b.
    pub q_trial_over_b: f64,
    /// Returned (p/p0, q/b) at p_tr = p0(1 − ε) and p0(1 + ε).
    pub inside: (f64, f64),
    pub outside: (f64, f64),
    /// |Δ(p/p0, q/b)| between the two: the jump of the mapping at the tip.
    pub jump: f64,
    pub epsilon: f64,
}

/// The atlas.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AtlasReport {
    pub runs: Vec<AtlasRun>,
    pub probes: Vec<TipProbe>,
}

/// The five mappings, with their names.
pub fn variants() -> Vec<(String, Case3Variant)> {
    vec![
        ("center".into(), Case3Variant::Center),
        ("continuous k=1".into(), Case3Variant::Continuous { k: 1.0 }),
        ("continuous k=2".into(), Case3Variant::Continuous { k: 2.0 }),
        ("continuous k=4".into(), Case3Variant::Continuous { k: 4.0 }),
        ("closest_point".into(), Case3Variant::ClosestPoint),
    ]
}

/// The baseline: α₀ −0.04, E 2000, ν 0.4, 8 m/s, Δt at 0.4 of the CFL limit.
#[derive(Clone, Copy, Debug)]
pub struct Setup {
    pub alpha0: f64,
    pub e: f64,
    pub nu: f64,
    pub speed: f64,
    pub cfl: f64,
}

pub const BASELINE: Setup = Setup {
    alpha0: -0.04,
    e: 2000.0,
    nu: 0.4,
    speed: 8.0,
    cfl: 0.4,
};

/// The sweeps: (name, values), each applied to the baseline.
pub fn sweeps(quick: bool) -> Vec<(&'static str, Vec<f64>)> {
    if quick {
        return vec![("speed", vec![8.0])];
    }
    vec![
        ("cfl", vec![0.4, 1.0, 1.5, 2.0, 4.0]),
        ("E", vec![500.0, 2000.0, 1e4, 5e4]),
        ("nu", vec![0.3, 0.45, 0.49, 0.499]),
        ("speed", vec![2.0, 8.0, 20.0, 40.0]),
        ("alpha0", vec![-0.1, -0.04, -0.01, -0.002]),
    ]
}

fn apply(sweep: &str, value: f64) -> Setup {
    let mut s = BASELINE;
    match sweep {
        "cfl" => s.cfl = value,
        "E" => s.e = value,
        "nu" => s.nu = value,
        "alpha0" => s.alpha0 = value,
        _ => s.speed = value,
    }
    s
}

/// Runs every sweep for every variant, and the tip probes.
pub fn run_atlas(quick: bool, log: &mut dyn FnMut(&AtlasRun)) -> AtlasReport {
    let mut runs = Vec::new();
    for (sweep, values) in sweeps(quick) {
        for value in values {
            for (name, variant) in variants() {
                let r = run_one(sweep, value, &name, variant, quick);
                log(&r);
                runs.push(r);
            }
        }
    }
    let probes = variants()
        .into_iter()
        .map(|(name, v)| tip_probe(&name, v))
        .collect();
    AtlasReport { runs, probes }
}

/// The classification rules, in order: `Nan` when the run stopped on a NaN/Inf or an
/// escaped particle; `EnergyBlowUp` when the total energy rose above ENERGY_BLOWUP × its
/// start; `Artifact` when it rose above ENERGY_ARTIFACT × (a kinetic-energy spike: with
/// plasticity and a sticky ground the energy can only fall), or a particle moved faster
/// than SPEED_OUTLIER × v_ref, or any particle returned near the right tip was such an
/// outlier; `TipArtifact` when more than TIP_ARTIFACT of the near-tip returns went
/// towards the top (q_new > TOWARDS_TOP · b); otherwise `Stable`.
pub fn classify(m: &Metrics) -> Class {
    if m.outcome != Outcome::Finished || !m.energy_ratio.is_finite() {
        Class::Nan
    } else if m.energy_ratio > ENERGY_BLOWUP {
        Class::EnergyBlowUp
    } else if m.energy_ratio > ENERGY_ARTIFACT
        || m.speed_ratio > SPEED_OUTLIER
        || m.tip_outliers > 0
    {
        Class::Artifact
    } else if m.towards_top > TIP_ARTIFACT {
        Class::TipArtifact
    } else {
        Class::Stable
    }
}

/// What [`classify`] looks at.
#[derive(Clone, Copy, Debug)]
pub struct Metrics {
    pub outcome: Outcome,
    pub energy_ratio: f64,
    pub speed_ratio: f64,
    pub tip_outliers: u64,
    pub towards_top: f64,
}

const G: f64 = 9.8;
const RADIUS: f64 = 0.08;
const GROUND: f64 = 0.04; // the sticky band's clamp node: (3 − 1) Δx above y = 0
const DX: f64 = 0.02;
const T_END: f64 = 0.03;

struct Tally {
    near_tip: u64,
    towards_top: u64,
    tip_speed_max: f64,
    upper_tip: u64,
    q_over_b: f64,
    tip_outliers: u64,
    energy_max: f64,
    speed_max: f64,
}

fn run_one(sweep: &str, value: f64, name: &str, variant: Case3Variant, quick: bool) -> AtlasRun {
    let s = apply(sweep, value);
    let params = NaccParams {
        e: s.e,
        nu: s.nu,
        alpha0: s.alpha0,
        beta: 1.0,
        xi: 2.0,
        m_slope: 2.36,
    };
    let material = Material::nacc(params, variant);
    let dx = if quick { 0.04 } else { DX };
    let center = DVec3::new(0.2, GROUND + RADIUS + 0.02, 0.2);
    let mut p = Particles::sample_sphere(center, RADIUS, dx / 2.0, 2.0);
    p.set_material(0, &material);
    p.v.iter_mut()
        .for_each(|v| *v = DVec3::new(0.0, -s.speed, 0.0));
    let mut grid = Grid::new(DVec3::ZERO, DVec3::new(0.4, 0.3, 0.4), dx);
    let dt = cfl_dt(&material, 2.0, dx, s.cfl);
    let steps = (T_END / dt).ceil() as usize;
    let sp = StepParams::sticky_ground(dt, DVec3::ZERO);
    let v_ref = (s.speed * s.speed + 2.0 * G * (center.y - GROUND)).sqrt();
    let e0 = energy(&p, &params);
    let mut t = Tally {
        near_tip: 0,
        towards_top: 0,
        tip_speed_max: 0.0,
        upper_tip: 0,
        q_over_b: 0.0,
        tip_outliers: 0,
        energy_max: e0,
        speed_max: 0.0,
    };
    let (mut f_old, mut a_old) = (p.f.clone(), p.alpha.clone());
    let gravity = |_| DVec3::new(0.0, -G, 0.0);
    let stats = simulate(
        &mut p,
        &mut grid,
        &[material],
        &sp,
        steps,
        gravity,
        |_, _, p| {
            tally_step(p, &f_old, &a_old, &params, variant, dt, v_ref, &mut t);
            t.energy_max = t.energy_max.max(energy(p, &params));
            f_old.clone_from(&p.f);
            a_old.clone_from(&p.alpha);
        },
    );
    let metrics = Metrics {
        outcome: stats.outcome,
        energy_ratio: t.energy_max / e0,
        speed_ratio: t.speed_max / v_ref,
        tip_outliers: t.tip_outliers,
        towards_top: t.towards_top as f64 / t.near_tip.max(1) as f64,
    };
    AtlasRun {
        sweep: sweep.into(),
        value,
        variant: name.into(),
        e: s.e,
        nu: s.nu,
        speed: s.speed,
        cfl: s.cfl,
        dt,
        steps,
        outcome: stats.outcome,
        energy_ratio: metrics.energy_ratio,
        speed_ratio: metrics.speed_ratio,
        near_tip_returns: t.near_tip,
        upper_tip_returns: t.upper_tip,
        near_tip_q_over_b: if t.near_tip > 0 {
            t.q_over_b / t.near_tip as f64
        } else {
            0.0
        },
        near_tip_towards_top: metrics.towards_top,
        near_tip_speed_ratio: t.tip_speed_max / v_ref,
        tip_speed_outliers: t.tip_outliers,
        alpha0: s.alpha0,
        class: classify(&metrics),
        wall_s: stats.wall_s,
    }
}

/// Kinetic + gravitational (above the ground's clamp node) + elastic energy.
fn energy(p: &Particles, params: &NaccParams) -> f64 {
    let lame = params.lame();
    (0..p.len())
        .map(|q| {
            let m = p.mass[q];
            let psi = ElasticModel::NeoHookean.energy_density(p.f[q], &lame);
            0.5 * m * p.v[q].length_squared() + m * G * (p.x[q].y - GROUND) + p.volume0[q] * psi
        })
        .sum()
}

/// Re-runs each particle's return map from the state G2P saw, counting the right-tip
/// cases and their speeds.
#[allow(clippy::too_many_arguments)]
fn tally_step(
    p: &Particles,
    f_old: &[DMat3],
    a_old: &[f64],
    params: &NaccParams,
    variant: Case3Variant,
    dt: f64,
    v_ref: f64,
    t: &mut Tally,
) {
    for q in 0..p.len() {
        let speed = p.v[q].length();
        t.speed_max = t.speed_max.max(speed);
        let f_trial = (DMat3::IDENTITY + p.c[q] * dt) * f_old[q];
        let r = return_map(f_trial, a_old[q], params, variant);
        let ell = params.ellipse(a_old[q]);
        let frac = (r.p_trial - ell.center()) / ell.half_width();
        match r.case {
            ReturnCase::UpperTip => t.upper_tip += 1,
            ReturnCase::Interior if frac > NEAR_TIP => {
                t.near_tip += 1;
                t.q_over_b += r.q / ell.half_height();
                t.tip_speed_max = t.tip_speed_max.max(speed);
                if r.q > TOWARDS_TOP * ell.half_height() {
                    t.towards_top += 1;
                }
                if speed > SPEED_OUTLIER * v_ref {
                    t.tip_outliers += 1;
                }
            }
            _ => {}
        }
    }
}

/// The mapping itself at the right tip: p_tr = p0(1 ∓ ε), q_tr = 3b.
fn tip_probe(name: &str, variant: Case3Variant) -> TipProbe {
    let ell = BASELINE_ELLIPSE;
    let (eps, qt) = (1e-3, 3.0);
    let b = ell.half_height();
    let map = |p: f64| {
        let (pn, qn, _) = project_pq(&ell, p, qt * b, variant);
        (pn / ell.p0, qn / b)
    };
    let inside = map(ell.p0 * (1.0 - eps));
    let outside = map(ell.p0 * (1.0 + eps));
    let jump = ((inside.0 - outside.0).powi(2) + (inside.1 - outside.1).powi(2)).sqrt();
    TipProbe {
        variant: name.into(),
        q_trial_over_b: qt,
        inside,
        outside,
        jump,
        epsilon: eps,
    }
}

/// An ellipse with β = 1, M = 2.36 (p0 = 1: the probe is scale free).
const BASELINE_ELLIPSE: splatter::sim::YieldEllipse = splatter::sim::YieldEllipse {
    p0: 1.0,
    beta: 1.0,
    m_slope: 2.36,
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classification_rules() {
        let ok = Metrics {
            outcome: Outcome::Finished,
            energy_ratio: 0.9,
            speed_ratio: 1.0,
            tip_outliers: 0,
            towards_top: 0.0,
        };
        let with = |f: &dyn Fn(&mut Metrics)| {
            let mut m = ok;
            f(&mut m);
            classify(&m)
        };
        assert_eq!(classify(&ok), Class::Stable);
        assert_eq!(with(&|m| m.outcome = Outcome::NonFinite(3)), Class::Nan);
        assert_eq!(with(&|m| m.outcome = Outcome::Escaped(3)), Class::Nan);
        assert_eq!(with(&|m| m.energy_ratio = f64::NAN), Class::Nan);
        assert_eq!(with(&|m| m.energy_ratio = 2.0), Class::EnergyBlowUp);
        assert_eq!(with(&|m| m.energy_ratio = 1.1), Class::Artifact);
        assert_eq!(with(&|m| m.speed_ratio = 1.9), Class::Stable);
        assert_eq!(with(&|m| m.speed_ratio = 2.1), Class::Artifact);
        assert_eq!(with(&|m| m.tip_outliers = 1), Class::Artifact);
        assert_eq!(with(&|m| m.towards_top = 0.09), Class::Stable);
        assert_eq!(with(&|m| m.towards_top = 0.2), Class::TipArtifact);
        // A dynamic failure wins over the tip statistic.
        assert_eq!(
            with(&|m| {
                m.towards_top = 0.5;
                m.energy_ratio = 3.0
            }),
            Class::EnergyBlowUp
        );
    }

    /// The probe sees `center`'s jump at the right tip and none for `continuous`.
    #[test]
    fn tip_probe_separates_center_from_continuous() {
        let c = tip_probe("center", Case3Variant::Center);
        let k = tip_probe("continuous k=2", Case3Variant::Continuous { k: 2.0 });
        assert!(c.jump > 0.5, "{c:?}");
        assert!(k.jump < 0.1, "{k:?}");
    }
}
