//! Procedural objects: lattice fill, region colours, validation, determinism.

use std::f32::consts::PI;

use glam::{Quat, Vec3};
use splatter::splat::procedural::{
    Checker, ProceduralError, ProceduralSpec, Shape, Shell, MAX_PROCEDURAL_GAUSSIANS,
    SCALE_PER_SPACING,
};
use splatter::splat::sh::rgb_to_dc;
use splatter::splat::GaussianCloud;

fn spec(shape: Shape, spacing: f32) -> ProceduralSpec {
    ProceduralSpec {
        shape,
        spacing,
        color: Some([0.8, 0.2, 0.1]),
        shells: Vec::new(),
        checker: None,
        opacity: 0.9,
        jitter: 0.5,
        seed: 1,
    }
}

fn dc(rgb: [f32; 3]) -> [f32; 3] {
    rgb_to_dc(rgb)
}

fn colour_of(c: &GaussianCloud, i: usize) -> [f32; 3] {
    [c.sh[3 * i], c.sh[3 * i + 1], c.sh[3 * i + 2]]
}

const EPS: f32 = 1e-5;

fn inside(shape: &Shape, p: Vec3) -> bool {
    match shape {
        Shape::Sphere { radius } => p.length() <= radius * (1.0 + EPS),
        Shape::Box { size } => (0..3).all(|i| p[i].abs() <= 0.5 * size[i] * (1.0 + EPS)),
        Shape::Cylinder { radius, height } => {
            p.truncate().length() <= radius * (1.0 + EPS) && p.z.abs() <= 0.5 * height * (1.0 + EPS)
        }
        Shape::Slab { size, thickness } => {
            p.x.abs() <= 0.5 * size[0] * (1.0 + EPS)
                && p.y.abs() <= 0.5 * size[1] * (1.0 + EPS)
                && p.z <= EPS
                && p.z >= -thickness * (1.0 + EPS)
        }
        other => panic!("basic shapes only (assets: tests/assets.rs), not {other:?}"),
    }
}

fn volume(shape: &Shape) -> f32 {
    match shape {
        Shape::Sphere { radius } => 4.0 / 3.0 * PI * radius.powi(3),
        Shape::Box { size } => size[0] * size[1] * size[2],
        Shape::Cylinder { radius, height } => PI * radius * radius * height,
        Shape::Slab { size, thickness } => size[0] * size[1] * thickness,
        other => panic!("basic shapes only, not {other:?}"),
    }
}

fn shapes() -> Vec<Shape> {
    vec![
        Shape::Sphere { radius: 1.0 },
        Shape::Box {
            size: [1.0, 2.0, 0.7],
        },
        Shape::Cylinder {
            radius: 0.6,
            height: 1.5,
        },
        Shape::Slab {
            size: [3.0, 2.0],
            thickness: 0.3,
        },
    ]
}

#[test]
fn points_lie_inside_every_shape_even_with_full_jitter() {
    for shape in shapes() {
        let c = spec(shape.clone(), 0.05).generate().unwrap();
        c.check_consistent().unwrap();
        assert!(!c.is_empty());
        for p in &c.positions {
            assert!(inside(&shape, *p), "{shape:?}: {p} is outside");
        }
    }
}

/// Jitter moves every point off its lattice site by a uniform offset of up to
/// `jitter · spacing` per axis, then clamps it into the solid (the nearest point of a convex
/// solid, which brings it no farther from its site, itself inside). Against the same spec
/// without jitter (the same sites in the same order): no point is farther from its site than
/// the offset's largest length, √3 · jitter · spacing, and the mean offset per axis is the
/// uniform distribution's, jitter · spacing / 2, less what the clamp takes back near the
/// surface.
#[test]
fn jitter_moves_points_off_the_lattice_by_up_to_its_bound() {
    let spacing = 0.05;
    for shape in shapes() {
        let jittered = spec(shape.clone(), spacing).generate().unwrap();
        let lattice = ProceduralSpec {
            jitter: 0.0,
            ..spec(shape.clone(), spacing)
        }
        .generate()
        .unwrap();
        assert_eq!(jittered.len(), lattice.len(), "{shape:?}: the same sites");
        let bound = 0.5 * spacing;
        let mut mean = Vec3::ZERO;
        for (p, site) in jittered.positions.iter().zip(&lattice.positions) {
            let offset = *p - *site;
            assert!(
                offset.length() <= 3f32.sqrt() * bound * (1.0 + 1e-4),
                "{shape:?}: {p} is {offset} from its site {site}, beyond √3·jitter·spacing"
            );
            mean += offset.abs();
        }
        mean /= jittered.len() as f32;
        let expected = 0.5 * bound;
        println!("{shape:?}: mean |offset| {mean} (uniform: {expected})");
        for axis in 0..3 {
            assert!(
                (0.9 * expected..=1.05 * expected).contains(&mean[axis]),
                "{shape:?}: mean offset {mean} along axis {axis}, expected about {expected}"
            );
        }
    }
}

