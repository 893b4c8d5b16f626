//! Checkpoints of a simulated run (`OUT_DIR/checkpoint.bin`), so that `splatter render
//! --resume` continues a killed run from its last checkpoint; and the scene hash that ties
//! a checkpoint (and a run manifest) to the scene it was made from.
//!
//! Format (little-endian throughout):
//!
//! | bytes | field |
//! |---|---|
//! | 8 | magic `SPLTCKPT` |
//! | 4 | format version ([`FORMAT_VERSION`]) |
//! | 32 | program version, UTF-8, zero-padded (`CARGO_PKG_VERSION`) |
//! | 8 | scene hash ([`scene_hash`]) |
//! | 4 | flags: bit 0 = written in deterministic mode |
//! | 4 | frame index f: the state after f · steps-per-frame steps |
//! | 4 | steps of the first frame |
//! | 8 | the largest particle speed of the last frame's steps, f64 (the next frame's Δt follows it) |
//! | 8 | steps taken since frame 0 |
//! | 8 | particle count n |
//! | n · 100 | per particle: x (3 f32), v (3 f32), F (9 f32, column-major), C (9 f32), α (f32) |
//! | 8 | FNV-1a 64 of every byte before it |
//!
//! The GPU holds x, v, F, C and α as f32, so storing f32 loses nothing: f32 → f64
//! ([`GpuSim::read_particles`](crate::sim::gpu::GpuSim::read_particles)) → f32 (the upload)
//! is exact, and a resumed run continues from the very bits it stopped at. Masses, rest
//! volumes and materials are not stored: they come from the scene, which the hash pins.
//!
//! The count is checked against the file's size before anything is allocated, so a corrupt
//! or hostile header cannot ask for a huge buffer.

use std::io::Read;
use std::path::{Path, PathBuf};

use glam::{DMat3, DVec3, Mat3, Vec3};

use crate::output::{write_atomically, OutputError};
use crate::render::Splats;
use crate::scene::simulation::SimulationSetup;
use crate::scene::Scene;
use crate::sim::time_step::Clock;
use crate::sim::Particles;

/// The first 8 bytes of a checkpoint.
pub const MAGIC: &[u8; 8] = b"SPLTCKPT";
/// Bumped whenever the layout changes; other versions are refused.
pub const FORMAT_VERSION: u32 = 2;
pub use crate::PROGRAM_VERSION;

const VERSION_BYTES: usize = 32;
const HEADER_BYTES: usize = 8 + 4 + VERSION_BYTES + 8 + 4 + 4 + 4 + 8 + 8 + 8;
const PARTICLE_BYTES: usize = 25 * 4;
const FLAG_DETERMINISTIC: u32 = 1;

/// `OUT_DIR/checkpoint.bin`.
pub fn checkpoint_path(dir: &Path) -> PathBuf {
    dir.join("checkpoint.bin")
}

#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error("cannot read the checkpoint {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path} is not a splatter checkpoint ({what}); delete it, or run without --resume")]
    NotACheckpoint { path: PathBuf, what: String },
    #[error("{path} was written by splatter {program} in checkpoint format {found}; this is splatter {PROGRAM_VERSION} (format {FORMAT_VERSION}), which cannot continue it: run without --resume to start over")]
    Version {
        path: PathBuf,
        found: u32,
        program: String,
    },
    #[error("{path} is a checkpoint of a different scene (scene hash {found:016x}, this run {expected:016x}): the scene file, a file it loads, or --width/--height changed since; run without --resume to start over")]
    SceneMismatch {
        path: PathBuf,
        found: u64,
        expected: u64,
    },
    #[error("{path} was written {found} --deterministic, this run is {expected} it; resume with the same mode, or run without --resume")]
    ModeMismatch {
        path: PathBuf,
        found: &'static str,
        expected: &'static str,
    },
    #[error("{path} is corrupt: {what}; delete it, or run without --resume")]
    Corrupt { path: PathBuf, what: String },
    #[error(transparent)]
    Write(#[from] OutputError),
}

/// A saved simulation state.
#[derive(Clone, Debug, PartialEq)]
pub struct Checkpoint {
    pub scene_hash: u64,
    pub deterministic: bool,
    /// The state is the one frame `frame` shows.
    pub frame: u32,
    pub steps_per_frame: u32,
    /// What the next frame's Δt is chosen from, and the steps so far.
    pub clock: Clock,
    pub x: Vec<Vec3>,
    pub v: Vec<Vec3>,
    pub f: Vec<Mat3>,
    pub c: Vec<Mat3>,
    pub alpha: Vec<f32>,
}

