//! The normal refit's passes (`gpu::pass`, the shape of the step's and the renderer's), in
//! the order they run: [`HashKeys`], [`CellSort`], [`CellRanges`], [`CellPoints`], [`Pca`].

use crate::gpu::pass::{Bound, Family, Pass};
use crate::gpu::ranges::Ranges;
use crate::gpu::scan::Scan;
use crate::gpu::sort::{RadixSort, SortBuffers};
use crate::gpu::{Executor, Kernel};

use super::source;

/// The family of the refit's passes.
pub(crate) struct Refit;

impl Family for Refit {
    type Inputs<'a> = RefitInputs<'a>;
    type Extent<'a> = RefitExtent<'a>;
}

/// The refit's own buffers: its constants and object table, the hash grid's keys and
/// values (and the sort's alternates), each cell's run, and the centres in cell order.
pub(crate) struct RefitBuffers {
    pub params: wgpu::Buffer,
    pub object_of: wgpu::Buffer,
    pub objects: wgpu::Buffer,
    pub keys: wgpu::Buffer,
    pub values: wgpu::Buffer,
    pub keys_alt: wgpu::Buffer,
    pub values_alt: wgpu::Buffer,
    pub key_count: wgpu::Buffer,
    pub cell_ranges: wgpu::Buffer,
    pub points: wgpu::Buffer,
}

/// What a refit pass binds over: its buffers, the renderer's Gaussians and shading
/// records, and (once the sort is bound) where it left the sorted keys and indices.
pub(crate) struct RefitInputs<'a> {
    pub b: &'a RefitBuffers,
    pub gaussians: &'a wgpu::Buffer,
    pub shading: &'a wgpu::Buffer,
    /// Gaussians refitted, and hash-grid cells.
    pub count: u32,
    pub cells: u32,
    pub sorted: Option<(&'a wgpu::Buffer, &'a wgpu::Buffer)>,
}

impl<'a> RefitInputs<'a> {
    fn sorted(&self) -> (&'a wgpu::Buffer, &'a wgpu::Buffer) {
        self.sorted
            .expect("a pass that reads the sorted Gaussians is bound before the sort")
    }
}

/// What a refit pass dispatches over.
pub(crate) struct RefitExtent<'a> {
    pub b: &'a RefitBuffers,
    /// Gaussians refitted.
    pub count: u32,
}

impl RefitExtent<'_> {
    fn groups(&self) -> u32 {
        self.count.div_ceil(256)
    }
}

fn kernel(device: &wgpu::Device, label: &'static str, pass: &str) -> Kernel {
    Kernel::new(device, label, &source(pass), "main")
}

/// `shaders/relight/normals_keys.wgsl`: each Gaussian's hash-grid cell as its sort key.
pub(crate) struct HashKeys(Kernel);

impl HashKeys {
    pub fn new(device: &wgpu::Device) -> HashKeys {
        HashKeys(kernel(
            device,
            "normals keys",
            include_str!("../../../shaders/relight/normals_keys.wgsl"),
        ))
    }
}

impl Pass<Refit> for HashKeys {
    fn name(&self) -> &'static str {
        "normals keys"
    }

    fn bind(&self, device: &wgpu::Device, at: &mut RefitInputs) -> Bound {
        let b = at.b;
        Bound::Whole(self.0.bind_named(
            device,
            &[
                ("params", &b.params),
                ("gaussians", at.gaussians),
                ("keys", &b.keys),
                ("values", &b.values),
            ],
        ))
    }

    /// One invocation per Gaussian.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &RefitExtent) {
        self.0.dispatch(c, bound.whole(), at.groups());
    }
}

/// The Gaussians sorted by cell with the shared radix sort, on the bits the cells need.
pub(crate) struct CellSort {
    sort: RadixSort,
    scan: Scan,
}

impl CellSort {
    pub fn new(device: &wgpu::Device, executor: Executor) -> CellSort {
        CellSort {
            sort: RadixSort::new(device, executor),
            scan: Scan::new(device),
        }
    }
}

