//! Camera files from the tools people pose and draw cameras in, read into one form: INRIA
//! 3DGS `cameras.json` ([`inria`]), COLMAP sparse models in text or binary ([`colmap`]),
//! `transforms.json` of nerfstudio and instant-ngp ([`transforms`]) and nerfstudio's
//! `camera_path.json` ([`nerfstudio`]); and the frames' cameras written back out as the
//! first and the last ([`export`]). Each file's convention (axes, direction, units) is
//! turned into ours in its reader, once; `docs/scene-format.md` has the table.
//!
//! Ours: a camera-to-world rotation whose columns are the camera's x (right), y (down) and
//! z (forward) axes in the world (OpenCV's axes), the camera centre, focal lengths in
//! pixels of the file's image size, the principal point at the image's centre.

use std::path::{Path, PathBuf};

use glam::{Mat3, Vec3};

use super::{rotation_problem, SceneError};
use crate::render::camera::{Camera, DEFAULT_NEAR};

pub mod colmap;
pub mod export;
pub mod inria;
pub mod nerfstudio;
pub mod transforms;

/// A camera as a file gives it, in our convention.
#[derive(Clone, Debug, PartialEq)]
pub struct FileCamera {
    /// The image's name, where the file has one.
    pub name: String,
    /// Camera centre in the file's world.
    pub position: Vec3,
    /// Camera-to-world rotation, OpenCV axes.
    pub rotation: Mat3,
    /// Focal lengths in pixels of `width` × `height`.
    pub fx: f32,
    pub fy: f32,
    pub width: u32,
    pub height: u32,
}

/// The cameras of a file, in order, and what the reader noticed.
#[derive(Clone, Debug, Default)]
pub struct CameraFile {
    pub cameras: Vec<FileCamera>,
    /// Lines for the user (distortion ignored, an off-centre principal point, …).
    pub warnings: Vec<String>,
}

/// The formats read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraFormat {
    /// INRIA 3DGS `cameras.json`: an array of cameras.
    Inria,
    /// A COLMAP sparse model: a folder (or a file of it) with `cameras` and `images`, `.txt`
    /// or `.bin`.
    Colmap,
    /// `transforms.json` (nerfstudio, instant-ngp, NeRF's Blender scenes).
    Transforms,
    /// nerfstudio's `camera_path.json`.
    Nerfstudio,
}

impl CameraFormat {
    pub fn name(self) -> &'static str {
        match self {
            CameraFormat::Inria => "INRIA cameras.json",
            CameraFormat::Colmap => "COLMAP model",
            CameraFormat::Transforms => "transforms.json",
            CameraFormat::Nerfstudio => "nerfstudio camera_path.json",
        }
    }

    /// The format of `path`, told by its content: a folder or a `cameras`/`images` file of a
    /// COLMAP model, or JSON that is an array (INRIA), an object with `frames`
    /// (transforms.json) or with `camera_path` (nerfstudio).
    pub fn of(path: &Path) -> Result<CameraFormat, SceneError> {
        if colmap::model_dir(path).is_some() {
            return Ok(CameraFormat::Colmap);
        }
        let text = read_text(path)?;
        let origin = path.display().to_string();
        let value: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| SceneError::parse(&origin, &e))?;
        match &value {
            serde_json::Value::Array(_) => Ok(CameraFormat::Inria),
            serde_json::Value::Object(o) if o.contains_key("camera_path") => {
                Ok(CameraFormat::Nerfstudio)
            }
            serde_json::Value::Object(o) if o.contains_key("frames") => Ok(CameraFormat::Transforms),
            _ => Err(SceneError::invalid(
                &origin,
                "(file)",
                "JSON that is no camera file we know",
                "an INRIA cameras.json (an array), a transforms.json (with `frames`), a nerfstudio camera_path.json (with `camera_path`), or a COLMAP model folder (cameras and images, .txt or .bin)",
            )),
        }
    }
}

/// Read the cameras of `path` in `format`. `dataparser` (nerfstudio only) maps a camera
/// path back into the capture's frame.
pub fn read(
    path: &Path,
    format: CameraFormat,
    dataparser: Option<&Path>,
) -> Result<CameraFile, SceneError> {
    if dataparser.is_some() && format != CameraFormat::Nerfstudio {
        return Err(SceneError::invalid(
            &path.display().to_string(),
            "dataparser_transforms",
            "given",
            "a nerfstudio camera_path.json (only its world is nerfstudio's normalised one)",
        ));
    }
    let file = match format {
        CameraFormat::Inria => inria::read(path)?,
        CameraFormat::Colmap => colmap::read(path)?,
        CameraFormat::Transforms => transforms::read(path)?,
        CameraFormat::Nerfstudio => nerfstudio::read(path, dataparser)?,
    };
    if file.cameras.is_empty() {
        return Err(SceneError::invalid(
            &path.display().to_string(),
            "(file)",
            "no cameras",
            "at least one camera",
        ));
    }
    Ok(file)
}

