// Shadows, pass 2 (per visible Gaussian, after project.wgsl): ask for the transmittance of
// exactly the voxels the shade pass will read — the 8 voxels of each light's lookup
// (`shadow_lookup`, lighting.wgsl) of every Gaussian it shades — and list each asked
// voxel once, for shadow_transmit.wgsl. Marching every voxel of the volume towards every
// light costs far more than the few voxels near lit surfaces that are ever read; the
// voxels it computes get the same values either way.

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> lights: Lights;
@group(0) @binding(2) var<storage, read> gaussians: array<GaussianIn>;
// x: packed normal (oct_decode), y: index into materials
@group(0) @binding(3) var<storage, read> shading: array<vec2<u32>>;
@group(0) @binding(4) var<storage, read> depth_keys: array<u32>;
// Per light and voxel (light-major, as the transmittance): 1 once asked for; cleared
// every frame.
@group(0) @binding(5) var<storage, read_write> asked: array<atomic<u32>>;
// The asked (light · voxels + voxel) indices, in any order.
@group(0) @binding(6) var<storage, read_write> asked_list: array<u32>;
// [x, y, z] workgroups of shadow_transmit.wgsl, split as x = min(groups, 65535),
// y = ⌈groups / 65535⌉; [3] the length of asked_list. Cleared every frame.
@group(0) @binding(7) var<storage, read_write> transmit_args: array<atomic<u32>, 4>;

const MAX_GROUPS_X: u32 = 65535u;

fn ask(index: u32) {
    if atomicExchange(&asked[index], 1u) != 0u {
        return;
    }
    let item = atomicAdd(&transmit_args[3], 1u);
    asked_list[item] = index;
    let group = item / 256u;
    atomicMax(&transmit_args[0], min(group + 1u, MAX_GROUPS_X));
    atomicMax(&transmit_args[1], group / MAX_GROUPS_X + 1u);
    atomicMax(&transmit_args[2], 1u);
}

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let g = flat_workgroup(wid, nwg) * 256u + lid;
    // The shade pass's conditions for looking up shadows (shade.wgsl).
    if lights.shadows == 0u || g >= frame.num_gaussians || depth_keys[g] == CULLED_KEY {
        return;
    }
    var n = oct_decode(shading[g].x);
    if all(n == vec3<f32>(0.0)) {
        return;
    }
    let p = gaussians[g].mean_opacity.xyz;
    n = facing_normal(n, normalize(frame.camera_near.xyz - p));
    let res = lights.volume_res.xyz;
    let voxels = res.x * res.y * res.z;
    for (var i = 0u; i < lights.count; i++) {
        let at = shadow_lookup(lights.position[i].xyz, p, n, lights.volume_lo_h, res);
        if !at.inside {
            continue;
        }
        for (var k = 0u; k < 8u; k++) {
            ask(i * voxels + voxel_index(vec3<u32>(at.lo + cell_corner(k)), res));
        }
    }
}
