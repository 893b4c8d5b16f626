//! A built scene run frame by frame: simulate, checkpoint, derive, render, write.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Result};
use glam::{DVec3, Vec3};

use super::{check_manifest_for_resume, create_dir, Event, FragmentLog, Job, Sink, Summary};
use crate::checkpoint::{self, checkpoint_path, Checkpoint};
use crate::derive::normals::GpuNormals;
use crate::derive::{Derive, RigidDerive};
use crate::gpu::GpuContext;
use crate::limits;
use crate::output::manifest::{manifest_path, FrameTiming, Settings};
use crate::output::passes::{IdTable, Pass};
use crate::render::{GpuRenderer, Splats};
use crate::scene::kinematic::KinematicObject;
use crate::scene::lighting::SceneLighting;
use crate::scene::simulation::SimulationSetup;
use crate::scene::{self, BuildReport, Scene};
use crate::sim::frame::FrameError;
use crate::sim::gpu::{GpuSim, P2gPath, SimPlan, SimRequest, Watchdog, FIXED_POINT_CELLS_PER_STEP};
use crate::sim::model::PlasticModel;
use crate::sim::time_step::{Clock, StepPlan};
use crate::splat::sh::ShRotator;

mod messages;
mod setup;
use messages::{
    describe_lighting, describe_simulation, inversion_warning, watchdog_message, Failure,
};
use setup::{
    create_outputs, first_missing_frame, manifest_settings, note_scene, plan_gpu, prepare_lighting,
    prepare_simulation, recomputed_normals, resume_state,
};

pub(super) fn execute(
    job: Job,
    splats: Splats,
    report: BuildReport,
    gpu: &GpuContext,
    on_event: &mut dyn FnMut(Event),
) -> Result<Summary> {
    let opts = &job.opts;
    let scene = &job.scene;
    let setup = prepare_simulation(&job, splats.clone(), &report, gpu)?;
    let hash = checkpoint::scene_hash(scene, &splats, setup.as_ref());
    let splats = setup.as_ref().map_or(splats, |s| s.splats.clone());
    let dir = scene.output_dir();
    create_outputs(&job, &dir)?;
    on_event(Event::Note(format!("adapter: {}", gpu.describe())));
    let manifest_file = manifest_path(&dir, &job.frames, scene.frame_count());
    let p2g = plan_gpu(&job, setup.as_ref(), splats.len(), gpu, on_event)?;
    let first_missing = first_missing_frame(&job, &dir, (&manifest_file, hash))?;
    let resume_from = resume_state(&job, setup.as_ref(), &dir, hash, first_missing, on_event)?;
    note_scene(&job, splats.len(), &dir, on_event);
    let mut renderer = GpuRenderer::new(gpu);
    renderer.set_passes(gpu, Pass::set(&opts.passes));
    renderer.upload(gpu, &splats)?;
    let ids = opts
        .passes
        .contains(&Pass::Id)
        .then(|| id_table(&splats, &report, setup.as_ref()));
    if let Some(t) = &ids {
        renderer.set_ids(gpu, &t.ids)?;
    }
    let lighting = prepare_lighting(
        &job,
        (&splats, &report),
        setup.as_ref(),
        (gpu, &mut renderer),
        on_event,
    )?;
    let mut sim = match &setup {
        Some(s) => Some(Simulation::start(
            s,
            (gpu, &renderer),
            resume_from.as_ref(),
            (p2g, opts.deterministic),
            on_event,
        )?),
        None => None,
    };
    let gpu_normals = match (&lighting, &setup) {
        (Some(l), Some(s)) => recomputed_normals(l, s, &splats, (gpu, &renderer))?,
        _ => None,
    };
    let mut settings = manifest_settings(
        &job,
        setup.as_ref(),
        (p2g, splats.len()),
        resume_from.as_ref(),
    );
    settings.ids = ids.map(|t| t.entries).unwrap_or_default();
    let mut manifest = job.manifest(manifest_file, hash, gpu, settings);
    manifest.write_now()?;
    let fragment_log = opts
        .fragments
        .then(|| FragmentLog::create(&dir.join("fragments.csv"), opts.resume))
        .transpose()?;
    let mut frames = Frames {
        job: &job,
        gpu,
        hash,
        renderer,
        splats: &splats,
        lighting: lighting.as_ref(),
        gpu_normals,
        rotator: opts.exports().next().map(|_| ShRotator::new()),
        fragment_log,
        checkpoint_file: checkpoint_path(&dir),
        sink: Sink::new(dir, &job.opts.passes, manifest),
    };
    on_event(Event::Frames(job.frames.clone()));
    let first_sim = resume_from.as_ref().map_or(0, |cp| cp.frame);
    let result = match first_missing {
        Some(_) => frames.run(sim.as_mut(), first_sim, on_event),
        None => Ok(()),
    };
    let Frames {
        sink, fragment_log, ..
    } = frames;
    let fragments = fragment_log.map(|l| l.last().to_vec()).unwrap_or_default();
    job.finish(result, sink, fragments, on_event)
}

