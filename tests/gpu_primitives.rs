//! The renderer's GPU building blocks against plain CPU versions: the prefix sum (with its
//! saturation), the stable sorts and the key ranges after them.

use splatter::gpu::buffers::copy_out;
use splatter::gpu::ranges::Ranges;
use splatter::gpu::scan::Scan;
use splatter::gpu::sort::{RadixSort, SortBuffers, SortPlan};
use splatter::gpu::{Executor, GpuContext};
use splatter::rng::SplitMix64;
use wgpu::util::DeviceExt;

fn gpu() -> GpuContext {
    GpuContext::new(None).expect("a wgpu adapter (install mesa-vulkan-drivers)")
}

fn upload(gpu: &GpuContext, data: &[u32]) -> wgpu::Buffer {
    let padded: Vec<u32> = if data.is_empty() {
        vec![0]
    } else {
        data.to_vec()
    };
    gpu.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("test data"),
            contents: bytemuck::cast_slice(&padded),
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
        })
}

fn download(gpu: &GpuContext, buffer: &wgpu::Buffer, n: usize) -> Vec<u32> {
    let bytes = copy_out(gpu, buffer).unwrap();
    bytemuck::cast_slice::<u8, u32>(&bytes)[..n].to_vec()
}

fn exclusive_scan(data: &[u32]) -> Vec<u32> {
    let mut sum = 0u32;
    data.iter()
        .map(|x| {
            let before = sum;
            sum = sum.saturating_add(*x);
            before
        })
        .collect()
}

#[test]
fn scan_matches_cpu_across_block_levels() {
    let gpu = gpu();
    let scan = Scan::new(&gpu.device);
    let mut rng = SplitMix64::new(3);
    // 1024 per block, 1024 blocks per level: these sizes use one, two and three levels.
    for n in [
        1usize,
        5,
        1023,
        1024,
        1025,
        4096 + 17,
        1_048_576 + 3,
        1_500_000,
    ] {
        let data: Vec<u32> = (0..n).map(|_| (rng.next_u64() % 20) as u32).collect();
        let buffer = upload(&gpu, &data);
        let plan = scan.plan(&gpu.device, &buffer, n as u32);
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        scan.record(&mut enc.begin_compute_pass(&Default::default()), &plan);
        gpu.queue.submit([enc.finish()]);
        assert_eq!(download(&gpu, &buffer, n), exclusive_scan(&data), "n = {n}");
    }
}

#[test]
fn scan_saturates_instead_of_wrapping() {
    let gpu = gpu();
    let scan = Scan::new(&gpu.device);
    // Overflow inside a thread, across threads and across blocks.
    let mut data = vec![0u32; 3000];
    data[0] = 0xF000_0000;
    data[1] = 0x2000_0000;
    data[700] = 7;
    data[2500] = 0x1000_0000;
    let buffer = upload(&gpu, &data);
    let plan = scan.plan(&gpu.device, &buffer, data.len() as u32);
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    scan.record(&mut enc.begin_compute_pass(&Default::default()), &plan);
    gpu.queue.submit([enc.finish()]);
    let got = download(&gpu, &buffer, data.len());
    assert_eq!(got[1], 0xF000_0000);
    assert!(
        got[2..].iter().all(|v| *v == u32::MAX),
        "offsets after the overflow stay saturated"
    );
}

#[test]
fn radix_sort_is_a_stable_sort() {
    let gpu = gpu();
    let scan = Scan::new(&gpu.device);
    // Both workgroup shapes of the block sort and the chunk sort at a few chunk counts, on
    // this adapter, whichever it would choose.
    for executor in [Executor::Gpu, Executor::Cpu] {
        let sort = RadixSort::blocks(&gpu.device, executor);
        stable_sort_cases(&gpu, &scan, &sort, &format!("blocks, {executor:?} shape"));
    }
    for cores in [1, 2, 17] {
        let sort = RadixSort::chunked(&gpu.device, cores);
        stable_sort_cases(&gpu, &scan, &sort, &format!("chunks for {cores} cores"));
    }
}

