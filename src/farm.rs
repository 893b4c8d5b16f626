//! Render farms: `splatter render SCENE --from-states DIR --frames A..B` renders frames from
//! the per-frame 3DGS PLY states that `--export-ply DIR` wrote, with the scene's camera path
//! and output settings and no simulation, so that frame ranges can go to separate machines
//! (see `docs/farm.md`). Each frame depends only on its own PLY, the scene and the adapter,
//! so a frame rendered by one process is byte-identical to the same frame rendered by
//! another on the same adapter.

use std::path::{Path, PathBuf};

use glam::{Mat3, Vec3};

use crate::output::export::frame_ply_path;
use crate::render::Splats;
use crate::splat::ply::{read_ply, PlyError};

#[derive(Debug, thiserror::Error)]
pub enum FarmError {
    #[error("--from-states {dir}: {missing} of the {total} frame states of frames {start}..{end} are missing, first {first} (write them with `splatter render SCENE --export-ply {dir}`)")]
    Missing {
        dir: PathBuf,
        missing: usize,
        total: usize,
        start: u32,
        end: u32,
        first: PathBuf,
    },
    #[error("--from-states {dir} is not a directory")]
    NotADirectory { dir: PathBuf },
    #[error(transparent)]
    Ply(#[from] PlyError),
}

/// Check, before rendering starts, that `dir` holds a state for every frame of `frames`.
pub fn check_states(dir: &Path, frames: std::ops::Range<u32>) -> Result<(), FarmError> {
    if !dir.is_dir() {
        return Err(FarmError::NotADirectory {
            dir: dir.to_owned(),
        });
    }
    let missing: Vec<PathBuf> = frames
        .clone()
        .map(|f| frame_ply_path(dir, f))
        .filter(|p| !p.is_file())
        .collect();
    if let Some(first) = missing.first() {
        return Err(FarmError::Missing {
            dir: dir.to_owned(),
            missing: missing.len(),
            total: frames.len(),
            start: frames.start,
            end: frames.end,
            first: first.clone(),
        });
    }
    Ok(())
}

/// Frame `frame`'s Gaussians from `dir/frame_NNNNN.ply` (world space, SH in the world
/// frame, as `--export-ply` writes them); also the number of Gaussians the reader skipped.
pub fn load_state(dir: &Path, frame: u32) -> Result<(Splats, usize), FarmError> {
    let (cloud, report) = read_ply(&frame_ply_path(dir, frame))?;
    let skipped = report.skipped_nonfinite + report.skipped_degenerate;
    Ok((
        Splats::from_cloud(&cloud, Mat3::IDENTITY, Vec3::ZERO),
        skipped,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_states_are_counted_and_named_before_rendering() {
        let dir = tempfile::tempdir().unwrap();
        for f in [0u32, 1, 3] {
            std::fs::write(frame_ply_path(dir.path(), f), b"ply").unwrap();
        }
        check_states(dir.path(), 0..2).unwrap();
        let e = check_states(dir.path(), 0..6).unwrap_err().to_string();
        assert!(
            e.contains("3 of the 6") && e.contains("frame_00002.ply"),
            "{e}"
        );
        assert!(e.contains("--export-ply"), "{e}");
        let e = check_states(&dir.path().join("nope"), 0..1)
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a directory"), "{e}");
    }
}
