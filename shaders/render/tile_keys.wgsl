// Tile keys: after the depth sort, every visible Gaussian writes one (tile, Gaussian) pair
// per tile its rectangle touches, in depth order, so that a stable sort by tile keeps
// each tile's list front to back. If the pairs exceed the buffers' capacity the farthest
// Gaussians are dropped (they come last) and the overflow is counted.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> tile_rects: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read> depth_order: array<u32>;
// tile counts in depth order; scanned in place into offsets between the passes
@group(0) @binding(3) var<storage, read_write> offsets: array<u32>;
@group(0) @binding(4) var<storage, read_write> tile_keys: array<u32>;
@group(0) @binding(5) var<storage, read_write> tile_values: array<u32>;
@group(0) @binding(6) var<storage, read_write> key_count: array<u32>;
@group(0) @binding(7) var<storage, read_write> stats: Stats;

fn rect_size(r: vec2<u32>) -> vec2<u32> {
    let mn = vec2<u32>(r.x & 0xffffu, r.x >> 16u);
    let mx = vec2<u32>(r.y & 0xffffu, r.y >> 16u);
    return mx - mn;
}

// Entry 1: tile counts in depth order (to be scanned).
@compute @workgroup_size(256)
fn gather_counts(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
                 @builtin(local_invocation_index) lid: u32) {
    let j = flat_workgroup(wid, nwg) * 256u + lid;
    if j >= frame.num_gaussians {
        return;
    }
    let s = rect_size(tile_rects[depth_order[j]]);
    offsets[j] = s.x * s.y;
}

// Entry 2 (one thread, after the scan): the total number of pairs and how many fit.
@compute @workgroup_size(1)
fn total() {
    let n = frame.num_gaussians;
    var sum = 0u;
    if n > 0u {
        let s = rect_size(tile_rects[depth_order[n - 1u]]);
        // Saturating, like the scan (see scan.wgsl).
        let last = offsets[n - 1u];
        sum = select(last + s.x * s.y, 0xffffffffu, last + s.x * s.y < last);
    }
    atomicStore(&stats.intersections, sum);
    key_count[0] = min(sum, frame.key_capacity);
}

// Entry 3: write the pairs.
@compute @workgroup_size(256)
fn emit(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let j = flat_workgroup(wid, nwg) * 256u + lid;
    if j >= frame.num_gaussians {
        return;
    }
    let g = depth_order[j];
    let r = tile_rects[g];
    let mn = vec2<u32>(r.x & 0xffffu, r.x >> 16u);
    let mx = vec2<u32>(r.y & 0xffffu, r.y >> 16u);
    var k = offsets[j];
    for (var y = mn.y; y < mx.y; y++) {
        for (var x = mn.x; x < mx.x; x++) {
            if k >= frame.key_capacity {
                return;
            }
            tile_keys[k] = y * frame.tiles_x + x;
            tile_values[k] = g;
            k++;
        }
    }
}
