//! Building a scene's Gaussians: each object loaded (a capture) or generated (procedural),
//! then placed by its transform.

use rayon::prelude::*;

use super::{one_line, ObjectSpec, Scene, SceneError};
use crate::render::Splats;

impl Scene {
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
                let labels = obj.label_property.as_deref();
                let (cloud, read) = crate::splat::formats::read_splats_labelled(&full, labels)
                    .map_err(|e| fail(e.to_string()))?;
                report.skipped_nonfinite = read.skipped_nonfinite;
                report.skipped_degenerate = read.skipped_degenerate;
                cloud
            }
            (None, Some(_)) if obj.label_property.is_some() => {
                return Err(fail(
                    "has `label_property`, which names a property of a `ply` capture, not of a procedural object (its labels are its regions)".into(),
                ))
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
