//! Material regions of a simulated object (`physics.regions`, docs/method.md §5): the watermelon's
//! rind, flesh and seeds are one object with three materials. Each region selects particles
//! by depth below the surface (`shell`), by a world box or ball (`box`, `sphere`, as
//! `physics.select`), by the Gaussians' label (`label`) or by nearness to the faces of a
//! Voronoi partition (`voronoi`, an art-directed fracture pattern), and gives them its own material
//! and, optionally, an interior colour for its fill particles. The first matching region
//! wins; particles in no region keep the object's `material`.

use glam::DVec3;

use super::physics::{RegionSpec, SelectSpec, ShellRange, VoronoiFaces};
use super::SceneError;
use crate::rng::SplitMix64;
use crate::sim::Material;

/// Most regions one object may have (the GPU step holds 16 materials for the whole scene).
pub const MAX_REGIONS: usize = 15;

/// A region's test, validated.
#[derive(Clone, Debug)]
enum Test {
    Shell { from: f64, to: f64 },
    Select(SelectSpec),
    Label(u16),
    Voronoi(VoronoiPartition),
}

/// Most cells a `voronoi` region may have (each particle is tested against every centre).
pub const MAX_VORONOI_CELLS: u32 = 256;

/// Candidates per centre in the best-candidate placement: more spreads the centres more
/// evenly (towards a Poisson-disc set), fewer leaves them closer to uniformly random.
const CANDIDATES: usize = 8;

/// A Voronoi partition of an object's rest particles and the half-thickness of its faces.
#[derive(Clone, Debug)]
pub struct VoronoiPartition {
    spec: VoronoiFaces,
    /// The cell centres, placed by [`VoronoiPartition::place`] (empty before).
    centres: Vec<DVec3>,
}

impl VoronoiPartition {
    /// Place the centres on `cells` of the particles `xs`, by Mitchell's best candidate:
    /// each new centre is the one of a few random particles farthest from those already
    /// placed, so the cells come out of similar size (as fracture patterns want) and the
    /// same seed gives the same centres.
    pub fn place(&mut self, xs: &[DVec3]) {
        let mut rng = SplitMix64::new(self.spec.seed);
        let mut pick = || xs[(rng.next_u64() % xs.len() as u64) as usize];
        self.centres.clear();
        self.centres.push(pick());
        while self.centres.len() < self.spec.cells as usize {
            let gap = |c: DVec3| {
                self.centres
                    .iter()
                    .map(|q| q.distance_squared(c))
                    .fold(f64::INFINITY, f64::min)
            };
            let best = (0..CANDIDATES)
                .map(|_| pick())
                .max_by(|a, b| gap(*a).total_cmp(&gap(*b)))
                .expect("candidates");
            self.centres.push(best);
        }
    }

    /// Distance from `x` to the nearest face of its cell: the smallest distance to the
    /// bisecting plane between its nearest centre c and another centre q,
    /// (|x − q|² − |x − c|²) / (2 |q − c|).
    pub fn face_distance(&self, x: DVec3) -> f64 {
        let Some((i, c)) = self.centres.iter().enumerate().min_by(|a, b| {
            x.distance_squared(*a.1)
                .total_cmp(&x.distance_squared(*b.1))
        }) else {
            return f64::INFINITY;
        };
        let own = x.distance_squared(*c);
        self.centres
            .iter()
            .enumerate()
            .filter(|(j, q)| *j != i && q.distance_squared(*c) > 0.0)
            .map(|(_, q)| (x.distance_squared(*q) - own) / (2.0 * q.distance(*c)))
            .fold(f64::INFINITY, f64::min)
    }

    /// Whether `x` lies within the faces' half-thickness.
    pub fn contains(&self, x: DVec3) -> bool {
        self.face_distance(x) <= self.spec.width
    }
}

/// What a particle is matched on.
pub struct ParticleKey {
    /// World position at rest.
    pub x: DVec3,
    /// Depth below the object's surface (world units).
    pub depth: f64,
    /// Index into the object's label names, if the particle has a label.
    pub label: Option<u16>,
}

/// An object's regions, validated and with their materials built.
pub struct ObjectRegions {
    tests: Vec<Test>,
    /// Per region: its material and density.
    pub materials: Vec<(Material, f64)>,
    /// Per region: the DC colour of its fill particles, if it sets one.
    pub fill_dc: Vec<Option<[f32; 3]>>,
}

