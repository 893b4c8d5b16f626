//! The GPU tile rasteriser (docs/method.md §7), one WGSL file and one Rust type per pass:
//!
//! 1. [`passes::Project`] — project every Gaussian, SH colour, tile rectangle, depth key;
//! 2. [`passes::DepthSort`] — sort all Gaussians by depth (32-bit keys);
//! 3. [`passes::TileKeys`] — count, scan and emit one (tile, Gaussian) pair per touched tile,
//!    in depth order;
//! 4. [`passes::TileSort`] — stable sort of the pairs by tile (only the bits the tile count
//!    needs);
//! 5. [`passes::TileRanges`] — start/end of each tile's run;
//! 6. [`passes::Rasterize`] — front-to-back compositing per 16×16 tile.
//!
//! With lighting set ([`GpuRenderer::set_lighting`], [`lighting`]), the shadow volume is
//! built and every visible Gaussian's colour relit right after pass 1.
//!
//! Each pass is a [`Pass`] of the [`Render`] family (`gpu::pass`, the shape the step's
//! passes share); [`GpuRenderer::passes`] lists them in this order. They are bound when
//! the buffers change, and all passes of a frame go into one command buffer; the image and
//! a few counters are read back at the end. Buffers are kept between frames and grown only
//! when needed.

mod buffers;
pub mod layout;
pub mod lighting;
pub(crate) mod passes;
mod state;

use std::sync::Arc;

use glam::Vec3;

pub use crate::gpu::buffers::read_buffer;
use crate::gpu::buffers::storage;
use crate::gpu::pages::{PageRanges, Pages};
use crate::gpu::pass::{bind_in_order, clear_all, Bound, Family, Pass};
use crate::gpu::ranges::Ranges;
use crate::gpu::scan::Scan;
use crate::gpu::sort::RadixSort;
use crate::gpu::stages;
use crate::gpu::wgsl::Module;
use crate::gpu::{Executor, GpuContext, GpuError};
use crate::relight::PointLight;
use crate::render::{Camera, Splats};
use layout::{Frame, GaussianIn, Stats, SH_WORDS, TILE};
use lighting::{Lighting, LightingSetup};

/// The render passes' shared declarations (mirrored by `layout.rs`).
pub(crate) static COMMON: Module = Module {
    name: "common",
    text: include_str!("../../../shaders/common.wgsl"),
    needs: &[],
};
/// Real spherical harmonics.
pub(crate) static SH: Module = Module {
    name: "sh",
    text: include_str!("../../../shaders/sh.wgsl"),
    needs: &[],
};

/// The family of the renderer's passes.
pub(crate) struct Render;

impl Family for Render {
    type Inputs<'a> = FrameInputs<'a>;
    type Extent<'a> = FrameExtent<'a>;
}

/// What a render pass binds over.
pub(crate) struct FrameInputs<'a> {
    /// The frame's constants (`Frame` of `common.wgsl`).
    pub frame: &'a wgpu::Buffer,
    /// The frame's counters (`Stats`).
    pub stats: &'a wgpu::Buffer,
    pub s: &'a SplatBuffers,
    pub f: &'a FrameBuffers,
    pub lighting: Option<&'a Lighting>,
    /// Where the depth sort leaves the Gaussians' order, once it is bound.
    pub depth_order: Option<&'a wgpu::Buffer>,
    /// Where the tile sort leaves the pairs, once it is bound.
    pub tile_pairs: Option<TilePairs<'a>>,
}

/// The (tile, Gaussian) pairs as the tile sort leaves them.
pub(crate) struct TilePairs<'a> {
    pub keys: &'a wgpu::Buffer,
    pub values: &'a wgpu::Buffer,
    /// Each tile's first slot, where the sort keeps them (`SortPlan::key_starts`).
    pub key_starts: Option<wgpu::Buffer>,
}

