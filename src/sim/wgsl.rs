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
//! | [`NACC`] | [`super::nacc`] | `nacc_return_map(F_tr, α, NaccMaterial) -> NaccReturn`, `nacc_p0`, `nacc_yield_scaled`, `nacc_project_pq`, `nacc_project_{center,continuous,closest_point}`, `nacc_principal_state`, `nacc_j_from_pressure`, `nacc_solve_b_bar`, `nacc_stretches_from_pq` |
//!
//! `tests/sim_wgsl.rs` runs each function on thousands of random inputs through a small
//! compute harness, on the best adapter and on the GL backend, against the oracle.

use bytemuck::{Pod, Zeroable};

use super::nacc::{Case3Variant, NaccParams, ReturnCase};

/// Helpers every other module uses (finiteness by bits, diag, trace, exact power-of-two
/// scaling, a cancellation-free sinh).
pub const MATH: &str = include_str!("../../shaders/sim/math.wgsl");
/// Quadratic B-spline stencil (docs/method.md §2). Needs [`MATH`].
pub const BSPLINE: &str = include_str!("../../shaders/sim/bspline.wgsl");
/// 3×3 SVD with det U = det V = +1 and the polar decomposition (docs/method.md §4, §6). Needs [`MATH`].
pub const SVD: &str = include_str!("../../shaders/sim/svd.wgsl");
/// Kirchhoff stresses (docs/method.md §3). Needs [`MATH`], [`SVD`].
pub const ELASTICITY: &str = include_str!("../../shaders/sim/elasticity.wgsl");
/// NACC return mapping (docs/method.md §4). Needs [`MATH`], [`SVD`].
pub const NACC: &str = include_str!("../../shaders/sim/nacc.wgsl");

/// All simulation modules in dependency order, ready to prepend to a kernel, after the
/// codes they read (`NACC_VARIANT_*`, `NACC_*` cases: [`super::codes`]).
pub fn library() -> String {
    let codes = super::codes::material_wgsl();
    [codes.as_str(), MATH, BSPLINE, SVD, ELASTICITY, NACC].join("\n")
}

/// The WGSL `NaccMaterial` (32 bytes): κ and μ computed here in f64, then rounded.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct NaccMaterialGpu {
    pub kappa: f32,
    pub mu: f32,
    pub beta: f32,
    pub xi: f32,
    pub m_slope: f32,
    /// Exponent of the `continuous` variant (0 for the others).
    pub k: f32,
    /// `NACC_VARIANT_*` ([`Case3Variant::gpu_code`]).
    pub variant: u32,
    /// Initial hardening state α₀ (a particle's damage, `Material::damage`).
    pub alpha0: f32,
}

impl NaccMaterialGpu {
    pub fn new(params: &NaccParams, variant: Case3Variant) -> Self {
        let k = match variant {
            Case3Variant::Continuous { k } => k,
            Case3Variant::Center | Case3Variant::ClosestPoint => 0.0,
        };
        NaccMaterialGpu {
            kappa: params.kappa() as f32,
            mu: params.mu() as f32,
            beta: params.beta as f32,
            xi: params.xi as f32,
            m_slope: params.m_slope as f32,
            k: k as f32,
            variant: variant.gpu_code(),
            alpha0: params.alpha0 as f32,
        }
    }
}

/// The [`ReturnCase`] of a WGSL `NACC_*` case code.
pub fn return_case(code: u32) -> Option<ReturnCase> {
    ReturnCase::from_gpu_code(code)
}

#[cfg(test)]
mod tests {
    use super::*;
    use wgpu::naga;

    /// Every module parses and validates with naga, alone (after its dependencies) and all
    /// together; the Rust mirror of `NaccMaterial` has the WGSL layout.
    #[test]
    fn modules_validate_and_material_layout_matches() {
        for parts in [
            vec![MATH],
            vec![MATH, BSPLINE],
            vec![MATH, SVD],
            vec![MATH, SVD, ELASTICITY],
            vec![MATH, SVD, NACC],
        ] {
            let codes = crate::sim::codes::material_wgsl();
            crate::gpu::layout_check::validated_module(&format!("{codes}\n{}", parts.join("\n")));
        }
        let src = library();
        let module = naga::front::wgsl::parse_str(&src).expect("WGSL parses");
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).expect("layout");
        let ty = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some("NaccMaterial"))
            .expect("NaccMaterial");
        let naga::TypeInner::Struct { members, span } = &ty.1.inner else {
            panic!("not a struct");
        };
        assert_eq!(*span as usize, std::mem::size_of::<NaccMaterialGpu>());
        let rust = [
            ("kappa", std::mem::offset_of!(NaccMaterialGpu, kappa)),
            ("mu", std::mem::offset_of!(NaccMaterialGpu, mu)),
            ("beta", std::mem::offset_of!(NaccMaterialGpu, beta)),
            ("xi", std::mem::offset_of!(NaccMaterialGpu, xi)),
            ("m_slope", std::mem::offset_of!(NaccMaterialGpu, m_slope)),
            ("k", std::mem::offset_of!(NaccMaterialGpu, k)),
            ("variant", std::mem::offset_of!(NaccMaterialGpu, variant)),
            ("alpha0", std::mem::offset_of!(NaccMaterialGpu, alpha0)),
        ];
        for (m, (name, off)) in members.iter().zip(rust) {
            assert_eq!(m.name.as_deref(), Some(name));
            assert_eq!(m.offset as usize, off, "{name}");
        }
    }
}
