//! The scene file's physics: the `simulation` block (grid, step, gravity, boundaries) and
//! each object's `physics` (material, selection, fill, regions), as serde types with their
//! validation and their conversion to the simulation's types. `scene::simulation` turns
//! them into particles, `scene::regions` into materials per particle.

use glam::DVec3;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

pub use super::material::{MaterialSpec, ModelName};
use super::SceneError;
use crate::sim::{Attractor, BoundaryKind, Condition, Fields, Gusts, Separation, Transfer, Wind};

fn default_gravity() -> [f64; 3] {
    [0.0, 0.0, -9.8]
}
fn default_cfl() -> f64 {
    0.4
}
/// `simulation.cfl_velocity` when the scene does not set it (docs/method.md §2.3).
pub const DEFAULT_CFL_VELOCITY: f64 = 0.15;

/// The `simulation` block.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SimulationSpec {
    /// Grid spacing Δx.
    pub dx: f64,
    /// Step Δt in seconds. Default: from the CFL condition Δt = cfl · Δx / c over the
    /// materials (c = sqrt((λ + 2μ)/ρ)).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dt: Option<f64>,
    /// CFL number for the default Δt (and the check of a given one). Default 0.4.
    #[serde(default = "default_cfl")]
    pub cfl: f64,
    /// Without `dt`: the fraction of a cell the fastest particle may cross in a step, so
    /// that Δt ≤ cfl_velocity · Δx / v_max too, re-chosen every frame from the speeds of
    /// the frame before (docs/method.md §2.3). Default 0.15. With `dt` the step is fixed
    /// and this is ignored (with a warning).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cfl_velocity: Option<f64>,
    /// The simulated box: only what moves is gridded. Its faces are where the walls and the
    /// ground act ([`SimulationSpec::grid_box`]).
    pub domain: DomainSpec,
    /// Default [0, 0, −9.8] (z up).
    #[serde(default = "default_gravity")]
    pub gravity: [f64; 3],
    /// Condition on the domain's faces. Default `separate`, no friction.
    #[serde(default)]
    pub walls: ConditionSpec,
    /// Condition on the bottom face (−z) only, e.g. a frictional or sticky ground.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground: Option<ConditionSpec>,
    /// Planar colliders (at most 8).
    #[serde(default)]
    pub colliders: Vec<ColliderSpec>,
    /// How velocity moves between particles and grid: `"apic"` (the default) or a FLIP/PIC
    /// blend `{"flip": f}`, f in [0, 1] (0: PIC; the official GaussianFluent release's
    /// watermelon uses 0.7).
    #[serde(default)]
    pub transfer: TransferSpec,
    /// How the grid keeps the pieces of a fractured body apart: `"none"` (the default, one
    /// velocity per node) or `"damage_gradient"` (two velocity fields per node where a
    /// broken particle is near, split by the damage field's gradient, with a
    /// frictionless contact between them; docs/method.md §4.9). Runs on the gather P2G
    /// path.
    #[serde(default)]
    pub separation: SeparationSpec,
    /// Force fields over the whole simulation, each `{"wind": {..}}` or
    /// `{"attractor": {..}}` (at most one of each; docs/method.md §2.5).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub fields: Vec<FieldSpec>,
}

/// One of `simulation.fields`.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum FieldSpec {
    /// A wind: the material takes its velocity at rate `drag`, dv/dt = drag (w − v).
    Wind(WindSpec),
    /// A pull towards a point (a push away when `strength` < 0).
    Attractor(AttractorSpec),
}

/// `{"wind": {..}}`.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct WindSpec {
    /// The wind's velocity w in m/s.
    pub velocity: [f64; 3],
    /// k in 1/s (> 0): how fast the material takes the wind's velocity (a body at rest
    /// reaches 1 − e^{−kt} of it).
    pub drag: f64,
    /// Gusts: the velocity scaled in time by 1 + strength · n(t / period), n a smooth seeded
    /// noise in [−1, 1]. Absent: a steady wind.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gusts: Option<GustsSpec>,
}

