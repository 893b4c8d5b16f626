//! The explicit MPM step on the GPU (docs/method.md §2), mirroring [`super::cpu`] pass for
//! pass: [`GpuSim`] holds the particle state, the sparse grid and the step's passes
//! ([`step`], one type per WGSL file), and records steps without readbacks.
//!
//! The grid is sparse: a pool of blocks of 4³ nodes with a block → slot table that
//! `compact_blocks.wgsl` fills each step (`node_index` in `common.wgsl` is the only way to a
//! node). The pool holds twice the blocks active at the start and grows between frames
//! ([`GpuSim::fit_pool`]) from the high-water mark the watchdog reads back.
//!
//! Every substep of a call to [`GpuSim::step`] goes into one command buffer with nothing
//! read back in between. The per-particle math is `shaders/sim/*.wgsl`, tested against the
//! f64 oracle in `tests/sim_wgsl.rs`; the whole step is tested against [`super::cpu`] in
//! `tests/sim_gpu.rs`.

use bytemuck::Pod;
use glam::{DMat3, DVec3, Mat3};
use wgpu::util::DeviceExt;

use super::kinematic::KinematicCollider;
use super::{Grid, Material, Particles, StepParams};
use crate::gpu::buffers::{read_buffer, storage};
use crate::gpu::pages::{PageRanges, Pages};
use crate::gpu::stages;
use crate::gpu::{GpuContext, GpuError};
use step::layout::{mat3_to_gpu, GpuAction, GpuKinematic, GpuPose};
use step::{
    Binds, Extent, GridTexture, Passes, Scatter, StepBuffers, StepPasses, GRID_TEXELS_PER_ROW,
};

pub use step::layout::{
    GpuCollider, GpuCondition, GpuMaterial, GpuStep, SimSetupError, MAX_COLLIDERS, MAX_KINEMATIC,
    MAX_MATERIALS,
};
/// Bytes of the largest per-particle record (F, C: `mat3x3<f32>`), which sizes the pages.
const MAT3_BYTES: u64 = 48;
/// The watchdog's counters (`flags` of the step passes): one word per [`WatchSlot`].
const WATCHDOG_BYTES: u64 = WatchSlot::COUNT as u64 * 4;
use codes::{BlockArg, WatchSlot, BLOCK};

pub mod codes;
mod p2g_path;
mod p2g_race;
pub mod plan;
mod pool;
mod readback;
mod setup;
pub mod step;
mod watchdog;
pub mod wgsl;

pub use p2g_path::P2gPath;
pub use p2g_race::P2gRace;
pub use plan::{PlanError, SimPlan, SimRequest};
pub use pool::gather_range_entries;
use pool::{blocks_reached, initial_pool, max_pool_blocks, sums_bytes};
use setup::{allocate, Layout, PoolSize};
pub use step::layout::FIXED_POINT_CELLS_PER_STEP;
pub use watchdog::Watchdog;

/// A simulation living on the GPU: particle state, grid, and the passes of one step.
pub struct GpuSim {
    path: P2gPath,
    passes: Passes,
    buffers: StepBuffers,
    binds: Binds,
    num_particles: u32,
    num_blocks: u32,
    /// The largest pool: every block of the domain, or as many as the grid texture's
    /// largest size holds.
    max_pool_blocks: u32,
    sort_bits: u32,
    /// The step constants as uploaded (moving colliders are added by `set_kinematic`).
    consts: GpuStep,
    kinematic: Vec<KinematicCollider>,
    /// A gusty wind, whose velocity the step constants take per substep.
    gusty_wind: Option<super::Wind>,
    /// The timed actions, whose effects the step constants take per substep.
    actions: Vec<super::Action>,
    /// Two-field separation (its buffers are sized to the pool).
    separation: bool,
    dt: f64,
    /// The particles' total and largest mass (as f32 on the GPU): the fixed-point units'
    /// inputs, again whenever Δt changes.
    masses: (f64, f64),
    /// Start time of the next substep, in seconds (the moving colliders' clock).
    time: std::cell::Cell<f64>,
    /// A copy of the particle state ([`GpuSim::save_state`]), made only while the grid pool
    /// can overflow.
    saved: Option<Vec<wgpu::Buffer>>,
}

/// Records uploaded for every substep of a call, copied into the step constants before
/// each substep (outside any compute pass, so the passes of that substep see them).
struct SubstepRecords {
    buffer: wgpu::Buffer,
    /// Bytes per substep.
    per_step: u64,
    /// Where they go in the step constants (`GpuStep`).
    at: u64,
}

impl SubstepRecords {
    fn copy(&self, enc: &mut wgpu::CommandEncoder, step: &wgpu::Buffer, s: u32) {
        let from = u64::from(s) * self.per_step;
        enc.copy_buffer_to_buffer(&self.buffer, from, step, self.at, Some(self.per_step));
    }
}

