//! Convergence study with known answers, on the CPU reference step (f64): each case is
//! run over a sweep of Δx, Δt (the CFL number) or particles per cell, and reports its
//! error against the known answer and its cost (wall seconds per simulated 1/50 s frame
//! on this machine).
//!
//! - **bar**: first axial mode of an elastic bar clamped at one end; period 4L/c (exact
//!   for ν = 0, where uniaxial displacement is an exact solution). Period from the zero
//!   crossings of the end layer's mean displacement, interpolated between steps and fitted
//!   over all crossings; small amplitude (v₀ = 10⁻³ c).
//! - **incline**: a block sliding down a 30° plane with Coulomb μ = 0.3;
//!   a = g(sin θ − μ cos θ), fitted to the centre-of-mass velocity after contact forms.
//! - **cantilever**: a square beam clamped at one end under gravity, gravity ramped over
//!   two periods of the first bending mode, tip deflection averaged over the next two;
//!   known answer 3ρgL⁴/(2Eh²) (Euler–Bernoulli) times 1 + (4/5)(1 + ν)(h/L)², the shear
//!   (Timoshenko) correction for a uniformly loaded cantilever with shear factor 5/6 —
//!   3.2% at L/h = 5, larger than the discretisation errors, so it is included.
//! - **fracture**: a NACC sphere (`scenes/fracture.json`'s material) thrown onto a sticky
//!   ground; error = symmetric mean nearest-particle distance (Chamfer) between the
//!   particles of a run and of a finely resolved run (Δx 0.007) at the same time, over the
//!   sphere's radius. `measured`/`exact` hold the fractured mass fraction (α ≥ 0) of the
//!   run and of the fine run. The error is against a run, not the truth, so it falls
//!   faster as Δx nears the fine Δx; the fitted order is an upper estimate.

use std::f64::consts::PI;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::runner::{seconds_per_frame, simulate, Outcome};
use splatter::sim::{
    cfl_dt, Boundaries, Condition, DomainWalls, Grid, Material, Particles, PlaneCollider,
    StepParams, Transfer,
};
use splatter::sim::{Case3Variant, NaccParams};

/// One run of a sweep.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConvRun {
    /// "bar", "incline", "cantilever", "fracture".
    pub case: String,
    /// What the sweep varies: "dx", "dt" or "ppc".
    pub sweep: String,
    pub dx: f64,
    pub dt: f64,
    pub cfl: f64,
    /// Particles per cell (per axis cubed).
    pub ppc: u32,
    pub particles: usize,
    pub steps: usize,
    /// The measured quantity and the known answer (fracture: none).
    pub measured: Option<f64>,
    pub exact: Option<f64>,
    /// Relative error (fracture: Chamfer distance over the radius); None when the run
    /// failed.
    pub error: Option<f64>,
    pub outcome: Outcome,
    pub wall_s: f64,
    pub s_per_frame: f64,
}

/// A fitted convergence order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OrderFit {
    pub case: String,
    pub order: f64,
    pub constant: f64,
    pub points: usize,
}

/// The whole study.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConvergenceReport {
    pub runs: Vec<ConvRun>,
    pub orders: Vec<OrderFit>,
}

/// Sweep sizes: `quick` is for tests and smoke runs.
#[derive(Clone, Copy, Debug)]
pub struct ConvOptions {
    pub quick: bool,
}

/// Runs every sweep and fits the Δx orders.
pub fn run_convergence(opts: ConvOptions, log: &mut dyn FnMut(&ConvRun)) -> ConvergenceReport {
    let mut runs = Vec::new();
    let mut push = |r: ConvRun, runs: &mut Vec<ConvRun>| {
        log(&r);
        runs.push(r);
    };
    let bar_cells: &[u32] = if opts.quick {
        &[8, 12]
    } else {
        &[10, 14, 20, 28, 40, 56]
    };
    for &n in bar_cells {
        push(bar(n, 0.4, 2, "dx"), &mut runs);
    }
    if !opts.quick {
        for cfl in [0.1, 0.2, 0.8] {
            push(bar(20, cfl, 2, "dt"), &mut runs);
        }
        for ppc in [1, 3] {
            push(bar(20, 0.4, ppc, "ppc"), &mut runs);
        }
    }
    let incline_dx: &[f64] = if opts.quick {
        &[0.02]
    } else {
        &[0.02, 0.014, 0.01, 0.007]
    };
    for &dx in incline_dx {
        push(incline(dx, 0.4, 2, "dx"), &mut runs);
    }
    if !opts.quick {
        push(incline(0.01, 0.2, 2, "dt"), &mut runs);
        push(incline(0.01, 0.4, 3, "ppc"), &mut runs);
    }
    let beam_cells: &[u32] = if opts.quick { &[2] } else { &[2, 3, 4, 5] };
    for &n in beam_cells {
        push(cantilever(n, 0.4, 2, "dx"), &mut runs);
    }
    if !opts.quick {
        push(cantilever(3, 0.2, 2, "dt"), &mut runs);
        push(cantilever(3, 0.4, 3, "ppc"), &mut runs);
    }
    for r in fracture_sweep(opts.quick) {
        push(r, &mut runs);
    }
    let orders = fit_orders(&runs);
    ConvergenceReport { runs, orders }
}

