//! The inertial-parameter regressor `Y(q, q̇, q̈)` with rotor and friction columns, so that
//! `τ + B q̇ + B_c sign(q̇) = Y θ` exactly (paper eq. 4 and 9).
//!
//! Body `i` contributes to joint `k` (for `k` in the support of `i`) the power-like product
//! `S_kᵀ f_i` with `f_i = I_i a_i + v_i ×* I_i v_i`. Writing `ⁱS_k` for joint `k`'s axis in body
//! `i` coordinates and using `(v×*) = −(v×)ᵀ`:
//!
//! `S_kᵀ f_i = ⁱS_kᵀ I_i a_i − (v_i × ⁱS_k)ᵀ I_i v_i = (K(ⁱS_k, a_i) − K(v_i × ⁱS_k, v_i)) · π_i`
//!
//! where `K(u, w)` is the linear form with `uᵀ I(π) w = K(u, w) · π` ([`inertia_bilinear`]).
//! Each row block therefore costs ten multiply-adds per (body, ancestor) pair, with no 6×10
//! matrices carried up the tree. Rotors are handled the same way in rotor coordinates.

use super::{check_len, forward_pass, sign, Data};
use crate::model::{Model, RotorModel};
use crate::spatial::Motion;
use crate::trajectory::Trajectory;
use nalgebra::DMatrix;

/// Calls `f(k, Y_k)` with the regressor of every sample `k` in `range` of `tr`, which must carry
/// q̈ (one workspace and one output matrix for the whole range).
pub fn for_each_regressor(
    model: &Model,
    tr: &Trajectory,
    range: std::ops::Range<usize>,
    f: &mut dyn FnMut(usize, &DMatrix<f64>),
) {
    let mut d = Data::new(model);
    let mut y = DMatrix::zeros(model.dof(), model.layout().len);
    for k in range {
        regressor(
            model,
            &mut d,
            tr.q_at(k),
            tr.qd_at(k),
            tr.qdd_at(k).expect("q̈ present"),
            &mut y,
        );
        f(k, &y);
    }
}

/// `K(u, w)`: the ten coefficients with `uᵀ I(π) w = K(u, w) · π` for the paper's `π` order.
///
/// `uᵀ I w = m v_u·v_w + h·(v_w × ω_u + v_u × ω_w) + ω_uᵀ Ī ω_w`.
#[inline]
pub fn inertia_bilinear(u: &Motion, w: &Motion) -> [f64; 10] {
    let (a, b) = (&u.ang, &w.ang);
    let hc = w.lin.cross(&u.ang) + u.lin.cross(&w.ang);
    [
        u.lin.dot(&w.lin),
        hc.x,
        hc.y,
        hc.z,
        a.x * b.x,
        a.x * b.y + a.y * b.x,
        a.x * b.z + a.z * b.x,
        a.y * b.y,
        a.y * b.z + a.z * b.y,
        a.z * b.z,
    ]
}

/// One row block: `K(s, a) − K(v × s, v)`, the coefficients of `sᵀ (I a + v ×* I v)`.
#[inline]
pub(crate) fn row_block(s: &Motion, v: &Motion, a: &Motion) -> [f64; 10] {
    let k1 = inertia_bilinear(s, a);
    let k2 = inertia_bilinear(&v.cross_motion(s), v);
    std::array::from_fn(|c| k1[c] - k2[c])
}

/// A column-major output matrix of `rows` rows, written at an offset: entry `(r, c)` of a
/// block goes to `(row0 + r, col0 + c)` (the fixed-base regressor at `(0, 0)`, the joint rows
/// of the floating-base one below the trunk's six and right of its ten columns).
pub(crate) struct Block<'a> {
    pub(crate) y: &'a mut [f64],
    pub(crate) rows: usize,
    pub(crate) row0: usize,
    pub(crate) col0: usize,
}

impl Block<'_> {
    /// Writes ten coefficients into row `row`, columns `col..col + 10`.
    #[inline]
    pub(crate) fn put(&mut self, row: usize, col: usize, vals: &[f64; 10]) {
        for (c, v) in vals.iter().enumerate() {
            self.y[(self.col0 + col + c) * self.rows + self.row0 + row] = *v;
        }
    }

    /// Writes one value at `(row, col)`.
    #[inline]
    fn set(&mut self, row: usize, col: usize, v: f64) {
        self.y[(self.col0 + col) * self.rows + self.row0 + row] = v;
    }
}

