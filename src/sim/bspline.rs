//! Quadratic B-spline interpolation weights (docs/method.md §2).
//!
//! For a particle at `x` and grid spacing Δx: `base = floor(x/Δx − 0.5)`, `fx = x/Δx − base`
//! (each component in [0.5, 1.5)), and per axis
//!
//! ```text
//! w0 = ½ (1.5 − f)²      dw0/df = f − 1.5
//! w1 = ¾ − (f − 1)²      dw1/df = −2 (f − 1)
//! w2 = ½ (f − 0.5)²      dw2/df = f − 0.5
//! ```
//!
//! Node `base + (a, b, c)`, a, b, c ∈ {0, 1, 2}, gets `w = w_a(x) · w_b(y) · w_c(z)`;
//! `d_ip = i·Δx − x_p` is the node's offset from the particle. The gradient with respect to
//! the particle position is `∇w = (dw_a w_b w_c, w_a dw_b w_c, w_a w_b dw_c) / Δx`.
//! The MLS-MPM factor `4/Δx²` of docs/method.md §2 is the inverse of `D_p = Σ w d dᵀ = (Δx²/4) I`,
//! which the tests check.

use glam::{DVec3, IVec3};

/// The 3×3×3 stencil of one particle: base node, fractional position and per-axis weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stencil {
    /// Lowest node of the stencil, `floor(x/Δx − 0.5)`.
    pub base: IVec3,
    /// `x/Δx − base`, each component in [0.5, 1.5).
    pub fx: DVec3,
    /// `w[a]` holds the weight of offset `a` ∈ {0,1,2} on each axis (x, y, z components).
    pub w: [DVec3; 3],
    /// Derivatives of `w[a]` with respect to `fx` (multiply by 1/Δx for ∂/∂x).
    pub dw: [DVec3; 3],
}

/// Per-axis quadratic B-spline weights for a fractional position `f` ∈ [0.5, 1.5) (docs/method.md §2).
pub fn axis_weights(f: f64) -> [f64; 3] {
    [
        0.5 * (1.5 - f) * (1.5 - f),
        0.75 - (f - 1.0) * (f - 1.0),
        0.5 * (f - 0.5) * (f - 0.5),
    ]
}

/// Derivatives of [`axis_weights`] with respect to `f`.
pub fn axis_weight_derivs(f: f64) -> [f64; 3] {
    [f - 1.5, -2.0 * (f - 1.0), f - 0.5]
}

impl Stencil {
    /// The stencil of a particle at `x` on a grid of spacing `dx` (node i at `i·dx`).
    pub fn new(x: DVec3, dx: f64) -> Self {
        let xs = x / dx;
        let base_f = (xs - 0.5).floor();
        let fx = xs - base_f;
        let (wx, wy, wz) = (axis_weights(fx.x), axis_weights(fx.y), axis_weights(fx.z));
        let (gx, gy, gz) = (
            axis_weight_derivs(fx.x),
            axis_weight_derivs(fx.y),
            axis_weight_derivs(fx.z),
        );
        let w = [0, 1, 2].map(|a| DVec3::new(wx[a], wy[a], wz[a]));
        let dw = [0, 1, 2].map(|a| DVec3::new(gx[a], gy[a], gz[a]));
        Stencil {
            base: base_f.as_ivec3(),
            fx,
            w,
            dw,
        }
    }

    /// Integer index of node `base + off`, `off` ∈ {0,1,2}³.
    pub fn node(&self, off: IVec3) -> IVec3 {
        self.base + off
    }

    /// Weight `w_ip` of node `base + off`.
    pub fn weight(&self, off: IVec3) -> f64 {
        let o = off.as_uvec3();
        self.w[o.x as usize].x * self.w[o.y as usize].y * self.w[o.z as usize].z
    }

    /// Gradient `∇_x w_ip` of node `base + off` with respect to the particle position.
    pub fn weight_grad(&self, off: IVec3, dx: f64) -> DVec3 {
        let o = off.as_uvec3();
        let (a, b, c) = (o.x as usize, o.y as usize, o.z as usize);
        let (w, dw) = (&self.w, &self.dw);
        DVec3::new(
            dw[a].x * w[b].y * w[c].z,
            w[a].x * dw[b].y * w[c].z,
            w[a].x * w[b].y * dw[c].z,
        ) / dx
    }

