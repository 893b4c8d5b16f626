//! Hostile input: the PLY reader and the scene parser on random, mutated, truncated and
//! oversized inputs must return an error or a value — never panic, never hang, and never
//! allocate far more than the input could need (a header's counts are checked against the
//! bytes present before anything is allocated).
//!
//! A seeded generator (`splatter::rng::SplitMix64`, fixed seeds) makes every run test the
//! same inputs, so the test cannot be flaky; the number of cases is fixed and the whole
//! file runs in a few seconds. A failing case prints the seed and case number and writes the
//! input to `out/hostile-input-failures/` as a reproducer.
//!
//! A counting global allocator records the largest single allocation while each input is
//! parsed; it must stay below a bound proportional to the input's size.

use std::alloc::{GlobalAlloc, Layout, System};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

use glam::{Quat, Vec3};
use splatter::rng::SplitMix64;
use splatter::splat::ply::{read_ply_bytes, write_ply_bytes, PlyFormat};
use splatter::splat::GaussianCloud;

// ---------------------------------------------------------------------------------------------
// Largest single allocation, measured while a case runs
// ---------------------------------------------------------------------------------------------

struct Counting;

static LARGEST: AtomicUsize = AtomicUsize::new(0);
static MEASURING: AtomicBool = AtomicBool::new(false);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if MEASURING.load(Ordering::Relaxed) {
            LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if MEASURING.load(Ordering::Relaxed) {
            LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
        }
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if MEASURING.load(Ordering::Relaxed) {
            LARGEST.fetch_max(new_size, Ordering::Relaxed);
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Tests in this file measure one at a time (the counter is global).
static SERIAL: Mutex<()> = Mutex::new(());

/// Run `f` on `input`, catching a panic; returns the largest allocation made meanwhile.
fn run_case<R>(what: &str, seed: u64, case: usize, input: &[u8], f: impl FnOnce() -> R) -> usize {
    LARGEST.store(0, Ordering::Relaxed);
    MEASURING.store(true, Ordering::Relaxed);
    let result = catch_unwind(AssertUnwindSafe(f));
    MEASURING.store(false, Ordering::Relaxed);
    if result.is_err() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("out/hostile-input-failures");
        let _ = std::fs::create_dir_all(&dir);
        let file = dir.join(format!("{what}-seed{seed}-case{case}.bin"));
        let _ = std::fs::write(&file, input);
        panic!(
            "{what}: seed {seed}, case {case} panicked; input written to {}",
            file.display()
        );
    }
    LARGEST.load(Ordering::Relaxed)
}

fn pick<T: Copy>(r: &mut SplitMix64, xs: &[T]) -> T {
    xs[(r.next_u64() % xs.len() as u64) as usize]
}

fn below(r: &mut SplitMix64, n: usize) -> usize {
    (r.next_u64() % n.max(1) as u64) as usize
}

// ---------------------------------------------------------------------------------------------
// PLY
// ---------------------------------------------------------------------------------------------

fn random_cloud(r: &mut SplitMix64, n: usize, degree: u32) -> GaussianCloud {
    let mut c = GaussianCloud {
        sh_degree: degree,
        ..Default::default()
    };
    let k = splatter::splat::sh_coeff_count(degree) * 3;
    for _ in 0..n {
        c.positions.push(Vec3::new(
            r.range(-1.0, 1.0),
            r.range(-1.0, 1.0),
            r.range(-1.0, 1.0),
        ));
        c.scales.push(Vec3::splat(r.range(0.01, 0.1)));
        c.rotations.push(
            Quat::from_xyzw(
                r.range(-1.0, 1.0),
                r.range(-1.0, 1.0),
                r.range(-1.0, 1.0),
                1.0,
            )
            .normalize(),
        );
        c.opacities.push(r.range(0.05, 0.95));
        for _ in 0..k {
            c.sh.push(r.range(-1.0, 1.0));
        }
    }
    c
}

/// Replace the vertex count in the header with `count` (text).
fn with_count(bytes: &[u8], count: &str) -> Vec<u8> {
    let text = String::from_utf8_lossy(bytes);
    let Some(start) = text.find("element vertex ") else {
        return bytes.to_vec();
    };
    let digits = start + "element vertex ".len();
    let end = digits + text[digits..].find('\n').unwrap_or(0);
    let mut out = bytes[..digits].to_vec();
    out.extend_from_slice(count.as_bytes());
    out.extend_from_slice(&bytes[end..]);
    out
}

/// One mutation of a valid PLY file.
fn mutate_ply(r: &mut SplitMix64, valid: &[u8]) -> Vec<u8> {
    let header_end = valid
        .windows(11)
        .position(|w| w == b"end_header\n")
        .map_or(valid.len(), |p| p + 11);
    let mut b = valid.to_vec();
    match below(r, 9) {
        // Truncated anywhere.
        0 => b.truncate(below(r, valid.len() + 1)),
        // Bytes flipped in the header (keywords, types, names, counts).
        1 => {
            for _ in 0..1 + below(r, 4) {
                let i = below(r, header_end);
                b[i] = r.next_u64() as u8;
            }
        }
        // Bytes flipped in the body.
        2 => {
            for _ in 0..1 + below(r, 16) {
                let i = below(r, b.len());
                b[i] = r.next_u64() as u8;
            }
        }
        // Absurd or malformed vertex counts.
        3 => {
            let counts = [
                "1000000000000",
                "18446744073709551615",
                "18446744073709551616",
                "99999999999999999999999",
                "-1",
                "0",
                "4294967296",
                "2147483648",
                "1e9",
                "",
                "0x10",
            ];
            b = with_count(valid, pick(r, &counts));
        }
        // A count slightly above or below the truth.
        4 => {
            let text = String::from_utf8_lossy(valid);
            let n: i64 = text
                .split("element vertex ")
                .nth(1)
                .and_then(|s| s.split('\n').next())
                .and_then(|s| s.parse().ok())
                .unwrap_or(0);
            let delta = below(r, 5) as i64 - 2;
            b = with_count(valid, &(n + delta).max(0).to_string());
        }
        // Property types swapped for other PLY types (sizes change).
        5 => {
            let types = [
                "char",
                "uchar",
                "short",
                "ushort",
                "int",
                "uint",
                "double",
                "list uchar float",
                "float64",
                "bogus",
            ];
            let text = String::from_utf8_lossy(&valid[..header_end]).into_owned();
            let lines: Vec<&str> = text.lines().collect();
            let props: Vec<usize> = (0..lines.len())
                .filter(|i| lines[*i].starts_with("property float"))
                .collect();
            if let Some(&i) = props.get(below(r, props.len())) {
                let name = lines[i].rsplit(' ').next().unwrap_or("x");
                let mut new: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
                new[i] = format!("property {} {name}", pick(r, &types));
                let mut out = (new.join("\n") + "\n").into_bytes();
                out.extend_from_slice(&valid[header_end..]);
                b = out;
            }
        }
        // Extra elements, comments and garbage lines in the header.
        6 => {
            let inserts = [
                "element face 1000000000000\nproperty list uchar int vertex_indices\n",
                "element vertex 5\n",
                "comment \u{0}\u{ff}\n",
                "property float x\n",
                "obj_info nothing\n",
                "format ascii 1.0\n",
                "\n\n\n",
            ];
            let at = valid[..header_end.saturating_sub(11)]
                .iter()
                .rposition(|c| *c == b'\n')
                .map_or(0, |p| p + 1);
            let mut out = valid[..at].to_vec();
            out.extend_from_slice(pick(r, &inserts).as_bytes());
            out.extend_from_slice(&valid[at..]);
            b = out;
        }
        // A header that never ends, or random bytes.
        7 => {
            b = b"ply\nformat binary_little_endian 1.0\n".to_vec();
            for _ in 0..below(r, 2000) {
                b.push(r.next_u64() as u8);
            }
        }
        // Oversized: the valid body repeated (more data than the header declares).
        _ => {
            let body = valid[header_end..].to_vec();
            for _ in 0..1 + below(r, 3) {
                b.extend_from_slice(&body);
            }
        }
    }
    b
}

#[test]
fn ply_reader_survives_random_truncated_and_oversized_files() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let seed = 0x5eed_0001;
    let mut r = SplitMix64::new(seed);
    let start = Instant::now();
    let mut valid_files = Vec::new();
    for degree in 0..=3 {
        for format in [PlyFormat::BinaryLittleEndian, PlyFormat::Ascii] {
            let n = 1 + below(&mut r, 20);
            let cloud = random_cloud(&mut r, n, degree);
            valid_files.push(write_ply_bytes(&cloud, format, "valid.ply").unwrap());
        }
    }
    // The unmutated files read back.
    for v in &valid_files {
        read_ply_bytes(v, "valid.ply").expect("a valid file reads");
    }
    let cases = 40_000;
    let (mut ok, mut err) = (0, 0);
    let mut worst = (0usize, 0usize);
    for case in 0..cases {
        let valid = &valid_files[case % valid_files.len()];
        let input = mutate_ply(&mut r, valid);
        let mut outcome = None;
        let largest = run_case("ply", seed, case, &input, || {
            outcome = Some(read_ply_bytes(&input, "fuzz.ply").map(|(c, _)| c.len()));
        });
        // The reader may hold a copy of the input and the cloud it decodes (at most one
        // Gaussian of ≤ 60 floats per 4 input bytes, i.e. ~60× the input) — never what
        // an absurd header count asks for.
        let bound = 64 * input.len() + (1 << 20);
        assert!(
            largest <= bound,
            "ply: seed {seed}, case {case}: an allocation of {largest} bytes for a {}-byte input",
            input.len()
        );
        if largest > worst.0 {
            worst = (largest, input.len());
        }
        match outcome {
            Some(Ok(_)) => ok += 1,
            Some(Err(e)) => {
                let msg = e.to_string();
                assert!(msg.contains("fuzz.ply"), "errors name the file: {msg}");
                err += 1;
            }
            None => unreachable!(),
        }
    }
    let secs = start.elapsed().as_secs_f64();
    eprintln!(
        "ply: {cases} cases in {secs:.2} s: {ok} read, {err} refused; largest allocation {} bytes (input {} bytes)",
        worst.0, worst.1
    );
    assert!(
        err > cases / 4 && ok > 0,
        "the mutations reach both outcomes"
    );
}

