//! What the renderers draw: Gaussians in world space with a full 3D covariance and the
//! rotation of their rest frame (used to evaluate view-dependent SH colour).
//!
//! Static objects get their covariance from the object transform M (Σ = M A Mᵀ) and the
//! rotation of M's polar decomposition; simulated ones (later) from F (docs/method.md §6).

use glam::{Mat3, Quat, Vec3};

use crate::splat::{GaussianCloud, NO_LABEL};

pub use crate::splat::{mat3_from_sym3, sym3_from_mat3, Sym3};

#[derive(Clone, Debug, Default)]
pub struct Splats {
    pub means: Vec<Vec3>,
    pub covariances: Vec<Sym3>,
    /// Rest-frame rotation R_p: SH are evaluated along R_pᵀ · view direction.
    pub rotations: Vec<Quat>,
    pub opacities: Vec<f32>,
    pub sh_degree: u32,
    /// Coefficient-major per Gaussian, as in [`GaussianCloud::sh`].
    pub sh: Vec<f32>,
    /// Region label per Gaussian (an index into `label_names`, [`NO_LABEL`] for none), or
    /// empty when no Gaussian has one. Renderers ignore it; the simulation setup uses it to
    /// find an object's regions (see [`Splats::label_name`]).
    pub labels: Vec<u16>,
    /// Names of the label ids, shared by all objects: `append` merges them by name.
    pub label_names: Vec<String>,
}

impl Splats {
    pub fn len(&self) -> usize {
        self.means.len()
    }

    pub fn is_empty(&self) -> bool {
        self.means.is_empty()
    }

    pub fn sh_stride(&self) -> usize {
        crate::splat::sh_coeff_count(self.sh_degree) * 3
    }

    /// The cloud placed in the world by x ↦ M x + t: means M X + t, covariances M A Mᵀ, and
    /// rest frames rotated by the rotation of M's polar decomposition.
    pub fn from_cloud(cloud: &GaussianCloud, m: Mat3, t: Vec3) -> Splats {
        let r = polar_rotation(m);
        let n = cloud.len();
        Splats {
            means: cloud.positions.iter().map(|x| m * *x + t).collect(),
            covariances: (0..n)
                .map(|i| sym3_from_mat3(m * cloud.covariance(i) * m.transpose()))
                .collect(),
            rotations: cloud.rotations.iter().map(|_| r).collect(),
            opacities: cloud.opacities.clone(),
            sh_degree: cloud.sh_degree,
            sh: cloud.sh.clone(),
            labels: cloud.labels.clone(),
            label_names: cloud.label_names.clone(),
        }
    }

    /// The region name of Gaussian `i` (`None` when it has no label).
    pub fn label_name(&self, i: usize) -> Option<&str> {
        let l = *self.labels.get(i)?;
        self.label_names.get(usize::from(l)).map(String::as_str)
    }

    /// Append `other`'s labels, renumbered into this set's names (new names are added);
    /// the side without labels gets [`NO_LABEL`]. Call before the other arrays grow.
    fn append_labels(&mut self, other: &Splats) {
        if other.labels.is_empty() {
            if !self.labels.is_empty() {
                self.labels.resize(self.len() + other.len(), NO_LABEL);
            }
            return;
        }
        if self.labels.is_empty() {
            self.labels = vec![NO_LABEL; self.len()];
        }
        let map: Vec<u16> = other
            .label_names
            .iter()
            .map(
                |name| match self.label_names.iter().position(|n| n == name) {
                    Some(i) => i as u16,
                    None => {
                        self.label_names.push(name.clone());
                        (self.label_names.len() - 1) as u16
                    }
                },
            )
            .collect();
        self.labels.extend(
            other
                .labels
                .iter()
                .map(|&l| map.get(usize::from(l)).copied().unwrap_or(NO_LABEL)),
        );
    }

    /// Append another set, padding SH to the larger degree.
    pub fn append(&mut self, other: Splats) {
        let degree = self.sh_degree.max(other.sh_degree);
        if self.is_empty() {
            self.sh_degree = degree;
        }
        self.pad_sh_degree(degree);
        let mut other = other;
        other.pad_sh_degree(degree);
        self.append_labels(&other);
        self.means.extend(other.means);
        self.covariances.extend(other.covariances);
        self.rotations.extend(other.rotations);
        self.opacities.extend(other.opacities);
        self.sh.extend(other.sh);
    }

    pub fn pad_sh_degree(&mut self, degree: u32) {
        if degree <= self.sh_degree {
            return;
        }
        let old = self.sh_stride();
        let new = crate::splat::sh_coeff_count(degree) * 3;
        let mut sh = vec![0.0; self.len() * new];
        for i in 0..self.len() {
            sh[i * new..i * new + old].copy_from_slice(&self.sh[i * old..(i + 1) * old]);
        }
        self.sh = sh;
        self.sh_degree = degree;
    }
}

/// Rotation R of the polar decomposition M = R S (S symmetric positive semi-definite),
/// by the scaled Newton iteration R ← ½(R + R⁻ᵀ); falls back to the identity for a singular
/// M. A reflection (det M < 0) is returned as a rotation times −1 removed on one axis.
pub fn polar_rotation(m: Mat3) -> Quat {
    let det = m.determinant();
    if !det.is_finite() || det.abs() < 1e-20 {
        return Quat::IDENTITY;
    }
    let mut r = if det < 0.0 { -m } else { m };
    for _ in 0..30 {
        let next = 0.5 * (r + r.inverse().transpose());
        let diff = (next - r)
            .to_cols_array()
            .iter()
            .map(|v| v.abs())
            .fold(0.0f32, f32::max);
        r = next;
        if diff < 1e-7 {
            break;
        }
    }
    Quat::from_mat3(&r).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polar_of_rotation_times_stretch_is_the_rotation() {
        let q = Quat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0);
        let s = Mat3::from_diagonal(Vec3::new(2.0, 0.5, 1.3));
        let r = polar_rotation(Mat3::from_quat(q) * s);
        assert!(r.dot(q).abs() > 1.0 - 1e-5, "{r:?} vs {q:?}");
    }

    #[test]
    fn sym3_round_trips() {
        let m = Mat3::from_cols(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(2.0, 4.0, 5.0),
            Vec3::new(3.0, 5.0, 6.0),
        );
        assert_eq!(mat3_from_sym3(sym3_from_mat3(m)), m);
    }
}