/// A buffer of per-substep records that the step copies into its constants.
fn copy_source<T: Pod>(gpu: &GpuContext, label: &str, data: &[T]) -> wgpu::Buffer {
    gpu.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::cast_slice(data),
            usage: wgpu::BufferUsages::COPY_SRC,
        })
}

fn mat3_from_gpu(m: &[[f32; 4]; 3]) -> DMat3 {
    let c = |v: &[f32; 4]| glam::Vec3::new(v[0], v[1], v[2]);
    Mat3::from_cols(c(&m[0]), c(&m[1]), c(&m[2])).as_dmat3()
}

fn init<T: Pod>(gpu: &GpuContext, label: &str, data: &[T], readable: bool) -> wgpu::Buffer {
    let bytes: &[u8] = bytemuck::cast_slice(data);
    // Padded to 256 bytes so that empty arrays still bind; large ones are not copied.
    let padded: std::borrow::Cow<[u8]> = if bytes.len() >= 256 {
        bytes.into()
    } else {
        let mut small = bytes.to_vec();
        small.resize(256, 0);
        small.into()
    };
    let mut usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
    if readable {
        usage |= wgpu::BufferUsages::COPY_SRC;
    }
    gpu.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: &padded,
            usage,
        })
}

/// The grid's velocity changes for a pool of `blocks`: as large as the pool for a FLIP/PIC
/// blend, one block (bound, never read) otherwise.
fn velocity_change_texture(device: &wgpu::Device, step: &GpuStep, blocks: u32) -> GridTexture {
    let blocks = if step.flip > 0.0 { blocks } else { 1 };
    GridTexture::new(device, "sim grid velocity change", blocks)
}

/// Bytes of a per-node array of two-field separation for a pool of `blocks`: `per_node`
/// bytes a node with separation, one node's worth (bound, never read) without.
fn separation_bytes(separation: bool, blocks: u32, per_node: u64) -> u64 {
    if separation {
        u64::from(blocks) * 64 * per_node
    } else {
        per_node
    }
}

fn zeroed(gpu: &GpuContext, label: &str, bytes: u64) -> wgpu::Buffer {
    storage(&gpu.device, label, bytes, wgpu::BufferUsages::empty())
}

impl GpuSim {
    /// Upload `particles` for stepping on `grid` (its box, spacing and cell count) with
    /// `materials` and `params` (Δt, gravity, boundaries, transfer, separation), with the
    /// best P2G path for them ([`P2gPath::for_params`]).
    pub fn new(
        gpu: &GpuContext,
        particles: &Particles,
        grid: &Grid,
        materials: &[Material],
        params: &StepParams,
    ) -> Result<GpuSim, SimSetupError> {
        let path = P2gPath::for_params(gpu, params);
        Self::with_path(gpu, particles, grid, materials, params, path)
    }

    /// As [`new`](Self::new) with a chosen P2G path (`Atomic` needs float atomics).
    pub fn with_path(
        gpu: &GpuContext,
        particles: &Particles,
        grid: &Grid,
        materials: &[Material],
        params: &StepParams,
        path: P2gPath,
    ) -> Result<GpuSim, SimSetupError> {
        let pages = Self::pages_for(gpu, particles.len());
        Self::with_pages(gpu, particles, grid, materials, params, path, pages)
    }

    /// The pages the particle arrays split into on `gpu` (`gpu::pages`): the largest that
    /// fit one storage binding.
    pub fn pages_for(gpu: &GpuContext, particles: usize) -> Pages {
        let binding = gpu.limits.max_storage_buffer_binding_size;
        Pages::new(particles as u32, MAT3_BYTES, binding)
    }

