//! Non-Associated Cam-Clay (NACC) plasticity of CD-MPM (docs/method.md §4) on top of the Borden
//! Neo-Hookean elasticity (docs/method.md §3), as a pure f64 oracle for the f32 WGSL kernel.
//!
//! Everything happens in principal space of the trial elastic gradient
//! `F_tr = U diag(σ) Vᵀ` ([`svd3`]):
//!
//! * J = σ₁σ₂σ₃, b̄ = J^(−2/3) σ² (a 3-vector with det = 1), p = κ/2 (1 − J²) (positive in
//!   compression), s = μ dev(b̄), q = sqrt(3/2) ‖s‖ ([`principal_state`]);
//! * cohesion p0 = κ (ε₀ + sinh(ξ max(−α, 0))) ([`NaccParams::p0`]);
//! * yield y(p, q) = (1 + 2β) q² + M² (p + β p0)(p − p0) ([`YieldEllipse::y`]);
//! * the return mapping of (p, q) ([`project_pq`]): elastic, the two tips, and the three
//!   case-3 variants of [`Case3Variant`];
//! * back to F ([`return_map`]): J_new = J_E(p_new) = sqrt(1 − 2 p_new/κ),
//!   s_new = s q_new/q_tr, b̄_new = s_new/μ + c (1,1,1) with **det b̄_new = 1** (a Newton
//!   solve for c, [`solve_b_bar`]; not the reference code's trace-keeping choice, which
//!   drifts off the yield surface), σ_new = J_new^(1/3) sqrt(b̄_new), F_new = U diag(σ_new) Vᵀ;
//! * hardening α ← α + ln(J_tr / J_new) on every plastic return, with p0 taken from the α
//!   at the start of the step.
//!
//! In the (u, q) plane with u = p − p_c the yield surface is the ellipse
//! u²/a² + q²/b² = 1, with centre p_c = (1 − β) p0/2, half width a = (1 + β) p0/2 = L_p
//! and half height b = M a / sqrt(1 + 2β), because (p + βp0)(p − p0) = u² − a²
//! ([`YieldEllipse`]). The GPU evaluates the same formulas in f32: it should compare y
//! against the scale M² a² (see [`YieldEllipse::scale`]) rather than against 0 exactly.

use glam::{DMat3, DVec3};

use crate::sim::model::elasticity::Lame;
use crate::sim::svd::svd3;

/// The floor ε₀ of the cohesion p0 = κ (ε₀ + sinh(…)) (docs/method.md §4, as in the reference code).
pub const EPS0: f64 = 1e-5;

/// Largest argument of the sinh in p0. sinh(20) ≈ 2.4e8, so p0 ≤ κ (ε₀ + 2.4e8) and the
/// terms of y stay below f32's 3.4e38 for κ up to ~1e10 (docs/method.md §4: "clamp the sinh argument
/// against f32 overflow"). Reaching it needs α ≤ −20/ξ (plastic volume ratio e^(−20/ξ),
/// 4.5e-5 for ξ = 2), and p0 is then far beyond the reachable pressures (p < κ/2 in
/// compression), so the clamp changes nothing physical.
pub const SINH_ARG_MAX: f64 = 20.0;

/// Singular values of the trial F are clamped to at least this before evaluating J, p, q
/// (docs/method.md §4: "clamp σ away from 0"). This also maps an inverted trial state (σ₃ < 0, see
/// [`svd3`]) to a strongly compressed, non-inverted one, which the return mapping then
/// treats as compression (it lands on the upper tip when p0 < κ/2; see [`return_map`] for
/// the elastic case).
pub const SIGMA_MIN: f64 = 1e-4;

/// Friction-angle form of the critical-state slope: M = 6 sin φ / (3 − sin φ) (docs/method.md §4),
/// φ in radians.
pub fn m_from_friction_angle(phi: f64) -> f64 {
    let s = phi.sin();
    6.0 * s / (3.0 - s)
}

/// NACC material parameters (docs/method.md §4); density lives with the particle, not here.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NaccParams {
    /// Young's modulus E.
    pub e: f64,
    /// Poisson ratio ν.
    pub nu: f64,
    /// Initial hardening state α₀ (< 0: cohesive).
    pub alpha0: f64,
    /// Tensile/compressive strength ratio β.
    pub beta: f64,
    /// Hardening coefficient ξ.
    pub xi: f64,
    /// Slope M of the critical-state line.
    pub m_slope: f64,
}

