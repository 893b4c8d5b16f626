//! `splatter inspect --preview`: the capture stood upright on z = 0 (the transform the
//! inspection suggests), over a ground grid of thin Gaussians with its lines labelled in
//! scene units, and the x (red), y (green) and z (blue) axes, from a three-quarter view
//! that frames the robust bounds. A user reads `select` boxes off it.

use std::path::Path;

use anyhow::{Context, Result};
use glam::{Mat3, Quat, Vec3};

use crate::gpu::GpuContext;
use crate::output::text::{draw_labels, Label};
use crate::render::{Camera, GpuRenderer, Splats};
use crate::scene::{CameraPath, CaptureUp};
use crate::splat::inspect::{upright_rotation, Inspection};
use crate::splat::GaussianCloud;

const WIDTH: u32 = 1280;
const HEIGHT: u32 = 720;
const BACKGROUND: Vec3 = Vec3::new(0.08, 0.08, 0.1);

/// Read and inspect a capture with its cameras (`cameras`, else a `cameras.json` next to
/// it): the cloud, what was found and the report `splatter inspect` prints (the suggested
/// transform for a support at `support_height`).
pub fn inspect_file(
    file: &Path,
    support_height: f32,
    cameras: Option<&Path>,
) -> Result<(GaussianCloud, CaptureUp, String)> {
    let (cloud, read) = crate::splat::formats::read_splats(file)?;
    // Only a named cameras file can fail.
    let found =
        crate::scene::inspect_capture(&cloud, file, cameras, read.up).with_context(|| {
            cameras.map_or_else(String::new, |c| format!("--cameras {}", c.display()))
        })?;
    let mut report = format!(
        "file:          {} ({} {})\n",
        file.display(),
        read.format,
        read.variant
    );
    if read.skipped_nonfinite + read.skipped_degenerate > 0 {
        report.push_str(&format!(
            "skipped:       {} with NaN/Inf values, {} with a degenerate scale or rotation\n",
            read.skipped_nonfinite, read.skipped_degenerate
        ));
    }
    if let Some(c) = found.cameras_text() {
        report.push_str(&format!("cameras:       {c}\n"));
    }
    report.push_str(&found.inspection.to_string());
    if support_height != 0.0 {
        let t = found.inspection.placement(support_height);
        report.push_str(&format!(
            "\n               with the support at z = {support_height}: translate [{:.4}, {:.4}, {:.4}]",
            t.x, t.y, t.z
        ));
    }
    Ok((cloud, found, report))
}

/// Render the preview of `cloud` to `png`.
pub fn write(
    gpu: &GpuContext,
    cloud: &GaussianCloud,
    found: &Inspection,
    png: &Path,
) -> Result<()> {
    let r = upright_rotation(found.up);
    let t = found.placement(0.0);
    let mut splats = Splats::from_cloud(cloud, r, t);
    let (lo, hi) = found.upright_robust_bounds();
    let (lo, hi) = (lo + t, hi + t);
    let grid = Grid::around(lo, hi);
    splats.append(grid.splats(splats.sh_degree, hi.z - lo.z));
    let camera = CameraPath::orbit_framing(
        (lo.min(grid.lo()), hi.max(grid.hi())),
        Vec3::Z,
        45.0,
        WIDTH,
        HEIGHT,
        8,
    )
    .camera(1);
    let mut renderer = GpuRenderer::new(gpu);
    renderer.upload(gpu, &splats)?;
    let mut image = renderer.render(gpu, &camera, BACKGROUND)?;
    let mut labels = grid.labels(&camera);
    if found.is_guess() {
        labels.push(Label {
            x: 16,
            y: 36,
            text: "up is a guess (the camera convention's -y): if the capture stands on its head, give its cameras or an axis"
                .into(),
            color: [255, 170, 60],
        });
    }
    draw_labels(&mut image.rgba, image.width, image.height, 16, &labels);
    crate::output::write_png(png, image.width, image.height, &image.rgba)?;
    Ok(())
}

/// A square grid on z = 0 with lines every `step`, from −`reach` to `reach` in x and y.
struct Grid {
    step: f32,
    reach: f32,
}

