//! Reading Gaussians out of a glTF: the splat primitives of every mesh the scene places
//! (each with its node's transform), decoded from their attributes or from an SPZ payload,
//! then turned into the frame PLY files hold (see the module above).

use std::path::Path;

use glam::{Mat4, Quat, Vec3};
use serde_json::{Map, Value};

use super::accessor::{
    accessor, item, view_bytes, Allowed, BYTE, FLOAT, FLOAT_ONLY, SHORT, UNSIGNED_BYTE,
    UNSIGNED_INT, UNSIGNED_SHORT,
};
use super::container::{damaged, open, Document};
use super::{
    half_turn, sh_attribute, Axis, EXTENSION, LABEL_ATTRIBUTE, OPACITY, ROTATION, SCALE,
    SPZ_EXTENSIONS,
};
use crate::splat::codec::{Builder, Decoded, Format, SplatError};
use crate::splat::sh::ShRotator;
use crate::splat::{sh_coeff_count, spz, GaussianCloud, NO_LABEL};

mod merge;
use merge::merge;

const ROTATION_TYPES: &[Allowed] = &[(FLOAT, false), (BYTE, true), (SHORT, true)];
const SCALE_TYPES: &[Allowed] = &[
    (FLOAT, false),
    (UNSIGNED_BYTE, false),
    (UNSIGNED_BYTE, true),
    (UNSIGNED_SHORT, false),
    (UNSIGNED_SHORT, true),
];
const OPACITY_TYPES: &[Allowed] = &[
    (FLOAT, false),
    (UNSIGNED_BYTE, true),
    (UNSIGNED_SHORT, true),
];
const LABEL_TYPES: &[Allowed] = &[
    (UNSIGNED_BYTE, false),
    (UNSIGNED_SHORT, false),
    (UNSIGNED_INT, false),
];

/// Read the Gaussians of a `.glb` or `.gltf` (`path` locates a `.gltf`'s buffers). Returns
/// them in the PLY frame, and the variant (`GLB`, `glTF JSON, SPZ-compressed`, …).
pub fn read(bytes: &[u8], path: &Path, file: &str) -> Result<(Builder, String), SplatError> {
    let doc = open(bytes, path, file)?;
    check_required_extensions(&doc.json, file)?;
    let meshes = splat_primitives(&doc.json);
    if meshes.iter().all(Vec::is_empty) {
        return no_splats(&doc.json, file).map(|b| (b, doc.kind.to_string()));
    }
    let mut parts = Vec::new();
    let mut compressed = false;
    let mut rotator = None;
    for (mesh, transform) in instances(&doc.json, &meshes, file)? {
        for &(p, prim) in &meshes[mesh] {
            let what = format!("mesh {mesh} primitive {p}");
            let (mut b, spz) = decode_primitive(&doc, prim, &what, file)?;
            compressed |= spz;
            if transform != Mat4::IDENTITY {
                let rotator = rotator.get_or_insert_with(ShRotator::new);
                place(&mut b.cloud, transform, rotator, &what, file)?;
            }
            parts.push(b);
        }
    }
    let count = parts.len();
    let mut b = merge(parts);
    half_turn(&mut b.cloud, Axis::Z);
    let mut variant = doc.kind.to_string();
    if compressed {
        variant.push_str(", SPZ-compressed");
    }
    if count > 1 {
        variant.push_str(&format!(", {count} primitives"));
    }
    Ok((b, variant))
}

/// Extensions a reader must know to read the file at all.
fn check_required_extensions(json: &Value, file: &str) -> Result<(), SplatError> {
    let required = json.get("extensionsRequired").and_then(Value::as_array);
    for name in required.into_iter().flatten().filter_map(Value::as_str) {
        if name != EXTENSION && !SPZ_EXTENSIONS.contains(&name) {
            return Err(SplatError::Unsupported {
                file: file.to_string(),
                format: Format::Gltf,
                what: format!("required extension {name}"),
                expected: "KHR_gaussian_splatting, optionally with its SPZ compression",
            });
        }
    }
    Ok(())
}

