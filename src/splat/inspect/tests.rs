use super::*;

#[test]
fn axis_names_round_trip_and_upright_turns_up_to_z() {
    for a in AXES {
        let v = axis_vector(a).unwrap();
        assert_eq!(axis_name(v), Some(a));
        assert!((upright_rotation(v) * v).distance(Vec3::Z) < 1e-6, "{a}");
    }
    assert_eq!(axis_vector("y"), Some(Vec3::Y));
    assert_eq!(axis_vector("w"), None);
    let tilted = Vec3::new(0.3, -0.8, 0.2).normalize();
    assert!((upright_rotation(tilted) * tilted).distance(Vec3::Z) < 1e-5);
}

/// Camera-to-world rotations (OpenCV axes) of `n` cameras on a circle round `up`, each
/// pitched `pitch_deg` down at the centre and rolled `roll_deg(i)` about its view axis.
fn orbit(up: Vec3, n: usize, pitch_deg: f32, roll_deg: impl Fn(usize) -> f32) -> Vec<Mat3> {
    let (e1, e2) = up.any_orthonormal_pair();
    let pitch = pitch_deg.to_radians();
    (0..n)
        .map(|i| {
            let azimuth = std::f32::consts::TAU * i as f32 / n as f32;
            let radial = azimuth.cos() * e1 + azimuth.sin() * e2;
            let forward = -pitch.cos() * radial - pitch.sin() * up;
            let right = forward.cross(up).normalize();
            let down = forward.cross(right);
            let roll = Mat3::from_axis_angle(forward, roll_deg(i).to_radians());
            Mat3::from_cols(roll * right, roll * down, forward)
        })
        .collect()
}

/// Cameras round a known up off every axis: their mean up is it, their agreement the
/// cosine of their pitch and their spread the pitch.
#[test]
fn cameras_up_of_an_orbit_is_its_up() {
    let up = Vec3::new(0.2, -0.9, 0.35).normalize();
    let found = cameras_up(&orbit(up, 24, 30.0, |_| 0.0)).unwrap();
    assert!(found.up.angle_between(up) < 1e-3, "{found:?}");
    assert_eq!(found.count, 24);
    assert!(
        (found.agreement - 30f32.to_radians().cos()).abs() < 1e-4,
        "{found:?}"
    );
    assert!((found.spread_deg - 30.0).abs() < 0.05, "{found:?}");
    // Hand-held roll of a few degrees either way moves the mean by less.
    let shaky = cameras_up(&orbit(up, 24, 30.0, |i| [4.0, -3.0, 1.0][i % 3])).unwrap();
    assert!(shaky.up.angle_between(up).to_degrees() < 1.0, "{shaky:?}");
    assert!(cameras_up(&[]).is_none());
}

/// Cameras decide ahead of the geometry, snapped to an axis within 10°; cameras whose ups
/// cancel (held every way round) do not, and the result is the convention's guess.
#[test]
fn cameras_decide_unless_they_disagree() {
    let scores = [0.0; 6];
    let tilted = Mat3::from_rotation_z(5f32.to_radians()) * Vec3::Y;
    let agreeing = cameras_up(&orbit(tilted, 12, 20.0, |_| 0.0));
    let (up, evidence) = estimate_up(agreeing, None, &scores);
    assert_eq!(up, Vec3::Y);
    assert!(
        matches!(evidence, UpEvidence::Cameras { count: 12, .. }),
        "{evidence:?}"
    );
    // Ahead of a support plane and a seen top that say otherwise.
    let mut seen_top = [0.0; 6];
    seen_top[4] = 0.5;
    let plane = Some((Vec3::Z, 0.0, 0.5));
    assert_eq!(estimate_up(agreeing, plane, &seen_top).0, Vec3::Y);
    assert_eq!(estimate_up(None, plane, &seen_top).0, Vec3::Z);
    let every_way = cameras_up(&orbit(Vec3::Y, 12, 20.0, |i| 90.0 * i as f32));
    assert!(
        every_way.is_none_or(|c| c.agreement < CAMERAS_AGREEMENT),
        "{every_way:?}"
    );
    let (up, evidence) = estimate_up(every_way, None, &scores);
    assert_eq!((up, evidence), (-Vec3::Y, UpEvidence::Convention));
}

