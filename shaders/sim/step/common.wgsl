// Shared declarations of the MPM step passes (docs/method.md §2). Mirrored by `#[repr(C)]` types in
// src/sim/gpu.rs (checked by `sim::gpu::tests::layouts_match_wgsl`). The step's codes and the
// registry's WGSL come with it (`sim::gpu::step::step_source`).
// Needs: sim/math, sim/bspline.

// The limits MAX_{MATERIALS,COLLIDERS,KINEMATIC}, the boundary kinds BOUNDARY_{STICKY,SLIP,
// SEPARATE}, the collider shapes SHAPE_{SPHERE,BOX,CYLINDER}, the block size BLOCK and
// BLOCK_NODES and GRID_TEXELS_PER_ROW are generated from the Rust side (src/sim/gpu/codes.rs)
// and precede this file.

// A boundary condition on a domain face or a collider.
struct Condition {
    // BOUNDARY_*
    kind: u32,
    // Coulomb friction μ on the tangential velocity
    friction: f32,
    _pad0: u32,
    _pad1: u32,
}

// A planar collider: the solid half-space (x − point)·normal ≤ 0, normal unit and outward.
struct Collider {
    point: vec4<f32>,
    normal: vec4<f32>,
    condition: Condition,
}

// A moving rigid collider (src/sim/kinematic.rs): a shape about `centre` in its own frame,
// covering the nodes within `margin` of it.
struct KinematicCollider {
    // SHAPE_*
    shape: u32,
    margin: f32,
    _pad0: u32,
    _pad1: u32,
    // sphere: x radius; box: xyz half extents; cylinder (axis z): x radius, y half height
    size: vec4<f32>,
    centre: vec4<f32>,
    condition: Condition,
}

// A kinematic collider's pose during the current substep: copied into `step.poses` before
// each substep from the poses uploaded for the whole call (GpuSim::step).
struct KinematicPose {
    // frame-to-world
    rotation: mat3x3<f32>,
    position: vec4<f32>,
    velocity: vec4<f32>,
    angular_velocity: vec4<f32>,
}

// What a timed action does over the current substep (sim::actions::Effect): with
// ACTION_PUSH, v_p += velocity; with ACTION_MOVE, x_p moves by displacement, v_p =
// velocity and C_p = 0. Copied into `step.actions` before each substep (GpuSim::step).
struct Action {
    velocity: vec3<f32>,
    mode: u32,
    displacement: vec3<f32>,
    _pad: u32,
}

// The captured surface collider (src/sim/boundary.rs, SurfaceCollider): `on` when the
// buffer `surface` holds φ at every node.
struct SurfaceCondition {
    on: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
    condition: Condition,
}

struct SimStep {
    // node i sits at lo + i·dx
    lo: vec3<f32>,
    dx: f32,
    gravity: vec3<f32>,
    dt: f32,
    // cells per axis (nodes = cells + 1)
    cells: vec3<u32>,
    num_particles: u32,
    // nodes per axis
    nodes: vec3<u32>,
    num_colliders: u32,
    // wall band width in nodes, and whether the transfer is APIC (1) or PIC (0)
    band: u32,
    apic: u32,
    num_kinematic: u32,
    // blocks the grid pool holds (sparse grid: common.wgsl, node_index)
    pool_blocks: u32,
    // the FLIP share of G2P's velocity (0: APIC or PIC; the grid's velocity change is then
    // neither written nor read)
    flip: f32,
    // the fixed-point P2G's units, 2^−e kg and 2^−e kg·m/s (p2g_fixed.wgsl), and the speed
    // under which every particle must stay for its sums to fit
    mass_exponent: i32,
    momentum_exponent: i32,
    speed_bound: f32,
    // the force fields (sim::fields): wind velocity and drag k (0: no wind), attractor
    // point, acceleration (0: none) and falloff r²
    wind: vec3<f32>,
    wind_drag: f32,
    attractor: vec3<f32>,
    attractor_strength: f32,
    attractor_falloff2: f32,
    // timed actions in `actions`, which act on the particles whose material word has their
    // bit (g2p.wgsl)
    num_actions: u32,
    _fields_pad0: u32,
    _fields_pad1: u32,
    surface: SurfaceCondition,
    // domain faces −x, +x, −y, +y, −z, +z
    walls: array<Condition, 6>,
    colliders: array<Collider, MAX_COLLIDERS>,
    materials: array<SimMaterial, MAX_MATERIALS>,
    kinematic: array<KinematicCollider, MAX_KINEMATIC>,
    // rewritten per substep
    poses: array<KinematicPose, MAX_KINEMATIC>,
    // last: rewritten per substep
    actions: array<Action, MAX_ACTIONS>,
}