/// The simulated part of a run on the GPU: the step, the derive pass into the renderer's
/// buffer, and the kinematic objects' rigid passes.
struct Simulation<'a> {
    setup: &'a SimulationSetup,
    sim: GpuSim,
    derive: Derive,
    /// Kinematic objects' Gaussians, moved rigidly along their paths every frame.
    rigid: Vec<(&'a KinematicObject, RigidDerive)>,
    /// The steps so far and the last frame's largest speed (the next Δt follows it).
    clock: Clock,
    /// Whether steps that inverted a particle's deformation have been reported (once a
    /// run).
    warned_inversion: bool,
}

impl<'a> Simulation<'a> {
    /// The simulation of `s` on the GPU, its warnings logged and its line noted.
    fn start(
        s: &'a SimulationSetup,
        (gpu, renderer): (&GpuContext, &GpuRenderer),
        resume_from: Option<&Checkpoint>,
        (p2g, deterministic): (P2gPath, bool),
        on_event: &mut dyn FnMut(Event),
    ) -> Result<Self> {
        for w in &s.warnings {
            log::warn!("{w}");
        }
        on_event(Event::Note(describe_simulation(s, p2g, deterministic)));
        Simulation::new(gpu, renderer, s, resume_from, p2g)
    }

    fn new(
        gpu: &GpuContext,
        renderer: &GpuRenderer,
        s: &'a SimulationSetup,
        resume_from: Option<&Checkpoint>,
        p2g: P2gPath,
    ) -> Result<Self> {
        let restored;
        let start = match resume_from {
            Some(cp) => {
                restored = cp.to_particles(&s.particles);
                &restored
            }
            None => &s.particles,
        };
        let mut sim = GpuSim::with_path(gpu, start, &s.grid, &s.materials, &s.params, p2g)?;
        let colliders: Vec<_> = s.kinematic.iter().map(|k| k.collider.clone()).collect();
        sim.set_kinematic(gpu, &colliders)?;
        let derive = Derive::new(
            gpu,
            &sim,
            renderer,
            &s.splats,
            s.static_count as u32,
            &s.binding,
        )?;
        let mut rigid = Vec::new();
        for k in &s.kinematic {
            for part in s.parts.iter().filter(|p| p.object == k.object) {
                let r =
                    RigidDerive::new(gpu, renderer, &s.splats, part.start as u32, part.len as u32)?;
                rigid.push((k, r));
            }
        }
        let clock = resume_from.map_or(
            Clock {
                speed: s.particles.max_speed(),
                steps_done: 0,
            },
            |cp| cp.clock,
        );
        Ok(Simulation {
            setup: s,
            sim,
            derive,
            rigid,
            clock,
            warned_inversion: false,
        })
    }

    /// The steps that lead to `frame` (none for the first simulated frame), then the pool
    /// fitted for the next frame; a watchdog count stops the run. Returns the steps taken
    /// and how often the frame's Δt was halved on the way.
    fn advance_to(
        &mut self,
        gpu: &GpuContext,
        scene: &Scene,
        frame: u32,
        first: u32,
    ) -> Result<Advanced> {
        let s = self.setup;
        let before = self.clock;
        let plan = match s.step_rule.frame_steps(before.speed) {
            Ok(plan) => plan,
            Err(e) => {
                let (culprit, _) =
                    self.describe_particle(gpu, scene, self.fastest_particle(gpu)?)?;
                bail!("frame {frame}: {e}; the fastest is {culprit}; try a smaller simulation.cfl, or a scene whose speeds the grid can follow")
            }
        };
        let (w, plan, halvings) = if frame > first {
            // The moving colliders' clock: this frame's steps start at frame − 1.
            let start = f64::from(frame - 1) * s.step_rule.frame;
            let done = match self
                .sim
                .step_frame(gpu, plan, start, s.step_rule.max_halvings())
            {
                Ok(done) => done,
                Err(FrameError::Gpu(e)) => return Err(e.into()),
                Err(e) => bail!("frame {frame}: {e}"),
            };
            self.clock = Clock {
                speed: f64::from(done.watchdog.speed_max),
                steps_done: before.steps_done + u64::from(done.plan.steps),
            };
            (done.watchdog, done.plan, done.halvings)
        } else {
            (self.sim.take_watchdog(gpu)?, plan, 0)
        };
        // Sparse grid: room for the active region to double before the next read.
        self.sim.fit_pool(gpu, &w)?;
        let inverted = match w.inverted_first_particle {
            Some(p) if w.failed() && Some(p) == w.first_particle => {
                Some("the same particle".to_string())
            }
            Some(p) if w.failed() || !self.warned_inversion => {
                Some(self.describe_particle(gpu, scene, p)?.0)
            }
            _ => None,
        };
        if w.failed() {
            let culprit = match w.first_particle {
                Some(p) => Some(self.describe_particle(gpu, scene, p)?),
                None => None,
            };
            let failure = Failure {
                frame,
                watchdog: w,
                plan,
                halvings,
                steps_before: before.steps_done,
                culprit,
                inverted,
            };
            bail!("{}", watchdog_message(&failure, s));
        }
        if let Some(particle) = inverted {
            log::warn!(
                "{}",
                inversion_warning(frame, &w, plan, before.steps_done, &particle, s)
            );
            self.warned_inversion = true;
        }
        Ok(Advanced {
            steps: if frame > first { plan.steps } else { 0 },
            halvings,
        })
    }

