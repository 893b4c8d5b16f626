//! The scene file (JSON): schema, validation, camera paths.
//!
//! A scene names the output (size, frame count, frame rate, background), the camera (its
//! intrinsics and a path: orbit, keyframes or an INRIA `cameras.json`) and the objects (PLY
//! files or procedural solids, each with a transform). `docs/scene-format.md` documents every
//! field; [`schema`] prints the JSON Schema.
//!
//! Parsing is strict: unknown keys are errors, and every number is checked after parsing
//! ([`Scene::validate`]). Errors name the file, the field path and the offending value.

pub mod actions;
mod build;
pub mod cameras;
pub mod fill;
pub mod kinematic;
pub mod lighting;
pub mod material;
pub(crate) mod path;
pub mod physics;
pub mod quality;
pub mod regions;
pub mod simulation;
pub mod surface;
mod up;
mod validate;

pub use build::{BuildReport, ObjectReport};
pub use up::{cameras_next_to, inspect_capture, CaptureUp};
pub(crate) use validate::{mat3_from_rows, rotation_problem};

use std::fmt::Display;
use std::path::{Path, PathBuf};

use glam::{Mat3, Vec3};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::splat::procedural::{ProceduralError, ProceduralSpec};

pub use path::{from_camera_file, from_cameras_json, CameraPath};

/// The embedded default scene (`scenes/default.json`).
pub const DEFAULT_SCENE_JSON: &str = include_str!("../../scenes/default.json");

/// Largest accepted image width or height, in pixels.
pub const MAX_IMAGE_SIZE: u32 = 16384;

/// Largest accepted frame count.
pub const MAX_FRAMES: u32 = 1_000_000;

/// Everything that can go wrong reading, validating or building a scene. `Display` is one line
/// that names the file (and, for parse errors, the line and column).
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("cannot read {}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// Malformed JSON or a key/type the schema does not allow.
    #[error("{origin}:{line}:{column}: {message}")]
    Parse {
        origin: String,
        line: usize,
        column: usize,
        message: String,
    },
    /// A value outside its allowed range.
    #[error("{origin}: {field} = {value}: expected {expected}")]
    Invalid {
        origin: String,
        field: String,
        value: String,
        expected: String,
    },
    /// Loading or generating object `index` failed.
    #[error("{origin}: objects[{index}] ({name}): {message}")]
    Object {
        origin: String,
        index: usize,
        name: String,
        message: String,
    },
}

impl SceneError {
    fn invalid(
        origin: &str,
        field: impl Into<String>,
        value: impl Display,
        expected: impl Into<String>,
    ) -> Self {
        SceneError::Invalid {
            origin: origin.to_string(),
            field: field.into(),
            value: one_line(&value.to_string()),
            expected: expected.into(),
        }
    }

    fn parse(origin: &str, err: &serde_json::Error) -> Self {
        let full = err.to_string();
        let suffix = format!(" at line {} column {}", err.line(), err.column());
        let message = full.strip_suffix(&suffix).unwrap_or(&full);
        SceneError::Parse {
            origin: origin.to_string(),
            line: err.line(),
            column: err.column(),
            message: one_line(message),
        }
    }
}

/// Collapse a possibly multi-line message onto one line.
fn one_line(s: &str) -> String {
    s.trim()
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join("; ")
}

// ---------------------------------------------------------------------------------------------
// The file format
// ---------------------------------------------------------------------------------------------