// Every step pass binds the step's constants here. Helpers below read this global rather
// than taking the struct as a parameter: the struct is over a kilobyte, and CPU drivers
// (lavapipe) copy by-value arguments. A read-only storage buffer rather than a uniform:
// lavapipe specialises a shader on uniform values that steer its branches and loops, and
// re-specialised the grid pass on every dispatch (visible in
// `splatter bench sim --per-pass`).
@group(0) @binding(0) var<storage, read> step: SimStep;

// The step's scalar constants, copied out of `step` by read_consts() as the first statement
// of every entry point, and read from here by the helpers. Why a copy: a CPU driver
// (lavapipe) loads a buffer value once for all invocations only outside branches and loops;
// inside one — and anywhere after an early return — it loads it once per invocation, in a
// loop over the SIMD lanes. Read where used, Δx alone was a tenth of the scatter's time.
struct StepConsts {
    lo: vec3<f32>,
    dx: f32,
    inv_dx: f32,
    dt: f32,
    gravity: vec3<f32>,
    cells: vec3<u32>,
    nodes: vec3<u32>,
    num_particles: u32,
    pool_blocks: u32,
    apic: u32,
    flip: f32,
    // step.materials[0], read for all invocations at once; particle_material
    material0: SimMaterial,
}

var<private> consts: StepConsts;

// The fixed-point P2G's scales (p2g_fixed.wgsl, grid_from_sums.wgsl): 2^e as f32, built
// from its bits so that it is exact (a CPU driver may call a library per lane for ldexp
// or exp2), for |e| ≤ 126.
const TWO_TO_32: f32 = 4294967296.0;
const TWO_TO_MINUS_32: f32 = 2.3283064365386963e-10;

fn power_of_two(e: i32) -> f32 {
    return bitcast<f32>(u32(e + 127) << 23u);
}

fn read_consts() {
    consts.lo = step.lo;
    consts.dx = step.dx;
    consts.inv_dx = 1.0 / step.dx;
    consts.dt = step.dt;
    consts.gravity = step.gravity;
    consts.cells = step.cells;
    consts.nodes = step.nodes;
    consts.num_particles = step.num_particles;
    consts.pool_blocks = step.pool_blocks;
    consts.apic = step.apic;
    consts.flip = step.flip;
    consts.material0 = step.materials[0];
}

// The parameters of material i. Material 0's come from the copy read at the top of the
// pass; other materials are read for the invocations that have them (a scene of one
// material pays nothing per particle for its parameters).
// A particle's `material` word holds its material's index in the low MATERIAL_BITS bits
// and the timed actions acting on it above them (sim::gpu::codes::material_word).
fn particle_material(word: u32) -> SimMaterial {
    let i = word & MATERIAL_INDEX_MASK;
    if i == 0u {
        return consts.material0;
    }
    return step.materials[i];
}

// The affine momentum term of P2G, m_p C_p − Δt V⁰_p (4/Δx²) τ(F_p, α_p) (docs/method.md
// §2 step 1), from the particle's material, F, hardening state, C, mass and initial volume.
fn affine_term(m: SimMaterial, f: mat3x3<f32>, alpha: f32, c: mat3x3<f32>, mass: f32,
               volume: f32) -> mat3x3<f32> {
    let inv_d = 4.0 / (consts.dx * consts.dx);
    var a = material_stress(m, f, alpha) * (-consts.dt * volume * inv_d);
    if consts.apic == 1u {
        a += c * mass;
    }
    return a;
}

// Key of a particle whose stencil is off the grid: one past the last base cell, so those
// particles sort last and fall into the extra slot of the cell ranges.
fn no_cell_key() -> u32 {
    let bc = consts.cells - 1u;
    return bc.x * bc.y * bc.z;
}