impl<'a> FrameInputs<'a> {
    pub fn depth_order(&self) -> &'a wgpu::Buffer {
        self.depth_order
            .expect("a pass that reads the depth order is bound before the depth sort")
    }

    pub fn tile_pairs(&self) -> &TilePairs<'a> {
        self.tile_pairs
            .as_ref()
            .expect("a pass that reads the sorted pairs is bound before the tile sort")
    }

    pub fn lighting(&self) -> &'a Lighting {
        self.lighting.expect("a lighting pass without lighting")
    }

    /// The projections' page windows, in page order.
    pub fn projected(&self) -> Vec<wgpu::BufferBinding<'a>> {
        let pages = &self.s.pages.pages;
        (0..pages.count)
            .map(|i| pages.window(&self.s.projected, i, PROJECTED_BYTES))
            .collect()
    }
}

/// What a render pass dispatches over.
pub(crate) struct FrameExtent<'a> {
    /// The frame's counters.
    pub stats: &'a wgpu::Buffer,
    pub s: &'a SplatBuffers,
    pub f: &'a FrameBuffers,
    pub lighting: Option<&'a Lighting>,
    /// Gaussians uploaded.
    pub count: u32,
    /// Tiles across and down.
    pub tiles: (u32, u32),
}

impl<'a> FrameExtent<'a> {
    pub fn lighting(&self) -> &'a Lighting {
        self.lighting.expect("a lighting pass without lighting")
    }
}

/// A rendered frame: RGBA8, row-major, plus what the passes counted.
#[derive(Clone, Debug)]
pub struct RenderedImage {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
    /// The alpha and depth passes, when the renderer makes them
    /// ([`GpuRenderer::set_passes`]).
    pub passes: Option<PassImages>,
    pub stats: Stats,
    /// Tile pairs dropped because they exceeded the buffer limit (farthest Gaussians).
    pub dropped_intersections: u32,
}

/// The passes of a frame beside its colour (docs/method.md §7.7), row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct PassImages {
    /// RGBA8: the straight (not premultiplied) colour and α = 1 − T, T the transmittance
    /// left after every Gaussian of the pixel.
    pub alpha: Vec<u8>,
    /// The alpha-weighted mean camera-space depth of the Gaussians' centres, Σ w_i z_i / α
    /// (w_i = α_i T_i, each Gaussian's share of the pixel), +∞ where α = 0.
    pub depth: Vec<f32>,
    /// The normal pass, when asked for: the direction of Σ w_i n_i, n_i each Gaussian's
    /// camera-space normal turned towards the camera (its shading normal when lit, else its
    /// axis of least extent), (0, 0, 0) where there is none.
    pub normal: Option<Vec<[f32; 3]>>,
    /// The id pass, when asked for: the id of the Gaussian with the largest w_i (the first
    /// of equals), 0 where nothing was drawn.
    pub id: Option<Vec<u16>>,
}

