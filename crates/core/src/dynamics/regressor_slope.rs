//! The slope of a weighted regressor, `∂⟨W, Y(q, q̇, q̈)⟩ / ∂(q_j, q̇_j, q̈_j)` for every joint
//! `j`, by one reverse sweep through the forward pass and the row blocks (the adjoint of
//! [`regressor`](super::regressor)): about two regressors' work for all `3n` partials, where
//! differences take `3n + 1` regressors.
//!
//! `⟨W, Y⟩ = Σ_i Σ_{k ∈ κ(i)} T(ⁱS_k, v_i, a_i; π_ik)` plus the rotors' and the viscous
//! columns' terms, where `π_ik` is `W`'s row `k` on body `i`'s ten columns and
//! `T(s, v, a; π) = sᵀ I(π) a − (v × s)ᵀ I(π) v` (the row block). Its partials are
//! `∂T/∂a = I s`, `∂T/∂s = I a + v ×* I v`, `∂T/∂v = I (s × v) − s ×* I v`, and the forward
//! pass `v_i = X_i v_λ + S_i q̇_i`, `a_i = X_i a_λ + S_i q̈_i + v_i × S_i q̇_i`,
//! `ⁱS_k = X_i ^λS_k` is followed back with `∂X_i/∂q_i = −(S_i ×) X_i` (a rotor's
//! `X_rot = X_J(N q_i) X_rot,0` likewise with `S_rot`). Adjoints of motions are forces:
//! `Xᵀ f` carries one from child to parent ([`Transform::inv_apply_force`]).

use super::regressor::ancestor_axes;
use super::{base_acceleration, check_len, forward_pass, Data};
use crate::model::{Model, RotorModel};
use crate::spatial::{Force, Motion, RigidInertia, Transform};
use nalgebra::{DMatrix, Matrix3, Vector3};

/// `[∂/∂q_j, ∂/∂q̇_j, ∂/∂q̈_j]` of `⟨W, Y(q, q̇, q̈)⟩` for each joint `j` (`W` is `n × p` like
/// `Y`; per rad, rad/s, rad/s² of the joint). The Coulomb columns `sign(q̇)` contribute
/// nothing (their slope is zero wherever it exists); gravity is included as in `Y`. Leaves
/// `data` holding the forward pass at `(q, q̇, q̈)`.
pub fn weighted_regressor_slope(
    model: &Model,
    data: &mut Data,
    [q, qd, qdd]: [&[f64]; 3],
    w: &DMatrix<f64>,
) -> Vec<[f64; 3]> {
    check_len(model, "q", q);
    check_len(model, "qd", qd);
    check_len(model, "qdd", qdd);
    let n = model.dof();
    assert_eq!(
        w.shape(),
        (n, model.layout().len),
        "the weight must have the regressor's shape"
    );
    forward_pass(model, data, q, qd, qdd, true);
    for i in 0..n {
        ancestor_axes(model, data, i);
    }
    let mut adj = Adjoint::new(n);
    for i in (0..n).rev() {
        adj.body_rows(model, data, w, i);
        adj.rotor(model, data, w, (i, qd[i]));
        adj.body(model, data, (i, qd[i]));
        adj.out[i][1] += w[(i, model.layout().viscous_col + i)];
    }
    adj.out
}

/// `I(π)` of ten entries of `W` in the paper's order `[m, h, Ixx, Ixy, Ixz, Iyy, Iyz, Izz]`
/// (any numbers: only its linearity is used).
fn inertia_of(w: &DMatrix<f64>, row: usize, col: usize) -> RigidInertia {
    let e = |c: usize| w[(row, col + c)];
    RigidInertia {
        m: e(0),
        h: Vector3::new(e(1), e(2), e(3)),
        ibar: Matrix3::new(e(4), e(5), e(6), e(5), e(7), e(8), e(6), e(8), e(9)),
    }
}

/// The motion `−S × x`: `∂(X(q) m)/∂q` for `x = X(q) m` and a joint of axis `S`.
fn turned(s: &Motion, x: &Motion) -> Motion {
    -s.cross_motion(x)
}

/// Adjoints of the forward pass's motions (forces) and the partials found so far.
struct Adjoint {
    n: usize,
    /// `∂⟨W, Y⟩/∂v_i`, `∂/∂a_i`, `∂/∂(ⁱS_k)` (at `i · n + k`).
    v: Vec<Force>,
    a: Vec<Force>,
    s: Vec<Force>,
    out: Vec<[f64; 3]>,
}

