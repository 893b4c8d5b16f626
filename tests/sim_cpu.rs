//! Analytic tests of the CPU reference MPM step (`splatter::sim::cpu`, docs/method.md §2). Each test states its tolerance and prints what it
//! measured (`cargo test --release --test sim_cpu -- --nocapture`).

use glam::{DMat3, DVec3};
use splatter::rng::SplitMix64;
use splatter::sim::cpu::{self, check, step};
use splatter::sim::{
    cfl_dt, Boundaries, Condition, DomainWalls, Grid, Material, Particles, PlaneCollider,
    StepParams, Transfer,
};
use splatter::sim::{Case3Variant, NaccParams};

const G: f64 = 9.81;

fn params(dt: f64, gravity: DVec3, boundaries: Boundaries) -> StepParams {
    StepParams {
        dt,
        gravity,
        boundaries,
        transfer: Transfer::Apic,
        separation: Default::default(),
        fields: Default::default(),
        actions: Default::default(),
    }
}

/// `skew(ω)`: the matrix with skew(ω) r = ω × r.
fn skew(w: DVec3) -> DMat3 {
    DMat3::from_cols(
        DVec3::new(0.0, w.z, -w.y),
        DVec3::new(-w.z, 0.0, w.x),
        DVec3::new(w.y, -w.x, 0.0),
    )
}

fn max_abs(m: DMat3) -> f64 {
    m.to_cols_array().iter().fold(0.0, |a, x| a.max(x.abs()))
}

/// Runs `steps` steps, asserting the watchdog stays quiet.
fn run(
    p: &mut Particles,
    g: &mut Grid,
    mats: &[Material],
    sp: &StepParams,
    steps: usize,
    mut each: impl FnMut(usize, &Particles),
) {
    for n in 1..=steps {
        let stats = step(p, g, mats, sp);
        assert_eq!(stats.escaped, 0, "step {n}");
        let h = check(p, g, sp.dt);
        if let Some(msg) = h.message(n as u64) {
            panic!("{msg}");
        }
        each(n, p);
    }
}

/// The transfers: APIC, PIC, and FLIP/PIC blends.
const TRANSFERS: [Transfer; 4] = [
    Transfer::Apic,
    Transfer::FlipPic { flip: 0.0 },
    Transfer::FlipPic { flip: 0.7 },
    Transfer::FlipPic { flip: 1.0 },
];

/// Test 1: Free fall, no wall touched, zero stress: symplectic Euler (v before x) gives
/// x_n = x₀ + n v₀ Δt + g Δt² n(n+1)/2 and v_n = v₀ + n g Δt; F stays I. With every
/// transfer: a uniform velocity field is carried exactly by APIC, PIC and FLIP alike.
/// Tolerance: 1e-12 on positions (domain of size 1), velocities and F − I (round-off).
#[test]
fn free_fall_matches_the_discrete_formula() {
    for transfer in TRANSFERS {
        free_fall(transfer);
    }
}

fn free_fall(transfer: Transfer) {
    let dx = 1.0 / 16.0;
    let mut g = Grid::new(DVec3::ZERO, DVec3::ONE, dx);
    let mats = [Material::fixed_corotated(1e4, 0.3)];
    let mut p = Particles::sample_box(DVec3::splat(0.4), DVec3::splat(0.6), dx / 2.0, 1000.0);
    let v0 = DVec3::new(0.3, 1.0, -0.2);
    p.v.iter_mut().for_each(|v| *v = v0);
    let x0 = p.x.clone();
    let (dt, steps) = (1e-3, 200);
    let gv = DVec3::new(0.0, -G, 0.0);
    let sp = StepParams {
        transfer,
        ..params(dt, gv, Boundaries::default())
    };
    let (mut ex, mut ev, mut ef) = (0.0f64, 0.0f64, 0.0f64);
    run(&mut p, &mut g, &mats, &sp, steps, |n, p| {
        let nf = n as f64;
        for (q, start) in x0.iter().enumerate() {
            let want = *start + v0 * (nf * dt) + gv * (dt * dt * nf * (nf + 1.0) / 2.0);
            ex = ex.max((p.x[q] - want).abs().max_element());
            ev = ev.max((p.v[q] - (v0 + gv * (nf * dt))).abs().max_element());
            ef = ef.max(max_abs(p.f[q] - DMat3::IDENTITY));
        }
    });
    println!(
        "free fall ({transfer:?}), {} particles, {steps} steps: max |x − formula| = {ex:.2e}, \
         max |v − formula| = {ev:.2e}, max |F − I| = {ef:.2e} (tol 1e-12)",
        p.len()
    );
    assert!(ex < 1e-12 && ev < 1e-12 && ef < 1e-12);
}

