//! A captured surface as a collider (docs/captures.md): the Gaussians of the objects that
//! declare `collider` (their static part, for simulated ones) are voxelised on the
//! simulation grid's nodes, the solid they bound is closed morphologically (a captured
//! table is a sheet of Gaussians, open underneath), and the signed distance φ to that
//! solid's surface is stored per node (negative inside). The step gives every node with
//! φ ≤ 0 the collider's condition, with the outward normal ∇φ/|∇φ|
//! (`sim::boundary::SurfaceCollider`).

use glam::DVec3;
use kiddo::{KdTree, SquaredEuclidean};
use rayon::prelude::*;

use crate::render::Splats;
use crate::sim::boundary::{Condition, SurfaceCollider};
use crate::sim::Grid;

/// Openings up to about twice this many cells wide are closed over.
const CLOSING_CELLS: usize = 2;
/// φ is exact within this many cells of the surface and clamped beyond.
const REACH_CELLS: f64 = 4.0;

/// The collider of the Gaussians `splats` (world space) on `grid`'s nodes.
pub fn build(splats: &Splats, grid: &Grid, condition: Condition) -> SurfaceCollider {
    let n = grid.nodes().to_array().map(|v| v as usize);
    let solid = super::fill::solid_on_lattice(
        &splats.means,
        &splats.covariances,
        &splats.opacities,
        grid.lo,
        grid.dx,
        n,
        CLOSING_CELLS,
    );
    let index = |i: [usize; 3]| i[0] + n[0] * (i[1] + n[1] * i[2]);
    let coords = |idx: usize| [idx % n[0], (idx / n[0]) % n[1], idx / (n[0] * n[1])];
    let node =
        |i: [usize; 3]| grid.lo + DVec3::new(i[0] as f64, i[1] as f64, i[2] as f64) * grid.dx;
    // The surface: midpoints between neighbouring nodes on either side of it.
    let mut tree: KdTree<f64, 3> = KdTree::new();
    let mut count = 0u64;
    for idx in 0..solid.len() {
        if !solid[idx] {
            continue;
        }
        let c = coords(idx);
        for a in 0..3 {
            for step in [-1i64, 1] {
                let m = c[a] as i64 + step;
                if m < 0 || m >= n[a] as i64 {
                    continue;
                }
                let mut o = c;
                o[a] = m as usize;
                if !solid[index(o)] {
                    let mid = 0.5 * (node(c) + node(o));
                    tree.add(&mid.to_array(), count);
                    count += 1;
                }
            }
        }
    }
    let reach = REACH_CELLS * grid.dx;
    let phi: Vec<f32> = (0..solid.len())
        .into_par_iter()
        .map(|idx| {
            let d = if count == 0 {
                reach
            } else {
                tree.nearest_one::<SquaredEuclidean>(&node(coords(idx)).to_array())
                    .distance
                    .sqrt()
                    .min(reach)
            };
            (if solid[idx] { -d } else { d }) as f32
        })
        .collect();
    SurfaceCollider { phi, condition }
}
