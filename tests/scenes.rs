//! The shipped scenes (`scenes/*.json`): each renders on the test adapter at a tiny size
//! for its first frames, and the relit scene's lighting reaches the image.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn splatter(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_splatter"))
        .args(args)
        .env_remove("RUST_LOG")
        .output()
        .expect("run splatter")
}

fn scenes() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut list: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("scenes/")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    list.sort();
    list
}

/// Render `frames` of `scene` at 64×48 into `out`, with `extra` arguments.
fn render(scene: &Path, out: &Path, frames: &str, extra: &[&str]) -> Vec<image::RgbImage> {
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--width",
        "64",
        "--height",
        "48",
        "--frames",
        frames,
    ];
    args.extend_from_slice(extra);
    let o = splatter(&args);
    assert!(
        o.status.success(),
        "{}: {}",
        scene.display(),
        String::from_utf8_lossy(&o.stderr)
    );
    let mut names: Vec<PathBuf> = std::fs::read_dir(out)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
        .collect();
    names.sort();
    names
        .iter()
        .map(|p| image::open(p).unwrap().to_rgb8())
        .collect()
}

fn mean_abs_diff(a: &image::RgbImage, b: &image::RgbImage) -> f64 {
    let s: u64 = a
        .as_raw()
        .iter()
        .zip(b.as_raw())
        .map(|(x, y)| u64::from(x.abs_diff(*y)))
        .sum();
    s as f64 / a.as_raw().len() as f64
}

#[test]
fn every_shipped_scene_renders_its_first_frames() {
    let list = scenes();
    assert!(list.len() >= 5, "scenes/ holds the example scenes");
    for scene in list {
        let dir = tempfile::tempdir().unwrap();
        // Draft quality (dx and spacings doubled): the paper scenes' first simulated frame
        // in seconds, not tens of seconds, each.
        let images = render(&scene, dir.path(), "0..2", &["--quality", "draft"]);
        assert_eq!(images.len(), 2, "{}", scene.display());
        let background = *images[0].get_pixel(0, 0);
        assert!(
            images[0].pixels().any(|p| *p != background),
            "{}: only background",
            scene.display()
        );
    }
}

/// `scenes/relit.json` (two moving lights around a dropped jelly cube): the lighting
/// changes the image (against the same scene without its `lighting` block), and the image
/// changes between frames.
#[test]
fn the_relit_scene_is_relit() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/relit.json");
    let dir = tempfile::tempdir().unwrap();
    let lit = render(&scene, &dir.path().join("lit"), "0..3", &[]);
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&scene).unwrap()).unwrap();
    assert!(json["lighting"]["lights"].as_array().unwrap().len() == 2);
    json.as_object_mut().unwrap().remove("lighting");
    let plain_scene = dir.path().join("plain.json");
    std::fs::write(&plain_scene, json.to_string()).unwrap();
    let plain = render(&plain_scene, &dir.path().join("plain"), "0..1", &[]);
    let lighting_effect = mean_abs_diff(&lit[0], &plain[0]);
    let frame_change = mean_abs_diff(&lit[0], &lit[2]);
    eprintln!("lit vs unlit: {lighting_effect:.2} levels; frame 0 vs 2: {frame_change:.2} levels");
    assert!(lighting_effect > 5.0);
    assert!(frame_change > 0.5);
}

/// One row of `--fragments`' CSV: (frame, object, pieces, largest share, debris,
/// damaged share, height).
type FragmentRow = (u32, String, usize, f64, usize, f64, f64);

fn fragment_rows(out: &Path) -> Vec<FragmentRow> {
    let text = std::fs::read_to_string(out.join("fragments.csv")).expect("fragments.csv");
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("frame,object,particles,pieces,largest_share,debris,fragments,damaged_share,height")
    );
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (
                f[0].parse().unwrap(),
                f[1].to_string(),
                f[3].parse().unwrap(),
                f[4].parse().unwrap(),
                f[5].parse().unwrap(),
                f[7].parse().unwrap(),
                f[8].parse().unwrap(),
            )
        })
        .collect()
}

/// The fracture examples as written (not at draft quality: pieces need the scene's Δx),
/// counted with `--fragments` (connected components of the particles, links < Δx): the
/// watermelon breaks into pieces on impact, the jelly stays one body through its bounce,
/// and the sandcastle slumps to under 60 % of its height, losing cohesion where it yields.
#[test]
fn watermelon_breaks_jelly_stays_whole_sandcastle_crumbles() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let dir = tempfile::tempdir().unwrap();

    let out = dir.path().join("watermelon");
    render(
        &root.join("watermelon.json"),
        &out,
        "0..3",
        &["--fragments"],
    );
    let rows = fragment_rows(&out);
    let (_, name, pieces, largest, debris, damaged, _) = rows.last().unwrap().clone();
    eprintln!("watermelon, frame 2: {pieces} pieces ≥ 1%, largest {largest}, debris {debris}, damaged {damaged}");
    assert_eq!(name, "watermelon");
    assert!(pieces >= 3, "the watermelon breaks into pieces ({pieces})");
    assert!(largest < 0.5, "no piece keeps half the melon ({largest})");

    let out = dir.path().join("jelly");
    render(&root.join("jelly.json"), &out, "0..10", &["--fragments"]);
    for (frame, _, pieces, largest, debris, damaged, _) in fragment_rows(&out) {
        assert!(
            pieces == 1 && largest == 1.0 && debris == 0 && damaged == 0.0,
            "jelly frame {frame}: {pieces} pieces, largest {largest}, debris {debris}, damaged {damaged}"
        );
    }

    let out = dir.path().join("sandcastle");
    render(
        &root.join("sandcastle.json"),
        &out,
        "0..12",
        &["--fragments"],
    );
    let rows = fragment_rows(&out);
    let (first, last) = (&rows[0], rows.last().unwrap());
    eprintln!(
        "sandcastle: height {:.3} m at frame 0, {:.3} m at frame {}; damaged {}",
        first.6, last.6, last.0, last.5
    );
    assert_eq!(first.5, 0.0, "the castle starts cohesive");
    assert!(
        last.6 < 0.6 * first.6,
        "the castle slumps ({:.3} m)",
        last.6
    );
    assert!(
        last.5 > 0.05,
        "the slump breaks some of its cohesion ({})",
        last.5
    );
}
