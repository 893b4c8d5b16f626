//! Stable GPU sort of (key, value) u32 pairs by their low bits, in passes of one digit,
//! each pass a count, an exclusive scan of the counts and a scatter. Two ways to run a
//! pass, chosen by [`Executor`], with the same result (a stable sort is unique):
//!
//! - on a GPU, a block radix sort (`shaders/gpu/radix_sort.wgsl`): 4-bit digits, blocks
//!   of 2048 keys ranked by a workgroup scan;
//! - on a CPU driver, a counting sort over chunks (`shaders/gpu/chunk_sort.wgsl`): one
//!   invocation walks each of a few dozen chunks in order, with digits of up to 13 bits,
//!   so that a tile key needs one pass and a 32-bit depth three, with no barrier or atomic;
//!   a small sort takes narrower digits, since every pass pays for all of its counters
//!   ([`chunk_digits`]).
//!
//! The number of keys is read on the GPU from a one-element buffer, so a sort can follow a
//! pass that decides how many keys there are without a CPU round trip.

use wgpu::util::DeviceExt;

use bytemuck::{Pod, Zeroable};

use super::scan::{Scan, ScanPlan};
use super::wgsl::Source;
use super::{Executor, Kernel, Shader};

/// `SortParams` of `shaders/gpu/radix_sort.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct SortParams {
    pub shift: u32,
    pub num_blocks: u32,
    pub _pad: [u32; 2],
}

/// `ChunkSortParams` of `shaders/gpu/chunk_sort.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct ChunkSortParams {
    pub shift: u32,
    pub bins: u32,
    pub chunks: u32,
    pub _pad: u32,
}

/// Keys per workgroup of the block radix sort (`BLOCK` in the shader).
pub const BLOCK: u32 = 2048;
/// Digit bits per pass of the block radix sort.
pub const BITS_PER_PASS: u32 = 4;

/// Invocations per workgroup of the chunk sort: one SIMD vector of a 256-bit CPU driver.
pub const CHUNK_LANES: u32 = 8;
/// The chunk sort's counters (digits × chunks) stay under this, which sets its digit width.
const CHUNK_COUNTERS: u32 = 1 << 20;
/// The chunk sort's counters per key of its capacity (and at least [`CHUNK_COUNTERS_MIN`]
/// in all), which narrows the digits of small sorts: each pass clears, scans and walks
/// every counter, so a small sort with wide digits spends its time on counters no key uses.
const CHUNK_COUNTERS_PER_KEY: u32 = 4;
const CHUNK_COUNTERS_MIN: u32 = 1 << 14;
/// Keys one invocation of the chunk sort walks at most, and its widest digit: lavapipe
/// stops an invocation after 65535 loop iterations in all (see `chunk_sort.wgsl`).
pub const CHUNK_KEYS: u32 = 1 << 15;
const CHUNK_DIGIT_BITS: u32 = 13;

/// Invocations per workgroup and keys per invocation of the block radix sort (`WG`,
/// `KEYS_PER_THREAD`).
pub fn shape(executor: Executor) -> (u32, u32) {
    match executor {
        Executor::Gpu => (256, 8),
        Executor::Cpu => (64, 32),
    }
}

/// Chunks of the chunk sort for `capacity` keys: at least a few workgroups per core of the
/// machine running the driver (`cores`), so that every core has work and the last to
/// finish waits little, and enough that no chunk holds more than [`CHUNK_KEYS`].
pub fn chunks(capacity: u32, cores: u32) -> u32 {
    let for_cores = CHUNK_LANES * (4 * cores).clamp(4, 64);
    let for_limit = capacity.div_ceil(CHUNK_KEYS).next_multiple_of(CHUNK_LANES);
    for_cores.max(for_limit)
}

/// How the passes run: see the module documentation.
enum Method {
    Blocks,
    /// `cores`: the cores the driver runs workgroups on, which sets the chunk count.
    Chunks {
        cores: u32,
    },
}

pub struct RadixSort {
    method: Method,
    count: Kernel,
    /// The chunk sort's digit prefix, between the count and the scan.
    prefix: Option<Kernel>,
    scatter: Kernel,
}

struct Pass {
    count_bind: wgpu::BindGroup,
    prefix_bind: Option<wgpu::BindGroup>,
    scatter_bind: wgpu::BindGroup,
}

