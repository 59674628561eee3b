//! Least squares without the cone solver, prediction errors, identifiability and parameter
//! uncertainty.

use super::NormalEquations;
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use physid_core::dynamics::{joint_friction, regressor, rnea, Data};
use physid_core::linalg::{excited_scale, RANK_TOL};
use physid_core::model::Model;
use physid_core::trajectory::{SampleSink, Trajectory};
use serde::Serialize;

/// The residual `τ − Y θ` (N m) of samples `range`, sample-major; computed in chunks of
/// [`RESIDUAL_CHUNK`] samples side by side (each sample's residual alone, so the same numbers on
/// any thread count).
pub fn residuals(
    model: &Model,
    theta: &DVector<f64>,
    tr: &Trajectory,
    range: std::ops::Range<usize>,
) -> Vec<f64> {
    use rayon::prelude::*;
    let n = model.dof();
    let carrying = model.with_parameters(theta).ok();
    let starts: Vec<usize> = range.clone().step_by(RESIDUAL_CHUNK).collect();
    let chunks: Vec<Vec<f64>> = starts
        .par_iter()
        .map(|&start| {
            let chunk = start..(start + RESIDUAL_CHUNK).min(range.end);
            let mut out = Vec::with_capacity(chunk.len() * n);
            let mut predict = Predictor::new(model, carrying.as_ref(), theta);
            let mut pred = vec![0.0; n];
            for k in chunk {
                let qdd = tr.qdd_at(k).expect("q̈ present");
                predict.torque(tr.q_at(k), tr.qd_at(k), qdd, &mut pred);
                out.extend((0..n).map(|j| tr.tau_at(k)[j] - pred[j]));
            }
            out
        })
        .collect();
    chunks.concat()
}

/// The joint torque `Y(q, q̇, q̈) θ` (N m) of a model's parameters `θ`, sample by sample: the
/// inverse dynamics with friction of the model carrying `θ` (`O(n)` per sample, against the
/// regressor's `O(n²)`; equal to `Y θ` up to round-off, `tests/dynamics.rs`), or the
/// regressor's product where there is no such model (a `θ` with a non-finite entry).
struct Predictor<'a> {
    /// The model carrying `θ`, or the model whose regressor multiplies it.
    model: &'a Model,
    theta: &'a DVector<f64>,
    data: Data,
    /// The regressor's buffer where no model carries `θ`.
    y: Option<DMatrix<f64>>,
}

impl<'a> Predictor<'a> {
    /// For `model`'s parameters `theta`, with `carrying` the model with them when there is one.
    fn new(model: &'a Model, carrying: Option<&'a Model>, theta: &'a DVector<f64>) -> Self {
        let y = carrying
            .is_none()
            .then(|| DMatrix::zeros(model.dof(), model.layout().len));
        // The workspace holds the spatial inertias of the model it is made for.
        let model = carrying.unwrap_or(model);
        Self {
            model,
            theta,
            data: Data::new(model),
            y,
        }
    }

    /// `Y θ` at one state into `out` (N m per joint).
    fn torque(&mut self, q: &[f64], qd: &[f64], qdd: &[f64], out: &mut [f64]) {
        match &mut self.y {
            None => {
                let tau = rnea(self.model, &mut self.data, q, qd, qdd);
                let joints = self.model.bodies().iter().zip(qd);
                for ((o, t), (b, &w)) in out.iter_mut().zip(tau.iter()).zip(joints) {
                    *o = t + joint_friction(&b.friction, w);
                }
            }
            Some(y) => {
                regressor(self.model, &mut self.data, q, qd, qdd, y);
                out.copy_from_slice((&*y * self.theta).as_slice());
            }
        }
    }
}

/// Samples per chunk of [`residuals`].
pub const RESIDUAL_CHUNK: usize = 1024;

/// Per-joint RMS of `Y θ − τ` over samples `range` (N m), and the overall RMS.
pub fn rms_error(
    model: &Model,
    theta: &DVector<f64>,
    tr: &Trajectory,
    range: std::ops::Range<usize>,
) -> (Vec<f64>, f64) {
    let n = model.dof();
    let count = range.len().max(1) as f64;
    let res = residuals(model, theta, tr, range);
    let per: Vec<f64> = (0..n)
        .map(|j| (res.iter().skip(j).step_by(n).map(|r| r * r).sum::<f64>() / count).sqrt())
        .collect();
    let overall = (res.iter().map(|r| r * r).sum::<f64>() / (count * n as f64)).sqrt();
    (per, overall)
}

