//! Moving kinematic colliders (docs/method.md §2, grid update): rigid solids with a prescribed path —
//! a knife, a projectile — that push, cut and carry the material.
//!
//! A collider is a shape in its own frame ([`ColliderShape`]: sphere, box, or cylinder
//! along z; signed distance d, outward normal) moved by a [`RigidMotion`]: keyframed
//! position on the scene's C¹ Hermite spline (`spline::KeyedPoint`, as lights and
//! cameras) and Euler angles `rotate_deg` interpolated linearly, the same convention as an
//! object's transform (R = Rz · Ry · Rx). Velocities are the path's analytic derivatives.
//!
//! At time t every grid node x with d(x) ≤ margin gets the collider's condition in the
//! collider's frame: the rigid velocity there is v_c = v_lin + ω × (x − c), and
//! v ← v_c + apply(v − v_c, n) — sticky gives v = v_c; slip removes the normal relative
//! component, separate only when approaching; Coulomb friction on the relative tangential
//! part (`boundary::Condition::apply`). Kinematic colliders apply after the planar colliders and
//! before the domain walls. A substep uses the pose at its start time.
//!
//! The CPU step ([`super::cpu::step_at`]) evaluates the pose every step; the GPU step gets
//! the pose of every substep of a call uploaded at once and copied into its constants
//! between substeps (`super::gpu::GpuSim::step`), so nothing is read back within a frame.

use glam::{DMat3, DVec3, Vec3};

use super::boundary::Condition;
use crate::spline::KeyedPoint;

/// The solid, centred on `centre` in the collider's frame (the object frame, scaled).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ColliderShape {
    Sphere {
        radius: f64,
    },
    /// Half extents per axis.
    Box {
        half: DVec3,
    },
    /// Axis along z, from −half_height to +half_height.
    Cylinder {
        radius: f64,
        half_height: f64,
    },
}

impl ColliderShape {
    /// Signed distance of `p` (relative to the shape's centre) and the outward unit normal
    /// of the nearest surface point (inside: the face the point is closest to).
    pub fn distance(&self, p: DVec3) -> (f64, DVec3) {
        match *self {
            ColliderShape::Sphere { radius } => {
                let len = p.length();
                let n = if len > 0.0 { p / len } else { DVec3::Z };
                (len - radius, n)
            }
            ColliderShape::Box { half } => {
                let q = p.abs() - half;
                let sign = DVec3::select(p.cmplt(DVec3::ZERO), -DVec3::ONE, DVec3::ONE);
                let outside = q.max(DVec3::ZERO);
                if outside.length_squared() > 0.0 {
                    (outside.length(), (outside * sign).normalize())
                } else {
                    let axis = q.max_position();
                    (q[axis], DVec3::AXES[axis] * sign[axis])
                }
            }
            ColliderShape::Cylinder {
                radius,
                half_height,
            } => {
                let r = p.truncate().length();
                let radial = if r > 0.0 {
                    (p.truncate() / r).extend(0.0)
                } else {
                    DVec3::X
                };
                let axial = DVec3::Z * if p.z < 0.0 { -1.0 } else { 1.0 };
                let (qr, qz) = (r - radius, p.z.abs() - half_height);
                if qr > 0.0 || qz > 0.0 {
                    let (a, b) = (qr.max(0.0), qz.max(0.0));
                    let len = a.hypot(b);
                    (len, (radial * a + axial * b) / len)
                } else if qr > qz {
                    (qr, radial)
                } else {
                    (qz, axial)
                }
            }
        }
    }
}

/// Where a rigid body is and how it moves at one time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidPose {
    /// Frame-to-world rotation.
    pub rotation: DMat3,
    /// Origin of the frame in the world.
    pub position: DVec3,
    pub velocity: DVec3,
    /// Angular velocity (rad/s, world frame).
    pub angular_velocity: DVec3,
}

impl RigidPose {
    /// Velocity of the body's point at world position `x`.
    pub fn velocity_at(&self, x: DVec3) -> DVec3 {
        self.velocity + self.angular_velocity.cross(x - self.position)
    }
}

/// A prescribed rigid path: keyframed positions (C¹ Hermite) and Euler angles in degrees
/// (linear), R = Rz · Ry · Rx.
#[derive(Clone, Debug, PartialEq)]
pub struct RigidMotion {
    path: KeyedPoint,
}

/// R = Rz · Ry · Rx of Euler angles in radians (the object transform's convention).
fn euler_rotation(a: DVec3) -> DMat3 {
    DMat3::from_rotation_z(a.z) * DMat3::from_rotation_y(a.y) * DMat3::from_rotation_x(a.x)
}

impl RigidMotion {
    /// Keys at strictly increasing `times` (seconds) with positions and `rotate_deg`.
    pub fn new(times: Vec<f32>, positions: Vec<Vec3>, rotate_deg: Vec<Vec3>) -> RigidMotion {
        RigidMotion {
            path: KeyedPoint::new(times, positions, rotate_deg),
        }
    }

