//! COLMAP sparse models (`sparse/0`): `cameras.txt` and `images.txt`, or `cameras.bin` and
//! `images.bin`. An image holds the world-to-camera rotation as a unit quaternion
//! (qw, qx, qy, qz) and translation t, OpenCV axes: x_cam = R x_world + t, so the camera's
//! centre is −Rᵀ t and its camera-to-world rotation Rᵀ. Cameras are intrinsics shared by
//! images: PINHOLE (fx, fy, cx, cy) and SIMPLE_PINHOLE (f, cx, cy) exactly; SIMPLE_RADIAL,
//! RADIAL and OPENCV with their distortion ignored (a warning says so). The principal point
//! is taken at the image's centre (a warning when it is off by more than 1% of the size).
//! Images come in the order of their names, as the 3DGS trainer orders its cameras.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{DMat3, DQuat, DVec3};

use super::{checked, read_bytes, read_text, CameraFile, FileCamera};
use crate::scene::SceneError;

/// The folder of the COLMAP model `path` names (the folder, or one of its `cameras` /
/// `images` files), when it has both files in one encoding.
pub fn model_dir(path: &Path) -> Option<PathBuf> {
    let dir = if path.is_dir() {
        path.to_path_buf()
    } else {
        let stem = path.file_stem()?.to_str()?;
        if !matches!(stem, "cameras" | "images" | "points3D") {
            return None;
        }
        path.parent()
            .map(Path::to_path_buf)
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or_else(|| PathBuf::from("."))
    };
    let both = |ext: &str| {
        dir.join(format!("cameras.{ext}")).is_file() && dir.join(format!("images.{ext}")).is_file()
    };
    (both("bin") || both("txt")).then_some(dir)
}

/// Intrinsics of one COLMAP camera.
#[derive(Clone, Debug)]
struct Intrinsics {
    model: &'static str,
    width: u32,
    height: u32,
    /// fx, fy, cx, cy.
    pinhole: [f64; 4],
    /// The model has distortion terms (ignored).
    distorted: bool,
}

/// One registered image.
#[derive(Clone, Debug)]
struct Image {
    q: [f64; 4],
    t: [f64; 3],
    camera: i64,
    name: String,
}

/// Read the model at `path` (binary when both `.bin` files are there, else text).
pub fn read(path: &Path) -> Result<CameraFile, SceneError> {
    let dir = model_dir(path).ok_or_else(|| {
        SceneError::invalid(
            &path.display().to_string(),
            "(file)",
            "no COLMAP model",
            "a folder with cameras.txt and images.txt, or cameras.bin and images.bin",
        )
    })?;
    let binary = dir.join("cameras.bin").is_file() && dir.join("images.bin").is_file();
    let (cams_path, imgs_path) = if binary {
        (dir.join("cameras.bin"), dir.join("images.bin"))
    } else {
        (dir.join("cameras.txt"), dir.join("images.txt"))
    };
    let (intrinsics, images) = if binary {
        (
            cameras_bin(&cams_path, &read_bytes(&cams_path)?)?,
            images_bin(&imgs_path, &read_bytes(&imgs_path)?)?,
        )
    } else {
        (
            cameras_txt(&cams_path, &read_text(&cams_path)?)?,
            images_txt(&imgs_path, &read_text(&imgs_path)?)?,
        )
    };
    assemble(&imgs_path, intrinsics, images)
}

/// The images with their cameras, sorted by name, and the warnings of the cameras used.
fn assemble(
    imgs_path: &Path,
    intrinsics: HashMap<i64, Intrinsics>,
    mut images: Vec<Image>,
) -> Result<CameraFile, SceneError> {
    let origin = imgs_path.display().to_string();
    images.sort_by(|a, b| a.name.cmp(&b.name));
    let mut out = CameraFile::default();
    let mut warned: Vec<i64> = Vec::new();
    for img in images {
        let field = format!("image {:?}", img.name);
        let Some(k) = intrinsics.get(&img.camera) else {
            return Err(SceneError::invalid(
                &origin,
                format!("{field}.camera_id"),
                img.camera,
                "the id of a camera in the model's cameras file",
            ));
        };
        if !warned.contains(&img.camera) {
            warned.push(img.camera);
            out.warnings.extend(camera_warnings(&origin, img.camera, k));
        }
        let [qw, qx, qy, qz] = img.q;
        let q = DQuat::from_xyzw(qx, qy, qz, qw);
        if !(q.is_finite() && (q.length() - 1.0).abs() < 1e-3) {
            return Err(SceneError::invalid(
                &origin,
                format!("{field}.q"),
                format!("{:?}", img.q),
                "a unit quaternion (qw, qx, qy, qz)",
            ));
        }
        let r_wc = DMat3::from_quat(q.normalize());
        let c2w = r_wc.transpose();
        let centre = -(c2w * DVec3::from_array(img.t));
        let [fx, fy, _, _] = k.pinhole;
        let camera = FileCamera {
            name: img.name,
            position: centre.as_vec3(),
            rotation: c2w.as_mat3(),
            fx: fx as f32,
            fy: fy as f32,
            width: k.width,
            height: k.height,
        };
        out.cameras.push(checked(&origin, &field, camera)?);
    }
    Ok(out)
}

