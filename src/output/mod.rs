//! Frame output: PNGs encoded on a worker thread and written to a temporary name, then
//! renamed, so a crash or a full disk never leaves a truncated `frame_*.png`; and the
//! progress display.

pub mod export;
pub mod manifest;
pub mod particles;
pub mod passes;
mod progress;
pub mod text;
pub mod video;

pub use progress::Progress;

use std::path::{Path, PathBuf};
use std::sync::{mpsc, Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("cannot create the output directory {path}: {source}")]
    CreateDir {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot write {path}: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot encode {path}: {source}")]
    Encode {
        path: PathBuf,
        source: image::ImageError,
    },
    #[error("cannot encode {path}: {source}")]
    EncodeExr {
        path: PathBuf,
        source: exr::error::Error,
    },
    #[error("the frame writer thread stopped unexpectedly")]
    WriterGone,
}

/// `DIR/frame_00042.png`.
pub fn frame_path(dir: &Path, frame: u32) -> PathBuf {
    dir.join(format!("frame_{frame:05}.png"))
}

/// Encode an RGBA8 image as an RGB PNG (the alpha channel is always opaque).
pub fn encode_png(width: u32, height: u32, rgba: &[u8]) -> Result<Vec<u8>, image::ImageError> {
    use image::ImageEncoder;
    let rgb: Vec<u8> = rgba
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes).write_image(
        &rgb,
        width,
        height,
        image::ExtendedColorType::Rgb8,
    )?;
    Ok(bytes)
}

/// Encode an RGBA8 image as an RGB PNG at `path`, atomically (temporary name, then rename).
pub fn write_png(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<(), OutputError> {
    let bytes = encode_png(width, height, rgba).map_err(|source| OutputError::Encode {
        path: path.to_owned(),
        source,
    })?;
    write_atomically(path, &bytes)
}

/// [`crate::files::write_atomically`], with the path in the error.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    crate::files::write_atomically(path, bytes).map_err(|source| OutputError::Write {
        path: path.to_owned(),
        source,
    })
}

struct Job {
    path: PathBuf,
    width: u32,
    height: u32,
    pixels: Pixels,
}

/// What a job writes.
pub enum Pixels {
    /// A colour frame: RGBA8 in, an RGB PNG out.
    Frame(Vec<u8>),
    /// The alpha pass: an RGBA PNG.
    Rgba(Vec<u8>),
    /// The depth pass: an OpenEXR of one float channel.
    Depth(Vec<f32>),
    /// The normal pass: an OpenEXR of three float channels.
    Normal(Vec<[f32; 3]>),
    /// The id pass: a 16-bit grey PNG.
    Id(Vec<u16>),
}

/// Encode and write a job, atomically.
fn write_job(job: &Job) -> Result<(), OutputError> {
    let (w, h, path) = (job.width, job.height, &job.path);
    let encoded = match &job.pixels {
        Pixels::Frame(rgba) => return write_png(path, w, h, rgba),
        Pixels::Rgba(rgba) => passes::encode_rgba_png(w, h, rgba),
        Pixels::Id(ids) => passes::encode_id_png(w, h, ids),
        Pixels::Normal(normals) => {
            let bytes = passes::encode_normal_exr(w, h, normals).map_err(|source| {
                OutputError::EncodeExr {
                    path: path.clone(),
                    source,
                }
            })?;
            return write_atomically(path, &bytes);
        }
        Pixels::Depth(depth) => {
            let bytes =
                passes::encode_depth_exr(w, h, depth).map_err(|source| OutputError::EncodeExr {
                    path: path.clone(),
                    source,
                })?;
            return write_atomically(path, &bytes);
        }
    };
    let bytes = encoded.map_err(|source| OutputError::Encode {
        path: path.clone(),
        source,
    })?;
    write_atomically(path, &bytes)
}

/// Encodes and writes frames on worker threads while the GPU renders the next ones. PNG
/// encoding of a large frame costs more than rendering it on a GPU, so several workers share
/// the queue (each frame is its own file, so the order of completion does not matter). At
/// most `depth` frames wait in the queue, so memory stays bounded.
pub struct FrameWriter {
    tx: Option<mpsc::SyncSender<Job>>,
    workers: Vec<JoinHandle<Result<Duration, OutputError>>>,
    /// Jobs finished (written or failed) and whether one failed, for
    /// [`flush`](Self::flush).
    done: Arc<(Mutex<(u64, bool)>, Condvar)>,
    submitted: u64,
}

impl FrameWriter {
    /// `workers` encoding threads (at least one) and a queue of `depth` frames.
    pub fn new(workers: usize, depth: usize) -> FrameWriter {
        let (tx, rx) = mpsc::sync_channel::<Job>(depth);
        let rx = Arc::new(Mutex::new(rx));
        let done = Arc::new((Mutex::new((0u64, false)), Condvar::new()));
        let workers = (0..workers.max(1))
            .map(|_| {
                let rx = Arc::clone(&rx);
                let done = Arc::clone(&done);
                std::thread::spawn(move || {
                    let mut busy = Duration::ZERO;
                    loop {
                        // The lock is held only while taking a job, not while encoding it.
                        let job = rx.lock().unwrap_or_else(|p| p.into_inner()).recv();
                        let Ok(job) = job else { return Ok(busy) };
                        let start = Instant::now();
                        let written = write_job(&job);
                        busy += start.elapsed();
                        let (state, cv) = &*done;
                        {
                            let mut state = state.lock().unwrap_or_else(|p| p.into_inner());
                            state.0 += 1;
                            state.1 |= written.is_err();
                        }
                        cv.notify_all();
                        written?;
                    }
                })
            })
            .collect();
        FrameWriter {
            tx: Some(tx),
            workers,
            done,
            submitted: 0,
        }
    }

