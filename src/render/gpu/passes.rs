//! The renderer's passes, in the order of a frame (the lighting passes, which run after
//! the projection, are in `lighting/passes.rs`). Each is a [`Pass`] of the [`Render`]
//! family and owns the pipeline(s) of one WGSL file under `shaders/render/`, or wraps a
//! GPU primitive of `crate::gpu` (the radix sort, the scan, the key ranges).

use std::sync::Arc;

use super::{tile_bits, GAUSSIAN_BYTES, PROJECTED_BYTES, SH_BYTES, TILE};
use super::{FrameExtent, FrameInputs, Render, TilePairs};
use super::{PassSet, COMMON, SH};
use crate::gpu::pages::{page_var, wgsl_paged_reader};
use crate::gpu::pass::{Bound, Pass};
use crate::gpu::ranges::{Ranges, SortedKeys};
use crate::gpu::scan::Scan;
use crate::gpu::sort::{RadixSort, SortBuffers};
use crate::gpu::wgsl::Source;
use crate::gpu::{Executor, GpuContext, Kernel, Shader};

/// The first binding number of the projected Gaussians' pages in the passes that read
/// them in any order (tile keys, rasterize), after their other bindings; they are bound by
/// their names `projected_0` … `projected_{pages-1}` ([`page_var`]).
pub const PROJECTED_PAGES_AT: u32 = 8;

/// Bind `buffers` by name and the projections' pages as `projected_0`, `projected_1`, …
/// (the names [`projected_reader`] declares).
fn bind_with_pages(
    kernel: &Kernel,
    device: &wgpu::Device,
    buffers: &[(&str, &wgpu::Buffer)],
    projected: &[wgpu::BufferBinding],
) -> wgpu::BindGroup {
    let names: Vec<String> = (0..projected.len() as u32)
        .map(|k| page_var("projected", k))
        .collect();
    let mut parts: Vec<(&str, wgpu::BufferBinding)> = buffers
        .iter()
        .map(|(name, b)| (*name, b.as_entire_buffer_binding()))
        .collect();
    parts.extend(
        names
            .iter()
            .map(String::as_str)
            .zip(projected.iter().cloned()),
    );
    kernel.bind_named_parts(device, &parts)
}

fn projected_reader(pages: u32) -> String {
    wgsl_paged_reader(
        "projected",
        "Projected",
        PROJECTED_PAGES_AT,
        pages,
        "frame.page_shift",
    )
}

/// `shaders/render/project.wgsl`.
pub struct Project {
    pub kernel: Kernel,
}

impl Project {
    /// With `passes.normal`, also each Gaussian's camera-space normal; with `passes.id`,
    /// its id (`Projected`'s spare floats, common.wgsl).
    pub fn new(device: &wgpu::Device, passes: PassSet) -> Project {
        let src = Source::new()
            .define("NORMALS", passes.normal)
            .define("IDS", passes.id)
            .module(&COMMON)
            .module(&SH)
            .pass(include_str!("../../../shaders/render/project.wgsl"));
        Project {
            kernel: Kernel::new(device, "project", &src, "main"),
        }
    }

    /// Over page `i` of the Gaussians.
    fn bind_page(&self, device: &wgpu::Device, at: &FrameInputs, i: u32) -> wgpu::BindGroup {
        let s = at.s;
        let pages = &s.pages.pages;
        fn whole(b: &wgpu::Buffer) -> wgpu::BufferBinding<'_> {
            b.as_entire_buffer_binding()
        }
        self.kernel.bind_named_parts(
            device,
            &[
                ("frame", whole(at.frame)),
                ("gaussians", pages.window(&s.gaussians, i, GAUSSIAN_BYTES)),
                ("sh_words", pages.window(&s.sh_words, i, SH_BYTES)),
                ("projected", pages.window(&s.projected, i, PROJECTED_BYTES)),
                ("tile_rects", whole(&s.tile_rects)),
                ("depth_keys", whole(&s.depth_keys)),
                ("depth_order", whole(&s.depth_order)),
                ("stats", whole(at.stats)),
                ("page", s.pages.entry(i)),
                ("ids", whole(&s.ids)),
            ],
        )
    }
}

