//! Loading a large binary 3DGS PLY (SH degree 3).
//!
//! `cargo bench --bench ply_load`; `SPLATTER_BENCH_PLY_N` overrides the Gaussian count
//! (default 1 000 000) and `SPLATTER_BENCH_PLY_RUNS` the number of timed runs (default 5).

use std::time::Instant;

use glam::{Quat, Vec3};
use splatter::splat::ply::{read_ply, read_ply_bytes, write_ply, PlyFormat};
use splatter::splat::GaussianCloud;

fn env_usize(name: &str, default: usize) -> usize {
    match std::env::var(name) {
        Ok(v) => v
            .trim()
            .parse()
            .unwrap_or_else(|_| panic!("{name}={v:?} is not a count")),
        Err(_) => default,
    }
}

/// Cheap deterministic value in [-1, 1) from an index.
fn hash(i: u64) -> f32 {
    let mut z = i.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    ((z >> 40) as f32 / (1u64 << 23) as f32) - 1.0
}

fn cloud(n: usize) -> GaussianCloud {
    let h = |i: usize, k: u64| hash(i as u64 * 64 + k);
    GaussianCloud {
        positions: (0..n)
            .map(|i| Vec3::new(h(i, 0), h(i, 1), h(i, 2)) * 10.0)
            .collect(),
        scales: (0..n)
            .map(|i| Vec3::new(h(i, 3), h(i, 4), h(i, 5)).map(|v| (v * 3.0 - 3.0).exp()))
            .collect(),
        rotations: (0..n)
            .map(|i| Quat::from_xyzw(h(i, 6), h(i, 7), h(i, 8), h(i, 9) + 1.5).normalize())
            .collect(),
        opacities: (0..n).map(|i| 0.5 + 0.49 * h(i, 10)).collect(),
        sh_degree: 3,
        sh: (0..n * 48).map(|j| 0.5 * hash(j as u64 ^ 0xABCD)).collect(),
        normals: Vec::new(),
        ..Default::default()
    }
}

fn main() {
    let n = env_usize("SPLATTER_BENCH_PLY_N", 1_000_000);
    let runs = env_usize("SPLATTER_BENCH_PLY_RUNS", 5).max(1);
    let dir = tempfile::tempdir().expect("temporary directory");
    let path = dir.path().join("bench.ply");

    let t = Instant::now();
    let c = cloud(n);
    write_ply(&path, &c, PlyFormat::BinaryLittleEndian).expect("write the bench PLY");
    let size = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
    eprintln!(
        "ply_load: wrote {n} Gaussians ({:.1} MB) in {:.0} ms",
        size as f64 / 1e6,
        t.elapsed().as_secs_f64() * 1e3
    );
    drop(c);

    let mut best = f64::INFINITY;
    for run in 0..runs {
        let t = Instant::now();
        let (cloud, report) = read_ply(&path).expect("read the bench PLY");
        let ms = t.elapsed().as_secs_f64() * 1e3;
        assert_eq!(cloud.len(), n);
        assert_eq!(report.skipped_nonfinite + report.skipped_degenerate, 0);
        eprintln!("ply_load: run {run}: {ms:.1} ms");
        best = best.min(ms);
        drop(cloud);
    }
    println!("ply_load: {n} gaussians, degree 3, {best:.1} ms (best of {runs})");

    // The same without the file read: decoding alone.
    let bytes = std::fs::read(&path).expect("read the bench PLY");
    let mut best_decode = f64::INFINITY;
    for _ in 0..runs {
        let t = Instant::now();
        let (cloud, _) = read_ply_bytes(&bytes, "bench.ply").expect("decode the bench PLY");
        best_decode = best_decode.min(t.elapsed().as_secs_f64() * 1e3);
        assert_eq!(cloud.len(), n);
    }
    println!("ply_load: decode only (bytes in memory) {best_decode:.1} ms (best of {runs})");
}
