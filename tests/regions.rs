//! Material regions: `physics.regions` selects
//! particles by shell depth, box, sphere or label and gives them their own material and
//! fill colour; the first match wins, the rest keep the object's material.

use std::f64::consts::PI;
use std::path::Path;

use glam::DVec3;
use splatter::scene::simulation::{prepare, PartKind, SimulationSetup};
use splatter::scene::{self, SceneError};
use splatter::sim::cpu;

fn scene_text(objects: &str, dx: f64, ground: &str) -> String {
    format!(
        r#"{{
  "output": {{ "width": 32, "height": 24, "frames": 1 }},
  "camera": {{ "fov_y_deg": 40, "path": {{ "type": "orbit", "target": [0.5, 0.5, 0.5], "radius": 2 }} }},
  "simulation": {{ "dx": {dx}, "domain": {{ "lo": [0, 0, 0], "hi": [1, 1, 1] }}{ground} }},
  "objects": [{objects}]
}}"#
    )
}

fn setup(text: &str) -> Result<SimulationSetup, SceneError> {
    let scene = scene::parse(text, "test.json", Path::new("."))?;
    let (splats, report) = scene.build_splats()?;
    Ok(prepare(&scene, splats, &report)?.expect("a simulation"))
}

fn material(e: f64) -> String {
    format!(r#"{{ "model": "fixed_corotated", "E": {e}, "nu": 0.3, "density": 2 }}"#)
}

/// Rest volume of the particles with material `m`.
fn volume_of(s: &SimulationSetup, m: u32) -> f64 {
    (0..s.particles.len())
        .filter(|&p| s.particles.material[p] == m)
        .map(|p| s.particles.volume0[p])
        .sum()
}

/// A filled sphere with a shell region and a box region (lower half): the volumes per
/// material match the geometry, the first match wins (the box does not take the shell's
/// lower half), and the shell's fill particles take its colour.
#[test]
fn shell_and_box_regions_split_a_sphere_by_geometry() {
    for particles in [r#""gaussians""#, r#"{ "spacing": 0.01 }"#] {
        println!("particles: {particles}");
        shell_and_box_regions(particles);
    }
}

fn shell_and_box_regions(particles: &str) {
    let (r, d, dx): (f64, f64, f64) = (0.15, 0.03, 0.02);
    let obj = format!(
        r#"{{ "procedural": {{ "shape": "sphere", "radius": {r}, "spacing": 0.02, "color": [1, 1, 1] }},
            "transform": {{ "translate": [0.5, 0.5, 0.5] }},
            "physics": {{ "material": {soft}, "fill": true, "particles": {particles}, "regions": [
              {{ "name": "skin", "shell": {{ "from": 0, "to": {d} }}, "material": {stiff}, "color": [1, 0, 0] }},
              {{ "box": {{ "lo": [0, 0, 0], "hi": [1, 1, 0.5] }}, "material": {mid} }}
            ] }} }}"#,
        soft = material(500.0),
        stiff = material(2e4),
        mid = material(2000.0),
    );
    let s = setup(&scene_text(&obj, dx, "")).unwrap();
    assert_eq!(s.materials.len(), 3);
    let shell = 4.0 / 3.0 * PI * (r.powi(3) - (r - d).powi(3));
    let half_core = 0.5 * 4.0 / 3.0 * PI * (r - d).powi(3);
    let measured = [volume_of(&s, 1), volume_of(&s, 2), volume_of(&s, 0)];
    let expected = [shell, half_core, half_core];
    for (name, (m, e)) in ["shell", "lower core", "upper core"]
        .iter()
        .zip(measured.iter().zip(&expected))
    {
        println!(
            "{name}: volume {m:.5} vs {e:.5} ({:+.1}%)",
            100.0 * (m - e) / e
        );
        assert!((m - e).abs() / e < 0.08, "{name}: {m} vs {e}");
    }
    // Every particle is where its material says.
    let centre = DVec3::splat(0.5);
    for p in 0..s.particles.len() {
        let x = s.particles.x[p];
        let depth = r - x.distance(centre);
        let expected = if depth < d {
            1
        } else if x.z <= 0.5 {
            2
        } else {
            0
        };
        assert_eq!(
            s.particles.material[p], expected,
            "particle at {x}, depth {depth}"
        );
    }
    // Shell fill particles are red; the others keep the object's white.
    let fill = s.parts.iter().find(|p| p.kind == PartKind::Fill).unwrap();
    let red_dc = splatter::splat::sh::rgb_to_dc([1.0, 0.0, 0.0]);
    let white_dc = splatter::splat::sh::rgb_to_dc([1.0, 1.0, 1.0]);
    let (mut red, mut white) = (0, 0);
    for g in fill.start..fill.start + fill.len {
        let p = s.binding.particle[g - s.static_count] as usize;
        let dc = &s.splats.sh[g * 3..g * 3 + 3];
        if s.particles.material[p] == 1 {
            assert_eq!(dc, red_dc, "shell fill particle");
            red += 1;
        } else {
            assert_eq!(dc, white_dc, "core fill particle");
            white += 1;
        }
    }
    assert!(red > 100 && white > 100, "{red} red, {white} white");
}

