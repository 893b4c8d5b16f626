// Kirchhoff stresses τ(F) of docs/method.md §3 in f32: the WGSL twin of src/sim/model/elasticity.rs.
// Needs: sim/math, sim/svd.
// Lamé parameters come from the host (computed in f64 from E, ν by
// `Lame::from_young_poisson`; κ = λ + 2μ/3).

// Fixed corotated: τ = 2μ (F − R) Fᵀ + λ (J − 1) J I, R = U Vᵀ from the polar
// decomposition (a rotation even when det F < 0).
fn elastic_kirchhoff_fixed_corotated(f: mat3x3<f32>, mu: f32, lambda: f32) -> mat3x3<f32> {
    let r = polar_rotation(f);
    let j = determinant(f);
    return (2.0 * mu) * ((f - r) * transpose(f)) + (lambda * (j - 1.0) * j) * SIM_IDENTITY3;
}

// Same, with the SVD of F already at hand (P2G computes it once per particle).
fn elastic_kirchhoff_fixed_corotated_svd(f: mat3x3<f32>, d: Svd3, mu: f32, lambda: f32) -> mat3x3<f32> {
    let r = d.u * transpose(d.v);
    let j = determinant(f);
    return (2.0 * mu) * ((f - r) * transpose(f)) + (lambda * (j - 1.0) * j) * SIM_IDENTITY3;
}

// Neo-Hookean, Borden form: τ = μ J^(−2/3) dev(F Fᵀ) + κ/2 (J² − 1) I. Needs J > 0, as the
// oracle (NACC's return mapping guarantees det F ≥ 1e-12; a pure Neo-Hookean material
// that inverts gives NaN, which the watchdog reports).
fn elastic_kirchhoff_neo_hookean(f: mat3x3<f32>, mu: f32, kappa: f32) -> mat3x3<f32> {
    let j = determinant(f);
    let b = f * transpose(f);
    let dev_b = b - (sim_trace3(b) / 3.0) * SIM_IDENTITY3;
    return (mu * pow(j, -2.0 / 3.0)) * dev_b + (0.5 * kappa * (j - 1.0) * (j + 1.0)) * SIM_IDENTITY3;
}

// Singular values below this are clamped before their logarithm (`elasticity::HENCKY_SIGMA_MIN`).
const HENCKY_SIGMA_MIN: f32 = 1e-4;

// The Hencky strains ε = ln σ of an SVD, σ clamped to ≥ HENCKY_SIGMA_MIN.
fn hencky_strain(d: Svd3) -> vec3<f32> {
    return log(max(d.sigma, vec3<f32>(HENCKY_SIGMA_MIN)));
}

// St. Venant–Kirchhoff on the Hencky strain: τ = U (2μ ε + λ tr(ε) I) Uᵀ, ε = ln σ.
fn elastic_kirchhoff_stvk_hencky(f: mat3x3<f32>, mu: f32, lambda: f32) -> mat3x3<f32> {
    let d = svd3(f);
    let eps = hencky_strain(d);
    let t = 2.0 * mu * eps + vec3<f32>(lambda * (eps.x + eps.y + eps.z));
    return d.u * sim_diag3(t) * transpose(d.u);
}