impl NaccParams {
    /// Lamé parameters from (E, ν) (docs/method.md §3).
    pub fn lame(&self) -> Lame {
        Lame::from_young_poisson(self.e, self.nu)
    }

    /// Bulk modulus κ.
    pub fn kappa(&self) -> f64 {
        self.lame().kappa()
    }

    /// Shear modulus μ.
    pub fn mu(&self) -> f64 {
        self.lame().mu
    }

    /// Cohesion p0(α) = κ (ε₀ + sinh(ξ max(−α, 0))), sinh argument clamped at
    /// [`SINH_ARG_MAX`] (docs/method.md §4).
    pub fn p0(&self, alpha: f64) -> f64 {
        let arg = (self.xi * (-alpha).max(0.0)).min(SINH_ARG_MAX);
        self.kappa() * (EPS0 + arg.sinh())
    }

    /// The yield ellipse for hardening state α.
    pub fn ellipse(&self, alpha: f64) -> YieldEllipse {
        YieldEllipse {
            p0: self.p0(alpha),
            beta: self.beta,
            m_slope: self.m_slope,
        }
    }
}

/// The yield surface y(p, q) = 0 for one p0 (docs/method.md §4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct YieldEllipse {
    pub p0: f64,
    pub beta: f64,
    pub m_slope: f64,
}

impl YieldEllipse {
    /// y(p, q) = (1 + 2β) q² + M² (p + β p0)(p − p0); > 0 outside.
    pub fn y(&self, p: f64, q: f64) -> f64 {
        let m2 = self.m_slope * self.m_slope;
        (1.0 + 2.0 * self.beta) * q * q + m2 * (p + self.beta * self.p0) * (p - self.p0)
    }

    /// Centre p_c = (1 − β) p0 / 2.
    pub fn center(&self) -> f64 {
        0.5 * (1.0 - self.beta) * self.p0
    }

    /// Half width a = L_p = p0 − p_c = (1 + β) p0 / 2.
    pub fn half_width(&self) -> f64 {
        0.5 * (1.0 + self.beta) * self.p0
    }

    /// Half height b = M a / sqrt(1 + 2β) (the largest q on the surface).
    pub fn half_height(&self) -> f64 {
        self.m_slope * self.half_width() / (1.0 + 2.0 * self.beta).sqrt()
    }

    /// The top of the ellipse (p_c, b) = ((1 − β)p0/2, M(1 + β)p0 / (2 sqrt(1 + 2β))).
    pub fn top(&self) -> (f64, f64) {
        (self.center(), self.half_height())
    }

    /// Scale of y's terms, M² a² (= −y at the centre), for relative tolerances.
    pub fn scale(&self) -> f64 {
        let ma = self.m_slope * self.half_width();
        ma * ma
    }

    /// q on the surface at pressure p ∈ [−β p0, p0]: M sqrt((p + βp0)(p0 − p) / (1 + 2β)).
    pub fn q_on_surface(&self, p: f64) -> f64 {
        let v = (p + self.beta * self.p0) * (self.p0 - p) / (1.0 + 2.0 * self.beta);
        self.m_slope * v.max(0.0).sqrt()
    }
}

/// The case-3 (interior) return mappings of docs/method.md §4, selectable per material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Case3Variant {
    /// Original CD-MPM: towards the centre (p_c, 0); discontinuous at the right tip.
    Center,
    /// Pseudo-centre p*_c = p_c + φ_k (p_tr − p_c), φ_k = |(p_tr − p_c)/L_p|^k; continuous
    /// for every finite k > 0; k → ∞ recovers `Center`.
    Continuous { k: f64 },
    /// Euclidean closest point of the ellipse in (p, q) (normal return), by bisection.
    ClosestPoint,
}

/// A case-3 return mapping by name: what the scene file's `return_mapping`, the command
/// line's `--shatter-mapping`, the shatter study and the GPU's `NACC_VARIANT_*` code
/// (`sim::gpu::codes`) all name. [`ReturnMapping::variant`] adds the `continuous` exponent.
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Hash,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum ReturnMapping {
    Center,
    Continuous,
    ClosestPoint,
}

impl ReturnMapping {
    /// Every mapping, in GPU code order.
    pub const ALL: [ReturnMapping; 3] = [
        ReturnMapping::Center,
        ReturnMapping::Continuous,
        ReturnMapping::ClosestPoint,
    ];

