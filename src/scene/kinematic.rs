//! An object's `kinematic` block: the object moves on a prescribed rigid path (a knife, a
//! projectile) and is a moving collider for the simulation (`sim::kinematic`). Its
//! Gaussians are rendered moving with it.

use std::ops::Range;

use glam::{DMat3, DVec3, Vec3};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::physics::{ConditionKind, ConditionSpec};
use super::{Scene, SceneError};
use crate::render::Splats;
use crate::sim::kinematic::{ColliderShape, KinematicCollider, RigidMotion};
use crate::splat::procedural::Shape;

fn default_kind() -> ConditionKind {
    ConditionKind::Sticky
}

/// `objects[i].kinematic`: keyframes replacing the object's `transform.translate` and
/// `transform.rotate_deg` over time (its scale stays), and how it acts on the simulation.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct KinematicSpec {
    /// At least one keyframe, with strictly increasing times. Positions follow the same C¹
    /// Hermite spline as camera keyframes; angles are interpolated linearly. The pose is
    /// held before the first and after the last keyframe.
    pub keyframes: Vec<KinematicKeyframe>,
    /// Condition on the material it touches, in its frame. Default `sticky`.
    #[serde(default = "default_kind")]
    pub kind: ConditionKind,
    /// Coulomb friction on the relative tangential velocity (slip, separate). Default 0.
    #[serde(default)]
    pub friction: f64,
    /// The collision shape in object coordinates (scaled by the transform's scale). Default:
    /// the procedural sphere, box or cylinder itself; for other objects the bounding box of
    /// their Gaussians.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shape: Option<ColliderShapeSpec>,
    /// Grid nodes within this distance (world units) outside the shape are covered too: a
    /// blade thinner than about 2 Δx needs it to reach nodes. Default 0.
    #[serde(default)]
    pub margin: f64,
}

/// A pose of a kinematic object at a time.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct KinematicKeyframe {
    /// Seconds (frame f is at time f / fps).
    pub time: f32,
    /// Where the object's origin is (its `translate` at this time).
    pub position: [f32; 3],
    /// Euler angles in degrees, as `transform.rotate_deg`. Default [0, 0, 0].
    #[serde(default)]
    pub rotate_deg: [f32; 3],
}

/// An explicit collision shape, centred on `center` (object coordinates).
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(tag = "shape", rename_all = "snake_case", deny_unknown_fields)]
pub enum ColliderShapeSpec {
    Sphere {
        radius: f64,
        #[serde(default)]
        center: [f64; 3],
    },
    Box {
        size: [f64; 3],
        #[serde(default)]
        center: [f64; 3],
    },
    /// Axis along the object's z.
    Cylinder {
        radius: f64,
        height: f64,
        #[serde(default)]
        center: [f64; 3],
    },
}

/// A kinematic object of the scene, ready for the simulation and the renderer.
#[derive(Clone, Debug, PartialEq)]
pub struct KinematicObject {
    /// Index in `scene.objects`.
    pub object: usize,
    pub collider: KinematicCollider,
    /// The transform's rotation and translation the object was built with.
    rest_rotation: DMat3,
    rest_translate: DVec3,
}

impl KinematicObject {
    /// The map x ↦ A x + b from the object's Gaussians as built (at its transform) to where
    /// they are at `t` seconds: A = R(t) R₀ᵀ, b = p(t) − A t₀.
    pub fn rest_to_world(&self, t: f64) -> (DMat3, DVec3) {
        let pose = self.collider.motion.pose(t);
        let a = pose.rotation * self.rest_rotation.transpose();
        (a, pose.position - a * self.rest_translate)
    }
}

/// The kinematic objects of `scene`; `splats` are all Gaussians as built (objects in file
/// order), object i at `range(i)`.
pub fn build(
    scene: &Scene,
    splats: &Splats,
    range: impl Fn(usize) -> Range<usize>,
) -> Result<Vec<KinematicObject>, SceneError> {
    let o = scene.origin.as_str();
    let mut out = Vec::new();
    for (i, obj) in scene.objects.iter().enumerate() {
        let Some(spec) = &obj.kinematic else {
            continue;
        };
        let field = |f: &str| format!("objects[{i}].kinematic{f}");
        if obj.physics.is_some() {
            return Err(SceneError::invalid(
                o,
                field(""),
                "set together with `physics`",
                "either `physics` (simulated) or `kinematic` (a prescribed path)",
            ));
        }
        let motion = motion(o, spec, &field)?;
        if !(spec.margin.is_finite() && spec.margin >= 0.0) {
            return Err(SceneError::invalid(
                o,
                field(".margin"),
                spec.margin,
                "a distance ≥ 0",
            ));
        }
        let condition = ConditionSpec {
            kind: spec.kind,
            friction: spec.friction,
        }
        .build(o, &field(""))?;
        let rest_rotation = obj.transform.rotation().as_dmat3();
        let rest_translate = Vec3::from(obj.transform.translate).as_dvec3();
        let scale = obj.transform.scale.as_vec3().as_dvec3();
        let (shape, centre) = match shape_spec(obj) {
            Some(s) => scaled_shape(o, &s, scale, &field)?,
            None => bounding_box(splats, range(i), rest_rotation, rest_translate),
        };
        out.push(KinematicObject {
            object: i,
            collider: KinematicCollider {
                shape,
                centre,
                margin: spec.margin,
                condition,
                motion,
            },
            rest_rotation,
            rest_translate,
        });
    }
    if out.len() > crate::sim::gpu::MAX_KINEMATIC {
        return Err(SceneError::invalid(
            o,
            "objects",
            format!("{} kinematic objects", out.len()),
            format!("at most {}", crate::sim::gpu::MAX_KINEMATIC),
        ));
    }
    Ok(out)
}

