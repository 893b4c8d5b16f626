//! `shaders/sim/step/damage_field.wgsl`: per node of the active blocks, the damage field
//! D_i and whether a broken particle reaches the node (two-field separation, first pass).

use crate::gpu::Kernel;

use super::{step_kernel, Sorted, StepBuffers};

pub(crate) struct DamageField {
    kernel: Kernel,
}

impl DamageField {
    pub fn new(device: &wgpu::Device) -> Self {
        let src = include_str!("../../../shaders/sim/step/damage_field.wgsl");
        DamageField {
            kernel: step_kernel(device, "sim damage field", src),
        }
    }

    pub fn bind(&self, device: &wgpu::Device, b: &StepBuffers, sorted: &Sorted) -> wgpu::BindGroup {
        self.kernel.bind_named_resources(
            device,
            &[
                ("step", b.step.as_entire_binding()),
                ("ranges", b.ranges.as_entire_binding()),
                ("cell_values", sorted.values.as_entire_binding()),
                ("x_mass", b.x_mass.as_entire_binding()),
                ("alpha", b.alpha.as_entire_binding()),
                ("material", b.material.as_entire_binding()),
                ("damage", b.damage.as_entire_binding()),
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
