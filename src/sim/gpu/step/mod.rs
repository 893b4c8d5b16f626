//! The passes of one explicit MPM step on the GPU (docs/method.md §2), one Rust type per
//! WGSL file under `shaders/sim/step/`, each owning its pipeline and binding its buffers
//! by the names its WGSL declares. One step, on the gather path (every adapter):
//!
//! 1. [`Prepare`] — per particle: base-cell sort key and the affine term
//!    m C − Δt V⁰ (4/Δx²) τ(F) (the first step of a submission only: later steps take
//!    both from the G2P before);
//! 2. [`SortCells`] — particles by base cell (only the bits the cell count needs);
//! 3. [`CellRanges`] — each cell's run of particles (the GPU primitive the renderer also
//!    uses for its tiles);
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
//!    its own field), then the next step's affine term and sort key.
//!
//! On the scatter paths steps 2–5 are instead [`MarkParticles`] (each particle flags the
//! blocks of its stencil), [`CompactBlocks`], a scatter in which each particle adds to its
//! 27 nodes — [`P2gScatter`] with float atomics (where the adapter has them; the order of
//! the additions varies) or [`P2gFixed`] with integer atomics on fixed-point sums
//! (deterministic, every adapter) — and [`GridFromSums`] (the grid update on the active
//! blocks). On every path only the first step of a submission runs [`Prepare`]: G2P
//! leaves the next step's affine term (and on the gather path its sort keys), so later
//! steps need not re-read F, C and the material for it.
//!
//! Each pass is a [`Pass`] of the [`Step`] family (`gpu::pass`, the shape the renderer's
//! passes share): its name, its bind groups over [`StepBuffers`], what it clears and its
//! dispatches. [`Passes::new`] lists a path's passes in this order, and [`Passes::stages`]
//! records them through the same named stages the renderer uses (`gpu::stages`). A new
//! pass is its file, its `mod` and `use` lines and its line in [`Passes::new`].

mod cell_ranges;
mod compact_blocks;
mod damage_field;
mod damage_gradient;
mod g2p;
mod grid_from_sums;
pub mod layout;
mod mark_blocks;
mod mark_particles;
mod p2g;
mod p2g_broadcast;
mod p2g_fixed;
mod p2g_scatter;
mod pass;
mod prepare;
mod ridge;
mod sort_cells;
mod sources;

pub(crate) use crate::gpu::pass::{Bound, Pass};
pub(crate) use cell_ranges::CellRanges;
pub(crate) use compact_blocks::CompactBlocks;
pub(crate) use damage_field::DamageField;
pub(crate) use damage_gradient::DamageGradient;
pub(crate) use g2p::G2p;
pub(crate) use grid_from_sums::GridFromSums;
pub(crate) use mark_blocks::MarkBlocks;
pub(crate) use mark_particles::MarkParticles;
pub(crate) use p2g::P2gGather;
pub(crate) use p2g_broadcast::P2gBroadcast;
pub(crate) use p2g_fixed::P2gFixed;
pub(crate) use p2g_scatter::P2gScatter;
pub(crate) use pass::{pages, per_page, BindAt, Extent, Step};
pub(crate) use prepare::Prepare;
pub(crate) use ridge::Ridge;
pub(crate) use sort_cells::SortCells;
pub(crate) use sources::{source, source_for, step_source};
use sources::{GROUP_WALK, NODE_GATHER, P2G_SUMS};

use crate::gpu::wgsl::Source;

use crate::gpu::pages::PageRanges;
use crate::gpu::pass::{bind_in_order, clear_all};
use crate::gpu::sort::SortPlan;
use crate::gpu::stages::Stage;
use crate::gpu::{GpuContext, Kernel};
use crate::sim::model::ModelsUsed;

/// The source of a node pass that gathers from the sorted particles, before the pass: the
/// step's source for the models in `used`, then [`NODE_GATHER`].
fn gather_source(used: &ModelsUsed) -> Source {
    step_source(used).module(&NODE_GATHER)
}

