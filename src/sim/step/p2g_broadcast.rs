//! `shaders/sim/step/p2g_broadcast.wgsl`: the gather of [`P2gGather`](super::P2gGather)
//! (one field), walked by subgroups of eight nodes that share each particle they read by
//! broadcast: for CPU drivers whose subgroups are 8 invocations
//! ([`GpuContext::cpu_subgroups_of_eight`](crate::gpu::GpuContext::cpu_subgroups_of_eight)).

use crate::gpu::Kernel;

use super::{
    gather_bindings, gather_source, p2g_gather_bindings, step_kernel, BindAt, Bound, Extent,
    StepPass,
};

/// The fields of `Lent` in `p2g_broadcast.wgsl`, each handed from one lane to all.
const LENT_FIELDS: [&str; 6] = ["base", "fx_mass", "mv", "a0", "a1", "a2"];

/// The unrolled adds of the particle each lane 0..8 holds (a broadcast's lane index must
/// be a constant expression).
fn lent_by_each_lane() -> String {
    (0..8)
        .map(|lane| {
            let fields: Vec<String> = LENT_FIELDS
                .iter()
                .map(|f| format!("subgroupBroadcast(own.{f}, {lane}u)"))
                .collect();
            format!("add_lent(&sums, node, Lent({}), carry);", fields.join(", "))
        })
        .collect::<Vec<_>>()
        .join("\n        ")
}

pub(crate) struct P2gBroadcast {
    kernel: Kernel,
}

impl P2gBroadcast {
    pub fn new(device: &wgpu::Device) -> Self {
        let pass = include_str!("../../../shaders/sim/step/p2g_broadcast.wgsl")
            .replace("LENT_BY_EACH_LANE", &lent_by_each_lane());
        P2gBroadcast {
            kernel: step_kernel(device, "sim p2g broadcast", &gather_source(&pass)),
        }
    }
}

impl StepPass for P2gBroadcast {
    fn name(&self) -> &'static str {
        "p2g gather + grid"
    }

    fn bind(&self, device: &wgpu::Device, at: &BindAt) -> Bound {
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
