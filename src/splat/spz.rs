//! Niantic SPZ (docs/formats.md): a header, then one stream per attribute (positions as
//! 24-bit fixed point, opacity, DC colour, log-scale and rotation as bytes, SH as bytes).
//! Versions 1–3 gzip the header and the streams together; version 4 keeps a plain header
//! and a table of contents and compresses each stream with zstd.
//!
//! Coordinates are read and written as stored, with no axis flip: that is what Niantic's
//! own converters and splat-transform 3 do with a graphdeco PLY's frame.
//!
//! Region labels travel in an extension record of our own ([`LABELS_EXTENSION`]); readers
//! skip record types they do not know.

use std::io::Read;

use rayon::prelude::*;

use super::codec::{decode_parallel, to_u8, Builder, Decoded, Format, SplatError};
use super::{sh_coeff_count, GaussianCloud, NO_LABEL};

/// `NGSP`, little-endian.
pub const MAGIC: u32 = 0x5053_474e;
/// The colour scale of the DC term: byte = DC · 0.15 · 255 + 127.5.
const COLOR_SCALE: f32 = 0.15;
const FLAG_EXTENSIONS: u8 = 0x2;
/// Our extension record: per-Gaussian region labels and their names.
pub const LABELS_EXTENSION: u32 = 0x5350_4c01;
/// Most Gaussians we accept in one file (the format's counts are u32; this bounds memory).
const MAX_POINTS: u64 = 1 << 28;

/// Which container to write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpzVersion {
    /// gzip over the header and streams (read by every SPZ reader).
    V3,
    /// Plain header, table of contents, zstd per stream.
    V4,
}

/// What the header says.
#[derive(Clone, Copy, Debug)]
struct Header {
    version: u32,
    points: usize,
    sh_degree: u32,
    fractional_bits: u32,
    flags: u8,
}

impl Header {
    /// SH coefficients per colour channel beyond the DC term, as stored.
    fn sh_dim(&self) -> usize {
        sh_coeff_count(self.sh_degree) - 1
    }

    /// Byte length of each stream: positions, alphas, colours, scales, rotations, SH.
    fn stream_sizes(&self) -> [usize; 6] {
        let n = self.points;
        [
            n * if self.version == 1 { 6 } else { 9 },
            n,
            n * 3,
            n * 3,
            n * if self.version < 3 { 3 } else { 4 },
            n * self.sh_dim() * 3,
        ]
    }
}

fn damaged(file: &str, what: impl Into<String>) -> SplatError {
    SplatError::Damaged {
        file: file.to_string(),
        format: Format::Spz,
        what: what.into(),
    }
}

fn u32_at(b: &[u8], o: usize) -> u32 {
    u32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]])
}

/// Parse the 16 bytes every version starts with (the v4 header adds 16 more).
fn parse_header(b: &[u8], file: &str) -> Result<Header, SplatError> {
    if b.len() < 16 {
        return Err(damaged(
            file,
            format!("truncated: the header needs 16 bytes, found {}", b.len()),
        ));
    }
    if u32_at(b, 0) != MAGIC {
        return Err(damaged(file, "no `NGSP` magic at the start of the data"));
    }
    let version = u32_at(b, 4);
    if !(1..=4).contains(&version) {
        return Err(SplatError::Unsupported {
            file: file.to_string(),
            format: Format::Spz,
            what: format!("version {version}"),
            expected: "SPZ versions 1 to 4",
        });
    }
    let points = u64::from(u32_at(b, 8));
    if points > MAX_POINTS {
        return Err(damaged(
            file,
            format!("{points} Gaussians declared; at most {MAX_POINTS} are accepted"),
        ));
    }
    let sh_degree = u32::from(b[12]);
    if sh_degree > 4 {
        return Err(damaged(
            file,
            format!("SH degree {sh_degree} (expected 0 to 4)"),
        ));
    }
    let fractional_bits = u32::from(b[13]);
    if fractional_bits > 24 {
        return Err(damaged(
            file,
            format!("{fractional_bits} fractional bits (expected at most 24)"),
        ));
    }
    Ok(Header {
        version,
        points: points as usize,
        sh_degree,
        fractional_bits,
        flags: b[14],
    })
}

