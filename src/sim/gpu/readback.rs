//! What [`super::GpuSim`] reads back from the GPU: the watchdog's counters once a frame,
//! and on request the active blocks, the damage gradients and the particle state.

use super::*;

impl GpuSim {
    /// The watchdog (docs/method.md §2.3): its counters over the steps since the last call
    /// (one word per [`WatchSlot`] read back, then cleared).
    pub fn take_watchdog(&self, gpu: &GpuContext) -> Result<Watchdog, GpuError> {
        let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("sim watchdog readback"),
            size: WATCHDOG_BYTES,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(&self.buffers.flags, 0, &staging, 0, Some(WATCHDOG_BYTES));
        enc.clear_buffer(&self.buffers.flags, 0, None);
        gpu.queue.submit([enc.finish()]);
        let bytes = read_buffer(gpu, &staging)?;
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&bytes[..WATCHDOG_BYTES as usize]);
        let v = |slot: WatchSlot| words[slot.index()];
        // The first step and particle are stored as bitwise NOTs (0: none).
        let not_zero = |w: u32| (w != 0).then_some(!w);
        Ok(Watchdog {
            nonfinite: v(WatchSlot::Nonfinite),
            escaped: v(WatchSlot::Escaped),
            first_step: not_zero(v(WatchSlot::FirstStep)),
            active_blocks_max: v(WatchSlot::ActiveBlocksMax),
            pool_overflow: v(WatchSlot::PoolOverflow),
            fixed_point_range: v(WatchSlot::FixedPointRange),
            speed_max: f32::from_bits(v(WatchSlot::SpeedMax)),
            first_particle: not_zero(v(WatchSlot::FirstParticle)),
            inverted: v(WatchSlot::Inverted),
            inverted_first_step: not_zero(v(WatchSlot::InvertedFirstStep)),
            inverted_first_particle: not_zero(v(WatchSlot::InvertedFirstParticle)),
        })
    }

    /// The blocks of 4³ nodes the last step's node passes visited (indices x-fastest over
    /// [`blocks`](Self::blocks) per axis), sorted.
    pub fn active_blocks(&self, gpu: &GpuContext) -> Result<Vec<u32>, GpuError> {
        let b = &self.buffers;
        let args = u64::from(BlockArg::WORDS) * 4;
        let staging = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("sim active blocks readback"),
            size: args + b.active_blocks.size(),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(&b.block_args, 0, &staging, 0, Some(args));
        enc.copy_buffer_to_buffer(&b.active_blocks, 0, &staging, args, None);
        gpu.queue.submit([enc.finish()]);
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&read_buffer(gpu, &staging)?);
        // Blocks beyond the pool's capacity were counted but not listed.
        let (args, listed) = words.split_at(BlockArg::WORDS as usize);
        let count = (args[BlockArg::Blocks.index()] as usize).min(listed.len());
        let mut list = listed[..count].to_vec();
        list.sort_unstable();
        Ok(list)
    }

    /// The number of blocks of 4³ nodes covering the grid.
    pub fn blocks(&self) -> u32 {
        self.num_blocks
    }

    /// Two-field separation's ∇D_p per particle as the last step computed it (from the
    /// state at that step's start; `damage_gradient.wgsl`).
    pub fn read_damage_gradients(&self, gpu: &GpuContext) -> Result<Vec<DVec3>, GpuError> {
        let n = self.num_particles as usize;
        let mut data = crate::gpu::buffers::copy_out(gpu, &self.buffers.damage_gradient)?;
        data.truncate(n * 16);
        let g: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&data);
        Ok(g.iter()
            .map(|a| DVec3::new(f64::from(a[0]), f64::from(a[1]), f64::from(a[2])))
            .collect())
    }

    /// Copy the particle state back (positions, velocities, F, C, α; masses, volumes and
    /// materials as uploaded).
    pub fn read_particles(
        &self,
        gpu: &GpuContext,
        like: &Particles,
    ) -> Result<Particles, GpuError> {
        let n = self.num_particles as usize;
        let b = &self.buffers;
        let read = |buf: &wgpu::Buffer, bytes: usize| -> Result<Vec<u8>, GpuError> {
            let mut data = crate::gpu::buffers::copy_out(gpu, buf)?;
            data.truncate(bytes);
            Ok(data)
        };
        let x: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&read(&b.x_mass, n * 16)?);
        let v: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&read(&b.v_volume, n * 16)?);
        let f: Vec<[[f32; 4]; 3]> = bytemuck::pod_collect_to_vec(&read(&b.deformation, n * 48)?);
        let c: Vec<[[f32; 4]; 3]> =
            bytemuck::pod_collect_to_vec(&read(&b.affine_velocity, n * 48)?);
        let alpha: Vec<f32> = bytemuck::pod_collect_to_vec(&read(&b.alpha, n * 4)?);
        let mut out = like.clone();
        let v3 = |a: &[f32; 4]| DVec3::new(f64::from(a[0]), f64::from(a[1]), f64::from(a[2]));
        out.x = x.iter().map(v3).collect();
        out.v = v.iter().map(v3).collect();
        out.f = f.iter().map(mat3_from_gpu).collect();
        out.c = c.iter().map(mat3_from_gpu).collect();
        out.alpha = alpha.iter().map(|a| f64::from(*a)).collect();
        Ok(out)
    }
}
