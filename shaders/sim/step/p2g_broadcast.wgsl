// P2G, part 2, and the grid update, gathered from the sorted particles by subgroups of
// eight nodes (per active block; docs/method.md §2.2): the sums of p2g.wgsl, one field or
// two (SEPARATION, a constant P2gBroadcast prepends), for CPU drivers whose subgroups are
// 8 consecutive invocations, one SIMD vector (lavapipe with 256-bit vectors).
//
// Why: such a driver runs p2g.wgsl's walk one lane at a time, since each node walks its
// own 27 cells and reads its particles at its own index. Here the eight nodes of a 2×2×2
// group walk the same particles together: those of the 4×4×4 base cells whose stencils
// reach any of the eight. Each lane reads one particle of a chunk of eight and the subgroup
// broadcasts it, so each particle is read once per group and every lane computes its
// node's weight at once. A particle's stencil reaches 27 of the 64 (particle, node) pairs
// it is tried against; it adds nothing to the others.
//
// The sum of each node runs over its group's cells in order (z, then y, then x, as the
// cell keys), and within a cell in the sort's order: the same on every run.

@group(0) @binding(3) var<storage, read> x_mass: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> v_volume: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> affine: array<mat3x3<f32>>;
// xyz: velocity after the grid update, w: mass (common.wgsl, grid_texel)
@group(0) @binding(6) var grid_velocity: texture_storage_2d<rgba32float, write>;
// xyz: what the step's forces changed, v_i − Σ w m_p v_p / m_i (FLIP/PIC blends only)
@group(0) @binding(16) var grid_velocity_change: texture_storage_2d<rgba32float, write>;
// Two-field separation only (step/separation.wgsl): ∇D_p per particle (xyz), the ridge
// gradient per pool node, and the far field per pool node (p2g_sums.wgsl, finish_node)
@group(0) @binding(9) var<storage, read> damage_gradient: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read> ridge: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read_write> far_field: array<vec4<f32>>;

// A particle as one lane hands it to the others: its stencil's base cell and fractional
// position (bspline_stencil), mass, m v, affine term (columns), and with two fields its
// damage gradient ∇D_p (zero, and not handed over, with one).
struct Lent {
    base: vec3<i32>,
    fx_mass: vec4<f32>,
    mv: vec3<f32>,
    a0: vec3<f32>,
    a1: vec3<f32>,
    a2: vec3<f32>,
    gradient: vec3<f32>,
}

// Base cell of a lane with no particle: no node's stencil offset reaches it.
const NO_BASE: i32 = -1000000;

// Add particle `q`'s share to node `node`'s sums (p2g_sums.wgsl), when its stencil reaches
// the node: to the near field, or with two fields to the far one when q lies across the
// ridge of the node's gradient `ridge_i`. The terms are p2g.wgsl's, from the particle's fx.
fn add_lent(near: ptr<function, FieldSums>, far: ptr<function, FieldSums>, node: vec3<i32>,
            ridge_i: vec3<f32>, q: Lent, carry: bool) {
    let off = node - q.base;
    if any(off < vec3<i32>(0)) || any(off > vec3<i32>(2)) {
        return;
    }
    let o = vec3<u32>(off);
    let fx = q.fx_mass.xyz;
    let m = q.fx_mass.w;
    let w = bspline_weight_at(fx, o);
    let d = (vec3<f32>(o) - fx) * consts.dx;
    let a = mat3x3<f32>(q.a0, q.a1, q.a2);
    let mom = w * (q.mv + a * d);
    if SEPARATION {
        // ∇w with respect to the node is minus that with respect to x_p
        let gm = -m * bspline_weight_grad_at(fx, o, consts.inv_dx);
        if in_far_field(q.gradient, ridge_i) {
            (*far).m += w * m;
            (*far).p += mom;
            (*far).q += w * q.mv;
            (*far).g += gm;
            return;
        }
        (*near).g += gm;
    }
    (*near).m += w * m;
    (*near).p += mom;
    if carry {
        (*near).q += w * q.mv;
    }
}

// The particle at `pos` of the sorted particles (`live`), or none.
fn lend(pos: u32, live: bool) -> Lent {
    var q: Lent;
    q.base = vec3<i32>(NO_BASE);
    if !live {
        return q;
    }
    let p = cell_values[pos];
    let xm = x_mass[p];
    let s = bspline_stencil(xm.xyz - consts.lo, consts.inv_dx);
    let a = affine[p];
    q.base = s.base;
    q.fx_mass = vec4<f32>(s.fx, xm.w);
    q.mv = xm.w * v_volume[p].xyz;
    q.a0 = a[0];
    q.a1 = a[1];
    q.a2 = a[2];
    q.gradient = vec3<f32>(0.0);
    if SEPARATION {
        q.gradient = damage_gradient[p].xyz;
    }
    return q;
}

// The run of sorted particles in the base cells (x0..x0+3, y, z), clipped to the grid, as
// (first, count): a row of cells is contiguous in the sorted order (keys x fastest); an
// empty cell's range is the cleared (0, 0).
fn row_run(x0: i32, y: i32, z: i32) -> vec2<u32> {
    let bc = vec3<i32>(consts.cells) - 1;
    if y < 0 || y >= bc.y || z < 0 || z >= bc.z {
        return vec2<u32>(0u);
    }
    var end = 0u;
    var count = 0u;
    for (var x = max(x0, 0); x <= min(x0 + 3, bc.x - 1); x++) {
        let r = ranges[u32(x + bc.x * (y + bc.y * z))];
        end = max(end, r.y);
        count += r.y - r.x;
    }
    return vec2<u32>(end - count, count);
}

