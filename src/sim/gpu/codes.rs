//! The codes and limits that Rust writes into the GPU records and WGSL reads, defined once:
//! here, as methods of the Rust types they encode. The WGSL side gets them as generated
//! `const` declarations ([`material_wgsl`] with the simulation's library, [`step_wgsl`]
//! with the step passes), so no number is typed twice. `tests::…` reads the generated
//! constants back with naga, an independent parser, and compares them with the codes the
//! Rust records carry.
//!
//! A new code (a boundary kind, a collider shape, a return-mapping variant): add the
//! variant to its Rust type, give it its code in the `gpu_code` match below and its WGSL
//! name in the list; the shaders then use the constant by name.

use crate::sim::actions::Effect;
use crate::sim::boundary::BoundaryKind;
use crate::sim::kinematic::ColliderShape;
use crate::sim::model::nacc::oracle::{Case3Variant, ReturnCase, ReturnMapping};

/// Materials a simulation may have (the GPU step's constant table).
pub const MAX_MATERIALS: usize = 16;
/// Planar colliders a simulation may have.
pub const MAX_COLLIDERS: usize = 8;
/// Moving colliders a simulation may have.
pub const MAX_KINEMATIC: usize = 4;
pub use crate::sim::actions::MAX_ACTIONS;
/// Bits of a particle's material word that hold its material's index (WGSL
/// `MATERIAL_BITS`); the timed actions acting on it take the bits above.
pub const MATERIAL_BITS: u32 = 16;

/// A particle's material word on the GPU: the index of its material, and bit
/// `MATERIAL_BITS + k` set when action k acts on it (`members`, bit k).
pub fn material_word(material: u32, members: u32) -> u32 {
    debug_assert!(material < 1 << MATERIAL_BITS && members < 1 << (32 - MATERIAL_BITS));
    material | members << MATERIAL_BITS
}

const _: () =
    assert!(MAX_MATERIALS <= 1 << MATERIAL_BITS && MAX_ACTIONS <= 32 - MATERIAL_BITS as usize);
/// Nodes per axis of an active block of the sparse grid (docs/method.md §2; WGSL `BLOCK`).
pub const BLOCK: u32 = 4;
/// Nodes per row of the grid texture (WGSL `GRID_TEXELS_PER_ROW`): 64 whole blocks.
pub const GRID_TEXELS_PER_ROW: u32 = 4096;

impl BoundaryKind {
    /// Every kind, in code order.
    pub const ALL: [BoundaryKind; 3] = [
        BoundaryKind::Sticky,
        BoundaryKind::Slip,
        BoundaryKind::Separate,
    ];

    /// `Condition.kind` on the GPU (WGSL `BOUNDARY_*`).
    pub fn gpu_code(self) -> u32 {
        match self {
            BoundaryKind::Sticky => 0,
            BoundaryKind::Slip => 1,
            BoundaryKind::Separate => 2,
        }
    }

    fn wgsl_name(self) -> &'static str {
        match self {
            BoundaryKind::Sticky => "BOUNDARY_STICKY",
            BoundaryKind::Slip => "BOUNDARY_SLIP",
            BoundaryKind::Separate => "BOUNDARY_SEPARATE",
        }
    }
}

impl ColliderShape {
    /// One shape of each kind (the sizes do not matter for the code).
    pub const KINDS: [ColliderShape; 3] = [
        ColliderShape::Sphere { radius: 0.0 },
        ColliderShape::Box {
            half: glam::DVec3::ZERO,
        },
        ColliderShape::Cylinder {
            radius: 0.0,
            half_height: 0.0,
        },
    ];

    /// `KinematicCollider.shape` on the GPU (WGSL `SHAPE_*`).
    pub fn gpu_code(&self) -> u32 {
        match self {
            ColliderShape::Sphere { .. } => 0,
            ColliderShape::Box { .. } => 1,
            ColliderShape::Cylinder { .. } => 2,
        }
    }

