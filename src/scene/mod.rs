//! The scene file (JSON): schema, validation, camera paths.
//!
//! A scene names the output (size, frame count, frame rate, background), the camera (its
//! intrinsics and a path: orbit, keyframes or an INRIA `cameras.json`) and the objects (PLY
//! files or procedural solids, each with a transform). `docs/scene-format.md` documents every
//! field; [`schema`] prints the JSON Schema.
//!
//! Parsing is strict: unknown keys are errors, and every number is checked after parsing
//! ([`Scene::validate`]). Errors name the file, the field path and the offending value.

pub mod fill;
pub mod kinematic;
pub mod lighting;
pub(crate) mod path;
pub mod physics;
pub mod quality;
pub mod regions;
pub mod simulation;

use std::fmt::Display;
use std::path::{Path, PathBuf};

use glam::{Mat3, Vec3};
use rayon::prelude::*;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::render::Splats;
use crate::splat::procedural::{ProceduralError, ProceduralSpec};

pub use path::{from_cameras_json, CameraPath};

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
    /// Path of the `cameras.json`, relative to the scene file.
    pub file: PathBuf,
    /// How the file's cameras map to frames. Default `each`.
    #[serde(default)]
    pub mode: CamerasJsonMode,
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
}

/// x_world = R · diag(scale) · x_object + translate, R from `rotate_deg`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TransformSpec {
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

impl TransformSpec {
    /// Rotation R = Rz · Ry · Rx of `rotate_deg`.
    pub fn rotation(&self) -> Mat3 {
        let [x, y, z] = self.rotate_deg.map(f32::to_radians);
        Mat3::from_rotation_z(z) * Mat3::from_rotation_y(y) * Mat3::from_rotation_x(x)
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

// ---------------------------------------------------------------------------------------------
// Validation
// ---------------------------------------------------------------------------------------------

fn check_finite3(origin: &str, field: &str, v: [f32; 3]) -> Result<(), SceneError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(SceneError::invalid(
            origin,
            field,
            format!("{v:?}"),
            "finite numbers",
        ))
    }
}

fn check_positive(origin: &str, field: &str, v: f32) -> Result<(), SceneError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(SceneError::invalid(origin, field, v, "a finite number > 0"))
    }
}

/// Error (message) when `r` is not a rotation matrix within `tol`.
pub(crate) fn rotation_problem(r: Mat3, tol: f32) -> Option<String> {
    let cols = r.to_cols_array();
    if !cols.iter().all(|x| x.is_finite()) {
        return Some("finite numbers".into());
    }
    let err = (r.transpose() * r - Mat3::IDENTITY)
        .to_cols_array()
        .iter()
        .fold(0.0f32, |m, x| m.max(x.abs()));
    if err > tol {
        return Some(format!(
            "an orthonormal matrix (|RᵀR − I| = {err:.2e} > {tol:.0e})"
        ));
    }
    if r.determinant() <= 0.0 {
        return Some("a rotation (determinant +1), not a reflection".into());
    }
    None
}

/// Camera-to-world matrix from an array of rows.
pub(crate) fn mat3_from_rows(rows: [[f32; 3]; 3]) -> Mat3 {
    Mat3::from_cols_array_2d(&rows).transpose()
}

