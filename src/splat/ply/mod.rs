//! 3DGS PLY files: read (binary little-endian and ASCII) and write (docs/method.md §5).
//!
//! The standard 3DGS layout is one element `vertex` with the float properties
//! `x y z`, optional `nx ny nz`, `f_dc_0..2`, `f_rest_0..(3·((d+1)²−1)−1)`, `opacity`,
//! `scale_0..2` and `rot_0..3`. Properties are found by name in any order; extra
//! properties and extra elements are ignored, and any numeric property type is accepted.
//!
//! * `f_rest_*` is **channel-major** in the file (all red rest coefficients, then green, then
//!   blue); [`GaussianCloud::sh`] is coefficient-major, so the reader and writer convert.
//! * `opacity` is a logit (the reader applies a sigmoid), `scale_*` are logs (the reader
//!   applies exp), `rot_*` is a quaternion `w x y z` (the reader normalises it).
//! * An opacity logit of +inf or −inf means fully opaque or fully transparent and is kept.
//! * A Gaussian with any other non-finite value (or a NaN opacity) is skipped and counted
//!   ([`PlyReport::skipped_nonfinite`]); so is one whose scale is ≤ 0 or non-finite after
//!   exp, or whose quaternion has zero norm ([`PlyReport::skipped_degenerate`]).
//! * Normals that are all exactly zero (as the 3DGS reference implementation writes them)
//!   carry no information and are dropped: the cloud then has no normals.
//!
//! The header is parsed with `ply-rs-bw`. Binary little-endian bodies are decoded directly
//! from the byte slice with per-property offsets, in parallel. ASCII bodies are tokenised
//! here (also in parallel) rather than with `ply-rs-bw`'s line grammar, which rejects the
//! `nan`/`inf` tokens and the `.5`/`1.` number forms other writers produce. Binary
//! big-endian is refused with a clear error. The body size is checked against the header's
//! counts before anything is allocated, so a header claiming 10¹² vertices is refused with
//! a message, not an allocation.

use std::path::Path;

use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{DefaultElement, ElementDef, Encoding};

use super::GaussianCloud;

mod body;
mod decode;
mod write;

use body::{read_ascii_body, read_binary_body};
use decode::{name_labels, Layout};
pub use write::{write_ply, write_ply_bytes};

/// Bytes of one value of a PLY scalar type (for readers of other PLY layouts).
pub(crate) fn scalar_size(t: &ply_rs_bw::ply::ScalarType) -> usize {
    decode::Scalar::of(t).size()
}

/// Body encoding of a PLY file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlyFormat {
    BinaryLittleEndian,
    Ascii,
}

/// What [`read_ply`] found besides the Gaussians.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlyReport {
    pub format: PlyFormat,
    /// Vertices the header declares (all of them are present, or reading fails).
    pub vertices_in_file: usize,
    /// Gaussians skipped because one of their values is NaN or infinite.
    pub skipped_nonfinite: usize,
    /// Gaussians skipped because their scale is ≤ 0 or non-finite after exp, or their
    /// quaternion has zero norm.
    pub skipped_degenerate: usize,
}

/// Reading or writing a PLY file failed. Every message starts with the file name.
#[derive(Debug, thiserror::Error)]
pub enum PlyError {
    #[error("{file}: cannot {action}: {source}")]
    Io {
        file: String,
        action: &'static str,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}: invalid PLY header: {message} (expected `ply`, a `format` line, `element`/`property` lines and `end_header`)")]
    Header { file: String, message: String },
    #[error("{file}: {what} is not supported (expected {expected})")]
    Unsupported {
        file: String,
        what: String,
        expected: &'static str,
    },
    #[error("{file}: element `vertex` lacks the properties {} (expected the 3DGS properties x y z f_dc_0..2 f_rest_* opacity scale_0..2 rot_0..3)", .missing.join(", "))]
    MissingProperties { file: String, missing: Vec<String> },
    #[error("{file}: element `vertex` has {count} f_rest_* properties (expected 0, 9, 24 or 45, i.e. SH degree 0, 1, 2 or 3)")]
    ShRestCount { file: String, count: usize },
    #[error("{file}: truncated: only {found} of the {declared} `{element}` entries the header declares are present ({detail})")]
    Truncated {
        file: String,
        element: String,
        declared: usize,
        found: u64,
        detail: String,
    },
    #[error("{file}: {what} (expected {expected})")]
    Invalid {
        file: String,
        what: String,
        expected: String,
    },
}

/// Read a 3DGS PLY file (binary little-endian or ASCII).
pub fn read_ply(path: &Path) -> Result<(GaussianCloud, PlyReport), PlyError> {
    let name = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|source| PlyError::Io {
        file: name.clone(),
        action: "read the PLY file",
        source,
    })?;
    read_ply_bytes(&bytes, &name)
}