// ---------------------------------------------------------------------------------------------
// The other splat formats
// ---------------------------------------------------------------------------------------------

/// Every compact format's reader on truncated and byte-flipped copies of a real file (the
/// fixtures splat-transform wrote, and what our writers write): an error or a cloud, never
/// a panic, and no allocation far beyond what the declared counts could hold.
#[test]
fn splat_format_readers_survive_truncated_and_flipped_files() {
    use splatter::splat::formats::{
        read_splats_bytes, write_splats_bytes, SourceFrame, WriteFormat,
    };
    use splatter::splat::spz::SpzVersion;
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let seed = 0x5eed_0005;
    let mut r = SplitMix64::new(seed);
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/formats");
    let small = random_cloud(&mut r, 300, 1);
    let mut files: Vec<(String, Vec<u8>)> = [
        "donut_4k.v3.spz",
        "donut_4k.v4.spz",
        "donut_4k.splat",
        "donut_4k.compressed.ply",
        "donut_4k.sog",
        "donut_300_sh3.glb",
    ]
    .iter()
    .map(|n| (n.to_string(), std::fs::read(dir.join(n)).unwrap()))
    .collect();
    for (name, f) in [
        ("ours.v3.spz", WriteFormat::Spz(SpzVersion::V3)),
        ("ours.v4.spz", WriteFormat::Spz(SpzVersion::V4)),
        ("ours.splat", WriteFormat::Splat),
        ("ours.glb", WriteFormat::Glb(SourceFrame::Capture)),
    ] {
        files.push((
            name.to_string(),
            write_splats_bytes(&small, f, name).unwrap(),
        ));
    }
    let cases = 1_500;
    let (mut ok, mut err) = (0, 0);
    for case in 0..cases {
        let (name, valid) = &files[case % files.len()];
        let mut input = valid.clone();
        match below(&mut r, 3) {
            0 => input.truncate(below(&mut r, valid.len())),
            1 => {
                for _ in 0..1 + below(&mut r, 8) {
                    let i = below(&mut r, input.len());
                    input[i] ^= 1 << below(&mut r, 8);
                }
            }
            _ => {
                // Flip bytes in the first 64 (the headers and tables of contents).
                for _ in 0..1 + below(&mut r, 3) {
                    let i = below(&mut r, input.len().min(64));
                    input[i] = r.next_u64() as u8;
                }
            }
        }
        let path = Path::new("fuzz").join(name);
        let mut outcome = None;
        let largest = run_case("formats", seed, case, &input, || {
            outcome = Some(read_splats_bytes(&input, &path).map(|(c, _)| c.len()));
        });
        // A decoded Gaussian takes ≤ 240 bytes; the compact formats spend ≥ 2 bits of
        // compressed input per byte of stream, and SOG images expand ~8× as RGBA.
        let bound = 2048 * input.len() + (16 << 20);
        assert!(
            largest <= bound,
            "{name}: case {case}: an allocation of {largest} bytes for a {}-byte input",
            input.len()
        );
        match outcome {
            Some(Ok(_)) => ok += 1,
            Some(Err(e)) => {
                let msg = e.to_string();
                assert!(
                    msg.contains(name.as_str()) && !msg.contains('\n'),
                    "one line naming the file: {msg}"
                );
                err += 1;
            }
            None => unreachable!(),
        }
    }
    eprintln!("formats: {cases} cases: {ok} read, {err} refused");
    assert!(
        err > cases / 4 && ok > 0,
        "the mutations reach both outcomes"
    );
}

