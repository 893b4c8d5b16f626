//! glTF accessors: a typed view of a buffer view (component type, element type, count,
//! stride, `normalized`), checked against what an attribute allows and read as floats.

use serde_json::Value;

use super::super::codec::SplatError;
use super::container::{damaged, Document};

pub const BYTE: u64 = 5120;
pub const UNSIGNED_BYTE: u64 = 5121;
pub const SHORT: u64 = 5122;
pub const UNSIGNED_SHORT: u64 = 5123;
pub const UNSIGNED_INT: u64 = 5125;
pub const FLOAT: u64 = 5126;

/// A component type an attribute accepts: the glTF enum and whether it is `normalized`.
pub type Allowed = (u64, bool);

pub const FLOAT_ONLY: &[Allowed] = &[(FLOAT, false)];

/// The words for a component type.
pub fn component_name(c: u64) -> &'static str {
    match c {
        BYTE => "signed byte",
        UNSIGNED_BYTE => "unsigned byte",
        SHORT => "signed short",
        UNSIGNED_SHORT => "unsigned short",
        UNSIGNED_INT => "unsigned int",
        FLOAT => "float",
        _ => "unknown",
    }
}

fn describe(allowed: &[Allowed]) -> String {
    let names: Vec<String> = allowed
        .iter()
        .map(|&(c, n)| {
            let norm = if n { " normalized" } else { "" };
            format!("{}{norm}", component_name(c))
        })
        .collect();
    names.join(", ")
}

/// The bytes and layout of one accessor.
pub struct Accessor<'a> {
    bytes: &'a [u8],
    pub count: usize,
    components: usize,
    component_type: u64,
    normalized: bool,
    stride: usize,
}

/// The accessor of attribute `name` (index `index`), which must have `components` per
/// element (1 for SCALAR, 3 for VEC3, …) and one of the `allowed` component types. Its
/// bytes are checked to lie within its buffer view and buffer.
pub fn accessor<'a>(
    doc: &'a Document<'_>,
    index: u64,
    name: &str,
    components: usize,
    allowed: &[Allowed],
    file: &str,
) -> Result<Accessor<'a>, SplatError> {
    let what = format!("{name} (accessor {index})");
    let a = item(&doc.json, "accessors", index)
        .ok_or_else(|| damaged(file, format!("{what} does not exist")))?;
    let type_name = a.get("type").and_then(Value::as_str).unwrap_or("none");
    let expected_type = ["SCALAR", "VEC2", "VEC3", "VEC4"][components - 1];
    if type_name != expected_type {
        return Err(damaged(
            file,
            format!("{what}: type {type_name}, expected {expected_type}"),
        ));
    }
    let component_type = a.get("componentType").and_then(Value::as_u64).unwrap_or(0);
    let normalized = a
        .get("normalized")
        .and_then(Value::as_bool)
        .unwrap_or(false);
    if !allowed.contains(&(component_type, normalized)) {
        let norm = if normalized { " normalized" } else { "" };
        return Err(damaged(
            file,
            format!(
                "{what}: componentType {component_type} ({}{norm}), expected {}",
                component_name(component_type),
                describe(allowed)
            ),
        ));
    }
    if a.get("sparse").is_some() {
        return Err(damaged(
            file,
            format!("{what}: sparse accessors are not supported"),
        ));
    }
    let count = a
        .get("count")
        .and_then(Value::as_u64)
        .ok_or_else(|| damaged(file, format!("{what} has no `count`")))? as usize;
    let size = component_size(component_type);
    let element = size * components;
    let Some(view_index) = a.get("bufferView").and_then(Value::as_u64) else {
        return Err(damaged(file, format!("{what} has no `bufferView`")));
    };
    let view = view_bytes(doc, view_index, file)?;
    let stride = item(&doc.json, "bufferViews", view_index)
        .and_then(|v| v.get("byteStride"))
        .and_then(Value::as_u64)
        .map_or(element, |s| s as usize);
    let offset = a.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
    let needed = match count {
        0 => Some(offset),
        n => (n - 1)
            .checked_mul(stride)
            .and_then(|b| b.checked_add(offset)?.checked_add(element)),
    };
    match needed {
        Some(end) if stride >= element && end <= view.len() => Ok(Accessor {
            bytes: &view[offset.min(view.len())..],
            count,
            components,
            component_type,
            normalized,
            stride,
        }),
        _ => Err(damaged(
            file,
            format!(
                "{what}: {count} elements of {element} bytes (stride {stride}, offset {offset}) do not fit in bufferView {view_index} of {} bytes",
                view.len()
            ),
        )),
    }
}

