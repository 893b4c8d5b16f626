//! The renderer's own passes (the sort, scan and ranges are GPU primitives in `crate::gpu`). Each type owns the
//! pipeline(s) of one WGSL file under `shaders/render/`.

use super::{COMMON, SH};
use crate::gpu::pages::wgsl_paged_reader;
use crate::gpu::wgsl::Source;
use crate::gpu::{Executor, GpuContext, Kernel, Shader};

/// The first binding number of the projected Gaussians' pages in the passes that read
/// them in any order (tile keys, rasterize), after their other bindings; they are bound by
/// their names `projected_0` … `projected_{pages-1}` ([`page_var`](crate::gpu::pages::page_var)).
pub const PROJECTED_PAGES_AT: u32 = 8;

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
    pub fn new(device: &wgpu::Device) -> Project {
        let src = Source::new()
            .module(&COMMON)
            .module(&SH)
            .pass(include_str!("../../../shaders/render/project.wgsl"));
        Project {
            kernel: Kernel::new(device, "project", &src, "main"),
        }
    }
}

/// `shaders/render/tile_keys.wgsl`: tile counts in depth order, their total, the pairs;
/// reading the projections from `pages` pages.
pub struct TileKeys {
    pub gather: Kernel,
    pub total: Kernel,
    pub emit: Kernel,
    pub pages: u32,
}

impl TileKeys {
    pub fn new(device: &wgpu::Device, pages: u32) -> TileKeys {
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
        }
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
    /// For `executor`'s workgroup shape, with the reads that shape allows on `gpu`.
    pub fn new(gpu: &GpuContext, pages: u32, executor: Executor) -> Rasterize {
        let reads = SplatReads::for_adapter(gpu, executor);
        let src = Source::new()
            .define("QUADS", rasterize_quads(executor))
            .module(&COMMON)
            .generated(reads.source().to_string())
            .generated(projected_reader(pages))
            .pass(include_str!("../../../shaders/render/rasterize.wgsl"));
        Rasterize {
            kernel: Kernel::new(&gpu.device, "rasterize", &src, "main"),
        }
    }
}
