//! The scene file's simulation: the `simulation` block (grid, step, gravity, boundaries) and
//! each object's `physics` (material, initial velocity), turned into what the MPM step
//! needs (docs/method.md §1–§5). The selected Gaussians of a simulated object
//! (`physics.select`, `physics.min_opacity`; default all) move, the rest of it stays static.
//! What moves them is `physics.particles`: a lattice over the object's solid, each Gaussian
//! bound to its nearest particle (`derive::binding`; the default), or one particle per
//! Gaussian. `physics.fill` adds the interior (`scene::fill`): particles beside the
//! Gaussians in the second mode, Gaussians for the look in the first.

use glam::DVec3;

use std::ops::Range;

mod bodies;
mod domain;
mod interior;

use bodies::Bodies;
use domain::*;
use interior::*;

use super::physics::{vec3, SelectSpec, SimulationSpec};
use super::regions::{ObjectRegions, ParticleKey};
use super::{BuildReport, Scene, SceneError};
use crate::derive::Binding;
use crate::render::Splats;
use crate::sim::time_step::{StepPlan, StepRule};
use crate::sim::{
    cfl_dt, Actions, Boundaries, DomainWalls, Grid, Material, Particles, PlaneCollider, StepParams,
};

/// Everything the simulate-and-render loop needs.
pub struct SimulationSetup {
    /// All Gaussians, static objects first, then the simulated ones in particle order.
    pub splats: Splats,
    /// Index of the first simulated Gaussian.
    pub static_count: usize,
    /// Where each object's Gaussians are in `splats`: contiguous runs, static ones first
    /// (file order), then per simulated object its selected Gaussians and its fill. An
    /// object with a `select` or `min_opacity` has a static and a simulated run.
    pub parts: Vec<SplatPart>,
    /// Which particle moves each simulated Gaussian (`splats[static_count..]`, in order) and
    /// its rest offset from it.
    pub binding: Binding,
    /// Each simulated object's particles and Gaussians.
    pub bodies: Vec<Body>,
    pub particles: Particles,
    pub grid: Grid,
    pub materials: Vec<Material>,
    pub params: StepParams,
    /// Steps of the first frame: ⌈(1/fps) / Δt⌉ (Δt shrunk to divide the frame exactly);
    /// `params.dt` is that frame's Δt. Later frames may take others ([`Self::step_rule`]).
    pub steps_per_frame: u32,
    /// How each frame's Δt is chosen: the CFL bound (or the scene's `dt`) and, without a
    /// `dt`, the bound on the fastest particle's cells a step.
    pub step_rule: StepRule,
    /// Objects on a prescribed path: moving colliders, rendered moving rigidly (their
    /// Gaussians are in the static runs of `parts`).
    pub kinematic: Vec<super::kinematic::KinematicObject>,
    /// Messages for the user (a Δt above the CFL bound, …).
    pub warnings: Vec<String>,
}

impl SimulationSetup {
    /// Region labels of a part's Gaussians (in order; `None` for an unlabelled one), e.g.
    /// `flesh`/`rind`/`seeds` for a procedural watermelon or `"3"` for a PLY `label` 3.
    /// Fill particles carry their region (procedural assets) or their nearest Gaussian's.
    pub fn part_labels<'a>(&'a self, part: &SplatPart) -> impl Iterator<Item = Option<&'a str>> {
        (part.start..part.start + part.len).map(|g| self.splats.label_name(g))
    }
}

/// One simulated object: its particles (a run of [`SimulationSetup::particles`]) and its
/// Gaussians (a run of [`SimulationSetup::splats`], selected ones then fill).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Body {
    /// Index in `scene.objects`.
    pub object: usize,
    pub particles: Range<usize>,
    pub gaussians: Range<usize>,
}

/// A run of one object's Gaussians in [`SimulationSetup::splats`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SplatPart {
    /// Index in `scene.objects`.
    pub object: usize,
    pub start: usize,
    pub len: usize,
    pub kind: PartKind,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PartKind {
    /// Rendered as loaded (static objects, unselected Gaussians of simulated ones).
    Static,
    /// Selected Gaussians of a simulated object.
    Simulated,
    /// Interior fill of a simulated object (isotropic Gaussians).
    Fill,
}

