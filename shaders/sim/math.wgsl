// Small f32 helpers shared by the simulation modules under shaders/sim/ (concatenate this
// first: math.wgsl, bspline.wgsl, svd.wgsl, elasticity.wgsl, nacc.wgsl). Every name of the
// simulation modules carries its module's prefix (sim_, bspline_, svd_/polar, elastic_,
// nacc_) so they can sit next to shaders/common.wgsl and a kernel's own code.
//
// Mirrors: nothing in Rust needs these one-liners, except `sim_sinh`, whose f64 twin is
// `f64::sinh` in `NaccParams::p0` (src/sim/model/nacc/oracle.rs).

const SIM_IDENTITY3 = mat3x3<f32>(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(0.0, 0.0, 1.0));

// Finite (not NaN, not ±Inf), by the exponent bits: comparisons with NaN may be folded
// away by some drivers' compilers (llvmpipe's GL), bit tests cannot.
fn sim_is_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

fn sim_is_finite3(v: vec3<f32>) -> bool {
    return sim_is_finite(v.x) && sim_is_finite(v.y) && sim_is_finite(v.z);
}

fn sim_is_finite_mat3(m: mat3x3<f32>) -> bool {
    return sim_is_finite3(m[0]) && sim_is_finite3(m[1]) && sim_is_finite3(m[2]);
}

// diag(d) as a matrix.
fn sim_diag3(d: vec3<f32>) -> mat3x3<f32> {
    return mat3x3<f32>(vec3<f32>(d.x, 0.0, 0.0), vec3<f32>(0.0, d.y, 0.0), vec3<f32>(0.0, 0.0, d.z));
}

fn sim_trace3(m: mat3x3<f32>) -> f32 {
    return m[0].x + m[1].y + m[2].z;
}

// Largest |entry|.
fn sim_max_abs3(m: mat3x3<f32>) -> f32 {
    let c = max(max(abs(m[0]), abs(m[1])), abs(m[2]));
    return max(max(c.x, c.y), c.z);
}

// Exact power-of-two scaling for a magnitude m > 0: returns (2^k, 2^−k) with m·2^k in
// [1, 2) (in [2, 4) for m ≥ 2^127). (1, 1) for zero, denormal or non-finite m. Built from
// the exponent bits, so it needs neither frexp/ldexp nor a division.
fn sim_pow2_scale(m: f32) -> vec2<f32> {
    let e = i32((bitcast<u32>(m) >> 23u) & 0xffu);
    if e == 0 || e == 255 {
        return vec2<f32>(1.0, 1.0);
    }
    // 2^k has biased exponent 127 + k = 254 − e, kept in [1, 253] so that both 2^k and
    // 2^−k (biased exponent 254 − that) are normal numbers.
    let k = clamp(254 - e, 1, 253);
    return vec2<f32>(bitcast<f32>(u32(k) << 23u), bitcast<f32>(u32(254 - k) << 23u));
}

// sinh without the cancellation of (eˣ − e⁻ˣ)/2 near 0 (WGSL's builtin may evaluate it that
// way: relative error ~ε/|x| for small x): a Taylor polynomial to x⁹ for |x| < 1 (relative
// error < 3e-8 there), the exponential form beyond.
fn sim_sinh(x: f32) -> f32 {
    let ax = abs(x);
    let x2 = x * x;
    let series = x * (1.0 + x2 * (1.0 / 6.0 + x2 * (1.0 / 120.0 + x2 * (1.0 / 5040.0 + x2 * (1.0 / 362880.0)))));
    let e = exp(min(ax, 88.0));
    let big = 0.5 * (e - 1.0 / e);
    return select(select(-big, big, x >= 0.0), series, ax < 1.0);
}
