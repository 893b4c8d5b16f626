//! `objects[i].physics.actions`: timed impulses, holds and drives on regions of a simulated
//! object (`sim::actions`, docs/method.md §2.6): the checks of the scene file's form
//! (`scene::physics::ActionSpec`) and the particles each action takes (its region, tested
//! once on the object's particles at rest).

use glam::{DVec3, Vec3};

use super::physics::{finite3, require, ActionSpec, PathKey, SelectSpec};
use super::SceneError;
use crate::sim::actions::{Action, ActionKind, Drive, Path, MAX_ACTIONS};

/// An action checked but not yet sized: a force still waits for its region's mass.
#[derive(Clone, Debug)]
pub(super) struct Draft {
    kind: DraftKind,
    from: f64,
    to: f64,
    region: Option<SelectSpec>,
    field: String,
}

/// What a draft does: an action ready as it is, or an impulse given as a force (N), whose
/// acceleration waits for the region's mass.
#[derive(Clone, Debug)]
enum DraftKind {
    Ready(ActionKind),
    Force(DVec3),
}

/// Object `i`'s actions (`specs`), checked; `before` actions of earlier objects already
/// hold bits of the scene's [`MAX_ACTIONS`].
pub(super) fn check(
    origin: &str,
    i: usize,
    specs: &[ActionSpec],
    before: usize,
) -> Result<Vec<Draft>, SceneError> {
    let base = format!("objects[{i}].physics.actions");
    require(
        before + specs.len() <= MAX_ACTIONS,
        origin,
        base.clone(),
        format!("{} actions in the scene", before + specs.len()),
        &format!("at most {MAX_ACTIONS} actions over all simulated objects"),
    )?;
    specs
        .iter()
        .enumerate()
        .map(|(k, spec)| spec.check(origin, &format!("{base}[{k}]")))
        .collect()
}

impl ActionSpec {
    fn check(&self, origin: &str, field: &str) -> Result<Draft, SceneError> {
        let given: Vec<&str> = [
            ("impulse", self.impulse.is_some()),
            ("hold", self.hold.is_some()),
            ("drive", self.drive.is_some()),
        ]
        .iter()
        .filter(|(_, set)| *set)
        .map(|(name, _)| *name)
        .collect();
        require(
            given.len() == 1,
            origin,
            field.to_string(),
            if given.is_empty() {
                "no action".to_string()
            } else {
                given.join(" and ")
            },
            "exactly one of `impulse`, `hold` or `drive`",
        )?;
        let to = self.to.unwrap_or(f64::INFINITY);
        require(
            self.from.is_finite() && self.from >= 0.0,
            origin,
            format!("{field}.from"),
            self.from,
            "a start time in seconds ≥ 0",
        )?;
        require(
            !to.is_nan() && to > self.from,
            origin,
            format!("{field}.to"),
            to,
            &format!("an end time in seconds after `from` ({})", self.from),
        )?;
        if let Some(r) = &self.region {
            r.validate(origin, &format!("{field}.region"))?;
        }
        let kind = self.kind(origin, field)?;
        Ok(Draft {
            kind,
            from: self.from,
            to,
            region: self.region.clone(),
            field: field.to_string(),
        })
    }

    /// What the action does (an impulse given as a force waits for its region's mass).
    fn kind(&self, origin: &str, field: &str) -> Result<DraftKind, SceneError> {
        use DraftKind::{Force, Ready};
        if let Some(imp) = &self.impulse {
            let at = format!("{field}.impulse");
            return match (imp.acceleration, imp.force) {
                (Some(a), None) => {
                    finite3(origin, &format!("{at}.acceleration"), a)?;
                    let acceleration = DVec3::from(a);
                    Ok(Ready(ActionKind::Impulse { acceleration }))
                }
                (None, Some(f)) => {
                    finite3(origin, &format!("{at}.force"), f)?;
                    Ok(Force(DVec3::from(f)))
                }
                _ => Err(SceneError::invalid(
                    origin,
                    at,
                    "both or neither of acceleration and force",
                    "exactly one of `acceleration` (m/s²) or `force` (N)",
                )),
            };
        }
        let Some(drive) = &self.drive else {
            return Ok(Ready(ActionKind::Hold));
        };
        let at = format!("{field}.drive");
        let drive = match (&drive.velocity, &drive.path) {
            (Some(u), None) => {
                finite3(origin, &format!("{at}.velocity"), *u)?;
                Drive::Velocity(DVec3::from(*u))
            }
            (None, Some(keys)) => Drive::Path(path(origin, &at, keys)?),
            _ => {
                return Err(SceneError::invalid(
                    origin,
                    at,
                    "both or neither of velocity and path",
                    "exactly one of `velocity` (m/s) or `path` (keyframes)",
                ))
            }
        };
        Ok(Ready(ActionKind::Drive(drive)))
    }
}

