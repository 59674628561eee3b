//! Floating-base dynamics: the tree's RNEA, CRBA and regressor with its root (the trunk) moving,
//! plus the trunk's own ten parameters and six rows (RBDA §9.3, written as in RNEA).
//!
//! With `ν = [v_B; q̇]` ([`crate::model::floating`]), the equations of motion are
//! `M(q) ν̇ + h(q, ν) = [0; τ] + Σ_c J_cᵀ λ_c`: the trunk is unactuated, contact forces `λ_c`
//! act through the contact Jacobians. [`rnea_floating`] returns the left side, the wrench on
//! the trunk `f_B` (its six rows) and the joint torques `τ_ID` that produce the given motion; a
//! robot in contact has `f_B = Σ_c J_c,Bᵀ λ_c` and `τ = τ_ID − Σ_c J_c,qᵀ λ_c`.
//!
//! The trunk's motion enters the tree's forward pass as its root's: `v_0 = v_B` and
//! `a_0 = a_B − ᴮX_W [0; g]` (fictitious gravity, trunk coordinates), after which every body and
//! rotor moves as in the fixed-base algorithms. The backward pass ends in the wrench the trunk
//! exerts on the tree, `f_root`; the trunk's own `I_B a_0 + v_B ×* I_B v_B` is added to it.
//! For the regressor, the trunk's six unit motions are "joints" of every body: body `i`'s base
//! row block is `K(ⁱX_0 e_j, a_i) − K(v_i × ⁱX_0 e_j, v_i)`, as for an ancestor joint.

use super::regressor::{joint_rows, row_block, Block};
use super::rnea::backward_pass;
use super::{check_len, crba, forward_pass_from_root, kinematics, update_transforms, Data};
use crate::model::floating::FloatingModel;
use crate::model::RotorModel;
use crate::spatial::{skew, Force, Motion, Transform};
use nalgebra::{DMatrix, DVector, Vector3, Vector6};

/// Where the trunk is and how it moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BaseState {
    /// `ᴮX_W`, world to trunk coordinates: `e` rotates world vectors into the trunk frame and
    /// `r` is the trunk origin's position in the world (m) ([`Transform::from_pose`] of the
    /// trunk's orientation and position).
    pub pose: Transform,
    /// Trunk spatial velocity `[ω; v]` in trunk coordinates (rad/s, m/s).
    pub v: Motion,
    /// Its time derivative `v̇_B` in trunk coordinates (rad/s², m/s²), gravity not included.
    pub a: Motion,
}

impl BaseState {
    /// The trunk at rest at the world origin, axes aligned.
    pub fn at_rest() -> Self {
        Self {
            pose: Transform::identity(),
            v: Motion::zero(),
            a: Motion::zero(),
        }
    }

    /// The root motion for the tree: `v_0 = v_B`, `a_0 = v̇_B − [0; E g]` (trunk coordinates).
    fn root_motion(&self, gravity_world: &Vector3<f64>) -> (Motion, Motion) {
        let g = Motion::new(Vector3::zeros(), self.pose.e * gravity_world);
        (self.v, self.a - g)
    }
}

