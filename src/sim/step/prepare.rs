//! `shaders/sim/step/prepare.wgsl`: per particle: the base-cell sort key and the affine
//! term m C − Δt V⁰ (4/Δx²) τ(F) (P2G, part 1).

use crate::gpu::Kernel;

use super::{step_kernel, StepBuffers};

pub(crate) struct Prepare {
    kernel: Kernel,
}

impl Prepare {
    pub fn new(device: &wgpu::Device) -> Self {
        let src = include_str!("../../../shaders/sim/step/prepare.wgsl");
        Prepare {
            kernel: step_kernel(device, "sim prepare", src),
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
                ("material", &b.material),
                ("cell_keys", &b.keys),
                ("cell_values", &b.values),
                ("affine", &b.affine),
            ],
        )
    }

    /// One invocation per particle.
    pub fn record(&self, c: &mut wgpu::ComputePass, bind: &wgpu::BindGroup, particles: u32) {
        self.kernel.dispatch(c, bind, particles.div_ceil(256));
    }
}
