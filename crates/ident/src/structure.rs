//! What identification needs to know of a robot: which columns of `θ` are whose ten inertial
//! parameters (and in which ellipsoid), and which are friction. A fixed-base [`Model`] and a
//! [`FloatingModel`] (the trunk's ten first, the tree's after) both answer.

use nalgebra::DVector;
use physid_core::model::floating::FloatingModel;
use physid_core::model::Model;
use physid_core::spatial::Ellipsoid;

/// A robot's parameter vector as identification sees it.
pub trait Parameterized {
    /// The bodies in parameter order: `(name, first column, bounding ellipsoid)`, links then
    /// rotors (a floating robot's trunk first).
    fn inertial_bodies(&self) -> Vec<(String, usize, Option<Ellipsoid>)>;

    /// The first viscous and the first Coulomb column, one of each per joint.
    fn friction_columns(&self) -> (usize, usize);

    /// Actuated joints.
    fn joints(&self) -> usize;

    /// Length of `θ`.
    fn parameter_count(&self) -> usize;

    /// The robot's own `θ` (the truth of a simulation, or a description's values).
    fn parameters(&self) -> DVector<f64>;

    /// A name per column of `θ`, e.g. `thigh.Ixz`, `knee_joint.B`.
    fn parameter_names(&self) -> Vec<String>;
}

impl Parameterized for Model {
    fn inertial_bodies(&self) -> Vec<(String, usize, Option<Ellipsoid>)> {
        let mut out: Vec<_> = self
            .bodies()
            .iter()
            .enumerate()
            .map(|(i, b)| (b.name.clone(), 10 * i, b.bounding))
            .collect();
        for (i, b) in self.bodies().iter().enumerate() {
            if let (Some(c), Some(r)) = (self.layout().rotor_col[i], &b.rotor) {
                out.push((r.name.clone(), c, r.bounding));
            }
        }
        out
    }

    fn friction_columns(&self) -> (usize, usize) {
        (self.layout().viscous_col, self.layout().coulomb_col)
    }

    fn joints(&self) -> usize {
        self.dof()
    }

    fn parameter_count(&self) -> usize {
        self.layout().len
    }

    fn parameters(&self) -> DVector<f64> {
        Model::parameters(self)
    }

    fn parameter_names(&self) -> Vec<String> {
        Model::parameter_names(self)
    }
}

impl Parameterized for FloatingModel {
    fn inertial_bodies(&self) -> Vec<(String, usize, Option<Ellipsoid>)> {
        let trunk = self.trunk();
        std::iter::once((trunk.name.clone(), 0, trunk.bounding))
            .chain(
                self.tree()
                    .inertial_bodies()
                    .into_iter()
                    .map(|(name, col, e)| (name, 10 + col, e)),
            )
            .collect()
    }

    fn friction_columns(&self) -> (usize, usize) {
        let (v, c) = self.tree().friction_columns();
        (10 + v, 10 + c)
    }

    fn joints(&self) -> usize {
        self.tree().dof()
    }

    fn parameter_count(&self) -> usize {
        FloatingModel::parameter_count(self)
    }

    fn parameters(&self) -> DVector<f64> {
        FloatingModel::parameters(self)
    }

    fn parameter_names(&self) -> Vec<String> {
        FloatingModel::parameter_names(self)
    }
}
