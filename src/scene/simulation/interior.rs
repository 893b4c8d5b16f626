//! The solid of a simulated object: its fill or its particle lattice (`scene::fill`) run
//! with the object's inside test and selection, and the fill's appearance (isotropic
//! Gaussians coloured by their donor, or by a procedural asset's region colour).

use super::*;

/// What [`fill_object`] makes of an object's solid.
#[derive(Clone, Copy)]
pub(super) enum Cover {
    /// `physics.fill`: points in the interior beside the Gaussians.
    Interior,
    /// `physics.particles`: a jittered lattice over all of it.
    Lattice { jitter: f64 },
}

/// Fill object `i`'s solid (its selected Gaussians `part`) at spacing `h`, as `cover` says.
// Over 80 lines on purpose: the fill modes share the voxel grid and the cover built at its
// start.
pub(super) fn fill_object(
    scene: &Scene,
    i: usize,
    part: &Splats,
    h: f64,
    dx: f64,
    cover: Cover,
) -> Result<crate::scene::fill::Fill, SceneError> {
    use crate::scene::fill::{fill, lattice, FillInput, InsideTest, MAX_CLOSING_VOXELS};
    use crate::scene::physics::FillMode;
    let o = scene.origin.as_str();
    let setting = match cover {
        Cover::Interior => "fill",
        Cover::Lattice { .. } => "particles",
    };
    let field = format!("objects[{i}].physics.{setting}.spacing");
    if !(h.is_finite() && h >= dx / 16.0 && h <= dx) {
        return Err(SceneError::invalid(
            o,
            field,
            h,
            format!("a spacing in [Δx/16, Δx] = [{}, {dx}]", dx / 16.0),
        ));
    }
    if let Cover::Lattice { jitter } = cover {
        if !(0.0..=1.0).contains(&jitter) {
            return Err(SceneError::invalid(
                o,
                format!("objects[{i}].physics.particles.jitter"),
                jitter,
                "a share of the spacing in [0, 1]",
            ));
        }
    }
    let obj = &scene.objects[i];
    let physics = obj.physics.as_ref().expect("simulated");
    let (m, t) = obj.transform.affine();
    let (m, t) = (m.as_dmat3(), t.as_dvec3());
    let m_inv = m.inverse();
    let in_labels = selected_regions(obj);
    let region = |p: DVec3| match &physics.select {
        None => true,
        // An asset's solid is whole: keep where its selected regions are.
        Some(SelectSpec::Label(_)) => in_labels.as_ref().is_none_or(|(spec, picked)| {
            spec.region_at((m_inv * (p - t)).to_array())
                .is_some_and(|(l, _)| picked[usize::from(l)])
        }),
        Some(s) => s.contains(p),
    };
    let contains = |p: DVec3| {
        obj.procedural
            .as_ref()
            .is_some_and(|s| s.contains((m_inv * (p - t)).to_array()))
    };
    let inside = match &obj.procedural {
        None => match physics.fill.as_ref().map(|f| f.mode(h)) {
            Some((FillMode::Closing, r)) => {
                let radius = (r / h).round();
                if !(r.is_finite() && r > 0.0 && radius <= MAX_CLOSING_VOXELS as f64) {
                    return Err(SceneError::invalid(
                        o,
                        format!("objects[{i}].physics.fill.closing_radius"),
                        r,
                        format!(
                            "a radius > 0 of at most {MAX_CLOSING_VOXELS} fill spacings ({})",
                            MAX_CLOSING_VOXELS as f64 * h
                        ),
                    ));
                }
                InsideTest::Closing {
                    radius: (radius as usize).max(1),
                }
            }
            _ => InsideTest::Parity,
        },
        Some(spec) => {
            let (blo, bhi) = spec.bounds();
            let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
            for c in 0..8 {
                let corner = DVec3::new(
                    if c & 1 == 0 { blo[0] } else { bhi[0] },
                    if c & 2 == 0 { blo[1] } else { bhi[1] },
                    if c & 4 == 0 { blo[2] } else { bhi[2] },
                );
                let w = m * corner + t;
                lo = lo.min(w);
                hi = hi.max(w);
            }
            // Only the selection needs voxels.
            if let Some(SelectSpec::Box { lo: sl, hi: sh }) = &physics.select {
                lo = lo.max(vec3(*sl));
                hi = hi.min(vec3(*sh)).max(lo);
            }
            if let Some(SelectSpec::Sphere { center, radius }) = &physics.select {
                lo = lo.max(vec3(*center) - *radius);
                hi = hi.min(vec3(*center) + *radius).max(lo);
            }
            InsideTest::Exact {
                contains: &contains,
                lo,
                hi,
            }
        }
    };
    let input = FillInput {
        means: &part.means,
        covariances: &part.covariances,
        opacities: &part.opacities,
        spacing: h,
        inside,
        region: &region,
    };
    match cover {
        Cover::Interior => fill(&input),
        Cover::Lattice { jitter } => lattice(&input, jitter, i as u64),
    }
    .map_err(|e| {
        SceneError::invalid(
            o,
            field,
            h,
            format!("a coarser spacing or a smaller selection: {e}"),
        )
    })
}