/// Δx orders of each case from its "dx" sweep (log-log least squares).
pub fn fit_orders(runs: &[ConvRun]) -> Vec<OrderFit> {
    let mut cases: Vec<&str> = runs.iter().map(|r| r.case.as_str()).collect();
    cases.dedup();
    cases
        .into_iter()
        .filter_map(|case| {
            let sel: Vec<&ConvRun> = runs
                .iter()
                .filter(|r| r.case == case && r.sweep == "dx" && r.error.is_some())
                .collect();
            let h: Vec<f64> = sel.iter().map(|r| r.dx).collect();
            let e: Vec<f64> = sel.iter().map(|r| r.error.unwrap_or(0.0)).collect();
            let (order, constant) = crate::fit::convergence_order(&h, &e)?;
            Some(OrderFit {
                case: case.to_string(),
                order,
                constant,
                points: h.len(),
            })
        })
        .collect()
}

fn walls_clamped_at_min_x() -> DomainWalls {
    let mut w = DomainWalls::uniform(Condition::SEPARATE);
    w.faces[0] = Condition::STICKY;
    w
}

fn params(dt: f64, walls: DomainWalls, colliders: Vec<PlaneCollider>) -> StepParams {
    StepParams {
        dt,
        gravity: DVec3::ZERO,
        boundaries: Boundaries {
            walls,
            colliders,
            surface: None,
        },
        transfer: Transfer::Apic,
        separation: Default::default(),
        fields: Default::default(),
        actions: Default::default(),
    }
}

/// The sticky −x wall fixes nodes 0..band−1, so the clamp is the node lo + (band − 1)Δx
/// (`sim::cpu` module docs); material starts one cell before it.
const BAND: f64 = 3.0;

/// Elastic bar, L = 1, c = 1, `cells` cells along it, cross-section 4Δx (exact for ν = 0);
/// also `tests/sim_cpu.rs`'s bar test.
pub fn bar(cells: u32, cfl: f64, ppc_axis: u32, sweep: &str) -> ConvRun {
    let (len, e, rho) = (1.0f64, 1.0f64, 1.0f64);
    let c = (e / rho).sqrt();
    let dx = len / f64::from(cells);
    let a = 4.0 * dx;
    let margin = 3.0 * dx;
    let xc = (BAND - 1.0) * dx;
    let side = a + 2.0 * (margin + BAND * dx);
    let hi = DVec3::new(xc + len + margin + BAND * dx, side, side);
    let mut grid = Grid::new(DVec3::ZERO, hi, dx);
    let mat = Material::fixed_corotated(e, 0.0);
    let y0 = BAND * dx + margin;
    let spacing = dx / f64::from(ppc_axis);
    let mut p = Particles::sample_box(
        DVec3::new(xc - dx, y0, y0),
        DVec3::new(xc + len, y0 + a, y0 + a),
        spacing,
        rho,
    );
    // The exact first mode's velocity field (and its gradient in C), so u_end ∝ sin ωt.
    let v0 = 1e-3 * c;
    let k = PI / (2.0 * len);
    for q in 0..p.len() {
        let s = p.x[q].x - xc;
        if s > 0.0 {
            p.v[q] = DVec3::X * v0 * (k * s).sin();
            p.c[q].x_axis.x = v0 * k * (k * s).cos();
        }
    }
    let x0 = p.x.clone();
    let end: Vec<usize> = (0..p.len())
        .filter(|&q| x0[q].x > xc + len - spacing)
        .collect();
    let dt = cfl_dt(&mat, rho, dx, cfl);
    let period = 4.0 * len / c;
    let steps = (2.3 * period / dt).ceil() as usize;
    let sp = params(dt, walls_clamped_at_min_x(), vec![]);
    let (mut ts, mut us) = (vec![0.0], vec![0.0]);
    let stats = simulate(
        &mut p,
        &mut grid,
        &[mat],
        &sp,
        steps,
        |_| DVec3::ZERO,
        |_, t, p| {
            ts.push(t);
            us.push(end.iter().map(|&q| p.x[q].x - x0[q].x).sum::<f64>() / end.len() as f64);
        },
    );
    let measured = crate::fit::period_from_crossings(&crate::fit::zero_crossings(&ts, &us));
    finish(
        ("bar", sweep),
        (dx, dt, cfl, ppc_axis),
        (p.len(), steps),
        measured.filter(|_| stats.outcome == Outcome::Finished),
        Some(period),
        stats,
    )
}

