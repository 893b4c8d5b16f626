//! The scene file's `material` objects (docs/scene-format.md): `model` names a registered
//! elastic model (`fixed_corotated`, `neo_hookean`, `stvk_hencky`) or a registered plastic
//! law (`nacc`, `drucker_prager`, `von_mises`, `snow`: `sim::model`), with `E`, `nu`,
//! `density` and the law's own parameters. Parsing, the schema and the validation of a
//! law's parameters all come from the registry.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

use super::SceneError;
use crate::sim::model::ParseError;
use crate::sim::{ElasticModel, Material, PlasticModel};

/// A material (docs/method.md §3–§4): a registered model by name, its elastic constants
/// and, for a plastic law, its parameters as written.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialSpec {
    pub model: ModelName,
    /// Young's modulus E in Pa.
    pub e: f64,
    /// Poisson ratio ν.
    pub nu: f64,
    /// Density in kg/m³.
    pub density: f64,
    /// The plastic law's parameters (empty for an elastic model).
    pub params: Map<String, Value>,
}

/// A model the scene file can name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelName {
    Elastic(ElasticModel),
    Plastic(PlasticModel),
}

impl ModelName {
    pub fn from_name(name: &str) -> Option<ModelName> {
        ElasticModel::from_name(name)
            .map(ModelName::Elastic)
            .or_else(|| PlasticModel::from_name(name).map(ModelName::Plastic))
    }

    pub fn name(self) -> &'static str {
        match self {
            ModelName::Elastic(m) => m.def().name,
            ModelName::Plastic(m) => m.name(),
        }
    }

    /// Every name a scene file can give, elastic models first.
    pub fn all() -> Vec<&'static str> {
        let elastic = ElasticModel::ALL.iter().map(|m| m.def().name);
        elastic
            .chain(PlasticModel::LAWS.iter().map(|m| m.name()))
            .collect()
    }
}

fn unknown_model(name: &str) -> String {
    format!(
        "unknown material model `{name}`, expected one of {}",
        ModelName::all()
            .iter()
            .map(|n| format!("`{n}`"))
            .collect::<Vec<_>>()
            .join(", ")
    )
}

/// The keys every material has.
const COMMON: [&str; 4] = ["model", "E", "nu", "density"];

impl Serialize for MaterialSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = s.serialize_map(Some(4 + self.params.len()))?;
        map.serialize_entry("model", self.model.name())?;
        map.serialize_entry("E", &self.e)?;
        map.serialize_entry("nu", &self.nu)?;
        map.serialize_entry("density", &self.density)?;
        for (key, value) in &self.params {
            map.serialize_entry(key, value)?;
        }
        map.end()
    }
}

impl<'de> Deserialize<'de> for MaterialSpec {
    /// By `model`; a plastic law's parameters are read by its own type (unknown or
    /// mistyped fields refused here), their ranges checked by [`MaterialSpec::build`].
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let mut object = Map::deserialize(d)?;
        let model = match object.remove("model") {
            Some(Value::String(m)) => m,
            Some(other) => {
                return Err(D::Error::custom(format!(
                    "`model` {other}: expected a string"
                )))
            }
            None => return Err(D::Error::missing_field("model")),
        };
        let model =
            ModelName::from_name(&model).ok_or_else(|| D::Error::custom(unknown_model(&model)))?;
        let mut number = |key: &'static str| match object.remove(key) {
            Some(v) => v
                .as_f64()
                .ok_or_else(|| D::Error::custom(format!("`{key}` {v}: expected a number"))),
            None => Err(D::Error::missing_field(key)),
        };
        let (e, nu, density) = (number("E")?, number("nu")?, number("density")?);
        let spec = MaterialSpec {
            model,
            e,
            nu,
            density,
            params: object,
        };
        match model {
            ModelName::Elastic(_) => {
                if let Some(key) = spec.params.keys().next() {
                    return Err(D::Error::custom(format!(
                        "unknown field `{key}` for the elastic model `{}`, expected one of {}",
                        model.name(),
                        COMMON.map(|k| format!("`{k}`")).join(", ")
                    )));
                }
            }
            ModelName::Plastic(law) => {
                if let Err(ParseError::Json(e)) =
                    law.parse(Value::Object(spec.params.clone()), e, nu)
                {
                    return Err(D::Error::custom(format!("{} parameters: {e}", law.name())));
                }
            }
        }
        Ok(spec)
    }
}

