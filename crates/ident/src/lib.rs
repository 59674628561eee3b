//! Identification under the paper's four constraint sets (eq. 10):
//!
//! `min_θ (1/n_s) Σ_k ‖Y_k θ − τ_k‖² + w ‖θ − θ̂‖²`, with per body (links and rotors)
//! - `none`: no constraint (ordinary least squares, solved directly);
//! - `semi`: `I(π) ⪰ ε 1` (6×6);
//! - `consistent`: `J(π) ⪰ ε 1` (4×4);
//! - `ellipsoid`: `J(π) ⪰ ε 1`, `tr(J(π) Q) ≥ 0` and `C(π) ⪰ 0` for the body's bounding
//!   ellipsoid;
//!
//! and non-negative friction coefficients in the constrained sets. `θ̂` is the prior (the robot
//! description's parameters, e.g. CAD) and `w` a small weight (the paper: 1e-6). The strict
//! inequalities become `⪰ ε 1` with `ε = 1e-6` (kg m², kg; see [`Options::eps`]): far below every
//! body's margin in the default truth (`λ_min(J) ≥ 5e-5`), far above round-off.
//!
//! The data enter only through the normal equations ([`NormalEquations`]): `P = 2 D (YᵀY/n_s +
//! w 1) D`, `q = −2 D (Yᵀτ/n_s + w θ̂)` in scaled variables `θ = D x` with
//! `D = diag(1/√(YᵀY_cc/n_s + w))`, so the cone program has `p` variables whatever `n_s` is and
//! unit-diagonal curvature. Clarabel solves it to global optimality; its status is mapped to a
//! result or an [`IdentError`]. No Clarabel type leaves this module.
//!
//! A floor of physid (docs/architecture.md §6) of its own crate, `physid-ident`; the `physid`
//! crate re-exports it as `physid::ident`.
#![warn(missing_docs)]

pub mod analysis;
pub mod information;
mod interior;
pub mod lmi;
pub mod normal;

pub use normal::NormalEquations;

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSolution, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use lmi::Lmi;
use nalgebra::{DMatrix, DVector};
use physid_core::conic::{AffineSym, ConeRows};
use physid_core::model::Model;
use physid_core::spatial::{ConsistencyReport, InertialParams};
use serde::Serialize;

/// The constraint set, loosest to tightest.
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Hash,
    Serialize,
    serde::Deserialize,
    PartialOrd,
    Ord,
    schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum ConstraintSet {
    /// Ordinary least squares.
    None,
    /// `I(π) ⪰ ε 1`.
    Semi,
    /// `J(π) ⪰ ε 1`.
    Consistent,
    /// `J(π) ⪰ ε 1`, `tr(J Q) ≥ 0`, `C(π) ⪰ 0`.
    Ellipsoid,
}

impl ConstraintSet {
    /// All four, loosest first.
    pub const ALL: [ConstraintSet; 4] = [
        ConstraintSet::None,
        ConstraintSet::Semi,
        ConstraintSet::Consistent,
        ConstraintSet::Ellipsoid,
    ];
    /// Lower-case name.
    pub fn name(&self) -> &'static str {
        match self {
            ConstraintSet::None => "none",
            ConstraintSet::Semi => "semi",
            ConstraintSet::Consistent => "consistent",
            ConstraintSet::Ellipsoid => "ellipsoid",
        }
    }
}

impl std::str::FromStr for ConstraintSet {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        ConstraintSet::ALL
            .into_iter()
            .find(|c| c.name() == s)
            .ok_or_else(|| {
                format!("unknown constraint set '{s}' (none, semi, consistent, ellipsoid)")
            })
    }
}

/// The largest margin `ε` of the strict matrix inequalities (kg m²).
pub const MAX_EPS: f64 = 1.0;

/// Identification options.
#[derive(Clone, Debug)]
pub struct Options {
    /// Constraint set.
    pub constraints: ConstraintSet,
    /// Weight `w` of `‖θ − θ̂‖²`.
    pub prior_weight: f64,
    /// Margin `ε` of the strict matrix inequalities.
    pub eps: f64,
    /// Solve `none` with the cone solver instead of directly (for cross-checks).
    pub force_cone_solver: bool,
    /// The prior term's geometry.
    pub regularizer: Regularizer,
    /// Further columns of θ constrained to be non-negative (e.g. the diagnosis's effect terms
    /// with a physical sign); they make even `none` a cone program.
    pub nonnegative: Vec<usize>,
    /// Bounds on masses: `(column of θ, lowest, highest)` in kg, each `lo ≤ θ_c ≤ hi`; they
    /// make even `none` a cone program.
    pub mass_bounds: Vec<(usize, f64, f64)>,
    /// The robot's total mass held within `lo..hi` kg: `(mass columns of θ summed, lo, hi)`;
    /// it makes even `none` a cone program.
    pub total_mass: Option<(Vec<usize>, f64, f64)>,
}