/// `"gusts"` of a wind.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GustsSpec {
    /// The gusts' share of the mean wind (≥ 0; 0.5: from half to one and a half times it).
    pub strength: f64,
    /// Seconds between the noise's values (> 0): about how long a gust lasts.
    pub period: f64,
    /// Seed of the noise (default 0): the same seed, the same gusts.
    #[serde(default)]
    pub seed: u32,
}

/// `{"attractor": {..}}`.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AttractorSpec {
    /// The point p it pulls towards, in m.
    pub point: [f64; 3],
    /// The acceleration towards p close to it, in m/s² (negative: away from p).
    pub strength: f64,
    /// r in m (> 0): at distance d the acceleration is scaled by r² / (r² + d²), half at r.
    pub falloff: f64,
}

/// The step's fields from `simulation.fields`, validated.
pub fn build_fields(specs: &[FieldSpec], origin: &str) -> Result<Fields, SceneError> {
    let mut fields = Fields::default();
    for (i, spec) in specs.iter().enumerate() {
        let at = |name: &str| format!("simulation.fields[{i}].{name}");
        match spec {
            FieldSpec::Wind(w) => {
                let first = fields.wind.is_none();
                require(
                    first,
                    origin,
                    at("wind"),
                    "a second wind",
                    "at most one wind",
                )?;
                finite3(origin, &at("wind.velocity"), w.velocity)?;
                require(
                    w.drag.is_finite() && w.drag > 0.0,
                    origin,
                    at("wind.drag"),
                    w.drag,
                    "a drag rate in 1/s > 0",
                )?;
                let gusts = match &w.gusts {
                    None => None,
                    Some(g) => {
                        require(
                            g.strength.is_finite() && g.strength >= 0.0,
                            origin,
                            at("wind.gusts.strength"),
                            g.strength,
                            "a share of the wind ≥ 0",
                        )?;
                        require(
                            g.period.is_finite() && g.period > 0.0,
                            origin,
                            at("wind.gusts.period"),
                            g.period,
                            "a time in s > 0",
                        )?;
                        Some(Gusts {
                            strength: g.strength,
                            period: g.period,
                            seed: g.seed,
                        })
                    }
                };
                fields.wind = Some(Wind {
                    velocity: DVec3::from(w.velocity),
                    drag: w.drag,
                    gusts,
                });
            }
            FieldSpec::Attractor(a) => {
                let first = fields.attractor.is_none();
                require(
                    first,
                    origin,
                    at("attractor"),
                    "a second attractor",
                    "at most one attractor",
                )?;
                finite3(origin, &at("attractor.point"), a.point)?;
                require(
                    a.strength.is_finite(),
                    origin,
                    at("attractor.strength"),
                    a.strength,
                    "an acceleration in m/s² (finite)",
                )?;
                require(
                    a.falloff.is_finite() && a.falloff > 0.0,
                    origin,
                    at("attractor.falloff"),
                    a.falloff,
                    "a distance in m > 0",
                )?;
                fields.attractor = Some(Attractor {
                    point: DVec3::from(a.point),
                    strength: a.strength,
                    falloff: a.falloff,
                });
            }
        }
    }
    Ok(fields)
}

/// `Ok` when `ok`, else the error naming `field`, its `value` and what it takes.
pub(super) fn require(
    ok: bool,
    origin: &str,
    field: String,
    value: impl std::fmt::Display,
    expected: &str,
) -> Result<(), SceneError> {
    if ok {
        Ok(())
    } else {
        Err(SceneError::invalid(origin, field, value, expected))
    }
}

pub(super) fn finite3(origin: &str, field: &str, v: [f64; 3]) -> Result<(), SceneError> {
    let ok = v.iter().all(|x| x.is_finite());
    require(
        ok,
        origin,
        field.to_string(),
        format!("{v:?}"),
        "three finite numbers",
    )
}

/// `simulation.separation`.
#[derive(Clone, Copy, Debug, Default, Serialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum SeparationSpec {
    #[default]
    None,
    DamageGradient,
}

/// By name, with an error that names the field (serde's own names only the value).
impl<'de> Deserialize<'de> for SeparationSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        match name.as_str() {
            "none" => Ok(SeparationSpec::None),
            "damage_gradient" => Ok(SeparationSpec::DamageGradient),
            other => Err(serde::de::Error::custom(format!(
                "`separation`: {other:?} is not one of \"none\", \"damage_gradient\""
            ))),
        }
    }
}

