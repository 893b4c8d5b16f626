//! `shaders/sim/step/p2g.wgsl`: per node of the active blocks: gather mass and momentum
//! from the 27 cells whose stencils reach it, in a fixed order (deterministic, no atomics),
//! then the grid update.

use crate::gpu::Kernel;

use super::{
    gather_bindings, p2g_gather_bindings, p2g_gather_source, BindAt, Bound, Extent, Pass, Step,
};

pub(crate) struct P2gGather {
    kernel: Kernel,
}

impl P2gGather {
    /// With `separation`, per field (two-field separation compiled in).
    pub fn new(device: &wgpu::Device, separation: bool) -> Self {
        let src = p2g_gather_source(separation)
            .pass(include_str!("../../../../shaders/sim/step/p2g.wgsl"));
        P2gGather {
            kernel: Kernel::new(device, "sim p2g", &src, "main"),
        }
    }
}

impl Pass<Step> for P2gGather {
    fn name(&self) -> &'static str {
        "p2g gather + grid"
    }

    fn bind(&self, device: &wgpu::Device, at: &mut BindAt) -> Bound {
        let all: Vec<_> = gather_bindings(at.b, at.sorted())
            .into_iter()
            .chain(p2g_gather_bindings(at.b))
            .collect();
        Bound::Whole(self.kernel.bind_named_resources(device, &all))
    }

    /// One workgroup per active block, as many as `compact_blocks` wrote into `block_args`.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &Extent) {
        self.kernel
            .dispatch_indirect(c, bound.whole(), &at.b.block_args, 0);
    }
}
