//! `splatter bench …`: benchmarks with synthetic, reproducible inputs. Results go to
//! `docs/performance.md` with the adapter's name.

use std::io::Write;
use std::time::Instant;

use anyhow::Result;
use glam::{Mat3, Quat, Vec3};

use crate::gpu::GpuContext;
use crate::render::splats::sym3_from_mat3;
use crate::render::{Camera, GpuRenderer, PassSet, Splats};
use crate::rng::SplitMix64;

mod sim;
pub use sim::{
    sim_bench, sim_paths, sim_scale_bench, time_sim, SimBench, SimCase, SimModel, SimTiming,
};

/// `n` Gaussians of SH degree `degree` filling a ball of radius 1, sized like a trained
/// capture of that density (scale ≈ the mean spacing), random orientations and colours.
pub fn synthetic_splats(n: usize, degree: u32, seed: u64) -> Splats {
    Synthetic::capture_like(n, degree, seed).build()
}

/// A synthetic scene of random Gaussians: the one generator the benchmarks, the suite and
/// the renderer's tests share.
#[derive(Clone, Copy, Debug)]
pub struct Synthetic {
    pub n: usize,
    pub degree: u32,
    pub seed: u64,
    /// Means in the unit ball (else the cube [−1, 1]³).
    pub ball: bool,
    /// Standard deviations drawn from this range per axis (else capture-like: about the
    /// mean spacing, one axis flatter).
    pub scale: Option<(f32, f32)>,
    /// Random rest frames (SH are then evaluated in a rotated frame), else identity.
    pub random_frames: bool,
    /// Opacities from this value to 1.
    pub min_opacity: f32,
    /// Amplitude of the rest SH coefficients (the DC term's is 1.5).
    pub rest_sh: f32,
}

impl Synthetic {
    /// What a trained capture of `n` Gaussians in a unit ball looks like.
    pub fn capture_like(n: usize, degree: u32, seed: u64) -> Synthetic {
        Synthetic {
            n,
            degree,
            seed,
            ball: true,
            scale: None,
            random_frames: false,
            min_opacity: 0.2,
            rest_sh: 0.2,
        }
    }