/// Fills `y` (`n × p`, see [`crate::model::ParamLayout`]) with the regressor at `(q, q̇, q̈)`,
/// gravity included. Friction columns: `q̇_k` (viscous) and `sign(q̇_k)` with `sign(0) = 0`.
pub fn regressor(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
    y: &mut DMatrix<f64>,
) {
    check_len(model, "q", q);
    check_len(model, "qd", qd);
    check_len(model, "qdd", qdd);
    let n = model.dof();
    assert_eq!(
        y.shape(),
        (n, model.layout().len),
        "regressor output has the wrong shape"
    );
    forward_pass(model, data, q, qd, qdd, true);
    let y = y.as_mut_slice();
    y.fill(0.0);
    let mut out = Block {
        y,
        rows: n,
        row0: 0,
        col0: 0,
    };
    joint_rows(model, data, qd, qdd, &mut out);
}

/// The joint rows of the regressor on the velocities and accelerations in `data` (after a
/// forward pass), into `out` (zeroed by the caller); also fills `data.s_anc`.
pub(crate) fn joint_rows(model: &Model, data: &mut Data, qd: &[f64], qdd: &[f64], out: &mut Block) {
    let n = model.dof();
    let layout = model.layout();
    let full = model.rotor_model() == RotorModel::Full;
    for i in 0..n {
        let b = &model.bodies()[i];
        ancestor_axes(model, data, i);
        let (v, a) = (data.v[i], data.a[i]);
        for &k in model.support(i) {
            out.put(k, 10 * i, &row_block(&data.s_anc[i * n + k], &v, &a));
        }
        if let (Some(col), Some(r)) = (layout.rotor_col[i], &b.rotor) {
            let (vr, ar) = (data.v_rot[i], data.a_rot[i]);
            if full {
                out.put(i, col, &row_block(&data.s_rot[i], &vr, &ar));
            } else {
                let s = r.motion_subspace();
                out.put(i, col, &inertia_bilinear(&s, &s).map(|c| c * qdd[i]));
            }
            if let Some(p) = b.parent {
                for &k in model.support(p) {
                    let s = data.x_rot[i].apply_motion(&data.s_anc[p * n + k]);
                    out.put(k, col, &row_block(&s, &vr, &ar));
                }
            }
        }
        out.set(i, layout.viscous_col + i, qd[i]);
        out.set(i, layout.coulomb_col + i, sign(qd[i]));
    }
}

/// `data.s_anc` of body `i`: the joint axes of its support in body `i` coordinates, from its
/// parent's (filled first, as a parent precedes its children) and the transforms in `data`.
pub(crate) fn ancestor_axes(model: &Model, data: &mut Data, i: usize) {
    let n = model.dof();
    data.s_anc[i * n + i] = data.s[i];
    if let Some(p) = model.bodies()[i].parent {
        for &k in model.support(p) {
            data.s_anc[i * n + k] = data.x_up[i].apply_motion(&data.s_anc[p * n + k]);
        }
    }
}

/// The columns of each joint's row of the regressor that can be nonzero, ascending: row `k`
/// holds the ten parameters of every body `i` whose support contains `k` (the subtree of `k`),
/// the rotors on those bodies' joints, and joint `k`'s own friction columns; every other entry
/// of row `k` is zero at every `(q, q̇, q̈)`. Used to accumulate `YᵀY` joint by joint over only
/// these columns.
pub fn row_columns(model: &Model) -> Vec<Vec<usize>> {
    let n = model.dof();
    let layout = model.layout();
    let mut cols = vec![vec![]; n];
    for i in 0..n {
        for &k in model.support(i) {
            cols[k].extend(10 * i..10 * i + 10);
            if let Some(c) = layout.rotor_col[i] {
                cols[k].extend(c..c + 10);
            }
        }
    }
    for (k, row) in cols.iter_mut().enumerate() {
        row.push(layout.viscous_col + k);
        row.push(layout.coulomb_col + k);
        row.sort_unstable();
    }
    cols
}