#[test]
fn ply_header_claiming_a_trillion_vertices_is_refused_without_allocating() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let mut r = SplitMix64::new(7);
    for format in [PlyFormat::BinaryLittleEndian, PlyFormat::Ascii] {
        let valid = write_ply_bytes(&random_cloud(&mut r, 3, 1), format, "v.ply").unwrap();
        let input = with_count(&valid, "1000000000000");
        let mut result = None;
        let largest = run_case("ply-trillion", 7, 0, &input, || {
            result = Some(read_ply_bytes(&input, "huge.ply").map(|(c, _)| c.len()))
        });
        let e = result.unwrap().unwrap_err().to_string();
        assert!(e.contains("huge.ply") && e.contains("1000000000000"), "{e}");
        assert!(largest < 1 << 20, "largest allocation {largest} bytes");
    }
}

// ---------------------------------------------------------------------------------------------
// Scene files
// ---------------------------------------------------------------------------------------------

fn repo_scenes() -> Vec<String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut texts: Vec<String> = ["default", "jelly", "fracture", "keyframes"]
        .iter()
        .map(|n| std::fs::read_to_string(root.join(format!("scenes/{n}.json"))).unwrap())
        .collect();
    texts.push(std::fs::read_to_string(root.join("tests/golden/procedural.json")).unwrap());
    texts
}

