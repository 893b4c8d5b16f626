// Tile keys: after the depth sort, every visible Gaussian writes one (tile, Gaussian) pair
// per tile of its rectangle that its footprint ellipse reaches (`ellipse_touches_tile`),
// in depth order, so that a stable sort by tile keeps
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
// projected_0 … from binding 8, and projected_at(g), follow (`gpu::pages`).

// The footprint of Gaussian g: its tile rectangle [mn, mx), mean, conic and k².
struct Footprint {
    mn: vec2<u32>,
    mx: vec2<u32>,
    xy: vec2<f32>,
    conic: vec3<f32>,
    k2: f32,
}

fn footprint(g: u32) -> Footprint {
    let r = tile_rects[g];
    var f: Footprint;
    f.mn = vec2<u32>(r.x & 0xffffu, r.x >> 16u);
    f.mx = vec2<u32>(r.y & 0xffffu, r.y >> 16u);
    if any(f.mx <= f.mn) {
        return f; // culled: its projection was not written
    }
    let p = projected_at(g);
    f.xy = p.xy_opacity.xy;
    f.conic = p.conic.xyz;
    let k = extent_sigmas(p.xy_opacity.z);
    f.k2 = k * k;
    return f;
}

// Tiles of the rectangle that the footprint ellipse reaches.
fn tile_count(f: Footprint) -> u32 {
    var count = 0u;
    for (var y = f.mn.y; y < f.mx.y; y++) {
        for (var x = f.mn.x; x < f.mx.x; x++) {
            count += u32(ellipse_touches_tile(f.xy, f.conic, f.k2, vec2<u32>(x, y)));
        }
    }
    return count;
}

// Entry 1: tile counts in depth order (to be scanned).
@compute @workgroup_size(256)
fn gather_counts(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
                 @builtin(local_invocation_index) lid: u32) {
    let j = flat_workgroup(wid, nwg) * 256u + lid;
    if j >= frame.num_gaussians {
        return;
    }
    offsets[j] = tile_count(footprint(depth_order[j]));
}

// Entry 2 (one thread, after the scan): the total number of pairs and how many fit.
@compute @workgroup_size(1)
fn total() {
    let n = frame.num_gaussians;
    var sum = 0u;
    if n > 0u {
        // Saturating, like the scan (see scan.wgsl).
        let last = offsets[n - 1u];
        let more = last + tile_count(footprint(depth_order[n - 1u]));
        sum = select(more, 0xffffffffu, more < last);
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
    let f = footprint(g);
    var k = offsets[j];
    for (var y = f.mn.y; y < f.mx.y; y++) {
        for (var x = f.mn.x; x < f.mx.x; x++) {
            if !ellipse_touches_tile(f.xy, f.conic, f.k2, vec2<u32>(x, y)) {
                continue;
            }
            if k >= frame.key_capacity {
                return;
            }
            tile_keys[k] = y * frame.tiles_x + x;
            tile_values[k] = g;
            k++;
        }
    }
}