impl Pass<Render> for Project {
    fn name(&self) -> &'static str {
        "project"
    }

    fn bind(&self, device: &wgpu::Device, at: &mut FrameInputs) -> Bound {
        let pages = at.s.pages.pages.count;
        Bound::Pages((0..pages).map(|i| self.bind_page(device, at, i)).collect())
    }

    /// The frame's counters, which it and [`TileKeys`] add to.
    fn clear(&self, enc: &mut wgpu::CommandEncoder, at: &FrameExtent) {
        enc.clear_buffer(at.stats, 0, None);
    }

    /// One invocation per Gaussian of the page.
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &FrameExtent) {
        for (i, bind) in (0..).zip(bound.pages()) {
            let (_, n) = at.s.pages.pages.range(i);
            self.kernel.dispatch(c, bind, n.div_ceil(256));
        }
    }

    fn runs(&self, at: &FrameExtent) -> bool {
        at.count > 0
    }
}

/// The Gaussians sorted by depth (32-bit keys) with the shared radix sort.
pub struct DepthSort {
    pub sort: Arc<RadixSort>,
    pub scan: Arc<Scan>,
}

impl Pass<Render> for DepthSort {
    fn name(&self) -> &'static str {
        "depth sort"
    }

    /// Its plan; the passes bound after it read the order from where the plan leaves it.
    fn bind(&self, device: &wgpu::Device, at: &mut FrameInputs) -> Bound {
        let s = at.s;
        let plan = self.sort.plan(
            device,
            &self.scan,
            &SortBuffers {
                count: &s.depth_count,
                keys: &s.depth_keys,
                values: &s.depth_order,
                keys_alt: &s.depth_keys_alt,
                values_alt: &s.depth_order_alt,
            },
            s.count,
            32,
        );
        at.depth_order = Some(if plan.result_in_alternates() {
            &s.depth_order_alt
        } else {
            &s.depth_order
        });
        Bound::Sort(plan)
    }

    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, _at: &FrameExtent) {
        self.sort.record(c, &self.scan, bound.sort_plan());
    }

    fn runs(&self, at: &FrameExtent) -> bool {
        at.count > 0
    }
}

/// `shaders/render/tile_keys.wgsl`: tile counts in depth order, their total, the pairs;
/// reading the projections from `pages` pages.
pub struct TileKeys {
    pub gather: Kernel,
    pub total: Kernel,
    pub emit: Kernel,
    pub pages: u32,
    /// The scan of the tile counts into each Gaussian's first pair.
    pub scan: Arc<Scan>,
}

impl TileKeys {
    pub fn new(device: &wgpu::Device, pages: u32, scan: Arc<Scan>) -> TileKeys {
        let src = Source::new()
            .module(&COMMON)
            .generated(projected_reader(pages))
            .pass(include_str!("../../../shaders/render/tile_keys.wgsl"));
        let shader = Shader::new(device, "tile_keys", &src);
        TileKeys {
            gather: shader.kernel(device, "tile_keys gather_counts", "gather_counts"),
            total: shader.kernel(device, "tile_keys total", "total"),
            emit: shader.kernel(device, "tile_keys emit", "emit"),
            pages,
            scan,
        }
    }
}

