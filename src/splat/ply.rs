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
//! * A Gaussian with a non-finite value is skipped and counted
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

use std::fmt::Write as _;
use std::path::Path;

use glam::{Quat, Vec3};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{DefaultElement, ElementDef, Encoding, PropertyType, ScalarType};
use rayon::prelude::*;

use super::{sh_coeff_count, GaussianCloud};

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
    let layout = Layout::new(vdef, file)?;

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

/// Write `cloud` as a standard 3DGS PLY file, atomically (a hidden temporary file, then a
/// rename: see [`crate::files::write_atomically`]).
pub fn write_ply(path: &Path, cloud: &GaussianCloud, format: PlyFormat) -> Result<(), PlyError> {
    let name = path.display().to_string();
    let bytes = write_ply_bytes(cloud, format, &name)?;
    crate::files::write_atomically(path, &bytes).map_err(|source| PlyError::Io {
        file: name,
        action: "write the PLY file",
        source,
    })
}

/// Encode `cloud` as a standard 3DGS PLY file in memory; `name` is used in error messages.
///
/// Properties (all `float`): `x y z nx ny nz f_dc_0..2 f_rest_* opacity scale_0..2 rot_0..3`,
/// then `int label` when the cloud has labels (the label id; a header comment
/// `comment label <id> <name>` per name lets the reader restore the names).
/// Normals are zeros when the cloud has none; opacity is written as a logit (clamped to
/// (1e−12, 1 − 1e−12) so that it stays finite), scale as its natural log.
pub fn write_ply_bytes(
    cloud: &GaussianCloud,
    format: PlyFormat,
    name: &str,
) -> Result<Vec<u8>, PlyError> {
    cloud.check_consistent().map_err(|what| PlyError::Invalid {
        file: name.to_string(),
        what: format!("cannot write an inconsistent cloud: {what}"),
        expected: "equal-length arrays".to_string(),
    })?;
    let k = sh_coeff_count(cloud.sh_degree);
    let rest = 3 * (k - 1);
    let mut header = String::from("ply\n");
    header.push_str(match format {
        PlyFormat::BinaryLittleEndian => "format binary_little_endian 1.0\n",
        PlyFormat::Ascii => "format ascii 1.0\n",
    });
    header.push_str("comment written by splatter\n");
    let has_label = !cloud.labels.is_empty();
    if has_label {
        for (id, name) in cloud.label_names.iter().enumerate() {
            // One token: whitespace would split the name when read back.
            let name: String = name
                .chars()
                .map(|c| if c.is_whitespace() { '_' } else { c })
                .collect();
            let _ = writeln!(header, "comment label {id} {name}");
        }
    }
    let _ = writeln!(header, "element vertex {}", cloud.len());
    let mut names: Vec<String> = [
        "x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    names.extend((0..rest).map(|j| format!("f_rest_{j}")));
    names.extend(
        [
            "opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3",
        ]
        .iter()
        .map(|s| s.to_string()),
    );
    for n in &names {
        let _ = writeln!(header, "property float {n}");
    }
    if has_label {
        header.push_str("property int label\n");
    }
    header.push_str("end_header\n");
    let nvals = names.len();

    const CHUNK: usize = 4096;
    let n = cloud.len();
    let mut out = header.into_bytes();
    match format {
        PlyFormat::BinaryLittleEndian => {
            let stride = nvals * 4 + if has_label { 4 } else { 0 };
            let start = out.len();
            out.resize(start + n * stride, 0);
            out[start..]
                .par_chunks_mut(CHUNK * stride)
                .enumerate()
                .for_each(|(ci, chunk)| {
                    let mut vals = [0.0f32; MAX_VALUES];
                    for (j, rec) in chunk.chunks_exact_mut(stride).enumerate() {
                        encode_vertex(cloud, ci * CHUNK + j, &mut vals[..nvals]);
                        for (dst, v) in rec.chunks_exact_mut(4).zip(&vals[..nvals]) {
                            dst.copy_from_slice(&v.to_le_bytes());
                        }
                        if let Some(&l) = cloud.labels.get(ci * CHUNK + j) {
                            rec[nvals * 4..].copy_from_slice(&i32::from(l).to_le_bytes());
                        }
                    }
                });
        }
        PlyFormat::Ascii => {
            let parts: Vec<String> = (0..n.div_ceil(CHUNK))
                .into_par_iter()
                .map(|ci| {
                    let mut s = String::new();
                    let mut vals = [0.0f32; MAX_VALUES];
                    for i in ci * CHUNK..((ci + 1) * CHUNK).min(n) {
                        encode_vertex(cloud, i, &mut vals[..nvals]);
                        for (j, v) in vals[..nvals].iter().enumerate() {
                            if j > 0 {
                                s.push(' ');
                            }
                            // `Display` of f32 is the shortest string that parses back exactly.
                            let _ = write!(s, "{v}");
                        }
                        if let Some(l) = cloud.labels.get(i) {
                            let _ = write!(s, " {l}");
                        }
                        s.push('\n');
                    }
                    s
                })
                .collect();
            for p in parts {
                out.extend_from_slice(p.as_bytes());
            }
        }
    }
    Ok(out)
}

/// Values of Gaussian `i` in the writer's property order.
fn encode_vertex(cloud: &GaussianCloud, i: usize, vals: &mut [f32]) {
    let k = sh_coeff_count(cloud.sh_degree);
    let p = cloud.positions[i];
    let nrm = cloud.normals.get(i).copied().unwrap_or(Vec3::ZERO);
    vals[0..3].copy_from_slice(&p.to_array());
    vals[3..6].copy_from_slice(&nrm.to_array());
    let sh = cloud.sh_of(i);
    vals[6..9].copy_from_slice(&sh[0..3]);
    for c in 0..3 {
        for j in 1..k {
            vals[9 + c * (k - 1) + (j - 1)] = sh[j * 3 + c];
        }
    }
    let o = 9 + 3 * (k - 1);
    let a = f64::from(cloud.opacities[i]).clamp(1e-12, 1.0 - 1e-12);
    vals[o] = (a / (1.0 - a)).ln() as f32;
    let s = cloud.scales[i];
    for (d, v) in vals[o + 1..o + 4].iter_mut().zip(s.to_array()) {
        *d = f64::from(v).ln() as f32;
    }
    let q = cloud.rotations[i];
    vals[o + 4..o + 8].copy_from_slice(&[q.w, q.x, q.y, q.z]);
}

// ---------------------------------------------------------------------------------------
// Header

fn parse_header(bytes: &[u8], file: &str) -> Result<(ply_rs_bw::ply::Header, usize), PlyError> {
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

/// Scalar types, as a `Copy` enum.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn of(t: &ScalarType) -> Scalar {
        match t {
            ScalarType::Char => Scalar::I8,
            ScalarType::UChar => Scalar::U8,
            ScalarType::Short => Scalar::I16,
            ScalarType::UShort => Scalar::U16,
            ScalarType::Int => Scalar::I32,
            ScalarType::UInt => Scalar::U32,
            ScalarType::Float => Scalar::F32,
            ScalarType::Double => Scalar::F64,
        }
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// Decode one little-endian value at the start of `b` (which holds at least `size()` bytes).
    #[inline(always)]
    fn read_le(self, b: &[u8]) -> f64 {
        fn arr<const N: usize>(b: &[u8]) -> [u8; N] {
            let mut a = [0u8; N];
            a.copy_from_slice(&b[..N]);
            a
        }
        match self {
            Scalar::F32 => f64::from(f32::from_le_bytes(arr(b))),
            Scalar::F64 => f64::from_le_bytes(arr(b)),
            Scalar::I8 => f64::from(b[0] as i8),
            Scalar::U8 => f64::from(b[0]),
            Scalar::I16 => f64::from(i16::from_le_bytes(arr(b))),
            Scalar::U16 => f64::from(u16::from_le_bytes(arr(b))),
            Scalar::I32 => f64::from(i32::from_le_bytes(arr(b))),
            Scalar::U32 => f64::from(u32::from_le_bytes(arr(b))),
        }
    }
}

/// Most values one vertex contributes: 3 + 3 + 45 + 1 + 3 + 4 + 3 + 1 (label) = 63.
const MAX_VALUES: usize = 64;

/// Which vertex properties hold the values we need, in canonical order:
/// `x y z | f_dc_0..2 | f_rest_0..R−1 | opacity | scale_0..2 | rot_0..3 | [nx ny nz]`.
struct Layout {
    degree: u32,
    /// Number of `f_rest_*` values, R = 3·(K − 1).
    rest: usize,
    has_normals: bool,
    /// Whether a scalar `label` (or `segment`) property gives region labels.
    has_label: bool,
    /// Property index (within the `vertex` element) of each needed value.
    props: Vec<usize>,
}

impl Layout {
    fn new(def: &ElementDef, file: &str) -> Result<Layout, PlyError> {
        let index_of = |name: &str| def.properties.get_index_of(name);
        let rest = def
            .properties
            .keys()
            .filter(|k| {
                k.strip_prefix("f_rest_")
                    .is_some_and(|s| s.parse::<usize>().is_ok())
            })
            .count();
        let degree = match rest {
            0 => 0,
            9 => 1,
            24 => 2,
            45 => 3,
            count => {
                return Err(PlyError::ShRestCount {
                    file: file.to_string(),
                    count,
                })
            }
        };
        let mut names: Vec<String> = ["x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        names.extend((0..rest).map(|j| format!("f_rest_{j}")));
        names.extend(
            [
                "opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3",
            ]
            .iter()
            .map(|s| s.to_string()),
        );
        let normal_idx: Vec<Option<usize>> =
            ["nx", "ny", "nz"].iter().map(|n| index_of(n)).collect();
        let has_normals = normal_idx.iter().all(|i| {
            i.is_some_and(|i| matches!(def.properties[i].data_type, PropertyType::Scalar(_)))
        });
        if has_normals {
            names.extend(["nx", "ny", "nz"].iter().map(|s| s.to_string()));
        }
        // Region labels, last: `label`, else `segment` (a list property is not a label).
        let label = ["label", "segment"].into_iter().find(|n| {
            index_of(n)
                .is_some_and(|i| matches!(def.properties[i].data_type, PropertyType::Scalar(_)))
        });
        if let Some(n) = label {
            names.push(n.to_string());
        }
        let missing: Vec<String> = names
            .iter()
            .filter(|n| index_of(n).is_none())
            .cloned()
            .collect();
        if !missing.is_empty() {
            return Err(PlyError::MissingProperties {
                file: file.to_string(),
                missing,
            });
        }
        let mut props = Vec::with_capacity(names.len());
        for n in &names {
            let i = index_of(n).unwrap_or_default();
            if let PropertyType::List(..) = def.properties[i].data_type {
                return Err(PlyError::Unsupported {
                    file: file.to_string(),
                    what: format!("the list property `{n}` in element `vertex`"),
                    expected: "scalar 3DGS properties",
                });
            }
            props.push(i);
        }
        Ok(Layout {
            degree,
            rest,
            has_normals,
            has_label: label.is_some(),
            props,
        })
    }

    fn value_count(&self) -> usize {
        self.props.len()
    }
}

// ---------------------------------------------------------------------------------------
// Decoding (shared by both encodings)

const CHUNK: usize = 8192;

/// Output slices of one chunk of vertices.
struct OutChunk<'a> {
    pos: &'a mut [Vec3],
    scale: &'a mut [Vec3],
    rot: &'a mut [Quat],
    opacity: &'a mut [f32],
    sh: &'a mut [f32],
    normals: &'a mut [Vec3],
    /// Raw label values, mapped to ids once all are read ([`label_ids`]).
    labels: &'a mut [f64],
}

#[derive(Clone, Copy, Default)]
struct Tally {
    kept: usize,
    nonfinite: usize,
    degenerate: usize,
}

enum Verdict {
    Kept,
    NonFinite,
    Degenerate,
}

/// Activate the canonical values `v` of one vertex and store them in slot `w` of `out`.
#[inline(always)]
fn store(v: &[f64], lay: &Layout, out: &mut OutChunk<'_>, w: usize) -> Verdict {
    if !v.iter().all(|x| (*x as f32).is_finite()) {
        return Verdict::NonFinite;
    }
    let r = lay.rest;
    let o = 6 + r;
    let scale = [
        v[o + 1].exp() as f32,
        v[o + 2].exp() as f32,
        v[o + 3].exp() as f32,
    ];
    if scale.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
        return Verdict::Degenerate;
    }
    let (qw, qx, qy, qz) = (v[o + 4], v[o + 5], v[o + 6], v[o + 7]);
    let norm = (qw * qw + qx * qx + qy * qy + qz * qz).sqrt();
    if !(norm > 0.0 && norm.is_finite()) {
        return Verdict::Degenerate;
    }
    out.pos[w] = Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32);
    out.scale[w] = Vec3::from_array(scale);
    out.rot[w] = Quat::from_xyzw(
        (qx / norm) as f32,
        (qy / norm) as f32,
        (qz / norm) as f32,
        (qw / norm) as f32,
    );
    out.opacity[w] = (1.0 / (1.0 + (-v[o]).exp())) as f32;
    let k = r / 3 + 1;
    let sh = &mut out.sh[w * 3 * k..(w + 1) * 3 * k];
    sh[0] = v[3] as f32;
    sh[1] = v[4] as f32;
    sh[2] = v[5] as f32;
    for c in 0..3 {
        for j in 1..k {
            sh[j * 3 + c] = v[6 + c * (k - 1) + (j - 1)] as f32;
        }
    }
    if lay.has_normals {
        let b = o + 8;
        out.normals[w] = Vec3::new(v[b] as f32, v[b + 1] as f32, v[b + 2] as f32);
    }
    if lay.has_label {
        out.labels[w] = v[v.len() - 1];
    }
    Verdict::Kept
}