impl Grid {
    /// Lines a "nice" distance apart (1, 2 or 5 × 10ᵏ), four to ten across the footprint.
    fn around(lo: Vec3, hi: Vec3) -> Grid {
        let half =
            lo.x.abs()
                .max(hi.x.abs())
                .max(lo.y.abs())
                .max(hi.y.abs())
                .max(1e-6);
        let raw = half / 3.0;
        let k = 10f32.powf(raw.log10().floor());
        let step = [1.0, 2.0, 5.0, 10.0]
            .into_iter()
            .map(|m| m * k)
            .find(|s| *s >= raw)
            .unwrap_or(10.0 * k);
        Grid {
            step,
            reach: (half / step).ceil() * step,
        }
    }

    fn lo(&self) -> Vec3 {
        Vec3::new(-self.reach, -self.reach, 0.0)
    }

    fn hi(&self) -> Vec3 {
        Vec3::new(self.reach, self.reach, 0.0)
    }

    fn lines(&self) -> i32 {
        (self.reach / self.step).round() as i32
    }

    /// Thin elongated Gaussians along each line (grey; the x axis red, the y axis green),
    /// and the z axis (blue) up to `height`.
    fn splats(&self, degree: u32, height: f32) -> Splats {
        let thickness = self.reach * 0.002;
        let mut out = Splats {
            sh_degree: degree,
            ..Default::default()
        };
        let k = crate::splat::sh_coeff_count(degree) * 3;
        let mut segment = |from: Vec3, to: Vec3, color: [f32; 3]| {
            let pieces = 64;
            let d = (to - from) / pieces as f32;
            let axis = d.normalize_or_zero();
            let rot = Mat3::from_quat(Quat::from_rotation_arc(Vec3::X, axis));
            let s = Mat3::from_diagonal(Vec3::new(d.length() * 0.6, thickness, thickness));
            let cov = rot * s * s * rot.transpose();
            for i in 0..pieces {
                out.means.push(from + d * (i as f32 + 0.5));
                out.covariances.push(crate::splat::sym3_from_mat3(cov));
                out.rotations.push(Quat::IDENTITY);
                out.opacities.push(0.9);
                let mut sh = vec![0.0; k];
                for c in 0..3 {
                    sh[c] = (color[c] - 0.5) / crate::splat::codec::SH_C0;
                }
                out.sh.extend(sh);
            }
        };
        let n = self.lines();
        for i in -n..=n {
            let v = i as f32 * self.step;
            let (cx, cy) = if i == 0 {
                ([0.9, 0.2, 0.2], [0.2, 0.8, 0.2])
            } else {
                ([0.45; 3], [0.45; 3])
            };
            // A line of constant y (along x), and one of constant x (along y).
            segment(
                Vec3::new(-self.reach, v, 0.0),
                Vec3::new(self.reach, v, 0.0),
                cx,
            );
            segment(
                Vec3::new(v, -self.reach, 0.0),
                Vec3::new(v, self.reach, 0.0),
                cy,
            );
        }
        segment(
            Vec3::ZERO,
            Vec3::Z * height.max(self.step),
            [0.25, 0.4, 1.0],
        );
        out
    }

    /// The value of each line at its end nearest the camera, and the axis names.
    fn labels(&self, camera: &Camera) -> Vec<Label> {
        let mut out = Vec::new();
        let n = self.lines();
        // The grid edges facing the camera.
        let near_y = self.reach * camera.position.y.signum();
        let near_x = self.reach * camera.position.x.signum();
        let mut put = |p: Vec3, text: String, color: [u8; 3]| {
            if let Some((x, y)) = project(camera, p) {
                out.push(Label {
                    x: x as i32 + 4,
                    y: y as i32 - 8,
                    text,
                    color,
                });
            }
        };
        for i in -n..=n {
            let v = i as f32 * self.step;
            put(
                Vec3::new(v, near_y, 0.0),
                format!("x={}", trim(v)),
                [255, 200, 200],
            );
            put(
                Vec3::new(near_x, v, 0.0),
                format!("y={}", trim(v)),
                [200, 255, 200],
            );
        }
        out.push(Label {
            x: 16,
            y: 12,
            text: format!(
                "upright, support at z = 0; grid step {}; axes x red, y green, z blue",
                trim(self.step)
            ),
            color: [220, 220, 220],
        });
        out
    }
}

/// A number without trailing zeros.
fn trim(v: f32) -> String {
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.to_string()
    }
}

/// Pixel position of a world point, None behind the camera.
fn project(camera: &Camera, p: Vec3) -> Option<(f32, f32)> {
    let c = camera.world_to_camera() * (p - camera.position);
    if c.z <= camera.near {
        return None;
    }
    let (cx, cy) = camera.principal_point();
    Some((cx + camera.fx * c.x / c.z, cy + camera.fy * c.y / c.z))
}