impl Scene {
    /// Check every field's range; errors name the file, the field path and the value.
    /// (Runs after parsing; run it again after editing a scene by hand.)
    pub fn validate(&self) -> Result<(), SceneError> {
        let o = self.origin.as_str();
        let out = &self.output;
        if let Some(dir) = &out.dir {
            if dir.as_os_str().is_empty() {
                return Err(SceneError::invalid(
                    o,
                    "output.dir",
                    "\"\"",
                    "a non-empty path",
                ));
            }
        }
        for (field, v) in [("output.width", out.width), ("output.height", out.height)] {
            if !(1..=MAX_IMAGE_SIZE).contains(&v) {
                return Err(SceneError::invalid(
                    o,
                    field,
                    v,
                    format!("a size in pixels in 1..={MAX_IMAGE_SIZE}"),
                ));
            }
        }
        if !(1..=MAX_FRAMES).contains(&out.frames) {
            return Err(SceneError::invalid(
                o,
                "output.frames",
                out.frames,
                format!("a frame count in 1..={MAX_FRAMES}"),
            ));
        }
        check_positive(o, "output.fps", out.fps)?;
        if !out
            .background
            .iter()
            .all(|c| c.is_finite() && (0.0..=1.0).contains(c))
        {
            return Err(SceneError::invalid(
                o,
                "output.background",
                format!("{:?}", out.background),
                "RGB components in [0, 1]",
            ));
        }

        let cam = &self.camera;
        let is_cameras_json = matches!(cam.path, PathSpec::CamerasJson(_));
        match (cam.fov_y_deg, cam.fx, cam.fy) {
            (Some(fov), None, None) => {
                if !(fov.is_finite() && fov > 0.0 && fov < 180.0) {
                    return Err(SceneError::invalid(
                        o,
                        "camera.fov_y_deg",
                        fov,
                        "an angle in degrees in (0, 180)",
                    ));
                }
            }
            (None, Some(fx), Some(fy)) => {
                check_positive(o, "camera.fx", fx)?;
                check_positive(o, "camera.fy", fy)?;
            }
            (None, None, None) if is_cameras_json => {}
            (None, None, None) => {
                return Err(SceneError::invalid(
                    o,
                    "camera",
                    "no intrinsics",
                    "`fov_y_deg` (degrees) or `fx` and `fy` (pixels)",
                ))
            }
            (Some(fov), _, _) => {
                return Err(SceneError::invalid(
                    o,
                    "camera.fov_y_deg",
                    fov,
                    "either `fov_y_deg` or `fx` + `fy`, not both",
                ))
            }
            (None, Some(fx), None) => {
                return Err(SceneError::invalid(
                    o,
                    "camera.fy",
                    format!("missing (fx = {fx})"),
                    "`fx` and `fy` together",
                ))
            }
            (None, None, Some(fy)) => {
                return Err(SceneError::invalid(
                    o,
                    "camera.fx",
                    format!("missing (fy = {fy})"),
                    "`fx` and `fy` together",
                ))
            }
        }
        check_positive(o, "camera.near", cam.near)?;
        check_finite3(o, "camera.up", cam.up)?;
        if Vec3::from_array(cam.up).length() < 1e-6 {
            return Err(SceneError::invalid(
                o,
                "camera.up",
                format!("{:?}", cam.up),
                "a non-zero direction",
            ));
        }

        match &cam.path {
            PathSpec::Orbit(orbit) => {
                check_finite3(o, "camera.path.target", orbit.target)?;
                check_positive(o, "camera.path.radius", orbit.radius)?;
                for (field, v) in [
                    ("camera.path.height", orbit.height),
                    ("camera.path.start_deg", orbit.start_deg),
                    ("camera.path.turns", orbit.turns),
                ] {
                    if !v.is_finite() {
                        return Err(SceneError::invalid(o, field, v, "a finite number"));
                    }
                }
            }
            PathSpec::Keyframes(k) => self.validate_keyframes(&k.keyframes)?,
            PathSpec::CamerasJson(c) => {
                if c.file.as_os_str().is_empty() {
                    return Err(SceneError::invalid(
                        o,
                        "camera.path.file",
                        "\"\"",
                        "a path to a cameras.json",
                    ));
                }
                let full = self.base_dir.join(&c.file);
                if !full.is_file() {
                    return Err(SceneError::invalid(
                        o,
                        "camera.path.file",
                        format!("{:?}", c.file.display().to_string()),
                        format!("an existing file ({} not found)", full.display()),
                    ));
                }
            }
        }

        for (i, obj) in self.objects.iter().enumerate() {
            self.validate_object(i, obj)?;
            if let Some(sh) = &obj.shading {
                lighting::validate_shading(o, i, sh)?;
            }
        }
        if let Some(l) = &self.lighting {
            l.validate(o)?;
        }
        Ok(())
    }