/// Inverse dynamics of the floating robot for joint vectors `q`, `qd`, `qdd` (length `n`) and
/// the trunk's `base`: returns the wrench on the trunk `f_B = [n; f]` (trunk coordinates, N m
/// and N) with the joint torques in `data.tau` (N m), rotors as in the fixed-base RNEA.
pub fn rnea_floating(
    robot: &FloatingModel,
    data: &mut Data,
    base: &BaseState,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> Force {
    let tree = robot.tree();
    check_len(tree, "q", q);
    check_len(tree, "qd", qd);
    check_len(tree, "qdd", qdd);
    update_transforms(tree, data, q);
    let (v0, a0) = base.root_motion(&tree.gravity());
    forward_pass_from_root(tree, data, qd, qdd, (v0, a0));
    backward_pass(tree, data, qdd);
    let i_b = robot.trunk().inertia.rigid();
    i_b.mul_motion(&a0) + v0.cross_force(&i_b.mul_motion(&v0)) + data.f_root
}

/// The floating-base regressor at the state, into `y` (`(6 + n) × (10 + p)`): rows the trunk
/// wrench `[n; f]` then the joints, columns `θ = [π_trunk; θ_tree]`, so that
/// `y θ = [f_B; τ_ID + friction]` of [`rnea_floating`].
pub fn regressor_floating(
    robot: &FloatingModel,
    data: &mut Data,
    base: &BaseState,
    (q, qd, qdd): (&[f64], &[f64], &[f64]),
    y: &mut DMatrix<f64>,
) {
    let tree = robot.tree();
    check_len(tree, "q", q);
    check_len(tree, "qd", qd);
    check_len(tree, "qdd", qdd);
    let rows = robot.dof();
    assert_eq!(
        y.shape(),
        (rows, robot.parameter_count()),
        "floating-base regressor output has the wrong shape"
    );
    kinematics::update_world(tree, data, q);
    let (v0, a0) = base.root_motion(&tree.gravity());
    forward_pass_from_root(tree, data, qd, qdd, (v0, a0));
    let y = y.as_mut_slice();
    y.fill(0.0);
    let mut out = Block {
        y,
        rows,
        row0: 6,
        col0: 10,
    };
    joint_rows(tree, data, qd, qdd, &mut out);
    out.row0 = 0;
    out.col0 = 0;
    let unit = unit_motions();
    for (j, e) in unit.iter().enumerate() {
        out.put(j, 0, &row_block(e, &v0, &a0));
    }
    base_rows_of_tree(robot, data, &unit, &mut out);
}

/// The trunk rows of the tree's bodies and rotors: body `i` (and the rotor on its parent)
/// sees the trunk's unit motions in its own coordinates, `ⁱX_0 e_j`.
fn base_rows_of_tree(robot: &FloatingModel, data: &Data, unit: &[Motion; 6], out: &mut Block) {
    let tree = robot.tree();
    let layout = tree.layout();
    for (i, b) in tree.bodies().iter().enumerate() {
        let x_i0 = &data.x_world[i];
        for (j, e) in unit.iter().enumerate() {
            out.put(
                j,
                10 + 10 * i,
                &row_block(&x_i0.apply_motion(e), &data.v[i], &data.a[i]),
            );
        }
        if let (Some(col), Some(_)) = (layout.rotor_col[i], &b.rotor) {
            let x_r0 = match b.parent {
                Some(p) => data.x_rot[i].compose(&data.x_world[p]),
                None => data.x_rot[i],
            };
            let (vr, ar) = (data.v_rot[i], data.a_rot[i]);
            // (The reflected model's armature acts on the joint row alone.)
            for (j, e) in unit.iter().enumerate() {
                out.put(j, 10 + col, &row_block(&x_r0.apply_motion(e), &vr, &ar));
            }
        }
    }
}

/// The six unit motions `e_j` of the trunk, `[ω; v]` order.
fn unit_motions() -> [Motion; 6] {
    std::array::from_fn(|j| {
        let mut e = Vector6::zeros();
        e[j] = 1.0;
        Motion::from_vec6(&e)
    })
}

/// The floating-base mass matrix `M(q)` (`(6 + n) × (6 + n)`, `ν = [v_B; q̇]`): the tree's
/// joint-space `H` (its CRBA), the trunk block `I^c_0` (the whole robot's composite inertia in
/// trunk coordinates) and the coupling `F_i = ⁰X_iᵀ I^c_i S_i` (plus each full rotor's
/// `X_rotᵀ I_rot S_rot` carried to the trunk). It depends on `q` only, not on the trunk's pose.
pub fn crba_floating(robot: &FloatingModel, data: &mut Data, q: &[f64]) -> DMatrix<f64> {
    let tree = robot.tree();
    let n = tree.dof();
    crba(tree, data, q);
    let mut m = DMatrix::zeros(6 + n, 6 + n);
    m.view_mut((6, 6), (n, n)).copy_from(&data.h);
    let mut ic0 = robot.trunk().inertia.rigid();
    let full = tree.rotor_model() == RotorModel::Full;
    for (i, b) in tree.bodies().iter().enumerate() {
        if b.parent.is_none() {
            ic0 = ic0.add(&data.ic[i].expressed_in_parent(&data.x_up[i]));
            if b.rotor.is_some() {
                ic0 = ic0.add(&data.inertia_rot[i].expressed_in_parent(&data.x_rot[i]));
            }
        }
        let mut f = to_root(tree, data, i, data.ic[i].mul_motion(&data.s[i]));
        if b.rotor.is_some() && full {
            let f_rot =
                data.x_rot[i].inv_apply_force(&data.inertia_rot[i].mul_motion(&data.s_rot[i]));
            f += match b.parent {
                Some(p) => to_root(tree, data, p, f_rot),
                None => f_rot,
            };
        }
        m.view_mut((0, 6 + i), (6, 1)).copy_from(&f.to_vec6());
        m.view_mut((6 + i, 0), (1, 6))
            .copy_from(&f.to_vec6().transpose());
    }
    let unit = unit_motions();
    for (j, e) in unit.iter().enumerate() {
        m.view_mut((0, j), (6, 1))
            .copy_from(&ic0.mul_motion(e).to_vec6());
    }
    m
}

/// A force `f` on body `i` (its coordinates) carried to the root: `⁰X_iᵀ f`.
fn to_root(tree: &crate::model::Model, data: &Data, i: usize, mut f: Force) -> Force {
    let mut j = i;
    loop {
        f = data.x_up[j].inv_apply_force(&f);
        match tree.bodies()[j].parent {
            Some(p) => j = p,
            None => return f,
        }
    }
}

/// The 3 × (6 + n) Jacobian of the point `p` fixed in `body` (body coordinates, m): its world
/// velocity is `J ν`. The trunk columns are `R_WB [−[p_B]×  1]` with `p_B` the point in trunk
/// coordinates; the joint columns the fixed-base point Jacobian's, rotated into the world.
/// Contact forces `λ` (world coordinates, N) at the point enter the equations as `Jᵀ λ`.
pub fn point_jacobian_floating(
    robot: &FloatingModel,
    data: &mut Data,
    base: &BaseState,
    q: &[f64],
    (body, p): (usize, &Vector3<f64>),
) -> DMatrix<f64> {
    let tree = robot.tree();
    kinematics::update_world(tree, data, q);
    let p_b = kinematics::point_position(data, body, p);
    let r_wb = base.pose.e.transpose();
    let n = tree.dof();
    let mut jac = DMatrix::zeros(3, 6 + n);
    jac.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(r_wb * -skew(&p_b)));
    jac.fixed_view_mut::<3, 3>(0, 3).copy_from(&r_wb);
    let joints = kinematics::point_jacobian(tree, data, body, p);
    jac.view_mut((0, 6), (3, n)).copy_from(&(r_wb * joints));
    jac
}

/// `[f_B; τ]` as one vector of length `6 + n` (trunk rows first), for tests and callers that
/// work with the whole equation.
pub fn stacked(f_b: &Force, tau: &DVector<f64>) -> DVector<f64> {
    DVector::from_iterator(
        6 + tau.len(),
        f_b.to_vec6().iter().chain(tau.iter()).copied(),
    )
}
