//! A bar pulled past yield (von Mises, `sim::model::VonMises`) on the CPU reference step
//! (f64): the validation of docs/notes/metal.md, *Metal and plasticine: a bar pulled past
//! yield*, shared by `lab/examples/von_mises_bar.rs` and `lab/tests/plastic_bar.rs`.
//!
//! The bar lies along x between two grips: the nodes at or beyond each end of the gauge
//! length L get a prescribed velocity ±v(t) (all three components, so the grips also hold
//! the cross-section), and the material runs `grip` further into each grip. Loading starts
//! from the uniform stretching field v = ε̇ (x − x_mid) (C = ε̇ e_x e_xᵀ), which is an exact
//! steady solution of a uniform bar pulled at a constant rate — so the loading carries no
//! wave, and the only departure from uniaxial stress is the grips' lateral hold near the
//! ends. The phases:
//!
//! 1. **load** at the grip speed v₀ = ε̇ L/2 until the nominal strain reaches the peak;
//! 2. **reverse** the grip speed from +v₀ to −v₀ along a half cosine over `reverse_transits`
//!    wave transits (no net grip displacement over the ramp);
//! 3. **unload** at −v₀ until the gauge's mean axial Kirchhoff stress crosses zero: the
//!    gauge strain there is the permanent set at zero load;
//! 4. **release**: the particles are brought to rest (a quasi-static unloading ends at
//!    rest), the grips let go, and the bar runs free for `release_transits` transits; the
//!    mean gauge strain over the second half is the permanent set after release (it differs
//!    from phase 3's by what the residual stresses at the grips spring back).
//!
//! Measured on the gauge, the particles whose rest x is within L/4 of the middle: its
//! logarithmic strain ε = ln(ℓ/ℓ₀) (ℓ between the mean x of its end layers), its mean axial
//! Kirchhoff stress τ_xx (`Material::kirchhoff` of each particle's F), and the axial force
//! F = Σ τ_xx V⁰ / ℓ_g (ℓ_g its current length: the volume average of the Cauchy stress
//! σ = τ/J over a slice, times its volume J V⁰, over its length). With St. Venant–Kirchhoff
//! Hencky elasticity the uniaxial answer is exactly bilinear in (ε, τ): τ = E ε up to
//! σ_y, then slope E H/(E + H) (τ = σ_y + H ε̄ᴾ, ε = τ/E + ε̄ᴾ). For a uniform gauge
//! F = τ A₀ e^{−ε}, so the analytic yield load is F_y = σ_y A₀ e^{−σ_y/E}, σ_y A₀ to within
//! the yield strain.
//! The yield point is measured by a bilinear fit: a line through the samples with
//! ε < ½ ε_y, another through those with ε > 1.5 ε_y (up to the peak), and their
//! intersection.

use glam::{DMat3, DVec3, UVec3};

use crate::driven::driven_step;
use splatter::sim::model::VonMises;
use splatter::sim::{
    cfl_dt, Boundaries, Condition, DomainWalls, Grid, Material, Particles, StepParams, Transfer,
};

/// The bar and its loading.
#[derive(Clone, Copy, Debug)]
pub struct BarSpec {
    /// Gauge length between the grips, m.
    pub length: f64,
    /// Side of the square cross-section, m.
    pub width: f64,
    /// Grid spacing Δx.
    pub dx: f64,
    /// Particles per cell per axis.
    pub ppc_axis: u32,
    /// Young's modulus, Poisson ratio, density.
    pub e: f64,
    pub nu: f64,
    pub density: f64,
    /// The material's σ_y and H.
    pub law: VonMises,
    /// Peak nominal strain of the grips (ΔL/L) at the end of loading.
    pub peak_strain: f64,
    /// Loading time in wave transits L/c (c = √(E/ρ)); sets the strain rate.
    pub load_transits: f64,
    /// Transits of the reversal ramp.
    pub reverse_transits: f64,
    /// Transits run free after release (0: stop after unloading).
    pub release_transits: f64,
    /// CFL number of Δt (P-wave speed).
    pub cfl: f64,
}

