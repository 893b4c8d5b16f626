// Last pass of the renderer: one workgroup per 16×16 tile, one thread per pixel. The tile's
// Gaussians (front to back) are loaded into workgroup memory 256 at a time and composited
// with α = min(0.99, ω · exp(−½ Δᵀ Σ'⁻¹ Δ)), skipping α < 1/255 and stopping once the
// transmittance would fall below 1e-4 (docs/method.md §7). Pixel (i, j) is sampled at (i + 0.5, j + 0.5).
// Mirrors `render::cpu::render`.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> ranges: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read> tile_values: array<u32>;
// RGBA8, one u32 per pixel, row-major
@group(0) @binding(4) var<storage, read_write> image: array<u32>;
// projected_0 … from binding 8, and projected_at(g), follow (`gpu::pages`).

var<workgroup> batch_xy_opacity: array<vec4<f32>, 256>;
var<workgroup> batch_conic: array<vec4<f32>, 256>;
var<workgroup> batch_color: array<vec4<f32>, 256>;
var<workgroup> finished: atomic<u32>;
var<workgroup> stop_flag: u32;
var<workgroup> tile_range: vec2<u32>;

@compute @workgroup_size(16, 16)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let tile = wid.y * frame.tiles_x + wid.x;
    let pixel = wid.xy * TILE + local.xy;
    let inside = pixel.x < frame.width && pixel.y < frame.height;
    let centre = vec2<f32>(pixel) + 0.5;
    if lid == 0u {
        atomicStore(&finished, 0u);
        tile_range = ranges[tile];
    }
    // Loaded through workgroup memory so every thread provably sees the same (uniform) value.
    let range = workgroupUniformLoad(&tile_range);
    var done = !inside;
    if done {
        atomicAdd(&finished, 1u);
    }
    var t = 1.0;
    var rgb = vec3<f32>(0.0);
    var start = range.x;
    loop {
        workgroupBarrier();
        if lid == 0u {
            stop_flag = select(0u, 1u, atomicLoad(&finished) == 256u);
        }
        if workgroupUniformLoad(&stop_flag) == 1u || start >= range.y {
            break;
        }
        let count = min(256u, range.y - start);
        if lid < count {
            let g = tile_values[start + lid];
            let p = projected_at(g);
            batch_xy_opacity[lid] = p.xy_opacity;
            batch_conic[lid] = p.conic;
            batch_color[lid] = p.color;
        }
        workgroupBarrier();
        for (var k = 0u; k < count && !done; k++) {
            let xo = batch_xy_opacity[k];
            let con = batch_conic[k];
            let d = xo.xy - centre;
            let power = -0.5 * (con.x * d.x * d.x + con.z * d.y * d.y) - con.y * d.x * d.y;
            if power > 0.0 {
                continue;
            }
            let alpha = min(0.99, xo.z * exp(power));
            if alpha < MIN_ALPHA {
                continue;
            }
            let next_t = t * (1.0 - alpha);
            if next_t < 1e-4 {
                done = true;
                atomicAdd(&finished, 1u);
                break;
            }
            rgb += batch_color[k].rgb * (alpha * t);
            t = next_t;
        }
        start += count;
    }
    if inside {
        let c = clamp(rgb + t * frame.background.rgb, vec3<f32>(0.0), vec3<f32>(1.0));
        image[pixel.y * frame.width + pixel.x] = pack4x8unorm(vec4<f32>(c, 1.0));
    }
}