/// Per-joint and overall RMS of `Y θ − τ` (N m) over the samples a source streams (e.g. a CSV
/// read from disk by `io::samples::stream_csv`).
pub fn rms_error_stream<E>(
    model: &Model,
    theta: &DVector<f64>,
    source: impl FnOnce(&mut SampleSink) -> Result<usize, E>,
) -> Result<(Vec<f64>, f64), E> {
    let n = model.dof();
    let mut ss = vec![0.0; n];
    let mut count = 0usize;
    residual_stream(model, theta, source, &mut |_, r| {
        for j in 0..n {
            ss[j] += r[j].powi(2);
        }
        count += 1;
    })?;
    let c = count.max(1) as f64;
    Ok((
        ss.iter().map(|v| (v / c).sqrt()).collect(),
        (ss.iter().sum::<f64>() / (c * n as f64)).sqrt(),
    ))
}

/// Passes `(t, Y θ − τ)` (s, N m per joint) of each sample a source streams to `each`; returns
/// the source's total sample count.
pub fn residual_stream<E>(
    model: &Model,
    theta: &DVector<f64>,
    source: impl FnOnce(&mut SampleSink) -> Result<usize, E>,
    each: &mut dyn FnMut(f64, &[f64]),
) -> Result<usize, E> {
    let n = model.dof();
    let carrying = model.with_parameters(theta).ok();
    let mut predict = Predictor::new(model, carrying.as_ref(), theta);
    let mut pred = vec![0.0; n];
    let mut r = vec![0.0; n];
    source(&mut |_, s| {
        predict.torque(s.q, s.qd, s.qdd, &mut pred);
        for j in 0..n {
            r[j] = pred[j] - s.tau[j];
        }
        each(s.t, &r);
    })
}

/// One base parameter: a combination of the model's parameters that the data determine,
/// `β = θ_lead + Σ c_k θ_k` (the lead parameter's coefficient is 1).
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct BaseParameter {
    /// The combination as text, e.g. `panda_link2.Izz + 0.0144 panda_link3.m − 0.12 panda_link3.hz`.
    pub expression: String,
    /// Its terms, the lead parameter first (coefficient 1).
    pub terms: Vec<BaseTerm>,
    /// Its value at the identified parameters (the lead parameter's unit).
    pub value: f64,
    /// Its standard error, `σ √((Y_bᵀ Y_b)⁻¹)_ii` over the base columns `Y_b`.
    pub standard_error: f64,
}

/// One term of a base parameter.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct BaseTerm {
    /// The parameter's name, e.g. `panda_link3.hz`.
    pub parameter: String,
    /// Its coefficient in the combination.
    pub coefficient: f64,
}

/// What the data determine.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct Identifiability {
    /// Numerical rank ([`physid_core::linalg::rank_and_condition`], the same definition).
    pub rank: usize,
    /// Number of parameters.
    pub parameters: usize,
    /// Condition number on the identifiable subspace ([`physid_core::linalg::rank_and_condition`]).
    pub condition: f64,
    /// A basis of the unidentifiable directions, each once: the parameters the data never
    /// excite (grouped by body, e.g. `"panda_link1: m, hx, hy (never excited)"`), then, for each
    /// parameter that is excited but not independently, the direction that leaves every base
    /// parameter unchanged (`"+1 panda_link3.m −0.045 panda_link2.hz"`). At most 40 are listed.
    pub unidentifiable: Vec<String>,
    /// How many unidentifiable directions there are (`parameters − rank`).
    pub unidentifiable_total: usize,
    /// The base parameters (the identifiable combinations, one per rank), by QR with column
    /// pivoting of the regressor's square root, with their values and standard errors.
    pub base: Vec<BaseParameter>,
    /// Standard error of each parameter (`σ² (YᵀY)⁺` with `σ²` the residual variance), infinite
    /// (null in JSON) where the parameter moves along an unidentifiable direction: only the
    /// parameters with a finite error are determined by the data on their own.
    pub standard_errors: Vec<f64>,
}