    /// The name in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ReturnMapping::Center => "center",
            ReturnMapping::Continuous => "continuous",
            ReturnMapping::ClosestPoint => "closest_point",
        }
    }

    /// The mapping of a name.
    pub fn from_name(name: &str) -> Option<ReturnMapping> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }

    /// The variant, with exponent `k` for `continuous`.
    pub fn variant(self, k: f64) -> Case3Variant {
        match self {
            ReturnMapping::Center => Case3Variant::Center,
            ReturnMapping::Continuous => Case3Variant::Continuous { k },
            ReturnMapping::ClosestPoint => Case3Variant::ClosestPoint,
        }
    }
}

impl std::fmt::Display for ReturnMapping {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl Case3Variant {
    /// Its mapping by name.
    pub fn mapping(&self) -> ReturnMapping {
        match self {
            Case3Variant::Center => ReturnMapping::Center,
            Case3Variant::Continuous { .. } => ReturnMapping::Continuous,
            Case3Variant::ClosestPoint => ReturnMapping::ClosestPoint,
        }
    }
}

/// Which row of docs/method.md §4's return-mapping table applied.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReturnCase {
    /// y_tr ≤ 0: unchanged.
    Elastic,
    /// Case 1: y_tr > 0 and p_tr > p0 → (p0, 0).
    UpperTip,
    /// Case 2: y_tr > 0 and p_tr < −β p0 → (−β p0, 0).
    LowerTip,
    /// Case 3: y_tr > 0 and −β p0 ≤ p_tr ≤ p0 → the chosen [`Case3Variant`].
    Interior,
}

/// Intersection of the segment from (p_start, 0) (inside the ellipse) to (p_tr, q_tr)
/// (outside) with y = 0 (docs/method.md §4, `center` and `continuous`). In u = p − p_c the segment is
/// (u* + t d, t q_tr) and y(t) = A t² + B t + C with C = M²(u*² − a²) ≤ 0 < A, so the root
/// in (0, 1] is unique; it is taken in the cancellation-free form.
pub fn segment_intersection(ell: &YieldEllipse, p_start: f64, p_tr: f64, q_tr: f64) -> (f64, f64) {
    let m2 = ell.m_slope * ell.m_slope;
    let a = ell.half_width();
    let u0 = p_start - ell.center();
    let d = p_tr - p_start;
    let qa = (1.0 + 2.0 * ell.beta) * q_tr * q_tr + m2 * d * d;
    let qb = 2.0 * m2 * u0 * d;
    let qc = (m2 * (u0 * u0 - a * a)).min(0.0);
    if qa <= 0.0 {
        return (p_start, 0.0);
    }
    let root = (qb * qb - 4.0 * qa * qc).max(0.0).sqrt();
    let t = if qb >= 0.0 {
        if qb + root > 0.0 {
            -2.0 * qc / (qb + root)
        } else {
            0.0
        }
    } else {
        (root - qb) / (2.0 * qa)
    };
    let t = t.clamp(0.0, 1.0);
    (p_start + t * d, t * q_tr)
}

/// `center` (docs/method.md §4): towards (p_c, 0).
pub fn project_center(ell: &YieldEllipse, p_tr: f64, q_tr: f64) -> (f64, f64) {
    segment_intersection(ell, ell.center(), p_tr, q_tr)
}

/// `continuous{k}` (docs/method.md §4): towards the pseudo-centre p*_c = p_c + φ_k (p_tr − p_c),
/// φ_k = |(p_tr − p_c)/L_p|^k clamped to [0, 1], L_p = p0 − p_c.
pub fn project_continuous(ell: &YieldEllipse, p_tr: f64, q_tr: f64, k: f64) -> (f64, f64) {
    let pc = ell.center();
    let phi = ((p_tr - pc) / ell.half_width()).abs().powf(k).min(1.0);
    segment_intersection(ell, pc + phi * (p_tr - pc), p_tr, q_tr)
}

/// Most bisection steps of the ellipse projection; f64 needs ~60 (it stops when the
/// bracket can no longer shrink), an f32 kernel ~30.
const BISECTION_STEPS: usize = 200;