/// How the estimate is pulled towards the prior `θ̂`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Regularizer {
    /// `w ‖θ − θ̂‖²` (the paper).
    Euclidean,
    /// `w Σ_b d(J_b, Ĵ_b)` with the Bregman divergence of `−log det`,
    /// `d(J, Ĵ) = −log det(Ĵ⁻¹ J) + tr(Ĵ⁻¹ J) − 4` (Lee, Wensing & Park, "Geometric robot
    /// dynamic identification", 2020), plus `w ‖·‖²` on the friction coefficients. Invariant to
    /// the body frame and finite only for `J ≻ 0`, so it implies physical consistency.
    /// Cast for Clarabel as `[[J, L], [Lᵀ, diag L]] ⪰ 0` (L lower triangular) with
    /// `u_i ≤ log L_ii` (exponential cones), so `Σ u_i ≤ log det J`. Very large weights
    /// (≳ 1e6 against unit-scaled data) make the program badly scaled.
    LogDet,
}

impl std::str::FromStr for Regularizer {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "euclidean" => Ok(Regularizer::Euclidean),
            "logdet" => Ok(Regularizer::LogDet),
            _ => Err(format!("unknown regularizer '{s}' (euclidean, logdet)")),
        }
    }
}

impl Options {
    /// The paper's settings for a constraint set: `w = 1e-6`, `ε = 1e-6`.
    pub fn new(constraints: ConstraintSet) -> Self {
        Self {
            constraints,
            prior_weight: 1e-6,
            eps: 1e-6,
            force_cone_solver: false,
            regularizer: Regularizer::Euclidean,
            nonnegative: vec![],
            mass_bounds: vec![],
            total_mass: None,
        }
    }
}

/// Identification failed.
#[derive(Debug, thiserror::Error)]
pub enum IdentError {
    /// Fewer samples than parameters, without a prior to fill the gap.
    #[error("{samples} samples give {rows} equations for {params} parameters; give more samples or a prior weight > 0")]
    TooFewSamples {
        /// Samples.
        samples: usize,
        /// Equations.
        rows: usize,
        /// Parameters.
        params: usize,
    },
    /// The ellipsoid set needs every body's bounding ellipsoid.
    #[error("constraint set 'ellipsoid' needs a bounding ellipsoid for '{0}' (add one to the robot description)")]
    MissingEllipsoid(String),
    /// The constraints admit no parameters.
    #[error("the constraints are infeasible ({0}): no parameters satisfy them")]
    Infeasible(String),
    /// The solver stopped without an answer.
    #[error("the cone solver stopped with status {status} after {iterations} iterations")]
    SolverFailed {
        /// Clarabel's status, as Clarabel spells it.
        status: String,
        /// Iterations.
        iterations: u32,
    },
    /// An option value out of its range.
    #[error("{option} must be {expected}, got {value}")]
    InvalidOption {
        /// The option.
        option: &'static str,
        /// Its valid range.
        expected: &'static str,
        /// The value given.
        value: f64,
    },
    /// An effect term of a calibration is given twice or without its value.
    #[error("term '{term}': {reason}")]
    InvalidTerm {
        /// The term as given.
        term: String,
        /// What it needs.
        reason: &'static str,
    },
    /// The normal equations or the prior do not match the model.
    #[error("normal equations have {columns} columns and the prior {prior} for a model of {params} parameters")]
    Shape {
        /// Columns of the normal equations.
        columns: usize,
        /// Length of the prior.
        prior: usize,
        /// The model's parameters.
        params: usize,
    },
    /// A non-negative or mass-bounded column index outside the parameters.
    #[error("non-negative or bounded column {column} outside the {params} parameters")]
    NonNegativeColumn {
        /// The column.
        column: usize,
        /// Parameters.
        params: usize,
    },
    /// The log-det regularizer needs a physically consistent prior.
    #[error("log-det regularizer: the prior of '{0}' is not physically consistent (J not positive definite)")]
    InconsistentPrior(String),
    /// Something that must be a finite number is not.
    #[error("{0} are not finite: check the data for absurd values")]
    NonFinite(&'static str),
    /// Clarabel refused the problem's data.
    #[error("cone program rejected: {0}")]
    Rejected(String),
}

physid_core::options::option_error!(IdentError);

/// How the optimum was reached, spelled the same (snake_case) in JSON, tables and text:
/// `direct`, `solved`, `almost_solved`.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum SolveStatus {
    /// Least squares solved directly, without the cone solver.
    Direct,
    /// The unconstrained optimum satisfies every constraint, so it is the constrained optimum
    /// (a convex problem, strictly convex objective): found without the cone solver.
    Interior,
    /// Clarabel: solved to its full tolerances.
    Solved,
    /// Clarabel: solved to its reduced tolerances.
    AlmostSolved,
}

impl std::fmt::Display for SolveStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            SolveStatus::Direct => "direct",
            SolveStatus::Interior => "interior",
            SolveStatus::Solved => "solved",
            SolveStatus::AlmostSolved => "almost_solved",
        })
    }
}

impl Options {
    /// Whether the fit is plain least squares (no constraint, prior or bound needs the cone
    /// solver).
    fn solved_directly(&self) -> bool {
        self.constraints == ConstraintSet::None
            && !self.force_cone_solver
            && self.regularizer != Regularizer::LogDet
            && self.nonnegative.is_empty()
            && self.mass_bounds.is_empty()
            && self.total_mass.is_none()
    }

