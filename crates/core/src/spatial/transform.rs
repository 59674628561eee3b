//! Plücker coordinate transforms (RBDA §2.8, eq. 2.24–2.26), applied without forming 6×6
//! matrices.

use super::{skew, Force, Motion};
use nalgebra::{Matrix3, Matrix6, Rotation3, Vector3};

/// A Plücker transform `B_X_A` from frame A to frame B.
///
/// `e` gives B coordinates of a vector given in A coordinates; `r` is the position of B's origin
/// relative to A's origin, in A coordinates (m). As a matrix, `X = [E 0; -E r× E]`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Transform {
    /// Rotation `E` (B coordinates from A coordinates).
    pub e: Matrix3<f64>,
    /// Origin of B relative to A, in A coordinates (m).
    pub r: Vector3<f64>,
}

impl Default for Transform {
    fn default() -> Self {
        Self::identity()
    }
}

/// Rotation matrix of a rotation by `angle` (rad) about the unit `axis` (Rodrigues):
/// `R = c 1 + s a× + (1 − c) a aᵀ`.
#[inline]
pub fn rot_axis_angle(a: &Vector3<f64>, angle: f64) -> Matrix3<f64> {
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    Matrix3::new(
        c + t * a.x * a.x,
        t * a.x * a.y - s * a.z,
        t * a.x * a.z + s * a.y,
        t * a.x * a.y + s * a.z,
        c + t * a.y * a.y,
        t * a.y * a.z - s * a.x,
        t * a.x * a.z - s * a.y,
        t * a.y * a.z + s * a.x,
        c + t * a.z * a.z,
    )
}

/// Rotation matrix from URDF roll-pitch-yaw angles (rad): `R = Rz(yaw) Ry(pitch) Rx(roll)`.
pub fn rpy_to_matrix(rpy: &Vector3<f64>) -> Matrix3<f64> {
    Rotation3::from_euler_angles(rpy.x, rpy.y, rpy.z).into_inner()
}

impl Transform {
    /// The identity transform.
    pub fn identity() -> Self {
        Self {
            e: Matrix3::identity(),
            r: Vector3::zeros(),
        }
    }

    /// The transform into a frame B whose pose in A is given by the rotation `rot` (B's axes in
    /// A coordinates, as URDF `rpy`) and position `pos` (m, A coordinates): `E = rotᵀ`, `r = pos`.
    pub fn from_pose(rot: &Matrix3<f64>, pos: &Vector3<f64>) -> Self {
        Self {
            e: rot.transpose(),
            r: *pos,
        }
    }

    /// A pure translation of the origin by `r` (RBDA `xlt`).
    pub fn translation(r: &Vector3<f64>) -> Self {
        Self {
            e: Matrix3::identity(),
            r: *r,
        }
    }

    /// The pose of B in A: rotation (B axes in A coordinates) and position.
    pub fn to_pose(&self) -> (Matrix3<f64>, Vector3<f64>) {
        (self.e.transpose(), self.r)
    }

    /// `X m`: a motion vector from A to B coordinates.
    #[inline]
    pub fn apply_motion(&self, m: &Motion) -> Motion {
        Motion::new(self.e * m.ang, self.e * (m.lin - self.r.cross(&m.ang)))
    }

    /// `X* f`: a force vector from A to B coordinates.
    #[inline]
    pub fn apply_force(&self, f: &Force) -> Force {
        Force::new(self.e * (f.ang - self.r.cross(&f.lin)), self.e * f.lin)
    }

    /// `X⁻¹ m`: a motion vector from B back to A coordinates.
    #[inline]
    pub fn inv_apply_motion(&self, m: &Motion) -> Motion {
        let ang = self.e.tr_mul(&m.ang);
        Motion::new(ang, self.e.tr_mul(&m.lin) + self.r.cross(&ang))
    }

    /// `Xᵀ f = (X*)⁻¹ f`: a force vector from B back to A coordinates.
    #[inline]
    pub fn inv_apply_force(&self, f: &Force) -> Force {
        let lin = self.e.tr_mul(&f.lin);
        Force::new(self.e.tr_mul(&f.ang) + self.r.cross(&lin), lin)
    }

