// Derive (per simulated Gaussian, docs/method.md §6): the Gaussian moved by the particle p it
// is bound to, written straight into the renderer's Gaussian buffer: mean x_p + F (X_g − X_p)
// (x_p exactly when one particle stands for one Gaussian: the offset is zero), covariance
// F A Fᵀ (A the rest covariance in world space), and the rest-frame rotation composed with
// the rotation of F's polar decomposition (SH are then evaluated along that frame). Opacity and SH are
// unchanged. With relighting on, the normal too: n = F⁻ᵀ n₀ normalised (normals are
// covectors; the cofactor matrix det(F)·F⁻ᵀ avoids the division), written into the
// renderer's shading records. Mirrors `sim::derive::derive_gaussian` and `derive_normal`.

struct DeriveParams {
    // index of the first simulated Gaussian in the renderer's buffer
    offset: u32,
    count: u32,
    // 1: write normals into `shading`
    normals: u32,
    _pad1: u32,
}

// What a particle's Gaussian looked like at rest.
struct RestGaussian {
    // rest covariance upper triangle: xx, xy, xz, yy
    cov_a: vec4<f32>,
    // yz, zz, opacity, and the rest normal packed by `relight::oct_encode` (as bits)
    cov_b: vec4<f32>,
    // rest-frame rotation (x, y, z, w)
    rotation: vec4<f32>,
    // the binding: rest offset X_g − X_p, and the particle's index p (as bits)
    anchor: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: DeriveParams;
@group(0) @binding(1) var<storage, read> x_mass: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> deformation: array<mat3x3<f32>>;
@group(0) @binding(3) var<storage, read> rest: array<RestGaussian>;
@group(0) @binding(4) var<storage, read_write> gaussians: array<GaussianIn>;
// The renderer's shading records (x: packed normal, y: material); a stand-in when off.
@group(0) @binding(5) var<storage, read_write> shading: array<vec2<u32>>;



// Unit quaternion (x, y, z, w) of a rotation matrix (Shepperd's method: divide by the
// largest of the four candidates). m[c][r] is row r, column c.
fn quat_from_rotation(m: mat3x3<f32>) -> vec4<f32> {
    let t = m[0][0] + m[1][1] + m[2][2];
    var q: vec4<f32>;
    if t > 0.0 {
        let s = sqrt(t + 1.0) * 2.0;
        q = vec4<f32>(m[1][2] - m[2][1], m[2][0] - m[0][2], m[0][1] - m[1][0], 0.25 * s * s) / s;
    } else if m[0][0] > m[1][1] && m[0][0] > m[2][2] {
        let s = sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]) * 2.0;
        q = vec4<f32>(0.25 * s * s, m[1][0] + m[0][1], m[2][0] + m[0][2], m[1][2] - m[2][1]) / s;
    } else if m[1][1] > m[2][2] {
        let s = sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]) * 2.0;
        q = vec4<f32>(m[1][0] + m[0][1], 0.25 * s * s, m[2][1] + m[1][2], m[2][0] - m[0][2]) / s;
    } else {
        let s = sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]) * 2.0;
        q = vec4<f32>(m[2][0] + m[0][2], m[2][1] + m[1][2], 0.25 * s * s, m[0][1] - m[1][0]) / s;
    }
    return normalize(q);
}

// Hamilton product a ⊗ b of (x, y, z, w) quaternions: rotate by b, then by a.
fn quat_mul(a: vec4<f32>, b: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(
        a.w * b.xyz + b.w * a.xyz + cross(a.xyz, b.xyz),
        a.w * b.w - dot(a.xyz, b.xyz));
}

@compute @workgroup_size(256)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {
    let g = (wid.x + wid.y * nwg.x) * 256u + lid;
    if g >= params.count {
        return;
    }
    let r = rest[g];
    let p = bitcast<u32>(r.anchor.w);
    let a = mat3x3<f32>(
        vec3<f32>(r.cov_a.x, r.cov_a.y, r.cov_a.z),
        vec3<f32>(r.cov_a.y, r.cov_a.w, r.cov_b.x),
        vec3<f32>(r.cov_a.z, r.cov_b.x, r.cov_b.y));
    let f = deformation[p];
    let c = f * a * transpose(f);
    let rot = quat_mul(quat_from_rotation(polar_rotation(f)), r.rotation);
    if params.normals == 1u {
        let bits = bitcast<u32>(r.cov_b.w);
        var packed = NO_NORMAL;
        if bits != NO_NORMAL {
            let cof = mat3x3<f32>(cross(f[1], f[2]), cross(f[2], f[0]), cross(f[0], f[1]));
            packed = oct_encode(cof * oct_decode(bits));
        }
        shading[params.offset + g].x = packed;
    }
    gaussians[params.offset + g] = GaussianIn(
        vec4<f32>(x_mass[p].xyz + f * r.anchor.xyz, r.cov_b.z),
        vec4<f32>(c[0][0], c[1][0], c[2][0], c[1][1]),
        vec4<f32>(c[2][1], c[2][2], 0.0, 0.0),
        rot);
}