    /// Checks every value against its range (the CLI relies on this, and so can any caller).
    pub fn validate(&self) -> Result<(), IdentError> {
        let w = self.prior_weight;
        if !(w.is_finite() && w >= 0.0) {
            return Err(IdentError::InvalidOption {
                option: "prior_weight",
                expected: "a finite number >= 0",
                value: w,
            });
        }
        if !(self.eps.is_finite() && (0.0..=MAX_EPS).contains(&self.eps)) {
            return Err(IdentError::InvalidOption {
                option: "eps",
                expected: "a margin in [0, 1] (kg m², of the matrix inequalities; beyond, no robot body's pseudo-inertia has room for it)",
                value: self.eps,
            });
        }
        if let Some((cols, lo, hi)) = &self.total_mass {
            if cols.is_empty() || !(lo.is_finite() && hi.is_finite() && 0.0 <= *lo && lo <= hi) {
                return Err(IdentError::InvalidOption {
                    option: "total_mass",
                    expected: "mass columns and finite masses 0 <= lowest <= highest (kg)",
                    value: if lo.is_finite() && *lo >= 0.0 {
                        *hi
                    } else {
                        *lo
                    },
                });
            }
        }
        for &(_, lo, hi) in &self.mass_bounds {
            if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo <= hi) {
                return Err(IdentError::InvalidOption {
                    option: "mass_bounds",
                    expected: "finite masses 0 <= lowest <= highest (kg)",
                    value: if lo.is_finite() && lo >= 0.0 { hi } else { lo },
                });
            }
        }
        Ok(())
    }
}

/// The quadratic part of the identification objective, `θᵀ H θ − 2 gᵀ θ + c` with
/// `H = YᵀY/n_s + W`, `g = Yᵀτ/n_s + W θ̂`, `c = τᵀτ/n_s + θ̂ᵀ W θ̂` (`W = w 1`; under the
/// log-det regularizer `W` weighs only the friction coefficients). What independent solvers
/// are given to check physid's optimum (`identify --export-problem`).
#[derive(Clone, Debug)]
pub struct Objective {
    /// `H` (p × p).
    pub h: DMatrix<f64>,
    /// `g` (p).
    pub g: DVector<f64>,
    /// `c`.
    pub c: f64,
}

/// The objective's quadratic part for `ne` with `prior` and `opts` (see [`Objective`]).
pub fn objective(
    model: &Model,
    ne: &NormalEquations,
    prior: &DVector<f64>,
    opts: &Options,
) -> Objective {
    let m = ne.samples as f64;
    let logdet = opts.regularizer == Regularizer::LogDet;
    // The Euclidean prior weight applies to every parameter, or only to friction under log-det.
    let first_friction = model.layout().viscous_col;
    let w = |i: usize| {
        if !logdet || i >= first_friction {
            opts.prior_weight
        } else {
            0.0
        }
    };
    let mut h = &ne.yty / m;
    let mut g = &ne.ytt / m;
    let mut c = ne.tt / m;
    for i in 0..h.nrows() {
        h[(i, i)] += w(i);
        g[i] += w(i) * prior[i];
        c += w(i) * prior[i] * prior[i];
    }
    Objective { h, g, c }
}

/// Solver information.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct SolverInfo {
    /// How the optimum was reached.
    pub status: SolveStatus,
    /// Interior-point iterations (0 for direct).
    pub iterations: u32,
    /// Solve time (s), setup included.
    pub seconds: f64,
    /// Primal and dual residuals.
    pub residuals: [f64; 2],
}

/// One identified body.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct IdentifiedBody {
    /// Body or rotor name.
    pub name: String,
    /// Ten parameters, paper order, body frame.
    pub pi: [f64; 10],
    /// Consistency margins computed from `pi` (independently of the solver).
    pub consistency: ConsistencyReport,
}

/// The result of one identification.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct Identified {
    /// Constraint set used.
    pub constraints: ConstraintSet,
    /// The full parameter vector θ (see [`physid_core::model::ParamLayout`]).
    pub theta: DVector<f64>,
    /// Links then rotors.
    pub bodies: Vec<IdentifiedBody>,
    /// Viscous coefficients (N m s/rad).
    pub viscous: Vec<f64>,
    /// Coulomb coefficients (N m).
    pub coulomb: Vec<f64>,
    /// The objective `(1/n_s) Σ ‖Y θ − τ‖² + w ‖θ − θ̂‖²`.
    pub objective: f64,
    /// Whether every constraint of the set holds (checked from the parameters, not the solver).
    pub constraints_hold: bool,
    /// Solver information.
    pub solver: SolverInfo,
}

/// The bodies of a model in parameter order: `(name, first column, ellipsoid)`.
pub fn bodies(model: &Model) -> Vec<(String, usize, Option<physid_core::spatial::Ellipsoid>)> {
    let mut out: Vec<_> = model
        .bodies()
        .iter()
        .enumerate()
        .map(|(i, b)| (b.name.clone(), 10 * i, b.bounding))
        .collect();
    for (i, b) in model.bodies().iter().enumerate() {
        if let (Some(c), Some(r)) = (model.layout().rotor_col[i], &b.rotor) {
            out.push((r.name.clone(), c, r.bounding));
        }
    }
    out
}