/// Wall-clock timings of one frame, in milliseconds.
#[derive(Clone, Debug, Default)]
pub struct FrameTimings {
    /// Recording + GPU execution of all render passes (until the GPU is idle).
    pub render_ms: f64,
    /// Copy to the readback buffer, map, and copy out.
    pub readback_ms: f64,
    /// Per pass, when [`GpuRenderer::profile_passes`] is on.
    pub passes: Vec<(&'static str, f64)>,
}

/// Buffers that depend on the number of Gaussians.
pub(crate) struct SplatBuffers {
    count: u32,
    sh_degree: u32,
    gaussians: wgpu::Buffer,
    sh_words: wgpu::Buffer,
    projected: wgpu::Buffer,
    tile_rects: wgpu::Buffer,
    depth_keys: wgpu::Buffer,
    depth_order: wgpu::Buffer,
    depth_keys_alt: wgpu::Buffer,
    depth_order_alt: wgpu::Buffer,
    offsets: wgpu::Buffer,
    depth_count: wgpu::Buffer,
    /// The id pass's ids, two 16-bit ids a word ([`GpuRenderer::set_ids`]).
    ids: wgpu::Buffer,
    /// How the per-Gaussian records split into pages (`gpu::pages`): the Gaussians, SH and
    /// projections are projected page by page and read back from every page.
    pages: PageRanges,
}

/// Buffers that depend on the image size and the tile-pair capacity.
pub(crate) struct FrameBuffers {
    width: u32,
    height: u32,
    capacity: u32,
    tile_keys: wgpu::Buffer,
    tile_values: wgpu::Buffer,
    tile_keys_alt: wgpu::Buffer,
    tile_values_alt: wgpu::Buffer,
    key_count: wgpu::Buffer,
    ranges: wgpu::Buffer,
    image: wgpu::Buffer,
    readback: wgpu::Buffer,
    stats_readback: wgpu::Buffer,
}

pub struct GpuRenderer {
    project: passes::Project,
    depth_sort: passes::DepthSort,
    tile_keys: passes::TileKeys,
    tile_sort: passes::TileSort,
    tile_ranges: passes::TileRanges,
    rasterize: passes::Rasterize,
    frame: wgpu::Buffer,
    stats: wgpu::Buffer,
    splats: Option<SplatBuffers>,
    frame_buffers: Option<FrameBuffers>,
    /// The bind groups of [`passes`](Self::passes) over the current buffers, one per pass.
    bound: Option<Vec<Bound>>,
    warned: WarnedOnce,
    /// Upper bound on the tile pairs of a frame, below what the adapter allows.
    pair_limit: Option<u32>,
    /// Upper bound on the Gaussians per page, below what a binding holds.
    page_limit: Option<u32>,
    profile: bool,
    lighting: Option<Lighting>,
    /// The workgroup shapes the sort and the rasteriser were built for.
    executor: Executor,
    /// The passes frames carry beside the colour ([`PassImages`]).
    passes: PassSet,
}

/// Which passes a frame carries beside its colour (docs/method.md §7.7). Alpha and depth
/// come whenever any pass is on (one accumulator more than the colour); the normal and id
/// passes each add theirs only when asked for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PassSet {
    pub alpha_depth: bool,
    pub normal: bool,
    pub id: bool,
}

impl PassSet {
    /// The image plane where the normal pass's three planes start.
    pub const NORMAL_PLANE: u32 = 3;

    /// Alpha and depth only.
    pub const ALPHA_DEPTH: PassSet = PassSet {
        alpha_depth: true,
        normal: false,
        id: false,
    };

    /// Every pass.
    pub const ALL: PassSet = PassSet {
        alpha_depth: true,
        normal: true,
        id: true,
    };

    pub fn any(self) -> bool {
        self.alpha_depth || self.normal || self.id
    }

    /// The image's planes of one u32 a pixel: the colour; with any pass the straight RGBA
    /// and the depth; the normal's x, y, z; the id.
    pub fn planes(self) -> u32 {
        1 + 2 * u32::from(self.any()) + 3 * u32::from(self.normal) + u32::from(self.id)
    }

    /// The image plane of the id pass.
    pub fn id_plane(self) -> u32 {
        Self::NORMAL_PLANE + 3 * u32::from(self.normal)
    }
}

#[derive(Default)]
struct WarnedOnce {
    nonfinite: bool,
    degenerate: bool,
    overflow: bool,
}

/// Bytes per Gaussian of the per-Gaussian arrays (their page windows).
const GAUSSIAN_BYTES: u64 = std::mem::size_of::<GaussianIn>() as u64;
const SH_BYTES: u64 = SH_WORDS as u64 * 4;
const PROJECTED_BYTES: u64 = std::mem::size_of::<layout::Projected>() as u64;

/// The most pages of projections the tile-key and rasterize passes can bind: at most 8,
/// and what the adapter's storage bindings per stage leave after their other 8.
fn max_pages(gpu: &GpuContext) -> u32 {
    gpu.limits
        .max_storage_buffers_per_shader_stage
        .saturating_sub(8)
        .clamp(1, 8)
}