impl From<SeparationSpec> for Separation {
    fn from(s: SeparationSpec) -> Separation {
        match s {
            SeparationSpec::None => Separation::None,
            SeparationSpec::DamageGradient => Separation::DamageGradient,
        }
    }
}

/// `simulation.transfer`.
#[derive(Clone, Debug, Default, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(
    untagged,
    expecting = "`transfer`: \"apic\" or {\"flip\": f} with f in [0, 1]"
)]
pub enum TransferSpec {
    #[default]
    #[serde(with = "apic_name")]
    #[schemars(with = "ApicName")]
    Apic,
    FlipPic(FlipPicSpec),
}

/// The name `"apic"`.
#[derive(JsonSchema)]
#[serde(rename_all = "snake_case")]
#[allow(dead_code)]
enum ApicName {
    Apic,
}

/// `"apic"` as the unit variant of an untagged enum.
mod apic_name {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str("apic")
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<(), D::Error> {
        let name = String::deserialize(d)?;
        if name == "apic" {
            Ok(())
        } else {
            Err(serde::de::Error::custom("not \"apic\""))
        }
    }
}

/// A FLIP/PIC blend: the FLIP share of G2P's velocity.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FlipPicSpec {
    pub flip: f64,
}

impl TransferSpec {
    /// The step's transfer, validated.
    pub fn build(&self, origin: &str) -> Result<Transfer, SceneError> {
        match self {
            TransferSpec::Apic => Ok(Transfer::Apic),
            TransferSpec::FlipPic(FlipPicSpec { flip }) => {
                if !(0.0..=1.0).contains(flip) {
                    return Err(SceneError::invalid(
                        origin,
                        "simulation.transfer.flip",
                        flip,
                        "a FLIP share in [0, 1] (0: PIC)",
                    ));
                }
                Ok(Transfer::FlipPic { flip: *flip })
            }
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DomainSpec {
    pub lo: [f64; 3],
    pub hi: [f64; 3],
}

impl SimulationSpec {
    /// The grid's box: `domain` grown by (band − 1)Δx on every side. A wall condition acts
    /// on the band of nodes next to a grid face and material meets it at the band's
    /// innermost node, (band − 1)Δx in (`sim::boundary`); growing the box by that much puts
    /// the wall, and the ground, on the face of the domain the scene wrote. (An upper
    /// face lies on the domain's only when its extent is a whole number of cells; the
    /// grid rounds it up.)
    pub fn grid_box(&self) -> (DVec3, DVec3) {
        let pad = DVec3::splat(f64::from(crate::sim::WALL_BAND - 1) * self.dx);
        (vec3(self.domain.lo) - pad, vec3(self.domain.hi) + pad)
    }
}

/// `sticky` (v = 0), `slip` (normal velocity removed) or `separate` (only the velocity into
/// the obstacle removed), with Coulomb friction on the tangential part.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ConditionSpec {
    pub kind: ConditionKind,
    #[serde(default)]
    pub friction: f64,
}

impl Default for ConditionSpec {
    fn default() -> Self {
        ConditionSpec {
            kind: ConditionKind::Separate,
            friction: 0.0,
        }
    }
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum ConditionKind {
    Sticky,
    Slip,
    Separate,
}

/// The solid half-space (x − point)·normal ≤ 0.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ColliderSpec {
    pub point: [f64; 3],
    /// Outward normal (normalised on use).
    pub normal: [f64; 3],
    #[serde(flatten)]
    pub condition: ConditionSpec,
}

/// An object's `physics`: it is simulated, with this material and initial motion.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PhysicsSpec {
    pub material: MaterialSpec,
    /// Initial velocity. Default 0.
    #[serde(default)]
    pub velocity: [f64; 3],
    /// Initial angular velocity (rad/s) about the object's centre of mass. Default 0.
    #[serde(default)]
    pub angular_velocity: [f64; 3],
    /// Which Gaussians move: those whose mean lies in this region (world coordinates, after
    /// the object's transform). Default: the whole object. The rest stays static.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub select: Option<SelectSpec>,
    /// Gaussians with a lower opacity stay static (rendered, not simulated). Default 0.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub min_opacity: f64,
    /// Interior filling (`scene::fill`): `true` (spacing Δx/2), `false`, or
    /// `{"spacing": h}`. Default off.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fill: Option<FillSpec>,
    /// Material regions (`scene::regions`): the first region a particle lies in gives its
    /// material (and its fill colour); particles in none keep `material`. Default none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub regions: Vec<RegionSpec>,
    /// What the object's MPM particles are: `{"spacing": h}` (a jittered lattice over the
    /// object's solid, its Gaussians bound to it; the default, at h = Δx/2) or
    /// `"gaussians"` (every selected Gaussian is a particle, plus the fill).
    #[serde(default)]
    pub particles: ParticlesSpec,
    /// Timed actions on regions of the object (`scene::actions`): impulses, holds and
    /// drives, each during its window. Default none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub actions: Vec<ActionSpec>,
}

/// One timed action: exactly one of `impulse`, `hold`, `drive`, on `region` (default: the
/// whole object) during [`from`, `to`).
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ActionSpec {
    /// A push: `{"acceleration": [ax, ay, az]}` in m/s², or `{"force": [Fx, Fy, Fz]}` in
    /// newtons spread over the region's mass. A poke, a kick, a tug.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub impulse: Option<ImpulseSpec>,
    /// `{}`: the region pinned where it is (v = 0, its shape kept) during the window: a pot
    /// on a table, a clamped end.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hold: Option<HoldSpec>,
    /// The region moved rigidly: `{"velocity": [..]}` in m/s, or `{"path": [{"time": t,
    /// "position": [..]}, ..]}`, moving it as the keyframed point moves from `from` on (the
    /// camera paths' C¹ spline, held before the first key and after the last): a hand
    /// holding a stem, a pulled corner.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub drive: Option<DriveSpec>,
    /// Which particles, as `physics.select`: `{"box": …}`, `{"sphere": …}` (world
    /// coordinates, tested on the particles at rest) or `{"label": [..]}` (a capture's
    /// segments, an asset's regions). Default: the whole object.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region: Option<SelectSpec>,
    /// Start of the window in seconds. Default 0.
    #[serde(default)]
    pub from: f64,
    /// End of the window in seconds (> from). Default: the end of the run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub to: Option<f64>,
}

/// An impulse's size: exactly one of the two.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ImpulseSpec {
    /// m/s² on every particle of the region.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub acceleration: Option<[f64; 3]>,
    /// Newtons on the region as a whole: each particle takes F / M, M the region's mass.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub force: Option<[f64; 3]>,
}

