//! `--export-particles`: each rendered frame's MPM particles as a binary PLY point cloud,
//! so that the physics can be inspected, plotted or compared with another solver, and
//! `splatter fragments` can count the pieces of any solver's particles the way
//! `--fragments` counts ours.
//!
//! Format (docs/formats.md, *Particle files*): `binary_little_endian` PLY, one `vertex`
//! per particle with `float x y z vx vy vz mass volume log_jp damage` and `int material
//! object`; a header comment `dx D` gives the grid spacing, the default link distance of
//! the fragment counter. `log_jp` is the hardening state α where the plastic model keeps
//! ln Jᴾ there (NACC, Drucker–Prager, snow), NaN otherwise; `damage` is the material's
//! damage d(α) ∈ [0, 1] (`Material::damage`, 1: the particle's cohesion is gone).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use glam::DVec3;
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{DefaultElement, Property};

use crate::fragments::{solid_fragment_ids, FragmentSummary, PIECE_SHARE};
use crate::output::export::frame_ply_path;
use crate::output::write_atomically;
use crate::scene::simulation::SimulationSetup;
use crate::sim::Particles;

/// The float properties of a particle record, in file order.
const FLOATS: [&str; 10] = [
    "x", "y", "z", "vx", "vy", "vz", "mass", "volume", "log_jp", "damage",
];
/// The integer properties, after the floats.
const INTS: [&str; 2] = ["material", "object"];

/// `DIR/frame_00042.ply`, named like the Gaussians' `--export-ply` files.
pub fn frame_particles_path(dir: &Path, frame: u32) -> PathBuf {
    frame_ply_path(dir, frame)
}

/// The header of a file of `n` particles on a grid of spacing `dx`.
fn header(n: usize, dx: f64, comment: &str) -> String {
    let mut h = format!(
        "ply\nformat binary_little_endian 1.0\ncomment splatter MPM particles: {comment}\ncomment dx {dx:e}\nelement vertex {n}\n"
    );
    for name in FLOATS {
        h.push_str(&format!("property float {name}\n"));
    }
    for name in INTS {
        h.push_str(&format!("property int {name}\n"));
    }
    h.push_str("end_header\n");
    h
}

/// Encode the particles of a run: every body's particles, with the body's object index.
pub fn encode(state: &Particles, setup: &SimulationSetup, comment: &str) -> Vec<u8> {
    let mut bytes = header(state.len(), setup.grid.dx, comment).into_bytes();
    bytes.reserve(state.len() * (FLOATS.len() + INTS.len()) * 4);
    for body in &setup.bodies {
        for i in body.particles.clone() {
            let material = &setup.materials[state.material[i] as usize];
            let alpha = state.alpha[i];
            let log_jp = if material.plastic_model().alpha_is_log_jp() {
                alpha
            } else {
                f64::NAN
            };
            let (x, v) = (state.x[i], state.v[i]);
            for value in [x.x, x.y, x.z, v.x, v.y, v.z].into_iter().chain([
                state.mass[i],
                state.volume0[i],
                log_jp,
                material.damage(alpha),
            ]) {
                bytes.extend_from_slice(&(value as f32).to_le_bytes());
            }
            bytes.extend_from_slice(&(state.material[i] as i32).to_le_bytes());
            bytes.extend_from_slice(&(body.object as i32).to_le_bytes());
        }
    }
    bytes
}

/// Write frame `frame`'s particles to `DIR/frame_NNNNN.ply`, atomically.
pub fn export_frame(
    dir: &Path,
    frame: u32,
    state: &Particles,
    setup: &SimulationSetup,
) -> Result<PathBuf> {
    let path = frame_particles_path(dir, frame);
    let bytes = encode(state, setup, &format!("frame {frame}"));
    write_atomically(&path, &bytes)?;
    Ok(path)
}

/// Particles read back from a particle file (ours or any PLY point cloud with `x y z`).
#[derive(Clone, Debug, Default)]
pub struct ParticleFile {
    pub x: Vec<DVec3>,
    /// α = log Jᴾ per particle, when the file has `log_jp`.
    pub log_jp: Option<Vec<f64>>,
    /// Damage d ∈ [0, 1] per particle, when the file has `damage`.
    pub damage: Option<Vec<f64>>,
    /// The object each particle belongs to, when the file has `object`.
    pub object: Option<Vec<i64>>,
    /// The `comment dx D` of the header.
    pub dx: Option<f64>,
}

fn scalar(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::Char(v) => v as f64,
        Property::UChar(v) => v as f64,
        Property::Short(v) => v as f64,
        Property::UShort(v) => v as f64,
        Property::Int(v) => v as f64,
        Property::UInt(v) => v as f64,
        Property::Float(v) => v as f64,
        Property::Double(v) => v,
        _ => return None,
    })
}

