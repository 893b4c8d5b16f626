//! Fragment statistics of a fractured body: how many separate pieces its particles form.
//!
//! Two particles belong to the same fragment when a chain of particles links them, each
//! link shorter than `link` (single-linkage clustering, the usual fragment definition of
//! particle fracture studies). With `link` = Δx a crack one grid cell wide separates two
//! pieces. Used by `splatter render --fragments` (per simulated object and frame) and by
//! the scene tests that check a fruit breaks and a jelly stays whole.
//!
//! Cost: O(N) with a hash grid of cell size `link` and a union–find over the links.

use std::collections::HashMap;

use glam::DVec3;

/// The fragment sizes (particle counts) of `points`, largest first.
pub fn fragment_sizes(points: &[DVec3], link: f64) -> Vec<usize> {
    sizes_of(&fragment_ids(points, link))
}

/// The fragment sizes of [`fragment_ids`]' numbering, largest first.
pub fn sizes_of(ids: &[u32]) -> Vec<usize> {
    let mut sizes = vec![0; ids.iter().max().map_or(0, |&m| m as usize + 1)];
    for &f in ids {
        sizes[f as usize] += 1;
    }
    sizes
}

/// The fragment of each of `points`, numbered by size (0: the largest; ties by the lowest
/// point index).
pub fn fragment_ids(points: &[DVec3], link: f64) -> Vec<u32> {
    assert!(link > 0.0, "fragment link distance must be positive");
    let cell = |p: DVec3| (p / link).floor().as_ivec3();
    let mut cells: HashMap<glam::IVec3, Vec<u32>> = HashMap::new();
    for (i, &p) in points.iter().enumerate() {
        cells.entry(cell(p)).or_default().push(i as u32);
    }
    let mut sets = UnionFind::new(points.len());
    let link2 = link * link;
    for (&c, members) in &cells {
        // Each pair of neighbouring cells once: the cell itself and the 13 "forward" ones.
        for d in FORWARD {
            let Some(other) = cells.get(&(c + glam::IVec3::from(d))) else {
                continue;
            };
            let same = d == [0, 0, 0];
            for (a, &i) in members.iter().enumerate() {
                let js = if same { &other[a + 1..] } else { &other[..] };
                for &j in js {
                    if points[i as usize].distance_squared(points[j as usize]) < link2 {
                        sets.union(i as usize, j as usize);
                    }
                }
            }
        }
    }
    // Roots are each set's lowest index (union keeps the smaller).
    let roots: Vec<usize> = (0..points.len()).map(|i| sets.find(i)).collect();
    let mut size = vec![0usize; points.len()];
    for &r in &roots {
        size[r] += 1;
    }
    let mut order: Vec<usize> = (0..points.len()).filter(|&r| size[r] > 0).collect();
    order.sort_by_key(|&r| (std::cmp::Reverse(size[r]), r));
    let mut id = vec![0u32; points.len()];
    for (k, &r) in order.iter().enumerate() {
        id[r] = k as u32;
    }
    roots.iter().map(|&r| id[r]).collect()
}

/// What `--fragments` reports for one body: fragments holding at least `min_share` of its
/// particles count as pieces; the rest is debris.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FragmentSummary {
    pub particles: usize,
    /// Fragments with at least `min_share` of the particles.
    pub pieces: usize,
    /// Share of the particles in the largest fragment.
    pub largest_share: f64,
    /// Particles in fragments below `min_share`.
    pub debris: usize,
    /// All fragments, of any size.
    pub fragments: usize,
    /// The Gaussians the body's particles move, and the share of them moved by the
    /// largest fragment (0 and 0 until [`with_gaussians`](Self::with_gaussians)).
    pub gaussians: usize,
    pub gaussian_largest_share: f64,
}

impl FragmentSummary {
    pub fn new(sizes: &[usize], min_share: f64) -> Self {
        let particles: usize = sizes.iter().sum();
        let floor = (min_share * particles as f64).ceil().max(1.0) as usize;
        let pieces = sizes.iter().filter(|&&s| s >= floor).count();
        Self {
            particles,
            pieces,
            largest_share: sizes.first().map_or(0.0, |&s| s as f64 / particles as f64),
            debris: sizes.iter().filter(|&&s| s < floor).sum(),
            fragments: sizes.len(),
            gaussians: 0,
            gaussian_largest_share: 0.0,
        }
    }

    /// The same, with the count of Gaussians and the share the largest fragment moves.
    pub fn with_gaussians(self, gaussians: usize, largest_share: f64) -> Self {
        Self {
            gaussians,
            gaussian_largest_share: largest_share,
            ..self
        }
    }
}

/// The share of a body's particles a fragment needs to count as a piece in reports.
pub const PIECE_SHARE: f64 = 0.01;

/// Offsets to the cell itself and half of its 26 neighbours (the other half is visited
/// from the neighbour's side).
const FORWARD: [[i32; 3]; 14] = [
    [0, 0, 0],
    [1, 0, 0],
    [-1, 1, 0],
    [0, 1, 0],
    [1, 1, 0],
    [-1, -1, 1],
    [0, -1, 1],
    [1, -1, 1],
    [-1, 0, 1],
    [0, 0, 1],
    [1, 0, 1],
    [-1, 1, 1],
    [0, 1, 1],
    [1, 1, 1],
];

struct UnionFind {
    parent: Vec<usize>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        Self {
            parent: (0..n).collect(),
        }
    }

    fn find(&mut self, mut i: usize) -> usize {
        while self.parent[i] != i {
            self.parent[i] = self.parent[self.parent[i]];
            i = self.parent[i];
        }
        i
    }

    fn union(&mut self, a: usize, b: usize) {
        let (a, b) = (self.find(a), self.find(b));
        if a != b {
            self.parent[a.max(b)] = a.min(b);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block(origin: DVec3, n: usize, h: f64) -> Vec<DVec3> {
        let mut v = Vec::new();
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    v.push(origin + h * DVec3::new(i as f64, j as f64, k as f64));
                }
            }
        }
        v
    }

    #[test]
    fn two_blocks_apart_are_two_fragments() {
        let h = 0.01;
        let mut p = block(DVec3::ZERO, 5, h);
        // A gap of 3 spacings between the blocks: separate with link 1.5 h.
        p.extend(block(DVec3::new(7.0 * h, 0.0, 0.0), 4, h));
        p.push(DVec3::new(0.0, 0.5, 0.0));
        assert_eq!(fragment_sizes(&p, 1.5 * h), vec![125, 64, 1]);
        // A link longer than the gap joins the blocks (the lone point stays apart).
        assert_eq!(fragment_sizes(&p, 3.5 * h), vec![189, 1]);
        let s = FragmentSummary::new(&fragment_sizes(&p, 1.5 * h), 0.05);
        assert_eq!(
            (s.pieces, s.debris, s.fragments, s.particles),
            (2, 1, 3, 190)
        );
        assert!((s.largest_share - 125.0 / 190.0).abs() < 1e-12);
    }

    #[test]
    fn a_diagonal_chain_is_one_fragment() {
        // Neighbours only across cell corners (every pair in different cells).
        let p: Vec<DVec3> = (0..50).map(|i| DVec3::splat(i as f64 * 0.05)).collect();
        assert_eq!(fragment_sizes(&p, 0.09), vec![50]);
        assert_eq!(fragment_sizes(&p, 0.08).len(), 50);
    }
}
