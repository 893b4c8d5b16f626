//! "Math twice": the f32 WGSL modules under `shaders/sim/` against the f64
//! oracle in `splatter::sim`, on thousands of random inputs per function, on the best
//! adapter and on the GL backend (lavapipe and llvmpipe on a machine without a GPU).
//!
//! Each function under test gets a compute shader: the simulation modules
//! ([`wgsl::library`]; for a law's functions, the registry's WGSL [`splatter::sim::model::wgsl`] in
//! `extra`) plus `shaders/common.wgsl` plus a small `@compute fn main` that
//! reads one input record per invocation from a flat `array<f32>` and writes one output
//! record. Inputs are drawn with [`SplitMix64`] in f64, rounded to f32 for the GPU, and the
//! oracle runs on exactly those rounded values (converted back to f64), so every difference
//! measured is the f32 arithmetic of the kernel. Tolerances are stated next to each check
//! (ε = 2⁻²³ ≈ 1.19e-7); every test prints what it measured
//! (`cargo test --release --test sim_wgsl -- --nocapture`).

use std::sync::OnceLock;
use std::time::Instant;

use glam::{DMat3, DQuat, DVec3, IVec3};
use splatter::gpu::{GpuContext, Kernel};
use splatter::render::gpu::read_buffer;
use splatter::rng::SplitMix64;
use splatter::sim::bspline::{stencil_offsets, Stencil};
use splatter::sim::gpu::wgsl;
use splatter::sim::model::elasticity::{kirchhoff_fixed_corotated, kirchhoff_neo_hookean, Lame};
use splatter::sim::model::nacc::oracle::{
    j_from_pressure, principal_state, project_pq, return_map, stretches_from_pq, Case3Variant,
    NaccParams, PlasticReturn, PrincipalState, ReturnCase, YieldEllipse, SIGMA_MIN,
};
use splatter::sim::model::nacc::{self as nacc_model, NaccMaterialGpu};
use splatter::sim::svd::{polar, svd3};
use wgpu::util::DeviceExt;

const COMMON: &str = include_str!("../shaders/common.wgsl");
const EPS: f64 = f32::EPSILON as f64;

/// The best adapter, plus the GL backend when it exists and is not the best one
/// (`SPLATTER_TEST_BACKEND=vulkan|gl` restricts the run to one backend), opened once and
/// shared by the tests of this file.
fn gpus() -> &'static [GpuContext] {
    static GPUS: OnceLock<Vec<GpuContext>> = OnceLock::new();
    GPUS.get_or_init(splatter::gpu::test_contexts)
}

fn backend(gpu: &GpuContext) -> String {
    format!("{:?}", gpu.info.backend)
}

/// A compute shader around `body`: invocation `item` reads `inputs[ib .. ib + in_stride]`
/// and writes `outputs[ob .. ob + out_stride]` through `get*`/`put*`.
fn harness(in_stride: usize, out_stride: usize, extra: &str, body: &str) -> String {
    let lib = wgsl::library();
    format!(
        r#"{COMMON}
{lib}
@group(0) @binding(0) var<storage, read> inputs: array<f32>;
@group(0) @binding(1) var<storage, read_write> outputs: array<f32>;
{extra}
const IN_STRIDE: u32 = {in_stride}u;
const OUT_STRIDE: u32 = {out_stride}u;

fn in1(i: u32) -> f32 {{ return inputs[i]; }}
fn in3(i: u32) -> vec3<f32> {{ return vec3<f32>(inputs[i], inputs[i + 1u], inputs[i + 2u]); }}
fn in_mat3(i: u32) -> mat3x3<f32> {{ return mat3x3<f32>(in3(i), in3(i + 3u), in3(i + 6u)); }}
fn out1(i: u32, v: f32) {{ outputs[i] = v; }}
fn out3(i: u32, v: vec3<f32>) {{ outputs[i] = v.x; outputs[i + 1u] = v.y; outputs[i + 2u] = v.z; }}
fn out_mat3(i: u32, m: mat3x3<f32>) {{ out3(i, m[0]); out3(i + 3u, m[1]); out3(i + 6u, m[2]); }}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) lid: u32) {{
    let item = flat_workgroup(wid, nwg) * 64u + lid;
    if item >= arrayLength(&inputs) / IN_STRIDE {{
        return;
    }}
    let ib = item * IN_STRIDE;
    let ob = item * OUT_STRIDE;
{body}
}}
"#
    )
}

/// Runs a [`harness`] kernel over `inputs` (records of `in_stride` floats), with an
/// optional third storage buffer, and returns the outputs.
fn run(
    gpu: &GpuContext,
    label: &'static str,
    source: &str,
    inputs: &[f32],
    (in_stride, out_stride): (usize, usize),
    extra: Option<&[u8]>,
) -> Vec<f32> {
    assert_eq!(inputs.len() % in_stride, 0);
    let n = inputs.len() / in_stride;
    let dev = &gpu.device;
    let kernel = Kernel::new(dev, label, source, "main");
    let storage = wgpu::BufferUsages::STORAGE;
    let input = dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("inputs"),
        contents: bytemuck::cast_slice(inputs),
        usage: storage,
    });
    let size = (n * out_stride * 4) as u64;
    let output = dev.create_buffer(&wgpu::BufferDescriptor {
        label: Some("outputs"),
        size,
        usage: storage | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let staging = dev.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let extra = extra.map(|bytes| {
        dev.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("extra"),
            contents: bytes,
            usage: storage,
        })
    });
    let mut buffers = vec![("inputs", &input), ("outputs", &output)];
    buffers.extend(extra.as_ref().map(|b| ("materials", b)));
    let bind = kernel.bind_named(dev, &buffers);
    let mut enc = dev.create_command_encoder(&Default::default());
    {
        let mut pass = enc.begin_compute_pass(&Default::default());
        kernel.dispatch(&mut pass, &bind, n.div_ceil(64) as u32);
    }
    enc.copy_buffer_to_buffer(&output, 0, &staging, 0, None);
    gpu.queue.submit([enc.finish()]);
    let bytes =
        read_buffer(gpu, &staging).unwrap_or_else(|e| panic!("{label} on {}: {e}", gpu.describe()));
    bytemuck::cast_slice::<u8, f32>(&bytes).to_vec()
}

// ---------------------------------------------------------------------------------------
// Input helpers

fn random_rotation(r: &mut SplitMix64) -> DMat3 {
    let v = DVec3::new(r.uniform(), r.uniform(), r.uniform()) - 0.5;
    DMat3::from_quat(DQuat::from_xyzw(v.x, v.y, v.z, r.uniform() - 0.5).normalize())
}

/// Rounds to f32 (what the GPU gets) and back (what the oracle gets).
fn round_f32(m: DMat3) -> DMat3 {
    DMat3::from_cols_array(&m.to_cols_array().map(|x| x as f32 as f64))
}

fn push_mat(out: &mut Vec<f32>, m: DMat3) {
    out.extend(m.to_cols_array().map(|x| x as f32));
}

fn mat_at(out: &[f32], i: usize) -> DMat3 {
    DMat3::from_cols_array(&std::array::from_fn(|k| out[i + k] as f64))
}

