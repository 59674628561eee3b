//! A floating-base robot: a **trunk** that moves freely in the world (six degrees of freedom, no
//! joint to the ground) and a [`Model`] tree mounted on it.
//!
//! The tree is an ordinary model whose "fixed base" is the trunk frame: its bodies with
//! `parent = None` (the legs' first links) and the rotors on them hang from the trunk, and its
//! gravity is the world's, expressed in world coordinates. The generalized velocity is
//! `ν = [v_B; q̇]` with `v_B = [ω; v]` the trunk's spatial velocity in trunk coordinates
//! (Featherstone's order: angular first; pinocchio's free flyer has linear first), so `ν` has
//! `6 + n` entries. The parameter vector is `θ = [π_trunk; θ_tree]`: the trunk's ten, then the
//! tree's [`super::ParamLayout`] shifted by ten.

use super::{check_params, Model, ModelError};
use crate::spatial::{Ellipsoid, InertialParams};
use nalgebra::DVector;

/// The free-floating root body.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Trunk {
    /// Body name.
    pub name: String,
    /// Inertial parameters in the trunk frame (paper order).
    pub inertia: InertialParams,
    /// Bounding ellipsoid in the trunk frame, if known.
    pub bounding: Option<Ellipsoid>,
}

/// A trunk and the tree on it. Immutable; build it with [`FloatingModel::new`].
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FloatingModel {
    trunk: Trunk,
    tree: Model,
}

impl FloatingModel {
    /// The robot of `trunk` carrying `tree`; the trunk's parameters must be finite and its
    /// name distinct from the tree's bodies'.
    pub fn new(trunk: Trunk, tree: Model) -> Result<Self, ModelError> {
        check_params(&format!("trunk '{}'", trunk.name), &trunk.inertia)?;
        if tree.bodies().iter().any(|b| b.name == trunk.name) {
            return Err(ModelError::DuplicateName {
                what: "body",
                name: trunk.name,
            });
        }
        Ok(Self { trunk, tree })
    }

    /// The trunk.
    pub fn trunk(&self) -> &Trunk {
        &self.trunk
    }

    /// The tree on the trunk (its root frame is the trunk frame).
    pub fn tree(&self) -> &Model {
        &self.tree
    }

    /// Robot name (the tree's).
    pub fn name(&self) -> &str {
        self.tree.name()
    }

    /// Actuated joints.
    pub fn joints(&self) -> usize {
        self.tree.dof()
    }

    /// Degrees of freedom, `6 + n`.
    pub fn dof(&self) -> usize {
        6 + self.tree.dof()
    }

    /// Number of parameters, `10 + p`.
    pub fn parameter_count(&self) -> usize {
        10 + self.tree.layout().len
    }

    /// `θ = [π_trunk; θ_tree]`.
    pub fn parameters(&self) -> DVector<f64> {
        let tree = self.tree.parameters();
        DVector::from_iterator(
            self.parameter_count(),
            self.trunk.inertia.0.iter().chain(tree.iter()).copied(),
        )
    }

    /// Names of the parameters: the trunk's (`trunk.m`, …), then the tree's.
    pub fn parameter_names(&self) -> Vec<String> {
        let names = crate::spatial::PARAM_NAMES;
        (0..10)
            .map(|k| format!("{}.{}", self.trunk.name, names[k]))
            .chain(self.tree.parameter_names())
            .collect()
    }

    /// A copy with every parameter replaced by `theta` (same layout; only finiteness checked).
    pub fn with_parameters(&self, theta: &DVector<f64>) -> Result<Self, ModelError> {
        if theta.len() != self.parameter_count() {
            return Err(ModelError::ParamLength {
                expected: self.parameter_count(),
                got: theta.len(),
            });
        }
        let trunk = Trunk {
            inertia: InertialParams(theta.fixed_rows::<10>(0).into_owned()),
            ..self.trunk.clone()
        };
        let tree = self
            .tree
            .with_parameters(&theta.rows(10, theta.len() - 10).into_owned())?;
        Self::new(trunk, tree)
    }

    /// Total mass of trunk, links and rotors (kg).
    pub fn total_mass(&self) -> f64 {
        self.trunk.inertia.mass() + self.tree.total_mass()
    }
}
