//! Procedural Gaussian objects (sphere, box, cylinder, ground slab, and the assets of
//! [`super::assets`]: watermelon, pumpkin, table, …), so that scenes and tests need no
//! downloaded captures. Each object is a jittered lattice of isotropic Gaussians filling
//! the solid, coloured and labelled per region: for the basic shapes `shells` by depth
//! below the surface (outermost first) and the `color` for everything deeper; an asset has
//! its own regions and palette.

use glam::{Quat, Vec3};
use rayon::prelude::*;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::assets::{Asset, Kind};
use super::sh::rgb_to_dc;
use super::GaussianCloud;
use crate::rng::SplitMix64;

mod checks;
mod solid;
use checks::{color_ok, invalid, positive, positive_all, unit_color, POSITIVE, UNIT};
use solid::{RegionColors, Solid};

/// The solid to fill. All shapes are centred on the object's origin; the slab's top face is
/// at z = 0 (z is up) so that it can serve as a ground.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "shape", rename_all = "snake_case", deny_unknown_fields)]
pub enum Shape {
    Sphere {
        radius: f32,
    },
    Box {
        size: [f32; 3],
    },
    /// Axis along z.
    Cylinder {
        radius: f32,
        height: f32,
    },
    /// A thin box whose top face is z = 0: `size` is its extent in x and y.
    Slab {
        size: [f32; 2],
        thickness: f32,
    },
    // Assets (`splat::assets`): `size` is the full extent [x, y, z] of the box the asset
    // fills, centred on the origin; each has a default.
    Watermelon {
        #[serde(default)]
        size: Option<[f32; 3]>,
    },
    Jelly {
        #[serde(default)]
        size: Option<[f32; 3]>,
    },
    Pumpkin {
        #[serde(default)]
        size: Option<[f32; 3]>,
    },
    Kiwi {
        #[serde(default)]
        size: Option<[f32; 3]>,
    },
    Pineapple {
        #[serde(default)]
        size: Option<[f32; 3]>,
    },
    Dragonfruit {
        #[serde(default)]
        size: Option<[f32; 3]>,
    },
    Toast {
        #[serde(default)]
        size: Option<[f32; 3]>,
    },
    Sandcastle {
        #[serde(default)]
        size: Option<[f32; 3]>,
    },
    Pillow {
        #[serde(default)]
        size: Option<[f32; 3]>,
    },
    Cloth {
        #[serde(default)]
        size: Option<[f32; 3]>,
    },
    Table {
        #[serde(default)]
        size: Option<[f32; 3]>,
    },
    Knife {
        #[serde(default)]
        size: Option<[f32; 3]>,
    },
    Projectile {
        #[serde(default)]
        size: Option<[f32; 3]>,
    },
}

impl Shape {
    /// The asset this shape names and its size as given, `None` for the basic shapes.
    pub fn asset_kind(&self) -> Option<(Kind, Option<[f32; 3]>)> {
        let (kind, size) = match self {
            Shape::Sphere { .. }
            | Shape::Box { .. }
            | Shape::Cylinder { .. }
            | Shape::Slab { .. } => return None,
            Shape::Watermelon { size } => (Kind::Watermelon, size),
            Shape::Jelly { size } => (Kind::Jelly, size),
            Shape::Pumpkin { size } => (Kind::Pumpkin, size),
            Shape::Kiwi { size } => (Kind::Kiwi, size),
            Shape::Pineapple { size } => (Kind::Pineapple, size),
            Shape::Dragonfruit { size } => (Kind::Dragonfruit, size),
            Shape::Toast { size } => (Kind::Toast, size),
            Shape::Sandcastle { size } => (Kind::Sandcastle, size),
            Shape::Pillow { size } => (Kind::Pillow, size),
            Shape::Cloth { size } => (Kind::Cloth, size),
            Shape::Table { size } => (Kind::Table, size),
            Shape::Knife { size } => (Kind::Knife, size),
            Shape::Projectile { size } => (Kind::Projectile, size),
        };
        Some((kind, *size))
    }

    /// The asset at its size (the default when none is given).
    pub fn asset(&self) -> Option<Asset> {
        let (kind, size) = self.asset_kind()?;
        Some(Asset::new(kind, size.unwrap_or(kind.default_size())))
    }
}