fn vec_at(out: &[f32], i: usize) -> DVec3 {
    DVec3::new(out[i] as f64, out[i + 1] as f64, out[i + 2] as f64)
}

fn frobenius(m: DMat3) -> f64 {
    m.to_cols_array().iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn max_abs(m: DMat3) -> f64 {
    m.to_cols_array().iter().fold(0.0, |a, x| a.max(x.abs()))
}

/// The oracle's ten kinds of hard SVD inputs (`src/sim/svd.rs` tests).
fn svd_input(r: &mut SplitMix64, kind: usize) -> DMat3 {
    let (a, b) = (random_rotation(r), random_rotation(r));
    let s = |r: &mut SplitMix64| 10f64.powf(4.0 * r.uniform() - 2.0);
    let sig = match kind {
        0 => return DMat3::from_cols_array(&[0.0; 9].map(|_: f64| r.uniform() * 2.0 - 1.0)),
        1 => return a,                                  // rotation
        2 => DVec3::new(s(r), s(r), s(r) * 1e-9),       // near-singular
        3 => DVec3::splat(s(r)),                        // all σ equal
        4 => DVec3::new(s(r), 0.7, 0.7),                // two equal
        5 => DVec3::new(s(r), s(r), -s(r)),             // reflection
        6 => DVec3::new(s(r), 0.0, 0.0),                // rank 1
        7 => DVec3::ZERO,                               // zero
        8 => DVec3::new(1.0, 1.0 + 1e-12, 1.0 - 1e-12), // near-repeated
        _ => DVec3::new(s(r), s(r), 0.0),               // rank 2
    };
    a * DMat3::from_diagonal(sig) * b.transpose()
}

// ---------------------------------------------------------------------------------------
// SVD and polar decomposition

/// Tolerances of the f32 SVD (ε = 2⁻²³): singular values within 2e-6·σ₁ of the oracle's
/// (≈ 17 ε; absolute in units of σ₁, because the f32 input itself only defines σ to
/// ~ε σ₁); reconstruction ‖U Σ Vᵀ − F‖_F ≤ 4e-6 ‖F‖_F; ‖UᵀU − I‖_F, ‖VᵀV − I‖_F and
/// |det − 1| ≤ 4e-6; σ₁ ≥ σ₂ ≥ |σ₃| exactly; sign σ₃ = sign det F where |σ₃| > 1e-5 σ₁.
/// Polar: R orthonormal with det +1 and ‖R S − F‖_F, ‖S − Sᵀ‖_F ≤ 4e-6 ‖F‖_F; R agrees with
/// the oracle's within 4e-6 · σ₁/(σ₂ + σ₃) (the conditioning of R), checked where
/// σ₂ + σ₃ > 1e-3 σ₁ (elsewhere R is not determined by F to f32 precision).
const SIGMA_TOL: f64 = 2e-6;
const SVD_TOL: f64 = 4e-6;

#[test]
fn svd_and_polar_match_the_oracle() {
    let mut r = SplitMix64::new(101);
    let mut inputs: Vec<DMat3> = (0..8200).map(|i| svd_input(&mut r, i % 10)).collect();
    inputs.extend([
        DMat3::IDENTITY,
        -DMat3::IDENTITY,
        DMat3::from_diagonal(DVec3::new(-1.0, 2.0, 3.0)),
        DMat3::from_cols(DVec3::Y, DVec3::X, DVec3::Z),
        DMat3::from_cols(DVec3::X, DVec3::X, DVec3::X),
        DMat3::from_diagonal(DVec3::new(1e-30, 3e-30, -2e-30)),
        DMat3::from_diagonal(DVec3::new(1e30, 3e30, 2e30)),
        DMat3::from_cols(DVec3::X, DVec3::Y * 1e-20, DVec3::Z * 1e-30),
    ]);
    let inputs: Vec<DMat3> = inputs.into_iter().map(round_f32).collect();
    let mut flat = Vec::new();
    for f in &inputs {
        push_mat(&mut flat, *f);
    }
    let oracle: Vec<_> = inputs.iter().map(|f| (svd3(*f), polar(*f).0)).collect();
    let body = "
    var sweeps: u32;
    let f = in_mat3(ib);
    let d = svd3_counted(f, &sweeps);
    out_mat3(ob, d.u);
    out3(ob + 9u, d.sigma);
    out_mat3(ob + 12u, d.v);
    out1(ob + 21u, f32(sweeps));
    let pd = polar3(f);
    out_mat3(ob + 22u, pd.r);
    out_mat3(ob + 31u, pd.s);
    out_mat3(ob + 40u, polar_rotation(f));";
    let src = harness(9, 49, "", body);
    for gpu in gpus() {
        let t = Instant::now();
        let out = run(gpu, "svd harness", &src, &flat, (9, 49), None);
        let gpu_ms = t.elapsed().as_secs_f64() * 1e3;
        let (mut e_sigma, mut e_rec, mut e_orth, mut e_det) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        let (mut e_prec, mut e_psym, mut e_r, mut r_checked) = (0.0f64, 0.0f64, 0.0f64, 0);
        let (mut sweeps_max, mut sweeps_sum, mut sign_checked) = (0usize, 0usize, 0);
        let mut by_kind = [[0.0f64; 2]; 11];
        for (i, (f, (want, want_r))) in inputs.iter().zip(&oracle).enumerate() {
            let o = i * 49;
            let (u, sigma, v) = (mat_at(&out, o), vec_at(&out, o + 9), mat_at(&out, o + 12));
            let sweeps = out[o + 21] as usize;
            let (rot, s) = (mat_at(&out, o + 22), mat_at(&out, o + 31));
            let ctx = || format!("input {i} {f} on {}", backend(gpu));
            sweeps_max = sweeps_max.max(sweeps);
            sweeps_sum += sweeps;
            assert!(
                sigma.x >= sigma.y && sigma.y >= sigma.z.abs(),
                "unsorted σ {sigma}, {}",
                ctx()
            );
            let s1 = want.sigma.x;
            let norm = frobenius(*f);
            let rel = |x: f64, scale: f64| if scale > 0.0 { x / scale } else { x };
            let es = rel((sigma - want.sigma).abs().max_element(), s1);
            let er = rel(
                frobenius(u * DMat3::from_diagonal(sigma) * v.transpose() - *f),
                norm,
            );
            let kind = if i < 8200 { i % 10 } else { 10 };
            by_kind[kind][0] = by_kind[kind][0].max(es);
            by_kind[kind][1] = by_kind[kind][1].max(er);
            e_sigma = e_sigma.max(es);
            e_rec = e_rec.max(er);
            e_orth = e_orth
                .max(frobenius(u.transpose() * u - DMat3::IDENTITY))
                .max(frobenius(v.transpose() * v - DMat3::IDENTITY))
                .max(frobenius(rot.transpose() * rot - DMat3::IDENTITY));
            e_det = e_det
                .max((u.determinant() - 1.0).abs())
                .max((v.determinant() - 1.0).abs())
                .max((rot.determinant() - 1.0).abs());
            if want.sigma.z.abs() > 1e-5 * s1 {
                sign_checked += 1;
                assert_eq!(
                    sigma.z < 0.0,
                    f.determinant() < 0.0,
                    "sign of σ₃ {sigma}, {}",
                    ctx()
                );
            }
            e_prec = e_prec.max(rel(frobenius(rot * s - *f), norm));
            e_psym = e_psym.max(rel(frobenius(s - s.transpose()), norm));
            // polar_rotation() is the same R as polar3().r.
            assert_eq!(mat_at(&out, o + 40), rot, "{}", ctx());
            let cond = (want.sigma.y + want.sigma.z) / s1;
            if cond > 1e-3 {
                r_checked += 1;
                e_r = e_r.max(max_abs(rot - *want_r) * cond);
            }
        }
        println!(
            "svd3 on {} ({} matrices, {gpu_ms:.0} ms): |Δσ| ≤ {e_sigma:.2e}·σ₁, reconstruction \
             ≤ {e_rec:.2e}, orthonormality ≤ {e_orth:.2e}, |det − 1| ≤ {e_det:.2e}, sign of σ₃ \
             checked on {sign_checked}; Jacobi sweeps ≤ {sweeps_max} (mean {:.2}); polar: \
             ‖RS − F‖ ≤ {e_prec:.2e}, ‖S − Sᵀ‖ ≤ {e_psym:.2e}, |R − R_oracle|·(σ₂+σ₃)/σ₁ ≤ \
             {e_r:.2e} on {r_checked}",
            backend(gpu),
            inputs.len(),
            sweeps_sum as f64 / inputs.len() as f64
        );
        println!(
            "  worst (Δσ/σ₁, reconstruction) per kind [general, rotation, near-singular, \
             σ equal, two equal, reflection, rank 1, zero, near-repeated, rank 2, special]: {}",
            by_kind
                .iter()
                .map(|[a, b]| format!("({a:.1e}, {b:.1e})"))
                .collect::<Vec<_>>()
                .join(" ")
        );
        assert!(e_sigma <= SIGMA_TOL, "σ: {e_sigma:e} on {}", backend(gpu));
        for (what, e) in [
            ("reconstruction", e_rec),
            ("orthonormality", e_orth),
            ("det", e_det),
            ("polar R S = F", e_prec),
            ("polar S symmetric", e_psym),
            ("polar R vs oracle", e_r),
        ] {
            assert!(e <= SVD_TOL, "{what}: {e:e} on {}", backend(gpu));
        }
        assert!(
            sweeps_max < 6,
            "the SVD needed all SVD_MAX_SWEEPS sweeps on some input"
        );
    }
}

/// Non-finite input comes back non-finite (for the watchdog) and does not hang.
#[test]
fn svd_of_non_finite_input_is_non_finite() {
    let mut flat = Vec::new();
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let mut m = [0.5f32, 0.1, 0.0, -0.2, 1.0, 0.3, 0.0, 0.2, 0.9];
        m[4] = bad;
        flat.extend(m);
    }
    let body = "
    let d = svd3(in_mat3(ib));
    out1(ob, select(0.0, 1.0, sim_is_finite_mat3(d.u) && sim_is_finite3(d.sigma) && sim_is_finite_mat3(d.v)));";
    let src = harness(9, 1, "", body);
    for gpu in gpus() {
        let out = run(gpu, "svd non-finite harness", &src, &flat, (9, 1), None);
        assert_eq!(out, vec![0.0; 3], "on {}", backend(gpu));
    }
}

