//! `shaders/sim/step/mark_particles.wgsl`: per particle: flag the blocks of its stencil
//! (atomic path).

use crate::gpu::Kernel;

use super::{pages, per_page, step_kernel, BindAt, Bound, Extent, Pass, Step, StepBuffers, VEC4};

pub(crate) struct MarkParticles {
    kernel: Kernel,
}

impl MarkParticles {
    pub fn new(device: &wgpu::Device) -> Self {
        let src = include_str!("../../../../shaders/sim/step/mark_particles.wgsl");
        MarkParticles {
            kernel: step_kernel(device, "sim mark_particles", src),
        }
    }

    /// Bind page `i` of the particles (`gpu::pages`): windows of the particle arrays.
    fn bind_page(&self, device: &wgpu::Device, b: &StepBuffers, i: u32) -> wgpu::BindGroup {
        self.kernel.bind_named_parts(
            device,
            &[
                ("step", b.step.as_entire_buffer_binding()),
                ("page", b.pages.entry(i)),
                ("x_mass", b.window(&b.x_mass, i, VEC4)),
                ("block_flags", b.block_flags.as_entire_buffer_binding()),
            ],
        )
    }
}

impl Pass<Step> for MarkParticles {
    fn name(&self) -> &'static str {
        "mark blocks (particles)"
    }

    fn bind(&self, device: &wgpu::Device, at: &mut BindAt) -> Bound {
        per_page(at.b, |i| self.bind_page(device, at.b, i))
    }

    /// One invocation per particle of the page.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &Extent) {
        for (bind, n) in pages(bound, at) {
            self.kernel.dispatch(c, bind, n.div_ceil(256));
        }
    }
}