/// A layer of the solid within `depth` of the surface (measured from the previous shell).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Shell {
    pub depth: f32,
    pub color: [f32; 3],
}

fn default_opacity() -> f32 {
    0.95
}
fn default_jitter() -> f32 {
    0.25
}

/// A procedural object as it appears in a scene file.
///
/// No `deny_unknown_fields` here: serde does not support it together with `flatten` (every
/// spec would fail with "unknown field `shape`"). Unknown fields are still refused, because
/// serde hands the fields this struct does not know to the flattened [`Shape`], which
/// denies them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ProceduralSpec {
    #[serde(flatten)]
    pub shape: Shape,
    /// Lattice spacing: distance between neighbouring Gaussians.
    pub spacing: f32,
    /// Colour (RGB in [0, 1]) of the core, below all shells. Required for the basic
    /// shapes; for an asset it optionally repaints its first region (`rind`, `jelly`, …).
    #[serde(default)]
    pub color: Option<[f32; 3]>,
    /// Surface layers, outermost first (basic shapes only).
    #[serde(default)]
    pub shells: Vec<Shell>,
    /// A checkerboard on the top face region (period in world units) — used for grounds.
    #[serde(default)]
    pub checker: Option<Checker>,
    #[serde(default = "default_opacity")]
    pub opacity: f32,
    /// Random offset of each lattice point, as a fraction of `spacing`.
    #[serde(default = "default_jitter")]
    pub jitter: f32,
    #[serde(default)]
    pub seed: u64,
}

/// Alternating colour squares of side `period` (in x and y), replacing `color` and shells.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Checker {
    pub period: f32,
    pub colors: [[f32; 3]; 2],
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ProceduralError {
    #[error("field `{field}` = {value}: {expected}")]
    Invalid {
        field: &'static str,
        value: String,
        expected: &'static str,
    },
    #[error("{count} Gaussians would be generated (spacing {spacing} is too fine for the shape); at most {max} are allowed")]
    TooMany { count: u64, spacing: f32, max: u64 },
}

/// Largest procedural object we agree to generate.
pub const MAX_PROCEDURAL_GAUSSIANS: u64 = 50_000_000;

/// Standard deviation of every procedural Gaussian, as a multiple of `spacing`.
///
/// 0.6 makes the solid read as opaque without visible blobs: halfway between two lattice
/// neighbours each Gaussian still reaches exp(−(0.5/0.6)²/2) ≈ 0.71 of its opacity, and at
/// the centre of a lattice square ≈ 0.5, so one lattice layer already covers ≥ 90 % of the
/// surface at the default opacity and the layer below closes the rest; yet the visible
/// footprint (≈ 2σ = 1.2 spacings) barely reaches past the nearest neighbours, so single
/// Gaussians do not stand out as bumps on the silhouette.
pub const SCALE_PER_SPACING: f32 = 0.6;

impl ProceduralSpec {
    /// Check every field (sizes > 0, colours finite, opacity in (0, 1], …).
    pub fn validate(&self) -> Result<(), ProceduralError> {
        if let Some((_, size)) = self.shape.asset_kind() {
            return self.validate_asset(size);
        }
        match &self.shape {
            Shape::Sphere { radius } => positive("radius", *radius)?,
            Shape::Box { size } => positive_all("size", size)?,
            Shape::Cylinder { radius, height } => {
                positive("radius", *radius)?;
                positive("height", *height)?;
            }
            Shape::Slab { size, thickness } => {
                positive_all("size", size)?;
                positive("thickness", *thickness)?;
            }
            _ => unreachable!("assets are validated above"),
        }
        positive("spacing", self.spacing)?;
        let Some(color) = &self.color else {
            return Err(invalid(
                "color",
                "missing".into(),
                "a colour [r, g, b] in [0, 1] (required for sphere, box, cylinder and slab)",
            ));
        };
        unit_color("color", color)?;
        for (i, shell) in self.shells.iter().enumerate() {
            // Past the table of static names the field is generic and `value` names the index.
            let (depth_field, color_field) = shell_fields(i);
            if !(shell.depth.is_finite() && shell.depth > 0.0) {
                let value = match depth_field {
                    Some(_) => shell.depth.to_string(),
                    None => format!("shells[{i}].depth = {}", shell.depth),
                };
                return Err(invalid(
                    depth_field.unwrap_or("shells[].depth"),
                    value,
                    POSITIVE,
                ));
            }
            if !color_ok(&shell.color) {
                let value = match color_field {
                    Some(_) => format!("{:?}", shell.color),
                    None => format!("shells[{i}].color = {:?}", shell.color),
                };
                return Err(invalid(
                    color_field.unwrap_or("shells[].color"),
                    value,
                    UNIT,
                ));
            }
        }
        if let Some(checker) = &self.checker {
            positive("checker.period", checker.period)?;
            unit_color("checker.colors[0]", &checker.colors[0])?;
            unit_color("checker.colors[1]", &checker.colors[1])?;
        }
        self.validate_common()
    }