impl Checkpoint {
    /// The dynamic state of `particles` (as read back from the GPU: every value an f32).
    pub fn from_particles(
        particles: &Particles,
        scene_hash: u64,
        deterministic: bool,
        frame: u32,
        steps_per_frame: u32,
        clock: Clock,
    ) -> Checkpoint {
        Checkpoint {
            scene_hash,
            deterministic,
            frame,
            steps_per_frame,
            clock,
            x: particles.x.iter().map(|p| p.as_vec3()).collect(),
            v: particles.v.iter().map(|p| p.as_vec3()).collect(),
            f: particles.f.iter().map(|m| m.as_mat3()).collect(),
            c: particles.c.iter().map(|m| m.as_mat3()).collect(),
            alpha: particles.alpha.iter().map(|a| *a as f32).collect(),
        }
    }

    /// `like` (the scene's particles: masses, volumes, materials) with this state.
    pub fn to_particles(&self, like: &Particles) -> Particles {
        let mut out = like.clone();
        out.x = self.x.iter().map(|p| p.as_dvec3()).collect();
        out.v = self.v.iter().map(|p| p.as_dvec3()).collect();
        out.f = self.f.iter().map(|m| m.as_dmat3()).collect();
        out.c = self.c.iter().map(|m| m.as_dmat3()).collect();
        out.alpha = self.alpha.iter().map(|a| f64::from(*a)).collect();
        out
    }

