//! The slosh peer of `splatter bench sim`: the fixed-corotated cube of
//! `benches/peers/taichi_mpm.py` stepped by dimforge's slosh (crate `slosh3d`) on the wgpu
//! adapter that slosh's backend picks.
//!
//! Same case as the Taichi peer: a cube of n³ particles at spacing dx/2 (8 per cell) with the
//! given density, cell width 1/cells, quadratic B-spline MLS-MPM/APIC, fixed-corotated
//! elasticity (slosh's `ElasticLinear`: τ = 2μ(F − R)Fᵀ + λ(J − 1)J I), the step Δt, gravity
//! −9.8 along y, a sticky ground and separating, frictionless walls at the unit domain's faces.
//! What is slosh's own: its sparse grid of 4³-node blocks rebuilt every step (a hash map, a
//! particle sort, indirect dispatches), its scatter P2G, its node-velocity clamp at one cell
//! per step, and walls that are rapier cuboid colliders (a node takes a collider's condition
//! within one cell of its surface, which matches the Taichi peer's two boundary nodes).
//!
//! Prints a line starting `slosh ` that says what ran, optional `pass <name>: <ms>` lines
//! (GPU timestamps, when the adapter has them), a `state:` line, and last `ms/step: <value>`.

use std::collections::BTreeMap;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use regex::Regex;
use slosh3d::math::Vector;
use slosh3d::pipeline::{MpmData, MpmPipeline, MpmPipelineKernels};
use slosh3d::rapier::prelude::{
    ColliderBuilder, ColliderHandle, ColliderSet, RigidBodyBuilder, RigidBodySet,
};
use slosh3d::re_exports::slang_hal::backend::{Backend, WebGpu};
use slosh3d::re_exports::slang_hal::{GpuTimestamps, SlangCompiler};
use slosh3d::re_exports::wgpu;
use slosh3d::solver::{
    GpuBoundaryCondition, GpuParticleModel, Particle, ParticleModel, SimulationParams,
};

type Pipeline = MpmPipeline<WebGpu, GpuParticleModel>;
type Data = MpmData<WebGpu, GpuParticleModel>;

const USAGE: &str = "usage: slosh-peer [--per-axis N] [--cells N] [--lo X Y Z] [--dt S] \
[--steps N] [--E PA] [--nu V] [--density D] [--warmup N] [--grid-blocks N] [--no-passes]";

/// The command line: the Taichi peer's arguments plus a few of this peer's own.
struct Args {
    per_axis: u32,
    cells: u32,
    lo: Option<[f64; 3]>,
    dt: f64,
    steps: u32,
    e: f64,
    nu: f64,
    density: f64,
    /// Untimed steps before the clock starts (Taichi's peer takes two).
    warmup: u32,
    /// Capacity of slosh's sparse grid, in 4³-node blocks (rounded up to a power of two).
    grid_blocks: Option<u32>,
    /// Time each pass with GPU timestamps in a second, separate run of `steps` steps.
    passes: bool,
}

impl Args {
    fn parse() -> Result<Args> {
        let mut a = Args {
            per_axis: 27,
            cells: 64,
            lo: None,
            dt: 1e-4,
            steps: 20,
            e: 2000.0,
            nu: 0.4,
            density: 2.0,
            warmup: 2,
            grid_blocks: None,
            passes: true,
        };
        let argv: Vec<String> = std::env::args().skip(1).collect();
        let mut it = argv.iter();
        fn value<T: std::str::FromStr>(
            it: &mut std::slice::Iter<'_, String>,
            flag: &str,
        ) -> Result<T> {
            let v = it.next().with_context(|| format!("{flag} needs a value"))?;
            v.parse()
                .map_err(|_| anyhow::anyhow!("{flag}: cannot read {v:?}"))
        }
        while let Some(flag) = it.next() {
            match flag.as_str() {
                "--per-axis" => a.per_axis = value(&mut it, flag)?,
                "--cells" => a.cells = value(&mut it, flag)?,
                "--lo" => {
                    a.lo = Some([
                        value(&mut it, flag)?,
                        value(&mut it, flag)?,
                        value(&mut it, flag)?,
                    ])
                }
                "--dt" => a.dt = value(&mut it, flag)?,
                "--steps" => a.steps = value(&mut it, flag)?,
                "--E" => a.e = value(&mut it, flag)?,
                "--nu" => a.nu = value(&mut it, flag)?,
                "--density" => a.density = value(&mut it, flag)?,
                "--warmup" => a.warmup = value(&mut it, flag)?,
                "--grid-blocks" => a.grid_blocks = Some(value(&mut it, flag)?),
                "--no-passes" => a.passes = false,
                "-h" | "--help" => {
                    println!("{USAGE}");
                    std::process::exit(0);
                }
                other => bail!("unknown argument {other:?}\n{USAGE}"),
            }
        }
        if a.per_axis == 0 || a.cells == 0 || a.steps == 0 {
            bail!("--per-axis, --cells and --steps must be positive");
        }
        Ok(a)
    }
}

