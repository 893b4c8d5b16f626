//! St. Venant–Kirchhoff on the Hencky strain (docs/method.md §3), the elasticity under
//! Drucker–Prager and von Mises: oracle in `sim::model::elasticity`, WGSL in
//! `shaders/sim/elasticity.wgsl`.

use super::ElasticDef;
use crate::sim::model::elasticity::{energy_stvk_hencky, kirchhoff_stvk_hencky};

pub const STVK_HENCKY: ElasticDef = ElasticDef {
    name: "stvk_hencky",
    kirchhoff: kirchhoff_stvk_hencky,
    energy: energy_stvk_hencky,
    wgsl_kirchhoff: "elastic_kirchhoff_stvk_hencky(f, m.mu, m.lambda)",
    wgsl_module: "",
};