/// Rank, conditioning, base parameters, null space and standard errors of the normal
/// equations at `theta` (the model's layout).
pub fn identifiability<R: crate::Parameterized + ?Sized>(
    model: &R,
    ne: &NormalEquations,
    theta: &DVector<f64>,
) -> Identifiability {
    let p = model.parameter_count();
    let yty = &ne.yty;
    let d = excited_scale(yty);
    let hs = DMatrix::from_fn(p, p, |i, j| d[i] * yty[(i, j)] * d[j]);
    let eig = SymmetricEigen::new(hs);
    let lmax = eig.eigenvalues.max().max(0.0);
    let kept: Vec<usize> = (0..p)
        .filter(|&k| eig.eigenvalues[k] > RANK_TOL * lmax)
        .collect();
    let rank = kept.len();
    let rows = (ne.samples * ne.rows_per_sample()) as f64;
    let sigma2 = ne.residual_sum_of_squares(theta) / (rows - rank as f64).max(1.0);
    let names = model.parameter_names();
    let basis = Basis::new(&eig, &kept, &d);
    let base = basis.parameters(yty, theta, sigma2, &names);
    let unidentifiable = basis.null_directions(&names);
    let standard_errors = parameter_errors(&eig, &kept, &d, sigma2);
    // The one definition of rank and condition; the filter above drew the same line.
    let (rank_checked, condition) = physid_core::linalg::rank_and_condition(yty);
    debug_assert_eq!(rank_checked, rank);
    Identifiability {
        rank,
        parameters: p,
        condition,
        unidentifiable,
        unidentifiable_total: p - rank,
        base,
        standard_errors,
    }
}

/// Each parameter's standard error, `√(σ² (YᵀY)⁺_ii)`, infinite where the parameter has a
/// component along a null direction (scaled eigenvectors `eig` of the normal matrix, `kept` the
/// identifiable ones, `d` the column scales).
fn parameter_errors(
    eig: &SymmetricEigen<f64, nalgebra::Dyn>,
    kept: &[usize],
    d: &[f64],
    sigma2: f64,
) -> Vec<f64> {
    let p = d.len();
    let mut cov_s = DMatrix::zeros(p, p);
    let mut null_weight = vec![0.0f64; p];
    for k in 0..p {
        let v = eig.eigenvectors.column(k);
        if kept.contains(&k) {
            cov_s += v * v.transpose() / eig.eigenvalues[k];
        } else {
            for i in 0..p {
                null_weight[i] = null_weight[i].max(v[i].abs());
            }
        }
    }
    (0..p)
        .map(|i| {
            if d[i] == 0.0 || null_weight[i] > 1e-6 {
                f64::INFINITY
            } else {
                (sigma2 * cov_s[(i, i)]).sqrt() * d[i]
            }
        })
        .collect()
}

/// The base columns of a regressor and how the others depend on them: QR with column pivoting
/// of the square root `A = Λ^{1/2} Vᵀ` of its scaled normal matrix (`AᵀA = D YᵀY D`, the
/// same column relations as `Y D`), as FIGAROH does on the stacked regressor.
struct Basis {
    /// Base columns, in pivot order.
    base: Vec<usize>,
    /// Excited columns that depend on the base ones.
    dependent: Vec<usize>,
    /// Columns the data never excite.
    unexcited: Vec<usize>,
    /// `θ`-space coefficients: column `dependent[j]` of `Y` is `Σ_i k[(i, j)] Y[base[i]]`.
    k: DMatrix<f64>,
}