impl Pass<Render> for TileKeys {
    fn name(&self) -> &'static str {
        "tile keys"
    }

    /// Its three kernels' bind groups and the scan's plan, in the order it records them.
    fn bind<'a>(&self, device: &wgpu::Device, at: &mut FrameInputs<'a>) -> Bound {
        let (s, f) = (at.s, at.f);
        let projected = at.projected();
        let reads = [
            ("frame", at.frame),
            ("tile_rects", &s.tile_rects),
            ("depth_order", at.depth_order()),
            ("offsets", &s.offsets),
        ];
        let with = |more: [(&'static str, &'a wgpu::Buffer); 2]| [reads.as_slice(), &more].concat();
        Bound::Parts(vec![
            Bound::Whole(bind_with_pages(&self.gather, device, &reads, &projected)),
            Bound::Scan(self.scan.plan(device, &s.offsets, s.count)),
            Bound::Whole(bind_with_pages(
                &self.total,
                device,
                &with([("key_count", &f.key_count), ("stats", at.stats)]),
                &projected,
            )),
            Bound::Whole(bind_with_pages(
                &self.emit,
                device,
                &with([("tile_keys", &f.tile_keys), ("tile_values", &f.tile_values)]),
                &projected,
            )),
        ])
    }

    /// The pair count, which the total pass writes in a frame with Gaussians.
    fn clear(&self, enc: &mut wgpu::CommandEncoder, at: &FrameExtent) {
        if at.count == 0 {
            enc.clear_buffer(&at.f.key_count, 0, None);
        }
    }

    /// One invocation per Gaussian (one for the total).
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &FrameExtent) {
        let [gather, scan, total, emit] = bound.parts() else {
            unreachable!("tile keys bound otherwise")
        };
        let groups = at.count.div_ceil(256);
        self.gather.dispatch(c, gather.whole(), groups);
        self.scan.record(c, scan.scan_plan());
        self.total.dispatch(c, total.whole(), 1);
        self.emit.dispatch(c, emit.whole(), groups);
    }

    fn runs(&self, at: &FrameExtent) -> bool {
        at.count > 0
    }
}

/// The (tile, Gaussian) pairs sorted by tile with the shared radix sort (stable, so each
/// tile's pairs stay in depth order), on only the bits the tile count needs.
pub struct TileSort {
    pub sort: Arc<RadixSort>,
    pub scan: Arc<Scan>,
}

impl Pass<Render> for TileSort {
    fn name(&self) -> &'static str {
        "tile sort"
    }

    /// Its plan; the passes bound after it read the pairs from where the plan leaves them.
    fn bind(&self, device: &wgpu::Device, at: &mut FrameInputs) -> Bound {
        let f = at.f;
        let tiles = f.width.div_ceil(TILE) * f.height.div_ceil(TILE);
        let plan = self.sort.plan(
            device,
            &self.scan,
            &SortBuffers {
                count: &f.key_count,
                keys: &f.tile_keys,
                values: &f.tile_values,
                keys_alt: &f.tile_keys_alt,
                values_alt: &f.tile_values_alt,
            },
            f.capacity,
            tile_bits(tiles),
        );
        let (keys, values) = if plan.result_in_alternates() {
            (&f.tile_keys_alt, &f.tile_values_alt)
        } else {
            (&f.tile_keys, &f.tile_values)
        };
        at.tile_pairs = Some(TilePairs {
            keys,
            values,
            key_starts: plan.key_starts().cloned(),
        });
        Bound::Sort(plan)
    }

    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, _at: &FrameExtent) {
        self.sort.record(c, &self.scan, bound.sort_plan());
    }

    fn runs(&self, at: &FrameExtent) -> bool {
        at.count > 0
    }
}

/// Each tile's run of sorted pairs with the shared key ranges (`gpu::ranges`).
pub struct TileRanges(pub Ranges);

impl Pass<Render> for TileRanges {
    fn name(&self) -> &'static str {
        "tile ranges"
    }

    fn bind(&self, device: &wgpu::Device, at: &mut FrameInputs) -> Bound {
        let f = at.f;
        let pairs = at.tile_pairs();
        let keys = SortedKeys {
            key_count: &f.key_count,
            sorted_keys: pairs.keys,
            key_starts: pairs.key_starts.as_ref(),
            capacity: f.capacity,
        };
        Bound::Ranges(self.0.after(device, &keys, &f.ranges))
    }

    /// Tiles no pair reaches keep an empty run (the rasteriser reads every tile's).
    fn clear(&self, enc: &mut wgpu::CommandEncoder, at: &FrameExtent) {
        enc.clear_buffer(&at.f.ranges, 0, None);
    }

    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, _at: &FrameExtent) {
        self.0.record(c, bound.ranges());
    }

    fn runs(&self, at: &FrameExtent) -> bool {
        at.count > 0
    }
}