/// Values that stress validation: zeros, negatives, huge, non-finite spellings, wrong types.
const HOSTILE_VALUES: [&str; 24] = [
    "0",
    "-0",
    "-1",
    "1e308",
    "-1e308",
    "1e-320",
    "1e400",
    "4294967295",
    "4294967296",
    "18446744073709551616",
    "99999999999999999999999999",
    "0.5",
    "NaN",
    "Infinity",
    "\"NaN\"",
    "\"\"",
    "null",
    "true",
    "[]",
    "{}",
    "[1e308, 1e308, 1e308]",
    "[0, 0, 0]",
    "[[0,0,0],[0,0,0],[0,0,0]]",
    "\"../../../../etc/passwd\"",
];

/// One mutation of a valid scene file's text.
fn mutate_scene(r: &mut SplitMix64, text: &str) -> String {
    let b = text.as_bytes();
    match below(r, 6) {
        0 => String::from_utf8_lossy(&b[..below(r, b.len() + 1)]).into_owned(),
        1 => {
            let mut v = b.to_vec();
            for _ in 0..1 + below(r, 4) {
                let i = below(r, v.len());
                v[i] = pick(r, b"{}[]\",:0123456789.-eE \n");
            }
            String::from_utf8_lossy(&v).into_owned()
        }
        // A number in the file replaced by a hostile value.
        2 | 3 => {
            let starts: Vec<usize> = (0..b.len())
                .filter(|&i| {
                    (b[i].is_ascii_digit() || b[i] == b'-')
                        && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'.'))
                })
                .collect();
            let Some(&s) = starts.get(below(r, starts.len())) else {
                return text.to_string();
            };
            let mut e = s + 1;
            while e < b.len() && (b[e].is_ascii_digit() || b"+-.eE".contains(&b[e])) {
                e += 1;
            }
            format!("{}{}{}", &text[..s], pick(r, &HOSTILE_VALUES), &text[e..])
        }
        // A string value (shape, model, type, kind…) replaced.
        4 => {
            let quotes: Vec<usize> = text.match_indices(": \"").map(|(i, _)| i + 3).collect();
            let Some(&s) = quotes.get(below(r, quotes.len())) else {
                return text.to_string();
            };
            let e = s + text[s..].find('"').unwrap_or(0);
            let long = "x".repeat(10_000);
            let words = [
                "",
                "sphere",
                "box",
                "slab",
                "orbit",
                "keyframes",
                "nacc",
                "sticky",
                long.as_str(),
            ];
            format!("{}{}{}", &text[..s], pick(r, &words), &text[e..])
        }
        // A key's value replaced wholesale by a hostile value.
        _ => {
            let keys: Vec<usize> = text.match_indices("\": ").map(|(i, _)| i + 3).collect();
            let Some(&s) = keys.get(below(r, keys.len())) else {
                return text.to_string();
            };
            // Up to the next comma or closing bracket at the same depth.
            let mut depth = 0i32;
            let mut e = s;
            for (i, c) in text[s..].char_indices() {
                match c {
                    '[' | '{' => depth += 1,
                    ']' | '}' if depth == 0 => {
                        e = s + i;
                        break;
                    }
                    ']' | '}' => depth -= 1,
                    ',' if depth == 0 => {
                        e = s + i;
                        break;
                    }
                    _ => {}
                }
            }
            format!("{}{}{}", &text[..s], pick(r, &HOSTILE_VALUES), &text[e..])
        }
    }
}

