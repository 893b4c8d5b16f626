//! Decoding vertices, shared by both body encodings: which properties hold the 3DGS
//! values, their activation, skipping of broken Gaussians and region labels.

use glam::{Quat, Vec3};
use ply_rs_bw::ply::{ElementDef, PropertyType, ScalarType};
use rayon::prelude::*;

use super::PlyError;
use crate::splat::{sh_coeff_count, GaussianCloud, NO_LABEL};

/// Scalar types, as a `Copy` enum.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Scalar {
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
    pub(super) fn of(t: &ScalarType) -> Scalar {
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

    pub(super) fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// Decode one little-endian value at the start of `b` (which holds at least `size()` bytes).
    #[inline(always)]
    pub(super) fn read_le(self, b: &[u8]) -> f64 {
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
pub(super) const MAX_VALUES: usize = 64;

/// The 3DGS vertex properties in their standard order: `x y z`, with `normals` also
/// `nx ny nz`, then `f_dc_0..2`, `rest` × `f_rest_*`, `opacity`, `scale_0..2`, `rot_0..3`.
pub(super) fn gaussian_properties(normals: bool, rest: usize) -> Vec<String> {
    let normal: &[&str] = if normals { &["nx", "ny", "nz"] } else { &[] };
    let mut names: Vec<String> = ["x", "y", "z"]
        .iter()
        .chain(normal)
        .chain(&["f_dc_0", "f_dc_1", "f_dc_2"])
        .map(|s| s.to_string())
        .collect();
    names.extend((0..rest).map(|j| format!("f_rest_{j}")));
    let tail = [
        "opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2", "rot_3",
    ];
    names.extend(tail.iter().map(|s| s.to_string()));
    names
}

/// Which vertex properties hold the values we need, in canonical order:
/// `x y z | f_dc_0..2 | f_rest_0..R−1 | opacity | scale_0..2 | rot_0..3 | [nx ny nz]`.
pub(super) struct Layout {
    degree: u32,
    /// Number of `f_rest_*` values, R = 3·(K − 1).
    rest: usize,
    has_normals: bool,
    /// Whether a scalar property gives region labels, and its name (`label` or `segment`
    /// unless the reader was told another).
    has_label: bool,
    label_name: String,
    /// Property index (within the `vertex` element) of each needed value.
    pub(super) props: Vec<usize>,
}

impl Layout {
    /// The layout of `def`, its region labels from the scalar property `labels` when given
    /// (an error when the file has no such property), else from `label` or `segment`.
    pub(super) fn new(
        def: &ElementDef,
        file: &str,
        labels: Option<&str>,
    ) -> Result<Layout, PlyError> {
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
        let mut names = gaussian_properties(false, rest);
        let normal_idx: Vec<Option<usize>> =
            ["nx", "ny", "nz"].iter().map(|n| index_of(n)).collect();
        let has_normals = normal_idx.iter().all(|i| {
            i.is_some_and(|i| matches!(def.properties[i].data_type, PropertyType::Scalar(_)))
        });
        if has_normals {
            names.extend(["nx", "ny", "nz"].iter().map(|s| s.to_string()));
        }
        // Region labels, last: the property asked for, else `label`, else `segment` (a list
        // property is not a label).
        let scalar = |n: &str| {
            index_of(n)
                .is_some_and(|i| matches!(def.properties[i].data_type, PropertyType::Scalar(_)))
        };
        let label = match labels {
            Some(n) if scalar(n) => Some(n),
            Some(n) => {
                let others: Vec<&str> = def
                    .properties
                    .keys()
                    .map(String::as_str)
                    .filter(|k| scalar(k) && !names.iter().any(|m| m == k))
                    .collect();
                return Err(PlyError::Invalid {
                    file: file.to_string(),
                    what: format!("no scalar vertex property `{n}` for the labels"),
                    expected: if others.is_empty() {
                        "a property of that name (this file has no scalar properties beyond the 3DGS ones)".to_string()
                    } else {
                        format!(
                            "one of the file's other scalar properties: {}",
                            others.join(", ")
                        )
                    },
                });
            }
            None => ["label", "segment"].into_iter().find(|n| scalar(n)),
        };
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
            label_name: label.unwrap_or_default().to_string(),
            props,
        })
    }

    pub(super) fn value_count(&self) -> usize {
        self.props.len()
    }
}

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
    let r = lay.rest;
    let o = 6 + r;
    // The opacity logit may be ±inf: fully opaque or fully transparent (a converter's
    // honest answer for an 8-bit alpha of 255 or 0). Only NaN is broken there.
    let broken = |(j, x): (usize, &f64)| {
        let x = *x as f32;
        if j == o {
            x.is_nan()
        } else {
            !x.is_finite()
        }
    };
    if v.iter().enumerate().any(broken) {
        return Verdict::NonFinite;
    }
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
// Over 80 lines on purpose: the parallel chunks, the skip counts and the compaction share the
// chunks' state.
pub(super) fn decode<G>(
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
    (cloud.labels, cloud.label_names) = label_ids(&raw_labels, &lay.label_name, file)?;
    Ok((cloud, nonfinite, degenerate))
}

/// Map raw label values (integers in any numeric type) to dense ids, numbered in
/// increasing value order and named by the value (`"3"`, `"-1"`).
fn label_ids(raw: &[f64], property: &str, file: &str) -> Result<(Vec<u16>, Vec<String>), PlyError> {
    if let Some(v) = raw.iter().find(|v| !(v.fract() == 0.0 && v.abs() < 9.0e15)) {
        return Err(PlyError::Invalid {
            file: file.to_string(),
            what: format!("vertex label {v}"),
            expected: format!("integer labels (property `{property}`)"),
        });
    }
    let mut values: Vec<i64> = raw.iter().map(|&v| v as i64).collect();
    values.sort_unstable();
    values.dedup();
    if values.len() >= usize::from(NO_LABEL) {
        return Err(PlyError::Invalid {
            file: file.to_string(),
            what: format!("{} distinct vertex labels", values.len()),
            expected: format!("at most {} distinct labels", NO_LABEL - 1),
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
pub(super) fn name_labels(cloud: &mut GaussianCloud, comments: &[String]) {
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
    if values.len() >= usize::from(NO_LABEL) {
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
