//! Every splat format against the graphdeco PLY it was made from (by PlayCanvas'
//! splat-transform, an independent writer: tests/data/formats/README.md): counts, values
//! within each format's quantisation, and renders within a stated PSNR; and what we write
//! read back by our readers. The bad-input cases are in tests/hostile_input.rs.

use std::path::{Path, PathBuf};

use glam::Vec3;
use kiddo::{KdTree, SquaredEuclidean};
use splatter::render::{cpu, Camera, Splats};
use splatter::splat::formats::{read_splats, write_splats_bytes, Format, WriteFormat};
use splatter::splat::spz::SpzVersion;
use splatter::splat::GaussianCloud;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/formats")
        .join(name)
}

fn source() -> GaussianCloud {
    read_splats(&fixture("donut_4k.ply")).unwrap().0
}

/// Per-field errors of `decoded` against `reference`, each decoded Gaussian matched to the
/// reference Gaussian nearest to it (compressed PLY and SOG reorder Gaussians).
#[derive(Debug, Default)]
struct Errors {
    /// Position error in scene units (99th percentile).
    position: f32,
    /// log-scale (99th percentile).
    log_scale: f32,
    opacity: f32,
    /// DC coefficient (99th percentile).
    dc: f32,
    /// Rotation angle in degrees (99th percentile).
    rotation_deg: f32,
}

fn p99(mut v: Vec<f32>) -> f32 {
    v.sort_by(f32::total_cmp);
    v[(v.len() as f32 * 0.99) as usize]
}

fn errors(reference: &GaussianCloud, decoded: &GaussianCloud) -> Errors {
    let mut tree: KdTree<f32, 3> = KdTree::new();
    for (i, p) in reference.positions.iter().enumerate() {
        tree.add(&p.to_array(), i as u64);
    }
    let (lo, hi) = reference.bounds().unwrap();
    let extent = (hi - lo).max_element();
    let (mut pos, mut scale, mut opa, mut dc, mut rot) = (vec![], vec![], vec![], vec![], vec![]);
    // Formats that keep the order are compared Gaussian by Gaussian (captures hold
    // Gaussians at the same position, which a nearest match would confuse).
    let ordered = decoded.len() == reference.len()
        && (0..decoded.len())
            .all(|i| decoded.positions[i].distance(reference.positions[i]) < 1e-3 * extent);
    for i in 0..decoded.len() {
        let j = if ordered {
            i
        } else {
            tree.nearest_one::<SquaredEuclidean>(&decoded.positions[i].to_array())
                .item as usize
        };
        pos.push(decoded.positions[i].distance(reference.positions[j]));
        let ls = |c: &GaussianCloud, k: usize| c.scales[k].to_array().map(f32::ln);
        let (a, b) = (ls(decoded, i), ls(reference, j));
        scale.push((0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f32::max));
        opa.push((decoded.opacities[i] - reference.opacities[j]).abs());
        dc.push(
            (0..3)
                .map(|c| (decoded.sh_of(i)[c] - reference.sh_of(j)[c]).abs())
                .fold(0.0, f32::max),
        );
        // Angle between the rotations, 4·asin(|a − ±b|/2): exact also for tiny angles.
        let (a, b) = (decoded.rotations[i], reference.rotations[j]);
        let b = if a.dot(b) < 0.0 { -b } else { b };
        rot.push(4.0 * ((a - b).length() * 0.5).min(1.0).asin().to_degrees());
    }
    Errors {
        position: p99(pos),
        log_scale: p99(scale),
        opacity: opa.iter().copied().fold(0.0, f32::max),
        dc: p99(dc),
        rotation_deg: p99(rot),
    }
}

/// PSNR of `cloud`'s render against `reference`'s, from three views (CPU reference
/// renderer: no adapter needed, same result everywhere).
fn render_psnr(reference: &GaussianCloud, cloud: &GaussianCloud) -> f64 {
    let (lo, hi) = reference.bounds().unwrap();
    let centre = (lo + hi) * 0.5;
    let r = (hi - lo).length();
    let mut worst = f64::INFINITY;
    for dir in [
        Vec3::new(1.0, 0.4, 0.5),
        Vec3::new(-0.3, 1.0, -0.6),
        Vec3::new(0.2, -0.5, -1.0),
    ] {
        let cam = Camera::look_at(
            centre + dir.normalize() * r * 1.2,
            centre,
            Vec3::Y,
            50f32.to_radians(),
            160,
            120,
        );
        let image = |c: &GaussianCloud| {
            let s = Splats::from_cloud(c, glam::Mat3::IDENTITY, Vec3::ZERO);
            cpu::render(&s, &cam, Vec3::ZERO)
        };
        let a = image(reference);
        let b = image(cloud);
        worst = worst.min(cpu::psnr(&a, &b));
    }
    worst
}

