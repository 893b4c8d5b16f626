//! Before the first frame: the simulation prepared and planned, the outputs created, the
//! relighting set up, the checkpoint to resume from, and the settings the manifest records.

use super::*;

/// The simulation of the scene, if it has one: the options and the grid checked against
/// the adapter before the setup builds it, and the options that need a simulation refused
/// without one.
pub(super) fn prepare_simulation(
    job: &Job,
    splats: Splats,
    report: &BuildReport,
    gpu: &GpuContext,
) -> Result<Option<SimulationSetup>> {
    let (opts, scene) = (&job.opts, &job.scene);
    SimPlan::check_options(opts.p2g, opts.deterministic)?;
    let simulated = scene.objects.iter().any(|o| o.physics.is_some());
    if let Some(spec) = scene.simulation.as_ref().filter(|_| simulated) {
        let (lo, hi) = spec.grid_box();
        let separation = spec.separation != scene::physics::SeparationSpec::None;
        let surface = scene.objects.iter().any(|o| o.collider.is_some());
        SimPlan::check_grid(gpu, (hi - lo) / spec.dx, separation, surface)?;
    }
    let setup = scene::simulation::prepare(scene, splats, report)?;
    if setup.is_none() {
        let name = match &opts.input {
            crate::run::Input::Scene(Some(p)) => p.display().to_string(),
            crate::run::Input::Text { name, .. } => name.clone(),
            _ => "the default scene".into(),
        };
        if opts.fragments {
            bail!("--fragments counts the pieces of simulated objects, and {name} simulates none (no object has `physics`)");
        }
        if opts.export_particles.is_some() {
            bail!("--export-particles writes the particles of simulated objects, and {name} simulates none (no object has `physics`)");
        }
    }
    Ok(setup)
}

/// The output directory and the export directories the options name.
pub(super) fn create_outputs(job: &Job, dir: &Path) -> Result<()> {
    create_dir(dir, "output directory")?;
    for (d, format) in job.opts.exports() {
        create_dir(d, format.directory_name())?;
    }
    if let Some(d) = &job.opts.export_particles {
        create_dir(d, "particle export directory")?;
    }
    for pass in &job.opts.passes {
        create_dir(&pass.dir(dir), "pass directory")?;
    }
    Ok(())
}

/// The scene's relighting, if it has a `lighting` block, set on the renderer.
pub(super) fn prepare_lighting(
    job: &Job,
    (splats, report): (&Splats, &BuildReport),
    setup: Option<&SimulationSetup>,
    (gpu, renderer): (&GpuContext, &mut GpuRenderer),
    on_event: &mut dyn FnMut(Event),
) -> Result<Option<SceneLighting>> {
    // Relighting before the derive pass is built: derive moves the simulated normals.
    let lighting = scene::lighting::prepare(
        &job.scene,
        splats,
        report,
        setup.map(|s| s.parts.as_slice()),
        setup.map(|s| (s.grid.lo.as_vec3(), s.grid.hi().as_vec3())),
    )?;
    if let Some(l) = &lighting {
        on_event(Event::Note(describe_lighting(l, splats.len())));
        renderer.set_lighting(gpu, &l.setup)?;
    }
    Ok(lighting)
}

/// The P2G path (the simulation's [`SimPlan`], its race noted), and every buffer the run
/// will allocate checked against the adapter.
pub(super) fn plan_gpu(
    job: &Job,
    setup: Option<&SimulationSetup>,
    gaussians: usize,
    gpu: &GpuContext,
    on_event: &mut dyn FnMut(Event),
) -> Result<P2gPath> {
    let opts = &job.opts;
    let (width, height) = (job.scene.output.width, job.scene.output.height);
    let plan = match setup {
        Some(s) => Some(SimPlan::choose(
            gpu,
            &SimRequest {
                params: &s.params,
                particles: s.particles.len(),
                cells: s.grid.cells,
                steps: u64::from(s.steps_per_frame) * u64::from(job.frames.last().unwrap_or(0)),
                forced: opts.p2g,
                deterministic: opts.deterministic,
            },
        )?),
        None => None,
    };
    if let Some(race) = plan.as_ref().and_then(|p| p.race) {
        on_event(Event::Note(race.describe()));
    }
    let mut needs = limits::render_needs(gaussians, width, height);
    if let Some(s) = setup {
        needs.extend(limits::derive_needs(
            s.binding.len(),
            s.particles.len(),
            gaussians,
        ));
    }
    limits::check_gpu(gpu, &needs)?;
    Ok(plan.map_or(P2gPath::best(gpu), |p| p.p2g))
}

