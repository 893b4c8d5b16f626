//! The passes of one explicit MPM step on the GPU (docs/method.md §2), one Rust type per
//! WGSL file under `shaders/sim/step/`, each owning its pipeline and binding its buffers
//! by the names its WGSL declares. One step, on the gather path (every adapter):
//!
//! 1. [`Prepare`] — per particle: base-cell sort key and the affine term
//!    m C − Δt V⁰ (4/Δx²) τ(F);
//! 2. [`RadixSort`] — particles by base cell (only the bits the cell count needs);
//! 3. [`Ranges`] — each cell's run of particles (the GPU primitive the renderer also uses
//!    for its tiles);
//! 4. [`MarkBlocks`], [`CompactBlocks`] — the blocks of 4³ nodes an occupied cell's
//!    stencils reach, listed with a pool slot each (the node passes run only there);
//! 5. with two-field separation (docs/method.md §4.9) [`DamageField`], [`DamageGradient`]
//!    and [`Ridge`] — the nodes' damage field, each particle's damage gradient and each
//!    node's ridge gradient, which split a node's particles into two fields;
//! 6. [`P2gGather`] — per node of the active blocks: gather mass and momentum from the
//!    27 cells whose stencils reach it (deterministic, no atomics; per field with
//!    separation), then the grid update (`grid_update.wgsl`: velocity, gravity, colliders,
//!    walls; with separation the fields' contact first);
//! 7. [`G2p`] — velocities, C, F, positions, the material's plasticity (each particle from
//!    its own field).
//!
//! On the scatter paths steps 2–5 are instead [`MarkParticles`] (each particle flags the
//! blocks of its stencil), [`CompactBlocks`], a scatter in which each particle adds to its
//! 27 nodes — [`P2gScatter`] with float atomics (where the adapter has them; the order of
//! the additions varies) or [`P2gFixed`] with integer atomics on fixed-point sums
//! (deterministic, every adapter) — and [`GridFromSums`] (the grid update on the active
//! blocks), and only the first step of a submission runs [`Prepare`]: that path's G2P
//! leaves the next step's affine term, so later steps need not re-read F, C and the
//! material for it. [`Passes::list`] is that algorithm; [`Passes::stages`] records it through the
//! same named stages the renderer uses (`gpu::stages`).

mod compact_blocks;
mod damage_field;
mod damage_gradient;
mod g2p;
mod grid_from_sums;
pub mod layout;
mod mark_blocks;
mod mark_particles;
mod p2g;
mod p2g_fixed;
mod p2g_scatter;
mod prepare;
mod ridge;

pub(crate) use compact_blocks::CompactBlocks;
pub(crate) use damage_field::DamageField;
pub(crate) use damage_gradient::DamageGradient;
pub(crate) use g2p::G2p;
pub(crate) use grid_from_sums::GridFromSums;
pub(crate) use mark_blocks::MarkBlocks;
pub(crate) use mark_particles::MarkParticles;
pub(crate) use p2g::P2gGather;
pub(crate) use p2g_fixed::P2gFixed;
pub(crate) use p2g_scatter::P2gScatter;
pub(crate) use prepare::Prepare;
pub(crate) use ridge::Ridge;

use crate::gpu::pages::PageRanges;
use crate::gpu::ranges::Ranges;
use crate::gpu::scan::Scan;
use crate::gpu::sort::{RadixSort, SortBuffers, SortPlan};
use crate::gpu::stages::Stage;
use crate::gpu::{Executor, Kernel};

/// Concatenated WGSL of a step pass: the per-particle math modules, the step's shared
/// declarations, the material models and their dispatch, then the pass.
pub(crate) fn source(pass: &str) -> String {
    [
        crate::sim::wgsl::library().as_str(),
        crate::sim::codes::step_wgsl().as_str(),
        include_str!("../../../shaders/sim/step/common.wgsl"),
        crate::sim::models::wgsl().as_str(),
        include_str!("../../../shaders/sim/step/grid_update.wgsl"),
        include_str!("../../../shaders/sim/step/separation.wgsl"),
        pass,
    ]
    .join("\n")
}

/// A node pass that gathers from the sorted particles: `node_gather.wgsl` (the cells'
/// runs, the active blocks, the walk over the 27 base cells), then the pass.
fn gather_source(pass: &str) -> String {
    [
        include_str!("../../../shaders/sim/step/node_gather.wgsl"),
        pass,
    ]
    .join("\n")
}