    /// Composition `self * other`: if `self = C_X_B` and `other = B_X_A`, the result is `C_X_A`.
    #[inline]
    pub fn compose(&self, other: &Transform) -> Transform {
        Transform {
            e: self.e * other.e,
            r: other.r + other.e.tr_mul(&self.r),
        }
    }

    /// The inverse `A_X_B`.
    pub fn inverse(&self) -> Transform {
        Transform {
            e: self.e.transpose(),
            r: -(self.e * self.r),
        }
    }

    /// A point given in A coordinates, expressed in B coordinates.
    #[inline]
    pub fn point_to_b(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.e * (p - self.r)
    }

    /// A point given in B coordinates, expressed in A coordinates.
    #[inline]
    pub fn point_to_a(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.e.tr_mul(p) + self.r
    }

    /// The 6×6 motion transform matrix `[E 0; -E r× E]` (for tests and export).
    pub fn to_matrix(&self) -> Matrix6<f64> {
        let mut x = Matrix6::zeros();
        x.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.e);
        x.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.e);
        x.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&(-self.e * skew(&self.r)));
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Transform {
        let rot = rot_axis_angle(&Vector3::new(1.0, 2.0, -0.5).normalize(), 0.83);
        Transform::from_pose(&rot, &Vector3::new(0.1, -0.4, 0.25))
    }

    #[test]
    fn structured_operations_match_matrix_forms() {
        let x = sample();
        let xm = x.to_matrix();
        let m = Motion::new(Vector3::new(0.3, -1.0, 0.2), Vector3::new(0.7, 0.5, -0.9));
        let f = Force::new(Vector3::new(-0.2, 0.6, 1.3), Vector3::new(0.4, -1.1, 0.8));
        let xf = xm.try_inverse().unwrap().transpose();
        assert!((x.apply_motion(&m).to_vec6() - xm * m.to_vec6()).norm() < 1e-14);
        assert!((x.apply_force(&f).to_vec6() - xf * f.to_vec6()).norm() < 1e-14);
        assert!((x.inv_apply_force(&f).to_vec6() - xm.transpose() * f.to_vec6()).norm() < 1e-14);
        let back = x.inv_apply_motion(&x.apply_motion(&m));
        assert!((back.to_vec6() - m.to_vec6()).norm() < 1e-14);
        // Power is frame independent.
        assert!((x.apply_motion(&m).dot(&x.apply_force(&f)) - m.dot(&f)).abs() < 1e-14);
    }

    #[test]
    fn composition_and_inverse() {
        let a = sample();
        let b = Transform::from_pose(
            &rot_axis_angle(&Vector3::z(), -1.2),
            &Vector3::new(0.0, 0.3, -0.1),
        );
        let ab = a.compose(&b);
        assert!((ab.to_matrix() - a.to_matrix() * b.to_matrix()).norm() < 1e-14);
        let id = a.compose(&a.inverse());
        assert!((id.to_matrix() - Matrix6::identity()).norm() < 1e-14);
        let p = Vector3::new(0.5, -0.2, 0.9);
        assert!((a.point_to_a(&a.point_to_b(&p)) - p).norm() < 1e-15);
    }

    #[test]
    fn rodrigues_matches_nalgebra() {
        let a = Vector3::new(0.3, -0.5, 0.8).normalize();
        for angle in [-2.5, -0.1, 0.0, 0.7, 3.1] {
            let want =
                Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(a), angle).into_inner();
            assert!((rot_axis_angle(&a, angle) - want).norm() < 1e-15);
        }
    }

    #[test]
    fn rpy_matches_urdf_convention() {
        // URDF: R = Rz(yaw) Ry(pitch) Rx(roll).
        let rpy = Vector3::new(0.3, -0.7, 1.1);
        let expect = rot_axis_angle(&Vector3::z(), rpy.z)
            * rot_axis_angle(&Vector3::y(), rpy.y)
            * rot_axis_angle(&Vector3::x(), rpy.x);
        assert!((rpy_to_matrix(&rpy) - expect).norm() < 1e-14);
    }
}
