//! One entry point for every splat format users exchange (docs/formats.md): the format is
//! told by the content (magic bytes, the PLY header, a glTF's JSON), with the extension
//! only for the one format that has no signature (antimatter15 `.splat`).

use std::path::Path;

use super::codec::Builder;
use super::ply::PlyFormat;
use super::spz::SpzVersion;
use super::{antimatter, compressed_ply, gltf, ply, sog, spz, GaussianCloud};

pub use super::codec::{DeclaredUp, Format, SplatError};
pub use super::gltf::SourceFrame;

/// What [`read_splats`] found besides the Gaussians.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReadReport {
    pub format: Format,
    /// The format's variant: `binary_little_endian`, `version 3`, …
    pub variant: String,
    /// Gaussians the file holds.
    pub in_file: usize,
    /// Gaussians skipped because one of their values is NaN or infinite (an infinite
    /// opacity logit is not broken: it means fully opaque or transparent).
    pub skipped_nonfinite: usize,
    /// Gaussians skipped for a scale ≤ 0 or a zero quaternion.
    pub skipped_degenerate: usize,
    /// The up axis the format defines (glTF's), where it defines one.
    pub up: Option<DeclaredUp>,
}

/// Tell the format of a file from its first bytes (and, for `.splat`, its name).
pub fn detect(path: &Path, head: &[u8]) -> Option<Format> {
    if head.starts_with(b"ply\n") || head.starts_with(b"ply\r\n") {
        let text = String::from_utf8_lossy(&head[..head.len().min(1 << 16)]);
        let header = text.split("end_header").next().unwrap_or_default();
        let compressed = header
            .lines()
            .any(|l| l.split_whitespace().take(2).eq(["element", "chunk"]))
            && header.contains("packed_position");
        return Some(if compressed {
            Format::CompressedPly
        } else {
            Format::Ply
        });
    }
    if head.starts_with(&[0x1f, 0x8b]) || head.starts_with(&spz::MAGIC.to_le_bytes()) {
        return Some(Format::Spz);
    }
    if head.starts_with(b"PK\x03\x04") {
        return Some(Format::Sog);
    }
    if head.first() == Some(&b'{') && path.file_name().is_some_and(|n| n == "meta.json") {
        return Some(Format::Sog);
    }
    if head.starts_with(gltf::GLB_MAGIC) || looks_like_gltf_json(head) {
        return Some(Format::Gltf);
    }
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or_default();
    ext.eq_ignore_ascii_case("splat").then_some(Format::Splat)
}

/// A JSON object whose first kilobytes name glTF's `asset` (every glTF has one; a SOG's
/// `meta.json` has none).
fn looks_like_gltf_json(head: &[u8]) -> bool {
    let text = String::from_utf8_lossy(&head[..head.len().min(1 << 16)]);
    let text = text.trim_start_matches('\u{feff}').trim_start();
    text.starts_with('{') && text.contains("\"asset\"")
}

/// Read a splat file of any supported format (a SOG folder may be given as the folder).
pub fn read_splats(path: &Path) -> Result<(GaussianCloud, ReadReport), SplatError> {
    read_splats_labelled(path, None)
}

/// As [`read_splats`], a PLY's region labels from its scalar vertex property `labels`
/// when given (only a PLY has such properties: any other format is then an error).
pub fn read_splats_labelled(
    path: &Path,
    labels: Option<&str>,
) -> Result<(GaussianCloud, ReadReport), SplatError> {
    let file = path.display().to_string();
    if path.is_dir() {
        let meta = path.join("meta.json");
        if !meta.is_file() {
            return Err(SplatError::Unknown {
                file,
                what: "a folder without meta.json".into(),
            });
        }
        return finish(
            sog::read(sog::Source::Folder(path), &file)?,
            Format::Sog,
            "folder".into(),
        );
    }
    let bytes = std::fs::read(path).map_err(|source| SplatError::Io {
        file: file.clone(),
        action: "read the splat file",
        source,
    })?;
    read_splats_bytes_labelled(&bytes, path, labels)
}

/// Read a splat file from memory; `path` names it in messages (and locates a SOG
/// folder's images when it is a `meta.json`).
pub fn read_splats_bytes(
    bytes: &[u8],
    path: &Path,
) -> Result<(GaussianCloud, ReadReport), SplatError> {
    read_splats_bytes_labelled(bytes, path, None)
}