/// Read an SPZ file of any version. Returns the Gaussians and the version.
pub fn read(bytes: &[u8], file: &str) -> Result<(Builder, u32), SplatError> {
    if bytes.starts_with(&[0x1f, 0x8b]) {
        return read_gzip(bytes, file);
    }
    let header = parse_header(bytes, file)?;
    if header.version == 4 {
        read_v4(bytes, header, file)
    } else {
        // A legacy payload without its gzip wrapper (some tools write these).
        let streams = split_legacy(&bytes[16..], &header, file)?;
        let cloud = decode(
            &header,
            &streams,
            legacy_extensions(&bytes[16..], &header),
            file,
        )?;
        Ok((cloud, header.version))
    }
}

fn read_gzip(bytes: &[u8], file: &str) -> Result<(Builder, u32), SplatError> {
    let mut gz = flate2::read::GzDecoder::new(bytes);
    let gzip_error = |e: std::io::Error| {
        let text = e.to_string();
        if e.kind() == std::io::ErrorKind::UnexpectedEof || text.contains("incomplete") {
            damaged(
                file,
                format!("truncated: the gzip stream ends early ({text})"),
            )
        } else {
            damaged(file, format!("gzip stream: {text}"))
        }
    };
    let mut head = [0u8; 16];
    let mut got = 0;
    while got < 16 {
        match gz.read(&mut head[got..]).map_err(gzip_error)? {
            0 => break,
            k => got += k,
        }
    }
    let header = parse_header(&head[..got], file)?;
    if header.version == 4 {
        return Err(damaged(
            file,
            "a version-4 header inside gzip (version 4 files are not gzipped)",
        ));
    }
    let need: usize = header.stream_sizes().iter().sum();
    let mut payload = Vec::with_capacity(need);
    // Everything after the streams is extension records; bound what we accept of them.
    (&mut gz)
        .take((need + (64 << 20)) as u64)
        .read_to_end(&mut payload)
        .map_err(gzip_error)?;
    let streams = split_legacy(&payload, &header, file)?;
    let cloud = decode(
        &header,
        &streams,
        legacy_extensions(&payload, &header),
        file,
    )?;
    Ok((cloud, header.version))
}

/// The six streams of a legacy payload (the data after the 16-byte header).
fn split_legacy<'a>(data: &'a [u8], h: &Header, file: &str) -> Result<Vec<&'a [u8]>, SplatError> {
    let sizes = h.stream_sizes();
    let need: usize = sizes.iter().sum();
    if data.len() < need {
        return Err(damaged(
            file,
            format!(
                "truncated: {} Gaussians need {need} bytes of data after the header, found {}",
                h.points,
                data.len()
            ),
        ));
    }
    let mut at = 0;
    Ok(sizes
        .iter()
        .map(|&s| {
            let part = &data[at..at + s];
            at += s;
            part
        })
        .collect())
}

fn legacy_extensions<'a>(data: &'a [u8], h: &Header) -> &'a [u8] {
    if h.flags & FLAG_EXTENSIONS == 0 {
        return &[];
    }
    let need: usize = h.stream_sizes().iter().sum();
    data.get(need..).unwrap_or_default()
}

