use super::*;
use crate::rng::SplitMix64;
use crate::sim::{cfl_dt, BoundaryKind, Condition, DomainWalls};

fn rand_vec(r: &mut SplitMix64) -> DVec3 {
    DVec3::new(r.uniform(), r.uniform(), r.uniform()) * 2.0 - 1.0
}

#[test]
fn conditions() {
    let n = DVec3::Y;
    let v = DVec3::new(2.0, -1.0, 0.0);
    assert_eq!(Condition::STICKY.apply(v, n), DVec3::ZERO);
    assert_eq!(Condition::SLIP.apply(v, n), DVec3::new(2.0, 0.0, 0.0));
    assert_eq!(Condition::SEPARATE.apply(v, n), DVec3::new(2.0, 0.0, 0.0));
    // Leaving: slip is bilateral, separate lets go.
    let up = DVec3::new(2.0, 1.0, 0.0);
    assert_eq!(Condition::SLIP.apply(up, n), DVec3::new(2.0, 0.0, 0.0));
    assert_eq!(Condition::SEPARATE.apply(up, n), up);
    // Friction: |v_t| 2 → 2 − 0.5·1, never v = 0 unless friction stops it.
    let fr = Condition::SEPARATE.with_friction(0.5);
    assert!((fr.apply(v, n) - DVec3::new(1.5, 0.0, 0.0)).length() < 1e-15);
    assert_eq!(
        Condition::SEPARATE.with_friction(3.0).apply(v, n),
        DVec3::ZERO
    );
    assert_eq!(fr.apply(up, n), up);
    assert!((Condition::SLIP.with_friction(0.5).apply(up, n) - DVec3::X * 2.0).length() < 1e-15);
}

#[test]
fn grid_layout() {
    let g = Grid::new(DVec3::ZERO, DVec3::new(1.0, 0.5, 0.25), 1.0 / 32.0);
    assert_eq!(g.cells, UVec3::new(32, 16, 8));
    for idx in [0, 5, 33, 1000, g.node_count() - 1] {
        assert_eq!(g.index(g.node_of(idx)), idx);
    }
    assert!(g.stencil(DVec3::splat(0.5 / 32.0)).is_some());
    assert!(g.stencil(DVec3::splat(0.49 / 32.0)).is_none());
    assert!(g.stencil(DVec3::new(1.0 - 0.51 / 32.0, 0.2, 0.1)).is_some());
    assert!(g.stencil(DVec3::new(1.0 - 0.5 / 32.0, 0.2, 0.1)).is_none());
    assert!(g.stencil(DVec3::NAN).is_none());
}

#[test]
fn sampling_and_cfl() {
    let p = Particles::sample_box(DVec3::ZERO, DVec3::new(0.1, 0.2, 0.3), 0.05, 1000.0);
    assert_eq!(p.len(), 2 * 4 * 6);
    assert!((p.total_mass() - 1000.0 * 0.1 * 0.2 * 0.3).abs() < 1e-12);
    let s = Particles::sample_sphere(DVec3::ZERO, 1.0, 0.05, 1.0);
    let vol = s.volume0.iter().sum::<f64>();
    assert!(
        (vol / (4.0 / 3.0 * std::f64::consts::PI) - 1.0).abs() < 0.01,
        "{vol}"
    );
    let m = Material::fixed_corotated(1.0, 0.0);
    assert!((cfl_dt(&m, 1.0, 0.1, 0.5) - 0.05).abs() < 1e-15);
}

#[test]
fn check_counts() {
    let g = Grid::new(DVec3::ZERO, DVec3::ONE, 0.1);
    let mut p = Particles::sample_box(DVec3::splat(0.4), DVec3::splat(0.6), 0.05, 1.0);
    assert!(check(&p, &g, 1e-3).is_ok());
    p.x[3] = DVec3::new(0.5, 0.5, 1.2);
    p.x[5] = DVec3::new(0.5, -0.1, 0.5);
    p.f[7].x_axis.y = f64::NAN;
    p.v[1] = DVec3::X * 200.0;
    let h = check(&p, &g, 1e-3);
    assert_eq!((h.non_finite, h.outside, h.too_fast), (1, 2, 1));
    assert_eq!((h.first_non_finite, h.first_outside), (Some(7), Some(3)));
    assert!(h.message(12).unwrap().contains("step 12"));
}