    /// The index of the fastest particle (read back from the GPU).
    fn fastest_particle(&self, gpu: &GpuContext) -> Result<u32> {
        let state = self.sim.read_particles(gpu, &self.setup.particles)?;
        let speed = |p: usize| state.v[p].length();
        let fastest =
            (0..state.v.len()).fold(0, |best, p| if speed(p) > speed(best) { p } else { best });
        Ok(fastest as u32)
    }

    /// Particle `p` as a failure names it: its object, material, where it is and how fast
    /// it moves (read back from the GPU); and its speed.
    fn describe_particle(&self, gpu: &GpuContext, scene: &Scene, p: u32) -> Result<(String, f64)> {
        let s = self.setup;
        let state = self.sim.read_particles(gpu, &s.particles)?;
        let p = p as usize;
        let object =
            s.bodies
                .iter()
                .find(|b| b.particles.contains(&p))
                .map_or("?".to_string(), |b| {
                    format!(
                        "objects[{}] ({})",
                        b.object,
                        scene.objects[b.object].display_name(b.object)
                    )
                });
        let m = &s.materials[s.particles.material[p] as usize];
        let v3 = |x: DVec3| format!("[{:.3}, {:.3}, {:.3}]", x.x, x.y, x.z);
        let text = format!(
            "particle {p} of {object}, material {} ({}), at {} m moving {} m/s",
            s.particles.material[p],
            match m.plastic_model() {
                PlasticModel::None => m.elastic_model().def().name,
                law => law.name(),
            },
            v3(state.x[p]),
            v3(state.v[p])
        );
        Ok((text, state.v[p].length()))
    }

    /// The simulated and kinematic Gaussians of the renderer's buffer, moved to `seconds`.
    fn derive(&self, gpu: &GpuContext, seconds: f64) -> Result<()> {
        self.derive.run(gpu)?;
        for (k, r) in &self.rigid {
            let (a, b) = k.rest_to_world(seconds);
            r.run(gpu, a, b)?;
        }
        Ok(())
    }
}

/// What [`Simulation::advance_to`] took: the steps that stood, and how often the frame
/// ran again at half the step.
struct Advanced {
    steps: u32,
    halvings: u32,
}

/// The frame loop's state.
struct Frames<'a> {
    job: &'a Job,
    gpu: &'a GpuContext,
    hash: u64,
    renderer: GpuRenderer,
    splats: &'a Splats,
    lighting: Option<&'a SceneLighting>,
    gpu_normals: Option<GpuNormals>,
    rotator: Option<ShRotator>,
    fragment_log: Option<FragmentLog>,
    checkpoint_file: PathBuf,
    sink: Sink,
}