/// Read a PLY point cloud's `vertex` positions, and `log_jp`, `object` and the `dx`
/// comment where present.
pub fn read(path: &Path) -> Result<ParticleFile> {
    let file =
        std::fs::File::open(path).with_context(|| format!("cannot open {}", path.display()))?;
    let mut reader = std::io::BufReader::new(file);
    let parser = Parser::<DefaultElement>::new();
    let ply = parser
        .read_ply(&mut reader)
        .map_err(|e| anyhow::anyhow!("{}: not a readable PLY file: {e}", path.display()))?;
    let dx = ply.header.comments.iter().find_map(|c| {
        c.strip_prefix("dx ")
            .and_then(|v| v.trim().parse::<f64>().ok())
    });
    let Some(vertices) = ply.payload.get("vertex") else {
        bail!("{}: no `vertex` element", path.display());
    };
    let column = |name: &str| -> Result<Option<Vec<f64>>> {
        if !vertices.first().is_some_and(|v| v.contains_key(name)) {
            return Ok(None);
        }
        vertices
            .iter()
            .enumerate()
            .map(|(i, v)| {
                v.get(name).and_then(scalar).with_context(|| {
                    format!(
                        "{}: vertex {i}: property `{name}` missing or not a scalar",
                        path.display()
                    )
                })
            })
            .collect::<Result<Vec<f64>>>()
            .map(Some)
    };
    let mut axes = Vec::new();
    for name in ["x", "y", "z"] {
        match column(name)? {
            Some(c) => axes.push(c),
            None => bail!(
                "{}: the vertices have no `{name}` property (a point cloud needs x, y, z)",
                path.display()
            ),
        }
    }
    let x = (0..vertices.len())
        .map(|i| DVec3::new(axes[0][i], axes[1][i], axes[2][i]))
        .collect();
    let object = column("object")?.map(|c| c.into_iter().map(|v| v as i64).collect());
    Ok(ParticleFile {
        x,
        log_jp: column("log_jp")?,
        damage: column("damage")?,
        object,
        dx,
    })
}

/// The pieces of one object's particles in a [`ParticleFile`].
#[derive(Clone, Debug)]
pub struct ObjectPieces {
    /// The `object` index; `None` when the file has no `object` property.
    pub object: Option<i64>,
    /// Its pieces; with a `damage` property, particles broken through link nothing.
    pub summary: FragmentSummary,
    /// Share of the object's particles whose damage is 1 (from `damage`, or for files
    /// without it, NACC's reading of `log_jp`: α ≥ 0).
    pub damaged_share: Option<f64>,
}

impl ParticleFile {
    /// The pieces of each object's particles (of all of them without `object`), linked
    /// at `link` as `--fragments` links ours, in object order.
    pub fn pieces(&self, link: f64) -> Vec<ObjectPieces> {
        let mut objects: Vec<Option<i64>> = match &self.object {
            Some(o) => o.iter().copied().map(Some).collect(),
            None => vec![None],
        };
        objects.sort_unstable();
        objects.dedup();
        objects
            .into_iter()
            .map(|object| {
                let members: Vec<usize> = (0..self.x.len())
                    .filter(|&i| self.object.as_ref().is_none_or(|o| Some(o[i]) == object))
                    .collect();
                let points: Vec<DVec3> = members.iter().map(|&i| self.x[i]).collect();
                // Rubble links nothing where the file says which particles are broken.
                let intact: Vec<bool> = match &self.damage {
                    Some(d) => members.iter().map(|&i| d[i] < 1.0).collect(),
                    None => vec![true; members.len()],
                };
                let summary =
                    FragmentSummary::of(&solid_fragment_ids(&points, &intact, link), PIECE_SHARE);
                let damaged = match (&self.damage, &self.log_jp) {
                    (Some(d), _) => Some((d, 1.0)),
                    (None, Some(a)) => Some((a, 0.0)),
                    (None, None) => None,
                };
                let damaged_share = damaged.map(|(a, at)| {
                    let n = members.iter().filter(|&&i| a[i] >= at).count();
                    n as f64 / members.len().max(1) as f64
                });
                ObjectPieces {
                    object,
                    summary,
                    damaged_share,
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The damaged share counts d = 1 from `damage`; a file without it falls back to
    /// NACC's α ≥ 0 in `log_jp` (a von Mises α, the plastic strain, is never read as
    /// damage: its file has `damage` 0 and `log_jp` NaN).
    #[test]
    fn damaged_share_reads_damage_before_log_jp() {
        let x = vec![DVec3::ZERO; 4];
        let mut file = ParticleFile {
            x,
            log_jp: Some(vec![0.5, -0.1, f64::NAN, 0.0]),
            damage: Some(vec![1.0, 0.3, 0.0, 0.0]),
            object: None,
            dx: None,
        };
        assert_eq!(file.pieces(0.1)[0].damaged_share, Some(0.25));
        file.damage = None;
        assert_eq!(file.pieces(0.1)[0].damaged_share, Some(0.5));
        file.log_jp = None;
        assert_eq!(file.pieces(0.1)[0].damaged_share, None);
    }
}