/// Whether `theta` satisfies `set` (with `ε` relaxed to strict positivity and a round-off
/// tolerance on the linear and CoM conditions).
pub fn constraints_hold(model: &Model, theta: &DVector<f64>, set: ConstraintSet) -> bool {
    let l = model.layout();
    let friction_ok = (l.viscous_col..l.len).all(|c| theta[c] >= -1e-9);
    bodies(model).iter().all(|(_, c, e)| {
        let p = InertialParams(theta.fixed_rows::<10>(*c).into_owned());
        let r = p.consistency(e.as_ref());
        match set {
            ConstraintSet::None => true,
            ConstraintSet::Semi => r.min_eig_spatial > 0.0 && friction_ok,
            ConstraintSet::Consistent => r.min_eig_pseudo > 0.0 && friction_ok,
            ConstraintSet::Ellipsoid => {
                r.min_eig_pseudo > 0.0
                    && r.trace_jq
                        .is_some_and(|t| t >= -1e-9 * p.mass().abs().max(1.0))
                    && r.min_eig_com.is_some_and(|c| c >= -1e-9)
                    && friction_ok
            }
        }
    })
}

/// The problem's shapes agree (the normal equations cover the model's parameters, the prior
/// has one value per column), the options are valid, and there are samples enough (more rows
/// than parameters unless a prior weighs in).
fn check_problem(
    model: &Model,
    ne: &NormalEquations,
    prior: &DVector<f64>,
    opts: &Options,
) -> Result<(), IdentError> {
    let p = ne.yty.nrows();
    if p < model.layout().len || prior.len() != p {
        return Err(IdentError::Shape {
            columns: p,
            prior: prior.len(),
            params: model.layout().len,
        });
    }
    let summed = opts.total_mass.iter().flat_map(|t| t.0.iter());
    let bounded = opts.mass_bounds.iter().map(|b| &b.0).chain(summed);
    if let Some(&c) = opts.nonnegative.iter().chain(bounded).find(|&&c| c >= p) {
        return Err(IdentError::NonNegativeColumn {
            column: c,
            params: p,
        });
    }
    opts.validate()?;
    let ns = ne.samples;
    if ns == 0 || (opts.prior_weight == 0.0 && ns * model.dof() < p) {
        return Err(IdentError::TooFewSamples {
            samples: ns,
            rows: ns * model.dof(),
            params: p,
        });
    }
    Ok(())
}

/// Identifies `model`'s parameters from normal equations `ne` under `opts`, with prior `prior`
/// (usually `model.parameters()`).
///
/// `ne` may carry extra columns after the model's `layout().len` (e.g. the diagnosis's effect
/// terms): their coefficients are free (no constraint), pulled to `prior` by the same weight `w`,
/// and returned at the end of `theta`.
pub fn identify(
    model: &Model,
    ne: &NormalEquations,
    prior: &DVector<f64>,
    opts: &Options,
) -> Result<Identified, IdentError> {
    check_problem(model, ne, prior, opts)?;
    let w = opts.prior_weight;
    let logdet = opts.regularizer == Regularizer::LogDet;
    let Objective { h, g, c: constant } = objective(model, ne, prior, opts);
    // Never hand the solver non-finite data (Clarabel panics on them).
    let finite = |x: &f64| x.is_finite();
    if !(h.iter().all(finite) && g.iter().all(finite) && constant.is_finite()) {
        return Err(IdentError::NonFinite("the normal equations of the data"));
    }
    if !prior.iter().all(finite) {
        return Err(IdentError::NonFinite(
            "the prior (the robot description's parameters)",
        ));
    }
    let start = std::time::Instant::now();
    let (theta, solver) = if opts.solved_directly() {
        let info = SolverInfo {
            status: SolveStatus::Direct,
            iterations: 0,
            seconds: 0.0,
            residuals: [0.0; 2],
        };
        (physid_core::linalg::least_squares(&h, &g), info)
    } else if let Some(theta) = interior::optimum(model, &h, &g, opts) {
        let info = SolverInfo {
            status: SolveStatus::Interior,
            iterations: 0,
            seconds: 0.0,
            residuals: [0.0; 2],
        };
        (theta, info)
    } else {
        solve_cone(model, &h, &g, prior, opts)?
    };
    let seconds = start.elapsed().as_secs_f64();
    let mut objective = theta.dot(&(&h * &theta)) - 2.0 * theta.dot(&g) + constant;
    if logdet {
        objective += w * bregman_logdet(model, &theta, prior).unwrap_or(f64::INFINITY);
    }
    if !objective.is_finite() || theta.iter().any(|v| !v.is_finite()) {
        return Err(IdentError::NonFinite(
            "the identified parameters or their objective",
        ));
    }
    Ok(result(
        model,
        theta,
        opts.constraints,
        objective,
        SolverInfo { seconds, ..solver },
    ))
}