/// Builds the run record; the error is |measured/exact − 1|.
fn finish(
    (case, sweep): (&str, &str),
    (dx, dt, cfl, ppc_axis): (f64, f64, f64, u32),
    (particles, steps): (usize, usize),
    measured: Option<f64>,
    exact: Option<f64>,
    stats: crate::runner::RunStats,
) -> ConvRun {
    let error = match (measured, exact) {
        (Some(m), Some(x)) => Some((m / x - 1.0).abs()),
        _ => None,
    };
    ConvRun {
        case: case.into(),
        sweep: sweep.into(),
        dx,
        dt,
        cfl,
        ppc: ppc_axis.pow(3),
        particles,
        steps,
        measured,
        exact,
        error,
        outcome: stats.outcome,
        wall_s: stats.wall_s,
        s_per_frame: seconds_per_frame(&stats, dt),
    }
}

const G: f64 = 9.81;

/// Block (0.1 × 0.04 × 0.04 m, E 1e5, ν 0.3, ρ 1000) on a 30° plane with μ = 0.3.
fn incline(dx: f64, cfl: f64, ppc_axis: u32, sweep: &str) -> ConvRun {
    let (theta, mu, t_end, t_fit) = (30f64.to_radians(), 0.3, 0.25, 0.05);
    let density = 1000.0;
    let mat = Material::fixed_corotated(1e5, 0.3);
    let tangent = DVec3::new(theta.cos(), -theta.sin(), 0.0);
    let normal = DVec3::new(theta.sin(), theta.cos(), 0.0);
    let size = DVec3::new(0.1, 0.04, 0.04);
    let pad = 5.0 * dx;
    let run_len = size.x + 0.5 * G * theta.sin() * t_end * t_end + 0.02;
    let drop = run_len * theta.sin() + pad;
    let origin = DVec3::new(pad + size.y * theta.sin(), drop, pad);
    let hi = DVec3::new(
        origin.x + run_len * theta.cos() + pad,
        drop + size.y / theta.cos() + pad,
        2.0 * pad + size.z,
    );
    let mut grid = Grid::new(DVec3::ZERO, hi, dx);
    let collider = PlaneCollider {
        point: origin,
        normal,
        condition: Condition::SEPARATE.with_friction(mu),
    };
    let local = Particles::sample_box(DVec3::ZERO, size, dx / f64::from(ppc_axis), density);
    let mut p = local.clone();
    for q in 0..p.len() {
        let l = local.x[q];
        p.x[q] = origin + tangent * l.x + normal * l.y + DVec3::Z * l.z;
    }
    let dt = cfl_dt(&mat, density, dx, cfl);
    let steps = (t_end / dt).ceil() as usize;
    let sp = params(
        dt,
        DomainWalls::uniform(Condition::SEPARATE),
        vec![collider],
    );
    let (mut ts, mut vs) = (Vec::new(), Vec::new());
    let gravity = |_| DVec3::new(0.0, -G, 0.0);
    let stats = simulate(&mut p, &mut grid, &[mat], &sp, steps, gravity, |_, t, p| {
        if t >= t_fit {
            ts.push(t);
            vs.push(p.momentum().dot(tangent) / p.total_mass());
        }
    });
    let measured = (stats.outcome == Outcome::Finished).then(|| slope(&ts, &vs));
    let exact = G * (theta.sin() - mu * theta.cos());
    finish(
        ("incline", sweep),
        (dx, dt, cfl, ppc_axis),
        (p.len(), steps),
        measured,
        Some(exact),
        stats,
    )
}

