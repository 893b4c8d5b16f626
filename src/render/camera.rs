//! The pinhole camera every renderer in splatter uses (docs/method.md §7).
//!
//! Conventions (the INRIA 3DGS / OpenCV ones):
//! - camera axes: x right, y down, z forward (the camera looks along +z);
//! - `rotation` is camera-to-world, so a world point x maps to camera space as
//!   `rotation.transpose() * (x - position)`;
//! - pixel (i, j) covers [i, i+1) × [j, j+1) and is sampled at its centre (i + 0.5, j + 0.5);
//! - the principal point is the image centre (width / 2, height / 2);
//! - a camera-space point (x, y, z) projects to (fx·x/z + cx, fy·y/z + cy).

use glam::{Mat3, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Camera centre in world space.
    pub position: Vec3,
    /// Camera-to-world rotation (columns: camera x, y, z axes in world space).
    pub rotation: Mat3,
    /// Focal lengths in pixels.
    pub fx: f32,
    pub fy: f32,
    pub width: u32,
    pub height: u32,
    /// Gaussians whose centre is closer than this (camera z) are culled.
    pub near: f32,
}

impl Camera {
    /// A camera at `position` looking at `target`, with `up` the world's up direction.
    /// `fov_y` is the vertical field of view in radians.
    pub fn look_at(
        position: Vec3,
        target: Vec3,
        up: Vec3,
        fov_y: f32,
        width: u32,
        height: u32,
    ) -> Camera {
        let fy = focal_from_fov(fov_y, height);
        Camera {
            position,
            rotation: look_at_rotation(position, target, up),
            fx: fy,
            fy,
            width,
            height,
            near: DEFAULT_NEAR,
        }
    }

    /// World-to-camera rotation.
    pub fn world_to_camera(&self) -> Mat3 {
        self.rotation.transpose()
    }

    pub fn principal_point(&self) -> (f32, f32) {
        (self.width as f32 * 0.5, self.height as f32 * 0.5)
    }

    /// tan of half the horizontal and vertical fields of view.
    pub fn tan_half_fov(&self) -> (f32, f32) {
        (
            self.width as f32 * 0.5 / self.fx,
            self.height as f32 * 0.5 / self.fy,
        )
    }
}

pub const DEFAULT_NEAR: f32 = 0.01;

/// Focal length in pixels for a field of view (radians) across `pixels`.
pub fn focal_from_fov(fov: f32, pixels: u32) -> f32 {
    pixels as f32 * 0.5 / (fov * 0.5).tan()
}

/// Camera-to-world rotation (OpenCV axes) of a camera at `eye` looking at `target`.
/// Falls back to another reference axis when `up` is parallel to the view direction.
pub fn look_at_rotation(eye: Vec3, target: Vec3, up: Vec3) -> Mat3 {
    let z = (target - eye).normalize_or(Vec3::Z);
    let mut x = z.cross(up);
    if x.length_squared() < 1e-12 {
        x = z.any_orthonormal_vector();
    }
    let x = x.normalize();
    let y = z.cross(x);
    Mat3::from_cols(x, y, z)
}
