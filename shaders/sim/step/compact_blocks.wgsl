// Active blocks (per block): list the flagged blocks, give each a slot of the grid pool
// (block_slot, common.wgsl; NO_SLOT for the others) and reset the flags for the next step.
// Blocks beyond the pool's capacity get no slot and are counted as overflow. The list's length goes into indirect dispatch arguments for the node passes, split
// as x = min(count, 65535), y = ⌈count / 65535⌉ (the portable per-dimension limit); node
// passes bounds-check their slot against the count.

@group(0) @binding(1) var<storage, read_write> block_flags: array<u32>;
@group(0) @binding(2) var<storage, read_write> active_blocks: array<u32>;
// [x, y, z] workgroups of the node passes, [3] the number of active blocks; zeroed before
// every step
@group(0) @binding(3) var<storage, read_write> block_args: array<atomic<u32>, BLOCK_ARGS>;

// The watchdog's counters (g2p.wgsl); [3] counts the steps since the last read: this pass
// runs once per step, so it keeps the clock; [4] the most active blocks in a step, [5]
// blocks left without a pool slot (overflow), both since the last read.
@group(0) @binding(4) var<storage, read_write> flags: array<atomic<u32>, WATCH_SLOTS>;

const MAX_GROUPS_X: u32 = 65535u;

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    read_consts();
    let b = flat_id(wid, nwg, lid);
    if b == 0u {
        atomicAdd(&flags[WATCH_STEP], 1u);
    }
    let nb = blocks_per_axis();
    if b >= nb.x * nb.y * nb.z {
        return;
    }
    if block_flags[b] == 0u {
        block_slot[b] = NO_SLOT;
        return;
    }
    block_flags[b] = 0u;
    let slot = atomicAdd(&block_args[BLOCK_ARG_BLOCKS], 1u);
    atomicMax(&flags[WATCH_ACTIVE_BLOCKS_MAX], slot + 1u);
    if slot >= consts.pool_blocks {
        block_slot[b] = NO_SLOT;
        atomicAdd(&flags[WATCH_POOL_OVERFLOW], 1u);
        return;
    }
    block_slot[b] = slot;
    active_blocks[slot] = b;
    atomicMax(&block_args[BLOCK_ARG_GROUPS_X], min(slot + 1u, MAX_GROUPS_X));
    atomicMax(&block_args[BLOCK_ARG_GROUPS_Y], slot / MAX_GROUPS_X + 1u);
    atomicMax(&block_args[BLOCK_ARG_GROUPS_Z], 1u);
}
