//! The sparse grid: the GPU grid is a pool of 4³-node blocks covering only the
//! active region, addressed through a block → slot table. The same steps with a pool as
//! large as the whole domain (the dense grid's memory) give bit-identical positions on the
//! deterministic gather path, and a pool too small is reported by the watchdog and grown.

use std::time::Instant;

use glam::DVec3;
use splatter::gpu::GpuContext;
use splatter::sim::gpu::{GpuSim, P2gPath};
use splatter::sim::time_step::StepPlan;
use splatter::sim::{
    Boundaries, Condition, DomainWalls, Grid, Material, Particles, StepParams, Transfer,
};

/// A 0.2 m fruit (a jelly ball falling on a frictional ground) in a 1 m domain at Δx 0.01.
fn fruit() -> (Particles, Grid, Vec<Material>, StepParams) {
    let dx = 0.01;
    let material = Material::fixed_corotated(2e4, 0.3);
    let mut p = Particles::sample_sphere(DVec3::new(0.5, 0.5, 0.14), 0.1, dx / 1.5, 1000.0);
    p.set_material(0, &material);
    p.v.iter_mut().for_each(|v| *v = DVec3::new(0.3, 0.0, -1.0));
    let grid = Grid::new(DVec3::ZERO, DVec3::ONE, dx);
    let walls = DomainWalls {
        faces: [Condition::SEPARATE; 6],
        band: 3,
    };
    let mut walls = walls;
    walls.faces[4] = Condition::SLIP.with_friction(0.3);
    let params = StepParams {
        dt: 2e-4,
        gravity: DVec3::new(0.0, 0.0, -9.8),
        boundaries: Boundaries {
            walls,
            colliders: vec![],
            surface: None,
        },
        transfer: Transfer::Apic,
        separation: Default::default(),
        fields: Default::default(),
        actions: Default::default(),
    };
    (p, grid, vec![material], params)
}

fn run(gpu: &GpuContext, sim: &GpuSim, like: &Particles, steps: u32) -> (Particles, f64) {
    sim.step(gpu, 1).unwrap();
    gpu.wait().unwrap();
    let start = Instant::now();
    sim.step(gpu, steps).unwrap();
    let out = sim.read_particles(gpu, like).unwrap();
    let ms = start.elapsed().as_secs_f64() * 1e3 / f64::from(steps);
    (out, ms)
}

#[test]
fn sparse_grid_equals_the_dense_result_in_a_quarter_of_the_memory() {
    let (p, grid, materials, params) = fruit();
    let dense_grid_bytes = grid.nodes().element_product() as u64 * 16;
    let steps = 40;
    for gpu in splatter::gpu::test_contexts() {
        let mut paths = vec![P2gPath::Gather, P2gPath::Fixed];
        if gpu.features.float32_atomics {
            paths.push(P2gPath::Atomic);
        }
        for path in paths {
            let sparse = GpuSim::with_path(&gpu, &p, &grid, &materials, &params, path).unwrap();
            let mut dense = GpuSim::with_path(&gpu, &p, &grid, &materials, &params, path).unwrap();
            dense.set_pool_blocks(&gpu, dense.blocks()).unwrap();
            let (a, ms_sparse) = run(&gpu, &sparse, &p, steps);
            let (b, ms_dense) = run(&gpu, &dense, &p, steps);
            let w = sparse.take_watchdog(&gpu).unwrap();
            let worst =
                a.x.iter()
                    .zip(&b.x)
                    .map(|(x, y)| (*x - *y).abs().max_element())
                    .fold(0.0, f64::max);
            let identical = a.x == b.x && a.v == b.v && a.f == b.f;
            let ratio = dense_grid_bytes as f64 / sparse.grid_bytes() as f64;
            eprintln!(
                "{} ({path:?}): {} particles, grid {}³ nodes; sparse pool {} of {} blocks (most active {}): grid {:.2} MB vs dense {:.2} MB ({ratio:.1}×), sim total {:.2} MB vs {:.2} MB; {:.1} vs {:.1} ms/step; max |Δx| {:.1e} (bit-identical: {identical})",
                gpu.describe(),
                p.len(),
                grid.nodes().x,
                sparse.pool_blocks(),
                sparse.blocks(),
                w.active_blocks_max,
                sparse.grid_bytes() as f64 / 1e6,
                dense_grid_bytes as f64 / 1e6,
                sparse.gpu_bytes() as f64 / 1e6,
                dense.gpu_bytes() as f64 / 1e6,
                ms_sparse,
                ms_dense,
                worst
            );
            assert_eq!(w.pool_overflow, 0);
            assert!(ratio >= 4.0, "grid memory only {ratio}× smaller");
            match path {
                // Deterministic: the slot a block gets never changes a sum's order.
                P2gPath::Gather => assert!(identical, "gather path differs by {worst}"),
                // Deterministic: no order changes an integer sum.
                P2gPath::Fixed => assert!(identical, "fixed-point path differs by {worst}"),
                P2gPath::Atomic => assert!(worst < 1e-4 * grid.dx, "{worst}"),
            }
        }
    }
}