/// Read a 3DGS PLY file from memory; `name` is used in error messages.
pub fn read_ply_bytes(bytes: &[u8], name: &str) -> Result<(GaussianCloud, PlyReport), PlyError> {
    read_ply_bytes_labelled(bytes, name, None)
}

/// As [`read_ply_bytes`], the region labels from the scalar vertex property `labels` when
/// given (else `label` or `segment`, where the file has one).
pub fn read_ply_bytes_labelled(
    bytes: &[u8],
    name: &str,
    labels: Option<&str>,
) -> Result<(GaussianCloud, PlyReport), PlyError> {
    let file = name;
    let (header, body_start) = parse_header(bytes, file)?;
    let body = &bytes[body_start..];

    let format = match header.encoding {
        Encoding::BinaryLittleEndian => PlyFormat::BinaryLittleEndian,
        Encoding::Ascii => PlyFormat::Ascii,
        Encoding::BinaryBigEndian => {
            return Err(PlyError::Unsupported {
                file: file.to_string(),
                what: "the binary_big_endian encoding".to_string(),
                expected: "binary_little_endian or ascii",
            })
        }
    };
    let Some(vertex_index) = header.elements.get_index_of("vertex") else {
        return Err(PlyError::Invalid {
            file: file.to_string(),
            what: "no element `vertex` in the header".to_string(),
            expected: "a 3DGS PLY with an element `vertex`".to_string(),
        });
    };
    let elements: Vec<&ElementDef> = header.elements.values().collect();
    let vdef = elements[vertex_index];
    let layout = Layout::new(vdef, file, labels)?;

    let (mut cloud, skipped_nonfinite, skipped_degenerate) = match format {
        PlyFormat::BinaryLittleEndian => {
            read_binary_body(body, &elements[..vertex_index], vdef, &layout, file)?
        }
        PlyFormat::Ascii => read_ascii_body(
            body,
            &elements[..vertex_index],
            vdef,
            &layout,
            file,
            header_line_count(&bytes[..body_start]),
        )?,
    };
    if !cloud.labels.is_empty() {
        name_labels(&mut cloud, &header.comments);
    }
    let report = PlyReport {
        format,
        vertices_in_file: vdef.count,
        skipped_nonfinite,
        skipped_degenerate,
    };
    Ok((cloud, report))
}

// ---------------------------------------------------------------------------------------
// Header

pub(crate) fn parse_header(
    bytes: &[u8],
    file: &str,
) -> Result<(ply_rs_bw::ply::Header, usize), PlyError> {
    let mut rest = bytes;
    let header = {
        let mut reader = Reader::new(&mut rest);
        Parser::<DefaultElement>::new()
            .read_header(&mut reader)
            .map_err(|e| PlyError::Header {
                file: file.to_string(),
                message: one_line(&e.to_string()),
            })?
    };
    let body_start = bytes.len() - rest.len();

    // `ply-rs-bw` keeps elements and properties in maps, so a repeated name would silently
    // drop a declaration and shift every byte offset after it. Count the lines ourselves.
    let text = String::from_utf8_lossy(&bytes[..body_start]);
    let first_word = |l: &str| l.split_whitespace().next().map(str::to_string);
    let element_lines = text
        .lines()
        .filter(|l| first_word(l).as_deref() == Some("element"))
        .count();
    let property_lines = text
        .lines()
        .filter(|l| first_word(l).as_deref() == Some("property"))
        .count();
    let declared_properties: usize = header.elements.values().map(|e| e.properties.len()).sum();
    if element_lines != header.elements.len() || property_lines != declared_properties {
        return Err(PlyError::Header {
            file: file.to_string(),
            message: "an element or property name is declared twice".to_string(),
        });
    }
    Ok((header, body_start))
}

/// `ply-rs-bw`'s messages span several lines (with a parser dump); keep the first line and
/// the offending text.
fn one_line(message: &str) -> String {
    let mut lines = message.lines();
    let mut out = lines.next().unwrap_or_default().trim().to_string();
    if let Some(text) = lines.find_map(|l| l.trim_start().strip_prefix("String:")) {
        let text: String = text.trim().trim_matches('\'').chars().take(80).collect();
        out.push_str(&format!(" `{text}`"));
    }
    out
}

