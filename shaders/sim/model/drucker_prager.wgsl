// Drucker–Prager plasticity for sand (sim::model::drucker_prager, docs/method.md §4.10):
// the return mapping in the Hencky strain ε = ln σ of the trial F = U diag(σ) Vᵀ onto the
// cone ‖ε̂‖ + (3κ/2μ) α_dp (tr ε − tr ε_apex) ≤ 0. params: α_dp, tr ε_apex.
fn drucker_prager_return_map(f: mat3x3<f32>, alpha: f32, mu: f32, lambda: f32, a_dp: f32,
                             apex: f32) -> PlasticState {
    let d = svd3(f);
    let eps = hencky_strain(d);
    let tr = eps.x + eps.y + eps.z;
    let shifted = tr - apex;
    var eps_new = eps;
    if shifted >= 0.0 {
        eps_new = vec3<f32>(apex / 3.0);
    } else {
        let dev = eps - vec3<f32>(tr / 3.0);
        let dev_norm = length(dev);
        let dgamma = dev_norm + (3.0 * lambda + 2.0 * mu) / (2.0 * mu) * shifted * a_dp;
        if dgamma <= 0.0 {
            if all(d.sigma >= vec3<f32>(HENCKY_SIGMA_MIN)) {
                return PlasticState(f, alpha);
            }
        } else {
            eps_new = eps - dev * (dgamma / dev_norm);
        }
    }
    let f_new = d.u * sim_diag3(exp(eps_new)) * transpose(d.v);
    let plastic = tr - (eps_new.x + eps_new.y + eps_new.z);
    return PlasticState(f_new, alpha + plastic);
}
