//! 3×3 singular value decomposition with the rotation sign convention, and the polar
//! decomposition built on it (SPEC §4, §6; §3's fixed-corotated R).
//!
//! **Convention.** `F = U diag(σ) Vᵀ` with `U`, `V` proper rotations (det = +1) and
//! `σ₁ ≥ σ₂ ≥ |σ₃|`. When det F < 0 no such factorisation has all σ ≥ 0; the sign is pushed
//! into the smallest singular value, so σ₃ < 0 exactly when det F < 0 (σ₁, σ₂ ≥ 0 always).
//! This is the "rotation variant" SVD used by MPM codes (Irving et al. 2004, McAdams et al.
//! 2011): it keeps R = U Vᵀ a rotation for the fixed-corotated model and for the SH frame.
//!
//! **Algorithm** (the one the f32 WGSL kernel mirrors; this oracle runs in f64):
//! 1. symmetric eigen-decomposition of `A = FᵀF` by cyclic Jacobi rotations → `V` (a product
//!    of rotations, det = +1), eigenvalues sorted descending (column swaps carry a sign flip
//!    to keep det V = +1);
//! 2. `B = F V` has (nearly) orthogonal columns of decreasing length; a Givens QR of `B`
//!    gives `B = U R` with `U` a product of rotations (det = +1), `r₁₁, r₂₂ ≥ 0`, and `r₃₃`
//!    carrying the sign of det F;
//! 3. `σ = diag(R)` (the tiny off-diagonal of R is dropped).
//!
//! The QR step is what makes this robust: it needs no division by σ, so repeated and zero
//! singular values (rank-deficient F, F = 0) still give an orthonormal U (the degenerate
//! columns are completed by the rotations themselves), and small singular values come out
//! with high relative accuracy because `r₃₃` is the part of `F v₃` orthogonal to the first
//! two columns rather than `sqrt(λ_min(FᵀF))`. A final pass enforces the ordering
//! `σ₁ ≥ σ₂ ≥ |σ₃|` exactly (it can be off by round-off for repeated values).

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

/// Most Jacobi sweeps; f64 converges (quadratically) in ≤ 6 for any input seen in the tests.
const MAX_SWEEPS: usize = 30;

/// Element (row r, column c) of a glam matrix (stored column-major).
fn at(m: &DMat3, r: usize, c: usize) -> f64 {
    m.col(c)[r]
}

fn set(m: &mut DMat3, r: usize, c: usize, v: f64) {
    m.col_mut(c)[r] = v;
}

/// One Jacobi rotation zeroing `a[p][q]` of the symmetric `a`; accumulates into `v`.
fn jacobi_rotate(a: &mut DMat3, v: &mut DMat3, p: usize, q: usize) {
    let apq = at(a, p, q);
    if apq == 0.0 {
        return;
    }
    // Numerically stable angle (Golub & Van Loan, Alg. 8.4.1).
    let tau = (at(a, q, q) - at(a, p, p)) / (2.0 * apq);
    let t = tau.signum() / (tau.abs() + (1.0 + tau * tau).sqrt());
    let c = 1.0 / (1.0 + t * t).sqrt();
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

/// Sum of squares of the off-diagonal entries of a symmetric matrix.
fn off_diagonal_norm2(a: &DMat3) -> f64 {
    let (x, y, z) = (at(a, 0, 1), at(a, 0, 2), at(a, 1, 2));
    2.0 * (x * x + y * y + z * z)
}

/// Symmetric eigen-decomposition `A = V diag(λ) Vᵀ` by cyclic Jacobi, λ sorted descending,
/// det V = +1.
pub fn symmetric_eigen(a: DMat3) -> (DVec3, DMat3) {
    let mut a = a;
    let mut v = DMat3::IDENTITY;
    let scale2 = a.to_cols_array().iter().map(|x| x * x).sum::<f64>();
    for _ in 0..MAX_SWEEPS {
        if off_diagonal_norm2(&a) <= 1e-34 * scale2 || scale2 == 0.0 {
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

/// QR of `b` by Givens rotations: `b = U R`, det U = +1, `r₁₁, r₂₂ ≥ 0`.
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

/// SVD with the sign convention of the module doc. Finite input assumed.
pub fn svd3(f: DMat3) -> Svd3 {
    let (_, v) = symmetric_eigen(f.transpose() * f);
    let (u, r) = givens_qr(f * v);
    let mut svd = Svd3 {
        u,
        sigma: DVec3::new(at(&r, 0, 0), at(&r, 1, 1), at(&r, 2, 2)),
        v,
    };
    normalize(&mut svd);
    svd
}

/// Polar decomposition `F = R S`: `R = U Vᵀ` a rotation (det +1), `S = V diag(σ) Vᵀ`
/// symmetric. When det F < 0, S has one negative eigenvalue (σ₃); R stays a rotation, which
/// is what the fixed-corotated stress (SPEC §3) and the SH frame (SPEC §6) need.
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
            1 => return a,                                   // rotation
            2 => DVec3::new(s(r), s(r), s(r) * 1e-9),        // near-singular
            3 => DVec3::splat(s(r)),                         // all σ equal
            4 => DVec3::new(s(r), 0.7, 0.7),                 // two equal
            5 => DVec3::new(s(r), s(r), -s(r)),              // reflection
            6 => DVec3::new(s(r), 0.0, 0.0),                 // rank 1
            7 => DVec3::ZERO,                                // zero
            8 => DVec3::new(1.0, 1.0 + 1e-12, 1.0 - 1e-12),  // near-repeated
            _ => DVec3::new(s(r), s(r), 0.0),                // rank 2
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
        let (mut worst_rec, mut worst_orth) = (0.0f64, 0.0f64);
        for i in 0..20_000 {
            let (rec, orth) = check(random_matrix(&mut r, i % 10));
            worst_rec = worst_rec.max(rec);
            worst_orth = worst_orth.max(orth);
        }
        println!("svd3: worst relative reconstruction {worst_rec:e}, orthonormality {worst_orth:e}");
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
            let f = random_rotation(&mut r) * DMat3::from_diagonal(sig) * random_rotation(&mut r).transpose();
            let got = svd3(f).sigma;
            let mut want = [sig.x.abs(), sig.y.abs(), sig.z.abs()];
            want.sort_by(|a, b| b.total_cmp(a));
            let want = DVec3::new(want[0], want[1], want[2] * sig.z.signum());
            let err = (got - want).abs().max_element() / want.x;
            assert!(err < 1e-14, "{got} vs {want}");
            // sqrt(λ_min(FᵀF)) would be off by ~1e-3 relative here.
            assert!((got.z - want.z).abs() < 1e-7 * want.z.abs(), "σ₃ {got} vs {want}");
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
        ];
        for f in cases {
            check(f);
        }
        assert_eq!(svd3(DMat3::IDENTITY).sigma, DVec3::ONE);
        assert_eq!(svd3(-DMat3::IDENTITY).sigma, DVec3::new(1.0, 1.0, -1.0));
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