/// `what` given more pages of Gaussians than it reads (the renderer: [`max_pages`]; the
/// lighting passes: one).
fn too_many_pages_for(what: &'static str, gpu: &GpuContext, pages: Pages) -> GpuError {
    GpuError::TooManyPages {
        what,
        gaussians: pages.total,
        pages: pages.count,
        size: pages.size,
        max: if what == "the renderer" {
            max_pages(gpu)
        } else {
            1
        },
        adapter: gpu.describe(),
    }
}

fn tile_bits(tiles: u32) -> u32 {
    32 - tiles.saturating_sub(1).leading_zeros()
}

impl GpuRenderer {
    pub fn new(gpu: &GpuContext) -> GpuRenderer {
        GpuRenderer::with_executor(gpu, gpu.executor())
    }

    /// With the workgroup shapes and the sort of `executor` instead of the adapter's own
    /// (the images are the same; tests check that on one adapter).
    pub fn with_executor(gpu: &GpuContext, executor: Executor) -> GpuRenderer {
        let device = &gpu.device;
        let sort = Arc::new(RadixSort::new(device, executor));
        let scan = Arc::new(Scan::new(device));
        GpuRenderer {
            project: passes::Project::new(device, PassSet::default()),
            depth_sort: passes::DepthSort {
                sort: sort.clone(),
                scan: scan.clone(),
            },
            tile_keys: passes::TileKeys::new(device, 1, scan.clone()),
            tile_sort: passes::TileSort { sort, scan },
            tile_ranges: passes::TileRanges(Ranges::new(device)),
            rasterize: passes::Rasterize::new(gpu, 1, executor, PassSet::default()),
            frame: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("frame"),
                size: std::mem::size_of::<Frame>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            stats: storage(
                device,
                "stats",
                std::mem::size_of::<Stats>() as u64,
                wgpu::BufferUsages::COPY_SRC,
            ),
            splats: None,
            frame_buffers: None,
            bound: None,
            warned: WarnedOnce::default(),
            pair_limit: None,
            page_limit: None,
            profile: false,
            lighting: None,
            executor,
            passes: PassSet::default(),
        }
    }

    /// Render these passes with every frame from now on (none: stop): the rasteriser
    /// writes them beside the colour from the same compositing.
    pub fn set_passes(&mut self, gpu: &GpuContext, passes: PassSet) {
        if passes == self.passes {
            return;
        }
        self.passes = passes;
        let pages = self.splats.as_ref().map_or(1, |s| s.pages.pages.count);
        self.project = passes::Project::new(&gpu.device, passes);
        self.rasterize = passes::Rasterize::new(gpu, pages, self.executor, passes);
        self.frame_buffers = None;
        self.bound = None;
    }

    /// Time each pass on its own (submit and wait after each): for benchmarks only, as it
    /// removes the overlap between passes.
    pub fn profile_passes(&mut self, on: bool) {
        self.profile = on;
    }

    /// Cap the (tile, Gaussian) pairs of a frame below the adapter's buffer limit, to bound
    /// memory. Past the cap the farthest Gaussians are dropped, with a warning.
    pub fn limit_tile_pairs(&mut self, max: u32) {
        self.pair_limit = Some(max.max(1));
    }

    /// Split the Gaussians into pages of at most `records` (a power of two of at least 64)
    /// from the next upload, as a binding limit would: for tests of the paged passes.
    pub fn limit_page_size(&mut self, records: u32) {
        self.page_limit = Some(records);
    }

    /// Render the uploaded Gaussians from `camera` over `background`.
    pub fn render(
        &mut self,
        gpu: &GpuContext,
        camera: &Camera,
        background: Vec3,
    ) -> Result<RenderedImage, GpuError> {
        self.render_timed(gpu, camera, background)
            .map(|(image, _)| image)
    }

