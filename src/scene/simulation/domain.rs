//! The simulation's domain from the scene file: its grid, the boundaries of its faces and
//! planar colliders, and the captured surface some objects lend as a collider.

use super::*;

/// The captured-surface collider of the objects that declare `collider` (their static
/// Gaussians `splats`), None when none does. They share one condition.
pub(super) fn surface_of(
    scene: &Scene,
    splats: &Splats,
    grid: &Grid,
) -> Result<Option<crate::sim::boundary::SurfaceCollider>, SceneError> {
    let o = scene.origin.as_str();
    let mut condition = None;
    for (i, obj) in scene.objects.iter().enumerate() {
        let Some(spec) = &obj.collider else { continue };
        let c = spec.build(o, &format!("objects[{i}].collider"))?;
        match condition {
            Some((_, first)) if first != c => {
                return Err(SceneError::invalid(
                    o,
                    format!("objects[{i}].collider"),
                    format!("{:?} with friction {}", c.kind, c.friction),
                    "the same condition as every other collider object (they form one surface)",
                ))
            }
            _ => condition = Some((i, c)),
        }
    }
    let Some((i, condition)) = condition else {
        return Ok(None);
    };
    if splats.is_empty() {
        return Err(SceneError::invalid(
            o,
            format!("objects[{i}].collider"),
            "set",
            "an object with static Gaussians to stand for the surface (a simulated object's collider is its unselected part)",
        ));
    }
    Ok(Some(crate::scene::surface::build(splats, grid, condition)))
}

/// The grid over `simulation.domain` at `simulation.dx`, validated; it reaches past the
/// domain by the walls' padding ([`SimulationSpec::grid_box`]).
pub(super) fn grid_of(spec: &SimulationSpec, o: &str) -> Result<Grid, SceneError> {
    let (lo, hi) = (vec3(spec.domain.lo), vec3(spec.domain.hi));
    if !(lo.is_finite() && hi.is_finite() && hi.cmpgt(lo).all()) {
        return Err(SceneError::invalid(
            o,
            "simulation.domain",
            format!("{lo} .. {hi}"),
            "finite lo < hi on every axis",
        ));
    }
    let dx = spec.dx;
    let cells = ((hi - lo) / dx).ceil();
    if !(dx.is_finite() && dx > 0.0) || cells.element_product() > 64e6 {
        return Err(SceneError::invalid(
            o,
            "simulation.dx",
            dx,
            "a spacing > 0 giving at most 64M cells over the domain",
        ));
    }
    let (lo, hi) = spec.grid_box();
    Ok(Grid::new(lo, hi, dx))
}

/// The domain walls (`walls`, `ground`) and the planar colliders.
pub(super) fn boundaries_of(spec: &SimulationSpec, o: &str) -> Result<Boundaries, SceneError> {
    let mut walls = DomainWalls::uniform(spec.walls.build(o, "simulation.walls")?);
    if let Some(g) = &spec.ground {
        walls.faces[4] = g.build(o, "simulation.ground")?;
    }
    if spec.colliders.len() > crate::sim::gpu::MAX_COLLIDERS {
        return Err(SceneError::invalid(
            o,
            "simulation.colliders",
            spec.colliders.len(),
            "at most 8 colliders",
        ));
    }
    let mut colliders = Vec::new();
    for (i, c) in spec.colliders.iter().enumerate() {
        let n = vec3(c.normal);
        if !(n.is_finite() && n.length() > 0.0 && vec3(c.point).is_finite()) {
            return Err(SceneError::invalid(
                o,
                format!("simulation.colliders[{i}].normal"),
                n,
                "a finite non-zero normal",
            ));
        }
        colliders.push(PlaneCollider {
            point: vec3(c.point),
            normal: n.normalize(),
            condition: c
                .condition
                .build(o, &format!("simulation.colliders[{i}]"))?,
        });
    }
    Ok(Boundaries {
        walls,
        colliders,
        surface: None,
    })
}

/// Whether a particle at `x` lies in `simulation.domain`, or at most half a cell outside
/// it: an object resting on the ground or touching a wall has its outermost particles
/// about that close to the face, and the grid's padding still holds their whole stencil.
pub(super) fn inside_domain(spec: &SimulationSpec, x: DVec3) -> bool {
    let slack = DVec3::splat(0.5 * spec.dx);
    let (lo, hi) = (vec3(spec.domain.lo) - slack, vec3(spec.domain.hi) + slack);
    x.is_finite() && x.cmpge(lo).all() && x.cmple(hi).all()
}