// ---------------------------------------------------------------------------------------
// Kirchhoff stresses

/// Lamé parameters of the paper's materials and a few stiffer/softer ones.
fn lame_list() -> Vec<Lame> {
    [
        (2000.0, 0.38),
        (1e4, 0.45),
        (50.0, 0.05),
        (1e6, 0.3),
        (5000.0, 0.49),
    ]
    .map(|(e, nu)| Lame::from_young_poisson(e, nu))
    .to_vec()
}

/// Deformation gradients for the stress tests: I + H (|H_ij| ≤ 0.4), rotated stretches in
/// [0.3, 2.5], pure rotations, and (for fixed corotated) reflections with σ₃ ∈ [−1, −0.2]
/// and σ₂ + σ₃ ≥ 0.2 with σ₁ ≤ 4.2 (where R is well determined).
fn stress_input(r: &mut SplitMix64, i: usize) -> DMat3 {
    let (a, b) = (random_rotation(r), random_rotation(r));
    let stretch = |r: &mut SplitMix64| 0.3 + 2.2 * r.uniform();
    match i % 4 {
        0 => {
            DMat3::IDENTITY
                + DMat3::from_cols_array(&[0.0; 9].map(|_: f64| 0.8 * r.uniform() - 0.4))
        }
        1 => {
            a * DMat3::from_diagonal(DVec3::new(stretch(r), stretch(r), stretch(r))) * b.transpose()
        }
        2 => a,
        _ => {
            let s3 = -(0.2 + 0.8 * r.uniform());
            let s2 = 1.2 + r.uniform();
            let s1 = s2 + 2.0 * r.uniform();
            a * DMat3::from_diagonal(DVec3::new(s1, s2, s3)) * b.transpose()
        }
    }
}

/// Tolerances: ‖Δτ‖_max ≤ 2e-6 · scale with, for fixed corotated,
/// scale = 2μ σ₁ (σ₁ + 1) + |λ| |J| (|J| + 1) (the size of its two terms before they
/// cancel), and for Neo-Hookean scale = μ J^(−2/3) σ₁² + κ/2 (J² + 1).
const STRESS_TOL: f64 = 2e-6;

#[test]
fn kirchhoff_stresses_match_the_oracle() {
    let mut r = SplitMix64::new(202);
    let lames = lame_list();
    let mut cases = Vec::new();
    let mut flat = Vec::new();
    for i in 0..6000 {
        let f = round_f32(stress_input(&mut r, i));
        let lame = lames[i % lames.len()];
        push_mat(&mut flat, f);
        flat.extend([lame.mu as f32, lame.lambda as f32, lame.kappa() as f32]);
        // the oracle with the parameters the GPU got
        let l32 = Lame {
            mu: lame.mu as f32 as f64,
            lambda: lame.lambda as f32 as f64,
        };
        let kappa32 = lame.kappa() as f32 as f64;
        cases.push((f, l32, kappa32));
    }
    let body = "
    let f = in_mat3(ib);
    let mu = in1(ib + 9u);
    let lambda = in1(ib + 10u);
    let kappa = in1(ib + 11u);
    out_mat3(ob, elastic_kirchhoff_fixed_corotated(f, mu, lambda));
    out_mat3(ob + 9u, elastic_kirchhoff_neo_hookean(f, mu, kappa));
    out_mat3(ob + 18u, elastic_kirchhoff_fixed_corotated_svd(f, svd3(f), mu, lambda));";
    let src = harness(12, 27, "", body);
    for gpu in gpus() {
        let out = run(gpu, "stress harness", &src, &flat, (12, 27), None);
        let (mut e_fc, mut e_nh, mut n_nh) = (0.0f64, 0.0f64, 0);
        for (i, (f, lame, kappa)) in cases.iter().enumerate() {
            let o = i * 27;
            let j = f.determinant();
            let s1 = svd3(*f).sigma.x;
            let want = kirchhoff_fixed_corotated(*f, lame);
            let scale =
                2.0 * lame.mu * s1 * (s1 + 1.0) + lame.lambda.abs() * j.abs() * (j.abs() + 1.0);
            let err = max_abs(mat_at(&out, o) - want) / scale;
            assert!(
                err <= STRESS_TOL,
                "fixed corotated {err:e} for {f} on {}",
                backend(gpu)
            );
            assert_eq!(mat_at(&out, o + 18), mat_at(&out, o), "svd variant");
            e_fc = e_fc.max(err);
            if j > 0.0 {
                n_nh += 1;
                // the Lamé pair whose κ is the one the GPU got
                let want = kirchhoff_neo_hookean(
                    *f,
                    &Lame {
                        mu: lame.mu,
                        lambda: kappa - 2.0 * lame.mu / 3.0,
                    },
                );
                let scale = lame.mu * j.powf(-2.0 / 3.0) * s1 * s1 + 0.5 * kappa * (j * j + 1.0);
                let err = max_abs(mat_at(&out, o + 9) - want) / scale;
                assert!(
                    err <= STRESS_TOL,
                    "Neo-Hookean {err:e} for {f} on {}",
                    backend(gpu)
                );
                e_nh = e_nh.max(err);
            }
        }
        println!(
            "Kirchhoff stress on {} ({} F × {} Lamé pairs): fixed corotated ‖Δτ‖ ≤ {e_fc:.2e}·scale, \
             Neo-Hookean ‖Δτ‖ ≤ {e_nh:.2e}·scale ({n_nh} with J > 0)",
            backend(gpu),
            cases.len(),
            lames.len()
        );
    }
}

