//! `shaders/sim/step/mark_blocks.wgsl`: per sorted particle: flag the blocks of 4³ nodes
//! its cell's stencils reach (gather path).

use crate::gpu::Kernel;

use super::{step_kernel, Sorted, StepBuffers};

pub(crate) struct MarkBlocks {
    kernel: Kernel,
}

impl MarkBlocks {
    pub fn new(device: &wgpu::Device) -> Self {
        let src = include_str!("../../../shaders/sim/step/mark_blocks.wgsl");
        MarkBlocks {
            kernel: step_kernel(device, "sim mark_blocks", src),
        }
    }

    pub fn bind(&self, device: &wgpu::Device, b: &StepBuffers, sorted: &Sorted) -> wgpu::BindGroup {
        self.kernel.bind_named(
            device,
            &[
                ("step", &b.step),
                ("cell_keys", sorted.keys),
                ("block_flags", &b.block_flags),
            ],
        )
    }

    /// One invocation per particle.
    pub fn record(&self, c: &mut wgpu::ComputePass, bind: &wgpu::BindGroup, particles: u32) {
        self.kernel.dispatch(c, bind, particles.div_ceil(256));
    }
}