/// Test 2: P2G conserves mass, momentum and (APIC) angular momentum, stress included:
/// Σ m_i = Σ m_p, Σ p_i = Σ m_p v_p, Σ x_i × p_i = Σ x_p × m_p v_p + m_p (Δx²/4) axial(C_p)
/// (the stress term is symmetric and adds nothing). Random particles, velocities, C and F.
/// Tolerance: 1e-13 relative to the sums of magnitudes (f64 round-off).
#[test]
fn p2g_conserves_mass_momentum_and_angular_momentum() {
    let mut r = SplitMix64::new(11);
    let mut rv = move || DVec3::new(r.uniform(), r.uniform(), r.uniform()) * 2.0 - 1.0;
    let dx = 1.0 / 20.0;
    let mut g = Grid::new(DVec3::ZERO, DVec3::ONE, dx);
    let mats = [
        Material::fixed_corotated(1e4, 0.3),
        Material::neo_hookean(5e3, 0.4),
    ];
    let mut p = Particles::new();
    for i in 0..4000 {
        let x = DVec3::splat(0.5) + rv() * 0.35;
        p.push(x, rv() * 2.0, 0.5 + rv().x.abs(), 1e-4, i % 2, 0.0);
        let q = i as usize;
        p.c[q] = DMat3::from_cols(rv(), rv(), rv()) * 10.0;
        p.f[q] = DMat3::IDENTITY + DMat3::from_cols(rv(), rv(), rv()) * 0.2;
    }
    let dt = 1e-3;
    cpu::p2g(&p, &mut g, &mats, dt, Transfer::Apic, Default::default());
    let origin = DVec3::splat(0.5);
    let sum_m: f64 = p.mass.iter().map(|m| m.abs()).sum();
    let sum_p: f64 = (0..p.len()).map(|q| p.mass[q] * p.v[q].length()).sum();
    let em = (g.total_mass() - p.total_mass()).abs() / sum_m;
    let ep = (g.total_momentum() - p.momentum()).length() / sum_p;
    let l_grid = g.angular_momentum(origin);
    let l_part = p.angular_momentum(origin, dx, true);
    let el = (l_grid - l_part).length() / (sum_p * 0.5);
    // Without the spin term the books do not balance: APIC's C carries real angular momentum.
    let el_orbital = (l_grid - p.angular_momentum(origin, dx, false)).length() / (sum_p * 0.5);
    println!(
        "P2G: relative error mass {em:.1e}, momentum {ep:.1e}, angular momentum {el:.1e} \
         (tol 1e-13; orbital part alone would be off by {el_orbital:.1e})"
    );
    assert!(em < 1e-13 && ep < 1e-13 && el < 1e-13);
    assert!(el_orbital > 1e-6);
}