// The sort key of a particle at x on the gather path: its base cell (x fastest), or
// no_cell_key() when its stencil is off the grid (prepare.wgsl, g2p.wgsl).
fn cell_key(x: vec3<f32>) -> u32 {
    let st = grid_stencil(x);
    if !st.ok {
        return no_cell_key();
    }
    let bc = consts.cells - 1u;
    let b = vec3<u32>(st.s.base);
    return b.x + bc.x * (b.y + bc.y * b.z);
}

// The stencil of x when its 3×3×3 nodes all lie on the grid (mirrors `cpu::Grid::stencil`).
struct GridStencil {
    ok: bool,
    s: BsplineStencil,
}

fn grid_stencil(x: vec3<f32>) -> GridStencil {
    var out: GridStencil;
    out.ok = false;
    if !sim_is_finite3(x) {
        return out;
    }
    let rel = (x - consts.lo) / consts.dx;
    let top = vec3<f32>(consts.cells) - 0.5;
    if any(rel < vec3<f32>(0.5)) || any(rel >= top) {
        return out;
    }
    out.s = bspline_stencil(x - consts.lo, consts.inv_dx);
    out.ok = all(out.s.base >= vec3<i32>(0)) && all(out.s.base + 2 <= vec3<i32>(consts.cells));
    return out;
}

// The particles one dispatch of a per-particle pass covers. Particle arrays may exceed one
// storage binding (gpu::pages): such a pass is dispatched once per page, over windows of
// the arrays that start at particle `base`, and runs for the local indices 0..count.
struct PageRange {
    base: u32,
    count: u32,
}

@group(0) @binding(13) var<storage, read> page: PageRange;

fn flat_id(wid: vec3<u32>, nwg: vec3<u32>, lid: u32) -> u32 {
    return (wid.x + wid.y * nwg.x) * 256u + lid;
}

// Active blocks. The node passes visit only blocks of 4×4×4 nodes that some particle's
// stencil reaches, one workgroup of 64 invocations per block: most of a domain is air, and
// even skipping an empty node costs a load. Particle
// passes flag the blocks (mark_blocks.wgsl, p2g_scatter.wgsl), compact_blocks.wgsl lists
// them, and the node passes are dispatched indirectly over the list.

fn blocks_per_axis() -> vec3<u32> {
    return (consts.nodes + BLOCK - 1u) / BLOCK;
}

fn block_index(b: vec3<u32>) -> u32 {
    let nb = blocks_per_axis();
    return b.x + nb.x * (b.y + nb.y * b.z);
}

// The blocks holding the 3×3×3 nodes from `base`: lo..=hi per axis (at most 2 per axis).
fn stencil_block_lo(base: vec3<u32>) -> vec3<u32> {
    return base / BLOCK;
}

fn stencil_block_hi(base: vec3<u32>) -> vec3<u32> {
    return (base + 2u) / BLOCK;
}

// Node `lid` (0..64) of block `block`, and whether it lies on the grid (blocks at the far
// faces stick out when the node count is not a multiple of 4).
struct BlockNode {
    ok: bool,
    node: vec3<u32>,
    index: u32,
}

fn block_node(block: u32, lid: u32) -> BlockNode {
    let nb = blocks_per_axis();
    let b = vec3<u32>(block % nb.x, (block / nb.x) % nb.y, block / (nb.x * nb.y));
    let node = b * BLOCK + vec3<u32>(lid % BLOCK, (lid / BLOCK) % BLOCK, lid / (BLOCK * BLOCK));
    var out: BlockNode;
    out.ok = all(node < consts.nodes);
    out.node = node;
    out.index = node_index(node);
    return out;
}

// Sparse grid. The grid's nodes live in a pool of `consts.pool_blocks` blocks of 4³ nodes
// (one vec4 each); `block_slot` maps every block of the domain to its pool slot for the
// current step (NO_SLOT: not active). compact_blocks.wgsl assigns the slots each step, so
// grid memory follows the active region, not the domain. Node i's storage is always found
// through node_index. Declared here at a binding number no pass uses for anything else;
// passes that address nodes bind it (GpuSim).
const NO_SLOT: u32 = 0xffffffffu;