impl BarSpec {
    /// The validation bar: 0.2 × 0.04 × 0.04 m at Δx 0.005 (8 cells across, 2³ particles
    /// per cell), plasticine-like E 1 MPa, ν 0.3, ρ 1000, σ_y 10 kPa (yield strain 1%),
    /// H 100 kPa, pulled to 3% over 10 transits.
    pub fn reference() -> Self {
        BarSpec {
            length: 0.2,
            width: 0.04,
            dx: 0.005,
            ppc_axis: 2,
            e: 1e6,
            nu: 0.3,
            density: 1000.0,
            law: VonMises {
                yield_stress: 1e4,
                hardening: 1e5,
            },
            peak_strain: 0.03,
            load_transits: 10.0,
            reverse_transits: 4.0,
            release_transits: 10.0,
            cfl: 0.4,
        }
    }

    /// Uniaxial yield strain σ_y/E.
    pub fn yield_strain(&self) -> f64 {
        self.law.yield_stress / self.e
    }

    /// Slope dτ/dε after yield in uniaxial stress, E H/(E + H).
    pub fn hardening_slope(&self) -> f64 {
        self.e * self.law.hardening / (self.e + self.law.hardening)
    }

    /// Initial cross-section A₀.
    pub fn area(&self) -> f64 {
        self.width * self.width
    }
}

/// The loading phase of a sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    Load,
    Reverse,
    Unload,
    Release,
}

/// One sample of the gauge, after a step.
#[derive(Clone, Copy, Debug)]
pub struct BarSample {
    pub t: f64,
    pub phase: Phase,
    /// Logarithmic gauge strain ln(ℓ/ℓ₀).
    pub strain: f64,
    /// Mean axial Kirchhoff stress over the gauge, Pa.
    pub tau: f64,
    /// Axial force through the gauge, N.
    pub force: f64,
    /// Mean equivalent plastic strain α over the gauge.
    pub alpha: f64,
}

/// What a run measured.
#[derive(Clone, Debug)]
pub struct BarResult {
    pub samples: Vec<BarSample>,
    pub particles: usize,
    pub steps: usize,
    pub dt: f64,
    /// Bilinear fit (None when the peak stayed below 1.5 ε_y): the yield strain and stress
    /// at the intersection, the elastic slope and the hardening slope.
    pub fit: Option<BilinearFit>,
    /// The largest gauge strain and the stress there.
    pub peak: (f64, f64),
    /// Gauge strain where τ crossed zero in unloading (None if it never did).
    pub set_at_zero_load: Option<f64>,
    /// Mean gauge strain over the second half of the release (None without release).
    pub set_after_release: Option<f64>,
    /// Largest gauge α.
    pub max_alpha: f64,
    /// Whether every step stayed finite and on the grid.
    pub healthy: bool,
}

/// Two lines fitted to the elastic and the hardening branch, and where they meet.
#[derive(Clone, Copy, Debug)]
pub struct BilinearFit {
    pub elastic_slope: f64,
    pub hardening_slope: f64,
    pub yield_strain: f64,
    pub yield_stress: f64,
}

/// Least-squares line y = a + b x; (a, b).
fn line(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    let n = points.len() as f64;
    if points.len() < 2 {
        return None;
    }
    let (sx, sy) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), &(x, y)| (a + x, b + y));
    let (mx, my) = (sx / n, sy / n);
    let (sxx, sxy) = points.iter().fold((0.0, 0.0), |(a, b), &(x, y)| {
        (a + (x - mx) * (x - mx), b + (x - mx) * (y - my))
    });
    (sxx > 0.0).then(|| {
        let b = sxy / sxx;
        (my - b * mx, b)
    })
}

/// The bilinear fit of the loading branch (module docs).
pub fn bilinear_fit(samples: &[BarSample], yield_strain: f64) -> Option<BilinearFit> {
    let load: Vec<(f64, f64)> = samples
        .iter()
        .filter(|s| s.phase == Phase::Load)
        .map(|s| (s.strain, s.tau))
        .collect();
    let elastic: Vec<_> = load
        .iter()
        .copied()
        .filter(|&(e, _)| e < 0.5 * yield_strain)
        .collect();
    let plastic: Vec<_> = load
        .iter()
        .copied()
        .filter(|&(e, _)| e > 1.5 * yield_strain)
        .collect();
    let (a1, b1) = line(&elastic)?;
    let (a2, b2) = line(&plastic)?;
    let x = (a2 - a1) / (b1 - b2);
    Some(BilinearFit {
        elastic_slope: b1,
        hardening_slope: b2,
        yield_strain: x,
        yield_stress: a1 + b1 * x,
    })
}