/// Decode `n` vertices in parallel chunks. `gather(i, vals)` fills the canonical values of
/// vertex `i`. Skipped vertices are compacted away; returns the cloud and the skip counts.
fn decode<G>(
    n: usize,
    lay: &Layout,
    file: &str,
    gather: G,
) -> Result<(GaussianCloud, usize, usize), PlyError>
where
    G: Fn(usize, &mut [f64]) -> Result<(), PlyError> + Sync,
{
    let stride = 3 * sh_coeff_count(lay.degree);
    let mut cloud = GaussianCloud {
        positions: vec![Vec3::ZERO; n],
        scales: vec![Vec3::ZERO; n],
        rotations: vec![Quat::IDENTITY; n],
        opacities: vec![0.0; n],
        sh_degree: lay.degree,
        sh: vec![0.0; n * stride],
        normals: if lay.has_normals {
            vec![Vec3::ZERO; n]
        } else {
            Vec::new()
        },
        ..Default::default()
    };
    let mut raw_labels = vec![0.0f64; if lay.has_label { n } else { 0 }];

    let mut chunks = Vec::with_capacity(n.div_ceil(CHUNK));
    {
        let (mut pos, mut scale, mut rot, mut opacity, mut sh, mut normals) = (
            &mut cloud.positions[..],
            &mut cloud.scales[..],
            &mut cloud.rotations[..],
            &mut cloud.opacities[..],
            &mut cloud.sh[..],
            &mut cloud.normals[..],
        );
        let mut labels = &mut raw_labels[..];
        while !pos.is_empty() {
            let m = pos.len().min(CHUNK);
            let (a, b) = pos.split_at_mut(m);
            pos = b;
            let (sa, sb) = scale.split_at_mut(m);
            scale = sb;
            let (ra, rb) = rot.split_at_mut(m);
            rot = rb;
            let (oa, ob) = opacity.split_at_mut(m);
            opacity = ob;
            let (ha, hb) = sh.split_at_mut(m * stride);
            sh = hb;
            let (na, nb) = normals.split_at_mut(if lay.has_normals { m } else { 0 });
            normals = nb;
            let (la, lb) = labels.split_at_mut(if lay.has_label { m } else { 0 });
            labels = lb;
            chunks.push(OutChunk {
                pos: a,
                scale: sa,
                rot: ra,
                opacity: oa,
                sh: ha,
                normals: na,
                labels: la,
            });
        }
    }

    let m = lay.value_count();
    let tallies: Vec<Result<Tally, PlyError>> = chunks
        .into_par_iter()
        .enumerate()
        .map(|(ci, mut out)| {
            let mut vals = [0.0f64; MAX_VALUES];
            let mut t = Tally::default();
            for i in ci * CHUNK..ci * CHUNK + out.pos.len() {
                gather(i, &mut vals[..m])?;
                match store(&vals[..m], lay, &mut out, t.kept) {
                    Verdict::Kept => t.kept += 1,
                    Verdict::NonFinite => t.nonfinite += 1,
                    Verdict::Degenerate => t.degenerate += 1,
                }
            }
            Ok(t)
        })
        .collect();

    // Close the gaps left by skipped vertices (nothing moves when none was skipped).
    let (mut kept, mut nonfinite, mut degenerate) = (0, 0, 0);
    for (ci, t) in tallies.into_iter().enumerate() {
        let t = t?;
        let start = ci * CHUNK;
        if start != kept && t.kept > 0 {
            let r = start..start + t.kept;
            cloud.positions.copy_within(r.clone(), kept);
            cloud.scales.copy_within(r.clone(), kept);
            cloud.rotations.copy_within(r.clone(), kept);
            cloud.opacities.copy_within(r.clone(), kept);
            if lay.has_normals {
                cloud.normals.copy_within(r.clone(), kept);
            }
            if lay.has_label {
                raw_labels.copy_within(r, kept);
            }
            cloud
                .sh
                .copy_within(start * stride..(start + t.kept) * stride, kept * stride);
        }
        kept += t.kept;
        nonfinite += t.nonfinite;
        degenerate += t.degenerate;
    }
    cloud.positions.truncate(kept);
    cloud.scales.truncate(kept);
    cloud.rotations.truncate(kept);
    cloud.opacities.truncate(kept);
    cloud.sh.truncate(kept * stride);
    cloud
        .normals
        .truncate(if lay.has_normals { kept } else { 0 });
    if cloud.normals.iter().all(|n| *n == Vec3::ZERO) {
        cloud.normals = Vec::new();
    }
    raw_labels.truncate(kept);
    (cloud.labels, cloud.label_names) = label_ids(&raw_labels, file)?;
    Ok((cloud, nonfinite, degenerate))
}