    fn wgsl_name(&self) -> &'static str {
        match self {
            ColliderShape::Sphere { .. } => "SHAPE_SPHERE",
            ColliderShape::Box { .. } => "SHAPE_BOX",
            ColliderShape::Cylinder { .. } => "SHAPE_CYLINDER",
        }
    }
}

impl ReturnMapping {
    /// `NaccMaterial.variant` on the GPU (WGSL `NACC_VARIANT_*`).
    pub fn gpu_code(self) -> u32 {
        match self {
            ReturnMapping::Center => 0,
            ReturnMapping::Continuous => 1,
            ReturnMapping::ClosestPoint => 2,
        }
    }

    fn wgsl_name(self) -> &'static str {
        match self {
            ReturnMapping::Center => "NACC_VARIANT_CENTER",
            ReturnMapping::Continuous => "NACC_VARIANT_CONTINUOUS",
            ReturnMapping::ClosestPoint => "NACC_VARIANT_CLOSEST_POINT",
        }
    }
}

impl Case3Variant {
    /// `NaccMaterial.variant` on the GPU (WGSL `NACC_VARIANT_*`): its mapping's code.
    pub fn gpu_code(&self) -> u32 {
        self.mapping().gpu_code()
    }
}

impl ReturnCase {
    /// Every row of the return-mapping table, in code order.
    pub const ALL: [ReturnCase; 4] = [
        ReturnCase::Elastic,
        ReturnCase::UpperTip,
        ReturnCase::LowerTip,
        ReturnCase::Interior,
    ];

    /// The row's code in WGSL (`NACC_*`), as the test harness reads it back.
    pub fn gpu_code(self) -> u32 {
        match self {
            ReturnCase::Elastic => 0,
            ReturnCase::UpperTip => 1,
            ReturnCase::LowerTip => 2,
            ReturnCase::Interior => 3,
        }
    }

    /// The row of a WGSL case code.
    pub fn from_gpu_code(code: u32) -> Option<ReturnCase> {
        Self::ALL.into_iter().find(|c| c.gpu_code() == code)
    }

    fn wgsl_name(self) -> &'static str {
        match self {
            ReturnCase::Elastic => "NACC_ELASTIC",
            ReturnCase::UpperTip => "NACC_UPPER_TIP",
            ReturnCase::LowerTip => "NACC_LOWER_TIP",
            ReturnCase::Interior => "NACC_INTERIOR",
        }
    }
}

/// The words of `block_args`, the active blocks' indirect dispatch that
/// `compact_blocks.wgsl` writes: the three workgroup counts an indirect dispatch reads, in
/// its order, then the number of blocks counted, which the node passes and
/// [`GpuSim::active_blocks`](super::GpuSim::active_blocks) read (WGSL `BLOCK_ARG_*`, the
/// array's length `BLOCK_ARGS`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlockArg {
    GroupsX,
    GroupsY,
    GroupsZ,
    /// Blocks counted (those beyond the pool's capacity are counted but not listed).
    Blocks,
}

impl BlockArg {
    /// Every word, in order.
    pub const ALL: [BlockArg; 4] = [
        BlockArg::GroupsX,
        BlockArg::GroupsY,
        BlockArg::GroupsZ,
        BlockArg::Blocks,
    ];

    /// Words in the buffer.
    pub const WORDS: u32 = Self::ALL.len() as u32;

    /// The word's index (WGSL `BLOCK_ARG_*`).
    pub fn index(self) -> usize {
        self as usize
    }

    fn wgsl_name(self) -> &'static str {
        match self {
            BlockArg::GroupsX => "BLOCK_ARG_GROUPS_X",
            BlockArg::GroupsY => "BLOCK_ARG_GROUPS_Y",
            BlockArg::GroupsZ => "BLOCK_ARG_GROUPS_Z",
            BlockArg::Blocks => "BLOCK_ARG_BLOCKS",
        }
    }
}