    pub fn build(&self) -> Splats {
        let mut rng = SplitMix64::new(self.seed);
        let k = crate::splat::sh_coeff_count(self.degree) * 3;
        let spacing = (4.19 / self.n.max(1) as f32).cbrt();
        let mut s = Splats {
            sh_degree: self.degree,
            ..Default::default()
        };
        s.means.reserve(self.n);
        s.covariances.reserve(self.n);
        s.sh.reserve(self.n * k);
        let unit = |rng: &mut SplitMix64| rng.range(-1.0, 1.0);
        while s.means.len() < self.n {
            let p = Vec3::new(unit(&mut rng), unit(&mut rng), unit(&mut rng));
            if self.ball && p.length_squared() > 1.0 {
                continue;
            }
            let q = Quat::from_xyzw(
                unit(&mut rng),
                unit(&mut rng),
                unit(&mut rng),
                unit(&mut rng),
            )
            .normalize();
            let scale = match self.scale {
                Some((lo, hi)) => {
                    Vec3::new(rng.range(lo, hi), rng.range(lo, hi), rng.range(lo, hi))
                }
                None => {
                    Vec3::new(
                        rng.range(0.3, 1.2),
                        rng.range(0.3, 1.2),
                        rng.range(0.1, 0.6),
                    ) * spacing
                }
            };
            let m = Mat3::from_quat(q) * Mat3::from_diagonal(scale);
            s.means.push(p);
            s.covariances.push(sym3_from_mat3(m * m.transpose()));
            s.rotations.push(if self.random_frames {
                Quat::from_xyzw(unit(&mut rng), unit(&mut rng), unit(&mut rng), 1.0).normalize()
            } else {
                Quat::IDENTITY
            });
            s.opacities.push(rng.range(self.min_opacity, 1.0));
            for j in 0..k {
                let amp = if j < 3 { 1.5 } else { self.rest_sh };
                s.sh.push(rng.range(-amp, amp));
            }
        }
        s
    }
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

/// Milliseconds per frame for 100k and 1M Gaussians (degree 3) at 1920×1080 and 100k at
/// 640×360: render passes (submit to GPU idle), readback, and PNG encoding, separately;
/// the same with the alpha and depth passes, and lit.
/// With `per_pass`, one more frame per case is rendered pass by pass and broken down.
pub fn render_bench(
    gpu: &GpuContext,
    repeat: usize,
    quick: bool,
    per_pass: bool,
    out: &mut dyn Write,
) -> Result<()> {
    writeln!(out, "adapter: {}", gpu.describe())?;
    writeln!(
        out,
        "{:>9} {:>11} {:>12} {:>12} {:>10} {:>12}",
        "gaussians", "resolution", "render ms", "readback ms", "png ms", "tile pairs"
    )?;
    let mut cases = vec![(100_000usize, 640u32, 360u32), (100_000, 1920, 1080)];
    if !quick {
        cases.push((1_000_000, 1920, 1080));
    }
    let mut renderer = GpuRenderer::new(gpu);
    let mut last_n = 0;
    for (n, w, h) in cases {
        if n != last_n {
            let splats = synthetic_splats(n, 3, 7);
            renderer.upload(gpu, &splats)?;
            last_n = n;
        }
        let camera = Camera::look_at(
            Vec3::new(0.0, -2.6, 0.9),
            Vec3::ZERO,
            Vec3::Z,
            50f32.to_radians(),
            w,
            h,
        );
        let t = time_render(gpu, &mut renderer, &camera, repeat)?;
        writeln!(
            out,
            "{:>9} {:>11} {:>12.2} {:>12.2} {:>10.2} {:>12}",
            n,
            format!("{w}x{h}"),
            t.render_ms,
            t.readback_ms,
            t.png_ms,
            t.tile_pairs
        )?;
        if per_pass {
            renderer.profile_passes(true);
            let (_, t) = renderer.render_timed(gpu, &camera, Vec3::ZERO)?;
            renderer.profile_passes(false);
            let list: Vec<String> = t
                .passes
                .iter()
                .map(|(name, ms)| format!("{name} {ms:.2}"))
                .collect();
            writeln!(
                out,
                "{:>22} per pass (ms, each waited for): {}",
                "",
                list.join(", ")
            )?;
        }
        for (what, set) in [
            ("the alpha and depth passes", PassSet::ALPHA_DEPTH),
            ("all passes", PassSet::ALL),
        ] {
            renderer.set_passes(gpu, set);
            let with_passes = time_render(gpu, &mut renderer, &camera, repeat)?;
            writeln!(
                out,
                "{:>22} with {what}: render ms {:.2} ({:+.0}%), readback ms {:.2}",
                "",
                with_passes.render_ms,
                100.0 * (with_passes.render_ms / t.render_ms - 1.0),
                with_passes.readback_ms
            )?;
        }
        renderer.set_passes(gpu, PassSet::default());
        let lit = lit_frame(gpu, n, &camera, repeat)?;
        writeln!(
            out,
            "{:>22} lit, 2 lights, shadows {}³: render ms {:.2} ({:+.0}%); shadows {:.2}, shade {:.2} (each waited for); normals (CPU PCA, k = 30, once per scene) {:.0} ms",
            "",
            LIT_RESOLUTION,
            lit.render_ms,
            100.0 * (lit.render_ms / t.render_ms - 1.0),
            lit.shadows_ms,
            lit.shade_ms,
            lit.normals_ms
        )?;
        out.flush()?;
    }
    Ok(())
}

/// One timed render case (`bench render`, `splatter-lab suite`): medians over the repeats.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RenderTiming {
    pub render_ms: f64,
    pub readback_ms: f64,
    pub png_ms: f64,
    pub tile_pairs: u64,
}