/// `shaders/render/rasterize.wgsl`, reading the projections from `pages` pages.
pub struct Rasterize {
    pub kernel: Kernel,
}

/// Pixels each rasteriser invocation composites, in quads of four (`QUADS`): one quad on a
/// GPU (64 invocations per tile), two on a CPU driver (32), where fewer invocations
/// mean fewer SIMD vectors to switch between at each barrier and each Gaussian read from
/// workgroup memory serves more pixels.
pub fn rasterize_quads(executor: Executor) -> u32 {
    match executor {
        Executor::Gpu => 1,
        Executor::Cpu => 2,
    }
}

/// How the rasteriser's invocations read a Gaussian from the batch in workgroup memory
/// (`read_splat`, `shaders/render/splat_reads/`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SplatReads {
    /// Every invocation reads the whole Gaussian (`each.wgsl`).
    Each,
    /// Each lane of a subgroup reads one element and the subgroup broadcasts them
    /// (`spread.wgsl`): for CPU drivers, which read workgroup memory at a per-invocation
    /// index one lane and one element at a time.
    Spread,
}

impl SplatReads {
    /// `Spread` where a subgroup is exactly one 8×8 block's eight columns: the CPU shape
    /// (8-pixel columns) on an adapter whose subgroups are always 8 invocations
    /// (lavapipe, which groups consecutive invocations into one SIMD vector).
    pub fn for_adapter(gpu: &GpuContext, executor: Executor) -> SplatReads {
        if executor == Executor::Cpu && gpu.cpu_subgroups_of_eight() {
            SplatReads::Spread
        } else {
            SplatReads::Each
        }
    }

    fn source(self) -> &'static str {
        match self {
            SplatReads::Each => include_str!("../../../shaders/render/splat_reads/each.wgsl"),
            SplatReads::Spread => {
                include_str!("../../../shaders/render/splat_reads/spread.wgsl")
            }
        }
    }
}

impl Rasterize {
    /// For `executor`'s workgroup shape, with the reads that shape allows on `gpu`; with
    /// `passes`, also those planes of the image ([`PassSet::planes`]).
    pub fn new(gpu: &GpuContext, pages: u32, executor: Executor, passes: PassSet) -> Rasterize {
        let reads = SplatReads::for_adapter(gpu, executor);
        let src = Source::new()
            .define("QUADS", rasterize_quads(executor))
            .define("PASSES", passes.any())
            .define("NORMALS", passes.normal)
            .define("IDS", passes.id)
            .define("NORMAL_PLANE", PassSet::NORMAL_PLANE)
            .define("ID_PLANE", passes.id_plane())
            .module(&COMMON)
            .generated(reads.source().to_string())
            .generated(projected_reader(pages))
            .pass(include_str!("../../../shaders/render/rasterize.wgsl"));
        Rasterize {
            kernel: Kernel::new(&gpu.device, "rasterize", &src, "main"),
        }
    }
}

impl Pass<Render> for Rasterize {
    fn name(&self) -> &'static str {
        "rasterize"
    }

    fn bind(&self, device: &wgpu::Device, at: &mut FrameInputs) -> Bound {
        let f = at.f;
        Bound::Whole(bind_with_pages(
            &self.kernel,
            device,
            &[
                ("frame", at.frame),
                ("ranges", &f.ranges),
                ("tile_values", at.tile_pairs().values),
                ("image", &f.image),
            ],
            &at.projected(),
        ))
    }

    /// One workgroup per tile, in every frame (an empty one too: the background).
    fn record(&self, c: &mut wgpu::ComputePass, bound: &Bound, at: &FrameExtent) {
        let (x, y) = at.tiles;
        self.kernel.dispatch_2d(c, bound.whole(), x, y);
    }
}
