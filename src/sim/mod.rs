//! The MPM physics (docs/method.md §2–§4, §6), by what it is:
//!
//! - [`model`]: the constitutive laws, each one `.rs` with its parameters and f64 oracle and
//!   one `.wgsl`, registered once (the elastic energies and stresses in
//!   [`model::elasticity`]);
//! - [`cpu`]: the f64 reference step (and [`cpu::textbook`], the same step in three plain
//!   loops);
//! - [`gpu`]: the GPU engine — its passes ([`gpu::step`]), the WGSL library and codes shared
//!   with Rust ([`gpu::wgsl`], [`gpu::codes`]), and [`gpu::plan::SimPlan`], which picks the
//!   P2G path and checks the limits;
//! - what all three share at the top: the particles, grid, materials, boundaries,
//!   colliders, parameters, the B-spline weights ([`bspline`]), the 3×3 [`svd`] and
//!   two-field [`separation`].
//!
//! The GPU runs the oracle's formulas in f32: compare with tolerances scaled to f32, not
//! bit for bit.
//!
//! Where each formula of `docs/method.md` lives:
//!
//! | method | formula | here |
//! |---|---|---|
//! | §2 | quadratic B-spline weights w0/w1/w2, base, fx, d_ip, ∇w | [`bspline`] |
//! | §2 | MLS factor 4/Δx² = D_p⁻¹ (Σ w d dᵀ = Δx²/4 I) | [`bspline`] (tested) |
//! | §4, §6 | 3×3 SVD F = U Σ Vᵀ, det U = det V = +1, sign in σ₃ | [`svd::svd3`] |
//! | §3, §6 | polar decomposition F = R S (R for fixed corotated and the SH frame) | [`svd::polar`] |
//! | §3 | Lamé μ, λ from (E, ν); bulk κ | [`model::elasticity::Lame`] |
//! | §3 | fixed-corotated τ = 2μ (F − R) Fᵀ + λ (J − 1) J I | [`model::elasticity::kirchhoff_fixed_corotated`] |
//! | §3 | Neo-Hookean (Borden) τ = μ J^(−2/3) dev(F Fᵀ) + κ/2 (J² − 1) I | [`model::elasticity::kirchhoff_neo_hookean`] |
//! | §4 | J, b̄, p, s, q of principal stretches | [`model::nacc::oracle::principal_state`] |
//! | §4 | p0(α) = κ (ε₀ + sinh(ξ max(−α, 0))), clamped sinh | [`model::nacc::oracle::NaccParams::p0`] |
//! | §4 | M from a friction angle | [`model::nacc::oracle::m_from_friction_angle`] |
//! | §4 | y(p, q) = (1 + 2β) q² + M² (p + βp0)(p − p0) | [`model::nacc::oracle::YieldEllipse::y`] |
//! | §4 | return-mapping table: elastic, tips, case 3 | [`model::nacc::oracle::project_pq`] |
//! | §4 | case 3: `center`, `continuous{k}`, `closest_point` | [`model::nacc::oracle::Case3Variant`] |
//! | §4 | back to F (J_E(p), scaled s, det b̄ = 1 solve) and hardening | [`model::nacc::oracle::return_map`] |
//! | §4.9 | damage d = clamp((α − α₀)/(−α₀), 0, 1) | [`Material::damage`] |
//! | §4.9 | damage field D_i, ∇D_p, ridge g_i, near/far partition | [`separation::partition`] |
//! | §4.9 | two-field contact about v_cm along n̂_near − n̂_far | [`separation::contact`] |

pub mod actions;
pub mod boundary;
pub mod bspline;
pub mod cpu;
pub mod fields;
pub mod frame;
pub mod gpu;
pub mod grid;
pub mod kinematic;
pub mod material;
pub mod model;
pub mod params;
pub mod particles;
pub mod separation;
pub mod svd;
pub mod time_step;

pub use actions::{Action, ActionKind, Actions, Drive};
pub use boundary::{Boundaries, BoundaryKind, Condition, DomainWalls, PlaneCollider, WALL_BAND};
pub use bspline::Stencil;
pub use fields::{Attractor, Fields, Gusts, Wind};
pub use grid::Grid;
pub use material::{cfl_dt, Material};
pub use model::elasticity::Lame;
pub use model::nacc::{
    return_map, Case3Variant, NaccParams, PlasticReturn, ReturnCase, YieldEllipse,
};
pub use model::{ElasticModel, PlasticModel};
pub use params::{StepParams, StepStats, Transfer};
pub use particles::{axial, Particles};
pub use separation::Separation;
pub use svd::{polar, svd3, Svd3};
