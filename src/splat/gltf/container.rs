//! The glTF container: a GLB (a 12-byte header, a JSON chunk, an optional BIN chunk) or a
//! `.gltf` JSON file whose buffers are base64 data URIs or files beside it.

use std::borrow::Cow;
use std::path::Path;

use serde_json::Value;

use super::super::codec::{Format, SplatError};

pub const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// The JSON and the bytes of each buffer.
pub struct Document<'a> {
    pub json: Value,
    pub buffers: Vec<Cow<'a, [u8]>>,
    /// `GLB` or `glTF JSON`.
    pub kind: &'static str,
}

pub fn damaged(file: &str, what: impl Into<String>) -> SplatError {
    SplatError::Damaged {
        file: file.to_string(),
        format: Format::Gltf,
        what: what.into(),
    }
}

fn u32_at(b: &[u8], o: usize) -> u32 {
    u32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]])
}

/// Open a GLB or a `.gltf` file (`path` locates the buffers of a `.gltf`).
pub fn open<'a>(bytes: &'a [u8], path: &Path, file: &str) -> Result<Document<'a>, SplatError> {
    if bytes.starts_with(GLB_MAGIC) {
        return open_glb(bytes, file);
    }
    let json = parse_json(bytes, file, "the file")?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let buffers = buffer_list(&json, file)?
        .iter()
        .enumerate()
        .map(|(i, b)| external_buffer(b, i, dir, file).map(Cow::Owned))
        .collect::<Result<_, _>>()?;
    Ok(Document {
        json,
        buffers,
        kind: "glTF JSON",
    })
}

fn parse_json(bytes: &[u8], file: &str, what: &str) -> Result<Value, SplatError> {
    let json: Value = serde_json::from_slice(bytes)
        .map_err(|e| damaged(file, format!("{what} is not valid JSON: {e}")))?;
    if !json.is_object() {
        return Err(damaged(file, format!("{what} is not a JSON object")));
    }
    Ok(json)
}

fn buffer_list<'j>(json: &'j Value, file: &str) -> Result<&'j [Value], SplatError> {
    match json.get("buffers") {
        None => Ok(&[]),
        Some(Value::Array(a)) => Ok(a),
        Some(other) => Err(damaged(
            file,
            format!("`buffers` is {other}, expected an array"),
        )),
    }
}

/// The chunks of a GLB: the JSON, and the BIN chunk as buffer 0 when buffer 0 has no URI.
// Over 80 lines on purpose: the GLB's chunks in file order, each checked where it is read.
fn open_glb<'a>(bytes: &'a [u8], file: &str) -> Result<Document<'a>, SplatError> {
    if bytes.len() < 20 {
        return Err(damaged(
            file,
            format!(
                "truncated: {} bytes, a GLB needs at least 20 (header and first chunk header)",
                bytes.len()
            ),
        ));
    }
    let version = u32_at(bytes, 4);
    if version != 2 {
        return Err(SplatError::Unsupported {
            file: file.to_string(),
            format: Format::Gltf,
            what: format!("GLB version {version}"),
            expected: "GLB version 2",
        });
    }
    let length = u32_at(bytes, 8) as usize;
    if length > bytes.len() {
        return Err(damaged(
            file,
            format!(
                "truncated: the GLB header says {length} bytes, the file has {}",
                bytes.len()
            ),
        ));
    }
    let bytes = &bytes[..length];
    let mut chunks = Vec::new();
    let mut at = 12;
    while at < bytes.len() {
        if bytes.len() - at < 8 {
            return Err(damaged(
                file,
                format!("a chunk header at byte {at} is cut short"),
            ));
        }
        let (len, kind) = (u32_at(bytes, at) as usize, u32_at(bytes, at + 4));
        let start = at + 8;
        if len > bytes.len() - start {
            return Err(damaged(
                file,
                format!(
                    "truncated: the chunk at byte {at} says {len} bytes, {} are left",
                    bytes.len() - start
                ),
            ));
        }
        chunks.push((kind, &bytes[start..start + len]));
        at = start + len.next_multiple_of(4).min(bytes.len() - start);
    }
    let Some(&(CHUNK_JSON, json_bytes)) = chunks.first() else {
        return Err(damaged(file, "the first GLB chunk is not the JSON chunk"));
    };
    let json = parse_json(json_bytes, file, "the JSON chunk")?;
    let bin = chunks.iter().find(|(k, _)| *k == CHUNK_BIN).map(|c| c.1);
    let mut buffers = Vec::new();
    for (i, b) in buffer_list(&json, file)?.iter().enumerate() {
        if i == 0 && b.get("uri").is_none() {
            let Some(bin) = bin else {
                return Err(damaged(
                    file,
                    "buffer 0 has no URI and the GLB has no BIN chunk",
                ));
            };
            buffers.push(Cow::Borrowed(bin));
        } else {
            return Err(SplatError::Unsupported {
                file: file.to_string(),
                format: Format::Gltf,
                what: format!("buffer {i} outside the GLB"),
                expected: "a GLB whose only buffer is its BIN chunk",
            });
        }
    }
    Ok(Document {
        json,
        buffers,
        kind: "GLB",
    })
}