/// Map raw label values (integers in any numeric type) to dense ids, numbered in
/// increasing value order and named by the value (`"3"`, `"-1"`).
fn label_ids(raw: &[f64], file: &str) -> Result<(Vec<u16>, Vec<String>), PlyError> {
    if let Some(v) = raw.iter().find(|v| !(v.fract() == 0.0 && v.abs() < 9.0e15)) {
        return Err(PlyError::Invalid {
            file: file.to_string(),
            what: format!("vertex label {v}"),
            expected: "integer labels (property `label` or `segment`)".to_string(),
        });
    }
    let mut values: Vec<i64> = raw.iter().map(|&v| v as i64).collect();
    values.sort_unstable();
    values.dedup();
    if values.len() >= usize::from(super::NO_LABEL) {
        return Err(PlyError::Invalid {
            file: file.to_string(),
            what: format!("{} distinct vertex labels", values.len()),
            expected: format!("at most {} distinct labels", super::NO_LABEL - 1),
        });
    }
    let ids = raw
        .iter()
        .map(|&v| values.binary_search(&(v as i64)).unwrap_or_default() as u16)
        .collect();
    Ok((ids, values.iter().map(i64::to_string).collect()))
}

/// Apply the label names that the writer records in header comments
/// (`comment label <value> <name>`), so that named regions survive a round trip, names of
/// regions without Gaussians included (ids then follow the comments' values); other
/// readers see only the numbers.
fn name_labels(cloud: &mut GaussianCloud, comments: &[String]) {
    let named: Vec<(i64, String)> = comments
        .iter()
        .filter_map(|c| {
            let rest = c.trim().strip_prefix("label ")?;
            let (value, name) = rest.trim_start().split_once(' ')?;
            Some((value.parse().ok()?, name.trim().to_string()))
        })
        .collect();
    if named.is_empty() {
        return;
    }
    // Values as read (label_names holds them as strings), then those only in comments.
    let mut values: Vec<i64> = cloud
        .label_names
        .iter()
        .filter_map(|n| n.parse().ok())
        .collect();
    let old = values.clone();
    values.extend(named.iter().map(|(v, _)| *v));
    values.sort_unstable();
    values.dedup();
    if values.len() >= usize::from(super::NO_LABEL) {
        return;
    }
    for l in &mut cloud.labels {
        *l = values
            .binary_search(&old[usize::from(*l)])
            .unwrap_or_default() as u16;
    }
    cloud.label_names = values
        .iter()
        .map(|v| {
            named
                .iter()
                .find(|(w, _)| w == v)
                .map_or_else(|| v.to_string(), |(_, n)| n.clone())
        })
        .collect();
}

