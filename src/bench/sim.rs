//! `splatter bench sim`: the GPU step on synthetic cases (NACC, the brittle law and fixed
//! corotated; 20k and 1M particles), per P2G path, with its memory per particle.

use super::*;

/// `splatter bench sim`: nanoseconds per particle-step of the GPU MPM step, with a NACC
/// material (the paper's fruit parameters), the brittle law and fixed corotated (the
/// peers' usual material), for 20k particles on a 64³ grid and (unless `quick`) 1M particles on a 128³
/// grid; plus GPU memory per particle. With `per_pass`, each case is also broken down by
/// pass. With `separation`, the fracturing cases only (NACC and brittle), with two-field
/// separation on the gather path. Returns the 20k cases' timings (what a peer is compared
/// with).
// Over 80 lines on purpose: one table whose cases, paths and per-pass lines print in the order
// they run.
pub fn sim_bench(
    gpu: &GpuContext,
    what: SimBench,
    out: &mut dyn Write,
) -> Result<Vec<(SimModel, SimTiming)>> {
    let SimBench {
        steps,
        quick,
        per_pass,
        separation,
    } = what;
    writeln!(out, "adapter: {}", gpu.describe())?;
    if separation {
        writeln!(
            out,
            "P2G with separation: gather (the only path that runs it)"
        )?;
    } else {
        writeln!(out, "{}", default_path_line(gpu)?)?;
    }
    writeln!(
        out,
        "{:>10} {:>6} {:>16} {:>7} {:>6} {:>10} {:>16} {:>14}",
        "particles",
        "grid",
        "material",
        "p2g",
        "steps",
        "ms/step",
        "ns/particle-step",
        "bytes/particle"
    )?;
    let mut cases = vec![(20_000usize, 64u32)];
    if !quick {
        cases.push((1_000_000, 128));
    }
    let mut small = Vec::new();
    let models: &[SimModel] = if separation {
        &[SimModel::Nacc, SimModel::Brittle]
    } else {
        &[SimModel::Nacc, SimModel::Brittle, SimModel::FixedCorotated]
    };
    let paths = if separation {
        vec![crate::sim::gpu::P2gPath::Gather]
    } else {
        sim_paths(gpu)
    };
    for (k, (n, cells)) in cases.into_iter().enumerate() {
        for &model in models {
            let mut case = SimCase::with_model(n, cells, model);
            if separation {
                case.params.separation = crate::sim::Separation::DamageGradient;
            }
            for &path in &paths {
                let (sim, t) = time_sim(gpu, &case, path, steps)?;
                writeln!(
                    out,
                    "{:>10} {:>5}³ {:>16} {:>7} {:>6} {:>10.2} {:>16.1} {:>14.0}",
                    t.particles,
                    cells,
                    if separation {
                        format!("{}, two fields", model.name())
                    } else {
                        model.name().to_string()
                    },
                    t.p2g,
                    steps,
                    t.ms_per_step,
                    t.ns_per_particle_step,
                    t.gpu_bytes as f64 / t.particles as f64
                )?;
                if per_pass {
                    write_passes(gpu, &sim, steps, out)?;
                }
                out.flush()?;
                if k == 0 {
                    small.push((model, t));
                }
            }
        }
    }
    Ok(small)
}

/// Which P2G path a long run on `gpu` takes by default (as a run's [`SimPlan`] chooses
/// it), and the race's times where the adapter leaves the choice to one.
///
/// [`SimPlan`]: crate::sim::gpu::SimPlan
fn default_path_line(gpu: &GpuContext) -> Result<String> {
    use crate::sim::gpu::{SimPlan, SimRequest};
    let case = SimCase::new(20_000, 64);
    let plan = SimPlan::choose(
        gpu,
        &SimRequest {
            params: &case.params,
            particles: case.particles.len(),
            cells: case.grid.cells,
            steps: u64::MAX,
            forced: None,
            deterministic: false,
        },
    )?;
    Ok(match plan.race {
        None => format!(
            "default P2G here: {} (no race on this adapter)",
            plan.p2g.name()
        ),
        Some(race) => format!(
            "default P2G of a long run here: {} (race: float atomics {:.2}, gather {:.2} ms a step of its probe block)",
            plan.p2g.name(),
            race.atomic_ms,
            race.gather_ms
        ),
    })
}

/// What `bench sim` steps: `steps` per case, the 20k case only (`quick`), each case also
/// by pass (`per_pass`), with two-field separation (`separation`).
#[derive(Clone, Copy, Debug)]
pub struct SimBench {
    pub steps: u32,
    pub quick: bool,
    pub per_pass: bool,
    pub separation: bool,
}

