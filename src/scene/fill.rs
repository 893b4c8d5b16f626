//! Interior filling (docs/method.md §5): particles inside a simulated object, so that a surface-only
//! capture breaks like a solid and a coarse procedural lattice gets the simulation's
//! resolution.
//!
//! The object is voxelised at the fill spacing h (default Δx/2: 8 particles per grid
//! cell). A voxel is *solid* when
//! - procedural objects: its centre passes the shape's exact inside test;
//! - PLY objects: ray-crossing parity of the Gaussians' density, voted over the x, y and z
//!   axes. Each Gaussian marks the voxels where ω·exp(−½ dᵀΣ'⁻¹d) ≥ [`BAND_ALPHA`] with
//!   Σ' = Σ + (h/2)² I (so that flat disks still mark a band one voxel thick); along each
//!   axis-aligned ray of voxels every run of marked voxels is one crossing, and the voxels
//!   between the 1st and 2nd, 3rd and 4th, … crossings are inside. A ray crossing an odd
//!   number of times (an open surface, a ray grazing the surface) votes for nothing. A voxel
//!   is solid when more rays through it say inside than outside.
//!
//! Every solid voxel that holds no Gaussian's mean gets one fill particle at its centre
//! (volume h³); the Gaussians share the volume h³ of the voxel that holds their mean
//! equally. The total rest volume is therefore the voxelised volume of the object.
//!
//! Guards (bounded time and memory whatever the input): at most [`MAX_FILL_VOXELS`] voxels
//! and [`MAX_FILL_PARTICLES`] fill particles (errors, with the counts); a Gaussian marks at
//! most [`MAX_REACH_VOXELS`] voxels either side of its mean per axis (wider ones are
//! clipped and counted); covariances that are non-finite or not positive semi-definite
//! mark only the voxel of their mean (counted); non-finite means are ignored (counted).
//! So the work is O(voxels + Gaussians · (2·4+1)³) and the memory six bytes per voxel.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicU8, AtomicUsize, Ordering::Relaxed};

use glam::{DMat3, DVec3, Vec3};
use rayon::prelude::*;

use crate::render::splats::{mat3_from_sym3, Sym3};

mod band;
use band::{flood_donors, mark_band, vote_axis};

/// Most voxels one fill may use (six bytes each: 192 MiB).
pub const MAX_FILL_VOXELS: usize = 1 << 25;
/// Most fill particles one object may get.
pub const MAX_FILL_PARTICLES: usize = 8 << 20;
/// A Gaussian marks voxels at most this many voxels away from its mean's, per axis.
pub const MAX_REACH_VOXELS: i64 = 4;
/// Largest closing radius, in voxels (the closing's work grows with it).
pub const MAX_CLOSING_VOXELS: usize = 16;
/// The density a voxel centre needs from one Gaussian to be on the surface.
pub const BAND_ALPHA: f64 = 0.1;
/// Above this share of odd rays (among the rays that meet the surface) a warning says the
/// surface looks open.
pub const OPEN_RAY_SHARE: f64 = 0.3;

const MEAN: u8 = 1;
const BAND: u8 = 2;

/// How solid voxels are found.
pub enum InsideTest<'a> {
    /// Ray-crossing parity of the Gaussians' density along x, y and z (captures whose
    /// surface is closed).
    Parity,
    /// Morphological closing of the density's band by `radius` voxels (open captures:
    /// leaves, a pot's mouth, a missing underside).
    Closing { radius: usize },
    /// An exact inside test in world coordinates and the solid's world bounding box
    /// (procedural objects).
    Exact {
        contains: &'a (dyn Fn(DVec3) -> bool + Sync),
        lo: DVec3,
        hi: DVec3,
    },
}

/// What to fill: one object's Gaussians (world space) and the fill settings.
pub struct FillInput<'a> {
    pub means: &'a [Vec3],
    pub covariances: &'a [Sym3],
    pub opacities: &'a [f32],
    /// Particle spacing h: one particle per h³ voxel.
    pub spacing: f64,
    pub inside: InsideTest<'a>,
    /// Only voxels whose centre passes this test are filled (the object's selection).
    pub region: &'a (dyn Fn(DVec3) -> bool + Sync),
}

