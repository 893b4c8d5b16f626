// A material as the step passes see it (`sim::gpu::step::GpuMaterial`): which registered
// elastic and plastic model, the Lamé parameters, and the plastic model's own parameters
// in the order its `PlasticLaw::gpu_params` packs them (its file under
// shaders/sim/model/ unpacks them). The ELASTIC_*/PLASTIC_* codes and the dispatch
// functions on them are generated from the Rust registry (sim::model::wgsl) and follow
// this file.
struct SimMaterial {
    // ELASTIC_*
    elastic: u32,
    // PLASTIC_*
    plastic: u32,
    mu: f32,
    lambda: f32,
    // bulk modulus κ = λ + 2μ/3
    kappa: f32,
    params: array<f32, 8>,
}