/// The bindings `node_gather.wgsl` declares, with the step constants and the block table
/// every node pass reads.
fn gather_bindings<'a>(
    b: &'a StepBuffers,
    sorted: &'a Sorted,
) -> [(&'static str, wgpu::BindingResource<'a>); 6] {
    [
        ("step", b.step.as_entire_binding()),
        ("ranges", b.ranges.as_entire_binding()),
        ("cell_values", sorted.values.as_entire_binding()),
        ("active_blocks", b.active_blocks.as_entire_binding()),
        ("block_args", b.block_args.as_entire_binding()),
        ("block_slot", b.block_slot.as_entire_binding()),
    ]
}

/// A step pass: its WGSL after the shared modules, entry point `main`.
fn step_kernel(device: &wgpu::Device, label: &'static str, pass: &str) -> Kernel {
    Kernel::new(device, label, &source(pass), "main")
}

/// The buffers of the step, named as the passes' WGSL names them where it can.
pub(crate) struct StepBuffers {
    pub step: wgpu::Buffer,
    pub x_mass: wgpu::Buffer,
    pub v_volume: wgpu::Buffer,
    pub deformation: wgpu::Buffer,
    pub affine_velocity: wgpu::Buffer,
    pub alpha: wgpu::Buffer,
    pub material: wgpu::Buffer,
    /// Cell keys and particle values before the sort, and the sort's alternates.
    pub keys: wgpu::Buffer,
    pub values: wgpu::Buffer,
    pub keys_alt: wgpu::Buffer,
    pub values_alt: wgpu::Buffer,
    pub key_count: wgpu::Buffer,
    pub affine: wgpu::Buffer,
    pub ranges: wgpu::Buffer,
    /// The sparse grid's pool: `pool_blocks` × 64 nodes × vec4 (common.wgsl, node_index);
    /// the atomic path's sums (a placeholder on the gather path, which needs none).
    pub grid: wgpu::Buffer,
    /// The grid's velocities after the grid update, for G2P (common.wgsl, grid_texel).
    pub grid_velocity: GridTexture,
    /// What the grid update changed at each node, for a FLIP/PIC blend's G2P (one block's
    /// worth, unused, otherwise).
    pub grid_velocity_change: GridTexture,
    pub block_flags: wgpu::Buffer,
    /// Block → pool slot, one u32 per block of the domain.
    pub block_slot: wgpu::Buffer,
    /// φ of the captured surface at every node (one 0 when there is none).
    pub surface: wgpu::Buffer,
    pub active_blocks: wgpu::Buffer,
    pub block_args: wgpu::Buffer,
    pub flags: wgpu::Buffer,
    /// Two-field separation (`separation.wgsl`; one element each without it): per pool
    /// node the damage field (vec2) and the ridge gradient (vec4), per particle ∇D_p
    /// (vec4), and per pool node the far field's velocity and mass, then its velocity
    /// change (2 × vec4).
    pub damage: wgpu::Buffer,
    pub ridge: wgpu::Buffer,
    pub damage_gradient: wgpu::Buffer,
    pub far_field: wgpu::Buffer,
    /// How the particle arrays split into pages, one entry per page for its dispatches.
    pub pages: PageRanges,
}

pub(crate) use crate::sim::codes::GRID_TEXELS_PER_ROW;

/// A vec4 per node of the grid pool as an rgba32float texture, node `n` at texel
/// (n mod [`GRID_TEXELS_PER_ROW`], n / [`GRID_TEXELS_PER_ROW`]); written by the grid
/// update, read by G2P (the velocities, and a FLIP blend's velocity changes).
pub(crate) struct GridTexture {
    pub texture: wgpu::Texture,
    pub view: wgpu::TextureView,
}

impl GridTexture {
    /// The most pool blocks a texture of at most `max_dimension` rows holds.
    pub fn max_blocks(max_dimension: u32) -> u32 {
        max_dimension.saturating_mul(GRID_TEXELS_PER_ROW / 64)
    }

    /// A texture for a pool of `blocks` blocks (at most [`Self::max_blocks`]).
    pub fn new(device: &wgpu::Device, label: &str, blocks: u32) -> GridTexture {
        let rows = (u64::from(blocks) * 64).div_ceil(u64::from(GRID_TEXELS_PER_ROW));
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: GRID_TEXELS_PER_ROW,
                height: rows.max(1) as u32,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        GridTexture { texture, view }
    }

    /// The texture as a bind-group resource.
    pub fn binding(&self) -> wgpu::BindingResource<'_> {
        wgpu::BindingResource::TextureView(&self.view)
    }

    pub fn bytes(&self) -> u64 {
        let s = self.texture.size();
        u64::from(s.width) * u64::from(s.height) * 16
    }
}

