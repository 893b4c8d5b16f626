//! `splatter convert IN OUT`: any format we read into any format we write, the output's
//! format told by its extension (docs/formats.md). A capture keeps its frame: PLY, SPZ and
//! `.splat` as stored, a GLB turned into glTF's frame as splat-transform turns it.

use std::fmt;
use std::path::Path;

use super::formats::{read_splats, write_splats, ReadReport, SourceFrame, SplatError, WriteFormat};
use super::spz::SpzVersion;

/// What a conversion read, wrote, and lost on the way.
#[derive(Clone, Debug)]
pub struct Converted {
    pub read: ReadReport,
    pub written: WriteFormat,
    pub gaussians: usize,
    pub sh_degree: u32,
    pub bytes: u64,
    /// What the output format cannot hold, one phrase each.
    pub dropped: Vec<String>,
}

/// The extensions we write, for messages.
pub const WRITTEN_EXTENSIONS: &str =
    ".ply (3DGS PLY), .spz (SPZ), .splat (antimatter15) or .glb (glTF with KHR_gaussian_splatting)";

/// The format `path`'s extension asks for, or why none.
pub fn output_format(path: &Path, spz: SpzVersion) -> Result<WriteFormat, String> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    let ext = name.rsplit_once('.').map_or("", |(_, e)| e);
    let refuse = |why: &str| {
        Err(format!(
            "{}: {why}; the output's extension picks the format: {WRITTEN_EXTENSIONS}",
            path.display()
        ))
    };
    match ext {
        _ if name.ends_with(".compressed.ply") => refuse(
            "compressed PLY is read, not written (other tools take the name for that format)",
        ),
        "ply" => Ok(WriteFormat::Ply),
        "spz" => Ok(WriteFormat::Spz(spz)),
        "splat" => Ok(WriteFormat::Splat),
        "glb" => Ok(WriteFormat::Glb(SourceFrame::Capture)),
        "gltf" => refuse("glTF is written as binary .glb only"),
        "sog" => refuse("SOG is read, not written"),
        "" => refuse("no extension"),
        other => refuse(&format!("extension .{other} is not a format we write")),
    }
}

/// Read `input` (any format) and write it to `output` (atomically).
pub fn convert(input: &Path, output: &Path, spz: SpzVersion) -> Result<Converted, ConvertError> {
    let written = output_format(output, spz).map_err(ConvertError::Output)?;
    let (cloud, read) = read_splats(input)?;
    write_splats(output, &cloud, written)?;
    let bytes = std::fs::metadata(output).map_or(0, |m| m.len());
    let mut dropped = Vec::new();
    if written == WriteFormat::Splat && cloud.sh_degree > 0 {
        dropped.push(format!(
            "SH degrees 1..={} (.splat holds degree 0)",
            cloud.sh_degree
        ));
    }
    if written == WriteFormat::Splat && !cloud.labels.is_empty() {
        dropped.push("region labels (.splat has no place for them)".into());
    }
    let normals = cloud.normals.iter().any(|n| *n != glam::Vec3::ZERO);
    if normals && written != WriteFormat::Ply {
        dropped.push("normals (only PLY keeps them)".into());
    }
    Ok(Converted {
        read,
        written,
        gaussians: cloud.len(),
        sh_degree: cloud.sh_degree,
        bytes,
        dropped,
    })
}

/// A conversion failed: the output's name, or reading or writing a file.
#[derive(Debug, thiserror::Error)]
pub enum ConvertError {
    #[error("{0}")]
    Output(String),
    #[error(transparent)]
    Splat(#[from] SplatError),
}

fn format_name(f: WriteFormat) -> String {
    match f {
        WriteFormat::Ply => "3DGS PLY binary_little_endian".into(),
        WriteFormat::Spz(SpzVersion::V3) => "SPZ version 3".into(),
        WriteFormat::Spz(SpzVersion::V4) => "SPZ version 4".into(),
        WriteFormat::Splat => ".splat".into(),
        WriteFormat::Glb(_) => "glTF GLB".into(),
    }
}

impl fmt::Display for Converted {
    /// `4148 Gaussians (SH degree 0): 3DGS PLY binary_little_endian → glTF GLB, 250556 bytes`,
    /// then what was skipped and dropped.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = &self.read;
        let variant = if r.variant.is_empty() {
            String::new()
        } else {
            format!(" {}", r.variant)
        };
        write!(
            f,
            "{} Gaussians (SH degree {}): {}{variant} → {}, {} bytes",
            self.gaussians,
            self.sh_degree,
            r.format,
            format_name(self.written),
            self.bytes
        )?;
        let skipped = r.skipped_nonfinite + r.skipped_degenerate;
        if skipped > 0 {
            write!(
                f,
                "; {skipped} of {} left out ({} with NaN/Inf values, {} with a degenerate scale or rotation)",
                r.in_file, r.skipped_nonfinite, r.skipped_degenerate
            )?;
        }
        if !self.dropped.is_empty() {
            write!(f, "; dropped: {}", self.dropped.join(", "))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_extension_picks_the_format() {
        let v = SpzVersion::V3;
        assert_eq!(output_format(Path::new("a/b.PLY"), v), Ok(WriteFormat::Ply));
        assert_eq!(
            output_format(Path::new("b.spz"), v),
            Ok(WriteFormat::Spz(v))
        );
        assert_eq!(
            output_format(Path::new("b.splat"), v),
            Ok(WriteFormat::Splat)
        );
        assert_eq!(
            output_format(Path::new("b.glb"), v),
            Ok(WriteFormat::Glb(SourceFrame::Capture))
        );
        for (name, why) in [
            ("b.compressed.ply", "compressed PLY"),
            ("b.gltf", ".glb only"),
            ("b.sog", "SOG"),
            ("b", "no extension"),
            ("b.obj", ".obj"),
        ] {
            let e = output_format(Path::new(name), v).unwrap_err();
            assert!(
                e.contains(name) && e.contains(why) && e.contains(".glb"),
                "{e}"
            );
        }
    }
}
