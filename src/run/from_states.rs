//! `--from-states DIR`: each frame's Gaussians from `DIR/frame_NNNNN.ply`, rendered with the
//! scene's camera and output settings; no build, no simulation.

use std::path::Path;
use std::time::Instant;

use anyhow::{bail, Result};
use glam::Vec3;

use super::{check_manifest_for_resume, create_dir, Event, Job, Sink, Summary};
use crate::checkpoint;
use crate::gpu::GpuContext;
use crate::limits;
use crate::output::frame_path;
use crate::output::manifest::{manifest_path, FrameTiming, Settings};
use crate::output::passes::Pass;
use crate::render::{GpuRenderer, Splats};

pub(super) fn execute(
    job: Job,
    states: &Path,
    gpu: &GpuContext,
    on_event: &mut dyn FnMut(Event),
) -> Result<Summary> {
    let scene = &job.scene;
    // The scene's settings only: its objects come from the states.
    let hash = checkpoint::scene_hash(scene, &Splats::default(), None);
    if job.opts.passes.contains(&Pass::Id) {
        bail!("--passes id: frames rendered --from-states carry no objects to number; render the scene itself for the id pass");
    }
    let dir = scene.output_dir();
    create_dir(&dir, "output directory")?;
    for pass in &job.opts.passes {
        create_dir(&pass.dir(&dir), "pass directory")?;
    }
    on_event(Event::Note(format!("adapter: {}", gpu.describe())));
    let manifest_file = manifest_path(&dir, &job.frames, scene.frame_count());
    let (width, height) = (scene.output.width, scene.output.height);
    limits::check_gpu(gpu, &limits::render_needs(0, width, height))?;
    if job.opts.resume {
        check_manifest_for_resume(&manifest_file, hash)?;
    }
    on_event(Event::Note(format!(
        "states: {}, {}×{}, frames {} → {}",
        states.display(),
        width,
        height,
        job.frames,
        dir.display()
    )));
    let settings = Settings {
        width,
        height,
        fps: scene.output.fps,
        deterministic: job.opts.deterministic,
        from_states: Some(states.to_path_buf()),
        ..job.frame_settings()
    };
    let mut manifest = job.manifest(manifest_file, hash, gpu, settings);
    manifest.write_now()?;
    let mut frames = StateFrames {
        job: &job,
        gpu,
        states,
        renderer: {
            let mut r = GpuRenderer::new(gpu);
            r.set_passes(gpu, Pass::set(&job.opts.passes));
            r
        },
        sink: Sink::new(dir, &job.opts.passes, manifest),
    };
    on_event(Event::Frames(job.frames.clone()));
    let result = frames.run(on_event);
    job.finish(result, frames.sink, Vec::new(), on_event)
}

struct StateFrames<'a> {
    job: &'a Job,
    gpu: &'a GpuContext,
    states: &'a Path,
    renderer: GpuRenderer,
    sink: Sink,
}

impl StateFrames<'_> {
    fn run(&mut self, on_event: &mut dyn FnMut(Event)) -> Result<()> {
        let job = self.job;
        for frame in job.frames.iter() {
            on_event(Event::FrameStart(frame));
            if job.opts.resume && frame_path(&self.sink.dir, frame).is_file() {
                on_event(Event::FrameDone {
                    frame,
                    skipped: true,
                });
                continue;
            }
            self.frame(frame)?;
            on_event(Event::FrameDone {
                frame,
                skipped: false,
            });
        }
        Ok(())
    }

    /// Load, upload (relit when the scene has lights), render and queue one frame.
    fn frame(&mut self, frame: u32) -> Result<()> {
        let (gpu, scene) = (self.gpu, &self.job.scene);
        let (width, height) = (scene.output.width, scene.output.height);
        let t0 = Instant::now();
        let (splats, skipped) = crate::farm::load_state(self.states, frame)?;
        if skipped > 0 {
            log::warn!(
                "frame {frame}: {skipped} NaN or degenerate Gaussians in its state were skipped"
            );
        }
        limits::check_gpu(gpu, &limits::render_needs(splats.len(), width, height))?;
        self.renderer.upload(gpu, &splats)?;
        if let Some(l) = crate::scene::lighting::prepare_state(scene, &splats)? {
            self.renderer.set_lighting(gpu, &l.setup)?;
            self.renderer
                .set_lights(&l.lights.at(frame as f32 / scene.output.fps));
        }
        let load_ms = t0.elapsed().as_secs_f64() * 1e3;
        let t1 = Instant::now();
        let background = Vec3::from(scene.output.background);
        let (image, timings) =
            self.renderer
                .render_timed(gpu, &self.job.path.camera(frame), background)?;
        let timing = FrameTiming {
            simulate_ms: 0.0,
            steps: None,
            halvings: None,
            load_ms: Some(load_ms),
            render_ms: t1.elapsed().as_secs_f64() * 1e3,
            gpu_ms: 0.0,
        };
        self.sink.submit(frame, image, &timings, timing)
    }
}
