//! Spatial motion and force vectors (RBDA §2.2–2.9), stored as two 3-vectors.

use nalgebra::{Vector3, Vector6};
use std::ops::{Add, AddAssign, Mul, Neg, Sub};

/// A spatial motion vector `[ω; v]` (rad/s, m/s), or an acceleration `[ω̇; v̇]`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Motion {
    /// Angular part ω.
    pub ang: Vector3<f64>,
    /// Linear part v: the velocity of the body-fixed point at the frame origin.
    pub lin: Vector3<f64>,
}

/// A spatial force vector `[n; f]` (N m about the frame origin, N).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Force {
    /// Moment n about the frame origin.
    pub ang: Vector3<f64>,
    /// Linear force f.
    pub lin: Vector3<f64>,
}

impl Motion {
    /// A motion vector from its angular and linear parts.
    #[inline]
    pub fn new(ang: Vector3<f64>, lin: Vector3<f64>) -> Self {
        Self { ang, lin }
    }
    /// The zero motion.
    #[inline]
    pub fn zero() -> Self {
        Self::default()
    }
    /// From a 6-vector in `[ω; v]` order.
    pub fn from_vec6(v: &Vector6<f64>) -> Self {
        Self::new(v.fixed_rows::<3>(0).into(), v.fixed_rows::<3>(3).into())
    }
    /// As a 6-vector in `[ω; v]` order.
    pub fn to_vec6(&self) -> Vector6<f64> {
        Vector6::new(
            self.ang.x, self.ang.y, self.ang.z, self.lin.x, self.lin.y, self.lin.z,
        )
    }
    /// Spatial cross product for motions, `self ×m` applied to `m` (RBDA eq. 2.31, `crm`).
    #[inline]
    pub fn cross_motion(&self, m: &Motion) -> Motion {
        Motion::new(
            self.ang.cross(&m.ang),
            self.ang.cross(&m.lin) + self.lin.cross(&m.ang),
        )
    }
    /// Spatial cross product for forces, `self ×*` applied to `f` (RBDA eq. 2.32, `crf`).
    #[inline]
    pub fn cross_force(&self, f: &Force) -> Force {
        Force::new(
            self.ang.cross(&f.ang) + self.lin.cross(&f.lin),
            self.ang.cross(&f.lin),
        )
    }
    /// The scalar product `m · f` (power, W).
    #[inline]
    pub fn dot(&self, f: &Force) -> f64 {
        self.ang.dot(&f.ang) + self.lin.dot(&f.lin)
    }
}

impl Force {
    /// A force vector from its moment and linear parts.
    #[inline]
    pub fn new(ang: Vector3<f64>, lin: Vector3<f64>) -> Self {
        Self { ang, lin }
    }
    /// The zero force.
    #[inline]
    pub fn zero() -> Self {
        Self::default()
    }
    /// As a 6-vector in `[n; f]` order.
    pub fn to_vec6(&self) -> Vector6<f64> {
        Vector6::new(
            self.ang.x, self.ang.y, self.ang.z, self.lin.x, self.lin.y, self.lin.z,
        )
    }
}

macro_rules! impl_linear_ops {
    ($t:ty) => {
        impl Add for $t {
            type Output = $t;
            #[inline]
            fn add(self, o: $t) -> $t {
                <$t>::new(self.ang + o.ang, self.lin + o.lin)
            }
        }
        impl Sub for $t {
            type Output = $t;
            #[inline]
            fn sub(self, o: $t) -> $t {
                <$t>::new(self.ang - o.ang, self.lin - o.lin)
            }
        }
        impl AddAssign for $t {
            #[inline]
            fn add_assign(&mut self, o: $t) {
                self.ang += o.ang;
                self.lin += o.lin;
            }
        }
        impl Neg for $t {
            type Output = $t;
            #[inline]
            fn neg(self) -> $t {
                <$t>::new(-self.ang, -self.lin)
            }
        }
        impl Mul<f64> for $t {
            type Output = $t;
            #[inline]
            fn mul(self, s: f64) -> $t {
                <$t>::new(self.ang * s, self.lin * s)
            }
        }
    };
}
impl_linear_ops!(Motion);
impl_linear_ops!(Force);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spatial::skew;
    use nalgebra::Matrix6;

    fn crm_matrix(m: &Motion) -> Matrix6<f64> {
        let mut x = Matrix6::zeros();
        let w = skew(&m.ang);
        x.fixed_view_mut::<3, 3>(0, 0).copy_from(&w);
        x.fixed_view_mut::<3, 3>(3, 3).copy_from(&w);
        x.fixed_view_mut::<3, 3>(3, 0).copy_from(&skew(&m.lin));
        x
    }

    #[test]
    fn cross_products_match_featherstone_matrices() {
        let v = Motion::new(Vector3::new(0.3, -1.2, 0.7), Vector3::new(2.0, 0.1, -0.5));
        let m = Motion::new(Vector3::new(-0.4, 0.9, 1.1), Vector3::new(0.2, -0.3, 0.8));
        let f = Force::new(Vector3::new(1.5, 0.2, -0.9), Vector3::new(-0.6, 0.4, 2.2));
        let crm = crm_matrix(&v);
        let crf = -crm.transpose();
        assert!((v.cross_motion(&m).to_vec6() - crm * m.to_vec6()).norm() < 1e-14);
        assert!((v.cross_force(&f).to_vec6() - crf * f.to_vec6()).norm() < 1e-14);
        // Duality: (v × m) · f = -m · (v ×* f).
        assert!((v.cross_motion(&m).dot(&f) + m.dot(&v.cross_force(&f))).abs() < 1e-14);
    }
}