/// A band of 3 keeps particles on the grid: a block thrown at each wall kind at
/// 0.9 Δx/Δt (the velocity CFL limit) for 60 steps never leaves it; a sticky wall stops
/// it, slip and separate keep its tangential velocity.
#[test]
fn walls_keep_particles_on_the_grid() {
    let dx = 0.1;
    let dt = 1e-3;
    let mats = [Material::fixed_corotated(10.0, 0.3)];
    for cond in [Condition::STICKY, Condition::SLIP, Condition::SEPARATE] {
        let mut g = Grid::new(DVec3::ZERO, DVec3::ONE, dx);
        let mut p =
            Particles::sample_box(DVec3::new(0.4, 0.4, 0.4), DVec3::splat(0.6), dx / 2.0, 1.0);
        let v0 = DVec3::new(-0.9 * dx / dt, 0.02 * dx / dt, 0.0);
        p.v.iter_mut().for_each(|v| *v = v0);
        let params = StepParams {
            dt,
            gravity: DVec3::ZERO,
            boundaries: Boundaries {
                walls: DomainWalls::uniform(cond),
                colliders: vec![],
                surface: None,
            },
            transfer: Transfer::Apic,
            separation: Default::default(),
            fields: Default::default(),
            actions: Default::default(),
        };
        for _ in 0..60 {
            assert_eq!(step(&mut p, &mut g, &mats, &params).escaped, 0);
            assert!(check(&p, &g, dt).is_ok(), "{cond:?}");
        }
        let xmin = p.x.iter().map(|x| x.x).fold(f64::MAX, f64::min);
        assert!(xmin >= 0.5 * dx, "{cond:?}: {xmin}");
        let vy = p.momentum().y / p.total_mass();
        match cond.kind {
            BoundaryKind::Sticky => {
                assert!(p.momentum().length() < 0.5 * v0.length() * p.total_mass())
            }
            _ => assert!(vy > 0.0, "{cond:?}: tangential velocity lost"),
        }
    }
}

/// The sorted gather equals a plain sequential scatter, and the step is bit-identical
/// for 1 and 3 threads.
#[test]
fn gather_matches_scatter_and_is_deterministic() {
    let mut r = SplitMix64::new(5);
    let dx = 0.1;
    let mut g = Grid::new(DVec3::ZERO, DVec3::ONE, dx);
    let mats = [
        Material::fixed_corotated(1e3, 0.3),
        Material::neo_hookean(2e3, 0.2),
    ];
    let mut p = Particles::new();
    for i in 0..500 {
        let x = DVec3::splat(0.5) + rand_vec(&mut r) * 0.3;
        p.push(x, rand_vec(&mut r), 0.5 + r.uniform(), 1e-3, i % 2, 0.0);
        p.c[i as usize] = DMat3::from_cols(rand_vec(&mut r), rand_vec(&mut r), rand_vec(&mut r));
        p.f[i as usize] +=
            DMat3::from_cols(rand_vec(&mut r), rand_vec(&mut r), rand_vec(&mut r)) * 0.1;
    }
    let dt = 1e-3;
    p2g(&p, &mut g, &mats, dt, Transfer::Apic, Separation::None);
    let mut m_ref = vec![0.0; g.node_count()];
    let mut p_ref = vec![DVec3::ZERO; g.node_count()];
    for q in 0..p.len() {
        let st = g.stencil(p.x[q]).unwrap();
        let tau = mats[p.material[q] as usize].kirchhoff(p.f[q], p.alpha[q]);
        let a = p.c[q] * p.mass[q] - tau * (dt * p.volume0[q] * 4.0 / (dx * dx));
        for o in crate::sim::bspline::stencil_offsets() {
            let i = g.index(st.node(o).as_uvec3());
            let w = st.weight(o);
            m_ref[i] += w * p.mass[q];
            p_ref[i] += (p.v[q] * p.mass[q] + a * st.offset(o, dx)) * w;
        }
    }
    for i in 0..g.node_count() {
        assert!((g.mass[i] - m_ref[i]).abs() < 1e-12);
        assert!((g.momentum[i] - p_ref[i]).length() < 1e-10);
    }
    let params = StepParams {
        dt,
        gravity: DVec3::new(0.0, -9.8, 0.0),
        boundaries: Boundaries::default(),
        transfer: Transfer::Apic,
        separation: Default::default(),
        fields: Default::default(),
        actions: Default::default(),
    };
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let (mut q, mut gg) = (p.clone(), g.clone());
            for _ in 0..5 {
                step(&mut q, &mut gg, &mats, &params);
            }
            q
        })
    };
    assert_eq!(run(1), run(3));
}
