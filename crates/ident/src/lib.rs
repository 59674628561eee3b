//! Identification under the paper's four constraint sets (eq. 10):
//!
//! `min_θ (1/n_s) Σ_k ‖Y_k θ − τ_k‖² + w ‖θ − θ̂‖²`, with per body (links and rotors)
//! - `none`: no constraint (ordinary least squares, solved directly);
//! - `semi`: `I(π) ⪰ ε 1` (6×6);
//! - `consistent`: `J(π) ⪰ ε 1` (4×4);
//! - `ellipsoid`: `J(π) ⪰ ε 1`, `tr(J(π) Q) ≥ ε` and `C(π) ⪰ 0` for the body's bounding
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
mod cone;
mod dense;
pub mod floating;
pub mod floating_log;
pub mod information;
mod interior;
pub mod lmi;
pub mod normal;
mod structure;

pub use normal::{NormalEquations, RowSums};
pub use structure::Parameterized;

use nalgebra::{DMatrix, DVector};
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
    /// Try the dense interior-point method (`dense.rs`) before Clarabel on programs of
    /// orthants and PSD cones. It stops on Clarabel's measures and tolerances, so the objective
    /// is as good, in about half the time; but along directions the objective is flat in, its
    /// parameters are less reproducible (two programs equal up to round-off: 4e-4 relative
    /// apart, against 6e-6 with Clarabel). The diagnosis's cross-validation fits, which only
    /// compare held-out errors, set it; identification itself does not.
    pub dense_solver: bool,
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
            dense_solver: false,
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
    /// The cone solver (physid's dense interior-point method, or Clarabel): solved to
    /// Clarabel's full tolerances.
    Solved,
    /// The cone solver: solved to reduced tolerances only (Clarabel's own; the dense method's,
    /// a fiftieth of them, where it stops short of the full ones).
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
pub fn objective<R: Parameterized + ?Sized>(
    model: &R,
    ne: &NormalEquations,
    prior: &DVector<f64>,
    opts: &Options,
) -> Objective {
    let m = ne.samples as f64;
    let logdet = opts.regularizer == Regularizer::LogDet;
    // The Euclidean prior weight applies to every parameter, or only to friction under log-det.
    let first_friction = model.friction_columns().0;
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
    model.inertial_bodies()
}

/// Whether `theta` satisfies `set` (with `ε` relaxed to strict positivity and a round-off
/// tolerance on the linear and CoM conditions).
pub fn constraints_hold<R: Parameterized + ?Sized>(
    model: &R,
    theta: &DVector<f64>,
    set: ConstraintSet,
) -> bool {
    let friction = model.friction_columns().0..model.parameter_count();
    let friction_ok = friction.into_iter().all(|c| theta[c] >= -1e-9);
    model.inertial_bodies().iter().all(|(_, c, e)| {
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
fn check_problem<R: Parameterized + ?Sized>(
    model: &R,
    ne: &NormalEquations,
    prior: &DVector<f64>,
    opts: &Options,
) -> Result<(), IdentError> {
    let p = ne.yty.nrows();
    if p < model.parameter_count() || prior.len() != p {
        return Err(IdentError::Shape {
            columns: p,
            prior: prior.len(),
            params: model.parameter_count(),
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
    let rows = ns * ne.rows_per_sample();
    if ns == 0 || (opts.prior_weight == 0.0 && rows < p) {
        return Err(IdentError::TooFewSamples {
            samples: ns,
            rows,
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
pub fn identify<R: Parameterized + ?Sized>(
    model: &R,
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
    let (theta, solver) = optimum(model, (&h, &g), prior, opts)?;
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

/// The minimizer of `θᵀ h θ − 2 gᵀ θ` under `opts`: least squares where nothing constrains
/// it, the unconstrained optimum where it satisfies every constraint, else the cone program's.
fn optimum<R: Parameterized + ?Sized>(
    model: &R,
    (h, g): (&DMatrix<f64>, &DVector<f64>),
    prior: &DVector<f64>,
    opts: &Options,
) -> Result<(DVector<f64>, SolverInfo), IdentError> {
    let found_without_solver = |status| SolverInfo {
        status,
        iterations: 0,
        seconds: 0.0,
        residuals: [0.0; 2],
    };
    if opts.solved_directly() {
        let theta = physid_core::linalg::least_squares(h, g);
        return Ok((theta, found_without_solver(SolveStatus::Direct)));
    }
    let groups = cone::groups(model, opts)?;
    match interior::optimum(&groups, h, g, opts) {
        Some(theta) => Ok((theta, found_without_solver(SolveStatus::Interior))),
        None => cone::solve(model, h, g, prior, opts),
    }
}

fn result<R: Parameterized + ?Sized>(
    model: &R,
    theta: DVector<f64>,
    set: ConstraintSet,
    objective: f64,
    solver: SolverInfo,
) -> Identified {
    let (viscous_col, coulomb_col) = model.friction_columns();
    let n = model.joints();
    let bodies = model
        .inertial_bodies()
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
        viscous: (0..n).map(|i| theta[viscous_col + i]).collect(),
        coulomb: (0..n).map(|i| theta[coulomb_col + i]).collect(),
        objective,
        constraints_hold: constraints_hold(model, &theta, set),
        theta,
        solver,
    }
}

/// `Σ_b d(J_b, Ĵ_b)`, the log-det Bregman divergence summed over bodies; `None` if some `J_b`
/// or `Ĵ_b` is not positive definite.
pub fn bregman_logdet<R: Parameterized + ?Sized>(
    model: &R,
    theta: &DVector<f64>,
    prior: &DVector<f64>,
) -> Option<f64> {
    let mut total = 0.0;
    for (_, c, _) in model.inertial_bodies() {
        let j = InertialParams(theta.fixed_rows::<10>(c).into_owned()).pseudo_inertia();
        let j0 = InertialParams(prior.fixed_rows::<10>(c).into_owned()).pseudo_inertia();
        let ch0 = j0.cholesky()?;
        let chj = j.cholesky()?;
        let logdet = |l: &nalgebra::Matrix4<f64>| 2.0 * (0..4).map(|i| l[(i, i)].ln()).sum::<f64>();
        total += -(logdet(&chj.l()) - logdet(&ch0.l())) + (ch0.inverse() * j).trace() - 4.0;
    }
    Some(total)
}