/// Read the cameras of `path` in whatever format it is.
pub fn read_any(path: &Path) -> Result<CameraFile, SceneError> {
    read(path, CameraFormat::of(path)?, None)
}

/// The file's cameras at the given output size (`None`: the file's; one of the two: the
/// other keeps each camera's aspect ratio). Focal lengths are rescaled to the output size
/// (fx·W/width, fy·H/height); positions and rotations are used as they are.
pub fn at_size(
    origin: &str,
    cameras: &[FileCamera],
    width: Option<u32>,
    height: Option<u32>,
) -> Result<Vec<Camera>, SceneError> {
    for (name, v) in [("width", width), ("height", height)] {
        if let Some(v) = v {
            if !(1..=super::MAX_IMAGE_SIZE).contains(&v) {
                return Err(SceneError::invalid(
                    origin,
                    format!("requested {name}"),
                    v,
                    format!("1..={}", super::MAX_IMAGE_SIZE),
                ));
            }
        }
    }
    Ok(cameras
        .iter()
        .map(|c| {
            let (w, h) = output_size(c.width, c.height, width, height);
            Camera {
                position: c.position,
                rotation: c.rotation,
                fx: c.fx * w as f32 / c.width as f32,
                fy: c.fy * h as f32 / c.height as f32,
                width: w,
                height: h,
                near: DEFAULT_NEAR,
            }
        })
        .collect())
}

/// Output size for a file camera of size (w, h): the given ones, the missing one following
/// the camera's aspect ratio.
fn output_size(w: u32, h: u32, width: Option<u32>, height: Option<u32>) -> (u32, u32) {
    let aspect = w as f64 / h as f64;
    match (width, height) {
        (Some(a), Some(b)) => (a, b),
        (Some(a), None) => (a, ((a as f64 / aspect).round() as u32).max(1)),
        (None, Some(b)) => (((b as f64 * aspect).round() as u32).max(1), b),
        (None, None) => (w, h),
    }
}

fn read_text(path: &Path) -> Result<String, SceneError> {
    std::fs::read_to_string(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })
}

fn read_bytes(path: &Path) -> Result<Vec<u8>, SceneError> {
    std::fs::read(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// A checked camera: sizes ≥ 1, focal lengths > 0, a finite centre, a rotation
/// orthonormal within 1e-3 (re-orthonormalised when off by more than 1e-5). `field` names
/// the camera in errors.
fn checked(origin: &str, field: &str, c: FileCamera) -> Result<FileCamera, SceneError> {
    for (name, v) in [("width", c.width), ("height", c.height)] {
        if v == 0 || v > super::MAX_IMAGE_SIZE {
            return Err(SceneError::invalid(
                origin,
                format!("{field}.{name}"),
                v,
                format!("a size in pixels from 1 to {}", super::MAX_IMAGE_SIZE),
            ));
        }
    }
    for (name, v) in [("fx", c.fx), ("fy", c.fy)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(SceneError::invalid(
                origin,
                format!("{field}.{name}"),
                v,
                "a focal length in pixels > 0",
            ));
        }
    }
    if !c.position.is_finite() {
        return Err(SceneError::invalid(
            origin,
            format!("{field}.position"),
            c.position,
            "a finite camera centre",
        ));
    }
    if let Some(problem) = rotation_problem(c.rotation, 1e-3) {
        return Err(SceneError::invalid(
            origin,
            format!("{field}.rotation"),
            format!("{:?}", c.rotation.transpose().to_cols_array_2d()),
            problem,
        ));
    }
    let rotation = if rotation_problem(c.rotation, 1e-5).is_some() {
        orthonormalise(c.rotation)
    } else {
        c.rotation
    };
    Ok(FileCamera { rotation, ..c })
}

/// Gram-Schmidt on the columns (keeps the z = view axis exactly).
fn orthonormalise(r: Mat3) -> Mat3 {
    let z = r.z_axis.normalize();
    let x = (r.x_axis - z * z.dot(r.x_axis)).normalize();
    Mat3::from_cols(x, z.cross(x), z)
}

/// OpenGL camera axes (x right, y up, looking down −z) to OpenCV's (x right, y down, z
/// forward): the camera-to-world rotation's y and z columns change sign. Its own inverse.
pub fn flip_gl_cv(r: Mat3) -> Mat3 {
    Mat3::from_cols(r.x_axis, -r.y_axis, -r.z_axis)
}

/// `name` beside `file` (a path a camera file names, relative to its folder).
fn beside(file: &Path, name: &str) -> PathBuf {
    file.parent().unwrap_or(Path::new(".")).join(name)
}

#[cfg(test)]
mod tests;
