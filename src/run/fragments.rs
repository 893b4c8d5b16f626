//! `--fragments`: per rendered frame and simulated object, how many pieces its particles
//! form ([`crate::fragments`]), appended to `OUT/fragments.csv` as the frames go.

use std::io::Write;
use std::path::Path;

use anyhow::{Context, Result};

use crate::fragments::{fragment_sizes, FragmentSummary, PIECE_SHARE};
use crate::scene::simulation::{PartKind, SimulationSetup};
use crate::scene::Scene;
use crate::sim::{Material, Particles};

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
fn height_extent(points: &[glam::DVec3]) -> f64 {
    if points.is_empty() {
        return 0.0;
    }
    let mut z: Vec<f64> = points.iter().map(|p| p.z).collect();
    z.sort_unstable_by(f64::total_cmp);
    let at = |q: f64| z[((z.len() - 1) as f64 * q).round() as usize];
    at(0.99) - at(0.01)
}

/// The open `fragments.csv` and the last frame's counts.
pub struct FragmentLog {
    file: std::io::BufWriter<std::fs::File>,
    last: Vec<(String, u32, FragmentSummary)>,
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
                "frame,object,particles,pieces,largest_share,debris,fragments,damaged_share,height"
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
        let mut objects: Vec<usize> = s
            .parts
            .iter()
            .filter(|p| p.kind != PartKind::Static)
            .map(|p| p.object)
            .collect();
        objects.dedup();
        for object in objects {
            // The object's particles: its simulated parts, in particle order.
            let particles: Vec<usize> = s
                .parts
                .iter()
                .filter(|p| p.object == object && p.kind != PartKind::Static)
                .flat_map(|p| p.start - s.static_count..p.start - s.static_count + p.len)
                .collect();
            let points: Vec<glam::DVec3> = particles.iter().map(|&i| state.x[i]).collect();
            let damaged = particles
                .iter()
                .filter(|&&i| {
                    matches!(
                        s.materials[state.material[i] as usize],
                        Material::Nacc { .. }
                    ) && state.alpha[i] >= 0.0
                })
                .count();
            let height = height_extent(&points);
            let sizes = fragment_sizes(&points, s.grid.dx);
            let summary = FragmentSummary::new(&sizes, PIECE_SHARE);
            let name = scene.objects[object]
                .name
                .clone()
                .unwrap_or_else(|| format!("objects[{object}]"));
            let name = csv_field(&name);
            writeln!(
                self.file,
                "{frame},{name},{},{},{:.4},{},{},{:.4},{height:.4}",
                summary.particles,
                summary.pieces,
                summary.largest_share,
                summary.debris,
                summary.fragments,
                damaged as f64 / summary.particles.max(1) as f64
            )?;
            self.last.push((name, frame, summary));
        }
        self.file.flush()?;
        Ok(())
    }

    /// The last recorded frame, per object: name, frame, pieces.
    pub fn last(&self) -> &[(String, u32, FragmentSummary)] {
        &self.last
    }

    /// The closing lines of `--fragments`.
    pub fn describe(last: &[(String, u32, FragmentSummary)]) -> Vec<String> {
        last.iter().map(|(name, frame, s)| format!(
                "fragments: {name} at frame {frame}: {} piece(s) with ≥ {:.0}% of its {} particles (largest {:.1}%), {} particles of debris, {} fragments in all",
                s.pieces,
                PIECE_SHARE * 100.0,
                s.particles,
                s.largest_share * 100.0,
                s.debris,
                s.fragments
            )).collect()
    }
}