/// Lowest top of the sphere over `steps` (how far the impact squashes it).
fn squash(regions: &str) -> f64 {
    let obj = format!(
        r#"{{ "procedural": {{ "shape": "sphere", "radius": 0.1, "spacing": 0.02, "color": [1, 1, 1] }},
            "transform": {{ "translate": [0.5, 0.5, 0.17] }},
            "physics": {{ "material": {soft}, "fill": true, "velocity": [0, 0, -3],
                          "regions": [{regions}] }} }}"#,
        soft = material(400.0),
    );
    let mut s = setup(&scene_text(
        &obj,
        0.02,
        r#", "ground": { "kind": "sticky" }, "dt": 1e-4"#,
    ))
    .unwrap();
    let mut lowest_top = f64::INFINITY;
    for _ in 0..400 {
        cpu::step(&mut s.particles, &mut s.grid, &s.materials, &s.params);
        let top = s.particles.x.iter().map(|x| x.z).fold(f64::MIN, f64::max);
        lowest_top = lowest_top.min(top);
    }
    lowest_top
}

/// A stiff shell on a soft core squashes less on impact than the all-soft sphere (same
/// mass, same drop), and more than a sphere that is stiff through.
#[test]
fn a_stiff_shell_on_a_soft_core_squashes_less() {
    let stiff = material(1.5e4);
    let soft = squash("");
    let shelled = squash(&format!(
        r#"{{ "shell": {{ "to": 0.025 }}, "material": {stiff} }}"#
    ));
    let solid = squash(&format!(
        r#"{{ "shell": {{ "to": 1 }}, "material": {stiff} }}"#
    ));
    println!("lowest top: all soft {soft:.4}, stiff shell {shelled:.4}, all stiff {solid:.4}");
    assert!(shelled > soft + 0.01, "shell {shelled} vs soft {soft}");
    assert!(solid > shelled, "all stiff {solid} vs shell {shelled}");
}

/// Bad region specs name the field, the value and what was expected.
#[test]
fn bad_regions_are_named() {
    let cases = [
        (
            r#"{ "material": M }"#,
            "objects[0].physics.regions[0] = no selector: expected exactly one of `shell`, `box`, `sphere`, `label` or `voronoi`",
        ),
        (
            r#"{ "shell": { "to": 0.1 }, "sphere": { "center": [0.5, 0.5, 0.5], "radius": 0.1 }, "material": M }"#,
            "objects[0].physics.regions[0] = shell and sphere: expected exactly one of",
        ),
        (
            r#"{ "shell": { "from": 0.2, "to": 0.1 }, "material": M }"#,
            "objects[0].physics.regions[0].shell = from 0.2 to 0.1: expected finite depths with 0 ≤ from < to",
        ),
        (
            r#"{ "box": { "lo": [0, 0, 0], "hi": [1, -1, 1] }, "material": M }"#,
            "objects[0].physics.regions[0].box",
        ),
        (
            r#"{ "sphere": { "center": [0.5, 0.5, 0.5], "radius": 0 }, "material": M }"#,
            "objects[0].physics.regions[0].sphere.radius = 0: expected a radius > 0",
        ),
        (
            r#"{ "voronoi": { "cells": 1, "width": 0.01 }, "material": M }"#,
            "objects[0].physics.regions[0].voronoi.cells = 1: expected a number of cells from 2 to 256",
        ),
        (
            r#"{ "voronoi": { "cells": 5, "width": 0 }, "material": M }"#,
            "objects[0].physics.regions[0].voronoi.width = 0: expected a face half-thickness > 0",
        ),
        (
            r#"{ "label": "flesh", "material": M }"#,
            r#"objects[0].physics.regions[0].label = "flesh": expected one of the object's labels: core"#,
        ),
        (
            r#"{ "shell": { "to": 0.1 }, "material": M, "color": [2, 0, 0] }"#,
            "objects[0].physics.regions[0].color = [2.0, 0.0, 0.0]: expected three numbers in [0, 1]",
        ),
        (
            r#"{ "shell": { "to": 0.1 }, "material": { "model": "fixed_corotated", "E": -1, "nu": 0.3, "density": 2 } }"#,
            "objects[0].physics.regions[0].material.E = -1: expected Young's modulus > 0",
        ),
        (
            &vec![r#"{ "shell": { "to": 0.1 }, "material": M }"#; 16].join(", "),
            "objects[0].physics.regions = 16 regions: expected at most 15 regions",
        ),
        (
            r#"{ "shell": { "to": 0.1 }, "material": M, "colour": [1, 0, 0] }"#,
            "unknown field `colour`",
        ),
    ];
    for (regions, want) in cases {
        let regions = regions.replace('M', &material(1000.0));
        let obj = format!(
            r#"{{ "procedural": {{ "shape": "sphere", "radius": 0.1, "spacing": 0.02, "color": [1, 1, 1] }},
                "transform": {{ "translate": [0.5, 0.5, 0.5] }},
                "physics": {{ "material": {m}, "regions": [{regions}] }} }}"#,
            m = material(1000.0)
        );
        let err = setup(&scene_text(&obj, 0.02, ""))
            .err()
            .unwrap_or_else(|| panic!("{regions}: accepted"))
            .to_string();
        assert!(err.contains(want), "{regions}:\n got  {err}\n want {want}");
    }
}

