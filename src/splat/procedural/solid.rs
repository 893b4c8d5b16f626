//! The solids a procedural shape samples: their inside test, their axis, the colours of
//! their regions.

use super::*;

pub(super) struct RegionColors {
    pub(super) core: [f32; 3],
    /// (cumulative depth of the shell's inner side, DC), outermost first.
    pub(super) shells: Vec<(f64, [f32; 3])>,
    pub(super) checker: Option<(f64, [[f32; 3]; 2])>,
}

/// The solid in f64, with its lattice, clamping and depth below the surface.
pub(super) enum Solid {
    Sphere { r: f64 },
    Box { half: [f64; 3] },
    Cylinder { r: f64, half_h: f64 },
    Slab { half: [f64; 2], t: f64 },
    Asset(Asset),
}

/// Lattice coordinates along one axis: `start + i · step`, i < count.
#[derive(Clone, Copy)]
pub(super) struct Axis {
    pub(super) start: f64,
    pub(super) step: f64,
    pub(super) count: usize,
}

impl Axis {
    /// Cell centres of a whole number of cells (close to `s` wide) covering [lo, hi].
    pub(super) fn fitted(lo: f64, hi: f64, s: f64) -> Axis {
        let count = ((hi - lo) / s).round().max(1.0) as usize;
        let step = (hi - lo) / count as f64;
        Axis {
            start: lo + 0.5 * step,
            step,
            count,
        }
    }

    /// Multiples of `s` within [−r, r] (always including 0).
    pub(super) fn centred(r: f64, s: f64) -> Axis {
        let m = (r / s).floor() as usize;
        Axis {
            start: -(m as f64) * s,
            step: s,
            count: 2 * m + 1,
        }
    }

    pub(super) fn coord(&self, i: usize) -> f64 {
        self.start + i as f64 * self.step
    }
}

impl Solid {
    pub(super) fn new(shape: &Shape) -> Solid {
        match shape {
            Shape::Sphere { radius } => Solid::Sphere {
                r: f64::from(*radius),
            },
            Shape::Box { size } => Solid::Box {
                half: size.map(|l| 0.5 * f64::from(l)),
            },
            Shape::Cylinder { radius, height } => Solid::Cylinder {
                r: f64::from(*radius),
                half_h: 0.5 * f64::from(*height),
            },
            Shape::Slab { size, thickness } => Solid::Slab {
                half: size.map(|l| 0.5 * f64::from(l)),
                t: f64::from(*thickness),
            },
            _ => Solid::Asset(shape.asset().expect("an asset shape")),
        }
    }

    pub(super) fn axes(&self, s: f64) -> [Axis; 3] {
        match *self {
            Solid::Sphere { r } => [Axis::centred(r, s); 3],
            Solid::Box { half } => half.map(|h| Axis::fitted(-h, h, s)),
            Solid::Cylinder { r, half_h } => [
                Axis::centred(r, s),
                Axis::centred(r, s),
                Axis::fitted(-half_h, half_h, s),
            ],
            Solid::Slab { half, t } => [
                Axis::fitted(-half[0], half[0], s),
                Axis::fitted(-half[1], half[1], s),
                Axis::fitted(-t, 0.0, s),
            ],
            // Cell centres, so that a sheet thinner than `spacing` still gets one layer.
            Solid::Asset(a) => a.half.to_array().map(|h| Axis::fitted(-h, h, s)),
        }
    }

    /// Whether a point lies in the solid (boundary included).
    pub(super) fn contains(&self, p: [f64; 3]) -> bool {
        match *self {
            Solid::Sphere { r } => p[0] * p[0] + p[1] * p[1] + p[2] * p[2] <= r * r,
            Solid::Box { half } => (0..3).all(|i| p[i].abs() <= half[i]),
            Solid::Cylinder { r, half_h } => {
                p[0] * p[0] + p[1] * p[1] <= r * r && p[2].abs() <= half_h
            }
            Solid::Slab { half, t } => {
                p[0].abs() <= half[0] && p[1].abs() <= half[1] && (-t..=0.0).contains(&p[2])
            }
            Solid::Asset(a) => a.contains(p),
        }
    }

    /// Whether an (unjittered) lattice point belongs to the solid.
    pub(super) fn contains_lattice(&self, x: f64, y: f64, _z: f64) -> bool {
        match *self {
            Solid::Sphere { r } => x * x + y * y + _z * _z <= r * r,
            Solid::Cylinder { r, .. } => x * x + y * y <= r * r,
            Solid::Box { .. } | Solid::Slab { .. } => true,
            Solid::Asset(a) => a.contains([x, y, _z]),
        }
    }

    /// The nearest point of the solid (the point itself when inside); for an asset, whose
    /// nearest point has no closed form, the unjittered `lattice` point (inside).
    pub(super) fn clamp(&self, p: [f64; 3], lattice: [f64; 3]) -> [f64; 3] {
        match *self {
            Solid::Sphere { r } => {
                let len = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
                if len > r {
                    p.map(|c| c * (r / len))
                } else {
                    p
                }
            }
            Solid::Box { half } => [0, 1, 2].map(|i| p[i].clamp(-half[i], half[i])),
            Solid::Cylinder { r, half_h } => {
                let rho = (p[0] * p[0] + p[1] * p[1]).sqrt();
                let f = if rho > r { r / rho } else { 1.0 };
                [p[0] * f, p[1] * f, p[2].clamp(-half_h, half_h)]
            }
            Solid::Slab { half, t } => [
                p[0].clamp(-half[0], half[0]),
                p[1].clamp(-half[1], half[1]),
                p[2].clamp(-t, 0.0),
            ],
            Solid::Asset(a) => {
                if a.contains(p) {
                    p
                } else {
                    lattice
                }
            }
        }
    }

    /// Depth below the surface of a point inside the solid.
    pub(super) fn depth(&self, p: [f64; 3]) -> f64 {
        match *self {
            Solid::Sphere { r } => r - (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt(),
            Solid::Box { half } => (0..3)
                .map(|i| half[i] - p[i].abs())
                .fold(f64::INFINITY, f64::min),
            Solid::Cylinder { r, half_h } => {
                (r - (p[0] * p[0] + p[1] * p[1]).sqrt()).min(half_h - p[2].abs())
            }
            Solid::Slab { .. } => -p[2],
            Solid::Asset(a) => a.depth(p),
        }
    }
}
