//! The oracle against the ellipse's geometry and NACC's analytic behaviour.

use super::*;

fn params() -> NaccParams {
    NaccParams {
        e: 2000.0,
        nu: 0.38,
        alpha0: -0.04,
        beta: 1.0,
        xi: 2.0,
        m_slope: 2.36,
    }
}

#[test]
fn friction_angle() {
    assert!((m_from_friction_angle(30f64.to_radians()) - 1.2).abs() < 1e-12);
    // The paper's M = 2.36 is a friction angle of about 57.9°.
    let phi = (3.0 * 2.36 / (6.0 + 2.36f64)).asin();
    assert!((m_from_friction_angle(phi) - 2.36).abs() < 1e-12);
}

#[test]
fn cohesion_floor_and_clamp() {
    let p = params();
    let k = p.kappa();
    assert_eq!(p.p0(0.0), k * EPS0);
    assert_eq!(p.p0(0.7), k * EPS0);
    assert!((p.p0(-0.04) - k * (EPS0 + 0.08f64.sinh())).abs() < 1e-12 * k);
    let huge = p.p0(-1e9);
    assert!(huge.is_finite() && huge == k * (EPS0 + SINH_ARG_MAX.sinh()));
    // The largest term of y, M² p0², stays finite in f32.
    let term = (p.m_slope * huge) as f32;
    assert!((term * term).is_finite());
}

#[test]
fn ellipse_geometry() {
    let e = params().ellipse(-0.3);
    let (pc, b) = e.top();
    assert!(e.y(pc, b).abs() < 1e-12 * e.scale());
    assert!(e.y(e.p0, 0.0).abs() < 1e-12 * e.scale());
    assert!(e.y(-e.beta * e.p0, 0.0).abs() < 1e-12 * e.scale());
    assert!((e.y(pc, 0.0) + e.scale()).abs() < 1e-12 * e.scale());
    for i in 0..=100 {
        let p = -e.beta * e.p0 + (1.0 + e.beta) * e.p0 * i as f64 / 100.0;
        assert!(e.y(p, e.q_on_surface(p)).abs() < 1e-12 * e.scale());
    }
}

#[test]
fn pressure_inverse() {
    let k = params().kappa();
    for j in [0.2, 0.9, 1.0, 1.3, 4.0] {
        let p = 0.5 * k * (1.0 - j * j);
        assert!((j_from_pressure(p, k) - j).abs() < 1e-14);
    }
}

#[test]
fn tip_cases_and_elastic_case() {
    let e = params().ellipse(-0.1);
    let v = Case3Variant::Continuous { k: 2.0 };
    assert_eq!(
        project_pq(&e, 2.0 * e.p0, 1.0, v),
        (e.p0, 0.0, ReturnCase::UpperTip)
    );
    let lower = -e.beta * e.p0;
    assert_eq!(
        project_pq(&e, 3.0 * lower, 1.0, v),
        (lower, 0.0, ReturnCase::LowerTip)
    );
    let (p, q) = (e.center(), 0.5 * e.half_height());
    assert_eq!(project_pq(&e, p, q, v), (p, q, ReturnCase::Elastic));
}

/// Inverted or flat trial states come back with det F > 0, plastic or not (a tiny
/// inverted F is elastic for the jelly, whose cap p0 > κ/2 is out of reach).
#[test]
fn inverted_trial_states_are_repaired() {
    let flat = DMat3::from_diagonal(DVec3::new(1.0, 1.0, -0.9));
    let tiny = DMat3::from_diagonal(DVec3::new(5e-5, 5e-5, -5e-5));
    let jelly = NaccParams {
        nu: 0.45,
        alpha0: -0.5,
        ..params()
    };
    assert!(jelly.p0(jelly.alpha0) > 0.5 * jelly.kappa());
    let cases = [
        (params(), flat, ReturnCase::UpperTip),
        (params(), tiny, ReturnCase::UpperTip),
        (jelly, flat, ReturnCase::Interior),
        (jelly, tiny, ReturnCase::Elastic),
    ];
    for (mat, f, case) in cases {
        let out = return_map(f, mat.alpha0, &mat, Case3Variant::ClosestPoint);
        assert_eq!(out.case, case);
        assert!(out.f.determinant() >= SIGMA_MIN.powi(3) * (1.0 - 1e-9));
    }
}

#[test]
fn det_one_solve() {
    let d = DVec3::new(0.3, -0.5, 0.2);
    let b = solve_b_bar(d, 1.0);
    assert!((b.x * b.y * b.z - 1.0).abs() < 1e-14);
    assert!((b - d - DVec3::splat(b.x - d.x)).abs().max_element() < 1e-15);
    // Any start, even a bad one, converges.
    let b2 = solve_b_bar(d, -7.0);
    assert!((b2 - b).abs().max_element() < 1e-14);
    assert!(
        (solve_b_bar(DVec3::ZERO, 1.3) - DVec3::ONE)
            .abs()
            .max_element()
            < 1e-15
    );
}
