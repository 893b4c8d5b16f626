// Relighting (per visible Gaussian, after project.wgsl): replace the SH colour c0 by its
// Blinn-Phong shading under the frame's point lights (lighting.wgsl), each light's term
// weighted by its visibility T, sampled trilinearly from the transmittance volume where
// `shadow_lookup` says (the voxels shadow_mark.wgsl asked shadow_transmit.wgsl for).
// Gaussians without a normal keep c0 under the ambient term only. Mirrors
// `relight::blinn_phong` and `relight::shadow::ShadowVolume::visibility`. The shading
// normal is also what the normal pass shows (docs/method.md §7.7).

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> lights: Lights;
@group(0) @binding(2) var<storage, read> gaussians: array<GaussianIn>;
// x: packed normal (oct_decode), y: index into materials
@group(0) @binding(3) var<storage, read> shading: array<vec2<u32>>;
@group(0) @binding(4) var<storage, read> materials: array<ShadeMaterial>;
@group(0) @binding(5) var<storage, read> transmittance: array<f32>;
@group(0) @binding(6) var<storage, read> depth_keys: array<u32>;
@group(0) @binding(7) var<storage, read_write> projected: array<Projected>;

fn visibility(light: u32, p: vec3<f32>, n: vec3<f32>) -> f32 {
    if lights.shadows == 0u {
        return 1.0;
    }
    let res = lights.volume_res.xyz;
    let at = shadow_lookup(lights.position[light].xyz, p, n, lights.volume_lo_h, res);
    if !at.inside {
        return 1.0;
    }
    let base = light * res.x * res.y * res.z;
    var t = 0.0;
    for (var k = 0u; k < 8u; k++) {
        let o = cell_corner(k);
        let w = select(1.0 - at.f, at.f, o == vec3<f32>(1.0));
        t += w.x * w.y * w.z * transmittance[base + voxel_index(vec3<u32>(at.lo + o), res)];
    }
    return t;
}

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let g = flat_workgroup(wid, nwg) * 256u + lid;
    if g >= frame.num_gaussians || depth_keys[g] == CULLED_KEY {
        return;
    }
    let p = gaussians[g].mean_opacity.xyz;
    let s = shading[g];
    let m = materials[s.y];
    var n = oct_decode(s.x);
    let c0 = projected[g].color.xyz;
    // The normal pass's normal (color.w, `normal_code`): the shading normal turned towards
    // the camera, in camera space, where the Gaussian has one; else what projection left.
    var code = projected[g].color.w;
    var out = m.ambient * c0 * lights.ambient.xyz;
    if any(n != vec3<f32>(0.0)) {
        let v = normalize(frame.camera_near.xyz - p);
        n = facing_normal(n, v);
        for (var i = 0u; i < lights.count; i++) {
            out += light_term(c0, p, n, v, m, lights.position[i].xyz, lights.radiance[i].xyz,
                              visibility(i, p, n));
        }
        let w = mat3x3<f32>(frame.view_row0.xyz, frame.view_row1.xyz, frame.view_row2.xyz);
        code = normal_code(n * w);
    }
    projected[g].color = vec4<f32>(out, code);
}
