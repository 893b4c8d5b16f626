//! The simulated bodies as the setup adds them, object by object: materials and regions,
//! particles (lattice or one per Gaussian and fill point), fill, Gaussians and binding.

use super::*;
use crate::sim::Action;

/// The simulated bodies as they are added: particles, bindings, materials, the CFL bound.
pub(super) struct Bodies {
    pub(super) particles: Particles,
    pub(super) binding: Binding,
    pub(super) bodies: Vec<Body>,
    pub(super) materials: Vec<Material>,
    pub(super) warnings: Vec<String>,
    pub(super) dt_cfl: f64,
    /// The scene's timed actions, and per particle the bits of those acting on it.
    pub(super) actions: Vec<Action>,
    pub(super) members: Vec<u32>,
}

impl Default for Bodies {
    fn default() -> Self {
        Bodies {
            particles: Particles::new(),
            binding: Binding::default(),
            bodies: Vec::new(),
            materials: Vec::new(),
            warnings: Vec::new(),
            dt_cfl: f64::INFINITY,
            actions: Vec::new(),
            members: Vec::new(),
        }
    }
}

impl Bodies {
    /// Object `i` with its selected Gaussians `part`: its materials (and regions'), its
    /// particles (the lattice, or one per Gaussian and fill point), its fill, its Gaussians
    /// into `out` and their binding.
    // Over 80 lines on purpose: one object's materials, particles, fill, Gaussians and
    // binding, in the order each needs the one before.
    pub(super) fn add(
        &mut self,
        scene: &Scene,
        i: usize,
        part: Splats,
        grid: &Grid,
        spec: &SimulationSpec,
        out: &mut Parts,
    ) -> Result<(), SceneError> {
        let o = scene.origin.as_str();
        let obj = &scene.objects[i];
        let name = obj.display_name(i);
        let physics = obj.physics.as_ref().expect("simulated");
        let (m_index, density, mut regions) =
            self.add_materials(scene, i, &part, grid.dx, spec.cfl)?;
        let filled = match physics.fill.as_ref().and_then(|f| f.spacing(grid.dx)) {
            None => None,
            Some(h) => Some(fill_object(scene, i, &part, h, grid.dx, Cover::Interior)?),
        };
        let mut fill_splats = filled
            .as_ref()
            .map(|f| paint_asset_fill(obj, fill_gaussians(&part, f)))
            .unwrap_or_default();
        let lattice = physics.particles.lattice(grid.dx);
        let cloud = match lattice {
            None => ParticleCloud::of_gaussians(obj, &part, filled.as_ref(), &fill_splats),
            Some((h, jitter)) => {
                let l = fill_object(scene, i, &part, h, grid.dx, Cover::Lattice { jitter })?;
                self.warnings.extend(l.warnings.iter().map(|w| {
                    let w = w.strip_prefix("fill: ").unwrap_or(w);
                    format!("objects[{i}] ({name}): particle lattice: {w}")
                }));
                ParticleCloud::of_lattice(obj, &part, &l, scene, i)?
            }
        };
        if let Some(f) = &filled {
            self.warnings.extend(
                f.warnings
                    .iter()
                    .map(|w| format!("objects[{i}] ({name}): {w}")),
            );
        }
        let (xs, volumes) = (&cloud.x, &cloud.volume);
        let centre = if filled.is_some() || lattice.is_some() {
            let total: f64 = volumes.iter().sum();
            xs.iter().zip(volumes).map(|(x, v)| *x * *v).sum::<DVec3>() / total.max(1e-300)
        } else {
            part.means.iter().map(|m| m.as_dvec3()).sum::<DVec3>() / part.len().max(1) as f64
        };
        let (v0, w0) = (vec3(physics.velocity), vec3(physics.angular_velocity));
        regions.place(o, i, xs)?;
        let region = assign_regions(obj, &regions, &cloud, &part);
        let start = self.particles.len();
        for ((x, volume), r) in xs.iter().zip(volumes).zip(&region) {
            let x = *x;
            let (m_index, density) = match r {
                None => (m_index, density),
                Some(r) => (m_index + 1 + *r as u32, regions.materials[*r].1),
            };
            if !inside_domain(spec, x) {
                let (lo, hi) = (vec3(spec.domain.lo), vec3(spec.domain.hi));
                return Err(SceneError::invalid(
                    o,
                    format!("objects[{i}]"),
                    format!("a particle at {x}"),
                    format!("every simulated particle inside simulation.domain ({lo} .. {hi}), within half a cell; enlarge the domain or move the object"),
                ));
            }
            self.particles.push(
                x,
                v0 + w0.cross(x - centre),
                density * volume,
                *volume,
                m_index,
                0.0,
            );
        }
        self.add_actions(scene, i, start, &cloud, &part)?;
        // APIC: a rigid spin has velocity gradient C = [ω]×.
        let skew = glam::DMat3::from_cols(
            DVec3::new(0.0, w0.z, -w0.y),
            DVec3::new(-w0.z, 0.0, w0.x),
            DVec3::new(w0.y, -w0.x, 0.0),
        );
        for p in start..self.particles.len() {
            self.particles.c[p] = skew;
            self.particles.alpha[p] =
                self.materials[self.particles.material[p] as usize].initial_alpha();
        }
        let gaussians = part.len() + fill_splats.len();
        let binding = match lattice {
            None => Binding::identity(start as u32, gaussians),
            Some((h, _)) => {
                let means: Vec<glam::Vec3> = part
                    .means
                    .iter()
                    .chain(&fill_splats.means)
                    .copied()
                    .collect();
                Binding::nearest(&means, xs, start as u32, h)
            }
        };
        // A fill Gaussian takes the colour of its particle's region.
        let fill_region: Vec<Option<usize>> = binding.particle[part.len()..]
            .iter()
            .map(|&p| region[p as usize - start])
            .collect();
        recolour_fill(&mut fill_splats, &fill_region, &regions);
        let first = out.splats.len();
        out.push(part, i, PartKind::Simulated);
        out.push(fill_splats, i, PartKind::Fill);
        self.binding.append(binding);
        self.bodies.push(Body {
            object: i,
            particles: start..self.particles.len(),
            gaussians: first..out.splats.len(),
        });
        Ok(())
    }