    fn validate_keyframes(&self, keys: &[Keyframe]) -> Result<(), SceneError> {
        let o = self.origin.as_str();
        if keys.is_empty() {
            return Err(SceneError::invalid(
                o,
                "camera.path.keyframes",
                "[]",
                "at least one keyframe",
            ));
        }
        for (i, k) in keys.iter().enumerate() {
            let f = |name: &str| format!("camera.path.keyframes[{i}].{name}");
            if !k.time.is_finite() {
                return Err(SceneError::invalid(
                    o,
                    f("time"),
                    k.time,
                    "a finite time in seconds",
                ));
            }
            if i > 0 && k.time <= keys[i - 1].time {
                return Err(SceneError::invalid(
                    o,
                    f("time"),
                    k.time,
                    format!(
                        "a time after the previous keyframe's ({}): times must strictly increase",
                        keys[i - 1].time
                    ),
                ));
            }
            check_finite3(o, &f("position"), k.position)?;
            match (k.look_at, k.rotation) {
                (Some(t), None) => {
                    check_finite3(o, &f("look_at"), t)?;
                    if (Vec3::from_array(t) - Vec3::from_array(k.position)).length() < 1e-6 {
                        return Err(SceneError::invalid(
                            o,
                            f("look_at"),
                            format!("{t:?}"),
                            "a point away from `position`",
                        ));
                    }
                }
                (None, Some(rows)) => {
                    if let Some(problem) = rotation_problem(mat3_from_rows(rows), 1e-3) {
                        return Err(SceneError::invalid(
                            o,
                            f("rotation"),
                            format!("{rows:?}"),
                            problem,
                        ));
                    }
                }
                (Some(_), Some(_)) => {
                    return Err(SceneError::invalid(
                        o,
                        f("rotation"),
                        "given with `look_at`",
                        "either `look_at` or `rotation`, not both",
                    ))
                }
                (None, None) => {
                    return Err(SceneError::invalid(
                        o,
                        format!("camera.path.keyframes[{i}]"),
                        "no orientation",
                        "`look_at` [x, y, z] or `rotation` (3×3 rows)",
                    ))
                }
            }
        }
        Ok(())
    }

    fn validate_object(&self, i: usize, obj: &ObjectSpec) -> Result<(), SceneError> {
        let o = self.origin.as_str();
        let f = |name: &str| format!("objects[{i}].{name}");
        match (&obj.ply, &obj.procedural) {
            (Some(ply), None) => {
                if ply.as_os_str().is_empty() {
                    return Err(SceneError::invalid(
                        o,
                        f("ply"),
                        "\"\"",
                        "a path to a PLY file",
                    ));
                }
                let full = self.base_dir.join(ply);
                if !full.is_file() {
                    return Err(SceneError::invalid(
                        o,
                        f("ply"),
                        format!("{:?}", ply.display().to_string()),
                        format!("an existing file ({} not found)", full.display()),
                    ));
                }
            }
            (None, Some(spec)) => spec.validate().map_err(|e| match e {
                ProceduralError::Invalid {
                    field,
                    value,
                    expected,
                } => SceneError::invalid(o, f(&format!("procedural.{field}")), value, expected),
                other => SceneError::invalid(o, f("procedural"), "", one_line(&other.to_string())),
            })?,
            (Some(_), Some(_)) => {
                return Err(SceneError::invalid(
                    o,
                    f("procedural"),
                    "given with `ply`",
                    "exactly one source: `ply` or `procedural`",
                ))
            }
            (None, None) => {
                return Err(SceneError::invalid(
                    o,
                    format!("objects[{i}]"),
                    "no source",
                    "`ply` (a file) or `procedural` (a shape)",
                ))
            }
        }
        let t = &obj.transform;
        check_finite3(o, &f("transform.translate"), t.translate)?;
        check_finite3(o, &f("transform.rotate_deg"), t.rotate_deg)?;
        let s = t.scale.as_vec3();
        if !s.is_finite() || s.min_element() <= 0.0 {
            let value = match t.scale {
                Scale::Uniform(v) => v.to_string(),
                Scale::PerAxis(v) => format!("{v:?}"),
            };
            return Err(SceneError::invalid(
                o,
                f("transform.scale"),
                value,
                "finite scale factors > 0",
            ));
        }
        Ok(())
    }

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

