//! SuperSplat / PlayCanvas `compressed.ply` (docs/formats.md): a binary PLY whose element
//! `chunk` holds, per 256 Gaussians, the ranges of position, log-scale (and colour), and
//! whose element `vertex` packs each Gaussian into four u32: position and log-scale as
//! 11-10-11 bits within the chunk's range, the rotation as "smallest three" (2 + 3×10
//! bits), colour and opacity as RGBA bytes. An optional element `sh` holds the rest
//! coefficients as bytes.

use ply_rs_bw::ply::{ElementDef, Header, PropertyType, ScalarType};

use super::codec::{decode_parallel, Builder, Decoded, Format, SplatError, SH_C0};
use super::ply::scalar_size;

/// Gaussians per chunk.
pub const CHUNK: usize = 256;

const POSITION: [&str; 6] = ["min_x", "min_y", "min_z", "max_x", "max_y", "max_z"];
const SCALE: [&str; 6] = [
    "min_scale_x",
    "min_scale_y",
    "min_scale_z",
    "max_scale_x",
    "max_scale_y",
    "max_scale_z",
];
const COLOR: [&str; 6] = ["min_r", "min_g", "min_b", "max_r", "max_g", "max_b"];
const PACKED: [&str; 4] = [
    "packed_position",
    "packed_rotation",
    "packed_scale",
    "packed_color",
];

fn damaged(file: &str, what: impl Into<String>) -> SplatError {
    SplatError::Damaged {
        file: file.to_string(),
        format: Format::CompressedPly,
        what: what.into(),
    }
}

/// A fixed-size binary element: its record size and the byte offset of each named
/// property of the wanted type.
struct Record {
    size: usize,
    count: usize,
}

fn record(def: &ElementDef, file: &str) -> Result<Record, SplatError> {
    let mut size = 0;
    for (name, p) in &def.properties {
        match &p.data_type {
            PropertyType::Scalar(t) => size += scalar_size(t),
            PropertyType::List(..) => {
                return Err(damaged(
                    file,
                    format!("list property `{name}` in element `{}`", def.name),
                ))
            }
        }
    }
    Ok(Record {
        size,
        count: def.count,
    })
}

/// Byte offset of property `name` in `def`'s records, checked to be of type `want`.
fn offset(def: &ElementDef, name: &str, want: ScalarType, file: &str) -> Result<usize, SplatError> {
    let mut at = 0;
    for (n, p) in &def.properties {
        let PropertyType::Scalar(t) = &p.data_type else {
            continue;
        };
        if n == name {
            if *t != want {
                return Err(damaged(
                    file,
                    format!("`{}.{name}` is {t:?}, expected {want:?}", def.name),
                ));
            }
            return Ok(at);
        }
        at += scalar_size(t);
    }
    Err(damaged(
        file,
        format!("element `{}` lacks the property `{name}`", def.name),
    ))
}

