//! `--video OUT.mp4`: the written frames assembled into a video by `ffmpeg` after
//! rendering. ffmpeg is looked up on the PATH before rendering starts, so a missing ffmpeg
//! is reported before hours of rendering, not after.

use std::path::{Path, PathBuf};
use std::process::Command;

#[derive(Debug, thiserror::Error)]
pub enum VideoError {
    #[error("--video {video}: ffmpeg was not found on the PATH; install it (e.g. `apt-get install ffmpeg`), or leave out --video and assemble the PNG frames yourself")]
    NoFfmpeg { video: PathBuf },
    #[error("--video {video}: expected a file name ending in a video extension such as .mp4, .mov, .mkv or .webm")]
    BadName { video: PathBuf },
    #[error("--video {video}: cannot run {ffmpeg}: {source}")]
    Spawn {
        video: PathBuf,
        ffmpeg: PathBuf,
        source: std::io::Error,
    },
    #[error("--video {video}: ffmpeg failed ({status}): {stderr}")]
    Failed {
        video: PathBuf,
        status: String,
        stderr: String,
    },
}

/// The `ffmpeg` executable on `path` (a PATH-style list), if any.
pub fn find_on_path(path: Option<&std::ffi::OsStr>) -> Option<PathBuf> {
    let path = path?;
    std::env::split_paths(path)
        .map(|dir| dir.join("ffmpeg"))
        .find(|candidate| is_executable(candidate))
}

fn is_executable(p: &Path) -> bool {
    let Ok(meta) = std::fs::metadata(p) else {
        return false;
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        meta.is_file() && meta.permissions().mode() & 0o111 != 0
    }
    #[cfg(not(unix))]
    {
        meta.is_file()
    }
}

/// Check before rendering: a plausible file name and ffmpeg on the PATH. Returns ffmpeg.
pub fn preflight(video: &Path) -> Result<PathBuf, VideoError> {
    let ok_ext = video.extension().and_then(|e| e.to_str()).is_some_and(|e| {
        ["mp4", "mov", "mkv", "webm", "avi", "m4v"].contains(&e.to_ascii_lowercase().as_str())
    });
    if !ok_ext {
        return Err(VideoError::BadName {
            video: video.to_owned(),
        });
    }
    find_on_path(std::env::var_os("PATH").as_deref()).ok_or_else(|| VideoError::NoFfmpeg {
        video: video.to_owned(),
    })
}

/// The ffmpeg arguments that turn `dir/frame_NNNNN.png` for `frames` into `video` at `fps`.
/// Odd sizes are padded to even (yuv420p needs even width and height).
pub fn ffmpeg_args(
    dir: &Path,
    frames: std::ops::Range<u32>,
    fps: f32,
    video: &Path,
) -> Vec<String> {
    vec![
        "-hide_banner".into(),
        "-loglevel".into(),
        "error".into(),
        "-y".into(),
        "-framerate".into(),
        format!("{fps}"),
        "-start_number".into(),
        frames.start.to_string(),
        "-i".into(),
        dir.join("frame_%05d.png").to_string_lossy().into_owned(),
        "-frames:v".into(),
        (frames.end - frames.start).to_string(),
        "-vf".into(),
        "pad=ceil(iw/2)*2:ceil(ih/2)*2".into(),
        "-pix_fmt".into(),
        "yuv420p".into(),
        video.to_string_lossy().into_owned(),
    ]
}

/// Run `ffmpeg` on the frames (after they are all written).
pub fn assemble(
    ffmpeg: &Path,
    dir: &Path,
    frames: std::ops::Range<u32>,
    fps: f32,
    video: &Path,
) -> Result<(), VideoError> {
    let out = Command::new(ffmpeg)
        .args(ffmpeg_args(dir, frames, fps, video))
        .output()
        .map_err(|source| VideoError::Spawn {
            video: video.to_owned(),
            ffmpeg: ffmpeg.to_owned(),
            source,
        })?;
    if !out.status.success() {
        let stderr = String::from_utf8_lossy(&out.stderr);
        let tail: Vec<&str> = stderr.lines().rev().take(3).collect();
        return Err(VideoError::Failed {
            video: video.to_owned(),
            status: out.status.to_string(),
            stderr: tail.into_iter().rev().collect::<Vec<_>>().join(" / "),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arguments_name_the_frames_rate_and_range() {
        let a = ffmpeg_args(Path::new("out/x"), 5..17, 24.0, Path::new("v.mp4"));
        let s = a.join(" ");
        assert!(
            s.contains("-framerate 24 -start_number 5 -i out/x/frame_%05d.png -frames:v 12"),
            "{s}"
        );
        assert!(s.ends_with("-pix_fmt yuv420p v.mp4"), "{s}");
        assert!(crate::output::frame_path(Path::new("out/x"), 5).ends_with("frame_00005.png"));
    }

    #[test]
    fn ffmpeg_is_found_only_where_it_is_executable() {
        let dir = tempfile::tempdir().unwrap();
        let empty = tempfile::tempdir().unwrap();
        assert_eq!(find_on_path(Some(empty.path().as_os_str())), None);
        assert_eq!(find_on_path(None), None);
        let ff = dir.path().join("ffmpeg");
        std::fs::write(&ff, "#!/bin/sh\n").unwrap();
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            assert_eq!(
                find_on_path(Some(dir.path().as_os_str())),
                None,
                "not executable"
            );
            std::fs::set_permissions(&ff, std::fs::Permissions::from_mode(0o755)).unwrap();
        }
        let list = std::env::join_paths([empty.path(), dir.path()]).unwrap();
        assert_eq!(find_on_path(Some(&list)), Some(ff));
    }
}