/// Test 3: A rigidly rotating elastic ball (v = ω × r, C = skew(ω)), no gravity, no wall
/// touched: APIC keeps its angular momentum within 1% over 100 steps (it conserves it to
/// round-off: transfers, advection and symmetric stress all preserve Σ x × m v + spin).
/// PIC filters the rotation through the grid every step and loses a large share of it;
/// FLIP carries the particles' own velocities and loses little; a blend lies in between,
/// in the order of its FLIP share.
#[test]
fn rigid_rotation_keeps_angular_momentum_with_apic() {
    let dx = 1.0 / 24.0;
    let density = 1000.0;
    let mat = Material::fixed_corotated(1e5, 0.3);
    let mats = [mat];
    let center = DVec3::splat(0.5);
    let omega = DVec3::new(1.0, 2.0, 3.0).normalize() * 6.0;
    let mut p0 = Particles::sample_sphere(center, 0.25, dx / 2.0, density);
    for q in 0..p0.len() {
        p0.v[q] = omega.cross(p0.x[q] - center);
        p0.c[q] = skew(omega);
    }
    let dt = cfl_dt(&mat, density, dx, 0.4);
    let steps = 100;
    let mut drift = [0.0; 4];
    for (slot, transfer) in TRANSFERS.into_iter().enumerate() {
        let mut p = p0.clone();
        let mut g = Grid::new(DVec3::ZERO, DVec3::ONE, dx);
        let sp = StepParams {
            transfer,
            ..params(dt, DVec3::ZERO, Boundaries::default())
        };
        let apic = transfer.apic();
        let l0 = p.angular_momentum(center, dx, apic);
        let mut worst = 0.0f64;
        run(&mut p, &mut g, &mats, &sp, steps, |_, p| {
            let l = p.angular_momentum(p.center_of_mass(), dx, apic);
            worst = worst.max((l - l0).length() / l0.length());
        });
        drift[slot] = worst;
    }
    println!(
        "rigid rotation, {} particles, {steps} steps of Δt = {dt:.2e} (ω t = {:.2} rad): \
         max |ΔL|/|L| APIC = {:.1e} (tol 1e-2), PIC = {:.1e}, FLIP 0.7 = {:.1e}, FLIP 1 = {:.1e}",
        p0.len(),
        omega.length() * dt * steps as f64,
        drift[0],
        drift[1],
        drift[2],
        drift[3]
    );
    assert!(drift[0] < 1e-2);
    assert!(drift[1] > 0.2, "PIC should lose much of the rotation");
    assert!(drift[3] < 0.05, "FLIP should keep the rotation");
    assert!(drift[1] > drift[2] && drift[2] > drift[3], "{drift:?}");
}

/// Test 3b: An elastic ball in free flight, translating and spinning, no gravity, no wall
/// touched. Every transfer conserves linear momentum (P2G and G2P both do, and the
/// internal forces sum to zero): M v₀ to 1e-12 relative. Energy (kinetic + elastic): PIC
/// keeps the translation and dissipates the spin, so what it keeps is the translation's
/// share ½ M |v₀|² / E₀ (within 0.02); pure FLIP keeps the energy (within 3%); a blend
/// keeps more than PIC.
#[test]
fn flip_pic_blend_conserves_momentum_and_orders_dissipation() {
    let dx = 1.0 / 24.0;
    let density = 1000.0;
    let mat = Material::fixed_corotated(1e5, 0.3);
    let mats = [mat];
    let center = DVec3::splat(0.5);
    let (v0, omega) = (DVec3::new(0.4, -0.2, 0.1), DVec3::new(0.0, 3.0, 4.0));
    let mut p0 = Particles::sample_sphere(center, 0.2, dx / 2.0, density);
    for q in 0..p0.len() {
        p0.v[q] = v0 + omega.cross(p0.x[q] - center);
        p0.c[q] = skew(omega);
    }
    let dt = cfl_dt(&mat, density, dx, 0.4);
    let steps = 100;
    let energy = |p: &Particles| -> f64 {
        (0..p.len())
            .map(|q| {
                let psi = mat.elastic_model().energy_density(p.f[q], &mat.lame());
                0.5 * p.mass[q] * p.v[q].length_squared() + psi * p.volume0[q]
            })
            .sum()
    };
    let e0 = energy(&p0);
    let m0 = p0.momentum();
    let mut kept = Vec::new();
    for transfer in TRANSFERS {
        let mut p = p0.clone();
        let mut g = Grid::new(DVec3::ZERO, DVec3::ONE, dx);
        let sp = StepParams {
            transfer,
            ..params(dt, DVec3::ZERO, Boundaries::default())
        };
        let mut dm = 0.0f64;
        run(&mut p, &mut g, &mats, &sp, steps, |_, p| {
            dm = dm.max((p.momentum() - m0).length() / m0.length());
        });
        let share = energy(&p) / e0;
        println!("{transfer:?}: energy kept {share:.4}, max |ΔP|/|P| {dm:.1e} (tol 1e-12)");
        assert!(dm < 1e-12, "{transfer:?}: momentum drift {dm:e}");
        kept.push(share);
    }
    let translation = 0.5 * p0.total_mass() * v0.length_squared() / e0;
    let (apic, pic, blend, flip) = (kept[0], kept[1], kept[2], kept[3]);
    println!("translation's share of the energy: {translation:.4}");
    assert!((apic - 1.0).abs() < 0.01, "APIC keeps the energy: {apic}");
    assert!((flip - 1.0).abs() < 0.03, "FLIP keeps the energy: {flip}");
    assert!(
        (pic - translation).abs() < 0.02,
        "PIC keeps the translation only: {pic} against {translation}"
    );
    assert!(
        blend > pic + 0.01,
        "the blend keeps more than PIC: {kept:?}"
    );
}

