//! The renderer's state between frames: lighting, lights, the uploaded Gaussians and
//! their pages, readbacks of what it holds, and its GPU memory.

use super::*;

impl GpuRenderer {
    /// Relight every frame from now on (after [`upload`](Self::upload): `setup.shading` has
    /// one entry per uploaded Gaussian). Lights come per frame from
    /// [`set_lights`](Self::set_lights); until then only the ambient term lights the scene.
    pub fn set_lighting(
        &mut self,
        gpu: &GpuContext,
        setup: &LightingSetup,
    ) -> Result<(), GpuError> {
        let count = self.splats.as_ref().map_or(0, |s| s.count) as usize;
        if let Some(s) = self.splats.as_ref().filter(|s| s.pages.pages.count > 1) {
            return Err(too_many_pages_for("lighting", gpu, s.pages.pages));
        }
        if setup.shading.len() != count {
            return Err(GpuError::Failed(format!(
                "lighting: {} shading entries for {count} uploaded Gaussians",
                setup.shading.len()
            )));
        }
        if let Some(bad) = setup
            .shading
            .iter()
            .find(|s| s[1] as usize >= setup.materials.len())
        {
            return Err(GpuError::Failed(format!(
                "lighting: material {} of {}",
                bad[1],
                setup.materials.len()
            )));
        }
        self.lighting = Some(Lighting::new(gpu, setup)?);
        // The lighting passes join the frame's: bind them all again.
        self.bound = None;
        Ok(())
    }

    /// The point lights of the next frames (at most `max_lights` of the setup are used).
    pub fn set_lights(&mut self, lights: &[PointLight]) {
        if let Some(l) = &mut self.lighting {
            l.frame_lights = lights.to_vec();
        }
    }

    /// Per-Gaussian shading records (packed normal, material) when lighting is set: the
    /// derive pass writes the simulated Gaussians' normals here.
    pub fn shading_buffer(&self) -> Option<&wgpu::Buffer> {
        self.lighting.as_ref().map(|l| &l.shading)
    }

    /// The shading records given to [`set_lighting`](Self::set_lighting) (packed rest
    /// normal, material per Gaussian), if lighting is set.
    pub fn rest_shading(&self) -> Option<&[[u32; 2]]> {
        self.lighting.as_ref().map(|l| l.rest_shading.as_slice())
    }

    /// The uploaded Gaussians on the GPU (`layout::GaussianIn` records): a simulation's
    /// derive pass writes the deformed Gaussians here, so frames need no CPU round trip.
    pub fn gaussian_buffer(&self) -> Option<&wgpu::Buffer> {
        self.splats.as_ref().map(|s| &s.gaussians)
    }

    /// Read the Gaussians back as the renderer has them (after any derive pass).
    pub fn read_gaussians(&self, gpu: &GpuContext) -> Result<Vec<GaussianIn>, GpuError> {
        let Some(s) = &self.splats else {
            return Ok(Vec::new());
        };
        let bytes = crate::gpu::buffers::copy_out(gpu, &s.gaussians)?;
        let n = s.count as usize * std::mem::size_of::<GaussianIn>();
        Ok(bytemuck::pod_collect_to_vec(&bytes[..n]))
    }

    /// The shadow transmittance of the last frame, light-major (`shadow_transmit.wgsl`), or
    /// None without shadows. Only the voxels some visible Gaussian looked up are current;
    /// the others hold stale values. For tests of the shadow passes.
    pub fn read_transmittance(&self, gpu: &GpuContext) -> Result<Option<Vec<f32>>, GpuError> {
        let Some(l) = self.lighting.as_ref().filter(|l| l.grid.is_some()) else {
            return Ok(None);
        };
        let bytes = crate::gpu::buffers::copy_out(gpu, &l.transmittance)?;
        Ok(Some(bytemuck::pod_collect_to_vec(&bytes)))
    }