// ---------------------------------------------------------------------------------------
// B-spline weights

/// Tolerance: per node, |Δw| and |Δ(∇w)|·Δx ≤ 16 ε (1 + |x|/Δx), |Δd|/Δx ≤ the same (the
/// f32 x/Δx carries ~ε|x|/Δx); Σw = 1 and Σ∇w = 0 to 1e-6, Σ w d dᵀ = Δx²/4 I to 1e-5
/// relative (MLS). Nodes are compared by global index, so a base that differs by one
/// (x/Δx − 0.5 within round-off of an integer) still compares the right weights.
#[test]
fn bspline_weights_match_the_oracle() {
    let mut r = SplitMix64::new(303);
    let spacings = [1e-2f64, 3e-3, 0.037, 1.0 / 64.0];
    let mut cases = Vec::new();
    let mut flat = Vec::new();
    for i in 0..6000 {
        let dx = spacings[i % spacings.len()] as f32;
        let x = match i % 5 {
            // exactly on a node, or exactly half-way: floor boundaries of x/Δx − 0.5
            3 => {
                (DVec3::new(r.uniform(), r.uniform(), r.uniform()) / dx as f64).floor() * dx as f64
            }
            4 => {
                ((DVec3::new(r.uniform(), r.uniform(), r.uniform()) / dx as f64).floor() + 0.5)
                    * dx as f64
            }
            _ => DVec3::new(r.uniform(), r.uniform(), r.uniform()) * 1.2 - 0.1,
        };
        let x = x.as_vec3();
        flat.extend([x.x, x.y, x.z, 1.0 / dx, dx]);
        cases.push((x.as_dvec3(), dx as f64));
    }
    let body = "
    let x = in3(ib);
    let inv_dx = in1(ib + 3u);
    let dx = in1(ib + 4u);
    let s = bspline_stencil(x, inv_dx);
    out3(ob, vec3<f32>(s.base));
    out3(ob + 3u, s.fx);
    for (var n = 0u; n < 27u; n++) {
        let off = bspline_stencil_offset(n);
        out1(ob + 6u + n, bspline_weight(s, off));
        out3(ob + 33u + 3u * n, bspline_weight_grad(s, off, inv_dx));
        out3(ob + 114u + 3u * n, bspline_offset(s, off, dx));
    }";
    let src = harness(5, 195, "", body);
    let offsets: Vec<IVec3> = stencil_offsets().collect();
    for gpu in gpus() {
        let out = run(gpu, "bspline harness", &src, &flat, (5, 195), None);
        let (mut e_w, mut e_sum, mut e_mls, mut shifted) = (0.0f64, 0.0f64, 0.0f64, 0);
        for (i, (x, dx)) in cases.iter().enumerate() {
            let o = i * 195;
            let want = Stencil::new(*x, *dx);
            let base = vec_at(&out, o).as_ivec3();
            if base != want.base {
                shifted += 1;
            }
            let tol = EPS * (1.0 + x.abs().max_element() / dx);
            // weight, gradient·Δx and offset/Δx of global node `node` (0 outside a stencil)
            let gpu_node = |node: IVec3| {
                let off = node - base;
                if off.cmplt(IVec3::ZERO).any() || off.cmpgt(IVec3::splat(2)).any() {
                    return None;
                }
                let n = (off.x + 3 * off.y + 9 * off.z) as usize;
                Some((
                    out[o + 6 + n] as f64,
                    vec_at(&out, o + 33 + 3 * n) * *dx,
                    vec_at(&out, o + 114 + 3 * n) / *dx,
                ))
            };
            let oracle_node = |node: IVec3| {
                let off = node - want.base;
                if off.cmplt(IVec3::ZERO).any() || off.cmpgt(IVec3::splat(2)).any() {
                    return None;
                }
                Some((
                    want.weight(off),
                    want.weight_grad(off, *dx) * *dx,
                    want.offset(off, *dx) / *dx,
                ))
            };
            let mut worst = 0.0f64;
            for a in -1..4 {
                for b in -1..4 {
                    for c in -1..4 {
                        let node = want.base + IVec3::new(a, b, c);
                        match (gpu_node(node), oracle_node(node)) {
                            (Some(g), Some(w)) => {
                                worst = worst
                                    .max((g.0 - w.0).abs())
                                    .max((g.1 - w.1).abs().max_element())
                                    .max((g.2 - w.2).abs().max_element());
                            }
                            (Some(g), None) => {
                                worst = worst.max(g.0.abs()).max(g.1.abs().max_element())
                            }
                            (None, Some(w)) => {
                                worst = worst.max(w.0.abs()).max(w.1.abs().max_element())
                            }
                            (None, None) => {}
                        }
                    }
                }
            }
            assert!(
                worst <= 16.0 * tol,
                "x = {x}, Δx = {dx}: {worst:e} > 16·{tol:e} on {}",
                backend(gpu)
            );
            e_w = e_w.max(worst / tol);
            let (mut sum, mut gsum, mut inertia) = (0.0, DVec3::ZERO, DMat3::ZERO);
            for (n, _) in offsets.iter().enumerate() {
                let w = out[o + 6 + n] as f64;
                let d = vec_at(&out, o + 114 + 3 * n) / *dx;
                sum += w;
                gsum += vec_at(&out, o + 33 + 3 * n) * *dx;
                inertia += DMat3::from_cols(d * d.x, d * d.y, d * d.z) * w;
            }
            e_sum = e_sum.max((sum - 1.0).abs()).max(gsum.abs().max_element());
            e_mls = e_mls.max(max_abs(inertia - DMat3::IDENTITY * 0.25) / 0.25);
        }
        println!(
            "bspline on {} ({} particles): per-node |Δw|, |Δ∇w|·Δx, |Δd|/Δx ≤ {e_w:.2} ε (1 + |x|/Δx); \
             |Σw − 1|, |Σ∇w| ≤ {e_sum:.2e}; MLS Σ w d dᵀ vs Δx²/4 I ≤ {e_mls:.2e} relative; \
             {shifted} bases shifted by round-off",
            backend(gpu),
            cases.len()
        );
        assert!(e_sum <= 1e-6 && e_mls <= 1e-5, "{e_sum:e} {e_mls:e}");
    }
}