/// Test 4: First axial mode of an elastic bar clamped at one end: period 4L/c within 3%.
///
/// A block (0.1 × 0.04 × 0.04 m along slope, normal, z; E = 1e5 Pa, ν = 0.3, ρ = 1000)
/// released at rest on a plane inclined at θ (going down towards +x) with Coulomb friction
/// μ. Gravity is switched on linearly over `ramp` seconds (0: at once). Returns (least-
/// squares acceleration along the slope of the centre-of-mass velocity over
/// t ∈ [t_fit, t_end], displacement of the centre of mass along the slope at t_end,
/// particle count).
fn incline(theta_deg: f64, mu: f64, t_end: f64, ramp: f64, t_fit: f64) -> (f64, f64, usize) {
    let theta = theta_deg.to_radians();
    let dx = 0.01;
    let density = 1000.0;
    let mat = Material::fixed_corotated(1e5, 0.3);
    let mats = [mat];
    let tangent = DVec3::new(theta.cos(), -theta.sin(), 0.0);
    let normal = DVec3::new(theta.sin(), theta.cos(), 0.0);
    let size = DVec3::new(0.1, 0.04, 0.04);
    let pad = 5.0 * dx; // band + margin
    let travel = 0.5 * G * theta.sin() * t_end * t_end + 0.02;
    let run_len = size.x + travel;
    // The plane passes through `origin`; the block starts at s ∈ [0, size.x] along it.
    let drop = run_len * theta.sin() + pad;
    let origin = DVec3::new(pad + size.y * theta.sin(), drop, pad);
    let hi = DVec3::new(
        origin.x + run_len * theta.cos() + pad,
        drop + size.y / theta.cos() + pad,
        2.0 * pad + size.z,
    );
    let mut g = Grid::new(DVec3::ZERO, hi, dx);
    let collider = PlaneCollider {
        point: origin,
        normal,
        condition: Condition::SEPARATE.with_friction(mu),
    };
    let local = Particles::sample_box(DVec3::ZERO, size, dx / 2.0, density);
    let mut p = local.clone();
    for q in 0..p.len() {
        let l = local.x[q];
        p.x[q] = origin + tangent * l.x + normal * l.y + DVec3::Z * l.z;
    }
    let dt = cfl_dt(&mat, density, dx, 0.4);
    let steps = (t_end / dt).ceil() as usize;
    let mut sp = params(
        dt,
        DVec3::ZERO,
        Boundaries {
            walls: DomainWalls::uniform(Condition::SEPARATE),
            colliders: vec![collider],
            surface: None,
        },
    );
    let com0 = p.center_of_mass();
    let (mut ts, mut vs) = (Vec::new(), Vec::new());
    for n in 1..=steps {
        let t = n as f64 * dt;
        let s = if ramp > 0.0 { (t / ramp).min(1.0) } else { 1.0 };
        sp.gravity = DVec3::new(0.0, -G * s, 0.0);
        assert_eq!(step(&mut p, &mut g, &mats, &sp).escaped, 0);
        if let Some(msg) = check(&p, &g, dt).message(n as u64) {
            panic!("{msg}");
        }
        if t >= t_fit {
            ts.push(t);
            vs.push(p.momentum().dot(tangent) / p.total_mass());
        }
    }
    let disp = (p.center_of_mass() - com0).dot(tangent);
    let nf = ts.len() as f64;
    let (mt, mv) = (ts.iter().sum::<f64>() / nf, vs.iter().sum::<f64>() / nf);
    let sxy: f64 = ts.iter().zip(&vs).map(|(t, v)| (t - mt) * (v - mv)).sum();
    let sxx: f64 = ts.iter().map(|t| (t - mt) * (t - mt)).sum();
    (sxy / sxx, disp, p.len())
}

