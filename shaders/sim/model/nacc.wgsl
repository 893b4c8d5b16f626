// Non-Associated Cam-Clay return mapping of CD-MPM (docs/method.md §4) on top of the Borden
// Neo-Hookean elasticity, in f32: the WGSL twin of src/sim/model/nacc/oracle.rs (same constants, same
// case table, same three case-3 variants, same det b̄ = 1 choice, same hardening, same σ
// clamp). Two f32-specific forms, same results in exact arithmetic: the det b̄ = 1 root is
// solved without cancellation (nacc_solve_b_bar), and p0's sinh is evaluated without it
// (sim_sinh). Needs math.wgsl and svd.wgsl; nacc_material needs SimMaterial (material.wgsl).
//
// Principal space of the trial F_tr = U diag(σ) Vᵀ (svd3), σ clamped to ≥ NACC_SIGMA_MIN:
// J = σ₁σ₂σ₃, b̄ = J^(−2/3) σ², p = κ/2 (1 − J²), s = μ dev(b̄), q = sqrt(3/2) ‖s‖;
// p0 = κ (ε₀ + sinh(min(ξ max(−α, 0), 20))); y = (1 + 2β) q² + M² (p + βp0)(p − p0).
// In u = p − p_c the surface is the ellipse u²/a² + q²/b² = 1, p_c = (1 − β) p0/2,
// a = (1 + β) p0/2, b = M a / sqrt(1 + 2β). The projections work in units of a, so no
// intermediate overflows for any p0 the sinh clamp allows.
//
// f32 resolution: p = κ/2 (1 − J²) resolves only ~1e-7 κ (J carries a few ulp from the SVD),
// so near the cohesion floor (p0 = 1e-5 κ) p is good to ~1% of p0. Compare and judge
// results on the scale of κ, not p0. The case test y_tr ≤ 0 is evaluated like the oracle's
// (sign of y), so only trial states within round-off of a boundary can be classified
// differently from the f64 oracle.

// The cohesion floor ε₀ of p0 (`nacc::EPS0`).
const NACC_EPS0: f32 = 1e-5;
// Largest sinh argument in p0 (`nacc::SINH_ARG_MAX`).
const NACC_SINH_ARG_MAX: f32 = 20.0;
// Trial singular values are clamped to at least this (`nacc::SIGMA_MIN`).
const NACC_SIGMA_MIN: f32 = 1e-4;
// Floor of the radicand of J_E(p) = sqrt(1 − 2p/κ): SIGMA_MIN⁶ (`nacc::j_from_pressure`).
const NACC_JE_RADICAND_MIN: f32 = 1e-24;

// The case-3 variants NACC_VARIANT_{CENTER,CONTINUOUS,CLOSEST_POINT} (`NaccMaterial.variant`,
// `nacc::Case3Variant`) and the rows of the return-mapping table NACC_{ELASTIC,UPPER_TIP,
// LOWER_TIP,INTERIOR} (`nacc::ReturnCase`) are generated from the Rust types
// (src/sim/gpu/codes.rs) and precede this file.

// Most bisection steps of the closest-point projection. It stops once the bracket is
// below 2⁻²³ (t + min e²) (x is then exact to f32), which takes log2(width/(ε min e²))
// steps: ≤ ~45 even for trial points 1e6 half-widths away; tests/sim_wgsl.rs measured ≤ 27.
const NACC_BISECTION_STEPS: u32 = 64u;
// Most Newton steps of the det b̄ = 1 solve (nacc_solve_b_bar). tests/sim_wgsl.rs measured
// ≤ 6 (1.4 on average); the bound covers roots far below the start, where Newton on the
// cubic shrinks the distance by a factor ≥ 1.5 per step until it converges quadratically.
const NACC_NEWTON_STEPS: u32 = 40u;

// One NACC material as the kernels see it (mirrored by `splatter::sim::model::nacc::NaccMaterialGpu`,
// 32 bytes). κ and μ are computed on the host in f64 and rounded.
struct NaccMaterial {
    // bulk modulus κ = λ + 2μ/3
    kappa: f32,
    // shear modulus μ
    mu: f32,
    // tensile/compressive strength ratio β
    beta: f32,
    // hardening coefficient ξ
    xi: f32,
    // critical-state slope M
    m_slope: f32,
    // exponent k of the `continuous` variant (unused by the others)
    k: f32,
    // NACC_VARIANT_*
    variant: u32,
    // initial hardening state α₀ (a particle's damage: step/separation.wgsl)
    alpha0: f32,
}

// A (p, q) point and the table row that produced it.
struct NaccPq {
    p: f32,
    q: f32,
    case_id: u32,
}

