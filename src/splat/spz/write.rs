//! Writing SPZ: the streams of version 3 (gzip) and 4 (zstd), the header, the labels'
//! extension record.

use super::*;

pub(super) fn smallest_three_encode(wxyz: [f32; 4]) -> u32 {
    let n = wxyz.iter().map(|c| c * c).sum::<f32>().sqrt().max(1e-30);
    let q = [wxyz[1] / n, wxyz[2] / n, wxyz[3] / n, wxyz[0] / n];
    let mut largest = 0;
    for i in 1..4 {
        if q[i].abs() > q[largest].abs() {
            largest = i;
        }
    }
    let negate = q[largest] < 0.0;
    let mut c = largest as u32;
    for (i, v) in q.iter().enumerate() {
        if i == largest {
            continue;
        }
        let sign = u32::from((*v < 0.0) != negate);
        let mag = (511.0 * v.abs() / std::f32::consts::FRAC_1_SQRT_2 + 0.5)
            .floor()
            .min(511.0) as u32;
        c = (c << 10) | (sign << 9) | mag;
    }
    c
}

fn labels_record(cloud: &GaussianCloud) -> Vec<u8> {
    if cloud.labels.is_empty() {
        return Vec::new();
    }
    let mut p = Vec::new();
    p.extend_from_slice(&(cloud.label_names.len() as u32).to_le_bytes());
    for name in &cloud.label_names {
        let bytes = &name.as_bytes()[..name.len().min(u16::MAX as usize)];
        p.extend_from_slice(&(bytes.len() as u16).to_le_bytes());
        p.extend_from_slice(bytes);
    }
    for l in &cloud.labels {
        p.extend_from_slice(&l.to_le_bytes());
    }
    let mut rec = Vec::with_capacity(p.len() + 8);
    rec.extend_from_slice(&LABELS_EXTENSION.to_le_bytes());
    rec.extend_from_slice(&(p.len() as u32).to_le_bytes());
    rec.extend_from_slice(&p);
    rec
}

/// Fractional bits for positions: 12 (Niantic's choice, ≈ 0.24 mm in metres) unless the
/// extent needs fewer to fit 24 bits.
fn fractional_bits(cloud: &GaussianCloud) -> u32 {
    let reach = cloud
        .positions
        .iter()
        .map(|p| p.abs().max_element())
        .fold(0.0f32, f32::max);
    let mut fb = 12u32;
    while fb > 0 && reach * (1u32 << fb) as f32 >= 8_388_607.0 {
        fb -= 1;
    }
    fb
}

/// The six attribute streams of `cloud` (version 3 and 4 layout).
fn encode_streams(cloud: &GaussianCloud, fb: u32) -> [Vec<u8>; 6] {
    let n = cloud.len();
    let dim = sh_coeff_count(cloud.sh_degree) - 1;
    let scale = (1u32 << fb) as f32;
    let pos: Vec<u8> = cloud
        .positions
        .par_iter()
        .flat_map_iter(|p| {
            p.to_array().into_iter().flat_map(move |v| {
                let q = (v * scale).round().clamp(-8_388_608.0, 8_388_607.0) as i32;
                [q as u8, (q >> 8) as u8, (q >> 16) as u8]
            })
        })
        .collect();
    let alpha: Vec<u8> = cloud.opacities.iter().map(|o| to_u8(o * 255.0)).collect();
    let mut color = Vec::with_capacity(n * 3);
    let mut sh = Vec::with_capacity(n * dim * 3);
    for i in 0..n {
        let c = cloud.sh_of(i);
        color.extend(
            c[..3]
                .iter()
                .map(|v| to_u8(v * COLOR_SCALE * 255.0 + 127.5)),
        );
        for (j, v) in c[3..].iter().enumerate() {
            // Degree-1 coefficients keep 5 bits, the rest 4 (as Niantic's writer): the
            // buckets cost little precision and compress much better.
            let bucket = if j < 9 { 8 } else { 16 };
            let q = (v * 128.0).round() as i32 + 128;
            sh.push((((q + bucket / 2) / bucket) * bucket).clamp(0, 255) as u8);
        }
    }
    let scales: Vec<u8> = cloud
        .scales
        .iter()
        .flat_map(|s| s.to_array().map(|v| to_u8((v.ln() + 10.0) * 16.0)))
        .collect();
    let rot: Vec<u8> = cloud
        .rotations
        .iter()
        .flat_map(|q| smallest_three_encode([q.w, q.x, q.y, q.z]).to_le_bytes())
        .collect();
    [pos, alpha, color, scales, rot, sh]
}

/// The 16 bytes every version starts with; `last` is reserved (versions 1–3) or the
/// stream count (version 4).
fn header_bytes(cloud: &GaussianCloud, version: u32, fb: u32, flags: u8, last: u8) -> Vec<u8> {
    let mut h = Vec::with_capacity(32);
    h.extend_from_slice(&MAGIC.to_le_bytes());
    h.extend_from_slice(&version.to_le_bytes());
    h.extend_from_slice(&(cloud.len() as u32).to_le_bytes());
    h.extend_from_slice(&[cloud.sh_degree as u8, fb as u8, flags, last]);
    h
}

/// Encode `cloud` as SPZ. The header's antialiased flag (Mip-Splatting captures) is not set:
/// the cloud does not record it, and our renderer draws every capture the same way.
pub fn write(cloud: &GaussianCloud, version: SpzVersion) -> Vec<u8> {
    let fb = fractional_bits(cloud);
    let streams = encode_streams(cloud, fb);
    let ext = labels_record(cloud);
    let flags = if ext.is_empty() { 0 } else { FLAG_EXTENSIONS };
    match version {
        SpzVersion::V3 => {
            use std::io::Write;
            let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
            let mut all = header_bytes(cloud, 3, fb, flags, 0);
            for s in &streams {
                all.extend_from_slice(s);
            }
            all.extend_from_slice(&ext);
            gz.write_all(&all).expect("writing to memory");
            gz.finish().expect("writing to memory")
        }
        SpzVersion::V4 => {
            let kept: Vec<&Vec<u8>> = streams.iter().filter(|s| !s.is_empty()).collect();
            let packed: Vec<Vec<u8>> = kept
                .par_iter()
                .map(|s| {
                    ruzstd::encoding::compress_to_vec(
                        &s[..],
                        ruzstd::encoding::CompressionLevel::Fastest,
                    )
                })
                .collect();
            let mut out = header_bytes(cloud, 4, fb, flags, kept.len() as u8);
            out.extend_from_slice(&((32 + ext.len()) as u32).to_le_bytes());
            out.extend_from_slice(&[0u8; 12]);
            out.extend_from_slice(&ext);
            for (p, s) in packed.iter().zip(&kept) {
                out.extend_from_slice(&(p.len() as u64).to_le_bytes());
                out.extend_from_slice(&(s.len() as u64).to_le_bytes());
            }
            for p in &packed {
                out.extend_from_slice(p);
            }
            out
        }
    }
}
