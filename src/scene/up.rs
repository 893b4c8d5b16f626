//! `transform.up: "auto"`: an object's up estimated from its capture (`splat::inspect`), with
//! the capture's cameras when they are known: named (`{"auto": {"cameras": FILE}}`, or
//! `inspect --cameras FILE`) or a `cameras.json` found next to the capture, as trainers
//! write it.

use std::path::{Path, PathBuf};

use glam::Vec3;

use super::{one_line, Scene, SceneError};
use crate::splat::formats::DeclaredUp;
use crate::splat::inspect::{cameras_up, inspect_declared, Inspection};
use crate::splat::GaussianCloud;

/// A capture's inspection, and where its cameras came from.
#[derive(Clone, Debug)]
pub struct CaptureUp {
    pub inspection: Inspection,
    /// The cameras file read, and whether it was found next to the capture (not named).
    pub cameras: Option<(PathBuf, bool)>,
    /// A `cameras.json` found next to the capture that could not be read, and why.
    pub ignored: Option<String>,
}

/// The `cameras.json` that belongs to a capture: in its folder, or in the model folder of
/// graphdeco's layout (`MODEL/point_cloud/iteration_N/point_cloud.ply` beside
/// `MODEL/cameras.json`).
pub fn cameras_next_to(capture: &Path) -> Option<PathBuf> {
    let folder = capture.parent()?;
    let here = folder.join("cameras.json");
    if here.is_file() {
        return Some(here);
    }
    let iteration = folder.file_name()?.to_string_lossy();
    let point_cloud = folder.parent()?;
    let model = point_cloud.parent()?;
    let graphdeco = iteration.starts_with("iteration_")
        && point_cloud.file_name().is_some_and(|n| n == "point_cloud");
    let there = model.join("cameras.json");
    (graphdeco && there.is_file()).then_some(there)
}

/// Inspect the capture `cloud` read from `capture`, with the cameras of `named` (an error
/// when it cannot be read) or else of a `cameras.json` next to the capture (ignored, with a
/// reason, when it cannot be read: it may be another tool's file of that name), and the up
/// its format defines (`declared`, which decides when there is one).
pub fn inspect_capture(
    cloud: &GaussianCloud,
    capture: &Path,
    named: Option<&Path>,
    declared: Option<DeclaredUp>,
) -> Result<CaptureUp, SceneError> {
    let (file, found) = match named {
        Some(f) => (Some(f.to_path_buf()), false),
        None => (cameras_next_to(capture), true),
    };
    let read = file
        .as_deref()
        .map(|f| super::from_camera_file(f, None, None, None).map(|(c, _)| c));
    let (cameras, ignored) = match read {
        None => (None, None),
        Some(Ok(c)) => (Some(c), None),
        Some(Err(e)) if found => (None, Some(one_line(&e.to_string()))),
        Some(Err(e)) => return Err(e),
    };
    let rotations: Vec<glam::Mat3> = cameras.iter().flatten().map(|c| c.rotation).collect();
    Ok(CaptureUp {
        inspection: inspect_declared(cloud, cameras_up(&rotations), declared),
        cameras: file.filter(|_| cameras.is_some()).map(|f| (f, found)),
        ignored,
    })
}

impl CaptureUp {
    /// `FILE (N cameras, found next to the capture)`, when cameras were read.
    pub fn cameras_text(&self) -> Option<String> {
        let (file, found) = self.cameras.as_ref()?;
        let count = self.inspection.cameras.map_or(0, |c| c.count);
        let how = if *found {
            ", found next to the capture"
        } else {
            ""
        };
        Some(format!("{} ({count} cameras{how})", file.display()))
    }

    /// How up was decided, for the object `name`: a note when the evidence decided it.
    pub fn note(&self, name: &str) -> Option<String> {
        if self.inspection.is_guess() {
            return None;
        }
        let cameras = self
            .cameras_text()
            .map(|c| format!("; cameras: {c}"))
            .unwrap_or_default();
        Some(format!("{name}: up {}{cameras}", self.inspection.up_text()))
    }

    /// One line each: up is a guess; a `cameras.json` next to the capture was not read.
    pub fn warnings(&self, name: &str) -> Vec<String> {
        let ignored = self
            .ignored
            .as_ref()
            .map(|why| format!("{name}: the cameras.json next to the capture was not used: {why}"));
        ignored
            .into_iter()
            .chain(self.inspection.guess_warning(name))
            .chain(self.inspection.declared_warning(name))
            .collect()
    }
}

impl Scene {
    /// Estimate `transform.up` of every object that says `"auto"`: captures are read and
    /// inspected with their cameras; procedural objects are z-up already.
    pub fn resolve_up(&mut self) -> Result<(), SceneError> {
        for index in 0..self.objects.len() {
            let obj = &self.objects[index];
            let Some(spec) = obj.transform.up.as_ref().filter(|u| u.is_auto()) else {
                continue;
            };
            let Some(file) = &obj.ply else {
                self.objects[index].transform.resolved_up = Some(Vec3::Z);
                continue;
            };
            let name = obj.display_name(index);
            let fail = |message: String| SceneError::Object {
                origin: self.origin.clone(),
                index,
                name: name.clone(),
                message: one_line(&message),
            };
            let capture = self.base_dir.join(file);
            let named = spec.auto_cameras().map(|c| self.base_dir.join(c));
            let (cloud, read) =
                crate::splat::formats::read_splats(&capture).map_err(|e| fail(e.to_string()))?;
            let found = inspect_capture(&cloud, &capture, named.as_deref(), read.up)
                .map_err(|e| fail(format!("transform.up.auto.cameras: {e}")))?;
            self.up_notes.extend(found.note(&name));
            self.up_warnings.extend(found.warnings(&name));
            self.objects[index].transform.resolved_up = Some(found.inspection.up);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Beside the capture, else the model folder of graphdeco's layout, else none.
    #[test]
    fn cameras_next_to_a_capture_or_in_its_graphdeco_model() {
        let dir = tempfile::tempdir().unwrap();
        let model = dir.path();
        let iteration = model.join("point_cloud/iteration_30000");
        let elsewhere = model.join("exports/iteration_1");
        for d in [&iteration, &elsewhere] {
            std::fs::create_dir_all(d).unwrap();
        }
        let ply = iteration.join("point_cloud.ply");
        assert_eq!(cameras_next_to(&ply), None);
        std::fs::write(model.join("cameras.json"), "[]").unwrap();
        assert_eq!(cameras_next_to(&ply), Some(model.join("cameras.json")));
        assert_eq!(cameras_next_to(&elsewhere.join("capture.ply")), None);
        std::fs::write(iteration.join("cameras.json"), "[]").unwrap();
        assert_eq!(cameras_next_to(&ply), Some(iteration.join("cameras.json")));
    }
}