    /// Load or generate every object, place it with its transform and gather all Gaussians.
    pub fn build_splats(&self) -> Result<(Splats, BuildReport), SceneError> {
        let built: Vec<(Splats, ObjectReport)> = self
            .objects
            .par_iter()
            .enumerate()
            .map(|(i, obj)| self.build_object(i, obj))
            .collect::<Result<_, _>>()?;
        let mut splats = Splats::default();
        let mut report = BuildReport::default();
        for (s, r) in built {
            splats.append(s);
            report.objects.push(r);
        }
        Ok((splats, report))
    }

    fn build_object(
        &self,
        index: usize,
        obj: &ObjectSpec,
    ) -> Result<(Splats, ObjectReport), SceneError> {
        let name = obj.display_name(index);
        let fail = |message: String| SceneError::Object {
            origin: self.origin.clone(),
            index,
            name: name.clone(),
            message: one_line(&message),
        };
        let mut report = ObjectReport {
            name: name.clone(),
            ..Default::default()
        };
        let cloud = match (&obj.ply, &obj.procedural) {
            (Some(ply), None) => {
                let full = self.base_dir.join(ply);
                report.source = full.display().to_string();
                let (cloud, ply_report) =
                    crate::splat::ply::read_ply(&full).map_err(|e| fail(e.to_string()))?;
                report.skipped_nonfinite = ply_report.skipped_nonfinite;
                report.skipped_degenerate = ply_report.skipped_degenerate;
                cloud
            }
            (None, Some(spec)) => {
                report.source = "procedural".into();
                spec.generate().map_err(|e| fail(e.to_string()))?
            }
            _ => {
                return Err(fail(
                    "needs exactly one source: `ply` or `procedural`".into(),
                ))
            }
        };
        cloud
            .check_consistent()
            .map_err(|e| fail(format!("inconsistent Gaussians: {e}")))?;
        let (m, t) = obj.transform.affine();
        report.gaussians = cloud.len();
        Ok((Splats::from_cloud(&cloud, m, t), report))
    }
}

/// What [`Scene::build_splats`] loaded.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct BuildReport {
    pub objects: Vec<ObjectReport>,
}

impl BuildReport {
    /// Gaussians over all objects.
    pub fn total_gaussians(&self) -> usize {
        self.objects.iter().map(|o| o.gaussians).sum()
    }

    /// One line per object that dropped Gaussians, e.g.
    /// `ball.ply: 3 Gaussians skipped (NaN/Inf)`.
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        for o in &self.objects {
            if o.skipped_nonfinite > 0 {
                out.push(format!(
                    "{}: {} Gaussians skipped (NaN/Inf)",
                    o.name, o.skipped_nonfinite
                ));
            }
            if o.skipped_degenerate > 0 {
                out.push(format!(
                    "{}: {} Gaussians skipped (degenerate scale or rotation)",
                    o.name, o.skipped_degenerate
                ));
            }
        }
        out
    }
}