/// Test 5: Frictional incline (planar collider, `separate` with Coulomb μ).
///
/// Sliding (tan θ > μ), gravity on at once: the acceleration along the slope, fitted to
/// the centre-of-mass velocity over t ∈ [0.05, 0.25] s (after the contact has formed), is
/// g(sin θ − μ cos θ) within 5%, for μ = 0 and μ = 0.3 at θ = 30°.
///
/// Sticking (θ = 20°, μ = 0.5, tan θ = 0.36 < μ): the block is loaded quasi-statically
/// (gravity ramped in over 0.05 s, ~4 periods of the block's normal vibration) and then
/// its displacement along the slope at t = 0.25 s must stay below 1% of the free-slide
/// distance ½ g sin θ t². Switched on at once, the undamped elastic block's contact force
/// swings between 0 and twice its weight, so it slips a little while it is unloaded; that
/// number is printed too and only has to stay ≪ the free slide (< 5%).
#[test]
fn block_on_frictional_incline() {
    let t_end = 0.25;
    for (theta, mu) in [(30.0f64, 0.0), (30.0, 0.3)] {
        let th = theta.to_radians();
        let want = G * (th.sin() - mu * th.cos());
        let (a, _, n) = incline(theta, mu, t_end, 0.0, 0.05);
        let err = a / want - 1.0;
        println!(
            "incline θ = {theta}°, μ = {mu}, {n} particles: a = {a:.4} m/s² vs \
             g(sinθ − μcosθ) = {want:.4} ({:+.2}%, tol 5%)",
            100.0 * err
        );
        assert!(err.abs() < 0.05);
    }
    let (theta, mu) = (20.0f64, 0.5);
    let th = theta.to_radians();
    let free = 0.5 * G * th.sin() * t_end * t_end;
    for (ramp, tol) in [(0.05, 0.01), (0.0, 0.05)] {
        let (_, d, n) = incline(theta, mu, t_end, ramp, t_end);
        println!(
            "incline θ = {theta}°, μ = {mu} (tanθ = {:.3} < μ), {n} particles, gravity ramp \
             {ramp} s: displacement {d:.2e} m vs free slide {free:.3} m (ratio {:.1e}, tol \
             {tol})",
            th.tan(),
            d.abs() / free
        );
        assert!(d.abs() < tol * free);
    }
}

/// Test 6: NACC smoke test: a small NACC sphere (the paper's fruit parameters, `continuous`
/// k = 2) thrown at 4 m/s onto a sticky ground stays finite for 400 steps (no NaN/Inf, no
/// particle outside), and α changes where it hits: more than a quarter of the particles of
/// the sphere's lowest quarter have |Δα| > 1e-3. Also prints the reference step's cost.
#[test]
fn nacc_sphere_hits_sticky_ground() {
    let dx = 0.02;
    let density = 2.0;
    let params_nacc = NaccParams {
        e: 2000.0,
        nu: 0.38,
        alpha0: -0.04,
        beta: 1.0,
        xi: 2.0,
        m_slope: 2.36,
    };
    let mat = Material::nacc(params_nacc, Case3Variant::Continuous { k: 2.0 });
    let mats = [mat];
    let mut g = Grid::new(DVec3::ZERO, DVec3::new(0.4, 0.4, 0.4), dx);
    let (center, radius) = (DVec3::new(0.2, 0.17, 0.2), 0.08);
    let mut p = Particles::sample_sphere(center, radius, dx / 2.0, density);
    p.set_material(0, &mat);
    let v0 = DVec3::new(0.0, -4.0, 0.0);
    p.v.iter_mut().for_each(|v| *v = v0);
    let x0 = p.x.clone();
    let dt = cfl_dt(&mat, density, dx, 0.4);
    let walls = DomainWalls::with_ground(Condition::STICKY, Condition::SEPARATE);
    let sp = params(
        dt,
        DVec3::new(0.0, -G, 0.0),
        Boundaries {
            walls,
            colliders: vec![],
            surface: None,
        },
    );
    let steps = 400;
    let clock = std::time::Instant::now();
    run(&mut p, &mut g, &mats, &sp, steps, |_, _| {});
    let ns = clock.elapsed().as_secs_f64() * 1e9 / (steps * p.len()) as f64;
    let a0 = params_nacc.alpha0;
    let bottom: Vec<usize> = (0..p.len())
        .filter(|&q| x0[q].y < center.y - 0.5 * radius)
        .collect();
    let changed = bottom
        .iter()
        .filter(|&&q| (p.alpha[q] - a0).abs() > 1e-3)
        .count();
    let (amin, amax) = p
        .alpha
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(*x), b.max(*x)));
    let fractured = p.alpha.iter().filter(|a| **a >= 0.0).count();
    let finite = check(&p, &g, dt);
    println!(
        "NACC sphere, {} particles, {steps} steps of {dt:.2e} s: non-finite {}, outside {}; \
         α ∈ [{amin:.3}, {amax:.3}] (α₀ = {a0}); {changed}/{} bottom-quarter particles have \
         |Δα| > 1e-3; {fractured} particles with α ≥ 0; centre of mass y {:.3} → {:.3}; \
         {ns:.0} ns per particle-step ({} threads, step + check)",
        p.len(),
        finite.non_finite,
        finite.outside,
        bottom.len(),
        center.y,
        p.center_of_mass().y,
        rayon::current_num_threads()
    );
    assert!(finite.is_ok());
    assert!(changed * 4 > bottom.len(), "α barely changed at the impact");
}

