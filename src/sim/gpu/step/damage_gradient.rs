//! `shaders/sim/step/damage_gradient.wgsl`: per particle, the damage field's gradient
//! ∇D_p (two-field separation, second pass; the gather path, one page).

use crate::gpu::Kernel;

use super::{step_kernel, BindAt, Bound, Extent, Pass, Step, StepBuffers};

pub(crate) struct DamageGradient {
    kernel: Kernel,
}

impl DamageGradient {
    pub fn new(device: &wgpu::Device) -> Self {
        let src = include_str!("../../../../shaders/sim/step/damage_gradient.wgsl");
        DamageGradient {
            kernel: step_kernel(device, "sim damage gradient", src),
        }
    }

    fn bind_group(&self, device: &wgpu::Device, b: &StepBuffers) -> wgpu::BindGroup {
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
}

impl Pass<Step> for DamageGradient {
    fn name(&self) -> &'static str {
        "damage gradient"
    }

    fn bind(&self, device: &wgpu::Device, at: &mut BindAt) -> Bound {
        Bound::Whole(self.bind_group(device, at.b))
    }

    /// One invocation per particle.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &Extent) {
        self.kernel
            .dispatch(c, bound.whole(), at.particles.div_ceil(256));
    }
}
