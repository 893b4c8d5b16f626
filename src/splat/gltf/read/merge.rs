//! The splat primitives of a file, each decoded on its own, merged into one cloud with
//! one table of label names.

use super::*;

/// The primitives' Gaussians in one cloud: SH padded to the highest degree; labels kept
/// when every primitive has them (names merged).
pub(super) fn merge(mut parts: Vec<Builder>) -> Builder {
    if parts.len() == 1 {
        return parts.pop().unwrap_or_else(|| Builder::new(0, 0));
    }
    let degree = parts.iter().map(|p| p.cloud.sh_degree).max().unwrap_or(0);
    let labelled = parts
        .iter()
        .all(|p| !p.cloud.labels.is_empty() || p.cloud.is_empty());
    let total = parts.iter().map(|p| p.cloud.len()).sum();
    let mut all = Builder::new(total, degree);
    let k = sh_coeff_count(degree) * 3;
    for p in parts {
        let c = p.cloud;
        all.skipped_nonfinite += p.skipped_nonfinite;
        all.skipped_degenerate += p.skipped_degenerate;
        if labelled {
            let ids: Vec<u16> = c
                .label_names
                .iter()
                .map(|n| label_id(&mut all.cloud.label_names, n))
                .collect();
            all.cloud
                .labels
                .extend(c.labels.iter().map(|&l| ids[usize::from(l)]));
        }
        let stride = c.sh_stride();
        for i in 0..c.len() {
            let start = all.cloud.sh.len();
            all.cloud
                .sh
                .extend_from_slice(&c.sh[i * stride..(i + 1) * stride]);
            all.cloud.sh.resize(start + k, 0.0);
        }
        all.cloud.positions.extend(c.positions);
        all.cloud.scales.extend(c.scales);
        all.cloud.rotations.extend(c.rotations);
        all.cloud.opacities.extend(c.opacities);
    }
    all
}

fn label_id(names: &mut Vec<String>, name: &str) -> u16 {
    match names.iter().position(|n| n == name) {
        Some(i) => i as u16,
        None => {
            names.push(name.to_string());
            (names.len() - 1) as u16
        }
    }
}