/// The adapter slosh's `WebGpu::new` will pick (same instance and request), its name and
/// backend, and the limits and features to ask of it.
fn probe_adapter() -> Result<(String, wgpu::Limits, wgpu::Features)> {
    let instance = wgpu::Instance::default();
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        ..Default::default()
    }))
    .context("no wgpu adapter")?;
    let info = adapter.get_info();
    let have = adapter.limits();
    // What slosh's testbed asks for, clamped to what the adapter has.
    let limits = wgpu::Limits {
        max_storage_buffers_per_shader_stage: 13.min(have.max_storage_buffers_per_shader_stage),
        max_compute_workgroup_storage_size: 32768.min(have.max_compute_workgroup_storage_size),
        max_buffer_size: 4_000_000_000u64.min(have.max_buffer_size),
        max_storage_buffer_binding_size: 4_000_000_000u32
            .min(have.max_storage_buffer_binding_size),
        ..wgpu::Limits::default()
    };
    let features = adapter.features() & wgpu::Features::TIMESTAMP_QUERY;
    Ok((
        format!("{} ({:?})", info.name, info.backend),
        limits,
        features,
    ))
}

/// The cube's particles, x fastest, as in the Taichi peer and `Particles::sample_box`.
fn cube(a: &Args, lo: [f64; 3], spacing: f64) -> Vec<Particle<ParticleModel>> {
    let n = a.per_axis;
    let model = ParticleModel::elastic(a.e as f32, a.nu as f32);
    let mut out = Vec::with_capacity((n * n * n) as usize);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let at = |lo: f64, i: u32| (lo + (f64::from(i) + 0.5) * spacing) as f32;
                let x = Vector::new(at(lo[0], i), at(lo[1], j), at(lo[2], k));
                // Particle volume (2r)³ = spacing³, mass = density · volume.
                out.push(Particle::new(
                    x,
                    (spacing / 2.0) as f32,
                    a.density as f32,
                    model,
                ));
            }
        }
    }
    out
}

/// The unit domain's walls as fixed rapier cuboids: the ground's top face at y = 0 (sticky),
/// the other five faces at 0 and 1 (separating, no friction). A node takes a collider's
/// condition when it lies within one cell of its surface, so nodes 0 and 1 take the ground's
/// and nodes cells−1 and cells the far walls', as `I < 2` and `I > cells − 2` in the Taichi peer.
fn walls(dx: f32) -> (RigidBodySet, ColliderSet, Vec<(ColliderHandle, GpuBoundaryCondition)>) {
    let mut bodies = RigidBodySet::new();
    let mut colliders = ColliderSet::new();
    let body = bodies.insert(RigidBodyBuilder::fixed());
    let t = 4.0 * dx; // half thickness
    let w = 0.5 + 2.0 * t; // half width, so that the slabs overlap at the edges
    let slabs = [
        // (center, half extents, condition)
        ([0.5, -t, 0.5], [w, t, w], GpuBoundaryCondition::stick()),
        ([0.5, 1.0 + t, 0.5], [w, t, w], GpuBoundaryCondition::separate(0.0)),
        ([-t, 0.5, 0.5], [t, w, w], GpuBoundaryCondition::separate(0.0)),
        ([1.0 + t, 0.5, 0.5], [t, w, w], GpuBoundaryCondition::separate(0.0)),
        ([0.5, 0.5, -t], [w, w, t], GpuBoundaryCondition::separate(0.0)),
        ([0.5, 0.5, 1.0 + t], [w, w, t], GpuBoundaryCondition::separate(0.0)),
    ];
    let mut materials = vec![];
    for (c, h, bc) in slabs {
        let co = ColliderBuilder::cuboid(h[0], h[1], h[2]).translation(Vector::new(c[0], c[1], c[2]));
        let handle = colliders.insert_with_parent(co, body, &mut bodies);
        materials.push((handle, bc));
    }
    (bodies, colliders, materials)
}

/// Records `steps` steps in one encoder and submits it (one submission, as splatter's
/// `time_sim` does); with `timestamps`, each pass is timed.
fn encode_steps(
    gpu: &WebGpu,
    pipeline: &Pipeline,
    data: &mut Data,
    steps: u32,
    mut timestamps: Option<&mut GpuTimestamps>,
) -> Result<()> {
    let mut encoder = gpu.begin_encoding();
    let mut hooks = ();
    let mut state = ();
    for _ in 0..steps {
        pollster::block_on(pipeline.launch_step(
            gpu,
            &mut encoder,
            data,
            &mut hooks,
            &mut state,
            timestamps.as_deref_mut(),
        ))?;
    }
    if let Some(ts) = timestamps {
        ts.resolve(&mut encoder);
    }
    gpu.submit(encoder)?;
    Ok(())
}

