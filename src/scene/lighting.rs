//! The scene file's `lighting` block and per-object `shading` (docs/scene-format.md,
//! docs/relighting.md): point lights on keyframed paths, ambient light, shadows, and the
//! per-object Blinn-Phong weights; [`prepare`] turns them into the renderer's
//! [`LightingSetup`] (normals by PCA per object) and [`SceneLights::at`] gives each frame's
//! lights.

use glam::Vec3;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::simulation::{PartKind, SplatPart};
use super::{BuildReport, Scene, SceneError};
use crate::derive::normals::{spacing_of, RecomputedObject};
use crate::relight::normals::{pca_normals, DEFAULT_K};
use crate::relight::shadow::VolumeGrid;
use crate::relight::{oct_encode, PointLight, ShadingParams, MAX_LIGHTS};
use crate::render::gpu::lighting::LightingSetup;
use crate::render::Splats;
use crate::spline::KeyedPoint;

fn one3() -> [f32; 3] {
    [1.0; 3]
}
fn one() -> f32 {
    1.0
}
fn default_k() -> usize {
    DEFAULT_K
}

/// `lighting`: without it, scenes keep their plain 3DGS colours.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LightingSpec {
    /// Ambient light I_a (linear RGB). Default [1, 1, 1] (scaled per object by
    /// `shading.ambient`, default 0.8).
    #[serde(default = "one3")]
    pub ambient: [f32; 3],
    /// Point lights, at most 8.
    #[serde(default)]
    pub lights: Vec<LightSpec>,
    /// Shadows. Default on, 64 voxels along the longest side of the scene.
    #[serde(default)]
    pub shadows: ShadowSpec,
    /// Neighbours per PCA normal. Default 30.
    #[serde(default = "default_k")]
    pub normal_neighbours: usize,
    /// How simulated objects keep their normals: `transport` (n = F⁻ᵀ n₀ on the GPU, in
    /// the derive pass: free, and exact while the material deforms smoothly), `recompute`
    /// (PCA in the deformed configuration every frame, on the GPU: follows fracture faces), or `auto`: recompute for
    /// objects that can fracture (NACC), transport for elastic ones. Default `auto`.
    #[serde(default)]
    pub simulated_normals: NormalMode,
}

/// `lighting.simulated_normals`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum NormalMode {
    #[default]
    Auto,
    Transport,
    Recompute,
}

/// A point light: fixed (`position`) or moving (`keyframes`).
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LightSpec {
    /// Where the light is, when it does not move.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position: Option<[f32; 3]>,
    /// A path: positions splined like the camera's, colour and intensity linear.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub keyframes: Vec<LightKey>,
    /// Colour (linear RGB). Default white.
    #[serde(default = "one3")]
    pub color: [f32; 3],
    /// Intensity: the light delivers colour × intensity / r² at distance r. Default 1.
    #[serde(default = "one")]
    pub intensity: f32,
}

/// One keyframe of a moving light; colour and intensity default to the light's.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LightKey {
    /// Seconds; strictly increasing.
    pub time: f32,
    pub position: [f32; 3],
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<[f32; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub intensity: Option<f32>,
}

/// `lighting.shadows`.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ShadowSpec {
    /// Cast shadows. Default true.
    #[serde(default = "yes")]
    pub enabled: bool,
    /// Voxels of the shadow volume along the scene's longest side, 8..=256. Default 64.
    #[serde(default = "default_resolution")]
    pub resolution: u32,
}

fn yes() -> bool {
    true
}
fn default_resolution() -> u32 {
    64
}

impl Default for ShadowSpec {
    fn default() -> Self {
        ShadowSpec {
            enabled: true,
            resolution: default_resolution(),
        }
    }
}

/// An object's `shading`: Blinn-Phong weights (defaults: the paper's code's).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ShadingSpec {
    /// Ambient weight. Default 0.8.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ambient: Option<f32>,
    /// Diffuse weight. Default 0.4.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diffuse: Option<f32>,
    /// Specular weight. Default 0.1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub specular: Option<f32>,
    /// Shininess exponent. Default 32.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shininess: Option<f32>,
}