/// Turn `splats` (as built by [`Scene::build_splats`], objects in file order with the
/// counts of `report`) into a simulation, or `None` when the scene simulates nothing.
// Over 80 lines on purpose: the setup's phases over shared state in their order: moving parts,
// bodies, grid, step rule.
pub fn prepare(
    scene: &Scene,
    splats: Splats,
    report: &BuildReport,
) -> Result<Option<SimulationSetup>, SceneError> {
    let o = scene.origin.as_str();
    let simulated: Vec<usize> = (0..scene.objects.len())
        .filter(|&i| scene.objects[i].physics.is_some())
        .collect();
    let Some(spec) = &scene.simulation else {
        let collider = scene
            .objects
            .iter()
            .position(|obj| obj.collider.is_some())
            .map(|i| (i, "collider"));
        if let Some((i, field)) = simulated.first().map(|&i| (i, "physics")).or(collider) {
            return Err(SceneError::invalid(
                o,
                format!("objects[{i}].{field}"),
                "set",
                "a `simulation` block in the scene",
            ));
        }
        return Ok(None);
    };
    if simulated.is_empty() {
        return Ok(None);
    }
    let grid = grid_of(spec, o)?;
    let mut boundaries = boundaries_of(spec, o)?;
    let ranges = object_ranges(report);
    let kinematic = super::kinematic::build(scene, &splats, |i| ranges[i].clone())?;
    let moving = select_moving(scene, &splats, &ranges, &simulated)?;

    // Static first: whole static objects and what simulated objects leave static, in file
    // order; then per simulated object its selected Gaussians and its fill.
    let mut out = Parts::new(splats.sh_degree);
    let mut surface = Parts::new(splats.sh_degree);
    for (i, range) in ranges.iter().enumerate() {
        let part = match &moving[i] {
            None => subset(&splats, range.clone()),
            Some(picked) => {
                let mut keep = vec![true; range.len()];
                for &g in picked {
                    keep[g - range.start] = false;
                }
                let rest: Vec<usize> = range.clone().filter(|g| keep[g - range.start]).collect();
                gather(&splats, &rest)
            }
        };
        if scene.objects[i].collider.is_some() {
            surface.push(part.clone(), i, PartKind::Static);
        }
        out.push(part, i, PartKind::Static);
    }
    boundaries.surface = surface_of(scene, &surface.splats, &grid)?;
    let static_count = out.splats.len();
    let mut body = Bodies::default();
    for &i in &simulated {
        let picked = moving[i].as_deref().expect("simulated");
        body.add(scene, i, gather(&splats, picked), &grid, spec, &mut out)?;
    }
    let speed = body.particles.max_speed();
    let (step_rule, first) = time_step(scene, spec, body.dt_cfl, speed, &mut body.warnings)?;
    let (dt, steps_per_frame) = (first.dt, first.steps);
    let params = StepParams {
        dt,
        gravity: vec3(spec.gravity),
        boundaries,
        transfer: spec.transfer.build(o)?,
        separation: spec.separation.into(),
        fields: super::physics::build_fields(&spec.fields, o)?,
        actions: Actions {
            members: match body.actions.is_empty() {
                true => Default::default(),
                false => body.members.into(),
            },
            list: body.actions,
        },
    };
    Ok(Some(SimulationSetup {
        splats: out.splats,
        static_count,
        parts: out.parts,
        binding: body.binding,
        bodies: body.bodies,
        particles: body.particles,
        grid,
        materials: body.materials,
        params,
        steps_per_frame,
        step_rule,
        kinematic,
        warnings: body.warnings,
    }))
}

/// Each object's run in the built Gaussians (file order).
fn object_ranges(report: &BuildReport) -> Vec<Range<usize>> {
    let mut acc = 0;
    report
        .objects
        .iter()
        .map(|r| {
            acc += r.gaussians;
            acc - r.gaussians..acc
        })
        .collect()
}