/// A hold takes no parameters.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct HoldSpec {}

/// How a driven region moves: exactly one of the two.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DriveSpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub velocity: Option<[f64; 3]>,
    /// At least one keyframe, times strictly increasing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path: Option<Vec<PathKey>>,
}

/// A keyframe of a drive's path.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PathKey {
    /// Seconds.
    pub time: f32,
    pub position: [f32; 3],
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

/// What of an object moves: a region of the world, or the Gaussians of some labels.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum SelectSpec {
    /// The axis-aligned box lo ≤ x ≤ hi.
    Box { lo: [f64; 3], hi: [f64; 3] },
    /// The ball |x − center| ≤ radius.
    Sphere { center: [f64; 3], radius: f64 },
    /// The Gaussians whose region label is one of these: a procedural asset's region names
    /// (`"rind"`, `"flesh"`, …), or a capture's segments, the values of its integer vertex
    /// property `label` (else `segment`), as numbers or strings. The object's solid is
    /// that of the selected Gaussians (an asset's: where its selected regions are).
    Label(Vec<LabelName>),
}

/// A label in a selection: its name, or a capture's segment id.
#[derive(Clone, Debug, Serialize, JsonSchema, PartialEq)]
#[serde(untagged)]
pub enum LabelName {
    Id(i64),
    Name(String),
}