/// A scene file.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Optional JSON Schema reference for editors (e.g. the output of `splatter schema`
    /// saved to a file); ignored by splatter.
    #[serde(rename = "$schema", default, skip_serializing_if = "Option::is_none")]
    pub schema_ref: Option<String>,
    /// What the scene is and where it comes from (free text for readers); ignored.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub description: Option<String>,
    /// What to write: image size, frame count and rate, background, output folder.
    pub output: OutputSpec,
    /// The camera: intrinsics and its path through the frames.
    pub camera: CameraSpec,
    /// The objects drawn, in order.
    #[serde(default)]
    pub objects: Vec<ObjectSpec>,
    /// The MPM simulation of the objects that have `physics` (see docs/physics.md).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub simulation: Option<physics::SimulationSpec>,
    /// Relighting: point lights, ambient light, shadows (see docs/relighting.md). Without
    /// it the Gaussians keep their own colours.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lighting: Option<lighting::LightingSpec>,
    /// Folder that relative paths in the scene (PLY files, cameras.json) resolve against:
    /// the scene file's folder.
    #[serde(skip)]
    pub base_dir: PathBuf,
    /// Where the scene came from (a file name), used in error messages.
    #[serde(skip)]
    pub origin: String,
    /// Scene name: the file stem (`default` for the embedded scene); the default output folder
    /// is `out/<name>`.
    #[serde(skip)]
    pub name: String,
    /// How each `"up": "auto"` was decided, said when the scene runs ([`Scene::resolve_up`]).
    #[serde(skip)]
    pub up_notes: Vec<String>,
    /// An `"up": "auto"` that is only a guess, or a `cameras.json` next to a capture that
    /// could not be read: one line each.
    #[serde(skip)]
    pub up_warnings: Vec<String>,
}

fn default_fps() -> f32 {
    24.0
}

/// The frames to write.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Output folder, relative to the current directory. Default: `out/<scene file stem>`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dir: Option<PathBuf>,
    /// Image width in pixels, 1..=16384.
    pub width: u32,
    /// Image height in pixels, 1..=16384.
    pub height: u32,
    /// Number of frames, ≥ 1. Frame f is at time f / fps.
    pub frames: u32,
    /// Frames per second (> 0). Default 24.
    #[serde(default = "default_fps")]
    pub fps: f32,
    /// Background colour, linear RGB in [0, 1]. Default black.
    #[serde(default)]
    pub background: [f32; 3],
}

fn default_near() -> f32 {
    crate::render::camera::DEFAULT_NEAR
}

fn default_up() -> [f32; 3] {
    [0.0, 0.0, 1.0]
}

/// The camera. Intrinsics: exactly one of `fov_y_deg` or `fx` + `fy` (for a `cameras_json`
/// path both may be left out: the file's intrinsics, rescaled to the output size, are used).
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    /// Vertical field of view in degrees, in (0, 180). Pixels are square (fx = fy).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fov_y_deg: Option<f32>,
    /// Horizontal focal length in pixels (of the output image).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fx: Option<f32>,
    /// Vertical focal length in pixels (of the output image).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fy: Option<f32>,
    /// Near plane (camera-space depth); Gaussians closer than this are culled. Default 0.01.
    #[serde(default = "default_near")]
    pub near: f32,
    /// World up direction. Default [0, 0, 1] (+z up).
    #[serde(default = "default_up")]
    pub up: [f32; 3],
    /// How the camera moves.
    pub path: PathSpec,
}

/// The camera's path through the frames.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum PathSpec {
    /// A circle around `target`, perpendicular to `up`, always looking at the target.
    Orbit(OrbitSpec),
    /// A smooth path through keyframes.
    Keyframes(KeyframesSpec),
    /// The cameras of an INRIA 3DGS `cameras.json`.
    CamerasJson(CamerasJsonSpec),
    /// The registered images of a COLMAP sparse model (a folder such as `sparse/0`, text or
    /// binary), in the order of their names.
    Colmap(CamerasJsonSpec),
    /// The frames of a `transforms.json` (nerfstudio, instant-ngp), in the file's order.
    TransformsJson(CamerasJsonSpec),
    /// A nerfstudio render path (`camera_path.json`), optionally mapped back into the
    /// capture's frame by the run's `dataparser_transforms.json`.
    Nerfstudio(CamerasJsonSpec),
}

impl PathSpec {
    /// The camera file a path reads, and its format (none for orbits and keyframes).
    pub fn camera_file(&self) -> Option<(&CamerasJsonSpec, cameras::CameraFormat)> {
        use cameras::CameraFormat as F;
        match self {
            PathSpec::CamerasJson(c) => Some((c, F::Inria)),
            PathSpec::Colmap(c) => Some((c, F::Colmap)),
            PathSpec::TransformsJson(c) => Some((c, F::Transforms)),
            PathSpec::Nerfstudio(c) => Some((c, F::Nerfstudio)),
            PathSpec::Orbit(_) | PathSpec::Keyframes(_) => None,
        }
    }
}

