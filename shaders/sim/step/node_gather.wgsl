// What the node passes that gather from the sorted particles share (p2g.wgsl,
// damage_field.wgsl, ridge.wgsl; `step::gather_source`): the base cells' runs of particles,
// the active blocks, and the walk over the 27 base cells whose stencils reach a node. The
// walk has a fixed order (x fastest, as bspline_stencil_offset), so a node's sums are the
// same on every run.
// Needs: sim/step/common.

@group(0) @binding(1) var<storage, read> ranges: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read> cell_values: array<u32>;
// The blocks some particle's stencil reaches (compact_blocks.wgsl); nodes elsewhere are left
// as they are: no particle reads them.
@group(0) @binding(7) var<storage, read> active_blocks: array<u32>;
// [3]: the number of active blocks
@group(0) @binding(8) var<storage, read> block_args: array<u32, BLOCK_ARGS>;

// Node `lid` of workgroup (wid, nwg)'s active block: not ok past the listed blocks or off
// the grid.
fn gathering_node(wid: vec3<u32>, nwg: vec3<u32>, lid: u32) -> BlockNode {
    let slot = wid.x + wid.y * nwg.x;
    if slot >= listed_blocks(block_args[BLOCK_ARG_BLOCKS]) {
        var none: BlockNode;
        none.ok = false;
        return none;
    }
    return block_node(active_blocks[slot], lid);
}

// The run (into cell_values) of the particles in base cell node − off, off ∈ {0,1,2}³:
// those whose stencil reaches the node at offset off. Empty where that cell is off the grid.
fn reaching_run(node: vec3<u32>, off: vec3<u32>) -> vec2<u32> {
    let b = vec3<i32>(node) - vec3<i32>(off);
    let bc = vec3<i32>(consts.cells) - 1;
    if any(b < vec3<i32>(0)) || any(b >= bc) {
        return vec2<u32>(0u);
    }
    return ranges[u32(b.x + bc.x * (b.y + bc.y * b.z))];
}