impl<'de> Deserialize<'de> for LabelName {
    /// A string or an integer; anything else is an error that says so (serde's untagged
    /// enums only say that no variant matched).
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visit;
        impl serde::de::Visitor<'_> for Visit {
            type Value = LabelName;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a label: a name (\"rind\") or a capture's integer segment id (3)")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<LabelName, E> {
                Ok(LabelName::Name(v.to_string()))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<LabelName, E> {
                Ok(LabelName::Id(v))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<LabelName, E> {
                i64::try_from(v)
                    .map(LabelName::Id)
                    .map_err(|_| E::invalid_value(serde::de::Unexpected::Unsigned(v), &self))
            }
        }
        d.deserialize_any(Visit)
    }
}

impl LabelName {
    /// The label's name as the Gaussians carry it (a segment id in decimal).
    pub fn text(&self) -> String {
        match self {
            LabelName::Id(id) => id.to_string(),
            LabelName::Name(name) => name.clone(),
        }
    }
}

impl SelectSpec {
    pub(crate) fn validate(&self, origin: &str, field: &str) -> Result<(), SceneError> {
        match self {
            SelectSpec::Box { lo, hi } => {
                let (lo, hi) = (vec3(*lo), vec3(*hi));
                if !(lo.is_finite() && hi.is_finite() && hi.cmpgt(lo).all()) {
                    return Err(SceneError::invalid(
                        origin,
                        format!("{field}.box"),
                        format!("{lo} .. {hi}"),
                        "finite lo < hi on every axis",
                    ));
                }
            }
            SelectSpec::Sphere { center, radius } => {
                if !vec3(*center).is_finite() {
                    return Err(SceneError::invalid(
                        origin,
                        format!("{field}.sphere.center"),
                        vec3(*center),
                        "a finite point",
                    ));
                }
                if !(radius.is_finite() && *radius > 0.0) {
                    return Err(SceneError::invalid(
                        origin,
                        format!("{field}.sphere.radius"),
                        radius,
                        "a radius > 0",
                    ));
                }
            }
            SelectSpec::Label(names) => {
                if names.is_empty() {
                    return Err(SceneError::invalid(
                        origin,
                        format!("{field}.label"),
                        "[]",
                        "at least one label",
                    ));
                }
            }
        }
        Ok(())
    }

    /// Whether the point lies in the region (boundary included). A label selection has no
    /// extent of its own: every point (its Gaussians, or an asset's regions, bound it).
    pub fn contains(&self, p: DVec3) -> bool {
        match self {
            SelectSpec::Box { lo, hi } => p.cmpge(vec3(*lo)).all() && p.cmple(vec3(*hi)).all(),
            SelectSpec::Sphere { center, radius } => {
                p.distance_squared(vec3(*center)) <= radius * radius
            }
            SelectSpec::Label(_) => true,
        }
    }

    /// Whether a Gaussian at `p` with the label `label` is selected.
    pub fn picks(&self, p: DVec3, label: Option<&str>) -> bool {
        match self {
            SelectSpec::Label(names) => label.is_some_and(|l| names.iter().any(|n| n.text() == l)),
            _ => self.contains(p),
        }
    }
}

/// `physics.particles`: the object's MPM particles.
///
/// The lattice is the default because it makes the simulation's cost follow the physics:
/// a capture of a million Gaussians and a coarse procedural object both get about eight
/// particles per grid cell, and the Gaussians keep the capture's detail by riding on them
/// (`derive::binding`). `"gaussians"` is the paper's way, for comparisons.
#[derive(Clone, Debug, Serialize, JsonSchema, PartialEq)]
#[serde(untagged)]
pub enum ParticlesSpec {
    /// `"gaussians"`: one particle per selected Gaussian, plus the fill.
    Each(ParticlesPerGaussian),
    /// `{"spacing": h, "jitter": j}`: particles on a lattice over the solid.
    Lattice(LatticeOptions),
}

/// The one word of [`ParticlesSpec::Each`].
#[derive(Clone, Copy, Debug, Serialize, Deserialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum ParticlesPerGaussian {
    Gaussians,
}

#[derive(Clone, Debug, Default, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LatticeOptions {
    /// Lattice spacing h, in [Δx/16, Δx]: one particle per h³ of the solid. Default Δx/2.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spacing: Option<f64>,
    /// Each particle is moved off its voxel's centre by up to ±jitter·h/2 per axis (a
    /// regular lattice prints its planes into cracks), in [0, 1]. Default 0.5.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub jitter: Option<f64>,
}