fn header_line_count(header: &[u8]) -> usize {
    header.iter().filter(|&&b| b == b'\n').count()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Quat, Vec3};

    fn header(props: &[&str], n: usize, format: &str) -> String {
        let mut h = format!("ply\nformat {format} 1.0\nelement vertex {n}\n");
        for p in props {
            h.push_str(&format!("property float {p}\n"));
        }
        h.push_str("end_header\n");
        h
    }

    const BASIC: [&str; 14] = [
        "x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1", "scale_2",
        "rot_0", "rot_1", "rot_2", "rot_3",
    ];

    #[test]
    fn activations_are_applied() {
        let mut s = header(&BASIC, 1, "ascii");
        s.push_str("1 2 3 0.1 0.2 0.3 0 0 -1 1 2 0 0 0\n");
        let (c, r) = read_ply_bytes(s.as_bytes(), "t.ply").unwrap();
        assert_eq!(r.format, PlyFormat::Ascii);
        assert_eq!(c.positions, vec![Vec3::new(1.0, 2.0, 3.0)]);
        assert!((c.opacities[0] - 0.5).abs() < 1e-7);
        assert!(
            (c.scales[0] - Vec3::new(1.0, (-1f32).exp(), 1f32.exp()))
                .abs()
                .max_element()
                < 1e-6
        );
        assert_eq!(c.rotations[0], Quat::IDENTITY);
        assert_eq!(c.sh, vec![0.1, 0.2, 0.3]);
        assert!(c.normals.is_empty());
    }

    #[test]
    fn infinite_opacity_logits_are_fully_opaque_or_transparent() {
        let mut s = header(&BASIC, 4, "ascii");
        s.push_str("0 0 0 0 0 0 inf 0 0 0 1 0 0 0\n");
        s.push_str("1 0 0 0 0 0 -inf 0 0 0 1 0 0 0\n");
        s.push_str("2 0 0 0 0 0 nan 0 0 0 1 0 0 0\n");
        s.push_str("3 0 0 0 0 0 0 inf 0 0 1 0 0 0\n");
        let (c, r) = read_ply_bytes(s.as_bytes(), "t.ply").unwrap();
        assert_eq!(c.opacities, vec![1.0, 0.0]);
        assert_eq!(c.positions[1], Vec3::X);
        // A NaN opacity and an infinite log-scale are still broken.
        assert_eq!(r.skipped_nonfinite, 2);
    }

    #[test]
    fn list_properties_and_leading_elements_are_skipped() {
        let mut h = String::from("ply\nformat binary_little_endian 1.0\nelement meta 2\nproperty list uchar int ids\nproperty short tag\n");
        h.push_str("element vertex 1\n");
        for p in BASIC {
            h.push_str(&format!("property float {p}\n"));
        }
        h.push_str("end_header\n");
        let mut b = h.into_bytes();
        // meta 0: 2 ids, tag; meta 1: 0 ids, tag
        b.push(2);
        b.extend_from_slice(&7i32.to_le_bytes());
        b.extend_from_slice(&8i32.to_le_bytes());
        b.extend_from_slice(&1i16.to_le_bytes());
        b.push(0);
        b.extend_from_slice(&2i16.to_le_bytes());
        for v in [
            1.0f32, 2.0, 3.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0,
        ] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        let (c, _) = read_ply_bytes(&b, "t.ply").unwrap();
        assert_eq!(c.positions, vec![Vec3::new(1.0, 2.0, 3.0)]);
    }

    #[test]
    fn duplicate_property_is_refused() {
        let mut props = BASIC.to_vec();
        props.push("x");
        let s = header(&props, 0, "ascii");
        let e = read_ply_bytes(s.as_bytes(), "dup.ply")
            .unwrap_err()
            .to_string();
        assert!(e.contains("declared twice"), "{e}");
    }

    #[test]
    fn garbage_never_panics() {
        let mut s = header(&BASIC, 3, "binary_little_endian").into_bytes();
        let mut x = 0x1234_5678_9abc_def0u64;
        for len in 0..200 {
            let mut b = s.clone();
            for _ in 0..len {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                b.push(x as u8);
            }
            let _ = read_ply_bytes(&b, "g.ply");
            // Corrupt the header too.
            if len < s.len() {
                b[len] ^= 0x5a;
                let _ = read_ply_bytes(&b, "g.ply");
            }
        }
        s.truncate(10);
        assert!(read_ply_bytes(&s, "g.ply").is_err());
        assert!(read_ply_bytes(b"", "g.ply").is_err());
    }
}