/// Everything needed to sort fixed buffers of a given capacity by their low `bits` bits.
pub struct SortPlan {
    /// Workgroups of each count and scatter dispatch, and of the chunk sort's digit prefix.
    groups: u32,
    prefix_groups: u32,
    passes: Vec<Pass>,
    scan: ScanPlan,
    key_starts: Option<wgpu::Buffer>,
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

/// Digit bits of each pass of the block radix sort for `bits` key bits.
pub fn pass_count(bits: u32) -> u32 {
    bits.div_ceil(BITS_PER_PASS).max(1)
}

/// Digit bits of each pass of the chunk sort over `chunks` chunks for `bits` key bits of
/// `capacity` keys: as few passes as the counter budget allows, the bits split evenly
/// between them.
pub fn chunk_digits(bits: u32, chunks: u32, capacity: u32) -> Vec<u32> {
    let budget = capacity
        .saturating_mul(CHUNK_COUNTERS_PER_KEY)
        .clamp(CHUNK_COUNTERS_MIN, CHUNK_COUNTERS);
    let widest = (budget / chunks).max(2).ilog2().min(CHUNK_DIGIT_BITS);
    let bits = bits.clamp(1, 32);
    let passes = bits.div_ceil(widest);
    let width = bits.div_ceil(passes);
    vec![width; passes as usize]
}

impl SortPlan {
    /// After an odd number of passes the sorted pairs are in `keys_alt`/`values_alt`.
    pub fn result_in_alternates(&self) -> bool {
        self.passes.len() % 2 == 1
    }

    /// Passes over the keys (each a count, a scan and a scatter).
    pub fn passes(&self) -> usize {
        self.passes.len()
    }

    /// After a chunk sort whose keys fit its one digit: for every key value, the slot of
    /// its first key (the exclusive prefix sum of the values' counts), so that a value's
    /// keys lie from its start to the next value's.
    pub fn key_starts(&self) -> Option<&wgpu::Buffer> {
        self.key_starts.as_ref()
    }
}

/// The block radix sort's WGSL, compiled for the workgroup shape of `executor`.
pub fn source(executor: Executor) -> String {
    let (threads, keys_per_thread) = shape(executor);
    debug_assert_eq!(threads * keys_per_thread, BLOCK);
    Source::new()
        .define("WG", threads)
        .define("KEYS_PER_THREAD", keys_per_thread)
        .pass(include_str!("../../shaders/gpu/radix_sort.wgsl"))
}

/// The chunk sort's WGSL.
pub fn chunk_source() -> String {
    Source::new()
        .define("LANES", CHUNK_LANES)
        .pass(include_str!("../../shaders/gpu/chunk_sort.wgsl"))
}

fn uniform(device: &wgpu::Device, bytes: &[u8]) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("sort params"),
        contents: bytes,
        usage: wgpu::BufferUsages::UNIFORM,
    })
}

impl RadixSort {
    /// The sort that suits `executor`.
    pub fn new(device: &wgpu::Device, executor: Executor) -> RadixSort {
        match executor {
            Executor::Gpu => RadixSort::blocks(device, executor),
            Executor::Cpu => {
                let cores = std::thread::available_parallelism().map_or(2, |n| n.get() as u32);
                RadixSort::chunked(device, cores)
            }
        }
    }

    /// The block radix sort, with the workgroup shape of `executor`.
    pub fn blocks(device: &wgpu::Device, executor: Executor) -> RadixSort {
        let shader = Shader::new(device, "radix_sort", &source(executor));
        RadixSort {
            method: Method::Blocks,
            count: shader.kernel(device, "radix count_digits", "count_digits"),
            prefix: None,
            scatter: shader.kernel(device, "radix scatter", "scatter"),
        }
    }

    /// The counting sort over chunks, as many as suit a driver running on `cores` cores
    /// ([`chunks`]).
    pub fn chunked(device: &wgpu::Device, cores: u32) -> RadixSort {
        let shader = Shader::new(device, "chunk_sort", &chunk_source());
        RadixSort {
            method: Method::Chunks { cores },
            count: shader.kernel(device, "chunk sort count", "count_chunks"),
            prefix: Some(shader.kernel(device, "chunk sort digit prefix", "digit_prefix")),
            scatter: shader.kernel(device, "chunk sort scatter", "scatter_chunks"),
        }
    }

