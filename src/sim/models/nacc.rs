//! NACC plasticity (docs/method.md §4): oracle `sim::nacc::return_map`, WGSL
//! `nacc_return_map` in `shaders/sim/nacc.wgsl`.

use super::PlasticDef;

pub const NACC: PlasticDef = PlasticDef {
    name: "nacc",
    wgsl_body: "let r = nacc_return_map(f, alpha, m.nacc); return PlasticState(r.f, r.alpha);",
    wgsl_module: "",
};