/// The watchdog's counters: one `atomic<u32>` word each in the `flags` buffer that the
/// step passes write and [`GpuSim::take_watchdog`](crate::sim::gpu::GpuSim::take_watchdog) reads once a frame (WGSL
/// `WATCH_*`, the array's length `WATCH_SLOTS`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WatchSlot {
    /// Particles with a non-finite position, velocity or F (`g2p.wgsl`).
    Nonfinite,
    /// Particles whose stencil left the grid (`g2p.wgsl`).
    Escaped,
    /// The first step that counted a failure, as its bitwise NOT so that `atomicMax`
    /// keeps the earliest (0: none).
    FirstStep,
    /// Steps since the last read (`compact_blocks.wgsl`).
    Step,
    /// The most active blocks of one step (`compact_blocks.wgsl`).
    ActiveBlocksMax,
    /// Active blocks that found the pool full (`compact_blocks.wgsl`).
    PoolOverflow,
    /// Particles past the fixed-point P2G's speed bound (`p2g_fixed.wgsl`).
    FixedPointRange,
    /// The largest particle speed, as the bits of a non-negative f32 (which order as the
    /// floats do).
    SpeedMax,
    /// The bitwise NOT of the lowest index of a particle counted as non-finite or escaped
    /// (0: none).
    FirstParticle,
    /// Particle-steps whose deformation increment inverted, det(I + Δt C) ≤ 0
    /// (`g2p.wgsl`): the step was too long for the velocity gradient there.
    Inverted,
    /// The first step that counted an inversion, as its bitwise NOT (0: none).
    InvertedFirstStep,
    /// The bitwise NOT of the lowest index of a particle counted as inverted (0: none).
    InvertedFirstParticle,
}

impl WatchSlot {
    /// Every slot, in word order.
    pub const ALL: [WatchSlot; 12] = [
        WatchSlot::Nonfinite,
        WatchSlot::Escaped,
        WatchSlot::FirstStep,
        WatchSlot::Step,
        WatchSlot::ActiveBlocksMax,
        WatchSlot::PoolOverflow,
        WatchSlot::FixedPointRange,
        WatchSlot::SpeedMax,
        WatchSlot::FirstParticle,
        WatchSlot::Inverted,
        WatchSlot::InvertedFirstStep,
        WatchSlot::InvertedFirstParticle,
    ];

    /// Words in the buffer.
    pub const COUNT: u32 = Self::ALL.len() as u32;

    /// The slot's word index (WGSL `WATCH_*`).
    pub fn index(self) -> usize {
        self as usize
    }

    fn wgsl_name(self) -> &'static str {
        match self {
            WatchSlot::Nonfinite => "WATCH_NONFINITE",
            WatchSlot::Escaped => "WATCH_ESCAPED",
            WatchSlot::FirstStep => "WATCH_FIRST_STEP",
            WatchSlot::Step => "WATCH_STEP",
            WatchSlot::ActiveBlocksMax => "WATCH_ACTIVE_BLOCKS_MAX",
            WatchSlot::PoolOverflow => "WATCH_POOL_OVERFLOW",
            WatchSlot::FixedPointRange => "WATCH_FIXED_POINT_RANGE",
            WatchSlot::SpeedMax => "WATCH_SPEED_MAX",
            WatchSlot::FirstParticle => "WATCH_FIRST_PARTICLE",
            WatchSlot::Inverted => "WATCH_INVERTED",
            WatchSlot::InvertedFirstStep => "WATCH_INVERTED_FIRST_STEP",
            WatchSlot::InvertedFirstParticle => "WATCH_INVERTED_FIRST_PARTICLE",
        }
    }
}

/// `Action.mode` on the GPU for what a timed action does over a substep (WGSL
/// `ACTION_*`): nothing (outside its window), a push, a move.
pub fn effect_code(e: Option<&Effect>) -> u32 {
    match e {
        None => 0,
        Some(Effect::Push(_)) => 1,
        Some(Effect::Move { .. }) => 2,
    }
}