    /// An asset's fields: `size` when given, `color` when given; no `shells` or `checker`
    /// (an asset has its own regions).
    fn validate_asset(&self, size: Option<[f32; 3]>) -> Result<(), ProceduralError> {
        if let Some(size) = size {
            positive_all("size", &size)?;
        }
        positive("spacing", self.spacing)?;
        if let Some(color) = &self.color {
            unit_color("color", color)?;
        }
        if !self.shells.is_empty() {
            return Err(invalid(
                "shells",
                format!("{} shells", self.shells.len()),
                "no shells for an asset (it has its own regions; use `color` to repaint the first)",
            ));
        }
        if self.checker.is_some() {
            return Err(invalid(
                "checker",
                "given".into(),
                "no checker for an asset (only for the basic shapes)",
            ));
        }
        self.validate_common()
    }

    /// Opacity and jitter, common to every shape.
    fn validate_common(&self) -> Result<(), ProceduralError> {
        if !(self.opacity.is_finite() && self.opacity > 0.0 && self.opacity <= 1.0) {
            return Err(invalid(
                "opacity",
                self.opacity.to_string(),
                "a number in (0, 1]",
            ));
        }
        if !(self.jitter.is_finite() && (0.0..=0.5).contains(&self.jitter)) {
            return Err(invalid(
                "jitter",
                self.jitter.to_string(),
                "a number in [0, 0.5]",
            ));
        }
        Ok(())
    }

    /// Generate the Gaussians (SH degree 0, colour stored as the DC coefficient).
    ///
    /// A cubic lattice of pitch `spacing` fills the solid (for boxes, slabs and the
    /// cylinder's height the pitch is adjusted so that a whole number of cells fits, with
    /// points at cell centres; spheres and the cylinder's cross-section use the lattice
    /// through the origin, so a shape smaller than `spacing` still gets one Gaussian).
    /// Every point moves by a uniform random offset of up to `jitter · spacing` per axis and
    /// is then clamped back into the solid. Gaussians are isotropic with standard deviation
    /// [`SCALE_PER_SPACING`] · `spacing`, identity rotation and the spec's opacity. The
    /// result depends only on the spec (the seed included), not on the thread count.
    pub fn generate(&self) -> Result<GaussianCloud, ProceduralError> {
        self.validate()?;
        let estimate = self.estimated_count();
        if estimate.is_nan() || estimate > MAX_PROCEDURAL_GAUSSIANS as f64 {
            return Err(ProceduralError::TooMany {
                // `as` saturates (and maps NaN to 0, which validate() has ruled out).
                count: estimate as u64,
                spacing: self.spacing,
                max: MAX_PROCEDURAL_GAUSSIANS,
            });
        }

        let s = f64::from(self.spacing);
        let solid = Solid::new(&self.shape);
        let [ax, ay, az] = solid.axes(s);
        let jitter = f64::from(self.jitter) * s;
        let colors = self.region_colors();

        let layers: Vec<(Vec<Vec3>, Vec<f32>, Vec<u16>)> = (0..az.count)
            .into_par_iter()
            .map(|iz| {
                let mut rng =
                    SplitMix64::new(self.seed ^ (iz as u64).wrapping_mul(0xD1B5_4A32_D192_ED03));
                let mut pos = Vec::new();
                let mut sh = Vec::new();
                let mut labels = Vec::new();
                let z = az.coord(iz);
                for iy in 0..ay.count {
                    let y = ay.coord(iy);
                    for ix in 0..ax.count {
                        let x = ax.coord(ix);
                        if !solid.contains_lattice(x, y, z) {
                            continue;
                        }
                        let mut p = [x, y, z];
                        for c in &mut p {
                            *c += (2.0 * rng.uniform() - 1.0) * jitter;
                        }
                        let p = solid.clamp(p, [x, y, z]);
                        let (dc, label) = self.color_at(&colors, &solid, p);
                        pos.push(Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32));
                        sh.extend_from_slice(&dc);
                        labels.push(label);
                    }
                }
                (pos, sh, labels)
            })
            .collect();

