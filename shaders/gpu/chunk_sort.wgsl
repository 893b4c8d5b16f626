// Stable LSD counting sort of (key, value) u32 pairs for CPU drivers, one digit of up to
// 13 bits per pass (docs/method.md §7: "GPU sort"). The keys are cut into `chunks`
// contiguous runs and each invocation walks one run in order:
//   `count_chunks`   counts[chunk * bins + digit] = keys of that digit in the chunk;
//   `digit_prefix`   per digit, over the chunks: counts of the digit in earlier chunks
//                    (in place), and the digit's total in `digit_base`;
//   (an exclusive scan of `digit_base` then gives each digit its first slot);
//   `scatter_chunks` moves every key to the next slot of its digit and chunk.
// Walking a chunk in order keeps equal digits in input order, so the sort is stable, and
// no two invocations touch the same counter, so there are no atomics and no barriers: on a
// CPU driver, which runs a workgroup as SIMD vectors and pays for every barrier and atomic
// one lane at a time, that beats ranking keys inside blocks (`radix_sort.wgsl`). A chunk's
// counters are contiguous so that the counting walks stay in cache.
// lavapipe ends an invocation's loops after 65535 iterations in all (its loop limiter), so
// `gpu::sort` sizes the chunks and digits to stay under it: at most 32768 keys a chunk,
// 8192 digits (13 bits) to zero, and fewer chunks than that.
// LANES (invocations per workgroup) is defined by `gpu::sort`.

struct ChunkSortParams {
    shift: u32,
    // bins per pass: 1 << (digit bits)
    bins: u32,
    chunks: u32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> params: ChunkSortParams;
@group(0) @binding(1) var<storage, read> key_count: array<u32>;
@group(0) @binding(2) var<storage, read> keys_in: array<u32>;
@group(0) @binding(3) var<storage, read_write> counts: array<u32>;
@group(0) @binding(4) var<storage, read_write> digit_base: array<u32>;
@group(0) @binding(5) var<storage, read> values_in: array<u32>;
@group(0) @binding(6) var<storage, read_write> keys_out: array<u32>;
@group(0) @binding(7) var<storage, read_write> values_out: array<u32>;

// The keys [begin, end) of chunk c: near-equal runs of the n keys.
fn chunk_bounds(c: u32) -> vec2<u32> {
    let n = key_count[0];
    let size = (n + params.chunks - 1u) / params.chunks;
    let begin = min(c * size, n);
    return vec2<u32>(begin, min(begin + size, n));
}

fn counter(c: u32, key: u32) -> u32 {
    return c * params.bins + ((key >> params.shift) & (params.bins - 1u));
}

@compute @workgroup_size(LANES)
fn count_chunks(@builtin(global_invocation_id) id: vec3<u32>) {
    let c = id.x;
    if c >= params.chunks {
        return;
    }
    for (var d = 0u; d < params.bins; d++) {
        counts[c * params.bins + d] = 0u;
    }
    let r = chunk_bounds(c);
    for (var i = r.x; i < r.y; i++) {
        counts[counter(c, keys_in[i])] += 1u;
    }
}

@compute @workgroup_size(LANES)
fn digit_prefix(@builtin(global_invocation_id) id: vec3<u32>) {
    let d = id.x;
    if d >= params.bins {
        return;
    }
    var before = 0u;
    for (var c = 0u; c < params.chunks; c++) {
        let slot = c * params.bins + d;
        let here = counts[slot];
        counts[slot] = before;
        before += here;
    }
    digit_base[d] = before;
}

@compute @workgroup_size(LANES)
fn scatter_chunks(@builtin(global_invocation_id) id: vec3<u32>) {
    let c = id.x;
    if c >= params.chunks {
        return;
    }
    let r = chunk_bounds(c);
    for (var i = r.x; i < r.y; i++) {
        let key = keys_in[i];
        let slot = counter(c, key);
        let rank = counts[slot];
        counts[slot] = rank + 1u;
        let dest = digit_base[slot - c * params.bins] + rank;
        keys_out[dest] = key;
        values_out[dest] = values_in[i];
    }
}
