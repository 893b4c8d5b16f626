//! `shaders/sim/step/damage_field.wgsl`: per node of the active blocks, the damage field
//! D_i and whether a broken particle reaches the node (two-field separation, first pass).

use crate::gpu::Kernel;

use super::{gather_bindings, gather_source, step_kernel, Sorted, StepBuffers};

pub(crate) struct DamageField {
    kernel: Kernel,
}

impl DamageField {
    pub fn new(device: &wgpu::Device) -> Self {
        let src = gather_source(include_str!("../../../shaders/sim/step/damage_field.wgsl"));
        DamageField {
            kernel: step_kernel(device, "sim damage field", &src),
        }
    }

    pub fn bind(&self, device: &wgpu::Device, b: &StepBuffers, sorted: &Sorted) -> wgpu::BindGroup {
        let own = [
            ("x_mass", b.x_mass.as_entire_binding()),
            ("alpha", b.alpha.as_entire_binding()),
            ("material", b.material.as_entire_binding()),
            ("damage", b.damage.as_entire_binding()),
        ];
        let all: Vec<_> = gather_bindings(b, sorted).into_iter().chain(own).collect();
        self.kernel.bind_named_resources(device, &all)
    }

    /// One workgroup per active block.
    pub fn record(&self, c: &mut wgpu::ComputePass, bind: &wgpu::BindGroup, b: &StepBuffers) {
        self.kernel.dispatch_indirect(c, bind, &b.block_args, 0);
    }
}
