//! PLY reading and writing (docs/method.md §5): round trips, layout conversion, robustness.

use std::time::Instant;

use glam::{Quat, Vec3};
use splatter::splat::ply::{
    read_ply, read_ply_bytes, write_ply, write_ply_bytes, PlyError, PlyFormat,
};
use splatter::splat::{sh_coeff_count, GaussianCloud};

/// xorshift64*, for reproducible test data.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        ((self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 40) as f32) / (1u64 << 24) as f32
    }

    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next()
    }
}

fn random_cloud(n: usize, degree: u32, normals: bool, seed: u64) -> GaussianCloud {
    let mut r = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    let mut c = GaussianCloud {
        sh_degree: degree,
        ..Default::default()
    };
    for _ in 0..n {
        c.positions.push(Vec3::new(
            r.range(-5.0, 5.0),
            r.range(-5.0, 5.0),
            r.range(-5.0, 5.0),
        ));
        c.scales.push(Vec3::new(
            r.range(-6.0, 1.0).exp(),
            r.range(-6.0, 1.0).exp(),
            r.range(-6.0, 1.0).exp(),
        ));
        let q = Quat::from_xyzw(
            r.range(-1.0, 1.0),
            r.range(-1.0, 1.0),
            r.range(-1.0, 1.0),
            r.range(0.1, 1.0),
        );
        c.rotations.push(q.normalize());
        c.opacities.push(r.range(0.001, 0.999));
        for _ in 0..3 * sh_coeff_count(degree) {
            c.sh.push(r.range(-2.0, 2.0));
        }
        if normals {
            c.normals.push(Vec3::new(
                r.range(-1.0, 1.0),
                r.range(-1.0, 1.0),
                r.range(-1.0, 1.0),
            ));
        }
    }
    c.check_consistent().unwrap();
    c
}

fn assert_close(a: &GaussianCloud, b: &GaussianCloud) {
    assert_eq!(a.len(), b.len());
    assert_eq!(a.sh_degree, b.sh_degree);
    assert_eq!(
        a.positions, b.positions,
        "positions are stored as f32 and must be exact"
    );
    assert_eq!(
        a.sh, b.sh,
        "SH coefficients are stored as f32 and must be exact"
    );
    assert_eq!(a.normals, b.normals);
    for i in 0..a.len() {
        let rel = ((a.scales[i] - b.scales[i]) / a.scales[i])
            .abs()
            .max_element();
        assert!(rel < 2e-6, "scale {i}: {} vs {}", a.scales[i], b.scales[i]);
        assert!(
            (a.opacities[i] - b.opacities[i]).abs() < 1e-6,
            "opacity {i}"
        );
        assert!(
            a.rotations[i].abs_diff_eq(b.rotations[i], 1e-6),
            "rotation {i}"
        );
    }
}

fn round_trip(degree: u32, format: PlyFormat, normals: bool) {
    let cloud = random_cloud(1000, degree, normals, u64::from(degree) + 1);
    let bytes = write_ply_bytes(&cloud, format, "mem.ply").unwrap();
    let (back, report) = read_ply_bytes(&bytes, "mem.ply").unwrap();
    assert_eq!(report.format, format);
    assert_eq!(report.vertices_in_file, 1000);
    assert_eq!(
        (report.skipped_nonfinite, report.skipped_degenerate),
        (0, 0)
    );
    assert_close(&cloud, &back);
}

#[test]
fn round_trip_binary_degree_0() {
    round_trip(0, PlyFormat::BinaryLittleEndian, false);
}

#[test]
fn round_trip_binary_degree_3() {
    round_trip(3, PlyFormat::BinaryLittleEndian, false);
}

#[test]
fn round_trip_ascii_degree_0() {
    round_trip(0, PlyFormat::Ascii, false);
}

#[test]
fn round_trip_ascii_degree_3() {
    round_trip(3, PlyFormat::Ascii, false);
}

