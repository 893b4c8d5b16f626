//! `shaders/sim/step/damage_gradient.wgsl`: per particle, the damage field's gradient
//! ∇D_p (two-field separation, second pass; the gather path, one page).

use crate::gpu::Kernel;

use super::{step_kernel, StepBuffers};

pub(crate) struct DamageGradient {
    kernel: Kernel,
}

impl DamageGradient {
    pub fn new(device: &wgpu::Device) -> Self {
        let src = include_str!("../../../shaders/sim/step/damage_gradient.wgsl");
        DamageGradient {
            kernel: step_kernel(device, "sim damage gradient", src),
        }
    }

    pub fn bind(&self, device: &wgpu::Device, b: &StepBuffers) -> wgpu::BindGroup {
        use wgpu::BindingResource::Buffer;
        self.kernel.bind_named_resources(
            device,
            &[
                ("step", b.step.as_entire_binding()),
                ("page", Buffer(b.pages.entry(0))),
                ("x_mass", b.x_mass.as_entire_binding()),
                ("damage", b.damage.as_entire_binding()),
                ("damage_gradient", b.damage_gradient.as_entire_binding()),
                ("block_slot", b.block_slot.as_entire_binding()),
            ],
        )
    }

    /// One invocation per particle.
    pub fn record(&self, c: &mut wgpu::ComputePass, bind: &wgpu::BindGroup, particles: u32) {
        self.kernel.dispatch(c, bind, particles.div_ceil(256));
    }
}