/// `closest_point` (docs/method.md §4): the point of the ellipse nearest to (p_tr, q_tr), for a trial
/// point outside it. The normal return (p, q) = (p_tr, q_tr) − Δγ ∇y gives, in units of
/// the half width a, x_i = e_i² z_i / (t + e_i²) with (e₀, e₁) = (1, b/a) and z the trial
/// point, t = 2 M² a² Δγ ≥ 0 the root of G(t) = Σ (e_i z_i / (t + e_i²))² − 1. G decreases
/// monotonically on t ≥ 0 and G(0) > 0 outside, so bisection on
/// [0, sqrt(Σ e_i² z_i²) − min e_i²] always converges (no unguarded Newton).
pub fn project_closest_point(ell: &YieldEllipse, p_tr: f64, q_tr: f64) -> (f64, f64) {
    let a = ell.half_width();
    let u = p_tr - ell.center();
    let z = [u.abs() / a, q_tr.abs() / a];
    let e2 = [1.0, (ell.half_height() / a).powi(2)];
    let g = |t: f64| -> f64 {
        let x0 = z[0] / (t + e2[0]);
        let x1 = z[1] / (t + e2[1]);
        e2[0] * x0 * x0 + e2[1] * x1 * x1 - 1.0
    };
    let (mut lo, mut hi) = (0.0f64, 0.0f64);
    let reach = (e2[0] * z[0] * z[0] + e2[1] * z[1] * z[1]).sqrt();
    if g(0.0) > 0.0 {
        hi = (reach - e2[0].min(e2[1])).max(0.0);
    }
    for _ in 0..BISECTION_STEPS {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if g(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let t = 0.5 * (lo + hi);
    let x0 = e2[0] * z[0] / (t + e2[0]);
    let x1 = e2[1] * z[1] / (t + e2[1]);
    (ell.center() + u.signum() * x0 * a, q_tr.signum() * x1 * a)
}

/// The return mapping R: (p_tr, q_tr) → (p_new, q_new) of docs/method.md §4's table.
pub fn project_pq(
    ell: &YieldEllipse,
    p_tr: f64,
    q_tr: f64,
    variant: Case3Variant,
) -> (f64, f64, ReturnCase) {
    if ell.y(p_tr, q_tr) <= 0.0 {
        return (p_tr, q_tr, ReturnCase::Elastic);
    }
    if p_tr > ell.p0 {
        return (ell.p0, 0.0, ReturnCase::UpperTip);
    }
    if p_tr < -ell.beta * ell.p0 {
        return (-ell.beta * ell.p0, 0.0, ReturnCase::LowerTip);
    }
    let (p, q) = match variant {
        Case3Variant::Center => project_center(ell, p_tr, q_tr),
        Case3Variant::Continuous { k } => project_continuous(ell, p_tr, q_tr, k),
        Case3Variant::ClosestPoint => project_closest_point(ell, p_tr, q_tr),
    };
    (p, q, ReturnCase::Interior)
}

/// Principal-space quantities of an elastic state (docs/method.md §4).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrincipalState {
    /// J = σ₁σ₂σ₃.
    pub j: f64,
    /// b̄ = J^(−2/3) σ² (det b̄ = 1).
    pub b_bar: DVec3,
    /// p = κ/2 (1 − J²).
    pub p: f64,
    /// s = μ dev(b̄).
    pub s: DVec3,
    /// q = sqrt(3/2) ‖s‖.
    pub q: f64,
}

/// Mean of a 3-vector's components.
fn mean(v: DVec3) -> f64 {
    (v.x + v.y + v.z) / 3.0
}

/// J, b̄, p, s, q of principal stretches σ (all > 0) (docs/method.md §4).
pub fn principal_state(sigma: DVec3, kappa: f64, mu: f64) -> PrincipalState {
    let j = sigma.x * sigma.y * sigma.z;
    let b_bar = sigma * sigma * j.powf(-2.0 / 3.0);
    let s = (b_bar - DVec3::splat(mean(b_bar))) * mu;
    PrincipalState {
        j,
        b_bar,
        p: 0.5 * kappa * (1.0 - j * j),
        s,
        q: (1.5f64).sqrt() * s.length(),
    }
}

/// Inverse of p(J): J_E(p) = sqrt(1 − 2p/κ) (docs/method.md §4). For p ≥ κ/2 (only reachable when
/// p0 ≥ κ/2 after extreme hardening) the radicand is floored so J stays ≥ SIGMA_MIN³.
pub fn j_from_pressure(p: f64, kappa: f64) -> f64 {
    let floor = SIGMA_MIN.powi(6);
    (1.0 - 2.0 * p / kappa).max(floor).sqrt()
}

/// Most Newton steps of [`solve_b_bar`]; f64 takes ≤ 6 in practice.
const NEWTON_STEPS: usize = 60;

/// b̄ = d + c (1,1,1) with det b̄ = 1, for a deviatoric d (Σ d = 0) (docs/method.md §4's det = 1
/// choice). g(c) = Π(d_i + c) − 1 is increasing and convex for c > −min d, so Newton started
/// where g ≥ 0 converges monotonically from the right. The start is `c_start` (docs/method.md §4: the
/// trial mean(b̄)); g(c_start) ≥ 0 holds whenever d = λ d_tr with λ ∈ [0, 1], since
/// ln Π(c_tr + λ d_tr,i) is concave in λ, 0 at λ = 1 and 3 ln c_tr ≥ 0 (AM-GM) at λ = 0.
/// Any other start falls back to 1 − min d (every factor ≥ 1, so g ≥ 0).
pub fn solve_b_bar(d: DVec3, c_start: f64) -> DVec3 {
    let g = |c: f64| (d.x + c) * (d.y + c) * (d.z + c) - 1.0;
    let mut c = c_start;
    if !(c + d.min_element() > 0.0 && g(c) >= 0.0) {
        c = 1.0 - d.min_element();
    }
    for _ in 0..NEWTON_STEPS {
        let (x, y, z) = (d.x + c, d.y + c, d.z + c);
        let dg = x * y + y * z + z * x;
        let step = g(c) / dg;
        c -= step;
        if step.abs() <= 1e-15 * c.abs() {
            break;
        }
    }
    d + DVec3::splat(c)
}

/// Principal stretches of the returned state (docs/method.md §4): J_new = J_E(p_new),
/// s_new = s q_new / q_tr, b̄_new from [`solve_b_bar`], σ_new = J_new^(1/3) sqrt(b̄_new).
pub fn stretches_from_pq(
    trial: &PrincipalState,
    p_new: f64,
    q_new: f64,
    kappa: f64,
    mu: f64,
) -> DVec3 {
    let ratio = if q_new > 0.0 && trial.q > 0.0 {
        q_new / trial.q
    } else {
        0.0
    };
    let d = trial.s * (ratio / mu);
    let b_bar = solve_b_bar(d, mean(trial.b_bar));
    let j_new = j_from_pressure(p_new, kappa);
    DVec3::new(b_bar.x.sqrt(), b_bar.y.sqrt(), b_bar.z.sqrt()) * j_new.cbrt()
}

/// Result of [`return_map`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlasticReturn {
    /// The projected elastic deformation gradient (= F_trial when elastic).
    pub f: DMat3,
    /// The updated hardening state.
    pub alpha: f64,
    /// Which row of the return-mapping table applied.
    pub case: ReturnCase,
    /// Trial (p, q) after the σ clamp.
    pub p_trial: f64,
    pub q_trial: f64,
    /// Returned (p, q) (= trial when elastic).
    pub p: f64,
    pub q: f64,
}