    // Over 80 lines on purpose: the radix sort's passes and their buffers sized in the order
    // they run.
    pub fn plan(
        &self,
        device: &wgpu::Device,
        scan: &Scan,
        buffers: &SortBuffers,
        capacity: u32,
        bits: u32,
    ) -> SortPlan {
        let layout = match self.method {
            Method::Blocks => blocks_layout(device, capacity, bits),
            Method::Chunks { cores } => chunks_layout(device, capacity, bits, cores),
        };
        let storage = |label, words: u32| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: u64::from(words.max(1)) * 4,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        };
        let counts = storage("sort digit counts", layout.counters);
        // The chunk sort scans the digits' totals; the block sort its counters themselves.
        let digit_base = (layout.digits > 0).then(|| storage("sort digit bases", layout.digits));
        let scan_plan = match &digit_base {
            Some(base) => scan.plan(device, base, layout.digits),
            None => scan.plan(device, &counts, layout.counters),
        };
        let passes: Vec<Pass> = layout
            .params
            .iter()
            .enumerate()
            .map(|(p, params)| {
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
                let mut digits = vec![
                    ("params", params),
                    ("key_count", buffers.count),
                    ("keys_in", kin),
                    ("counts", &counts),
                ];
                let prefix_bind = self
                    .prefix
                    .as_ref()
                    .zip(digit_base.as_ref())
                    .map(|(k, base)| {
                        digits.push(("digit_base", base));
                        k.bind_named(
                            device,
                            &[
                                ("params", params),
                                ("counts", &counts),
                                ("digit_base", base),
                            ],
                        )
                    });
                let moves = [("values_in", vin), ("keys_out", kout), ("values_out", vout)];
                Pass {
                    count_bind: self.count.bind_named(device, &digits[..4]),
                    prefix_bind,
                    scatter_bind: self
                        .scatter
                        .bind_named(device, &[&digits[..], &moves].concat()),
                }
            })
            .collect();
        let mut owned = layout.params;
        owned.push(counts);
        // The digits' bases are the keys' starts when one pass covered every key bit.
        let key_starts =
            digit_base.filter(|_| passes.len() == 1 && layout.digits >= 1 << bits.min(31));
        SortPlan {
            groups: layout.groups,
            prefix_groups: layout.digits.div_ceil(CHUNK_LANES),
            passes,
            scan: scan_plan,
            key_starts,
            _buffers: owned,
        }
    }

    pub fn record(&self, cpass: &mut wgpu::ComputePass, scan: &Scan, plan: &SortPlan) {
        for pass in &plan.passes {
            self.count.dispatch(cpass, &pass.count_bind, plan.groups);
            if let (Some(prefix), Some(bind)) = (&self.prefix, &pass.prefix_bind) {
                prefix.dispatch(cpass, bind, plan.prefix_groups);
            }
            scan.record(cpass, &plan.scan);
            self.scatter
                .dispatch(cpass, &pass.scatter_bind, plan.groups);
        }
    }
}

/// The sizes of one sort: each pass's parameters, the counters, the digits of a pass (the
/// chunk sort's; 0 for the block sort) and the workgroups of a count or scatter.
struct Layout {
    params: Vec<wgpu::Buffer>,
    counters: u32,
    digits: u32,
    groups: u32,
}

fn blocks_layout(device: &wgpu::Device, capacity: u32, bits: u32) -> Layout {
    let blocks = capacity.div_ceil(BLOCK).max(1);
    let params = (0..pass_count(bits))
        .map(|p| {
            let p = SortParams {
                shift: p * BITS_PER_PASS,
                num_blocks: blocks,
                _pad: [0; 2],
            };
            uniform(device, bytemuck::bytes_of(&p))
        })
        .collect();
    Layout {
        params,
        counters: blocks * 16,
        digits: 0,
        groups: blocks,
    }
}

fn chunks_layout(device: &wgpu::Device, capacity: u32, bits: u32, cores: u32) -> Layout {
    let chunks = chunks(capacity, cores);
    // The digit prefix walks every chunk in one invocation (see `chunk_sort.wgsl`).
    assert!(
        chunks <= CHUNK_KEYS,
        "{capacity} keys are more than the chunk sort can take"
    );
    let widths = chunk_digits(bits, chunks, capacity);
    let params = widths
        .iter()
        .scan(0, |shift, &width| {
            let p = ChunkSortParams {
                shift: *shift,
                bins: 1 << width,
                chunks,
                _pad: 0,
            };
            *shift += width;
            Some(uniform(device, bytemuck::bytes_of(&p)))
        })
        .collect();
    let digits = 1 << widths[0];
    Layout {
        params,
        counters: digits * chunks,
        digits,
        groups: chunks / CHUNK_LANES,
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
        let src = chunk_source();
        assert_layout!(
            &src,
            ChunkSortParams,
            "ChunkSortParams",
            [shift, bins, chunks]
        );
    }

    #[test]
    fn chunks_and_digits_stay_within_the_budgets() {
        for capacity in [0, 1, 5000, 1 << 21, 27_000_000, 1 << 30] {
            for cores in [1, 2, 16, 256] {
                let chunks = chunks(capacity, cores);
                assert_eq!(chunks % CHUNK_LANES, 0);
                assert!(capacity.div_ceil(chunks) <= CHUNK_KEYS, "{capacity} keys");
                assert!(chunks <= CHUNK_KEYS, "{capacity} keys");
                for bits in 1..=32 {
                    let digits = chunk_digits(bits, chunks, capacity);
                    assert!(
                        digits.iter().sum::<u32>() >= bits,
                        "{bits} bits, {chunks} chunks"
                    );
                    assert!(digits[0] <= CHUNK_DIGIT_BITS);
                    assert!(
                        (1u64 << digits[0]) * u64::from(chunks)
                            <= u64::from(CHUNK_COUNTERS).max(2 * u64::from(chunks))
                    );
                    assert!(digits.iter().all(|&w| w == digits[0]));
                }
            }
        }
        // The tile keys of a 1080p frame (13 bits) in one pass over 64 chunks.
        assert_eq!(chunk_digits(13, 64, 1 << 21), vec![13]);
        assert_eq!(chunk_digits(32, 64, 1 << 21), vec![11; 3]);
        // A small simulation's cell keys: two narrow passes rather than 8192 counters a
        // chunk for 1331 keys.
        assert_eq!(chunk_digits(13, 64, 1331), vec![7, 7]);
    }
}