/// Least-squares slope of y against x.
fn slope(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

/// Cantilever L = 0.5, h = b = 0.1, E 1e4, ν 0, ρ 1, g 1 (tip deflection ≈ 1e-3 m,
/// 0.2% of L: small deflection), `cells` cells across the thickness.
fn cantilever(cells: u32, cfl: f64, ppc_axis: u32, sweep: &str) -> ConvRun {
    let (len, h, e, nu, rho, g) = (0.5f64, 0.1f64, 1e4f64, 0.0f64, 1.0f64, 1.0f64);
    let dx = h / f64::from(cells);
    let mat = Material::fixed_corotated(e, nu);
    let margin = 2.0 * dx;
    let xc = (BAND - 1.0) * dx;
    let side = h + 2.0 * (margin + BAND * dx);
    let hi = DVec3::new(xc + len + margin + BAND * dx, side, side);
    let mut grid = Grid::new(DVec3::ZERO, hi, dx);
    let y0 = BAND * dx + margin;
    let spacing = dx / f64::from(ppc_axis);
    let mut p = Particles::sample_box(
        DVec3::new(xc - dx, y0, y0),
        DVec3::new(xc + len, y0 + h, y0 + h),
        spacing,
        rho,
    );
    let x0 = p.x.clone();
    let tip: Vec<usize> = (0..p.len())
        .filter(|&q| x0[q].x > xc + len - spacing)
        .collect();
    // First bending mode ω₁ = 1.875² sqrt(EI/(ρA L⁴)), I/A = h²/12.
    let omega = 1.875f64.powi(2) * (e * h * h / (12.0 * rho * len.powi(4))).sqrt();
    let period = 2.0 * PI / omega;
    let (ramp, window) = (2.0 * period, 2.0 * period);
    let dt = cfl_dt(&mat, rho, dx, cfl);
    let steps = ((ramp + window) / dt).ceil() as usize;
    let sp = params(dt, walls_clamped_at_min_x(), vec![]);
    let gravity = move |t: f64| DVec3::new(0.0, -g * (t / ramp).min(1.0), 0.0);
    let (mut sum, mut count) = (0.0, 0usize);
    let stats = simulate(&mut p, &mut grid, &[mat], &sp, steps, gravity, |_, t, p| {
        if t > ramp {
            sum += tip.iter().map(|&q| x0[q].y - p.x[q].y).sum::<f64>() / tip.len() as f64;
            count += 1;
        }
    });
    let measured = (stats.outcome == Outcome::Finished && count > 0).then(|| sum / count as f64);
    let euler_bernoulli = 3.0 * rho * g * len.powi(4) / (2.0 * e * h * h);
    let exact = euler_bernoulli * (1.0 + 0.8 * (1.0 + nu) * (h / len).powi(2));
    finish(
        ("cantilever", sweep),
        (dx, dt, cfl, ppc_axis),
        (p.len(), steps),
        measured,
        Some(exact),
        stats,
    )
}

/// The fracture scene, as `scenes/fracture.json` (E 2000, ν 0.4, α₀ −0.01, β 1, ξ 2,
/// M 2.36, `continuous` k = 2, ρ 2, 12 m/s onto a sticky ground; radius 0.1 instead of
/// 0.12); the particles at t = 0.03 s (about 0.025 s after impact).
fn fracture_run(dx: f64) -> (Particles, crate::runner::RunStats, f64) {
    let material = Material::nacc(
        NaccParams {
            e: 2000.0,
            nu: 0.4,
            alpha0: -0.01,
            beta: 1.0,
            xi: 2.0,
            m_slope: 2.36,
        },
        Case3Variant::Continuous { k: 2.0 },
    );
    let (radius, speed, t_end) = (0.1, 12.0, 0.03);
    let center = DVec3::new(0.3, 0.1 + radius + 0.06, 0.3);
    let mut p = Particles::sample_sphere(center, radius, dx / 2.0, 2.0);
    p.set_material(0, &material);
    p.v.iter_mut()
        .for_each(|v| *v = DVec3::new(0.0, -speed, 0.0));
    let mut grid = Grid::new(DVec3::ZERO, DVec3::new(0.6, 0.45, 0.6), dx);
    let dt = cfl_dt(&material, 2.0, dx, 0.4);
    let steps = (t_end / dt).round() as usize;
    let dt = t_end / steps as f64;
    let sp = StepParams::sticky_ground(dt, DVec3::ZERO);
    let gravity = |_| DVec3::new(0.0, -9.8, 0.0);
    let stats = simulate(
        &mut p,
        &mut grid,
        &[material],
        &sp,
        steps,
        gravity,
        |_, _, _| {},
    );
    (p, stats, dt)
}

const FRACTURE_RADIUS: f64 = 0.1;

/// Runs at several Δx against a finely resolved one (Δx 0.01).
fn fracture_sweep(quick: bool) -> Vec<ConvRun> {
    let (fine_dx, coarse): (f64, &[f64]) = if quick {
        (0.025, &[0.05])
    } else {
        (0.007, &[0.04, 0.028, 0.02, 0.014, 0.01])
    };
    let (fine, _, _) = fracture_run(fine_dx);
    let fine_damaged = damaged_fraction(&fine);
    coarse
        .iter()
        .map(|&dx| {
            let (p, stats, dt) = fracture_run(dx);
            let error = (stats.outcome == Outcome::Finished)
                .then(|| chamfer(&p.x, &fine.x) / FRACTURE_RADIUS);
            ConvRun {
                case: "fracture".into(),
                sweep: "dx".into(),
                dx,
                dt,
                cfl: 0.4,
                ppc: 8,
                particles: p.len(),
                steps: stats.steps,
                measured: Some(damaged_fraction(&p)),
                exact: Some(fine_damaged),
                error,
                outcome: stats.outcome,
                wall_s: stats.wall_s,
                s_per_frame: seconds_per_frame(&stats, dt),
            }
        })
        .collect()
}

/// Mass fraction with α ≥ 0 (cohesion at the floor ε₀ κ: the material has fractured).
/// Reported next to the Chamfer error as a second, coarser view of the same runs.
pub fn damaged_fraction(p: &Particles) -> f64 {
    // fold from +0.0: an empty f64 sum is −0.0.
    let broken = (0..p.len())
        .filter(|&q| p.alpha[q] >= 0.0)
        .fold(0.0, |acc, q| acc + p.mass[q]);
    broken / p.total_mass()
}

/// Symmetric mean nearest-neighbour distance between two point sets (Chamfer): the mean
/// over `a` of the distance to the nearest point of `b`, plus the same from `b` to `a`,
/// halved. Resolution independent, so runs of different particle counts compare.
pub fn chamfer(a: &[DVec3], b: &[DVec3]) -> f64 {
    0.5 * (mean_nearest(a, b) + mean_nearest(b, a))
}

fn mean_nearest(from: &[DVec3], to: &[DVec3]) -> f64 {
    use kiddo::immutable::float::kdtree::ImmutableKdTree;
    use kiddo::SquaredEuclidean;
    use rayon::prelude::*;
    let coords: Vec<[f64; 3]> = to.iter().map(|x| x.to_array()).collect();
    let tree: ImmutableKdTree<f64, u32, 3, 32> = ImmutableKdTree::new_from_slice(&coords);
    let sum: f64 = from
        .par_iter()
        .map(|x| {
            tree.nearest_one::<SquaredEuclidean>(&x.to_array())
                .distance
                .sqrt()
        })
        .sum();
    sum / from.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chamfer_of_shifted_sets() {
        let a: Vec<DVec3> = (0..10).map(|i| DVec3::X * i as f64).collect();
        let b: Vec<DVec3> = a.iter().map(|x| *x + DVec3::Y * 0.5).collect();
        assert!((chamfer(&a, &b) - 0.5).abs() < 1e-12);
        assert_eq!(chamfer(&a, &a), 0.0);
    }

    #[test]
    fn orders_are_fitted_per_case_from_dx_sweeps() {
        let run = |case: &str, sweep: &str, dx: f64, err: f64| ConvRun {
            case: case.into(),
            sweep: sweep.into(),
            dx,
            dt: 1e-3,
            cfl: 0.4,
            ppc: 8,
            particles: 10,
            steps: 10,
            measured: None,
            exact: None,
            error: Some(err),
            outcome: Outcome::Finished,
            wall_s: 1.0,
            s_per_frame: 1.0,
        };
        let runs = vec![
            run("bar", "dx", 0.1, 0.01),
            run("bar", "dx", 0.05, 0.0025),
            run("bar", "dt", 0.05, 0.5),
            run("beam", "dx", 0.1, 0.1),
            run("beam", "dx", 0.05, 0.05),
        ];
        let fits = fit_orders(&runs);
        assert_eq!(fits.len(), 2);
        assert!((fits[0].order - 2.0).abs() < 1e-9 && fits[0].points == 2);
        assert!((fits[1].order - 1.0).abs() < 1e-9);
    }
}