        let n: usize = layers.iter().map(|l| l.0.len()).sum();
        let mut cloud = GaussianCloud {
            positions: Vec::with_capacity(n),
            scales: vec![Vec3::splat(SCALE_PER_SPACING * self.spacing); n],
            rotations: vec![Quat::IDENTITY; n],
            opacities: vec![self.opacity; n],
            sh_degree: 0,
            sh: Vec::with_capacity(3 * n),
            normals: Vec::new(),
            labels: Vec::with_capacity(n),
            label_names: self.region_names(),
        };
        for (pos, sh, labels) in layers {
            cloud.positions.extend(pos);
            cloud.sh.extend(sh);
            cloud.labels.extend(labels);
        }
        Ok(cloud)
    }

    /// Whether the point `p` (object coordinates) lies in the solid: the exact inside test
    /// that interior filling uses for procedural objects (`scene::fill`).
    pub fn contains(&self, p: [f64; 3]) -> bool {
        Solid::new(&self.shape).contains(p)
    }

    /// Depth below the solid's surface of a point (object coordinates): the distance to
    /// the nearest face for a point inside, 0 on the surface and outside. Material regions
    /// select shells with it (`scene::regions`).
    pub fn depth(&self, p: [f64; 3]) -> f64 {
        Solid::new(&self.shape).depth(p).max(0.0)
    }

    /// The solid's bounding box (object coordinates), as (lo, hi).
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        match Solid::new(&self.shape) {
            Solid::Sphere { r } => ([-r; 3], [r; 3]),
            Solid::Box { half } => (half.map(|h| -h), half),
            Solid::Cylinder { r, half_h } => ([-r, -r, -half_h], [r, r, half_h]),
            Solid::Slab { half, t } => ([-half[0], -half[1], -t], [half[0], half[1], 0.0]),
            Solid::Asset(a) => ((-a.half).to_array(), a.half.to_array()),
        }
    }

    /// An upper estimate of the number of Gaussians `generate` makes (no allocation).
    pub fn estimated_count(&self) -> f64 {
        let s = f64::from(self.spacing);
        let fitted = |l: f32| (f64::from(l) / s).round().max(1.0);
        match &self.shape {
            // Lattice points within r of the origin lie in cells within r + √3/2·s.
            Shape::Sphere { radius } => {
                4.0 / 3.0 * std::f64::consts::PI * (f64::from(*radius) / s + 0.87).powi(3)
            }
            Shape::Box { size } => size.iter().map(|&l| fitted(l)).product(),
            Shape::Cylinder { radius, height } => {
                std::f64::consts::PI * (f64::from(*radius) / s + 0.71).powi(2) * fitted(*height)
            }
            Shape::Slab { size, thickness } => {
                fitted(size[0]) * fitted(size[1]) * fitted(*thickness)
            }
            // Lattice cells of the box times the most the solid fills of it.
            _ => match self.shape.asset() {
                Some(a) => {
                    let cells: f64 = a
                        .half
                        .to_array()
                        .iter()
                        .map(|&h| fitted((2.0 * h) as f32))
                        .product();
                    (cells * a.kind.fill_fraction()).ceil()
                }
                None => 0.0,
            },
        }
    }

    /// DC coefficients of the core colour, the shells (with cumulative depths) and the
    /// checker colours.
    fn region_colors(&self) -> RegionColors {
        let mut bottom = 0.0f64;
        let shells = self
            .shells
            .iter()
            .map(|sh| {
                bottom += f64::from(sh.depth);
                (bottom, rgb_to_dc(sh.color))
            })
            .collect();
        RegionColors {
            core: rgb_to_dc(self.color.unwrap_or([0.5; 3])),
            shells,
            checker: self.checker.as_ref().map(|c| {
                (
                    f64::from(c.period),
                    [rgb_to_dc(c.colors[0]), rgb_to_dc(c.colors[1])],
                )
            }),
        }
    }

    /// Region names, indexed by the label ids of [`Self::color_at`]: `checker0`/`checker1`
    /// for a checkerboard, else `shell0`, `shell1`, … (outermost first) and `core`.
    fn region_names(&self) -> Vec<String> {
        if let Some((kind, _)) = self.shape.asset_kind() {
            return kind.regions().iter().map(|r| r.to_string()).collect();
        }
        if self.checker.is_some() {
            return vec!["checker0".into(), "checker1".into()];
        }
        (0..self.shells.len())
            .map(|i| format!("shell{i}"))
            .chain(std::iter::once("core".into()))
            .collect()
    }

    /// DC colour and label id of the region at `p`.
    fn color_at(&self, colors: &RegionColors, solid: &Solid, p: [f64; 3]) -> ([f32; 3], u16) {
        if let Solid::Asset(a) = solid {
            return self.asset_color(a, p);
        }
        if let Some((period, dc)) = &colors.checker {
            let parity = ((p[0] / period).floor() + (p[1] / period).floor()).rem_euclid(2.0);
            return if parity < 0.5 { (dc[0], 0) } else { (dc[1], 1) };
        }
        let depth = solid.depth(p);
        colors
            .shells
            .iter()
            .position(|(bottom, _)| depth < *bottom)
            .map_or((colors.core, colors.shells.len() as u16), |i| {
                (colors.shells[i].1, i as u16)
            })
    }
}