/// Each mesh's primitives that carry the extension: (primitive index, primitive).
fn splat_primitives(json: &Value) -> Vec<Vec<(usize, &Value)>> {
    let meshes = json.get("meshes").and_then(Value::as_array);
    meshes
        .into_iter()
        .flatten()
        .map(|m| {
            let prims = m.get("primitives").and_then(Value::as_array);
            prims
                .into_iter()
                .flatten()
                .enumerate()
                .filter(|(_, p)| splat_extension(p).is_some())
                .collect()
        })
        .collect()
}

fn splat_extension(prim: &Value) -> Option<&Value> {
    prim.get("extensions")?.get(EXTENSION)
}

/// A file without splat primitives: empty when it declares the extension and has no mesh
/// at all (what we write for an empty cloud), else not a splat file.
fn no_splats(json: &Value, file: &str) -> Result<Builder, SplatError> {
    let used: Vec<&str> = json
        .get("extensionsUsed")
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .filter_map(Value::as_str)
        .collect();
    let meshes = json
        .get("meshes")
        .and_then(Value::as_array)
        .map_or(0, Vec::len);
    if meshes == 0 && used.contains(&EXTENSION) {
        return Ok(Builder::new(0, 0));
    }
    let used = if used.is_empty() {
        "none".to_string()
    } else {
        used.join(", ")
    };
    Err(SplatError::Unsupported {
        file: file.to_string(),
        format: Format::Gltf,
        what: format!(
            "file without KHR_gaussian_splatting (no primitive of its {meshes} mesh(es) has the extension; extensionsUsed: {used})"
        ),
        expected: "Gaussian splats: a POINTS primitive with the KHR_gaussian_splatting extension",
    })
}

/// The meshes the scene places, with each node's global transform. A file without nodes
/// (or whose nodes place no splat mesh) has its splat meshes read where they are.
fn instances(
    json: &Value,
    meshes: &[Vec<(usize, &Value)>],
    file: &str,
) -> Result<Vec<(usize, Mat4)>, SplatError> {
    let nodes: &[Value] = json
        .get("nodes")
        .and_then(Value::as_array)
        .map_or(&[], |v| v);
    let mut out = Vec::new();
    let mut seen = vec![false; nodes.len()];
    let mut stack: Vec<(u64, Mat4)> = roots(json, nodes)
        .into_iter()
        .map(|n| (n, Mat4::IDENTITY))
        .collect();
    while let Some((index, parent)) = stack.pop() {
        let Some(node) = usize::try_from(index).ok().and_then(|i| nodes.get(i)) else {
            return Err(damaged(file, format!("node {index} does not exist")));
        };
        if std::mem::replace(&mut seen[index as usize], true) {
            return Err(damaged(
                file,
                format!("node {index} appears twice in the node hierarchy"),
            ));
        }
        let global = parent * local_transform(node, index, file)?;
        if let Some(mesh) = node.get("mesh").and_then(Value::as_u64) {
            if meshes.get(mesh as usize).is_some_and(|m| !m.is_empty()) {
                out.push((mesh as usize, global));
            }
        }
        let children = node.get("children").and_then(Value::as_array);
        for c in children.into_iter().flatten().rev() {
            stack.push((c.as_u64().unwrap_or(u64::MAX), global));
        }
    }
    out.reverse();
    if out.is_empty() {
        out = (0..meshes.len())
            .filter(|&m| !meshes[m].is_empty())
            .map(|m| (m, Mat4::IDENTITY))
            .collect();
    }
    Ok(out)
}

/// The scene's root nodes: those of `scene` (else of the first scene), else every node
/// that is no other node's child. Listed last first, for a stack.
fn roots(json: &Value, nodes: &[Value]) -> Vec<u64> {
    let scene = json.get("scene").and_then(Value::as_u64).unwrap_or(0);
    let listed = item(json, "scenes", scene).and_then(|s| s.get("nodes")?.as_array());
    let mut roots: Vec<u64> = match listed {
        Some(list) => list
            .iter()
            .map(|n| n.as_u64().unwrap_or(u64::MAX))
            .collect(),
        None => {
            let children: Vec<u64> = nodes
                .iter()
                .filter_map(|n| n.get("children")?.as_array())
                .flatten()
                .filter_map(Value::as_u64)
                .collect();
            (0..nodes.len() as u64)
                .filter(|i| !children.contains(i))
                .collect()
        }
    };
    roots.reverse();
    roots
}

