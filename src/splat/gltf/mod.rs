//! glTF 2.0 with `KHR_gaussian_splatting` (docs/formats.md): a POINTS mesh primitive whose
//! attributes are the Gaussians: `POSITION`, `KHR_gaussian_splatting:ROTATION` (xyzw),
//! `…:SCALE` (linear), `…:OPACITY` (in [0, 1], after the sigmoid) and
//! `…:SH_DEGREE_l_COEF_n` (the raw coefficients, DC included: colour = 0.5 + C0 · DC), in
//! a `.glb` or a `.gltf` JSON file. `KHR_gaussian_splatting_compression_spz_2` carries an
//! SPZ payload instead of the attribute data.
//!
//! **Container.** The GLB chunks and the JSON are read here with serde_json, not with the
//! `gltf` crate: gltf 1.4.1 refuses a whole document at the first attribute name outside
//! the core set ("invalid semantic name"), and every attribute of this extension is one.
//! The container is small (a 12-byte header, a JSON chunk, a BIN chunk).
//!
//! **Frame.** glTF is +y up, +z forward, right-handed. PLY, SPZ and `.splat` hold a
//! capture in its trainer's frame, y down for COLMAP-based trainers; splat-transform and
//! Niantic's spz library turn such a frame into glTF's by a half turn about z (x and y
//! change sign). We do the same both ways, so a cloud read from a GLB is held in the frame
//! its PLY would have (a GLB that splat-transform made from a PLY reads back as that PLY),
//! and glTF's up is then −y ([`DECLARED_UP`]).
//!
//! **Labels.** Region labels travel as an application attribute, [`LABEL_ATTRIBUTE`] (an
//! unsigned integer per Gaussian; glTF reserves names with a leading underscore for
//! applications), with their names in the primitive's `extras` under the same key.

mod accessor;
mod container;
mod read;
mod write;

use glam::{Quat, Vec3};

use super::codec::DeclaredUp;
use super::sh::basis;
use super::GaussianCloud;

pub use container::GLB_MAGIC;
pub use read::read;
pub use write::{write, SourceFrame};

pub const EXTENSION: &str = "KHR_gaussian_splatting";
/// The SPZ compression extension, as ratified and as an earlier draft named it.
pub const SPZ_EXTENSIONS: [&str; 2] = [
    "KHR_gaussian_splatting_compression_spz_2",
    "KHR_gaussian_splatting_compression_spz",
];
pub const ROTATION: &str = "KHR_gaussian_splatting:ROTATION";
pub const SCALE: &str = "KHR_gaussian_splatting:SCALE";
pub const OPACITY: &str = "KHR_gaussian_splatting:OPACITY";
/// Per-Gaussian region labels (ours); their names are in the primitive's
/// `extras["_SPLATTER_LABEL"]`.
pub const LABEL_ATTRIBUTE: &str = "_SPLATTER_LABEL";

/// glTF's +y up, in the frame a GLB's cloud is held in (after the half turn about z).
pub const DECLARED_UP: DeclaredUp = DeclaredUp {
    axis: "-y",
    source: "the glTF frame (its +y up, held here in a PLY's frame: a half turn about z)",
};

/// `KHR_gaussian_splatting:SH_DEGREE_{degree}_COEF_{n}`.
pub fn sh_attribute(degree: u32, n: u32) -> String {
    format!("KHR_gaussian_splatting:SH_DEGREE_{degree}_COEF_{n}")
}

/// A coordinate axis of a half turn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    X,
    Y,
    Z,
}

/// Turn `cloud` half a turn about `axis`: the two other coordinates change sign. Exact:
/// positions and normals change sign, quaternions are multiplied by a unit axis (a signed
/// permutation of their components) and each SH coefficient keeps or changes its sign.
pub fn half_turn(cloud: &mut GaussianCloud, axis: Axis) {
    let (flip, turn) = match axis {
        Axis::X => (
            Vec3::new(1.0, -1.0, -1.0),
            Quat::from_xyzw(1.0, 0.0, 0.0, 0.0),
        ),
        Axis::Y => (
            Vec3::new(-1.0, 1.0, -1.0),
            Quat::from_xyzw(0.0, 1.0, 0.0, 0.0),
        ),
        Axis::Z => (
            Vec3::new(-1.0, -1.0, 1.0),
            Quat::from_xyzw(0.0, 0.0, 1.0, 0.0),
        ),
    };
    for p in cloud.positions.iter_mut().chain(cloud.normals.iter_mut()) {
        *p *= flip;
    }
    for q in &mut cloud.rotations {
        *q = turn * *q;
    }
    let signs = sh_signs(cloud.sh_degree, flip);
    let stride = cloud.sh_stride();
    if stride == 0 {
        return;
    }
    for coeffs in cloud.sh.chunks_exact_mut(stride) {
        for (k, sign) in signs.iter().enumerate() {
            for c in &mut coeffs[k * 3..k * 3 + 3] {
                *c *= sign;
            }
        }
    }
}

/// The sign each SH basis function takes when the direction's coordinates are multiplied
/// by `flip` (each real SH is a polynomial of one parity in each coordinate), read off the
/// basis at a direction where none of them vanishes.
fn sh_signs(degree: u32, flip: Vec3) -> Vec<f32> {
    let d = Vec3::new(0.31, 0.52, 0.79).normalize();
    let (a, b) = (basis(degree, d), basis(degree, d * flip));
    (0..super::sh_coeff_count(degree))
        .map(|k| (b[k] / a[k]).signum())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::splat::sh::eval;

    /// A half turn keeps every Gaussian's colour seen from the turned direction, and two
    /// half turns give back the cloud bit for bit.
    #[test]
    fn half_turns_turn_colours_and_undo_themselves() {
        let mut cloud = GaussianCloud {
            positions: vec![Vec3::new(1.0, 2.0, 3.0)],
            scales: vec![Vec3::new(0.1, 0.2, 0.3)],
            rotations: vec![Quat::from_xyzw(0.1, 0.2, 0.3, 0.9).normalize()],
            opacities: vec![0.5],
            sh_degree: 3,
            sh: (0..48).map(|i| (i as f32 * 0.37).sin()).collect(),
            ..Default::default()
        };
        let before = cloud.clone();
        for axis in [Axis::X, Axis::Y, Axis::Z] {
            let mut turned = before.clone();
            half_turn(&mut turned, axis);
            let q = match axis {
                Axis::X => Quat::from_rotation_x(std::f32::consts::PI),
                Axis::Y => Quat::from_rotation_y(std::f32::consts::PI),
                Axis::Z => Quat::from_rotation_z(std::f32::consts::PI),
            };
            assert!((turned.positions[0] - q * before.positions[0]).length() < 1e-5);
            let r = turned.rotations[0];
            assert!((r.dot(q * before.rotations[0])).abs() > 1.0 - 1e-6);
            let d = Vec3::new(0.2, -0.7, 0.4).normalize();
            let seen = eval(3, &turned.sh, q * d);
            let was = eval(3, &before.sh, d);
            assert!((seen - was).length() < 1e-5, "{axis:?}: {seen} vs {was}");
            half_turn(&mut turned, axis);
            // The quaternion comes back as itself or its negative (the same rotation).
            let back = turned.rotations[0];
            assert!(back == before.rotations[0] || back == -before.rotations[0]);
            turned.rotations[0] = before.rotations[0];
            assert_eq!(turned, before);
        }
        cloud.sh_degree = 0;
        cloud.sh.truncate(3);
        half_turn(&mut cloud, Axis::Z);
        assert_eq!(cloud.sh, before.sh[..3]);
    }
}