// ---------------------------------------------------------------------------------------
// NACC return mapping

mod common;
use common::{paper_materials as nacc_materials, VARIANTS};

fn variant_name(v: Case3Variant) -> String {
    match v {
        Case3Variant::Center => "center".into(),
        Case3Variant::Continuous { k } => format!("continuous{{k={k}}}"),
        Case3Variant::ClosestPoint => "closest_point".into(),
    }
}

/// The material the GPU sees, as f64 oracle parameters: κ, μ rounded to f32 exactly as
/// [`NaccMaterialGpu`] holds them (E, ν chosen back so that the oracle's κ, μ are those).
fn params_as_gpu(m: &NaccMaterialGpu) -> NaccParams {
    let (kappa, mu) = (m.kappa as f64, m.mu as f64);
    // E = 9κμ/(3κ + μ), ν = (3κ − 2μ)/(2(3κ + μ))
    NaccParams {
        e: 9.0 * kappa * mu / (3.0 * kappa + mu),
        nu: (3.0 * kappa - 2.0 * mu) / (2.0 * (3.0 * kappa + mu)),
        alpha0: 0.0,
        beta: m.beta as f64,
        xi: m.xi as f64,
        m_slope: m.m_slope as f64,
    }
}

/// A trial elastic gradient: mostly principal stretches in [0.6, 1.5] (compression,
/// tension, shear: all four cases), some mild ones in [0.95, 1.05], and 5% nearly flat or
/// inverted ones (σ₃ ∈ [−0.9, −0.05] or 5e-5) that exercise the σ clamp.
fn nacc_trial(r: &mut SplitMix64) -> DMat3 {
    let u = r.uniform();
    let s = if u < 0.80 {
        DVec3::new(r.uniform(), r.uniform(), r.uniform()) * 0.9 + 0.6
    } else if u < 0.95 {
        DVec3::new(r.uniform(), r.uniform(), r.uniform()) * 0.1 + 0.95
    } else {
        let s3 = if r.uniform() < 0.5 {
            -0.05 - 0.85 * r.uniform()
        } else {
            5e-5
        };
        DVec3::new(0.6 + 0.9 * r.uniform(), 0.6 + 0.9 * r.uniform(), s3)
    };
    random_rotation(r) * DMat3::from_diagonal(s) * random_rotation(r).transpose()
}

/// A trial F whose (p, q) lies exactly (in f64, before rounding to f32) on a case
/// boundary of the yield ellipse for α: on the surface (elastic vs plastic), or outside
/// it at p = p0 (upper tip vs interior) or p = −βp0 (lower tip vs interior). Built from a
/// random trial's U, V and deviator direction with the oracle's own `stretches_from_pq`.
fn boundary_trial(r: &mut SplitMix64, params: &NaccParams, alpha: f64) -> DMat3 {
    let (kappa, mu) = (params.kappa(), params.mu());
    let ell = params.ellipse(alpha);
    let (a, b) = (ell.half_width(), ell.half_height());
    let base = random_rotation(r)
        * DMat3::from_diagonal(DVec3::new(r.uniform(), r.uniform(), r.uniform()) * 0.9 + 0.6)
        * random_rotation(r).transpose();
    let svd = svd3(base);
    let trial = principal_state(svd.sigma, kappa, mu);
    let outside = b * (0.05 + 3.0 * r.uniform());
    let which = r.uniform();
    let (mut p, mut q) = if which < 0.5 {
        let theta = std::f64::consts::PI * r.uniform();
        (ell.center() + a * theta.cos(), b * theta.sin())
    } else if which < 0.75 {
        (ell.p0, outside)
    } else {
        (-ell.beta * ell.p0, outside)
    };
    if p >= 0.45 * kappa {
        // no J_E for p ≥ κ/2: take the lower tip instead
        (p, q) = (-ell.beta * ell.p0, outside);
    }
    let sigma = stretches_from_pq(&trial, p, q, kappa, mu);
    svd.u * DMat3::from_diagonal(sigma) * svd.v.transpose()
}

/// Tolerances (ε = 2⁻²³). p = κ/2 (1 − J²) resolves only ~ε κ in f32, so everything is
/// judged on the scale of κ (plus p0 where p0 > κ), never of p0 alone:
/// - case: identical to the oracle except for trial states within 2e-5 (κ max(1, J²) + q_tr)
///   (the f32 resolution of the trial state, below) of the boundary between the two cases (|y|/‖∇y‖ for elastic vs plastic, |p_tr − p0| or |p_tr + βp0|
///   for a tip vs interior); mismatches are at most 0.1% of the random inputs (10% of the
///   inputs are constructed on a boundary, where either answer is right and a large
///   fraction differs: it is reported, not bounded);
/// - trial p, q: |Δ| ≤ 2e-5 (κ max(1, J²) + q_tr);
/// - returned p, q (same case): |Δ| ≤ 2e-5 (κ + p0) + 2 S_pq;
/// - F_new: ‖ΔF‖_max ≤ (2e-5 c + 2 S_σ) ‖F‖_max, c = max(1, σ₁/(σ₂ + σ₃)) for an inverted
///   trial F (σ₃ < 0: U Vᵀ is determined only to ε c), 1 otherwise; bit for bit F_trial
///   when elastic and no σ was clamped;
/// - α_new: |Δα| ≤ 2e-5 + 2 S_α (α is a log: this is the relative error of J_tr/J_new);
///   bit for bit when elastic;
/// - the GPU's F_new, re-evaluated in f64, lies within 2e-5 (κ max(1, J²) + q) c' of the
///   yield surface, c' = σ₁/σ₃ of F_new (an f32 F_new defines σ₃ only to ~ε σ₁, and its
///   (p, q) only to that times κ J² + q).
///
/// S is the oracle's own spread ([`oracle_spread`]): how far its result moves when the
/// trial (p, q) moves by 4e-6 (κ max(1, J²) + q_tr) and p0 by 4e-6 p0, a few times their
/// f32 errors. It is negligible except (a) next to the tips, where the mapping is only
/// Hölder-½ continuous (the ellipse is vertical there) and `continuous{k}` is steep for
/// large k, and (b) where p_new approaches κ/2, where J_E(p) = sqrt(1 − 2p/κ) amplifies
/// the error of p by 1/J_E² (after strong hardening, p0 → κ/2). There any f32 evaluation
/// inherits the amplified round-off of its inputs.
const NACC_TOL: f64 = 2e-5;
const NACC_DELTA: f64 = 4e-6;
const NACC_MISMATCH_FRACTION: f64 = 1e-3;

/// The oracle's spread under trial perturbations (see the tolerances above).
#[derive(Default)]
struct Spread {
    pq: f64,
    sigma: f64,
    alpha: f64,
}