/// A seen top decides only with the margin measured on real captures: the guitar's
/// wrong +y (0.036 against 0.010) falls back to the convention's guess, the donut's +z
/// (0.067 against 0.022) decides; and either way round (flipped, turned by 90°: the
/// scores permuted) the answer turns with the capture.
#[test]
fn a_seen_top_decides_only_by_the_measured_margin() {
    // +x, −x, +y, −y, +z, −z
    let guitar = [0.004, -0.004, 0.036, -0.036, 0.010, -0.010];
    assert_eq!(estimate_up(None, None, &guitar).1, UpEvidence::Convention);
    let donut = [0.019, -0.019, 0.022, -0.022, 0.067, -0.067];
    let (up, evidence) = estimate_up(None, None, &donut);
    assert_eq!(up, Vec3::Z);
    assert!(
        matches!(evidence, UpEvidence::SeenTop { .. }),
        "{evidence:?}"
    );
    // Turned so that +z goes to −y: the scores move with the axes.
    let turned = [donut[0], donut[1], donut[5], donut[4], donut[2], donut[3]];
    assert_eq!(estimate_up(None, None, &turned).0, -Vec3::Y);
    let flipped = donut.map(|s| -s);
    assert_eq!(estimate_up(None, None, &flipped).0, -Vec3::Z);
}

/// A capture turned by 90° about an axis, or flipped, has its seen-top scores permuted
/// (and negated for a flip): the margins measured on a capture as it was written hold
/// for every axis-aligned orientation of it. On the repository's plant capture.
#[test]
fn turning_a_capture_permutes_its_scores() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/captures/plant_3k.ply");
    let cloud = crate::splat::formats::read_splats(&path)
        .expect("the plant capture")
        .0;
    let scores = inspect(&cloud).axis_scores;
    // (x, y, z) → (x, −z, y): a quarter turn about x; +y's score becomes +z's.
    let mut turned = cloud.clone();
    for p in &mut turned.positions {
        *p = Vec3::new(p.x, -p.z, p.y);
    }
    let t = inspect(&turned).axis_scores;
    let close = |a: f32, b: f32| (a - b).abs() < 2e-3;
    assert!(close(t[0], scores[0]), "{t:?} {scores:?}");
    assert!(
        close(t[4], scores[2]),
        "+z of the turned is +y: {t:?} {scores:?}"
    );
    assert!(
        close(t[2], scores[5]),
        "+y of the turned is −z: {t:?} {scores:?}"
    );
    let mut flipped = cloud.clone();
    for p in &mut flipped.positions {
        *p = -*p;
    }
    let f = inspect(&flipped).axis_scores;
    for (a, b) in f.iter().zip(scores) {
        assert!(close(*a, -b), "{f:?} {scores:?}");
    }
}

/// Cameras that disagree are reported as not used, and the guess's warning says why.
#[test]
fn disagreeing_cameras_are_reported() {
    let mut cloud = GaussianCloud::default();
    let mut rng = SplitMix64::new(3);
    for _ in 0..500 {
        let p = Vec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        cloud.positions.push(p);
        cloud.scales.push(Vec3::splat(0.01));
        cloud.rotations.push(glam::Quat::IDENTITY);
        cloud.opacities.push(0.9);
        cloud.sh.extend([0.0; 3]);
    }
    let every_way = cameras_up(&orbit(Vec3::Y, 12, 20.0, |i| 90.0 * i as f32));
    let found = inspect_with_cameras(&cloud, every_way);
    assert!(found.is_guess(), "{:?}", found.evidence);
    let report = found.to_string();
    assert!(report.contains("not from the 12 cameras"), "{report}");
    let warning = found.guess_warning("cube").unwrap();
    assert!(
        warning.contains("12 cameras whose ups disagree"),
        "{warning}"
    );
}
