// NACC (sim::models::nacc): its parameters out of the material record, and its damage.
// The return mapping itself, nacc_return_map, is in shaders/sim/nacc.wgsl.

// params: β, ξ, M, k, the variant's code (bits), α₀ (`Nacc::gpu_params`).
fn nacc_material(m: SimMaterial) -> NaccMaterial {
    return NaccMaterial(m.kappa, m.mu, m.params[0], m.params[1], m.params[2], m.params[3],
                        bitcast<u32>(m.params[4]), m.params[5]);
}

// Damage of a particle with hardening state alpha and initial state alpha0 (`Nacc::damage`).
fn nacc_damage(alpha0: f32, alpha: f32) -> f32 {
    if alpha0 < 0.0 {
        return clamp((alpha - alpha0) / -alpha0, 0.0, 1.0);
    }
    return 1.0;
}