/// Counts of what the fill saw, for reports and tests.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FillStats {
    /// Voxels of the grid [nx, ny, nz].
    pub dims: [usize; 3],
    /// Voxels marked as surface by the density (parity only).
    pub band_voxels: usize,
    /// Solid voxels (inside), with or without a Gaussian.
    pub solid_voxels: usize,
    /// Rays (parity only) that meet the surface, and those among them with an odd count.
    pub rays_hit: usize,
    pub odd_rays: usize,
    /// Gaussians whose covariance was unusable (marked as points), or whose mean was not
    /// finite (ignored).
    pub degenerate: usize,
    pub nonfinite_means: usize,
    /// Gaussians wider than [`MAX_REACH_VOXELS`] voxels, clipped.
    pub clipped: usize,
}

/// The fill of one object.
#[derive(Clone, Debug, Default)]
pub struct Fill {
    /// Fill particles (voxel centres), in voxel order (x fastest).
    pub points: Vec<DVec3>,
    /// For each fill particle, an input Gaussian nearest to it in voxel steps (its
    /// appearance donor, [`flood_donors`]).
    pub nearest: Vec<u32>,
    /// Rest volume of each input Gaussian (its share of its voxel).
    pub volumes: Vec<f64>,
    /// Rest volume of each fill particle: h³.
    pub point_volume: f64,
    pub stats: FillStats,
    /// Messages for the user: what was odd in the input.
    pub warnings: Vec<String>,
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FillError {
    #[error("{count:.0} voxels ({nx:.0} × {ny:.0} × {nz:.0}) at spacing {spacing}; at most {max} are allowed")]
    TooManyVoxels {
        count: f64,
        nx: f64,
        ny: f64,
        nz: f64,
        spacing: f64,
        max: usize,
    },
    #[error("{count} fill particles at spacing {spacing}; at most {max} are allowed")]
    TooManyParticles {
        count: usize,
        spacing: f64,
        max: usize,
    },
    #[error("spacing {0}: expected a finite spacing > 0")]
    BadSpacing(f64),
}

/// The voxel grid: centres lo + (i + ½) h.
struct Voxels {
    lo: DVec3,
    h: f64,
    n: [usize; 3],
}

impl Voxels {
    fn len(&self) -> usize {
        self.n[0] * self.n[1] * self.n[2]
    }
    fn index(&self, i: [usize; 3]) -> usize {
        i[0] + self.n[0] * (i[1] + self.n[1] * i[2])
    }
    fn coords(&self, idx: usize) -> [usize; 3] {
        let x = idx % self.n[0];
        let r = idx / self.n[0];
        [x, r % self.n[1], r / self.n[1]]
    }
    fn centre(&self, i: [usize; 3]) -> DVec3 {
        self.lo + (DVec3::new(i[0] as f64, i[1] as f64, i[2] as f64) + 0.5) * self.h
    }
    /// The voxel holding p, as signed coordinates (may be outside the grid).
    fn cell(&self, p: DVec3) -> [i64; 3] {
        let c = ((p - self.lo) / self.h).floor();
        [c.x as i64, c.y as i64, c.z as i64]
    }
    /// The indices of the (up to six) face neighbours of voxel `idx` on the grid.
    fn neighbours(&self, idx: usize) -> impl Iterator<Item = usize> + '_ {
        let c = self.coords(idx);
        [(0, -1), (0, 1), (1, -1), (1, 1), (2, -1), (2, 1)]
            .into_iter()
            .filter_map(move |(axis, step)| {
                let mut n = c.map(|v| v as i64);
                n[axis] += step;
                self.inside(n).map(|n| self.index(n))
            })
    }
    fn inside(&self, c: [i64; 3]) -> Option<[usize; 3]> {
        let ok = (0..3).all(|a| c[a] >= 0 && (c[a] as u64) < self.n[a] as u64);
        ok.then(|| c.map(|v| v as usize))
    }
}

/// Which voxels a fill turns into particles.
#[derive(Clone, Copy)]
enum Cover {
    /// Solid voxels that hold no Gaussian's mean, at their centres: the interior beside
    /// the Gaussians, which are particles themselves.
    Interior,
    /// Every solid voxel (and for a capture every voxel holding a mean or on the density's
    /// surface band), moved off its centre by up to ±jitter·h/2 per axis: particles
    /// standing for the whole object.
    Solid { jitter: f64, seed: u64 },
}

/// Fill one object's interior. Errors only when the grid or the particle count would
/// exceed the limits; everything odd in the Gaussians is reported in `warnings`.
pub fn fill(input: &FillInput) -> Result<Fill, FillError> {
    cover(input, Cover::Interior)
}

