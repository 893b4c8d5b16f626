//! Camera paths: orbit, keyframes (Hermite/Catmull-Rom positions, slerp or look-at
//! orientation) and camera files (`scene::cameras`: INRIA `cameras.json`, COLMAP,
//! `transforms.json`, nerfstudio camera paths).

use std::path::Path;

use glam::{Mat3, Quat, Vec3};

use super::{cameras, mat3_from_rows, CamerasJsonMode, PathSpec, Scene, SceneError};
use crate::render::camera::{focal_from_fov, look_at_rotation, Camera, DEFAULT_NEAR};
use crate::spline::{locate, Hermite, Segment};

impl Scene {
    /// Frames that do not meet: a `cameras_json` path is posed in the frame its trainer
    /// reconstructed the capture in, so a capture this scene moves (any `transform`,
    /// `up: "auto"` among them) is no longer where those cameras look. One line per such
    /// object; the scene still renders as written.
    pub fn camera_frame_warnings(&self) -> Vec<String> {
        let Some((spec, _)) = self.camera.path.camera_file() else {
            return Vec::new();
        };
        self.objects
            .iter()
            .enumerate()
            .filter(|(_, obj)| obj.ply.is_some())
            .filter(|(_, obj)| {
                let (m, t) = obj.transform.affine();
                !(m.abs_diff_eq(Mat3::IDENTITY, 1e-6) && t == Vec3::ZERO)
            })
            .map(|(index, obj)| {
                format!(
                    "{}: object {:?} is transformed, but camera.path takes its poses from {}, \
                     which are in the capture's own frame: its training views will not line \
                     up (drop the object's transform to render them; docs/captures.md, Frames)",
                    self.origin,
                    obj.display_name(index),
                    spec.file.display()
                )
            })
            .collect()
    }
}

/// The camera of every frame of a scene.
#[derive(Clone, Debug)]
pub struct CameraPath {
    frames: u32,
    fps: f32,
    kind: Kind,
}

#[derive(Clone, Debug)]
enum Kind {
    Still(Camera),
    /// One camera per frame; frames past the end hold the last.
    Sequence(Vec<Camera>),
    Orbit(Orbit),
    Spline(Spline),
}

#[derive(Clone, Debug)]
struct Orbit {
    /// Intrinsics, size and near plane; position and rotation are set per frame.
    template: Camera,
    target: Vec3,
    up: Vec3,
    /// Orthonormal basis of the plane perpendicular to `up` (e1 × e2 = up).
    e1: Vec3,
    e2: Vec3,
    radius: f32,
    height: f32,
    start: f32,
    turns: f32,
}

impl CameraPath {
    /// The same camera for every frame (one frame).
    pub fn still(camera: Camera) -> CameraPath {
        CameraPath {
            frames: 1,
            fps: 24.0,
            kind: Kind::Still(camera),
        }
    }

    /// One camera per frame, in order (frames past the end hold the last camera).
    pub fn sequence(cameras: Vec<Camera>, fps: f32) -> CameraPath {
        assert!(
            !cameras.is_empty(),
            "a camera sequence needs at least one camera"
        );
        CameraPath {
            frames: cameras.len() as u32,
            fps,
            kind: Kind::Sequence(cameras),
        }
    }

