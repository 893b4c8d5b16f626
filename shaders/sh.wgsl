// Real spherical harmonics of the 3DGS reference (docs/method.md §7). Mirrors src/splat/sh.rs.
// Coefficients are stored as f16 pairs: per Gaussian 24 u32 = 48 halves, coefficient-major
// (k * 3 + c), padded with zeros up to degree 3.

const SH_C0: f32 = 0.28209479177387814;
const SH_C1: f32 = 0.4886025119029199;
const SH_C2 = array<f32, 5>(1.0925484305920792, -1.0925484305920792, 0.31539156525252005, -1.0925484305920792, 0.5462742152960396);
const SH_C3 = array<f32, 7>(-0.5900435899266435, 2.890611442640554, -0.4570457994644658, 0.3731763325901154, -0.4570457994644658, 1.445305721320277, -0.5900435899266435);
const SH_WORDS: u32 = 24u;

fn sh_coeff(g: u32, k: u32) -> vec3<f32> {
    let h = k * 3u; // first half index of coefficient k
    let base = g * SH_WORDS;
    var v: vec3<f32>;
    for (var c = 0u; c < 3u; c++) {
        let idx = h + c;
        let pair = unpack2x16float(sh_words[base + idx / 2u]);
        v[c] = select(pair.x, pair.y, (idx & 1u) == 1u);
    }
    return v;
}

// Colour max(0, 0.5 + Σ Y_k(d) c_k) for a unit rest-frame direction d.
fn sh_color(g: u32, degree: u32, d: vec3<f32>) -> vec3<f32> {
    var rgb = SH_C0 * sh_coeff(g, 0u);
    if degree >= 1u {
        let x = d.x; let y = d.y; let z = d.z;
        rgb += -SH_C1 * y * sh_coeff(g, 1u) + SH_C1 * z * sh_coeff(g, 2u) - SH_C1 * x * sh_coeff(g, 3u);
        if degree >= 2u {
            let xx = x * x; let yy = y * y; let zz = z * z;
            let xy = x * y; let yz = y * z; let xz = x * z;
            rgb += SH_C2[0] * xy * sh_coeff(g, 4u)
                + SH_C2[1] * yz * sh_coeff(g, 5u)
                + SH_C2[2] * (2.0 * zz - xx - yy) * sh_coeff(g, 6u)
                + SH_C2[3] * xz * sh_coeff(g, 7u)
                + SH_C2[4] * (xx - yy) * sh_coeff(g, 8u);
            if degree >= 3u {
                rgb += SH_C3[0] * y * (3.0 * xx - yy) * sh_coeff(g, 9u)
                    + SH_C3[1] * xy * z * sh_coeff(g, 10u)
                    + SH_C3[2] * y * (4.0 * zz - xx - yy) * sh_coeff(g, 11u)
                    + SH_C3[3] * z * (2.0 * zz - 3.0 * xx - 3.0 * yy) * sh_coeff(g, 12u)
                    + SH_C3[4] * x * (4.0 * zz - xx - yy) * sh_coeff(g, 13u)
                    + SH_C3[5] * z * (xx - yy) * sh_coeff(g, 14u)
                    + SH_C3[6] * x * (xx - 3.0 * yy) * sh_coeff(g, 15u);
            }
        }
    }
    return max(rgb + 0.5, vec3<f32>(0.0));
}
