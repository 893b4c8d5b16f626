// Last pass of the renderer: one workgroup per 16×16 tile. Each invocation composites a
// column of 4·QUADS pixels (one `Quad` is four pixels, one vector lane each), so that every
// Gaussian read from workgroup memory is blended into several pixels at once. The tile's
// Gaussians (front to back) are loaded into workgroup memory BATCH at a time; each 8×8
// block of the tile then keeps a bit mask of the batch's Gaussians that can reach one of
// its pixels, and its invocations walk only those (`block_masks`). They are
// composited with α = min(0.99, ω · exp(−½ Δᵀ Σ'⁻¹ Δ)), skipping α < 1/255 and stopping
// a pixel once its transmittance would fall below 1e-4 (docs/method.md §7). Pixel (i, j)
// is sampled at (i + 0.5, j + 0.5). Mirrors `render::cpu::render`.
// QUADS (and so the workgroup size, THREADS) is set per adapter by `passes::Rasterize`, and
// so is `read_splat`, how the invocations of a block read a Gaussian from the batch.
// With PASSES (also set there) the same compositing also yields the alpha and depth passes
// (docs/method.md §7.7): the image's second plane holds the straight (not premultiplied)
// colour and α = 1 − T, its third the depth Σ w_i z_i / α (+∞ where nothing was drawn).
// With NORMALS the planes from NORMAL_PLANE hold the normal pass, Σ w_i n_i normalised
// (x, y, z a plane each; 0 where nothing was drawn); with IDS plane ID_PLANE holds the id
// of the Gaussian with the largest weight w_i (0 where nothing was drawn).

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> ranges: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read> tile_values: array<u32>;
// RGBA8, one u32 per pixel, row-major; with PASSES more planes of as many words (read
// back as render::gpu::PassImages): straight RGBA8, the depth's f32 bits, then with
// NORMALS the normal's three f32 planes and with IDS the ids.
@group(0) @binding(4) var<storage, read_write> image: array<u32>;
// projected_0 … from binding 8, and projected_at(g), follow (`gpu::pages`).

const COLUMN: u32 = 4u * QUADS;
const THREADS: u32 = TILE * TILE / COLUMN;
const BATCH: u32 = 256u;
// Blocks of BLOCK×BLOCK pixels with a Gaussian mask each; a column lies within one block.
const BLOCK: u32 = 8u;
const BLOCKS_X: u32 = TILE / BLOCK;
const WORDS: u32 = BATCH / 32u;
const_assert BLOCK % COLUMN == 0u;

// Batch Gaussian k is the three vectors from 3k (`Splat2D`). With IDS the first one's w
// holds the id instead of the reach, which `reach2` then recomputes.
var<workgroup> batch: array<vec4<f32>, 3 * BATCH>;
// Bit i of word w of block b: batch Gaussian 32w + i reaches a pixel of block b.
var<workgroup> block_masks: array<u32, BLOCKS_X * BLOCKS_X * WORDS>;
// pixels of the tile that are done (saturated or outside the image)
var<workgroup> finished: atomic<u32>;
var<workgroup> stop_flag: u32;
var<workgroup> tile_range: vec2<u32>;

// A projected Gaussian as the batch holds it.
struct Splat2D {
    // xy: mean, z: opacity, w: the squared Mahalanobis radius beyond which α < MIN_ALPHA
    xy_opacity: vec4<f32>,
    // (a, b, c) of the conic [[a, b], [b, c]]
    conic: vec4<f32>,
    color: vec4<f32>,
}

// Four pixels of a column, front-to-back state of each.
struct Quad {
    centre_y: vec4<f32>,
    t: vec4<f32>,
    r: vec4<f32>,
    g: vec4<f32>,
    b: vec4<f32>,
    // Σ w_i z_i, the depth pass's sum (PASSES only)
    d: vec4<f32>,
    // Σ w_i n_i, the normal pass's sums (NORMALS only)
    nx: vec4<f32>,
    ny: vec4<f32>,
    nz: vec4<f32>,
    // the largest w_i so far and its Gaussian's id (IDS only)
    best_w: vec4<f32>,
    best_id: vec4<f32>,
    live: vec4<bool>,
}

fn count_true(v: vec4<bool>) -> u32 {
    return dot(vec4<u32>(v), vec4<u32>(1u));
}