/// The adjoints a row block `T(s, v, a; I)` adds: to `v`, to `a`, and to `s`.
fn row_adjoints(inertia: &RigidInertia, s: &Motion, v: &Motion, a: &Motion) -> [Force; 3] {
    let iv = inertia.mul_motion(v);
    [
        inertia.mul_motion(&s.cross_motion(v)) - s.cross_force(&iv),
        inertia.mul_motion(s),
        inertia.mul_motion(a) + v.cross_force(&iv),
    ]
}

/// One link of the forward pass, `v = X v_λ + S q̇`, `a = X a_λ + S q̈ + v × S q̇`, and its
/// axes `X ^λS_k`, as the adjoint sweep needs it: the transform, the joint axis and rate, the
/// parent's motion (the base's for the root).
struct Link<'a> {
    x: &'a Transform,
    s: Motion,
    qd: f64,
    v: Motion,
    parent: (Motion, Motion),
}

/// What following one [`Link`] back gives: the parent's adjoints (velocity, acceleration)
/// and the partials in `q`, `q̇`, `q̈` of the joint.
struct Back {
    v_parent: Force,
    a_parent: Force,
    slope: [f64; 3],
}

impl Link<'_> {
    /// The link followed back from the adjoints `(v̄, ā)` of its velocity and acceleration.
    fn back(&self, v_bar: Force, a_bar: Force) -> Back {
        let (x, s) = (self.x, &self.s);
        let vj = *s * self.qd;
        let (x_v, x_a) = (
            x.apply_motion(&self.parent.0),
            x.apply_motion(&self.parent.1),
        );
        // Through a = X a_λ + S q̈ + v × S q̇ first: it adds to v̄.
        let v_bar = v_bar + vj.cross_force(&a_bar);
        let dq = turned(s, &x_a).dot(&a_bar) + turned(s, &x_v).dot(&v_bar);
        let dqd = self.v.cross_motion(s).dot(&a_bar) + s.dot(&v_bar);
        Back {
            v_parent: x.inv_apply_force(&v_bar),
            a_parent: x.inv_apply_force(&a_bar),
            slope: [dq, dqd, s.dot(&a_bar)],
        }
    }
}

impl Adjoint {
    fn new(n: usize) -> Self {
        Adjoint {
            n,
            v: vec![Force::zero(); n],
            a: vec![Force::zero(); n],
            s: vec![Force::zero(); n * n],
            out: vec![[0.0; 3]; n],
        }
    }

    /// Body `i`'s row blocks, one per joint of its support.
    fn body_rows(&mut self, model: &Model, data: &Data, w: &DMatrix<f64>, i: usize) {
        let n = self.n;
        let (v, a) = (data.v[i], data.a[i]);
        for &k in model.support(i) {
            let inertia = inertia_of(w, k, 10 * i);
            let [dv, da, ds] = row_adjoints(&inertia, &data.s_anc[i * n + k], &v, &a);
            self.v[i] += dv;
            self.a[i] += da;
            self.s[i * n + k] += ds;
        }
    }

    /// The parent's motion of body `i` (the base's, gravity included, at the root).
    fn parent_motion(model: &Model, data: &Data, i: usize) -> (Motion, Motion) {
        match model.bodies()[i].parent {
            Some(p) => (data.v[p], data.a[p]),
            None => (Motion::zero(), base_acceleration(model)),
        }
    }

    /// Body `i`'s link of the forward pass followed back to its parent, its axes too.
    fn body(&mut self, model: &Model, data: &Data, (i, qd): (usize, f64)) {
        let n = self.n;
        let link = Link {
            x: &data.x_up[i],
            s: data.s[i],
            qd,
            v: data.v[i],
            parent: Self::parent_motion(model, data, i),
        };
        let back = link.back(self.v[i], self.a[i]);
        self.add_slope(i, back.slope);
        let Some(p) = model.bodies()[i].parent else {
            return;
        };
        self.v[p] += back.v_parent;
        self.a[p] += back.a_parent;
        for &k in model.support(p) {
            let s_bar = self.s[i * n + k];
            self.out[i][0] += turned(&data.s[i], &data.s_anc[i * n + k]).dot(&s_bar);
            self.s[p * n + k] += data.x_up[i].inv_apply_force(&s_bar);
        }
    }