/// Particles on a lattice of spacing h over the whole object (docs/method.md §5.7): one per
/// solid voxel (for a capture also per voxel holding a Gaussian's mean or on the surface
/// band), jittered by up to ±`jitter`·h/2 per axis
/// (a hash of `seed` and the voxel: reproducible), volume h³ each. `nearest` names each
/// point's nearest Gaussian in voxel steps, `volumes` is unused.
pub fn lattice(input: &FillInput, jitter: f64, seed: u64) -> Result<Fill, FillError> {
    cover(input, Cover::Solid { jitter, seed })
}

fn cover(input: &FillInput, cover: Cover) -> Result<Fill, FillError> {
    let h = input.spacing;
    if !(h.is_finite() && h > 0.0) {
        return Err(FillError::BadSpacing(h));
    }
    let n_in = input.means.len();
    let mut stats = FillStats {
        nonfinite_means: input.means.iter().filter(|m| !m.is_finite()).count(),
        ..Default::default()
    };
    let mut out = Fill {
        volumes: vec![h.powi(3); n_in],
        point_volume: h.powi(3),
        ..Default::default()
    };
    let Some(grid) = voxel_grid(input)? else {
        out.warnings
            .push("fill: no Gaussian with a finite position; nothing filled".into());
        out.stats = stats;
        return Ok(out);
    };
    stats.dims = grid.n;
    let flags: Vec<AtomicU8> = (0..grid.len()).map(|_| AtomicU8::new(0)).collect();
    let home = mark_means(input, &grid, &flags);
    let solid = solid_voxels(input, &grid, &flags, &mut stats);
    stats.solid_voxels = solid.iter().filter(|s| **s).count();

    let exact = matches!(input.inside, InsideTest::Exact { .. });
    // Fill voxels: solid (and, for the interior, no Gaussian there), inside the selection.
    let fill_idx: Vec<usize> = (0..grid.len())
        .into_par_iter()
        .filter(|&idx| {
            let flag = flags[idx].load(Relaxed);
            let taken = match cover {
                Cover::Interior => solid[idx] && flag & MEAN == 0,
                // An exact test is the solid; a capture's solid is its inside, its surface
                // band and wherever its Gaussians are.
                Cover::Solid { .. } if exact => solid[idx],
                Cover::Solid { .. } => solid[idx] || flag & (MEAN | BAND) != 0,
            };
            taken && (input.region)(grid.centre(grid.coords(idx)))
        })
        .collect();
    if fill_idx.len() > MAX_FILL_PARTICLES {
        return Err(FillError::TooManyParticles {
            count: fill_idx.len(),
            spacing: h,
            max: MAX_FILL_PARTICLES,
        });
    }
    out.points = fill_idx
        .iter()
        .map(|&idx| {
            let centre = grid.centre(grid.coords(idx));
            match cover {
                Cover::Interior => centre,
                Cover::Solid { jitter, seed } => {
                    let mut r = crate::rng::SplitMix64::new(
                        seed ^ (idx as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15),
                    );
                    let d = DVec3::new(r.uniform(), r.uniform(), r.uniform()) - 0.5;
                    centre + d * (jitter * h)
                }
            }
        })
        .collect();

    let by_voxel = share_volumes(&home, h, &mut out.volumes);
    // Appearance donors: flooded out from the voxels that hold Gaussians.
    if by_voxel.is_empty() {
        out.points.clear();
    } else {
        let donor = flood_donors(&grid, &by_voxel);
        out.nearest = fill_idx.iter().map(|&idx| donor[idx]).collect();
    }
    out.warnings = warnings(input, &stats);
    out.stats = stats;
    Ok(out)
}

/// The voxel grid over what is to be filled, with a margin, or None when no Gaussian has a
/// finite position. The closing mode needs its radius of margin more, so that dilation
/// never meets the grid's edge.
fn voxel_grid(input: &FillInput) -> Result<Option<Voxels>, FillError> {
    let h = input.spacing;
    let (lo, hi) = match &input.inside {
        InsideTest::Parity | InsideTest::Closing { .. } => {
            let (lo, hi) = input
                .means
                .iter()
                .filter(|m| m.is_finite())
                .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), m| {
                    (lo.min(m.as_dvec3()), hi.max(m.as_dvec3()))
                });
            let margin = match input.inside {
                InsideTest::Closing { radius } => 2 + radius,
                _ => 2,
            };
            (lo - margin as f64 * h, hi + margin as f64 * h)
        }
        InsideTest::Exact { lo, hi, .. } => (*lo - h, *hi + h),
    };
    if !(lo.is_finite() && hi.is_finite()) {
        return Ok(None);
    }
    let dims = ((hi - lo) / h).ceil().max(DVec3::ONE);
    let count = dims.element_product();
    if count.is_nan() || count > MAX_FILL_VOXELS as f64 {
        return Err(FillError::TooManyVoxels {
            count,
            nx: dims.x,
            ny: dims.y,
            nz: dims.z,
            spacing: h,
            max: MAX_FILL_VOXELS,
        });
    }
    Ok(Some(Voxels {
        lo,
        h,
        n: [dims.x as usize, dims.y as usize, dims.z as usize],
    }))
}

