//! The capture's surface band: voxels its Gaussians' ellipsoids reach (at `BAND_ALPHA`),
//! the axis votes that close it, and the donors that share the band's volume.

use super::*;

/// Mark the voxels each Gaussian's density reaches (BAND). Returns (degenerate, clipped).
pub(super) fn mark_band(input: &FillInput, grid: &Voxels, flags: &[AtomicU8]) -> (usize, usize) {
    let h = grid.h;
    let degenerate = AtomicUsize::new(0);
    let clipped = AtomicUsize::new(0);
    (0..input.means.len()).into_par_iter().for_each(|i| {
        let m = input.means[i];
        if !m.is_finite() {
            return;
        }
        let mu = m.as_dvec3();
        let centre = grid.cell(mu);
        let mark = |c: [i64; 3]| {
            if let Some(c) = grid.inside(c) {
                flags[grid.index(c)].fetch_or(BAND, Relaxed);
            }
        };
        let sigma = mat3_from_sym3(input.covariances[i]).as_dmat3()
            + DMat3::from_diagonal(DVec3::splat(0.25 * h * h));
        let Some(inv) = spd_inverse(sigma) else {
            degenerate.fetch_add(1, Relaxed);
            mark(centre);
            return;
        };
        let omega = f64::from(input.opacities[i]);
        let q_max = if omega.is_finite() && omega > BAND_ALPHA {
            2.0 * (omega / BAND_ALPHA).ln()
        } else {
            0.0
        };
        let mut lo = [0i64; 3];
        let mut hi = [0i64; 3];
        let mut was_clipped = false;
        let diag = [sigma.x_axis.x, sigma.y_axis.y, sigma.z_axis.z];
        for a in 0..3 {
            let e = (q_max * diag[a]).sqrt();
            let (l, u) = (
                ((mu[a] - e - grid.lo[a]) / h).floor(),
                ((mu[a] + e - grid.lo[a]) / h).floor(),
            );
            let r = MAX_REACH_VOXELS as f64;
            let c = centre[a] as f64;
            if l < c - r || u > c + r {
                was_clipped = true;
            }
            lo[a] = l.max(c - r) as i64;
            hi[a] = u.min(c + r) as i64;
        }
        if was_clipped {
            clipped.fetch_add(1, Relaxed);
        }
        mark(centre);
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let Some(c) = grid.inside([x, y, z]) else {
                        continue;
                    };
                    let d = grid.centre(c) - mu;
                    if d.dot(inv * d) <= q_max {
                        flags[grid.index(c)].fetch_or(BAND, Relaxed);
                    }
                }
            }
        }
    });
    (degenerate.into_inner(), clipped.into_inner())
}

/// The inverse of a symmetric matrix when it is finite and positive definite (Cholesky).
pub(super) fn spd_inverse(s: DMat3) -> Option<DMat3> {
    if !s.is_finite() {
        return None;
    }
    let (a, b, c) = (s.x_axis.x, s.y_axis.x, s.z_axis.x);
    let (d, e, f) = (s.y_axis.y, s.z_axis.y, s.z_axis.z);
    let l00 = a.sqrt();
    if a.is_nan() || a <= 0.0 {
        return None;
    }
    let l10 = b / l00;
    let l20 = c / l00;
    let t = d - l10 * l10;
    if t.is_nan() || t <= 0.0 {
        return None;
    }
    let l11 = t.sqrt();
    let l21 = (e - l20 * l10) / l11;
    let t = f - l20 * l20 - l21 * l21;
    if t.is_nan() || t <= 0.0 {
        return None;
    }
    let inv = s.inverse();
    inv.is_finite().then_some(inv)
}

/// Walk every ray along `axis`; add one inside vote (low nibble) and one conclusive vote
/// (high nibble) per voxel of each ray with an even number of crossings. Returns (rays
/// meeting the surface, odd rays).
pub(super) fn vote_axis(
    grid: &Voxels,
    flags: &[AtomicU8],
    votes: &[AtomicU8],
    axis: usize,
) -> (usize, usize) {
    let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
    let (nb, nc, na) = (grid.n[b], grid.n[c], grid.n[axis]);
    let at = |ib: usize, ic: usize, ia: usize| {
        let mut i = [0; 3];
        i[axis] = ia;
        i[b] = ib;
        i[c] = ic;
        grid.index(i)
    };
    (0..nb * nc)
        .into_par_iter()
        .map(|ray| {
            let (ib, ic) = (ray % nb, ray / nb);
            let band = |ia: usize| flags[at(ib, ic, ia)].load(Relaxed) & BAND != 0;
            let mut runs = 0usize;
            let mut prev = false;
            for ia in 0..na {
                let now = band(ia);
                if now && !prev {
                    runs += 1;
                }
                prev = now;
            }
            if runs == 0 {
                // Misses the surface: all outside, conclusively.
                for ia in 0..na {
                    votes[at(ib, ic, ia)].fetch_add(16, Relaxed);
                }
                return (0, 0);
            }
            if runs % 2 == 1 {
                return (1, 1);
            }
            let mut crossings = 0usize;
            let mut prev = false;
            for ia in 0..na {
                let now = band(ia);
                if now && !prev {
                    crossings += 1;
                }
                prev = now;
                if !now {
                    let inside = crossings % 2 == 1;
                    votes[at(ib, ic, ia)].fetch_add(16 + u8::from(inside), Relaxed);
                }
            }
            (1, 0)
        })
        .reduce(|| (0, 0), |x, y| (x.0 + y.0, x.1 + y.1))
}

/// The appearance donor of every voxel: a breadth-first flood (6-neighbour steps) from the
/// voxels that hold Gaussians, each seeded with its lowest-numbered Gaussian
/// (`by_voxel`: (voxel, Gaussian) sorted). A voxel takes the donor of the seed whose flood
/// reaches it first, i.e. a Gaussian nearest in grid steps — close to the Euclidean nearest
/// near the surface, where colour matters. A k-d tree's nearest query is O(N) per point
/// deep inside a hollow shell (every surface point is almost equally far): a surface-only
/// sphere of 1M Gaussians took minutes that way; the flood is O(voxels) whatever the shape.
pub(super) fn flood_donors(grid: &Voxels, by_voxel: &[(u32, u32)]) -> Vec<u32> {
    let mut donor = vec![u32::MAX; grid.len()];
    let mut queue = VecDeque::new();
    for run in by_voxel.chunk_by(|a, b| a.0 == b.0) {
        donor[run[0].0 as usize] = run[0].1;
        queue.push_back(run[0].0 as usize);
    }
    while let Some(idx) = queue.pop_front() {
        for nidx in grid.neighbours(idx) {
            if donor[nidx] == u32::MAX {
                donor[nidx] = donor[idx];
                queue.push_back(nidx);
            }
        }
    }
    donor
}
