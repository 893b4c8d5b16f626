use super::*;
use crate::rng::SplitMix64;

fn sample(n: usize, seed: u64) -> Checkpoint {
    let mut r = SplitMix64::new(seed);
    let mut v3 = || Vec3::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(-1.0, 1.0));
    let x: Vec<Vec3> = (0..n).map(|_| v3()).collect();
    let v: Vec<Vec3> = (0..n).map(|_| v3()).collect();
    let f: Vec<Mat3> = (0..n).map(|_| Mat3::from_cols(v3(), v3(), v3())).collect();
    let c: Vec<Mat3> = (0..n).map(|_| Mat3::from_cols(v3(), v3(), v3())).collect();
    let alpha: Vec<f32> = (0..n).map(|i| -(i as f32) * 0.01).collect();
    Checkpoint {
        scene_hash: 0x1234_5678_9abc_def0,
        deterministic: true,
        frame: 20,
        steps_per_frame: 7,
        clock: Clock {
            speed: 12.345678901234,
            steps_done: 140,
        },
        x,
        v,
        f,
        c,
        alpha,
    }
}

#[test]
fn round_trips_bit_for_bit_through_a_file_and_particles() {
    let dir = tempfile::tempdir().unwrap();
    let path = checkpoint_path(dir.path());
    let cp = sample(50, 3);
    cp.save(&path).unwrap();
    let back = Checkpoint::load(&path).unwrap();
    assert_eq!(back, cp);
    // f32 → f64 particles → f32 is exact.
    let like = Particles {
        x: vec![DVec3::ZERO; 50],
        v: vec![DVec3::ZERO; 50],
        f: vec![DMat3::IDENTITY; 50],
        c: vec![DMat3::ZERO; 50],
        alpha: vec![0.0; 50],
        mass: vec![1.0; 50],
        volume0: vec![1.0; 50],
        material: vec![0; 50],
    };
    let p = back.to_particles(&like);
    assert_eq!(
        Checkpoint::from_particles(&p, cp.scene_hash, true, 20, 7, cp.clock),
        cp
    );
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "no temporary file left"
    );
}

#[test]
fn refuses_other_scenes_modes_versions_and_damage() {
    let path = Path::new("run/checkpoint.bin");
    let cp = sample(4, 5);
    let bytes = cp.to_bytes();
    let err = |b: &[u8]| Checkpoint::from_bytes(path, b).unwrap_err().to_string();

    let e = cp
        .check_matches(path, 99, true, 4, 7)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("different scene") && e.contains("run/checkpoint.bin"),
        "{e}"
    );
    let e = cp
        .check_matches(path, cp.scene_hash, false, 4, 7)
        .unwrap_err()
        .to_string();
    assert!(e.contains("--deterministic"), "{e}");
    let e = cp
        .check_matches(path, cp.scene_hash, true, 5, 7)
        .unwrap_err()
        .to_string();
    assert!(e.contains("4 particles"), "{e}");
    cp.check_matches(path, cp.scene_hash, true, 4, 7).unwrap();

    let e = err(b"PK\x03\x04 not a checkpoint at all");
    assert!(e.contains("not a splatter checkpoint"), "{e}");
    let mut other = bytes.clone();
    other[8] = 1;
    let e = err(&other);
    assert!(
        e.contains("format 1") && e.contains("cannot continue"),
        "{e}"
    );
    let mut other = bytes.clone();
    other[12..17].copy_from_slice(b"9.9.9");
    let e = err(&other);
    assert!(e.contains("splatter 9.9.9"), "{e}");
    let e = err(&bytes[..bytes.len() - 1]);
    assert!(e.contains("truncated"), "{e}");
    let e = err(&bytes[..30]);
    assert!(e.contains("shorter than"), "{e}");
    let mut flipped = bytes.clone();
    flipped[HEADER_BYTES + 5] ^= 1;
    let e = err(&flipped);
    assert!(e.contains("checksum"), "{e}");
}

#[test]
fn a_huge_count_is_refused_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("checkpoint.bin");
    let mut bytes = sample(1, 1).to_bytes();
    let o = HEADER_BYTES - 8;
    bytes[o..o + 8].copy_from_slice(&(1u64 << 60).to_le_bytes());
    std::fs::write(&path, &bytes).unwrap();
    let e = Checkpoint::load(&path).unwrap_err().to_string();
    assert!(e.contains("1152921504606846976 particles"), "{e}");
    bytes[o..o + 8].copy_from_slice(&u64::MAX.to_le_bytes());
    std::fs::write(&path, &bytes).unwrap();
    let e = Checkpoint::load(&path).unwrap_err().to_string();
    assert!(e.contains("more than 2^64"), "{e}");
}

#[test]
fn fuzzed_checkpoints_never_panic() {
    let good = sample(3, 9).to_bytes();
    let mut r = SplitMix64::new(42);
    let path = Path::new("fuzz.bin");
    for _ in 0..2000 {
        let mut b = good.clone();
        match r.next_u64() % 3 {
            0 => b.truncate((r.next_u64() as usize) % (good.len() + 1)),
            1 => {
                for _ in 0..1 + r.next_u64() % 8 {
                    let i = (r.next_u64() as usize) % b.len();
                    b[i] = r.next_u64() as u8;
                }
            }
            _ => {
                b = (0..r.next_u64() % 400)
                    .map(|_| r.next_u64() as u8)
                    .collect()
            }
        }
        let _ = Checkpoint::from_bytes(path, &b);
    }
}
