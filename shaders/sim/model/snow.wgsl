// Snow (sim::model::snow, docs/method.md §4.12). params: θ_c, θ_s, ξ.

// The singular values of the trial F clamped to [1 − θ_c, 1 + θ_s]; α = ln Jᴾ gains
// ln(J_trial / J_new) (an inverted trial counted at σ = 1e-4).
fn snow_return_map(f: mat3x3<f32>, alpha: f32, theta_c: f32, theta_s: f32) -> PlasticState {
    let d = svd3(f);
    let sigma = clamp(d.sigma, vec3<f32>(1.0 - theta_c), vec3<f32>(1.0 + theta_s));
    if all(sigma == d.sigma) {
        return PlasticState(f, alpha);
    }
    let ratio = log(max(d.sigma, vec3<f32>(1e-4)) / sigma);
    let f_new = d.u * sim_diag3(sigma) * transpose(d.v);
    return PlasticState(f_new, alpha + ratio.x + ratio.y + ratio.z);
}

// The factor e^{ξ (1 − Jᴾ)} on the Lamé parameters, Jᴾ = e^α, the exponent clamped at 60.
fn snow_hardening(xi: f32, alpha: f32) -> f32 {
    return exp(min(xi * (1.0 - exp(alpha)), 60.0));
}