/// For a procedural asset whose selection is by label: the asset, and per region of it
/// whether the selection names it. `None` for other objects (a capture's solid is that of
/// its selected Gaussians already).
fn selected_regions(
    obj: &crate::scene::ObjectSpec,
) -> Option<(&crate::splat::procedural::ProceduralSpec, Vec<bool>)> {
    let physics = obj.physics.as_ref()?;
    let Some(SelectSpec::Label(names)) = &physics.select else {
        return None;
    };
    let spec = obj
        .procedural
        .as_ref()
        .filter(|s| s.shape.asset().is_some())?;
    let picked = spec
        .label_names()
        .iter()
        .map(|n| names.iter().any(|s| &s.text() == n))
        .collect();
    Some((spec, picked))
}

/// Fill particles of a procedural asset take the colour and label of the asset's region
/// at their position rather than their nearest Gaussian's: below a watermelon's rind lies
/// flesh, not more rind (`ProceduralSpec::region_at`). Other objects keep `fill` as it is.
pub(super) fn paint_asset_fill(obj: &crate::scene::ObjectSpec, mut fill: Splats) -> Splats {
    let Some(spec) = obj
        .procedural
        .as_ref()
        .filter(|s| s.shape.asset().is_some())
    else {
        return fill;
    };
    // Asset label ids → ids in the scene-wide names that `fill` carries.
    let ids: Vec<u16> = spec
        .label_names()
        .iter()
        .map(|n| {
            fill.label_names
                .iter()
                .position(|m| m == n)
                .map_or(crate::splat::NO_LABEL, |i| i as u16)
        })
        .collect();
    let (m, t) = obj.transform.affine();
    let (m_inv, t) = (m.as_dmat3().inverse(), t.as_dvec3());
    let k = fill.sh_stride();
    for j in 0..fill.len() {
        let x = m_inv * (fill.means[j].as_dvec3() - t);
        if let Some((label, rgb)) = spec.region_at(x.to_array()) {
            fill.sh[j * k..j * k + 3].copy_from_slice(&crate::splat::sh::rgb_to_dc(rgb));
            if let Some(l) = fill.labels.get_mut(j) {
                *l = ids[usize::from(label)];
            }
        }
    }
    fill
}

/// Opacity of fill Gaussians (the procedural default: opaque when exposed).
pub const FILL_OPACITY: f32 = 0.95;

/// The fill particles as Gaussians: isotropic with σ = `SCALE_PER_SPACING` · h (as the
/// procedural lattices, so that an exposed interior has no holes), the DC colour and rest
/// frame of the nearest selected Gaussian (higher SH bands zero: no view-dependent
/// highlights inside), opacity [`FILL_OPACITY`], and the nearest Gaussian's label.
pub(super) fn fill_gaussians(part: &Splats, f: &crate::scene::fill::Fill) -> Splats {
    let h = f.point_volume.cbrt();
    let sigma = crate::splat::procedural::SCALE_PER_SPACING * h as f32;
    let var = sigma * sigma;
    let k = part.sh_stride();
    let mut sh = vec![0.0; f.points.len() * k];
    for (j, &d) in f.nearest.iter().enumerate() {
        let d = d as usize;
        sh[j * k..j * k + 3].copy_from_slice(&part.sh[d * k..d * k + 3]);
    }
    Splats {
        means: f.points.iter().map(|p| p.as_vec3()).collect(),
        covariances: vec![[var, 0.0, 0.0, var, 0.0, var]; f.points.len()],
        rotations: f
            .nearest
            .iter()
            .map(|&d| part.rotations[d as usize])
            .collect(),
        opacities: vec![FILL_OPACITY; f.points.len()],
        sh_degree: part.sh_degree,
        sh,
        // A fill particle belongs to the region of its nearest Gaussian.
        labels: if part.labels.is_empty() {
            Vec::new()
        } else {
            f.nearest.iter().map(|&d| part.labels[d as usize]).collect()
        },
        label_names: part.label_names.clone(),
    }
}
