// 3×3 singular value decomposition and polar decomposition in f32 (docs/method.md §3, §4, §6): the
// WGSL twin of src/sim/svd.rs, same convention and same algorithm, f32 tolerances.
// Needs: sim/math.
//
// Convention: F = U diag(σ) Vᵀ with U, V proper rotations (det +1) and σ₁ ≥ σ₂ ≥ |σ₃|,
// σ₁, σ₂ ≥ 0; when det F < 0 the sign is pushed into σ₃ (σ₃ < 0 exactly when det F < 0, up
// to round-off for |σ₃| ≲ 1e-6 σ₁). R = U Vᵀ is then always a rotation (fixed corotated,
// SH frame).
//
// Algorithm:
// 0. scale F by a power of two (exact) so its largest entry is in [1, 2): no overflow or
//    underflow of the squared column lengths for any finite F;
// 1. one-sided (Hestenes) Jacobi on the columns of F: plane rotations on the right,
//    B ← B G, V ← V G, in cyclic sweeps over the pairs (0,1), (0,2), (1,2). A pair is left
//    alone when |b_p·b_q| ≤ max(1e-6 |b_p||b_q|, 2.5e-7 max(|b_p|², |b_q|²)) (relative
//    orthogonality to ~8ε, or a dot product at the round-off level of the longer column,
//    which a rotation could not improve: after rotating a short column against a long one
//    it carries an absolute error ~ε times the long one; dropping such a dot product costs
//    ≤ 2.5e-7 ‖F‖ in the reconstruction), or when a column is below 1e-15 in length
//    (round-off noise). At most SVD_MAX_SWEEPS = 6 sweeps, stopping after the first sweep
//    that rotated nothing; tests/sim_wgsl.rs measured at most 4 rotating sweeps (1.24 on
//    average) on ten kinds of random matrices (general, rotations, near-singular,
//    repeated σ, reflections, rank 1 and 2, zero), never reaching the bound;
// 2. the columns of B are sorted by length, descending (a swap negates one column of B and
//    of V: det V = +1 and F = B Vᵀ are kept);
// 3. a Givens QR of B gives B = U R, U a product of rotations, σ = diag(R) (the
//    off-diagonal of R is at the Jacobi tolerance relative to the shorter column and is
//    dropped; it bounds the reconstruction error);
// 4. signs are pushed into σ₃ and σ₁ ≥ σ₂ ≥ |σ₃| is enforced exactly.
// No division by σ anywhere: repeated and zero singular values still give orthonormal U, V.
// Non-finite input gives non-finite output (no hang: every loop has a fixed bound).

struct Svd3 {
    u: mat3x3<f32>,
    sigma: vec3<f32>,
    v: mat3x3<f32>,
}

const SVD_MAX_SWEEPS: u32 = 6u;
const SVD_ORTHO_TOL: f32 = 1e-6;
const SVD_ABS_TOL: f32 = 2.5e-7;
const SVD_NEGLIGIBLE2: f32 = 1e-30;

// One Jacobi rotation making columns bp, bq orthogonal (applied to vp, vq alike); false
// when the pair needed none. t = s/c solves t² + 2ζt − 1 = 0, ζ = (|b_q|² − |b_p|²)/(2 b_p·b_q),
// smaller root (Golub & Van Loan §8.4).
fn svd_jacobi_pair(
    bp: ptr<function, vec3<f32>>,
    bq: ptr<function, vec3<f32>>,
    vp: ptr<function, vec3<f32>>,
    vq: ptr<function, vec3<f32>>,
) -> bool {
    let p = *bp;
    let q = *bq;
    let alpha = dot(p, p);
    let beta = dot(q, q);
    let gamma = dot(p, q);
    let tol = max(SVD_ORTHO_TOL * sqrt(alpha) * sqrt(beta), SVD_ABS_TOL * max(alpha, beta));
    if min(alpha, beta) <= SVD_NEGLIGIBLE2 || abs(gamma) <= tol {
        return false;
    }
    let zeta = (beta - alpha) / (2.0 * gamma);
    let az = abs(zeta);
    // for huge |ζ|, sqrt(1 + ζ²) would overflow; t → 1/(2|ζ|) there
    let t_abs = select(1.0 / (az + sqrt(1.0 + az * az)), 0.5 / az, az > 1e15);
    let t = select(-t_abs, t_abs, zeta >= 0.0);
    let c = 1.0 / sqrt(1.0 + t * t);
    let s = c * t;
    *bp = c * p - s * q;
    *bq = s * p + c * q;
    let v0 = *vp;
    let v1 = *vq;
    *vp = c * v0 - s * v1;
    *vq = s * v0 + c * v1;
    return true;
}

// Puts the longer of columns bi, bj first; the swap negates the new j-th columns (of B
// and V alike) so that F = B Vᵀ and det V are kept.
fn svd_order_pair(
    bi: ptr<function, vec3<f32>>,
    bj: ptr<function, vec3<f32>>,
    vi: ptr<function, vec3<f32>>,
    vj: ptr<function, vec3<f32>>,
) {
    let b0 = *bi;
    let b1 = *bj;
    if dot(b0, b0) < dot(b1, b1) {
        *bi = b1;
        *bj = -b0;
        let v0 = *vi;
        *vi = *vj;
        *vj = -v0;
    }
}

