//! The design's optimizer: sequential quadratic programming in a trust region over the Fourier
//! coefficients, the kinematic limits as linear constraints.
//!
//! - **Variables.** `x = (a_jl, b_jl)`, joint-major (all `a`, then all `b`), optimized as
//!   `y_i = x_i ω_l² / Ā_j` (each coefficient's peak acceleration over joint `j`'s acceleration
//!   limit), so that one step size suits every harmonic and joint.
//! - **Gradient** of the objective `φ(F)` by the chain rule, analytic throughout:
//!   `dφ = ⟨Φ, dF⟩` with `Φ = ∂φ/∂F` (`F⁻¹/r` for D-optimality),
//!   `dF = Vᵀ D⁻¹ (Σ_k dY_kᵀ Y_k + Y_kᵀ dY_k) D⁻¹ V / K`, so `∂φ/∂s_k = (2/K) ⟨Y_k M, ∂Y_k/∂s_k⟩`
//!   with `M = D⁻¹ V Φ Vᵀ D⁻¹` for each of a sample's `3n` states `s_k` (`q_j`, `q̇_j`, `q̈_j`),
//!   all `3n` by one reverse sweep of the regressor ([`weighted_regressor_slope`]), then
//!   through the Fourier series, linear in `x`: about three regressors per sample instead of
//!   `2nL + 1` objective evaluations (the design's Coulomb columns are smooth,
//!   [`super::design_regressor`]).
//! - **Limits.** Position, speed, acceleration and jerk at the check times (`K` per period of
//!   the steady motion and over both ramps) are linear in `x`, windowed or not: each step keeps
//!   them at those times. The rows near their limit enter the subproblem; any other row its
//!   solution would break is added and the subproblem solved again. A trial is then shrunk
//!   (never grown) into the limits on the final check's grid of `4 K` points, and refused where
//!   its torque leaves the effort limits.
//! - **Step.** `max gᵀd − ½ dᵀBd` over the box `‖d‖∞ ≤ ρ` within the limits (a convex QP, by
//!   Clarabel), `B` a damped BFGS model of `−∇²φ`; the step is taken where the objective gains
//!   at least `1e-4` of the model's prediction (far from the optimum `log det` curves faster
//!   than the model), and `ρ` grows or shrinks with that ratio; the steps end when the predicted
//!   gain falls below `1e-6` of the objective. Deterministic: every sum runs in a fixed order
//!   whatever the thread count.

use super::{design_regressor, times, FourierSeries, GramSum, Problem, COULOMB_SPEED};
use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSettings, DefaultSolver, IPSolver, SolverStatus, SupportedConeT};
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use physid_core::dynamics::{weighted_regressor_slope, Data};
use rayon::prelude::*;

/// Rows whose use of their limit is above this enter the subproblem from the start; any other
/// the solution breaks is added and the subproblem solved again ([`Subproblem::step`]). Near a
/// smooth motion's peak many check times use nearly as much of the limit, with nearly parallel
/// rows: at 0.9 the KUKA's 30 s design took about 1,060 rows into each subproblem, at 0.99
/// about 350, with no step failing for rows broken six times over.
const NEAR: f64 = 0.99;
/// The trust region's first, largest and smallest sizes (in `y`).
const RHO: [f64; 3] = [0.05, 1.0, 1e-6];

/// The objective's value and its gradient in `x`.
pub(super) struct Slope {
    pub value: f64,
    pub gradient: DVector<f64>,
}

/// `x` of a series (joint-major `a`, then `b`).
pub(super) fn coefficients(s: &FourierSeries) -> DVector<f64> {
    let a = s.sin.iter().flatten();
    let b = s.cos.iter().flatten();
    DVector::from_iterator(2 * s.sin.len() * s.sin[0].len(), a.chain(b).copied())
}

