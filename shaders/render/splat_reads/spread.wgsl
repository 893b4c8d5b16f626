// `read_splat` for rasterize.wgsl on CPU drivers whose subgroups are 8 consecutive
// invocations, one SIMD vector (lavapipe with 256-bit vectors). Such a driver reads
// workgroup memory at a per-invocation index one lane at a time, element by element, so
// a Gaussian read whole by every invocation costs 8 × 12 scalar reads. Here lane j reads
// only element j of the first eight and element j mod 4 of the colour, and the subgroup
// broadcasts them: 16 reads. A subgroup's eight invocations are the columns of one 8×8 block,
// so they walk the same Gaussians; they also stay in the loop together until all are done
// (`any_live`), since a broadcast needs every lane.

fn read_splat(k: u32, lid: u32) -> Splat2D {
    let lane = lid & 7u;
    let first = batch[3u * k + (lane >> 2u)][lane & 3u];
    let color = batch[3u * k + 2u][lane & 3u];
    // the colour's w (the normal pass's normal) only where the normal pass reads it
    var color_w = 0.0;
    if NORMALS {
        color_w = subgroupBroadcast(color, 3u);
    }
    return Splat2D(
        vec4<f32>(subgroupBroadcast(first, 0u), subgroupBroadcast(first, 1u),
                  subgroupBroadcast(first, 2u), subgroupBroadcast(first, 3u)),
        vec4<f32>(subgroupBroadcast(first, 4u), subgroupBroadcast(first, 5u),
                  subgroupBroadcast(first, 6u), subgroupBroadcast(first, 7u)),
        vec4<f32>(subgroupBroadcast(color, 0u), subgroupBroadcast(color, 1u),
                  subgroupBroadcast(color, 2u), color_w),
    );
}

fn any_live(live: bool) -> bool {
    return subgroupAny(live);
}