@group(0) @binding(15) var<storage, read_write> block_slot: array<u32>;

// Index into the grid pool of node i (on the grid, in an active block); NO_SLOT when its
// block has no slot this step (a pool overflow, reported by the watchdog).
fn node_index(i: vec3<u32>) -> u32 {
    let slot = block_slot[block_index(i / BLOCK)];
    if slot == NO_SLOT {
        return NO_SLOT;
    }
    let l = i % BLOCK;
    return slot * BLOCK_NODES + l.x + BLOCK * (l.y + BLOCK * l.z);
}

// The grid's velocities after the grid update go to a 2D rgba32float texture (xyz
// velocity, w mass), node node_index n at texel grid_texel(n), and G2P reads its 27 nodes
// from there. Why a texture: a CPU driver (lavapipe) fetches texels for all SIMD lanes
// in one unrolled gather, but loads a storage-buffer element at a per-invocation index one
// lane at a time, in a loop through memory; on a GPU a texel fetch costs no more than a
// buffer load. A row holds a power of two of nodes, 64 whole blocks.

fn grid_texel(n: u32) -> vec2<u32> {
    return vec2<u32>(n % GRID_TEXELS_PER_ROW, n / GRID_TEXELS_PER_ROW);
}

// The pool slots of the blocks holding the 3×3×3 nodes of a stencil from `base` (at most
// 2 per axis), looked up once per particle: the transfers visit 27 nodes, and a lookup per
// node (node_index) is a load from the block table each, which cost as much as the grid
// reads themselves on a CPU driver.
struct StencilBlocks {
    base: vec3<u32>,
    // slot of block stencil_block_lo(base) + (a, b, c), a, b, c ∈ {0, 1} (the second where
    // the stencil crosses into the next block on that axis): near[a + 2b] for c = 0,
    // far[a + 2b] for c = 1
    near: vec4<u32>,
    far: vec4<u32>,
}

fn block_slot_at(b: vec3<u32>) -> u32 {
    return block_slot[block_index(b)];
}

// The slots of the stencil's blocks in block layer z (order a + 2b, as StencilBlocks);
// the blocks the stencil does not cross into are left NO_SLOT unread: stencil_node never
// picks them, and a CPU driver pays for each invocation's load (3.4 of 8 are read on
// average).
fn stencil_block_row(lo: vec3<u32>, hi: vec3<u32>, z: u32, cross: vec3<bool>) -> vec4<u32> {
    var row = vec4<u32>(block_slot_at(vec3<u32>(lo.x, lo.y, z)), NO_SLOT, NO_SLOT, NO_SLOT);
    if cross.x {
        row.y = block_slot_at(vec3<u32>(hi.x, lo.y, z));
    }
    if cross.y {
        row.z = block_slot_at(vec3<u32>(lo.x, hi.y, z));
        if cross.x {
            row.w = block_slot_at(vec3<u32>(hi.x, hi.y, z));
        }
    }
    return row;
}

fn stencil_blocks(base: vec3<u32>) -> StencilBlocks {
    let lo = stencil_block_lo(base);
    let hi = stencil_block_hi(base);
    let cross = hi != lo;
    var s: StencilBlocks;
    s.base = base;
    s.near = stencil_block_row(lo, hi, lo.z, cross);
    s.far = vec4<u32>(NO_SLOT);
    if cross.z {
        s.far = stencil_block_row(lo, hi, hi.z, cross);
    }
    return s;
}

// node_index of stencil node base + off, off ∈ {0, 1, 2}³, from the stencil's blocks.
fn stencil_node(s: StencilBlocks, off: vec3<u32>) -> u32 {
    let i = s.base + off;
    let far = i / BLOCK != s.base / BLOCK;
    let row = select(s.near, s.far, far.z);
    let slot = select(select(row.x, row.y, far.x), select(row.z, row.w, far.x), far.y);
    if slot == NO_SLOT {
        return NO_SLOT;
    }
    let l = i % BLOCK;
    return slot * BLOCK_NODES + l.x + BLOCK * (l.y + BLOCK * l.z);
}

// The number of listed active blocks: those that got a pool slot.
fn listed_blocks(count: u32) -> u32 {
    return min(count, consts.pool_blocks);
}
