//! INRIA 3DGS `cameras.json`, as its trainer writes it: an array of `{id, img_name, width,
//! height, position, rotation, fx, fy}`, `position` the camera centre and `rotation` the
//! camera-to-world rotation as rows, OpenCV axes: our convention already.

use std::path::Path;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::{checked, read_text, CameraFile, FileCamera};
use crate::scene::{mat3_from_rows, SceneError};

/// One entry.
#[derive(Clone, Debug, Deserialize, Serialize)]
pub(super) struct Entry {
    #[serde(default)]
    pub id: Option<serde_json::Value>,
    #[serde(default)]
    pub img_name: Option<String>,
    pub width: u32,
    pub height: u32,
    pub position: [f32; 3],
    pub rotation: [[f32; 3]; 3],
    pub fx: f32,
    pub fy: f32,
}

/// Read and check a `cameras.json` (field names in errors are `[i].fx`, …).
pub fn read(path: &Path) -> Result<CameraFile, SceneError> {
    let origin = path.display().to_string();
    let entries: Vec<Entry> =
        serde_json::from_str(&read_text(path)?).map_err(|e| SceneError::parse(&origin, &e))?;
    let cameras = entries
        .into_iter()
        .enumerate()
        .map(|(i, e)| {
            let camera = FileCamera {
                name: e.img_name.unwrap_or_default(),
                position: Vec3::from_array(e.position),
                rotation: mat3_from_rows(e.rotation),
                fx: e.fx,
                fy: e.fy,
                width: e.width,
                height: e.height,
            };
            checked(&origin, &format!("[{i}]"), camera)
        })
        .collect::<Result<_, _>>()?;
    Ok(CameraFile {
        cameras,
        ..Default::default()
    })
}