/// A warm-up frame (pipelines, buffer growth), then `repeat` frames: render passes
/// (submit to GPU idle), readback and PNG encoding, each the median.
pub fn time_render(
    gpu: &GpuContext,
    renderer: &mut GpuRenderer,
    camera: &Camera,
    repeat: usize,
) -> Result<RenderTiming> {
    let (image, _) = renderer.render_timed(gpu, camera, Vec3::ZERO)?;
    let (mut render, mut readback, mut png) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..repeat.max(1) {
        let (image, t) = renderer.render_timed(gpu, camera, Vec3::ZERO)?;
        render.push(t.render_ms);
        readback.push(t.readback_ms);
        let start = Instant::now();
        crate::output::encode_png(image.width, image.height, &image.rgba)?;
        png.push(start.elapsed().as_secs_f64() * 1e3);
    }
    Ok(RenderTiming {
        render_ms: median(&mut render),
        readback_ms: median(&mut readback),
        png_ms: median(&mut png),
        tile_pairs: image.stats.intersections as u64,
    })
}

/// Shadow-volume resolution of the lit benchmark.
const LIT_RESOLUTION: u32 = 64;

struct LitTimes {
    render_ms: f64,
    shadows_ms: f64,
    shade_ms: f64,
    normals_ms: f64,
}

/// The same synthetic scene relit: PCA normals on the CPU, two point lights and
/// a shadow volume; median render time over `repeat` frames, then one frame pass by pass
/// for the cost of the shadow and shade passes.
fn lit_frame(gpu: &GpuContext, n: usize, camera: &Camera, repeat: usize) -> Result<LitTimes> {
    use crate::relight::normals::{pca_normals, DEFAULT_K};
    use crate::relight::shadow::VolumeGrid;
    use crate::relight::{oct_encode, PointLight, ShadingParams};
    use crate::render::gpu::lighting::LightingSetup;

    let splats = synthetic_splats(n, 3, 7);
    let start = Instant::now();
    let normals = pca_normals(&splats.means, DEFAULT_K);
    let normals_ms = start.elapsed().as_secs_f64() * 1e3;
    let mut renderer = GpuRenderer::new(gpu);
    renderer.upload(gpu, &splats)?;
    renderer.set_lighting(
        gpu,
        &LightingSetup {
            ambient: Vec3::splat(0.3),
            materials: vec![ShadingParams::default()],
            shading: normals.iter().map(|n| [oct_encode(*n), 0]).collect(),
            shadows: Some(VolumeGrid::covering(
                Vec3::splat(-1.0),
                Vec3::splat(1.0),
                LIT_RESOLUTION,
            )),
            max_lights: 2,
        },
    )?;
    renderer.set_lights(&[
        PointLight {
            position: Vec3::new(2.0, -1.0, 2.0),
            radiance: Vec3::new(6.0, 5.0, 4.0),
        },
        PointLight {
            position: Vec3::new(-2.0, 1.0, 1.0),
            radiance: Vec3::new(2.0, 3.0, 4.0),
        },
    ]);
    renderer.render_timed(gpu, camera, Vec3::ZERO)?;
    let mut times = Vec::new();
    for _ in 0..repeat {
        times.push(renderer.render_timed(gpu, camera, Vec3::ZERO)?.1.render_ms);
    }
    renderer.profile_passes(true);
    let (_, t) = renderer.render_timed(gpu, camera, Vec3::ZERO)?;
    let pass = |name: &str| {
        t.passes
            .iter()
            .find(|(p, _)| *p == name)
            .map_or(0.0, |(_, ms)| *ms)
    };
    Ok(LitTimes {
        render_ms: median(&mut times),
        shadows_ms: pass("shadows"),
        shade_ms: pass("shade"),
        normals_ms,
    })
}

/// Peak resident memory of this process (`VmHWM`), in bytes, where the OS reports it. On a
/// CPU driver (lavapipe) GPU buffers live in it too.
pub fn peak_memory() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

fn gib(bytes: u64) -> f64 {
    bytes as f64 / f64::from(1u32 << 30)
}

/// The GPU bytes of a scale benchmark, per `unit`, and the process's peak memory.
fn write_memory(out: &mut dyn Write, gpu_bytes: u64, count: usize, unit: &str) -> Result<()> {
    writeln!(
        out,
        "GPU buffers {:.2} GiB ({:.0} bytes/{unit}); peak memory of the process {}",
        gib(gpu_bytes),
        gpu_bytes as f64 / count.max(1) as f64,
        peak_memory().map_or("unknown".into(), |b| format!("{:.2} GiB", gib(b)))
    )?;
    Ok(())
}