// Per row r (0..16) of a group's cells: where the group's particle list reaches it
// (`before`: the particles of rows 0..r) and the jump from list position to sorted
// position there, as the change from row r − 1's (`step_up`), so that position k lies at
// k + Σ step_up over the rows with before ≤ k (every row up to k's, in order).
struct RowTable {
    before: array<vec4<u32>, 4>,
    step_up: array<vec4<u32>, 4>,
    total: u32,
}

// Rows 4k..4k+3 of the table, from their first sorted positions and counts; `shift_before`
// carries row 4k − 1's jump in and row 4k + 3's out.
fn rows_of(first: vec4<u32>, count: vec4<u32>, t: ptr<function, RowTable>, k: u32,
           shift_before: ptr<function, u32>) {
    var before = vec4<u32>((*t).total);
    before.y += count.x;
    before.z = before.y + count.y;
    before.w = before.z + count.z;
    (*t).total = before.w + count.w;
    let shift = first - before;
    let prev = vec4<u32>(*shift_before, shift.x, shift.y, shift.z);
    (*t).before[k] = before;
    (*t).step_up[k] = shift - prev;
    *shift_before = shift.w;
}

// The table of the group's 16 rows, from each lane's two: `lo` (row 2·lane) and `hi`
// (row 2·lane + 1), as (first, count). Four calls written out: a broadcast's lane must be
// a constant.
fn row_table(lo: vec2<u32>, hi: vec2<u32>) -> RowTable {
    let first = vec2<u32>(lo.x, hi.x);
    let count = vec2<u32>(lo.y, hi.y);
    var t: RowTable;
    t.total = 0u;
    var shift = 0u;
    rows_of(vec4<u32>(subgroupBroadcast(first, 0u), subgroupBroadcast(first, 1u)),
            vec4<u32>(subgroupBroadcast(count, 0u), subgroupBroadcast(count, 1u)), &t, 0u,
            &shift);
    rows_of(vec4<u32>(subgroupBroadcast(first, 2u), subgroupBroadcast(first, 3u)),
            vec4<u32>(subgroupBroadcast(count, 2u), subgroupBroadcast(count, 3u)), &t, 1u,
            &shift);
    rows_of(vec4<u32>(subgroupBroadcast(first, 4u), subgroupBroadcast(first, 5u)),
            vec4<u32>(subgroupBroadcast(count, 4u), subgroupBroadcast(count, 5u)), &t, 2u,
            &shift);
    rows_of(vec4<u32>(subgroupBroadcast(first, 6u), subgroupBroadcast(first, 7u)),
            vec4<u32>(subgroupBroadcast(count, 6u), subgroupBroadcast(count, 7u)), &t, 3u,
            &shift);
    return t;
}

// Sorted position of the group's list position k (< t.total).
fn sorted_position(t: RowTable, k: u32) -> u32 {
    let kk = vec4<u32>(k);
    let pos = select(vec4<u32>(0u), t.step_up[0], t.before[0] <= kk)
        + select(vec4<u32>(0u), t.step_up[1], t.before[1] <= kk)
        + select(vec4<u32>(0u), t.step_up[2], t.before[2] <= kk)
        + select(vec4<u32>(0u), t.step_up[3], t.before[3] <= kk);
    return k + pos.x + pos.y + pos.z + pos.w;
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(subgroup_id) group: u32, @builtin(subgroup_invocation_id) lane: u32) {
    read_consts();
    let slot = wid.x + wid.y * nwg.x;
    if slot >= listed_blocks(block_args[3]) {
        return;
    }
    let nb = blocks_per_axis();
    let block = active_blocks[slot];
    let b = vec3<u32>(block % nb.x, (block / nb.x) % nb.y, block / (nb.x * nb.y));
    // The group's lowest node, and this lane's node within the 2×2×2 group.
    let corner = vec3<i32>(b * BLOCK + 2u * vec3<u32>(group & 1u, (group >> 1u) & 1u, group >> 2u));
    let node = corner + vec3<i32>(vec3<u32>(lane & 1u, (lane >> 1u) & 1u, lane >> 2u));
    // The base cells that reach the group: corner − 2 ..= corner + 1; rows 2·lane and
    // 2·lane + 1 of their 4 × 4 rows (y fastest).
    let r0 = 2u * lane;
    let lo = row_run(corner.x - 2, corner.y - 2 + i32(r0 & 3u), corner.z - 2 + i32(r0 >> 2u));
    let r1 = r0 + 1u;
    let hi = row_run(corner.x - 2, corner.y - 2 + i32(r1 & 3u), corner.z - 2 + i32(r1 >> 2u));
    let table = row_table(lo, hi);
    let carry = consts.flip > 0.0;
    // The lane's node in the pool, and with two fields its ridge gradient. Lanes off the
    // grid or outside the pool still walk: a broadcast needs every lane of the subgroup.
    let on_grid = all(vec3<u32>(node) < consts.nodes);
    var idx = NO_SLOT;
    if on_grid {
        idx = node_index(vec3<u32>(node));
    }
    var ridge_i = vec3<f32>(0.0);
    if SEPARATION && idx != NO_SLOT {
        ridge_i = ridge[idx].xyz;
    }
    var near = no_sums();
    var far = no_sums();
    for (var k = 0u; k < table.total; k += 8u) {
        let mine = k + lane;
        let live = mine < table.total;
        let own = lend(select(0u, sorted_position(table, mine), live), live);
        // add_lent of the particle of each lane 0..8 in turn, generated by P2gBroadcast
        // (a broadcast's lane must be a constant)
        LENT_BY_EACH_LANE
    }
    if idx == NO_SLOT {
        return;
    }
    finish_node(vec3<u32>(node), idx, near, far, carry);
}