/// As [`read_splats_bytes`], with a PLY's labels from `labels` ([`read_splats_labelled`]).
pub fn read_splats_bytes_labelled(
    bytes: &[u8],
    path: &Path,
    labels: Option<&str>,
) -> Result<(GaussianCloud, ReadReport), SplatError> {
    let file = path.display().to_string();
    let Some(format) = detect(path, bytes) else {
        return Err(SplatError::Unknown {
            file,
            what: describe_start(bytes),
        });
    };
    if let Some(name) = labels.filter(|_| format != Format::Ply) {
        return Err(SplatError::Unsupported {
            file,
            format,
            what: format!("file's labels from a property `{name}`"),
            expected: "a PLY file: only PLY carries per-Gaussian properties of any name",
        });
    }
    match format {
        Format::Ply => {
            let (cloud, r) = ply::read_ply_bytes_labelled(bytes, &file, labels)?;
            let variant = match r.format {
                PlyFormat::BinaryLittleEndian => "binary_little_endian",
                PlyFormat::Ascii => "ascii",
            };
            Ok((
                cloud,
                ReadReport {
                    format,
                    variant: variant.into(),
                    in_file: r.vertices_in_file,
                    skipped_nonfinite: r.skipped_nonfinite,
                    skipped_degenerate: r.skipped_degenerate,
                    up: None,
                },
            ))
        }
        Format::CompressedPly => {
            let (header, body) = ply::parse_header(bytes, &file)?;
            let b = compressed_ply::read(bytes, &header, body, &file)?;
            finish(b, format, "binary_little_endian".into())
        }
        Format::Splat => finish(antimatter::read(bytes, &file)?, format, String::new()),
        Format::Spz => {
            let (b, version) = spz::read(bytes, &file)?;
            finish(b, format, format!("version {version}"))
        }
        Format::Gltf => {
            let (b, variant) = gltf::read(bytes, path, &file)?;
            let (cloud, mut report) = finish(b, format, variant)?;
            report.up = Some(gltf::DECLARED_UP);
            Ok((cloud, report))
        }
        Format::Sog => {
            if bytes.starts_with(b"PK") {
                finish(
                    sog::read(sog::Source::Zip(bytes), &file)?,
                    format,
                    "bundle".into(),
                )
            } else {
                let dir = path
                    .parent()
                    .filter(|p| !p.as_os_str().is_empty())
                    .unwrap_or(Path::new("."));
                finish(
                    sog::read(sog::Source::Folder(dir), &file)?,
                    format,
                    "folder".into(),
                )
            }
        }
    }
}

fn finish(
    b: Builder,
    format: Format,
    variant: String,
) -> Result<(GaussianCloud, ReadReport), SplatError> {
    let in_file = b.cloud.len() + b.skipped_nonfinite + b.skipped_degenerate;
    Ok((
        b.cloud,
        ReadReport {
            format,
            variant,
            in_file,
            skipped_nonfinite: b.skipped_nonfinite,
            skipped_degenerate: b.skipped_degenerate,
            up: None,
        },
    ))
}

/// What the first bytes of an unrecognised file look like, for the error message.
fn describe_start(bytes: &[u8]) -> String {
    if bytes.is_empty() {
        return "the file is empty".into();
    }
    let head: String = bytes
        .iter()
        .take(8)
        .map(|b| format!("{b:02x}"))
        .collect::<Vec<_>>()
        .join(" ");
    format!("no known signature (it starts with {head}); an antimatter15 .splat has none and must be named *.splat")
}

/// A format we write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WriteFormat {
    Ply,
    Spz(SpzVersion),
    Splat,
    /// GLB with KHR_gaussian_splatting, from a cloud whose axes lie as the frame says.
    Glb(SourceFrame),
}

/// Encode `cloud` in `format`; labels travel in PLY, SPZ and GLB (not in `.splat`).
pub fn write_splats_bytes(
    cloud: &GaussianCloud,
    format: WriteFormat,
    name: &str,
) -> Result<Vec<u8>, SplatError> {
    match format {
        WriteFormat::Ply => Ok(ply::write_ply_bytes(
            cloud,
            PlyFormat::BinaryLittleEndian,
            name,
        )?),
        WriteFormat::Spz(v) => Ok(spz::write(cloud, v)),
        WriteFormat::Splat => Ok(antimatter::write(cloud)),
        WriteFormat::Glb(frame) => gltf::write(cloud, frame, name),
    }
}

/// Write `cloud` to `path` in `format`, atomically (see [`crate::files::write_atomically`]).
pub fn write_splats(
    path: &Path,
    cloud: &GaussianCloud,
    format: WriteFormat,
) -> Result<(), SplatError> {
    let name = path.display().to_string();
    let bytes = write_splats_bytes(cloud, format, &name)?;
    crate::files::write_atomically(path, &bytes).map_err(|source| SplatError::Io {
        file: name,
        action: "write the splat file",
        source,
    })
}