// ---------------------------------------------------------------------------------------
// Binary little-endian

fn read_binary_body(
    body: &[u8],
    before: &[&ElementDef],
    vdef: &ElementDef,
    lay: &Layout,
    file: &str,
) -> Result<(GaussianCloud, usize, usize), PlyError> {
    let mut at = 0usize;
    for def in before {
        at = skip_binary_element(body, at, def, file)?;
    }
    let body = &body[at..];

    // Byte offset and type of every vertex property.
    let mut offsets = Vec::with_capacity(vdef.properties.len());
    let mut stride = 0usize;
    for (name, p) in &vdef.properties {
        match &p.data_type {
            PropertyType::Scalar(t) => {
                let t = Scalar::of(t);
                offsets.push((stride, t));
                stride += t.size();
            }
            PropertyType::List(..) => {
                return Err(PlyError::Unsupported {
                    file: file.to_string(),
                    what: format!(
                        "the list property `{name}` in element `vertex` of a binary file"
                    ),
                    expected: "scalar vertex properties",
                })
            }
        }
    }
    let n = vdef.count;
    let need = (n as u128) * (stride as u128);
    if need > body.len() as u128 {
        return Err(PlyError::Truncated {
            file: file.to_string(),
            element: "vertex".to_string(),
            declared: n,
            found: (body.len() / stride.max(1)) as u64,
            detail: format!(
                "expected {need} bytes of vertex data ({n} × {stride}), found {}",
                body.len()
            ),
        });
    }
    let fields: Vec<(usize, Scalar)> = lay.props.iter().map(|&i| offsets[i]).collect();
    let body = &body[..n * stride];
    decode(n, lay, file, |i, vals| {
        let rec = &body[i * stride..(i + 1) * stride];
        for (v, &(off, t)) in vals.iter_mut().zip(&fields) {
            *v = t.read_le(&rec[off..]);
        }
        Ok(())
    })
}