impl Frames<'_> {
    /// Frame f shows the state after f · steps_per_frame steps, so a simulation steps
    /// through every frame up to the last one asked for (from frame 0 or the checkpoint),
    /// and renders only the frames asked for; a frame set with gaps saves rendering, not
    /// simulating. Without a simulation only the frames asked for are visited.
    fn run(
        &mut self,
        mut sim: Option<&mut Simulation>,
        first_sim: u32,
        on_event: &mut dyn FnMut(Event),
    ) -> Result<()> {
        let frames = &self.job.frames;
        let Some(last) = frames.last() else {
            return Ok(());
        };
        let visited: Vec<u32> = match sim {
            Some(_) => (first_sim..=last).collect(),
            None => frames.iter().collect(),
        };
        for frame in visited {
            on_event(Event::FrameStart(frame));
            let t0 = Instant::now();
            let mut timing = FrameTiming::default();
            if let Some(sim) = sim.as_deref_mut() {
                let done = sim.advance_to(self.gpu, &self.job.scene, frame, first_sim)?;
                timing.steps = Some(done.steps);
                timing.halvings = (done.halvings > 0).then_some(done.halvings);
                if self.job.opts.checkpoint_every > 0
                    && frame > first_sim
                    && frame % self.job.opts.checkpoint_every == 0
                {
                    self.checkpoint(sim, frame)?;
                }
                timing.simulate_ms = t0.elapsed().as_secs_f64() * 1e3;
                if !self.job.frames.contains(frame) {
                    continue;
                }
            }
            if self.job.opts.resume && self.job.frame_done(&self.sink.dir, frame) {
                on_event(Event::FrameDone {
                    frame,
                    skipped: true,
                });
                continue;
            }
            if let Some(sim) = sim.as_deref_mut() {
                let wants_state =
                    self.fragment_log.is_some() || self.job.opts.export_particles.is_some();
                if wants_state {
                    let state = sim.sim.read_particles(self.gpu, &sim.setup.particles)?;
                    if let Some(log) = &mut self.fragment_log {
                        log.record(frame, &state, sim.setup, &self.job.scene)?;
                    }
                    if let Some(dir) = &self.job.opts.export_particles {
                        crate::output::particles::export_frame(dir, frame, &state, sim.setup)?;
                    }
                }
                sim.derive(
                    self.gpu,
                    f64::from(frame) / f64::from(self.job.scene.output.fps),
                )?;
            }
            self.render(frame, timing)?;
            on_event(Event::FrameDone {
                frame,
                skipped: false,
            });
        }
        Ok(())
    }

    /// Frames before this one reach the disk first, so a crash after the checkpoint never
    /// loses a frame that resuming from it would skip.
    fn checkpoint(&mut self, sim: &Simulation, frame: u32) -> Result<()> {
        self.sink.writer.flush()?;
        let s = sim.setup;
        let state = sim.sim.read_particles(self.gpu, &s.particles)?;
        Checkpoint::from_particles(
            &state,
            self.hash,
            self.job.opts.deterministic,
            frame,
            s.steps_per_frame,
            sim.clock,
        )
        .save(&self.checkpoint_file)?;
        self.sink.manifest.write_now()?;
        Ok(())
    }

    /// Export, relight, render and queue the PNG of the Gaussians now in the renderer.
    fn render(&mut self, frame: u32, mut timing: FrameTiming) -> Result<()> {
        let gpu = self.gpu;
        let scene = &self.job.scene;
        let t1 = Instant::now();
        if let Some(rotator) = &self.rotator {
            let gaussians = self.renderer.read_gaussians(gpu)?;
            let cloud = crate::output::export::world_cloud(&gaussians, self.splats, rotator);
            for (dir, format) in self.job.opts.exports() {
                crate::output::export::export_frame(dir, frame, &cloud, format)?;
            }
        }
        if let Some(l) = self.lighting {
            self.renderer
                .set_lights(&l.lights.at(frame as f32 / scene.output.fps));
        }
        if let Some(n) = &self.gpu_normals {
            // Normals in the deformed configuration (new fracture faces included).
            n.run(gpu)?;
        }
        let camera = self.job.path.camera(frame);
        let background = Vec3::from(scene.output.background);
        let (image, timings) = self.renderer.render_timed(gpu, &camera, background)?;
        timing.render_ms = t1.elapsed().as_secs_f64() * 1e3;
        self.sink.submit(frame, image, &timings, timing)
    }
}

/// The id pass's table: each object's Gaussians (in `splats`' order: as built, or as the
/// simulation's setup arranged them) by object and region label.
fn id_table(splats: &Splats, report: &BuildReport, setup: Option<&SimulationSetup>) -> IdTable {
    let name = |o: usize| report.objects[o].name.clone();
    let runs: Vec<(String, std::ops::Range<usize>)> = match setup {
        Some(s) => s
            .parts
            .iter()
            .map(|p| (name(p.object), p.start..p.start + p.len))
            .collect(),
        None => {
            let mut start = 0;
            (0..report.objects.len())
                .map(|o| {
                    let run = start..start + report.objects[o].gaussians;
                    start = run.end;
                    (name(o), run)
                })
                .collect()
        }
    };
    IdTable::new(&runs, splats)
}