/// Which Gaussians of each simulated object move (`physics.select`, `min_opacity`), as
/// indices into `splats`; `None` for objects that do not simulate.
fn select_moving(
    scene: &Scene,
    splats: &Splats,
    ranges: &[Range<usize>],
    simulated: &[usize],
) -> Result<Vec<Option<Vec<usize>>>, SceneError> {
    let o = scene.origin.as_str();
    let mut moving: Vec<Option<Vec<usize>>> = vec![None; scene.objects.len()];
    for &i in simulated {
        let physics = scene.objects[i].physics.as_ref().expect("simulated");
        if let Some(sel) = &physics.select {
            sel.validate(o, &format!("objects[{i}].physics.select"))?;
            check_labels(o, i, sel, splats, &ranges[i])?;
        }
        let min_opacity = physics.min_opacity;
        if !(min_opacity.is_finite() && (0.0..=1.0).contains(&min_opacity)) {
            return Err(SceneError::invalid(
                o,
                format!("objects[{i}].physics.min_opacity"),
                min_opacity,
                "an opacity in [0, 1]",
            ));
        }
        let picked: Vec<usize> = ranges[i]
            .clone()
            .filter(|&g| {
                f64::from(splats.opacities[g]) >= min_opacity
                    && physics
                        .select
                        .as_ref()
                        .is_none_or(|s| s.picks(splats.means[g].as_dvec3(), label_of(splats, g)))
            })
            .collect();
        if picked.is_empty() && !ranges[i].is_empty() {
            let field = if physics.select.is_some() {
                "select"
            } else {
                "min_opacity"
            };
            return Err(SceneError::invalid(
                o,
                format!("objects[{i}].physics.{field}"),
                format!("a selection of none of the object's {} Gaussians", ranges[i].len()),
                "at least one Gaussian to simulate (check the region against the object's transform)",
            ));
        }
        moving[i] = Some(picked);
    }
    Ok(moving)
}

/// The label Gaussian `g` carries, if any.
fn label_of(splats: &Splats, g: usize) -> Option<&str> {
    let l = *splats.labels.get(g)?;
    splats.label_names.get(usize::from(l)).map(String::as_str)
}

/// A label selection names only labels that object `i`'s Gaussians (`range`) carry.
fn check_labels(
    o: &str,
    i: usize,
    select: &SelectSpec,
    splats: &Splats,
    range: &Range<usize>,
) -> Result<(), SceneError> {
    let SelectSpec::Label(names) = select else {
        return Ok(());
    };
    let mut present: Vec<&str> = range.clone().filter_map(|g| label_of(splats, g)).collect();
    present.sort_unstable();
    present.dedup();
    match names.iter().find(|n| !present.contains(&n.text().as_str())) {
        None => Ok(()),
        Some(missing) => Err(SceneError::invalid(
            o,
            format!("objects[{i}].physics.select.label"),
            format!("{:?}", missing.text()),
            if present.is_empty() {
                "a label of the object's Gaussians (this object has none: a capture's come from an integer vertex property `label` or `segment`, an asset's are its regions)".to_string()
            } else {
                format!("one of the object's labels: {}", present.join(", "))
            },
        )),
    }
}

/// The Gaussians of a simulation in order, and the runs they form.
struct Parts {
    splats: Splats,
    parts: Vec<SplatPart>,
}

impl Parts {
    fn new(sh_degree: u32) -> Parts {
        Parts {
            splats: Splats {
                sh_degree,
                ..Default::default()
            },
            parts: Vec::new(),
        }
    }

    fn push(&mut self, part: Splats, object: usize, kind: PartKind) {
        if !part.is_empty() {
            self.parts.push(SplatPart {
                object,
                start: self.splats.len(),
                len: part.len(),
                kind,
            });
            self.splats.append(part);
        }
    }
}

/// An object's particles before they become [`Particles`]: positions, rest volumes, and
/// what their regions are judged by.
struct ParticleCloud {
    x: Vec<DVec3>,
    volume: Vec<f64>,
    /// Each particle's label (empty: none carry one).
    labels: Vec<u16>,
    /// The Gaussian (of the object's selected ones) whose distance is a particle's depth
    /// below a capture's surface; None for a particle that is a Gaussian (depth 0).
    donor: Vec<Option<u32>>,
}

impl ParticleCloud {
    /// One particle per selected Gaussian, then one per fill point.
    fn of_gaussians(
        obj: &super::ObjectSpec,
        part: &Splats,
        filled: Option<&super::fill::Fill>,
        fill_splats: &Splats,
    ) -> ParticleCloud {
        let mut x: Vec<DVec3> = part.means.iter().map(|m| m.as_dvec3()).collect();
        let mut donor = vec![None; part.len()];
        let volume = match filled {
            None => vec![particle_volume(obj, part); part.len()],
            Some(f) => {
                x.extend(f.points.iter().copied());
                donor.extend(f.nearest.iter().map(|&d| Some(d)));
                f.volumes
                    .iter()
                    .copied()
                    .chain(std::iter::repeat_n(f.point_volume, f.points.len()))
                    .collect()
            }
        };
        let labels = if part.labels.is_empty() {
            Vec::new()
        } else {
            part.labels
                .iter()
                .chain(&fill_splats.labels)
                .copied()
                .collect()
        };
        ParticleCloud {
            x,
            volume,
            labels,
            donor,
        }
    }