#[test]
fn round_trip_degrees_1_and_2_with_normals() {
    for format in [PlyFormat::BinaryLittleEndian, PlyFormat::Ascii] {
        round_trip(1, format, true);
        round_trip(2, format, true);
    }
}

#[test]
fn write_ply_goes_through_a_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cloud.ply");
    let cloud = random_cloud(100, 3, false, 9);
    write_ply(&path, &cloud, PlyFormat::BinaryLittleEndian).unwrap();
    let entries: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(entries.len(), 1, "only cloud.ply, no temporary file left");
    let (back, _) = read_ply(&path).unwrap();
    assert_close(&cloud, &back);
    // Overwriting works too.
    write_ply(&path, &random_cloud(5, 0, false, 1), PlyFormat::Ascii).unwrap();
    assert_eq!(read_ply(&path).unwrap().0.len(), 5);
}

#[test]
fn empty_cloud_round_trips() {
    let cloud = GaussianCloud {
        sh_degree: 2,
        ..Default::default()
    };
    for format in [PlyFormat::BinaryLittleEndian, PlyFormat::Ascii] {
        let bytes = write_ply_bytes(&cloud, format, "e.ply").unwrap();
        let (back, _) = read_ply_bytes(&bytes, "e.ply").unwrap();
        assert_eq!(back, cloud);
    }
}

// ---------------------------------------------------------------------------------------
// Hand-written files

/// Build a PLY file: `props` are (type, name); `rows` hold one value per property.
fn ply(format: &str, props: &[(&str, &str)], rows: &[Vec<f64>]) -> Vec<u8> {
    let mut h = format!(
        "ply\nformat {format} 1.0\ncomment test\nelement vertex {}\n",
        rows.len()
    );
    for (t, n) in props {
        h.push_str(&format!("property {t} {n}\n"));
    }
    h.push_str("end_header\n");
    let mut b = h.into_bytes();
    for row in rows {
        assert_eq!(row.len(), props.len());
        if format == "ascii" {
            let line: Vec<String> = row.iter().map(|v| v.to_string()).collect();
            b.extend_from_slice(line.join(" ").as_bytes());
            b.push(b'\n');
            continue;
        }
        for ((t, _), &v) in props.iter().zip(row) {
            let le = format == "binary_little_endian";
            let bytes: Vec<u8> = match *t {
                "float" => {
                    if le {
                        (v as f32).to_le_bytes().to_vec()
                    } else {
                        (v as f32).to_be_bytes().to_vec()
                    }
                }
                "double" => {
                    if le {
                        v.to_le_bytes().to_vec()
                    } else {
                        v.to_be_bytes().to_vec()
                    }
                }
                "uchar" => vec![v as u8],
                "short" => (v as i16).to_le_bytes().to_vec(),
                "int" => (v as i32).to_le_bytes().to_vec(),
                other => panic!("type {other}"),
            };
            b.extend_from_slice(&bytes);
        }
    }
    b
}

const BASIC: [&str; 14] = [
    "x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1", "scale_2",
    "rot_0", "rot_1", "rot_2", "rot_3",
];

fn floats<'a>(names: &[&'a str]) -> Vec<(&'a str, &'a str)> {
    names.iter().map(|n| ("float", *n)).collect()
}

/// A well-formed degree-0 row in BASIC order.
fn basic_row(x: f64) -> Vec<f64> {
    vec![
        x, 2.0, 3.0, 0.1, 0.2, 0.3, 0.0, -1.0, -2.0, -3.0, 1.0, 0.0, 0.0, 0.0,
    ]
}

