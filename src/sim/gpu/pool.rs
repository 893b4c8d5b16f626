//! The sparse grid's pool of blocks: its size, growing it between frames from the
//! watchdog's high-water mark, and the copy of the particle state a frame that overflowed
//! it is re-run from ([`super::GpuSim`]).

use super::*;

/// Bytes of a scatter path's sums for a pool of `blocks` blocks (64 nodes of 16 bytes
/// each with floats, 32 with fixed-point word pairs; twice that for a FLIP/PIC blend); the
/// gather path sums in registers and needs none (one placeholder node).
pub(super) fn sums_bytes(path: P2gPath, step: &GpuStep, blocks: u32) -> u64 {
    // A FLIP/PIC blend also sums the momentum without forces: a second vec4 per node.
    let per_node = if step.flip > 0.0 { 32 } else { 16 };
    match path {
        P2gPath::Atomic => u64::from(blocks) * 64 * per_node,
        P2gPath::Fixed => u64::from(blocks) * 64 * per_node * 2,
        P2gPath::Gather => 16,
    }
}

/// Blocks of 4³ nodes the particles' stencils reach now.
pub(super) fn blocks_reached(particles: &Particles, grid: &Grid) -> u32 {
    let per_axis = grid.nodes().map(|n| n.div_ceil(BLOCK));
    let mut seen = std::collections::HashSet::new();
    for x in &particles.x {
        let Some(st) = grid.stencil(*x) else {
            continue;
        };
        let base = st.base.as_uvec3();
        let (lo, hi) = (base / BLOCK, (base + 2) / BLOCK);
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    seen.insert(x + per_axis.x * (y + per_axis.y * z));
                }
            }
        }
    }
    seen.len() as u32
}

/// Entries of the gather path's cell ranges: one per base cell of a quadratic stencil
/// ((cells − 1) per axis, every stencil on the grid), and one for particles off it.
pub fn gather_range_entries(cells: glam::UVec3) -> u64 {
    cells
        .to_array()
        .iter()
        .map(|c| u64::from(c.saturating_sub(1)))
        .product::<u64>()
        + 1
}

/// First pool size: twice the blocks `reached` at the start (at least 64), at most
/// `max_blocks`. [`GpuSim::fit_pool`] grows it between frames.
pub(super) fn initial_pool(reached: u32, max_blocks: u32) -> u32 {
    (2 * reached).max(64).min(max_blocks)
}

/// The largest pool: every block of the domain, at most what the grid texture holds and
/// what keeps the pool's per-node arrays (the scatter's sums, separation's far field)
/// within one storage binding each (they are bound whole).
pub(super) fn max_pool_blocks(
    limits: &wgpu::Limits,
    (path, step, separation): (P2gPath, &GpuStep, bool),
    blocks: u32,
) -> u32 {
    let per_block = sums_bytes(path, step, 1).max(separation_bytes(separation, 1, 32));
    let binding = limits.max_storage_buffer_binding_size;
    let by_binding = u32::try_from(binding / per_block.max(1)).unwrap_or(u32::MAX);
    let texture = GridTexture::max_blocks(limits.max_texture_dimension_2d);
    blocks.min(texture).min(by_binding)
}

impl GpuSim {
    /// Blocks of 4³ nodes the grid pool holds (the sparse grid's capacity).
    pub fn pool_blocks(&self) -> u32 {
        self.consts.pool_blocks
    }

    /// Bytes of the grid itself: the pool (the atomic path's sums), the grid texture and
    /// the block → slot table.
    pub fn grid_bytes(&self) -> u64 {
        let b = &self.buffers;
        b.grid.size()
            + b.grid_velocity.bytes()
            + b.grid_velocity_change.bytes()
            + b.block_slot.size()
            + b.damage.size()
            + b.ridge.size()
            + b.far_field.size()
    }

