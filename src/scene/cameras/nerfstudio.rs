//! nerfstudio's `camera_path.json`, as its viewer writes a render path: `camera_path`
//! entries of `{camera_to_world, fov, aspect}` (the matrix as 16 numbers, rows first, OpenGL
//! axes; `fov` the vertical field of view in degrees), the render size `render_width` ×
//! `render_height` (its `fps` is left to the scene's `output.fps`, which times every path).
//! The poses are in nerfstudio's normalised world; with the
//! training run's `dataparser_transforms.json` (`transform`, three rows of four, and
//! `scale`: x_ns = scale · (T x + t)) they map back into the capture's frame,
//! x = T⁻¹ (x_ns / scale − t), as nerfstudio's own exporter does.

use std::path::Path;

use glam::{DMat3, DVec3};
use serde::Deserialize;

use super::{checked, flip_gl_cv, read_text, CameraFile, FileCamera};
use crate::scene::SceneError;

#[derive(Clone, Debug, Deserialize)]
struct Entry {
    camera_to_world: Vec<f64>,
    fov: f64,
    #[serde(default)]
    aspect: Option<f64>,
}

#[derive(Clone, Debug, Deserialize)]
struct File {
    camera_path: Vec<Entry>,
    #[serde(default)]
    render_width: Option<u32>,
    render_height: u32,
    #[serde(default)]
    camera_type: Option<String>,
}

#[derive(Clone, Debug, Deserialize)]
struct Dataparser {
    transform: [[f64; 4]; 3],
    scale: f64,
}

/// Read and check a `camera_path.json`, mapped back by `dataparser` when given.
pub fn read(path: &Path, dataparser: Option<&Path>) -> Result<CameraFile, SceneError> {
    let origin = path.display().to_string();
    let file: File =
        serde_json::from_str(&read_text(path)?).map_err(|e| SceneError::parse(&origin, &e))?;
    let mut out = CameraFile::default();
    if let Some(t) = file.camera_type.as_deref().filter(|t| *t != "perspective") {
        return Err(SceneError::invalid(
            &origin,
            "camera_type",
            format!("{t:?}"),
            "\"perspective\" (the only projection rendered)",
        ));
    }
    let back = dataparser.map(read_dataparser).transpose()?;
    for (i, e) in file.camera_path.iter().enumerate() {
        let field = format!("camera_path[{i}]");
        let m = &e.camera_to_world;
        if m.len() != 16 {
            return Err(SceneError::invalid(
                &origin,
                format!("{field}.camera_to_world"),
                format!("{} numbers", m.len()),
                "16 numbers (a 4×4 matrix, rows first)",
            ));
        }
        let height = file.render_height;
        let aspect = e
            .aspect
            .or(file.render_width.map(|w| f64::from(w) / f64::from(height)))
            .unwrap_or(1.0);
        let width = file
            .render_width
            .unwrap_or_else(|| (f64::from(height) * aspect).round() as u32);
        let focal = 0.5 * f64::from(height) / (0.5 * e.fov.to_radians()).tan();
        let rotation = DMat3::from_cols(
            DVec3::new(m[0], m[4], m[8]),
            DVec3::new(m[1], m[5], m[9]),
            DVec3::new(m[2], m[6], m[10]),
        );
        let position = DVec3::new(m[3], m[7], m[11]);
        let (rotation, position) = match &back {
            Some((inv, t, scale)) => (*inv * rotation, *inv * (position / *scale - *t)),
            None => (rotation, position),
        };
        let camera = FileCamera {
            name: format!("{i:05}"),
            position: position.as_vec3(),
            rotation: flip_gl_cv(rotation.as_mat3()),
            fx: focal as f32,
            fy: focal as f32,
            width,
            height,
        };
        out.cameras.push(checked(&origin, &field, camera)?);
    }
    Ok(out)
}

/// T⁻¹, t and the scale of a `dataparser_transforms.json`.
fn read_dataparser(path: &Path) -> Result<(DMat3, DVec3, f64), SceneError> {
    let origin = path.display().to_string();
    let d: Dataparser =
        serde_json::from_str(&read_text(path)?).map_err(|e| SceneError::parse(&origin, &e))?;
    let r = &d.transform;
    let m = DMat3::from_cols(
        DVec3::new(r[0][0], r[1][0], r[2][0]),
        DVec3::new(r[0][1], r[1][1], r[2][1]),
        DVec3::new(r[0][2], r[1][2], r[2][2]),
    );
    if !(d.scale.is_finite() && d.scale > 0.0 && m.determinant().abs() > 1e-12) {
        return Err(SceneError::invalid(
            &origin,
            "transform, scale",
            format!("det {} scale {}", m.determinant(), d.scale),
            "an invertible transform and a scale > 0",
        ));
    }
    Ok((m.inverse(), DVec3::new(r[0][3], r[1][3], r[2][3]), d.scale))
}
