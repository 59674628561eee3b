//! The rows a floating-base robot's sample gives identification, in the three data settings
//! users have.
//!
//! The equations of motion are `Y(q, ν, ν̇) θ = [0; τ] + Σ_c J_cᵀ λ_c`
//! ([`physid_core::dynamics::regressor_floating`]): six trunk rows (unactuated) and one row per
//! joint, the contact forces `λ_c` (world coordinates) at the feet in contact entering through
//! their Jacobians `J_c`.
//!
//! - [`DataSetting::TorquesAndContacts`]: joint torques and contact forces are measured: every
//!   row, target `[0; τ] + Σ J_cᵀ λ_c`.
//! - [`DataSetting::TorquesOnly`]: joint torques without contact forces. The forces are
//!   eliminated by projecting onto the null space of the stacked contact Jacobian `J`
//!   (`Z` with orthonormal columns, `J Z = 0`): `Zᵀ Y θ = Zᵀ [0; τ]`, `6 + n − rank J` rows
//!   (with four feet down, 6 of 18). A sample without contact keeps every row.
//! - [`DataSetting::BaseOnly`]: the trunk's six rows alone, from the base's and joints' motion
//!   and the contact forces, no joint torques (Ayusawa, Venture & Nakamura, IJRR 2014): target
//!   `Σ J_c,Bᵀ λ_c`. Joint friction does not enter the trunk rows, so it is not identified
//!   (its columns are zero); the inertial parameters are identifiable up to the same
//!   combinations as from the whole body (their result), which the base-parameter analysis
//!   reports.
//!
//! Every setting's sample has the same number of rows ([`rows_per_sample`]): projected samples
//! are padded with zero rows, which add nothing to the normal equations.

use nalgebra::{DMatrix, DVector, Vector3};
use physid_core::dynamics::{point_jacobian_floating, regressor_floating, BaseState, Data};
use physid_core::model::floating::FloatingModel;

/// Which quantities the data carry.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DataSetting {
    /// Joint torques and the feet's contact forces.
    TorquesAndContacts,
    /// Joint torques; contact forces eliminated.
    TorquesOnly,
    /// The trunk's dynamics from contact forces, without joint torques.
    BaseOnly,
}

/// A foot in contact: the point `point` (m) fixed in `body` and the force `force` (world
/// coordinates, N) the ground exerts on it (ignored by [`DataSetting::TorquesOnly`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// Body index in the tree.
    pub body: usize,
    /// The point in body coordinates (m).
    pub point: Vector3<f64>,
    /// The ground's force on it, world coordinates (N).
    pub force: Vector3<f64>,
}

/// One sample of a floating robot: the trunk's state, the joints' and the feet in contact.
#[derive(Clone, Copy, Debug)]
pub struct FloatingSample<'a> {
    /// Trunk pose, twist and acceleration.
    pub base: &'a BaseState,
    /// Joint positions (rad).
    pub q: &'a [f64],
    /// Joint velocities (rad/s).
    pub qd: &'a [f64],
    /// Joint accelerations (rad/s²).
    pub qdd: &'a [f64],
    /// Joint torques (N m); unused by [`DataSetting::BaseOnly`].
    pub tau: &'a [f64],
    /// The feet in contact.
    pub contacts: &'a [Contact],
}

/// Rows per sample in `setting`: `6 + n`, or 6 for the trunk's rows alone.
pub fn rows_per_sample(robot: &FloatingModel, setting: DataSetting) -> usize {
    match setting {
        DataSetting::BaseOnly => 6,
        _ => robot.dof(),
    }
}

/// Workspace for the rows of many samples of one robot.
pub struct FloatingRows {
    data: Data,
    y: DMatrix<f64>,
}

impl FloatingRows {
    /// A workspace for `robot`.
    pub fn new(robot: &FloatingModel) -> Self {
        Self {
            data: Data::new(robot.tree()),
            y: DMatrix::zeros(robot.dof(), robot.parameter_count()),
        }
    }

    /// The rows and targets of sample `s` in `setting` ([`rows_per_sample`] of each).
    pub fn rows(
        &mut self,
        robot: &FloatingModel,
        s: &FloatingSample,
        setting: DataSetting,
    ) -> (DMatrix<f64>, DVector<f64>) {
        let n = robot.joints();
        regressor_floating(
            robot,
            &mut self.data,
            s.base,
            (s.q, s.qd, s.qdd),
            &mut self.y,
        );
        let jacobians: Vec<DMatrix<f64>> = s
            .contacts
            .iter()
            .map(|c| {
                point_jacobian_floating(robot, &mut self.data, s.base, s.q, (c.body, &c.point))
            })
            .collect();
        let mut generalized = DVector::zeros(6 + n);
        generalized.rows_mut(6, n).copy_from_slice(s.tau);
        let mut contact_force = DVector::zeros(6 + n);
        for (jac, c) in jacobians.iter().zip(s.contacts) {
            contact_force += jac.transpose() * DVector::from_column_slice(c.force.as_slice());
        }
        match setting {
            DataSetting::TorquesAndContacts => (self.y.clone(), generalized + contact_force),
            DataSetting::BaseOnly => (
                self.y.rows(0, 6).into_owned(),
                contact_force.rows(0, 6).into_owned(),
            ),
            DataSetting::TorquesOnly => {
                let z = contact_null_space(&jacobians, 6 + n);
                let mut rows = DMatrix::zeros(6 + n, self.y.ncols());
                let mut target = DVector::zeros(6 + n);
                rows.rows_mut(0, z.ncols())
                    .copy_from(&(z.transpose() * &self.y));
                target
                    .rows_mut(0, z.ncols())
                    .copy_from(&(z.transpose() * generalized));
                (rows, target)
            }
        }
    }
}

/// An orthonormal basis `Z` (`dim × k`) of the vectors `z` with `J_c z = 0` for every contact
/// Jacobian: `Zᵀ J_cᵀ λ = 0` whatever the forces. The whole space without contacts.
fn contact_null_space(jacobians: &[DMatrix<f64>], dim: usize) -> DMatrix<f64> {
    if jacobians.is_empty() {
        return DMatrix::identity(dim, dim);
    }
    let rows: usize = jacobians.iter().map(|j| j.nrows()).sum();
    let mut j = DMatrix::zeros(rows.max(dim), dim);
    let mut r = 0;
    for jac in jacobians {
        j.rows_mut(r, jac.nrows()).copy_from(jac);
        r += jac.nrows();
    }
    // Right singular vectors of the (zero-padded, square or tall) stack; those whose singular
    // value is below round-off relative to the largest span its null space.
    let svd = j.svd(false, true);
    let v_t = svd.v_t.expect("asked for V");
    let largest = svd.singular_values.max();
    let null: Vec<usize> = (0..dim)
        .filter(|&i| svd.singular_values[i] <= 1e-10 * largest)
        .collect();
    DMatrix::from_fn(dim, null.len(), |row, c| v_t[(null[c], row)])
}