impl ShadingSpec {
    pub fn params(&self) -> ShadingParams {
        let d = ShadingParams::default();
        ShadingParams {
            ambient: self.ambient.unwrap_or(d.ambient),
            diffuse: self.diffuse.unwrap_or(d.diffuse),
            specular: self.specular.unwrap_or(d.specular),
            shininess: self.shininess.unwrap_or(d.shininess),
        }
    }
}

fn check_color(o: &str, field: String, c: [f32; 3]) -> Result<(), SceneError> {
    if c.iter().all(|v| v.is_finite() && *v >= 0.0) {
        Ok(())
    } else {
        Err(SceneError::invalid(
            o,
            field,
            format!("{c:?}"),
            "finite values ≥ 0",
        ))
    }
}

fn check_weight(o: &str, field: String, v: f32) -> Result<(), SceneError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(SceneError::invalid(o, field, v, "a finite number ≥ 0"))
    }
}

impl LightingSpec {
    /// Check every value; errors name the field.
    pub fn validate(&self, o: &str) -> Result<(), SceneError> {
        check_color(o, "lighting.ambient".into(), self.ambient)?;
        if self.lights.len() > MAX_LIGHTS {
            return Err(SceneError::invalid(
                o,
                "lighting.lights",
                format!("{} lights", self.lights.len()),
                format!("at most {MAX_LIGHTS}"),
            ));
        }
        if !(3..=256).contains(&self.normal_neighbours) {
            return Err(SceneError::invalid(
                o,
                "lighting.normal_neighbours",
                self.normal_neighbours,
                "3 to 256",
            ));
        }
        if !(8..=256).contains(&self.shadows.resolution) {
            return Err(SceneError::invalid(
                o,
                "lighting.shadows.resolution",
                self.shadows.resolution,
                "8 to 256 voxels",
            ));
        }
        for (i, l) in self.lights.iter().enumerate() {
            let f = |name: &str| format!("lighting.lights[{i}].{name}");
            check_color(o, f("color"), l.color)?;
            check_weight(o, f("intensity"), l.intensity)?;
            match (&l.position, l.keyframes.is_empty()) {
                (Some(p), true) => {
                    if !p.iter().all(|v| v.is_finite()) {
                        return Err(SceneError::invalid(
                            o,
                            f("position"),
                            format!("{p:?}"),
                            "finite coordinates",
                        ));
                    }
                }
                (None, false) => {
                    for (k, key) in l.keyframes.iter().enumerate() {
                        let g = |name: &str| format!("lighting.lights[{i}].keyframes[{k}].{name}");
                        if !key.time.is_finite() || (k > 0 && key.time <= l.keyframes[k - 1].time) {
                            return Err(SceneError::invalid(
                                o,
                                g("time"),
                                key.time,
                                "finite times that strictly increase",
                            ));
                        }
                        if !key.position.iter().all(|v| v.is_finite()) {
                            return Err(SceneError::invalid(
                                o,
                                g("position"),
                                format!("{:?}", key.position),
                                "finite coordinates",
                            ));
                        }
                        if let Some(c) = key.color {
                            check_color(o, g("color"), c)?;
                        }
                        if let Some(v) = key.intensity {
                            check_weight(o, g("intensity"), v)?;
                        }
                    }
                }
                _ => {
                    return Err(SceneError::invalid(
                        o,
                        format!("lighting.lights[{i}]"),
                        "both or neither of position and keyframes",
                        "exactly one of `position` or `keyframes`",
                    ))
                }
            }
        }
        Ok(())
    }
}

/// Validate an object's `shading` (field path `objects[i].shading`).
pub fn validate_shading(o: &str, i: usize, s: &ShadingSpec) -> Result<(), SceneError> {
    let p = s.params();
    for (name, v) in [
        ("ambient", p.ambient),
        ("diffuse", p.diffuse),
        ("specular", p.specular),
    ] {
        check_weight(o, format!("objects[{i}].shading.{name}"), v)?;
    }
    if !(p.shininess.is_finite() && p.shininess > 0.0) {
        return Err(SceneError::invalid(
            o,
            format!("objects[{i}].shading.shininess"),
            p.shininess,
            "a finite number > 0",
        ));
    }
    Ok(())
}

