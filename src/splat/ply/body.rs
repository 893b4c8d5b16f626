//! PLY bodies: binary little-endian decoded from byte offsets, ASCII tokenised here.

use ply_rs_bw::ply::{ElementDef, PropertyType};

use super::decode::{decode, Layout, Scalar};
use super::PlyError;
use crate::splat::GaussianCloud;

// ---------------------------------------------------------------------------------------
// Binary little-endian

pub(super) fn read_binary_body(
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

// Over 80 lines on purpose: a tokenizer loop with each field's error where the field is read.
pub(super) fn read_ascii_body(
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