    /// Object `i`'s timed actions, on its particles from `start` on (`cloud` at rest).
    fn add_actions(
        &mut self,
        scene: &Scene,
        i: usize,
        start: usize,
        cloud: &ParticleCloud,
        part: &Splats,
    ) -> Result<(), SceneError> {
        let o = scene.origin.as_str();
        let physics = scene.objects[i].physics.as_ref().expect("simulated");
        let drafts = crate::scene::actions::check(o, i, &physics.actions, self.actions.len())?;
        self.members.resize(self.particles.len(), 0);
        if drafts.is_empty() {
            return Ok(());
        }
        let labels: Vec<Option<&str>> = (0..cloud.x.len())
            .map(|p| {
                let l = *cloud.labels.get(p)?;
                part.label_names.get(usize::from(l)).map(String::as_str)
            })
            .collect();
        let rest = (&cloud.x[..], &labels[..], &self.particles.mass[start..]);
        for d in drafts {
            let bit = self.actions.len();
            let action = d.take(o, bit, rest, &mut self.members[start..])?;
            self.actions.push(action);
        }
        Ok(())
    }

    /// Object `i`'s material and its regions' materials, each lowering the CFL bound:
    /// the index of the first, its density, and the regions.
    pub(super) fn add_materials(
        &mut self,
        scene: &Scene,
        i: usize,
        part: &Splats,
        dx: f64,
        cfl: f64,
    ) -> Result<(u32, f64, ObjectRegions), SceneError> {
        let o = scene.origin.as_str();
        let physics = scene.objects[i].physics.as_ref().expect("simulated");
        let field = format!("objects[{i}].physics.material");
        let material = physics.material.build(o, &field)?.for_grid(dx);
        let density = physics.material.density();
        self.dt_cfl = self.dt_cfl.min(cfl_dt(&material, density, dx, cfl));
        let m_index = self.materials.len() as u32;
        self.materials.push(material);
        let regions = ObjectRegions::build(o, i, &physics.regions, &object_labels(part))?;
        for (m, rho) in &regions.materials {
            self.dt_cfl = self.dt_cfl.min(cfl_dt(m, *rho, dx, cfl));
            self.materials.push(m.for_grid(dx));
        }
        if self.materials.len() > crate::sim::gpu::MAX_MATERIALS {
            return Err(SceneError::invalid(
                o,
                format!("objects[{i}].physics.regions"),
                format!("{} materials in the scene", self.materials.len()),
                format!(
                    "at most {} materials over all simulated objects and their regions",
                    crate::sim::gpu::MAX_MATERIALS
                ),
            ));
        }
        Ok((m_index, density, regions))
    }
}