impl Basis {
    fn new(eig: &SymmetricEigen<f64, nalgebra::Dyn>, kept: &[usize], d: &[f64]) -> Basis {
        let p = d.len();
        let unexcited: Vec<usize> = (0..p).filter(|&i| d[i] == 0.0).collect();
        let excited: Vec<usize> = (0..p).filter(|&i| d[i] != 0.0).collect();
        let a = DMatrix::from_fn(kept.len(), excited.len(), |r, c| {
            let k = kept[r];
            eig.eigenvalues[k].sqrt() * eig.eigenvectors[(excited[c], k)]
        });
        let r_rank = kept.len().min(excited.len());
        let qr = a.clone().col_piv_qr();
        let mut order: Vec<usize> = (0..excited.len()).collect();
        let mut perm = DMatrix::from_fn(1, excited.len(), |_, c| c as f64);
        qr.p().permute_columns(&mut perm);
        for (c, o) in order.iter_mut().enumerate() {
            *o = perm[(0, c)] as usize;
        }
        let r = qr.r();
        let r11 = r.view((0, 0), (r_rank, r_rank)).into_owned();
        let r12 = r
            .view((0, r_rank), (r_rank, excited.len() - r_rank))
            .into_owned();
        let k_scaled = r11
            .solve_upper_triangular(&r12)
            .unwrap_or_else(|| DMatrix::zeros(r_rank, excited.len() - r_rank));
        let base: Vec<usize> = order[..r_rank].iter().map(|&c| excited[c]).collect();
        let dependent: Vec<usize> = order[r_rank..].iter().map(|&c| excited[c]).collect();
        // Y D = A-relations: (Y D)_dep = (Y D)_base K, so Y_dep = Y_base diag(d_b) K / d_dep.
        let k = DMatrix::from_fn(base.len(), dependent.len(), |i, j| {
            k_scaled[(i, j)] * d[base[i]] / d[dependent[j]]
        });
        Basis {
            base,
            dependent,
            unexcited,
            k,
        }
    }

    /// The base parameters `β_i = θ_{b_i} + Σ_j K_ij θ_{d_j}` with values at `theta` and
    /// standard errors `σ √((Y_bᵀ Y_b)⁻¹)_ii`.
    fn parameters(
        &self,
        yty: &DMatrix<f64>,
        theta: &DVector<f64>,
        sigma2: f64,
        names: &[String],
    ) -> Vec<BaseParameter> {
        let b = &self.base;
        // The base columns' normal matrix, scaled to unit diagonal (its condition is that of
        // the pivoted R₁₁, while the unscaled one mixes kg and kg m² columns).
        let d: Vec<f64> = b.iter().map(|&i| 1.0 / yty[(i, i)].sqrt()).collect();
        let gram = DMatrix::from_fn(b.len(), b.len(), |i, j| d[i] * yty[(b[i], b[j])] * d[j]);
        let cov = gram
            .cholesky()
            .map(|c| c.inverse())
            .map(|inv| DMatrix::from_fn(b.len(), b.len(), |i, j| d[i] * inv[(i, j)] * d[j]))
            .unwrap_or_else(|| DMatrix::from_element(b.len(), b.len(), f64::INFINITY));
        (0..b.len())
            .map(|i| {
                let mut terms = vec![BaseTerm {
                    parameter: names[b[i]].clone(),
                    coefficient: 1.0,
                }];
                let mut value = theta[b[i]];
                for (j, &dep) in self.dependent.iter().enumerate() {
                    let c = self.k[(i, j)];
                    if c != 0.0
                        && (c * yty[(dep, dep)].sqrt()).abs() > 1e-9 * yty[(b[i], b[i])].sqrt()
                    {
                        terms.push(BaseTerm {
                            parameter: names[dep].clone(),
                            coefficient: c,
                        });
                        value += c * theta[dep];
                    }
                }
                BaseParameter {
                    expression: expression(&terms),
                    terms,
                    value,
                    standard_error: (sigma2 * cov[(i, i)]).sqrt(),
                }
            })
            .collect()
    }

