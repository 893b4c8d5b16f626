//! `shaders/sim/step/compact_blocks.wgsl`: per block of the domain: list the flagged
//! blocks, give each a pool slot, and write the node passes' dispatch size.

use crate::gpu::Kernel;

use super::{step_kernel, BindAt, Bound, Extent, Pass, Step, StepBuffers};

pub(crate) struct CompactBlocks {
    kernel: Kernel,
}

impl CompactBlocks {
    pub fn new(device: &wgpu::Device) -> Self {
        let src = include_str!("../../../../shaders/sim/step/compact_blocks.wgsl");
        CompactBlocks {
            kernel: step_kernel(device, "sim compact_blocks", src),
        }
    }

    fn bind_group(&self, device: &wgpu::Device, b: &StepBuffers) -> wgpu::BindGroup {
        self.kernel.bind_named(
            device,
            &[
                ("step", &b.step),
                ("block_flags", &b.block_flags),
                ("active_blocks", &b.active_blocks),
                ("block_args", &b.block_args),
                ("flags", &b.flags),
                ("block_slot", &b.block_slot),
            ],
        )
    }
}

impl Pass<Step> for CompactBlocks {
    fn name(&self) -> &'static str {
        "compact blocks"
    }

    fn bind(&self, device: &wgpu::Device, at: &mut BindAt) -> Bound {
        Bound::Whole(self.bind_group(device, at.b))
    }

    /// The active-block count it adds to.
    fn clear(&self, enc: &mut wgpu::CommandEncoder, at: &Extent) {
        enc.clear_buffer(&at.b.block_args, 0, None);
    }

    /// One invocation per block of the domain.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &Extent) {
        self.kernel
            .dispatch(c, bound.whole(), at.blocks.div_ceil(256));
    }
}
