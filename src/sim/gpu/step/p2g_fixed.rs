//! `shaders/sim/step/p2g_fixed.wgsl`: per particle: add mass and momentum to its 27 nodes
//! as 64-bit fixed-point sums with integer atomics (fixed-point path: deterministic).

use crate::gpu::Kernel;

use super::{
    pages, per_page, step_kernel, BindAt, Bound, Extent, Pass, Step, StepBuffers, MAT3, VEC4,
};

pub(crate) struct P2gFixed {
    kernel: Kernel,
}

impl P2gFixed {
    pub fn new(device: &wgpu::Device) -> Self {
        let src = include_str!("../../../../shaders/sim/step/p2g_fixed.wgsl");
        P2gFixed {
            kernel: step_kernel(device, "sim p2g_fixed", src),
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
                ("v_volume", b.window(&b.v_volume, i, VEC4)),
                ("affine", b.window(&b.affine, i, MAT3)),
                ("grid_sum", b.grid.as_entire_buffer_binding()),
                ("flags", b.flags.as_entire_buffer_binding()),
                ("block_slot", b.block_slot.as_entire_buffer_binding()),
            ],
        )
    }
}

impl Pass<Step> for P2gFixed {
    fn name(&self) -> &'static str {
        "p2g scatter"
    }

    fn bind(&self, device: &wgpu::Device, at: &mut BindAt) -> Bound {
        per_page(at.b, |i| self.bind_page(device, at.b, i))
    }

    /// The grid's fixed-point sums it adds to.
    fn clear(&self, enc: &mut wgpu::CommandEncoder, at: &Extent) {
        enc.clear_buffer(&at.b.grid, 0, None);
    }

    /// One invocation per particle of the page.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &Extent) {
        for (bind, n) in pages(bound, at) {
            self.kernel.dispatch(c, bind, n.div_ceil(256));
        }
    }
}