#[test]
fn rest_coefficients_are_converted_from_channel_major() {
    // Degree 1: 9 rest values; in the file red k=1..3, then green, then blue.
    let rest: Vec<String> = (0..9).map(|j| format!("f_rest_{j}")).collect();
    let mut props = floats(&BASIC);
    props.extend(rest.iter().map(|n| ("float", n.as_str())));
    let mut row = basic_row(1.0);
    row.extend((0..9).map(|j| 10.0 + f64::from(j)));
    let text = ply("ascii", &props, &[row]);
    let (c, _) = read_ply_bytes(&text, "hand.ply").unwrap();
    assert_eq!(c.sh_degree, 1);
    // Coefficient-major: [k * 3 + c]; DC first.
    #[rustfmt::skip]
    let expect = [
        0.1, 0.2, 0.3, // k = 0 (f_dc)
        10.0, 13.0, 16.0, // k = 1: red f_rest_0, green f_rest_3, blue f_rest_6
        11.0, 14.0, 17.0, // k = 2
        12.0, 15.0, 18.0, // k = 3
    ];
    assert_eq!(c.sh, expect);
    // And the writer converts back.
    let again = write_ply_bytes(&c, PlyFormat::Ascii, "again.ply").unwrap();
    let text = String::from_utf8(again).unwrap();
    let last = text.lines().last().unwrap();
    let vals: Vec<f32> = last.split(' ').map(|t| t.parse().unwrap()).collect();
    // x y z nx ny nz f_dc_0..2 f_rest_0..8 …
    assert_eq!(
        &vals[9..18],
        &[10.0, 11.0, 12.0, 13.0, 14.0, 15.0, 16.0, 17.0, 18.0]
    );
}

#[test]
fn shuffled_properties_extra_properties_and_elements_are_handled() {
    let cloud = random_cloud(50, 1, true, 77);
    // Canonical file values per Gaussian, by name.
    let value = |i: usize, name: &str| -> f64 {
        let k = 4;
        let sh = cloud.sh_of(i);
        match name {
            "x" => cloud.positions[i].x.into(),
            "y" => cloud.positions[i].y.into(),
            "z" => cloud.positions[i].z.into(),
            "nx" => cloud.normals[i].x.into(),
            "ny" => cloud.normals[i].y.into(),
            "nz" => cloud.normals[i].z.into(),
            "opacity" => {
                let a = f64::from(cloud.opacities[i]);
                (a / (1.0 - a)).ln()
            }
            "rot_0" => cloud.rotations[i].w.into(),
            "rot_1" => cloud.rotations[i].x.into(),
            "rot_2" => cloud.rotations[i].y.into(),
            "rot_3" => cloud.rotations[i].z.into(),
            "extra_a" | "extra_b" => 42.0,
            n if n.starts_with("scale_") => {
                let a: usize = n[6..].parse().unwrap();
                f64::from(cloud.scales[i][a]).ln()
            }
            n if n.starts_with("f_dc_") => sh[n[5..].parse::<usize>().unwrap()].into(),
            n if n.starts_with("f_rest_") => {
                let j: usize = n[7..].parse().unwrap();
                let (c, kk) = (j / (k - 1), j % (k - 1) + 1);
                sh[kk * 3 + c].into()
            }
            n => panic!("{n}"),
        }
    };
    let mut names: Vec<String> = [
        "rot_2", "extra_a", "f_dc_1", "scale_2", "z", "nx", "opacity", "rot_0", "f_dc_0", "y",
        "scale_0", "ny", "rot_3", "extra_b", "x", "scale_1", "f_dc_2", "rot_1", "nz",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    // Rest coefficients interleaved backwards among the others.
    for j in (0..9).rev() {
        names.insert(2 * j % names.len(), format!("f_rest_{j}"));
    }
    let props: Vec<(&str, &str)> = names
        .iter()
        .map(|n| match n.as_str() {
            "extra_a" => ("uchar", n.as_str()),
            "extra_b" => ("int", n.as_str()),
            "x" | "y" | "z" | "opacity" => ("double", n.as_str()),
            _ => ("float", n.as_str()),
        })
        .collect();
    let rows: Vec<Vec<f64>> = (0..cloud.len())
        .map(|i| names.iter().map(|n| value(i, n)).collect())
        .collect();
    for format in ["binary_little_endian", "ascii"] {
        let mut bytes = ply(format, &props, &rows);
        // An extra element after the vertices is ignored.
        let text_end = bytes.windows(10).position(|w| w == b"end_header").unwrap();
        bytes.splice(
            text_end..text_end,
            b"element face 3\nproperty list uchar int vertex_indices\n"
                .iter()
                .copied(),
        );
        bytes.extend_from_slice(if format == "ascii" {
            b"3 0 1 2\n"
        } else {
            b"\x03\0\0\0\0\x01\0\0\0\x02\0\0\0"
        });
        let (back, report) = read_ply_bytes(&bytes, "shuffled.ply").unwrap();
        assert_eq!(report.vertices_in_file, 50);
        assert_close(&cloud, &back);
    }
}

#[test]
fn integer_and_double_properties_are_accepted() {
    let props: Vec<(&str, &str)> = BASIC
        .iter()
        .enumerate()
        .map(|(i, n)| (["short", "int", "double", "uchar"][i % 4], *n))
        .collect();
    let row = vec![
        1.0, 2.0, 3.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0,
    ];
    for format in ["binary_little_endian", "ascii"] {
        let (c, _) =
            read_ply_bytes(&ply(format, &props, std::slice::from_ref(&row)), "ints.ply").unwrap();
        assert_eq!(c.positions, vec![Vec3::new(1.0, 2.0, 3.0)]);
        assert_eq!(c.sh, vec![0.0, 0.0, 1.0]);
        assert_eq!(c.opacities, vec![0.5]);
        assert!((c.scales[0].y - 1f32.exp()).abs() < 1e-6);
    }
}

// ---------------------------------------------------------------------------------------
// Errors

#[test]
fn missing_file_is_an_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nope.ply");
    let e = read_ply(&path).unwrap_err();
    assert!(matches!(e, PlyError::Io { .. }));
    let msg = e.to_string();
    assert!(msg.contains("nope.ply"), "{msg}");
}