/// One object of a [`BuildReport`].
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ObjectReport {
    /// `name`, else the PLY's file name, else `<shape> <index>`.
    pub name: String,
    /// The PLY path read, or `procedural`.
    pub source: String,
    /// Gaussians kept.
    pub gaussians: usize,
    /// Gaussians dropped by the PLY reader for NaN/Inf values.
    pub skipped_nonfinite: usize,
    /// Gaussians dropped by the PLY reader for degenerate scales or rotations.
    pub skipped_degenerate: usize,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn minimal(camera: &str) -> String {
        format!(r#"{{"output": {{"width": 64, "height": 48, "frames": 4}}, "camera": {camera}}}"#)
    }

    #[test]
    fn parse_error_message_has_no_serde_position_suffix() {
        let err = parse("{\n  \"outputs\": 1\n}", "x.json", Path::new(".")).unwrap_err();
        let s = err.to_string();
        assert!(s.starts_with("x.json:2:"), "{s}");
        assert!(!s.contains("at line"), "{s}");
    }

    #[test]
    fn defaults_are_filled_in() {
        let s = parse(
            &minimal(r#"{"fov_y_deg": 40, "path": {"type": "orbit", "radius": 2}}"#),
            "scenes/a.json",
            Path::new("scenes"),
        )
        .unwrap();
        assert_eq!(s.output.fps, 24.0);
        assert_eq!(s.output.background, [0.0; 3]);
        assert_eq!(s.camera.near, 0.01);
        assert_eq!(s.camera.up, [0.0, 0.0, 1.0]);
        assert_eq!(s.output_dir(), Path::new("out/a"));
        let PathSpec::Orbit(o) = &s.camera.path else {
            panic!()
        };
        assert_eq!(o.turns, 1.0);
        assert_eq!(o.target, [0.0; 3]);
    }

    #[test]
    fn half_given_focal_lengths_are_rejected() {
        let err = parse(
            &minimal(r#"{"fx": 100, "path": {"type": "orbit", "radius": 2}}"#),
            "a.json",
            Path::new("."),
        )
        .unwrap_err();
        assert!(err.to_string().contains("camera.fy"), "{err}");
    }

    #[test]
    fn scale_accepts_number_or_triple() {
        let t: TransformSpec = serde_json::from_str(r#"{"scale": 2}"#).unwrap();
        assert_eq!(t.scale.as_vec3(), Vec3::splat(2.0));
        let t: TransformSpec = serde_json::from_str(r#"{"scale": [1, 2, 3]}"#).unwrap();
        assert_eq!(t.scale.as_vec3(), Vec3::new(1.0, 2.0, 3.0));
        let e = serde_json::from_str::<TransformSpec>(r#"{"scale": "big"}"#).unwrap_err();
        assert!(
            e.to_string().contains("a number or an array of 3 numbers"),
            "{e}"
        );
    }

    #[test]
    fn euler_rotation_is_x_then_y_then_z() {
        let t = TransformSpec {
            rotate_deg: [90.0, 0.0, 90.0],
            ..Default::default()
        };
        // +y →(Rx 90°) +z →(Rz 90°) +z
        let v = t.rotation() * Vec3::Y;
        assert!((v - Vec3::Z).length() < 1e-6, "{v}");
        // +z →(Rx 90°) −y →(Rz 90°) +x
        let v = t.rotation() * Vec3::Z;
        assert!((v - Vec3::X).length() < 1e-6, "{v}");
    }

    #[test]
    fn overrides_keep_aspect_and_rescale_focal() {
        let mut s = parse(
            &minimal(r#"{"fx": 50, "fy": 60, "path": {"type": "orbit", "radius": 2}}"#),
            "a.json",
            Path::new("."),
        )
        .unwrap();
        s.with_overrides(Some("elsewhere".into()), Some(128), None)
            .unwrap();
        assert_eq!((s.output.width, s.output.height), (128, 96));
        assert_eq!((s.camera.fx, s.camera.fy), (Some(100.0), Some(120.0)));
        assert_eq!(s.output_dir(), Path::new("elsewhere"));
        assert!(s.with_overrides(None, Some(0), Some(10)).is_err());
    }

    #[test]
    fn one_line_joins_lines() {
        assert_eq!(one_line("a\n  b\n\nc\n"), "a; b; c");
    }
}