/// The run's settings as the manifest records them.
pub(super) fn manifest_settings(
    job: &Job,
    setup: Option<&SimulationSetup>,
    (p2g, gaussians): (P2gPath, usize),
    resume_from: Option<&Checkpoint>,
) -> Settings {
    let opts = &job.opts;
    Settings {
        width: job.scene.output.width,
        height: job.scene.output.height,
        fps: job.scene.output.fps,
        deterministic: opts.deterministic,
        gaussians,
        particles: setup.map(|s| s.particles.len()),
        p2g: setup.map(|_| p2g.name().to_string()),
        steps_per_frame: setup.map(|s| s.steps_per_frame),
        dt: setup.map(|s| s.params.dt),
        checkpoint_every: if setup.is_some() {
            opts.checkpoint_every
        } else {
            0
        },
        resumed_from: resume_from.map(|cp| cp.frame),
        from_states: None,
        export_ply: opts.export_ply.clone(),
        export_spz: opts.export_spz.clone(),
        export_glb: opts.export_glb.clone(),
        export_particles: opts.export_particles.clone(),
        ..job.frame_settings()
    }
}

/// With `--resume`: the checkpoint to continue from, if it is not past the first frame
/// still to render.
pub(super) fn resume_state(
    job: &Job,
    setup: Option<&SimulationSetup>,
    dir: &Path,
    hash: u64,
    first_missing: Option<u32>,
    on_event: &mut dyn FnMut(Event),
) -> Result<Option<Checkpoint>> {
    if !job.opts.resume {
        return Ok(None);
    }
    let file = checkpoint_path(dir);
    let state = match (setup, first_missing) {
        (Some(s), Some(missing)) if file.exists() => {
            let cp = Checkpoint::load(&file)?;
            cp.check_matches(
                &file,
                hash,
                job.opts.deterministic,
                s.particles.len(),
                s.steps_per_frame,
            )?;
            if cp.frame <= missing {
                Some(cp)
            } else {
                on_event(Event::Note(format!(
                    "resume: the checkpoint is at frame {}, after frame {missing} which is missing; simulating from frame 0",
                    cp.frame
                )));
                None
            }
        }
        _ => None,
    };
    on_event(Event::Note(match (first_missing, &state) {
        (None, _) => format!("resume: frames {} are all written already", job.frames),
        (Some(m), Some(cp)) => format!(
            "resume: continuing from the checkpoint at frame {} (first missing frame {m})",
            cp.frame
        ),
        (Some(m), None) => format!("resume: first missing frame {m}"),
    }));
    Ok(state)
}

/// The GPU normals of the simulated objects whose normals the lighting recomputes every
/// frame, if any.
pub(super) fn recomputed_normals(
    lighting: &SceneLighting,
    s: &SimulationSetup,
    splats: &Splats,
    (gpu, renderer): (&GpuContext, &GpuRenderer),
) -> Result<Option<GpuNormals>> {
    if lighting.recompute.is_empty() {
        return Ok(None);
    }
    Ok(Some(GpuNormals::new(
        gpu,
        renderer,
        &lighting.recomputed_objects(splats),
        s.grid.lo.as_vec3(),
        s.grid.hi().as_vec3(),
    )?))
}

/// The scene's notes for the log: its up axis, and its size, frames and output directory.
pub(super) fn note_scene(job: &Job, gaussians: usize, dir: &Path, on_event: &mut dyn FnMut(Event)) {
    let scene = &job.scene;
    for note in &scene.up_notes {
        on_event(Event::Note(note.clone()));
    }
    on_event(Event::Note(format!(
        "scene: {} Gaussians, {}×{}, frames {} → {}",
        gaussians,
        scene.output.width,
        scene.output.height,
        job.frames,
        dir.display()
    )));
}

/// The first frame of the set still to render: the set's first, or with `--resume` the
/// first whose PNG is missing (after the manifest is checked to be this scene's).
pub(super) fn first_missing_frame(
    job: &Job,
    dir: &Path,
    (manifest_file, hash): (&Path, u64),
) -> Result<Option<u32>> {
    let opts = &job.opts;
    if opts.resume {
        check_manifest_for_resume(manifest_file, hash)?;
    }
    Ok(if opts.resume {
        job.frames.iter().find(|f| !job.frame_done(dir, *f))
    } else {
        job.frames.first()
    })
}
