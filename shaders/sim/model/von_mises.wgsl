// Von Mises plasticity (sim::model::von_mises, docs/method.md §4.11): the radial return
// of the Hencky strain ε = ln σ of the trial F = U diag(σ) Vᵀ onto q = √(3/2) 2μ ‖ε̂‖ ≤
// σ_y + H α, α the equivalent plastic strain. params: σ_y, H.
fn von_mises_return_map(f: mat3x3<f32>, alpha: f32, mu: f32, yield_stress: f32,
                        hardening: f32) -> PlasticState {
    let d = svd3(f);
    let eps = hencky_strain(d);
    let mean = (eps.x + eps.y + eps.z) / 3.0;
    let dev = eps - vec3<f32>(mean);
    let q_trial = 2.0 * mu * sqrt(1.5) * length(dev);
    let excess = q_trial - (yield_stress + hardening * alpha);
    var eps_new = eps;
    var d_eq = 0.0;
    if excess > 0.0 {
        d_eq = excess / (3.0 * mu + hardening);
        eps_new = vec3<f32>(mean) + dev * (1.0 - 3.0 * mu * d_eq / q_trial);
    } else if all(d.sigma >= vec3<f32>(HENCKY_SIGMA_MIN)) {
        return PlasticState(f, alpha);
    }
    let f_new = d.u * sim_diag3(exp(eps_new)) * transpose(d.v);
    return PlasticState(f_new, alpha + d_eq);
}