/// A drive's keyframes as a path: at least one, finite, times strictly increasing.
fn path(origin: &str, at: &str, keys: &[PathKey]) -> Result<Path, SceneError> {
    require(
        !keys.is_empty(),
        origin,
        format!("{at}.path"),
        "no keyframes",
        "at least one keyframe {\"time\": t, \"position\": [x, y, z]}",
    )?;
    for (j, k) in keys.iter().enumerate() {
        let ok = k.time.is_finite() && k.position.iter().all(|v| v.is_finite());
        require(
            ok,
            origin,
            format!("{at}.path[{j}]"),
            format!("time {} position {:?}", k.time, k.position),
            "a finite time and position",
        )?;
        if j > 0 {
            require(
                k.time > keys[j - 1].time,
                origin,
                format!("{at}.path[{j}].time"),
                k.time,
                &format!("a time after the keyframe before ({})", keys[j - 1].time),
            )?;
        }
    }
    Ok(Path::new(
        keys.iter().map(|k| k.time).collect(),
        keys.iter().map(|k| Vec3::from(k.position)).collect(),
    ))
}

impl Draft {
    /// The action's bit set on the particles of its region, among the object's particles
    /// at rest (`xs`, with their labels); a force becomes the acceleration F / M of the
    /// region's mass (`mass`). An empty region is refused, naming what the object has.
    pub(super) fn take(
        self,
        origin: &str,
        bit: usize,
        (xs, labels, mass): (&[DVec3], &[Option<&str>], &[f64]),
        members: &mut [u32],
    ) -> Result<Action, SceneError> {
        let mut region_mass = 0.0;
        for p in 0..xs.len() {
            let inside = self
                .region
                .as_ref()
                .is_none_or(|r| r.picks(xs[p], labels[p]));
            if inside {
                members[p] |= 1 << bit;
                region_mass += mass[p];
            }
        }
        if region_mass == 0.0 {
            return Err(self.empty(origin, xs, labels));
        }
        let kind = match self.kind {
            DraftKind::Force(f) => ActionKind::Impulse {
                acceleration: f / region_mass,
            },
            DraftKind::Ready(kind) => kind,
        };
        Ok(Action {
            kind,
            from: self.from,
            to: self.to,
        })
    }

    /// The error for a region that takes none of the object's particles: for labels, the
    /// labels the particles carry; for a box or a ball, the particles' bounds.
    fn empty(&self, origin: &str, xs: &[DVec3], labels: &[Option<&str>]) -> SceneError {
        let field = format!("{}.region", self.field);
        if let Some(SelectSpec::Label(names)) = &self.region {
            let mut present: Vec<&str> = labels.iter().flatten().copied().collect();
            present.sort_unstable();
            present.dedup();
            let asked: Vec<String> = names.iter().map(|n| n.text()).collect();
            return SceneError::invalid(
                origin,
                format!("{field}.label"),
                format!("{asked:?}"),
                if present.is_empty() {
                    "a label of the object's particles (this object has none: a capture's come from an integer vertex property `label` or `segment`, an asset's are its regions)".to_string()
                } else {
                    format!(
                        "labels the object's particles carry: {}",
                        present.join(", ")
                    )
                },
            );
        }
        let lo = xs.iter().copied().fold(DVec3::INFINITY, DVec3::min);
        let hi = xs.iter().copied().fold(DVec3::NEG_INFINITY, DVec3::max);
        SceneError::invalid(
            origin,
            field,
            "a region with none of the object's particles",
            format!("a region that takes some of them (they lie in {lo} .. {hi} at rest)"),
        )
    }
}