// Givens rotation on rows i, j of r zeroing r[j][col] (row j, column col); accumulated as
// u ← u Gᵀ so that u r stays the same product.
fn svd_givens(r: ptr<function, mat3x3<f32>>, u: ptr<function, mat3x3<f32>>, i: u32, j: u32, col: u32) {
    let x = (*r)[col][i];
    let y = (*r)[col][j];
    let m = max(abs(x), abs(y));
    if y == 0.0 || m == 0.0 {
        return;
    }
    let xs = x / m;
    let ys = y / m;
    let h = sqrt(xs * xs + ys * ys);
    let c = xs / h;
    let s = ys / h;
    for (var k = 0u; k < 3u; k++) {
        let ri = (*r)[k][i];
        let rj = (*r)[k][j];
        (*r)[k][i] = c * ri + s * rj;
        (*r)[k][j] = c * rj - s * ri;
    }
    (*r)[col][j] = 0.0;
    let ui = (*u)[i];
    let uj = (*u)[j];
    (*u)[i] = c * ui + s * uj;
    (*u)[j] = c * uj - s * ui;
}

// Makes σ₁, σ₂ ≥ 0 by moving their signs onto σ₃ (negating σ_i, σ₃, u_i, u₃ together).
fn svd_push_sign_last(d: ptr<function, Svd3>) {
    for (var i = 0u; i < 2u; i++) {
        if (*d).sigma[i] < 0.0 {
            (*d).sigma[i] = -(*d).sigma[i];
            (*d).sigma[2] = -(*d).sigma[2];
            (*d).u[i] = -(*d).u[i];
            (*d).u[2] = -(*d).u[2];
        }
    }
}

// Swaps singular triplets i and j when |σ_i| < |σ_j|; the new u_j, v_j are both negated.
fn svd_order_triplets(d: ptr<function, Svd3>, i: u32, j: u32) {
    let si = (*d).sigma[i];
    let sj = (*d).sigma[j];
    if abs(si) < abs(sj) {
        (*d).sigma[i] = sj;
        (*d).sigma[j] = si;
        let ui = (*d).u[i];
        (*d).u[i] = (*d).u[j];
        (*d).u[j] = -ui;
        let vi = (*d).v[i];
        (*d).v[i] = (*d).v[j];
        (*d).v[j] = -vi;
    }
}

// SVD with the convention above; `sweeps` receives the number of Jacobi sweeps that
// rotated something (SVD_MAX_SWEEPS when the last allowed sweep still rotated).
fn svd3_counted(f: mat3x3<f32>, sweeps: ptr<function, u32>) -> Svd3 {
    let scale = sim_pow2_scale(sim_max_abs3(f));
    var b0 = f[0] * scale.x;
    var b1 = f[1] * scale.x;
    var b2 = f[2] * scale.x;
    var v0 = vec3<f32>(1.0, 0.0, 0.0);
    var v1 = vec3<f32>(0.0, 1.0, 0.0);
    var v2 = vec3<f32>(0.0, 0.0, 1.0);
    *sweeps = SVD_MAX_SWEEPS;
    for (var sweep = 0u; sweep < SVD_MAX_SWEEPS; sweep++) {
        let r01 = svd_jacobi_pair(&b0, &b1, &v0, &v1);
        let r02 = svd_jacobi_pair(&b0, &b2, &v0, &v2);
        let r12 = svd_jacobi_pair(&b1, &b2, &v1, &v2);
        if !(r01 || r02 || r12) {
            *sweeps = sweep;
            break;
        }
    }
    svd_order_pair(&b0, &b1, &v0, &v1);
    svd_order_pair(&b0, &b2, &v0, &v2);
    svd_order_pair(&b1, &b2, &v1, &v2);
    var r = mat3x3<f32>(b0, b1, b2);
    var u = SIM_IDENTITY3;
    svd_givens(&r, &u, 0u, 1u, 0u);
    svd_givens(&r, &u, 0u, 2u, 0u);
    svd_givens(&r, &u, 1u, 2u, 1u);
    var d: Svd3;
    d.u = u;
    d.sigma = vec3<f32>(r[0].x, r[1].y, r[2].z) * scale.y;
    d.v = mat3x3<f32>(v0, v1, v2);
    svd_push_sign_last(&d);
    svd_order_triplets(&d, 0u, 1u);
    svd_order_triplets(&d, 0u, 2u);
    svd_order_triplets(&d, 1u, 2u);
    svd_push_sign_last(&d);
    return d;
}

// F = U diag(σ) Vᵀ (convention above).
fn svd3(f: mat3x3<f32>) -> Svd3 {
    var sweeps: u32;
    return svd3_counted(f, &sweeps);
}

// U diag(σ) Vᵀ.
fn svd3_compose(u: mat3x3<f32>, sigma: vec3<f32>, v: mat3x3<f32>) -> mat3x3<f32> {
    return u * sim_diag3(sigma) * transpose(v);
}

// Polar decomposition F = R S: R = U Vᵀ a rotation (det +1 even when det F < 0),
// S = V diag(σ) Vᵀ symmetric (one negative eigenvalue when det F < 0).
struct Polar3 {
    r: mat3x3<f32>,
    s: mat3x3<f32>,
}

fn polar3(f: mat3x3<f32>) -> Polar3 {
    let d = svd3(f);
    return Polar3(d.u * transpose(d.v), d.v * sim_diag3(d.sigma) * transpose(d.v));
}

// Just the rotation R = U Vᵀ of F = R S.
fn polar_rotation(f: mat3x3<f32>) -> mat3x3<f32> {
    let d = svd3(f);
    return d.u * transpose(d.v);
}
