//! `shaders/sim/step/p2g.wgsl`: per node of the active blocks: gather mass and momentum
//! from the 27 cells whose stencils reach it, in a fixed order (deterministic, no atomics),
//! then the grid update.

use crate::gpu::Kernel;

use super::{
    gather_bindings, gather_source, p2g_gather_bindings, step_kernel, BindAt, Bound, Extent,
    Sorted, StepBuffers, StepPass,
};

pub(crate) struct P2gGather {
    kernel: Kernel,
}

impl P2gGather {
    /// With `separation`, per field (two-field separation compiled in).
    pub fn new(device: &wgpu::Device, separation: bool) -> Self {
        let src = format!(
            "const SEPARATION: bool = {separation};\n{}",
            gather_source(include_str!("../../../shaders/sim/step/p2g.wgsl"))
        );
        P2gGather {
            kernel: step_kernel(device, "sim p2g", &src),
        }
    }

    fn bind_group(
        &self,
        device: &wgpu::Device,
        b: &StepBuffers,
        sorted: &Sorted,
    ) -> wgpu::BindGroup {
        let separation = [
            ("damage_gradient", b.damage_gradient.as_entire_binding()),
            ("ridge", b.ridge.as_entire_binding()),
            ("far_field", b.far_field.as_entire_binding()),
        ];
        let all: Vec<_> = gather_bindings(b, sorted)
            .into_iter()
            .chain(p2g_gather_bindings(b))
            .chain(separation)
            .collect();
        self.kernel.bind_named_resources(device, &all)
    }
}

impl StepPass for P2gGather {
    fn name(&self) -> &'static str {
        "p2g gather + grid"
    }

    fn bind(&self, device: &wgpu::Device, at: &BindAt) -> Bound {
        Bound::Whole(self.bind_group(device, at.b, at.sorted()))
    }

    /// One workgroup per active block, as many as `compact_blocks` wrote into `block_args`.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &Extent) {
        self.kernel
            .dispatch_indirect(c, bound.whole(), &at.b.block_args, 0);
    }
}