    /// Offset `d_ip = i·Δx − x_p` of node `base + off` from the particle (docs/method.md §2).
    /// Computed from `fx` so that it does not depend on the magnitude of `x`.
    pub fn offset(&self, off: IVec3, dx: f64) -> DVec3 {
        (off.as_dvec3() - self.fx) * dx
    }
}

/// The 27 stencil offsets (a, b, c) ∈ {0,1,2}³, x fastest.
pub fn stencil_offsets() -> impl Iterator<Item = IVec3> {
    (0..27).map(|i| IVec3::new(i % 3, (i / 3) % 3, i / 9))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;
    use glam::DMat3;

    fn random_point(r: &mut SplitMix64) -> DVec3 {
        DVec3::new(r.uniform(), r.uniform(), r.uniform()) * 20.0 - 10.0
    }

    /// Σ w = 1 and Σ ∇w = 0 (partition of unity), every w ≥ 0 and fx ∈ [0.5, 1.5).
    #[test]
    fn partition_of_unity_and_nonnegative() {
        let mut r = SplitMix64::new(1);
        let dx = 0.037;
        for _ in 0..10_000 {
            let s = Stencil::new(random_point(&mut r), dx);
            assert!(s.fx.cmpge(DVec3::splat(0.5)).all() && s.fx.cmplt(DVec3::splat(1.5)).all());
            let sum: f64 = stencil_offsets().map(|o| s.weight(o)).sum();
            let gsum: DVec3 = stencil_offsets().map(|o| s.weight_grad(o, dx)).sum();
            assert!((sum - 1.0).abs() < 1e-14, "Σw = {sum}");
            assert!(gsum.abs().max_element() < 1e-10, "Σ∇w = {gsum}");
            assert!(stencil_offsets().all(|o| s.weight(o) >= 0.0));
        }
    }

    /// Linear reproduction Σ w x_i = x_p, and the MLS inertia D_p = Σ w d dᵀ = Δx²/4 I.
    #[test]
    fn linear_reproduction_and_inertia() {
        let mut r = SplitMix64::new(2);
        let dx = 0.01;
        for _ in 0..10_000 {
            let x = random_point(&mut r);
            let s = Stencil::new(x, dx);
            let xi: DVec3 = stencil_offsets()
                .map(|o| s.weight(o) * s.node(o).as_dvec3() * dx)
                .sum();
            assert!((xi - x).abs().max_element() < 1e-12, "{xi} vs {x}");
            let mut d = DMat3::ZERO;
            for o in stencil_offsets() {
                let v = s.offset(o, dx);
                d += DMat3::from_cols(v * v.x, v * v.y, v * v.z) * s.weight(o);
            }
            let err = (d - DMat3::IDENTITY * (0.25 * dx * dx))
                .abs()
                .to_cols_array();
            assert!(err.iter().all(|e| *e < 1e-16), "{d}");
        }
    }

    /// ∇w matches central finite differences of w, and Σ x_i ⊗ ∇w_i = I.
    #[test]
    fn gradient_matches_finite_differences() {
        let mut r = SplitMix64::new(3);
        let dx = 0.5;
        let h = 1e-6;
        for _ in 0..2_000 {
            let x = random_point(&mut r);
            let s = Stencil::new(x, dx);
            let mut outer = DMat3::ZERO;
            for o in stencil_offsets() {
                let node = s.node(o);
                let w_at = |y: DVec3| {
                    let t = Stencil::new(y, dx);
                    let off = node - t.base;
                    if off.cmpge(IVec3::ZERO).all() && off.cmple(IVec3::splat(2)).all() {
                        t.weight(off)
                    } else {
                        0.0
                    }
                };
                let fd = DVec3::new(
                    w_at(x + DVec3::X * h) - w_at(x - DVec3::X * h),
                    w_at(x + DVec3::Y * h) - w_at(x - DVec3::Y * h),
                    w_at(x + DVec3::Z * h) - w_at(x - DVec3::Z * h),
                ) / (2.0 * h);
                let g = s.weight_grad(o, dx);
                assert!((fd - g).abs().max_element() < 1e-6, "{fd} vs {g}");
                let xi = node.as_dvec3() * dx;
                outer += DMat3::from_cols(xi * g.x, xi * g.y, xi * g.z);
            }
            let err = (outer - DMat3::IDENTITY).abs().to_cols_array();
            assert!(err.iter().all(|e| *e < 1e-9), "{outer}");
        }
    }
}
