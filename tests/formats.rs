//! Every splat format against the graphdeco PLY it was made from (by PlayCanvas'
//! splat-transform, an independent writer: tests/data/formats/README.md): counts, values
//! within each format's quantisation, and renders within a stated PSNR; and what we write
//! read back by our readers. The bad-input cases are in tests/hostile_input.rs.

use std::path::{Path, PathBuf};

use glam::Vec3;
use kiddo::{KdTree, SquaredEuclidean};
use splatter::render::{cpu, Camera, Splats};
use splatter::splat::formats::{read_splats, write_splats_bytes, Format, SourceFrame, WriteFormat};
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
    // Labels must survive in PLY, SPZ and GLB.
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
        (
            WriteFormat::Glb(SourceFrame::Capture),
            "glb",
            [0.0, 0.0, 0.0, 0.0, 1e-3],
        ),
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

/// The rest coefficient `j` (channel-major, as in the PLY) that `make_sh3_subset.py` gave
/// row `i` of the GLB fixture's source.
fn fixture_rest(i: usize, j: usize) -> f32 {
    ((31 * i + 17 * j) % 201) as f32 / 256.0 - 100.0 / 256.0
}

/// A GLB that splat-transform wrote (`donut_300_sh3.glb`: rows 0, 13, 26, … of the donut
/// with SH degree 3 added, tests/data/formats/README.md) holds the values of its PLY:
/// turned back from glTF's frame by the half turn about z, quaternions taken as x y z w,
/// scales linear, opacity after the sigmoid, the DC coefficient raw, and the rest
/// coefficients in the order of the PLY's (m = −l … l within each degree).
#[test]
fn glb_from_splat_transform_holds_its_ply() {
    let (cloud, report) = read_splats(&fixture("donut_300_sh3.glb")).unwrap();
    assert_eq!(report.format, Format::Gltf);
    assert_eq!(report.variant, "GLB");
    assert_eq!(report.up.map(|u| u.axis), Some("-y"));
    assert_eq!((cloud.len(), cloud.sh_degree), (300, 3));
    let source = source();
    let mut worst = [0.0f32; 5];
    for i in 0..cloud.len() {
        let s = 13 * i;
        let err = [
            (cloud.positions[i] - source.positions[s])
                .abs()
                .max_element(),
            (cloud.scales[i] / source.scales[s] - 1.0)
                .abs()
                .max_element(),
            1.0 - cloud.rotations[i].dot(source.rotations[s]).abs(),
            (cloud.opacities[i] - source.opacities[s]).abs(),
            (0..48)
                .map(|at| {
                    let (k, c) = (at / 3, at % 3);
                    let want = match k {
                        0 => source.sh_of(s)[c],
                        _ => fixture_rest(i, c * 15 + k - 1),
                    };
                    (cloud.sh_of(i)[at] - want).abs()
                })
                .fold(0.0, f32::max),
        ];
        for (w, e) in worst.iter_mut().zip(err) {
            *w = w.max(e);
        }
    }
    println!("position, scale (relative), 1 - |q·q'|, opacity, SH: {worst:?}");
    for ((name, w), limit) in ["position", "scale", "rotation", "opacity", "SH"]
        .iter()
        .zip(worst)
        .zip([0.0, 1e-7, 1e-6, 1e-7, 1e-7])
    {
        assert!(w <= limit, "{name}: error {w} above {limit}");
    }
}