    /// Workers for this machine: the cores left after the rendering thread, at most 8.
    pub fn default_workers() -> usize {
        std::thread::available_parallelism()
            .map_or(1, |n| n.get().saturating_sub(1))
            .clamp(1, 8)
    }

    /// Queue a frame. Fails if a write failed (with that write's error).
    pub fn submit(
        &mut self,
        path: PathBuf,
        width: u32,
        height: u32,
        rgba: Vec<u8>,
    ) -> Result<(), OutputError> {
        self.submit_pixels(path, width, height, Pixels::Frame(rgba))
    }

    /// Queue an image of any kind (a frame or a pass). Fails if a write failed.
    pub fn submit_pixels(
        &mut self,
        path: PathBuf,
        width: u32,
        height: u32,
        pixels: Pixels,
    ) -> Result<(), OutputError> {
        if self.workers.iter().any(|w| w.is_finished()) {
            // A worker only stops early on an error: report it now rather than at the end.
            return Err(self.join().err().unwrap_or(OutputError::WriterGone));
        }
        let tx = self.tx.as_ref().ok_or(OutputError::WriterGone)?;
        if tx
            .send(Job {
                path,
                width,
                height,
                pixels,
            })
            .is_err()
        {
            return Err(self.join().err().unwrap_or(OutputError::WriterGone));
        }
        self.submitted += 1;
        Ok(())
    }

    /// Wait until every frame queued so far is on disk (or failed: then that error), while
    /// keeping the workers for more frames. A checkpoint is saved only after a flush, so the
    /// frames before it are never lost to a crash.
    pub fn flush(&mut self) -> Result<(), OutputError> {
        let (state, cv) = &*self.done;
        let mut done = state.lock().unwrap_or_else(|p| p.into_inner());
        while done.0 < self.submitted && !done.1 {
            if self.workers.iter().any(|w| w.is_finished()) {
                break;
            }
            done = cv
                .wait_timeout(done, Duration::from_millis(100))
                .unwrap_or_else(|p| p.into_inner())
                .0;
        }
        let failed = done.1 || done.0 < self.submitted;
        drop(done);
        if failed {
            // A failed worker has returned (or is returning) its error: join to get it.
            return Err(self.join().err().unwrap_or(OutputError::WriterGone));
        }
        Ok(())
    }

    /// Wait for every queued frame; returns the time spent encoding and writing (summed
    /// over the workers).
    pub fn finish(mut self) -> Result<Duration, OutputError> {
        self.join()
    }

    fn join(&mut self) -> Result<Duration, OutputError> {
        self.tx = None;
        if self.workers.is_empty() {
            return Err(OutputError::WriterGone);
        }
        let mut busy = Duration::ZERO;
        let mut first_error = None;
        for worker in self.workers.drain(..) {
            match worker.join() {
                Ok(Ok(d)) => busy += d,
                Ok(Err(e)) => {
                    first_error.get_or_insert(e);
                }
                Err(_) => {
                    first_error.get_or_insert(OutputError::WriterGone);
                }
            }
        }
        first_error.map_or(Ok(busy), Err)
    }
}

impl Drop for FrameWriter {
    fn drop(&mut self) {
        if !self.workers.is_empty() {
            let _ = self.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn png_is_written_atomically_and_reads_back() {
        let dir = tempfile::tempdir().unwrap();
        let path = frame_path(dir.path(), 3);
        let rgba: Vec<u8> = (0..4 * 6).map(|i| (i * 10) as u8).collect();
        write_png(&path, 3, 2, &rgba).unwrap();
        assert!(path.ends_with("frame_00003.png"));
        let img = image::open(&path).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (3, 2));
        assert_eq!(img.get_pixel(1, 0).0, [40, 50, 60]);
        let leftovers: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .filter_map(|e| e.ok())
            .collect();
        assert_eq!(leftovers.len(), 1, "no temporary file left behind");
    }

    #[test]
    fn flush_waits_for_every_queued_frame() {
        let dir = tempfile::tempdir().unwrap();
        let mut w = FrameWriter::new(2, 4);
        let rgba = vec![200u8; 64 * 64 * 4];
        for f in 0..6 {
            w.submit(frame_path(dir.path(), f), 64, 64, rgba.clone())
                .unwrap();
        }
        w.flush().unwrap();
        for f in 0..6 {
            assert!(frame_path(dir.path(), f).exists(), "frame {f} written");
        }
        w.submit(frame_path(dir.path(), 6), 64, 64, rgba).unwrap();
        w.finish().unwrap();
        assert!(frame_path(dir.path(), 6).exists());
    }

    #[test]
    fn flush_reports_a_failed_write() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("a-file");
        std::fs::write(&file, b"x").unwrap();
        let mut w = FrameWriter::new(1, 2);
        // The parent of the frame is a regular file: the write fails with ENOTDIR.
        let bad = frame_path(&file, 0);
        w.submit(bad, 1, 1, vec![0, 0, 0, 255]).unwrap();
        let err = w.flush().unwrap_err().to_string();
        assert!(err.contains("a-file/frame_00000.png"), "{err}");
        assert!(err.to_lowercase().contains("not a directory"), "{err}");
    }

    #[test]
    fn writer_reports_an_unwritable_directory() {
        let mut w = FrameWriter::new(2, 2);
        let bad = PathBuf::from("/nonexistent-dir-for-splatter-test/frame_00000.png");
        let _ = w.submit(bad, 1, 1, vec![0, 0, 0, 255]);
        let err = w.finish().unwrap_err();
        assert!(
            err.to_string()
                .contains("nonexistent-dir-for-splatter-test"),
            "{err}"
        );
    }
}
