// Shadows, pass 3 (per voxel and light that shadow_mark.wgsl asked for, by indirect
// dispatch): the transmittance T = exp(−∫ σ ds) from the voxel's centre to the light
// through the optical-depth volume, marched in steps of one voxel with trilinear samples,
// stopping where the ray leaves the volume (nothing outside casts shadows) or once the
// light is blocked (τ > OPAQUE). Voxels nobody asked for keep stale values, which nothing
// reads. Mirrors `relight::shadow::transmittance`.

// exp(−12) ≈ 6e-6: no visible light gets through.
const OPAQUE: f32 = 12.0;

@group(0) @binding(0) var<storage, read> lights: Lights;
@group(0) @binding(1) var<storage, read> depth: array<u32>;
// T per voxel, light-major: [light · voxels + voxel]
@group(0) @binding(2) var<storage, read_write> transmittance: array<f32>;
// What shadow_mark.wgsl asked for: (light · voxels + voxel) indices, and their count at [3].
@group(0) @binding(3) var<storage, read> asked_list: array<u32>;
@group(0) @binding(4) var<storage, read> transmit_args: array<u32, 4>;

fn depth_at(x: vec3<f32>, res: vec3<u32>) -> f32 {
    // x in voxel-centre coordinates; trilinear, zero outside.
    let lo = floor(x);
    let f = x - lo;
    var sum = 0.0;
    for (var k = 0u; k < 8u; k++) {
        let o = cell_corner(k);
        let c = lo + o;
        if any(c < vec3<f32>(0.0)) || any(c >= vec3<f32>(res)) {
            continue;
        }
        let w = select(1.0 - f, f, o == vec3<f32>(1.0));
        sum += w.x * w.y * w.z * f32(depth[voxel_index(vec3<u32>(c), res)]);
    }
    return sum * DEPTH_UNIT;
}

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let item = flat_workgroup(wid, nwg) * 256u + lid;
    if item >= transmit_args[3] {
        return;
    }
    let i = asked_list[item];
    let res = lights.volume_res.xyz;
    let voxels = res.x * res.y * res.z;
    let light = i / voxels;
    let v = i % voxels;
    let cell = vec3<u32>(v % res.x, (v / res.x) % res.y, v / (res.x * res.y));
    let h = lights.volume_lo_h.w;
    // In voxel-centre coordinates (voxel centres at integers).
    let start = vec3<f32>(cell);
    let goal = (lights.position[light].xyz - lights.volume_lo_h.xyz) / h - 0.5;
    let to = goal - start;
    let dist = length(to);
    var tau = 0.0;
    if dist > 0.0 {
        let dir = to / dist;
        // Where the ray leaves the box [−½, res − ½] (or reaches the light).
        let inv = 1.0 / select(dir, vec3<f32>(1e-30), dir == vec3<f32>(0.0));
        let t0 = (vec3<f32>(-0.5) - start) * inv;
        let t1 = (vec3<f32>(res) - 0.5 - start) * inv;
        let exit = min(min(max(t0.x, t1.x), max(t0.y, t1.y)), max(t0.z, t1.z));
        let end = min(dist, max(exit, 0.0));
        let steps = u32(ceil(end));
        let ds = end / f32(max(steps, 1u));
        for (var s = 0u; s < steps && tau < OPAQUE; s++) {
            tau += depth_at(start + dir * ((f32(s) + 0.5) * ds), res) * ds;
        }
    }
    transmittance[i] = exp(-tau);
}
