//! Fragment statistics of a fractured body: how many separate pieces its particles form.
//!
//! Two particles belong to the same fragment when a chain of particles links them, each
//! link shorter than `link` (single-linkage clustering, the usual fragment definition of
//! particle fracture studies). With `link` = Δx a crack one grid cell wide separates two
//! pieces. Used by `splatter render --fragments` (per simulated object and frame) and by
//! the scene tests that check a fruit breaks and a jelly stays whole.
//!
//! A fractured body's *pieces* are its solid fragments ([`solid_fragment_ids`]): only
//! particles that still hold together link. A particle broken through (damage 1: a brittle
//! crack's rubble, NACC flesh without cohesion) carries no tension, so it cannot hold two
//! chunks together; it links nothing and counts as debris. Linking every particle instead
//! ([`fragment_ids`] over the whole body) glues chunks through the rubble that fills the
//! cracks between them; `--fragments` reports that count too, as the linked pieces.
//!
//! Cost: O(N) with a hash grid of cell size `link` and a union–find over the links.

use std::collections::HashMap;

use glam::DVec3;

/// The fragment sizes (particle counts) of `points`, largest first.
pub fn fragment_sizes(points: &[DVec3], link: f64) -> Vec<usize> {
    sizes_of(&fragment_ids(points, link))
}

/// The fragment sizes of [`fragment_ids`]' (or [`solid_fragment_ids`]') numbering,
/// largest first; [`RUBBLE`] is no fragment.
pub fn sizes_of(ids: &[u32]) -> Vec<usize> {
    let solid = ids.iter().filter(|&&f| f != RUBBLE);
    let mut sizes = vec![0; solid.clone().max().map_or(0, |&m| m as usize + 1)];
    for &f in solid {
        sizes[f as usize] += 1;
    }
    sizes
}

/// The fragment id of a particle broken through: it belongs to no fragment.
pub const RUBBLE: u32 = u32::MAX;

/// The solid fragments of `points`: [`fragment_ids`] of the points with `intact[i]`,
/// numbered by size, and [`RUBBLE`] for the others.
pub fn solid_fragment_ids(points: &[DVec3], intact: &[bool], link: f64) -> Vec<u32> {
    let kept: Vec<usize> = (0..points.len()).filter(|&i| intact[i]).collect();
    let kept_points: Vec<DVec3> = kept.iter().map(|&i| points[i]).collect();
    let mut ids = vec![RUBBLE; points.len()];
    for (&i, id) in kept.iter().zip(fragment_ids(&kept_points, link)) {
        ids[i] = id;
    }
    ids
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
    /// Particles in no piece: in fragments below `min_share`, or rubble.
    pub debris: usize,
    /// Particles broken through ([`RUBBLE`]), part of the debris.
    pub rubble: usize,
    /// All fragments, of any size.
    pub fragments: usize,
    /// The Gaussians the body's particles move, and the share of them moved by the
    /// largest fragment (0 and 0 until [`with_gaussians`](Self::with_gaussians)).
    pub gaussians: usize,
    pub gaussian_largest_share: f64,
}

impl FragmentSummary {
    /// The summary of fragments of these sizes (largest first), no rubble.
    pub fn new(sizes: &[usize], min_share: f64) -> Self {
        Self::of_sizes(sizes, sizes.iter().sum(), min_share)
    }

    /// The summary of a numbering by [`fragment_ids`] or [`solid_fragment_ids`]: shares are
    /// of all the particles, rubble included.
    pub fn of(ids: &[u32], min_share: f64) -> Self {
        Self::of_sizes(&sizes_of(ids), ids.len(), min_share)
    }

    fn of_sizes(sizes: &[usize], particles: usize, min_share: f64) -> Self {
        let floor = (min_share * particles as f64).ceil().max(1.0) as usize;
        let pieces = sizes.iter().filter(|&&s| s >= floor).count();
        let in_pieces: usize = sizes.iter().filter(|&&s| s >= floor).sum();
        Self {
            particles,
            pieces,
            largest_share: sizes
                .first()
                .map_or(0.0, |&s| s as f64 / particles.max(1) as f64),
            debris: particles - in_pieces,
            rubble: particles - sizes.iter().sum::<usize>(),
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
    fn rubble_links_nothing() {
        // Two blocks whose gap is bridged by a line of points: one fragment while the
        // bridge holds, two pieces once the bridge is rubble.
        let h = 0.01;
        let mut p = block(DVec3::ZERO, 4, h);
        p.extend(block(DVec3::new(6.0 * h, 0.0, 0.0), 4, h));
        let bridge = [4.0, 5.0].map(|i| DVec3::new(i * h, 0.0, 0.0));
        p.extend(bridge);
        let mut intact = vec![true; p.len()];
        let linked = FragmentSummary::of(&fragment_ids(&p, 1.5 * h), 0.01);
        assert_eq!((linked.pieces, linked.rubble), (1, 0));
        assert_eq!(
            linked,
            FragmentSummary::of(&solid_fragment_ids(&p, &intact, 1.5 * h), 0.01)
        );
        intact[128] = false;
        intact[129] = false;
        let ids = solid_fragment_ids(&p, &intact, 1.5 * h);
        assert_eq!(
            (ids[0], ids[64], ids[128], ids[129]),
            (0, 1, RUBBLE, RUBBLE)
        );
        let solid = FragmentSummary::of(&ids, 0.01);
        assert_eq!(
            (solid.pieces, solid.fragments, solid.rubble, solid.debris),
            (2, 2, 2, 2)
        );
        assert!((solid.largest_share - 64.0 / 130.0).abs() < 1e-12);
    }

    #[test]
    fn a_diagonal_chain_is_one_fragment() {
        // Neighbours only across cell corners (every pair in different cells).
        let p: Vec<DVec3> = (0..50).map(|i| DVec3::splat(i as f64 * 0.05)).collect();
        assert_eq!(fragment_sizes(&p, 0.09), vec![50]);
        assert_eq!(fragment_sizes(&p, 0.08).len(), 50);
    }
}
