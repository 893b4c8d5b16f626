//! Named stages of GPU work, recorded the same way by the renderer and the simulation:
//! all into one compute pass (each dispatch is its own synchronisation scope, so a stage
//! sees the writes of the stages before it), or, for per-pass timing, each submitted on
//! its own and waited for.

use super::{GpuContext, GpuError};

/// A named part of a frame or a step: the dispatches it records into a compute pass.
pub struct Stage<'a> {
    pub name: &'static str,
    record: Box<dyn Fn(&mut wgpu::ComputePass) + 'a>,
}

impl<'a> Stage<'a> {
    pub fn new(name: &'static str, record: impl Fn(&mut wgpu::ComputePass) + 'a) -> Self {
        Stage {
            name,
            record: Box::new(record),
        }
    }
}

/// Record `stages`, in order, into one compute pass of `enc`.
pub fn record(enc: &mut wgpu::CommandEncoder, label: &str, stages: &[Stage]) {
    let mut cpass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
        label: Some(label),
        timestamp_writes: None,
    });
    for stage in stages {
        (stage.record)(&mut cpass);
    }
}

/// Run each stage alone, submitted and waited for: its name and wall milliseconds. The
/// sum exceeds the time of the stages recorded together by the submissions' overhead.
pub fn profile(gpu: &GpuContext, stages: &[Stage]) -> Result<Vec<(&'static str, f64)>, GpuError> {
    let mut out = Vec::with_capacity(stages.len());
    for stage in stages {
        let start = std::time::Instant::now();
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        (stage.record)(&mut enc.begin_compute_pass(&Default::default()));
        gpu.queue.submit([enc.finish()]);
        gpu.wait()?;
        out.push((stage.name, start.elapsed().as_secs_f64() * 1e3));
    }
    Ok(out)
}