/// The active blocks and the per-pass times of one case.
fn write_passes(
    gpu: &GpuContext,
    sim: &crate::sim::gpu::GpuSim,
    steps: u32,
    out: &mut dyn Write,
) -> Result<()> {
    let active = sim.active_blocks(gpu)?.len();
    let blocks = sim.blocks();
    writeln!(
        out,
        "{:>22} active blocks of 4³ nodes: {active} of {blocks}",
        ""
    )?;
    let list: Vec<String> = sim
        .profile_passes(gpu, steps)?
        .iter()
        .map(|(name, ms)| format!("{name} {ms:.2}"))
        .collect();
    writeln!(
        out,
        "{:>22} per pass (ms per step, each waited for): {}",
        "",
        list.join(", ")
    )?;
    Ok(())
}

/// `splatter bench sim --particles N`: one NACC step of about `n` particles on a grid sized
/// to hold them, on the atomic path where the adapter has float atomics (it steps particle
/// arrays larger than one storage binding, page by page); wall time, GPU bytes per particle,
/// peak memory, and the most particles this adapter's buffer limits allow.
pub fn sim_scale_bench(gpu: &GpuContext, n: usize, steps: u32, out: &mut dyn Write) -> Result<()> {
    use crate::sim::gpu::{GpuSim, P2gPath};
    writeln!(out, "adapter: {}", gpu.describe())?;
    let binding = gpu.limits.max_storage_buffer_binding_size;
    let buffer = gpu.limits.max_buffer_size;
    writeln!(
        out,
        "limits: storage binding {} MiB, buffer {} MiB: at most {} particles on the atomic path (paged), {} on the gather path (one binding)",
        binding >> 20,
        buffer >> 20,
        buffer / 48,
        binding.min(buffer) / 48
    )?;
    // 8 particles per cell in a cube that fills 3/4 of the domain's side.
    let side = (n as f64 / 8.0).cbrt();
    let cells = ((side / 0.75 / 16.0).ceil() * 16.0) as u32;
    let start = Instant::now();
    let case = SimCase::with_model(n, cells.max(16), SimModel::Nacc);
    let np = case.particles.len();
    let path = P2gPath::best(gpu);
    let pages = GpuSim::pages_for(gpu, np);
    let sim = GpuSim::with_pages(
        gpu,
        &case.particles,
        &case.grid,
        &[case.material],
        &case.params,
        path,
        pages,
    )?;
    drop(case);
    gpu.wait()?;
    let setup_s = start.elapsed().as_secs_f64();
    writeln!(
        out,
        "{np} particles, {cells}³ grid, {} P2G, {} page(s) of {} particles; setup (sample, upload) {setup_s:.1} s",
        path.name(),
        pages.count,
        pages.size
    )?;
    out.flush()?;
    let start = Instant::now();
    sim.step(gpu, 1)?;
    gpu.wait()?;
    let first = start.elapsed().as_secs_f64();
    let start = Instant::now();
    sim.step(gpu, steps)?;
    gpu.wait()?;
    let secs = start.elapsed().as_secs_f64() / f64::from(steps);
    let w = sim.take_watchdog(gpu)?;
    writeln!(
        out,
        "first step {first:.2} s; then {secs:.2} s/step ({:.1} ns/particle-step) over {steps}; watchdog: {} non-finite, {} escaped, pool overflow {}",
        secs * 1e9 / np as f64,
        w.nonfinite,
        w.escaped,
        w.pool_overflow
    )?;
    write_memory(out, sim.gpu_bytes(), np, "particle")
}

/// The P2G paths `gpu` can run: the sorted gather and the fixed-point scatter everywhere,
/// the float-atomic scatter where the adapter has SHADER_FLOAT32_ATOMIC.
pub fn sim_paths(gpu: &GpuContext) -> Vec<crate::sim::gpu::P2gPath> {
    use crate::sim::gpu::P2gPath;
    let mut paths = vec![P2gPath::Gather, P2gPath::Fixed];
    if gpu.features.float32_atomics {
        paths.push(P2gPath::Atomic);
    }
    paths
}

/// The material of a simulation benchmark case.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SimModel {
    /// NACC with the paper's fruit parameters, `continuous` k = 2.
    Nacc,
    /// Brittle damage with the same E and ν (`sim::model::Brittle`: σ̄ 100 Pa,
    /// Weibull m 6, softening 0.5), the law the shipped drops break with.
    Brittle,
    /// Fixed corotated with the same E and ν (what MPM peers run).
    FixedCorotated,
}

