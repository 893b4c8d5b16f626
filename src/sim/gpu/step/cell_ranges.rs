//! Each cell's run of sorted particles with the shared ranges pass (`gpu::ranges`,
//! `shaders/gpu/ranges.wgsl`) (gather path).

use crate::gpu::ranges::Ranges;

use super::{BindAt, Bound, Extent, Pass, Step};

pub(crate) struct CellRanges {
    ranges: Ranges,
}

impl CellRanges {
    pub fn new(device: &wgpu::Device) -> Self {
        CellRanges {
            ranges: Ranges::new(device),
        }
    }
}

impl Pass<Step> for CellRanges {
    fn name(&self) -> &'static str {
        "cell ranges"
    }

    fn bind(&self, device: &wgpu::Device, at: &mut BindAt) -> Bound {
        let b = at.b;
        Bound::Whole(
            self.ranges
                .bind(device, &b.key_count, at.sorted().keys, &b.ranges),
        )
    }

    /// Cells no particle reaches keep an empty run.
    fn clear(&self, enc: &mut wgpu::CommandEncoder, at: &Extent) {
        enc.clear_buffer(&at.b.ranges, 0, None);
    }

    /// One invocation per sorted particle.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &Extent) {
        self.ranges
            .kernel
            .dispatch(c, bound.whole(), at.particles.div_ceil(256));
    }
}
