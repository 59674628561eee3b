//! The dynamics over many samples at once, on flat arrays as numpy and other callers hold
//! them: `q`, `q̇`, `q̈` sample-major (`samples × n`, row-major), results likewise. Shapes and
//! values are checked before any work (an error naming the array and the sample, never a
//! panic); samples are computed in parallel (rayon) and the results do not depend on the
//! thread count (each sample is computed alone).

use super::ApiError;
use crate::dynamics::{
    crba, crba_floating, regressor, regressor_floating, rnea_floating, rnea_with_friction, stacked,
    BaseState, Data,
};
use crate::model::floating::FloatingModel;
use crate::model::Model;
use crate::spatial::{Motion, Transform};
use nalgebra::{DMatrix, Quaternion, UnitQuaternion, Vector3};
use rayon::prelude::*;

/// A wrong shape or value in an array given to a batch routine.
#[derive(Debug, thiserror::Error)]
pub enum ShapeError {
    /// The array's length is not `samples × n`.
    #[error("{name} has {len} values, not a whole number of samples of {n} values")]
    Length {
        /// The array (`q`, `qd`, `qdd`).
        name: &'static str,
        /// Its length.
        len: usize,
        /// Values per sample (the robot's joints; for a floating robot its configuration's or
        /// velocity's size).
        n: usize,
    },
    /// Two arrays hold different numbers of samples.
    #[error("{name} has {got} samples, q has {want}")]
    Samples {
        /// The array.
        name: &'static str,
        /// Its samples.
        got: usize,
        /// q's samples.
        want: usize,
    },
    /// A value is NaN or infinite.
    #[error("{name}: sample {sample}, joint {joint} is {value}")]
    NotFinite {
        /// The array.
        name: &'static str,
        /// The sample.
        sample: usize,
        /// The joint (index in the robot's order).
        joint: usize,
        /// The value.
        value: f64,
    },
}

