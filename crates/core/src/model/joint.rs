//! Joint models: `jcalc` (RBDA Table 4.1) for the joint types physid supports.

use crate::spatial::{rot_axis_angle, Motion, Transform};
use nalgebra::Vector3;

/// A one-degree-of-freedom joint, its axis given in the joint frame.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
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

    /// `X_J(q) X_T`: the tree transform `x_tree` followed by the joint's. A revolute joint
    /// only rotates, so the translation is `x_tree`'s as it is (what [`Transform::compose`]
    /// gives, without adding `E_Tᵀ 0`).
    #[inline]
    pub fn transform_after(&self, q: f64, x_tree: &Transform) -> Transform {
        match *self {
            Joint::Revolute { axis } => Transform {
                e: rot_axis_angle(&axis, -q) * x_tree.e,
                r: x_tree.r,
            },
            Joint::Prismatic { .. } => self.transform(q).compose(x_tree),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spatial::rpy_to_matrix;

    /// `transform_after` is `transform(q).compose(x_tree)`, entry for entry, for both joint
    /// kinds on a tree transform that rotates and translates.
    #[test]
    fn transform_after_is_the_joint_transform_composed_with_the_tree_transform() {
        let x_tree = Transform {
            e: rpy_to_matrix(&Vector3::new(0.3, -1.1, 2.0)),
            r: Vector3::new(0.12, -0.4, 0.05),
        };
        let axis = Vector3::new(0.2, -0.5, 0.8).normalize();
        for joint in [Joint::Revolute { axis }, Joint::Prismatic { axis }] {
            for q in [-2.7, -0.3, 0.0, 0.9, 3.1] {
                let composed = joint.transform(q).compose(&x_tree);
                let after = joint.transform_after(q, &x_tree);
                assert_eq!(after.e, composed.e, "{joint:?} at {q}");
                assert_eq!(after.r, composed.r, "{joint:?} at {q}");
            }
        }
    }
}