fn result(
    model: &Model,
    theta: DVector<f64>,
    set: ConstraintSet,
    objective: f64,
    solver: SolverInfo,
) -> Identified {
    let l = model.layout();
    let n = model.dof();
    let bodies = bodies(model)
        .into_iter()
        .map(|(name, c, e)| {
            let pi = InertialParams(theta.fixed_rows::<10>(c).into_owned());
            IdentifiedBody {
                name,
                pi: pi.0.into(),
                consistency: pi.consistency(e.as_ref()),
            }
        })
        .collect();
    Identified {
        constraints: set,
        bodies,
        viscous: (0..n).map(|i| theta[l.viscous_col + i]).collect(),
        coulomb: (0..n).map(|i| theta[l.coulomb_col + i]).collect(),
        objective,
        constraints_hold: constraints_hold(model, &theta, set),
        theta,
        solver,
    }
}

/// `Σ_b d(J_b, Ĵ_b)`, the log-det Bregman divergence summed over bodies; `None` if some `J_b`
/// or `Ĵ_b` is not positive definite.
pub fn bregman_logdet(model: &Model, theta: &DVector<f64>, prior: &DVector<f64>) -> Option<f64> {
    let mut total = 0.0;
    for (_, c, _) in bodies(model) {
        let j = InertialParams(theta.fixed_rows::<10>(c).into_owned()).pseudo_inertia();
        let j0 = InertialParams(prior.fixed_rows::<10>(c).into_owned()).pseudo_inertia();
        let ch0 = j0.cholesky()?;
        let chj = j.cholesky()?;
        let logdet = |l: &nalgebra::Matrix4<f64>| 2.0 * (0..4).map(|i| l[(i, i)].ln()).sum::<f64>();
        total += -(logdet(&chj.l()) - logdet(&ch0.l())) + (ch0.inverse() * j).trace() - 4.0;
    }
    Some(total)
}

/// Upper triangle of a symmetric matrix as CSC (Clarabel needs the upper triangle).
fn upper_csc(m: &DMatrix<f64>) -> CscMatrix<f64> {
    let n = m.nrows();
    let (mut colptr, mut rowval, mut nzval) = (vec![0], vec![], vec![]);
    for j in 0..n {
        for i in 0..=j {
            let v = m[(i, j)];
            if v != 0.0 {
                rowval.push(i);
                nzval.push(v);
            }
        }
        colptr.push(rowval.len());
    }
    CscMatrix::new(n, n, colptr, rowval, nzval)
}

/// `M(π) − ε 1 ⪰ 0` for the body whose ten parameters start at `col` (scaled by `d`):
/// `s = svec(M(π)) − ε svec(1)`, i.e. `A = −svec(M_k) d_k`, `b = −ε svec(1)`.
fn lmi_rows(rows: &mut ConeRows, lmi: Lmi, col: usize, eps: f64, d: &[f64]) {
    let r0 = rows.next_row();
    for (k, colv) in lmi.basis().iter().enumerate() {
        for (r, v) in colv.iter().enumerate() {
            rows.entry(r0 + r, col + k, -v * d[col + k]);
        }
    }
    let eye = DMatrix::<f64>::identity(lmi.dim(), lmi.dim()) * eps;
    rows.close(
        lmi::svec(&eye).iter().map(|x| -x),
        SupportedConeT::PSDTriangleConeT(lmi.dim()),
    );
}

/// The CoM-in-ellipsoid LMI `C(π) = [[m, dᵀ], [d, m Q_s]] ⪰ 0`, `d = h − m x_s` (paper eq. 22),
/// as the second-order cone it is equal to: with `Q_s = L Lᵀ`, the Schur complement of `m`
/// gives `C ⪰ 0 ⇔ ‖L⁻¹ d‖ ≤ m` (and `m = 0` forces `d = 0` in both). Four rows in a
/// second-order cone instead of a 4×4 PSD block, which the solver handles with no
/// eigen-decompositions; a flat ellipsoid (no `L⁻¹`) keeps the LMI.
fn com_rows(rows: &mut ConeRows, e: &physid_core::spatial::Ellipsoid, col: usize, d: &[f64]) {
    let Some(l_inv) = e.qs.cholesky().and_then(|c| c.l().try_inverse()) else {
        return lmi_rows(rows, Lmi::Com(*e), col, 0.0, d);
    };
    let (m, h) = (col, [col + 1, col + 2, col + 3]);
    let l_inv_x = l_inv * e.center;
    // Row 0: m. Rows 1–3: (L⁻¹ h)_r − m (L⁻¹ x_s)_r. Columns in scaled variables (θ = D x).
    let mut a = vec![vec![(m, d[m])]];
    a.extend((0..3).map(|r| {
        let mut terms = vec![(m, -l_inv_x[r] * d[m])];
        terms.extend((0..3).map(|c| (h[c], l_inv[(r, c)] * d[h[c]])));
        terms
    }));
    rows.second_order(&[0.0; 4], &a);
}