/// The number of samples in `q` (and in each of `others`, which must hold as many), every value
/// finite: the check every batch routine makes before any work.
pub fn samples(
    model: &Model,
    q: &[f64],
    others: &[(&'static str, &[f64])],
) -> Result<usize, ShapeError> {
    let n = model.dof();
    let others: Vec<_> = others.iter().map(|&(name, v)| (name, v, n)).collect();
    samples_of_widths(("q", q, n), &others)
}

/// The samples of `first` (name, values, values per sample), and of each of `others`, which
/// must hold as many; every value finite.
fn samples_of_widths(
    first: (&'static str, &[f64], usize),
    others: &[(&'static str, &[f64], usize)],
) -> Result<usize, ShapeError> {
    let count = |(name, v, n): (&'static str, &[f64], usize)| -> Result<usize, ShapeError> {
        if n == 0 || v.len() % n != 0 {
            return Err(ShapeError::Length {
                name,
                len: v.len(),
                n,
            });
        }
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(ShapeError::NotFinite {
                name,
                sample: i / n,
                joint: i % n,
                value: v[i],
            });
        }
        Ok(v.len() / n)
    };
    let want = count(first)?;
    for &(name, v, n) in others {
        let got = count((name, v, n))?;
        if got != want {
            return Err(ShapeError::Samples { name, got, want });
        }
    }
    Ok(want)
}

/// Runs `f` on every sample in parallel (`out` values per sample), each with its own
/// workspace.
fn per_sample(
    model: &Model,
    count: usize,
    out: usize,
    f: impl Fn(&mut Data, usize, &mut [f64]) + Sync,
) -> Vec<f64> {
    let mut result = vec![0.0; count * out];
    if out == 0 {
        return result;
    }
    result
        .par_chunks_mut(out)
        .enumerate()
        .for_each_init(|| Data::new(model), |data, (k, slot)| f(data, k, slot));
    result
}

/// `τ = RNEA(q, q̇, q̈) + friction` (N m) per sample: `samples × n`.
pub fn inverse_dynamics(
    model: &Model,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> Result<Vec<f64>, ApiError> {
    let count = samples(model, q, &[("qd", qd), ("qdd", qdd)])?;
    let n = model.dof();
    Ok(per_sample(model, count, n, |data, k, tau| {
        let s = k * n..(k + 1) * n;
        let t = rnea_with_friction(model, data, &q[s.clone()], &qd[s.clone()], &qdd[s]);
        tau.copy_from_slice(t.as_slice());
    }))
}

/// The joint-space mass matrix `H(q)` (kg m², rotors' reflected inertia included) per
/// sample: `samples × n × n`, each matrix row-major.
pub fn mass_matrices(model: &Model, q: &[f64]) -> Result<Vec<f64>, ApiError> {
    let count = samples(model, q, &[])?;
    let n = model.dof();
    Ok(per_sample(model, count, n * n, |data, k, h| {
        let m = crba(model, data, &q[k * n..(k + 1) * n]);
        for i in 0..n {
            for j in 0..n {
                h[i * n + j] = m[(i, j)];
            }
        }
    }))
}

/// The regressor `Y(q, q̇, q̈)` with `Y θ = τ` (the model's parameter layout, friction
/// columns last) per sample: `samples × n × p`, each matrix row-major.
pub fn regressors(model: &Model, q: &[f64], qd: &[f64], qdd: &[f64]) -> Result<Vec<f64>, ApiError> {
    let count = samples(model, q, &[("qd", qd), ("qdd", qdd)])?;
    let (n, p) = (model.dof(), model.layout().len);
    Ok(per_sample(model, count, n * p, |data, k, out| {
        let s = k * n..(k + 1) * n;
        let mut y = DMatrix::zeros(n, p);
        regressor(model, data, &q[s.clone()], &qd[s.clone()], &qdd[s], &mut y);
        for i in 0..n {
            for j in 0..p {
                out[i * p + j] = y[(i, j)];
            }
        }
    }))
}

/// A floating robot's states in pinocchio's free-flyer layout, checked: per sample the
/// configuration `[x, y, z, qx, qy, qz, qw, q…]` (`7 + n`: the trunk origin's position in the
/// world, m; its orientation, a unit quaternion, world from trunk; the joints in the robot's
/// order) and the velocity and acceleration `[v, ω, q̇…]` (`6 + n`: the trunk origin's velocity
/// and the angular velocity in trunk axes, and its spatial acceleration alike).
struct FloatingStates<'a> {
    q: &'a [f64],
    v: &'a [f64],
    a: &'a [f64],
    count: usize,
    n: usize,
}

impl<'a> FloatingStates<'a> {
    fn new(
        robot: &FloatingModel,
        q: &'a [f64],
        v: &'a [f64],
        a: &'a [f64],
    ) -> Result<Self, ApiError> {
        let n = robot.joints();
        let count = configurations(q, n, &[("v", v, 6 + n), ("a", a, 6 + n)])?;
        Ok(Self { q, v, a, count, n })
    }

    /// Sample `k`: the trunk's state and the joints' `(q, q̇, q̈)`.
    fn at(&self, k: usize) -> (BaseState, [&'a [f64]; 3]) {
        let (nq, nv) = (7 + self.n, 6 + self.n);
        let (q, v, a) = (
            &self.q[k * nq..(k + 1) * nq],
            &self.v[k * nv..(k + 1) * nv],
            &self.a[k * nv..(k + 1) * nv],
        );
        let orientation = UnitQuaternion::from_quaternion(Quaternion::new(q[6], q[3], q[4], q[5]));
        let twist = |x: &[f64]| {
            Motion::new(
                Vector3::new(x[3], x[4], x[5]),
                Vector3::new(x[0], x[1], x[2]),
            )
        };
        let base = BaseState {
            pose: Transform::from_pose(
                orientation.to_rotation_matrix().matrix(),
                &Vector3::new(q[0], q[1], q[2]),
            ),
            v: twist(v),
            a: twist(a),
        };
        (base, [&q[7..], &v[6..], &a[6..]])
    }
}

/// The samples of the configurations `q` (`7 + n` each) and of `others` (as many each), every
/// value finite and every quaternion of unit norm (within 1e-6).
fn configurations(
    q: &[f64],
    n: usize,
    others: &[(&'static str, &[f64], usize)],
) -> Result<usize, ApiError> {
    let count = samples_of_widths(("q", q, 7 + n), others)?;
    for (k, x) in q.chunks_exact(7 + n).enumerate() {
        let norm = x[3..7].iter().map(|c| c * c).sum::<f64>().sqrt();
        if (norm - 1.0).abs() > 1e-6 {
            return Err(ApiError::Options(format!(
                "q: sample {k}: the quaternion (entries 3..7: qx, qy, qz, qw) has norm {norm:.9}, not 1"
            )));
        }
    }
    Ok(count)
}

/// physid's floating row order `[ω-row (moment), v-row (force), joints]` to pinocchio's
/// `[force, moment, joints]`: row `i` of the result is physid's row `pinocchio_row(i)`.
fn pinocchio_row(i: usize) -> usize {
    match i {
        0..3 => i + 3,
        3..6 => i - 3,
        _ => i,
    }
}

/// A floating robot's inverse dynamics per sample, pinocchio's `rnea` of the free flyer: the
/// wrench on the trunk (N, then N m; trunk axes) and the joint torques (N m), `samples × (6 +
/// n)`; friction not included. States as [`FloatingStates`] describes.
pub fn floating_inverse_dynamics(
    robot: &FloatingModel,
    q: &[f64],
    v: &[f64],
    a: &[f64],
) -> Result<Vec<f64>, ApiError> {
    let x = FloatingStates::new(robot, q, v, a)?;
    let nv = 6 + x.n;
    Ok(per_sample(robot.tree(), x.count, nv, |data, k, out| {
        let (base, [q, qd, qdd]) = x.at(k);
        let f_b = rnea_floating(robot, data, &base, q, qd, qdd);
        let tau = stacked(&f_b, &data.tau);
        for (i, o) in out.iter_mut().enumerate() {
            *o = tau[pinocchio_row(i)];
        }
    }))
}

/// A floating robot's mass matrix per sample (pinocchio's `crba` of the free flyer, both
/// triangles), `samples × (6 + n) × (6 + n)`, rows and columns in pinocchio's velocity order.
/// `q` as [`FloatingStates`] describes (the configuration alone).
pub fn floating_mass_matrices(robot: &FloatingModel, q: &[f64]) -> Result<Vec<f64>, ApiError> {
    let n = robot.joints();
    let count = configurations(q, n, &[])?;
    let (nq, nv) = (7 + n, 6 + n);
    Ok(per_sample(robot.tree(), count, nv * nv, |data, k, out| {
        // The mass matrix depends on the joints alone, not on the trunk's pose.
        let m = crba_floating(robot, data, &q[k * nq + 7..(k + 1) * nq]);
        for i in 0..nv {
            for j in 0..nv {
                out[i * nv + j] = m[(pinocchio_row(i), pinocchio_row(j))];
            }
        }
    }))
}

/// A floating robot's regressor per sample, `Y θ` = [`floating_inverse_dynamics`] plus the
/// joints' friction with θ the robot's parameters (`[π_trunk; θ_tree]`, `parameter_names`
/// order, the viscous and Coulomb friction columns last): `samples × (6 + n) × p`, rows in
/// pinocchio's order.
pub fn floating_regressors(
    robot: &FloatingModel,
    q: &[f64],
    v: &[f64],
    a: &[f64],
) -> Result<Vec<f64>, ApiError> {
    let x = FloatingStates::new(robot, q, v, a)?;
    let (nv, p) = (6 + x.n, robot.parameter_count());
    Ok(per_sample(robot.tree(), x.count, nv * p, |data, k, out| {
        let (base, [q, qd, qdd]) = x.at(k);
        let mut y = DMatrix::zeros(nv, p);
        regressor_floating(robot, data, &base, (q, qd, qdd), &mut y);
        for i in 0..nv {
            for j in 0..p {
                out[i * p + j] = y[(pinocchio_row(i), j)];
            }
        }
    }))
}
