// A material as the step passes see it (`sim::gpu::GpuMaterial`): which registered
// elastic and plastic model, and their parameters. The ELASTIC_*/PLASTIC_* codes and the
// dispatch functions on them are generated from the Rust registry (sim::models::wgsl) and
// follow this file.
struct SimMaterial {
    // ELASTIC_*
    elastic: u32,
    // PLASTIC_*
    plastic: u32,
    mu: f32,
    lambda: f32,
    kappa: f32,
    nacc: NaccMaterial,
}