impl Default for ParticlesSpec {
    fn default() -> Self {
        ParticlesSpec::Lattice(LatticeOptions::default())
    }
}

impl<'de> Deserialize<'de> for ParticlesSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        match serde_json::Value::deserialize(d)? {
            serde_json::Value::String(s) if s == "gaussians" => {
                Ok(ParticlesSpec::Each(ParticlesPerGaussian::Gaussians))
            }
            v @ serde_json::Value::Object(_) => serde_json::from_value::<LatticeOptions>(v)
                .map(ParticlesSpec::Lattice)
                .map_err(|e| D::Error::custom(format!("physics.particles: {e}"))),
            other => Err(D::Error::custom(format!(
                "physics.particles: expected \"gaussians\" or {{\"spacing\": h}}, got {other}"
            ))),
        }
    }
}

impl ParticlesSpec {
    /// The lattice's spacing and jitter for grid spacing `dx`, or None for one particle per
    /// Gaussian.
    pub(super) fn lattice(&self, dx: f64) -> Option<(f64, f64)> {
        match self {
            ParticlesSpec::Each(_) => None,
            ParticlesSpec::Lattice(o) => {
                Some((o.spacing.unwrap_or(0.5 * dx), o.jitter.unwrap_or(0.5)))
            }
        }
    }
}

/// `physics.fill`: `true` / `false`, or options.
#[derive(Clone, Debug, Serialize, JsonSchema, PartialEq)]
#[serde(untagged)]
pub enum FillSpec {
    /// `true`: fill at spacing Δx/2 (8 particles per cell); `false`: no filling.
    Enabled(bool),
    Options(FillOptions),
}

#[derive(Clone, Debug, Default, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FillOptions {
    /// Particle spacing h of the fill, in [Δx/16, Δx]. Default Δx/2.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spacing: Option<f64>,
    /// How a capture's inside is found: `parity` (ray crossings; closed surfaces) or
    /// `closing` (the surface closed morphologically; open captures). Procedural objects
    /// use their exact inside test whatever this says. Default `parity`.
    #[serde(default)]
    pub mode: FillMode,
    /// `closing` only: the widest opening to bridge is about twice this (scene units).
    /// Default 3 fill spacings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub closing_radius: Option<f64>,
}

/// `physics.fill.mode`.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum FillMode {
    #[default]
    Parity,
    Closing,
}

impl<'de> Deserialize<'de> for FillSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        match serde_json::Value::deserialize(d)? {
            serde_json::Value::Bool(b) => Ok(FillSpec::Enabled(b)),
            v @ serde_json::Value::Object(_) => serde_json::from_value::<FillOptions>(v)
                .map(FillSpec::Options)
                .map_err(|e| D::Error::custom(format!("physics.fill: {e}"))),
            other => Err(D::Error::custom(format!(
                "physics.fill: expected true, false or {{\"spacing\": h}}, got {other}"
            ))),
        }
    }
}

impl FillSpec {
    /// The fill spacing for grid spacing `dx`, or None when filling is off.
    pub(super) fn spacing(&self, dx: f64) -> Option<f64> {
        match self {
            FillSpec::Enabled(false) => None,
            FillSpec::Enabled(true) => Some(0.5 * dx),
            FillSpec::Options(o) => Some(o.spacing.unwrap_or(0.5 * dx)),
        }
    }

    /// The inside test's mode and, for `closing`, its radius in scene units (for spacing h).
    pub(super) fn mode(&self, h: f64) -> (FillMode, f64) {
        match self {
            FillSpec::Options(o) => (o.mode, o.closing_radius.unwrap_or(3.0 * h)),
            FillSpec::Enabled(_) => (FillMode::Parity, 3.0 * h),
        }
    }
}

impl ConditionSpec {
    pub(super) fn build(&self, origin: &str, field: &str) -> Result<Condition, SceneError> {
        if !(self.friction.is_finite() && self.friction >= 0.0) {
            return Err(SceneError::invalid(
                origin,
                format!("{field}.friction"),
                self.friction,
                "a friction coefficient ≥ 0",
            ));
        }
        let kind = match self.kind {
            ConditionKind::Sticky => BoundaryKind::Sticky,
            ConditionKind::Slip => BoundaryKind::Slip,
            ConditionKind::Separate => BoundaryKind::Separate,
        };
        Ok(Condition {
            kind,
            friction: self.friction,
        })
    }
}

