// The walk of the gathers by subgroups (p2g_broadcast.wgsl, damage_field_broadcast.wgsl;
// docs/method.md §2.2), for CPU drivers whose subgroups are 8 consecutive invocations, one
// SIMD vector (lavapipe with 256-bit vectors).
//
// Why: such a driver runs a per-node gather (p2g.wgsl, damage_field.wgsl) one lane at a
// time, since each node walks its own 27 cells and reads its particles at its own index.
// Here the eight nodes of a 2×2×2 group walk the same particles together: those of the
// 4×4×4 base cells whose stencils reach any of the eight. Each lane reads one particle of
// a chunk of eight and the subgroup broadcasts it, so each particle is read once per group
// and every lane computes its node's share at once. A particle's stencil reaches 27 of the
// 64 (particle, node) pairs it is tried against; it adds nothing to the others.
//
// The sum of each node runs over its group's cells in order (z, then y, then x, as the
// cell keys), and within a cell in the sort's order: the same on every run. A pass lends
// its particles as a struct `Lent` whose `base` is the stencil's base cell, and calls
// `lent_by_lane_0` … `lent_by_lane_7` in turn, generated from its fields by its Rust type
// (`step::lent_by_lane`): a broadcast's lane must be a constant.
// Needs: sim/step/common.

// Base cell of a lane with no particle: no node's stencil offset reaches it.
const NO_BASE: i32 = -1000000;

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

// A lane's place in the walk: its node, and the table of its group's particles.
struct GroupWalk {
    // false past the listed blocks (the whole workgroup returns)
    ok: bool,
    node: vec3<i32>,
    table: RowTable,
}

// The walk of subgroup `group`, lane `lane`, of workgroup (wid, nwg)'s active block: the
// block's 64 nodes are 8 groups of 2×2×2, one per subgroup.
fn group_walk(wid: vec3<u32>, nwg: vec3<u32>, group: u32, lane: u32) -> GroupWalk {
    var w: GroupWalk;
    let slot = wid.x + wid.y * nwg.x;
    w.ok = slot < listed_blocks(block_args[BLOCK_ARG_BLOCKS]);
    if !w.ok {
        return w;
    }
    let nb = blocks_per_axis();
    let block = active_blocks[slot];
    let b = vec3<u32>(block % nb.x, (block / nb.x) % nb.y, block / (nb.x * nb.y));
    // The group's lowest node, and this lane's node within the 2×2×2 group.
    let corner = vec3<i32>(b * BLOCK + 2u * vec3<u32>(group & 1u, (group >> 1u) & 1u, group >> 2u));
    w.node = corner + vec3<i32>(vec3<u32>(lane & 1u, (lane >> 1u) & 1u, lane >> 2u));
    // The base cells that reach the group: corner − 2 ..= corner + 1; rows 2·lane and
    // 2·lane + 1 of their 4 × 4 rows (y fastest).
    let r0 = 2u * lane;
    let lo = row_run(corner.x - 2, corner.y - 2 + i32(r0 & 3u), corner.z - 2 + i32(r0 >> 2u));
    let r1 = r0 + 1u;
    let hi = row_run(corner.x - 2, corner.y - 2 + i32(r1 & 3u), corner.z - 2 + i32(r1 >> 2u));
    w.table = row_table(lo, hi);
    return w;
}

// The sorted position of the particle this lane lends at list position `mine` of its
// group's walk (the group's particle 0 when past the end: `live` then says so).
fn walk_position(t: RowTable, mine: u32) -> u32 {
    return select(0u, sorted_position(t, mine), mine < t.total);
}

// The pool slot of a lane's node: NO_SLOT off the grid or outside the active blocks.
// Such lanes still walk: a broadcast needs every lane of the subgroup.
fn lane_slot(node: vec3<i32>) -> u32 {
    if !all(vec3<u32>(node) < consts.nodes) {
        return NO_SLOT;
    }
    return node_index(vec3<u32>(node));
}

// The stencil offset of `node` from a lent particle's base cell, when its stencil
// reaches the node (each component in 0..=2).
fn lent_offset(node: vec3<i32>, base: vec3<i32>) -> vec4<u32> {
    let off = node - base;
    let reaches = all(off >= vec3<i32>(0)) && all(off <= vec3<i32>(2));
    return vec4<u32>(vec3<u32>(off), select(0u, 1u, reaches));
}