/// Skip the binary data of an element we do not read; returns the new position.
fn skip_binary_element(
    body: &[u8],
    at: usize,
    def: &ElementDef,
    file: &str,
) -> Result<usize, PlyError> {
    let truncated = |found: u64, detail: String| PlyError::Truncated {
        file: file.to_string(),
        element: def.name.clone(),
        declared: def.count,
        found,
        detail,
    };
    let left = body.len() - at;
    let all_scalar = def
        .properties
        .values()
        .all(|p| matches!(p.data_type, PropertyType::Scalar(_)));
    if all_scalar {
        let stride: usize = def
            .properties
            .values()
            .map(|p| match &p.data_type {
                PropertyType::Scalar(t) => Scalar::of(t).size(),
                PropertyType::List(..) => 0,
            })
            .sum();
        let need = (def.count as u128) * (stride as u128);
        if need > left as u128 {
            return Err(truncated(
                (left / stride.max(1)) as u64,
                format!("expected {need} bytes, found {left}"),
            ));
        }
        return Ok(at + need as usize);
    }
    // Lists: walk element by element. Every element holds at least one list count, so the
    // loop ends (with an error) after at most `left` iterations.
    let mut pos = at;
    for e in 0..def.count {
        for p in def.properties.values() {
            let step = match &p.data_type {
                PropertyType::Scalar(t) => Some(Scalar::of(t).size()),
                PropertyType::List(ct, et) => {
                    let ct = Scalar::of(ct);
                    (body.len() - pos >= ct.size())
                        .then(|| ct.read_le(&body[pos..]))
                        .and_then(|c| {
                            (c >= 0.0 && c.fract() == 0.0)
                                .then(|| (c as usize).checked_mul(Scalar::of(et).size()))
                                .flatten()
                                .and_then(|b| b.checked_add(ct.size()))
                        })
                }
            };
            match step {
                Some(s) if s <= body.len() - pos => pos += s,
                _ => {
                    return Err(truncated(
                        e as u64,
                        format!(
                            "element {e} runs past the end of the file or has a bad list count"
                        ),
                    ))
                }
            }
        }
    }
    Ok(pos)
}

