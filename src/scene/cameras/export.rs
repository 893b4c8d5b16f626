//! The frames' cameras written out (`--export-cameras DIR`), so that a plate can be matched
//! in the tools that read them: `DIR/cameras.json` (INRIA 3DGS: camera-to-world rows, OpenCV
//! axes, the centre, focal lengths in pixels; read back, it gives the very same cameras) and
//! `DIR/camera_path.json` (nerfstudio's render path: camera-to-world, OpenGL axes, 16
//! numbers rows first; the vertical field of view in degrees; render size and fps).

use std::path::Path;

use glam::Mat3;
use serde_json::json;

use super::flip_gl_cv;
use super::inria::Entry;
use crate::render::Camera;

/// One frame's camera, named by its frame number.
pub struct FrameCamera {
    pub frame: u32,
    pub camera: Camera,
}

fn rows(r: Mat3) -> [[f32; 3]; 3] {
    r.transpose().to_cols_array_2d()
}

/// `cameras.json` of the frames.
pub fn inria_json(frames: &[FrameCamera]) -> String {
    let entries: Vec<Entry> = frames
        .iter()
        .map(|f| {
            let c = &f.camera;
            Entry {
                id: Some(json!(f.frame)),
                img_name: Some(format!("frame_{:05}", f.frame)),
                width: c.width,
                height: c.height,
                position: c.position.to_array(),
                rotation: rows(c.rotation),
                fx: c.fx,
                fy: c.fy,
            }
        })
        .collect();
    serde_json::to_string_pretty(&entries).expect("cameras serialise")
}

/// nerfstudio's `camera_path.json` of the frames at `fps`.
pub fn nerfstudio_json(frames: &[FrameCamera], fps: f32) -> String {
    let first = frames.first().map(|f| f.camera);
    let (w, h) = first.map_or((0, 0), |c| (c.width, c.height));
    let path: Vec<serde_json::Value> = frames
        .iter()
        .map(|f| {
            let c = &f.camera;
            let r = rows(flip_gl_cv(c.rotation));
            let p = c.position;
            let m = [
                r[0][0], r[0][1], r[0][2], p.x, r[1][0], r[1][1], r[1][2], p.y, r[2][0], r[2][1],
                r[2][2], p.z, 0.0, 0.0, 0.0, 1.0,
            ];
            let fov = (2.0 * (0.5 * f64::from(c.height) / f64::from(c.fy)).atan()).to_degrees();
            json!({
                "camera_to_world": m,
                "fov": fov,
                "aspect": f64::from(c.width) / f64::from(c.height),
            })
        })
        .collect();
    serde_json::to_string_pretty(&json!({
        "camera_type": "perspective",
        "render_width": w,
        "render_height": h,
        "fps": fps,
        "seconds": frames.len() as f64 / f64::from(fps),
        "camera_path": path,
    }))
    .expect("camera path serialises")
}

/// Write both files into `dir` (created if missing), each atomically.
pub fn write(dir: &Path, frames: &[FrameCamera], fps: f32) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    crate::files::write_atomically(&dir.join("cameras.json"), inria_json(frames).as_bytes())?;
    crate::files::write_atomically(
        &dir.join("camera_path.json"),
        nerfstudio_json(frames, fps).as_bytes(),
    )
}