    /// An orbit that frames the bounding box: it circles the box centre about `up`, 20° above
    /// the box centre, at a distance where the box's bounding sphere fills about 80% of the
    /// narrower field of view. One turn over `frames`.
    pub fn orbit_framing(
        bounds: (Vec3, Vec3),
        up: Vec3,
        fov_y_deg: f32,
        width: u32,
        height: u32,
        frames: u32,
    ) -> CameraPath {
        let (lo, hi) = bounds;
        let (centre, sphere) = if lo.is_finite() && hi.is_finite() {
            ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).max(1e-3))
        } else {
            (Vec3::ZERO, 1.0)
        };
        let up = up.try_normalize().unwrap_or(Vec3::Z);
        let fov_y_deg = if fov_y_deg.is_finite() && fov_y_deg > 0.0 && fov_y_deg < 180.0 {
            fov_y_deg
        } else {
            50.0
        };
        let (width, height) = (width.max(1), height.max(1));
        let fy = focal_from_fov(fov_y_deg.to_radians(), height);
        let half_x = (width as f32 * 0.5 / fy).atan();
        let half = half_x.min(fov_y_deg.to_radians() * 0.5);
        let distance = sphere / half.sin() / 0.8;
        let elevation = 20f32.to_radians();
        let template = Camera {
            position: Vec3::ZERO,
            rotation: Mat3::IDENTITY,
            fx: fy,
            fy,
            width,
            height,
            near: (distance * 1e-3).clamp(1e-4, DEFAULT_NEAR),
        };
        let (e1, e2) = plane_basis(up);
        CameraPath {
            frames: frames.max(1),
            fps: 24.0,
            kind: Kind::Orbit(Orbit {
                template,
                target: centre,
                up,
                e1,
                e2,
                radius: distance * elevation.cos(),
                height: distance * elevation.sin(),
                start: 0.0,
                turns: 1.0,
            }),
        }
    }

    /// Number of frames the path was made for.
    pub fn frames(&self) -> u32 {
        self.frames
    }

    /// Frames per second (frame f is at time f / fps).
    pub fn fps(&self) -> f32 {
        self.fps
    }

    /// The camera of frame `frame`.
    pub fn camera(&self, frame: u32) -> Camera {
        match &self.kind {
            Kind::Spline(s) => s.eval(frame as f32 / self.fps),
            _ => self.camera_at_frame(frame as f32),
        }
    }

    /// The camera at time `seconds` (frame f is at time f / fps; a sequence holds each camera
    /// for a whole frame).
    pub fn camera_at_time(&self, seconds: f32) -> Camera {
        match &self.kind {
            Kind::Spline(s) => s.eval(seconds),
            _ => self.camera_at_frame(seconds * self.fps),
        }
    }

    fn camera_at_frame(&self, frame: f32) -> Camera {
        match &self.kind {
            Kind::Still(c) => *c,
            Kind::Sequence(cams) => {
                let i = if frame.is_finite() && frame > 0.0 {
                    frame.floor() as usize
                } else {
                    0
                };
                cams[i.min(cams.len() - 1)]
            }
            Kind::Orbit(o) => {
                let angle =
                    o.start + std::f32::consts::TAU * o.turns * frame / self.frames.max(1) as f32;
                let position = o.target
                    + o.up * o.height
                    + o.radius * (angle.cos() * o.e1 + angle.sin() * o.e2);
                Camera {
                    position,
                    rotation: look_at_rotation(position, o.target, o.up),
                    ..o.template
                }
            }
            Kind::Spline(s) => s.eval(frame / self.fps),
        }
    }
}

/// A unit vector basis (e1, e2) of the plane perpendicular to unit `up`, with e1 × e2 = up and
/// e1 as close to +x as possible (so that for +z up, angle 0 is +x and angles turn toward +y).
fn plane_basis(up: Vec3) -> (Vec3, Vec3) {
    let mut e1 = Vec3::X - up * up.dot(Vec3::X);
    if e1.length_squared() < 1e-6 {
        e1 = Vec3::Y - up * up.dot(Vec3::Y);
    }
    let e1 = e1.normalize();
    (e1, up.cross(e1))
}

// ---------------------------------------------------------------------------------------------
// Keyframe splines
// ---------------------------------------------------------------------------------------------

#[derive(Clone, Debug)]
enum Orientation {
    /// Slerp between neighbouring keyframes' rotations.
    Slerp(Vec<Quat>),
    /// A look-at target interpolated like the positions.
    LookAt(Hermite),
}

#[derive(Clone, Debug)]
struct Spline {
    template: Camera,
    up: Vec3,
    positions: Hermite,
    orientation: Orientation,
    /// Per-keyframe focal lengths (fx, fy), interpolated linearly; empty: the template's.
    focals: Vec<(f32, f32)>,
}