/// The textbook step (`sim::cpu::textbook`, three plain loops) and the reference step (a
/// sorted gather in parallel, every option) compute the same MPM: an elastic ball thrown
/// spinning at the floor of a box with `separate` walls, 120 steps through its impact and
/// rebound. Positions agree to 1e-9 Δx and F to 1e-9 (only the summation order differs;
/// measured about 1e-13). A wrong weight, stress sign or wall in either would part them by
/// far more.
#[test]
fn the_textbook_step_equals_the_reference_step() {
    use splatter::sim::cpu::textbook::{self, Textbook};
    use splatter::sim::{Lame, WALL_BAND};
    let dx = 1.0 / 24.0;
    let density = 1000.0;
    let (e, nu) = (2e4, 0.3);
    let mat = Material::fixed_corotated(e, nu);
    let center = DVec3::new(0.5, 0.3, 0.5);
    let omega = DVec3::new(0.3, 1.0, 0.2) * 4.0;
    let mut reference = Particles::sample_sphere(center, 0.15, dx / 2.0, density);
    for q in 0..reference.len() {
        reference.v[q] = DVec3::new(0.4, -3.0, 0.1) + omega.cross(reference.x[q] - center);
        reference.c[q] = skew(omega);
    }
    let mut plain = reference.clone();
    let dt = cfl_dt(&mat, density, dx, 0.4);
    let gravity = DVec3::new(0.0, -G, 0.0);
    let mut grid = Grid::new(DVec3::ZERO, DVec3::ONE, dx);
    let sp = params(dt, gravity, Boundaries::default());
    let t = Textbook {
        lo: grid.lo,
        dx,
        cells: grid.cells,
        dt,
        gravity,
        lame: Lame::from_young_poisson(e, nu),
        band: WALL_BAND,
    };
    let (mut dx_worst, mut f_worst, mut lowest) = (0.0f64, 0.0f64, f64::MAX);
    for _ in 0..120 {
        step(&mut reference, &mut grid, &[mat], &sp);
        textbook::step(&mut plain, &t);
        for q in 0..plain.len() {
            dx_worst = dx_worst.max((plain.x[q] - reference.x[q]).length() / dx);
            f_worst = f_worst.max(max_abs(plain.f[q] - reference.f[q]));
            lowest = lowest.min(plain.x[q].y);
        }
    }
    println!(
        "textbook against reference, {} particles, 120 steps: max |Δx| {dx_worst:.1e} Δx, \
         max |ΔF| {f_worst:.1e}, lowest particle at y = {lowest:.3} (the walls act below {:.3})",
        plain.len(),
        WALL_BAND as f64 * dx
    );
    assert!(
        lowest < (WALL_BAND as f64 + 1.0) * dx,
        "the ball should reach the floor"
    );
    assert!(dx_worst < 1e-9 && f_worst < 1e-9);
}
