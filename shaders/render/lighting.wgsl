// Shared declarations of the relighting passes (docs/method.md §8, docs/relighting.md). Mirrored by
// `#[repr(C)]` types in src/render/gpu/lighting.rs (checked by a layout test).
// Needs: common.

const MAX_LIGHTS: u32 = 8u;

// Fixed-point unit of the optical-depth volume: u32 atomics add exactly (and GL has no
// float atomics), so the volume is the same whatever the order of the adds.
const DEPTH_UNIT: f32 = 1.0 / 1024.0;

// Per-frame lighting constants. A storage buffer rather than a uniform: the passes branch
// and loop on these values, which lavapipe would re-specialise the shaders on per dispatch.
struct Lights {
    // rgb: ambient light I_a, w unused
    ambient: vec4<f32>,
    // number of point lights, shadows on (1) or off (0)
    count: u32,
    shadows: u32,
    _pad0: u32,
    _pad1: u32,
    // xyz: light position
    position: array<vec4<f32>, MAX_LIGHTS>,
    // rgb: colour × intensity (I_L)
    radiance: array<vec4<f32>, MAX_LIGHTS>,
    // The shadow volume: voxel (i, j, k) has its centre at lo + (i + ½, j + ½, k + ½)·h.
    // xyz: lo, w: h
    volume_lo_h: vec4<f32>,
    // xyz: voxels per axis, w: unused
    volume_res: vec4<u32>,
}

// Per-object shading weights (`ShadingParams`).
struct ShadeMaterial {
    ambient: f32,
    diffuse: f32,
    specular: f32,
    shininess: f32,
}

// Blinn-Phong of one Gaussian (docs/relighting.md; twin of `relight::blinn_phong`):
// k_a c0 ⊙ I_a + Σ_m T_m (c0 ⊙ I_L,m)(k_d D_m + k_s S_m)/r_m².
fn light_term(c0: vec3<f32>, p: vec3<f32>, n: vec3<f32>, v: vec3<f32>, m: ShadeMaterial,
              light_pos: vec3<f32>, radiance: vec3<f32>, t: f32) -> vec3<f32> {
    let to_light = light_pos - p;
    let r2 = max(dot(to_light, to_light), 1e-12);
    let l = to_light * inverseSqrt(r2);
    let hv = l + v;
    let h = select(vec3<f32>(0.0), normalize(hv), dot(hv, hv) > 0.0);
    let d = max(dot(n, l), 0.0);
    let s = pow(max(dot(n, h), 0.0), m.shininess);
    return t * c0 * radiance * (m.diffuse * d + m.specular * s) / r2;
}

// `relight::NO_NORMAL`: a Gaussian without a normal.
const NO_NORMAL: u32 = 0x80008000u;

// Inverse of `relight::oct_encode`: two 16-bit snorms on the octahedron → unit normal
// (NO_NORMAL: zero).
fn oct_decode(bits: u32) -> vec3<f32> {
    if bits == NO_NORMAL {
        return vec3<f32>(0.0);
    }
    let e = max(unpack2x16snorm(bits), vec2<f32>(-1.0));
    let z = 1.0 - abs(e.x) - abs(e.y);
    let t = max(-z, 0.0);
    let sgn = select(vec2<f32>(-1.0), vec2<f32>(1.0), e >= vec2<f32>(0.0));
    let xy = e - sgn * t;
    return normalize(vec3<f32>(xy, z));
}

// `relight::oct_encode`: a unit normal onto the octahedron, two 16-bit snorms.
fn oct_encode(n: vec3<f32>) -> u32 {
    let l1 = abs(n.x) + abs(n.y) + abs(n.z);
    if !(l1 > 0.0) {
        return NO_NORMAL;
    }
    let p = n.xy / l1;
    var e = p;
    if n.z < 0.0 {
        let sgn = select(vec2<f32>(-1.0), vec2<f32>(1.0), p >= vec2<f32>(0.0));
        e = (vec2<f32>(1.0) - abs(p.yx)) * sgn;
    }
    return pack2x16snorm(clamp(e, vec2<f32>(-1.0), vec2<f32>(1.0)));
}

fn voxel_index(v: vec3<u32>, res: vec3<u32>) -> u32 {
    return v.x + res.x * (v.y + res.y * v.z);
}

// The normal a visible Gaussian is shaded with, seen along v (towards the eye). Two-sided: a
// visible surface faces the camera, so a normal pointing away is a wrongly oriented one
// (PCA cannot always tell the sides of a thin sheet or a concave patch apart) and is
// flipped. Correct normals are unaffected.
fn facing_normal(n: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    return select(n, -n, dot(n, v) < 0.0);
}

// Where a Gaussian at p with shading normal n looks up a light's transmittance: p moved two
// voxels toward the light at `light_pos` and 1.5 voxels along n (so that a Gaussian and the
// surface it lies on do not shadow themselves, also at grazing light), in voxel-centre
// coordinates; sampled trilinearly from the 8 voxels lo + {0,1}³ with fractions f. Outside
// the volume (`inside` false) nothing is in the way. The shade pass reads these voxels and
// the mark pass (shadow_mark.wgsl) asks for exactly them.
struct ShadowLookup {
    inside: bool,
    lo: vec3<f32>,
    f: vec3<f32>,
}

fn shadow_lookup(light_pos: vec3<f32>, p: vec3<f32>, n: vec3<f32>, lo_h: vec4<f32>,
                 res: vec3<u32>) -> ShadowLookup {
    let h = lo_h.w;
    let l = normalize(light_pos - p);
    let x = (p + l * (2.0 * h) + n * (1.5 * h) - lo_h.xyz) / h - 0.5;
    let hi = vec3<f32>(res) - 1.0;
    var out: ShadowLookup;
    out.inside = !(any(x < vec3<f32>(0.0)) || any(x > hi));
    out.lo = min(floor(x), hi - 1.0);
    out.f = x - out.lo;
    return out;
}

// Corner k ∈ [0, 8) of a trilinear cell, x fastest.
fn cell_corner(k: u32) -> vec3<f32> {
    return vec3<f32>(f32(k & 1u), f32((k >> 1u) & 1u), f32(k >> 2u));
}
