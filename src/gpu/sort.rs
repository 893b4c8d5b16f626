//! Stable GPU radix sort of (key, value) pairs (`shaders/gpu/radix_sort.wgsl`), 4 bits
//! per pass. The number of keys is read on the GPU from a one-element buffer, so a sort
//! can follow a pass that decides how many keys there are without a CPU round trip.

use wgpu::util::DeviceExt;

use bytemuck::{Pod, Zeroable};

use super::scan::{Scan, ScanPlan};
use super::{Executor, Kernel, Shader};

/// `SortParams` of `shaders/gpu/radix_sort.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct SortParams {
    pub shift: u32,
    pub num_blocks: u32,
    pub _pad: [u32; 2],
}

/// Keys per workgroup (`BLOCK` in the shader).
pub const BLOCK: u32 = 2048;
pub const BITS_PER_PASS: u32 = 4;

/// Invocations per workgroup and keys per invocation (`WG`, `KEYS_PER_THREAD`): a CPU
/// driver pays for each of the ranking scan's barriers once per SIMD vector of the
/// workgroup, so there a block is ranked by fewer invocations holding more keys.
pub fn shape(executor: Executor) -> (u32, u32) {
    match executor {
        Executor::Gpu => (256, 8),
        Executor::Cpu => (64, 32),
    }
}

pub struct RadixSort {
    count: Kernel,
    scatter: Kernel,
}

struct Pass {
    count_bind: wgpu::BindGroup,
    scatter_bind: wgpu::BindGroup,
}

/// Everything needed to sort fixed buffers of a given capacity by their low `bits` bits.
pub struct SortPlan {
    blocks: u32,
    passes: Vec<Pass>,
    scan: ScanPlan,
    _buffers: Vec<wgpu::Buffer>,
}

/// The buffers of one sort: `keys`/`values` hold the input; the passes ping-pong with
/// `keys_alt`/`values_alt`, and the output is in whichever pair the last pass wrote
/// ([`SortPlan::result_in_alternates`]) — no copy, so that a whole sort can be recorded in
/// one compute pass.
pub struct SortBuffers<'a> {
    pub count: &'a wgpu::Buffer,
    pub keys: &'a wgpu::Buffer,
    pub values: &'a wgpu::Buffer,
    pub keys_alt: &'a wgpu::Buffer,
    pub values_alt: &'a wgpu::Buffer,
}

/// Passes for `bits` key bits.
pub fn pass_count(bits: u32) -> u32 {
    bits.div_ceil(BITS_PER_PASS).max(1)
}

impl SortPlan {
    /// After an odd number of passes the sorted pairs are in `keys_alt`/`values_alt`.
    pub fn result_in_alternates(&self) -> bool {
        self.passes.len() % 2 == 1
    }
}

/// The sort's WGSL with the workgroup shape of `executor` prepended.
pub fn source(executor: Executor) -> String {
    let (threads, keys_per_thread) = shape(executor);
    debug_assert_eq!(threads * keys_per_thread, BLOCK);
    format!(
        "const WG: u32 = {threads}u;\nconst KEYS_PER_THREAD: u32 = {keys_per_thread}u;\n{}",
        include_str!("../../shaders/gpu/radix_sort.wgsl")
    )
}

impl RadixSort {
    pub fn new(device: &wgpu::Device, executor: Executor) -> RadixSort {
        let shader = Shader::new(device, "radix_sort", &source(executor));
        RadixSort {
            count: shader.kernel(device, "radix count_digits", "count_digits"),
            scatter: shader.kernel(device, "radix scatter", "scatter"),
        }
    }

    pub fn plan(
        &self,
        device: &wgpu::Device,
        scan: &Scan,
        buffers: &SortBuffers,
        capacity: u32,
        bits: u32,
    ) -> SortPlan {
        let blocks = capacity.div_ceil(BLOCK).max(1);
        let counts = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("radix digit counts"),
            size: u64::from(blocks) * 16 * 4,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let scan_plan = scan.plan(device, &counts, blocks * 16);
        let mut owned = Vec::new();
        let mut passes = Vec::new();
        for p in 0..pass_count(bits) {
            let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("radix params"),
                contents: bytemuck::bytes_of(&SortParams {
                    shift: p * BITS_PER_PASS,
                    num_blocks: blocks,
                    _pad: [0; 2],
                }),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let (kin, vin, kout, vout) = if p % 2 == 0 {
                (
                    buffers.keys,
                    buffers.values,
                    buffers.keys_alt,
                    buffers.values_alt,
                )
            } else {
                (
                    buffers.keys_alt,
                    buffers.values_alt,
                    buffers.keys,
                    buffers.values,
                )
            };
            let digits = [
                ("params", &params),
                ("key_count", buffers.count),
                ("keys_in", kin),
                ("counts", &counts),
            ];
            let moves = [("values_in", vin), ("keys_out", kout), ("values_out", vout)];
            passes.push(Pass {
                count_bind: self.count.bind_named(device, &digits),
                scatter_bind: self
                    .scatter
                    .bind_named(device, &[&digits[..], &moves].concat()),
            });
            owned.push(params);
        }
        owned.push(counts);
        SortPlan {
            blocks,
            passes,
            scan: scan_plan,
            _buffers: owned,
        }
    }

    pub fn record(&self, cpass: &mut wgpu::ComputePass, scan: &Scan, plan: &SortPlan) {
        for pass in &plan.passes {
            self.count.dispatch(cpass, &pass.count_bind, plan.blocks);
            scan.record(cpass, &plan.scan);
            self.scatter
                .dispatch(cpass, &pass.scatter_bind, plan.blocks);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::layout_check::assert_layout;

    #[test]
    fn params_match_wgsl() {
        let src = source(Executor::Gpu);
        assert_layout!(&src, SortParams, "SortParams", [shift, num_blocks]);
    }
}
