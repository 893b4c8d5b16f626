//! `shaders/sim/step/mark_particles.wgsl`: per particle: flag the blocks of its stencil
//! (atomic path).

use crate::gpu::Kernel;

use super::{step_kernel, StepBuffers};

pub(crate) struct MarkParticles {
    kernel: Kernel,
}

impl MarkParticles {
    pub fn new(device: &wgpu::Device) -> Self {
        let src = include_str!("../../../shaders/sim/step/mark_particles.wgsl");
        MarkParticles {
            kernel: step_kernel(device, "sim mark_particles", src),
        }
    }

    pub fn bind(&self, device: &wgpu::Device, b: &StepBuffers) -> wgpu::BindGroup {
        self.kernel.bind_named(
            device,
            &[
                ("step", &b.step),
                ("x_mass", &b.x_mass),
                ("block_flags", &b.block_flags),
            ],
        )
    }

    /// One invocation per particle.
    pub fn record(&self, c: &mut wgpu::ComputePass, bind: &wgpu::BindGroup, particles: u32) {
        self.kernel.dispatch(c, bind, particles.div_ceil(256));
    }
}