impl ProceduralSpec {
    /// DC colour and label id of an asset's region at `p` (a point of the solid); the
    /// first region takes `color` when the scene gives one.
    fn asset_color(&self, a: &Asset, p: [f64; 3]) -> ([f32; 3], u16) {
        let (label, rgb) = a.sample(p).unwrap_or((0, [0.5; 3]));
        let rgb = match self.color {
            Some(c) if label == 0 => c,
            _ => rgb,
        };
        (rgb_to_dc(rgb), label)
    }

    /// Label id and colour (RGB) of the region at `p` (object coordinates) for an asset,
    /// `None` for the basic shapes or outside the solid: interior fill particles take
    /// their region from here.
    pub fn region_at(&self, p: [f64; 3]) -> Option<(u16, [f32; 3])> {
        let a = self.shape.asset()?;
        let (label, rgb) = a.sample(p)?;
        Some((
            label,
            if label == 0 {
                self.color.unwrap_or(rgb)
            } else {
                rgb
            },
        ))
    }

    /// The names of the label ids `generate` gives.
    pub fn label_names(&self) -> Vec<String> {
        self.region_names()
    }
}

macro_rules! shell_field_table {
    ($suffix:literal; $($i:literal)*) => { [$(concat!("shells[", $i, "].", $suffix)),*] };
}
const SHELL_DEPTH_FIELDS: [&str; 32] = shell_field_table!("depth";
    0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31);
const SHELL_COLOR_FIELDS: [&str; 32] = shell_field_table!("color";
    0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31);

/// `field` names (`&'static str`) of shell `i`'s depth and colour; `None` beyond the table,
/// where the error's `value` names the index instead.
fn shell_fields(i: usize) -> (Option<&'static str>, Option<&'static str>) {
    (
        SHELL_DEPTH_FIELDS.get(i).copied(),
        SHELL_COLOR_FIELDS.get(i).copied(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shell_field_names() {
        assert_eq!(SHELL_DEPTH_FIELDS[1], "shells[1].depth");
        assert_eq!(SHELL_COLOR_FIELDS[31], "shells[31].color");
    }
}
