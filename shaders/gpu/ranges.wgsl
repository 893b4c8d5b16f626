// Key ranges: after a sort by key (a tile, a grid cell), the entries of each key are
// contiguous; find the start and end (exclusive) of every key's run. `main` compares
// neighbouring sorted keys (keys with no entry keep the cleared (0, 0)); `from_starts`
// reads the runs off the first slot of every key value, which a sort whose keys fit one
// digit leaves behind (`gpu::sort::SortPlan::key_starts`).

@group(0) @binding(0) var<storage, read> key_count: array<u32>;
@group(0) @binding(1) var<storage, read> sorted_keys: array<u32>;
@group(0) @binding(2) var<storage, read_write> ranges: array<vec2<u32>>;

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let i = (wid.x + wid.y * nwg.x) * 256u + lid;
    let n = key_count[0];
    if i >= n {
        return;
    }
    let t = sorted_keys[i];
    if i == 0u || sorted_keys[i - 1u] != t {
        ranges[t].x = i;
    }
    if i + 1u == n || sorted_keys[i + 1u] != t {
        ranges[t].y = i + 1u;
    }
}

@group(0) @binding(3) var<storage, read> starts: array<u32>;

@compute @workgroup_size(256)
fn from_starts(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
               @builtin(local_invocation_index) lid: u32) {
    let k = (wid.x + wid.y * nwg.x) * 256u + lid;
    if k >= arrayLength(&ranges) {
        return;
    }
    // Key values past the last one counted start at the key count.
    let end = select(key_count[0], starts[k + 1u], k + 1u < arrayLength(&starts));
    ranges[k] = vec2<u32>(starts[k], end);
}
