//! Runs of equal keys in a sorted key array (`shaders/gpu/ranges.wgsl`): for every key k,
//! the start and end (exclusive) of its run. The renderer finds each tile's pairs with it,
//! the simulation each cell's particles and the normals pass each hash cell's Gaussians.

use super::sort::SortPlan;
use super::{Kernel, Shader};

/// `shaders/gpu/ranges.wgsl`: `kernel`, one invocation per sorted key, the key count read
/// on the GPU; or `from_starts`, one invocation per key value, after a sort that left each
/// value's first slot ([`SortPlan::key_starts`]).
pub struct Ranges {
    pub kernel: Kernel,
    pub from_starts: Kernel,
}

/// What a sort left for the ranges: its keys (at most `capacity`, their number in
/// `key_count`) and, where it has them, each key value's first slot
/// ([`SortPlan::key_starts`]).
pub struct SortedKeys<'a> {
    pub key_count: &'a wgpu::Buffer,
    pub sorted_keys: &'a wgpu::Buffer,
    pub key_starts: Option<&'a wgpu::Buffer>,
    pub capacity: u32,
}

/// A bound pass writing the ranges, and its workgroups.
pub struct RangesPass {
    bind: wgpu::BindGroup,
    from_starts: bool,
    groups: u32,
}

impl Ranges {
    pub fn new(device: &wgpu::Device) -> Ranges {
        let shader = Shader::new(
            device,
            "ranges",
            include_str!("../../shaders/gpu/ranges.wgsl"),
        );
        Ranges {
            kernel: shader.kernel(device, "ranges", "main"),
            from_starts: shader.kernel(device, "ranges from starts", "from_starts"),
        }
    }

    /// The ranges of the keys `sort` sorted into `sorted_keys` (at most `capacity` of
    /// them, their number in `key_count`), one (start, end) per key value of `ranges`: read
    /// off the sort's key starts where it has them, else found by comparing neighbours.
    pub fn after_sort(
        &self,
        device: &wgpu::Device,
        sort: &SortPlan,
        key_count: &wgpu::Buffer,
        sorted_keys: &wgpu::Buffer,
        capacity: u32,
        ranges: &wgpu::Buffer,
    ) -> RangesPass {
        let keys = SortedKeys {
            key_count,
            sorted_keys,
            key_starts: sort.key_starts(),
            capacity,
        };
        self.after(device, &keys, ranges)
    }

    /// As [`after_sort`](Self::after_sort), from what the sort left in `keys`.
    pub fn after(
        &self,
        device: &wgpu::Device,
        keys: &SortedKeys,
        ranges: &wgpu::Buffer,
    ) -> RangesPass {
        let values = (ranges.size() / 8) as u32;
        match keys.key_starts {
            Some(starts) => RangesPass {
                bind: self.from_starts.bind_named(
                    device,
                    &[
                        ("key_count", keys.key_count),
                        ("starts", starts),
                        ("ranges", ranges),
                    ],
                ),
                from_starts: true,
                groups: values.div_ceil(256),
            },
            None => RangesPass {
                bind: self.bind(device, keys.key_count, keys.sorted_keys, ranges),
                from_starts: false,
                groups: keys.capacity.div_ceil(256),
            },
        }
    }

    pub fn record(&self, cpass: &mut wgpu::ComputePass, pass: &RangesPass) {
        let kernel = if pass.from_starts {
            &self.from_starts
        } else {
            &self.kernel
        };
        kernel.dispatch(cpass, &pass.bind, pass.groups);
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
