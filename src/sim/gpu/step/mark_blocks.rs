//! `shaders/sim/step/mark_blocks.wgsl`: per sorted particle: flag the blocks of 4³ nodes
//! its cell's stencils reach (gather path).

use crate::gpu::Kernel;

use super::{step_kernel, BindAt, Bound, Extent, Pass, Sorted, Step, StepBuffers};

pub(crate) struct MarkBlocks {
    kernel: Kernel,
}

impl MarkBlocks {
    pub fn new(device: &wgpu::Device) -> Self {
        let src = include_str!("../../../../shaders/sim/step/mark_blocks.wgsl");
        MarkBlocks {
            kernel: step_kernel(device, "sim mark_blocks", src),
        }
    }

    fn bind_group(
        &self,
        device: &wgpu::Device,
        b: &StepBuffers,
        sorted: &Sorted,
    ) -> wgpu::BindGroup {
        self.kernel.bind_named(
            device,
            &[
                ("step", &b.step),
                ("cell_keys", sorted.keys),
                ("block_flags", &b.block_flags),
            ],
        )
    }
}

impl Pass<Step> for MarkBlocks {
    fn name(&self) -> &'static str {
        "mark blocks"
    }

    fn bind(&self, device: &wgpu::Device, at: &mut BindAt) -> Bound {
        Bound::Whole(self.bind_group(device, at.b, at.sorted()))
    }

    /// One invocation per particle.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &Extent) {
        self.kernel
            .dispatch(c, bound.whole(), at.particles.div_ceil(256));
    }
}