/// The schema of one elastic model's material.
fn elastic_schema() -> schemars::Schema {
    schemars::json_schema!({
        "description": "An elastic material, no plasticity (docs/method.md §3).",
        "type": "object",
        "properties": {
            "model": { "type": "string", "enum": ElasticModel::ALL.iter().map(|m| m.def().name).collect::<Vec<_>>() },
            "E": { "type": "number", "description": "Young's modulus in Pa (> 0)" },
            "nu": { "type": "number", "description": "Poisson ratio in (−1, 0.5)" },
            "density": { "type": "number", "description": "density in kg/m³ (> 0)" }
        },
        "required": ["model", "E", "nu", "density"],
        "additionalProperties": false
    })
}

/// The schema of a plastic law's material: the common keys and the law's parameters.
fn plastic_schema(
    law: PlasticModel,
    generator: &mut schemars::SchemaGenerator,
) -> schemars::Schema {
    let mut schema = elastic_schema();
    let params = law.params_schema(generator);
    let object = schema.as_object_mut().expect("an object schema");
    object.insert(
        "description".into(),
        format!(
            "The plastic law `{}` on {} elasticity (docs/method.md §4); α holds {}.",
            law.name(),
            law.elastic().map_or("any", |m| m.def().name),
            law.alpha_meaning()
        )
        .into(),
    );
    object["properties"]["model"] = serde_json::json!({ "const": law.name() });
    if let Some(Value::Object(props)) = params.get("properties") {
        let target = object["properties"].as_object_mut().expect("properties");
        target.extend(props.clone());
    }
    if let Some(Value::Array(required)) = params.get("required") {
        object["required"]
            .as_array_mut()
            .expect("required")
            .extend(required.clone());
    }
    schema
}

impl JsonSchema for MaterialSpec {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "MaterialSpec".into()
    }
    fn json_schema(generator: &mut schemars::SchemaGenerator) -> schemars::Schema {
        let mut one_of = vec![elastic_schema()];
        for &law in PlasticModel::LAWS {
            one_of.push(plastic_schema(law, generator));
        }
        schemars::json_schema!({
            "description": "A material: a registered elastic model, or a registered plastic law on its elasticity (docs/method.md §3–§4).",
            "oneOf": one_of
        })
    }
}

impl MaterialSpec {
    pub fn density(&self) -> f64 {
        self.density
    }

    /// Whether the material breaks into pieces (its plastic law's α measures damage).
    pub fn fractures(&self) -> bool {
        matches!(self.model, ModelName::Plastic(law) if law.fractures())
    }

    /// Check the values and build the material; `field` names it in errors.
    pub fn build(&self, origin: &str, field: &str) -> Result<Material, SceneError> {
        let bad = |name: &str, v: f64, expected: &str| {
            SceneError::invalid(origin, format!("{field}.{name}"), v, expected)
        };
        let (e, nu, density) = (self.e, self.nu, self.density);
        if !(e.is_finite() && e > 0.0) {
            return Err(bad("E", e, "Young's modulus > 0"));
        }
        if !(nu.is_finite() && nu > -1.0 && nu < 0.5) {
            return Err(bad("nu", nu, "a Poisson ratio in (−1, 0.5)"));
        }
        if !(density.is_finite() && density > 0.0) {
            return Err(bad("density", density, "a density > 0"));
        }
        match self.model {
            ModelName::Elastic(model) => Ok(Material::elastic(model, e, nu)),
            ModelName::Plastic(law) => {
                let plastic = law
                    .parse(Value::Object(self.params.clone()), e, nu)
                    .map_err(|err| match err {
                        ParseError::Param(p) => SceneError::invalid(
                            origin,
                            format!("{field}.{}", p.field),
                            p.value,
                            p.expected,
                        ),
                        ParseError::Json(j) => SceneError::invalid(
                            origin,
                            field.to_string(),
                            law.name(),
                            j.to_string(),
                        ),
                    })?;
                Ok(Material::with_plastic(plastic, e, nu))
            }
        }
    }
}

