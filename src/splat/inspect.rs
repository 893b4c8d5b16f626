//! What a capture holds, for a user about to simulate it (docs/captures.md): robust bounds
//! next to the full ones, the floaters, opacity and scale statistics, the up axis, the
//! support under the object and the transform that stands it upright on a chosen height.
//!
//! Captures come in whatever frame their reconstruction chose (COLMAP's is y-down, many
//! are y-up, none is guaranteed z-up), so the up axis is estimated, from the first of these
//! that decides:
//! 0. **The capture's cameras**, when they are known: people film with the camera upright,
//!    so the mean of the cameras' up vectors is the world's up (nerfstudio's
//!    `auto_orient_and_center_poses`, method `up`). Each camera's pitch tilts its up towards
//!    or away from the object; round an object those tilts cancel in the mean.
//! 1. **A support plane**: the dominant plane of the robust core (RANSAC), when it holds a
//!    good share of the Gaussians and nearly all others lie on one side of it (a table or
//!    floor under the object). Up is its normal, towards the object.
//! 2. **A seen top**: otherwise, along each of the six axis directions, the share of
//!    Gaussians in the highest 5% of the height range minus the share in the lowest 5%.
//!    Cameras circle an object from above, so its top is seen from every view and densely
//!    reconstructed while the side it stood on was never seen: the direction with the
//!    clearly largest difference is up.
//! 3. **The camera convention**: when none decides, −y (COLMAP's and OpenCV's frames
//!    point y down the image, so the first camera's −y is the world's up). This is a guess,
//!    wrong for every capture written y-up, and [`Inspection::guess_warning`] says so.
//!
//! A format that defines its up axis (glTF: +y) decides it instead of all of these; when
//! the capture's own evidence points elsewhere (a file converted without turning it into
//! glTF's frame), the report and a warning say so.
//!
//! Each can be wrong for a given capture (cameras held sideways, an object photographed
//! from below, a capture whose densest layer is its base); the report prints the evidence
//! and the preview shows the result, and a scene can name the axis instead (`"up": "+z"`).

use glam::{Mat3, Vec3};

use super::codec::DeclaredUp;
use super::GaussianCloud;
use crate::rng::SplitMix64;

/// Percentiles of one quantity.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Spread {
    pub p1: f32,
    pub median: f32,
    pub p99: f32,
}

impl Spread {
    fn of(mut v: Vec<f32>) -> Spread {
        if v.is_empty() {
            return Spread::default();
        }
        v.sort_by(f32::total_cmp);
        let at = |q: f32| v[((v.len() - 1) as f32 * q).round() as usize];
        Spread {
            p1: at(0.01),
            median: at(0.5),
            p99: at(0.99),
        }
    }
}

/// How the up axis was decided.
#[derive(Clone, Debug, PartialEq)]
pub enum UpEvidence {
    /// The mean up of `count` cameras, whose ups spread `spread_deg` (RMS) about it.
    Cameras { count: usize, spread_deg: f32 },
    /// The normal of a support plane holding `share` of the core's Gaussians.
    SupportPlane { share: f32 },
    /// A seen top: (share in the highest 5%) − (share in the lowest 5%) along up, and the
    /// next best direction's score.
    SeenTop { score: f32, runner_up: f32 },
    /// None decided; the camera convention's −y, a guess.
    Convention,
    /// The file's format defines it (`source` says how). `against` is the up the capture's
    /// own evidence points to when that differs, and which evidence it is.
    Declared {
        source: &'static str,
        against: Option<(Vec3, &'static str)>,
    },
}

/// What a capture's cameras say about up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CamerasUp {
    /// The mean of the cameras' up vectors, normalised.
    pub up: Vec3,
    pub count: usize,
    /// The length of that mean before normalising: 1 when every camera's up is the same, 0
    /// when they cancel (cameras rolled every way, or all looking straight down).
    pub agreement: f32,
    /// The RMS angle between each camera's up and their mean, in degrees.
    pub spread_deg: f32,
}

/// The least [`CamerasUp::agreement`] with which the cameras decide: an orbit pitched
/// 70° down on average still reaches it, cameras held every which way do not.
pub const CAMERAS_AGREEMENT: f32 = 0.3;

/// How far the best seen-top score must lead the next direction's for it to decide up.
/// Measured on real captures (docs/captures.md, "The up axis"): a guitar on a wall hanger
/// had a wrong direction lead by 0.026 and the donut capture its true up by 0.045; the
/// plant's leader (wrong) by 0.002. Turning a capture by 90° or flipping it permutes its
/// six scores, so these margins hold for every axis-aligned orientation. Below the margin
/// the camera convention's guess, with its warning, is the answer.
pub const SEEN_TOP_MARGIN: f32 = 0.04;