fn oracle_spread(
    params: &NaccParams,
    ell: &YieldEllipse,
    variant: Case3Variant,
    trial: &PrincipalState,
    want: &PlasticReturn,
    delta: f64,
) -> Spread {
    let (kappa, mu) = (params.kappa(), params.mu());
    let sigma0 = stretches_from_pq(trial, want.p, want.q, kappa, mu);
    let ln_j0 = j_from_pressure(want.p, kappa).ln();
    let mut s = Spread::default();
    let steps = [-1.0, 0.0, 1.0];
    for (i, (dp, dq)) in steps
        .iter()
        .flat_map(|a| steps.iter().map(move |b| (*a, *b)))
        .enumerate()
    {
        // every trial perturbation with p0 as is, and p0 ± its own f32 error bound
        let dp0 = [0.0, -1.0, 1.0][i % 3] * NACC_DELTA * ell.p0;
        let perturbed = YieldEllipse {
            p0: ell.p0 + dp0,
            ..*ell
        };
        let (p, q, case) = project_pq(
            &perturbed,
            trial.p + dp * delta,
            (trial.q + dq * delta).max(0.0),
            variant,
        );
        if case != want.case {
            continue;
        }
        s.pq = s.pq.max((p - want.p).abs()).max((q - want.q).abs());
        let sig = stretches_from_pq(trial, p, q, kappa, mu);
        s.sigma = s
            .sigma
            .max((sig - sigma0).abs().max_element() / sigma0.max_element());
        s.alpha = s.alpha.max((j_from_pressure(p, kappa).ln() - ln_j0).abs());
    }
    s
}

/// |y| / ‖∇y‖ / κ: the distance of (p, q) from the yield surface, in units of κ.
fn surface_distance(ell: &YieldEllipse, p: f64, q: f64, kappa: f64) -> f64 {
    let m2 = ell.m_slope * ell.m_slope;
    let grad = (2.0 * m2 * (p - ell.center()))
        .hypot(2.0 * (1.0 + 2.0 * ell.beta) * q)
        .max(1e-300);
    ell.y(p, q).abs() / grad / kappa
}

/// Worst error and worst ratio to the allowed error, of one quantity.
#[derive(Default)]
struct Worst {
    /// largest error in its base unit, over inputs where the oracle's spread is negligible
    plain: f64,
    /// largest error / allowed error, over all inputs
    ratio: f64,
}

impl Worst {
    fn add(&mut self, err: f64, base: f64, spread: f64, well_conditioned: bool) -> bool {
        if well_conditioned {
            self.plain = self.plain.max(err / base);
        }
        let ratio = err / (NACC_TOL * base + 2.0 * spread);
        self.ratio = self.ratio.max(ratio);
        ratio <= 1.0
    }
}