    /// As [`render`](Self::render), also returning wall-clock timings of the passes and
    /// of the readback.
    pub fn render_timed(
        &mut self,
        gpu: &GpuContext,
        camera: &Camera,
        background: Vec3,
    ) -> Result<(RenderedImage, FrameTimings), GpuError> {
        if self.splats.is_none() {
            self.upload(gpu, &Splats::default())?;
        }
        let count = self.splats.as_ref().map_or(0, |s| s.count);
        // Start from a guess of 8 tiles per Gaussian; grow to what a frame needed.
        let mut capacity = self
            .frame_buffers
            .as_ref()
            .map_or(0, |f| f.capacity)
            .max(count.saturating_mul(8))
            .max(1 << 16);
        let max_capacity = (gpu.max_binding() / 4).min(u64::from(u32::MAX)) as u32;
        let max_capacity = self
            .pair_limit
            .map_or(max_capacity, |l| l.min(max_capacity));
        capacity = capacity.min(max_capacity);
        loop {
            self.ensure_frame_buffers(gpu, camera.width, camera.height, capacity)?;
            self.ensure_bound(gpu);
            let (image, timings) = self.render_once(gpu, camera, background)?;
            let wanted = image.stats.intersections;
            let cap = self.frame_buffers.as_ref().map_or(0, |f| f.capacity);
            if wanted <= cap || cap >= max_capacity {
                let mut image = image;
                image.dropped_intersections = wanted.saturating_sub(cap);
                self.warn(&image);
                return Ok((image, timings));
            }
            // Too many pairs for the buffers: grow with headroom and render again.
            capacity = (u64::from(wanted) * 5 / 4).min(u64::from(max_capacity)) as u32;
        }
    }

    fn warn(&mut self, image: &RenderedImage) {
        let s = image.stats;
        if s.skipped_nonfinite > 0 && !self.warned.nonfinite {
            self.warned.nonfinite = true;
            log::warn!(
                "{} Gaussians skipped: NaN or Inf in mean, covariance or rotation (warned once)",
                s.skipped_nonfinite
            );
        }
        if s.skipped_degenerate > 0 && !self.warned.degenerate {
            self.warned.degenerate = true;
            log::warn!(
                "{} Gaussians skipped: degenerate projected covariance (warned once)",
                s.skipped_degenerate
            );
        }
        if image.dropped_intersections > 0 && !self.warned.overflow {
            self.warned.overflow = true;
            log::warn!(
                "{} of {} tile intersections exceed this adapter's buffer limit: the farthest Gaussians were dropped (warned once)",
                image.dropped_intersections,
                s.intersections
            );
        }
    }

    /// The passes of a frame, in order (the module's documentation).
    fn passes(&self) -> Vec<&dyn Pass<Render>> {
        let mut list: Vec<&dyn Pass<Render>> = vec![&self.project];
        if let Some(l) = &self.lighting {
            if l.grid.is_some() {
                list.push(&l.shadows);
            }
            list.push(&l.shade);
        }
        list.extend([
            &self.depth_sort as &dyn Pass<Render>,
            &self.tile_keys,
            &self.tile_sort,
            &self.tile_ranges,
            &self.rasterize,
        ]);
        list
    }

    /// Bind the passes over the current buffers, unless they are bound.
    fn ensure_bound(&mut self, gpu: &GpuContext) {
        if self.bound.is_some() {
            return;
        }
        let inputs = FrameInputs {
            frame: &self.frame,
            stats: &self.stats,
            s: self.splats.as_ref().expect("upload() before render()"),
            f: self.frame_buffers.as_ref().expect("frame buffers"),
            lighting: self.lighting.as_ref(),
            depth_order: None,
            tile_pairs: None,
        };
        self.bound = Some(bind_in_order(&self.passes(), &gpu.device, inputs));
    }

