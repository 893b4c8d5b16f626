//! Material regions of a simulated object (`physics.regions`, docs/method.md §5): the watermelon's
//! rind, flesh and seeds are one object with three materials. Each region selects particles
//! by depth below the surface (`shell`), by a world box or ball (`box`, `sphere`, as
//! `physics.select`) or by the Gaussians' label (`label`), and gives them its own material
//! and, optionally, an interior colour for its fill particles. The first matching region
//! wins; particles in no region keep the object's `material`.

use glam::DVec3;

use super::physics::{RegionSpec, SelectSpec, ShellRange};
use super::SceneError;
use crate::sim::Material;

/// Most regions one object may have (the GPU step holds 16 materials for the whole scene).
pub const MAX_REGIONS: usize = 15;

/// A region's test, validated.
#[derive(Clone, Debug)]
enum Test {
    Shell { from: f64, to: f64 },
    Select(SelectSpec),
    Label(u16),
}

/// What a particle is matched on.
pub struct ParticleKey {
    /// World position at rest.
    pub x: DVec3,
    /// Depth below the object's surface (world units).
    pub depth: f64,
    /// Index into the object's label names, if the particle has a label.
    pub label: Option<u16>,
}

/// An object's regions, validated and with their materials built.
pub struct ObjectRegions {
    tests: Vec<Test>,
    /// Per region: its material and density.
    pub materials: Vec<(Material, f64)>,
    /// Per region: the DC colour of its fill particles, if it sets one.
    pub fill_dc: Vec<Option<[f32; 3]>>,
}

impl ObjectRegions {
    /// Check `specs` (the regions of `objects[object]`) and build their materials.
    /// `labels` are the labels the object's Gaussians carry, as (name, id) (empty when it
    /// has none).
    pub fn build(
        origin: &str,
        object: usize,
        specs: &[RegionSpec],
        labels: &[(String, u16)],
    ) -> Result<Self, SceneError> {
        let base = format!("objects[{object}].physics.regions");
        if specs.len() > MAX_REGIONS {
            return Err(SceneError::invalid(
                origin,
                base,
                format!("{} regions", specs.len()),
                format!("at most {MAX_REGIONS} regions"),
            ));
        }
        let mut out = ObjectRegions {
            tests: Vec::with_capacity(specs.len()),
            materials: Vec::with_capacity(specs.len()),
            fill_dc: Vec::with_capacity(specs.len()),
        };
        for (j, spec) in specs.iter().enumerate() {
            let field = format!("{base}[{j}]");
            out.tests.push(spec.test(origin, &field, labels)?);
            let material = spec.material.build(origin, &format!("{field}.material"))?;
            out.materials.push((material, spec.material.density()));
            if let Some(c) = spec.color {
                if !c.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)) {
                    return Err(SceneError::invalid(
                        origin,
                        format!("{field}.color"),
                        format!("{c:?}"),
                        "three numbers in [0, 1] (linear RGB)",
                    ));
                }
            }
            out.fill_dc
                .push(spec.color.map(crate::splat::sh::rgb_to_dc));
        }
        Ok(out)
    }

    pub fn is_empty(&self) -> bool {
        self.tests.is_empty()
    }

    /// Whether any region needs depths below the surface.
    pub fn needs_depth(&self) -> bool {
        self.tests.iter().any(|t| matches!(t, Test::Shell { .. }))
    }

    /// The first region the particle lies in, or None (the object's own material).
    pub fn region_of(&self, key: &ParticleKey) -> Option<usize> {
        self.tests.iter().position(|t| match t {
            Test::Shell { from, to } => key.depth >= *from && key.depth < *to,
            Test::Select(s) => s.contains(key.x),
            Test::Label(l) => key.label == Some(*l),
        })
    }
}

impl RegionSpec {
    /// The validated test: exactly one selector with sane values.
    fn test(
        &self,
        origin: &str,
        field: &str,
        labels: &[(String, u16)],
    ) -> Result<Test, SceneError> {
        let given: Vec<&str> = [
            ("shell", self.shell.is_some()),
            ("box", self.box_region.is_some()),
            ("sphere", self.sphere.is_some()),
            ("label", self.label.is_some()),
        ]
        .iter()
        .filter(|(_, set)| *set)
        .map(|(name, _)| *name)
        .collect();
        if given.len() != 1 {
            return Err(SceneError::invalid(
                origin,
                field.to_string(),
                if given.is_empty() {
                    "no selector".to_string()
                } else {
                    given.join(" and ")
                },
                "exactly one of `shell`, `box`, `sphere` or `label`",
            ));
        }
        if let Some(ShellRange { from, to }) = &self.shell {
            if !(from.is_finite() && to.is_finite() && *from >= 0.0 && to > from) {
                return Err(SceneError::invalid(
                    origin,
                    format!("{field}.shell"),
                    format!("from {from} to {to}"),
                    "finite depths with 0 ≤ from < to (world units below the surface)",
                ));
            }
            return Ok(Test::Shell {
                from: *from,
                to: *to,
            });
        }
        if let Some(b) = &self.box_region {
            let s = SelectSpec::Box { lo: b.lo, hi: b.hi };
            s.validate(origin, field)?;
            return Ok(Test::Select(s));
        }
        if let Some(b) = &self.sphere {
            let s = SelectSpec::Sphere {
                center: b.center,
                radius: b.radius,
            };
            s.validate(origin, field)?;
            return Ok(Test::Select(s));
        }
        let label = self.label.as_deref().unwrap_or_default();
        match labels.iter().find(|(n, _)| n == label) {
            Some((_, id)) => Ok(Test::Label(*id)),
            None => Err(SceneError::invalid(
                origin,
                format!("{field}.label"),
                format!("{label:?}"),
                if labels.is_empty() {
                    "a label of the object's Gaussians (this object has no labels)".to_string()
                } else {
                    let names: Vec<&str> = labels.iter().map(|(n, _)| n.as_str()).collect();
                    format!("one of the object's labels: {}", names.join(", "))
                },
            )),
        }
    }
}
