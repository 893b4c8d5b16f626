//! Fixed corotated (docs/method.md §3): oracle in `sim::model::elasticity`, WGSL in
//! `shaders/sim/elasticity.wgsl`.

use super::ElasticDef;
use crate::sim::model::elasticity::{energy_fixed_corotated, kirchhoff_fixed_corotated};

pub const FIXED_COROTATED: ElasticDef = ElasticDef {
    name: "fixed_corotated",
    kirchhoff: kirchhoff_fixed_corotated,
    energy: energy_fixed_corotated,
    wgsl_kirchhoff: "elastic_kirchhoff_fixed_corotated(f, m.mu, m.lambda)",
    wgsl_module: "",
};