impl Spline {
    fn eval(&self, t: f32) -> Camera {
        let seg = locate(&self.positions.times, t);
        let position = self.positions.eval(seg);
        let rotation = match &self.orientation {
            Orientation::LookAt(targets) => look_at_rotation(position, targets.eval(seg), self.up),
            Orientation::Slerp(qs) => Mat3::from_quat(match seg {
                Segment::At(i) => qs[i],
                Segment::Between(i, u) => qs[i].slerp(qs[i + 1], u).normalize(),
            }),
        };
        let (fx, fy) = match (self.focals.is_empty(), seg) {
            (true, _) => (self.template.fx, self.template.fy),
            (false, Segment::At(i)) => self.focals[i],
            (false, Segment::Between(i, u)) => {
                let (a, b) = (self.focals[i], self.focals[i + 1]);
                (a.0 + (b.0 - a.0) * u, a.1 + (b.1 - a.1) * u)
            }
        };
        Camera {
            position,
            rotation,
            fx,
            fy,
            ..self.template
        }
    }
}

/// A keyframe in world terms, for building splines.
struct Key {
    time: f32,
    position: Vec3,
    look_at: Option<Vec3>,
    rotation: Option<Mat3>,
    focal: Option<(f32, f32)>,
}

fn spline(template: Camera, up: Vec3, keys: &[Key]) -> Spline {
    let times: Vec<f32> = keys.iter().map(|k| k.time).collect();
    let positions = Hermite::new(times.clone(), keys.iter().map(|k| k.position).collect());
    let orientation = match keys
        .iter()
        .map(|k| k.look_at)
        .collect::<Option<Vec<Vec3>>>()
    {
        Some(targets) => Orientation::LookAt(Hermite::new(times, targets)),
        None => Orientation::Slerp(
            keys.iter()
                .map(|k| {
                    let r = k.rotation.unwrap_or_else(|| {
                        look_at_rotation(k.position, k.look_at.unwrap_or(Vec3::ZERO), up)
                    });
                    Quat::from_mat3(&r).normalize()
                })
                .collect(),
        ),
    };
    let focals = keys
        .iter()
        .map(|k| k.focal)
        .collect::<Option<Vec<_>>>()
        .unwrap_or_default();
    Spline {
        template,
        up,
        positions,
        orientation,
        focals,
    }
}

// ---------------------------------------------------------------------------------------------
// Camera files
// ---------------------------------------------------------------------------------------------

/// The cameras of an INRIA 3DGS `cameras.json` (array of {id, img_name, width, height,
/// position, rotation (camera-to-world rows), fx, fy}), at the given output size (`None`: the
/// file's; one of the two: the other keeps each camera's aspect ratio). Focal lengths are
/// rescaled to the output size (fx·W/width, fy·H/height); position and rotation are used as
/// they are.
pub fn from_cameras_json(
    path: &Path,
    width: Option<u32>,
    height: Option<u32>,
) -> Result<Vec<Camera>, SceneError> {
    let file = cameras::read(path, cameras::CameraFormat::Inria, None)?;
    cameras::at_size(&path.display().to_string(), &file.cameras, width, height)
}

/// As [`from_cameras_json`] for a camera file of any format we read (`scene::cameras`,
/// told by its content), with what the reader warned of.
pub fn from_camera_file(
    path: &Path,
    dataparser: Option<&Path>,
    width: Option<u32>,
    height: Option<u32>,
) -> Result<(Vec<Camera>, Vec<String>), SceneError> {
    let file = cameras::read(path, cameras::CameraFormat::of(path)?, dataparser)?;
    let cams = cameras::at_size(&path.display().to_string(), &file.cameras, width, height)?;
    Ok((cams, file.warnings))
}

// ---------------------------------------------------------------------------------------------
// From a scene
// ---------------------------------------------------------------------------------------------