/// Bytes per particle of the particle arrays, by record type (their page windows).
pub(crate) const VEC4: u64 = 16;
pub(crate) const MAT3: u64 = 48;
pub(crate) const SCALAR: u64 = 4;

impl StepBuffers {
    /// Page `i`'s window of the particle array `buffer` of `record`-byte records.
    pub fn window<'a>(
        &'a self,
        buffer: &'a wgpu::Buffer,
        i: u32,
        record: u64,
    ) -> wgpu::BufferBinding<'a> {
        self.pages.pages.window(buffer, i, record)
    }
}

/// The sorted cell keys and particle indices (in the sort's primary or alternate buffers).
pub(crate) struct Sorted<'a> {
    pub keys: &'a wgpu::Buffer,
    pub values: &'a wgpu::Buffer,
}

/// The pipelines of the step; a scatter path's only when the step scatters.
pub(crate) struct Passes {
    prepare: Prepare,
    sort: RadixSort,
    scan: Scan,
    ranges: Ranges,
    mark_blocks: MarkBlocks,
    compact_blocks: CompactBlocks,
    gather: P2gGather,
    g2p: G2p,
    atomic: Option<AtomicPasses>,
    separation: Option<SeparationPasses>,
}

/// Two-field separation's passes (gather path only).
struct SeparationPasses {
    damage_field: DamageField,
    damage_gradient: DamageGradient,
    ridge: Ridge,
}

struct AtomicPasses {
    mark: MarkParticles,
    scatter: ScatterPass,
    grid: GridFromSums,
}

/// How a scatter path's particles add to their nodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Scatter {
    /// Float atomics ([`P2gScatter`]).
    Float,
    /// Integer atomics on fixed-point sums ([`P2gFixed`]).
    Fixed,
}

enum ScatterPass {
    Float(P2gScatter),
    Fixed(P2gFixed),
}

impl ScatterPass {
    fn new(device: &wgpu::Device, scatter: Scatter) -> Self {
        match scatter {
            Scatter::Float => ScatterPass::Float(P2gScatter::new(device)),
            Scatter::Fixed => ScatterPass::Fixed(P2gFixed::new(device)),
        }
    }

    fn bind(&self, device: &wgpu::Device, b: &StepBuffers, i: u32) -> wgpu::BindGroup {
        match self {
            ScatterPass::Float(p) => p.bind(device, b, i),
            ScatterPass::Fixed(p) => p.bind(device, b, i),
        }
    }

    fn record(&self, c: &mut wgpu::ComputePass, bind: &wgpu::BindGroup, particles: u32) {
        match self {
            ScatterPass::Float(p) => p.record(c, bind, particles),
            ScatterPass::Fixed(p) => p.record(c, bind, particles),
        }
    }
}

/// The bind groups of [`Passes`] over one set of [`StepBuffers`]; the per-particle passes
/// have one per page of the particles.
pub(crate) struct Binds {
    prepare: Vec<wgpu::BindGroup>,
    compact_blocks: wgpu::BindGroup,
    g2p: Vec<wgpu::BindGroup>,
    /// Particles of each page.
    page_counts: Vec<u32>,
    /// The path's own passes: one of the two.
    gather: Option<GatherBinds>,
    atomic: Option<AtomicBinds>,
}

/// The gather path's passes, which bind all particles whole (one page).
struct GatherBinds {
    sort: SortPlan,
    ranges: wgpu::BindGroup,
    mark_blocks: wgpu::BindGroup,
    gather: wgpu::BindGroup,
    /// Two-field separation's: damage field, damage gradient, ridge.
    separation: Option<[wgpu::BindGroup; 3]>,
}

struct AtomicBinds {
    mark: Vec<wgpu::BindGroup>,
    scatter: Vec<wgpu::BindGroup>,
    grid: wgpu::BindGroup,
}

/// One pass of the step, for recording and per-pass timing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum StepPass {
    Clear,
    Prepare,
    MarkParticles,
    Scatter,
    GridFromSums,
    Sort,
    Ranges,
    MarkBlocks,
    CompactBlocks,
    DamageField,
    DamageGradient,
    Ridge,
    Gather,
    G2p,
}

impl StepPass {
    pub fn name(self) -> &'static str {
        match self {
            StepPass::Clear => "clear",
            StepPass::Prepare => "prepare",
            StepPass::MarkParticles => "mark blocks (particles)",
            StepPass::Scatter => "p2g scatter",
            StepPass::GridFromSums => "grid from sums",
            StepPass::Sort => "sort",
            StepPass::Ranges => "cell ranges",
            StepPass::MarkBlocks => "mark blocks",
            StepPass::CompactBlocks => "compact blocks",
            StepPass::DamageField => "damage field",
            StepPass::DamageGradient => "damage gradient",
            StepPass::Ridge => "ridge",
            StepPass::Gather => "p2g gather + grid",
            StepPass::G2p => "g2p",
        }
    }
}

