//! 3×3 singular value decomposition with the rotation sign convention, and the polar
//! decomposition built on it (docs/method.md §4, §6; §3's fixed-corotated R).
//!
//! **Convention.** `F = U diag(σ) Vᵀ` with `U`, `V` proper rotations (det = +1) and
//! `σ₁ ≥ σ₂ ≥ |σ₃|`. When det F < 0 no such factorisation has all σ ≥ 0; the sign is pushed
//! into the smallest singular value, so σ₃ < 0 exactly when det F < 0 (σ₁, σ₂ ≥ 0 always).
//! This is the "rotation variant" SVD used by MPM codes (Irving et al. 2004, McAdams et al.
//! 2011): it keeps R = U Vᵀ a rotation for the fixed-corotated model and for the SH frame.
//!
//! **Algorithm** (f64 here; the f32 WGSL kernel may use a cheaper scheme and is compared
//! against this one with f32 tolerances):
//! 1. one-sided (Hestenes) Jacobi on the columns of F: plane rotations on the right,
//!    `B ← B G`, `V ← V G`, until every pair of columns of `B = F V` is orthogonal to
//!    1e-15 of the product of their lengths. V is a product of rotations (det = +1);
//! 2. the columns of B are sorted by length, descending (a swap negates one column of B
//!    and of V, keeping det V = +1 and F = B Vᵀ);
//! 3. a Givens QR of B gives `B = U R` with U a product of rotations (det = +1),
//!    `r₁₁, r₂₂ ≥ 0` and `r₃₃` carrying the sign of det F; `σ = diag(R)` (the
//!    off-diagonal of R is at round-off level relative to the shorter column and dropped);
//! 4. a final pass pushes any remaining sign into σ₃ and enforces `σ₁ ≥ σ₂ ≥ |σ₃|` exactly
//!    (a skipped Givens rotation can leave r₁₁ or r₂₂ negative; round-off can misorder
//!    repeated σ).
//!
//! Why this shape: working on F rather than on FᵀF keeps the accuracy of small singular
//! values (a Jacobi eigen-decomposition of FᵀF mixes the two smallest singular vectors by
//! ε‖F‖²/(σ₂² − σ₃²); that variant measured 1.4e-13 relative reconstruction error on a
//! matrix with σ = (52, 1.2e-2, 3e-8); this one stays ≤ 1.5e-15 on all test inputs). The QR step needs no division
//! by σ, so repeated and zero singular values (rank-deficient F, F = 0) still give an
//! orthonormal U: the rotations complete the degenerate columns themselves.

use glam::{DMat3, DVec3};

/// `F = U diag(sigma) Vᵀ`, det U = det V = +1, `sigma.x ≥ sigma.y ≥ |sigma.z|`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Svd3 {
    pub u: DMat3,
    pub sigma: DVec3,
    pub v: DMat3,
}

impl Svd3 {
    /// `U diag(σ) Vᵀ`.
    pub fn reconstruct(&self) -> DMat3 {
        self.u * DMat3::from_diagonal(self.sigma) * self.v.transpose()
    }
}

/// Most Jacobi sweeps; f64 converges (quadratically) in ≤ 5 on every input of the tests.
const MAX_SWEEPS: usize = 30;

/// One-sided Jacobi stops when every |b_p·b_q| ≤ ORTHO_TOL |b_p| |b_q|.
const ORTHO_TOL: f64 = 1e-15;

/// Squared column length below which a column counts as zero, for F scaled so that its
/// largest entry is in [1, 2) (a column of length 1e-18 there is far below round-off).
const NEGLIGIBLE2: f64 = 1e-36;

/// Element (row r, column c) of a glam matrix (stored column-major).
fn at(m: &DMat3, r: usize, c: usize) -> f64 {
    m.col(c)[r]
}

fn set(m: &mut DMat3, r: usize, c: usize, v: f64) {
    m.col_mut(c)[r] = v;
}

/// Rotates columns p, q of `m`: m_p ← c m_p − s m_q, m_q ← s m_p + c m_q.
fn rotate_cols(m: &mut DMat3, p: usize, q: usize, c: f64, s: f64) {
    let (mp, mq) = (m.col(p), m.col(q));
    *m.col_mut(p) = mp * c - mq * s;
    *m.col_mut(q) = mp * s + mq * c;
}

