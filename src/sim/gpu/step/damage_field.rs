//! `shaders/sim/step/damage_field.wgsl`: per node of the active blocks, the damage field
//! D_i and whether a broken particle reaches the node (two-field separation, first pass);
//! and `damage_field_broadcast.wgsl`, the same sums walked by subgroups of eight nodes
//! (`group_walk.wgsl`) for CPU drivers whose subgroups are 8 invocations.

use crate::gpu::Kernel;
use crate::sim::model::ModelsUsed;

use super::{
    gather_bindings, gather_source, lent_by_lane, BindAt, Bound, Extent, Pass, Sorted, Step,
    StepBuffers, GROUP_WALK,
};

pub(crate) struct DamageField {
    kernel: Kernel,
}

impl DamageField {
    /// Walked by subgroups with `by_subgroups`
    /// ([`GpuContext::cpu_subgroups_of_eight`](crate::gpu::GpuContext::cpu_subgroups_of_eight)).
    pub fn new(device: &wgpu::Device, used: &ModelsUsed, by_subgroups: bool) -> Self {
        let src = if by_subgroups {
            gather_source(used)
                .module(&GROUP_WALK)
                .generated(lent_by_lane(&[
                    ("base", None),
                    ("fx_mass", None),
                    ("d", None),
                ]))
                .pass(include_str!(
                    "../../../../shaders/sim/step/damage_field_broadcast.wgsl"
                ))
        } else {
            gather_source(used).pass(include_str!(
                "../../../../shaders/sim/step/damage_field.wgsl"
            ))
        };
        DamageField {
            kernel: Kernel::new(device, "sim damage field", &src, "main"),
        }
    }

    fn bind_group(
        &self,
        device: &wgpu::Device,
        b: &StepBuffers,
        sorted: &Sorted,
    ) -> wgpu::BindGroup {
        let own = [
            ("x_mass", b.x_mass.as_entire_binding()),
            ("alpha", b.alpha.as_entire_binding()),
            ("material", b.material.as_entire_binding()),
            ("damage", b.damage.as_entire_binding()),
        ];
        let all: Vec<_> = gather_bindings(b, sorted).into_iter().chain(own).collect();
        self.kernel.bind_named_resources(device, &all)
    }
}

impl Pass<Step> for DamageField {
    fn name(&self) -> &'static str {
        "damage field"
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