/// What is ignored of camera `id`: its distortion, an off-centre principal point.
fn camera_warnings(origin: &str, id: i64, k: &Intrinsics) -> Vec<String> {
    let mut w = Vec::new();
    if k.distorted {
        w.push(format!(
            "{origin}: camera {id} is {} with distortion; the distortion is ignored (rendered as a pinhole camera; undistort the images to compare with them)",
            k.model
        ));
    }
    let [_, _, cx, cy] = k.pinhole;
    let (dx, dy) = (
        cx - f64::from(k.width) / 2.0,
        cy - f64::from(k.height) / 2.0,
    );
    if dx.abs() > 0.01 * f64::from(k.width) || dy.abs() > 0.01 * f64::from(k.height) {
        w.push(format!(
            "{origin}: camera {id}'s principal point ({cx}, {cy}) is off the image's centre by ({dx:.1}, {dy:.1}) px; it is taken at the centre"
        ));
    }
    w
}

/// The pinhole part of a model's parameters: (name, fx, fy, cx, cy, distorted), or `None`
/// for a model not read.
fn pinhole(model: &str, p: &[f64]) -> Option<(&'static str, [f64; 4], bool)> {
    Some(match (model, p.len()) {
        ("SIMPLE_PINHOLE", 3) => ("SIMPLE_PINHOLE", [p[0], p[0], p[1], p[2]], false),
        ("PINHOLE", 4) => ("PINHOLE", [p[0], p[1], p[2], p[3]], false),
        ("SIMPLE_RADIAL", 4) => ("SIMPLE_RADIAL", [p[0], p[0], p[1], p[2]], true),
        ("RADIAL", 5) => ("RADIAL", [p[0], p[0], p[1], p[2]], true),
        ("OPENCV", 8) => ("OPENCV", [p[0], p[1], p[2], p[3]], true),
        _ => return None,
    })
}

/// COLMAP's model ids (`colmap/src/colmap/sensor/models.h`) with their parameter counts.
const MODELS: [(&str, usize); 11] = [
    ("SIMPLE_PINHOLE", 3),
    ("PINHOLE", 4),
    ("SIMPLE_RADIAL", 4),
    ("RADIAL", 5),
    ("OPENCV", 8),
    ("OPENCV_FISHEYE", 8),
    ("FULL_OPENCV", 12),
    ("FOV", 5),
    ("SIMPLE_RADIAL_FISHEYE", 4),
    ("RADIAL_FISHEYE", 5),
    ("THIN_PRISM_FISHEYE", 12),
];

fn intrinsics(
    origin: &str,
    id: i64,
    model: &str,
    (width, height): (u64, u64),
    params: &[f64],
) -> Result<Intrinsics, SceneError> {
    let Some((model, pinhole, distorted)) = pinhole(model, params) else {
        return Err(SceneError::invalid(
            origin,
            format!("camera {id}"),
            format!("{model} with {} parameters", params.len()),
            "a PINHOLE or SIMPLE_PINHOLE camera (SIMPLE_RADIAL, RADIAL and OPENCV are read with their distortion ignored); undistort the model (colmap image_undistorter) for others",
        ));
    };
    let size = |v: u64| u32::try_from(v).unwrap_or(u32::MAX);
    Ok(Intrinsics {
        model,
        width: size(width),
        height: size(height),
        pinhole,
        distorted,
    })
}

/// The lines of a text file that are not comments.
fn content_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim_start().starts_with('#'))
        .map(|(i, l)| (i + 1, l))
}

fn number<T: std::str::FromStr>(
    origin: &str,
    line: usize,
    what: &str,
    word: Option<&str>,
) -> Result<T, SceneError> {
    word.and_then(|w| w.parse().ok()).ok_or_else(|| {
        SceneError::invalid(
            origin,
            format!("line {line}"),
            format!("{:?}", word.unwrap_or("")),
            format!("{what} (a number)"),
        )
    })
}

/// `cameras.txt`: `CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]` per line.
fn cameras_txt(path: &Path, text: &str) -> Result<HashMap<i64, Intrinsics>, SceneError> {
    let origin = path.display().to_string();
    let mut out = HashMap::new();
    for (n, line) in content_lines(text).filter(|(_, l)| !l.trim().is_empty()) {
        let mut w = line.split_whitespace();
        let id: i64 = number(&origin, n, "CAMERA_ID", w.next())?;
        let model = w.next().unwrap_or("").to_string();
        let width: u64 = number(&origin, n, "WIDTH", w.next())?;
        let height: u64 = number(&origin, n, "HEIGHT", w.next())?;
        let params = w
            .map(|p| number(&origin, n, "a parameter", Some(p)))
            .collect::<Result<Vec<f64>, _>>()?;
        out.insert(
            id,
            intrinsics(&origin, id, &model, (width, height), &params)?,
        );
    }
    Ok(out)
}