/// A `.gltf` buffer: a base64 data URI, or a file relative to the `.gltf`.
fn external_buffer(b: &Value, i: usize, dir: &Path, file: &str) -> Result<Vec<u8>, SplatError> {
    let Some(uri) = b.get("uri").and_then(Value::as_str) else {
        return Err(damaged(file, format!("buffer {i} has no `uri`")));
    };
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((_, data)) = rest.split_once(";base64,") else {
            return Err(damaged(
                file,
                format!("buffer {i}: a data URI that is not base64"),
            ));
        };
        return decode_base64(data).ok_or_else(|| {
            damaged(
                file,
                format!("buffer {i}: the data URI is not valid base64"),
            )
        });
    }
    if uri.contains("://") {
        return Err(SplatError::Unsupported {
            file: file.to_string(),
            format: Format::Gltf,
            what: format!("buffer {i} at {uri:?}"),
            expected: "a data URI or a file beside the .gltf",
        });
    }
    let path = dir.join(percent_decode(uri));
    std::fs::read(&path).map_err(|source| SplatError::Io {
        file: format!("{file}: buffer {i} ({})", path.display()),
        action: "read the buffer",
        source,
    })
}

/// `%20` and the like in a relative URI.
fn percent_decode(uri: &str) -> String {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        match (
            b[i],
            b.get(i + 1).copied().and_then(hex),
            b.get(i + 2).copied().and_then(hex),
        ) {
            (b'%', Some(h), Some(l)) => {
                out.push((h * 16 + l) as u8);
                i += 3;
            }
            (c, _, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Standard base64 (padding optional), or None on a character outside the alphabet.
fn decode_base64(text: &str) -> Option<Vec<u8>> {
    let value = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    };
    let digits = text.trim_end_matches('=').as_bytes();
    let mut out = Vec::with_capacity(digits.len() * 3 / 4);
    for group in digits.chunks(4) {
        let mut acc = 0u32;
        for (j, &c) in group.iter().enumerate() {
            acc |= value(c)? << (18 - 6 * j);
        }
        let bytes = acc.to_be_bytes();
        match group.len() {
            4 => out.extend_from_slice(&bytes[1..4]),
            3 => out.extend_from_slice(&bytes[1..3]),
            2 => out.push(bytes[1]),
            _ => return None,
        }
    }
    Some(out)
}

/// A GLB of `json` and `bin`: each chunk padded to 4 bytes (JSON with spaces, BIN with
/// zeros), or None when it would pass the format's 4 GiB.
pub fn assemble_glb(json: &[u8], bin: &[u8]) -> Option<Vec<u8>> {
    let (json_len, bin_len) = (
        json.len().next_multiple_of(4),
        bin.len().next_multiple_of(4),
    );
    let bin_chunk = if bin.is_empty() { 0 } else { 8 + bin_len };
    let total = 12 + 8 + json_len + bin_chunk;
    let total32 = u32::try_from(total).ok()?;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(GLB_MAGIC);
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total32.to_le_bytes());
    out.extend_from_slice(&(json_len as u32).to_le_bytes());
    out.extend_from_slice(&CHUNK_JSON.to_le_bytes());
    out.extend_from_slice(json);
    out.resize(20 + json_len, b' ');
    if !bin.is_empty() {
        out.extend_from_slice(&(bin_len as u32).to_le_bytes());
        out.extend_from_slice(&CHUNK_BIN.to_le_bytes());
        out.extend_from_slice(bin);
        out.resize(total, 0);
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_and_percent_escapes_decode() {
        assert_eq!(decode_base64("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(decode_base64("aGVsbG8").unwrap(), b"hello");
        assert_eq!(decode_base64("AAECAw==").unwrap(), [0, 1, 2, 3]);
        assert_eq!(decode_base64("").unwrap(), b"");
        assert!(decode_base64("a?==").is_none());
        assert!(decode_base64("a").is_none());
        assert_eq!(percent_decode("my%20splats.bin"), "my splats.bin");
        assert_eq!(percent_decode("100%"), "100%");
    }

    #[test]
    fn a_glb_we_assemble_opens() {
        let glb = assemble_glb(br#"{"buffers":[{"byteLength":3}]}"#, &[1, 2, 3]).unwrap();
        assert_eq!(glb.len() % 4, 0);
        let doc = open(&glb, Path::new("x.glb"), "x.glb").unwrap();
        assert_eq!(&doc.buffers[0][..3], &[1, 2, 3]);
        let e = open(&glb[..glb.len() - 4], Path::new("x.glb"), "x.glb")
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("truncated"), "{e}");
    }
}