/// A GLB whose primitive carries its Gaussians as SPZ (`KHR_gaussian_splatting_compression_
/// spz_2`): the payload is in SPZ's own frame (x right, y up, z back), which the extension
/// turns into glTF's by a half turn about y, then the reader into the PLY frame by a half
/// turn about z. Built here from the donut: read back within SPZ's quantisation, in order.
#[test]
fn glb_with_an_spz_payload_reads_within_spz_precision() {
    use splatter::splat::gltf::{half_turn, Axis};
    let reference = source();
    let mut in_spz_frame = reference.clone();
    half_turn(&mut in_spz_frame, Axis::X);
    let mut payload =
        write_splats_bytes(&in_spz_frame, WriteFormat::Spz(SpzVersion::V3), "p").unwrap();
    let payload_len = payload.len();
    payload.resize(payload_len.next_multiple_of(4), 0);
    let n = reference.len();
    let json = serde_json::json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_gaussian_splatting", "KHR_gaussian_splatting_compression_spz_2"],
        "extensionsRequired": ["KHR_gaussian_splatting_compression_spz_2"],
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "buffers": [{"byteLength": payload.len()}],
        "bufferViews": [{"buffer": 0, "byteLength": payload_len}],
        "accessors": [
            {"componentType": 5126, "count": n, "type": "VEC3"},
            {"componentType": 5126, "count": n, "type": "VEC4"},
            {"componentType": 5126, "count": n, "type": "VEC3"},
            {"componentType": 5126, "count": n, "type": "SCALAR"},
            {"componentType": 5126, "count": n, "type": "VEC3"},
        ],
        "meshes": [{"primitives": [{
            "mode": 0,
            "attributes": {
                "POSITION": 0,
                "KHR_gaussian_splatting:ROTATION": 1,
                "KHR_gaussian_splatting:SCALE": 2,
                "KHR_gaussian_splatting:OPACITY": 3,
                "KHR_gaussian_splatting:SH_DEGREE_0_COEF_0": 4,
            },
            "extensions": {"KHR_gaussian_splatting": {
                "kernel": "ellipse", "colorSpace": "srgb_rec709_display",
                "extensions": {"KHR_gaussian_splatting_compression_spz_2": {"bufferView": 0}},
            }},
        }]}],
    });
    let glb = glb_of(&json, &payload);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("spz.glb");
    std::fs::write(&path, &glb).unwrap();
    let (cloud, report) = read_splats(&path).unwrap();
    assert_eq!(report.variant, "GLB, SPZ-compressed");
    assert_eq!(cloud.len(), n);
    let worst = cloud
        .positions
        .iter()
        .zip(&reference.positions)
        .map(|(p, q)| p.distance(*q))
        .fold(0.0f32, f32::max);
    let e = errors(&reference, &cloud);
    println!("in order: position {worst:.2e}; matched: {e:?}");
    assert!(
        worst < 2.5e-4,
        "in order, within 12 fractional bits: {worst}"
    );
    for ((name, g), l) in ["position", "log-scale", "opacity", "DC", "rotation"]
        .iter()
        .zip([e.position, e.log_scale, e.opacity, e.dc, e.rotation_deg])
        .zip([2.5e-4, 0.032, 0.0021, 0.014, 0.2])
    {
        assert!(g <= l, "{name} error {g} above {l}");
    }
    // The count the accessors give must be the payload's.
    let mut json = json;
    json["accessors"][0]["count"] = 7.into();
    std::fs::write(&path, glb_of(&json, &payload)).unwrap();
    let e = read_splats(&path).unwrap_err().to_string();
    assert!(
        e.contains("POSITION (accessor 0) has 7 elements, the SPZ payload 4148 Gaussians"),
        "{e}"
    );
}

/// A GLB of `json` and a BIN chunk `bin` (a multiple of 4 bytes).
fn glb_of(json: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut text = serde_json::to_vec(json).unwrap();
    text.resize(text.len().next_multiple_of(4), b' ');
    let mut glb = b"glTF".to_vec();
    glb.extend(2u32.to_le_bytes());
    glb.extend(((28 + text.len() + bin.len()) as u32).to_le_bytes());
    glb.extend((text.len() as u32).to_le_bytes());
    glb.extend(b"JSON");
    glb.extend(&text);
    glb.extend((bin.len() as u32).to_le_bytes());
    glb.extend(b"BIN\0");
    glb.extend(bin);
    glb
}