/// `images.txt`: per image two lines, `IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME` and its
/// 2D points (possibly empty, not read).
fn images_txt(path: &Path, text: &str) -> Result<Vec<Image>, SceneError> {
    let origin = path.display().to_string();
    let lines: Vec<(usize, &str)> = content_lines(text).collect();
    let mut out = Vec::new();
    let mut k = 0;
    while k < lines.len() {
        let (n, line) = lines[k];
        k += 2;
        if line.trim().is_empty() {
            // a trailing blank line, or an image line missing: nothing to read here
            k -= 1;
            continue;
        }
        let mut w = line.split_whitespace();
        let _id: i64 = number(&origin, n, "IMAGE_ID", w.next())?;
        let mut v = [0.0; 7];
        for (slot, what) in v.iter_mut().zip(["QW", "QX", "QY", "QZ", "TX", "TY", "TZ"]) {
            *slot = number(&origin, n, what, w.next())?;
        }
        let camera: i64 = number(&origin, n, "CAMERA_ID", w.next())?;
        let name = w.collect::<Vec<_>>().join(" ");
        out.push(Image {
            q: [v[0], v[1], v[2], v[3]],
            t: [v[4], v[5], v[6]],
            camera,
            name,
        });
    }
    Ok(out)
}

/// A little-endian reader over a binary model file, whose errors name the file and offset.
struct Bytes<'a> {
    origin: String,
    data: &'a [u8],
    at: usize,
}

impl Bytes<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], SceneError> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.data.len());
        let Some(end) = end else {
            return Err(SceneError::invalid(
                &self.origin,
                format!("byte {}", self.at),
                format!("{} bytes left", self.data.len() - self.at),
                format!("{n} more bytes (the file is cut short or not a COLMAP model)"),
            ));
        };
        let out = &self.data[self.at..end];
        self.at = end;
        Ok(out)
    }
    fn u64(&mut self) -> Result<u64, SceneError> {
        Ok(u64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        ))
    }
    fn i32(&mut self) -> Result<i32, SceneError> {
        Ok(i32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }
    fn f64(&mut self) -> Result<f64, SceneError> {
        Ok(f64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        ))
    }
    /// A count of records of at least `record` bytes each, checked against what is left.
    fn count(&mut self, record: usize) -> Result<usize, SceneError> {
        let n = self.u64()?;
        let left = (self.data.len() - self.at) as u64;
        if n > left / record as u64 {
            return Err(SceneError::invalid(
                &self.origin,
                format!("byte {}", self.at - 8),
                format!("a count of {n}"),
                format!(
                    "at most {} records in the {left} bytes left",
                    left / record as u64
                ),
            ));
        }
        Ok(n as usize)
    }
}

/// `cameras.bin`: u64 count; per camera i32 id, i32 model id, u64 width, u64 height, then
/// the model's f64 parameters.
fn cameras_bin(path: &Path, data: &[u8]) -> Result<HashMap<i64, Intrinsics>, SceneError> {
    let origin = path.display().to_string();
    let mut b = Bytes {
        origin: origin.clone(),
        data,
        at: 0,
    };
    let n = b.count(24)?;
    let mut out = HashMap::new();
    for _ in 0..n {
        let id = i64::from(b.i32()?);
        let model_id = b.i32()?;
        let (width, height) = (b.u64()?, b.u64()?);
        let Some(&(model, count)) = usize::try_from(model_id).ok().and_then(|m| MODELS.get(m))
        else {
            return Err(SceneError::invalid(
                &origin,
                format!("camera {id}"),
                format!("model id {model_id}"),
                "a COLMAP camera model id from 0 to 10",
            ));
        };
        let params = (0..count).map(|_| b.f64()).collect::<Result<Vec<_>, _>>()?;
        out.insert(
            id,
            intrinsics(&origin, id, model, (width, height), &params)?,
        );
    }
    Ok(out)
}

/// `images.bin`: u64 count; per image i32 id, f64 qw qx qy qz tx ty tz, i32 camera id, the
/// name NUL-terminated, u64 count of 2D points and 24 bytes each (skipped).
fn images_bin(path: &Path, data: &[u8]) -> Result<Vec<Image>, SceneError> {
    let mut b = Bytes {
        origin: path.display().to_string(),
        data,
        at: 0,
    };
    let n = b.count(4 + 56 + 4 + 1 + 8)?;
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let _id = b.i32()?;
        let mut v = [0.0; 7];
        for slot in &mut v {
            *slot = b.f64()?;
        }
        let camera = i64::from(b.i32()?);
        let mut name = Vec::new();
        loop {
            let c = b.take(1)?[0];
            if c == 0 {
                break;
            }
            name.push(c);
        }
        let points = b.count(24)?;
        b.take(points * 24)?;
        out.push(Image {
            q: [v[0], v[1], v[2], v[3]],
            t: [v[4], v[5], v[6]],
            camera,
            name: String::from_utf8_lossy(&name).into_owned(),
        });
    }
    Ok(out)
}