/// One entry of `physics.regions`: exactly one selector (`shell`, `box`, `sphere`,
/// `label`), a `material` and an optional interior `color`.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RegionSpec {
    /// A name for messages. Default `regions[<index>]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Particles whose depth below the object's surface lies in [from, to).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shell: Option<ShellRange>,
    /// Particles in the world box lo ≤ x ≤ hi (at the start of the simulation).
    #[serde(rename = "box", default, skip_serializing_if = "Option::is_none")]
    pub box_region: Option<BoxRegion>,
    /// Particles in the world ball |x − center| ≤ radius.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sphere: Option<SphereRegion>,
    /// Gaussians carrying this label (fill particles take their nearest Gaussian's label).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub label: Option<String>,
    /// Particles near the faces of a Voronoi partition of the object into `cells` cells:
    /// given a weaker material, the faces become the cracks of an art-directed fracture.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub voronoi: Option<VoronoiFaces>,
    /// The region's material (NACC, fixed corotated or Neo-Hookean).
    pub material: MaterialSpec,
    /// Colour (linear RGB in [0, 1]) of the region's fill particles. Default: the colour of
    /// the nearest Gaussian, as without regions.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub color: Option<[f32; 3]>,
}

/// Depths below the surface, in world units: from ≤ depth < to.
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ShellRange {
    /// Default 0 (the surface).
    #[serde(default)]
    pub from: f64,
    pub to: f64,
}

#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BoxRegion {
    pub lo: [f64; 3],
    pub hi: [f64; 3],
}

/// The faces of a Voronoi partition of an object's particles (at rest).
#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct VoronoiFaces {
    /// Number of cells N (2 to 256): the pieces a fracture along every face would give.
    pub cells: u32,
    /// Half-thickness of a face in world units (> 0): particles within this distance of
    /// the plane between their nearest cell centre and another are selected.
    pub width: f64,
    /// Seed of the cell centres (default 0): the same seed, the same partition.
    #[serde(default)]
    pub seed: u64,
}

#[derive(Clone, Debug, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SphereRegion {
    pub center: [f64; 3],
    pub radius: f64,
}

/// A scene file's `[x, y, z]`.
pub(super) fn vec3(v: [f64; 3]) -> DVec3 {
    DVec3::from_array(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `transfer` reads and writes back as written, and its values become the step's.
    #[test]
    fn transfer_round_trips_and_builds() {
        for (text, want) in [
            (r#""apic""#, Transfer::Apic),
            (r#"{"flip":0.7}"#, Transfer::FlipPic { flip: 0.7 }),
            (r#"{"flip":0.0}"#, Transfer::FlipPic { flip: 0.0 }),
        ] {
            let spec: TransferSpec = serde_json::from_str(text).unwrap();
            assert_eq!(serde_json::to_string(&spec).unwrap(), text);
            assert_eq!(spec.build("t.json").unwrap(), want);
        }
        for bad in [r#""pic""#, r#"{"flip":0.7,"k":1}"#, "0.7"] {
            assert!(serde_json::from_str::<TransferSpec>(bad).is_err(), "{bad}");
        }
        let over: TransferSpec = serde_json::from_str(r#"{"flip":1.5}"#).unwrap();
        assert!(over.build("t.json").is_err());
    }

    /// `separation` reads and writes back by name, and becomes the step's.
    #[test]
    fn separation_round_trips_and_builds() {
        for (text, want) in [
            (r#""none""#, Separation::None),
            (r#""damage_gradient""#, Separation::DamageGradient),
        ] {
            let spec: SeparationSpec = serde_json::from_str(text).unwrap();
            assert_eq!(serde_json::to_string(&spec).unwrap(), text);
            assert_eq!(Separation::from(spec), want);
        }
        assert!(serde_json::from_str::<SeparationSpec>(r#""dfg""#).is_err());
    }
}