/// The voxel of each mean (u32::MAX: none), setting the MEAN flags.
fn mark_means(input: &FillInput, grid: &Voxels, flags: &[AtomicU8]) -> Vec<u32> {
    input
        .means
        .par_iter()
        .map(|m| {
            if !m.is_finite() {
                return u32::MAX;
            }
            match grid.inside(grid.cell(m.as_dvec3())) {
                Some(c) => {
                    let idx = grid.index(c);
                    flags[idx].fetch_or(MEAN, Relaxed);
                    idx as u32
                }
                None => u32::MAX,
            }
        })
        .collect()
}

/// Which voxels are inside the object, by the input's inside test.
fn solid_voxels(
    input: &FillInput,
    grid: &Voxels,
    flags: &[AtomicU8],
    stats: &mut FillStats,
) -> Vec<bool> {
    if let InsideTest::Exact { contains, .. } = &input.inside {
        return (0..grid.len())
            .into_par_iter()
            .map(|idx| contains(grid.centre(grid.coords(idx))))
            .collect();
    }
    let (degenerate, clipped) = mark_band(input, grid, flags);
    stats.degenerate = degenerate;
    stats.clipped = clipped;
    let band: Vec<bool> = flags
        .par_iter()
        .map(|f| f.load(Relaxed) & BAND != 0)
        .collect();
    stats.band_voxels = band.iter().filter(|b| **b).count();
    match input.inside {
        InsideTest::Closing { radius } => closed_interior(grid, &band, radius),
        _ => parity_interior(grid, flags, &band, stats),
    }
}

/// Ray-crossing parity voted over the three axes: a voxel off the band is inside when more
/// rays through it say inside than outside.
fn parity_interior(
    grid: &Voxels,
    flags: &[AtomicU8],
    band: &[bool],
    stats: &mut FillStats,
) -> Vec<bool> {
    let votes: Vec<AtomicU8> = (0..grid.len()).map(|_| AtomicU8::new(0)).collect();
    for axis in 0..3 {
        let (hit, odd) = vote_axis(grid, flags, &votes, axis);
        stats.rays_hit += hit;
        stats.odd_rays += odd;
    }
    votes
        .par_iter()
        .zip(band.par_iter())
        .map(|(v, &on_band)| {
            let v = v.load(Relaxed);
            let (inside, conclusive) = (v & 15, v >> 4);
            !on_band && 2 * inside > conclusive
        })
        .collect()
}

/// Morphological closing of the band: dilate it by `radius` voxels (a cube), flood the
/// outside from the grid's faces through what is not dilated, take everything the flood
/// did not reach, and erode that by `radius` again. Openings narrower than about
/// 2·radius voxels (a pot's mouth, a missing underside, gaps between leaves) are bridged
/// by the dilation, so the flood cannot get in; the erosion puts the outer surface back
/// where the band was. Band voxels themselves hold the surface's Gaussians and are not
/// filled.
fn closed_interior(grid: &Voxels, band: &[bool], radius: usize) -> Vec<bool> {
    let dilated = box_filter(grid, band, radius, true);
    let outside = flood_outside(grid, &dilated);
    let closed: Vec<bool> = outside.par_iter().map(|o| !o).collect();
    let eroded = box_filter(grid, &closed, radius, false);
    eroded
        .par_iter()
        .zip(band.par_iter())
        .map(|(&e, &b)| e && !b)
        .collect()
}

/// Separable cube dilation (`any`) or erosion (not `any`: all) of `set` by `radius`
/// voxels along each axis. Outside the grid counts as empty for dilation and as full
/// for erosion (the grid's margin is empty anyway).
fn box_filter(grid: &Voxels, set: &[bool], radius: usize, any: bool) -> Vec<bool> {
    let mut cur = set.to_vec();
    let r = radius as i64;
    for axis in 0..3 {
        let prev = cur;
        cur = (0..grid.len())
            .into_par_iter()
            .map(|idx| {
                let c = grid.coords(idx);
                let mut n = c.map(|v| v as i64);
                let around = (-r..=r).filter_map(|d| {
                    n[axis] = c[axis] as i64 + d;
                    grid.inside(n).map(|m| prev[grid.index(m)])
                });
                if any {
                    around.into_iter().any(|v| v)
                } else {
                    around.into_iter().all(|v| v)
                }
            })
            .collect();
    }
    cur
}