/// The lights of a scene over time.
#[derive(Clone, Debug)]
pub struct SceneLights {
    lights: Vec<KeyedPoint>,
}

impl SceneLights {
    /// The point lights at `seconds`.
    pub fn at(&self, seconds: f32) -> Vec<PointLight> {
        self.lights
            .iter()
            .map(|l| {
                let (position, radiance) = l.at(seconds);
                PointLight { position, radiance }
            })
            .collect()
    }
}

/// What a run needs to relight a scene.
pub struct SceneLighting {
    pub setup: LightingSetup,
    pub lights: SceneLights,
    /// Seconds spent on PCA normals.
    pub normals_seconds: f64,
    /// The simulated objects' Gaussian ranges whose normals are recomputed every frame
    /// on the GPU (`derive::normals`; empty in `transport` mode).
    pub recompute: Vec<std::ops::Range<usize>>,
}

impl SceneLighting {
    /// The objects whose normals the GPU recomputes every frame, with their Gaussians'
    /// spacing at rest (from `splats`, the uploaded Gaussians).
    pub fn recomputed_objects(&self, splats: &Splats) -> Vec<RecomputedObject> {
        self.recompute
            .iter()
            .map(|r| RecomputedObject {
                range: r.clone(),
                spacing: spacing_of(&splats.means[r.clone()]),
            })
            .collect()
    }
}

/// The relighting of `scene` whose Gaussians `splats` hold the objects in the order the
/// run uploads them: file order with the counts of `report`, or — when simulating — the
/// simulation's `parts` (static runs first, then each simulated object's selected
/// Gaussians and fill; see `simulation::prepare`). None when
/// the scene has no `lighting` block. `extra_bounds` (the simulation domain) widens the
/// shadow volume to cover everything that may move.
// Over 80 lines on purpose: normals, shadow grid and lights built in the order each needs the
// one before, for one setup.
pub fn prepare(
    scene: &Scene,
    splats: &Splats,
    report: &BuildReport,
    parts: Option<&[SplatPart]>,
    extra_bounds: Option<(Vec3, Vec3)>,
) -> Result<Option<SceneLighting>, SceneError> {
    let Some(spec) = &scene.lighting else {
        return Ok(None);
    };
    let o = scene.origin.as_str();
    spec.validate(o)?;
    // Runs of one object's Gaussians: the simulation's parts (a simulated object's
    // selected Gaussians and its fill merged into one run), or whole objects in file order.
    let mut runs: Vec<(usize, std::ops::Range<usize>, bool)> = Vec::new();
    match parts {
        Some(parts) => {
            for p in parts {
                let simulated = p.kind != PartKind::Static;
                let range = p.start..p.start + p.len;
                match runs.last_mut() {
                    Some((obj, r, sim))
                        if *obj == p.object && *sim == simulated && r.end == range.start =>
                    {
                        r.end = range.end;
                    }
                    _ => runs.push((p.object, range, simulated)),
                }
            }
        }
        None => {
            let mut at = 0;
            for (i, r) in report.objects.iter().enumerate() {
                runs.push((i, at..at + r.gaussians, false));
                at += r.gaussians;
            }
        }
    }
    let covered: usize = runs.iter().map(|(_, r, _)| r.len()).sum();
    if covered != splats.len()
        || runs
            .iter()
            .any(|(i, r, _)| *i >= scene.objects.len() || r.end > splats.len())
    {
        return Err(SceneError::invalid(
            o,
            "objects",
            format!("{covered} Gaussians in the objects"),
            format!("{} (internal: object counts do not add up)", splats.len()),
        ));
    }
    let start = std::time::Instant::now();
    let mut shading = vec![[0u32; 2]; splats.len()];
    let mut materials = Vec::new();
    let mut material_of = vec![None; scene.objects.len()];
    let mut recompute = Vec::new();
    for (i, range, simulated) in runs {
        let obj = &scene.objects[i];
        let material = match material_of[i] {
            Some(m) => m,
            None => {
                let params = obj.shading.clone().unwrap_or_default();
                validate_shading(o, i, &params)?;
                materials.push(params.params());
                let m = (materials.len() - 1) as u32;
                material_of[i] = Some(m);
                m
            }
        };
        let fractures = obj.physics.as_ref().is_some_and(|p| p.material.fractures());
        let recomputed = match spec.simulated_normals {
            NormalMode::Recompute => true,
            NormalMode::Transport => false,
            NormalMode::Auto => fractures,
        };
        if simulated && recomputed {
            recompute.push(range.clone());
        }
        let normals = pca_normals(&splats.means[range.clone()], spec.normal_neighbours);
        for (slot, n) in shading[range].iter_mut().zip(&normals) {
            *slot = [oct_encode(*n), material];
        }
    }
    let normals_seconds = start.elapsed().as_secs_f64();
    let shadows = spec.shadows.enabled.then(|| {
        let (mut lo, mut hi) = splats.means.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        if let Some((a, b)) = extra_bounds {
            lo = lo.min(a);
            hi = hi.max(b);
        }
        if !lo.is_finite() || !hi.is_finite() {
            (lo, hi) = (Vec3::splat(-1.0), Vec3::splat(1.0));
        }
        VolumeGrid::covering(lo, hi, spec.shadows.resolution)
    });
    let lights = scene_lights(spec);
    Ok(Some(SceneLighting {
        setup: LightingSetup {
            ambient: Vec3::from(spec.ambient),
            materials,
            shading,
            shadows,
            max_lights: spec.lights.len().max(1),
        },
        lights,
        normals_seconds,
        recompute,
    }))
}