// Principal-space quantities of an elastic state (`nacc::PrincipalState`).
struct NaccState {
    j: f32,
    b_bar: vec3<f32>,
    p: f32,
    s: vec3<f32>,
    q: f32,
}

// Result of nacc_return_map (`nacc::PlasticReturn`).
struct NaccReturn {
    // projected elastic gradient (= F_trial bit for bit when elastic and no σ was clamped)
    f: mat3x3<f32>,
    // updated hardening state
    alpha: f32,
    // NACC_ELASTIC, NACC_UPPER_TIP, NACC_LOWER_TIP or NACC_INTERIOR
    case_id: u32,
    // trial (p, q) after the σ clamp
    p_trial: f32,
    q_trial: f32,
    // returned (p, q) (= trial when elastic)
    p: f32,
    q: f32,
}

// Cohesion p0(α) = κ (ε₀ + sinh(ξ max(−α, 0))), argument clamped at NACC_SINH_ARG_MAX.
fn nacc_p0(alpha: f32, mat: NaccMaterial) -> f32 {
    let arg = min(mat.xi * max(-alpha, 0.0), NACC_SINH_ARG_MAX);
    return mat.kappa * (NACC_EPS0 + sim_sinh(arg));
}

// y(p, q) / a², a = (1 + β) p0 / 2: the sign of docs/method.md §4's yield function (> 0 outside),
// evaluated in the same factored form, scaled so that it cannot overflow.
fn nacc_yield_scaled(p: f32, q: f32, p0: f32, mat: NaccMaterial) -> f32 {
    let inv_a = 2.0 / ((1.0 + mat.beta) * p0);
    let qn = q * inv_a;
    return (1.0 + 2.0 * mat.beta) * qn * qn
        + (mat.m_slope * mat.m_slope) * ((p + mat.beta * p0) * inv_a) * ((p - p0) * inv_a);
}

// y(p, q) itself, unscaled (for diagnostics; may overflow f32 for p0 beyond ~1e18).
fn nacc_yield(p: f32, q: f32, p0: f32, mat: NaccMaterial) -> f32 {
    return (1.0 + 2.0 * mat.beta) * q * q + mat.m_slope * mat.m_slope * (p + mat.beta * p0) * (p - p0);
}

// Intersection of the segment from (p_start, 0) (inside the ellipse) to (p_tr, q_tr)
// (outside) with y = 0 (`nacc::segment_intersection`): in units of a and u = p − p_c the
// segment is (u* + t d, t q) and y(t) = A t² + B t + C with C ≤ 0 < A; the root in (0, 1]
// in its cancellation-free form.
fn nacc_segment_intersection(p_start: f32, p_tr: f32, q_tr: f32, p0: f32, mat: NaccMaterial) -> vec2<f32> {
    let m2 = mat.m_slope * mat.m_slope;
    let a = 0.5 * (1.0 + mat.beta) * p0;
    let pc = 0.5 * (1.0 - mat.beta) * p0;
    let u0 = (p_start - pc) / a;
    let d = (p_tr - p_start) / a;
    let qn = q_tr / a;
    let qa = (1.0 + 2.0 * mat.beta) * qn * qn + m2 * d * d;
    let qb = 2.0 * m2 * u0 * d;
    let qc = min(m2 * (u0 - 1.0) * (u0 + 1.0), 0.0);
    if qa <= 0.0 {
        return vec2<f32>(p_start, 0.0);
    }
    let root = sqrt(max(qb * qb - 4.0 * qa * qc, 0.0));
    var t: f32;
    if qb >= 0.0 {
        let den = qb + root;
        t = select(0.0, -2.0 * qc / den, den > 0.0);
    } else {
        t = (root - qb) / (2.0 * qa);
    }
    t = clamp(t, 0.0, 1.0);
    return vec2<f32>(p_start + t * (p_tr - p_start), t * q_tr);
}

// `center`: towards (p_c, 0).
fn nacc_project_center(p_tr: f32, q_tr: f32, p0: f32, mat: NaccMaterial) -> vec2<f32> {
    return nacc_segment_intersection(0.5 * (1.0 - mat.beta) * p0, p_tr, q_tr, p0, mat);
}

// `continuous{k}`: towards p*_c = p_c + φ_k (p_tr − p_c), φ_k = |(p_tr − p_c)/L_p|^k ≤ 1.
fn nacc_project_continuous(p_tr: f32, q_tr: f32, p0: f32, mat: NaccMaterial) -> vec2<f32> {
    let pc = 0.5 * (1.0 - mat.beta) * p0;
    let lp = 0.5 * (1.0 + mat.beta) * p0;
    let x = abs((p_tr - pc) / lp);
    let phi = min(select(pow(x, mat.k), 0.0, x <= 0.0), 1.0);
    return nacc_segment_intersection(pc + phi * (p_tr - pc), p_tr, q_tr, p0, mat);
}

