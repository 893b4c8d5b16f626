// Brittle damage (sim::model::brittle, docs/method.md §4.13): tension-driven damage d ∈ [0, 1]
// that never heals, on St. Venant–Kirchhoff Hencky elasticity split so that damage degrades
// the deviatoric energy always and the volumetric energy only in tension. Each particle's
// strength is a Weibull draw keyed by its index. params: σ₀ (Weibull scale), 1/m (0: one
// strength), softening s, the seed's key (an integer below 2^24, exact in f32), ln(1 − θ)
// (the compaction's floor on ln J).

// Damage at which a particle is rubble (`brittle::BROKEN`).
const BRITTLE_BROKEN: f32 = 0.99;

// lowbias32 (`brittle::hash32`).
fn brittle_hash(v: u32) -> u32 {
    var x = v;
    x ^= x >> 16u;
    x *= 0x7feb352du;
    x ^= x >> 15u;
    x *= 0x846ca68bu;
    return x ^ (x >> 16u);
}

// Particle `particle`'s strength σ₀ (−ln u)^{1/m}, u from its hash (`Brittle::strength_of`).
fn brittle_strength(particle: u32, scale: f32, inv_m: f32, key: u32) -> f32 {
    if inv_m == 0.0 {
        return scale;
    }
    let u = (f32(brittle_hash(particle ^ key) >> 9u) + 0.5) * (1.0 / 8388608.0);
    return scale * pow(-log(u), inv_m);
}

// d ← max(d, D(y)) with y the largest effective principal stress over the strength; a
// compression past ln J = ln_j_min compacts; a particle past BRITTLE_BROKEN keeps its
// rotation and a compression down to ln_j_min only.
fn brittle_return_map(f: mat3x3<f32>, alpha: f32, particle: u32, mu: f32, kappa: f32,
                      scale: f32, inv_m: f32, softening: f32, key: u32,
                      ln_j_min: f32) -> PlasticState {
    let d = svd3(f);
    let eps = hencky_strain(d);
    let tr = eps.x + eps.y + eps.z;
    let s = 2.0 * mu * (eps - vec3<f32>(tr / 3.0)) + vec3<f32>(kappa * tr);
    let peak = max(max(s.x, max(s.y, s.z)), 0.0);
    let y = peak / brittle_strength(particle, scale, inv_m, key);
    var damage = alpha;
    if y > 1.0 {
        damage = max(damage, 1.0 - exp(-(y - 1.0) / softening) / y);
    }
    damage = clamp(damage, 0.0, 1.0);
    if damage >= BRITTLE_BROKEN {
        let stretch = exp(clamp(tr, ln_j_min, 0.0) / 3.0);
        return PlasticState(d.u * transpose(d.v) * stretch, 1.0);
    }
    if tr >= ln_j_min {
        return PlasticState(f, damage);
    }
    let eps_new = eps - vec3<f32>((tr - ln_j_min) / 3.0);
    return PlasticState(d.u * sim_diag3(exp(eps_new)) * transpose(d.v), damage);
}

// τ = U diag(g 2μ ε̂ + h κ tr ε) Uᵀ, g = 1 − d, h = g in tension and 1 in compression.
fn brittle_kirchhoff(f: mat3x3<f32>, alpha: f32, mu: f32, kappa: f32) -> mat3x3<f32> {
    let d = svd3(f);
    let eps = hencky_strain(d);
    let tr = eps.x + eps.y + eps.z;
    let g = 1.0 - clamp(alpha, 0.0, 1.0);
    var h = 1.0;
    if tr > 0.0 {
        h = g;
    }
    let t = (2.0 * mu * g) * (eps - vec3<f32>(tr / 3.0)) + vec3<f32>(h * kappa * tr);
    return d.u * sim_diag3(t) * transpose(d.u);
}
