//! The particles sorted by base cell with the shared radix sort (`gpu::sort`,
//! `shaders/gpu/radix_sort.wgsl`), on only the bits the cell count needs (gather path).

use crate::gpu::scan::Scan;
use crate::gpu::sort::{RadixSort, SortBuffers};
use crate::gpu::Executor;

use super::{BindAt, Bound, Extent, Pass, Sorted, Step};

pub(crate) struct SortCells {
    sort: RadixSort,
    scan: Scan,
}

impl SortCells {
    pub fn new(device: &wgpu::Device, executor: Executor) -> Self {
        SortCells {
            sort: RadixSort::new(device, executor),
            scan: Scan::new(device),
        }
    }
}

impl Pass<Step> for SortCells {
    fn name(&self) -> &'static str {
        "sort"
    }

    /// The sort's plan for the prepared keys; the passes bound after it read the sorted
    /// pairs from where the plan leaves them.
    fn bind(&self, device: &wgpu::Device, at: &mut BindAt) -> Bound {
        let b = at.b;
        let buffers = SortBuffers {
            count: &b.key_count,
            keys: &b.keys,
            values: &b.values,
            keys_alt: &b.keys_alt,
            values_alt: &b.values_alt,
        };
        let plan = self.sort.plan(
            device,
            &self.scan,
            &buffers,
            at.particles.max(1),
            at.sort_bits,
        );
        at.sorted = Some(Sorted::after(b, &plan));
        Bound::Sort(plan)
    }

    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, _at: &Extent) {
        self.sort.record(c, &self.scan, bound.sort_plan());
    }
}