/// The cameras' up from their camera-to-world rotations (OpenCV axes: x right, y down the
/// image, z forward, so a camera's up in the world is −y, the negated second column).
/// None without cameras, or when their ups cancel exactly.
pub fn cameras_up(camera_to_world: &[Mat3]) -> Option<CamerasUp> {
    let ups: Vec<Vec3> = camera_to_world
        .iter()
        .filter_map(|r| (-r.y_axis).try_normalize())
        .collect();
    let sum: Vec3 = ups.iter().sum();
    let up = sum.try_normalize()?;
    let mean_square = ups
        .iter()
        .map(|u| u.dot(up).clamp(-1.0, 1.0).acos().powi(2))
        .sum::<f32>()
        / ups.len() as f32;
    Some(CamerasUp {
        up,
        count: ups.len(),
        agreement: sum.length() / ups.len() as f32,
        spread_deg: mean_square.sqrt().to_degrees(),
    })
}

#[derive(Clone, Debug, PartialEq)]
pub struct Inspection {
    pub count: usize,
    pub sh_degree: u32,
    pub bounds: (Vec3, Vec3),
    /// Per-axis 1st–99th percentiles of the means.
    pub robust: (Vec3, Vec3),
    /// Gaussians outside the robust box grown by a quarter of its size on every side.
    pub floaters: usize,
    pub opacity: Spread,
    /// The largest standard deviation of each Gaussian.
    pub scale: Spread,
    /// The estimated up direction (a unit vector; an axis when it is within 10° of one).
    pub up: Vec3,
    pub evidence: UpEvidence,
    /// What the capture's cameras said, when they were given (whether or not they decided).
    pub cameras: Option<CamerasUp>,
    /// The seen-top score of each signed axis: +x, −x, +y, −y, +z, −z.
    pub axis_scores: [f32; 6],
    /// The support's height along `up`: the plane's, or the 1st percentile of the core's
    /// heights (the lowest dense layer).
    pub support: f32,
    /// Each region label the Gaussians carry (a capture's segment ids, from its integer
    /// vertex property `label` or `segment`) and how many carry it, in label order.
    pub labels: Vec<(String, usize)>,
}

/// Names of the signed axes, in the order of [`Inspection::axis_scores`].
pub const AXES: [&str; 6] = ["+x", "-x", "+y", "-y", "+z", "-z"];

/// The unit vector of a signed axis name (`"+x"`, `"-y"`, `"z"`, …).
pub fn axis_vector(name: &str) -> Option<Vec3> {
    let (sign, axis) = match name.as_bytes() {
        [b'-', a] => (-1.0, *a),
        [b'+', a] | [a] => (1.0, *a),
        _ => return None,
    };
    let v = match axis {
        b'x' => Vec3::X,
        b'y' => Vec3::Y,
        b'z' => Vec3::Z,
        _ => return None,
    };
    Some(sign * v)
}

/// The name of `v` when it is a signed axis.
pub fn axis_name(v: Vec3) -> Option<&'static str> {
    AXES.iter()
        .copied()
        .find(|n| axis_vector(n).is_some_and(|a| a.distance(v) < 1e-5))
}

/// The rotation that turns `up` into +z: a quarter or half turn about a world axis when
/// `up` is a signed axis, else the shortest rotation.
pub fn upright_rotation(up: Vec3) -> Mat3 {
    let up = up.try_normalize().unwrap_or(Vec3::Z);
    if up.distance(-Vec3::Z) < 1e-6 {
        return Mat3::from_rotation_x(std::f32::consts::PI);
    }
    Mat3::from_quat(glam::Quat::from_rotation_arc(up, Vec3::Z))
}

/// [`inspect_with_cameras`] without cameras.
pub fn inspect(cloud: &GaussianCloud) -> Inspection {
    inspect_with_cameras(cloud, None)
}

/// Inspect a capture whose cameras said `cameras` about its up (see [`cameras_up`]).
pub fn inspect_with_cameras(cloud: &GaussianCloud, cameras: Option<CamerasUp>) -> Inspection {
    inspect_declared(cloud, cameras, None)
}