/// Voxels reachable (6-neighbour steps) from the grid's faces without entering `wall`.
fn flood_outside(grid: &Voxels, wall: &[bool]) -> Vec<bool> {
    let mut outside = vec![false; grid.len()];
    let mut queue = VecDeque::new();
    for idx in 0..grid.len() {
        let c = grid.coords(idx);
        let on_face = (0..3).any(|a| c[a] == 0 || c[a] + 1 == grid.n[a]);
        if on_face && !wall[idx] {
            outside[idx] = true;
            queue.push_back(idx);
        }
    }
    while let Some(idx) = queue.pop_front() {
        for nidx in grid.neighbours(idx) {
            if !outside[nidx] && !wall[nidx] {
                outside[nidx] = true;
                queue.push_back(nidx);
            }
        }
    }
    outside
}

/// Each voxel holding means shares h³ among them. Returns the (voxel, Gaussian) pairs,
/// sorted.
fn share_volumes(home: &[u32], h: f64, volumes: &mut [f64]) -> Vec<(u32, u32)> {
    let mut by_voxel: Vec<(u32, u32)> = home
        .iter()
        .enumerate()
        .filter(|(_, v)| **v != u32::MAX)
        .map(|(i, v)| (*v, i as u32))
        .collect();
    by_voxel.par_sort_unstable();
    for run in by_voxel.chunk_by(|a, b| a.0 == b.0) {
        let share = h.powi(3) / run.len() as f64;
        for &(_, i) in run {
            volumes[i as usize] = share;
        }
    }
    by_voxel
}

/// What the user should hear about the input and the result.
fn warnings(input: &FillInput, stats: &FillStats) -> Vec<String> {
    let h = input.spacing;
    let mut w = Vec::new();
    if stats.nonfinite_means > 0 {
        w.push(format!(
            "fill: {} Gaussians with a non-finite position ignored",
            stats.nonfinite_means
        ));
    }
    if stats.degenerate > 0 {
        w.push(format!(
            "fill: {} Gaussians with a degenerate covariance (non-finite or not positive semi-definite) counted as points",
            stats.degenerate
        ));
    }
    if stats.clipped > 0 {
        w.push(format!(
            "fill: {} Gaussians wider than {MAX_REACH_VOXELS} spacings ({:.3e}) clipped to that reach",
            stats.clipped,
            MAX_REACH_VOXELS as f64 * h
        ));
    }
    if matches!(input.inside, InsideTest::Parity) {
        let share = stats.odd_rays as f64 / stats.rays_hit.max(1) as f64;
        if share > OPEN_RAY_SHARE {
            w.push(format!(
                "fill: {:.0}% of the rays that meet the surface cross it an odd number of times: the surface looks open (or has holes wider than the spacing {h:.3e}); only voxels that rays agree on are filled. For an open capture use {{\"mode\": \"closing\"}} (docs/captures.md, filling an open capture)",
                100.0 * share
            ));
        }
    }
    if stats.solid_voxels == 0 {
        w.push(format!(
            "fill: no interior found at spacing {h:.3e} (no closed surface, or the object is thinner than two spacings); nothing added"
        ));
    }
    w
}

/// The solid a surface of Gaussians bounds, on the lattice of points `lo` + i·h (i < `n`):
/// the points their density reaches (the band, as for filling), closed morphologically by
/// `radius` lattice steps (a captured table top, an open floor). For colliders.
pub(crate) fn solid_on_lattice(
    means: &[Vec3],
    covariances: &[Sym3],
    opacities: &[f32],
    lo: DVec3,
    h: f64,
    n: [usize; 3],
    radius: usize,
) -> Vec<bool> {
    // Voxel centres lo' + (i + ½)h on the lattice points.
    let grid = Voxels {
        lo: lo - 0.5 * h,
        h,
        n,
    };
    let everywhere = |_: DVec3| true;
    let input = FillInput {
        means,
        covariances,
        opacities,
        spacing: h,
        inside: InsideTest::Closing { radius },
        region: &everywhere,
    };
    let flags: Vec<AtomicU8> = (0..grid.len()).map(|_| AtomicU8::new(0)).collect();
    mark_band(&input, &grid, &flags);
    let band: Vec<bool> = flags.iter().map(|f| f.load(Relaxed) & BAND != 0).collect();
    let interior = closed_interior(&grid, &band, radius);
    band.iter().zip(interior).map(|(b, i)| *b || i).collect()
}
