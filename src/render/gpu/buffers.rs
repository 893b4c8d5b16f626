//! The renderer's per-frame buffers and sort plans, sized for the frame and the uploaded
//! Gaussians and grown only when needed, and the projection pass's bind group per page.

use super::*;

impl GpuRenderer {
    pub(super) fn ensure_frame_buffers(
        &mut self,
        gpu: &GpuContext,
        width: u32,
        height: u32,
        capacity: u32,
    ) -> Result<(), GpuError> {
        if let Some(f) = &self.frame_buffers {
            if f.width == width && f.height == height && f.capacity >= capacity {
                return Ok(());
            }
        }
        let image_bytes = u64::from(width) * u64::from(height) * 4;
        if image_bytes > gpu.max_binding() {
            return Err(GpuError::TooLarge {
                what: format!("a {width}×{height} image"),
                needed: image_bytes,
                limit: gpu.max_binding(),
                advice: "render a smaller image (--width/--height)".into(),
            });
        }
        let device = &gpu.device;
        let tiles = u64::from(width.div_ceil(TILE)) * u64::from(height.div_ceil(TILE));
        let cap = u64::from(capacity);
        let pixels = u64::from(width) * u64::from(height);
        let none = wgpu::BufferUsages::empty();
        let readback = |label: &str, size: u64| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        self.frame_buffers = Some(FrameBuffers {
            width,
            height,
            capacity,
            tile_keys: storage(device, "tile keys", cap * 4, none),
            tile_values: storage(device, "tile values", cap * 4, none),
            tile_keys_alt: storage(device, "tile keys alt", cap * 4, none),
            tile_values_alt: storage(device, "tile values alt", cap * 4, none),
            key_count: storage(device, "key count", 4, none),
            ranges: storage(device, "tile ranges", tiles * 8, none),
            image: storage(device, "image", pixels * 4, wgpu::BufferUsages::COPY_SRC),
            readback: readback("image readback", pixels * 4),
            stats_readback: readback("stats readback", std::mem::size_of::<Stats>() as u64),
        });
        self.plans = None;
        Ok(())
    }

    // Over 80 lines on purpose: every frame buffer sized from the frame's plan in one place,
    // so none is sized twice.
    pub(super) fn ensure_plans(&mut self, gpu: &GpuContext) {
        if self.plans.is_some() {
            return;
        }
        let device = &gpu.device;
        let s = self.splats.as_ref().expect("upload() before render()");
        let f = self.frame_buffers.as_ref().expect("frame buffers");
        let tiles = f.width.div_ceil(TILE) * f.height.div_ceil(TILE);
        let depth_sort = self.sort.plan(
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
        let tile_sort = self.sort.plan(
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
        // The depth sort leaves the order in whichever buffer its last pass wrote.
        let depth_order = if depth_sort.result_in_alternates() {
            &s.depth_order_alt
        } else {
            &s.depth_order
        };
        let projected: Vec<wgpu::BufferBinding> = (0..s.pages.pages.count)
            .map(|i| s.pages.pages.window(&s.projected, i, PROJECTED_BYTES))
            .collect();
        let (sorted_keys, sorted_values) = if tile_sort.result_in_alternates() {
            (&f.tile_keys_alt, &f.tile_values_alt)
        } else {
            (&f.tile_keys, &f.tile_values)
        };
        self.plans = Some(Plans {
            project: (0..s.pages.pages.count)
                .map(|i| self.project_bind(device, s, i))
                .collect(),
            depth_sort,
            gather: bind_with_pages(
                &self.tile_keys.gather,
                device,
                &[
                    ("frame", &self.frame),
                    ("tile_rects", &s.tile_rects),
                    ("depth_order", depth_order),
                    ("offsets", &s.offsets),
                ],
                &projected,
            ),
            offsets_scan: self.scan.plan(device, &s.offsets, s.count),
            total: bind_with_pages(
                &self.tile_keys.total,
                device,
                &[
                    ("frame", &self.frame),
                    ("tile_rects", &s.tile_rects),
                    ("depth_order", depth_order),
                    ("offsets", &s.offsets),
                    ("key_count", &f.key_count),
                    ("stats", &self.stats),
                ],
                &projected,
            ),
            emit: bind_with_pages(
                &self.tile_keys.emit,
                device,
                &[
                    ("frame", &self.frame),
                    ("tile_rects", &s.tile_rects),
                    ("depth_order", depth_order),
                    ("offsets", &s.offsets),
                    ("tile_keys", &f.tile_keys),
                    ("tile_values", &f.tile_values),
                ],
                &projected,
            ),
            ranges: self.tile_ranges.after_sort(
                device,
                &tile_sort,
                &f.key_count,
                sorted_keys,
                f.capacity,
                &f.ranges,
            ),
            tile_sort,
            rasterize: bind_with_pages(
                &self.rasterize.kernel,
                device,
                &[
                    ("frame", &self.frame),
                    ("ranges", &f.ranges),
                    ("tile_values", sorted_values),
                    ("image", &f.image),
                ],
                &projected,
            ),
        });
    }

    /// The projection pass over page `i` of the Gaussians.
    pub(super) fn project_bind(
        &self,
        device: &wgpu::Device,
        s: &SplatBuffers,
        i: u32,
    ) -> wgpu::BindGroup {
        let pages = &s.pages.pages;
        fn whole(b: &wgpu::Buffer) -> wgpu::BufferBinding<'_> {
            b.as_entire_buffer_binding()
        }
        self.project.kernel.bind_named_parts(
            device,
            &[
                ("frame", whole(&self.frame)),
                ("gaussians", pages.window(&s.gaussians, i, GAUSSIAN_BYTES)),
                ("sh_words", pages.window(&s.sh_words, i, SH_BYTES)),
                ("projected", pages.window(&s.projected, i, PROJECTED_BYTES)),
                ("tile_rects", whole(&s.tile_rects)),
                ("depth_keys", whole(&s.depth_keys)),
                ("depth_order", whole(&s.depth_order)),
                ("stats", whole(&self.stats)),
                ("page", s.pages.entry(i)),
            ],
        )
    }
}
