//! Procedural assets: recognisable objects (fruit, food, furniture, props) for the paper's
//! scenes, as implicit solids with named regions.
//!
//! Each asset is one function of a point (object coordinates, z up, the asset centred on
//! the origin inside the box ±`size`/2) that answers `None` outside the solid and otherwise
//! the region's label id and colour there. That one function is the exact inside test
//! (interior filling), the colour of lattice and fill Gaussians, and the region labels, so
//! the three always agree. Every solid is clipped to its box, so `bounds` is exact too.
//! Patterns (stripes, seeds, pores, grain) come from a fixed hash of position, so an asset
//! looks the same whatever its lattice `spacing` or `seed`.

use glam::DVec3;

mod patterns;
mod shapes;

use shapes::*;

/// Display colour in [0, 1] (what the PNG shows for an unlit Gaussian).
pub type Rgb = [f32; 3];

/// The assets, as named by `"shape"` in a scene's `procedural` block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Watermelon,
    Jelly,
    Pumpkin,
    Kiwi,
    Pineapple,
    Dragonfruit,
    Toast,
    Sandcastle,
    Pillow,
    Cloth,
    Table,
    Knife,
    Projectile,
}

impl Kind {
    /// Every asset, in documentation order.
    pub const ALL: [Kind; 13] = [
        Kind::Watermelon,
        Kind::Jelly,
        Kind::Pumpkin,
        Kind::Kiwi,
        Kind::Pineapple,
        Kind::Dragonfruit,
        Kind::Toast,
        Kind::Sandcastle,
        Kind::Pillow,
        Kind::Cloth,
        Kind::Table,
        Kind::Knife,
        Kind::Projectile,
    ];

    /// The `"shape"` name.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Watermelon => "watermelon",
            Kind::Jelly => "jelly",
            Kind::Pumpkin => "pumpkin",
            Kind::Kiwi => "kiwi",
            Kind::Pineapple => "pineapple",
            Kind::Dragonfruit => "dragonfruit",
            Kind::Toast => "toast",
            Kind::Sandcastle => "sandcastle",
            Kind::Pillow => "pillow",
            Kind::Cloth => "cloth",
            Kind::Table => "table",
            Kind::Knife => "knife",
            Kind::Projectile => "projectile",
        }
    }

    /// Full extent [x, y, z] in scene units when the scene gives no `size` (the scale of
    /// the example scenes, whose simulation domains are about a metre wide).
    pub fn default_size(self) -> [f32; 3] {
        match self {
            Kind::Watermelon => [0.30, 0.22, 0.22],
            Kind::Jelly => [0.18, 0.18, 0.18],
            Kind::Pumpkin => [0.30, 0.30, 0.24],
            Kind::Kiwi => [0.12, 0.09, 0.09],
            Kind::Pineapple => [0.16, 0.16, 0.36],
            Kind::Dragonfruit => [0.13, 0.13, 0.17],
            Kind::Toast => [0.12, 0.11, 0.02],
            Kind::Sandcastle => [0.40, 0.40, 0.30],
            Kind::Pillow => [0.50, 0.34, 0.14],
            Kind::Cloth => [0.60, 0.60, 0.01],
            Kind::Table => [0.80, 0.50, 0.40],
            Kind::Knife => [0.30, 0.03, 0.05],
            Kind::Projectile => [0.06, 0.06, 0.06],
        }
    }

    /// Region names; label ids index this. Id 0 is the region a scene's `color` repaints.
    pub fn regions(self) -> &'static [&'static str] {
        match self {
            Kind::Watermelon => &["rind", "white_rind", "flesh", "seeds"],
            Kind::Jelly => &["jelly"],
            Kind::Pumpkin => &["skin", "flesh", "seeds", "stem"],
            Kind::Kiwi => &["skin", "flesh", "core", "seeds"],
            Kind::Pineapple => &["skin", "flesh", "core", "crown"],
            Kind::Dragonfruit => &["skin", "bracts", "flesh", "seeds"],
            Kind::Toast => &["crust", "crumb"],
            Kind::Sandcastle => &["sand"],
            Kind::Pillow => &["fabric", "stuffing", "seam"],
            Kind::Cloth => &["cloth"],
            Kind::Table => &["top", "legs"],
            Kind::Knife => &["blade", "handle"],
            Kind::Projectile => &["ball"],
        }
    }

    /// An upper bound on the fraction of the bounding box the solid fills (measured on
    /// the default shapes, with a margin for coarse lattices), for `estimated_count`.
    pub fn fill_fraction(self) -> f64 {
        match self {
            Kind::Jelly | Kind::Cloth => 1.0,
            Kind::Toast => 0.95,
            Kind::Pillow => 0.9,
            Kind::Watermelon | Kind::Kiwi | Kind::Projectile => 0.62,
            Kind::Sandcastle => 0.52,
            Kind::Pumpkin => 0.42,
            Kind::Pineapple => 0.4,
            Kind::Knife => 0.25,
            Kind::Dragonfruit => 0.3,
            Kind::Table => 0.12,
        }
    }
}