impl Passes {
    /// Compile the passes; a scatter path's with `scatter` (else the gather path's),
    /// two-field separation's with `separation` (on the gather path).
    pub fn new(
        device: &wgpu::Device,
        executor: Executor,
        scatter: Option<Scatter>,
        separation: bool,
    ) -> Passes {
        let atomic = scatter.is_some();
        Passes {
            prepare: Prepare::new(device),
            sort: RadixSort::new(device, executor),
            scan: Scan::new(device),
            ranges: Ranges::new(device),
            mark_blocks: MarkBlocks::new(device),
            compact_blocks: CompactBlocks::new(device),
            gather: P2gGather::new(device, separation),
            g2p: G2p::new(device, atomic, separation),
            atomic: scatter.map(|scatter| AtomicPasses {
                mark: MarkParticles::new(device),
                scatter: ScatterPass::new(device, scatter),
                grid: GridFromSums::new(device, scatter == Scatter::Fixed),
            }),
            separation: (separation && !atomic).then(|| SeparationPasses {
                damage_field: DamageField::new(device),
                damage_gradient: DamageGradient::new(device),
                ridge: Ridge::new(device),
            }),
        }
    }

    /// Bind every pass of the path to `b`, for `n` particles sorted (on the gather path) by
    /// keys of `sort_bits` bits.
    pub fn bind(&self, device: &wgpu::Device, b: &StepBuffers, n: u32, sort_bits: u32) -> Binds {
        let pages = 0..b.pages.pages.count;
        let per_page = |bind: &dyn Fn(u32) -> wgpu::BindGroup| pages.clone().map(bind).collect();
        Binds {
            prepare: per_page(&|i| self.prepare.bind(device, b, i)),
            compact_blocks: self.compact_blocks.bind(device, b),
            g2p: per_page(&|i| self.g2p.bind(device, b, i)),
            page_counts: pages.clone().map(|i| b.pages.pages.range(i).1).collect(),
            gather: self
                .atomic
                .is_none()
                .then(|| self.bind_gather(device, b, n, sort_bits)),
            atomic: self.atomic.as_ref().map(|a| AtomicBinds {
                mark: per_page(&|i| a.mark.bind(device, b, i)),
                scatter: per_page(&|i| a.scatter.bind(device, b, i)),
                grid: a.grid.bind(device, b),
            }),
        }
    }

    fn bind_gather(
        &self,
        device: &wgpu::Device,
        b: &StepBuffers,
        n: u32,
        sort_bits: u32,
    ) -> GatherBinds {
        let sort = self.sort.plan(
            device,
            &self.scan,
            &SortBuffers {
                count: &b.key_count,
                keys: &b.keys,
                values: &b.values,
                keys_alt: &b.keys_alt,
                values_alt: &b.values_alt,
            },
            n.max(1),
            sort_bits,
        );
        let sorted = if sort.result_in_alternates() {
            Sorted {
                keys: &b.keys_alt,
                values: &b.values_alt,
            }
        } else {
            Sorted {
                keys: &b.keys,
                values: &b.values,
            }
        };
        GatherBinds {
            ranges: self
                .ranges
                .kernel
                .bind(device, &[&b.key_count, sorted.keys, &b.ranges]),
            mark_blocks: self.mark_blocks.bind(device, b, &sorted),
            gather: self.gather.bind(device, b, &sorted),
            separation: self.separation.as_ref().map(|s| {
                [
                    s.damage_field.bind(device, b, &sorted),
                    s.damage_gradient.bind(device, b),
                    s.ridge.bind(device, b, &sorted),
                ]
            }),
            sort,
        }
    }

    /// The passes of one step, in order; `first`: the first step of a submission. The
    /// atomic path runs [`Prepare`] only then: its G2P leaves the next step's affine term.
    pub fn list(&self, particles: u32, first: bool) -> Vec<StepPass> {
        use StepPass::*;
        let mut list = vec![Clear];
        if particles == 0 {
            // Nothing reaches the grid, and there is nothing to move.
            return list;
        }
        if first || self.atomic.is_none() {
            list.push(Prepare);
        }
        match &self.atomic {
            Some(_) => list.extend([MarkParticles, CompactBlocks, Scatter, GridFromSums]),
            None => {
                list.extend([Sort, Ranges, MarkBlocks, CompactBlocks]);
                if self.separation.is_some() {
                    list.extend([DamageField, DamageGradient, Ridge]);
                }
                list.push(Gather);
            }
        }
        list.push(G2p);
        list
    }

