// `read_splat` for rasterize.wgsl: every invocation reads the Gaussian from workgroup
// memory itself, and leaves the batch loop as soon as its own pixels are done.

fn read_splat(k: u32, lid: u32) -> Splat2D {
    return Splat2D(batch[3u * k], batch[3u * k + 1u], batch[3u * k + 2u]);
}

fn any_live(live: bool) -> bool {
    return live;
}
