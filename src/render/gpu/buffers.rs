//! The renderer's per-frame buffers, sized for the frame and the uploaded Gaussians and
//! grown only when needed.

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
        // The colour, and the passes' planes (rasterize.wgsl).
        let planes = u64::from(self.passes.planes());
        let image_bytes = u64::from(width) * u64::from(height) * 4 * planes;
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
            image: storage(
                device,
                "image",
                pixels * 4 * planes,
                wgpu::BufferUsages::COPY_SRC,
            ),
            readback: readback("image readback", pixels * 4 * planes),
            stats_readback: readback("stats readback", std::mem::size_of::<Stats>() as u64),
        });
        self.bound = None;
        Ok(())
    }
}