    /// The lattice `l` over the object: volume h³ each, the label of the asset's region
    /// there or of the nearest Gaussian.
    fn of_lattice(
        obj: &super::ObjectSpec,
        part: &Splats,
        l: &super::fill::Fill,
        scene: &Scene,
        i: usize,
    ) -> Result<ParticleCloud, SceneError> {
        if l.points.is_empty() {
            return Err(SceneError::invalid(
                scene.origin.as_str(),
                format!("objects[{i}].physics.particles.spacing"),
                l.point_volume.cbrt(),
                "a spacing that puts particles in the object (none landed in its solid)",
            ));
        }
        let labels = paint_asset_fill(obj, fill_gaussians(part, l)).labels;
        Ok(ParticleCloud {
            x: l.points.clone(),
            volume: vec![l.point_volume; l.points.len()],
            labels,
            donor: l.nearest.iter().map(|&d| Some(d)).collect(),
        })
    }
}

/// How each frame's Δt is chosen (given, or the CFL bound and the particles' speed), and
/// the first frame's steps, for particles that start at most at `speed`.
fn time_step(
    scene: &Scene,
    spec: &SimulationSpec,
    dt_cfl: f64,
    speed: f64,
    warnings: &mut Vec<String>,
) -> Result<(StepRule, StepPlan), SceneError> {
    let o = scene.origin.as_str();
    let frame = 1.0 / f64::from(scene.output.fps);
    let dt = match spec.dt {
        Some(dt) if dt.is_finite() && dt > 0.0 => {
            if dt > dt_cfl {
                warnings.push(format!(
                    "simulation.dt = {dt:e} exceeds the CFL bound {dt_cfl:.3e} (cfl {}, Δx {}): expect instability; suggested dt ≤ {dt_cfl:.3e}",
                    spec.cfl, spec.dx
                ));
            }
            dt
        }
        Some(dt) => {
            return Err(SceneError::invalid(
                o,
                "simulation.dt",
                dt,
                "a step > 0 in seconds",
            ))
        }
        None => dt_cfl,
    };
    if (frame / dt).ceil() > 1e7 {
        return Err(SceneError::invalid(
            o,
            "simulation.dt",
            dt,
            "a step giving at most 10⁷ steps per frame",
        ));
    }
    let c = spec
        .cfl_velocity
        .unwrap_or(crate::scene::physics::DEFAULT_CFL_VELOCITY);
    if spec.dt.is_some() && spec.cfl_velocity.is_some() {
        warnings.push(
            "simulation.cfl_velocity is ignored: simulation.dt fixes the step for the whole run"
                .to_string(),
        );
    }
    if !(c.is_finite() && c > 0.0 && c <= 1.0) {
        return Err(SceneError::invalid(
            o,
            "simulation.cfl_velocity",
            c,
            "a fraction of a cell in (0, 1]",
        ));
    }
    let rule = StepRule {
        frame,
        dt_max: dt,
        cfl_velocity: spec.dt.is_none().then_some(c),
        dx: spec.dx,
        gravity: vec3(spec.gravity).length(),
    };
    let first = rule.frame_steps(speed).map_err(|e| {
        SceneError::invalid(
            o,
            "objects[].physics.velocity",
            format!("{:.4e} m/s", e.speed),
            format!(
                "a start speed that a step of at least 1/{} of the CFL bound follows (at most about {:.4e} m/s)",
                crate::sim::time_step::MAX_SHRINK,
                c * spec.dx * crate::sim::time_step::MAX_SHRINK / dt
            ),
        )
    })?;
    Ok((rule, first))
}