#[test]
fn counts_match_volume_over_spacing_cubed() {
    for shape in shapes() {
        for spacing in [0.05, 0.03] {
            let n = spec(shape.clone(), spacing).generate().unwrap().len() as f32;
            let expect = volume(&shape) / spacing.powi(3);
            assert!(
                (n / expect - 1.0).abs() < 0.15,
                "{shape:?} spacing {spacing}: {n} Gaussians, expected ≈ {expect}"
            );
        }
    }
}

#[test]
fn gaussians_are_isotropic_with_the_documented_scale() {
    let c = spec(Shape::Sphere { radius: 0.5 }, 0.1).generate().unwrap();
    assert_eq!(c.sh_degree, 0);
    assert!(c.normals.is_empty());
    for i in 0..c.len() {
        assert_eq!(c.scales[i], Vec3::splat(SCALE_PER_SPACING * 0.1));
        assert_eq!(c.rotations[i], Quat::IDENTITY);
        assert_eq!(c.opacities[i], 0.9);
        assert_eq!(colour_of(&c, i), dc([0.8, 0.2, 0.1]));
    }
}

#[test]
fn shells_colour_by_depth_below_the_surface() {
    let rind = [0.1, 0.6, 0.1];
    let white = [0.9, 0.9, 0.8];
    let flesh = [0.9, 0.1, 0.2];
    for shape in shapes() {
        let mut s = spec(shape.clone(), 0.03);
        s.color = Some(flesh);
        s.shells = vec![
            Shell {
                depth: 0.06,
                color: rind,
            },
            Shell {
                depth: 0.04,
                color: white,
            },
        ];
        let c = s.generate().unwrap();
        let mut seen = [0usize; 3];
        for i in 0..c.len() {
            let p = c.positions[i];
            let depth = match &shape {
                Shape::Sphere { radius } => radius - p.length(),
                Shape::Box { size } => (0..3)
                    .map(|a| 0.5 * size[a] - p[a].abs())
                    .fold(f32::MAX, f32::min),
                Shape::Cylinder { radius, height } => {
                    (radius - p.truncate().length()).min(0.5 * height - p.z.abs())
                }
                Shape::Slab { .. } => -p.z,
                other => panic!("basic shapes only, not {other:?}"),
            };
            let got = colour_of(&c, i);
            // Leave a little slack at the boundaries for f32 round-off.
            let expect = if depth < 0.06 - 1e-4 {
                Some((0, rind))
            } else if depth > 0.06 + 1e-4 && depth < 0.10 - 1e-4 {
                Some((1, white))
            } else if depth > 0.10 + 1e-4 {
                Some((2, flesh))
            } else {
                None
            };
            if let Some((k, rgb)) = expect {
                assert_eq!(got, dc(rgb), "{shape:?}: depth {depth} at {p}");
                seen[k] += 1;
            }
        }
        assert!(seen.iter().all(|&k| k > 0), "{shape:?}: {seen:?}");
    }
}