/// NACC return mapping of a trial elastic gradient (docs/method.md §4), with p0 from the α at the
/// start of the step and hardening α ← α + ln(J_tr / J_new) when y_tr > 0.
///
/// Elastic trial states come back unchanged, except that a state with some σ below
/// [`SIGMA_MIN`] (nearly flat or inverted) comes back as `U diag(max(σ, SIGMA_MIN)) Vᵀ`: a
/// material whose cap p0 exceeds κ/2 (e.g. the jelly's α₀ = −0.5, ξ = 2) never yields in
/// compression, and without this an inverted F would reach the Neo-Hookean stress with
/// J ≤ 0 (J^(−2/3) is NaN there). So every F this returns has det F ≥ SIGMA_MIN³ > 0.
pub fn return_map(
    f_trial: DMat3,
    alpha: f64,
    params: &NaccParams,
    variant: Case3Variant,
) -> PlasticReturn {
    let (kappa, mu) = (params.kappa(), params.mu());
    let ell = params.ellipse(alpha);
    let svd = svd3(f_trial);
    let sigma = svd.sigma.max(DVec3::splat(SIGMA_MIN));
    let trial = principal_state(sigma, kappa, mu);
    let (p, q, case) = project_pq(&ell, trial.p, trial.q, variant);
    let mut out = PlasticReturn {
        f: f_trial,
        alpha,
        case,
        p_trial: trial.p,
        q_trial: trial.q,
        p,
        q,
    };
    if case != ReturnCase::Elastic {
        let sigma_new = stretches_from_pq(&trial, p, q, kappa, mu);
        out.f = svd.u * DMat3::from_diagonal(sigma_new) * svd.v.transpose();
        out.alpha = alpha + (trial.j / j_from_pressure(p, kappa)).ln();
    } else if sigma != svd.sigma {
        out.f = svd.u * DMat3::from_diagonal(sigma) * svd.v.transpose();
    }
    out
}

#[cfg(test)]
mod tests;
