//! `shaders/sim/step/p2g_broadcast.wgsl`: the gather of [`P2gGather`](super::P2gGather)
//! (one field or two), walked by subgroups of eight nodes that share each particle they read by
//! broadcast: for CPU drivers whose subgroups are 8 invocations
//! ([`GpuContext::cpu_subgroups_of_eight`](crate::gpu::GpuContext::cpu_subgroups_of_eight)).

use crate::gpu::Kernel;

use super::{
    gather_bindings, lent_by_lane, p2g_gather_bindings, p2g_gather_source, BindAt, Bound, Extent,
    Pass, Step, GROUP_WALK,
};

pub(crate) struct P2gBroadcast {
    kernel: Kernel,
}

impl P2gBroadcast {
    /// With `separation`, per field (two-field separation compiled in).
    pub fn new(device: &wgpu::Device, separation: bool) -> Self {
        // the fields of `Lent`; one field has no damage gradient to hand over
        let gradient = (!separation).then_some("vec3<f32>()");
        let fields = [
            ("base", None),
            ("fx_mass", None),
            ("mv", None),
            ("a0", None),
            ("a1", None),
            ("a2", None),
            ("gradient", gradient),
        ];
        let src = p2g_gather_source(separation)
            .module(&GROUP_WALK)
            .generated(lent_by_lane(&fields))
            .pass(include_str!(
                "../../../../shaders/sim/step/p2g_broadcast.wgsl"
            ));
        P2gBroadcast {
            kernel: Kernel::new(device, "sim p2g broadcast", &src, "main"),
        }
    }
}

impl Pass<Step> for P2gBroadcast {
    fn name(&self) -> &'static str {
        "p2g gather + grid"
    }

    fn bind(&self, device: &wgpu::Device, at: &mut BindAt) -> Bound {
        let b = at.b;
        let all: Vec<_> = gather_bindings(b, at.sorted())
            .into_iter()
            .chain(p2g_gather_bindings(b))
            .collect();
        Bound::Whole(self.kernel.bind_named_resources(device, &all))
    }

    /// One workgroup per active block, as many as `compact_blocks` wrote into `block_args`.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &Extent) {
        self.kernel
            .dispatch_indirect(c, bound.whole(), &at.b.block_args, 0);
    }
}
