//! The step's WGSL: its shared modules (each names what it needs, as its file's `// Needs:`
//! line does), and the start every pass's source shares.

use crate::gpu::wgsl::{Module, Source};
use crate::sim::gpu::wgsl;
use crate::sim::model::ModelsUsed;

/// The step's shared declarations (buffers' layouts, node indexing, the grid texture).
/// With the codes and the registry's dispatch, which [`step_source`] generates.
pub(crate) static COMMON: Module = Module {
    name: "sim/step/common",
    text: include_str!("../../../../shaders/sim/step/common.wgsl"),
    needs: &[&wgsl::MATH, &wgsl::BSPLINE],
};
/// The grid update, called by the P2G gathers as each node's sums finish.
pub(crate) static GRID_UPDATE: Module = Module {
    name: "sim/step/grid_update",
    text: include_str!("../../../../shaders/sim/step/grid_update.wgsl"),
    needs: &[&COMMON],
};
/// What two-field separation's passes, P2G and G2P share.
pub(crate) static SEPARATION: Module = Module {
    name: "sim/step/separation",
    text: include_str!("../../../../shaders/sim/step/separation.wgsl"),
    needs: &[&COMMON],
};
/// The node passes' gather from the sorted particles (cells' runs, active blocks, the walk
/// over the 27 base cells).
pub(crate) static NODE_GATHER: Module = Module {
    name: "sim/step/node_gather",
    text: include_str!("../../../../shaders/sim/step/node_gather.wgsl"),
    needs: &[&COMMON],
};
/// What both P2G gathers sum at a node and how they finish it.
pub(crate) static P2G_SUMS: Module = Module {
    name: "sim/step/p2g_sums",
    text: include_str!("../../../../shaders/sim/step/p2g_sums.wgsl"),
    needs: &[&GRID_UPDATE, &SEPARATION, &NODE_GATHER],
};
/// The walk of the gathers by subgroups.
pub(crate) static GROUP_WALK: Module = Module {
    name: "sim/step/group_walk",
    text: include_str!("../../../../shaders/sim/step/group_walk.wgsl"),
    needs: &[&COMMON],
};

/// The step's modules, for the tests that tie each to its file's `// Needs:` line.
#[cfg(test)]
pub(crate) static MODULES: [&Module; 6] = [
    &COMMON,
    &GRID_UPDATE,
    &SEPARATION,
    &NODE_GATHER,
    &P2G_SUMS,
    &GROUP_WALK,
];

/// The start of every step pass's source: the library, the step's codes, the shared
/// declarations, the registry's WGSL for the models in `used` (their codes, functions and
/// dispatch), the grid update and separation's shared functions.
pub(crate) fn step_source(used: &ModelsUsed) -> Source {
    wgsl::library_source()
        .generated(crate::sim::gpu::codes::step_wgsl())
        .module(&COMMON)
        .generated(crate::sim::model::wgsl_for(used))
        .module(&GRID_UPDATE)
        .module(&SEPARATION)
}

/// A step pass's whole source, with dispatch cases for every model.
pub(crate) fn source(pass: &str) -> String {
    source_for(pass, &ModelsUsed::all())
}

/// As [`source`], with dispatch cases for the models in `used` only.
pub(crate) fn source_for(pass: &str, used: &ModelsUsed) -> String {
    step_source(used).pass(pass)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::wgsl::declared_needs;
    use crate::sim::gpu::step::p2g_gather_source;

    /// Each shared step file names in its `// Needs:` line exactly the modules its Rust
    /// [`Module`] includes before it, and every pass's source validates.
    #[test]
    fn step_modules_declare_what_they_need() {
        for m in MODULES {
            let listed: Vec<&str> = m.needs.iter().map(|n| n.name).collect();
            assert_eq!(declared_needs(m.text), listed, "{}", m.name);
        }
        let all = ModelsUsed::all();
        let sources = [
            source("@compute @workgroup_size(1) fn main() {}"),
            p2g_gather_source(true).pass(include_str!("../../../../shaders/sim/step/p2g.wgsl")),
            step_source(&all)
                .define("NEXT_KEYS", true)
                .define("SEPARATION", false)
                .define("ACTIONS", true)
                .pass(include_str!("../../../../shaders/sim/step/g2p.wgsl")),
        ];
        for src in sources {
            crate::gpu::layout_check::validated_module(&src);
        }
    }
}
