//! NACC plasticity (docs/method.md §4): Non-Associated Cam-Clay with hardening on
//! Neo-Hookean, the fruit, bread and sand of CD-MPM. Its parameters and registry line here,
//! the f64 oracle in [`oracle`], the f32 twin (`nacc_return_map` and its helpers) in
//! `shaders/sim/model/nacc.wgsl`, compiled only into simulations that use the law.

use glam::DMat3;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use bytemuck::{Pod, Zeroable};

use super::{ElasticModel, Example, ParamError, PlasticLaw, PlasticWgsl, PLASTIC_PARAMS};
use crate::sim::model::elasticity::Lame;

pub mod oracle;
pub use oracle::{
    m_from_friction_angle, project_pq, return_map, Case3Variant, NaccParams, PlasticReturn,
    ReturnCase, ReturnMapping, YieldEllipse,
};

/// NACC's parameters and its case-3 return mapping.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nacc {
    pub params: NaccParams,
    pub variant: Case3Variant,
}

/// The scene file's NACC parameters (the paper's table).
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NaccSpec {
    /// Initial hardening state α₀ (< 0: cohesive; the cohesion p0 = κ sinh(−ξ α₀)).
    pub alpha0: f64,
    /// Tensile/compressive strength ratio β (≥ 0).
    pub beta: f64,
    /// Hardening coefficient ξ (≥ 0).
    pub xi: f64,
    /// Slope M of the critical-state line (or give `friction_angle_deg`).
    #[serde(rename = "M", default, skip_serializing_if = "Option::is_none")]
    pub m_slope: Option<f64>,
    /// Friction angle in degrees, M = 6 sin φ / (3 − sin φ) (or give `M`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction_angle_deg: Option<f64>,
    /// Case-3 return mapping: `center`, `continuous` (default) or `closest_point`.
    #[serde(default = "default_mapping")]
    pub return_mapping: ReturnMapping,
    /// Exponent k of the `continuous` mapping. Default 2.
    #[serde(default = "default_k")]
    pub k: f64,
}

fn default_mapping() -> ReturnMapping {
    ReturnMapping::Continuous
}

fn default_k() -> f64 {
    2.0
}

impl PlasticLaw for Nacc {
    const NAME: &'static str = "nacc";
    const ELASTIC: ElasticModel = ElasticModel::NeoHookean;
    const FRACTURES: bool = true;
    const ALPHA: &'static str =
        "the hardening state, log of the plastic volume ratio Jᴾ (starts at α₀)";
    const ALPHA_IS_LOG_JP: bool = true;
    // params: β, ξ, M, k, variant (bits), α₀.
    const WGSL: PlasticWgsl = PlasticWgsl {
        return_map: "let r = nacc_return_map(f, alpha, nacc_material(m)); return PlasticState(r.f, r.alpha);",
        damage: "nacc_damage(m.params[5], alpha)",
        stress_scale: "1.0",
        kirchhoff: None,
        module: WGSL_MODULE,
    };
    const EXAMPLE: Example = Example {
        params: r#"{"alpha0": -0.04, "beta": 1.0, "xi": 2.0, "M": 2.36, "return_mapping": "continuous", "k": 2.0}"#,
        alpha: -0.04,
    };
    type Spec = NaccSpec;

    fn from_spec(spec: NaccSpec, e: f64, nu: f64) -> Result<Self, ParamError> {
        let m_slope = match (spec.m_slope, spec.friction_angle_deg) {
            (Some(m), None) => {
                ParamError::check(m.is_finite() && m > 0.0, "M", m, "a slope > 0")?;
                m
            }
            (None, Some(phi)) => {
                ParamError::check(
                    phi.is_finite() && phi > 0.0 && phi < 90.0,
                    "friction_angle_deg",
                    phi,
                    "an angle in (0, 90)",
                )?;
                m_from_friction_angle(phi.to_radians())
            }
            _ => {
                return Err(ParamError::new(
                    "M",
                    "M and friction_angle_deg",
                    "exactly one of `M` or `friction_angle_deg`",
                ))
            }
        };
        ParamError::check(
            spec.alpha0.is_finite(),
            "alpha0",
            spec.alpha0,
            "a finite value",
        )?;
        ParamError::check(
            spec.beta.is_finite() && spec.beta >= 0.0,
            "beta",
            spec.beta,
            "β ≥ 0",
        )?;
        ParamError::check(
            spec.xi.is_finite() && spec.xi >= 0.0,
            "xi",
            spec.xi,
            "ξ ≥ 0",
        )?;
        ParamError::check(spec.k.is_finite() && spec.k > 0.0, "k", spec.k, "k > 0")?;
        Ok(Nacc {
            params: NaccParams {
                e,
                nu,
                alpha0: spec.alpha0,
                beta: spec.beta,
                xi: spec.xi,
                m_slope,
            },
            variant: spec.return_mapping.variant(spec.k),
        })
    }

    fn return_map(&self, f_trial: DMat3, alpha: f64, _lame: &Lame) -> (DMat3, f64) {
        let r = return_map(f_trial, alpha, &self.params, self.variant);
        (r.f, r.alpha)
    }

    fn initial_alpha(&self) -> f64 {
        self.params.alpha0
    }

    /// The share of the initial cohesion −α₀ that α has lost, clamp((α − α₀)/(−α₀), 0, 1):
    /// 0 when fresh or compacted, 1 at α ≥ 0, where the material holds no tension (1
    /// everywhere for a material that starts without cohesion, α₀ ≥ 0).
    fn damage(&self, alpha: f64) -> f64 {
        let a0 = self.params.alpha0;
        if a0 < 0.0 {
            ((alpha - a0) / -a0).clamp(0.0, 1.0)
        } else {
            1.0
        }
    }

    fn gpu_params(&self, _lame: &Lame) -> [f32; PLASTIC_PARAMS] {
        let k = match self.variant {
            Case3Variant::Continuous { k } => k,
            Case3Variant::Center | Case3Variant::ClosestPoint => 0.0,
        };
        let p = &self.params;
        [
            p.beta as f32,
            p.xi as f32,
            p.m_slope as f32,
            k as f32,
            f32::from_bits(self.variant.gpu_code()),
            p.alpha0 as f32,
            0.0,
            0.0,
        ]
    }
}

/// The law's WGSL: `NaccMaterial`, `nacc_return_map` and its helpers, `nacc_material` and
/// `nacc_damage`. Needs the simulation's library (`sim::gpu::wgsl::library`) and, for
/// `nacc_material`, `SimMaterial` (`sim::model::wgsl`).
pub const WGSL_MODULE: &str = include_str!("../../../../shaders/sim/model/nacc.wgsl");

/// The WGSL `NaccMaterial` (32 bytes), as the tests hand it to `nacc_return_map`
/// directly: κ and μ computed here in f64, then rounded.
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

    /// The Rust mirror of `NaccMaterial` has the WGSL layout, read by naga from the law's
    /// module after the library and the registry's WGSL.
    #[test]
    fn material_layout_matches_the_wgsl() {
        let src = format!(
            "{}\n{}",
            crate::sim::gpu::wgsl::library(),
            crate::sim::model::wgsl()
        );
        let module = crate::gpu::layout_check::validated_module(&src);
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
        assert_eq!(members.len(), rust.len());
        for (m, (name, off)) in members.iter().zip(rust) {
            assert_eq!(m.name.as_deref(), Some(name));
            assert_eq!(m.offset as usize, off, "{name}");
        }
    }
}
