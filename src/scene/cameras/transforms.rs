//! `transforms.json` (nerfstudio's data format, instant-ngp, NeRF's Blender scenes): `frames`
//! of `{file_path, transform_matrix}`, the matrix camera-to-world as four rows, OpenGL axes
//! (x right, y up, looking down −z). Intrinsics at the top or per frame: `fl_x`/`fl_y`
//! (pixels), or `camera_angle_x`/`camera_angle_y` (full angles in radians: f = ½ size /
//! tan(½ angle)); the size `w`/`h`, or where a file has none (the Blender scenes) the size
//! of the frame's image. A missing `fl_y` is `fl_x`. Frames come in the file's order.

use std::path::Path;

use glam::{Mat3, Vec3};
use serde::Deserialize;

use super::{beside, checked, flip_gl_cv, read_text, CameraFile, FileCamera};
use crate::scene::SceneError;

/// Intrinsics as the file may give them, at the top or per frame (a frame's win).
#[derive(Clone, Debug, Default, Deserialize)]
struct Intrinsics {
    fl_x: Option<f64>,
    fl_y: Option<f64>,
    camera_angle_x: Option<f64>,
    camera_angle_y: Option<f64>,
    w: Option<f64>,
    h: Option<f64>,
}

impl Intrinsics {
    fn or(&self, shared: &Intrinsics) -> Intrinsics {
        Intrinsics {
            fl_x: self.fl_x.or(shared.fl_x),
            fl_y: self.fl_y.or(shared.fl_y),
            camera_angle_x: self.camera_angle_x.or(shared.camera_angle_x),
            camera_angle_y: self.camera_angle_y.or(shared.camera_angle_y),
            w: self.w.or(shared.w),
            h: self.h.or(shared.h),
        }
    }
}

#[derive(Clone, Debug, Deserialize)]
struct Frame {
    #[serde(default)]
    file_path: Option<String>,
    transform_matrix: [[f64; 4]; 4],
    #[serde(flatten)]
    intrinsics: Intrinsics,
}

#[derive(Clone, Debug, Deserialize)]
struct File {
    frames: Vec<Frame>,
    #[serde(flatten)]
    intrinsics: Intrinsics,
}

/// Read and check a `transforms.json`.
pub fn read(path: &Path) -> Result<CameraFile, SceneError> {
    let origin = path.display().to_string();
    let file: File =
        serde_json::from_str(&read_text(path)?).map_err(|e| SceneError::parse(&origin, &e))?;
    let mut out = CameraFile::default();
    for (i, frame) in file.frames.iter().enumerate() {
        let field = format!("frames[{i}]");
        let k = frame.intrinsics.or(&file.intrinsics);
        let (width, height) = size(path, &field, frame, &k)?;
        let focal = |fl: Option<f64>, angle: Option<f64>, size: u32| {
            fl.or(angle.map(|a| 0.5 * f64::from(size) / (0.5 * a).tan()))
        };
        let fx = focal(k.fl_x, k.camera_angle_x, width).ok_or_else(|| {
            SceneError::invalid(
                &origin,
                field.clone(),
                "no focal length",
                "`fl_x` (pixels) or `camera_angle_x` (radians), for the frame or the file",
            )
        })?;
        let fy = focal(k.fl_y, k.camera_angle_y, height).unwrap_or(fx);
        let m = &frame.transform_matrix;
        let rotation_gl = Mat3::from_cols(
            Vec3::new(m[0][0] as f32, m[1][0] as f32, m[2][0] as f32),
            Vec3::new(m[0][1] as f32, m[1][1] as f32, m[2][1] as f32),
            Vec3::new(m[0][2] as f32, m[1][2] as f32, m[2][2] as f32),
        );
        let camera = FileCamera {
            name: frame.file_path.clone().unwrap_or_default(),
            position: Vec3::new(m[0][3] as f32, m[1][3] as f32, m[2][3] as f32),
            rotation: flip_gl_cv(rotation_gl),
            fx: fx as f32,
            fy: fy as f32,
            width,
            height,
        };
        out.cameras.push(checked(&origin, &field, camera)?);
    }
    Ok(out)
}

/// The frame's image size: `w`/`h`, else its image file's (tried as named, then with
/// `.png`, as the Blender scenes name their images without an extension).
fn size(path: &Path, field: &str, frame: &Frame, k: &Intrinsics) -> Result<(u32, u32), SceneError> {
    let origin = path.display().to_string();
    if let (Some(w), Some(h)) = (k.w, k.h) {
        let ok =
            |v: f64| v >= 1.0 && v <= f64::from(crate::scene::MAX_IMAGE_SIZE) && v.fract() == 0.0;
        if !(ok(w) && ok(h)) {
            return Err(SceneError::invalid(
                &origin,
                format!("{field}.w, h"),
                format!("{w} × {h}"),
                "whole sizes in pixels",
            ));
        }
        return Ok((w as u32, h as u32));
    }
    let candidates: Vec<std::path::PathBuf> = match &frame.file_path {
        Some(p) => vec![beside(path, p), beside(path, &format!("{p}.png"))],
        None => vec![],
    };
    candidates
        .iter()
        .find_map(|p| image::image_dimensions(p).ok())
        .ok_or_else(|| {
            SceneError::invalid(
                &origin,
                field.to_string(),
                "no image size",
                "`w` and `h` (pixels), for the frame or the file, or an image at its `file_path`",
            )
        })
}