/// 16 materials over the scene at most: two objects of 8 regions each are refused with
/// the count.
#[test]
fn too_many_materials_over_the_scene_are_refused() {
    let regions = [r#"{ "shell": { "to": 0.01 }, "material": M }"#; 8]
        .join(", ")
        .replace('M', &material(1000.0));
    let obj = |x: f64| {
        format!(
            r#"{{ "procedural": {{ "shape": "sphere", "radius": 0.1, "spacing": 0.02, "color": [1, 1, 1] }},
                "transform": {{ "translate": [{x}, 0.5, 0.5] }},
                "physics": {{ "material": {m}, "regions": [{regions}] }} }}"#,
            m = material(1000.0)
        )
    };
    let objects = format!("{}, {}", obj(0.3), obj(0.7));
    let err = setup(&scene_text(&objects, 0.02, ""))
        .err()
        .expect("refused")
        .to_string();
    assert!(
        err.contains("objects[1].physics.regions = 18 materials in the scene: expected at most 16"),
        "{err}"
    );
}

/// A label region: the basic shapes label their shells (`shell0`, …, `core`); a region on
/// `shell0` takes exactly the Gaussians so labelled, fill particles follow the label of
/// their nearest Gaussian, and an unknown label lists the object's labels.
#[test]
fn label_regions_follow_the_gaussians_labels() {
    let obj = |label: &str| {
        format!(
            r#"{{ "procedural": {{ "shape": "sphere", "radius": 0.15, "spacing": 0.02, "color": [1, 1, 1],
                                 "shells": [{{ "depth": 0.04, "color": [0, 1, 0] }}] }},
                "transform": {{ "translate": [0.5, 0.5, 0.5] }},
                "physics": {{ "material": {m}, "fill": true, "particles": "gaussians",
                              "regions": [{{ "label": "{label}", "material": {stiff} }}] }} }}"#,
            m = material(1000.0),
            stiff = material(5000.0)
        )
    };
    let s = setup(&scene_text(&obj("shell0"), 0.02, "")).unwrap();
    let (mut labelled, mut stiff) = (0, 0);
    for part in &s.parts {
        for (k, label) in s.part_labels(part).enumerate() {
            let p = part.start + k - s.static_count;
            let in_region = label == Some("shell0");
            assert_eq!(
                s.particles.material[p] == 1,
                in_region,
                "{:?} {label:?}",
                part.kind
            );
            labelled += usize::from(in_region);
            stiff += usize::from(s.particles.material[p] == 1);
        }
    }
    println!("shell0: {labelled} particles, {stiff} stiff");
    assert!(labelled > 1000 && labelled == stiff);
    let err = setup(&scene_text(&obj("rind"), 0.02, ""))
        .err()
        .expect("refused")
        .to_string();
    assert!(
        err.contains(r#"objects[0].physics.regions[0].label = "rind": expected one of the object's labels: shell0, core"#),
        "{err}"
    );
}
