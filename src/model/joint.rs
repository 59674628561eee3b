//! Joint models: `jcalc` (RBDA Table 4.1) for the joint types physid supports.

use crate::spatial::{rot_axis_angle, Motion, Transform};
use nalgebra::Vector3;

/// A one-degree-of-freedom joint, its axis given in the joint frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Joint {
    /// Rotation by `q` (rad) about a unit axis.
    Revolute {
        /// Unit axis in the joint frame.
        axis: Vector3<f64>,
    },
    /// Translation by `q` (m) along a unit axis.
    Prismatic {
        /// Unit axis in the joint frame.
        axis: Vector3<f64>,
    },
}

impl Joint {
    /// The joint axis.
    pub fn axis(&self) -> Vector3<f64> {
        match *self {
            Joint::Revolute { axis } | Joint::Prismatic { axis } => axis,
        }
    }

    /// The same joint with a unit axis, or why that is impossible.
    pub fn normalized(&self) -> Result<Joint, String> {
        let a = self.axis();
        let n = a.norm();
        if !n.is_finite() || n < 1e-9 {
            return Err(format!(
                "axis {:?} is not a non-zero finite vector",
                a.as_slice()
            ));
        }
        Ok(match self {
            Joint::Revolute { .. } => Joint::Revolute { axis: a / n },
            Joint::Prismatic { .. } => Joint::Prismatic { axis: a / n },
        })
    }

    /// Motion subspace `S` (constant in the joint frame for these joints).
    #[inline]
    pub fn motion_subspace(&self) -> Motion {
        match *self {
            Joint::Revolute { axis } => Motion::new(axis, Vector3::zeros()),
            Joint::Prismatic { axis } => Motion::new(Vector3::zeros(), axis),
        }
    }

    /// Joint transform `X_J(q)` from the joint's predecessor frame to its successor frame.
    #[inline]
    pub fn transform(&self, q: f64) -> Transform {
        match *self {
            // E = R(q)ᵀ = R(−q).
            Joint::Revolute { axis } => Transform {
                e: rot_axis_angle(&axis, -q),
                r: Vector3::zeros(),
            },
            Joint::Prismatic { axis } => Transform::translation(&(axis * q)),
        }
    }
}