/// The series of `x`, shaped and timed like `like`.
pub(super) fn series_of(x: &DVector<f64>, like: &FourierSeries) -> FourierSeries {
    let (n, h) = (like.sin.len(), like.sin[0].len());
    let rows = |k: usize| {
        (0..n)
            .map(|j| x.rows(k + j * h, h).iter().copied().collect())
            .collect()
    };
    FourierSeries {
        sin: rows(0),
        cos: rows(n * h),
        ..like.clone()
    }
}

/// `∂φ/∂F` of the objective `which` at `F` (`None` where `F` is singular).
fn objective_slope(f: &DMatrix<f64>, which: super::Objective) -> Option<DMatrix<f64>> {
    let eig = SymmetricEigen::new(f.clone());
    let r = f.nrows();
    let (lo, hi) = (eig.eigenvalues.imin(), eig.eigenvalues.imax());
    let (l_lo, l_hi) = (eig.eigenvalues[lo], eig.eigenvalues[hi]);
    if !(l_lo > 0.0 && l_hi.is_finite()) {
        return None;
    }
    let outer = |k: usize| {
        let v = eig.eigenvectors.column(k);
        v * v.transpose()
    };
    Some(match which {
        super::Objective::DOptimal => {
            let inv = DMatrix::from_diagonal(&eig.eigenvalues.map(|l| 1.0 / (l * r as f64)));
            &eig.eigenvectors * inv * eig.eigenvectors.transpose()
        }
        super::Objective::EOptimal => outer(lo) / l_lo,
        super::Objective::Condition => (outer(lo) / l_lo - outer(hi) / l_hi) * 0.5,
    })
}

impl Problem<'_> {
    /// The objective of `s`'s steady motion and its gradient in `x`.
    pub(super) fn slope(&self, s: &FourierSeries) -> Option<Slope> {
        let steady = s.steady();
        let (n, p) = (self.model.dof(), self.model.layout().len);
        let ts: Vec<f64> = times(&steady, self.opts.samples).collect();
        let k_count = ts.len() as f64;
        let states: Vec<[Vec<f64>; 3]> = ts.iter().map(|&t| steady.at(t)).collect();
        let ys: Vec<DMatrix<f64>> = states
            .par_iter()
            .map_init(
                || Data::new(self.model),
                |data, [q, qd, qdd]| {
                    let mut y = DMatrix::zeros(n, p);
                    design_regressor(self.model, data, [q, qd, qdd], &mut y);
                    y
                },
            )
            .collect();
        let mut sum = GramSum::new(n, p);
        ys.iter().for_each(|y| sum.add(y));
        let (a, _) = sum.finish();
        let f = self.basis.information(&(a / k_count));
        let value = self.objective_of(&f);
        let phi = objective_slope(&f, self.opts.objective)?;
        let dv = DMatrix::from_fn(p, self.basis.v.ncols(), |i, c| {
            self.basis.inv_scale[i] * self.basis.v[(i, c)]
        });
        let m = &dv * phi * dv.transpose() * (2.0 / k_count);
        // Per sample, ∂φ/∂(q_j, q̇_j, q̈_j).
        let per_state: Vec<Vec<[f64; 3]>> = states
            .par_iter()
            .zip(&ys)
            .map_init(
                || Data::new(self.model),
                |data, ([q, qd, qdd], y)| self.state_slope(data, [q, qd, qdd], &(y * &m)),
            )
            .collect();
        Some(Slope {
            value,
            gradient: self.chain(&steady, &ts, &per_state),
        })
    }

    /// `⟨W, ∂Y/∂s⟩` for each joint's `q`, `q̇`, `q̈` at one sample: the regressor's by its
    /// adjoint ([`weighted_regressor_slope`]), the design's smooth Coulomb column's
    /// (`tanh(q̇ / COULOMB_SPEED)`) added.
    fn state_slope(
        &self,
        data: &mut Data,
        [q, qd, qdd]: [&Vec<f64>; 3],
        w: &DMatrix<f64>,
    ) -> Vec<[f64; 3]> {
        let mut out = weighted_regressor_slope(self.model, data, [q, qd, qdd], w);
        let c = self.model.layout().coulomb_col;
        for (j, o) in out.iter_mut().enumerate() {
            let t = (qd[j] / COULOMB_SPEED).tanh();
            o[1] += w[(j, c + j)] * (1.0 - t * t) / COULOMB_SPEED;
        }
        out
    }

    /// `∂φ/∂x` from the per-sample state slopes, through the steady series.
    fn chain(&self, s: &FourierSeries, ts: &[f64], per_state: &[Vec<[f64; 3]>]) -> DVector<f64> {
        let (n, h) = (s.sin.len(), s.sin[0].len());
        let mut g = DVector::zeros(2 * n * h);
        for (t, slopes) in ts.iter().zip(per_state) {
            for l in 0..h {
                let w = s.angular_frequency(l);
                let (sn, cs) = (w * t).sin_cos();
                for (j, [cq, cqd, cqdd]) in slopes.iter().enumerate() {
                    g[j * h + l] += cq * sn + cqd * w * cs - cqdd * w * w * sn;
                    g[(n + j) * h + l] += cq * (cs - 1.0) - cqd * w * sn - cqdd * w * w * cs;
                }
            }
        }
        g
    }
}