    fn render_once(
        &self,
        gpu: &GpuContext,
        camera: &Camera,
        background: Vec3,
    ) -> Result<(RenderedImage, FrameTimings), GpuError> {
        let start = std::time::Instant::now();
        let s = self.splats.as_ref().expect("upload() before render()");
        let f = self.frame_buffers.as_ref().expect("frame buffers");
        let bound = self.bound.as_ref().expect("bound passes");
        let mut frame = Frame::new(camera, background, s.count, s.sh_degree, f.capacity);
        frame.page_shift = s.pages.pages.shift();
        gpu.queue
            .write_buffer(&self.frame, 0, bytemuck::bytes_of(&frame));
        if let Some(l) = &self.lighting {
            gpu.queue
                .write_buffer(&l.lights, 0, bytemuck::bytes_of(&l.uniforms()));
        }
        let at = FrameExtent {
            stats: &self.stats,
            s,
            f,
            lighting: self.lighting.as_ref(),
            count: s.count,
            tiles: (frame.tiles_x, frame.tiles_y),
        };
        let passes = self.passes();
        let stages = crate::gpu::pass::stages(&passes, bound, &at, |_| true);
        let mut enc = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("render"),
            });
        clear_all(&passes, &mut enc, &at);
        // All stages go into one compute pass (each dispatch is its own synchronisation
        // scope) unless passes are profiled one by one.
        let mut timed = Vec::new();
        if self.profile {
            gpu.queue.submit([enc.finish()]);
            timed = stages::profile(gpu, &stages)?;
        } else {
            stages::record(&mut enc, "render", &stages);
            gpu.queue.submit([enc.finish()]);
        }
        gpu.wait()?;
        let render_ms = start.elapsed().as_secs_f64() * 1e3;

        let start = std::time::Instant::now();
        let (mut rgba, stats) = self.read_image(gpu, f)?;
        let readback_ms = start.elapsed().as_secs_f64() * 1e3;
        let plane = (f.width * f.height * 4) as usize;
        let set = self.passes;
        let floats = |k: u32| -> Vec<f32> {
            let k = k as usize;
            bytemuck::pod_collect_to_vec(&rgba[k * plane..(k + 1) * plane])
        };
        let passes = set.any().then(|| PassImages {
            alpha: rgba[plane..2 * plane].to_vec(),
            depth: floats(2),
            normal: set.normal.then(|| {
                let (x, y, z) = (
                    floats(PassSet::NORMAL_PLANE),
                    floats(PassSet::NORMAL_PLANE + 1),
                    floats(PassSet::NORMAL_PLANE + 2),
                );
                (0..x.len()).map(|i| [x[i], y[i], z[i]]).collect()
            }),
            id: set.id.then(|| {
                let k = set.id_plane() as usize;
                rgba[k * plane..(k + 1) * plane]
                    .chunks_exact(4)
                    .map(|w| {
                        u16::try_from(u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
                            .unwrap_or(u16::MAX)
                    })
                    .collect()
            }),
        });
        rgba.truncate(plane);
        Ok((
            RenderedImage {
                width: f.width,
                height: f.height,
                rgba,
                passes,
                stats,
                dropped_intersections: 0,
            },
            FrameTimings {
                render_ms,
                readback_ms,
                passes: timed,
            },
        ))
    }

    /// Copy the image and the frame's counters back to the CPU.
    fn read_image(&self, gpu: &GpuContext, f: &FrameBuffers) -> Result<(Vec<u8>, Stats), GpuError> {
        let mut enc = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("readback"),
            });
        enc.copy_buffer_to_buffer(&f.image, 0, &f.readback, 0, Some(f.readback.size()));
        enc.copy_buffer_to_buffer(
            &self.stats,
            0,
            &f.stats_readback,
            0,
            Some(f.stats_readback.size()),
        );
        gpu.queue.submit([enc.finish()]);
        let rgba = read_buffer(gpu, &f.readback)?;
        let stats_bytes = read_buffer(gpu, &f.stats_readback)?;
        let stats: Stats = *bytemuck::from_bytes(&stats_bytes[..std::mem::size_of::<Stats>()]);
        Ok((rgba, stats))
    }
}