// One Gaussian blended behind the quad's pixels. Along the invocation's column the
// exponent −½ Δᵀ Σ'⁻¹ Δ is a quadratic in Δy, p.x + Δy (p.y + p.z Δy), whose coefficients
// (`column_power`) are computed once per Gaussian for all of the column's pixels.
fn blend(quad: Quad, xo: vec4<f32>, p: vec3<f32>, color: vec3<f32>, depth: f32, normal: vec3<f32>) -> Quad {
    var q = quad;
    let dy = vec4<f32>(xo.y) - q.centre_y;
    let power = p.x + dy * (p.y + p.z * dy);
    let alpha = min(vec4<f32>(0.99), xo.z * exp(power));
    let next_t = q.t * (1.0 - alpha);
    let visible = q.live & (power <= vec4<f32>(0.0)) & (alpha >= vec4<f32>(MIN_ALPHA));
    let saturated = visible & (next_t < vec4<f32>(1e-4));
    let take = visible & !saturated;
    let w = select(vec4<f32>(0.0), alpha * q.t, take);
    q.r += color.r * w;
    q.g += color.g * w;
    q.b += color.b * w;
    if PASSES {
        q.d += depth * w;
    }
    if NORMALS {
        q.nx += normal.x * w;
        q.ny += normal.y * w;
        q.nz += normal.z * w;
    }
    if IDS {
        // the first (nearest) of equal weights keeps the pixel
        let larger = w > q.best_w;
        q.best_w = select(q.best_w, w, larger);
        q.best_id = select(q.best_id, vec4<f32>(xo.w), larger);
    }
    q.t = select(q.t, next_t, take);
    q.live &= !saturated;
    return q;
}

// −½ Δᵀ C Δ = −½ a Δx² − b Δx Δy − ½ c Δy² for the conic (a, b, c) at the column's Δx.
fn column_power(xo: vec4<f32>, con: vec4<f32>, centre_x: f32) -> vec3<f32> {
    let dx = xo.x - centre_x;
    return vec3<f32>(-0.5 * con.x * dx * dx, -con.y * dx, -0.5 * con.z);
}

// dᵀ C d up to which α = ω exp(−½ dᵀ C d) ≥ MIN_ALPHA, widened a little so that rounding
// never drops a pixel that `blend` would composite. Unlike the tile keys' extent this is not
// clamped to 3σ: every pixel of a listed tile that `blend` takes must stay in.
fn alpha_reach2(opacity: f32) -> f32 {
    return 2.0 * log(opacity / MIN_ALPHA) * 1.001 + 1e-3;
}

// The batch's squared reach of a Gaussian (its first vector `xo`): kept in xo.w, or with
// IDS, where xo.w holds the id, computed again.
fn reach2(xo: vec4<f32>) -> f32 {
    if IDS {
        return alpha_reach2(xo.z);
    }
    return xo.w;
}

// Which of the batch's `count` Gaussians reach a pixel centre of each block, a word of
// the mask per invocation (`block_masks`).
fn mark_blocks(lid: u32, count: u32, tile_origin: vec2<u32>) {
    for (var j = lid; j < BLOCKS_X * BLOCKS_X * WORDS; j += THREADS) {
        let block = j / WORDS;
        let w = j % WORDS;
        let corner = tile_origin + BLOCK * vec2<u32>(block % BLOCKS_X, block / BLOCKS_X);
        let lo = vec2<f32>(corner) + 0.5;
        let first = w * 32u;
        let n = min(32u, count - min(count, first));
        var bits = 0u;
        for (var i = 0u; i < n; i++) {
            let xo = batch[3u * (first + i)];
            let conic = batch[3u * (first + i) + 1u].xyz;
            let reach = ellipse_touches_square(xo.xy, conic, reach2(xo), lo, f32(BLOCK - 1u));
            bits |= u32(reach) << i;
        }
        block_masks[j] = bits;
    }
}

// +∞: the depth where nothing was drawn.
const NO_DEPTH: u32 = 0x7f800000u;

// 8-bit rounding, as the frame's bytes (render::cpu::to_u8).
fn to_levels(v: vec3<f32>) -> vec3<f32> {
    return floor(clamp(v, vec3<f32>(0.0), vec3<f32>(1.0)) * 255.0 + 0.5) / 255.0;
}

// The alpha and depth planes of `pixel` from its frame colour `rgb`, α = 1 − T and the
// depth sum Σ w_i z_i. The straight colour is the one that, over the background at the
// 8-bit α, gives back the frame's 8-bit colour (the premultiplied sum / α up to rounding;
// the frame's own colour where α = 1), and the depth is the depth sum / α.
fn write_passes(pixel: u32, rgb: vec3<f32>, alpha: f32, depth_sum: f32) {
    let plane = frame.width * frame.height;
    let a8 = floor(clamp(alpha, 0.0, 1.0) * 255.0 + 0.5) / 255.0;
    var straight = vec3<f32>(0.0);
    if a8 > 0.0 {
        straight = (to_levels(rgb) - (1.0 - a8) * frame.background.rgb) / a8;
    }
    var depth = NO_DEPTH;
    if alpha > 0.0 {
        depth = bitcast<u32>(depth_sum / alpha);
    }
    image[plane + pixel] = pack4x8unorm(vec4<f32>(clamp(straight, vec3<f32>(0.0), vec3<f32>(1.0)), a8));
    image[2u * plane + pixel] = depth;
}

