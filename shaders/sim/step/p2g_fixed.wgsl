// P2G with integer atomics on fixed-point sums (per particle; docs/method.md §2.2 and
// §2.4): the contributions of p2g_scatter.wgsl, but each of a node's sums is a 64-bit
// two's-complement integer counting units of 2^−e (e: step.mass_exponent for the mass,
// step.momentum_exponent for the momenta), held in a low and a high 32-bit word. Integer
// addition is associative, so every order of the additions leaves the same bits: the sums,
// and the step, are deterministic; and integer atomics run on every backend. The exponents
// are chosen on the CPU (GpuStep::set_fixed_point) so that one particle's contribution
// stays under 2^32 units (the high word then changes only by the low word's carry, so most
// additions take one atomic) and no sum reaches 2^62, while every particle's reach —
// |m v| + ‖affine‖ r over its stencil — stays under m times step.speed_bound. A particle
// past it adds nothing and is counted in flags[WATCH_FIXED_POINT_RANGE]: the watchdog stops the run; a sum is
// never silently wrong.

@group(0) @binding(1) var<storage, read> x_mass: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> v_volume: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> affine: array<mat3x3<f32>>;
// The grid pool, 8 words per node: momentum x, y, z and mass, each as (low, high) — and
// for a FLIP/PIC blend 8 more: Σ w m_p v_p's x, y, z and an unused pair; cleared before
// every step; grid_from_sums.wgsl decodes them.
@group(0) @binding(4) var<storage, read_write> grid_sum: array<atomic<u32>>;
// The watchdog's counters (g2p.wgsl): [6] particles past the fixed-point range.
@group(0) @binding(8) var<storage, read_write> flags: array<atomic<u32>, WATCH_SLOTS>;

// The farthest a node of the quadratic stencil lies from its particle: 1.5·√3 Δx.
const STENCIL_REACH: f32 = 2.6;

// x · scale (scale a power of two: exact) rounded to the nearest unit (no drift towards
// zero), as a two's-complement (low, high) pair. |x · scale| < 2^62, so the high word is
// exact, and the low word is what a 24-bit mantissa leaves below 2^32 (exact too).
fn fixed_words(x: f32, scale: f32) -> vec2<u32> {
    let a = floor(abs(x * scale) + 0.5);
    let high = floor(a * TWO_TO_MINUS_32);
    let low = a - high * TWO_TO_32;
    var w = vec2<u32>(u32(low), u32(high));
    if x < 0.0 {
        w = ~w;
        w.x += 1u;
        w.y += select(0u, 1u, w.x == 0u);
    }
    return w;
}

// Add a pair to the sum at words (i, i + 1): the low word first, then the high word with
// the low word's carry (the low addition wrapped exactly when its result is below either
// addend).
fn add_fixed(i: u32, w: vec2<u32>) {
    let before = atomicAdd(&grid_sum[i], w.x);
    let high = w.y + select(0u, 1u, before + w.x < before);
    if high != 0u {
        atomicAdd(&grid_sum[i + 1u], high);
    }
}

fn add_momentum(i: u32, m: vec3<f32>, scale: f32) {
    add_fixed(i, fixed_words(m.x, scale));
    add_fixed(i + 2u, fixed_words(m.y, scale));
    add_fixed(i + 4u, fixed_words(m.z, scale));
}

fn frobenius(a: mat3x3<f32>) -> f32 {
    return sqrt(dot(a[0], a[0]) + dot(a[1], a[1]) + dot(a[2], a[2]));
}

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    read_consts();
    let p = flat_id(wid, nwg, lid);
    if p >= page.count {
        return;
    }
    let xm = x_mass[p];
    let st = grid_stencil(xm.xyz);
    if !st.ok {
        return;
    }
    let mv = xm.w * v_volume[p].xyz;
    let a = affine[p];
    // Also false for a non-finite velocity or affine term.
    if !(length(mv) + frobenius(a) * STENCIL_REACH * consts.dx <= xm.w * step.speed_bound) {
        atomicAdd(&flags[WATCH_FIXED_POINT_RANGE], 1u);
        // compact_blocks.wgsl has already counted this step (g2p.wgsl, count_failure)
        atomicMax(&flags[WATCH_FIRST_STEP], ~(atomicLoad(&flags[WATCH_STEP]) - 1u));
        return;
    }
    let mass_scale = power_of_two(step.mass_exponent);
    let momentum_scale = power_of_two(step.momentum_exponent);
    let s = st.s;
    let blocks = stencil_blocks(vec3<u32>(s.base));
    let carry = consts.flip > 0.0;
    let stride = select(8u, 16u, carry);
    for (var k = 0u; k < 27u; k++) {
        let off = bspline_stencil_offset(k);
        let node = stencil_node(blocks, off);
        if node == NO_SLOT {
            continue;
        }
        let idx = stride * node;
        let w = bspline_weight(s, off);
        add_momentum(idx, w * (mv + a * bspline_offset(s, off, consts.dx)), momentum_scale);
        add_fixed(idx + 6u, fixed_words(w * xm.w, mass_scale));
        if carry {
            add_momentum(idx + 8u, w * mv, momentum_scale);
        }
    }
}
