//! `shaders/sim/step/ridge.wgsl`: per node of the active blocks, the ridge gradient g_i
//! that splits its particles into two fields (two-field separation, third pass).

use crate::gpu::Kernel;

use super::{step_kernel, Sorted, StepBuffers};

pub(crate) struct Ridge {
    kernel: Kernel,
}

impl Ridge {
    pub fn new(device: &wgpu::Device) -> Self {
        let src = include_str!("../../../shaders/sim/step/ridge.wgsl");
        Ridge {
            kernel: step_kernel(device, "sim ridge", src),
        }
    }

    pub fn bind(&self, device: &wgpu::Device, b: &StepBuffers, sorted: &Sorted) -> wgpu::BindGroup {
        self.kernel.bind_named_resources(
            device,
            &[
                ("step", b.step.as_entire_binding()),
                ("ranges", b.ranges.as_entire_binding()),
                ("cell_values", sorted.values.as_entire_binding()),
                ("damage", b.damage.as_entire_binding()),
                ("damage_gradient", b.damage_gradient.as_entire_binding()),
                ("ridge", b.ridge.as_entire_binding()),
                ("active_blocks", b.active_blocks.as_entire_binding()),
                ("block_args", b.block_args.as_entire_binding()),
                ("block_slot", b.block_slot.as_entire_binding()),
            ],
        )
    }

    /// One workgroup per active block.
    pub fn record(&self, c: &mut wgpu::ComputePass, bind: &wgpu::BindGroup, b: &StepBuffers) {
        self.kernel.dispatch_indirect(c, bind, &b.block_args, 0);
    }
}