/// Builds and solves the cone program in scaled variables.
fn solve_cone(
    model: &Model,
    h: &DMatrix<f64>,
    g: &DVector<f64>,
    prior: &DVector<f64>,
    opts: &Options,
) -> Result<(DVector<f64>, SolverInfo), IdentError> {
    let p = h.nrows();
    let logdet = opts.regularizer == Regularizer::LogDet;
    let nb = bodies(model).len();
    // Log-det extra variables per body: 10 entries of a lower-triangular L, then 4 of u.
    let extra = if logdet { 14 * nb } else { 0 };
    let nv = p + extra;
    let d: Vec<f64> = physid_core::linalg::unit_diagonal_scale(h, 1.0)
        .into_iter()
        .chain(std::iter::repeat_n(1.0, extra))
        .collect();
    let ps = DMatrix::from_fn(nv, nv, |i, j| {
        if i < p && j < p {
            2.0 * d[i] * h[(i, j)] * d[j]
        } else {
            0.0
        }
    });
    let mut q: Vec<f64> = (0..nv)
        .map(|i| if i < p { -2.0 * d[i] * g[i] } else { 0.0 })
        .collect();
    let mut rows = ConeRows::default();
    let nonneg = physical_rows(model, opts, &d, &mut rows)?;
    if logdet {
        logdet_rows(model, prior, opts.prior_weight, &d, &mut q, &mut rows)?;
    }
    nonnegative_rows(&nonneg, &d, &mut rows);
    run_clarabel(&ps, &q, rows, p, &d)
}

/// An affine form over θ, `Σ v θ_c + constant`, held non-negative.
type Affine = (Vec<(usize, f64)>, f64);

/// The constraint rows of the set `opts.constraints` per body (`I ⪰ ε1`, `J ⪰ ε1`, the CoM
/// LMI), appended to `rows`; returns the rows that must be non-negative (`tr(JQ)`, friction,
/// `opts.nonnegative`, the mass bounds) as affine forms over θ.
fn physical_rows(
    model: &Model,
    opts: &Options,
    d: &[f64],
    rows: &mut ConeRows,
) -> Result<Vec<Affine>, IdentError> {
    let set = opts.constraints;
    let mut nonneg: Vec<Affine> = vec![];
    for (name, col, ell) in bodies(model) {
        match set {
            ConstraintSet::None => {}
            ConstraintSet::Semi => lmi_rows(rows, Lmi::Spatial, col, opts.eps, d),
            ConstraintSet::Consistent => lmi_rows(rows, Lmi::Pseudo, col, opts.eps, d),
            ConstraintSet::Ellipsoid => {
                let e = ell.ok_or_else(|| IdentError::MissingEllipsoid(name.clone()))?;
                lmi_rows(rows, Lmi::Pseudo, col, opts.eps, d);
                com_rows(rows, &e, col, d);
                let form = lmi::trace_jq_form(&e);
                nonneg.push(((0..10).map(|k| (col + k, form[k])).collect(), 0.0));
            }
        }
    }
    if set != ConstraintSet::None {
        let l = model.layout();
        nonneg.extend((l.viscous_col..l.len).map(|c| (vec![(c, 1.0)], 0.0)));
    }
    nonneg.extend(opts.nonnegative.iter().map(|&c| (vec![(c, 1.0)], 0.0)));
    for &(c, lo, hi) in &opts.mass_bounds {
        nonneg.push((vec![(c, 1.0)], -lo));
        nonneg.push((vec![(c, -1.0)], hi));
    }
    if let Some((cols, lo, hi)) = &opts.total_mass {
        nonneg.push((cols.iter().map(|&c| (c, 1.0)).collect(), -lo));
        nonneg.push((cols.iter().map(|&c| (c, -1.0)).collect(), *hi));
    }
    Ok(nonneg)
}

/// The log-det regularizer's variables and cones for every body (Lee, Wensing & Park): per
/// body `w (tr(Ĵ⁻¹ J) − Σ u_i)` in the objective `q`, `[[J, L], [Lᵀ, diag L]] ⪰ 0` (8×8) and
/// `(u_i, 1, L_ii)` in the exponential cone, so that `Σ u_i ≤ log det J`.
/// The extra variables follow θ's `p` entries, 14 per body (L's ten, then the four `u`).
fn logdet_rows(
    model: &Model,
    prior: &DVector<f64>,
    w: f64,
    d: &[f64],
    q: &mut [f64],
    rows: &mut ConeRows,
) -> Result<(), IdentError> {
    let p = prior.len();
    let jbasis: Vec<nalgebra::Matrix4<f64>> = (0..10)
        .map(|k| {
            let mut e = nalgebra::SVector::<f64, 10>::zeros();
            e[k] = 1.0;
            InertialParams(e).pseudo_inertia()
        })
        .collect();
    // L's lower-triangular entries (i >= j) in order; `lpos(i, j)` is the variable offset.
    let lentries: Vec<(usize, usize)> = (0..4).flat_map(|j| (j..4).map(move |i| (i, j))).collect();
    let lpos = |i: usize, j: usize| {
        lentries
            .iter()
            .position(|&x| x == (i, j))
            .expect("lower-triangular entry")
    };
    for (bi, (name, col, _)) in bodies(model).iter().enumerate() {
        let j0 = InertialParams(prior.fixed_rows::<10>(*col).into_owned()).pseudo_inertia();
        let j0inv = j0
            .try_inverse()
            .filter(|_| j0.cholesky().is_some())
            .ok_or_else(|| IdentError::InconsistentPrior(name.clone()))?;
        for (k, m_k) in jbasis.iter().enumerate() {
            q[col + k] += w * (j0inv * m_k).trace() * d[col + k];
        }
        let base = p + 14 * bi;
        for i in 0..4 {
            q[base + 10 + i] = -w;
        }
        // J(π) entry by entry, its terms over the body's scaled parameters (zeros left out).
        let mut j = AffineSym::new(4);
        for (k, m_k) in jbasis.iter().enumerate() {
            for c in 0..4 {
                for r in 0..=c {
                    let v = m_k[(r, c)] * d[col + k];
                    if v != 0.0 {
                        j.at(r, c).1.push((col + k, v));
                    }
                }
            }
        }
        let factor = |r: usize, c: usize| (r >= c).then(|| base + lpos(r, c));
        rows.log_det(j, factor, |i| base + 10 + i);
    }
    Ok(())
}

