//! The MPM physics (docs/method.md §2–§4, §6), in three parts: the f64 oracle and CPU
//! reference step (`bspline`, `svd`, `elasticity`, `cpu`, `separation`, …), the constitutive
//! laws registered once with their oracles and WGSL ([`models`]), and the GPU engine
//! ([`gpu`], its passes in [`step`], the shared WGSL in [`wgsl`] and [`codes`]). The GPU runs
//! the oracle's formulas in f32: compare with tolerances scaled to f32, not bit for bit.
//!
//! Where each formula of `docs/method.md` lives:
//!
//! | method | formula | here |
//! |---|---|---|
//! | §2 | quadratic B-spline weights w0/w1/w2, base, fx, d_ip, ∇w | [`bspline`] |
//! | §2 | MLS factor 4/Δx² = D_p⁻¹ (Σ w d dᵀ = Δx²/4 I) | [`bspline`] (tested) |
//! | §4, §6 | 3×3 SVD F = U Σ Vᵀ, det U = det V = +1, sign in σ₃ | [`svd::svd3`] |
//! | §3, §6 | polar decomposition F = R S (R for fixed corotated and the SH frame) | [`svd::polar`] |
//! | §3 | Lamé μ, λ from (E, ν); bulk κ | [`elasticity::Lame`] |
//! | §3 | fixed-corotated τ = 2μ (F − R) Fᵀ + λ (J − 1) J I | [`elasticity::kirchhoff_fixed_corotated`] |
//! | §3 | Neo-Hookean (Borden) τ = μ J^(−2/3) dev(F Fᵀ) + κ/2 (J² − 1) I | [`elasticity::kirchhoff_neo_hookean`] |
//! | §4 | J, b̄, p, s, q of principal stretches | [`models::nacc::oracle::principal_state`] |
//! | §4 | p0(α) = κ (ε₀ + sinh(ξ max(−α, 0))), clamped sinh | [`models::nacc::oracle::NaccParams::p0`] |
//! | §4 | M from a friction angle | [`models::nacc::oracle::m_from_friction_angle`] |
//! | §4 | y(p, q) = (1 + 2β) q² + M² (p + βp0)(p − p0) | [`models::nacc::oracle::YieldEllipse::y`] |
//! | §4 | return-mapping table: elastic, tips, case 3 | [`models::nacc::oracle::project_pq`] |
//! | §4 | case 3: `center`, `continuous{k}`, `closest_point` | [`models::nacc::oracle::Case3Variant`] |
//! | §4 | back to F (J_E(p), scaled s, det b̄ = 1 solve) and hardening | [`models::nacc::oracle::return_map`] |
//! | §4.9 | damage d = clamp((α − α₀)/(−α₀), 0, 1) | [`Material::damage`] |
//! | §4.9 | damage field D_i, ∇D_p, ridge g_i, near/far partition | [`separation::partition`] |
//! | §4.9 | two-field contact about v_cm along n̂_near − n̂_far | [`separation::contact`] |

pub mod boundary;
pub mod bspline;
pub mod codes;
pub mod cpu;
pub mod elasticity;
pub mod frame;
pub mod gpu;
pub mod grid;
pub mod kinematic;
pub mod material;
pub mod models;
pub mod params;
pub mod particles;
pub mod separation;
pub mod step;
pub mod svd;
pub mod time_step;
pub mod wgsl;

pub use boundary::{Boundaries, BoundaryKind, Condition, DomainWalls, PlaneCollider, WALL_BAND};
pub use bspline::Stencil;
pub use elasticity::Lame;
pub use grid::Grid;
pub use material::{cfl_dt, Material};
pub use models::nacc::{
    return_map, Case3Variant, NaccParams, PlasticReturn, ReturnCase, YieldEllipse,
};
pub use models::{ElasticModel, PlasticModel};
pub use params::{StepParams, StepStats, Transfer};
pub use particles::{axial, Particles};
pub use separation::Separation;
pub use svd::{polar, svd3, Svd3};
