use super::*;

#[test]
fn locate_finds_segments() {
    let t = [0.0, 1.0, 3.0];
    assert!(matches!(locate(&t, -1.0), Segment::At(0)));
    assert!(matches!(locate(&t, 0.0), Segment::At(0)));
    assert!(matches!(locate(&t, 1.0), Segment::At(1)));
    assert!(matches!(locate(&t, 5.0), Segment::At(2)));
    match locate(&t, 2.0) {
        Segment::Between(1, u) => assert!((u - 0.5).abs() < 1e-6),
        s => panic!("{s:?}"),
    }
}

#[test]
fn hermite_reproduces_a_straight_line_at_constant_speed() {
    let h = Hermite::new(
        vec![0.0, 1.0, 3.0, 3.5],
        vec![Vec3::ZERO, Vec3::X, Vec3::X * 3.0, Vec3::X * 3.5],
    );
    for k in 0..=35 {
        let t = k as f32 * 0.1;
        let p = h.eval(locate(&h.times, t));
        assert!((p.x - t).abs() < 1e-5 && p.y == 0.0, "{t}: {p}");
    }
}

#[test]
fn plane_basis_is_right_handed_about_up() {
    for up in [
        Vec3::Z,
        Vec3::Y,
        Vec3::new(0.3, -0.2, 0.9).normalize(),
        Vec3::X,
    ] {
        let (e1, e2) = plane_basis(up);
        assert!(e1.dot(up).abs() < 1e-6 && e2.dot(up).abs() < 1e-6 && e1.dot(e2).abs() < 1e-6);
        assert!((e1.cross(e2) - up).length() < 1e-5);
    }
    assert_eq!(plane_basis(Vec3::Z), (Vec3::X, Vec3::Y));
}

#[test]
fn orbit_framing_sees_the_whole_box() {
    let bounds = (Vec3::new(-1.0, -2.0, 0.0), Vec3::new(3.0, 2.0, 1.0));
    let path = CameraPath::orbit_framing(bounds, Vec3::Z, 45.0, 320, 180, 12);
    for f in 0..12 {
        let c = path.camera(f);
        assert!(c.position.z > 0.5, "above the centre");
        for corner in 0..8 {
            let p = Vec3::new(
                if corner & 1 == 0 {
                    bounds.0.x
                } else {
                    bounds.1.x
                },
                if corner & 2 == 0 {
                    bounds.0.y
                } else {
                    bounds.1.y
                },
                if corner & 4 == 0 {
                    bounds.0.z
                } else {
                    bounds.1.z
                },
            );
            let q = c.world_to_camera() * (p - c.position);
            assert!(q.z > c.near);
            let (u, v) = (c.fx * q.x / q.z + 160.0, c.fy * q.y / q.z + 90.0);
            assert!(
                (0.0..320.0).contains(&u) && (0.0..180.0).contains(&v),
                "frame {f} corner {corner}: {u} {v}"
            );
        }
    }
}