/// Inspect a capture whose format may define its up (`declared`, from the reader).
pub fn inspect_declared(
    cloud: &GaussianCloud,
    cameras: Option<CamerasUp>,
    declared: Option<DeclaredUp>,
) -> Inspection {
    let n = cloud.len();
    let bounds = cloud.bounds().unwrap_or((Vec3::ZERO, Vec3::ZERO));
    let robust = robust_bounds(&cloud.positions);
    let size = robust.1 - robust.0;
    let (grow_lo, grow_hi) = (robust.0 - 0.25 * size, robust.1 + 0.25 * size);
    let floaters = cloud
        .positions
        .iter()
        .filter(|p| p.cmplt(grow_lo).any() || p.cmpgt(grow_hi).any())
        .count();
    let core: Vec<Vec3> = (0..n)
        .filter(|&i| {
            let p = cloud.positions[i];
            cloud.opacities[i] >= 0.1 && p.cmpge(robust.0).all() && p.cmple(robust.1).all()
        })
        .map(|i| cloud.positions[i])
        .collect();
    let axis_scores = AXES.map(|a| seen_top_score(&core, axis_vector(a).unwrap_or(Vec3::Z)));
    let plane = support_plane(&core, size.length());
    let (up, evidence) = estimate_up(cameras, plane, &axis_scores);
    let (up, evidence) = match declared.and_then(|d| Some((axis_vector(d.axis)?, d.source))) {
        Some((axis, source)) => (axis, declared_evidence(axis, source, up, &evidence)),
        None => (up, evidence),
    };
    let mut heights: Vec<f32> = core.iter().map(|p| p.dot(up)).collect();
    heights.sort_by(f32::total_cmp);
    let support = match (&evidence, heights.is_empty()) {
        (_, true) => 0.0,
        (UpEvidence::SupportPlane { .. }, _) => plane
            .map_or(heights[heights.len() / 100], |(normal, offset, _)| {
                offset * normal.dot(up).signum()
            }),
        _ => heights[(heights.len() - 1) / 100],
    };
    Inspection {
        count: n,
        sh_degree: cloud.sh_degree,
        bounds,
        robust,
        floaters,
        opacity: Spread::of(cloud.opacities.clone()),
        scale: Spread::of(cloud.scales.iter().map(|s| s.max_element()).collect()),
        up,
        evidence,
        cameras,
        axis_scores,
        support,
        labels: label_counts(cloud),
    }
}

/// How many Gaussians carry each label, in label order (labels no Gaussian carries left out).
fn label_counts(cloud: &GaussianCloud) -> Vec<(String, usize)> {
    let mut counts = vec![0usize; cloud.label_names.len()];
    for &l in &cloud.labels {
        if let Some(c) = counts.get_mut(usize::from(l)) {
            *c += 1;
        }
    }
    cloud
        .label_names
        .iter()
        .zip(counts)
        .filter(|&(_, c)| c > 0)
        .map(|(name, c)| (name.clone(), c))
        .collect()
}

impl Inspection {
    /// The transform (up rotation, then this translation) that stands the capture upright
    /// with its support at height `support_height` and its robust centre over the origin.
    pub fn placement(&self, support_height: f32) -> Vec3 {
        let r = upright_rotation(self.up);
        let centre = r * (0.5 * (self.robust.0 + self.robust.1));
        Vec3::new(-centre.x, -centre.y, support_height - self.support)
    }

    /// The robust bounds after [`upright_rotation`] (the box of the eight rotated corners).
    pub fn upright_robust_bounds(&self) -> (Vec3, Vec3) {
        rotated_box(upright_rotation(self.up), self.robust)
    }

    /// Up is the convention's guess: no evidence decided it.
    pub fn is_guess(&self) -> bool {
        self.evidence == UpEvidence::Convention
    }

    /// What kept the evidence from deciding, in words.
    fn undecided(&self) -> String {
        let cameras = match &self.cameras {
            None => "no cameras".to_string(),
            Some(c) => format!(
                "{} cameras whose ups disagree (agreement {:.2} < {CAMERAS_AGREEMENT})",
                c.count, c.agreement
            ),
        };
        let mut order: Vec<usize> = (0..6).collect();
        order.sort_by(|&a, &b| self.axis_scores[b].total_cmp(&self.axis_scores[a]));
        let lead = self.axis_scores[order[0]] - self.axis_scores[order[1]];
        format!(
            "{cameras}, no support plane, and the seen top leads with {} by {lead:.3}, under the {SEEN_TOP_MARGIN} a decision needs",
            AXES[order[0]]
        )
    }

    /// One line for a capture (`name`) whose up is a guess, naming the ways to decide it.
    pub fn guess_warning(&self, name: &str) -> Option<String> {
        self.is_guess().then(|| {
            format!(
                "{name}: up {} is a guess ({}; the camera convention's -y): if it stands on its head, \
                 say which way is up with `render --ply FILE --up AXIS`, `\"up\": \"+y\"` (or another axis) \
                 in a scene, or the capture's cameras (`--cameras cameras.json`, or a cameras.json next to the capture)",
                self.up_name(),
                self.undecided()
            )
        })
    }