/// One kinematic limit at one check time: `coef · y_j ≤ 1` over joint `j`'s `2h` variables.
struct Row {
    joint: usize,
    coef: Vec<f64>,
}

/// Every limit row of the check times of `s`, in `y` (`sigma` the scale `x = σ y`).
fn limit_rows(problem: &Problem<'_>, s: &FourierSeries, sigma: &DVector<f64>) -> Vec<Row> {
    let (n, h) = (s.sin.len(), s.sin[0].len());
    let lim = &problem.limits;
    let unit = |sin: bool, l: usize| FourierSeries {
        offset: vec![0.0],
        sin: vec![(0..h).map(|m| f64::from(u8::from(sin && m == l))).collect()],
        cos: vec![(0..h)
            .map(|m| f64::from(u8::from(!sin && m == l)))
            .collect()],
        ..s.clone()
    };
    let units: Vec<FourierSeries> = (0..2 * h).map(|i| unit(i < h, i % h)).collect();
    let mut rows = vec![];
    for t in super::check_times(s, problem.opts.samples) {
        // Each variable's q − o, q̇, q̈, q⃛ at t (window applied).
        let per: Vec<[f64; 4]> = units
            .iter()
            .map(|u| {
                let v = u.with_jerk(t);
                [v[0][0], v[1][0], v[2][0], v[3][0]]
            })
            .collect();
        for j in 0..n {
            let o = s.offset[j];
            let bounds = [
                (lim.upper[j] - o, o - lim.lower[j]),
                (lim.velocity[j], lim.velocity[j]),
                (lim.acceleration[j], lim.acceleration[j]),
                (lim.jerk[j], lim.jerk[j]),
            ];
            for (d, (up, down)) in bounds.into_iter().enumerate() {
                for (bound, sign) in [(up, 1.0), (down, -1.0)] {
                    if !bound.is_finite() {
                        continue;
                    }
                    let coef = (0..2 * h)
                        .map(|i| {
                            let var = if i < h {
                                j * h + i
                            } else {
                                (n + j) * h + i - h
                            };
                            sign * per[i][d] * sigma[var] / bound
                        })
                        .collect();
                    rows.push(Row { joint: j, coef });
                }
            }
        }
    }
    rows
}

/// Joint `j`'s variables in `v` (its `a`, then its `b`).
fn joint_vars(v: &DVector<f64>, j: usize, n: usize, h: usize) -> impl Iterator<Item = f64> + '_ {
    let s = v.as_slice();
    s[j * h..(j + 1) * h]
        .iter()
        .chain(&s[(n + j) * h..(n + j + 1) * h])
        .copied()
}

