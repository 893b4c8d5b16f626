//! `shaders/sim/step/p2g_broadcast.wgsl`: the gather of [`P2gGather`](super::P2gGather)
//! (one field or two), walked by subgroups of eight nodes that share each particle they read by
//! broadcast: for CPU drivers whose subgroups are 8 invocations
//! ([`GpuContext::cpu_subgroups_of_eight`](crate::gpu::GpuContext::cpu_subgroups_of_eight)).

use crate::gpu::Kernel;

use super::{
    gather_bindings, p2g_gather_bindings, p2g_gather_source, step_kernel, BindAt, Bound, Extent,
    StepPass,
};

/// The fields of `Lent` in `p2g_broadcast.wgsl`, each handed from one lane to all, and
/// whether only two-field separation reads it (else it is left zero, not handed over).
const LENT_FIELDS: [(&str, bool); 7] = [
    ("base", false),
    ("fx_mass", false),
    ("mv", false),
    ("a0", false),
    ("a1", false),
    ("a2", false),
    ("gradient", true),
];

/// The unrolled adds of the particle each lane 0..8 holds (a broadcast's lane index must
/// be a constant expression).
fn lent_by_each_lane(separation: bool) -> String {
    (0..8)
        .map(|lane| {
            let fields: Vec<String> = LENT_FIELDS
                .iter()
                .map(|&(f, two_only)| {
                    if two_only && !separation {
                        "vec3<f32>()".to_string()
                    } else {
                        format!("subgroupBroadcast(own.{f}, {lane}u)")
                    }
                })
                .collect();
            format!(
                "add_lent(&near, &far, node, ridge_i, Lent({}), carry);",
                fields.join(", ")
            )
        })
        .collect::<Vec<_>>()
        .join("\n        ")
}

pub(crate) struct P2gBroadcast {
    kernel: Kernel,
}

impl P2gBroadcast {
    /// With `separation`, per field (two-field separation compiled in).
    pub fn new(device: &wgpu::Device, separation: bool) -> Self {
        let pass = include_str!("../../../shaders/sim/step/p2g_broadcast.wgsl")
            .replace("LENT_BY_EACH_LANE", &lent_by_each_lane(separation));
        let src = p2g_gather_source(&pass, separation);
        P2gBroadcast {
            kernel: step_kernel(device, "sim p2g broadcast", &src),
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