    pub fn len(&self) -> usize {
        self.x.len()
    }

    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let n = self.len();
        let mut b = Vec::with_capacity(HEADER_BYTES + n * PARTICLE_BYTES + 8);
        b.extend_from_slice(MAGIC);
        b.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        let mut version = [0u8; VERSION_BYTES];
        let v = PROGRAM_VERSION.as_bytes();
        version[..v.len().min(VERSION_BYTES)].copy_from_slice(&v[..v.len().min(VERSION_BYTES)]);
        b.extend_from_slice(&version);
        b.extend_from_slice(&self.scene_hash.to_le_bytes());
        let flags = if self.deterministic {
            FLAG_DETERMINISTIC
        } else {
            0
        };
        b.extend_from_slice(&flags.to_le_bytes());
        b.extend_from_slice(&self.frame.to_le_bytes());
        b.extend_from_slice(&self.steps_per_frame.to_le_bytes());
        b.extend_from_slice(&self.clock.speed.to_le_bytes());
        b.extend_from_slice(&self.clock.steps_done.to_le_bytes());
        b.extend_from_slice(&(n as u64).to_le_bytes());
        for p in 0..n {
            let mut put = |xs: &[f32]| {
                for x in xs {
                    b.extend_from_slice(&x.to_le_bytes());
                }
            };
            put(&self.x[p].to_array());
            put(&self.v[p].to_array());
            put(&self.f[p].to_cols_array());
            put(&self.c[p].to_cols_array());
            put(&[self.alpha[p]]);
        }
        let sum = fnv1a(FNV_OFFSET, &b);
        b.extend_from_slice(&sum.to_le_bytes());
        b
    }

    /// Write to `path` atomically (temporary file, then rename): a crash while saving
    /// leaves the previous checkpoint.
    pub fn save(&self, path: &Path) -> Result<(), CheckpointError> {
        write_atomically(path, &self.to_bytes())?;
        Ok(())
    }

    /// Read `path`, checking magic, format, program version, the count against the file
    /// size (before allocating) and the checksum. Scene and mode are checked by
    /// [`check_matches`](Self::check_matches).
    pub fn load(path: &Path) -> Result<Checkpoint, CheckpointError> {
        let io = |source| CheckpointError::Io {
            path: path.to_owned(),
            source,
        };
        let mut file = std::fs::File::open(path).map_err(io)?;
        let size = file.metadata().map_err(io)?.len();
        let mut header = Vec::with_capacity(HEADER_BYTES);
        (&mut file)
            .take(HEADER_BYTES as u64)
            .read_to_end(&mut header)
            .map_err(io)?;
        Self::check_header(path, &header, size)?;
        let mut bytes = header;
        bytes.reserve_exact((size as usize).saturating_sub(bytes.len()));
        file.read_to_end(&mut bytes).map_err(io)?;
        Self::from_bytes(path, &bytes)
    }

    /// Magic, format version and (when the header is complete) the count against `size`.
    fn check_header(path: &Path, header: &[u8], size: u64) -> Result<(), CheckpointError> {
        let not = |what: &str| CheckpointError::NotACheckpoint {
            path: path.to_owned(),
            what: what.to_owned(),
        };
        if header.len() < 8 || &header[..8] != MAGIC {
            return Err(not("it does not start with SPLTCKPT"));
        }
        if header.len() < 12 + VERSION_BYTES {
            return Err(CheckpointError::Corrupt {
                path: path.to_owned(),
                what: format!("{size} bytes, shorter than the {HEADER_BYTES}-byte header"),
            });
        }
        let format = u32::from_le_bytes(header[8..12].try_into().unwrap());
        let program = String::from_utf8_lossy(&header[12..12 + VERSION_BYTES])
            .trim_end_matches('\0')
            .to_string();
        if format != FORMAT_VERSION || program != PROGRAM_VERSION {
            return Err(CheckpointError::Version {
                path: path.to_owned(),
                found: format,
                program,
            });
        }
        if header.len() < HEADER_BYTES {
            return Err(CheckpointError::Corrupt {
                path: path.to_owned(),
                what: format!("{size} bytes, shorter than the {HEADER_BYTES}-byte header"),
            });
        }
        let n = u64::from_le_bytes(header[HEADER_BYTES - 8..HEADER_BYTES].try_into().unwrap());
        let expected = n
            .checked_mul(PARTICLE_BYTES as u64)
            .and_then(|b| b.checked_add(HEADER_BYTES as u64 + 8));
        if expected != Some(size) {
            return Err(CheckpointError::Corrupt {
                path: path.to_owned(),
                what: format!(
                    "the header claims {n} particles, which need {} bytes, but the file has {size} (truncated?)",
                    expected.map_or("more than 2^64".to_string(), |e| e.to_string())
                ),
            });
        }
        Ok(())
    }

    /// Parse a whole checkpoint file's bytes (`path` names it in errors).
    pub fn from_bytes(path: &Path, bytes: &[u8]) -> Result<Checkpoint, CheckpointError> {
        Self::check_header(path, bytes, bytes.len() as u64)?;
        let body = bytes.len() - 8;
        let stored = u64::from_le_bytes(bytes[body..].try_into().unwrap());
        if fnv1a(FNV_OFFSET, &bytes[..body]) != stored {
            return Err(CheckpointError::Corrupt {
                path: path.to_owned(),
                what: "its checksum does not match its contents".into(),
            });
        }
        let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
        let o = 12 + VERSION_BYTES;
        let scene_hash = u64::from_le_bytes(bytes[o..o + 8].try_into().unwrap());
        let flags = u32_at(o + 8);
        let frame = u32_at(o + 12);
        let steps_per_frame = u32_at(o + 16);
        let u64_at = |o: usize| u64::from_le_bytes(bytes[o..o + 8].try_into().unwrap());
        let clock = Clock {
            speed: f64::from_bits(u64_at(o + 20)),
            steps_done: u64_at(o + 28),
        };
        let n = (body - HEADER_BYTES) / PARTICLE_BYTES;
        let mut cp = Checkpoint {
            scene_hash,
            deterministic: flags & FLAG_DETERMINISTIC != 0,
            frame,
            steps_per_frame,
            clock,
            x: Vec::with_capacity(n),
            v: Vec::with_capacity(n),
            f: Vec::with_capacity(n),
            c: Vec::with_capacity(n),
            alpha: Vec::with_capacity(n),
        };
        for rec in bytes[HEADER_BYTES..body].chunks_exact(PARTICLE_BYTES) {
            let mut w = [0f32; 25];
            for (i, x) in w.iter_mut().enumerate() {
                *x = f32::from_le_bytes(rec[4 * i..4 * i + 4].try_into().unwrap());
            }
            cp.x.push(Vec3::from_slice(&w[0..3]));
            cp.v.push(Vec3::from_slice(&w[3..6]));
            cp.f.push(Mat3::from_cols_slice(&w[6..15]));
            cp.c.push(Mat3::from_cols_slice(&w[15..24]));
            cp.alpha.push(w[24]);
        }
        Ok(cp)
    }

    /// Refuse a checkpoint of another scene, mode, particle count or step count.
    pub fn check_matches(
        &self,
        path: &Path,
        scene_hash: u64,
        deterministic: bool,
        particles: usize,
        steps_per_frame: u32,
    ) -> Result<(), CheckpointError> {
        if self.scene_hash != scene_hash {
            return Err(CheckpointError::SceneMismatch {
                path: path.to_owned(),
                found: self.scene_hash,
                expected: scene_hash,
            });
        }
        if self.deterministic != deterministic {
            let mode = |d: bool| if d { "with" } else { "without" };
            return Err(CheckpointError::ModeMismatch {
                path: path.to_owned(),
                found: mode(self.deterministic),
                expected: mode(deterministic),
            });
        }
        if self.len() != particles || self.steps_per_frame != steps_per_frame {
            return Err(CheckpointError::Corrupt {
                path: path.to_owned(),
                what: format!(
                    "it holds {} particles at {} steps per frame, the scene {particles} at {steps_per_frame}",
                    self.len(),
                    self.steps_per_frame
                ),
            });
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------
// Hashing
// ---------------------------------------------------------------------------------------------

const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
const FNV_PRIME: u64 = 0x0000_0100_0000_01b3;

/// FNV-1a 64 of `bytes`, continuing from `state` (start with the offset basis).
fn fnv1a(mut state: u64, bytes: &[u8]) -> u64 {
    for b in bytes {
        state ^= u64::from(*b);
        state = state.wrapping_mul(FNV_PRIME);
    }
    state
}

/// An incremental FNV-1a 64 hasher (not cryptographic: it tells runs apart, it does not
/// guard against forgery).
#[derive(Clone, Debug)]
pub struct Fnv64(u64);

impl Default for Fnv64 {
    fn default() -> Self {
        Fnv64(FNV_OFFSET)
    }
}

impl Fnv64 {
    pub fn write(&mut self, bytes: &[u8]) -> &mut Self {
        self.0 = fnv1a(self.0, bytes);
        self
    }

    /// A length-prefixed section, so that `("ab", "c")` and `("a", "bc")` differ.
    pub fn section(&mut self, bytes: &[u8]) -> &mut Self {
        self.write(&(bytes.len() as u64).to_le_bytes()).write(bytes)
    }

    pub fn f32s(&mut self, xs: impl IntoIterator<Item = f32>) -> &mut Self {
        for x in xs {
            self.write(&x.to_bits().to_le_bytes());
        }
        self
    }

    pub fn f64s(&mut self, xs: impl IntoIterator<Item = f64>) -> &mut Self {
        for x in xs {
            self.write(&x.to_bits().to_le_bytes());
        }
        self
    }

    pub fn finish(&self) -> u64 {
        self.0
    }
}

fn dvec3s(v: &[DVec3]) -> impl Iterator<Item = f64> + '_ {
    v.iter().flat_map(|p| p.to_array())
}

fn dmat3s(v: &[DMat3]) -> impl Iterator<Item = f64> + '_ {
    v.iter().flat_map(|m| m.to_cols_array())
}