/// `coef · y_j`: the row's use of its limit at `y` (1 at the limit).
fn row_use(r: &Row, y: &DVector<f64>, n: usize, h: usize) -> f64 {
    r.coef
        .iter()
        .zip(joint_vars(y, r.joint, n, h))
        .map(|(c, v)| c * v)
        .sum()
}

/// One step's subproblem: the limit rows, the point `y`, the gradient `g` there, the curvature
/// `B`, the box `ρ`, and the shape `(n, h)` (joints, harmonics).
struct Subproblem<'a> {
    rows: &'a [Row],
    y: &'a DVector<f64>,
    g: &'a DVector<f64>,
    b: &'a DMatrix<f64>,
    rho: f64,
    shape: (usize, usize),
}

impl Subproblem<'_> {
    /// The step `d` maximizing `gᵀd − ½ dᵀBd` over `‖d‖∞ ≤ ρ` with every row kept at `y + d`
    /// (rows added as the solution breaks them); `None` if the solver fails.
    fn step(&self) -> Option<DVector<f64>> {
        let (n, h) = self.shape;
        let uses = |at: &DVector<f64>| -> Vec<f64> {
            self.rows.iter().map(|r| row_use(r, at, n, h)).collect()
        };
        let mut active: Vec<bool> = uses(self.y).into_iter().map(|u| u > NEAR).collect();
        for _ in 0..6 {
            let d = self.solve(&active)?;
            let moved = self.y + &d;
            let mut broken = false;
            for (a, u) in active.iter_mut().zip(uses(&moved)) {
                if !*a && u > 1.0 + 1e-9 {
                    (*a, broken) = (true, true);
                }
            }
            if !broken {
                return Some(d);
            }
        }
        None
    }

    /// `min ½ dᵀBd − gᵀd` s.t. the `active` rows at `y + d` and `‖d‖∞ ≤ ρ`, by Clarabel.
    fn solve(&self, active: &[bool]) -> Option<DVector<f64>> {
        let ((n, h), m) = (self.shape, self.y.len());
        let mut a: Vec<(usize, usize, f64)> = vec![];
        let mut rhs = vec![];
        let kept = self.rows.iter().zip(active).filter(|(_, on)| **on);
        for (k, (row, _)) in kept.enumerate() {
            let vars = (0..h)
                .map(|l| row.joint * h + l)
                .chain((0..h).map(|l| (n + row.joint) * h + l));
            a.extend(row.coef.iter().zip(vars).map(|(c, v)| (k, v, *c)));
            rhs.push((1.0 - row_use(row, self.y, n, h)).max(0.0));
        }
        for i in 0..m {
            let k = rhs.len();
            a.extend([(k, i, 1.0), (k + 1, i, -1.0)]);
            rhs.extend([self.rho, self.rho]);
        }
        let b = self.b;
        let upper = (0..m).flat_map(|j| (0..=j).map(move |i| (i, j, b[(i, j)])));
        let p = csc(m, m, upper.collect());
        let a = csc(rhs.len(), m, a);
        let q: Vec<f64> = self.g.iter().map(|v| -v).collect();
        let cones = [SupportedConeT::NonnegativeConeT(rhs.len())];
        let settings = DefaultSettings {
            verbose: false,
            ..DefaultSettings::default()
        };
        let mut solver = DefaultSolver::new(&p, &q, &a, &rhs, &cones, settings).ok()?;
        solver.solve();
        matches!(
            solver.solution.status,
            SolverStatus::Solved | SolverStatus::AlmostSolved
        )
        .then(|| DVector::from_column_slice(&solver.solution.x))
    }
}

