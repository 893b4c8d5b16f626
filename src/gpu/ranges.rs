//! Runs of equal keys in a sorted key array (`shaders/gpu/ranges.wgsl`): for every key k,
//! the start and end (exclusive) of its run. The renderer finds each tile's pairs with it,
//! the simulation each cell's particles and the normals pass each hash cell's Gaussians.

use super::Kernel;

/// `shaders/gpu/ranges.wgsl`: one invocation per sorted key, the key count read on the GPU.
pub struct Ranges {
    pub kernel: Kernel,
}

impl Ranges {
    pub fn new(device: &wgpu::Device) -> Ranges {
        let src = include_str!("../../shaders/gpu/ranges.wgsl");
        Ranges {
            kernel: Kernel::new(device, "ranges", src, "main"),
        }
    }

    /// The pass over `sorted_keys` (their number in `key_count`) writing `ranges`, one
    /// (start, end) per key value.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        key_count: &wgpu::Buffer,
        sorted_keys: &wgpu::Buffer,
        ranges: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        self.kernel.bind_named(
            device,
            &[
                ("key_count", key_count),
                ("sorted_keys", sorted_keys),
                ("ranges", ranges),
            ],
        )
    }
}
