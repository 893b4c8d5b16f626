//! Render farms: `splatter render SCENE --from-states DIR --frames SPEC` renders frames from
//! the per-frame 3DGS PLY states that `--export-ply DIR` wrote, with the scene's camera path
//! and output settings and no simulation, so that frame sets can go to separate machines
//! (see `docs/farm.md`). Each frame depends only on its own PLY, the scene and the adapter,
//! so a frame rendered by one process is byte-identical to the same frame rendered by
//! another on the same adapter.
//!
//! `--chunk N` gives one task of a job array its share of the frames; its index comes from
//! `--task-index`, or from the variable a render manager sets for each task.

use std::path::{Path, PathBuf};

use glam::{Mat3, Vec3};

use crate::frames::FrameSet;
use crate::output::export::frame_ply_path;
use crate::render::Splats;
use crate::splat::ply::{read_ply, PlyError};

#[derive(Debug, thiserror::Error)]
pub enum FarmError {
    #[error("--from-states {dir}: {missing} of the {total} frame states of frames {frames} are missing, first {first} (write them with `splatter render SCENE --export-ply {dir}`)")]
    Missing {
        dir: PathBuf,
        missing: usize,
        total: usize,
        frames: FrameSet,
        first: PathBuf,
    },
    #[error("--from-states {dir} is not a directory")]
    NotADirectory { dir: PathBuf },
    #[error(transparent)]
    Ply(#[from] PlyError),
    #[error("--chunk 0: expected a chunk of at least 1 frame")]
    EmptyChunk,
    #[error("--chunk {size}: no task index; give --task-index I (0-based), or run it as a Slurm array task (SLURM_ARRAY_TASK_ID) or a Kubernetes Indexed Job pod (JOB_COMPLETION_INDEX)")]
    NoTaskIndex { size: u32 },
    #[error("{var}={value:?}: expected a task index (a whole number, 0 or more)")]
    BadTaskIndex { var: &'static str, value: String },
}

/// One task's share of a render's frames: chunk `index` (0-based) of the sorted frame set
/// cut into chunks of `size` frames.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Chunk {
    pub size: u32,
    pub index: u32,
    /// Where the index came from: `--task-index` or an environment variable's name.
    pub index_from: &'static str,
    /// Something about the index the user should know (it is still used).
    pub warning: Option<String>,
}

/// The variables render managers set for each task of an array, in order of precedence.
/// Both are taken as 0-based chunk indices: Kubernetes numbers an Indexed Job's pods from
/// 0; Slurm numbers array tasks as `--array` says, so a farm's script says `--array=0-K`.
pub const TASK_INDEX_VARS: [&str; 2] = ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"];

/// `--chunk size` with the task index from `flag` (`--task-index`), else from the first of
/// [`TASK_INDEX_VARS`] that `env` has. `env` is the process environment in the program,
/// a table in tests.
pub fn chunk(
    size: u32,
    flag: Option<u32>,
    env: &dyn Fn(&str) -> Option<String>,
) -> Result<Chunk, FarmError> {
    if size == 0 {
        return Err(FarmError::EmptyChunk);
    }
    if let Some(index) = flag {
        return Ok(Chunk {
            size,
            index,
            index_from: "--task-index",
            warning: None,
        });
    }
    let Some((var, value)) = TASK_INDEX_VARS
        .into_iter()
        .find_map(|var| env(var).map(|v| (var, v)))
    else {
        return Err(FarmError::NoTaskIndex { size });
    };
    let index = value
        .trim()
        .parse()
        .map_err(|_| FarmError::BadTaskIndex { var, value })?;
    Ok(Chunk {
        size,
        index,
        index_from: var,
        warning: (var == "SLURM_ARRAY_TASK_ID")
            .then(|| slurm_base_warning(env))
            .flatten(),
    })
}

/// A Slurm array numbered from 1 (`--array=1-K`) would leave chunk 0 to no task. It may
/// also be a re-run of some tasks of a larger array, so this only warns.
fn slurm_base_warning(env: &dyn Fn(&str) -> Option<String>) -> Option<String> {
    let min: u32 = env("SLURM_ARRAY_TASK_MIN")?.trim().parse().ok()?;
    (min > 0).then(|| {
        format!(
            "SLURM_ARRAY_TASK_MIN={min}: this array has no task 0, and chunk indices start at 0, so no task of it renders chunk 0; submit the array as --array=0-K (unless it re-runs some tasks on purpose)"
        )
    })
}

/// Check, before rendering starts, that `dir` holds a state for every frame of `frames`.
pub fn check_states(dir: &Path, frames: &FrameSet) -> Result<(), FarmError> {
    if !dir.is_dir() {
        return Err(FarmError::NotADirectory {
            dir: dir.to_owned(),
        });
    }
    let missing: Vec<PathBuf> = frames
        .iter()
        .map(|f| frame_ply_path(dir, f))
        .filter(|p| !p.is_file())
        .collect();
    if let Some(first) = missing.first() {
        return Err(FarmError::Missing {
            dir: dir.to_owned(),
            missing: missing.len(),
            total: frames.len(),
            frames: frames.clone(),
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
        check_states(dir.path(), &FrameSet::from(0..2)).unwrap();
        let e = check_states(dir.path(), &FrameSet::from(0..6))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("3 of the 6") && e.contains("frame_00002.ply") && e.contains("0-5"),
            "{e}"
        );
        assert!(e.contains("--export-ply"), "{e}");
        // Only the listed frames need states.
        let listed = FrameSet::parse(Some("0,3"), 6).unwrap();
        check_states(dir.path(), &listed).unwrap();
        let e = check_states(&dir.path().join("nope"), &FrameSet::from(0..1))
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a directory"), "{e}");
    }

    /// An environment of `vars` only.
    fn env<'a>(vars: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |name| {
            vars.iter()
                .find(|(k, _)| *k == name)
                .map(|(_, v)| v.to_string())
        }
    }