    /// One line when the format's up and the capture's evidence disagree.
    pub fn declared_warning(&self, name: &str) -> Option<String> {
        let UpEvidence::Declared {
            against: Some((other, kind)),
            ..
        } = self.evidence
        else {
            return None;
        };
        let other = axis_name(other).map_or_else(|| format!("{other:?}"), str::to_string);
        Some(format!(
            "{name}: up {} is the file format's, but {kind} points to {other}: if it lies on its side, \
             its writer did not turn it into the format's frame; say which way is up with \
             `render --ply FILE --up {other}` or `\"up\": \"{other}\"` in a scene",
            self.up_name()
        ))
    }

    /// The up found and how: `"-y", from the mean up of 24 cameras, …`.
    pub fn up_text(&self) -> String {
        format!("{}, from {}", self.up_name(), self.evidence_text())
    }

    /// `"+y"` for an axis, else the vector.
    fn up_name(&self) -> String {
        axis_name(self.up).map_or_else(
            || format!("[{:.4}, {:.4}, {:.4}]", self.up.x, self.up.y, self.up.z),
            |a| format!("\"{a}\""),
        )
    }

    /// How up was decided, in words.
    fn evidence_text(&self) -> String {
        match &self.evidence {
            UpEvidence::Cameras { count, spread_deg } => {
                let off = self
                    .cameras
                    .map_or(0.0, |c| c.up.angle_between(self.up).to_degrees());
                let snapped = if off > 0.05 {
                    format!(" {off:.1}° off the axis,")
                } else {
                    String::new()
                };
                format!(
                    "the mean up of {count} cameras,{snapped} whose ups spread {spread_deg:.1}° (RMS) about it"
                )
            }
            UpEvidence::SupportPlane { share } => format!(
                "the normal of a support plane holding {:.0}% of the core",
                100.0 * share
            ),
            UpEvidence::SeenTop { score, runner_up } => format!(
                "a seen top: {:+.3} (next best direction {:+.3})",
                score, runner_up
            ),
            UpEvidence::Convention => {
                format!("the camera convention's -y, a guess ({})", self.undecided())
            }
            UpEvidence::Declared { source, against } => match against {
                None => source.to_string(),
                Some((v, kind)) => format!(
                    "{source}; {kind} points to {}",
                    axis_name(*v).map_or_else(|| format!("{v:?}"), |a| format!("\"{a}\""))
                ),
            },
        }
    }
}

/// The axis-aligned box of `m` applied to the corners of `b`.
pub fn rotated_box(m: Mat3, b: (Vec3, Vec3)) -> (Vec3, Vec3) {
    let mut lo = Vec3::INFINITY;
    let mut hi = Vec3::NEG_INFINITY;
    for c in 0..8 {
        let p = Vec3::new(
            if c & 1 == 0 { b.0.x } else { b.1.x },
            if c & 2 == 0 { b.0.y } else { b.1.y },
            if c & 4 == 0 { b.0.z } else { b.1.z },
        );
        lo = lo.min(m * p);
        hi = hi.max(m * p);
    }
    (lo, hi)
}

/// Per-axis 1st and 99th percentiles of finite positions.
pub fn robust_bounds(positions: &[Vec3]) -> (Vec3, Vec3) {
    let mut lo = Vec3::ZERO;
    let mut hi = Vec3::ZERO;
    for a in 0..3 {
        let mut v: Vec<f32> = positions
            .iter()
            .map(|p| p[a])
            .filter(|x| x.is_finite())
            .collect();
        if v.is_empty() {
            continue;
        }
        v.sort_by(f32::total_cmp);
        let at = |q: f32| v[((v.len() - 1) as f32 * q).round() as usize];
        lo[a] = at(0.01);
        hi[a] = at(0.99);
    }
    (lo, hi)
}

/// (share of the heights in the highest 5% of their range) − (share in the lowest 5%).
fn seen_top_score(core: &[Vec3], up: Vec3) -> f32 {
    if core.is_empty() {
        return 0.0;
    }
    let (lo, hi) = core
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), p| {
            let z = p.dot(up);
            (l.min(z), h.max(z))
        });
    let band = 0.05 * (hi - lo);
    let bottom = core.iter().filter(|p| p.dot(up) <= lo + band).count();
    let top = core.iter().filter(|p| p.dot(up) >= hi - band).count();
    (top as f32 - bottom as f32) / core.len() as f32
}