    /// The buffer clears a step starts with (outside any compute pass).
    pub fn clear(&self, enc: &mut wgpu::CommandEncoder, b: &StepBuffers) {
        match &self.atomic {
            Some(_) => enc.clear_buffer(&b.grid, 0, None),
            None => enc.clear_buffer(&b.ranges, 0, None),
        }
        enc.clear_buffer(&b.block_args, 0, None);
    }

    /// The dispatches of `passes` as named stages, for `particles` particles on a domain
    /// of `blocks` blocks (`StepPass::Clear` is [`Passes::clear`], not a stage).
    pub fn stages<'a>(
        &'a self,
        binds: &'a Binds,
        b: &'a StepBuffers,
        passes: &[StepPass],
        (particles, blocks): (u32, u32),
    ) -> Vec<Stage<'a>> {
        passes
            .iter()
            .filter(|p| **p != StepPass::Clear)
            .map(|&pass| {
                Stage::new(pass.name(), move |c: &mut wgpu::ComputePass| match pass {
                    StepPass::Clear => {}
                    StepPass::Prepare => {
                        for (bind, n) in binds.pages(&binds.prepare) {
                            self.prepare.record(c, bind, n);
                        }
                    }
                    StepPass::MarkParticles => {
                        let (a, ab) = self.atomic_passes(binds);
                        for (bind, n) in binds.pages(&ab.mark) {
                            a.mark.record(c, bind, n);
                        }
                    }
                    StepPass::Scatter => {
                        let (a, ab) = self.atomic_passes(binds);
                        for (bind, n) in binds.pages(&ab.scatter) {
                            a.scatter.record(c, bind, n);
                        }
                    }
                    StepPass::GridFromSums => {
                        let (a, ab) = self.atomic_passes(binds);
                        a.grid.record(c, &ab.grid, b);
                    }
                    StepPass::Sort => self.sort.record(c, &self.scan, &gather_binds(binds).sort),
                    StepPass::Ranges => self.ranges.kernel.dispatch(
                        c,
                        &gather_binds(binds).ranges,
                        particles.div_ceil(256),
                    ),
                    StepPass::MarkBlocks => {
                        self.mark_blocks
                            .record(c, &gather_binds(binds).mark_blocks, particles)
                    }
                    StepPass::CompactBlocks => {
                        self.compact_blocks.record(c, &binds.compact_blocks, blocks)
                    }
                    StepPass::DamageField => {
                        let (s, sb) = self.separation_passes(binds);
                        s.damage_field.record(c, &sb[0], b);
                    }
                    StepPass::DamageGradient => {
                        let (s, sb) = self.separation_passes(binds);
                        s.damage_gradient.record(c, &sb[1], particles);
                    }
                    StepPass::Ridge => {
                        let (s, sb) = self.separation_passes(binds);
                        s.ridge.record(c, &sb[2], b);
                    }
                    StepPass::Gather => self.gather.record(c, &gather_binds(binds).gather, b),
                    StepPass::G2p => {
                        for (bind, n) in binds.pages(&binds.g2p) {
                            self.g2p.record(c, bind, n);
                        }
                    }
                })
            })
            .collect()
    }

    fn separation_passes<'a>(
        &'a self,
        binds: &'a Binds,
    ) -> (&'a SeparationPasses, &'a [wgpu::BindGroup; 3]) {
        match (&self.separation, &gather_binds(binds).separation) {
            (Some(s), Some(b)) => (s, b),
            _ => unreachable!("separation pass recorded without separation"),
        }
    }

    fn atomic_passes<'a>(&'a self, binds: &'a Binds) -> (&'a AtomicPasses, &'a AtomicBinds) {
        match (&self.atomic, &binds.atomic) {
            (Some(a), Some(b)) => (a, b),
            _ => unreachable!("atomic pass recorded on the gather path"),
        }
    }
}

fn gather_binds(binds: &Binds) -> &GatherBinds {
    binds
        .gather
        .as_ref()
        .expect("gather pass recorded on the atomic path")
}

impl Binds {
    /// Each page's bind group of a per-particle pass, with the page's particle count.
    fn pages<'a>(
        &'a self,
        binds: &'a [wgpu::BindGroup],
    ) -> impl Iterator<Item = (&'a wgpu::BindGroup, u32)> + 'a {
        binds.iter().zip(self.page_counts.iter().copied())
    }
}