fn default_turns() -> f32 {
    1.0
}

#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct OrbitSpec {
    /// The point looked at and circled. Default [0, 0, 0].
    #[serde(default)]
    pub target: [f32; 3],
    /// Horizontal distance from the target (perpendicular to `up`), > 0.
    pub radius: f32,
    /// Height of the camera above the target, along `up`. Default 0.
    #[serde(default)]
    pub height: f32,
    /// Angle of frame 0 in degrees, counter-clockwise about `up` (0 = along +x for +z up).
    #[serde(default)]
    pub start_deg: f32,
    /// Number of turns over the frame count (negative: clockwise). Frame f is at angle
    /// start + 360° · turns · f / frames, so a full turn loops seamlessly. Default 1.
    #[serde(default = "default_turns")]
    pub turns: f32,
}

#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct KeyframesSpec {
    /// At least one keyframe, with strictly increasing times.
    pub keyframes: Vec<Keyframe>,
}

/// A camera pose at a time. Exactly one of `look_at` or `rotation`.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Keyframe {
    /// Time in seconds (frame f is at time f / fps).
    pub time: f32,
    /// Camera centre in world space.
    pub position: [f32; 3],
    /// A world point the camera looks at (the image's up is as close to `up` as possible).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub look_at: Option<[f32; 3]>,
    /// Camera-to-world rotation, OpenCV axes (x right, y down, z forward), as an array of rows
    /// (the layout of `cameras.json`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotation: Option<[[f32; 3]; 3]>,
}

#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CamerasJsonSpec {
    /// Path of the camera file (for `colmap`, the model's folder or one of its files),
    /// relative to the scene file.
    pub file: PathBuf,
    /// How the file's cameras map to frames. Default `each`.
    #[serde(default)]
    pub mode: CamerasJsonMode,
    /// `nerfstudio` only: the training run's `dataparser_transforms.json`, relative to the
    /// scene file, which maps the path from nerfstudio's normalised world back into the
    /// capture's frame. Default: the path is used as it is.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dataparser_transforms: Option<PathBuf>,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum CamerasJsonMode {
    /// Frame i uses camera i (the frame count must not exceed the number of cameras).
    #[default]
    Each,
    /// The cameras become keyframes spread uniformly over the frames (first camera at frame
    /// 0, last at the last frame), interpolated smoothly.
    Smooth,
}

/// An object: exactly one source (`ply` or `procedural`) and a transform.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    /// A name for messages and reports.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// A 3DGS PLY file, relative to the scene file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ply: Option<PathBuf>,
    /// The integer vertex property of a PLY capture that holds its segments (its region
    /// labels, which `physics.select` and `physics.regions` name). Default: `label`, else
    /// `segment`, where the file has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub label_property: Option<String>,
    /// A procedural solid.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub procedural: Option<ProceduralSpec>,
    /// Placement in the world. Default: identity.
    #[serde(default)]
    pub transform: TransformSpec,
    /// Simulate this object (needs the scene's `simulation` block). Default: static.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub physics: Option<physics::PhysicsSpec>,
    /// Move on a prescribed rigid path and push the simulated material (a knife, a
    /// projectile). Needs the scene's `simulation` block. Default: none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kinematic: Option<kinematic::KinematicSpec>,
    /// Blinn-Phong weights under the scene's `lighting`. Default: the paper's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shading: Option<lighting::ShadingSpec>,
    /// Stop what the simulation moves: this object's Gaussians (the static part, for a
    /// simulated object) become a collider with this condition. Needs `simulation`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub collider: Option<physics::ConditionSpec>,
}