    /// As [`with_path`](Self::with_path) with the particle arrays split into `pages`
    /// (several pages need the atomic path; each array must fit one buffer).
    pub fn with_pages(
        gpu: &GpuContext,
        particles: &Particles,
        grid: &Grid,
        materials: &[Material],
        params: &StepParams,
        path: P2gPath,
        pages: Pages,
    ) -> Result<GpuSim, SimSetupError> {
        let separation = params.separation != super::Separation::None;
        Self::check_path(gpu, particles.len(), path, pages, separation)?;
        let n = particles.len() as u32;
        let mut step = GpuStep::new(grid, materials, params, n)?;
        // From the masses as the GPU holds them (f32), so that particles the GPU cannot
        // tell apart get the same units.
        let mass = || particles.mass.iter().map(|m| f64::from(*m as f32));
        let masses = (mass().sum(), mass().fold(0.0, f64::max));
        step.set_fixed_point(masses.0, masses.1);
        let pool = PoolSize::of(gpu, particles, grid, (path, &step, separation))?;
        step.pool_blocks = pool.first;
        let scatter = match path {
            P2gPath::Gather => None,
            P2gPath::Atomic => Some(Scatter::Float),
            P2gPath::Fixed => Some(Scatter::Fixed),
        };
        let used = crate::sim::model::ModelsUsed::of(materials);
        let acting = !params.actions.is_empty();
        let passes = Passes::new(gpu, (scatter, separation, acting), &used);
        let layout = Layout {
            particles,
            grid,
            params,
            step: &step,
            path,
            separation,
            pool,
            pages,
        };
        let buffers = allocate(gpu, &layout);
        let sort_bits = 32 - (grid.cells - 1).element_product().leading_zeros();
        let binds = passes.bind(&gpu.device, &buffers, n, sort_bits);
        Ok(GpuSim {
            path,
            passes,
            buffers,
            binds,
            num_particles: n,
            num_blocks: pool.domain,
            max_pool_blocks: pool.max,
            sort_bits,
            consts: step,
            kinematic: Vec::new(),
            gusty_wind: params.fields.wind.filter(|w| w.varies()),
            actions: params.actions.list.clone(),
            separation,
            dt: params.dt,
            masses,
            time: std::cell::Cell::new(0.0),
            saved: None,
        })
    }

    /// Move `colliders` along their paths in every following step (replacing any set before).
    pub fn set_kinematic(
        &mut self,
        gpu: &GpuContext,
        colliders: &[KinematicCollider],
    ) -> Result<(), SimSetupError> {
        if colliders.len() > MAX_KINEMATIC {
            return Err(SimSetupError::TooManyKinematic(colliders.len()));
        }
        self.kinematic = colliders.to_vec();
        self.consts.num_kinematic = colliders.len() as u32;
        self.consts.kinematic = [GpuKinematic::default(); MAX_KINEMATIC];
        for (slot, k) in self.consts.kinematic.iter_mut().zip(colliders) {
            *slot = GpuKinematic::from_cpu(k);
        }
        for (slot, k) in self.consts.poses.iter_mut().zip(colliders) {
            *slot = GpuPose::from_cpu(&k.motion.pose(self.time.get()));
        }
        gpu.queue
            .write_buffer(&self.buffers.step, 0, bytemuck::bytes_of(&self.consts));
        gpu.check()?;
        Ok(())
    }

    /// Step by `dt` from now on (a frame's Δt, `sim::time_step`): the step's constants, the
    /// fixed-point P2G's units (its speed bound is cells a step) and the moving colliders'
    /// substep clock.
    pub fn set_dt(&mut self, gpu: &GpuContext, dt: f64) -> Result<(), GpuError> {
        if dt == self.dt {
            return Ok(());
        }
        self.dt = dt;
        self.consts.dt = dt as f32;
        self.consts.set_fixed_point(self.masses.0, self.masses.1);
        gpu.queue
            .write_buffer(&self.buffers.step, 0, bytemuck::bytes_of(&self.consts));
        gpu.check()
    }

    /// Set the start time (seconds) of the next step: the moving colliders' clock, which
    /// [`step`](Self::step) advances by Δt per substep.
    pub fn set_time(&self, seconds: f64) {
        self.time.set(seconds);
    }

    /// Start time of the next step, in seconds.
    pub fn time(&self) -> f64 {
        self.time.get()
    }

    /// `records(t, out)` pushed for the start time t of each of `steps` substeps from the
    /// current time, uploaded once, to be copied before each substep into the step
    /// constants at byte `at`; `None` when a substep has no records.
    fn substep_records<T: Pod>(
        &self,
        gpu: &GpuContext,
        (label, steps, at): (&str, u32, usize),
        records: impl Fn(f64, &mut Vec<T>),
    ) -> Option<SubstepRecords> {
        let t0 = self.time.get();
        let mut all = Vec::new();
        for s in 0..steps {
            records(t0 + f64::from(s) * self.dt, &mut all);
        }
        let per_step = all.len() / steps.max(1) as usize * std::mem::size_of::<T>();
        (per_step > 0).then(|| SubstepRecords {
            buffer: copy_source(gpu, label, &all),
            per_step: per_step as u64,
            at: at as u64,
        })
    }