/// The rotation (c, s) that makes columns with |b_p|² = α, |b_q|² = β, b_p·b_q = γ
/// orthogonal: t = s/c solves t² + 2ζt − 1 = 0 with ζ = (β − α)/(2γ), smaller root
/// (Golub & Van Loan §8.4). None when the pair is already orthogonal to [`ORTHO_TOL`], or
/// when a column is below [`NEGLIGIBLE2`] (its direction is round-off noise, and rotating
/// noise against noise need not converge).
fn jacobi_angle(alpha: f64, beta: f64, gamma: f64) -> Option<(f64, f64)> {
    if alpha.min(beta) <= NEGLIGIBLE2 || gamma.abs() <= ORTHO_TOL * alpha.sqrt() * beta.sqrt() {
        return None;
    }
    let zeta = (beta - alpha) / (2.0 * gamma);
    let t = zeta.signum() / (zeta.abs() + zeta.hypot(1.0));
    let c = 1.0 / t.hypot(1.0);
    Some((c, c * t))
}

/// One-sided Jacobi: returns (B, V, sweeps) with B = F V having mutually orthogonal
/// columns; `sweeps` counts the sweeps that rotated something.
fn one_sided_jacobi(f: DMat3) -> (DMat3, DMat3, usize) {
    let (mut b, mut v) = (f, DMat3::IDENTITY);
    for sweep in 0..MAX_SWEEPS {
        let mut rotated = false;
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            let (bp, bq) = (b.col(p), b.col(q));
            let angle = jacobi_angle(bp.length_squared(), bq.length_squared(), bp.dot(bq));
            if let Some((c, s)) = angle {
                rotate_cols(&mut b, p, q, c, s);
                rotate_cols(&mut v, p, q, c, s);
                rotated = true;
            }
        }
        if !rotated {
            return (b, v, sweep);
        }
    }
    (b, v, MAX_SWEEPS)
}

/// One two-sided Jacobi rotation zeroing `a[p][q]` of the symmetric `a`; accumulates into `v`.
fn jacobi_rotate(a: &mut DMat3, v: &mut DMat3, p: usize, q: usize) {
    let apq = at(a, p, q);
    if apq == 0.0 {
        return;
    }
    let zeta = (at(a, q, q) - at(a, p, p)) / (2.0 * apq);
    let t = zeta.signum() / (zeta.abs() + zeta.hypot(1.0));
    let c = 1.0 / t.hypot(1.0);
    let s = t * c;
    let mut g = DMat3::IDENTITY;
    set(&mut g, p, p, c);
    set(&mut g, q, q, c);
    set(&mut g, p, q, s);
    set(&mut g, q, p, -s);
    *a = g.transpose() * *a * g;
    set(a, p, q, 0.0);
    set(a, q, p, 0.0);
    *v *= g;
}

/// Symmetric eigen-decomposition `A = V diag(λ) Vᵀ` by cyclic two-sided Jacobi, λ sorted
/// descending, det V = +1 (for covariance PCA; the SVD does not use it).
pub fn symmetric_eigen(a: DMat3) -> (DVec3, DMat3) {
    let mut a = a;
    let mut v = DMat3::IDENTITY;
    let scale2: f64 = a.to_cols_array().iter().map(|x| x * x).sum();
    for _ in 0..MAX_SWEEPS {
        let off2: f64 = [(0, 1), (0, 2), (1, 2)]
            .map(|(p, q)| at(&a, p, q).powi(2))
            .iter()
            .sum();
        if off2 <= 1e-32 * scale2 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            jacobi_rotate(&mut a, &mut v, p, q);
        }
    }
    let mut lambda = DVec3::new(at(&a, 0, 0), at(&a, 1, 1), at(&a, 2, 2));
    sort_descending(&mut lambda, &mut v);
    (lambda, v)
}

/// Swaps entries i, j of `d` and columns i, j of `m`, negating one column so det m is kept.
fn swap_keep_det(d: &mut DVec3, m: &mut DMat3, i: usize, j: usize) {
    let (di, dj) = (d[i], d[j]);
    d[i] = dj;
    d[j] = di;
    let (ci, cj) = (m.col(i), m.col(j));
    *m.col_mut(i) = cj;
    *m.col_mut(j) = -ci;
}

/// Sorts `d` descending, permuting the columns of `m` alike (det m kept).
fn sort_descending(d: &mut DVec3, m: &mut DMat3) {
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        if d[i] < d[j] {
            swap_keep_det(d, m, i, j);
        }
    }
}