    /// The pose at `t` seconds (held before the first key and after the last).
    pub fn pose(&self, t: f64) -> RigidPose {
        let t = t as f32;
        let (position, deg) = self.path.at(t);
        let (velocity, deg_rate) = self.path.rates_at(t);
        let a = deg.as_dvec3().to_radians_each();
        let rate = deg_rate.as_dvec3().to_radians_each();
        // ω of R = Rz Ry Rx: ż about z, ẏ about Rz·y, ẋ about Rz·Ry·x.
        let rz = DMat3::from_rotation_z(a.z);
        let rzy = rz * DMat3::from_rotation_y(a.y);
        let angular_velocity = DVec3::Z * rate.z + rz * DVec3::Y * rate.y + rzy * DVec3::X * rate.x;
        RigidPose {
            rotation: euler_rotation(a),
            position: position.as_dvec3(),
            velocity: velocity.as_dvec3(),
            angular_velocity,
        }
    }
}

trait RadiansEach {
    fn to_radians_each(self) -> Self;
}

impl RadiansEach for DVec3 {
    fn to_radians_each(self) -> DVec3 {
        self * (std::f64::consts::PI / 180.0)
    }
}

/// A moving collider: a shape at `centre` in the frame of `motion`, a boundary condition,
/// and a margin (nodes with d ≤ margin are covered: a blade thinner than a cell still
/// reaches nodes).
#[derive(Clone, Debug, PartialEq)]
pub struct KinematicCollider {
    pub shape: ColliderShape,
    pub centre: DVec3,
    pub margin: f64,
    pub condition: Condition,
    pub motion: RigidMotion,
}

impl KinematicCollider {
    /// The grid velocity `v` of the node at `x` after this collider at `pose` (module docs).
    pub fn apply(&self, pose: &RigidPose, x: DVec3, v: DVec3) -> DVec3 {
        let local = pose.rotation.transpose() * (x - pose.position) - self.centre;
        let (d, n) = self.shape.distance(local);
        if d > self.margin {
            return v;
        }
        let vc = pose.velocity_at(x);
        vc + self.condition.apply(v - vc, pose.rotation * n)
    }

    /// Signed distance of world point `x` to the collider at `pose`.
    pub fn distance(&self, pose: &RigidPose, x: DVec3) -> f64 {
        let local = pose.rotation.transpose() * (x - pose.position) - self.centre;
        self.shape.distance(local).0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(got: (f64, DVec3), d: f64, n: DVec3) -> bool {
        (got.0 - d).abs() < 1e-12 && (got.1 - n).length() < 1e-12
    }

    #[test]
    fn box_and_cylinder_distances() {
        let b = ColliderShape::Box {
            half: DVec3::new(1.0, 2.0, 3.0),
        };
        assert!(close(b.distance(DVec3::new(0.5, 0.0, 0.0)), -0.5, DVec3::X));
        assert!(close(
            b.distance(DVec3::new(0.0, -1.5, 0.0)),
            -0.5,
            -DVec3::Y
        ));
        let diagonal = DVec3::new(1.0, 1.0, 0.0).normalize();
        assert!(close(
            b.distance(DVec3::new(2.0, 3.0, 0.0)),
            2f64.sqrt(),
            diagonal
        ));
        let c = ColliderShape::Cylinder {
            radius: 1.0,
            half_height: 1.0,
        };
        assert!(close(
            c.distance(DVec3::new(0.0, 0.0, -0.8)),
            -0.2,
            -DVec3::Z
        ));
        assert!(close(c.distance(DVec3::new(0.0, 0.9, 0.0)), -0.1, DVec3::Y));
        assert!(close(c.distance(DVec3::new(3.0, 0.0, 0.0)), 2.0, DVec3::X));
        let s = ColliderShape::Sphere { radius: 0.5 };
        assert!(close(s.distance(DVec3::new(0.0, 0.0, 0.2)), -0.3, DVec3::Z));
    }

    /// The pose's velocities are the derivatives of its position and rotation.
    #[test]
    fn pose_rates_are_derivatives() {
        let m = RigidMotion::new(
            vec![0.0, 1.0, 2.5],
            vec![
                Vec3::ZERO,
                Vec3::new(1.0, 0.5, 0.0),
                Vec3::new(2.0, 0.0, 1.0),
            ],
            vec![
                Vec3::ZERO,
                Vec3::new(30.0, 60.0, 90.0),
                Vec3::new(0.0, 90.0, 0.0),
            ],
        );
        for t in [0.3, 1.4, 2.2] {
            let h = 1e-3;
            let (a, b) = (m.pose(t - h), m.pose(t + h));
            let p = m.pose(t);
            let v = (b.position - a.position) / (2.0 * h);
            assert!(
                (v - p.velocity).length() < 1e-3 * (1.0 + v.length()),
                "t {t}"
            );
            // Ṙ Rᵀ = [ω]×
            let w = (b.rotation - a.rotation) * p.rotation.transpose() / (2.0 * h);
            let omega = DVec3::new(w.y_axis.z, w.z_axis.x, w.x_axis.y);
            assert!(
                (omega - p.angular_velocity).length() < 1e-3,
                "t {t}: {omega} vs {}",
                p.angular_velocity
            );
        }
        // Held after the last key.
        assert_eq!(m.pose(3.0).velocity, DVec3::ZERO);
        assert_eq!(m.pose(3.0).angular_velocity, DVec3::ZERO);
    }
}