#[test]
fn nacc_return_map_matches_the_oracle() {
    let mut r = SplitMix64::new(404);
    let materials = nacc_materials();
    let gpu_materials: Vec<NaccMaterialGpu> = VARIANTS
        .iter()
        .flat_map(|v| materials.iter().map(move |m| NaccMaterialGpu::new(m, *v)))
        .collect();
    let per_variant = 4200;
    let mut cases = Vec::new();
    let mut flat = Vec::new();
    for vi in 0..VARIANTS.len() {
        for i in 0..per_variant {
            let mi = vi * materials.len() + i % materials.len();
            let alpha = if i % 50 == 7 {
                -5.0 - 10.0 * r.uniform() // p0 at the sinh clamp
            } else {
                -0.6 + 0.8 * r.uniform()
            } as f32;
            let params = params_as_gpu(&gpu_materials[mi]);
            let on_boundary = i % 10 == 3;
            let f = if on_boundary {
                boundary_trial(&mut r, &params, alpha as f64)
            } else {
                nacc_trial(&mut r)
            };
            let f = round_f32(f);
            push_mat(&mut flat, f);
            flat.extend([alpha, mi as f32]);
            cases.push((vi, mi, f, alpha as f64, on_boundary));
        }
    }
    let oracle: Vec<_> = cases
        .iter()
        .map(|(vi, mi, f, alpha, _)| {
            let params = params_as_gpu(&gpu_materials[*mi]);
            return_map(*f, *alpha, &params, VARIANTS[*vi])
        })
        .collect();
    let extra = format!(
        "{}\n@group(0) @binding(2) var<storage, read> materials: array<NaccMaterial>;",
        splatter::sim::model::wgsl()
    );
    let body = "
    let out = nacc_return_map(in_mat3(ib), in1(ib + 9u), materials[u32(in1(ib + 10u))]);
    out_mat3(ob, out.f);
    out1(ob + 9u, out.alpha);
    out1(ob + 10u, f32(out.case_id));
    out1(ob + 11u, out.p_trial);
    out1(ob + 12u, out.q_trial);
    out1(ob + 13u, out.p);
    out1(ob + 14u, out.q);";
    let src = harness(11, 15, &extra, body);
    for gpu in gpus() {
        let t = Instant::now();
        let out = run(
            gpu,
            "nacc harness",
            &src,
            &flat,
            (11, 15),
            Some(bytemuck::cast_slice(&gpu_materials)),
        );
        let gpu_ms = t.elapsed().as_secs_f64() * 1e3;
        for (vi, variant) in VARIANTS.iter().enumerate() {
            let mut counts = [0usize; 4];
            let (mut n, mut worst_boundary, mut amplified) = (0, 0.0f64, 0);
            // [random, on a boundary]: inputs and case mismatches
            let (mut inputs, mut mismatches) = ([0usize; 2], [0usize; 2]);
            let (mut e_trial, mut e_surface) = (0.0f64, 0.0f64);
            let (mut w_pq, mut w_f, mut w_alpha) =
                (Worst::default(), Worst::default(), Worst::default());
            for (i, ((cvi, mi, f, alpha, on_boundary), want)) in
                cases.iter().zip(&oracle).enumerate()
            {
                if *cvi != vi {
                    continue;
                }
                n += 1;
                inputs[*on_boundary as usize] += 1;
                let o = i * 15;
                let params = params_as_gpu(&gpu_materials[*mi]);
                let (kappa, mu) = (params.kappa(), params.mu());
                let ell = params.ellipse(*alpha);
                let got_f = mat_at(&out, o);
                let got_alpha = out[o + 9] as f64;
                let got_case = nacc_model::return_case(out[o + 10] as u32).expect("case code");
                let (p_tr, q_tr, p, q) = (
                    out[o + 11] as f64,
                    out[o + 12] as f64,
                    out[o + 13] as f64,
                    out[o + 14] as f64,
                );
                let ctx = || {
                    format!(
                        "input {i}: F = {f}, α = {alpha}, {params:?}, {}, on {}: GPU {got_case:?} \
                         (p, q) = ({p}, {q}), α = {got_alpha}, F = {got_f}; oracle {want:?}",
                        variant_name(*variant),
                        backend(gpu)
                    )
                };
                counts[want.case as usize] += 1;
                let svd = svd3(*f);
                let trial = principal_state(svd.sigma.max(DVec3::splat(SIGMA_MIN)), kappa, mu);
                let scale_tr = kappa * (trial.j * trial.j).max(1.0) + trial.q;
                let e = (p_tr - want.p_trial).abs().max((q_tr - want.q_trial).abs()) / scale_tr;
                assert!(e <= NACC_TOL, "trial p, q: {e:e}: {}", ctx());
                e_trial = e_trial.max(e);
                if got_case != want.case {
                    mismatches[*on_boundary as usize] += 1;
                    use ReturnCase::*;
                    let d = match (got_case, want.case) {
                        (Elastic, _) | (_, Elastic) => {
                            surface_distance(&ell, want.p_trial, want.q_trial, 1.0)
                        }
                        (UpperTip, Interior) | (Interior, UpperTip) => {
                            (want.p_trial - ell.p0).abs()
                        }
                        (LowerTip, Interior) | (Interior, LowerTip) => {
                            (want.p_trial + ell.beta * ell.p0).abs()
                        }
                        _ => f64::INFINITY,
                    } / scale_tr;
                    worst_boundary = worst_boundary.max(d);
                    assert!(
                        d <= NACC_TOL,
                        "case mismatch {d:e}·scale from the boundary: {}",
                        ctx()
                    );
                    continue;
                }
                if want.case == ReturnCase::Elastic {
                    assert_eq!(got_alpha, *alpha, "{}", ctx());
                    if want.f == *f {
                        assert_eq!(got_f, *f, "{}", ctx());
                    } else {
                        let e = max_abs(got_f - want.f) / max_abs(want.f);
                        assert!(w_f.add(e, 1.0, 0.0, true), "clamped F: {e:e}: {}", ctx());
                    }
                    continue;
                }
                let spread =
                    oracle_spread(&params, &ell, *variant, &trial, want, NACC_DELTA * scale_tr);
                let scale_pq = kappa + ell.p0;
                let well = spread.pq <= 0.5 * NACC_TOL * scale_pq
                    && spread.sigma <= 0.5 * NACC_TOL
                    && spread.alpha <= 0.5 * NACC_TOL;
                if !well {
                    amplified += 1;
                }
                let e = (p - want.p).abs().max((q - want.q).abs());
                assert!(w_pq.add(e, scale_pq, spread.pq, well), "p, q: {}", ctx());
                // an inverted trial F (σ₃ < 0) determines U Vᵀ only to ε σ₁/(σ₂ + σ₃)
                let s = svd.sigma;
                let c = if s.z < 0.0 {
                    (s.x / (s.y + s.z)).max(1.0)
                } else {
                    1.0
                };
                let e = max_abs(got_f - want.f) / max_abs(want.f);
                assert!(w_f.add(e, c, spread.sigma, well), "F: {}", ctx());
                let e = (got_alpha - want.alpha).abs();
                assert!(w_alpha.add(e, 1.0, spread.alpha, well), "α: {}", ctx());
                // The GPU's F_new lands on the yield surface of p0(α_start) (not checked
                // where p_new ≥ κ/2 has no J_E, or where σ_new is near the clamp).
                let s_new = svd3(got_f).sigma;
                if want.p < 0.49 * kappa && s_new.z > 2e-4 {
                    let st = principal_state(s_new, kappa, mu);
                    let scale = (st.j * st.j).max(1.0) + st.q / kappa;
                    let d = surface_distance(&ell, st.p, st.q, kappa) / (scale * s_new.x / s_new.z);
                    assert!(d <= NACC_TOL, "surface {d:e}: {}", ctx());
                    e_surface = e_surface.max(d);
                }
            }
            let fraction = mismatches[0] as f64 / inputs[0] as f64;
            let fraction_boundary = mismatches[1] as f64 / inputs[1] as f64;
            println!(
                "nacc {} on {} ({n} trials; oracle cases [elastic, upper, lower, interior] = \
                 {counts:?}):\n  case mismatches: {} of {} random inputs ({:.3}%), {} of {} \
                 inputs constructed on a boundary ({:.1}%), all within {worst_boundary:.1e}·scale \
                 of it; trial |Δp|,|Δq| ≤ {e_trial:.1e}·scale; returned |Δp|,|Δq| ≤ \
                 {:.1e}·(κ + p0), ‖ΔF‖ ≤ {:.1e}·c·‖F‖, |Δα| ≤ {:.1e} where the oracle's spread \
                 is negligible; {amplified} inputs with an amplified spread; worst error / \
                 allowed: p,q {:.2}, F {:.2}, α {:.2}; GPU F_new within {e_surface:.1e}·(κJ² + q)·c' \
                 of the surface",
                variant_name(*variant),
                backend(gpu),
                mismatches[0],
                inputs[0],
                fraction * 100.0,
                mismatches[1],
                inputs[1],
                fraction_boundary * 100.0,
                w_pq.plain,
                w_f.plain,
                w_alpha.plain,
                w_pq.ratio,
                w_f.ratio,
                w_alpha.ratio,
            );
            assert!(fraction <= NACC_MISMATCH_FRACTION, "{fraction}");
            assert!(counts.iter().all(|c| *c > 100), "{counts:?}");
        }
        println!("nacc harness on {}: {gpu_ms:.0} ms", backend(gpu));
    }
}

/// p0(α) = κ (ε₀ + sinh(min(ξ max(−α, 0), 20))) against the oracle, α from −15 (sinh
/// clamp) through tiny negative values to positive ones (the floor κ ε₀): relative error
/// ≤ 4 ε (1 + x), x the sinh argument (ξα itself is rounded to f32, and sinh amplifies a
/// relative error of its argument by x coth x ≤ 1 + x). For contrast it reports WGSL's
/// builtin sinh on the same arguments, which the spec lets drivers evaluate as
/// (eˣ − e⁻ˣ)/2 (relative error ~ε/x for small x; measured: up to 5, i.e. 500%, on
/// lavapipe and llvmpipe at x ~ 1e-8), next to `sim_sinh` (measured ≤ 8.4e-7 relative,
/// from WGSL's exp, accurate to 3 + 2x ulp, on the large arguments).
#[test]
fn nacc_p0_matches_the_oracle() {
    let mut r = SplitMix64::new(505);
    let base = nacc_materials()[0];
    let materials: Vec<NaccMaterialGpu> = [0.5, 1.0, 2.0, 5.0]
        .map(|xi| NaccMaterialGpu::new(&NaccParams { xi, ..base }, Case3Variant::Center))
        .to_vec();
    let mut flat = Vec::new();
    for i in 0..6000 {
        let alpha = match i % 3 {
            0 => -(10f64.powf(-8.0 + 7.0 * r.uniform())),
            1 => -15.0 * r.uniform(),
            _ => r.uniform(),
        };
        flat.extend([alpha as f32, (i % materials.len()) as f32]);
    }
    let extra = format!(
        "{}\n@group(0) @binding(2) var<storage, read> materials: array<NaccMaterial>;",
        splatter::sim::model::wgsl()
    );
    let body = "
    let alpha = in1(ib);
    let mat = materials[u32(in1(ib + 1u))];
    let arg = min(mat.xi * max(-alpha, 0.0), NACC_SINH_ARG_MAX);
    out1(ob, nacc_p0(alpha, mat));
    out1(ob + 1u, sim_sinh(arg));
    out1(ob + 2u, sinh(arg));";
    let src = harness(2, 3, &extra, body);
    for gpu in gpus() {
        let out = run(
            gpu,
            "p0 harness",
            &src,
            &flat,
            (2, 3),
            Some(bytemuck::cast_slice(&materials)),
        );
        let (mut e_p0, mut e_sinh, mut e_builtin) = (0.0f64, 0.0f64, 0.0f64);
        for (i, rec) in flat.chunks(2).enumerate() {
            let (alpha, m) = (rec[0] as f64, &materials[rec[1] as usize]);
            let params = params_as_gpu(m);
            let x = (params.xi * (-alpha).max(0.0)).min(20.0);
            let want = params.p0(alpha);
            let e = (out[3 * i] as f64 - want).abs() / want / (EPS * (1.0 + x));
            assert!(
                e <= 4.0,
                "p0({alpha}) ξ = {}: {e} on {}",
                params.xi,
                backend(gpu)
            );
            e_p0 = e_p0.max(e);
            // the argument as the GPU rounds it
            let x32 = (m.xi * (-rec[0]).max(0.0)).min(20.0) as f64;
            if x32 > 0.0 {
                let s = x32.sinh();
                e_sinh = e_sinh.max((out[3 * i + 1] as f64 - s).abs() / s);
                e_builtin = e_builtin.max((out[3 * i + 2] as f64 - s).abs() / s);
            }
        }
        println!(
            "nacc_p0 on {} ({} α): relative error ≤ {e_p0:.2} ε (1 + x); sim_sinh relative error \
             ≤ {e_sinh:.1e}, the builtin sinh ≤ {e_builtin:.1e}",
            backend(gpu),
            flat.len() / 2
        );
    }
}

