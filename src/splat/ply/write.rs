//! Writing 3DGS PLY files: the standard property set, binary or ASCII, with labels.

use std::fmt::Write as _;
use std::path::Path;

use glam::Vec3;
use rayon::prelude::*;

use super::decode::MAX_VALUES;
use super::{PlyError, PlyFormat};
use crate::splat::{sh_coeff_count, GaussianCloud};

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
// Over 80 lines on purpose: the header and then the body, in the file's property order.
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
    let names = super::decode::gaussian_properties(true, rest);
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
