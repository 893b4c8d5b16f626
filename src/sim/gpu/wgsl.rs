//! The WGSL twins of this module's f64 oracle: per-particle math in f32 for the GPU MPM
//! kernels, kept under `shaders/sim/` as [`Module`]s that a kernel's [`Source`] includes
//! (WGSL has no includes; `gpu::wgsl` puts each in once, after what it needs).
//!
//! | module | oracle | WGSL API |
//! |---|---|---|
//! | [`MATH`] | — | `sim_is_finite*`, `sim_diag3`, `sim_trace3`, `sim_max_abs3`, `sim_pow2_scale`, `sim_sinh` |
//! | [`BSPLINE`] | [`crate::sim::bspline`] | `bspline_stencil(x, inv_dx) -> BsplineStencil`, `bspline_weight`, `bspline_weight_grad`, `bspline_offset`, `bspline_stencil_offset` |
//! | [`SVD`] | [`crate::sim::svd`] | `svd3(F) -> Svd3 {u, sigma, v}`, `svd3_counted`, `svd3_compose`, `polar3(F) -> Polar3 {r, s}`, `polar_rotation` |
//! | [`ELASTICITY`] | [`crate::sim::model::elasticity`] | `elastic_kirchhoff_fixed_corotated(F, μ, λ)`, `…_svd(F, svd, μ, λ)`, `elastic_kirchhoff_neo_hookean(F, μ, κ)` |
//!
//! The laws' own WGSL (NACC's return mapping among them) is not here: each law's file under
//! `shaders/sim/model/` comes with the registry's WGSL (`sim::model::wgsl_for`), and only
//! for the laws a simulation uses.
//!
//! `tests/sim_wgsl.rs` runs each function on thousands of random inputs through a small
//! compute harness, on the best adapter and on the GL backend, against the oracle.

use crate::gpu::wgsl::{Module, Source};

/// Helpers every other module uses (finiteness by bits, diag, trace, exact power-of-two
/// scaling, a cancellation-free sinh).
pub static MATH: Module = Module {
    name: "sim/math",
    text: include_str!("../../../shaders/sim/math.wgsl"),
    needs: &[],
};
/// Quadratic B-spline stencil (docs/method.md §2).
pub static BSPLINE: Module = Module {
    name: "sim/bspline",
    text: include_str!("../../../shaders/sim/bspline.wgsl"),
    needs: &[],
};
/// 3×3 SVD with det U = det V = +1 and the polar decomposition (docs/method.md §4, §6).
pub static SVD: Module = Module {
    name: "sim/svd",
    text: include_str!("../../../shaders/sim/svd.wgsl"),
    needs: &[&MATH],
};
/// Kirchhoff stresses (docs/method.md §3).
pub static ELASTICITY: Module = Module {
    name: "sim/elasticity",
    text: include_str!("../../../shaders/sim/elasticity.wgsl"),
    needs: &[&MATH, &SVD],
};

/// Every module of the library.
pub static MODULES: [&Module; 4] = [&MATH, &BSPLINE, &SVD, &ELASTICITY];

/// The simulation's library as the start of a shader: the codes the laws read
/// (`NACC_VARIANT_*`, `NACC_*` cases: [`super::codes`]), then every module.
pub fn library_source() -> Source {
    MODULES.iter().fold(
        Source::new().generated(super::codes::material_wgsl()),
        |s, m| s.module(m),
    )
}

/// [`library_source`] as text, ready to prepend to a kernel.
pub fn library() -> String {
    library_source().pass("")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::wgsl::declared_needs;

    /// Every module validates with naga after the modules it says it needs, and nothing
    /// else (so a need left out of its list fails), and its file's `// Needs:` line names
    /// the same modules; the whole library validates.
    #[test]
    fn modules_validate_after_their_declared_needs() {
        for m in MODULES {
            let codes = crate::sim::gpu::codes::material_wgsl();
            let src = Source::new().generated(codes).module(m).pass("");
            crate::gpu::layout_check::validated_module(&src);
            let listed: Vec<&str> = m.needs.iter().map(|n| n.name).collect();
            assert_eq!(declared_needs(m.text), listed, "{}", m.name);
        }
        crate::gpu::layout_check::validated_module(&library());
    }
}