// ---------------------------------------------------------------------------------------
// The model registry: the codes Rust gives a material reach the models they name

/// Every registered model, called through the generated dispatch with the record
/// `GpuMaterial::from_material` builds, against its own f64 oracle (`Material::kirchhoff`,
/// `Material::plasticity`): the elastic models' τ, and each plastic law's return mapping,
/// hardening and stress factor from its packed parameters. A code that named another
/// model, or parameters packed in another order than the model's WGSL reads them, fails
/// here: the models and their parameters differ by far more than the tolerance.
#[test]
fn every_registered_model_is_reached_by_its_code() {
    use splatter::sim::gpu::GpuMaterial;
    use splatter::sim::{model, ElasticModel, Material, PlasticModel};
    let mut r = SplitMix64::new(404);
    let n = 2000;
    let mut flat = Vec::new();
    for i in 0..n {
        // Half at moderate strains (J > 0, where the models differ at second order and
        // every law yields), half near the identity (where some stay elastic).
        let amp = if i % 2 == 0 { 0.8 } else { 0.04 };
        let stretch = DVec3::new(r.uniform(), r.uniform(), r.uniform()) * amp + (1.0 - amp * 0.5);
        let f = round_f32(random_rotation(&mut r) * DMat3::from_diagonal(stretch));
        push_mat(&mut flat, f);
    }
    // Each material with the hardening state α it is tried at.
    let mut materials: Vec<(Material, f64)> = ElasticModel::ALL
        .iter()
        .map(|&m| (Material::elastic(m, 2000.0, 0.38), 0.0))
        .collect();
    // Every registered law at its own example material (`PlasticLaw::EXAMPLE`).
    for &law in PlasticModel::LAWS {
        let (plastic, alpha) = law.example(2000.0, 0.3).expect("a law has an example");
        materials.push((Material::with_plastic(plastic, 2000.0, 0.3), alpha));
    }

    let records: Vec<GpuMaterial> = materials
        .iter()
        .map(|(m, _)| GpuMaterial::from_material(m))
        .collect();
    let alphas: Vec<String> = materials.iter().map(|(_, a)| format!("{a:?}")).collect();
    let extra = format!(
        "{}\n@group(0) @binding(2) var<storage, read> materials: array<SimMaterial>;\n\
         const ALPHAS = array<f32, {}>({});",
        model::wgsl(),
        materials.len(),
        alphas.join(", ")
    );
    // Per material: τ·scale (9), the plastic F (9) and α (1).
    let body = "
    let f = in_mat3(ib);
    for (var k = 0u; k < arrayLength(&materials); k++) {
        let m = materials[k];
        let a = ALPHAS[k];
        let o = ob + k * 19u;
        out_mat3(o, material_stress(m, f, a));
        let p = material_plasticity(m, f, a, item);
        out_mat3(o + 9u, p.f);
        out1(o + 18u, p.alpha);
    }";
    let stride = 19 * records.len();
    let src = harness(9, stride, &extra, body);
    for gpu in gpus() {
        let out = run(
            gpu,
            "registry harness",
            &src,
            &flat,
            (9, stride),
            Some(bytemuck::cast_slice(&records)),
        );
        let mut worst_tau = 0.0f64;
        let mut report = Vec::new();
        for (k, (m, alpha)) in materials.iter().enumerate() {
            let (mut yielded, mut worst_f, mut worst_alpha) = (0, 0.0f64, 0.0f64);
            for i in 0..n {
                let f = mat_at(&flat, i * 9);
                let o = i * stride + k * 19;
                let want = m.kirchhoff(f, *alpha);
                let err = max_abs(mat_at(&out, o) - want) / max_abs(want).max(1.0);
                assert!(
                    err < 5e-4,
                    "{:?}/{:?} (codes {}/{}): τ off by {err:e} for {f} on {}",
                    m.elastic_model(),
                    m.plastic_model(),
                    records[k].elastic,
                    records[k].plastic,
                    backend(gpu)
                );
                worst_tau = worst_tau.max(err);
                let (want_f, want_alpha) = m.plasticity_at(f, *alpha, i as u32);
                let (got_f, got_alpha) = (mat_at(&out, o + 9), f64::from(out[o + 18]));
                let err_f = max_abs(got_f - want_f);
                let err_alpha = (got_alpha - want_alpha).abs();
                assert!(
                    err_f < 1e-5 && err_alpha < 1e-5,
                    "{:?} (code {}): F off by {err_f:e}, α by {err_alpha:e} for {f} on {}",
                    m.plastic_model(),
                    records[k].plastic,
                    backend(gpu)
                );
                worst_f = worst_f.max(err_f);
                worst_alpha = worst_alpha.max(err_alpha);
                yielded += usize::from(max_abs(want_f - f) > 1e-5);
            }
            if m.plastic_model() == PlasticModel::None {
                assert_eq!(yielded, 0, "{:?} yielded", m.elastic_model());
            } else {
                assert!(
                    yielded > n / 20 && yielded < n - n / 20,
                    "test setup: {:?} must yield on some F and not on others ({yielded} of {n})",
                    m.plastic_model()
                );
                report.push(format!(
                    "{} ({yielded} of {n} yielded, F ≤ {worst_f:.1e}, α ≤ {worst_alpha:.1e})",
                    m.plastic_model().name()
                ));
            }
        }
        println!(
            "registry on {}: {} elastic models, τ ≤ {worst_tau:.1e} relative; {}",
            backend(gpu),
            ElasticModel::ALL.len(),
            report.join("; ")
        );
    }
}
