//! A scene's simulation on the CPU reference step (`sim::cpu`, f64), frame by frame, with
//! each simulated object's fragments: a way to try what the GPU step does not have yet
//! (two-field separation) on a real scene.
//!
//! `cargo run --release --example cpu_reference -- SCENE.json FRAMES [scene|one|two]`
//!
//! Prints per frame and object: pieces (solid fragments with ≥ 1% of the particles), the
//! largest one's share, the share broken through, the same count linking every particle,
//! the fastest particle and the wall time so far.

use std::time::Instant;

use anyhow::{bail, Context, Result};
use splatter::fragments::{fragment_ids, solid_fragment_ids, FragmentSummary, PIECE_SHARE};
use splatter::sim::cpu::{check, step_at};
use splatter::sim::Separation;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene_path, frames, rest @ ..] = args.as_slice() else {
        bail!("usage: cpu_reference SCENE.json FRAMES [scene|one|two]");
    };
    let frames: u32 = frames.parse().context("FRAMES")?;
    let separation = match rest.first().map(String::as_str) {
        None | Some("scene") => None,
        Some("one") => Some(Separation::None),
        Some("two") => Some(Separation::DamageGradient),
        Some(other) => bail!("unknown field mode {other:?}: scene, one or two"),
    };
    let scene = splatter::scene::load(std::path::Path::new(scene_path))?;
    let (splats, report) = scene.build_splats()?;
    let Some(mut s) = splatter::scene::simulation::prepare(&scene, splats, &report)? else {
        bail!("{scene_path} simulates nothing");
    };
    if !s.kinematic.is_empty() {
        bail!("moving colliders are not driven here");
    }
    if let Some(separation) = separation {
        s.params.separation = separation;
    }
    println!(
        "{} particles, dx {}, dt {:.3e}, {} steps per frame, {:?}",
        s.particles.len(),
        s.grid.dx,
        s.params.dt,
        s.steps_per_frame,
        s.params.separation
    );
    let clock = Instant::now();
    let mut n = 0u64;
    for frame in 1..=frames {
        for _ in 0..s.steps_per_frame {
            let t = n as f64 * s.params.dt;
            step_at(
                &mut s.particles,
                &mut s.grid,
                &s.materials,
                &s.params,
                &[],
                t,
            );
            n += 1;
            if let Some(msg) = check(&s.particles, &s.grid, s.params.dt).message(n) {
                bail!("{msg}");
            }
        }
        for body in &s.bodies {
            let points: Vec<_> = body.particles.clone().map(|i| s.particles.x[i]).collect();
            let intact: Vec<bool> = body
                .particles
                .clone()
                .map(|i| {
                    s.materials[s.particles.material[i] as usize].damage(s.particles.alpha[i]) < 1.0
                })
                .collect();
            let sum = FragmentSummary::of(
                &solid_fragment_ids(&points, &intact, s.grid.dx),
                PIECE_SHARE,
            );
            let linked = FragmentSummary::of(&fragment_ids(&points, s.grid.dx), PIECE_SHARE);
            let vmax = body
                .particles
                .clone()
                .map(|i| s.particles.v[i].length())
                .fold(0.0, f64::max);
            println!(
                "frame {frame} object {}: pieces {} largest {:.3} broken {:.3} linked pieces {} largest {:.3} fragments {} vmax {vmax:.2} ({:.0} s)",
                body.object,
                sum.pieces,
                sum.largest_share,
                sum.rubble as f64 / points.len() as f64,
                linked.pieces,
                linked.largest_share,
                sum.fragments,
                clock.elapsed().as_secs_f64()
            );
        }
    }
    Ok(())
}