/// The lights of `spec` over time.
fn scene_lights(spec: &LightingSpec) -> SceneLights {
    SceneLights {
        lights: spec
            .lights
            .iter()
            .map(|l| {
                let base = Vec3::from(l.color) * l.intensity;
                match l.position {
                    Some(p) => KeyedPoint::new(vec![0.0], vec![Vec3::from(p)], vec![base]),
                    None => KeyedPoint::new(
                        l.keyframes.iter().map(|k| k.time).collect(),
                        l.keyframes.iter().map(|k| Vec3::from(k.position)).collect(),
                        l.keyframes
                            .iter()
                            .map(|k| {
                                Vec3::from(k.color.unwrap_or(l.color))
                                    * k.intensity.unwrap_or(l.intensity)
                            })
                            .collect(),
                    ),
                }
            })
            .collect(),
    }
}

/// Relighting for a render from a saved state (`--from-states`): the state's Gaussians
/// are one cloud with no object boundaries, so they get PCA normals in the state's own
/// (deformed) configuration, the default shading weights, and a shadow volume over the
/// state's bounds. None when the scene has no `lighting` block.
pub fn prepare_state(scene: &Scene, splats: &Splats) -> Result<Option<SceneLighting>, SceneError> {
    let Some(spec) = &scene.lighting else {
        return Ok(None);
    };
    spec.validate(&scene.origin)?;
    let start = std::time::Instant::now();
    let normals = pca_normals(&splats.means, spec.normal_neighbours);
    let normals_seconds = start.elapsed().as_secs_f64();
    let shadows = spec.shadows.enabled.then(|| {
        let (lo, hi) = splats.means.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        if lo.is_finite() && hi.is_finite() {
            VolumeGrid::covering(lo, hi, spec.shadows.resolution)
        } else {
            VolumeGrid::covering(Vec3::splat(-1.0), Vec3::ONE, spec.shadows.resolution)
        }
    });
    Ok(Some(SceneLighting {
        setup: LightingSetup {
            ambient: Vec3::from(spec.ambient),
            materials: vec![ShadingParams::default()],
            shading: normals.iter().map(|n| [oct_encode(*n), 0]).collect(),
            shadows,
            max_lights: spec.lights.len().max(1),
        },
        lights: scene_lights(spec),
        normals_seconds,
        recompute: Vec::new(),
    }))
}