/// What a gather by subgroups' pass (`group_walk.wgsl`) adds to its source: the
/// functions `lent_by_lane_0` … `lent_by_lane_7`, each the particle that lane lends, its
/// `Lent` with every field broadcast from that lane, or given a value instead (`Some`)
/// where the pass's configuration does not read it. A broadcast's lane index must be a
/// constant expression, hence one function per lane (the pass calls all eight in turn).
fn lent_by_lane(fields: &[(&str, Option<&str>)]) -> String {
    (0..8)
        .map(|lane| {
            let values: Vec<String> = fields
                .iter()
                .map(|&(f, value)| match value {
                    Some(v) => v.to_string(),
                    None => format!("subgroupBroadcast(own.{f}, {lane}u)"),
                })
                .collect();
            format!(
                "fn lent_by_lane_{lane}(own: Lent) -> Lent {{\n    return Lent({});\n}}",
                values.join(", ")
            )
        })
        .collect::<Vec<_>>()
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

/// A P2G gather's source before the pass ([`P2gGather`], [`P2gBroadcast`]): `SEPARATION`
/// (two-field separation compiled in or out) and `p2g_sums.wgsl` (the sums both keep per
/// field, and how they finish a node; after the node gather's declarations).
fn p2g_gather_source(separation: bool) -> Source {
    step_source(&ModelsUsed::all())
        .define("SEPARATION", separation)
        .module(&P2G_SUMS)
}

/// What both P2G gathers read and write besides [`gather_bindings`]: the particles' P2G
/// inputs, the grid textures, the captured surface (the grid update), and two-field
/// separation's particle gradients, ridge and far field.
fn p2g_gather_bindings(b: &StepBuffers) -> [(&'static str, wgpu::BindingResource<'_>); 9] {
    [
        ("x_mass", b.x_mass.as_entire_binding()),
        ("v_volume", b.v_volume.as_entire_binding()),
        ("affine", b.affine.as_entire_binding()),
        ("grid_velocity", b.grid_velocity.binding()),
        ("grid_velocity_change", b.grid_velocity_change.binding()),
        ("surface", b.surface.as_entire_binding()),
        ("damage_gradient", b.damage_gradient.as_entire_binding()),
        ("ridge", b.ridge.as_entire_binding()),
        ("far_field", b.far_field.as_entire_binding()),
    ]
}

/// A step pass that calls no material function: its WGSL after the shared modules, entry
/// point `main`.
fn step_kernel(device: &wgpu::Device, label: &'static str, pass: &str) -> Kernel {
    Kernel::new(device, label, &source(pass), "main")
}

/// A step pass that calls the material dispatch (`material_kirchhoff`, `_plasticity`,
/// `_damage`, `_stress_scale`), built for the simulation's models `used`.
fn material_kernel(
    device: &wgpu::Device,
    label: &'static str,
    pass: &str,
    used: &ModelsUsed,
) -> Kernel {
    Kernel::new(device, label, &source_for(pass, used), "main")
}

/// The buffers of the step, named as the passes' WGSL names them where it can.
pub(crate) struct StepBuffers {
    pub step: wgpu::Buffer,
    pub x_mass: wgpu::Buffer,
    pub v_volume: wgpu::Buffer,
    pub deformation: wgpu::Buffer,
    pub affine_velocity: wgpu::Buffer,
    pub alpha: wgpu::Buffer,
    /// Per particle, its material word (`codes::material_word`).
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

impl StepBuffers {
    /// Bytes of every buffer and texture of the step. The struct is taken apart field by
    /// field (no `..`), so a buffer added to it cannot be left out of the count.
    pub fn bytes(&self) -> u64 {
        let StepBuffers {
            step,
            x_mass,
            v_volume,
            deformation,
            affine_velocity,
            alpha,
            material,
            keys,
            values,
            keys_alt,
            values_alt,
            key_count,
            affine,
            ranges,
            grid,
            grid_velocity,
            grid_velocity_change,
            block_flags,
            block_slot,
            surface,
            active_blocks,
            block_args,
            flags,
            damage,
            ridge,
            damage_gradient,
            far_field,
            pages,
        } = self;
        let buffers = [
            step,
            x_mass,
            v_volume,
            deformation,
            affine_velocity,
            alpha,
            material,
            keys,
            values,
            keys_alt,
            values_alt,
            key_count,
            affine,
            ranges,
            grid,
            block_flags,
            block_slot,
            surface,
            active_blocks,
            block_args,
            flags,
            damage,
            ridge,
            damage_gradient,
            far_field,
            &pages.buffer,
        ];
        buffers.iter().map(|b| b.size()).sum::<u64>()
            + grid_velocity.bytes()
            + grid_velocity_change.bytes()
    }
}

pub(crate) use crate::sim::gpu::codes::GRID_TEXELS_PER_ROW;

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

impl<'a> Sorted<'a> {
    /// Where `plan`'s sort of `b`'s cell keys leaves them.
    fn after(b: &'a StepBuffers, plan: &SortPlan) -> Sorted<'a> {
        if plan.result_in_alternates() {
            Sorted {
                keys: &b.keys_alt,
                values: &b.values_alt,
            }
        } else {
            Sorted {
                keys: &b.keys,
                values: &b.values,
            }
        }
    }
}

/// The passes of one path of the step, in the order a step runs them.
pub(crate) struct Passes {
    passes: Vec<Box<dyn Pass<Step>>>,
}

/// How a scatter path's particles add to their nodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Scatter {
    /// Float atomics ([`P2gScatter`]).
    Float,
    /// Integer atomics on fixed-point sums ([`P2gFixed`]).
    Fixed,
}

/// The bind groups of [`Passes`] over one set of [`StepBuffers`], a [`Bound`] per pass.
pub(crate) struct Binds {
    bound: Vec<Bound>,
    /// Particles of each page.
    page_counts: Vec<u32>,
}

/// Which passes of a step [`Passes::stages`] records.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum StepPasses {
    /// Those of the first step of a submission.
    First,
    /// Those of a later step.
    Later,
    /// [`Prepare`] alone (the first pass): the affine term and keys a step after the
    /// first of a submission reads from the step before.
    PrepareOnly,
}

impl Passes {
    /// Compile the passes; a scatter path's with `scatter` (else the gather path's),
    /// two-field separation's with `separation` (on the gather path), G2P with the timed
    /// actions with `actions`. This is the
    /// algorithm of the module's documentation; a new pass goes in here.
    pub fn new(
        gpu: &GpuContext,
        (scatter, separation, actions): (Option<Scatter>, bool, bool),
        used: &ModelsUsed,
    ) -> Passes {
        let device = &gpu.device;
        let executor = gpu.executor();
        let atomic = scatter.is_some();
        let mut passes: Vec<Box<dyn Pass<Step>>> = vec![Box::new(Prepare::new(device, used))];
        match scatter {
            Some(scatter) => {
                passes.push(Box::new(MarkParticles::new(device)));
                passes.push(Box::new(CompactBlocks::new(device)));
                passes.push(match scatter {
                    Scatter::Float => Box::new(P2gScatter::new(device)),
                    Scatter::Fixed => Box::new(P2gFixed::new(device)),
                });
                passes.push(Box::new(GridFromSums::new(
                    device,
                    scatter == Scatter::Fixed,
                )));
            }
            None => {
                passes.push(Box::new(SortCells::new(device, executor)));
                passes.push(Box::new(CellRanges::new(device)));
                passes.push(Box::new(MarkBlocks::new(device)));
                passes.push(Box::new(CompactBlocks::new(device)));
                if separation {
                    let by_subgroups = gpu.cpu_subgroups_of_eight();
                    passes.push(Box::new(DamageField::new(device, used, by_subgroups)));
                    passes.push(Box::new(DamageGradient::new(device)));
                    passes.push(Box::new(Ridge::new(device)));
                }
                if gpu.cpu_subgroups_of_eight() {
                    passes.push(Box::new(P2gBroadcast::new(device, separation)));
                } else {
                    passes.push(Box::new(P2gGather::new(device, separation)));
                }
            }
        }
        let g2p = (!atomic, separation, actions);
        passes.push(Box::new(G2p::new(device, g2p, used)));
        Passes { passes }
    }

    fn list(&self) -> Vec<&dyn Pass<Step>> {
        self.passes.iter().map(|p| p.as_ref()).collect()
    }

    /// Bind every pass to `b`, in step order (a pass after the sort finds the sorted
    /// pairs), for `n` particles sorted (on the gather path) by keys of `sort_bits` bits.
    pub fn bind(&self, device: &wgpu::Device, b: &StepBuffers, n: u32, sort_bits: u32) -> Binds {
        let at = BindAt {
            b,
            sorted: None,
            particles: n,
            sort_bits,
        };
        Binds {
            bound: bind_in_order(&self.list(), device, at),
            page_counts: (0..b.pages.pages.count)
                .map(|i| b.pages.pages.range(i).1)
                .collect(),
        }
    }

    /// What the `which` passes dispatch over: `particles` particles on a domain of
    /// `blocks` blocks.
    pub fn extent<'a>(
        &self,
        binds: &'a Binds,
        b: &'a StepBuffers,
        (particles, blocks): (u32, u32),
        which: StepPasses,
    ) -> Extent<'a> {
        Extent {
            b,
            particles,
            blocks,
            page_counts: &binds.page_counts,
            first: which != StepPasses::Later,
        }
    }

    /// The buffer clears a step starts with (outside any compute pass).
    pub fn clear(&self, enc: &mut wgpu::CommandEncoder, at: &Extent) {
        clear_all(&self.list(), enc, at);
    }

    /// The dispatches of the step's `which` passes as named stages.
    pub fn stages<'a>(
        &'a self,
        binds: &'a Binds,
        at: &'a Extent<'a>,
        which: StepPasses,
    ) -> Vec<Stage<'a>> {
        if at.particles == 0 {
            // Nothing reaches the grid, and there is nothing to move.
            return Vec::new();
        }
        crate::gpu::pass::stages(&self.list(), &binds.bound, at, |i| {
            which != StepPasses::PrepareOnly || i == 0
        })
    }
}