    /// What the step constants take per substep: the moving colliders' poses, a gusty
    /// wind's velocity and drag (a steady wind is in the constants already), the timed
    /// actions' effects.
    fn per_substep(&self, gpu: &GpuContext, steps: u32) -> Vec<SubstepRecords> {
        use std::mem::offset_of;
        let poses = self.substep_records(
            gpu,
            ("sim kinematic poses", steps, offset_of!(GpuStep, poses)),
            |t, out| {
                out.extend(
                    self.kinematic
                        .iter()
                        .map(|k| GpuPose::from_cpu(&k.motion.pose(t))),
                )
            },
        );
        let winds = self.gusty_wind.and_then(|wind| {
            self.substep_records(
                gpu,
                ("sim gusty wind", steps, offset_of!(GpuStep, wind)),
                |t, out| {
                    let w = wind.velocity_at(t).as_vec3();
                    // `wind` and `wind_drag` are adjacent in the constants.
                    out.push([w.x, w.y, w.z, wind.drag as f32]);
                },
            )
        });
        let effects = self.substep_records(
            gpu,
            ("sim action effects", steps, offset_of!(GpuStep, actions)),
            |t, out| {
                out.extend(
                    self.actions
                        .iter()
                        .map(|a| GpuAction::from_cpu(a.effect(t, self.dt))),
                )
            },
        );
        [poses, winds, effects].into_iter().flatten().collect()
    }

    /// Record `steps` substeps into one command buffer and submit it; nothing is read back.
    /// Moving colliders get each substep's pose, a gusty wind its velocity and the timed
    /// actions their effects, from one upload per call.
    pub fn step(&self, gpu: &GpuContext, steps: u32) -> Result<(), GpuError> {
        let per_substep = self.per_substep(gpu, steps);
        let mut enc = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("sim steps"),
            });
        for s in 0..steps {
            for records in &per_substep {
                records.copy(&mut enc, &self.buffers.step, s);
            }
            let which = if s == 0 {
                StepPasses::First
            } else {
                StepPasses::Later
            };
            self.record(&mut enc, which);
        }
        gpu.queue.submit([enc.finish()]);
        self.time.set(self.time.get() + f64::from(steps) * self.dt);
        gpu.check()
    }

    /// What the `which` passes of a step dispatch over.
    fn extent(&self, which: StepPasses) -> Extent<'_> {
        let sizes = (self.num_particles, self.num_blocks);
        self.passes.extent(&self.binds, &self.buffers, sizes, which)
    }

    /// Record one step: its clears, then its `which` passes in one compute pass.
    fn record(&self, enc: &mut wgpu::CommandEncoder, which: StepPasses) {
        let at = self.extent(which);
        self.passes.clear(enc, &at);
        stages::record(
            enc,
            "sim step",
            &self.passes.stages(&self.binds, &at, which),
        );
    }

    /// Milliseconds per step of each pass, over `steps` real steps in which every pass is
    /// submitted on its own and waited for (so the sum exceeds a step's time by the
    /// submissions' overhead): the passes of a step after the first of a submission, as
    /// nearly every step runs. For benchmarks.
    pub fn profile_passes(
        &self,
        gpu: &GpuContext,
        steps: u32,
    ) -> Result<Vec<(&'static str, f64)>, GpuError> {
        // The passes of a step after the first of a submission, after one untimed prepare.
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        self.record(&mut enc, StepPasses::PrepareOnly);
        gpu.queue.submit([enc.finish()]);
        let at = self.extent(StepPasses::Later);
        let list = self.passes.stages(&self.binds, &at, StepPasses::Later);
        let mut total: Vec<(&'static str, f64)> = list.iter().map(|s| (s.name, 0.0)).collect();
        for _ in 0..steps {
            // The clears, untimed (as the renderer's), then each stage alone.
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            self.passes.clear(&mut enc, &at);
            gpu.queue.submit([enc.finish()]);
            for (t, (_, ms)) in total.iter_mut().zip(stages::profile(gpu, &list)?) {
                t.1 += ms;
            }
        }
        gpu.check()?;
        Ok(total
            .into_iter()
            .map(|(name, ms)| (name, ms / f64::from(steps)))
            .collect())
    }

    /// The P2G path in use.
    pub fn path(&self) -> P2gPath {
        self.path
    }

    /// Number of particles.
    pub fn len(&self) -> u32 {
        self.num_particles
    }

    pub fn is_empty(&self) -> bool {
        self.num_particles == 0
    }

    /// How the particle arrays are split into pages.
    pub fn pages(&self) -> Pages {
        self.buffers.pages.pages
    }

    /// Positions and masses (`vec4`), and deformation gradients (`mat3x3`), for passes that
    /// read the particle state on the GPU (the derive pass: one page only).
    pub fn state_buffers(&self) -> (&wgpu::Buffer, &wgpu::Buffer) {
        (&self.buffers.x_mass, &self.buffers.deformation)
    }

    /// Bytes of GPU memory this simulation holds (particles, sort, cells, grid).
    pub fn gpu_bytes(&self) -> u64 {
        self.buffers.bytes()
    }
}