fn main() -> Result<()> {
    let a = Args::parse()?;
    let dx = 1.0 / f64::from(a.cells);
    let spacing = dx / 2.0;
    let side = f64::from(a.per_axis) * spacing;
    let lo = a.lo.unwrap_or([0.5 - side / 2.0, 0.1, 0.5 - side / 2.0]);

    let (adapter, limits, features) = probe_adapter()?;
    let mut gpu = pollster::block_on(WebGpu::new(features, limits))?;
    // slosh's testbed and tests install this on every backend: Slang gives no access to the
    // `exchanged` flag of WGSL's weak compare-exchange, which the grid's hash map needs.
    let weak_cas =
        Regex::new(r"(?<out>var.*)(?<exch>atomicCompareExchangeWeak.*).old_value;").unwrap();
    gpu.append_hack(
        weak_cas,
        "var exch = $exch;
            while (!exch.exchanged && exch.old_value == u32(4294967295)) {
                exch = $exch;
            }
            $out exch.old_value;"
            .to_string(),
    );

    let setup = Instant::now();
    let mut compiler = SlangCompiler::default();
    slosh3d::register_shaders(&mut compiler);
    compiler.set_global_macro("DIM", "3");
    // The CDF and rigid-particle kernels are compile-only in this version (never dispatched).
    let kernels = MpmPipelineKernels {
        cdf: false,
        rigid_particles: false,
        ..MpmPipelineKernels::default()
    };
    let pipeline: Pipeline = MpmPipeline::new_with_kernels(&gpu, &compiler, kernels)?;
    let compile_s = setup.elapsed().as_secs_f64();

    let particles = cube(&a, lo, spacing);
    let np = particles.len();
    let (bodies, colliders, materials) = walls(dx as f32);
    // Blocks the cube can touch, with room to spread, times four.
    let blocks_per_axis = (side / (4.0 * dx)).ceil() as u32 + 3;
    let grid_blocks = a
        .grid_blocks
        .unwrap_or(4 * blocks_per_axis.pow(3))
        .next_power_of_two();
    let params = SimulationParams {
        gravity: Vector::new(0.0, -9.8, 0.0),
        dt: a.dt as f32,
    };
    let mut data: Data = MpmData::new(
        &gpu,
        params,
        &particles,
        &bodies,
        &colliders,
        &materials,
        dx as f32,
        grid_blocks,
    )?;
    let y0: f64 = particles.iter().map(|p| f64::from(p.position.y)).sum::<f64>() / np as f64;
    drop(particles);

    // Warm-up, then the timed steps, each waited for to GPU idle.
    encode_steps(&gpu, &pipeline, &mut data, a.warmup, None)?;
    gpu.synchronize()?;
    let start = Instant::now();
    encode_steps(&gpu, &pipeline, &mut data, a.steps, None)?;
    gpu.synchronize()?;
    let ms = start.elapsed().as_secs_f64() * 1e3 / f64::from(a.steps);

    // Per-pass GPU times, in a separate run (timestamps cost time of their own).
    let mut passes: BTreeMap<String, (usize, f64)> = BTreeMap::new();
    let mut order: Vec<String> = vec![];
    if a.passes && features.contains(wgpu::Features::TIMESTAMP_QUERY) {
        let mut ts = GpuTimestamps::new(gpu.device(), gpu.queue(), a.steps * 8);
        encode_steps(&gpu, &pipeline, &mut data, a.steps, Some(&mut ts))?;
        gpu.synchronize()?;
        for r in pollster::block_on(ts.read_results(gpu.device()))? {
            if !passes.contains_key(&r.label) {
                order.push(r.label.clone());
            }
            let e = passes.entry(r.label).or_default();
            e.0 += 1;
            e.1 += r.duration.as_secs_f64() * 1e3;
        }
    }
    let total_steps = a.warmup + a.steps * if passes.is_empty() { 1 } else { 2 };

    // A look at the state, so that a broken run shows.
    let pos: Vec<slosh3d::solver::ParticlePosition> =
        pollster::block_on(gpu.slow_read_vec(data.particles.positions().buffer()))?;
    let finite = pos.iter().all(|p| p.x.is_finite() && p.y.is_finite() && p.z.is_finite());
    let y: f64 = pos.iter().map(|p| f64::from(p.y)).sum::<f64>() / np as f64;
    let min_y = pos.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);

    println!(
        "slosh slosh3d {} (Slang {}, runtime-compiled WGSL), wgpu {}, {} particles ({}³ at dx/2), \
         1/{} cell width, sparse grid of 4³-node blocks ({} blocks), fixed corotated \
         (ElasticLinear) E {} ν {}, dt {}, {} steps; differs: sparse grid rebuilt each step, \
         scatter P2G, node speed clamped to 1 cell/step, walls are rapier cuboid colliders, f32",
        env!("PEER_SLOSH_VERSION"),
        env!("PEER_SLANG_VERSION"),
        adapter,
        np,
        a.per_axis,
        a.cells,
        grid_blocks,
        a.e,
        a.nu,
        a.dt,
        a.steps,
    );
    for label in &order {
        let (count, total) = passes[label];
        // Passes run once a step; report the per-step mean.
        println!(
            "pass {label}: {:.3} ms/step ({count} runs)",
            total / f64::from(a.steps)
        );
    }
    println!(
        "state: after {total_steps} steps mean y {y:.6} (start {y0:.6}), min y {min_y:.6}, \
         all finite: {finite}; setup (Slang + pipeline compile) {compile_s:.1} s"
    );
    println!("ms/step: {ms:.3}");
    Ok(())
}
