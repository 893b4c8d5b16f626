//! What the compact splat formats share: the activations, the DC colour constant, the
//! quantisers and a builder that turns decoded values into a [`GaussianCloud`] with the
//! same rules for broken Gaussians as the PLY reader (docs/formats.md).

use std::fmt;

use glam::{Quat, Vec3};

use super::ply::PlyError;
use super::{sh_coeff_count, GaussianCloud};

/// A splat file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// graphdeco / INRIA 3DGS PLY (nerfstudio, Brush, Mip-Splatting write it too).
    Ply,
    /// SuperSplat / PlayCanvas `compressed.ply`.
    CompressedPly,
    /// antimatter15 `.splat`.
    Splat,
    /// Niantic SPZ.
    Spz,
    /// PlayCanvas SOG (`meta.json` + WebP images, or a `.sog` zip).
    Sog,
    /// glTF 2.0 (`.glb`, or `.gltf` JSON) with `KHR_gaussian_splatting`.
    Gltf,
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Format::Ply => "3DGS PLY",
            Format::CompressedPly => "compressed PLY",
            Format::Splat => ".splat",
            Format::Spz => "SPZ",
            Format::Sog => "SOG",
            Format::Gltf => "glTF",
        })
    }
}

/// Reading or writing a splat file failed. Every message starts with the file name, and
/// names the format the file looks like.
#[derive(Debug, thiserror::Error)]
pub enum SplatError {
    #[error("{file}: cannot {action}: {source}")]
    Io {
        file: String,
        action: &'static str,
        #[source]
        source: std::io::Error,
    },
    #[error(transparent)]
    Ply(#[from] PlyError),
    #[error("{file}: damaged {format} file: {what}")]
    Damaged {
        file: String,
        format: Format,
        what: String,
    },
    #[error("{file}: {format} {what} is not supported (expected {expected})")]
    Unsupported {
        file: String,
        format: Format,
        what: String,
        expected: &'static str,
    },
    #[error("{file}: not a splat file this program reads: {what} (expected a 3DGS PLY, a compressed.ply, an SPZ, a SOG folder or .sog, a .splat, or a glTF/GLB with KHR_gaussian_splatting)")]
    Unknown { file: String, what: String },
}

/// An up axis that a format defines rather than leaves to a guess (glTF is +y up), named
/// in the frame the reader hands the cloud over in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DeclaredUp {
    /// A signed axis: `"-y"`.
    pub axis: &'static str,
    /// Where it comes from, in words.
    pub source: &'static str,
}

/// The degree-0 real spherical harmonic, Y₀₀ = 1/(2√π): display colour = 0.5 + C0 · DC.
pub const SH_C0: f32 = 0.282_094_8;

pub fn sigmoid(x: f32) -> f32 {
    1.0 / (1.0 + (-x).exp())
}

/// The inverse of [`sigmoid`], ±inf at 0 and 1.
pub fn logit(p: f32) -> f32 {
    (p / (1.0 - p)).ln()
}

/// `round(x)` clamped to a byte.
pub fn to_u8(x: f32) -> u8 {
    x.round().clamp(0.0, 255.0) as u8
}

/// A unit quaternion with components in the order `[w, x, y, z]`, or None when its norm is
/// zero or not finite.
pub fn unit_wxyz(q: [f32; 4]) -> Option<Quat> {
    let n = q.iter().map(|c| c * c).sum::<f32>().sqrt();
    (n > 0.0 && n.is_finite()).then(|| Quat::from_xyzw(q[1] / n, q[2] / n, q[3] / n, q[0] / n))
}

/// Decoded Gaussians, collected in the cloud's activated form. A Gaussian with a
/// non-finite value (other than an infinite opacity logit) or a degenerate scale or
/// rotation is counted and left out, as by the PLY reader.
pub struct Builder {
    pub cloud: GaussianCloud,
    pub skipped_nonfinite: usize,
    pub skipped_degenerate: usize,
}

/// One decoded Gaussian: scale as natural logs, the quaternion as `[w, x, y, z]` (any
/// norm), opacity in [0, 1], SH coefficient-major (`[k * 3 + c]`, k = 0 the DC term).
pub struct Decoded<'a> {
    pub position: [f32; 3],
    pub log_scale: [f32; 3],
    pub rotation: [f32; 4],
    pub opacity: f32,
    pub sh: &'a [f32],
}

