//! `shaders/sim/step/grid_from_sums.wgsl`: per node of the active blocks: velocity from the
//! scattered sums (float or fixed-point), then the grid update (atomic and fixed-point
//! paths).

use crate::gpu::Kernel;

use super::{BindAt, Bound, Extent, Pass, Step, StepBuffers};

pub(crate) struct GridFromSums {
    kernel: Kernel,
}

impl GridFromSums {
    /// With `fixed_point`, the sums are `p2g_fixed.wgsl`'s word pairs, else floats.
    pub fn new(device: &wgpu::Device, fixed_point: bool) -> Self {
        let src = super::step_source(&crate::sim::model::ModelsUsed::all())
            .define("FIXED_POINT", fixed_point)
            .pass(include_str!(
                "../../../../shaders/sim/step/grid_from_sums.wgsl"
            ));
        GridFromSums {
            kernel: Kernel::new(device, "sim grid_from_sums", &src, "main"),
        }
    }

    fn bind_group(&self, device: &wgpu::Device, b: &StepBuffers) -> wgpu::BindGroup {
        self.kernel.bind_named_resources(
            device,
            &[
                ("step", b.step.as_entire_binding()),
                ("grid", b.grid.as_entire_binding()),
                ("grid_velocity", b.grid_velocity.binding()),
                ("grid_velocity_change", b.grid_velocity_change.binding()),
                ("active_blocks", b.active_blocks.as_entire_binding()),
                ("block_args", b.block_args.as_entire_binding()),
                ("block_slot", b.block_slot.as_entire_binding()),
                ("surface", b.surface.as_entire_binding()),
            ],
        )
    }
}

impl Pass<Step> for GridFromSums {
    fn name(&self) -> &'static str {
        "grid from sums"
    }

    fn bind(&self, device: &wgpu::Device, at: &mut BindAt) -> Bound {
        Bound::Whole(self.bind_group(device, at.b))
    }

    /// One workgroup per active block, as many as `compact_blocks` wrote into `block_args`.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &Extent) {
        self.kernel
            .dispatch_indirect(c, bound.whole(), &at.b.block_args, 0);
    }
}