    /// Upload a set of Gaussians (replacing the previous one). Lighting set for a different
    /// number of Gaussians is dropped: call [`set_lighting`](Self::set_lighting) again.
    pub fn upload(&mut self, gpu: &GpuContext, splats: &Splats) -> Result<(), GpuError> {
        let n = splats.len() as u64;
        // Lighting holds one shading record per Gaussian: a different set needs a new one.
        if self
            .lighting
            .as_ref()
            .is_some_and(|l| l.rest_shading.len() as u64 != n)
        {
            self.lighting = None;
        }
        let mut pages = Self::pages_for(gpu, splats.len())?;
        if let Some(limit) = self.page_limit.filter(|l| *l < pages.size) {
            pages = Pages::with_size(pages.total, limit);
            if pages.count > max_pages(gpu) {
                return Err(too_many_pages_for("the renderer", gpu, pages));
            }
        }
        if pages.count > 1 && self.lighting.is_some() {
            return Err(too_many_pages_for("lighting", gpu, pages));
        }
        if self.tile_keys.pages != pages.count {
            // The passes that read projections in any order declare one binding per page.
            self.tile_keys =
                passes::TileKeys::new(&gpu.device, pages.count, self.tile_keys.scan.clone());
            self.rasterize = passes::Rasterize::new(gpu, pages.count, self.executor, self.passes);
        }
        let device = &gpu.device;
        let (gaussians, words) = layout::pack_splats(splats);
        let usage = wgpu::BufferUsages::empty();
        let b = SplatBuffers {
            count: n as u32,
            sh_degree: splats.sh_degree,
            gaussians: storage(device, "gaussians", n * 64, wgpu::BufferUsages::COPY_SRC),
            sh_words: storage(device, "sh words", n * SH_WORDS as u64 * 4, usage),
            projected: storage(device, "projected", n * 48, usage),
            tile_rects: storage(device, "tile rects", n * 8, usage),
            depth_keys: storage(device, "depth keys", n * 4, usage),
            depth_order: storage(device, "depth order", n * 4, usage),
            depth_keys_alt: storage(device, "depth keys alt", n * 4, usage),
            depth_order_alt: storage(device, "depth order alt", n * 4, usage),
            offsets: storage(device, "tile offsets", n * 4, usage),
            depth_count: storage(device, "depth count", 4, usage),
            // two 16-bit ids a word, all 0 until set_ids
            ids: storage(device, "ids", n.div_ceil(2).max(1) * 4, usage),
            pages: PageRanges::new(device, "gaussian pages", pages),
        };
        gpu.queue
            .write_buffer(&b.gaussians, 0, bytemuck::cast_slice(&gaussians));
        gpu.queue
            .write_buffer(&b.sh_words, 0, bytemuck::cast_slice(&words));
        gpu.queue
            .write_buffer(&b.depth_count, 0, bytemuck::bytes_of(&(n as u32)));
        self.splats = Some(b);
        self.bound = None;
        Ok(())
    }

    /// The id pass's id of each uploaded Gaussian (0: none; after [`upload`](Self::upload),
    /// one per Gaussian), kept until the next upload.
    pub fn set_ids(&mut self, gpu: &GpuContext, ids: &[u16]) -> Result<(), GpuError> {
        let Some(s) = &self.splats else {
            return Err(GpuError::Failed("set_ids before upload".into()));
        };
        if ids.len() != s.count as usize {
            return Err(GpuError::Failed(format!(
                "the id pass: {} ids for {} uploaded Gaussians",
                ids.len(),
                s.count
            )));
        }
        let mut words = vec![0u32; ids.len().div_ceil(2).max(1)];
        for (i, id) in ids.iter().enumerate() {
            words[i / 2] |= u32::from(*id) << (16 * (i % 2));
        }
        gpu.queue
            .write_buffer(&s.ids, 0, bytemuck::cast_slice(&words));
        Ok(())
    }

    /// The most Gaussians `gpu`'s limits allow: every page the passes bind, each array in
    /// one buffer.
    pub fn most_gaussians(gpu: &GpuContext) -> u64 {
        let page = Pages::new(
            u32::MAX / 2,
            SH_BYTES,
            gpu.limits.max_storage_buffer_binding_size,
        );
        (u64::from(page.size) * u64::from(max_pages(gpu)))
            .min(gpu.limits.max_buffer_size / SH_BYTES)
    }

    /// Bytes of GPU memory the renderer holds (Gaussians, projections, sorts, image).
    pub fn gpu_bytes(&self) -> u64 {
        let splats = self.splats.iter().flat_map(|s| {
            [
                &s.gaussians,
                &s.sh_words,
                &s.projected,
                &s.tile_rects,
                &s.depth_keys,
                &s.depth_order,
                &s.depth_keys_alt,
                &s.depth_order_alt,
                &s.offsets,
            ]
        });
        let frame = self.frame_buffers.iter().flat_map(|f| {
            [
                &f.tile_keys,
                &f.tile_values,
                &f.tile_keys_alt,
                &f.tile_values_alt,
                &f.ranges,
                &f.image,
                &f.readback,
            ]
        });
        splats.chain(frame).map(|b| b.size()).sum()
    }

    /// The pages `gaussians` Gaussians split into on `gpu`: as large as one storage binding
    /// holds of the largest record (the SH), as many as the passes can bind, each array in
    /// one buffer.
    pub fn pages_for(gpu: &GpuContext, gaussians: usize) -> Result<Pages, GpuError> {
        let n = gaussians as u64;
        let pages = Pages::new(
            gaussians as u32,
            SH_BYTES,
            gpu.limits.max_storage_buffer_binding_size,
        );
        let buffer = gpu.limits.max_buffer_size;
        if n * SH_BYTES > buffer || gaussians > u32::MAX as usize / 2 {
            return Err(GpuError::TooLarge {
                what: format!("the SH coefficients of {n} Gaussians"),
                needed: n * SH_BYTES,
                limit: buffer,
                advice: "render fewer Gaussians (raise the opacity threshold, or split the scene) or use a GPU with larger buffers".into(),
            });
        }
        if pages.count > max_pages(gpu) {
            return Err(too_many_pages_for("the renderer", gpu, pages));
        }
        Ok(pages)
    }
}