/// x_world = R · U · diag(scale) · x_object + translate: U turns the object's `up` to +z,
/// R is `rotate_deg`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TransformSpec {
    /// Which way is up in the object's own frame, turned to +z before `rotate_deg`:
    /// `"auto"` (estimated from the capture and, when there is one, the `cameras.json` next
    /// to it; `splatter inspect` shows the evidence), `{"auto": {"cameras": FILE}}` (from the
    /// capture's cameras in FILE, relative to the scene), a signed axis (`"+x"`, `"-y"`, …)
    /// or a vector [x, y, z]. Default: the object's +z.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub up: Option<UpSpec>,
    /// `up: "auto"` as estimated when the scene was loaded ([`Scene::resolve_up`]).
    #[serde(skip)]
    #[schemars(skip)]
    pub resolved_up: Option<Vec3>,
    /// Translation. Default [0, 0, 0].
    #[serde(default)]
    pub translate: [f32; 3],
    /// Rotation as Euler angles in degrees [x, y, z]: about the world x axis first, then y,
    /// then z (R = Rz · Ry · Rx). Default [0, 0, 0].
    #[serde(default)]
    pub rotate_deg: [f32; 3],
    /// Scale, uniform (a number) or per object axis ([x, y, z]), every component > 0.
    /// Default 1.
    #[serde(default)]
    pub scale: Scale,
}

/// A uniform scale (a number) or one per axis ([x, y, z]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged, expecting = "`scale`: a number or an array of 3 numbers")]
pub enum Scale {
    Uniform(f32),
    PerAxis([f32; 3]),
}

impl Default for Scale {
    fn default() -> Self {
        Scale::Uniform(1.0)
    }
}

impl Scale {
    pub fn as_vec3(self) -> Vec3 {
        match self {
            Scale::Uniform(s) => Vec3::splat(s),
            Scale::PerAxis(s) => Vec3::from_array(s),
        }
    }
}

/// `transform.up`: `"auto"`, `{"auto": {"cameras": FILE}}`, a signed axis name, or a
/// vector.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(
    untagged,
    expecting = "`up`: \"auto\", {\"auto\": {\"cameras\": \"cameras.json\"}}, an axis such as \"-y\", or an array of 3 numbers"
)]
pub enum UpSpec {
    Named(String),
    Vector([f32; 3]),
    Auto(AutoUpSpec),
}

/// `{"auto": {…}}`: up estimated as for `"auto"`, with what is given here.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AutoUpSpec {
    pub auto: AutoUp,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AutoUp {
    /// The capture's INRIA 3DGS `cameras.json` (relative to the scene file): up is the mean
    /// of its cameras' up vectors. Default: a `cameras.json` found next to the capture.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cameras: Option<PathBuf>,
}

impl UpSpec {
    /// The up vector, None for `auto` (resolved from the data) or an invalid value.
    pub fn vector(&self) -> Option<Vec3> {
        match self {
            UpSpec::Named(n) => crate::splat::inspect::axis_vector(n),
            UpSpec::Vector(v) => Vec3::from_array(*v).try_normalize(),
            UpSpec::Auto(_) => None,
        }
    }

    pub fn is_auto(&self) -> bool {
        matches!(self, UpSpec::Named(n) if n == "auto") || matches!(self, UpSpec::Auto(_))
    }

    /// The cameras file an auto up names.
    pub fn auto_cameras(&self) -> Option<&Path> {
        match self {
            UpSpec::Auto(a) => a.auto.cameras.as_deref(),
            _ => None,
        }
    }
}

impl TransformSpec {
    /// Rotation R · U: `up` turned to +z, then R = Rz · Ry · Rx of `rotate_deg`.
    pub fn rotation(&self) -> Mat3 {
        let [x, y, z] = self.rotate_deg.map(f32::to_radians);
        let euler = Mat3::from_rotation_z(z) * Mat3::from_rotation_y(y) * Mat3::from_rotation_x(x);
        let up = self
            .resolved_up
            .or_else(|| self.up.as_ref().and_then(UpSpec::vector))
            .unwrap_or(Vec3::Z);
        euler * crate::splat::inspect::upright_rotation(up)
    }

    /// The affine map x ↦ M x + t with M = R · diag(scale).
    pub fn affine(&self) -> (Mat3, Vec3) {
        (
            self.rotation() * Mat3::from_diagonal(self.scale.as_vec3()),
            Vec3::from_array(self.translate),
        )
    }
}

