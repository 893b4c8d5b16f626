//! `shaders/sim/step/g2p.wgsl`: per particle: velocity, C, F and position from the grid,
//! then the material's plasticity (G2P).

use crate::gpu::Kernel;

use super::{step_kernel, StepBuffers, MAT3, SCALAR, VEC4};

pub(crate) struct G2p {
    kernel: Kernel,
}

impl G2p {
    pub fn new(device: &wgpu::Device) -> Self {
        let src = include_str!("../../../shaders/sim/step/g2p.wgsl");
        G2p {
            kernel: step_kernel(device, "sim g2p", src),
        }
    }

    /// Bind page `i` of the particles (`gpu::pages`): windows of the particle arrays.
    pub fn bind(&self, device: &wgpu::Device, b: &StepBuffers, i: u32) -> wgpu::BindGroup {
        self.kernel.bind_named_parts(
            device,
            &[
                ("step", b.step.as_entire_buffer_binding()),
                ("page", b.pages.entry(i)),
                ("x_mass", b.window(&b.x_mass, i, VEC4)),
                ("v_volume", b.window(&b.v_volume, i, VEC4)),
                ("deformation", b.window(&b.deformation, i, MAT3)),
                ("affine_velocity", b.window(&b.affine_velocity, i, MAT3)),
                ("alpha", b.window(&b.alpha, i, SCALAR)),
                ("material", b.window(&b.material, i, SCALAR)),
                ("grid", b.grid.as_entire_buffer_binding()),
                ("flags", b.flags.as_entire_buffer_binding()),
                ("block_slot", b.block_slot.as_entire_buffer_binding()),
            ],
        )
    }

    /// One invocation per particle of the page.
    pub fn record(&self, c: &mut wgpu::ComputePass, bind: &wgpu::BindGroup, particles: u32) {
        self.kernel.dispatch(c, bind, particles.div_ceil(256));
    }
}