/// The hash of a scene as this run sees it: the scene file's settings (re-serialised, with
/// the output folder left out: where frames go does not change them, but `--width` and
/// `--height` do), every Gaussian built from it (so an edited PLY it loads changes the
/// hash), and the simulation setup (particles, grid, materials, step parameters).
pub fn scene_hash(scene: &Scene, splats: &Splats, setup: Option<&SimulationSetup>) -> u64 {
    let mut h = Fnv64::default();
    let mut spec = scene.clone();
    spec.output.dir = None;
    h.section(
        serde_json::to_string(&spec)
            .unwrap_or_else(|e| format!("unserialisable scene: {e}"))
            .as_bytes(),
    );
    hash_splats(&mut h, splats);
    if let Some(s) = setup {
        h.section(b"simulation");
        hash_splats(&mut h, &s.splats);
        h.write(&(s.static_count as u64).to_le_bytes());
        for (p, d) in s.binding.particle.iter().zip(&s.binding.offset) {
            h.write(&p.to_le_bytes());
            h.f64s(d.to_array().map(f64::from));
        }
        let p = &s.particles;
        h.write(&(p.len() as u64).to_le_bytes());
        h.f64s(dvec3s(&p.x)).f64s(dvec3s(&p.v));
        h.f64s(dmat3s(&p.f)).f64s(dmat3s(&p.c));
        h.f64s(p.alpha.iter().copied())
            .f64s(p.mass.iter().copied())
            .f64s(p.volume0.iter().copied());
        for m in &p.material {
            h.write(&m.to_le_bytes());
        }
        h.f64s(s.grid.lo.to_array()).f64s([s.grid.dx]);
        for c in s.grid.cells.to_array() {
            h.write(&c.to_le_bytes());
        }
        // Debug output of f64 is exact (shortest round-trip), so it pins every value.
        h.section(format!("{:?}", s.materials).as_bytes());
        h.section(format!("{:?}", s.params).as_bytes());
        h.write(&s.steps_per_frame.to_le_bytes());
        h.section(format!("{:?}", s.step_rule).as_bytes());
    }
    h.finish()
}

fn hash_splats(h: &mut Fnv64, s: &Splats) {
    h.write(&(s.len() as u64).to_le_bytes());
    h.f32s(s.means.iter().flat_map(|m| m.to_array()));
    h.f32s(s.covariances.iter().flat_map(|c| *c));
    h.f32s(s.rotations.iter().flat_map(|q| q.to_array()));
    h.f32s(s.opacities.iter().copied());
    h.write(&s.sh_degree.to_le_bytes());
    h.f32s(s.sh.iter().copied());
}

#[cfg(test)]
mod tests;
