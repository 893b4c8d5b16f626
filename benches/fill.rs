//! Interior filling on adversarial input, against a time budget.
//!
//! `cargo bench --bench fill`. Four inputs of `SPLATTER_BENCH_FILL_N` Gaussians (default
//! 1 000 000), filled at a spacing that gives about 200³ voxels: a closed surface-only
//! sphere; the same sphere cut open (a hemisphere); a random cloud whose covariances are
//! degenerate (NaN, negative definite, 1e30 wide, zero) in turn; and every Gaussian at the
//! same point but one. Each must finish within `SPLATTER_BENCH_FILL_BUDGET_S` seconds
//! (default 60, for a 2-core machine); the process exits with status 1 otherwise.

use std::time::Instant;

use glam::{DVec3, Quat, Vec3};
use splatter::scene::fill::{fill, FillInput, InsideTest};

fn env_f64(name: &str, default: f64) -> f64 {
    match std::env::var(name) {
        Ok(v) => v
            .trim()
            .parse()
            .unwrap_or_else(|_| panic!("{name}={v:?} is not a number")),
        Err(_) => default,
    }
}

fn sym(m: glam::Mat3) -> [f32; 6] {
    let s = m * m.transpose();
    [
        s.x_axis.x, s.y_axis.x, s.z_axis.x, s.y_axis.y, s.z_axis.y, s.z_axis.z,
    ]
}

/// Tangent disks on a Fibonacci sphere of radius 1; `open` keeps z > −0.5 only.
fn sphere(n: usize, open: bool) -> (Vec<Vec3>, Vec<[f32; 6]>) {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    let disk = (4.0 * std::f32::consts::PI / n as f32).sqrt() * 0.6;
    let mut means = Vec::with_capacity(n);
    let mut covs = Vec::with_capacity(n);
    for i in 0..n {
        let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
        if open && z < -0.5 {
            continue;
        }
        let rho = (1.0 - z * z).sqrt();
        let phi = golden * i as f32;
        let d = Vec3::new(rho * phi.cos(), rho * phi.sin(), z);
        means.push(d);
        let r = glam::Mat3::from_quat(Quat::from_rotation_arc(Vec3::Z, d));
        covs.push(sym(r * glam::Mat3::from_diagonal(Vec3::new(
            disk,
            disk,
            disk * 0.01,
        ))));
    }
    (means, covs)
}

fn hash(i: u64) -> f32 {
    let mut z = i.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    ((z >> 40) as f32 / (1u64 << 23) as f32) - 1.0
}

/// A named adversarial input: means and upper-triangle covariances.
type Case = (&'static str, Vec<Vec3>, Vec<[f32; 6]>);

fn main() {
    let n = env_f64("SPLATTER_BENCH_FILL_N", 1e6) as usize;
    let budget = env_f64("SPLATTER_BENCH_FILL_BUDGET_S", 60.0);
    let spacing = 2.2 / 200.0;
    let mut cases: Vec<Case> = Vec::new();
    let (m, c) = sphere(n, false);
    cases.push(("closed surface-only sphere", m, c));
    let (m, c) = sphere(n, true);
    cases.push(("open surface (sphere cut at z = -0.5)", m, c));
    let means: Vec<Vec3> = (0..n as u64)
        .map(|i| Vec3::new(hash(3 * i), hash(3 * i + 1), hash(3 * i + 2)))
        .collect();
    let covs: Vec<[f32; 6]> = (0..n)
        .map(|i| match i % 4 {
            0 => [f32::NAN; 6],
            1 => [-1.0, 0.0, 0.0, -1.0, 0.0, -1.0],
            2 => [1e30, 0.0, 0.0, 1e30, 0.0, 1e30],
            _ => [0.0; 6],
        })
        .collect();
    cases.push(("degenerate covariances in a random cloud", means, covs));
    let mut means = vec![Vec3::splat(0.25); n];
    means[0] = Vec3::splat(-1.0);
    cases.push((
        "all Gaussians at one point but one",
        means,
        vec![[1e-4, 0.0, 0.0, 1e-4, 0.0, 1e-4]; n],
    ));

    let all = |_: DVec3| true;
    let mut over = false;
    println!(
        "fill bench: {n} Gaussians per case, spacing {spacing:.4}, budget {budget} s per case"
    );
    for (name, means, covs) in &cases {
        let opacities = vec![0.9f32; means.len()];
        let t = Instant::now();
        let f = fill(&FillInput {
            means,
            covariances: covs,
            opacities: &opacities,
            spacing,
            inside: InsideTest::Parity,
            region: &all,
        });
        let secs = t.elapsed().as_secs_f64();
        match f {
            Ok(f) => {
                println!(
                    "  {name}: {secs:.2} s; {} Gaussians, grid {:?}, {} fill particles, {} solid voxels",
                    means.len(),
                    f.stats.dims,
                    f.points.len(),
                    f.stats.solid_voxels
                );
                for w in &f.warnings {
                    println!("    warning: {w}");
                }
            }
            Err(e) => println!("  {name}: {secs:.2} s; error: {e}"),
        }
        if secs > budget {
            println!("    OVER BUDGET ({secs:.2} s > {budget} s)");
            over = true;
        }
    }
    if over {
        std::process::exit(1);
    }
}