/// Standard base64 with padding (for building `.gltf` data URIs here).
fn base64(bytes: &[u8]) -> String {
    const ABC: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = u32::from(b[0]) << 16 | u32::from(b[1]) << 8 | u32::from(b[2]);
        for j in 0..4 {
            out.push(if j <= chunk.len() {
                ABC[(n >> (18 - 6 * j) & 63) as usize] as char
            } else {
                '='
            });
        }
    }
    out
}

/// The GLB fixture as `.gltf` JSON, its buffer once as a base64 data URI and once as a
/// `.bin` file beside it (named with a space, escaped in the URI): both read as the GLB.
#[test]
fn gltf_json_with_a_data_uri_or_an_adjacent_bin_reads_as_the_glb() {
    let glb = std::fs::read(fixture("donut_300_sh3.glb")).unwrap();
    let (from_glb, _) = read_splats(&fixture("donut_300_sh3.glb")).unwrap();
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let mut json: serde_json::Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let bin = &glb[20 + json_len + 8..];
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("the data.bin"), bin).unwrap();
    for (name, uri) in [
        (
            "embedded.gltf",
            format!("data:application/octet-stream;base64,{}", base64(bin)),
        ),
        ("adjacent.gltf", "the%20data.bin".to_string()),
    ] {
        json["buffers"][0]["uri"] = uri.into();
        let path = dir.path().join(name);
        std::fs::write(&path, serde_json::to_vec_pretty(&json).unwrap()).unwrap();
        let (cloud, report) = read_splats(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(report.variant, "glTF JSON", "{name}");
        assert_eq!(cloud, from_glb, "{name}");
    }
}

/// A node's transform places its splats (glTF: the mesh's values are in the node's local
/// frame): the fixture under a node turned a quarter turn about y, scaled by 2 and moved
/// reads as the fixture so moved, colours turned with it. An uneven scale is refused.
#[test]
fn a_node_transform_places_the_splats_and_an_uneven_scale_is_refused() {
    use glam::{Mat3, Quat};
    use splatter::splat::sh::eval;
    let (plain, _) = read_splats(&fixture("donut_300_sh3.glb")).unwrap();
    let glb = std::fs::read(fixture("donut_300_sh3.glb")).unwrap();
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let mut json: serde_json::Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let bin = glb[20 + json_len + 8..].to_vec();
    let turn = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    json["nodes"][0]["rotation"] = serde_json::json!(turn.to_array());
    json["nodes"][0]["scale"] = serde_json::json!([2.0, 2.0, 2.0]);
    json["nodes"][0]["translation"] = serde_json::json!([1.0, 2.0, 3.0]);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("placed.glb");
    std::fs::write(&path, glb_of(&json, &bin)).unwrap();
    let (placed, _) = read_splats(&path).unwrap();
    // In the PLY frame the reader holds: glTF's frame turned half a turn about z.
    let h = Mat3::from_diagonal(Vec3::new(-1.0, -1.0, 1.0));
    let m = h * Mat3::from_quat(turn) * h;
    let t = h * Vec3::new(1.0, 2.0, 3.0);
    let q = Quat::from_mat3(&m);
    let d = Vec3::new(0.3, -0.5, 0.8).normalize();
    for i in 0..plain.len() {
        let want = m * (2.0 * plain.positions[i]) + t;
        assert!(
            (placed.positions[i] - want).length() < 1e-5,
            "{i}: position"
        );
        assert!(
            (placed.scales[i] - 2.0 * plain.scales[i])
                .abs()
                .max_element()
                < 1e-6
        );
        assert!(placed.rotations[i].dot(q * plain.rotations[i]).abs() > 1.0 - 1e-5);
        let seen = eval(3, placed.sh_of(i), m * d);
        let was = eval(3, plain.sh_of(i), d);
        assert!((seen - was).length() < 1e-4, "{i}: colour {seen} vs {was}");
    }
    json["nodes"][0]["scale"] = serde_json::json!([2.0, 1.0, 2.0]);
    std::fs::write(&path, glb_of(&json, &bin)).unwrap();
    let e = read_splats(&path).unwrap_err().to_string();
    assert!(
        e.contains("placed.glb") && e.contains("uniform positive scale"),
        "{e}"
    );
}
