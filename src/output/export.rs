//! `--export-ply`, `--export-spz` and `--export-glb`: the Gaussians of a frame, as the
//! renderer draws them, written as a standard 3DGS PLY, as SPZ or as glTF GLB
//! (KHR_gaussian_splatting) so that any splat viewer can play a simulation, region labels
//! included (PLY: an integer property and header comments; SPZ: an extension record; GLB:
//! an application attribute, docs/formats.md). The GLB is turned from the z-up world into
//! glTF's y-up frame, so that glTF viewers show the scene upright. Each covariance is
//! folded back into scale and rotation (its eigen-decomposition), and SH coefficients are
//! rotated from the Gaussian's rest frame into the world frame (viewers have no
//! per-Gaussian frame).

use std::path::{Path, PathBuf};

use glam::{DMat3, DQuat, Vec3};
use rayon::prelude::*;

use crate::render::gpu::layout::GaussianIn;
use crate::render::splats::mat3_from_sym3;
use crate::render::Splats;
use crate::sim::svd::symmetric_eigen;
use crate::splat::formats::{write_splats, SourceFrame, SplatError, WriteFormat};
use crate::splat::sh::ShRotator;
use crate::splat::spz::SpzVersion;
use crate::splat::{GaussianCloud, NO_LABEL};

/// A per-frame export format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Export {
    Ply,
    Spz,
    Glb,
}

impl Export {
    fn extension(self) -> &'static str {
        match self {
            Export::Ply => "ply",
            Export::Spz => "spz",
            Export::Glb => "glb",
        }
    }

    /// What its directory is called in messages.
    pub fn directory_name(self) -> &'static str {
        match self {
            Export::Ply => "PLY export directory",
            Export::Spz => "SPZ export directory",
            Export::Glb => "GLB export directory",
        }
    }
}

/// `DIR/frame_00042.ply`.
pub fn frame_ply_path(dir: &Path, frame: u32) -> PathBuf {
    frame_file(dir, frame, Export::Ply)
}

/// `DIR/frame_00042.<ext>` for the export format.
pub fn frame_file(dir: &Path, frame: u32, format: Export) -> PathBuf {
    dir.join(format!("frame_{frame:05}.{}", format.extension()))
}

/// The cloud a viewer should see for `gaussians` (renderer records), with the SH of `splats`
/// (same order; SH do not change over a simulation).
pub fn world_cloud(
    gaussians: &[GaussianIn],
    splats: &Splats,
    rotator: &ShRotator,
) -> GaussianCloud {
    let stride = splats.sh_stride();
    let parts: Vec<(Vec3, Vec3, glam::Quat, f32, Vec<f32>)> = gaussians
        .par_iter()
        .enumerate()
        .map(|(i, g)| {
            let cov = mat3_from_sym3([
                g.cov_a[0], g.cov_a[1], g.cov_a[2], g.cov_a[3], g.cov_b[0], g.cov_b[1],
            ]);
            let (lambda, v) = symmetric_eigen(cov.as_dmat3());
            let scale = lambda
                .max(glam::DVec3::splat(1e-24))
                .to_array()
                .map(f64::sqrt);
            let rotation = DQuat::from_mat3(&DMat3::from_cols(v.x_axis, v.y_axis, v.z_axis))
                .normalize()
                .as_quat();
            let frame = DQuat::from_xyzw(
                g.rotation[0].into(),
                g.rotation[1].into(),
                g.rotation[2].into(),
                g.rotation[3].into(),
            )
            .normalize();
            let sh = rotator.to_world(
                splats.sh_degree,
                &splats.sh[i * stride..(i + 1) * stride],
                frame,
            );
            let mean = Vec3::new(g.mean_opacity[0], g.mean_opacity[1], g.mean_opacity[2]);
            (
                mean,
                glam::DVec3::from_array(scale).as_vec3(),
                rotation,
                g.mean_opacity[3],
                sh,
            )
        })
        .collect();
    let mut cloud = GaussianCloud {
        sh_degree: splats.sh_degree,
        labels: splats.labels.clone(),
        label_names: splats.label_names.clone(),
        ..Default::default()
    };
    // Gaussians of unlabelled objects merged with labelled ones carry NO_LABEL; files
    // name every label they use.
    if cloud.labels.contains(&NO_LABEL) {
        let id = cloud.label_names.len() as u16;
        cloud.label_names.push("unlabelled".into());
        for l in &mut cloud.labels {
            if *l == NO_LABEL {
                *l = id;
            }
        }
    }
    for (mean, scale, rotation, opacity, sh) in parts {
        cloud.positions.push(mean);
        cloud.scales.push(scale);
        cloud.rotations.push(rotation);
        cloud.opacities.push(opacity);
        cloud.sh.extend(sh);
    }
    cloud
}

/// Write frame `frame`'s Gaussians (the world cloud of [`world_cloud`]) to
/// `DIR/frame_NNNNN.<ext>`, atomically.
pub fn export_frame(
    dir: &Path,
    frame: u32,
    cloud: &GaussianCloud,
    format: Export,
) -> Result<PathBuf, SplatError> {
    let path = frame_file(dir, frame, format);
    let write = match format {
        Export::Ply => WriteFormat::Ply,
        Export::Spz => WriteFormat::Spz(SpzVersion::V3),
        Export::Glb => WriteFormat::Glb(SourceFrame::ZUp),
    };
    write_splats(&path, cloud, write)?;
    Ok(path)
}
