//! Snow packed under load: a block of Stomakhin et al.'s reference snow in a frictionless
//! box, pressed by a plate (`splatter_lab::snow_press`, docs/notes/snow.md *Snow*).
//!
//! `cargo run --release --example snow_press [-- COMPRESSION [SPEED]]`
//!
//! Prints twenty samples: compression 1 − H/H₀, the density ratio ρ/ρ₀ against H₀/H and
//! against H₀/H with H to the plate's first grid node (mass conservation in the confined
//! box; and the particles' own: the rest distance of the top and bottom layers over the
//! current one), the plastic part 1/Jᴾ (mean, largest), the
//! pressure on the plate and Δt (which shrinks as the packed snow stiffens).

use anyhow::{Context, Result};
use splatter_lab::snow_press::{run, PressSpec};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut spec = PressSpec::reference();
    if let Some(c) = args.first() {
        spec.compression = c.parse().context("COMPRESSION")?;
    }
    if let Some(s) = args.get(1) {
        spec.speed = s.parse().context("SPEED")?;
    }
    let clock = std::time::Instant::now();
    let r = run(&spec);
    println!(
        "{} particles, {} steps, {:.1} s, healthy {}",
        r.particles,
        r.steps,
        clock.elapsed().as_secs_f64(),
        r.healthy
    );
    println!(
        "compression | rho/rho0 | H0/H    | H0/H_node | layers  | 1/Jp mean | 1/Jp max | pressure (Pa) | dt"
    );
    let every = (r.samples.len() / 20).max(1);
    for (i, s) in r.samples.iter().enumerate() {
        if i % every == 0 || i + 1 == r.samples.len() {
            println!(
                "{:11.4} | {:8.4} | {:7.4} | {:9.4} | {:7.4} | {:9.4} | {:8.4} | {:13.1} | {:.2e}",
                s.compression,
                s.density_ratio,
                1.0 / (1.0 - s.compression),
                s.confined_ratio,
                s.layer_ratio,
                s.plastic_mean,
                s.plastic_max,
                s.pressure,
                s.dt
            );
        }
    }
    Ok(())
}