#[test]
fn scene_parser_survives_mutated_and_truncated_scenes() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let seed = 0x5eed_0002;
    let mut r = SplitMix64::new(seed);
    let scenes = repo_scenes();
    let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let start = Instant::now();
    let cases = 30_000;
    let (mut ok, mut err) = (0, 0);
    for case in 0..cases {
        let text = mutate_scene(&mut r, &scenes[case % scenes.len()]);
        let mut outcome = None;
        let largest = run_case("scene", seed, case, text.as_bytes(), || {
            // Parse and validate, then evaluate the camera path at a few frames (what a
            // render does before loading any object).
            outcome = Some(
                splatter::scene::parse(&text, "fuzz.json", &base).map(|scene| {
                    if let Ok(path) = scene.camera_path() {
                        let last = scene.frame_count().saturating_sub(1);
                        for f in [0, last / 2, last] {
                            let _ = path.camera(f);
                        }
                    }
                }),
            );
        });
        assert!(
            largest <= 64 * text.len() + (4 << 20),
            "scene: seed {seed}, case {case}: an allocation of {largest} bytes"
        );
        match outcome {
            Some(Ok(())) => ok += 1,
            Some(Err(e)) => {
                let msg = e.to_string();
                assert!(msg.contains("fuzz.json"), "errors name the file: {msg}");
                err += 1;
            }
            None => unreachable!(),
        }
    }
    eprintln!(
        "scene: {cases} cases in {:.2} s: {ok} parsed, {err} refused",
        start.elapsed().as_secs_f64()
    );
    assert!(
        err > cases / 4 && ok > 0,
        "the mutations reach both outcomes"
    );
}

#[test]
fn random_bytes_are_neither_ply_nor_scene() {
    let _serial = SERIAL.lock().unwrap_or_else(|p| p.into_inner());
    let seed = 0x5eed_0003;
    let mut r = SplitMix64::new(seed);
    for case in 0..5000 {
        let n = below(&mut r, 512);
        let mut input: Vec<u8> = (0..n).map(|_| r.next_u64() as u8).collect();
        if case % 2 == 0 && input.len() >= 4 {
            input[..4].copy_from_slice(b"ply\n");
        }
        let text = String::from_utf8_lossy(&input).into_owned();
        let mut results = (true, true);
        run_case("bytes", seed, case, &input, || {
            results.0 = read_ply_bytes(&input, "r.ply").is_err();
            results.1 = splatter::scene::parse(&text, "r.json", Path::new(".")).is_err();
        });
        assert!(results.0 && results.1, "case {case}: random bytes accepted");
    }
}
