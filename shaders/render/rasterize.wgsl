// Last pass of the renderer: one workgroup per 16×16 tile. Each invocation composites a
// column of 4·QUADS pixels (one `Quad` is four pixels, one vector lane each), so that every
// Gaussian read from workgroup memory is blended into several pixels at once. The tile's
// Gaussians (front to back) are loaded into workgroup memory BATCH at a time and
// composited with α = min(0.99, ω · exp(−½ Δᵀ Σ'⁻¹ Δ)), skipping α < 1/255 and stopping
// a pixel once its transmittance would fall below 1e-4 (docs/method.md §7). Pixel (i, j)
// is sampled at (i + 0.5, j + 0.5). Mirrors `render::cpu::render`.
// QUADS (and so the workgroup size, THREADS) is set per adapter by `passes::Rasterize`.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> ranges: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read> tile_values: array<u32>;
// RGBA8, one u32 per pixel, row-major
@group(0) @binding(4) var<storage, read_write> image: array<u32>;
// projected_0 … from binding 8, and projected_at(g), follow (`gpu::pages`).

const COLUMN: u32 = 4u * QUADS;
const THREADS: u32 = TILE * TILE / COLUMN;
const BATCH: u32 = 256u;

var<workgroup> batch_xy_opacity: array<vec4<f32>, BATCH>;
var<workgroup> batch_conic: array<vec4<f32>, BATCH>;
var<workgroup> batch_color: array<vec4<f32>, BATCH>;
// pixels of the tile that are done (saturated or outside the image)
var<workgroup> finished: atomic<u32>;
var<workgroup> stop_flag: u32;
var<workgroup> tile_range: vec2<u32>;

// Four pixels of a column, front-to-back state of each.
struct Quad {
    centre_y: vec4<f32>,
    t: vec4<f32>,
    r: vec4<f32>,
    g: vec4<f32>,
    b: vec4<f32>,
    live: vec4<bool>,
}

fn count_true(v: vec4<bool>) -> u32 {
    return dot(vec4<u32>(v), vec4<u32>(1u));
}

// One Gaussian blended behind the quad's pixels. Along the invocation's column the
// exponent −½ Δᵀ Σ'⁻¹ Δ is a quadratic in Δy, p.x + Δy (p.y + p.z Δy), whose coefficients
// (`column_power`) are computed once per Gaussian for all of the column's pixels.
fn blend(quad: Quad, xo: vec4<f32>, p: vec3<f32>, color: vec3<f32>) -> Quad {
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
    q.t = select(q.t, next_t, take);
    q.live &= !saturated;
    return q;
}

// −½ Δᵀ C Δ = −½ a Δx² − b Δx Δy − ½ c Δy² for the conic (a, b, c) at the column's Δx.
fn column_power(xo: vec4<f32>, con: vec4<f32>, centre_x: f32) -> vec3<f32> {
    let dx = xo.x - centre_x;
    return vec3<f32>(-0.5 * con.x * dx * dx, -con.y * dx, -0.5 * con.z);
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
    let x = wid.x * TILE + lid % TILE;
    let y0 = wid.y * TILE + (lid / TILE) * COLUMN;
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
        quads[q] = Quad(vec4<f32>(y) + 0.5, vec4<f32>(1.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), live);
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
            batch_xy_opacity[i] = p.xy_opacity;
            batch_conic[i] = p.conic;
            batch_color[i] = p.color;
        }
        workgroupBarrier();
        // Pixels that saturate are counted once per batch, not per Gaussian: the early
        // stop is only checked between batches.
        let live_before = live_pixels(quads);
        var live = live_before > 0u;
        for (var k = 0u; k < count && live; k++) {
            let xo = batch_xy_opacity[k];
            let p = column_power(xo, batch_conic[k], centre_x);
            let color = batch_color[k].rgb;
            live = false;
            for (var q = 0u; q < QUADS; q++) {
                quads[q] = blend(quads[q], xo, p, color);
                live = live || any(quads[q].live);
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
                image[y * frame.width + x] = pack4x8unorm(vec4<f32>(clamp(rgb, vec3<f32>(0.0), vec3<f32>(1.0)), 1.0));
            }
        }
    }
}