// G(t) = Σ (e_i z_i / (t + e_i²))² − 1 of the closest-point projection, e = (1, e1).
fn nacc_closest_g(t: f32, z: vec2<f32>, e1sq: f32) -> f32 {
    let x0 = z.x / (t + 1.0);
    let x1 = z.y / (t + e1sq);
    return x0 * x0 + e1sq * x1 * x1 - 1.0;
}

// `closest_point`: the point of the ellipse nearest to (p_tr, q_tr) (normal return,
// `nacc::project_closest_point`). In units of a, x_i = e_i² z_i / (t + e_i²) with
// (e₀, e₁) = (1, b/a) and t ≥ 0 the root of the decreasing G; bisection on
// [0, sqrt(Σ e_i² z_i²) − min e_i²] (no unguarded Newton).
fn nacc_project_closest_point(p_tr: f32, q_tr: f32, p0: f32, mat: NaccMaterial) -> vec2<f32> {
    let a = 0.5 * (1.0 + mat.beta) * p0;
    let pc = 0.5 * (1.0 - mat.beta) * p0;
    let u = p_tr - pc;
    let z = vec2<f32>(abs(u) / a, abs(q_tr) / a);
    let e1sq = mat.m_slope * mat.m_slope / (1.0 + 2.0 * mat.beta);
    let emin = min(1.0, e1sq);
    var lo = 0.0;
    var hi = 0.0;
    if nacc_closest_g(0.0, z, e1sq) > 0.0 {
        hi = max(sqrt(z.x * z.x + e1sq * z.y * z.y) - emin, 0.0);
    }
    for (var i = 0u; i < NACC_BISECTION_STEPS; i++) {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi || hi - lo <= 1.1920929e-7 * (hi + emin) {
            break;
        }
        if nacc_closest_g(mid, z, e1sq) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let t = 0.5 * (lo + hi);
    let x0 = z.x / (t + 1.0);
    let x1 = e1sq * z.y / (t + e1sq);
    let su = select(-1.0, 1.0, u >= 0.0);
    let sq = select(-1.0, 1.0, q_tr >= 0.0);
    return vec2<f32>(pc + su * x0 * a, sq * x1 * a);
}

// The return mapping R: (p_tr, q_tr) → (p_new, q_new) of docs/method.md §4's table, for cohesion p0
// (from the α at the start of the step).
fn nacc_project_pq(p_tr: f32, q_tr: f32, p0: f32, mat: NaccMaterial) -> NaccPq {
    if nacc_yield_scaled(p_tr, q_tr, p0, mat) <= 0.0 {
        return NaccPq(p_tr, q_tr, NACC_ELASTIC);
    }
    if p_tr > p0 {
        return NaccPq(p0, 0.0, NACC_UPPER_TIP);
    }
    if p_tr < -mat.beta * p0 {
        return NaccPq(-mat.beta * p0, 0.0, NACC_LOWER_TIP);
    }
    var pq: vec2<f32>;
    if mat.variant == NACC_VARIANT_CLOSEST_POINT {
        pq = nacc_project_closest_point(p_tr, q_tr, p0, mat);
    } else if mat.variant == NACC_VARIANT_CONTINUOUS {
        pq = nacc_project_continuous(p_tr, q_tr, p0, mat);
    } else {
        pq = nacc_project_center(p_tr, q_tr, p0, mat);
    }
    return NaccPq(pq.x, pq.y, NACC_INTERIOR);
}

// J, b̄, p, s, q of principal stretches σ (all > 0).
fn nacc_principal_state(sigma: vec3<f32>, kappa: f32, mu: f32) -> NaccState {
    let j = sigma.x * sigma.y * sigma.z;
    let b_bar = sigma * sigma * pow(j, -2.0 / 3.0);
    let s = (b_bar - vec3<f32>((b_bar.x + b_bar.y + b_bar.z) / 3.0)) * mu;
    return NaccState(j, b_bar, 0.5 * kappa * (1.0 - j) * (1.0 + j), s, sqrt(1.5) * length(s));
}

// J_E(p) = sqrt(1 − 2p/κ), radicand floored at SIGMA_MIN⁶ (`nacc::j_from_pressure`).
fn nacc_j_from_pressure(p: f32, kappa: f32) -> f32 {
    return sqrt(max(1.0 - 2.0 * p / kappa, NACC_JE_RADICAND_MIN));
}

// The returned b̄: b̄_new = ratio·dev(b̄_tr) + c (1,1,1) with det b̄_new = 1 (docs/method.md §4's
// s_new/μ + c (1,1,1), s_new = ratio·s_tr; `nacc::solve_b_bar`, same root). Solved as
// b̄_new,i = ratio·b̄_tr,i + c′, c′ = c − ratio·mean(b̄_tr): since det b̄_tr = 1,
// g(c′) = Π(ratio b̄_tr,i + c′) − 1 has g(0) = ratio³ − 1 ≤ 0 and, by the weighted AM-GM
// inequality, g(1 − ratio) ≥ 0, so the root lies in [0, 1 − ratio] and every component is
// a sum of non-negative terms. (The oracle's form d + c cancels: for a strongly sheared
// state, q/μ ~ 1e3, b̄_min ~ 1e-6 is the difference of two numbers ~5e2 and is lost in
// f32.) Newton from c′ = 1 − ratio converges monotonically from the right (g is increasing
// and convex for c′ ≥ 0); it stops once |g| ≤ 1e-6 (one more step is taken), which bounds
// the relative error of every component, the smallest included, by about that.
fn nacc_solve_b_bar(b_tr: vec3<f32>, ratio: f32) -> vec3<f32> {
    let rb = ratio * b_tr;
    var c = 1.0 - ratio;
    for (var i = 0u; i < NACC_NEWTON_STEPS; i++) {
        let x = rb + vec3<f32>(c);
        let g = x.x * x.y * x.z - 1.0;
        c = max(c - g / (x.x * x.y + x.y * x.z + x.z * x.x), 0.0);
        if abs(g) <= 1e-6 {
            break;
        }
    }
    return rb + vec3<f32>(c);
}

// Principal stretches of the returned state: J_new = J_E(p_new), s_new = s q_new/q_tr,
// b̄_new = s_new/μ + c (1,1,1) with det b̄_new = 1, σ_new = J_new^(1/3) sqrt(b̄_new).
fn nacc_stretches_from_pq(trial: NaccState, p_new: f32, q_new: f32, kappa: f32) -> vec3<f32> {
    let ratio = select(0.0, q_new / trial.q, q_new > 0.0 && trial.q > 0.0);
    let b_bar = nacc_solve_b_bar(trial.b_bar, min(ratio, 1.0));
    let j_new = nacc_j_from_pressure(p_new, kappa);
    return sqrt(b_bar) * pow(j_new, 1.0 / 3.0);
}

// NACC return mapping of a trial elastic gradient, with p0 from the α at the start of the
// step and hardening α ← α + ln(J_tr / J_new) when y_tr > 0 (`nacc::return_map`). Elastic
// trial states come back unchanged, except that σ below NACC_SIGMA_MIN (nearly flat or
// inverted F) is clamped: every returned F has det F ≥ SIGMA_MIN³ > 0.
fn nacc_return_map(f_trial: mat3x3<f32>, alpha: f32, mat: NaccMaterial) -> NaccReturn {
    let d = svd3(f_trial);
    let sigma = max(d.sigma, vec3<f32>(NACC_SIGMA_MIN));
    let trial = nacc_principal_state(sigma, mat.kappa, mat.mu);
    let pq = nacc_project_pq(trial.p, trial.q, nacc_p0(alpha, mat), mat);
    var out = NaccReturn(f_trial, alpha, pq.case_id, trial.p, trial.q, pq.p, pq.q);
    if pq.case_id != NACC_ELASTIC {
        let sigma_new = nacc_stretches_from_pq(trial, pq.p, pq.q, mat.kappa);
        out.f = svd3_compose(d.u, sigma_new, d.v);
        out.alpha = alpha + log(trial.j / nacc_j_from_pressure(pq.p, mat.kappa));
    } else if any(sigma != d.sigma) {
        out.f = svd3_compose(d.u, sigma, d.v);
    }
    return out;
}

// The registry's side (sim::model::nacc): the law's parameters out of the material record,
// and its damage.

// params: β, ξ, M, k, the variant's code (bits), α₀ (`Nacc::gpu_params`).
fn nacc_material(m: SimMaterial) -> NaccMaterial {
    return NaccMaterial(m.kappa, m.mu, m.params[0], m.params[1], m.params[2], m.params[3],
                        bitcast<u32>(m.params[4]), m.params[5]);
}

// Damage of a particle with hardening state alpha and initial state alpha0 (`Nacc::damage`).
fn nacc_damage(alpha0: f32, alpha: f32) -> f32 {
    if alpha0 < 0.0 {
        return clamp((alpha - alpha0) / -alpha0, 0.0, 1.0);
    }
    return 1.0;
}