fn component_size(c: u64) -> usize {
    match c {
        BYTE | UNSIGNED_BYTE => 1,
        SHORT | UNSIGNED_SHORT => 2,
        _ => 4,
    }
}

/// `json[array][index]`.
pub fn item<'j>(json: &'j Value, array: &str, index: u64) -> Option<&'j Value> {
    json.get(array)?
        .as_array()?
        .get(usize::try_from(index).ok()?)
}

/// The bytes of buffer view `index`, checked against its buffer.
pub fn view_bytes<'a>(
    doc: &'a Document<'_>,
    index: u64,
    file: &str,
) -> Result<&'a [u8], SplatError> {
    let v = item(&doc.json, "bufferViews", index)
        .ok_or_else(|| damaged(file, format!("bufferView {index} does not exist")))?;
    let buffer = v.get("buffer").and_then(Value::as_u64).unwrap_or(u64::MAX);
    let bytes = usize::try_from(buffer)
        .ok()
        .and_then(|b| doc.buffers.get(b))
        .ok_or_else(|| {
            damaged(
                file,
                format!("bufferView {index}: buffer {buffer} does not exist"),
            )
        })?;
    let offset = v.get("byteOffset").and_then(Value::as_u64).unwrap_or(0);
    let length = v.get("byteLength").and_then(Value::as_u64).unwrap_or(0);
    let end = offset.saturating_add(length);
    if end > bytes.len() as u64 {
        return Err(damaged(
            file,
            format!(
                "truncated: bufferView {index} needs bytes {offset}..{end} of buffer {buffer}, which holds {}",
                bytes.len()
            ),
        ));
    }
    Ok(&bytes[offset as usize..end as usize])
}

impl Accessor<'_> {
    /// Every element's components as floats (`count × components`), normalized integers
    /// mapped to [0, 1] or [−1, 1] as glTF defines.
    pub fn floats(&self) -> Vec<f32> {
        let mut out = Vec::with_capacity(self.count * self.components);
        let size = component_size(self.component_type);
        for i in 0..self.count {
            let e = &self.bytes[i * self.stride..];
            for c in 0..self.components {
                out.push(self.component(&e[c * size..c * size + size]));
            }
        }
        out
    }

    /// Every element's components as unsigned integers (labels).
    pub fn integers(&self) -> Vec<u32> {
        let size = component_size(self.component_type);
        (0..self.count)
            .map(|i| {
                let b = &self.bytes[i * self.stride..i * self.stride + size];
                match self.component_type {
                    UNSIGNED_BYTE => u32::from(b[0]),
                    UNSIGNED_SHORT => u32::from(u16::from_le_bytes([b[0], b[1]])),
                    _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                }
            })
            .collect()
    }

    fn component(&self, b: &[u8]) -> f32 {
        let n = self.normalized;
        match self.component_type {
            FLOAT => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            UNSIGNED_BYTE if n => f32::from(b[0]) / 255.0,
            UNSIGNED_BYTE => f32::from(b[0]),
            BYTE if n => (f32::from(b[0] as i8) / 127.0).max(-1.0),
            BYTE => f32::from(b[0] as i8),
            UNSIGNED_SHORT if n => f32::from(u16::from_le_bytes([b[0], b[1]])) / 65535.0,
            UNSIGNED_SHORT => f32::from(u16::from_le_bytes([b[0], b[1]])),
            SHORT if n => (f32::from(i16::from_le_bytes([b[0], b[1]])) / 32767.0).max(-1.0),
            SHORT => f32::from(i16::from_le_bytes([b[0], b[1]])),
            _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
        }
    }
}