/// The scene file's plastic laws and their parameters as a markdown table, from the
/// registry and the parameters' doc comments (the table in docs/scene-format.md).
pub fn materials_table() -> String {
    let mut generator = schemars::SchemaGenerator::default();
    let mut out =
        String::from("| `model` | elasticity | parameter | meaning |\n|---|---|---|---|\n");
    for &law in PlasticModel::LAWS {
        let schema = law.params_schema(&mut generator);
        let elastic = law.elastic().map_or("", |m| m.def().name);
        let required: Vec<&str> = schema
            .get("required")
            .and_then(Value::as_array)
            .map(|r| r.iter().filter_map(Value::as_str).collect())
            .unwrap_or_default();
        let props = schema.get("properties").and_then(Value::as_object);
        for (name, prop) in props.into_iter().flatten() {
            let description = prop
                .get("description")
                .and_then(Value::as_str)
                .unwrap_or("")
                .replace('\n', " ");
            let need = if required.contains(&name.as_str()) {
                " (required)"
            } else {
                ""
            };
            out += &format!(
                "| `{}` | `{elastic}` | `{name}`{need} | {description} |\n",
                law.name()
            );
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// docs/scene-format.md carries the registry's table of the plastic laws' parameters
    /// as `materials_table` writes it (paste the printed table when a law changes).
    #[test]
    fn the_docs_table_is_the_registrys() {
        let docs = include_str!("../../docs/scene-format.md");
        let table = materials_table();
        assert!(
            docs.contains(&table),
            "docs/scene-format.md's table of plastic laws is out of date; the registry's:\n{table}"
        );
    }

    /// Every registered name parses, and no elastic model shares a name with a law.
    #[test]
    fn registered_names_are_distinct_and_parse() {
        let names = ModelName::all();
        let unique: std::collections::HashSet<_> = names.iter().collect();
        assert_eq!(unique.len(), names.len(), "{names:?}");
        assert!(!names.contains(&"none"));
    }

    /// A material reads and writes back as written, and a law's range error names the
    /// field.
    #[test]
    fn round_trip_and_errors() {
        let text = r#"{"model":"von_mises","E":1000000.0,"nu":0.3,"density":1000.0,"yield_stress":5000.0}"#;
        let spec: MaterialSpec = serde_json::from_str(text).unwrap();
        assert_eq!(serde_json::to_string(&spec).unwrap(), text);
        let m = spec.build("s.json", "m").unwrap();
        assert_eq!(m.plastic_model(), PlasticModel::VonMises);
        assert_eq!(m.elastic_model(), ElasticModel::StvkHencky);
        let bad: MaterialSpec = serde_json::from_str(&text.replace("5000.0", "-1.0")).unwrap();
        let err = bad.build("s.json", "m").unwrap_err().to_string();
        assert!(err.contains("m.yield_stress"), "{err}");
        for refused in [
            r#"{"model":"von_mises","E":1e6,"nu":0.3,"density":1000,"yield":5}"#,
            r#"{"model":"neo_hookean","E":1e6,"nu":0.3,"density":1000,"yield_stress":5}"#,
            r#"{"model":"sand","E":1e6,"nu":0.3,"density":1000}"#,
            r#"{"model":"snow","nu":0.3,"density":1000}"#,
        ] {
            assert!(
                serde_json::from_str::<MaterialSpec>(refused).is_err(),
                "{refused}"
            );
        }
    }
}