    #[test]
    fn the_task_index_comes_from_the_flag_then_slurm_then_kubernetes() {
        let both = env(&[("SLURM_ARRAY_TASK_ID", "3"), ("JOB_COMPLETION_INDEX", "5")]);
        let c = chunk(4, Some(1), &both).unwrap();
        assert_eq!((c.index, c.index_from), (1, "--task-index"));
        let c = chunk(4, None, &both).unwrap();
        assert_eq!((c.index, c.index_from), (3, "SLURM_ARRAY_TASK_ID"));
        let c = chunk(4, None, &env(&[("JOB_COMPLETION_INDEX", "0")])).unwrap();
        assert_eq!(
            (c.index, c.index_from, c.size),
            (0, "JOB_COMPLETION_INDEX", 4)
        );
        assert_eq!(c.warning, None);
    }

    #[test]
    fn a_missing_or_bad_task_index_is_refused() {
        let e = chunk(4, None, &env(&[])).unwrap_err().to_string();
        assert!(
            e.contains("--chunk 4: no task index")
                && e.contains("--task-index")
                && e.contains("SLURM_ARRAY_TASK_ID")
                && e.contains("JOB_COMPLETION_INDEX"),
            "{e}"
        );
        let e = chunk(4, None, &env(&[("SLURM_ARRAY_TASK_ID", "4294967296")]))
            .unwrap_err()
            .to_string();
        assert!(e.contains("SLURM_ARRAY_TASK_ID=\"4294967296\""), "{e}");
        let e = chunk(4, None, &env(&[("JOB_COMPLETION_INDEX", "-1")]))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("JOB_COMPLETION_INDEX=\"-1\": expected a task index"),
            "{e}"
        );
        let e = chunk(0, Some(0), &env(&[])).unwrap_err().to_string();
        assert!(e.contains("--chunk 0"), "{e}");
    }

    #[test]
    fn a_slurm_array_numbered_from_one_is_warned_about() {
        let vars = [("SLURM_ARRAY_TASK_ID", "1"), ("SLURM_ARRAY_TASK_MIN", "1")];
        let w = chunk(4, None, &env(&vars)).unwrap().warning.unwrap();
        assert!(w.contains("--array=0-K"), "{w}");
        let vars = [("SLURM_ARRAY_TASK_ID", "1"), ("SLURM_ARRAY_TASK_MIN", "0")];
        assert_eq!(chunk(4, None, &env(&vars)).unwrap().warning, None);
    }
}