/// `splatter bench render --gaussians N`: one 1920×1080 frame of `n` synthetic SH-3
/// Gaussians (arrays past one storage binding are projected and read page by page): wall
/// time, tile pairs, GPU bytes per Gaussian, peak memory, and the most Gaussians this
/// adapter's limits allow.
pub fn render_scale_bench(
    gpu: &GpuContext,
    n: usize,
    repeat: usize,
    out: &mut dyn Write,
) -> Result<()> {
    writeln!(out, "adapter: {}", gpu.describe())?;
    let most = GpuRenderer::most_gaussians(gpu);
    writeln!(
        out,
        "limits: storage binding {} MiB, buffer {} MiB: at most {most} Gaussians",
        gpu.limits.max_storage_buffer_binding_size >> 20,
        gpu.limits.max_buffer_size >> 20
    )?;
    let start = Instant::now();
    let splats = Synthetic::capture_like(n, 3, 7).build();
    let mut renderer = GpuRenderer::new(gpu);
    renderer.upload(gpu, &splats)?;
    drop(splats);
    gpu.wait()?;
    let pages = GpuRenderer::pages_for(gpu, n)?;
    writeln!(
        out,
        "{n} Gaussians (SH degree 3), {} page(s) of {}; setup (generate, upload) {:.1} s",
        pages.count,
        pages.size,
        start.elapsed().as_secs_f64()
    )?;
    let camera = Camera::look_at(
        Vec3::new(0.0, -2.6, 0.9),
        Vec3::ZERO,
        Vec3::Z,
        50f32.to_radians(),
        1920,
        1080,
    );
    let t = time_render(gpu, &mut renderer, &camera, repeat)?;
    let (image, _) = renderer.render_timed(gpu, &camera, Vec3::ZERO)?;
    writeln!(
        out,
        "1920x1080: render {:.0} ms, readback {:.1} ms, png {:.0} ms (medians of {repeat}); {} visible, {} tile pairs, {} dropped",
        t.render_ms,
        t.readback_ms,
        t.png_ms,
        image.stats.visible,
        image.stats.intersections,
        image.dropped_intersections
    )?;
    write_memory(out, renderer.gpu_bytes(), n, "Gaussian")
}

/// `splatter bench read`: the median wall time of [`crate::splat::formats::read_splats`]
/// per file, with the rate in Gaussians per second.
pub fn read_bench(files: &[std::path::PathBuf], repeat: usize, out: &mut dyn Write) -> Result<()> {
    writeln!(out, "threads: {}", rayon::current_num_threads())?;
    writeln!(
        out,
        "| file | format | Gaussians | size (MB) | read (s, median of {repeat}) | M Gaussians/s |"
    )?;
    writeln!(out, "|---|---|---:|---:|---:|---:|")?;
    for file in files {
        let size = dir_or_file_size(file);
        let mut times = Vec::with_capacity(repeat);
        let mut last = None;
        for _ in 0..repeat {
            let t = Instant::now();
            let (cloud, report) = crate::splat::formats::read_splats(file)?;
            times.push(t.elapsed().as_secs_f64());
            last = Some((cloud.len(), report));
        }
        times.sort_by(f64::total_cmp);
        let median = times[times.len() / 2];
        let (n, report) = last.expect("repeat ≥ 1");
        writeln!(
            out,
            "| {} | {} {} | {n} | {:.1} | {median:.3} | {:.2} |",
            file.display(),
            report.format,
            report.variant,
            size as f64 / 1e6,
            n as f64 / median / 1e6
        )?;
    }
    Ok(())
}

fn dir_or_file_size(path: &std::path::Path) -> u64 {
    match std::fs::read_dir(path) {
        Ok(entries) => entries
            .filter_map(|e| e.ok()?.metadata().ok())
            .map(|m| m.len())
            .sum(),
        Err(_) => std::fs::metadata(path).map_or(0, |m| m.len()),
    }
}