/// One non-negative cone over the affine forms `nonneg` (none when empty): `s = Σ v θ_c +
/// constant`, i.e. `A = −v d_c`, `b = constant`.
fn nonnegative_rows(nonneg: &[Affine], d: &[f64], rows: &mut ConeRows) {
    let r0 = rows.next_row();
    for (r, (terms, _)) in nonneg.iter().enumerate() {
        for &(c, v) in terms {
            rows.entry(r0 + r, c, -v * d[c]);
        }
    }
    rows.close(
        nonneg.iter().map(|(_, constant)| *constant),
        SupportedConeT::NonnegativeConeT(nonneg.len()),
    );
}

/// The program in `δ = x − x₀` about the unconstrained minimizer `x₀ = −P⁻¹q` of θ's `p`
/// entries (the others 0): `min ½ δᵀPδ + (q + P x₀)ᵀδ` s.t. `A δ + s = b − A x₀`, the same
/// program for any `x₀`. Its optimal value is what the constraints cost above least squares,
/// near 0, instead of `−Σ τ²`-sized: Clarabel's relative gap (and so the optimum's accuracy in
/// the fit's objective) is then measured on that excess. Returns `x₀`, `q + P x₀`, `b − A x₀`;
/// `x₀ = 0` where `P`'s block is not positive definite.
fn shifted_to_unconstrained(
    ps: &DMatrix<f64>,
    q: &[f64],
    a: &CscMatrix<f64>,
    mut b: Vec<f64>,
    p: usize,
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let nv = q.len();
    let pp = ps.view((0, 0), (p, p)).into_owned();
    let minus_q = DVector::from_iterator(p, q[..p].iter().map(|v| -v));
    let mut x0 = vec![0.0; nv];
    if let Some(ch) = pp.cholesky() {
        let xp = ch.solve(&minus_q);
        if xp.iter().all(|v| v.is_finite()) {
            x0[..p].copy_from_slice(xp.as_slice());
        }
    }
    let x0v = DVector::from_column_slice(&x0);
    let q_shift: Vec<f64> = (ps * &x0v).iter().zip(q).map(|(px, q)| q + px).collect();
    subtract_a_x(a, &x0, &mut b);
    (x0, q_shift, b)
}

/// `b ← b − A x` for a CSC matrix `A` (Clarabel's own product is private to it).
fn subtract_a_x(a: &CscMatrix<f64>, x: &[f64], b: &mut [f64]) {
    for (j, &xj) in x.iter().enumerate() {
        for k in a.colptr[j]..a.colptr[j + 1] {
            b[a.rowval[k]] -= a.nzval[k] * xj;
        }
    }
}

/// Solves the scaled cone program `min ½ xᵀ P x + qᵀ x` s.t. `rows` with Clarabel and maps its
/// status: θ = D x on success, an [`IdentError`] otherwise. No Clarabel type leaves here.
fn run_clarabel(
    ps: &DMatrix<f64>,
    q: &[f64],
    rows: ConeRows,
    p: usize,
    d: &[f64],
) -> Result<(DVector<f64>, SolverInfo), IdentError> {
    let nv = q.len();
    let (a, b, cones) = rows.into_parts(nv);
    let p_upper = upper_csc(ps);
    let shifted = shifted_to_unconstrained(ps, q, &a, b.clone(), p);
    let origin = (vec![0.0; nv], q.to_vec(), b);
    // In `x − x₀` first, then about the origin; each with Clarabel's equilibration, then
    // without it. The variables are already scaled to unit curvature; the equilibration on top
    // can stall in the nearly flat directions only the prior weight holds (a simulated KUKA log
    // under `consistent`: "almost solved" after 40 iterations, 2.5e-5 relative above the
    // optimum it reaches without in 13). About the origin is the fallback for the rare program
    // whose shift the solver cannot follow (the sample-size experiment at 19 samples, seed 13,
    // `semi`: a numerical error both ways about `x₀`). The first "solved" answer is kept, else
    // the first "almost solved", else the first attempt's status; the time is all attempts'.
    let attempts = [
        (&shifted, true),
        (&shifted, false),
        (&origin, true),
        (&origin, false),
    ];
    let mut seconds = 0.0;
    let mut kept: Option<(Vec<f64>, DefaultSolution<f64>)> = None;
    for ((x0, q, b), equilibrate) in attempts {
        let settings = DefaultSettings {
            verbose: false,
            max_iter: 200,
            equilibrate_enable: equilibrate,
            ..DefaultSettings::default()
        };
        let mut solver = DefaultSolver::new(&p_upper, q, &a, b, &cones, settings)
            .map_err(|e| IdentError::Rejected(e.to_string()))?;
        solver.solve();
        let sol = solver.solution;
        seconds += sol.solve_time;
        let better = |k: &DefaultSolution<f64>| {
            sol.status == SolverStatus::Solved
                || (sol.status == SolverStatus::AlmostSolved
                    && k.status != SolverStatus::AlmostSolved)
        };
        if kept.as_ref().is_none_or(|(_, k)| better(k)) {
            kept = Some((x0.clone(), sol));
        }
        if kept
            .as_ref()
            .is_some_and(|(_, k)| k.status == SolverStatus::Solved)
        {
            break;
        }
    }
    let (x0, sol) = kept.expect("at least one attempt");
    solution(sol, &x0, p, d, seconds)
}