impl Pass<Refit> for CellSort {
    fn name(&self) -> &'static str {
        "normals sort"
    }

    /// Its plan; the passes bound after it read the pairs from where the plan leaves them.
    fn bind(&self, device: &wgpu::Device, at: &mut RefitInputs) -> Bound {
        let b = at.b;
        let plan = self.sort.plan(
            device,
            &self.scan,
            &SortBuffers {
                count: &b.key_count,
                keys: &b.keys,
                values: &b.values,
                keys_alt: &b.keys_alt,
                values_alt: &b.values_alt,
            },
            at.count.max(1),
            32 - at.cells.saturating_sub(1).leading_zeros().min(31),
        );
        at.sorted = Some(if plan.result_in_alternates() {
            (&b.keys_alt, &b.values_alt)
        } else {
            (&b.keys, &b.values)
        });
        Bound::Sort(plan)
    }

    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, _at: &RefitExtent) {
        self.sort.record(c, &self.scan, bound.sort_plan());
    }
}

/// Each cell's run of sorted Gaussians with the shared key ranges.
pub(crate) struct CellRanges(Ranges);

impl CellRanges {
    pub fn new(device: &wgpu::Device) -> CellRanges {
        CellRanges(Ranges::new(device))
    }
}

impl Pass<Refit> for CellRanges {
    fn name(&self) -> &'static str {
        "normals ranges"
    }

    fn bind(&self, device: &wgpu::Device, at: &mut RefitInputs) -> Bound {
        let b = at.b;
        let (sorted_keys, _) = at.sorted();
        Bound::Whole(
            self.0
                .bind(device, &b.key_count, sorted_keys, &b.cell_ranges),
        )
    }

    /// Cells no Gaussian falls in keep an empty run.
    fn clear(&self, enc: &mut wgpu::CommandEncoder, at: &RefitExtent) {
        enc.clear_buffer(&at.b.cell_ranges, 0, None);
    }

    /// One invocation per sorted Gaussian.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &RefitExtent) {
        self.0.kernel.dispatch(c, bound.whole(), at.groups());
    }
}

/// `shaders/relight/normals_points.wgsl`: the centres copied into cell order.
pub(crate) struct CellPoints(Kernel);

impl CellPoints {
    pub fn new(device: &wgpu::Device) -> CellPoints {
        CellPoints(kernel(
            device,
            "normals points",
            include_str!("../../../shaders/relight/normals_points.wgsl"),
        ))
    }
}

impl Pass<Refit> for CellPoints {
    fn name(&self) -> &'static str {
        "normals points"
    }

    fn bind(&self, device: &wgpu::Device, at: &mut RefitInputs) -> Bound {
        let b = at.b;
        let (_, sorted_values) = at.sorted();
        Bound::Whole(self.0.bind_named(
            device,
            &[
                ("params", &b.params),
                ("gaussians", at.gaussians),
                ("sorted_values", sorted_values),
                ("object_of", &b.object_of),
                ("points", &b.points),
            ],
        ))
    }

    /// One invocation per Gaussian.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &RefitExtent) {
        self.0.dispatch(c, bound.whole(), at.groups());
    }
}

/// `shaders/relight/normals_pca.wgsl`: each Gaussian's normal refitted from its object's
/// centres within a radius, into the renderer's shading records.
pub(crate) struct Pca(Kernel);

impl Pca {
    pub fn new(device: &wgpu::Device) -> Pca {
        Pca(kernel(
            device,
            "normals pca",
            include_str!("../../../shaders/relight/normals_pca.wgsl"),
        ))
    }
}

impl Pass<Refit> for Pca {
    fn name(&self) -> &'static str {
        "normals pca"
    }

    fn bind(&self, device: &wgpu::Device, at: &mut RefitInputs) -> Bound {
        let b = at.b;
        let (_, sorted_values) = at.sorted();
        Bound::Whole(self.0.bind_named(
            device,
            &[
                ("params", &b.params),
                ("ranges", &b.cell_ranges),
                ("sorted_values", sorted_values),
                ("points", &b.points),
                ("objects", &b.objects),
                ("shading", at.shading),
            ],
        ))
    }

    /// One invocation per Gaussian.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &RefitExtent) {
        self.0.dispatch(c, bound.whole(), at.groups());
    }
}
