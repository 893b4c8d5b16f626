// Stable LSD radix sort of (key, value) u32 pairs, 4 bits per pass (docs/method.md §7: "GPU sort").
// One pass = `count_digits` (a 16-bin histogram per block of 2048 keys), an exclusive scan
// of the histograms laid out digit-major (counts[digit * num_blocks + block]), then
// `scatter`, which ranks keys inside the block with a workgroup scan of digit counts
// (16 fields of 16 bits packed in two vec4<u32>) so the order of equal keys is kept.
// Needs no subgroup operations and no float atomics, so it runs on every backend.
// WG (invocations per workgroup) and KEYS_PER_THREAD are set per adapter by `gpu::sort`
// (constants `gpu::sort::source` defines); a block is always WG · KEYS_PER_THREAD = 2048 keys.

struct SortParams {
    shift: u32,
    num_blocks: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> params: SortParams;
@group(0) @binding(1) var<storage, read> key_count: array<u32>;
@group(0) @binding(2) var<storage, read> keys_in: array<u32>;
@group(0) @binding(3) var<storage, read_write> counts: array<u32>;
@group(0) @binding(4) var<storage, read> values_in: array<u32>;
@group(0) @binding(5) var<storage, read_write> keys_out: array<u32>;
@group(0) @binding(6) var<storage, read_write> values_out: array<u32>;

const BLOCK: u32 = WG * KEYS_PER_THREAD;

// The block's digit counts, packed as in `Packed` below.
var<workgroup> hist: array<atomic<u32>, 8>;
var<workgroup> shared_count: u32;

// The number of keys, loaded so that every invocation provably sees the same value (blocks
// past the end can then leave early in uniform control flow).
fn uniform_key_count(lid: u32) -> u32 {
    if lid == 0u {
        shared_count = key_count[0];
    }
    return workgroupUniformLoad(&shared_count);
}

fn flat_wg(wid: vec3<u32>, nwg: vec3<u32>) -> u32 {
    return wid.x + wid.y * nwg.x;
}

fn digit_of(key: u32) -> u32 {
    return (key >> params.shift) & 15u;
}

// Digit counts packed one-hot: digit d is field (d & 1) (16 bits) of word d >> 1, words
// 0..3 in `lo`, 4..7 in `hi`. A field counts at most BLOCK = 2048 keys, so 16 bits suffice,
// and adding two packed counts adds all sixteen counters at once.
struct Packed {
    lo: vec4<u32>,
    hi: vec4<u32>,
}

// `c` with one more key of digit d (no branch: the same instructions for every digit).
fn count_digit(c: Packed, d: u32) -> Packed {
    let bit = 1u << ((d & 1u) * 16u);
    let word = vec4<u32>(d >> 1u);
    let zero = vec4<u32>(0u);
    return Packed(c.lo + select(zero, vec4<u32>(bit), word == vec4<u32>(0u, 1u, 2u, 3u)),
                  c.hi + select(zero, vec4<u32>(bit), word == vec4<u32>(4u, 5u, 6u, 7u)));
}

// The count of digit d in `c`.
fn field(c: Packed, d: u32) -> u32 {
    let word = d >> 1u;
    let lane = select(vec4<u32>(0u), vec4<u32>(1u), vec4<u32>(word & 3u) == vec4<u32>(0u, 1u, 2u, 3u));
    let w = dot(select(c.hi, c.lo, word < 4u), lane);
    return (w >> ((d & 1u) * 16u)) & 0xffffu;
}

@compute @workgroup_size(WG)
fn count_digits(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
                @builtin(local_invocation_index) lid: u32) {
    let block = flat_wg(wid, nwg);
    // The dispatch grid may overshoot (see gpu::dispatch_1d); the test is workgroup-uniform.
    if block >= params.num_blocks {
        return;
    }
    let n = uniform_key_count(lid);
    if block * BLOCK >= n {
        // An empty block (the sort is dispatched for the buffers' capacity): zero counts.
        if lid < 16u {
            counts[lid * params.num_blocks + block] = 0u;
        }
        return;
    }
    if lid < 8u {
        atomicStore(&hist[lid], 0u);
    }
    // Each invocation counts its keys in registers, then adds all its counters to the
    // block's with eight atomics (one per packed word) instead of one per key.
    var c = Packed(vec4<u32>(0u), vec4<u32>(0u));
    for (var r = 0u; r < KEYS_PER_THREAD; r++) {
        let idx = block * BLOCK + r * WG + lid;
        if idx < n {
            c = count_digit(c, digit_of(keys_in[idx]));
        }
    }
    workgroupBarrier();
    for (var w = 0u; w < 4u; w++) {
        atomicAdd(&hist[w], c.lo[w]);
        atomicAdd(&hist[w + 4u], c.hi[w]);
    }
    workgroupBarrier();
    if lid < 16u {
        let word = atomicLoad(&hist[lid >> 1u]);
        counts[lid * params.num_blocks + block] = (word >> ((lid & 1u) * 16u)) & 0xffffu;
    }
}

// The packed counts of the invocations, scanned in place.
var<workgroup> scan_lo: array<vec4<u32>, WG>;
var<workgroup> scan_hi: array<vec4<u32>, WG>;
var<workgroup> digit_base: array<u32, 16>;

// Each invocation takes KEYS_PER_THREAD consecutive keys, counts its digits, and one
// workgroup scan of those counts gives every key its rank among equal digits of the block:
// (keys of earlier invocations) + (earlier keys of the same invocation). Few barriers per
// key matters on CPU drivers such as lavapipe, where a barrier is expensive.
@compute @workgroup_size(WG)
fn scatter(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
           @builtin(local_invocation_index) lid: u32) {
    let block = flat_wg(wid, nwg);
    if block >= params.num_blocks {
        return;
    }
    let n = uniform_key_count(lid);
    if block * BLOCK >= n {
        return;
    }
    if lid < 16u {
        digit_base[lid] = counts[lid * params.num_blocks + block];
    }
    let base = block * BLOCK + lid * KEYS_PER_THREAD;
    var keys: array<u32, KEYS_PER_THREAD>;
    var local_rank: array<u32, KEYS_PER_THREAD>;
    var mine = Packed(vec4<u32>(0u), vec4<u32>(0u));
    for (var i = 0u; i < KEYS_PER_THREAD; i++) {
        if base + i < n {
            let key = keys_in[base + i];
            let d = digit_of(key);
            keys[i] = key;
            local_rank[i] = field(mine, d);
            mine = count_digit(mine, d);
        }
    }
    scan_lo[lid] = mine.lo;
    scan_hi[lid] = mine.hi;
    workgroupBarrier();
    for (var off = 1u; off < WG; off <<= 1u) {
        var add_lo = vec4<u32>(0u);
        var add_hi = vec4<u32>(0u);
        if lid >= off {
            add_lo = scan_lo[lid - off];
            add_hi = scan_hi[lid - off];
        }
        workgroupBarrier();
        scan_lo[lid] += add_lo;
        scan_hi[lid] += add_hi;
        workgroupBarrier();
    }
    // Exclusive: counts of the invocations before this one.
    let before = Packed(scan_lo[lid] - mine.lo, scan_hi[lid] - mine.hi);
    for (var i = 0u; i < KEYS_PER_THREAD; i++) {
        if base + i < n {
            let d = digit_of(keys[i]);
            let dest = digit_base[d] + field(before, d) + local_rank[i];
            keys_out[dest] = keys[i];
            values_out[dest] = values_in[base + i];
        }
    }
}
