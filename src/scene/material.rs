//! The scene file's `material` objects (docs/scene-format.md): a registered elastic model
//! or NACC, parsed, validated and turned into [`crate::sim::Material`].

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::SceneError;
use crate::sim::nacc::{m_from_friction_angle, Case3Variant, NaccParams};
use crate::sim::{ElasticModel, Material};

/// A material (docs/method.md §3–§4, parameters as in the paper's table): `model` is a
/// registered elastic model (`sim::models`: `fixed_corotated`, `neo_hookean`, …) or
/// `nacc`.
#[derive(Clone, Debug)]
pub enum MaterialSpec {
    /// Elastic, no plasticity.
    Elastic(ElasticSpec),
    /// CD-MPM: Non-Associated Cam-Clay on Neo-Hookean, with hardening.
    Nacc(NaccSpec),
}

/// An elastic material of a registered model.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ElasticSpec {
    pub model: ElasticModelName,
    #[serde(rename = "E")]
    pub e: f64,
    pub nu: f64,
    pub density: f64,
}

/// A NACC material.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NaccSpec {
    pub model: NaccTag,
    #[serde(rename = "E")]
    pub e: f64,
    pub nu: f64,
    pub density: f64,
    pub alpha0: f64,
    pub beta: f64,
    pub xi: f64,
    /// Slope M of the critical-state line (or give `friction_angle_deg`).
    #[serde(rename = "M", default, skip_serializing_if = "Option::is_none")]
    pub m_slope: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction_angle_deg: Option<f64>,
    /// Case-3 return mapping: `center`, `continuous` (default) or `closest_point`.
    #[serde(default = "default_mapping")]
    pub return_mapping: ReturnMappingSpec,
    /// Exponent k of the `continuous` mapping. Default 2.
    #[serde(default = "default_k")]
    pub k: f64,
}

/// `"model": "nacc"`.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum NaccTag {
    Nacc,
}

/// A registered elastic model, by its name in the scene file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ElasticModelName(pub ElasticModel);

fn elastic_names() -> Vec<&'static str> {
    ElasticModel::ALL.iter().map(|m| m.def().name).collect()
}

impl Serialize for ElasticModelName {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.0.def().name)
    }
}

impl<'de> Deserialize<'de> for ElasticModelName {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        ElasticModel::from_name(&name)
            .map(ElasticModelName)
            .ok_or_else(|| serde::de::Error::custom(unknown_model(&name)))
    }
}

impl JsonSchema for ElasticModelName {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "ElasticModelName".into()
    }
    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({ "type": "string", "enum": elastic_names() })
    }
}

fn unknown_model(name: &str) -> String {
    format!(
        "unknown material model `{name}`, expected one of {}, `nacc`",
        elastic_names()
            .iter()
            .map(|n| format!("`{n}`"))
            .collect::<Vec<_>>()
            .join(", ")
    )
}

impl Serialize for MaterialSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            MaterialSpec::Elastic(m) => m.serialize(s),
            MaterialSpec::Nacc(m) => m.serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for MaterialSpec {
    /// By `model`: `nacc`, or a registered elastic model.
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let value = serde_json::Value::deserialize(d)?;
        let model = match value.get("model") {
            Some(serde_json::Value::String(m)) => m.clone(),
            Some(other) => {
                return Err(D::Error::custom(format!(
                    "`model` {other}: expected a string"
                )))
            }
            None => return Err(D::Error::missing_field("model")),
        };
        if model == "nacc" {
            NaccSpec::deserialize(value)
                .map(MaterialSpec::Nacc)
                .map_err(D::Error::custom)
        } else if ElasticModel::from_name(&model).is_some() {
            ElasticSpec::deserialize(value)
                .map(MaterialSpec::Elastic)
                .map_err(D::Error::custom)
        } else {
            Err(D::Error::custom(unknown_model(&model)))
        }
    }
}

impl JsonSchema for MaterialSpec {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "MaterialSpec".into()
    }
    fn json_schema(generator: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "description": "A material: a registered elastic model, or NACC (docs/method.md §3–§4).",
            "oneOf": [generator.subschema_for::<ElasticSpec>(), generator.subschema_for::<NaccSpec>()]
        })
    }
}

fn default_mapping() -> ReturnMappingSpec {
    ReturnMappingSpec::Continuous
}
fn default_k() -> f64 {
    2.0
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum ReturnMappingSpec {
    Center,
    Continuous,
    ClosestPoint,
}

impl MaterialSpec {
    pub fn density(&self) -> f64 {
        match self {
            MaterialSpec::Elastic(m) => m.density,
            MaterialSpec::Nacc(m) => m.density,
        }
    }

    /// Check the values and build the material; `field` names it in errors.
    pub fn build(&self, origin: &str, field: &str) -> Result<Material, SceneError> {
        let bad = |name: &str, v: f64, expected: &str| {
            SceneError::invalid(origin, format!("{field}.{name}"), v, expected)
        };
        let (e, nu, density) = match self {
            MaterialSpec::Elastic(m) => (m.e, m.nu, m.density),
            MaterialSpec::Nacc(m) => (m.e, m.nu, m.density),
        };
        if !(e.is_finite() && e > 0.0) {
            return Err(bad("E", e, "Young's modulus > 0"));
        }
        if !(nu.is_finite() && nu > -1.0 && nu < 0.5) {
            return Err(bad("nu", nu, "a Poisson ratio in (−1, 0.5)"));
        }
        if !(density.is_finite() && density > 0.0) {
            return Err(bad("density", density, "a density > 0"));
        }
        Ok(match self {
            MaterialSpec::Elastic(m) => Material::elastic(m.model.0, e, nu),
            MaterialSpec::Nacc(NaccSpec {
                alpha0,
                beta,
                xi,
                m_slope,
                friction_angle_deg,
                return_mapping,
                k,
                ..
            }) => {
                let m_slope = match (m_slope, friction_angle_deg) {
                    (Some(m), None) if m.is_finite() && *m > 0.0 => *m,
                    (Some(m), None) => return Err(bad("M", *m, "a slope > 0")),
                    (None, Some(phi)) if phi.is_finite() && *phi > 0.0 && *phi < 90.0 => {
                        m_from_friction_angle(phi.to_radians())
                    }
                    (None, Some(phi)) => {
                        return Err(bad("friction_angle_deg", *phi, "an angle in (0, 90)"))
                    }
                    _ => {
                        return Err(SceneError::invalid(
                            origin,
                            field.to_string(),
                            "M and friction_angle_deg",
                            "exactly one of `M` or `friction_angle_deg`",
                        ))
                    }
                };
                for (name, v, ok) in [
                    ("alpha0", *alpha0, alpha0.is_finite()),
                    ("beta", *beta, beta.is_finite() && *beta >= 0.0),
                    ("xi", *xi, xi.is_finite() && *xi >= 0.0),
                    ("k", *k, k.is_finite() && *k > 0.0),
                ] {
                    if !ok {
                        return Err(bad(name, v, "a finite value (β, ξ ≥ 0; k > 0)"));
                    }
                }
                let variant = match return_mapping {
                    ReturnMappingSpec::Center => Case3Variant::Center,
                    ReturnMappingSpec::Continuous => Case3Variant::Continuous { k: *k },
                    ReturnMappingSpec::ClosestPoint => Case3Variant::ClosestPoint,
                };
                Material::Nacc {
                    params: NaccParams {
                        e,
                        nu,
                        alpha0: *alpha0,
                        beta: *beta,
                        xi: *xi,
                        m_slope,
                    },
                    variant,
                }
            }
        })
    }
}