fn motion(
    o: &str,
    spec: &KinematicSpec,
    field: &dyn Fn(&str) -> String,
) -> Result<RigidMotion, SceneError> {
    let keys = &spec.keyframes;
    if keys.is_empty() {
        return Err(SceneError::invalid(
            o,
            field(".keyframes"),
            "[]",
            "at least one keyframe",
        ));
    }
    for (k, key) in keys.iter().enumerate() {
        let finite = key.time.is_finite()
            && key
                .position
                .iter()
                .chain(&key.rotate_deg)
                .all(|v| v.is_finite());
        let increasing = k == 0 || key.time > keys[k - 1].time;
        if !(finite && increasing) {
            return Err(SceneError::invalid(
                o,
                field(&format!(".keyframes[{k}]")),
                format!("time {}", key.time),
                "finite values and strictly increasing times",
            ));
        }
    }
    Ok(RigidMotion::new(
        keys.iter().map(|k| k.time).collect(),
        keys.iter().map(|k| Vec3::from(k.position)).collect(),
        keys.iter().map(|k| Vec3::from(k.rotate_deg)).collect(),
    ))
}

/// The explicit shape, else the procedural sphere, box or cylinder.
fn shape_spec(obj: &super::ObjectSpec) -> Option<ColliderShapeSpec> {
    if let Some(s) = obj.kinematic.as_ref().and_then(|k| k.shape.clone()) {
        return Some(s);
    }
    let center = [0.0; 3];
    match obj.procedural.as_ref()?.shape {
        Shape::Sphere { radius } => Some(ColliderShapeSpec::Sphere {
            radius: f64::from(radius),
            center,
        }),
        Shape::Box { size } => Some(ColliderShapeSpec::Box {
            size: size.map(f64::from),
            center,
        }),
        Shape::Cylinder { radius, height } => Some(ColliderShapeSpec::Cylinder {
            radius: f64::from(radius),
            height: f64::from(height),
            center,
        }),
        #[allow(unreachable_patterns)]
        _ => None,
    }
}

/// The shape in the scaled object frame: boxes scale per axis; a sphere's radius by the
/// largest scale, a cylinder's by the larger of x and y (bounds, not exact, under a
/// non-uniform scale).
fn scaled_shape(
    o: &str,
    s: &ColliderShapeSpec,
    scale: DVec3,
    field: &dyn Fn(&str) -> String,
) -> Result<(ColliderShape, DVec3), SceneError> {
    let positive = |name: &str, v: f64| {
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(SceneError::invalid(
                o,
                field(&format!(".shape.{name}")),
                v,
                "a length > 0",
            ))
        }
    };
    let (shape, center) = match s {
        ColliderShapeSpec::Sphere { radius, center } => (
            ColliderShape::Sphere {
                radius: positive("radius", *radius)? * scale.max_element(),
            },
            center,
        ),
        ColliderShapeSpec::Box { size, center } => {
            for v in size {
                positive("size", *v)?;
            }
            let half = DVec3::from_array(*size) * scale / 2.0;
            (ColliderShape::Box { half }, center)
        }
        ColliderShapeSpec::Cylinder {
            radius,
            height,
            center,
        } => (
            ColliderShape::Cylinder {
                radius: positive("radius", *radius)? * scale.x.max(scale.y),
                half_height: positive("height", *height)? * scale.z / 2.0,
            },
            center,
        ),
    };
    let c = DVec3::from_array(*center);
    if !c.is_finite() {
        return Err(SceneError::invalid(
            o,
            field(".shape.center"),
            c,
            "finite numbers",
        ));
    }
    Ok((shape, c * scale))
}

/// The bounding box of the object's Gaussian means in its scaled, unrotated frame.
fn bounding_box(
    splats: &Splats,
    range: Range<usize>,
    rotation: DMat3,
    translate: DVec3,
) -> (ColliderShape, DVec3) {
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for g in range {
        let local = rotation.transpose() * (splats.means[g].as_dvec3() - translate);
        lo = lo.min(local);
        hi = hi.max(local);
    }
    if !(lo.is_finite() && hi.is_finite()) {
        (lo, hi) = (DVec3::ZERO, DVec3::ZERO);
    }
    let half = ((hi - lo) / 2.0).max(DVec3::splat(1e-6));
    (ColliderShape::Box { half }, (lo + hi) / 2.0)
}
