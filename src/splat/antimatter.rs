//! antimatter15 `.splat`: no header, 32 bytes per Gaussian (docs/formats.md): position
//! f32×3, linear scale f32×3, colour and opacity as RGBA bytes (colour = 0.5 + C0·DC,
//! alpha = sigmoid(logit)), and the rotation as bytes `w x y z` mapped by (q·128 + 128).
//! Only SH degree 0 fits; higher coefficients are dropped on writing.

use super::codec::{decode_parallel, to_u8, Builder, Decoded, Format, SplatError, SH_C0};
use super::GaussianCloud;

pub const RECORD: usize = 32;

pub fn read(bytes: &[u8], file: &str) -> Result<Builder, SplatError> {
    if !bytes.len().is_multiple_of(RECORD) {
        return Err(SplatError::Damaged {
            file: file.to_string(),
            format: Format::Splat,
            what: format!(
                "{} bytes is not a whole number of {RECORD}-byte records ({} records and {} bytes over)",
                bytes.len(),
                bytes.len() / RECORD,
                bytes.len() % RECORD
            ),
        });
    }
    let n = bytes.len() / RECORD;
    let f32_at = |r: &[u8], o: usize| f32::from_le_bytes([r[o], r[o + 1], r[o + 2], r[o + 3]]);
    Ok(decode_parallel(n, 0, |b, i| {
        let r = &bytes[i * RECORD..(i + 1) * RECORD];
        let dc = [r[24], r[25], r[26]].map(|c| (f32::from(c) / 255.0 - 0.5) / SH_C0);
        let scale = [f32_at(r, 12), f32_at(r, 16), f32_at(r, 20)];
        b.push(Decoded {
            position: [f32_at(r, 0), f32_at(r, 4), f32_at(r, 8)],
            // A scale ≤ 0 becomes NaN or −inf here and is counted as broken.
            log_scale: scale.map(f32::ln),
            rotation: [r[28], r[29], r[30], r[31]].map(|c| (f32::from(c) - 128.0) / 128.0),
            opacity: f32::from(r[27]) / 255.0,
            sh: &dc,
        })
    }))
}

pub fn write(cloud: &GaussianCloud) -> Vec<u8> {
    let mut out = Vec::with_capacity(cloud.len() * RECORD);
    for i in 0..cloud.len() {
        for v in cloud.positions[i].to_array() {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for v in cloud.scales[i].to_array() {
            out.extend_from_slice(&v.to_le_bytes());
        }
        let sh = cloud.sh_of(i);
        for dc in &sh[..3] {
            out.push(to_u8((0.5 + SH_C0 * dc) * 255.0));
        }
        out.push(to_u8(cloud.opacities[i] * 255.0));
        let q = cloud.rotations[i].normalize();
        for c in [q.w, q.x, q.y, q.z] {
            out.push(to_u8(c * 128.0 + 128.0));
        }
    }
    out
}