/// What each format keeps, and the bounds we hold it to (errors: position in scene units,
/// log-scale, opacity, DC coefficient, rotation in degrees; PSNR over three views). What
/// limits each:
/// - `.splat`: colour in 8 bits of [0, 1] (this donut's DC reaches 14.9, far outside),
///   opacity truncated to 8 bits, the rotation in 8 bits a component; splat-transform
///   writes the donut's unnormalised quaternions without normalising them, so components
///   above 1 clamp (10°; ours normalise first: 0.7°).
/// - SPZ: positions in 12 fractional bits (√3·2⁻¹³ = 2.1e-4), log-scales in 1/16 steps,
///   opacity in 8 bits, DC in 8 bits of ±3.3, rotations in 9 bits (smallest three).
/// - compressed PLY: 11/10/11 bits of each 256-Gaussian chunk's range for position and
///   log-scale, 8 bits of the chunk's colour range, 10-bit smallest-three rotations.
/// - SOG: 16 bits of a log-transformed position; 256-entry codebooks for log-scale and DC
///   (the donut's rare large DC values fall between entries), 8-bit rotations.
#[test]
fn every_format_reads_the_same_model() {
    let reference = source();
    assert_eq!(reference.len(), 4_148, "the fixture's count");
    println!("format            | count | pos | log-scale | opacity | DC    | rot (°) | PSNR (dB)");
    for (file, format, limits, min_psnr) in [
        (
            "donut_4k.splat",
            Format::Splat,
            [1e-6, 1e-5, 0.004, 0.8, 10.0],
            40.0,
        ),
        (
            "donut_4k.v3.spz",
            Format::Spz,
            [2.5e-4, 0.032, 0.0021, 0.014, 0.2],
            45.0,
        ),
        (
            "donut_4k.v4.spz",
            Format::Spz,
            [2.5e-4, 0.032, 0.0021, 0.014, 0.2],
            45.0,
        ),
        (
            "donut_4k.compressed.ply",
            Format::CompressedPly,
            [1.5e-4, 0.005, 0.0021, 0.03, 0.2],
            55.0,
        ),
        (
            "donut_4k.sog",
            Format::Sog,
            [1e-5, 0.02, 0.004, 3.0, 1.5],
            55.0,
        ),
        (
            "donut_4k_sog",
            Format::Sog,
            [1e-5, 0.02, 0.004, 3.0, 1.5],
            55.0,
        ),
    ] {
        let (cloud, report) = read_splats(&fixture(file)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(report.format, format, "{file}");
        let e = errors(&reference, &cloud);
        let psnr = render_psnr(&reference, &cloud);
        println!(
            "{file:<24} | {} | {:.1e} | {:.3} | {:.4} | {:.3} | {:.2} | {psnr:.1}",
            cloud.len(),
            e.position,
            e.log_scale,
            e.opacity,
            e.dc,
            e.rotation_deg
        );
        assert_eq!(cloud.len(), reference.len(), "{file}: count");
        let got = [e.position, e.log_scale, e.opacity, e.dc, e.rotation_deg];
        for ((name, g), l) in ["position", "log-scale", "opacity", "DC", "rotation"]
            .iter()
            .zip(got)
            .zip(limits)
        {
            assert!(g <= l, "{file}: {name} error {g} above {l}");
        }
        assert!(
            psnr >= min_psnr,
            "{file}: PSNR {psnr:.1} dB below {min_psnr}"
        );
    }
}

/// What we write, read back by our readers within the format's quantisation (the same
/// files open in splat-transform: docs/formats.md says how that was checked).
#[test]
fn what_we_write_reads_back() {
    let mut reference = source();
    // Labels must survive in PLY and SPZ.
    reference.label_names = vec!["flesh".into(), "rind".into()];
    reference.labels = (0..reference.len()).map(|i| (i % 2) as u16).collect();
    for (format, ext, limits) in [
        (WriteFormat::Ply, "ply", [1e-7, 1e-6, 1e-6, 1e-7, 1e-3]),
        (
            WriteFormat::Spz(SpzVersion::V3),
            "spz",
            [2.5e-4, 0.032, 0.0021, 0.014, 0.2],
        ),
        (
            WriteFormat::Spz(SpzVersion::V4),
            "spz",
            [2.5e-4, 0.032, 0.0021, 0.014, 0.2],
        ),
        (WriteFormat::Splat, "splat", [1e-7, 1e-6, 0.0021, 0.8, 0.8]),
    ] {
        let bytes = write_splats_bytes(&reference, format, "out").unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(format!("out.{ext}"));
        std::fs::write(&path, &bytes).unwrap();
        let (cloud, _) = read_splats(&path).unwrap_or_else(|e| panic!("{format:?}: {e}"));
        let e = errors(&reference, &cloud);
        println!("{format:?}: {} bytes, {e:?}", bytes.len());
        let got = [e.position, e.log_scale, e.opacity, e.dc, e.rotation_deg];
        for ((name, g), l) in ["position", "log-scale", "opacity", "DC", "rotation"]
            .iter()
            .zip(got)
            .zip(limits)
        {
            assert!(g <= l, "{format:?}: {name} error {g} above {l}");
        }
        if format != WriteFormat::Splat {
            assert_eq!(cloud.labels, reference.labels, "{format:?}: labels");
            assert_eq!(
                cloud.label_names, reference.label_names,
                "{format:?}: label names"
            );
        }
    }
}

/// The plant capture as distributed (`.splat`) is the PLY it was decoded from: every 32nd
/// record of each, cut byte for byte (tests/data/captures/README.md).
#[test]
fn plant_splat_matches_plant_ply() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/captures");
    let (splat, r) = read_splats(&data.join("plant_3k.splat")).unwrap();
    let (ply, _) = read_splats(&data.join("plant_3k.ply")).unwrap();
    assert_eq!(r.format, Format::Splat);
    assert_eq!(splat.len(), 3552);
    assert_eq!(splat.positions, ply.positions);
    let e = errors(&ply, &splat);
    println!("plant.splat vs plant.ply: {e:?}");
    assert!(e.log_scale < 1e-5 && e.dc < 1e-5 && e.opacity < 0.003);
}