impl ObjectRegions {
    /// Check `specs` (the regions of `objects[object]`) and build their materials.
    /// `labels` are the labels the object's Gaussians carry, as (name, id) (empty when it
    /// has none).
    pub fn build(
        origin: &str,
        object: usize,
        specs: &[RegionSpec],
        labels: &[(String, u16)],
    ) -> Result<Self, SceneError> {
        let base = format!("objects[{object}].physics.regions");
        if specs.len() > MAX_REGIONS {
            return Err(SceneError::invalid(
                origin,
                base,
                format!("{} regions", specs.len()),
                format!("at most {MAX_REGIONS} regions"),
            ));
        }
        let mut out = ObjectRegions {
            tests: Vec::with_capacity(specs.len()),
            materials: Vec::with_capacity(specs.len()),
            fill_dc: Vec::with_capacity(specs.len()),
        };
        for (j, spec) in specs.iter().enumerate() {
            let field = format!("{base}[{j}]");
            out.tests.push(spec.test(origin, &field, labels)?);
            let material = spec.material.build(origin, &format!("{field}.material"))?;
            out.materials.push((material, spec.material.density()));
            if let Some(c) = spec.color {
                if !c.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)) {
                    return Err(SceneError::invalid(
                        origin,
                        format!("{field}.color"),
                        format!("{c:?}"),
                        "three numbers in [0, 1] (linear RGB)",
                    ));
                }
            }
            out.fill_dc
                .push(spec.color.map(crate::splat::sh::rgb_to_dc));
        }
        Ok(out)
    }

    pub fn is_empty(&self) -> bool {
        self.tests.is_empty()
    }

    /// Whether any region needs depths below the surface.
    pub fn needs_depth(&self) -> bool {
        self.tests.iter().any(|t| matches!(t, Test::Shell { .. }))
    }

    /// Place every `voronoi` region's cell centres on the object's rest particles `xs`
    /// (before [`ObjectRegions::region_of`]). An object with fewer particles than cells
    /// is refused.
    pub fn place(&mut self, origin: &str, object: usize, xs: &[DVec3]) -> Result<(), SceneError> {
        for (j, t) in self.tests.iter_mut().enumerate() {
            if let Test::Voronoi(v) = t {
                if xs.len() < v.spec.cells as usize {
                    return Err(SceneError::invalid(
                        origin,
                        format!("objects[{object}].physics.regions[{j}].voronoi.cells"),
                        v.spec.cells,
                        format!("at most the object's {} particles", xs.len()),
                    ));
                }
                v.place(xs);
            }
        }
        Ok(())
    }

    /// The first region the particle lies in, or None (the object's own material).
    pub fn region_of(&self, key: &ParticleKey) -> Option<usize> {
        self.tests.iter().position(|t| match t {
            Test::Shell { from, to } => key.depth >= *from && key.depth < *to,
            Test::Select(s) => s.contains(key.x),
            Test::Label(l) => key.label == Some(*l),
            Test::Voronoi(v) => v.contains(key.x),
        })
    }
}