impl ObjectSpec {
    /// The name used in reports: `name`, else the PLY's file name, else the shape.
    pub fn display_name(&self, index: usize) -> String {
        if let Some(name) = &self.name {
            return name.clone();
        }
        if let Some(ply) = &self.ply {
            return ply
                .file_name()
                .map(|f| f.to_string_lossy().into_owned())
                .unwrap_or_else(|| ply.display().to_string());
        }
        if let Some(p) = &self.procedural {
            let shape = serde_json::to_value(&p.shape)
                .ok()
                .and_then(|v| v.get("shape").and_then(|s| s.as_str().map(str::to_string)))
                .unwrap_or_else(|| "procedural".into());
            return format!("{shape} {index}");
        }
        format!("object {index}")
    }
}

// ---------------------------------------------------------------------------------------------
// Loading
// ---------------------------------------------------------------------------------------------

/// Read, parse and validate a scene file. Relative paths in it resolve against its folder.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let base_dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let mut scene = parse(&text, &path.display().to_string(), &base_dir)?;
    if let Some(stem) = path.file_stem() {
        scene.name = stem.to_string_lossy().into_owned();
    }
    Ok(scene)
}

/// Parse and validate scene JSON. `origin` names it in error messages (a file name);
/// relative paths resolve against `base_dir`. The scene's name is `origin`'s file stem.
pub fn parse(text: &str, origin: &str, base_dir: &Path) -> Result<Scene, SceneError> {
    let mut scene: Scene = serde_json::from_str(text).map_err(|e| SceneError::parse(origin, &e))?;
    scene.base_dir = base_dir.to_path_buf();
    scene.origin = origin.to_string();
    scene.name = Path::new(origin)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "scene".into());
    scene.validate()?;
    scene.resolve_up()?;
    Ok(scene)
}

/// The embedded default scene (`scenes/default.json`), relative paths against the current
/// directory; its output folder defaults to `out/default`.
pub fn default_scene() -> Scene {
    parse(DEFAULT_SCENE_JSON, "default.json", Path::new("."))
        .expect("the embedded default scene is valid")
}

/// The JSON Schema of a scene file.
pub fn schema() -> serde_json::Value {
    schemars::schema_for!(Scene).to_value()
}

impl Scene {
    /// Number of frames to render.
    pub fn frame_count(&self) -> u32 {
        self.output.frames
    }

    /// The output folder: `output.dir`, else `out/<scene name>`.
    pub fn output_dir(&self) -> PathBuf {
        match &self.output.dir {
            Some(dir) => dir.clone(),
            None => Path::new("out").join(if self.name.is_empty() {
                "scene"
            } else {
                &self.name
            }),
        }
    }

    /// Apply command-line overrides and validate again. When only one of width and height is
    /// given the other follows the scene's aspect ratio. Focal lengths given in pixels
    /// (`camera.fx`/`fy`) are rescaled with the image so that the field of view is kept.
    pub fn with_overrides(
        &mut self,
        out: Option<PathBuf>,
        width: Option<u32>,
        height: Option<u32>,
    ) -> Result<(), SceneError> {
        if let Some(out) = out {
            self.output.dir = Some(out);
        }
        let (w0, h0) = (self.output.width, self.output.height);
        let aspect = w0 as f64 / h0.max(1) as f64;
        let (w, h) = match (width, height) {
            (Some(w), Some(h)) => (w, h),
            (Some(w), None) => (w, ((w as f64 / aspect).round() as u32).max(1)),
            (None, Some(h)) => (((h as f64 * aspect).round() as u32).max(1), h),
            (None, None) => (w0, h0),
        };
        if let (Some(fx), Some(fy)) = (self.camera.fx, self.camera.fy) {
            if w0 > 0 && h0 > 0 {
                self.camera.fx = Some(fx * w as f32 / w0 as f32);
                self.camera.fy = Some(fy * h as f32 / h0 as f32);
            }
        }
        self.output.width = w;
        self.output.height = h;
        self.validate()
    }

    /// The camera for every frame (reads `cameras.json` for such paths).
    pub fn camera_path(&self) -> Result<CameraPath, SceneError> {
        path::build(self)
    }
}

#[cfg(test)]
mod tests;