/// Each particle's region (None: the object's own material). Depth below the surface: for
/// a procedural object from its exact solid (object depth × the transform's mean scale
/// |det M|^(1/3), exact for uniform scales); for a PLY, a Gaussian is on the surface
/// (depth 0) and any other particle is as deep as the distance to its donor Gaussian.
fn assign_regions(
    obj: &super::ObjectSpec,
    regions: &ObjectRegions,
    cloud: &ParticleCloud,
    part: &Splats,
) -> Vec<Option<usize>> {
    let xs = &cloud.x;
    if regions.is_empty() {
        return vec![None; xs.len()];
    }
    let (m, t) = obj.transform.affine();
    let (m, t) = (m.as_dmat3(), t.as_dvec3());
    let m_inv = m.inverse();
    let scale = m.determinant().abs().cbrt();
    let depth = |p: usize| -> f64 {
        if !regions.needs_depth() {
            return 0.0;
        }
        if let Some(spec) = &obj.procedural {
            return spec.depth((m_inv * (xs[p] - t)).to_array()) * scale;
        }
        cloud.donor[p].map_or(0.0, |d| xs[p].distance(part.means[d as usize].as_dvec3()))
    };
    (0..xs.len())
        .map(|p| {
            regions.region_of(&ParticleKey {
                x: xs[p],
                depth: depth(p),
                label: cloud
                    .labels
                    .get(p)
                    .copied()
                    .filter(|&l| l != crate::splat::NO_LABEL),
            })
        })
        .collect()
}

/// The labels `part`'s Gaussians carry, as (name, id) in id order.
fn object_labels(part: &Splats) -> Vec<(String, u16)> {
    let mut seen = vec![false; part.label_names.len()];
    for &l in &part.labels {
        if let Some(s) = seen.get_mut(usize::from(l)) {
            *s = true;
        }
    }
    (0..seen.len())
        .filter(|&l| seen[l])
        .map(|l| (part.label_names[l].clone(), l as u16))
        .collect()
}

/// Fill particles of a region with a `color` take it (DC only, as every fill Gaussian).
fn recolour_fill(fill: &mut Splats, region: &[Option<usize>], regions: &ObjectRegions) {
    let k = fill.sh_stride();
    for (j, r) in region.iter().enumerate() {
        if let Some(dc) = r.and_then(|r| regions.fill_dc[r]) {
            fill.sh[j * k..j * k + 3].copy_from_slice(&dc);
        }
    }
}

/// Rest volume per particle without `fill`: a procedural object's lattice cell (spacing³);
/// for a PLY, the selection's bounding-box volume shared equally (a stand-in: with `fill`
/// the volumes come from the voxelisation instead, `scene::fill`).
fn particle_volume(obj: &super::ObjectSpec, part: &Splats) -> f64 {
    let (m, _) = obj.transform.affine();
    let scale = f64::from(m.determinant().abs());
    if let Some(p) = &obj.procedural {
        return f64::from(p.spacing).powi(3) * scale;
    }
    let lo = part
        .means
        .iter()
        .fold(DVec3::INFINITY, |a, m| a.min(m.as_dvec3()));
    let hi = part
        .means
        .iter()
        .fold(DVec3::NEG_INFINITY, |a, m| a.max(m.as_dvec3()));
    ((hi - lo).max(DVec3::splat(1e-6)).element_product() / part.len().max(1) as f64).max(1e-12)
}

fn subset(s: &Splats, r: std::ops::Range<usize>) -> Splats {
    let k = s.sh_stride();
    Splats {
        means: s.means[r.clone()].to_vec(),
        covariances: s.covariances[r.clone()].to_vec(),
        rotations: s.rotations[r.clone()].to_vec(),
        opacities: s.opacities[r.clone()].to_vec(),
        sh_degree: s.sh_degree,
        sh: s.sh[r.start * k..r.end * k].to_vec(),
        labels: s.labels.get(r).map(<[u16]>::to_vec).unwrap_or_default(),
        label_names: s.label_names.clone(),
    }
}

/// The Gaussians at `idx`, in that order.
fn gather(s: &Splats, idx: &[usize]) -> Splats {
    let k = s.sh_stride();
    let mut sh = Vec::with_capacity(idx.len() * k);
    for &i in idx {
        sh.extend_from_slice(&s.sh[i * k..(i + 1) * k]);
    }
    Splats {
        means: idx.iter().map(|&i| s.means[i]).collect(),
        covariances: idx.iter().map(|&i| s.covariances[i]).collect(),
        rotations: idx.iter().map(|&i| s.rotations[i]).collect(),
        opacities: idx.iter().map(|&i| s.opacities[i]).collect(),
        sh_degree: s.sh_degree,
        sh,
        labels: if s.labels.is_empty() {
            Vec::new()
        } else {
            idx.iter().map(|&i| s.labels[i]).collect()
        },
        label_names: s.label_names.clone(),
    }
}