#[test]
fn checker_alternates_in_x_and_y() {
    let mut s = spec(
        Shape::Slab {
            size: [4.0, 4.0],
            thickness: 0.1,
        },
        0.05,
    );
    s.shells = vec![Shell {
        depth: 0.05,
        color: [0.0, 0.0, 1.0],
    }]; // overridden by the checker
    let colors = [[1.0, 1.0, 1.0], [0.0, 0.0, 0.0]];
    s.checker = Some(Checker {
        period: 0.5,
        colors,
    });
    let c = s.generate().unwrap();
    let mut seen = [0usize; 2];
    for i in 0..c.len() {
        let p = c.positions[i];
        let parity = ((p.x / 0.5).floor() + (p.y / 0.5).floor()).rem_euclid(2.0) as usize;
        // Skip points within round-off of a square's edge.
        let near_edge = |v: f32| ((v / 0.5) - (v / 0.5).round()).abs() < 1e-4;
        if near_edge(p.x) || near_edge(p.y) {
            continue;
        }
        assert_eq!(colour_of(&c, i), dc(colors[parity]), "at {p}");
        seen[parity] += 1;
    }
    assert!(seen[0] > 1000 && seen[1] > 1000, "{seen:?}");
    // Neighbouring squares differ.
    let at = |x: f32, y: f32| {
        let i = (0..c.len())
            .min_by(|&a, &b| {
                let da = (c.positions[a].truncate() - glam::Vec2::new(x, y)).length();
                let db = (c.positions[b].truncate() - glam::Vec2::new(x, y)).length();
                da.total_cmp(&db)
            })
            .unwrap();
        colour_of(&c, i)
    };
    assert_ne!(at(0.25, 0.25), at(0.75, 0.25));
    assert_ne!(at(0.25, 0.25), at(0.25, 0.75));
    assert_eq!(at(0.25, 0.25), at(0.75, 0.75));
    assert_eq!(at(-0.25, -0.25), at(0.25, 0.25));
}

#[test]
fn generation_is_deterministic_for_a_seed() {
    for shape in shapes() {
        let s = spec(shape, 0.05);
        let a = s.generate().unwrap();
        let b = s.generate().unwrap();
        assert_eq!(a, b);
        let mut other = s.clone();
        other.seed = 2;
        assert_ne!(a.positions, other.generate().unwrap().positions);
    }
    // Without jitter the seed does not matter.
    let mut s = spec(Shape::Sphere { radius: 0.5 }, 0.1);
    s.jitter = 0.0;
    let a = s.generate().unwrap();
    s.seed = 99;
    assert_eq!(a, s.generate().unwrap());
}

#[test]
fn shapes_smaller_than_the_spacing_still_get_a_gaussian() {
    for shape in [
        Shape::Sphere { radius: 0.01 },
        Shape::Box {
            size: [0.01, 0.01, 0.01],
        },
        Shape::Cylinder {
            radius: 0.01,
            height: 0.01,
        },
        Shape::Slab {
            size: [0.01, 0.01],
            thickness: 0.01,
        },
    ] {
        let c = spec(shape.clone(), 0.1).generate().unwrap();
        assert_eq!(c.len(), 1, "{shape:?}");
        assert!(
            inside(&shape, c.positions[0]),
            "{shape:?}: {}",
            c.positions[0]
        );
    }
}

fn invalid_field(s: &ProceduralSpec) -> &'static str {
    match s.validate() {
        Err(ProceduralError::Invalid { field, .. }) => field,
        other => panic!("expected an Invalid error, got {other:?}"),
    }
}