/// Up from the cameras when they agree, else from a support plane (as [`support_plane`]
/// found it), else from a seen top, else the convention.
fn estimate_up(
    cameras: Option<CamerasUp>,
    plane: Option<(Vec3, f32, f32)>,
    scores: &[f32; 6],
) -> (Vec3, UpEvidence) {
    if let Some(c) = cameras.filter(|c| c.agreement >= CAMERAS_AGREEMENT) {
        return (
            snap_to_axis(c.up),
            UpEvidence::Cameras {
                count: c.count,
                spread_deg: c.spread_deg,
            },
        );
    }
    if let Some((normal, _, share)) = plane {
        return (snap_to_axis(normal), UpEvidence::SupportPlane { share });
    }
    let mut order: Vec<usize> = (0..6).collect();
    order.sort_by(|&a, &b| scores[b].total_cmp(&scores[a]));
    let (best, next) = (order[0], order[1]);
    // A top layer that stands out from the other directions' by the measured margin, and
    // holds at least 2% more than the bottom layer.
    if scores[best] >= 0.02 && scores[best] - scores[next] >= SEEN_TOP_MARGIN {
        return (
            axis_vector(AXES[best]).unwrap_or(Vec3::Z),
            UpEvidence::SeenTop {
                score: scores[best],
                runner_up: scores[next],
            },
        );
    }
    (-Vec3::Y, UpEvidence::Convention)
}

/// The format's up, with the evidence's up when that is decisive and points elsewhere.
fn declared_evidence(
    axis: Vec3,
    source: &'static str,
    estimate: Vec3,
    evidence: &UpEvidence,
) -> UpEvidence {
    let kind = match evidence {
        UpEvidence::Cameras { .. } => Some("the capture's cameras"),
        UpEvidence::SupportPlane { .. } => Some("a support plane"),
        UpEvidence::SeenTop { .. } => Some("a seen top"),
        _ => None,
    };
    UpEvidence::Declared {
        source,
        against: kind
            .filter(|_| estimate.distance(axis) > 1e-3)
            .map(|k| (estimate, k)),
    }
}

/// An axis when `v` is within 10° of one, else `v`.
fn snap_to_axis(v: Vec3) -> Vec3 {
    AXES.iter()
        .filter_map(|a| axis_vector(a))
        .find(|a| a.dot(v) > 10f32.to_radians().cos())
        .unwrap_or(v)
}

/// The dominant plane of the core by RANSAC (fixed seed: the same answer every run), as
/// (unit normal pointing to the side holding the other Gaussians, offset along it, share
/// of inliers), when it is a support: at least 15% of the core within 0.5% of the
/// diagonal of it, and at least 90% of the rest on one side.
fn support_plane(core: &[Vec3], diagonal: f32) -> Option<(Vec3, f32, f32)> {
    if core.len() < 100 {
        return None;
    }
    let tol = 0.005 * diagonal;
    let mut rng = SplitMix64::new(0x5eed_b1a7);
    let step = (core.len() / 4096).max(1);
    let sample: Vec<Vec3> = core.iter().step_by(step).copied().collect();
    let pick = |rng: &mut SplitMix64| sample[(rng.next_u64() % sample.len() as u64) as usize];
    let mut best: Option<(Vec3, f32, usize)> = None;
    for _ in 0..256 {
        let (a, b, c) = (pick(&mut rng), pick(&mut rng), pick(&mut rng));
        let Some(normal) = (b - a).cross(c - a).try_normalize() else {
            continue;
        };
        let offset = normal.dot(a);
        let inliers = sample
            .iter()
            .filter(|p| (p.dot(normal) - offset).abs() <= tol)
            .count();
        if best.is_none_or(|(_, _, k)| inliers > k) {
            best = Some((normal, offset, inliers));
        }
    }
    let (normal, offset, inliers) = best?;
    let share = inliers as f32 / sample.len() as f32;
    let (above, below) = sample.iter().fold((0usize, 0usize), |(a, b), p| {
        let d = p.dot(normal) - offset;
        if d > tol {
            (a + 1, b)
        } else if d < -tol {
            (a, b + 1)
        } else {
            (a, b)
        }
    });
    let rest = (above + below).max(1) as f32;
    if share < 0.15 || (above.max(below) as f32) < 0.9 * rest {
        return None;
    }
    Some(if above >= below {
        (normal, offset, share)
    } else {
        (-normal, -offset, share)
    })
}

mod report;

#[cfg(test)]
mod tests;
