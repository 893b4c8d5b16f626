//! `shaders/sim/step/p2g_scatter.wgsl`: per particle: add mass and momentum to its 27 nodes
//! with float atomics (atomic path).

use crate::gpu::Kernel;

use super::{step_kernel, StepBuffers};

pub(crate) struct P2gScatter {
    kernel: Kernel,
}

impl P2gScatter {
    pub fn new(device: &wgpu::Device) -> Self {
        let src = include_str!("../../../shaders/sim/step/p2g_scatter.wgsl");
        P2gScatter {
            kernel: step_kernel(device, "sim p2g_scatter", src),
        }
    }

    pub fn bind(&self, device: &wgpu::Device, b: &StepBuffers) -> wgpu::BindGroup {
        self.kernel.bind_named(
            device,
            &[
                ("step", &b.step),
                ("x_mass", &b.x_mass),
                ("v_volume", &b.v_volume),
                ("affine", &b.affine),
                ("grid_sum", &b.grid),
                ("block_slot", &b.block_slot),
            ],
        )
    }

    /// One invocation per particle.
    pub fn record(&self, c: &mut wgpu::ComputePass, bind: &wgpu::BindGroup, particles: u32) {
        self.kernel.dispatch(c, bind, particles.div_ceil(256));
    }
}