// The normal pass of `pixel` from its sums Σ w_i n_i: their direction, 0 where there is none.
fn write_normal(pixel: u32, sum: vec3<f32>) {
    let plane = frame.width * frame.height;
    let len2 = dot(sum, sum);
    var n = vec3<f32>(0.0);
    if len2 > 0.0 {
        n = sum * inverseSqrt(len2);
    }
    image[NORMAL_PLANE * plane + pixel] = bitcast<u32>(n.x);
    image[(NORMAL_PLANE + 1u) * plane + pixel] = bitcast<u32>(n.y);
    image[(NORMAL_PLANE + 2u) * plane + pixel] = bitcast<u32>(n.z);
}

// Pixels of the invocation still compositing.
fn live_pixels(quads: array<Quad, QUADS>) -> u32 {
    var n = 0u;
    for (var q = 0u; q < QUADS; q++) {
        n += count_true(quads[q].live);
    }
    return n;
}

@compute @workgroup_size(THREADS)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let tile = wid.y * frame.tiles_x + wid.x;
    let tile_origin = wid.xy * TILE;
    let x = tile_origin.x + lid % TILE;
    let y0 = tile_origin.y + (lid / TILE) * COLUMN;
    let block = (lid % TILE) / BLOCK + BLOCKS_X * ((lid / TILE) * COLUMN / BLOCK);
    if lid == 0u {
        atomicStore(&finished, 0u);
        tile_range = ranges[tile];
    }
    // Loaded through workgroup memory so every invocation provably sees the same value.
    let range = workgroupUniformLoad(&tile_range);
    let centre_x = f32(x) + 0.5;
    var quads: array<Quad, QUADS>;
    var outside = 0u;
    for (var q = 0u; q < QUADS; q++) {
        let y = y0 + 4u * q + vec4<u32>(0u, 1u, 2u, 3u);
        let live = (y < vec4<u32>(frame.height)) & vec4<bool>(x < frame.width);
        let zero = vec4<f32>(0.0);
        quads[q] = Quad(vec4<f32>(y) + 0.5, vec4<f32>(1.0), zero, zero, zero, zero, zero, zero, zero, zero, zero, live);
        outside += 4u - count_true(live);
    }
    if outside > 0u {
        atomicAdd(&finished, outside);
    }
    var start = range.x;
    loop {
        workgroupBarrier();
        if lid == 0u {
            stop_flag = select(0u, 1u, atomicLoad(&finished) == TILE * TILE);
        }
        if workgroupUniformLoad(&stop_flag) == 1u || start >= range.y {
            break;
        }
        let count = min(BATCH, range.y - start);
        for (var i = lid; i < count; i += THREADS) {
            let p = projected_at(tile_values[start + i]);
            var fourth = alpha_reach2(p.xy_opacity.z);
            if IDS {
                fourth = p.xy_opacity.w;
            }
            batch[3u * i] = vec4<f32>(p.xy_opacity.xyz, fourth);
            batch[3u * i + 1u] = p.conic;
            batch[3u * i + 2u] = p.color;
        }
        workgroupBarrier();
        mark_blocks(lid, count, tile_origin);
        workgroupBarrier();
        // Pixels that saturate are counted once per batch, not per Gaussian: the early
        // stop is only checked between batches.
        let live_before = live_pixels(quads);
        var live = live_before > 0u;
        for (var w = 0u; w < WORDS && any_live(live); w++) {
            // Set bits in increasing order keep the batch front to back.
            var bits = block_masks[block * WORDS + w];
            loop {
                if bits == 0u || !any_live(live) {
                    break;
                }
                let k = w * 32u + firstTrailingBit(bits);
                bits &= bits - 1u;
                let splat = read_splat(k, lid);
                let xo = splat.xy_opacity;
                let p = column_power(xo, splat.conic, centre_x);
                let color = splat.color.rgb;
                var normal = vec3<f32>(0.0);
                if NORMALS {
                    normal = normal_from_code(splat.color.w);
                }
                live = false;
                for (var q = 0u; q < QUADS; q++) {
                    quads[q] = blend(quads[q], xo, p, color, splat.conic.w, normal);
                    live = live || any(quads[q].live);
                }
            }
        }
        let saturated = live_before - live_pixels(quads);
        if saturated > 0u {
            atomicAdd(&finished, saturated);
        }
        start += count;
    }
    for (var q = 0u; q < QUADS; q++) {
        let quad = quads[q];
        for (var j = 0u; j < 4u; j++) {
            let y = y0 + 4u * q + j;
            if y < frame.height && x < frame.width {
                let rgb = vec3<f32>(quad.r[j], quad.g[j], quad.b[j]) + quad.t[j] * frame.background.rgb;
                let pixel = y * frame.width + x;
                image[pixel] = pack4x8unorm(vec4<f32>(clamp(rgb, vec3<f32>(0.0), vec3<f32>(1.0)), 1.0));
                if PASSES {
                    write_passes(pixel, rgb, 1.0 - quad.t[j], quad.d[j]);
                }
                if NORMALS {
                    write_normal(pixel, vec3<f32>(quad.nx[j], quad.ny[j], quad.nz[j]));
                }
                if IDS {
                    image[ID_PLANE * frame.width * frame.height + pixel] = u32(quad.best_id[j]);
                }
            }
        }
    }
}