// Over 80 lines on purpose: one arm per kind of camera path, each short; the match is the
// table of kinds.
pub(super) fn build(scene: &Scene) -> Result<CameraPath, SceneError> {
    let out = &scene.output;
    let cam = &scene.camera;
    let (width, height) = (out.width, out.height);
    let up = Vec3::from_array(cam.up).try_normalize().unwrap_or(Vec3::Z);
    // Intrinsics the scene sets itself, in output pixels.
    let scene_focal = match (cam.fov_y_deg, cam.fx, cam.fy) {
        (Some(fov), _, _) => {
            let f = focal_from_fov(fov.to_radians(), height);
            Some((f, f))
        }
        (None, Some(fx), Some(fy)) => Some((fx, fy)),
        _ => None,
    };
    let template = |(fx, fy): (f32, f32)| Camera {
        position: Vec3::ZERO,
        rotation: Mat3::IDENTITY,
        fx,
        fy,
        width,
        height,
        near: cam.near,
    };
    let missing_intrinsics = || {
        SceneError::invalid(
            &scene.origin,
            "camera",
            "no intrinsics",
            "`fov_y_deg` (degrees) or `fx` and `fy` (pixels)",
        )
    };
    let kind = match &cam.path {
        PathSpec::Orbit(o) => {
            let (e1, e2) = plane_basis(up);
            Kind::Orbit(Orbit {
                template: template(scene_focal.ok_or_else(missing_intrinsics)?),
                target: Vec3::from_array(o.target),
                up,
                e1,
                e2,
                radius: o.radius,
                height: o.height,
                start: o.start_deg.to_radians(),
                turns: o.turns,
            })
        }
        PathSpec::Keyframes(k) => {
            let keys: Vec<Key> = k
                .keyframes
                .iter()
                .map(|k| Key {
                    time: k.time,
                    position: Vec3::from_array(k.position),
                    look_at: k.look_at.map(Vec3::from_array),
                    rotation: k.rotation.map(mat3_from_rows),
                    focal: None,
                })
                .collect();
            Kind::Spline(spline(
                template(scene_focal.ok_or_else(missing_intrinsics)?),
                up,
                &keys,
            ))
        }
        PathSpec::CamerasJson(c)
        | PathSpec::Colmap(c)
        | PathSpec::TransformsJson(c)
        | PathSpec::Nerfstudio(c) => {
            let (_, format) = cam.path.camera_file().expect("a camera file");
            let file = scene.base_dir.join(&c.file);
            let dataparser = c
                .dataparser_transforms
                .as_ref()
                .map(|d| scene.base_dir.join(d));
            let read = cameras::read(&file, format, dataparser.as_deref())?;
            for w in &read.warnings {
                log::warn!("{w}");
            }
            let origin = file.display().to_string();
            let cams = cameras::at_size(&origin, &read.cameras, Some(width), Some(height))?;
            let with_scene_focal = |c: Camera| match scene_focal {
                Some((fx, fy)) => Camera {
                    fx,
                    fy,
                    near: cam.near,
                    ..c
                },
                None => Camera {
                    near: cam.near,
                    ..c
                },
            };
            match c.mode {
                CamerasJsonMode::Each => {
                    if out.frames as usize > cams.len() {
                        return Err(SceneError::invalid(
                            &scene.origin,
                            "output.frames",
                            out.frames,
                            format!(
                                "at most {} (the number of cameras in {}) with mode \"each\"; use mode \"smooth\" to interpolate",
                                cams.len(),
                                file.display()
                            ),
                        ));
                    }
                    Kind::Sequence(
                        cams.into_iter()
                            .take(out.frames as usize)
                            .map(with_scene_focal)
                            .collect(),
                    )
                }
                CamerasJsonMode::Smooth => {
                    let n = cams.len();
                    if n == 1 || out.frames == 1 {
                        Kind::Still(with_scene_focal(cams[0]))
                    } else {
                        let last = (out.frames - 1) as f64;
                        let keys: Vec<Key> = cams
                            .iter()
                            .enumerate()
                            .map(|(i, c)| Key {
                                // The same arithmetic as `camera(frame)`: frame / fps in f32.
                                time: (i as f64 * last / (n - 1) as f64) as f32 / out.fps,
                                position: c.position,
                                look_at: None,
                                rotation: Some(c.rotation),
                                focal: Some(scene_focal.unwrap_or((c.fx, c.fy))),
                            })
                            .collect();
                        // Keep times strictly increasing even for very many cameras per frame.
                        if keys.windows(2).any(|w| w[1].time <= w[0].time) {
                            return Err(SceneError::invalid(
                                &scene.origin,
                                "output.frames",
                                out.frames,
                                format!("enough frames to spread {n} cameras over (times collide)"),
                            ));
                        }
                        Kind::Spline(spline(template((cams[0].fx, cams[0].fy)), up, &keys))
                    }
                }
            }
        }
    };
    Ok(CameraPath {
        frames: out.frames,
        fps: out.fps,
        kind,
    })
}

#[cfg(test)]
mod tests;