// Over 80 lines on purpose: the version-4 container's streams in file order, each checked
// where it is read.
fn read_v4(bytes: &[u8], header: Header, file: &str) -> Result<(Builder, u32), SplatError> {
    if bytes.len() < 32 {
        return Err(damaged(
            file,
            format!(
                "truncated: a version-4 header needs 32 bytes, found {}",
                bytes.len()
            ),
        ));
    }
    let streams = usize::from(bytes[15]);
    let toc = u32_at(bytes, 16) as usize;
    let sizes = header.stream_sizes();
    let expected: Vec<usize> = sizes.iter().copied().filter(|&s| s > 0).collect();
    if streams != expected.len() && streams != 6 {
        return Err(damaged(
            file,
            format!(
                "{streams} streams declared (expected {} for SH degree {})",
                expected.len(),
                header.sh_degree
            ),
        ));
    }
    let toc_end = toc + 16 * streams;
    if toc < 32 || toc_end > bytes.len() {
        return Err(damaged(
            file,
            format!(
                "truncated: the table of contents at byte {toc} runs past the end ({} bytes)",
                bytes.len()
            ),
        ));
    }
    let mut at = toc_end;
    let mut raw: Vec<Vec<u8>> = Vec::with_capacity(6);
    let mut wanted = sizes.iter().copied().filter(|&s| streams == 6 || s > 0);
    for s in 0..streams {
        let e = toc + 16 * s;
        let packed = u64::from_le_bytes(bytes[e..e + 8].try_into().unwrap_or_default());
        let unpacked = u64::from_le_bytes(bytes[e + 8..e + 16].try_into().unwrap_or_default());
        let want = wanted.next().unwrap_or_default() as u64;
        if unpacked != want {
            return Err(damaged(
                file,
                format!(
                    "stream {s} holds {unpacked} bytes; {} Gaussians need {want}",
                    header.points
                ),
            ));
        }
        let end = (at as u64).saturating_add(packed);
        if end > bytes.len() as u64 {
            return Err(damaged(
                file,
                format!(
                    "truncated: stream {s} ends at byte {end}, the file has {}",
                    bytes.len()
                ),
            ));
        }
        raw.push(unzstd(&bytes[at..end as usize], want as usize, s, file)?);
        at = end as usize;
    }
    let empty = Vec::new();
    let mut it = raw.iter();
    let streams: Vec<&[u8]> = sizes
        .iter()
        .map(|&s| {
            if s == 0 && streams != 6 {
                &empty[..]
            } else {
                it.next().map_or(&empty[..], |v| &v[..])
            }
        })
        .collect();
    let ext = if header.flags & FLAG_EXTENSIONS != 0 {
        &bytes[32..toc]
    } else {
        &[]
    };
    Ok((decode(&header, &streams, ext, file)?, 4))
}

fn unzstd(packed: &[u8], want: usize, s: usize, file: &str) -> Result<Vec<u8>, SplatError> {
    let bad = |e: String| damaged(file, format!("zstd stream {s}: {e}"));
    let mut src = packed;
    let mut dec =
        ruzstd::decoding::StreamingDecoder::new(&mut src).map_err(|e| bad(e.to_string()))?;
    let mut out = Vec::with_capacity(want);
    (&mut dec)
        .take(want as u64 + 1)
        .read_to_end(&mut out)
        .map_err(|e| bad(e.to_string()))?;
    if out.len() != want {
        return Err(bad(format!(
            "{} bytes decompressed, {want} expected",
            out.len()
        )));
    }
    Ok(out)
}

/// Decode the attribute streams (and our labels record, if present).
fn decode(h: &Header, s: &[&[u8]], extensions: &[u8], file: &str) -> Result<Builder, SplatError> {
    let (pos, alpha, color, scale, rot, sh) = (s[0], s[1], s[2], s[3], s[4], s[5]);
    let dim = h.sh_dim();
    // We keep SH up to degree 3; degree-4 files lose their last band.
    let degree = h.sh_degree.min(3);
    let keep = sh_coeff_count(degree) - 1;
    let unit = 1.0 / (1u32 << h.fractional_bits) as f32;
    let v1 = h.version == 1;
    let mut b = decode_parallel(h.points, degree, |b, i| {
        let position = if v1 {
            let p = &pos[i * 6..i * 6 + 6];
            [0, 1, 2].map(|a| half::f16::from_le_bytes([p[2 * a], p[2 * a + 1]]).to_f32())
        } else {
            let p = &pos[i * 9..i * 9 + 9];
            [0, 1, 2].map(|a| {
                let v = i32::from(p[3 * a])
                    | i32::from(p[3 * a + 1]) << 8
                    | i32::from(p[3 * a + 2]) << 16;
                ((v << 8) >> 8) as f32 * unit
            })
        };
        let rotation = if h.version < 3 {
            let r = &rot[i * 3..i * 3 + 3];
            let [x, y, z] = [r[0], r[1], r[2]].map(|c| f32::from(c) / 127.5 - 1.0);
            [(1.0 - x * x - y * y - z * z).max(0.0).sqrt(), x, y, z]
        } else {
            let r = &rot[i * 4..i * 4 + 4];
            smallest_three_decode(u32::from_le_bytes([r[0], r[1], r[2], r[3]]))
        };
        let mut coeffs = [0.0f32; 48];
        for c in 0..3 {
            coeffs[c] = (f32::from(color[i * 3 + c]) / 255.0 - 0.5) / COLOR_SCALE;
        }
        let shs = &sh[i * dim * 3..(i + 1) * dim * 3];
        for (j, v) in shs.iter().take(keep * 3).enumerate() {
            coeffs[3 + j] = (f32::from(*v) - 128.0) / 128.0;
        }
        b.push(Decoded {
            position,
            log_scale: [0, 1, 2].map(|a| f32::from(scale[i * 3 + a]) / 16.0 - 10.0),
            rotation,
            opacity: f32::from(alpha[i]) / 255.0,
            sh: &coeffs[..3 * (keep + 1)],
        })
    });
    read_labels(&mut b, extensions, h.points, file)?;
    Ok(b)
}