/// Runs the bar (module docs).
pub fn run(spec: &BarSpec) -> BarResult {
    let dx = spec.dx;
    let spacing = dx / f64::from(spec.ppc_axis);
    let grip = 2.0 * dx;
    let pad = 6.0 * dx;
    let stretch_room = spec.length * (spec.peak_strain + 0.02);
    // The gauge ends xa, xb on nodes; the bar's rest span [xa − grip, xb + grip].
    let xa = ((pad + stretch_room / 2.0 + grip) / dx).ceil() * dx;
    let cells_long = (spec.length / dx).round();
    let xb = xa + cells_long * dx;
    let length = xb - xa;
    let y0 = pad;
    let hi = DVec3::new(
        xb + grip + stretch_room / 2.0 + pad,
        y0 + spec.width + pad,
        y0 + spec.width + pad,
    );
    let mut grid = Grid::new(DVec3::ZERO, hi, dx);
    let mut p = Particles::sample_box(
        DVec3::new(xa - grip, y0, y0),
        DVec3::new(xb + grip, y0 + spec.width, y0 + spec.width),
        spacing,
        spec.density,
    );
    let mat = Material::plastic(spec.law, spec.e, spec.nu);
    let materials = [mat];
    let x_mid = 0.5 * (xa + xb);
    let c_bar = (spec.e / spec.density).sqrt();
    let transit = length / c_bar;
    let rate = spec.peak_strain / (spec.load_transits * transit);
    let v0 = 0.5 * rate * length;
    for q in 0..p.len() {
        let s = (p.x[q].x - x_mid).clamp(-0.5 * length, 0.5 * length);
        p.v[q] = DVec3::X * (rate * s);
        if (p.x[q].x - x_mid).abs() < 0.5 * length {
            p.c[q] = DMat3::from_cols(DVec3::X * rate, DVec3::ZERO, DVec3::ZERO);
        }
    }
    // The gauge and its end layers (rest lattice columns).
    let x0 = p.x.clone();
    let col = |x: f64| ((x - (xa - grip)) / spacing).floor() as i64;
    let (ca, cb) = (col(x_mid - 0.25 * length), col(x_mid + 0.25 * length));
    let gauge: Vec<usize> = (0..p.len())
        .filter(|&q| (ca..=cb).contains(&col(x0[q].x)))
        .collect();
    let layer_a: Vec<usize> = gauge
        .iter()
        .copied()
        .filter(|&q| col(x0[q].x) == ca)
        .collect();
    let layer_b: Vec<usize> = gauge
        .iter()
        .copied()
        .filter(|&q| col(x0[q].x) == cb)
        .collect();
    let l0 = (cb - ca) as f64 * spacing;
    let region0 = (cb - ca + 1) as f64 * spacing;
    let mean_x = |p: &Particles, idx: &[usize]| {
        idx.iter().map(|&q| p.x[q].x).sum::<f64>() / idx.len() as f64
    };

    let dt = cfl_dt(&mat, spec.density, dx, spec.cfl);
    let params = StepParams {
        dt,
        gravity: DVec3::ZERO,
        boundaries: Boundaries {
            walls: DomainWalls::uniform(Condition::SEPARATE),
            colliders: vec![],
            surface: None,
        },
        transfer: Transfer::Apic,
        separation: Default::default(),
        fields: Default::default(),
        actions: Default::default(),
    };
    let t_load = spec.load_transits * transit;
    let t_rev = spec.reverse_transits * transit;
    let t_release = spec.release_transits * transit;
    // Grip nodes: at or beyond the gauge ends.
    let nodes = grid.nodes();
    let grip_side = |i: UVec3| -> f64 {
        let x = grid.lo.x + f64::from(i.x) * dx;
        if x <= xa + 1e-9 * dx {
            -1.0
        } else if x >= xb - 1e-9 * dx {
            1.0
        } else {
            0.0
        }
    };
    let sides: Vec<f64> = (0..grid.node_count())
        .map(|idx| {
            let n = nodes;
            let (nx, ny) = (n.x as usize, n.y as usize);
            grip_side(UVec3::new(
                (idx % nx) as u32,
                ((idx / nx) % ny) as u32,
                (idx / (nx * ny)) as u32,
            ))
        })
        .collect();

    let mut samples = Vec::new();
    let mut phase = Phase::Load;
    let mut t = 0.0;
    let mut phase_start = 0.0;
    let mut healthy = true;
    let mut set_at_zero_load = None;
    let mut steps = 0usize;
    let max_steps = ((t_load + t_rev + 4.0 * t_load + t_release) / dt).ceil() as usize;
    while steps < max_steps {
        // The grip speed (None: released).
        let speed = match phase {
            Phase::Load => Some(v0),
            Phase::Reverse => {
                let s = ((t - phase_start) / t_rev).min(1.0);
                Some(v0 * (std::f64::consts::PI * s).cos())
            }
            Phase::Unload => Some(-v0),
            Phase::Release => None,
        };
        // The grips: their nodes move apart (or together) along x at the grip speed.
        let pull = |grid: &mut Grid| {
            let Some(speed) = speed else { return };
            for (idx, v) in grid.velocity.iter_mut().enumerate() {
                if sides[idx] != 0.0 && grid.mass[idx] > 0.0 {
                    *v = DVec3::X * (sides[idx] * speed);
                }
            }
        };
        let ok = driven_step(&mut p, &mut grid, &materials, &params, pull);
        steps += 1;
        t += dt;
        if !ok {
            healthy = false;
            break;
        }
        let l = mean_x(&p, &layer_b) - mean_x(&p, &layer_a);
        let strain = (l / l0).ln();
        let (mut tau_sum, mut tv_sum, mut alpha_sum) = (0.0, 0.0, 0.0);
        for &q in &gauge {
            let tau = mat.kirchhoff(p.f[q], p.alpha[q]).x_axis.x;
            tau_sum += tau;
            tv_sum += tau * p.volume0[q];
            alpha_sum += p.alpha[q];
        }
        let n = gauge.len() as f64;
        let sample = BarSample {
            t,
            phase,
            strain,
            tau: tau_sum / n,
            force: tv_sum / (region0 * strain.exp()),
            alpha: alpha_sum / n,
        };
        // Phase changes.
        match phase {
            Phase::Load if t >= t_load => {
                phase = Phase::Reverse;
                phase_start = t;
            }
            Phase::Reverse if t - phase_start >= t_rev => {
                phase = Phase::Unload;
                phase_start = t;
            }
            Phase::Unload if sample.tau <= 0.0 => {
                let prev = samples.last().copied().unwrap_or(sample);
                let w = prev.tau / (prev.tau - sample.tau);
                set_at_zero_load = Some(prev.strain + w * (sample.strain - prev.strain));
                if spec.release_transits <= 0.0 {
                    samples.push(sample);
                    break;
                }
                for q in 0..p.len() {
                    p.v[q] = DVec3::ZERO;
                    p.c[q] = DMat3::ZERO;
                }
                phase = Phase::Release;
                phase_start = t;
            }
            Phase::Release if t - phase_start >= t_release => {
                samples.push(sample);
                break;
            }
            _ => {}
        }
        samples.push(sample);
    }
    let yield_strain = spec.yield_strain();
    let peak = samples
        .iter()
        .map(|s| (s.strain, s.tau))
        .fold((f64::MIN, 0.0), |a, b| if b.0 > a.0 { b } else { a });
    let fit = if peak.0 > 2.0 * yield_strain {
        bilinear_fit(&samples, yield_strain)
    } else {
        None
    };
    let release: Vec<&BarSample> = samples
        .iter()
        .filter(|s| s.phase == Phase::Release && s.t - phase_start >= 0.5 * t_release)
        .collect();
    let set_after_release = (phase == Phase::Release && !release.is_empty())
        .then(|| release.iter().map(|s| s.strain).sum::<f64>() / release.len() as f64);
    let max_alpha = gauge.iter().map(|&q| p.alpha[q]).fold(0.0, f64::max);
    BarResult {
        samples,
        particles: p.len(),
        steps,
        dt,
        fit,
        peak,
        set_at_zero_load,
        set_after_release,
        max_alpha,
        healthy,
    }
}