/// An asset of a given size.
#[derive(Clone, Copy, Debug)]
pub struct Asset {
    pub kind: Kind,
    /// Half extents of the bounding box.
    pub half: DVec3,
}

impl Asset {
    pub fn new(kind: Kind, size: [f32; 3]) -> Asset {
        Asset {
            kind,
            half: DVec3::new(size[0].into(), size[1].into(), size[2].into()) * 0.5,
        }
    }

    /// Label id and colour of the region at `p` (object coordinates), `None` outside.
    pub fn sample(&self, p: [f64; 3]) -> Option<(u16, Rgb)> {
        let p = DVec3::from_array(p);
        if !(p.abs().cmple(self.half).all()) {
            return None;
        }
        let h = self.half;
        match self.kind {
            Kind::Watermelon => watermelon(p, h),
            Kind::Jelly => jelly(p, h),
            Kind::Pumpkin => pumpkin(p, h),
            Kind::Kiwi => kiwi(p, h),
            Kind::Pineapple => pineapple(p, h),
            Kind::Dragonfruit => dragonfruit(p, h),
            Kind::Toast => toast(p, h),
            Kind::Sandcastle => sandcastle(p, h),
            Kind::Pillow => pillow(p, h),
            Kind::Cloth => cloth(p, h),
            Kind::Table => table(p, h),
            Kind::Knife => knife(p, h),
            Kind::Projectile => projectile(p, h),
        }
    }

    /// Whether `p` is in the solid.
    pub fn contains(&self, p: [f64; 3]) -> bool {
        self.sample(p).is_some()
    }

    /// Approximate depth below the surface of a point inside: the shortest escape along 26
    /// directions (axes, face and space diagonals), marched in steps of 1/16 of the
    /// smallest half extent (thinner gaps may be stepped over) and refined by bisection to
    /// 1/16 000 of it. 0 outside. Hundreds of ray marches a point: for shell regions at
    /// setup, not per frame.
    pub fn depth(&self, p: [f64; 3]) -> f64 {
        let p = DVec3::from_array(p);
        if !self.contains(p.to_array()) {
            return 0.0;
        }
        let step = self.half.min_element() / 16.0;
        let reach = 2.0 * self.half.max_element();
        let mut best = reach;
        for d in directions() {
            // Sample up to the best escape so far (the last step is cut short at it).
            let mut t = 0.0;
            while t < best {
                let next = (t + step).min(best);
                if !self.contains((p + d * next).to_array()) {
                    // Bisect between the last inside point and this outside one.
                    let (mut lo, mut hi) = (t, next);
                    for _ in 0..10 {
                        let mid = 0.5 * (lo + hi);
                        if self.contains((p + d * mid).to_array()) {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    best = hi;
                    break;
                }
                t = next;
            }
        }
        best
    }
}

/// The 26 unit directions to the neighbours of a cube cell.
fn directions() -> impl Iterator<Item = DVec3> {
    (0..27).filter(|&i| i != 13).map(|i| {
        DVec3::new(
            (i % 3) as f64 - 1.0,
            ((i / 3) % 3) as f64 - 1.0,
            (i / 9) as f64 - 1.0,
        )
        .normalize()
    })
}