/// A node's `matrix`, or its `translation`, `rotation` and `scale`.
fn local_transform(node: &Value, index: u64, file: &str) -> Result<Mat4, SplatError> {
    let numbers = |key: &str, len: usize| -> Result<Option<Vec<f32>>, SplatError> {
        let Some(v) = node.get(key) else {
            return Ok(None);
        };
        let values: Option<Vec<f32>> = v
            .as_array()
            .filter(|a| a.len() == len)
            .map(|a| {
                a.iter()
                    .filter_map(Value::as_f64)
                    .map(|x| x as f32)
                    .collect()
            })
            .filter(|a: &Vec<f32>| a.len() == len && a.iter().all(|x| x.is_finite()));
        values.map(Some).ok_or_else(|| {
            damaged(
                file,
                format!("node {index}: `{key}` is not {len} finite numbers"),
            )
        })
    };
    if let Some(m) = numbers("matrix", 16)? {
        return Ok(Mat4::from_cols_slice(&m));
    }
    let t = numbers("translation", 3)?.map_or(Vec3::ZERO, |v| Vec3::from_slice(&v));
    let r = numbers("rotation", 4)?.map_or(Quat::IDENTITY, |v| Quat::from_slice(&v).normalize());
    let s = numbers("scale", 3)?.map_or(Vec3::ONE, |v| Vec3::from_slice(&v));
    Ok(Mat4::from_scale_rotation_translation(s, r, t))
}

/// Apply a node's transform to its Gaussians: a rotation, a uniform positive scale and a
/// translation (a Gaussian under an uneven scale or a mirror has no scale and rotation of
/// this form, and the extension leaves it undefined).
fn place(
    cloud: &mut GaussianCloud,
    m: Mat4,
    rotator: &ShRotator,
    what: &str,
    file: &str,
) -> Result<(), SplatError> {
    let (s, r, t) = m.to_scale_rotation_translation();
    let uniform =
        s.min_element() > 0.0 && s.max_element() - s.min_element() <= 1e-5 * s.max_element();
    if !uniform || !r.is_finite() {
        return Err(SplatError::Unsupported {
            file: file.to_string(),
            format: Format::Gltf,
            what: format!(
                "node transform of {what} with scale [{}, {}, {}]",
                s.x, s.y, s.z
            ),
            expected: "a rotation, a translation and a uniform positive scale",
        });
    }
    let scale = s.x;
    for p in &mut cloud.positions {
        *p = r * (*p * scale) + t;
    }
    for n in &mut cloud.normals {
        *n = r * *n;
    }
    for q in &mut cloud.rotations {
        *q = (r * *q).normalize();
    }
    for sc in &mut cloud.scales {
        *sc *= scale;
    }
    let stride = cloud.sh_stride();
    if cloud.sh_degree > 0 {
        for coeffs in cloud.sh.chunks_exact_mut(stride) {
            let turned = rotator.to_world(cloud.sh_degree, coeffs, r.as_dquat());
            coeffs.copy_from_slice(&turned);
        }
    }
    Ok(())
}

/// The Gaussians of one primitive (in glTF's frame), and whether they came from SPZ.
fn decode_primitive(
    doc: &Document<'_>,
    prim: &Value,
    what: &str,
    file: &str,
) -> Result<(Builder, bool), SplatError> {
    let mode = prim.get("mode").and_then(Value::as_u64).unwrap_or(4);
    if mode != 0 {
        return Err(damaged(
            file,
            format!("{what}: mode {mode}, expected 0 (POINTS), as KHR_gaussian_splatting requires"),
        ));
    }
    let empty = Map::new();
    let attributes = prim
        .get("attributes")
        .and_then(Value::as_object)
        .unwrap_or(&empty);
    let spz = splat_extension(prim)
        .and_then(|e| e.get("extensions"))
        .and_then(|e| {
            SPZ_EXTENSIONS
                .iter()
                .find_map(|n| e.get(*n).map(|v| (*n, v)))
        });
    if let Some((name, ext)) = spz {
        return decode_spz(doc, attributes, name, ext, what, file).map(|b| (b, true));
    }
    decode_attributes(doc, prim, attributes, what, file).map(|b| (b, false))
}

