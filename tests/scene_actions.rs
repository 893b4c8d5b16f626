//! `physics.actions` in the scene file: each action takes the particles of its region (a
//! box, a ball or a capture's segments; the whole object by default) as one bit of their
//! membership word, a force becomes the acceleration of its region's mass, and every bad
//! value is refused with one line that names its field.

use std::path::Path;

use glam::DVec3;
use splatter::scene::simulation::{prepare, SimulationSetup};
use splatter::scene::{self, SceneError};
use splatter::sim::ActionKind;

fn scene_text(actions: &str) -> String {
    format!(
        r#"{{
  "output": {{ "width": 32, "height": 24, "frames": 1 }},
  "camera": {{ "fov_y_deg": 40, "path": {{ "type": "orbit", "target": [0.5, 0.5, 0.5], "radius": 2 }} }},
  "simulation": {{ "dx": 0.02, "domain": {{ "lo": [0, 0, 0], "hi": [1, 1, 1] }} }},
  "objects": [{{
    "procedural": {{ "shape": "sphere", "radius": 0.15, "spacing": 0.02, "color": [1, 1, 1],
                    "shells": [{{ "depth": 0.04, "color": [0, 1, 0] }}] }},
    "transform": {{ "translate": [0.5, 0.5, 0.5] }},
    "physics": {{ "material": {{ "model": "fixed_corotated", "E": 1000, "nu": 0.3, "density": 2 }},
                  "fill": true, "particles": "gaussians", "actions": [{actions}] }} }}]
}}"#
    )
}

fn setup(text: &str) -> Result<SimulationSetup, SceneError> {
    let scene = scene::parse(text, "test.json", Path::new("."))?;
    let (splats, report) = scene.build_splats()?;
    Ok(prepare(&scene, splats, &report)?.expect("a simulation"))
}

/// A force on the lower half, a hold on the labelled outer shell, a drive of the whole
/// object: the bits follow the regions exactly, and the force's acceleration times its
/// region's mass is the force.
#[test]
fn actions_take_their_regions() {
    let s = setup(&scene_text(
        r#"{ "impulse": { "force": [0, 0.5, 2] }, "region": { "box": { "lo": [0, 0, 0], "hi": [1, 1, 0.5] } }, "from": 0.1, "to": 0.2 },
           { "hold": {}, "region": { "label": ["shell0"] } },
           { "drive": { "velocity": [0, 0, 1] }, "from": 0.3 }"#,
    ))
    .unwrap();
    let a = &s.params.actions;
    assert_eq!(a.list.len(), 3);
    assert_eq!((a.list[0].from, a.list[0].to), (0.1, 0.2));
    assert_eq!((a.list[2].from, a.list[2].to), (0.3, f64::INFINITY));
    let p = &s.particles;
    let mut labelled = 0;
    for part in &s.parts {
        for (k, label) in s.part_labels(part).enumerate() {
            let q = part.start + k - s.static_count;
            let bits = a.members[q];
            assert_eq!(bits & 1 == 1, p.x[q].z <= 0.5, "{q} at {}", p.x[q]);
            assert_eq!(bits >> 1 & 1 == 1, label == Some("shell0"), "{q} {label:?}");
            assert_eq!(bits >> 2 & 1, 1, "{q}: the drive takes the whole object");
            labelled += usize::from(label == Some("shell0"));
        }
    }
    assert!(labelled > 1000, "{labelled}");
    let ActionKind::Impulse { acceleration } = a.list[0].kind else {
        panic!("{:?}", a.list[0].kind)
    };
    let f = acceleration * a.region_mass(0, &p.mass);
    assert!((f - DVec3::new(0.0, 0.5, 2.0)).length() < 1e-12, "{f}");
    assert!(matches!(a.list[1].kind, ActionKind::Hold));
}

#[test]
fn bad_actions_are_named() {
    let cases = [
        (
            r#"{ "from": 0 }"#,
            "objects[0].physics.actions[0] = no action: expected exactly one of `impulse`, `hold` or `drive`",
        ),
        (
            r#"{ "hold": {}, "drive": { "velocity": [0, 0, 1] } }"#,
            "objects[0].physics.actions[0] = hold and drive: expected exactly one of",
        ),
        (
            r#"{ "hold": {}, "from": 0.5, "to": 0.5 }"#,
            "objects[0].physics.actions[0].to = 0.5: expected an end time in seconds after `from` (0.5)",
        ),
        (
            r#"{ "hold": {}, "from": -1 }"#,
            "objects[0].physics.actions[0].from = -1: expected a start time in seconds ≥ 0",
        ),
        (
            r#"{ "impulse": { "acceleration": [0, 0, 1], "force": [0, 0, 1] } }"#,
            "objects[0].physics.actions[0].impulse = both or neither of acceleration and force",
        ),
        (
            r#"{ "drive": { "path": [{ "time": 0.2, "position": [0, 0, 0] }, { "time": 0.1, "position": [0, 0, 1] }] } }"#,
            "objects[0].physics.actions[0].drive.path[1].time = 0.1: expected a time after the keyframe before (0.2)",
        ),
        (
            r#"{ "drive": { "path": [] } }"#,
            "objects[0].physics.actions[0].drive.path = no keyframes",
        ),
        (
            r#"{ "hold": {}, "region": { "box": { "lo": [0, 0, 0], "hi": [0.1, 0.1, 0.1] } } }"#,
            "objects[0].physics.actions[0].region = a region with none of the object's particles: expected a region that takes some of them (they lie in",
        ),
        (
            r#"{ "hold": {}, "region": { "label": ["stem"] } }"#,
            r#"objects[0].physics.actions[0].region.label = ["stem"]: expected labels the object's particles carry: core, shell0"#,
        ),
        (
            r#"{ "hold": {}, "region": { "sphere": { "center": [0.5, 0.5, 0.5], "radius": -1 } } }"#,
            "objects[0].physics.actions[0].region.sphere.radius = -1",
        ),
        (
            &[r#"{ "hold": {} }"#; 9].join(", "),
            "objects[0].physics.actions = 9 actions in the scene: expected at most 8 actions over all simulated objects",
        ),
        (r#"{ "hold": { "strength": 1 } }"#, "unknown field `strength`"),
        (r#"{ "poke": {} }"#, "unknown field `poke`"),
    ];
    for (actions, want) in cases {
        let err = setup(&scene_text(actions))
            .err()
            .unwrap_or_else(|| panic!("{actions}: accepted"))
            .to_string();
        assert!(err.contains(want), "{actions}:\n got  {err}\n want {want}");
    }
}