// Over 80 lines on purpose: the format's elements in file order (header, chunks, vertices,
// SH), each checked where it is read, so every error names its element.
pub fn read(
    bytes: &[u8],
    header: &Header,
    body_start: usize,
    file: &str,
) -> Result<Builder, SplatError> {
    if header.encoding != ply_rs_bw::ply::Encoding::BinaryLittleEndian {
        return Err(damaged(file, "the body is not binary_little_endian"));
    }
    let mut at = body_start;
    let mut chunk_data: &[u8] = &[];
    let mut vertex_data: &[u8] = &[];
    let mut sh_data: &[u8] = &[];
    let (mut chunk, mut vertex, mut sh) = (None, None, None);
    for def in header.elements.values() {
        let rec = record(def, file)?;
        let len = rec.size.saturating_mul(rec.count);
        let Some(data) = bytes.get(at..at.saturating_add(len)) else {
            return Err(damaged(
                file,
                format!(
                    "truncated: element `{}` needs {len} bytes from byte {at}, the file has {}",
                    def.name,
                    bytes.len()
                ),
            ));
        };
        at += len;
        match def.name.as_str() {
            "chunk" => (chunk_data, chunk) = (data, Some((def, rec))),
            "vertex" => (vertex_data, vertex) = (data, Some((def, rec))),
            "sh" => (sh_data, sh) = (data, Some((def, rec))),
            _ => {}
        }
    }
    let (Some((cdef, crec)), Some((vdef, vrec))) = (chunk, vertex) else {
        return Err(damaged(
            file,
            "elements `chunk` and `vertex` are both needed",
        ));
    };
    let n = vrec.count;
    if crec.count != n.div_ceil(CHUNK) {
        return Err(damaged(
            file,
            format!(
                "{} chunks for {n} vertices (expected ⌈{n}/{CHUNK}⌉ = {})",
                crec.count,
                n.div_ceil(CHUNK)
            ),
        ));
    }
    let f = |name| offset(cdef, name, ScalarType::Float, file);
    let pos_off = POSITION.map(f);
    let scale_off = SCALE.map(f);
    let pos_off = collect6(pos_off)?;
    let scale_off = collect6(scale_off)?;
    let color_off = if cdef.properties.contains_key("min_r") {
        Some(collect6(COLOR.map(f))?)
    } else {
        None
    };
    let packed = PACKED.map(|name| offset(vdef, name, ScalarType::UInt, file));
    let [p_pos, p_rot, p_scale, p_col] = [0, 1, 2, 3].map(|i| packed[i].as_ref().map(|v| *v).ok());
    let (Some(p_pos), Some(p_rot), Some(p_scale), Some(p_col)) = (p_pos, p_rot, p_scale, p_col)
    else {
        let missing: Vec<&str> = PACKED
            .iter()
            .zip(&packed)
            .filter(|(_, r)| r.is_err())
            .map(|(n, _)| *n)
            .collect();
        return Err(damaged(
            file,
            format!("element `vertex` lacks or mistypes {}", missing.join(", ")),
        ));
    };
    let (degree, rest) = match sh {
        None => (0, 0),
        Some((def, rec)) => {
            if rec.count != n {
                return Err(damaged(
                    file,
                    format!("element `sh` has {} entries for {n} vertices", rec.count),
                ));
            }
            let k = def.properties.len();
            let degree = match k {
                9 => 1,
                24 => 2,
                45 => 3,
                _ => {
                    return Err(damaged(
                        file,
                        format!("element `sh` has {k} properties (expected 9, 24 or 45)"),
                    ))
                }
            };
            if rec.size != k {
                return Err(damaged(file, "element `sh` properties are not all uchar"));
            }
            (degree, k / 3)
        }
    };
    let chunk_float = |c: usize, o: usize| {
        let b = &chunk_data[c * crec.size + o..c * crec.size + o + 4];
        f32::from_le_bytes([b[0], b[1], b[2], b[3]])
    };
    let vert_u32 = |i: usize, o: usize| {
        let b = &vertex_data[i * vrec.size + o..i * vrec.size + o + 4];
        u32::from_le_bytes([b[0], b[1], b[2], b[3]])
    };
    Ok(decode_parallel(n, degree, |b, i| {
        let c = i / CHUNK;
        let range =
            |offs: &[usize; 6], a: usize| (chunk_float(c, offs[a]), chunk_float(c, offs[a + 3]));
        let unpack_11_10_11 = |v: u32, offs: &[usize; 6]| {
            let t = [
                (v >> 21) as f32 / 2047.0,
                ((v >> 11) & 1023) as f32 / 1023.0,
                (v & 2047) as f32 / 2047.0,
            ];
            [0, 1, 2].map(|a| {
                let (lo, hi) = range(offs, a);
                lo + (hi - lo) * t[a]
            })
        };
        let position = unpack_11_10_11(vert_u32(i, p_pos), &pos_off);
        let log_scale = unpack_11_10_11(vert_u32(i, p_scale), &scale_off);
        let col = vert_u32(i, p_col);
        let bytes = [
            (col >> 24) & 255,
            (col >> 16) & 255,
            (col >> 8) & 255,
            col & 255,
        ]
        .map(|v| v as f32 / 255.0);
        let mut coeffs = [0.0f32; 48];
        for ch in 0..3 {
            let rgb = match &color_off {
                Some(offs) => {
                    let (lo, hi) = range(offs, ch);
                    lo + (hi - lo) * bytes[ch]
                }
                None => bytes[ch],
            };
            coeffs[ch] = (rgb - 0.5) / SH_C0;
        }
        if rest > 0 {
            let s = &sh_data[i * 3 * rest..(i + 1) * 3 * rest];
            for ch in 0..3 {
                for j in 0..rest {
                    let v = s[ch * rest + j];
                    let t = match v {
                        0 => 0.0,
                        255 => 1.0,
                        _ => (f32::from(v) + 0.5) / 256.0,
                    };
                    coeffs[3 * (j + 1) + ch] = (t - 0.5) * 8.0;
                }
            }
        }
        b.push(Decoded {
            position,
            log_scale,
            rotation: unpack_rotation(vert_u32(i, p_rot)),
            opacity: bytes[3],
            sh: &coeffs[..3 * (rest + 1)],
        })
    }))
}

fn collect6(offs: [Result<usize, SplatError>; 6]) -> Result<[usize; 6], SplatError> {
    let mut out = [0; 6];
    for (o, r) in out.iter_mut().zip(offs) {
        *o = r?;
    }
    Ok(out)
}

/// "Smallest three" of PlayCanvas: the index of the largest of (w, x, y, z) in bits 31..30,
/// the other three in increasing index order as 10-bit unorms of q·√½ + ½.
fn unpack_rotation(v: u32) -> [f32; 4] {
    let largest = (v >> 30) as usize;
    let mut q = [0.0f32; 4];
    let mut sum = 0.0;
    let mut shift = 20;
    for (i, c) in q.iter_mut().enumerate() {
        if i == largest {
            continue;
        }
        let u = ((v >> shift) & 1023) as f32 / 1023.0;
        *c = (u - 0.5) * std::f32::consts::SQRT_2;
        sum += *c * *c;
        shift -= 10;
    }
    q[largest] = (1.0 - sum).max(0.0).sqrt();
    q
}
