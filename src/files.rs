//! Files that are never seen half written.

use std::path::{Path, PathBuf};

/// Write `bytes` to a hidden temporary file beside `path`, then rename it to `path`, so
/// that `path` is never seen partly written (a crash or a full disk leaves the old file, or
/// none).
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = temporary_name(path);
    let result = std::fs::write(&tmp, bytes).and_then(|()| std::fs::rename(&tmp, path));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// `frame_00001.png` → `.frame_00001.png.<pid>.tmp` (hidden, so globbing `frame_*.png`
/// never matches a partial file; the process id keeps two processes that write the same
/// file — two farm jobs saving a checkpoint into one folder — off each other's temporary).
fn temporary_name(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}