fn stable_sort_cases(gpu: &GpuContext, scan: &Scan, sort: &RadixSort, method: &str) {
    let mut rng = SplitMix64::new(11);
    // Odd and even pass counts (the result in the alternates or the inputs), no keys, and
    // fewer keys than chunks.
    for (n, bits, capacity) in [
        (0usize, 8u32, 16u32),
        (1, 4, 10),
        (50, 16, 100),
        (777, 8, 2048),
        (5000, 11, 9000),
        (20_000, 13, 30_000),
        (300_000, 32, 300_000),
        // Past 65535 loop iterations per invocation if the chunk sort took one chunk per
        // lane of a single core's workgroups (see `gpu::sort::chunks`).
        (2_500_000, 13, 2_500_000),
    ] {
        // Few distinct keys relative to n, so stability is exercised.
        let mask = if bits == 32 {
            u32::MAX
        } else {
            (1u32 << bits) - 1
        };
        let keys: Vec<u32> = (0..n)
            .map(|_| (rng.next_u64() as u32) & mask & !0xF0)
            .collect();
        let values: Vec<u32> = (0..n as u32).collect();
        let mut padded_keys = keys.clone();
        padded_keys.resize(capacity as usize, 0xDEAD);
        let mut padded_values = values.clone();
        padded_values.resize(capacity as usize, 0xBEEF);
        let (k, v) = (upload(gpu, &padded_keys), upload(gpu, &padded_values));
        let (ka, va) = (upload(gpu, &padded_keys), upload(gpu, &padded_values));
        let count = upload(gpu, &[n as u32]);
        let buffers = SortBuffers {
            count: &count,
            keys: &k,
            values: &v,
            keys_alt: &ka,
            values_alt: &va,
        };
        let plan = sort.plan(&gpu.device, scan, &buffers, capacity, bits);
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        sort.record(
            &mut enc.begin_compute_pass(&Default::default()),
            scan,
            &plan,
        );
        gpu.queue.submit([enc.finish()]);
        let (k, v) = if plan.result_in_alternates() {
            (&ka, &va)
        } else {
            (&k, &v)
        };
        let mut expected: Vec<(u32, u32)> =
            keys.iter().copied().zip(values.iter().copied()).collect();
        expected.sort_by_key(|(key, _)| *key); // stable
        let got_keys = download(gpu, k, n);
        let got_values = download(gpu, v, n);
        let got: Vec<(u32, u32)> = got_keys.into_iter().zip(got_values).collect();
        assert_eq!(got, expected, "n = {n}, {bits} bits, {method}");
        if bits <= 16 {
            let sorted: Vec<u32> = expected.iter().map(|(key, _)| *key).collect();
            let ranges = key_ranges(gpu, &plan, &count, k, capacity, bits, &sorted);
            assert_eq!(
                ranges,
                cpu_ranges(&sorted, 1 << bits),
                "n = {n}, {bits} bits, {method}: key ranges"
            );
        }
    }
}

/// The runs of every key value after `plan`'s sort, by `Ranges::after_sort` (read off the
/// sort's key starts, or by comparing neighbours), as (start, length) with empty runs as
/// (0, 0): the neighbour pass leaves them cleared, the starts give them their slot.
fn key_ranges(
    gpu: &GpuContext,
    plan: &SortPlan,
    count: &wgpu::Buffer,
    sorted_keys: &wgpu::Buffer,
    capacity: u32,
    bits: u32,
    sorted: &[u32],
) -> Vec<(u32, u32)> {
    let values = 1usize << bits;
    let out = upload(gpu, &vec![0u32; 2 * values]);
    let ranges = Ranges::new(&gpu.device);
    let pass = ranges.after_sort(&gpu.device, plan, count, sorted_keys, capacity, &out);
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    ranges.record(&mut enc.begin_compute_pass(&Default::default()), &pass);
    gpu.queue.submit([enc.finish()]);
    let raw = download(gpu, &out, 2 * values);
    assert!(sorted.len() <= capacity as usize);
    raw.chunks(2)
        .map(|r| {
            if r[1] > r[0] {
                (r[0], r[1] - r[0])
            } else {
                (0, 0)
            }
        })
        .collect()
}

fn cpu_ranges(sorted: &[u32], values: usize) -> Vec<(u32, u32)> {
    let mut ranges = vec![(0u32, 0u32); values];
    for (i, key) in sorted.iter().enumerate() {
        let r = &mut ranges[*key as usize];
        if r.1 == 0 {
            r.0 = i as u32;
        }
        r.1 += 1;
    }
    ranges
}

const DIFFERENCE: &str = "
@group(0) @binding(0) var<storage, read> a: array<u32>;
@group(0) @binding(1) var<storage, read> b: array<u32>;
@group(0) @binding(2) var<storage, read_write> out: array<u32>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < arrayLength(&out) {
        out[id.x] = a[id.x] - b[id.x];
    }
}";

/// `Kernel::bind_named` binds by the WGSL names whatever the order of the list: a − b
/// comes out as a − b with the list given as (out, b, a).
#[test]
fn buffers_bound_by_name_reach_their_variables() {
    let gpu = gpu();
    let kernel = splatter::gpu::Kernel::new(&gpu.device, "difference", DIFFERENCE, "main");
    let (a, b) = (upload(&gpu, &[10, 20, 30]), upload(&gpu, &[1, 2, 3]));
    let out = upload(&gpu, &[0, 0, 0]);
    let bind = kernel.bind_named(&gpu.device, &[("out", &out), ("b", &b), ("a", &a)]);
    let mut enc = gpu.device.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        kernel.dispatch(&mut pass, &bind, 1);
    }
    gpu.queue.submit([enc.finish()]);
    assert_eq!(download(&gpu, &out, 3), vec![9, 18, 27]);
}

#[test]
#[should_panic(expected = "no `var c` at group 0")]
fn a_name_the_shader_does_not_declare_is_refused() {
    let gpu = gpu();
    let kernel = splatter::gpu::Kernel::new(&gpu.device, "difference", DIFFERENCE, "main");
    let x = upload(&gpu, &[0]);
    kernel.bind_named(&gpu.device, &[("a", &x), ("c", &x), ("out", &x)]);
}
