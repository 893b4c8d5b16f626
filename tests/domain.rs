//! The domain a scene writes is the box the physics sees: its faces are the walls and its
//! −z face the ground (the grid reaches past them by the wall band's padding), so an
//! object may start resting on the floor or touching a wall, and material that falls
//! onto the floor stops at the domain's face, not a few cells above it.

use std::path::Path;

use splatter::scene::simulation::{prepare, SimulationSetup};
use splatter::scene::{self, SceneError};
use splatter::sim::cpu;

const DX: f64 = 0.05;

/// A 0.15 m jelly cube centred at `centre`, moving at `velocity`, in the domain
/// [0, 0.5]³ with a frictional separating ground and separating walls.
fn cube(centre: [f64; 3], velocity: [f64; 3]) -> Result<SimulationSetup, SceneError> {
    let text = format!(
        r#"{{
  "output": {{ "width": 32, "height": 24, "frames": 1 }},
  "camera": {{ "fov_y_deg": 40, "path": {{ "type": "orbit", "target": [0.25, 0.25, 0.1], "radius": 1 }} }},
  "simulation": {{ "dx": {DX}, "domain": {{ "lo": [0, 0, 0], "hi": [0.5, 0.5, 0.5] }},
                   "ground": {{ "kind": "separate", "friction": 0.5 }} }},
  "objects": [{{
    "procedural": {{ "shape": "box", "size": [0.15, 0.15, 0.15], "spacing": 0.025, "color": [1, 1, 1] }},
    "transform": {{ "translate": {centre:?} }},
    "physics": {{ "material": {{ "model": "fixed_corotated", "E": 2e4, "nu": 0.3, "density": 1000 }},
                  "particles": "gaussians", "velocity": {velocity:?} }}
  }}]
}}"#
    );
    let scene = scene::parse(&text, "cube.json", Path::new("."))?;
    let (splats, report) = scene.build_splats()?;
    Ok(prepare(&scene, splats, &report)?.expect("a simulation"))
}

/// The lowest z and the smallest x any particle reaches over `seconds`.
fn reach(s: &mut SimulationSetup, seconds: f64) -> (f64, f64) {
    let steps = (seconds / s.params.dt).ceil() as usize;
    let (mut lowest, mut leftmost) = (f64::MAX, f64::MAX);
    for _ in 0..steps {
        cpu::step(&mut s.particles, &mut s.grid, &s.materials, &s.params);
        for x in &s.particles.x {
            lowest = lowest.min(x.z);
            leftmost = leftmost.min(x.x);
        }
    }
    (lowest, leftmost)
}

/// A cube whose bottom is 1 mm above z = 0 (the domain's floor) and whose side is 1 mm
/// from x = 0 is accepted, and it stays where it rests: the floor and the wall hold it
/// at the domain's faces.
#[test]
fn an_object_resting_on_the_floor_and_touching_a_wall_is_accepted() {
    let mut s = cube([0.076, 0.25, 0.076], [0.0, 0.0, 0.0]).expect("accepted");
    let (lowest, leftmost) = reach(&mut s, 0.3);
    println!("lowest z {lowest:.4}, smallest x {leftmost:.4}");
    assert!(
        lowest.abs() < 0.5 * DX,
        "the floor moved: lowest particle at z {lowest}"
    );
    assert!(
        leftmost.abs() < 0.5 * DX,
        "the wall moved: leftmost particle at x {leftmost}"
    );
}

/// A cube dropped from 0.3 m lands on the floor at the domain's face (within half a
/// cell), not (band − 1) cells above it; one thrown at the −x wall reaches x = 0 before it
/// rebounds.
#[test]
fn falling_and_thrown_cubes_stop_at_the_domains_faces() {
    let mut dropped = cube([0.25, 0.25, 0.3], [0.0, 0.0, -1.0]).expect("accepted");
    let (lowest, _) = reach(&mut dropped, 0.4);
    println!("dropped: lowest z {lowest:.4}");
    assert!(
        lowest.abs() < 0.5 * DX,
        "lowest particle at z {lowest}, not on the floor z = 0"
    );
    let mut thrown = cube([0.25, 0.25, 0.3], [-3.0, 0.0, 0.0]).expect("accepted");
    let (_, leftmost) = reach(&mut thrown, 0.15);
    println!("thrown: smallest x {leftmost:.4}");
    assert!(
        leftmost.abs() < 0.5 * DX,
        "the cube turned at x {leftmost}, not at the wall x = 0"
    );
}

/// An object that crosses a face is refused with one line naming the object, the particle
/// and the domain.
#[test]
fn an_object_through_the_floor_is_refused() {
    let err = cube([0.25, 0.25, 0.03], [0.0; 3]).err().expect("refused");
    let text = err.to_string();
    println!("{text}");
    assert!(text.contains("objects[0]") && text.contains("inside simulation.domain"));
    assert_eq!(text.lines().count(), 1);
}