    /// Resize the grid pool to `blocks` blocks (at most every block of the domain, and at
    /// most what the grid texture and one binding hold: [`Self::pool_at_limit`]). Results
    /// do not depend on the size as long as no step overflows it.
    pub fn set_pool_blocks(&mut self, gpu: &GpuContext, blocks: u32) -> Result<(), GpuError> {
        let blocks = blocks.clamp(1, self.max_pool_blocks);
        self.consts.pool_blocks = blocks;
        super::setup::PoolBuffers::new(gpu, (self.path, &self.consts, self.separation), blocks)
            .install(&mut self.buffers);
        gpu.queue
            .write_buffer(&self.buffers.step, 0, bytemuck::bytes_of(&self.consts));
        self.binds = self.passes.bind(
            &gpu.device,
            &self.buffers,
            self.num_particles,
            self.sort_bits,
        );
        gpu.check()
    }

    /// Whether the pool is as large as it can be on this adapter (every block of the
    /// domain, or what the grid texture and one binding hold): an overflow then cannot be
    /// grown out of.
    pub fn pool_at_limit(&self) -> bool {
        self.consts.pool_blocks >= self.max_pool_blocks
    }

    /// Cap the pool at `blocks` (below what the adapter allows), as an adapter with a
    /// smaller largest texture would: for tests of that limit.
    #[doc(hidden)]
    pub fn limit_pool_blocks(&mut self, gpu: &GpuContext, blocks: u32) -> Result<(), GpuError> {
        self.max_pool_blocks = self.max_pool_blocks.min(blocks.max(1));
        let pool = self.consts.pool_blocks.min(self.max_pool_blocks);
        self.set_pool_blocks(gpu, pool)
    }

    /// Whether a step can overflow the grid pool (it holds fewer blocks than the domain).
    pub fn pool_can_overflow(&self) -> bool {
        self.consts.pool_blocks < self.num_blocks
    }

    /// The buffers that carry the particle state from step to step (x, v, F, C, α).
    fn state(&self) -> [&wgpu::Buffer; 5] {
        let b = &self.buffers;
        [
            &b.x_mass,
            &b.v_volume,
            &b.deformation,
            &b.affine_velocity,
            &b.alpha,
        ]
    }

    /// Copy the particle state aside on the GPU (no readback), so that steps that overflow
    /// the grid pool can be re-run from here with a larger pool ([`Self::restore_state`]).
    pub fn save_state(&mut self, gpu: &GpuContext) -> Result<(), GpuError> {
        if self.saved.is_none() {
            let copies = self
                .state()
                .iter()
                .map(|b| zeroed(gpu, "sim saved state", b.size()))
                .collect();
            self.saved = Some(copies);
        }
        let saved = self.saved.as_ref().expect("allocated above");
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        for (src, dst) in self.state().iter().zip(saved) {
            enc.copy_buffer_to_buffer(src, 0, dst, 0, None);
        }
        gpu.queue.submit([enc.finish()]);
        gpu.check()
    }

    /// Put back the state of the last [`Self::save_state`].
    pub fn restore_state(&self, gpu: &GpuContext) -> Result<(), GpuError> {
        let Some(saved) = &self.saved else {
            return Ok(());
        };
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        for (src, dst) in saved.iter().zip(self.state()) {
            enc.copy_buffer_to_buffer(src, 0, dst, 0, None);
        }
        gpu.queue.submit([enc.finish()]);
        gpu.check()
    }

    /// Between frames: grow the pool to twice the most active blocks the watchdog saw when
    /// that came above 3/4 of the capacity (or overflowed it). Returns whether it grew.
    pub fn fit_pool(&mut self, gpu: &GpuContext, w: &Watchdog) -> Result<bool, GpuError> {
        let cap = self.consts.pool_blocks;
        if cap >= self.max_pool_blocks || u64::from(w.active_blocks_max) * 4 <= u64::from(cap) * 3 {
            return Ok(false);
        }
        self.set_pool_blocks(gpu, w.active_blocks_max.saturating_mul(2))?;
        Ok(true)
    }
}
