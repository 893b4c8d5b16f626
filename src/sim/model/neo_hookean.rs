//! Neo-Hookean, Borden form (docs/method.md §3), also the elasticity under NACC: oracle
//! in `sim::model::elasticity`, WGSL in `shaders/sim/elasticity.wgsl`.

use super::ElasticDef;
use crate::sim::model::elasticity::{energy_neo_hookean, kirchhoff_neo_hookean};

pub const NEO_HOOKEAN: ElasticDef = ElasticDef {
    name: "neo_hookean",
    kirchhoff: kirchhoff_neo_hookean,
    energy: energy_neo_hookean,
    wgsl_kirchhoff: "elastic_kirchhoff_neo_hookean(f, m.mu, m.kappa)",
    wgsl_module: "",
};
