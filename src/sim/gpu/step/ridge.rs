//! `shaders/sim/step/ridge.wgsl`: per node of the active blocks, the ridge gradient g_i
//! that splits its particles into two fields (two-field separation, third pass).

use crate::gpu::Kernel;
use crate::sim::model::ModelsUsed;

use super::{
    gather_bindings, gather_source, BindAt, Bound, Extent, Pass, Sorted, Step, StepBuffers,
};

pub(crate) struct Ridge {
    kernel: Kernel,
}

impl Ridge {
    pub fn new(device: &wgpu::Device) -> Self {
        let src = gather_source(&ModelsUsed::all())
            .pass(include_str!("../../../../shaders/sim/step/ridge.wgsl"));
        Ridge {
            kernel: Kernel::new(device, "sim ridge", &src, "main"),
        }
    }

    fn bind_group(
        &self,
        device: &wgpu::Device,
        b: &StepBuffers,
        sorted: &Sorted,
    ) -> wgpu::BindGroup {
        let own = [
            ("damage", b.damage.as_entire_binding()),
            ("damage_gradient", b.damage_gradient.as_entire_binding()),
            ("ridge", b.ridge.as_entire_binding()),
        ];
        let all: Vec<_> = gather_bindings(b, sorted).into_iter().chain(own).collect();
        self.kernel.bind_named_resources(device, &all)
    }
}

impl Pass<Step> for Ridge {
    fn name(&self) -> &'static str {
        "ridge"
    }

    fn bind(&self, device: &wgpu::Device, at: &mut BindAt) -> Bound {
        Bound::Whole(self.bind_group(device, at.b, at.sorted()))
    }

    /// One workgroup per active block.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &Extent) {
        self.kernel
            .dispatch_indirect(c, bound.whole(), &at.b.block_args, 0);
    }
}