/// A pool smaller than the active region: the watchdog counts the blocks left out and
/// `fit_pool` grows the pool to twice the need, after which nothing overflows.
#[test]
fn an_overflowing_pool_is_reported_and_grown() {
    let (p, grid, materials, params) = fruit();
    let gpu = GpuContext::new(None).unwrap();
    let mut sim = GpuSim::with_path(&gpu, &p, &grid, &materials, &params, P2gPath::Gather).unwrap();
    sim.set_pool_blocks(&gpu, 16).unwrap();
    sim.step(&gpu, 2).unwrap();
    let w = sim.take_watchdog(&gpu).unwrap();
    assert!(w.pool_overflow > 0 && w.active_blocks_max > 16, "{w:?}");
    assert!(sim.fit_pool(&gpu, &w).unwrap());
    assert_eq!(sim.pool_blocks(), 2 * w.active_blocks_max);
    sim.step(&gpu, 2).unwrap();
    let w2 = sim.take_watchdog(&gpu).unwrap();
    assert_eq!(w2.pool_overflow, 0, "{w2:?}");
    assert!(!sim.fit_pool(&gpu, &w2).unwrap());
}

/// `GpuSim::step_frame` (what a run does per frame) re-runs steps that overflow the pool
/// from a saved state with a grown pool: the result equals a run that never overflowed,
/// bit for bit on the gather path.
#[test]
fn an_overflowed_frame_rerun_from_the_saved_state_equals_a_clean_run() {
    let (p, grid, materials, params) = fruit();
    let gpu = GpuContext::new(None).unwrap();
    let steps = 6;
    let clean = GpuSim::with_path(&gpu, &p, &grid, &materials, &params, P2gPath::Gather).unwrap();
    clean.step(&gpu, steps).unwrap();
    assert_eq!(clean.take_watchdog(&gpu).unwrap().pool_overflow, 0);
    let want = clean.read_particles(&gpu, &p).unwrap();

    let mut sim = GpuSim::with_path(&gpu, &p, &grid, &materials, &params, P2gPath::Gather).unwrap();
    sim.set_pool_blocks(&gpu, 4).unwrap();
    assert!(sim.pool_can_overflow());
    let plan = StepPlan {
        dt: params.dt,
        steps,
    };
    let frame = sim.step_frame(&gpu, plan, 0.0, 0).unwrap();
    let reruns = frame.reruns;
    assert_eq!(frame.watchdog.pool_overflow, 0);
    let got = sim.read_particles(&gpu, &p).unwrap();
    eprintln!("{reruns} rerun(s), pool {} blocks", sim.pool_blocks());
    assert!(reruns > 0, "test setup: the small pool must overflow");
    assert!(got.x == want.x && got.v == want.v && got.f == want.f);
}

/// A pool that cannot grow (capped as the grid texture of an adapter with a small largest
/// texture would cap it) and overflows: `step_frame` stops with an error that names the
/// blocks needed and the limit, instead of re-running the frame for ever.
#[test]
fn an_overflow_past_the_adapters_pool_limit_is_an_error() {
    use splatter::sim::frame::FrameError;
    let (p, grid, materials, params) = fruit();
    let gpu = GpuContext::new(None).unwrap();
    let mut sim = GpuSim::with_path(&gpu, &p, &grid, &materials, &params, P2gPath::Gather).unwrap();
    sim.limit_pool_blocks(&gpu, 8).unwrap();
    assert!(sim.pool_at_limit() && sim.pool_can_overflow());
    match sim.step_frame(
        &gpu,
        StepPlan {
            dt: params.dt,
            steps: 2,
        },
        0.0,
        0,
    ) {
        Err(e @ FrameError::PoolAtLimit { needed, limit }) => {
            assert!(needed > 8 && limit == 8, "{e}");
            assert!(e.to_string().contains("coarser grid"), "{e}");
        }
        other => panic!("expected PoolAtLimit, got {other:?}"),
    }
}

/// The pool's cap is checked when the simulation is set up: particles that already reach
/// more blocks than the adapter's pool can hold are refused, naming the blocks needed and
/// the limit, before anything is allocated (here the cap comes from a storage binding of
/// 1 MiB, which holds the sums of 512 blocks in fixed point, 1 024 in floats).
#[test]
fn particles_past_the_pool_cap_are_refused_up_front() {
    let mut gpu = GpuContext::new(None).unwrap();
    gpu.limits.max_storage_buffer_binding_size = 1 << 20;
    let dx = 1.0 / 64.0;
    let grid = Grid::new(DVec3::ZERO, DVec3::ONE, dx);
    // One particle in each block of 4³ nodes (their centres, 4 Δx apart): 15³ blocks.
    let p = Particles::sample_box(DVec3::splat(0.06), DVec3::splat(0.99), 4.0 * dx, 1000.0);
    let params = StepParams {
        dt: 1e-4,
        gravity: DVec3::ZERO,
        boundaries: Default::default(),
        transfer: Default::default(),
        separation: Default::default(),
        fields: Default::default(),
        actions: Default::default(),
    };
    let materials = [Material::fixed_corotated(1e4, 0.3)];
    let mut paths = vec![P2gPath::Fixed];
    if gpu.features.float32_atomics {
        paths.push(P2gPath::Atomic);
    }
    for path in paths {
        let e = GpuSim::with_path(&gpu, &p, &grid, &materials, &params, path)
            .err()
            .unwrap_or_else(|| panic!("{path:?}: {} particles accepted", p.len()))
            .to_string();
        eprintln!("{path:?}: {e}");
        assert!(e.contains("blocks of 4³ grid nodes"), "{e}");
        assert!(e.contains("coarser grid"), "{e}");
    }
}