impl Builder {
    pub fn new(capacity: usize, sh_degree: u32) -> Builder {
        let k = sh_coeff_count(sh_degree);
        Builder {
            cloud: GaussianCloud {
                positions: Vec::with_capacity(capacity),
                scales: Vec::with_capacity(capacity),
                rotations: Vec::with_capacity(capacity),
                opacities: Vec::with_capacity(capacity),
                sh_degree,
                sh: Vec::with_capacity(capacity * 3 * k),
                ..Default::default()
            },
            skipped_nonfinite: 0,
            skipped_degenerate: 0,
        }
    }

    pub fn push(&mut self, g: Decoded<'_>) {
        self.push_scaled(g, |log| log.map(f32::exp));
    }

    /// [`Builder::push`] for a format that stores scales linear (glTF): `g.log_scale` holds
    /// them as stored, and they are kept bit for bit (no exp/ln round trip).
    pub fn push_linear(&mut self, g: Decoded<'_>) {
        self.push_scaled(g, |linear| linear);
    }

    fn push_scaled(&mut self, g: Decoded<'_>, to_linear: impl Fn([f32; 3]) -> [f32; 3]) {
        let finite = g.position.iter().all(|v| v.is_finite())
            && g.log_scale.iter().all(|v| v.is_finite())
            && g.rotation.iter().all(|v| v.is_finite())
            && !g.opacity.is_nan()
            && g.sh.iter().all(|v| v.is_finite());
        if !finite {
            self.skipped_nonfinite += 1;
            return;
        }
        let scale = Vec3::from_array(to_linear(g.log_scale));
        let Some(rotation) = unit_wxyz(g.rotation) else {
            self.skipped_degenerate += 1;
            return;
        };
        if !(scale.is_finite() && scale.min_element() > 0.0) {
            self.skipped_degenerate += 1;
            return;
        }
        let c = &mut self.cloud;
        c.positions.push(Vec3::from_array(g.position));
        c.scales.push(scale);
        c.rotations.push(rotation);
        c.opacities.push(g.opacity.clamp(0.0, 1.0));
        c.sh.extend_from_slice(g.sh);
    }

    /// Append the Gaussians another builder decoded (for chunks decoded in parallel).
    pub fn append(&mut self, other: Builder) {
        let (c, o) = (&mut self.cloud, other.cloud);
        c.positions.extend(o.positions);
        c.scales.extend(o.scales);
        c.rotations.extend(o.rotations);
        c.opacities.extend(o.opacities);
        c.sh.extend(o.sh);
        self.skipped_nonfinite += other.skipped_nonfinite;
        self.skipped_degenerate += other.skipped_degenerate;
    }
}

/// Decode `n` Gaussians in parallel chunks: `decode(builder, i)` pushes Gaussian i.
pub fn decode_parallel(
    n: usize,
    sh_degree: u32,
    decode: impl Fn(&mut Builder, usize) + Sync,
) -> Builder {
    use rayon::prelude::*;
    const CHUNK: usize = 16_384;
    let parts: Vec<Builder> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|ci| {
            let range = ci * CHUNK..((ci + 1) * CHUNK).min(n);
            let mut b = Builder::new(range.len(), sh_degree);
            for i in range {
                decode(&mut b, i);
            }
            b
        })
        .collect();
    let mut all = Builder::new(n, sh_degree);
    for p in parts {
        all.append(p);
    }
    all
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn broken_gaussians_are_counted_not_kept() {
        let mut b = Builder::new(4, 0);
        let ok = Decoded {
            position: [1.0, 2.0, 3.0],
            log_scale: [0.0; 3],
            rotation: [2.0, 0.0, 0.0, 0.0],
            opacity: 1.0,
            sh: &[0.1, 0.2, 0.3],
        };
        b.push(ok);
        b.push(Decoded {
            position: [f32::NAN, 0.0, 0.0],
            log_scale: [0.0; 3],
            rotation: [1.0, 0.0, 0.0, 0.0],
            opacity: 0.5,
            sh: &[0.0; 3],
        });
        b.push(Decoded {
            position: [0.0; 3],
            log_scale: [0.0; 3],
            rotation: [0.0; 4],
            opacity: 0.5,
            sh: &[0.0; 3],
        });
        assert_eq!(b.cloud.len(), 1);
        assert_eq!(b.cloud.rotations[0], Quat::IDENTITY);
        assert_eq!((b.skipped_nonfinite, b.skipped_degenerate), (1, 1));
        assert_eq!(logit(sigmoid(0.3)), logit(sigmoid(0.3)));
        assert!((logit(sigmoid(0.3)) - 0.3).abs() < 1e-5);
        assert_eq!(logit(1.0), f32::INFINITY);
    }
}