/// An attribute's accessor index, or an error naming the attribute the extension requires.
fn required(
    attributes: &Map<String, Value>,
    name: &str,
    what: &str,
    file: &str,
) -> Result<u64, SplatError> {
    attributes.get(name).and_then(Value::as_u64).ok_or_else(|| {
        damaged(
            file,
            format!("{what}: no {name} attribute (KHR_gaussian_splatting requires it)"),
        )
    })
}

/// The uncompressed form: one accessor per attribute.
fn decode_attributes(
    doc: &Document<'_>,
    prim: &Value,
    attributes: &Map<String, Value>,
    what: &str,
    file: &str,
) -> Result<Builder, SplatError> {
    let degree = sh_degree(attributes, what, file)?;
    let read = |name: &str, components: usize, allowed: &[Allowed], n: Option<usize>| {
        let index = required(attributes, name, what, file)?;
        let a = accessor(
            doc,
            index,
            &format!("{what}: {name}"),
            components,
            allowed,
            file,
        )?;
        match n {
            Some(n) if a.count != n => Err(damaged(
                file,
                format!(
                    "{what}: {name} (accessor {index}) has {} elements, POSITION has {n}",
                    a.count
                ),
            )),
            _ => Ok((a.floats(), a.count)),
        }
    };
    let (position, count) = read("POSITION", 3, FLOAT_ONLY, None)?;
    let n = Some(count);
    let rotation = read(ROTATION, 4, ROTATION_TYPES, n)?.0;
    let scale = read(SCALE, 3, SCALE_TYPES, n)?.0;
    let opacity = read(OPACITY, 1, OPACITY_TYPES, n)?.0;
    let mut coefficients = vec![read(&sh_attribute(0, 0), 3, FLOAT_ONLY, n)?.0];
    for l in 1..=degree {
        for c in 0..2 * l + 1 {
            coefficients.push(read(&sh_attribute(l, c), 3, FLOAT_ONLY, n)?.0);
        }
    }
    let labels = labels(doc, prim, attributes, count, what, file)?;
    let mut b = Builder::new(count, degree);
    let mut sh = vec![0.0; sh_coeff_count(degree) * 3];
    let mut kept = Vec::new();
    for i in 0..count {
        for (k, c) in coefficients.iter().enumerate() {
            sh[k * 3..k * 3 + 3].copy_from_slice(&c[i * 3..i * 3 + 3]);
        }
        let before = b.cloud.len();
        let (r, s) = (&rotation[i * 4..i * 4 + 4], &scale[i * 3..i * 3 + 3]);
        b.push_linear(Decoded {
            position: [position[i * 3], position[i * 3 + 1], position[i * 3 + 2]],
            log_scale: [s[0], s[1], s[2]],
            // glTF's quaternions are x y z w; the builder's are w x y z.
            rotation: [r[3], r[0], r[1], r[2]],
            opacity: opacity[i],
            sh: &sh,
        });
        if let (Some((ids, _)), true) = (&labels, b.cloud.len() > before) {
            kept.push(ids[i]);
        }
    }
    if let Some((_, names)) = labels {
        b.cloud.labels = kept;
        b.cloud.label_names = names;
    }
    Ok(b)
}

