//! GPU data layouts of the renderer, defined once: each struct mirrors the WGSL struct of
//! the same name in `shaders/common.wgsl` (or the pass's own file); `tests::layouts_match_wgsl`
//! checks sizes and member offsets against naga's layout of the shader.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::render::{Camera, Splats};

/// `GaussianIn`: one Gaussian as uploaded (64 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct GaussianIn {
    pub mean_opacity: [f32; 4],
    pub cov_a: [f32; 4],
    pub cov_b: [f32; 4],
    pub rotation: [f32; 4],
}

/// `Projected`: a Gaussian on screen (48 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Projected {
    pub xy_opacity: [f32; 4],
    pub conic: [f32; 4],
    pub color: [f32; 4],
}

/// `Frame`: per-frame constants.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Frame {
    pub view_row0: [f32; 4],
    pub view_row1: [f32; 4],
    pub view_row2: [f32; 4],
    pub camera_near: [f32; 4],
    pub focal_principal: [f32; 4],
    pub background: [f32; 4],
    pub lim_x: f32,
    pub lim_y: f32,
    pub width: u32,
    pub height: u32,
    pub tiles_x: u32,
    pub tiles_y: u32,
    pub num_gaussians: u32,
    pub sh_degree: u32,
    pub key_capacity: u32,
    /// log₂ of the records per page of the per-Gaussian arrays (`gpu::pages`).
    pub page_shift: u32,
    pub _pad: [u32; 2],
}

/// `Stats`: counters read back with every frame.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq, Eq)]
pub struct Stats {
    pub skipped_nonfinite: u32,
    pub skipped_degenerate: u32,
    pub visible: u32,
    pub intersections: u32,
}

pub const TILE: u32 = 16;

/// Words of f16-packed SH per Gaussian (48 halves: degree 3, padded).
pub const SH_WORDS: usize = 24;

/// The 3DGS clamp of the projected mean used in the Jacobian: 1.3 × tan(half fov).
pub const FOV_CLAMP: f32 = 1.3;

impl Frame {
    pub fn new(
        camera: &Camera,
        background: Vec3,
        num_gaussians: u32,
        sh_degree: u32,
        key_capacity: u32,
    ) -> Frame {
        let w = camera.world_to_camera();
        let row = |i: usize| {
            let r = w.row(i);
            [r.x, r.y, r.z, 0.0]
        };
        let (tan_x, tan_y) = camera.tan_half_fov();
        let (cx, cy) = camera.principal_point();
        Frame {
            view_row0: row(0),
            view_row1: row(1),
            view_row2: row(2),
            camera_near: [
                camera.position.x,
                camera.position.y,
                camera.position.z,
                camera.near,
            ],
            focal_principal: [camera.fx, camera.fy, cx, cy],
            background: [background.x, background.y, background.z, 0.0],
            lim_x: FOV_CLAMP * tan_x,
            lim_y: FOV_CLAMP * tan_y,
            width: camera.width,
            height: camera.height,
            tiles_x: camera.width.div_ceil(TILE),
            tiles_y: camera.height.div_ceil(TILE),
            num_gaussians,
            sh_degree,
            key_capacity,
            page_shift: 31,
            _pad: [0; 2],
        }
    }
}

/// Pack `Splats` into the upload layout: Gaussians and f16 SH words (degree padded to 3).
pub fn pack_splats(splats: &Splats) -> (Vec<GaussianIn>, Vec<u32>) {
    let gaussians = (0..splats.len())
        .map(|i| {
            let m = splats.means[i];
            let c = splats.covariances[i];
            let q = splats.rotations[i];
            GaussianIn {
                mean_opacity: [m.x, m.y, m.z, splats.opacities[i]],
                cov_a: [c[0], c[1], c[2], c[3]],
                cov_b: [c[4], c[5], 0.0, 0.0],
                rotation: [q.x, q.y, q.z, q.w],
            }
        })
        .collect();
    let stride = splats.sh_stride();
    let mut words = vec![0u32; splats.len() * SH_WORDS];
    for i in 0..splats.len() {
        let sh = &splats.sh[i * stride..(i + 1) * stride];
        for (h, v) in sh.iter().enumerate() {
            let bits = u32::from(half::f16::from_f32(*v).to_bits());
            words[i * SH_WORDS + h / 2] |= bits << (16 * (h % 2));
        }
    }
    (gaussians, words)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::layout_check::assert_layout;

    #[test]
    fn layouts_match_wgsl() {
        let common = super::super::COMMON.text;
        assert_layout!(
            &common,
            GaussianIn,
            "GaussianIn",
            [mean_opacity, cov_a, cov_b, rotation]
        );
        assert_layout!(&common, Projected, "Projected", [xy_opacity, conic, color]);
        assert_layout!(
            &common,
            Frame,
            "Frame",
            [
                view_row0,
                view_row1,
                view_row2,
                camera_near,
                focal_principal,
                background,
                lim_x,
                lim_y,
                width,
                height,
                tiles_x,
                tiles_y,
                num_gaussians,
                sh_degree,
                key_capacity,
                page_shift
            ]
        );
        assert_layout!(
            &common,
            Stats,
            "Stats",
            [
                skipped_nonfinite,
                skipped_degenerate,
                visible,
                intersections
            ]
        );
    }
}