/// "Smallest three": 2 bits for the index of the largest of (x, y, z, w), then the other
/// three in increasing index order, 10 bits each (a sign bit, 9 bits of |q| / √½). The
/// largest is positive. Returns `[w, x, y, z]`.
fn smallest_three_decode(mut c: u32) -> [f32; 4] {
    let largest = (c >> 30) as usize;
    let mut q = [0.0f32; 4]; // x y z w
    let mut sum = 0.0;
    for i in (0..4).rev() {
        if i == largest {
            continue;
        }
        let mag = (c & 511) as f32 / 511.0 * std::f32::consts::FRAC_1_SQRT_2;
        let v = if c & 512 != 0 { -mag } else { mag };
        q[i] = v;
        sum += v * v;
        c >>= 10;
    }
    q[largest] = (1.0 - sum).max(0.0).sqrt();
    [q[3], q[0], q[1], q[2]]
}

/// Extension records: `[u32 type][u32 length][payload]`, unknown types skipped.
fn read_labels(
    b: &mut Builder,
    mut ext: &[u8],
    points: usize,
    file: &str,
) -> Result<(), SplatError> {
    while ext.len() >= 8 {
        let (kind, len) = (u32_at(ext, 0), u32_at(ext, 4) as usize);
        let Some(payload) = ext.get(8..8 + len) else {
            return Err(damaged(
                file,
                format!("extension record {kind:#x} runs past the end"),
            ));
        };
        if kind == LABELS_EXTENSION {
            let (labels, names) = parse_labels(payload, points)
                .ok_or_else(|| damaged(file, "the labels extension record is malformed"))?;
            // Labels of Gaussians the builder skipped cannot be matched any more.
            if b.cloud.len() == points {
                b.cloud.labels = labels;
                b.cloud.label_names = names;
            }
        }
        ext = &ext[8 + len..];
    }
    Ok(())
}

fn parse_labels(p: &[u8], points: usize) -> Option<(Vec<u16>, Vec<String>)> {
    let count = u32::from_le_bytes(p.get(0..4)?.try_into().ok()?) as usize;
    let mut at = 4;
    let mut names = Vec::with_capacity(count.min(1024));
    for _ in 0..count {
        let len = usize::from(u16::from_le_bytes(p.get(at..at + 2)?.try_into().ok()?));
        names.push(String::from_utf8(p.get(at + 2..at + 2 + len)?.to_vec()).ok()?);
        at += 2 + len;
    }
    let ids = p.get(at..at + 2 * points)?;
    let labels: Vec<u16> = ids
        .chunks_exact(2)
        .map(|c| u16::from_le_bytes([c[0], c[1]]))
        .collect();
    labels
        .iter()
        .all(|&l| l == NO_LABEL || usize::from(l) < names.len())
        .then_some((labels, names))
}

mod write;
#[cfg(test)]
use write::smallest_three_encode;
pub use write::write;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn smallest_three_round_trips() {
        assert_eq!(smallest_three_encode([1.0, 0.0, 0.0, 0.0]), 0xC000_0000);
        for q in [
            [0.9f32, 0.1, -0.3, 0.2],
            [-0.2, 0.7, 0.1, -0.6],
            [0.1, -0.2, -0.9, 0.3],
        ] {
            let d = smallest_three_decode(smallest_three_encode(q));
            let n = q.iter().map(|c| c * c).sum::<f32>().sqrt();
            let dot: f32 = q.iter().zip(d).map(|(a, b)| a / n * b).sum();
            assert!(dot.abs() > 0.9999, "{q:?} -> {d:?}");
        }
    }
}