/// Givens rotation on rows i, j of `b` zeroing `b[j][col]`; accumulated as `u ← u Gᵀ`.
fn givens_zero(b: &mut DMat3, u: &mut DMat3, i: usize, j: usize, col: usize) {
    let (x, y) = (at(b, i, col), at(b, j, col));
    let r = x.hypot(y);
    if y == 0.0 || r == 0.0 {
        return;
    }
    let (c, s) = (x / r, y / r);
    // G acts on rows: row_i ← c row_i + s row_j, row_j ← −s row_i + c row_j.
    let mut g = DMat3::IDENTITY;
    set(&mut g, i, i, c);
    set(&mut g, i, j, s);
    set(&mut g, j, i, -s);
    set(&mut g, j, j, c);
    *b = g * *b;
    set(b, j, col, 0.0);
    *u *= g.transpose();
}

/// QR of `b` by Givens rotations: `b = U R`, det U = +1, `r₁₁, r₂₂ ≥ 0` except where a
/// column needed no rotation (then its diagonal keeps its sign; [`normalize`] fixes it).
fn givens_qr(b: DMat3) -> (DMat3, DMat3) {
    let mut r = b;
    let mut u = DMat3::IDENTITY;
    givens_zero(&mut r, &mut u, 0, 1, 0);
    givens_zero(&mut r, &mut u, 0, 2, 0);
    givens_zero(&mut r, &mut u, 1, 2, 1);
    (u, r)
}

/// Makes σ₁, σ₂ ≥ 0 by moving their signs onto σ₃ (negating σ_i, σ₃, u_i and u₃ together
/// keeps both `U diag(σ) Vᵀ` and det U).
fn push_sign_last(svd: &mut Svd3) {
    for i in 0..2 {
        if svd.sigma[i] < 0.0 {
            svd.sigma[i] = -svd.sigma[i];
            svd.sigma[2] = -svd.sigma[2];
            *svd.u.col_mut(i) = -svd.u.col(i);
            *svd.u.col_mut(2) = -svd.u.col(2);
        }
    }
}

/// Swaps singular triplets i and j; the new u_j and v_j are both negated, which keeps
/// `U diag(σ) Vᵀ` and both determinants.
fn swap_triplets(svd: &mut Svd3, i: usize, j: usize) {
    let mut sigma_for_v = svd.sigma;
    swap_keep_det(&mut svd.sigma, &mut svd.u, i, j);
    swap_keep_det(&mut sigma_for_v, &mut svd.v, i, j);
}

/// Enforces `σ₁ ≥ σ₂ ≥ |σ₃|` with σ₁, σ₂ ≥ 0 exactly (QR gives it up to round-off).
fn normalize(svd: &mut Svd3) {
    push_sign_last(svd);
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        if svd.sigma[i].abs() < svd.sigma[j].abs() {
            swap_triplets(svd, i, j);
        }
    }
    push_sign_last(svd);
}

/// Power of two that brings the largest entry of `f` into [1, 2) (exact scaling; the
/// exponent is clamped to ±1000 so the factor itself stays finite); 1 for 0.
fn normalizing_scale(f: DMat3) -> f64 {
    let m = f
        .abs()
        .to_cols_array()
        .iter()
        .fold(0.0f64, |a, x| a.max(*x));
    if m > 0.0 && m.is_finite() {
        (-m.log2().floor()).clamp(-1000.0, 1000.0).exp2()
    } else {
        1.0
    }
}

/// SVD with the sign convention of the module doc. Finite input assumed. F is first scaled
/// by a power of two (exact) so that tiny or huge matrices neither underflow nor overflow.
pub fn svd3(f: DMat3) -> Svd3 {
    let scale = normalizing_scale(f);
    let (mut b, mut v, _) = one_sided_jacobi(f * scale);
    let mut len2 = DVec3::new(
        b.col(0).length_squared(),
        b.col(1).length_squared(),
        b.col(2).length_squared(),
    );
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        if len2[i] < len2[j] {
            let mut l = len2;
            swap_keep_det(&mut l, &mut b, i, j);
            swap_keep_det(&mut len2, &mut v, i, j);
        }
    }
    let (u, r) = givens_qr(b);
    let mut svd = Svd3 {
        u,
        sigma: DVec3::new(at(&r, 0, 0), at(&r, 1, 1), at(&r, 2, 2)) / scale,
        v,
    };
    normalize(&mut svd);
    svd
}