    /// A basis of the null space, each direction once: unexcited parameters grouped by body,
    /// then `e_d − Σ_i K_id e_{b_i}` for each dependent column (at most 40 lines).
    fn null_directions(&self, names: &[String]) -> Vec<String> {
        let mut out: Vec<String> = vec![];
        let mut by_body: Vec<(String, Vec<String>)> = vec![];
        for &i in &self.unexcited {
            let (body, what) = names[i].rsplit_once('.').unwrap_or((&names[i], ""));
            match by_body.last_mut().filter(|(b, _)| b == body) {
                Some((_, list)) => list.push(what.to_string()),
                None => by_body.push((body.to_string(), vec![what.to_string()])),
            }
        }
        out.extend(
            by_body
                .into_iter()
                .map(|(b, list)| format!("{b}: {} (never excited)", list.join(", "))),
        );
        for (j, &dep) in self.dependent.iter().enumerate() {
            let mut terms = vec![BaseTerm {
                parameter: names[dep].clone(),
                coefficient: 1.0,
            }];
            let mut others: Vec<(usize, f64)> = (0..self.base.len())
                .map(|i| (i, -self.k[(i, j)]))
                .filter(|(_, c)| c.abs() > 1e-12)
                .collect();
            others.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
            terms.extend(others.into_iter().take(3).map(|(i, c)| BaseTerm {
                parameter: names[self.base[i]].clone(),
                coefficient: c,
            }));
            out.push(expression(&terms));
        }
        out.truncate(40);
        out
    }
}

/// `a + 0.5 b − 2 c` from terms (coefficients to 3 significant digits).
fn expression(terms: &[BaseTerm]) -> String {
    let mut s = String::new();
    for (k, t) in terms.iter().enumerate() {
        let c = t.coefficient;
        let sign = if c < 0.0 { "−" } else { "+" };
        let mag = if (c.abs() - 1.0).abs() < 1e-12 {
            String::new()
        } else {
            format!("{} ", significant(c.abs()))
        };
        match (k, c < 0.0) {
            (0, false) => s += &format!("{mag}{}", t.parameter),
            (0, true) => s += &format!("−{mag}{}", t.parameter),
            _ => s += &format!(" {sign} {mag}{}", t.parameter),
        }
    }
    s
}

/// `x` with three significant digits.
fn significant(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    let digits = (2 - x.abs().log10().floor() as i32).max(0) as usize;
    if (1e-4..1e5).contains(&x.abs()) {
        format!("{x:.digits$}")
    } else {
        format!("{x:.2e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use physid_core::model::random::{random_state, random_tree};
    use physid_core::model::RotorModel;

    #[test]
    fn residuals_are_the_torque_less_the_regressor_times_theta_in_memory_and_streamed() {
        for m in [
            random_tree(3, 5),
            random_tree(4, 4).with_rotor_model(RotorModel::Reflected),
        ] {
            let (n, p) = (m.dof(), m.layout().len);
            let [r, _, _] = random_state(9, p, 1.0);
            let theta = DVector::from_iterator(
                p,
                m.parameters()
                    .iter()
                    .zip(&r)
                    .map(|(t, r)| t * (1.0 + r) - 0.2 * r),
            );
            let mut tr = Trajectory::new((0..n).map(|j| format!("j{j}")).collect(), true);
            let mut want = vec![];
            let (mut d, mut y) = (Data::new(&m), DMatrix::zeros(n, p));
            for k in 0..2 * RESIDUAL_CHUNK + 7 {
                let [q, qd, qdd] = random_state(100 + k as u64, n, 2.0);
                let [tau, _, _] = random_state(5000 + k as u64, n, 10.0);
                regressor(&m, &mut d, &q, &qd, &qdd, &mut y);
                want.extend((&y * &theta).iter().zip(&tau).map(|(yt, t)| t - yt));
                tr.push(k as f64 * 1e-3, &q, &qd, Some(&qdd), &tau);
            }
            let largest = |got: &[f64]| -> f64 {
                let gaps = got.iter().zip(&want).map(|(g, w)| (g - w).abs());
                gaps.fold(0.0, f64::max)
            };
            let worst = largest(&residuals(&m, &theta, &tr, 0..tr.len()));
            assert!(
                worst < 1e-9,
                "{}: largest difference {worst:e} N m",
                m.name()
            );
            let mut streamed = vec![];
            residual_stream(
                &m,
                &theta,
                |sink: &mut SampleSink| -> Result<usize, ()> { Ok(tr.stream(0..tr.len(), sink)) },
                &mut |_, r| streamed.extend(r.iter().map(|v| -v)),
            )
            .unwrap();
            let worst = largest(&streamed);
            assert!(
                worst < 1e-9,
                "{}: streamed, largest difference {worst:e} N m",
                m.name()
            );
        }
    }
}