/// A `rows × cols` sparse matrix of `(row, column, value)` triplets.
fn csc(rows: usize, cols: usize, t: Vec<(usize, usize, f64)>) -> CscMatrix<f64> {
    let (mut i, mut j, mut v) = (vec![], vec![], vec![]);
    for (r, c, x) in t {
        i.push(r);
        j.push(c);
        v.push(x);
    }
    CscMatrix::new_from_triplets(rows, cols, i, j, v)
}

/// Damped BFGS update of `B ≈ −∇²φ` with the step `s` and the gradient's change `−r`
/// (Powell's damping keeps `B` positive definite).
fn bfgs(b: &mut DMatrix<f64>, s: &DVector<f64>, r: &DVector<f64>) {
    let bs = &*b * s;
    let sbs = s.dot(&bs);
    if sbs <= 0.0 || !sbs.is_finite() {
        return;
    }
    let sr = s.dot(r);
    let theta = if sr >= 0.2 * sbs {
        1.0
    } else {
        0.8 * sbs / (sbs - sr)
    };
    let r = r * theta + &bs * (1.0 - theta);
    let sr = s.dot(&r);
    if sr > 0.0 {
        *b += &r * r.transpose() / sr - &bs * bs.transpose() / sbs;
    }
}

impl Problem<'_> {
    /// `s` with each joint shrunk (never grown) to within its kinematic limits: the steps keep
    /// them to the solver's tolerance.
    fn shrunk_into_limits(&self, mut s: FourierSeries) -> FourierSeries {
        for (j, f) in self.kinematic_factors(&s).into_iter().enumerate() {
            if f < 1.0 {
                s.scale_joint(j, f);
            }
        }
        s
    }

    /// A step's end `moved`, shrunk into the kinematic limits, with its slope; `None` where its
    /// torque leaves the effort limits or its information is singular.
    fn trial(&self, moved: FourierSeries, data: &mut Data) -> Option<(FourierSeries, Slope)> {
        let trial = self.shrunk_into_limits(moved);
        if !self.within_torque(&trial, data) {
            return None;
        }
        let slope = self.slope(&trial)?;
        Some((trial, slope))
    }

    /// Whether `s`'s torque stays within the effort limits.
    fn within_torque(&self, s: &FourierSeries, data: &mut Data) -> bool {
        let ratios = self.torque_ratio(s, data, self.opts.samples);
        ratios.into_iter().all(|r| r <= 1.0)
    }

    /// `σ` of `x = σ y`: coefficient `(j, l)`'s amplitude whose peak acceleration `ω_l² x` is
    /// joint `j`'s acceleration limit.
    fn variable_scales(&self, s: &FourierSeries) -> DVector<f64> {
        let (n, h) = (s.sin.len(), s.sin[0].len());
        DVector::from_fn(2 * n * h, |i, _| {
            let (j, l) = ((i / h) % n, i % h);
            let w = s.angular_frequency(l);
            let a = self.limits.acceleration[j];
            if a.is_finite() {
                a / (w * w)
            } else {
                1.0 / w
            }
        })
    }

    /// Up to `iterations` SQP steps from `start` (inside the limits): the end's value, the end,
    /// and the evaluations made (a value with its gradient counts as one).
    pub(super) fn improve(
        &self,
        start: FourierSeries,
        data: &mut Data,
    ) -> (f64, FourierSeries, usize) {
        let (n, h) = (start.sin.len(), start.sin[0].len());
        let sigma = self.variable_scales(&start);
        let rows = limit_rows(self, &start, &sigma);
        let mut s = start;
        let Some(mut at) = self.slope(&s) else {
            return (self.value(&s, data), s, 1);
        };
        let mut y = coefficients(&s).component_div(&sigma);
        let mut g = at.gradient.component_mul(&sigma);
        let mut b = DMatrix::identity(y.len(), y.len()) * (g.amax() / RHO[0]).max(1e-12);
        let (mut rho, mut evaluations) = (RHO[0], 1);
        for _ in 0..self.opts.iterations {
            if (self.watch.stop)() || rho < RHO[2] {
                break;
            }
            self.evaluated();
            let subproblem = Subproblem {
                rows: &rows,
                y: &y,
                g: &g,
                b: &b,
                rho,
                shape: (n, h),
            };
            let Some(d) = subproblem.step() else {
                rho *= 0.25;
                continue;
            };
            let predicted = g.dot(&d) - 0.5 * d.dot(&(&b * &d));
            // Converged (or a model that predicts no gain, NaN included).
            let gain = predicted / (1.0 + at.value.abs());
            if gain.is_nan() || gain <= 1e-6 {
                break;
            }
            evaluations += 1;
            let moved = series_of(&(&y + &d).component_mul(&sigma), &s);
            let Some((trial, next)) = self.trial(moved, data) else {
                rho *= 0.25;
                continue;
            };
            let ratio = (next.value - at.value) / predicted;
            if ratio > 1e-4 {
                let y_next = coefficients(&trial).component_div(&sigma);
                let g_next = next.gradient.component_mul(&sigma);
                bfgs(&mut b, &(&y_next - &y), &(&g - &g_next));
                (y, g, s, at) = (y_next, g_next, trial, next);
            }
            if ratio < 0.25 {
                rho *= 0.25;
            } else if ratio > 0.75 && d.amax() > 0.99 * rho {
                rho = (2.0 * rho).min(RHO[1]);
            }
        }
        (at.value, s, evaluations)
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Basis, DesignOptions, Limits, Objective, Watch, BASIS_SEED};
    use super::*;
    use physid_core::model::cheetah3;

    /// The chain-rule gradient against central differences of the objective itself, for each
    /// objective, on the leg with its rotors.
    #[test]
    fn the_gradient_matches_finite_differences_of_the_objective() {
        let kuka = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../data/kuka_lwr4/kuka_lwr4.urdf"
        );
        let robots = [
            (cheetah3::leg(), 60.0),
            (physid_io::load_robot(kuka).unwrap(), 3.0),
        ];
        let cases = robots.iter().flat_map(|r| {
            [
                Objective::DOptimal,
                Objective::EOptimal,
                Objective::Condition,
            ]
            .map(|o| (r, o))
        });
        for ((model, acceleration), objective) in cases {
            let model = model.clone();
            let opts = DesignOptions {
                objective,
                max_acceleration: vec![*acceleration],
                base_frequency: 0.1,
                ..Default::default()
            };
            let limits = Limits::new(&model, None, &opts).unwrap();
            let basis = Basis::new(&model, &limits, BASIS_SEED).unwrap();
            let problem = Problem {
                model: &model,
                limits,
                basis,
                opts: &opts,
                watch: &Watch::NONE,
                evaluations: Default::default(),
            };
            let mut rng = <rand_chacha::ChaCha8Rng as rand::SeedableRng>::seed_from_u64(3);
            let mut data = Data::new(&model);
            let s = problem.scaled_into_limits(problem.random_start(&mut rng), &mut data);
            let slope = problem.slope(&s).unwrap();
            let x = coefficients(&s);
            for i in [0, 3, 7, 12, 16, 24, 29, 40, 55, 69]
                .into_iter()
                .filter(|&i| i < x.len())
            {
                let h = 1e-6 * x.amax();
                let mut at = |dx: f64| {
                    let mut x = x.clone();
                    x[i] += dx;
                    problem.value(&series_of(&x, &s), &mut data)
                };
                let fd = (at(h) - at(-h)) / (2.0 * h);
                let g = slope.gradient[i];
                assert!(
                    // (The regressor's own derivatives are forward differences: about 1e-4.)
                    (g - fd).abs() <= 1e-3 * fd.abs().max(slope.gradient.amax() * 1e-3),
                    "{objective:?} x[{i}]: chain rule {g}, differences {fd}"
                );
            }
        }
    }
}