/// Polar decomposition `F = R S`: `R = U Vᵀ` a rotation (det +1), `S = V diag(σ) Vᵀ`
/// symmetric. When det F < 0, S has one negative eigenvalue (σ₃); R stays a rotation, which
/// is what the fixed-corotated stress (docs/method.md §3) and the SH frame (docs/method.md §6) need.
pub fn polar(f: DMat3) -> (DMat3, DMat3) {
    let svd = svd3(f);
    let r = svd.u * svd.v.transpose();
    let s = svd.v * DMat3::from_diagonal(svd.sigma) * svd.v.transpose();
    (r, s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;
    use glam::DQuat;

    fn norm(m: DMat3) -> f64 {
        m.to_cols_array().iter().map(|x| x * x).sum::<f64>().sqrt()
    }

    fn random_rotation(r: &mut SplitMix64) -> DMat3 {
        let q = DQuat::from_xyzw(
            r.uniform() - 0.5,
            r.uniform() - 0.5,
            r.uniform() - 0.5,
            r.uniform() - 0.5,
        );
        DMat3::from_quat(q.normalize())
    }

    /// A family of hard inputs; `kind` picks one.
    fn random_matrix(r: &mut SplitMix64, kind: usize) -> DMat3 {
        let (a, b) = (random_rotation(r), random_rotation(r));
        let s = |r: &mut SplitMix64| 10f64.powf(4.0 * r.uniform() - 2.0);
        let sig = match kind {
            0 => return DMat3::from_cols_array(&[0.0; 9].map(|_: f64| r.uniform() * 2.0 - 1.0)),
            1 => return a,                                  // rotation
            2 => DVec3::new(s(r), s(r), s(r) * 1e-9),       // near-singular
            3 => DVec3::splat(s(r)),                        // all σ equal
            4 => DVec3::new(s(r), 0.7, 0.7),                // two equal
            5 => DVec3::new(s(r), s(r), -s(r)),             // reflection
            6 => DVec3::new(s(r), 0.0, 0.0),                // rank 1
            7 => DVec3::ZERO,                               // zero
            8 => DVec3::new(1.0, 1.0 + 1e-12, 1.0 - 1e-12), // near-repeated
            _ => DVec3::new(s(r), s(r), 0.0),               // rank 2
        };
        a * DMat3::from_diagonal(sig) * b.transpose()
    }

    fn check(f: DMat3) -> (f64, f64) {
        let svd = svd3(f);
        let scale = norm(f).max(1e-300);
        let rec = norm(svd.reconstruct() - f) / scale;
        let orth = norm(svd.u.transpose() * svd.u - DMat3::IDENTITY)
            .max(norm(svd.v.transpose() * svd.v - DMat3::IDENTITY));
        assert!(rec < 1e-13, "reconstruction {rec:e} for {f}");
        assert!(orth < 1e-13, "orthonormality {orth:e} for {f}");
        assert!((svd.u.determinant() - 1.0).abs() < 1e-12);
        assert!((svd.v.determinant() - 1.0).abs() < 1e-12);
        let s = svd.sigma;
        assert!(s.x >= s.y && s.y >= s.z.abs() && s.y >= 0.0, "unsorted {s}");
        let det = f.determinant();
        if det.abs() > 1e-12 * scale.powi(3) {
            assert_eq!(s.z < 0.0, det < 0.0, "sign of σ₃ {s} vs det {det:e}");
        } else {
            assert!(s.x >= 0.0);
        }
        (rec, orth)
    }

    /// 20 000 random matrices of 10 hard kinds: reconstruction, orthonormality, det U = det V
    /// = +1, σ₁ ≥ σ₂ ≥ |σ₃|, σ₃ < 0 iff det F < 0.
    #[test]
    fn random_matrices_decompose() {
        let mut r = SplitMix64::new(11);
        let (mut worst_rec, mut worst_orth, mut sweeps) = (0.0f64, 0.0f64, 0);
        for i in 0..20_000 {
            let f = random_matrix(&mut r, i % 10);
            sweeps = sweeps.max(one_sided_jacobi(f * normalizing_scale(f)).2);
            let (rec, orth) = check(f);
            worst_rec = worst_rec.max(rec);
            worst_orth = worst_orth.max(orth);
        }
        println!(
            "svd3: worst relative reconstruction {worst_rec:e}, orthonormality {worst_orth:e}, \
             at most {sweeps} Jacobi sweeps"
        );
        assert!(sweeps <= 6, "{sweeps} sweeps");
    }

    /// Known singular values come back (to relative accuracy, including tiny ones).
    #[test]
    fn singular_values_are_accurate() {
        let mut r = SplitMix64::new(12);
        for _ in 0..5_000 {
            let mut sig = DVec3::new(
                0.5 + r.uniform() * 2.5,
                0.5 + r.uniform() * 2.5,
                (0.5 + r.uniform()) * 1e-6,
            );
            if r.uniform() < 0.5 {
                sig.z = -sig.z;
            }
            let f = random_rotation(&mut r)
                * DMat3::from_diagonal(sig)
                * random_rotation(&mut r).transpose();
            let got = svd3(f).sigma;
            let mut want = [sig.x.abs(), sig.y.abs(), sig.z.abs()];
            want.sort_by(|a, b| b.total_cmp(a));
            let want = DVec3::new(want[0], want[1], want[2] * sig.z.signum());
            let err = (got - want).abs().max_element() / want.x;
            assert!(err < 1e-14, "{got} vs {want}");
            // sqrt(λ_min(FᵀF)) would be off by ~1e-3 relative here.
            assert!(
                (got.z - want.z).abs() < 1e-7 * want.z.abs(),
                "σ₃ {got} vs {want}"
            );
        }
    }

    /// Special matrices: identity, zero, diagonal with sign, permutation reflection.
    #[test]
    fn special_matrices() {
        let cases = [
            DMat3::IDENTITY,
            DMat3::ZERO,
            DMat3::from_diagonal(DVec3::new(-1.0, 2.0, 3.0)),
            DMat3::from_diagonal(DVec3::new(-1.0, -1.0, -1.0)),
            DMat3::from_cols(DVec3::Y, DVec3::X, DVec3::Z),
            DMat3::from_cols(DVec3::X, DVec3::X, DVec3::X),
            DMat3::from_diagonal(DVec3::new(1e-200, 3e-200, -2e-200)),
            DMat3::from_diagonal(DVec3::new(1e200, 3e200, 2e200)),
            DMat3::from_cols(DVec3::X, DVec3::Y * 1e-300, DVec3::Z * 1e-310),
            DMat3::IDENTITY * 1e-310,
        ];
        for f in cases {
            check(f);
        }
        assert_eq!(svd3(DMat3::IDENTITY).sigma, DVec3::ONE);
        assert_eq!(svd3(-DMat3::IDENTITY).sigma, DVec3::new(1.0, 1.0, -1.0));
    }

    /// Symmetric eigen-decomposition (for covariance PCA): A V = V Λ, V orthonormal with
    /// det +1, λ descending.
    #[test]
    fn symmetric_eigen_decomposes() {
        let mut r = SplitMix64::new(14);
        for i in 0..5_000 {
            let f = random_matrix(&mut r, i % 10);
            let a = f.transpose() * f;
            let (lambda, v) = symmetric_eigen(a);
            let scale = norm(a).max(1e-300);
            assert!(norm(a * v - v * DMat3::from_diagonal(lambda)) / scale < 1e-13);
            assert!(norm(v.transpose() * v - DMat3::IDENTITY) < 1e-13);
            assert!((v.determinant() - 1.0).abs() < 1e-12);
            assert!(lambda.x >= lambda.y && lambda.y >= lambda.z);
        }
    }

    /// Polar: R a rotation, S symmetric, F = R S; R = F for rotations, R = I for SPD F.
    #[test]
    fn polar_decomposition() {
        let mut r = SplitMix64::new(13);
        for i in 0..5_000 {
            let f = random_matrix(&mut r, i % 10);
            let (rot, s) = polar(f);
            let scale = norm(f).max(1e-300);
            assert!(norm(rot * s - f) / scale < 1e-13);
            assert!(norm(s - s.transpose()) / scale < 1e-13);
            assert!(norm(rot.transpose() * rot - DMat3::IDENTITY) < 1e-13);
            assert!((rot.determinant() - 1.0).abs() < 1e-12);
        }
        let q = random_rotation(&mut r);
        assert!(norm(polar(q).0 - q) < 1e-13);
        let spd = DMat3::from_cols_array(&[2.0, 0.3, 0.1, 0.3, 1.5, 0.2, 0.1, 0.2, 1.0]);
        assert!(norm(polar(spd).0 - DMat3::IDENTITY) < 1e-13);
    }
}