#[test]
fn truncated_binary_file_is_an_error() {
    let cloud = random_cloud(10, 3, false, 3);
    let bytes = write_ply_bytes(&cloud, PlyFormat::BinaryLittleEndian, "t.ply").unwrap();
    let cut = &bytes[..bytes.len() - 100];
    let e = read_ply_bytes(cut, "cut.ply").unwrap_err();
    let msg = e.to_string();
    assert!(
        matches!(
            e,
            PlyError::Truncated {
                declared: 10,
                found: 9,
                ..
            }
        ),
        "{msg}"
    );
    // stride = (3 + 3 + 48 + 1 + 3 + 4) floats = 62 × 4 = 248 bytes
    assert!(msg.starts_with("cut.ply: "), "{msg}");
    assert!(msg.contains("2480 bytes"), "{msg}");
    assert!(msg.contains(&format!("found {}", 2480 - 100)), "{msg}");
    assert!(msg.contains("9 of the 10"), "{msg}");
}

#[test]
fn truncated_ascii_file_is_an_error() {
    let cloud = random_cloud(10, 0, false, 3);
    let bytes = write_ply_bytes(&cloud, PlyFormat::Ascii, "t.ply").unwrap();
    let text = String::from_utf8(bytes).unwrap();
    let cut: Vec<&str> = text.lines().collect();
    let cut = cut[..cut.len() - 3].join("\n");
    let msg = read_ply_bytes(cut.as_bytes(), "cut.ply")
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("cut.ply") && msg.contains("7 of the 10"),
        "{msg}"
    );
}

