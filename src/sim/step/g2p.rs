//! `shaders/sim/step/g2p.wgsl`: per particle: velocity, C, F and position from the grid,
//! then the material's plasticity (G2P).

use crate::gpu::Kernel;

use super::{step_kernel, StepBuffers};

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

    pub fn bind(&self, device: &wgpu::Device, b: &StepBuffers) -> wgpu::BindGroup {
        self.kernel.bind_named(
            device,
            &[
                ("step", &b.step),
                ("x_mass", &b.x_mass),
                ("v_volume", &b.v_volume),
                ("deformation", &b.deformation),
                ("affine_velocity", &b.affine_velocity),
                ("alpha", &b.alpha),
                ("material", &b.material),
                ("grid", &b.grid),
                ("flags", &b.flags),
                ("block_slot", &b.block_slot),
            ],
        )
    }

    /// One invocation per particle.
    pub fn record(&self, c: &mut wgpu::ComputePass, bind: &wgpu::BindGroup, particles: u32) {
        self.kernel.dispatch(c, bind, particles.div_ceil(256));
    }
}