impl SimModel {
    pub fn name(self) -> &'static str {
        match self {
            SimModel::Nacc => "nacc",
            SimModel::Brittle => "brittle",
            SimModel::FixedCorotated => "fixed_corotated",
        }
    }
}

/// The simulation benchmark's input: a cube (NACC with the paper's fruit parameters, or
/// fixed corotated) of 8 particles per cell falling onto a sticky ground in a unit domain of
/// `cells`³ cells: contact, plasticity and free flight in one run.
pub struct SimCase {
    pub particles: crate::sim::Particles,
    pub grid: crate::sim::Grid,
    pub material: crate::sim::Material,
    pub params: crate::sim::StepParams,
    pub cells: u32,
}

impl SimCase {
    /// Young's modulus, Poisson ratio and density of every case.
    pub const E: f64 = 2000.0;
    pub const NU: f64 = 0.4;
    pub const DENSITY: f64 = 2.0;

    /// About `n` NACC particles on a `cells`³ grid.
    pub fn new(n: usize, cells: u32) -> SimCase {
        Self::with_model(n, cells, SimModel::Nacc)
    }

    /// About `n` particles of `model` on a `cells`³ grid.
    pub fn with_model(n: usize, cells: u32, model: SimModel) -> SimCase {
        use crate::sim::model::nacc::oracle::{Case3Variant, NaccParams};
        use crate::sim::{cfl_dt, Grid, Material, Particles, StepParams};
        use glam::DVec3;
        let material = match model {
            SimModel::Nacc => Material::nacc(
                NaccParams {
                    e: Self::E,
                    nu: Self::NU,
                    alpha0: -0.04,
                    beta: 1.0,
                    xi: 2.0,
                    m_slope: 2.36,
                },
                Case3Variant::Continuous { k: 2.0 },
            ),
            SimModel::Brittle => {
                use crate::sim::model::{Brittle, PlasticLaw};
                let spec = serde_json::json!({
                    "strength": 100.0, "weibull_modulus": 6.0, "softening": 0.5
                });
                let spec = serde_json::from_value(spec).expect("the brittle case's parameters");
                let law = Brittle::from_spec(spec, Self::E, Self::NU).expect("valid");
                Material::with_plastic(law.into(), Self::E, Self::NU)
            }
            SimModel::FixedCorotated => Material::fixed_corotated(Self::E, Self::NU),
        };
        let dx = 1.0 / f64::from(cells);
        let side = (n as f64 / 8.0).cbrt() * dx;
        let lo = DVec3::new(0.5 - side / 2.0, 0.1, 0.5 - side / 2.0);
        let mut particles =
            Particles::sample_box(lo, lo + DVec3::splat(side), dx / 2.0, Self::DENSITY);
        particles.set_material(0, &material);
        let params = StepParams::sticky_ground(
            cfl_dt(&material, Self::DENSITY, dx, 0.4).min(1e-4),
            DVec3::new(0.0, -9.8, 0.0),
        );
        SimCase {
            particles,
            grid: Grid::new(DVec3::ZERO, DVec3::ONE, dx),
            material,
            params,
            cells,
        }
    }
}

/// One timed simulation case (`bench sim`, `splatter-lab suite`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SimTiming {
    pub particles: usize,
    pub cells: u32,
    pub p2g: String,
    pub steps: u32,
    pub ms_per_step: f64,
    pub ns_per_particle_step: f64,
    /// All GPU buffers of the simulation (`GpuSim::gpu_bytes`).
    pub gpu_bytes: u64,
}

/// Runs one warm-up step, then `steps` steps in one submission, timed to GPU idle.
pub fn time_sim(
    gpu: &GpuContext,
    case: &SimCase,
    path: crate::sim::gpu::P2gPath,
    steps: u32,
) -> Result<(crate::sim::gpu::GpuSim, SimTiming)> {
    use crate::sim::gpu::GpuSim;
    let sim = GpuSim::with_path(
        gpu,
        &case.particles,
        &case.grid,
        &[case.material],
        &case.params,
        path,
    )?;
    sim.step(gpu, 1)?;
    gpu.wait()?;
    let start = Instant::now();
    sim.step(gpu, steps)?;
    gpu.wait()?;
    let secs = start.elapsed().as_secs_f64();
    let np = case.particles.len();
    let timing = SimTiming {
        particles: np,
        cells: case.cells,
        p2g: format!("{path:?}").to_lowercase(),
        steps,
        ms_per_step: secs * 1e3 / f64::from(steps),
        ns_per_particle_step: secs * 1e9 / (f64::from(steps) * np as f64),
        gpu_bytes: sim.gpu_bytes(),
    };
    Ok((sim, timing))
}