#[test]
fn missing_required_properties_are_named() {
    let names: Vec<&str> = BASIC
        .iter()
        .copied()
        .filter(|n| *n != "opacity" && *n != "rot_3")
        .collect();
    let mut row = basic_row(0.0);
    row.truncate(names.len());
    let bytes = ply("binary_little_endian", &floats(&names), &[row]);
    let e = read_ply_bytes(&bytes, "partial.ply").unwrap_err();
    let msg = e.to_string();
    match &e {
        PlyError::MissingProperties { missing, .. } => assert_eq!(missing, &["opacity", "rot_3"]),
        other => panic!("{other:?}"),
    }
    assert!(
        msg.starts_with("partial.ply: ") && msg.contains("opacity, rot_3"),
        "{msg}"
    );
}

#[test]
fn bad_f_rest_count_is_an_error_naming_the_count() {
    let mut names = BASIC.to_vec();
    names.extend(["f_rest_0", "f_rest_1", "f_rest_2", "f_rest_3", "f_rest_4"]);
    let mut row = basic_row(0.0);
    row.extend([0.0; 5]);
    let e = read_ply_bytes(&ply("ascii", &floats(&names), &[row]), "rest.ply").unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, PlyError::ShRestCount { count: 5, .. }), "{msg}");
    assert!(
        msg.contains("rest.ply") && msg.contains("5 f_rest"),
        "{msg}"
    );
}

#[test]
fn huge_vertex_count_is_refused_without_allocating() {
    for format in ["binary_little_endian", "ascii"] {
        let bytes = ply(format, &floats(&BASIC), &[basic_row(0.0)]);
        let text = String::from_utf8_lossy(&bytes)
            .replace("element vertex 1\n", "element vertex 1000000000000\n");
        let t = Instant::now();
        let e = read_ply_bytes(text.as_bytes(), "huge.ply").unwrap_err();
        assert!(t.elapsed().as_secs_f64() < 1.0);
        let msg = e.to_string();
        assert!(matches!(e, PlyError::Truncated { .. }), "{msg}");
        assert!(
            msg.contains("huge.ply") && msg.contains("1000000000000"),
            "{msg}"
        );
    }
    // Also a count that overflows every integer type is a header error, not a panic.
    let bytes = ply("binary_little_endian", &floats(&BASIC), &[basic_row(0.0)]);
    let text = String::from_utf8_lossy(&bytes).replace(
        "element vertex 1\n",
        "element vertex 99999999999999999999999\n",
    );
    assert!(read_ply_bytes(text.as_bytes(), "huge.ply").is_err());
}

#[test]
fn big_endian_is_unsupported() {
    let bytes = ply("binary_big_endian", &floats(&BASIC), &[basic_row(0.0)]);
    let e = read_ply_bytes(&bytes, "be.ply").unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, PlyError::Unsupported { .. }), "{msg}");
    assert!(
        msg.contains("be.ply") && msg.contains("big_endian"),
        "{msg}"
    );
}

#[test]
fn not_a_ply_file_is_a_header_error() {
    let e = read_ply_bytes(b"hello world\n\x00\x01", "junk.ply").unwrap_err();
    assert!(matches!(e, PlyError::Header { .. }), "{e}");
    assert!(e.to_string().starts_with("junk.ply: "));
}

// ---------------------------------------------------------------------------------------
// Skipping bad Gaussians

#[test]
fn nonfinite_values_are_skipped_and_counted() {
    let mut rows: Vec<Vec<f64>> = (0..6).map(|i| basic_row(f64::from(i))).collect();
    rows[1][0] = f64::NAN; // x
    rows[3][4] = f64::INFINITY; // f_dc_1
    rows[4][10] = f64::NEG_INFINITY; // rot_0
    for format in ["binary_little_endian", "ascii"] {
        let (c, r) = read_ply_bytes(&ply(format, &floats(&BASIC), &rows), "nan.ply").unwrap();
        assert_eq!(r.vertices_in_file, 6);
        assert_eq!(
            (r.skipped_nonfinite, r.skipped_degenerate),
            (3, 0),
            "{format}"
        );
        let xs: Vec<f32> = c.positions.iter().map(|p| p.x).collect();
        assert_eq!(xs, vec![0.0, 2.0, 5.0], "{format}");
        c.check_consistent().unwrap();
    }
}

