//! The WGSL twins of this module's f64 oracle: per-particle math in f32 for the GPU MPM
//! kernels, kept under `shaders/sim/` as modules to concatenate before a kernel's own code
//! (WGSL has no includes), like `shaders/common.wgsl` for the renderer.
//!
//! | module | oracle | WGSL API |
//! |---|---|---|
//! | [`MATH`] | — | `sim_is_finite*`, `sim_diag3`, `sim_trace3`, `sim_max_abs3`, `sim_pow2_scale`, `sim_sinh` |
//! | [`BSPLINE`] | [`super::bspline`] | `bspline_stencil(x, inv_dx) -> BsplineStencil`, `bspline_weight`, `bspline_weight_grad`, `bspline_offset`, `bspline_stencil_offset` |
//! | [`SVD`] | [`super::svd`] | `svd3(F) -> Svd3 {u, sigma, v}`, `svd3_counted`, `svd3_compose`, `polar3(F) -> Polar3 {r, s}`, `polar_rotation` |
//! | [`ELASTICITY`] | [`super::elasticity`] | `elastic_kirchhoff_fixed_corotated(F, μ, λ)`, `…_svd(F, svd, μ, λ)`, `elastic_kirchhoff_neo_hookean(F, μ, κ)` |
//!
//! The laws' own WGSL (NACC's return mapping among them) is not here: each law's file under
//! `shaders/sim/models/` comes with the registry's WGSL (`sim::models::wgsl_for`), and only
//! for the laws a simulation uses.
//!
//! `tests/sim_wgsl.rs` runs each function on thousands of random inputs through a small
//! compute harness, on the best adapter and on the GL backend, against the oracle.

/// Helpers every other module uses (finiteness by bits, diag, trace, exact power-of-two
/// scaling, a cancellation-free sinh).
pub const MATH: &str = include_str!("../../shaders/sim/math.wgsl");
/// Quadratic B-spline stencil (docs/method.md §2). Needs [`MATH`].
pub const BSPLINE: &str = include_str!("../../shaders/sim/bspline.wgsl");
/// 3×3 SVD with det U = det V = +1 and the polar decomposition (docs/method.md §4, §6). Needs [`MATH`].
pub const SVD: &str = include_str!("../../shaders/sim/svd.wgsl");
/// Kirchhoff stresses (docs/method.md §3). Needs [`MATH`], [`SVD`].
pub const ELASTICITY: &str = include_str!("../../shaders/sim/elasticity.wgsl");

/// All simulation modules in dependency order, ready to prepend to a kernel, after the
/// codes the laws read (`NACC_VARIANT_*`, `NACC_*` cases: [`super::codes`]).
pub fn library() -> String {
    let codes = super::codes::material_wgsl();
    [codes.as_str(), MATH, BSPLINE, SVD, ELASTICITY].join("\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every module parses and validates with naga, alone (after its dependencies) and all
    /// together.
    #[test]
    fn modules_validate() {
        for parts in [
            vec![MATH],
            vec![MATH, BSPLINE],
            vec![MATH, SVD],
            vec![MATH, SVD, ELASTICITY],
        ] {
            let codes = crate::sim::codes::material_wgsl();
            crate::gpu::layout_check::validated_module(&format!("{codes}\n{}", parts.join("\n")));
        }
        crate::gpu::layout_check::validated_module(&library());
    }
}
