//! A run's input: the scene file (or the default scene, or a quick look at a capture) with
//! the command line's overrides, and its camera path.

use std::path::Path;

use anyhow::{bail, Result};
use glam::Vec3;

use super::RunOptions;
use crate::render::Splats;
use crate::scene::{self, BuildReport, CameraPath, Scene};

/// `--width`/`--height` within what the renderer supports.
pub(super) fn check_image_size(opts: &RunOptions) -> Result<()> {
    for (flag, value) in [("--width", opts.width), ("--height", opts.height)] {
        if let Some(v) = value {
            if !(1..=scene::MAX_IMAGE_SIZE).contains(&v) {
                bail!(
                    "{flag} {v}: expected an image size in pixels in 1..={}",
                    scene::MAX_IMAGE_SIZE
                );
            }
        }
    }
    Ok(())
}

/// The scene file (or the default scene) with quality and overrides applied, and its
/// camera path.
pub(super) fn load_scene(file: Option<&Path>, opts: &RunOptions) -> Result<(Scene, CameraPath)> {
    let scene = match file {
        Some(path) => scene::load(path)?,
        None => scene::default_scene(),
    };
    prepare_scene(scene, opts)
}

/// A scene input ([`Input::Scene`](super::Input::Scene) or a scene's JSON text) as
/// [`load_scene`] prepares it.
pub(super) fn load_scene_input(
    input: &super::Input,
    opts: &RunOptions,
) -> Result<(Scene, CameraPath)> {
    match input {
        super::Input::Text {
            text,
            name,
            base_dir,
        } => prepare_scene(scene::parse(text, name, base_dir)?, opts),
        super::Input::Scene(file) => load_scene(file.as_deref(), opts),
        _ => bail!("load_scene_input takes a scene file or a scene's text"),
    }
}

fn prepare_scene(mut scene: Scene, opts: &RunOptions) -> Result<(Scene, CameraPath)> {
    scene.apply_quality(opts.quality);
    scene.with_overrides(opts.out.clone(), opts.width, opts.height)?;
    let path = scene.camera_path()?;
    for w in scene.camera_frame_warnings() {
        log::warn!("{w}");
    }
    log_up_warnings(&scene);
    Ok((scene, path))
}

fn log_up_warnings(scene: &Scene) {
    for w in &scene.up_warnings {
        log::warn!("{w}");
    }
}

/// The scene's Gaussians, its build warnings logged.
pub(super) fn build_splats(scene: &Scene) -> Result<(Splats, BuildReport)> {
    let (splats, report) = scene.build_splats()?;
    for w in report.warnings() {
        log::warn!("{w}");
    }
    Ok((splats, report))
}

/// `--ply FILE`: the capture alone, stood upright (on `up`, else on the estimate, which
/// takes a `cameras.json` next to the capture) and framed by an orbit round its robust
/// bounds (docs/captures.md), or seen from a camera of an INRIA `cameras.json`. Those
/// cameras were posed in the capture's own frame (the trainer's), so with them the
/// capture is drawn untouched: standing it upright would move it out of their view.
pub(super) fn quick_look(
    opts: &RunOptions,
    ply: &Path,
    (cameras, dataparser): (Option<&Path>, Option<&Path>),
    camera: Option<usize>,
    up: Option<&str>,
) -> Result<(Scene, CameraPath, Splats, BuildReport)> {
    if let Some(axis) = up.filter(|a| crate::splat::inspect::axis_vector(a).is_none()) {
        bail!("--up {axis:?}: expected an axis: +x, -x, +y, -y, +z or -z");
    }
    let transform = match (cameras, up) {
        (Some(_), _) => "{}".to_string(),
        (None, Some(axis)) => format!(r#"{{"up": {}}}"#, serde_json::to_string(axis)?),
        (None, None) => r#"{"up": "auto"}"#.to_string(),
    };
    let text = format!(
        r#"{{"output": {{"width": {w}, "height": {h}, "frames": 60}},
            "camera": {{"fov_y_deg": 50, "path": {{"type": "orbit", "target": [0, 0, 0], "radius": 1}}}},
            "objects": [{{"ply": {p}, "transform": {transform}}}]}}"#,
        w = opts.width.unwrap_or(1280),
        h = opts.height.unwrap_or(720),
        p = serde_json::to_string(&ply.to_string_lossy())?,
    );
    let stem = ply
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "ply".into());
    let mut scene = scene::parse(&text, &format!("--ply {}", ply.display()), Path::new("."))?;
    scene.name = stem;
    scene.with_overrides(opts.out.clone(), None, None)?;
    log_up_warnings(&scene);
    let (splats, report) = build_splats(&scene)?;
    let path = match cameras {
        Some(file) => {
            let (cameras, warnings) =
                scene::from_camera_file(file, dataparser, opts.width, opts.height)?;
            for w in warnings {
                log::warn!("{w}");
            }
            let index = camera.unwrap_or(0);
            let Some(camera) = cameras.get(index) else {
                bail!(
                    "--camera {index}: {} has {} cameras (valid: 0..{})",
                    file.display(),
                    cameras.len(),
                    cameras.len()
                );
            };
            scene.output.frames = 1;
            scene.output.width = camera.width;
            scene.output.height = camera.height;
            CameraPath::still(*camera)
        }
        None => {
            // Stood upright (`up: auto`), framed by the robust bounds: floaters do not
            // shrink the object in the frame.
            let bounds = crate::splat::inspect::robust_bounds(&splats.means);
            let (w, h) = (scene.output.width, scene.output.height);
            CameraPath::orbit_framing(bounds, Vec3::Z, 50.0, w, h, scene.output.frames)
        }
    };
    Ok((scene, path, splats, report))
}