#[test]
fn degenerate_scales_and_rotations_are_skipped_and_counted() {
    let mut rows: Vec<Vec<f64>> = (0..7).map(|i| basic_row(f64::from(i))).collect();
    rows[0][7] = -1000.0; // scale_0 underflows to 0 after exp
    rows[2][9] = 1000.0; // scale_2 overflows to inf after exp
    rows[3][10..14].copy_from_slice(&[0.0, 0.0, 0.0, 0.0]); // zero quaternion
    rows[5][8] = -200.0; // exp(-200) is 0 in f32
    rows[6][0] = f64::NAN; // and one non-finite
    for format in ["binary_little_endian", "ascii"] {
        let (c, r) = read_ply_bytes(&ply(format, &floats(&BASIC), &rows), "degen.ply").unwrap();
        assert_eq!(
            (r.skipped_nonfinite, r.skipped_degenerate),
            (1, 4),
            "{format}"
        );
        let xs: Vec<f32> = c.positions.iter().map(|p| p.x).collect();
        assert_eq!(xs, vec![1.0, 4.0], "{format}");
        assert!(c.scales.iter().all(|s| s.min_element() > 0.0));
    }
}

#[test]
fn skipping_across_parallel_chunks_keeps_order() {
    // Enough vertices for several decode chunks, every third one bad.
    let n = 50_000;
    let mut cloud = random_cloud(n, 0, false, 5);
    for i in (0..n).step_by(3) {
        cloud.positions[i].y = f32::NAN;
    }
    let bytes = write_ply_bytes(&cloud, PlyFormat::BinaryLittleEndian, "many.ply").unwrap();
    let (back, r) = read_ply_bytes(&bytes, "many.ply").unwrap();
    assert_eq!(r.skipped_nonfinite, n.div_ceil(3));
    let kept: Vec<usize> = (0..n).filter(|i| i % 3 != 0).collect();
    assert_eq!(back.len(), kept.len());
    for (j, &i) in kept.iter().enumerate() {
        assert_eq!(back.positions[j], cloud.positions[i]);
        assert_eq!(back.sh_of(j), cloud.sh_of(i));
    }
}

#[test]
fn unnormalised_quaternions_are_normalised() {
    let mut row = basic_row(0.0);
    row[10..14].copy_from_slice(&[0.0, 0.0, 0.0, 3.0]); // w x y z
    let (c, _) = read_ply_bytes(&ply("ascii", &floats(&BASIC), &[row]), "q.ply").unwrap();
    assert!(c.rotations[0].abs_diff_eq(Quat::from_xyzw(0.0, 0.0, 1.0, 0.0), 1e-7));
}

#[test]
fn mutated_files_never_panic() {
    let mut r = Rng(0xDEAD_BEEF);
    for format in [PlyFormat::BinaryLittleEndian, PlyFormat::Ascii] {
        let good = write_ply_bytes(&random_cloud(20, 1, true, 4), format, "m.ply").unwrap();
        for _ in 0..3000 {
            let mut b = good.clone();
            for _ in 0..1 + (r.next() * 4.0) as usize {
                let at = (r.next() * b.len() as f32) as usize % b.len();
                b[at] = match (r.next() * 4.0) as u32 {
                    0 => b'0' + (r.next() * 10.0) as u8,
                    1 => b' ',
                    2 => b'\n',
                    _ => (r.next() * 256.0) as u8,
                };
            }
            if r.next() < 0.2 {
                b.truncate((r.next() * b.len() as f32) as usize);
            }
            if let Ok((c, _)) = read_ply_bytes(&b, "m.ply") {
                c.check_consistent().unwrap();
            }
        }
    }
}
