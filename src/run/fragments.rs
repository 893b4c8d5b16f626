//! `--fragments`: per rendered frame and simulated object, how many pieces its particles
//! form ([`crate::fragments`]) and how its Gaussians follow them, appended to
//! `OUT/fragments.csv` as the frames go.

use std::io::Write;
use std::path::Path;

use anyhow::{Context, Result};

use glam::DVec3;

use crate::derive::binding::{bound_mean, Binding};
use crate::fragments::{fragment_ids, solid_fragment_ids, FragmentSummary, PIECE_SHARE};
use crate::render::splats::mat3_from_sym3;
use crate::scene::simulation::{Body, SimulationSetup};
use crate::scene::Scene;
use crate::sim::svd::symmetric_eigen;
use crate::sim::Particles;

/// A CSV field: quoted (with doubled quotes) when it holds a comma, quote or line break.
fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Vertical extent of a body (z from its 1st to its 99th percentile, so that a few
/// thrown-off particles do not count): how far a slumping heap has sunk.
fn height_extent(points: &[DVec3]) -> f64 {
    if points.is_empty() {
        return 0.0;
    }
    let mut z: Vec<f64> = points.iter().map(|p| p.z).collect();
    z.sort_unstable_by(f64::total_cmp);
    let at = |q: f64| z[((z.len() - 1) as f64 * q).round() as usize];
    at(0.99) - at(0.01)
}

/// What tells a stable run from one that gains energy: the fastest particle, the kinetic
/// plus gravitational energy ½ Σ m|v|² − Σ m g·x (joules; elastic energy is not counted, so
/// it dips during an impact and may never rise above its start in a sound run), and the
/// particles whose position or velocity is not finite (left out of both).
struct Motion {
    speed_max: f64,
    energy: f64,
    nonfinite: usize,
}

impl Motion {
    fn of(particles: std::ops::Range<usize>, state: &Particles, gravity: DVec3) -> Self {
        let mut m = Motion {
            speed_max: 0.0,
            energy: 0.0,
            nonfinite: 0,
        };
        for i in particles {
            let (x, v, mass) = (state.x[i], state.v[i], state.mass[i]);
            if !(x.is_finite() && v.is_finite()) {
                m.nonfinite += 1;
                continue;
            }
            m.speed_max = m.speed_max.max(v.length());
            m.energy += 0.5 * mass * v.length_squared() - mass * gravity.dot(x);
        }
        m
    }
}

/// How a body's Gaussians follow its fragments (the derive pass's f64 twin, on the state
/// read back).
struct GaussianFragments {
    gaussians: usize,
    /// Share of the Gaussians moved by particles of the largest fragment.
    largest_share: f64,
    /// The largest growth of a Gaussian's extent: √(λ_max(F A Fᵀ) / λ_max(A)).
    stretch: f64,
    /// Gaussians nearer to a particle of another fragment than to the particle that moves
    /// them: pulled across a crack.
    astray: usize,
}

impl GaussianFragments {
    /// `points` are the body's particles now, `solid` their pieces' numbering (the largest
    /// share's) and `linked` their fragments linking every particle (astray's: a Gaussian
    /// pulled across a crack is one whose particle is no longer beside it).
    fn new(
        body: &Body,
        points: &[DVec3],
        solid: &[u32],
        linked: &[u32],
        state: &Particles,
        s: &SimulationSetup,
    ) -> Self {
        let first = body.particles.start;
        let bound = |g: usize| {
            let k = g - s.static_count;
            (
                s.binding.particle[k] as usize,
                s.binding.offset[k].as_dvec3(),
            )
        };
        let mut in_largest = 0;
        let mut stretch: f64 = 1.0;
        let mut means = Vec::with_capacity(body.gaussians.len());
        for g in body.gaussians.clone() {
            let (p, offset) = bound(g);
            in_largest += usize::from(solid[p - first] == 0);
            let a = mat3_from_sym3(s.splats.covariances[g]).as_dmat3();
            let f = state.f[p];
            let rest = symmetric_eigen(a).0.max_element();
            let now = symmetric_eigen(f * a * f.transpose()).0.max_element();
            if rest > 0.0 && now.is_finite() {
                stretch = stretch.max((now / rest).sqrt());
            }
            means.push(bound_mean(state.x[p], f, offset).as_vec3());
        }
        let nearest = Binding::nearest(&means, points, 0, s.grid.dx);
        let astray = body
            .gaussians
            .clone()
            .zip(&nearest.particle)
            .filter(|&(g, &q)| linked[bound(g).0 - first] != linked[q as usize])
            .count();
        let gaussians = body.gaussians.len();
        GaussianFragments {
            gaussians,
            largest_share: in_largest as f64 / gaussians.max(1) as f64,
            stretch,
            astray,
        }
    }
}

/// One simulated object's fragments at a recorded frame.
#[derive(Clone, Debug)]
pub struct ObjectFragments {
    /// The object's name (or `objects[i]`), as a CSV field.
    pub name: String,
    pub frame: u32,
    /// Its pieces: solid fragments, rubble linking nothing ([`crate::fragments`]).
    pub pieces: FragmentSummary,
    /// Its fragments linking every particle, rubble included.
    pub linked: FragmentSummary,
}

/// The open `fragments.csv` and the last frame's counts.
pub struct FragmentLog {
    file: std::io::BufWriter<std::fs::File>,
    last: Vec<ObjectFragments>,
}

impl FragmentLog {
    /// With `resume`, rows of an earlier run of the same output directory are kept and the
    /// resumed frames appended after them.
    pub fn create(path: &Path, resume: bool) -> Result<Self> {
        let append = resume && path.is_file();
        let file = std::fs::OpenOptions::new()
            .create(true)
            .append(append)
            .write(true)
            .truncate(!append)
            .open(path)
            .with_context(|| format!("--fragments: cannot create {}", path.display()))?;
        let mut file = std::io::BufWriter::new(file);
        if !append {
            writeln!(
                file,
                "frame,object,particles,pieces,largest_share,debris,fragments,damaged_share,height,gaussians,gaussian_largest_share,stretch,astray,speed_max,energy,nonfinite,linked_pieces,linked_largest_share"
            )?;
        }
        Ok(Self {
            file,
            last: Vec::new(),
        })
    }

    pub fn record(
        &mut self,
        frame: u32,
        state: &Particles,
        s: &SimulationSetup,
        scene: &Scene,
    ) -> Result<()> {
        self.last.clear();
        for body in &s.bodies {
            let points: Vec<DVec3> = body.particles.clone().map(|i| state.x[i]).collect();
            let intact: Vec<bool> = body
                .particles
                .clone()
                .map(|i| s.materials[state.material[i] as usize].damage(state.alpha[i]) < 1.0)
                .collect();
            let damaged = intact.iter().filter(|&&ok| !ok).count();
            let height = height_extent(&points);
            let motion = Motion::of(body.particles.clone(), state, s.params.gravity);
            let solid = solid_fragment_ids(&points, &intact, s.grid.dx);
            let linked = fragment_ids(&points, s.grid.dx);
            let look = GaussianFragments::new(body, &points, &solid, &linked, state, s);
            let summary = FragmentSummary::of(&solid, PIECE_SHARE)
                .with_gaussians(look.gaussians, look.largest_share);
            let linked = FragmentSummary::of(&linked, PIECE_SHARE);
            let name = scene.objects[body.object]
                .name
                .clone()
                .unwrap_or_else(|| format!("objects[{}]", body.object));
            let name = csv_field(&name);
            writeln!(
                self.file,
                "{frame},{name},{},{},{:.4},{},{},{:.4},{height:.4},{},{:.4},{:.4},{},{:.4},{:.6e},{},{},{:.4}",
                summary.particles,
                summary.pieces,
                summary.largest_share,
                summary.debris,
                summary.fragments,
                damaged as f64 / summary.particles.max(1) as f64,
                look.gaussians,
                look.largest_share,
                look.stretch,
                look.astray,
                motion.speed_max,
                motion.energy,
                motion.nonfinite,
                linked.pieces,
                linked.largest_share,
            )?;
            self.last.push(ObjectFragments {
                name,
                frame,
                pieces: summary,
                linked,
            });
        }
        self.file.flush()?;
        Ok(())
    }

    /// The last recorded frame, per object.
    pub fn last(&self) -> &[ObjectFragments] {
        &self.last
    }

    /// The closing lines of `--fragments`.
    pub fn describe(last: &[ObjectFragments]) -> Vec<String> {
        last.iter()
            .map(|o| {
                let (s, l) = (&o.pieces, &o.linked);
                format!(
                    "fragments: {} at frame {}: {} piece(s) with ≥ {:.0}% of its {} particles (largest {:.1}%), {} particles of debris ({} broken through), {} fragments in all; the largest moves {:.1}% of its {} Gaussians; linked through the broken particles: {} piece(s), largest {:.1}%",
                    o.name,
                    o.frame,
                    s.pieces,
                    PIECE_SHARE * 100.0,
                    s.particles,
                    s.largest_share * 100.0,
                    s.debris,
                    s.rubble,
                    s.fragments,
                    s.gaussian_largest_share * 100.0,
                    s.gaussians,
                    l.pieces,
                    l.largest_share * 100.0,
                )
            })
            .collect()
    }
}
