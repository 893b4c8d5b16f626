//! Building a [`GpuSim`]: a path checked against the adapter and the parameters, the
//! particles packed into the GPU's records, the grid pool's first size, and every buffer of
//! the step allocated in one place (the pool's again when it grows, by the same code).

use super::*;

impl GpuSim {
    /// Refuses a P2G path that the adapter or the parameters cannot run.
    pub(super) fn check_path(
        gpu: &GpuContext,
        particles: usize,
        path: P2gPath,
        pages: Pages,
        separation: bool,
    ) -> Result<(), SimSetupError> {
        let refuse = |why: String| Err(SimSetupError::Gpu(GpuError::Failed(why)));
        if pages.count > 1 && path == P2gPath::Gather {
            return refuse(format!(
                "{particles} particles span {} storage bindings of {}; the gather P2G path needs them in one: use the fixed-point or atomic path, or fewer particles",
                pages.count,
                gpu.describe()
            ));
        }
        if path == P2gPath::Atomic && !gpu.features.float32_atomics {
            return refuse(format!(
                "the atomic P2G path needs float atomics, which {} lacks",
                gpu.describe()
            ));
        }
        if separation && path != P2gPath::Gather {
            return refuse(format!(
                "two-field separation (simulation.separation) runs on the gather P2G path; \
                 the {} path has one velocity field per node",
                path.name()
            ));
        }
        let texture_limit = gpu.limits.max_texture_dimension_2d;
        if texture_limit < GRID_TEXELS_PER_ROW {
            return refuse(format!(
                "the simulation's grid texture is {GRID_TEXELS_PER_ROW} texels wide, and {} allows 2D textures of at most {texture_limit}",
                gpu.describe()
            ));
        }
        Ok(())
    }
}

/// The particle arrays as the GPU holds them: x with the mass and v with the rest volume
/// in one `vec4` each, F and C as padded `mat3x3`, α in f32.
pub(super) struct Packed {
    x_mass: Vec<[f32; 4]>,
    v_volume: Vec<[f32; 4]>,
    f: Vec<[[f32; 4]; 3]>,
    c: Vec<[[f32; 4]; 3]>,
    alpha: Vec<f32>,
}

impl Packed {
    pub(super) fn of(p: &Particles) -> Packed {
        let with = |v: &[DVec3], w: &[f64]| -> Vec<[f32; 4]> {
            v.iter()
                .zip(w)
                .map(|(v, w)| v.as_vec3().extend(*w as f32).to_array())
                .collect()
        };
        Packed {
            x_mass: with(&p.x, &p.mass),
            v_volume: with(&p.v, &p.volume0),
            f: p.f.iter().map(|m| mat3_to_gpu(*m)).collect(),
            c: p.c.iter().map(|m| mat3_to_gpu(*m)).collect(),
            alpha: p.alpha.iter().map(|a| *a as f32).collect(),
        }
    }
}

/// The grid pool's sizes in blocks of 4³ nodes: every block of the domain, the most this
/// adapter holds, and the first pool.
#[derive(Clone, Copy, Debug)]
pub(super) struct PoolSize {
    pub domain: u32,
    pub max: u32,
    pub first: u32,
}

impl PoolSize {
    pub(super) fn of(
        gpu: &GpuContext,
        particles: &Particles,
        grid: &Grid,
        (path, step, separation): (P2gPath, &GpuStep, bool),
    ) -> Result<PoolSize, SimSetupError> {
        let domain = grid.nodes().map(|n| n.div_ceil(BLOCK)).element_product();
        let max = max_pool_blocks(&gpu.limits, (path, step, separation), domain);
        if domain > max {
            // Said at setup, not hours in: the domain is larger than any pool this adapter
            // holds, so only a moving region that stays within the cap can run.
            log::warn!(
                "the simulation's domain has {domain} blocks of 4³ grid nodes and this adapter's grid pool holds at most {max} (its grid texture and one storage binding): the run stops with an error if the moving region grows past that; a larger simulation.dx or a smaller simulation.domain avoids it"
            );
        }
        let reached = blocks_reached(particles, grid);
        if reached > max {
            return Err(SimSetupError::PoolAtLimit {
                needed: reached,
                limit: max,
            });
        }
        Ok(PoolSize {
            domain,
            max,
            first: initial_pool(reached, max),
        })
    }
}

/// The buffers whose size follows the pool's: the scatter's sums, the grid textures, the
/// active-block list and the two-field arrays.
pub(super) struct PoolBuffers {
    grid: wgpu::Buffer,
    grid_velocity: GridTexture,
    grid_velocity_change: GridTexture,
    active_blocks: wgpu::Buffer,
    damage: wgpu::Buffer,
    ridge: wgpu::Buffer,
    far_field: wgpu::Buffer,
}

