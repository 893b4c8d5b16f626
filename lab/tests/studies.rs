//! The studies' own pieces checked against what they stand for: the convergence study's
//! bar against its analytic period, and the shatter study's quarter fruit against the
//! whole fruit.

use std::path::Path;

use splatter::gpu::GpuContext;
use splatter::run::{Input, Run, RunOptions};
use splatter::scene::quality::Quality;

/// Wave speed: with ν = 0, λ = 0 and the P-wave modulus λ + 2μ equals E, so a uniaxial
/// displacement u(x) x̂ is an exact solution with stress-free lateral faces whatever the
/// cross-section, and c = sqrt(E/ρ) exactly (no thin-bar approximation needed).
/// Clamp: the sticky −x wall; its band fixes nodes 0..=2, so the clamp is the node
/// x_c = lo + 2Δx (module docs of `cpu`); material starts Δx before it and L = 1 is
/// measured from x_c to the free end. Initial velocity: the mode shape
/// v = v₀ sin(π(x − x_c)/2L) x̂ (C its gradient), so u_end(t) ∝ sin(2πt/T).
/// Period: from the zero crossings of the mean x-displacement of the end layer of
/// particles, a least-squares line through crossing time against index (half a period
/// apart; `splatter_lab::fit::period_from_crossings`).
#[test]
fn elastic_bar_first_axial_mode_period() {
    // The convergence study's bar (`splatter_lab::convergence::bar`): L/Δx = 40, CFL 0.4, 2³
    // particles per cell, 2.3 periods.
    let r = splatter_lab::convergence::bar(40, 0.4, 2, "test");
    let (measured, period) = (r.measured.expect("period measured"), r.exact.unwrap());
    let err = measured / period - 1.0;
    println!(
        "elastic bar, {} particles, {} steps: period {measured:.5} vs 4L/c = {period:.5} \
         ({:+.2}%, tol 3%)",
        r.particles,
        r.steps,
        100.0 * err
    );
    assert!(err.abs() < 0.03);
}

/// The shatter study's quarter fruit (`splatter_lab::shatter::cut_to_quarter` on the NACC drop,
/// `scenes/watermelon_drop_nacc.json`: one quarter between
/// two slip planes through the centre) moves as its part of the whole fruit: at draft
/// quality it holds exactly a quarter of the particles, and through the impact and rebound
/// (frames 1–4) four times its kinetic plus gravitational energy is the whole fruit's within
/// 5% and its damaged share within 3 points. A plane that let material through, or held
/// it, or a selection off the centre would break one of these.
#[test]
fn a_quarter_of_the_dropped_watermelon_moves_as_a_quarter_of_the_whole() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let gpu = GpuContext::new(None).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(root.join("watermelon_drop_nacc.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    splatter_lab::shatter::cut_to_quarter(&mut v).unwrap();
    let quarter_scene = dir.path().join("quarter.json");
    std::fs::write(&quarter_scene, v.to_string()).unwrap();
    let columns = ["particles", "damaged_share", "energy", "nonfinite"];
    let mut runs = Vec::new();
    for (name, scene) in [
        ("whole", root.join("watermelon_drop_nacc.json")),
        ("quarter", quarter_scene),
    ] {
        let out = dir.path().join(name);
        render_draft_with_fragments(&gpu, &scene, &out, 5);
        runs.push(fruit_rows(&out, &columns));
    }
    let (whole, quarter) = (&runs[0], &runs[1]);
    eprintln!("watermelon_drop, draft: whole {whole:?}, quarter {quarter:?}");
    assert_eq!(4.0 * quarter[0][0], whole[0][0], "particles");
    for frame in 1..5 {
        let (w, q) = (&whole[frame], &quarter[frame]);
        assert_eq!(
            (w[3], q[3]),
            (0.0, 0.0),
            "frame {frame}: non-finite particles"
        );
        let energy = 4.0 * q[2] / w[2];
        assert!(
            (energy - 1.0).abs() < 0.05,
            "frame {frame}: 4 × the quarter's energy is {energy} of the whole's"
        );
        assert!(
            (q[1] - w[1]).abs() < 0.03,
            "frame {frame}: damaged {} (quarter) against {} (whole)",
            q[1],
            w[1]
        );
        assert!(w[1] > 0.05, "frame {frame}: the impact damages the fruit");
    }
}

/// Frames 0..frames of `scene` at draft quality and 64×48, with `OUT/fragments.csv`.
fn render_draft_with_fragments(gpu: &GpuContext, scene: &Path, out: &Path, frames: u32) {
    let opts = RunOptions {
        input: Input::Scene(Some(scene.to_path_buf())),
        out: Some(out.to_path_buf()),
        frames: Some(format!("0..{frames}")),
        width: Some(64),
        height: Some(48),
        quality: Quality::Draft,
        fragments: true,
        ..RunOptions::default()
    };
    Run::prepare(opts)
        .and_then(|run| run.execute(gpu, &mut |_| {}))
        .unwrap_or_else(|e| panic!("{}: {e:#}", scene.display()));
}

/// The watermelon's rows of `out/fragments.csv`, the named columns of each.
fn fruit_rows(out: &Path, columns: &[&str]) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(out.join("fragments.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    lines
        .map(|l| l.split(',').collect::<Vec<&str>>())
        .filter(|f| f[col("object")] == "watermelon")
        .map(|f| columns.iter().map(|c| f[col(c)].parse().unwrap()).collect())
        .collect()
}