// ---------------------------------------------------------------------------------------
// ASCII

fn read_ascii_body(
    body: &[u8],
    before: &[&ElementDef],
    vdef: &ElementDef,
    lay: &Layout,
    file: &str,
    header_lines: usize,
) -> Result<(GaussianCloud, usize, usize), PlyError> {
    // Non-blank lines with their 1-based line numbers in the file. One element per line.
    let mut lines = body
        .split(|&b| b == b'\n')
        .enumerate()
        .map(|(i, l)| (header_lines + i + 1, l))
        .filter(|(_, l)| !l.iter().all(u8::is_ascii_whitespace));
    for def in before {
        for e in 0..def.count {
            if lines.next().is_none() {
                return Err(PlyError::Truncated {
                    file: file.to_string(),
                    element: def.name.clone(),
                    declared: def.count,
                    found: e as u64,
                    detail: "the file ends early".to_string(),
                });
            }
        }
    }
    let n = vdef.count;
    // Grows only as far as the lines present, whatever the header claims.
    let vlines: Vec<(usize, &[u8])> = lines.by_ref().take(n).collect();
    if vlines.len() < n {
        return Err(PlyError::Truncated {
            file: file.to_string(),
            element: "vertex".to_string(),
            declared: n,
            found: vlines.len() as u64,
            detail: format!("expected {n} vertex lines, found {}", vlines.len()),
        });
    }

    // For each vertex property: its type and the canonical slot it fills, if any.
    let mut slot = vec![None; vdef.properties.len()];
    for (s, &p) in lay.props.iter().enumerate() {
        slot[p] = Some(s);
    }
    let props: Vec<(&str, &PropertyType, Option<usize>)> = vdef
        .properties
        .iter()
        .zip(slot)
        .map(|((name, p), s)| (name.as_str(), &p.data_type, s))
        .collect();

    decode(n, lay, file, |i, vals| {
        let (lineno, line) = vlines[i];
        let bad = |what: String, expected: String| PlyError::Invalid {
            file: file.to_string(),
            what: format!("line {lineno} (vertex {i}): {what}"),
            expected,
        };
        let mut tokens = line
            .split(|b| b.is_ascii_whitespace())
            .filter(|t| !t.is_empty());
        let mut next = |name: &str| {
            tokens.next().ok_or_else(|| {
                bad(
                    format!("the line ends before property `{name}`"),
                    format!("{} values", props.len()),
                )
            })
        };
        for &(name, ty, s) in &props {
            match ty {
                PropertyType::Scalar(t) => {
                    let tok = next(name)?;
                    if let Some(s) = s {
                        vals[s] = parse_number(tok, Scalar::of(t)).ok_or_else(|| {
                            bad(
                                format!("property `{name}` is `{}`", String::from_utf8_lossy(tok)),
                                "a number".to_string(),
                            )
                        })?;
                    }
                }
                PropertyType::List(..) => {
                    let tok = next(name)?;
                    let count = std::str::from_utf8(tok)
                        .ok()
                        .and_then(|t| t.parse::<usize>().ok())
                        .ok_or_else(|| {
                            bad(
                                format!(
                                    "list count of property `{name}` is `{}`",
                                    String::from_utf8_lossy(tok)
                                ),
                                "a non-negative integer".to_string(),
                            )
                        })?;
                    for _ in 0..count {
                        next(name)?;
                    }
                }
            }
        }
        Ok(())
    })
}

/// Parse an ASCII token (`nan`, `inf`, `.5`, `1e3` included). Floats are parsed at their
/// declared precision so that written values round-trip exactly.
fn parse_number(tok: &[u8], t: Scalar) -> Option<f64> {
    let s = std::str::from_utf8(tok).ok()?;
    match t {
        Scalar::F64 => s.parse::<f64>().ok(),
        _ => s.parse::<f32>().ok().map(f64::from),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