/// Every `Action.mode`, with its WGSL name.
fn effect_codes() -> [(&'static str, u32); 3] {
    let (push, moved) = (
        Effect::Push(glam::DVec3::ZERO),
        Effect::Move {
            velocity: glam::DVec3::ZERO,
            displacement: glam::DVec3::ZERO,
        },
    );
    [
        ("ACTION_IDLE", effect_code(None)),
        ("ACTION_PUSH", effect_code(Some(&push))),
        ("ACTION_MOVE", effect_code(Some(&moved))),
    ]
}

/// The constants the material modules read (`shaders/sim/model/nacc.wgsl`), name and value.
pub fn material_constants() -> Vec<(&'static str, u32)> {
    let variants = ReturnMapping::ALL
        .iter()
        .map(|v| (v.wgsl_name(), v.gpu_code()));
    let cases = ReturnCase::ALL.map(|c| (c.wgsl_name(), c.gpu_code()));
    variants.chain(cases).collect()
}

/// The constants the step passes read (`shaders/sim/step/common.wgsl`), name and value.
pub fn step_constants() -> Vec<(&'static str, u32)> {
    let limits = [
        ("MAX_MATERIALS", MAX_MATERIALS as u32),
        ("MAX_COLLIDERS", MAX_COLLIDERS as u32),
        ("MAX_KINEMATIC", MAX_KINEMATIC as u32),
        ("MAX_ACTIONS", MAX_ACTIONS as u32),
        ("MATERIAL_BITS", MATERIAL_BITS),
        ("MATERIAL_INDEX_MASK", (1 << MATERIAL_BITS) - 1),
        ("BLOCK", BLOCK),
        ("BLOCK_NODES", BLOCK * BLOCK * BLOCK),
        ("GRID_TEXELS_PER_ROW", GRID_TEXELS_PER_ROW),
    ];
    let kinds = BoundaryKind::ALL.map(|k| (k.wgsl_name(), k.gpu_code()));
    let shapes = ColliderShape::KINDS
        .iter()
        .map(|s| (s.wgsl_name(), s.gpu_code()));
    let watch = WatchSlot::ALL.map(|w| (w.wgsl_name(), w.index() as u32));
    let block_args = BlockArg::ALL.map(|a| (a.wgsl_name(), a.index() as u32));
    limits
        .into_iter()
        .chain([("WATCH_SLOTS", WatchSlot::COUNT)])
        .chain([("BLOCK_ARGS", BlockArg::WORDS)])
        .chain(block_args)
        .chain(effect_codes())
        .chain(kinds)
        .chain(shapes)
        .chain(watch)
        .collect()
}

fn declare(title: &str, constants: &[(&'static str, u32)]) -> String {
    let mut out = format!("// Generated by sim::gpu::codes::{title} (src/sim/gpu/codes.rs).\n");
    for (name, value) in constants {
        out += &format!("const {name}: u32 = {value}u;\n");
    }
    out
}

/// WGSL declarations of [`material_constants`], part of the simulation's library.
pub fn material_wgsl() -> String {
    declare("material_wgsl", &material_constants())
}

/// WGSL declarations of [`step_constants`], for the step passes.
pub fn step_wgsl() -> String {
    declare("step_wgsl", &step_constants())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::boundary::Condition;
    use crate::sim::gpu::step::layout::{GpuCondition, GpuKinematic, GpuMaterial};
    use crate::sim::kinematic::{KinematicCollider, RigidMotion};
    use crate::sim::model::nacc::NaccMaterialGpu;
    use crate::sim::Material;
    use wgpu::naga;

    /// The value of every u32 `const` of `src`, as naga reads it after the module validates.
    fn wgsl_constants(src: &str) -> std::collections::HashMap<String, u32> {
        let module = crate::gpu::layout_check::validated_module(src);
        module
            .constants
            .iter()
            .filter_map(|(_, c)| match module.global_expressions[c.init] {
                naga::Expression::Literal(naga::Literal::U32(v)) => Some((c.name.clone()?, v)),
                _ => None,
            })
            .collect()
    }

    /// The value of the WGSL constant `name` in the shaders the step passes are built
    /// from (the whole step source with a trivial entry point).
    fn step_constant(name: &str) -> u32 {
        let src = crate::sim::gpu::step::source("@compute @workgroup_size(1) fn main() {}");
        *wgsl_constants(&src)
            .get(name)
            .unwrap_or_else(|| panic!("{name} is not declared in the step's WGSL"))
    }

    /// What each Rust record writes is what the WGSL constant of the same meaning holds,
    /// read back by naga from the sources the passes are compiled from: boundary kinds,
    /// collider shapes, return-mapping variants and cases, and the limits.
    #[test]
    fn every_code_rust_writes_is_the_wgsl_constant_of_its_name() {
        for kind in BoundaryKind::ALL {
            let record = GpuCondition::from_cpu(&Condition {
                kind,
                friction: 0.0,
            });
            assert_eq!(record.kind, step_constant(kind.wgsl_name()), "{kind:?}");
        }
        for shape in ColliderShape::KINDS {
            let k = KinematicCollider {
                shape,
                centre: glam::DVec3::ZERO,
                margin: 0.0,
                condition: Condition::STICKY,
                motion: RigidMotion::new(vec![0.0], vec![glam::Vec3::ZERO], vec![glam::Vec3::ZERO]),
            };
            let record = GpuKinematic::from_cpu(&k);
            assert_eq!(record.shape, step_constant(shape.wgsl_name()), "{shape:?}");
        }
        let params = crate::sim::model::nacc::oracle::NaccParams {
            e: 2000.0,
            nu: 0.38,
            alpha0: -0.04,
            beta: 1.0,
            xi: 2.0,
            m_slope: 2.36,
        };
        for mapping in ReturnMapping::ALL {
            let variant = mapping.variant(2.0);
            let record = NaccMaterialGpu::new(&params, variant);
            assert_eq!(
                record.variant,
                step_constant(mapping.wgsl_name()),
                "{variant:?}"
            );
            // The step's record carries it among NACC's parameters (`Nacc::gpu_params`).
            let step_record = GpuMaterial::from_material(&Material::nacc(params, variant));
            assert_eq!(
                step_record.params[4].to_bits(),
                record.variant,
                "{variant:?}"
            );
        }
        for slot in WatchSlot::ALL {
            assert_eq!(
                step_constant(slot.wgsl_name()),
                slot.index() as u32,
                "{slot:?}"
            );
        }
        assert_eq!(step_constant("WATCH_SLOTS"), WatchSlot::COUNT);
        for arg in BlockArg::ALL {
            assert_eq!(
                step_constant(arg.wgsl_name()),
                arg.index() as u32,
                "{arg:?}"
            );
        }
        assert_eq!(step_constant("BLOCK_ARGS"), BlockArg::WORDS);
        // An indirect dispatch reads its x, y, z counts from the buffer's first words.
        assert_eq!(
            [BlockArg::GroupsX, BlockArg::GroupsY, BlockArg::GroupsZ].map(BlockArg::index),
            [0, 1, 2]
        );
        for case in ReturnCase::ALL {
            assert_eq!(case.gpu_code(), step_constant(case.wgsl_name()), "{case:?}");
            assert_eq!(ReturnCase::from_gpu_code(case.gpu_code()), Some(case));
        }
        assert_eq!(step_constant("MAX_MATERIALS") as usize, MAX_MATERIALS);
        assert_eq!(step_constant("MAX_COLLIDERS") as usize, MAX_COLLIDERS);
        assert_eq!(step_constant("MAX_KINEMATIC") as usize, MAX_KINEMATIC);
        assert_eq!(step_constant("MAX_ACTIONS") as usize, MAX_ACTIONS);
        let word = material_word(5, 0b101);
        assert_eq!(word & step_constant("MATERIAL_INDEX_MASK"), 5);
        assert_eq!(word >> step_constant("MATERIAL_BITS"), 0b101);
        let codes = effect_codes();
        assert_eq!(codes.map(|(_, c)| c), [0, 1, 2], "distinct modes");
        for (name, code) in codes {
            assert_eq!(step_constant(name), code, "{name}");
        }
        assert_eq!(step_constant("BLOCK"), BLOCK);
        assert_eq!(step_constant("GRID_TEXELS_PER_ROW"), GRID_TEXELS_PER_ROW);
    }

    /// Within each family the codes are distinct (no two share a dispatch case), and no
    /// hand-written WGSL file declares one of them again (naga would reject the duplicate,
    /// but only when both land in one module; this checks the files themselves).
    #[test]
    fn codes_are_distinct_and_declared_only_here() {
        let families: [Vec<u32>; 4] = [
            BoundaryKind::ALL.map(|k| k.gpu_code()).to_vec(),
            ColliderShape::KINDS.iter().map(|s| s.gpu_code()).collect(),
            ReturnMapping::ALL.iter().map(|v| v.gpu_code()).collect(),
            ReturnCase::ALL.map(|c| c.gpu_code()).to_vec(),
        ];
        for codes in families {
            let unique: std::collections::HashSet<_> = codes.iter().collect();
            assert_eq!(unique.len(), codes.len(), "codes {codes:?}");
        }
        let shaders = [
            include_str!("../../../shaders/sim/model/nacc.wgsl"),
            include_str!("../../../shaders/sim/step/common.wgsl"),
            include_str!("../../../shaders/sim/material.wgsl"),
        ];
        for (name, _) in material_constants().into_iter().chain(step_constants()) {
            for text in shaders {
                assert!(
                    !text.contains(&format!("const {name}:")),
                    "{name} is declared by hand in a shader; it comes from sim::gpu::codes"
                );
            }
        }
    }

    /// Every pass that binds the watchdog's `flags` declares them as the buffer
    /// `take_watchdog` reads: `WATCH_SLOTS` words, not a length typed by hand.
    #[test]
    fn every_pass_declares_the_watchdog_by_its_slot_count() {
        let passes = [
            ("g2p", include_str!("../../../shaders/sim/step/g2p.wgsl")),
            (
                "compact_blocks",
                include_str!("../../../shaders/sim/step/compact_blocks.wgsl"),
            ),
            (
                "p2g_fixed",
                include_str!("../../../shaders/sim/step/p2g_fixed.wgsl"),
            ),
        ];
        for (name, src) in passes {
            let decl = src
                .lines()
                .find(|l| l.contains("> flags:"))
                .unwrap_or_else(|| panic!("{name}.wgsl binds no watchdog flags"));
            assert!(
                decl.contains("array<atomic<u32>, WATCH_SLOTS>"),
                "{name}.wgsl: {decl}"
            );
        }
    }

    /// Every pass that binds the active blocks' dispatch declares it `BLOCK_ARGS` words
    /// long and reads its words by their names, not by indices typed by hand.
    #[test]
    fn every_pass_reads_the_block_dispatch_by_its_names() {
        let files = [
            (
                "compact_blocks",
                include_str!("../../../shaders/sim/step/compact_blocks.wgsl"),
            ),
            (
                "grid_from_sums",
                include_str!("../../../shaders/sim/step/grid_from_sums.wgsl"),
            ),
            (
                "node_gather",
                include_str!("../../../shaders/sim/step/node_gather.wgsl"),
            ),
            (
                "group_walk",
                include_str!("../../../shaders/sim/step/group_walk.wgsl"),
            ),
        ];
        for (name, src) in files {
            for line in src.lines().filter(|l| !l.trim_start().starts_with("//")) {
                if line.contains("> block_args:") {
                    assert!(
                        line.contains("u32>, BLOCK_ARGS>") || line.contains("u32, BLOCK_ARGS>"),
                        "{name}.wgsl: {line}"
                    );
                }
                for (at, _) in line.match_indices("block_args[") {
                    let index = &line[at + "block_args[".len()..];
                    assert!(index.starts_with("BLOCK_ARG_"), "{name}.wgsl: {line}");
                }
            }
        }
    }
}
