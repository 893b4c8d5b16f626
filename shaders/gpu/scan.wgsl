// Exclusive prefix sum of u32 values, in blocks of 1024 (256 threads × 4 values).
// `scan_blocks` scans each block in place and writes the block's total to `block_sums`;
// the caller scans `block_sums` the same way (recursively) and `add_block_offsets` adds
// each block's scanned offset back. Used for tile-intersection offsets and by the radix sort.

struct ScanParams {
    n: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> params: ScanParams;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read_write> block_sums: array<u32>;

const WG: u32 = 256u;
const PER_THREAD: u32 = 4u;
const BLOCK: u32 = 1024u;

var<workgroup> partial: array<u32, 256>;

// Sums saturate at 2³² − 1 instead of wrapping: tile-pair offsets past any buffer's capacity
// then stay past it (those pairs are dropped) rather than wrapping onto valid slots.
fn sat_add(a: u32, b: u32) -> u32 {
    let s = a + b;
    return select(s, 0xffffffffu, s < a);
}

fn flat_wg(wid: vec3<u32>, nwg: vec3<u32>) -> u32 {
    return wid.x + wid.y * nwg.x;
}

@compute @workgroup_size(256)
fn scan_blocks(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
               @builtin(local_invocation_index) lid: u32) {
    let block = flat_wg(wid, nwg);
    // The dispatch grid may overshoot (see gpu::dispatch_1d); the test is workgroup-uniform.
    if block * BLOCK >= params.n {
        return;
    }
    let base = block * BLOCK + lid * PER_THREAD;
    var v: array<u32, 4>;
    var sum = 0u;
    for (var i = 0u; i < PER_THREAD; i++) {
        let idx = base + i;
        var x = 0u;
        if idx < params.n {
            x = data[idx];
        }
        v[i] = sum;
        sum = sat_add(sum, x);
    }
    // Inclusive Hillis–Steele scan of the per-thread totals.
    partial[lid] = sum;
    workgroupBarrier();
    for (var off = 1u; off < WG; off <<= 1u) {
        var add = 0u;
        if lid >= off {
            add = partial[lid - off];
        }
        workgroupBarrier();
        partial[lid] = sat_add(partial[lid], add);
        workgroupBarrier();
    }
    var before = 0u;
    if lid > 0u {
        before = partial[lid - 1u];
    }
    for (var i = 0u; i < PER_THREAD; i++) {
        let idx = base + i;
        if idx < params.n {
            data[idx] = sat_add(before, v[i]);
        }
    }
    if lid == WG - 1u {
        block_sums[block] = partial[WG - 1u];
    }
}

@compute @workgroup_size(256)
fn add_block_offsets(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
                     @builtin(local_invocation_index) lid: u32) {
    let block = flat_wg(wid, nwg);
    if block * BLOCK >= params.n {
        return;
    }
    let offset = block_sums[block];
    let base = block * BLOCK + lid * PER_THREAD;
    for (var i = 0u; i < PER_THREAD; i++) {
        let idx = base + i;
        if idx < params.n {
            data[idx] = sat_add(data[idx], offset);
        }
    }
}