impl RegionSpec {
    /// The validated test: exactly one selector with sane values.
    // Over 80 lines on purpose: one check per selector kind, each with its own error.
    fn test(
        &self,
        origin: &str,
        field: &str,
        labels: &[(String, u16)],
    ) -> Result<Test, SceneError> {
        let given: Vec<&str> = [
            ("shell", self.shell.is_some()),
            ("box", self.box_region.is_some()),
            ("sphere", self.sphere.is_some()),
            ("label", self.label.is_some()),
            ("voronoi", self.voronoi.is_some()),
        ]
        .iter()
        .filter(|(_, set)| *set)
        .map(|(name, _)| *name)
        .collect();
        if given.len() != 1 {
            return Err(SceneError::invalid(
                origin,
                field.to_string(),
                if given.is_empty() {
                    "no selector".to_string()
                } else {
                    given.join(" and ")
                },
                "exactly one of `shell`, `box`, `sphere`, `label` or `voronoi`",
            ));
        }
        if let Some(ShellRange { from, to }) = &self.shell {
            if !(from.is_finite() && to.is_finite() && *from >= 0.0 && to > from) {
                return Err(SceneError::invalid(
                    origin,
                    format!("{field}.shell"),
                    format!("from {from} to {to}"),
                    "finite depths with 0 ≤ from < to (world units below the surface)",
                ));
            }
            return Ok(Test::Shell {
                from: *from,
                to: *to,
            });
        }
        if let Some(b) = &self.box_region {
            let s = SelectSpec::Box { lo: b.lo, hi: b.hi };
            s.validate(origin, field)?;
            return Ok(Test::Select(s));
        }
        if let Some(b) = &self.sphere {
            let s = SelectSpec::Sphere {
                center: b.center,
                radius: b.radius,
            };
            s.validate(origin, field)?;
            return Ok(Test::Select(s));
        }
        if let Some(v) = &self.voronoi {
            if !(2..=MAX_VORONOI_CELLS).contains(&v.cells) {
                return Err(SceneError::invalid(
                    origin,
                    format!("{field}.voronoi.cells"),
                    v.cells,
                    format!("a number of cells from 2 to {MAX_VORONOI_CELLS}"),
                ));
            }
            if !(v.width.is_finite() && v.width > 0.0) {
                return Err(SceneError::invalid(
                    origin,
                    format!("{field}.voronoi.width"),
                    v.width,
                    "a face half-thickness > 0 in world units",
                ));
            }
            return Ok(Test::Voronoi(VoronoiPartition {
                spec: v.clone(),
                centres: Vec::new(),
            }));
        }
        let label = self.label.as_deref().unwrap_or_default();
        match labels.iter().find(|(n, _)| n == label) {
            Some((_, id)) => Ok(Test::Label(*id)),
            None => Err(SceneError::invalid(
                origin,
                format!("{field}.label"),
                format!("{label:?}"),
                if labels.is_empty() {
                    "a label of the object's Gaussians (this object has no labels)".to_string()
                } else {
                    let names: Vec<&str> = labels.iter().map(|(n, _)| n.as_str()).collect();
                    format!("one of the object's labels: {}", names.join(", "))
                },
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn partition(cells: u32, width: f64, seed: u64) -> VoronoiPartition {
        VoronoiPartition {
            spec: VoronoiFaces { cells, width, seed },
            centres: Vec::new(),
        }
    }

    /// A jittered lattice of points in the unit cube.
    fn cloud(n: usize) -> Vec<DVec3> {
        let mut rng = SplitMix64::new(3);
        (0..n * n * n)
            .map(|i| {
                let ijk = DVec3::new((i % n) as f64, (i / n % n) as f64, (i / n / n) as f64);
                (ijk + DVec3::new(rng.uniform(), rng.uniform(), rng.uniform())) / n as f64
            })
            .collect()
    }

    /// With two cells the one face is the bisecting plane of the centres: every point's
    /// face distance is its distance to that plane, and the region is the slab around it.
    #[test]
    fn two_cells_meet_on_the_bisecting_plane() {
        let xs = cloud(12);
        let mut v = partition(2, 0.05, 11);
        v.place(&xs);
        let (a, b) = (v.centres[0], v.centres[1]);
        let n = (b - a).normalize();
        let mid = 0.5 * (a + b);
        for &x in &xs {
            let plane = (x - mid).dot(n).abs();
            assert!((v.face_distance(x) - plane).abs() < 1e-12, "{x}");
            assert_eq!(v.contains(x), plane <= 0.05, "{x}");
        }
    }

    /// With many cells, a point's face distance d is the distance to its cell's boundary:
    /// a step of just under d in any direction keeps its nearest centre, and a step of d
    /// straight at the nearest bisector lands on it (equally far from two centres).
    #[test]
    fn the_face_distance_is_the_distance_to_the_cell_boundary() {
        let xs = cloud(10);
        let mut v = partition(7, 0.02, 5);
        v.place(&xs);
        let nearest = |x: DVec3| {
            v.centres
                .iter()
                .copied()
                .min_by(|p, q| x.distance(*p).total_cmp(&x.distance(*q)))
                .unwrap()
        };
        let mut rng = SplitMix64::new(9);
        for &x in xs.iter().step_by(13) {
            let d = v.face_distance(x);
            let c = nearest(x);
            assert!(d >= 0.0, "{x}: {d}");
            for _ in 0..64 {
                let dir = DVec3::new(rng.uniform(), rng.uniform(), rng.uniform()) - 0.5;
                let step = x + dir.normalize() * 0.999 * d;
                assert_eq!(nearest(step), c, "{x} moved {d} along {dir}");
            }
            let hits = v.centres.iter().filter(|q| **q != c).any(|q| {
                let foot = x + (*q - c).normalize() * d;
                (foot.distance(*q) - foot.distance(c)).abs() < 1e-9
            });
            assert!(hits, "{x}: no bisector at distance {d}");
        }
    }

    /// The seed decides the centres; best-candidate placement spreads them: no two closer
    /// than a third of the spacing of a regular arrangement of as many cells.
    #[test]
    fn centres_are_reproducible_and_spread() {
        let xs = cloud(16);
        let place = |seed| {
            let mut v = partition(8, 0.01, seed);
            v.place(&xs);
            v.centres
        };
        assert_eq!(place(4), place(4));
        assert_ne!(place(4), place(5));
        let c = place(4);
        let closest = (0..c.len())
            .flat_map(|i| (0..i).map(move |j| (i, j)))
            .map(|(i, j)| c[i].distance(c[j]))
            .fold(f64::INFINITY, f64::min);
        let regular = 1.0 / (c.len() as f64).cbrt();
        assert!(closest > regular / 3.0, "closest centres {closest}");
    }
}