#[test]
fn invalid_specs_name_the_field() {
    let base = spec(Shape::Sphere { radius: 1.0 }, 0.1);
    base.validate().unwrap();
    let with = |f: &dyn Fn(&mut ProceduralSpec)| {
        let mut s = base.clone();
        f(&mut s);
        s
    };
    let cases: Vec<(ProceduralSpec, &str)> = vec![
        (with(&|s| s.shape = Shape::Sphere { radius: 0.0 }), "radius"),
        (
            with(&|s| s.shape = Shape::Sphere { radius: f32::NAN }),
            "radius",
        ),
        (
            with(&|s| {
                s.shape = Shape::Box {
                    size: [1.0, -1.0, 1.0],
                }
            }),
            "size",
        ),
        (
            with(&|s| {
                s.shape = Shape::Cylinder {
                    radius: 1.0,
                    height: f32::INFINITY,
                }
            }),
            "height",
        ),
        (
            with(&|s| {
                s.shape = Shape::Cylinder {
                    radius: -1.0,
                    height: 1.0,
                }
            }),
            "radius",
        ),
        (
            with(&|s| {
                s.shape = Shape::Slab {
                    size: [1.0, 1.0],
                    thickness: 0.0,
                }
            }),
            "thickness",
        ),
        (
            with(&|s| {
                s.shape = Shape::Slab {
                    size: [0.0, 1.0],
                    thickness: 1.0,
                }
            }),
            "size",
        ),
        (with(&|s| s.spacing = 0.0), "spacing"),
        (with(&|s| s.spacing = f32::NAN), "spacing"),
        (with(&|s| s.color = Some([0.5, 1.5, 0.5])), "color"),
        (with(&|s| s.color = Some([0.5, f32::NAN, 0.5])), "color"),
        (with(&|s| s.opacity = 0.0), "opacity"),
        (with(&|s| s.opacity = 1.01), "opacity"),
        (with(&|s| s.jitter = 0.6), "jitter"),
        (with(&|s| s.jitter = -0.1), "jitter"),
        (
            with(&|s| {
                s.shells = vec![
                    Shell {
                        depth: 0.1,
                        color: [0.1; 3],
                    },
                    Shell {
                        depth: -0.1,
                        color: [0.1; 3],
                    },
                ]
            }),
            "shells[1].depth",
        ),
        (
            with(&|s| {
                s.shells = vec![Shell {
                    depth: 0.1,
                    color: [2.0; 3],
                }]
            }),
            "shells[0].color",
        ),
        (
            with(&|s| {
                s.checker = Some(Checker {
                    period: 0.0,
                    colors: [[0.0; 3]; 2],
                })
            }),
            "checker.period",
        ),
        (
            with(&|s| {
                s.checker = Some(Checker {
                    period: 1.0,
                    colors: [[0.0; 3], [0.0, -1.0, 0.0]],
                })
            }),
            "checker.colors[1]",
        ),
    ];
    for (s, field) in cases {
        assert_eq!(invalid_field(&s), field, "{s:?}");
        // generate() validates too.
        assert!(matches!(s.generate(), Err(ProceduralError::Invalid { .. })));
    }
    // The message carries the value and what was expected.
    let msg = with(&|s| s.spacing = -2.0)
        .validate()
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("spacing") && msg.contains("-2") && msg.contains("> 0"),
        "{msg}"
    );
}

#[test]
fn too_many_gaussians_are_refused_before_allocating() {
    let cases = [
        spec(Shape::Sphere { radius: 1.0 }, 1e-4),
        spec(
            Shape::Box {
                size: [1e6, 1e-6, 1e-6],
            },
            1e-3,
        ),
        spec(
            Shape::Cylinder {
                radius: 1e6,
                height: 1e-9,
            },
            1.0,
        ),
        spec(
            Shape::Slab {
                size: [f32::MAX, f32::MAX],
                thickness: 1.0,
            },
            1e-3,
        ),
    ];
    for s in cases {
        let t = std::time::Instant::now();
        match s.generate() {
            Err(ProceduralError::TooMany { count, max, .. }) => {
                assert!(count > max, "{count}");
                assert_eq!(max, MAX_PROCEDURAL_GAUSSIANS);
            }
            other => panic!("{:?}: {other:?}", s.shape),
        }
        assert!(t.elapsed().as_secs_f64() < 0.5);
    }
}

#[test]
fn spec_serde_shape_is_flat_with_defaults() {
    let json = r#"{"shape": "cylinder", "radius": 0.5, "height": 2.0, "spacing": 0.1, "color": [1, 0, 0]}"#;
    let s: ProceduralSpec = serde_json::from_str(json).unwrap();
    assert_eq!(
        s.shape,
        Shape::Cylinder {
            radius: 0.5,
            height: 2.0
        }
    );
    assert_eq!((s.opacity, s.jitter, s.seed), (0.95, 0.25, 0));
    s.generate().unwrap();
}

#[test]
fn spec_refuses_unknown_fields() {
    let json = r#"{"shape": "sphere", "radius": 0.5, "spacing": 0.1, "color": [1, 0, 0], "colour": [1, 0, 0]}"#;
    let e = serde_json::from_str::<ProceduralSpec>(json)
        .unwrap_err()
        .to_string();
    assert!(e.contains("colour"), "{e}");
    let json =
        r#"{"shape": "sphere", "radius": 0.5, "height": 1, "spacing": 0.1, "color": [1, 0, 0]}"#;
    assert!(serde_json::from_str::<ProceduralSpec>(json).is_err());
}