/// The SH degree a primitive's attributes define: every coefficient of each degree up to
/// it, none above.
fn sh_degree(attributes: &Map<String, Value>, what: &str, file: &str) -> Result<u32, SplatError> {
    let known: Vec<String> = (0..=3)
        .flat_map(|l| (0..2 * l + 1).map(move |c| sh_attribute(l, c)))
        .collect();
    let prefix = "KHR_gaussian_splatting:SH_DEGREE_";
    if let Some(odd) = attributes
        .keys()
        .find(|k| k.starts_with(prefix) && !known.contains(k))
    {
        return Err(damaged(
            file,
            format!("{what}: attribute {odd} (expected SH degrees 0 to 3, COEF_0 to COEF_2l)"),
        ));
    }
    let present = |l: u32| {
        (0..2 * l + 1)
            .filter(|&c| attributes.contains_key(&sh_attribute(l, c)))
            .count() as u32
    };
    let degree = (1..=3).rev().find(|&l| present(l) > 0).unwrap_or(0);
    for l in 1..=degree {
        if present(l) != 2 * l + 1 {
            return Err(damaged(
                file,
                format!(
                    "{what}: SH degree {l} is partly defined ({} of its {} coefficients), and degree {degree} is present",
                    present(l),
                    2 * l + 1
                ),
            ));
        }
    }
    Ok(degree)
}

type Labels = Option<(Vec<u16>, Vec<String>)>;

/// Our label attribute and its names, when the primitive has them.
fn labels(
    doc: &Document<'_>,
    prim: &Value,
    attributes: &Map<String, Value>,
    n: usize,
    what: &str,
    file: &str,
) -> Result<Labels, SplatError> {
    let Some(index) = attributes.get(LABEL_ATTRIBUTE).and_then(Value::as_u64) else {
        return Ok(None);
    };
    let a = accessor(
        doc,
        index,
        &format!("{what}: {LABEL_ATTRIBUTE}"),
        1,
        LABEL_TYPES,
        file,
    )?;
    if a.count != n {
        return Err(damaged(
            file,
            format!(
                "{what}: {LABEL_ATTRIBUTE} (accessor {index}) has {} elements, POSITION has {n}",
                a.count
            ),
        ));
    }
    let names: Vec<String> = prim
        .get("extras")
        .and_then(|e| e.get(LABEL_ATTRIBUTE))
        .and_then(Value::as_array)
        .map(|a| {
            a.iter()
                .map(|v| v.as_str().unwrap_or_default().to_string())
                .collect()
        })
        .unwrap_or_default();
    let ids = a.integers();
    if let Some(bad) = ids.iter().find(|&&l| l as usize >= names.len()) {
        return Err(damaged(
            file,
            format!(
                "{what}: {LABEL_ATTRIBUTE} {bad} has no name (extras.{LABEL_ATTRIBUTE} names {})",
                names.len()
            ),
        ));
    }
    if names.len() >= usize::from(NO_LABEL) {
        return Err(damaged(
            file,
            format!("{what}: {} label names", names.len()),
        ));
    }
    Ok(Some((ids.into_iter().map(|l| l as u16).collect(), names)))
}

/// The SPZ form: the payload holds every attribute; the accessors only give the count.
/// SPZ keeps its own frame (x right, y up, z back), which the extension turns into glTF's
/// by a half turn about y (the spz library's `LUF` unpacking).
fn decode_spz(
    doc: &Document<'_>,
    attributes: &Map<String, Value>,
    name: &str,
    ext: &Value,
    what: &str,
    file: &str,
) -> Result<Builder, SplatError> {
    let Some(view) = ext.get("bufferView").and_then(Value::as_u64) else {
        return Err(damaged(file, format!("{what}: {name} has no bufferView")));
    };
    let payload = view_bytes(doc, view, file)?;
    let (mut b, _) = spz::read(payload, &format!("{file} ({what}, SPZ payload)"))?;
    let in_payload = b.cloud.len() + b.skipped_nonfinite + b.skipped_degenerate;
    let index = required(attributes, "POSITION", what, file)?;
    let count = item(&doc.json, "accessors", index)
        .and_then(|a| a.get("count"))
        .and_then(Value::as_u64);
    if count != Some(in_payload as u64) {
        return Err(damaged(
            file,
            format!(
                "{what}: POSITION (accessor {index}) has {} elements, the SPZ payload {in_payload} Gaussians",
                count.map_or("no count".into(), |c| c.to_string())
            ),
        ));
    }
    half_turn(&mut b.cloud, Axis::Y);
    Ok(b)
}