/// θ = D (x₀ + δ) from Clarabel's solution `δ`, or the error its status names.
fn solution(
    sol: DefaultSolution<f64>,
    x0: &[f64],
    p: usize,
    d: &[f64],
    seconds: f64,
) -> Result<(DVector<f64>, SolverInfo), IdentError> {
    let info = |status: SolveStatus| SolverInfo {
        status,
        iterations: sol.iterations,
        seconds,
        residuals: [sol.r_prim, sol.r_dual],
    };
    match sol.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {
            let x = sol.x.iter().zip(x0).map(|(dx, x0)| x0 + dx);
            let theta = DVector::from_iterator(p, x.zip(d).take(p).map(|(x, s)| x * s));
            let status = if sol.status == SolverStatus::Solved {
                SolveStatus::Solved
            } else {
                SolveStatus::AlmostSolved
            };
            Ok((theta, info(status)))
        }
        SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
            Err(IdentError::Infeasible(format!("{:?}", sol.status)))
        }
        s => Err(IdentError::SolverFailed {
            status: format!("{s:?}"),
            iterations: sol.iterations,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, Vector3};
    use physid_core::spatial::Ellipsoid;
    use rand::{Rng, SeedableRng};

    /// `s = b − A x` of the only cone in `rows`.
    fn slack(rows: ConeRows, x: &[f64]) -> Vec<f64> {
        let (a, mut s, _) = rows.into_parts(x.len());
        subtract_a_x(&a, x, &mut s);
        s
    }

    #[test]
    fn the_com_cone_holds_exactly_where_the_com_lmi_does() {
        // Random rotated ellipsoids and bodies (mass, CoM inside or outside), in scaled
        // variables: the second-order cone of `com_rows` and the 4×4 LMI agree on membership,
        // and the cone's margin has the LMI's sign.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (mut inside, mut outside) = (0, 0);
        for _ in 0..400 {
            let axes = Vector3::from_fn(|_, _| rng.random_range(0.02..0.4));
            let rot =
                Rotation3::from_scaled_axis(Vector3::from_fn(|_, _| rng.random_range(-2.0..2.0)));
            let center = Vector3::from_fn(|_, _| rng.random_range(-0.3..0.3));
            let e = Ellipsoid {
                center,
                qs: rot.matrix()
                    * nalgebra::Matrix3::from_diagonal(&axes.component_mul(&axes))
                    * rot.matrix().transpose(),
            };
            let m = rng.random_range(0.0..5.0);
            let dir = Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0));
            let com = center + rot.matrix() * axes.component_mul(&dir) * rng.random_range(0.0..1.6);
            let h = com * m;
            let d: Vec<f64> = (0..10).map(|_| rng.random_range(0.5..2.0)).collect();
            let x: Vec<f64> = [m, h.x, h.y, h.z]
                .iter()
                .zip(&d)
                .map(|(t, s)| t / s)
                .chain([0.0; 6])
                .collect();
            let lmi_min = nalgebra::SymmetricEigen::new(e.com_lmi(m, &h))
                .eigenvalues
                .min();
            if lmi_min.abs() < 1e-9 {
                continue;
            }
            let mut rows = ConeRows::default();
            com_rows(&mut rows, &e, 0, &d);
            let s = slack(rows, &x);
            assert_eq!(s.len(), 4);
            let margin = s[0] - (s[1] * s[1] + s[2] * s[2] + s[3] * s[3]).sqrt();
            assert_eq!(
                margin >= 0.0,
                lmi_min >= 0.0,
                "margin {margin:e}, λ_min {lmi_min:e}"
            );
            if lmi_min >= 0.0 {
                inside += 1;
            } else {
                outside += 1;
            }
        }
        assert!(
            inside > 100 && outside > 100,
            "{inside} inside, {outside} outside"
        );
    }

    #[test]
    fn a_flat_ellipsoid_keeps_the_com_lmi() {
        let flat = Ellipsoid::axis_aligned(Vector3::zeros(), Vector3::new(0.1, 0.1, 0.0));
        let mut rows = ConeRows::default();
        com_rows(&mut rows, &flat, 0, &[1.0; 10]);
        let (_, b, cones) = rows.into_parts(10);
        assert_eq!(b.len(), 10);
        assert!(matches!(cones[0], SupportedConeT::PSDTriangleConeT(4)));
    }
}
