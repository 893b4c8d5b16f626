//! Gaussian clouds: the in-memory representation, PLY input/output, spherical harmonics,
//! and procedural objects (docs/method.md §1, §5).

pub mod antimatter;
pub mod assets;
pub mod codec;
pub mod compressed_ply;
pub mod convert;
pub mod formats;
pub mod gltf;
pub mod inspect;
pub mod ply;
pub mod procedural;
pub mod sh;
pub mod sog;
pub mod spz;

use glam::{Mat3, Quat, Vec3};

/// A set of 3D Gaussians, stored as a struct of arrays.
///
/// Everything is in *linear* (activated) form: `opacities` are in (0, 1] (the PLY's logit
/// has been through a sigmoid), `scales` are standard deviations (the PLY's log has been
/// through exp), `rotations` are unit quaternions. The rest covariance of Gaussian p is
/// A_p = R S Sᵀ Rᵀ with R = rotation, S = diag(scale) (docs/method.md §1).
///
/// Spherical-harmonic coefficients are stored coefficient-major per Gaussian:
/// `sh[p * K * 3 + k * 3 + c]` is coefficient k (0 = DC) of colour channel c, with
/// K = (degree + 1)². (The PLY file is channel-major for the rest coefficients; the
/// reader and writer convert.)
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GaussianCloud {
    pub positions: Vec<Vec3>,
    pub scales: Vec<Vec3>,
    pub rotations: Vec<Quat>,
    pub opacities: Vec<f32>,
    /// Degree of the spherical harmonics, 0..=3.
    pub sh_degree: u32,
    pub sh: Vec<f32>,
    /// Optional per-Gaussian normals (PLY `nx ny nz`); empty when absent.
    pub normals: Vec<Vec3>,
    /// Optional per-Gaussian region labels, indices into `label_names`; empty when absent.
    /// Procedural assets label their regions (`flesh`, `rind`, …); the PLY reader fills
    /// them from an integer vertex property `label` (or `segment`).
    pub labels: Vec<u16>,
    /// Name of each label id (`labels[i]` indexes this).
    pub label_names: Vec<String>,
}

/// Label id of a Gaussian that has none, where labelled and unlabelled sets are merged
/// (`render::Splats::append`).
pub const NO_LABEL: u16 = u16::MAX;

/// Number of SH coefficients per colour channel for a degree.
pub const fn sh_coeff_count(degree: u32) -> usize {
    ((degree + 1) * (degree + 1)) as usize
}

impl GaussianCloud {
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Coefficients per Gaussian (all three channels).
    pub fn sh_stride(&self) -> usize {
        sh_coeff_count(self.sh_degree) * 3
    }

    /// The SH coefficients of Gaussian `i`, coefficient-major (`[k * 3 + c]`).
    pub fn sh_of(&self, i: usize) -> &[f32] {
        let s = self.sh_stride();
        &self.sh[i * s..(i + 1) * s]
    }

    /// Rest covariance A = R S Sᵀ Rᵀ of Gaussian `i`.
    pub fn covariance(&self, i: usize) -> Mat3 {
        let r = Mat3::from_quat(self.rotations[i]);
        let s = Mat3::from_diagonal(self.scales[i]);
        let m = r * s;
        m * m.transpose()
    }

    /// Axis-aligned bounds of the means, `None` when empty.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p))),
        )
    }

    /// Check the struct-of-arrays invariants (equal lengths, SH length, degree range).
    pub fn check_consistent(&self) -> Result<(), String> {
        let n = self.len();
        if self.sh_degree > 3 {
            return Err(format!("SH degree {} is above 3", self.sh_degree));
        }
        for (name, len) in [
            ("scales", self.scales.len()),
            ("rotations", self.rotations.len()),
            ("opacities", self.opacities.len()),
        ] {
            if len != n {
                return Err(format!("{name} has {len} entries for {n} Gaussians"));
            }
        }
        if self.sh.len() != n * self.sh_stride() {
            return Err(format!(
                "sh has {} values, expected {}",
                self.sh.len(),
                n * self.sh_stride()
            ));
        }
        if !self.normals.is_empty() && self.normals.len() != n {
            return Err(format!(
                "normals has {} entries for {n} Gaussians",
                self.normals.len()
            ));
        }
        if !self.labels.is_empty() && self.labels.len() != n {
            return Err(format!(
                "labels has {} entries for {n} Gaussians",
                self.labels.len()
            ));
        }
        if self.label_names.len() >= usize::from(NO_LABEL) {
            return Err(format!(
                "{} label names, at most {} allowed",
                self.label_names.len(),
                NO_LABEL - 1
            ));
        }
        if let Some(l) = self
            .labels
            .iter()
            .find(|&&l| usize::from(l) >= self.label_names.len())
        {
            return Err(format!(
                "label {l} has no name ({} label names)",
                self.label_names.len()
            ));
        }
        Ok(())
    }

    /// The region name of Gaussian `i`, `None` when the cloud has no labels.
    pub fn label_name(&self, i: usize) -> Option<&str> {
        let l = *self.labels.get(i)?;
        self.label_names.get(usize::from(l)).map(String::as_str)
    }

    /// The id of the label called `name`, if the cloud has it.
    pub fn label_id(&self, name: &str) -> Option<u16> {
        self.label_names
            .iter()
            .position(|n| n == name)
            .map(|i| i as u16)
    }
}

/// Upper triangle of a symmetric 3×3 matrix: xx, xy, xz, yy, yz, zz.
pub type Sym3 = [f32; 6];

pub fn sym3_from_mat3(m: Mat3) -> Sym3 {
    [
        m.x_axis.x, m.y_axis.x, m.z_axis.x, m.y_axis.y, m.z_axis.y, m.z_axis.z,
    ]
}

pub fn mat3_from_sym3(s: Sym3) -> Mat3 {
    Mat3::from_cols(
        Vec3::new(s[0], s[1], s[2]),
        Vec3::new(s[1], s[3], s[4]),
        Vec3::new(s[2], s[4], s[5]),
    )
}