    /// The rotor of joint `i` (on body `i`'s parent): its row blocks and its link.
    fn rotor(&mut self, model: &Model, data: &Data, w: &DMatrix<f64>, (i, qd): (usize, f64)) {
        let (Some(col), Some(r)) = (model.layout().rotor_col[i], &model.bodies()[i].rotor) else {
            return;
        };
        let n = self.n;
        let inertia = |k: usize| inertia_of(w, k, col);
        let (vr, ar, x_rot) = (data.v_rot[i], data.a_rot[i], &data.x_rot[i]);
        let (mut v_bar, mut a_bar) = (Force::zero(), Force::zero());
        if model.rotor_model() == RotorModel::Full {
            let [dv, da, _] = row_adjoints(&inertia(i), &data.s_rot[i], &vr, &ar);
            (v_bar, a_bar) = (dv, da);
        } else {
            // Reflected: the rotor's own row is `K(S, S) q̈_i`, its spin on the diagonal.
            let s = r.motion_subspace();
            let k = crate::dynamics::inertia_bilinear(&s, &s);
            let pi = (0..10).map(|c| w[(i, col + c)]);
            self.out[i][2] += k.iter().zip(pi).map(|(k, p)| k * p).sum::<f64>();
        }
        let parent = model.bodies()[i].parent;
        // The rows of the parent's support, on its axes carried into rotor coordinates.
        if let Some(p) = parent {
            for &k in model.support(p) {
                let s = x_rot.apply_motion(&data.s_anc[p * n + k]);
                let [dv, da, ds] = row_adjoints(&inertia(k), &s, &vr, &ar);
                v_bar += dv;
                a_bar += da;
                self.out[i][0] += turned(&data.s_rot[i], &s).dot(&ds);
                self.s[p * n + k] += x_rot.inv_apply_force(&ds);
            }
        }
        let link = Link {
            x: x_rot,
            s: data.s_rot[i],
            qd,
            v: vr,
            parent: Self::parent_motion(model, data, i),
        };
        let back = link.back(v_bar, a_bar);
        self.add_slope(i, back.slope);
        if let Some(p) = parent {
            self.v[p] += back.v_parent;
            self.a[p] += back.a_parent;
        }
    }

    /// Adds partials in joint `i`'s `q`, `q̇`, `q̈`.
    fn add_slope(&mut self, i: usize, slope: [f64; 3]) {
        for (o, d) in self.out[i].iter_mut().zip(slope) {
            *o += d;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::regressor;
    use crate::model::random::{random_state, random_tree};
    use crate::model::{cheetah3, RotorModel};

    /// `⟨W, Y⟩` at a state.
    fn weighted(model: &Model, w: &DMatrix<f64>, state: &[Vec<f64>; 3]) -> f64 {
        let mut data = Data::new(model);
        let mut y = DMatrix::zeros(model.dof(), model.layout().len);
        regressor(model, &mut data, &state[0], &state[1], &state[2], &mut y);
        w.dot(&y)
    }

    /// Central differences of `⟨W, Y⟩` in each joint's `q`, `q̇`, `q̈`.
    fn differences(model: &Model, w: &DMatrix<f64>, state: &[Vec<f64>; 3]) -> Vec<[f64; 3]> {
        let h = 1e-6;
        (0..model.dof())
            .map(|j| {
                std::array::from_fn(|d| {
                    let at = |by: f64| {
                        let mut s = state.clone();
                        s[d][j] += by;
                        weighted(model, w, &s)
                    };
                    (at(h) - at(-h)) / (2.0 * h)
                })
            })
            .collect()
    }

    fn check(model: &Model, seed: u64) {
        let n = model.dof();
        let p = model.layout().len;
        let mut state = random_state(seed, n, 1.5);
        // Joint speeds away from zero: the Coulomb columns' sign does not flip within a step.
        for v in state[1].iter_mut() {
            *v += 0.1_f64.copysign(*v);
        }
        let w = DMatrix::from_fn(n, p, |i, c| {
            ((7 * i + 3 * c + seed as usize) % 11) as f64 - 5.0
        });
        let mut data = Data::new(model);
        let slope =
            weighted_regressor_slope(model, &mut data, [&state[0], &state[1], &state[2]], &w);
        let fd = differences(model, &w, &state);
        let scale = fd.iter().flatten().fold(1.0_f64, |m, v| m.max(v.abs()));
        for (j, (a, b)) in slope.iter().zip(&fd).enumerate() {
            for d in 0..3 {
                assert!(
                    (a[d] - b[d]).abs() <= 1e-6 * scale,
                    "joint {j}, state {d}: adjoint {} against differences {} (scale {scale})",
                    a[d],
                    b[d]
                );
            }
        }
    }

    #[test]
    fn the_adjoint_slope_is_the_differences_on_the_leg_with_and_without_rotors() {
        let leg = cheetah3::leg();
        check(&leg, 1);
        check(&leg.clone().with_rotor_model(RotorModel::Reflected), 2);
        check(&leg.without_rotors(), 3);
    }

    #[test]
    fn the_adjoint_slope_is_the_differences_on_random_trees() {
        // Branches, prismatic joints, rotors of either gear sign, sliding rotors.
        for seed in 0..12 {
            let tree = random_tree(seed, 3 + (seed as usize % 5));
            check(&tree, seed);
            check(&tree.with_rotor_model(RotorModel::Reflected), seed + 100);
        }
    }
}