impl PoolBuffers {
    pub(super) fn new(
        gpu: &GpuContext,
        (path, step, separation): (P2gPath, &GpuStep, bool),
        blocks: u32,
    ) -> PoolBuffers {
        let two = |per_node| separation_bytes(separation, blocks, per_node);
        PoolBuffers {
            grid: zeroed(gpu, "sim grid pool", sums_bytes(path, step, blocks)),
            grid_velocity: GridTexture::new(&gpu.device, "sim grid velocity", blocks),
            grid_velocity_change: velocity_change_texture(&gpu.device, step, blocks),
            active_blocks: zeroed(gpu, "sim active blocks", u64::from(blocks) * 4),
            damage: zeroed(gpu, "sim damage field", two(8)),
            ridge: zeroed(gpu, "sim ridge", two(16)),
            far_field: zeroed(gpu, "sim far field", two(32)),
        }
    }

    /// These buffers in place of `b`'s.
    pub(super) fn install(self, b: &mut StepBuffers) {
        b.grid = self.grid;
        b.grid_velocity = self.grid_velocity;
        b.grid_velocity_change = self.grid_velocity_change;
        b.active_blocks = self.active_blocks;
        b.damage = self.damage;
        b.ridge = self.ridge;
        b.far_field = self.far_field;
    }
}

/// What [`allocate`] sizes the buffers by.
pub(super) struct Layout<'a> {
    pub particles: &'a Particles,
    pub grid: &'a Grid,
    pub params: &'a StepParams,
    pub step: &'a GpuStep,
    pub path: P2gPath,
    pub separation: bool,
    pub pool: PoolSize,
    pub pages: Pages,
}

/// Each particle's material word: its material's index and the actions acting on it.
fn material_words(l: &Layout) -> Vec<u32> {
    let members = &l.params.actions.members;
    let of = |p: usize| members.get(p).copied().unwrap_or(0);
    let m = &l.particles.material;
    (0..m.len())
        .map(|p| codes::material_word(m[p], of(p)))
        .collect()
}

/// Every buffer of the step, the particle arrays uploaded and the rest zeroed.
pub(super) fn allocate(gpu: &GpuContext, l: &Layout) -> StepBuffers {
    let device = &gpu.device;
    let n = l.particles.len() as u32;
    let nn = u64::from(n);
    let packed = Packed::of(l.particles);
    let pool = PoolBuffers::new(gpu, (l.path, l.step, l.separation), l.pool.first);
    let surface: &[f32] = match &l.params.boundaries.surface {
        Some(s) => &s.phi,
        None => &[0.0],
    };
    StepBuffers {
        step: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("sim step"),
            contents: bytemuck::bytes_of(l.step),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        }),
        x_mass: init(gpu, "sim x_mass", &packed.x_mass, true),
        v_volume: init(gpu, "sim v_volume", &packed.v_volume, true),
        deformation: init(gpu, "sim F", &packed.f, true),
        affine_velocity: init(gpu, "sim C", &packed.c, true),
        alpha: init(gpu, "sim alpha", &packed.alpha, true),
        material: init(gpu, "sim material", &material_words(l), false),
        keys: zeroed(gpu, "sim cell keys", nn * 4),
        values: zeroed(gpu, "sim cell values", nn * 4),
        keys_alt: zeroed(gpu, "sim cell keys alt", nn * 4),
        values_alt: zeroed(gpu, "sim cell values alt", nn * 4),
        key_count: init(gpu, "sim key count", &[n], false),
        affine: zeroed(gpu, "sim affine", nn * 48),
        // Each cell's run of sorted particles: the gather path's alone.
        ranges: zeroed(
            gpu,
            "sim cell ranges",
            match l.path {
                P2gPath::Gather => gather_range_entries(l.grid.cells) * 8,
                _ => 16,
            },
        ),
        grid: pool.grid,
        grid_velocity: pool.grid_velocity,
        grid_velocity_change: pool.grid_velocity_change,
        block_flags: zeroed(gpu, "sim block flags", u64::from(l.pool.domain) * 4),
        block_slot: zeroed(gpu, "sim block slots", u64::from(l.pool.domain) * 4),
        surface: init(gpu, "sim surface phi", surface, false),
        active_blocks: pool.active_blocks,
        block_args: device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("sim block dispatch"),
            size: u64::from(BlockArg::WORDS) * 4,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::INDIRECT
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        }),
        flags: zeroed(gpu, "sim watchdog flags", WATCHDOG_BYTES),
        damage: pool.damage,
        ridge: pool.ridge,
        damage_gradient: zeroed(
            gpu,
            "sim damage gradient",
            if l.separation { nn.max(1) * 16 } else { 16 },
        ),
        far_field: pool.far_field,
        pages: PageRanges::new(device, "sim particle pages", l.pages),
    }
}
