//! The paper's validation-error-versus-sample-size experiment (its last figure), with ground
//! truth: for each seed, simulate the scenario once; for each training size `n_s` on a grid and
//! each constraint set, identify on the first `n_s` samples and validate on the next
//! `validation` samples; record per-joint validation RMS, parameter errors against the truth,
//! physical consistency and solve time.
//!
//! Work is reused: the regressor of every sample is computed once per seed and the normal
//! equations grow incrementally along the size grid. Seeds run in parallel (rayon), and within a
//! seed its (size, set) cells (twenty seeds alone would keep at most twenty threads busy, the
//! last few seeds alone at the end); rows come back in (seed, size, set) order, so results are
//! identical whatever the thread count.
//!
//! A floor of physid (docs/architecture.md §6) of its own crate, `physid-experiment`; the `physid`
//! crate re-exports it as `physid::experiment`.
#![warn(missing_docs)]

use nalgebra::{DMatrix, DVector};
use physid_core::model::Model;
use physid_core::spatial::InertialParams;
use physid_ident::{self as ident, ConstraintSet, NormalEquations, Options};
use physid_sim::scenario::Scenario;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;

pub mod compare;
pub mod motions;
pub mod plots;
pub mod sweep;
pub mod tables;
pub mod whole_robot;
#[cfg(test)]
mod whole_robot_tests;
use serde::{Deserialize, Serialize};

/// The `[experiment]` table of a scenario file.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ExperimentSpec {
    /// Number of seeds (simulated experiments).
    #[serde(default = "seeds")]
    pub seeds: usize,
    /// First seed; seeds are `first_seed .. first_seed + seeds`.
    #[serde(default = "first_seed")]
    pub first_seed: u64,
    /// Training sizes (samples); default a log grid of `points` sizes from `min_size` to
    /// `max_size`.
    pub sizes: Option<Vec<usize>>,
    /// Smallest training size of the default grid.
    #[serde(default = "min_size")]
    pub min_size: usize,
    /// Largest training size of the default grid.
    #[serde(default = "max_size")]
    pub max_size: usize,
    /// Grid points.
    #[serde(default = "points")]
    pub points: usize,
    /// Validation samples after each training window (the paper: 10,000).
    #[serde(default = "validation")]
    pub validation: usize,
    /// Constraint sets to compare (default all four).
    #[serde(default = "all_sets")]
    pub constraints: Vec<ConstraintSet>,
    /// Prior weight `w`.
    #[serde(default = "prior_weight")]
    pub prior_weight: f64,
    /// Training windows: `"first"` (the first n_s samples, the paper) or `"random"` (n_s
    /// consecutive samples at a random start, validated on the samples that follow them).
    #[serde(default)]
    pub windows: Windows,
    /// Relative error of the "CAD" prior: masses, principal inertias and friction are scaled by
    /// `1 + e·n` and the CoM moved by `e/10` m·n, `n ~ N(0, 1)` drawn from the prior seed.
    #[serde(default = "prior_error")]
    pub prior_error: f64,
    /// The excitation axis: motions to compare, each a scenario file (relative to this one)
    /// whose excitation, simulation and sensors replace this scenario's (its robot must be
    /// the same); empty: this scenario's own motion alone ([`motions`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub excitations: Vec<motions::ExcitationEntry>,
    /// Validate every model on an independent run of this motion (a name in `excitations`,
    /// simulated with seed + 1,000,000) instead of on the samples after its training window,
    /// so that motions are compared on the same data.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub validate_on: Option<String>,
}

impl ExperimentSpec {
    /// The `[experiment]` table of a scenario (defaults when it has none); unknown keys are
    /// errors naming the key.
    pub fn from_scenario(sc: &Scenario) -> Result<Self, toml::de::Error> {
        match &sc.experiment {
            None => Ok(Self::default()),
            Some(table) => table.clone().try_into(),
        }
    }
}

/// Where the training window starts.
#[derive(
    Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq, schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum Windows {
    /// At sample 0.
    #[default]
    First,
    /// At a random sample (drawn from the seed), per size.
    Random,
}

fn seeds() -> usize {
    20
}
fn first_seed() -> u64 {
    1
}
fn min_size() -> usize {
    10
}
fn max_size() -> usize {
    10_000
}
fn points() -> usize {
    12
}
fn validation() -> usize {
    10_000
}
fn all_sets() -> Vec<ConstraintSet> {
    ConstraintSet::ALL.to_vec()
}
fn prior_weight() -> f64 {
    1e-6
}
fn prior_error() -> f64 {
    0.2
}

impl Default for ExperimentSpec {
    fn default() -> Self {
        Self {
            seeds: seeds(),
            first_seed: first_seed(),
            sizes: None,
            min_size: min_size(),
            max_size: max_size(),
            points: points(),
            validation: validation(),
            constraints: all_sets(),
            prior_weight: prior_weight(),
            prior_error: prior_error(),
            windows: Windows::First,
            excitations: vec![],
            validate_on: None,
        }
    }
}

impl ExperimentSpec {
    /// The training sizes, ascending and distinct.
    pub fn grid(&self) -> Vec<usize> {
        let mut g = match &self.sizes {
            Some(s) => s.clone(),
            None => {
                let (a, b) = ((self.min_size.max(1)) as f64, (self.max_size.max(1)) as f64);
                let k = self.points.max(2);
                (0..k)
                    .map(|i| (a * (b / a).powf(i as f64 / (k - 1) as f64)).round() as usize)
                    .collect()
            }
        };
        g.sort_unstable();
        g.dedup();
        g
    }

    /// Checks the values; errors name the key.
    pub fn validate(&self) -> Result<(), physid_sim::scenario::ScenarioError> {
        let e = |key: &str, reason: String| {
            Err(physid_sim::scenario::ScenarioError {
                key: format!("experiment.{key}"),
                reason,
            })
        };
        if self.seeds == 0 {
            return e("seeds", "must be at least 1".into());
        }
        let log_grid = (self.min_size, self.max_size, self.points);
        if self.sizes.is_some() && log_grid != (min_size(), max_size(), points()) {
            return e("sizes", format!("given with min_size/max_size/points ({}, {}, {}), which it replaces: give the sizes or the log grid, not both (a sweep over min_size would change nothing)", log_grid.0, log_grid.1, log_grid.2));
        }
        if self.sizes.is_none() && self.min_size > self.max_size {
            return e(
                "min_size",
                format!("{} is above max_size {}", self.min_size, self.max_size),
            );
        }
        if self.grid().first().is_none_or(|&s| s == 0) {
            return e("sizes", "need positive training sizes".into());
        }
        if self.validation == 0 {
            return e("validation", "must be at least 1".into());
        }
        let largest = self.grid().last().copied().unwrap_or(0);
        if largest.saturating_add(self.validation) > MAX_EXPERIMENT_SAMPLES {
            return e(
                "sizes",
                format!(
                    "the largest training size {largest} and {} validation samples are more than the {MAX_EXPERIMENT_SAMPLES} samples one simulated run may hold",
                    self.validation
                ),
            );
        }
        if self.constraints.is_empty() {
            return e("constraints", "name at least one set".into());
        }
        if !(self.prior_weight.is_finite() && self.prior_weight > 0.0) {
            return e(
                "prior_weight",
                format!(
                    "{} must be > 0 (the small sizes need the prior)",
                    self.prior_weight
                ),
            );
        }
        motions::validate_entries(&self.excitations, self.validate_on.as_deref())?;
        if !(self.prior_error.is_finite() && self.prior_error >= 0.0 && self.prior_error < 0.5) {
            return e(
                "prior_error",
                format!("{} must be in [0, 0.5)", self.prior_error),
            );
        }
        Ok(())
    }
}

/// The most samples an experiment's run may hold (the simulation's bound, 1e8).
pub const MAX_EXPERIMENT_SAMPLES: usize = 100_000_000;

/// One (seed, size, set) cell.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Row {
    /// Seed of the simulated experiment.
    pub seed: u64,
    /// Training samples.
    pub n_s: usize,
    /// Constraint set.
    pub constraints: ConstraintSet,
    /// Validation RMS per joint (N m), joints in model order, `;`-joined in CSV.
    pub val_rms: Vec<f64>,
    /// Validation RMS over all joints (N m).
    pub val_rms_overall: f64,
    /// Training RMS over all joints (N m).
    pub train_rms_overall: f64,
    /// RMS over all joints of the identified model's torque minus the true model's on the
    /// validation samples' measured states, `Y (θ̂ − θ)` (N m): the prediction error without
    /// the sensor noise, comparable across motions.
    #[serde(default)]
    pub val_truth_rms: f64,
    /// Mean relative mass error over bodies.
    pub mass_err: f64,
    /// Mean CoM error over bodies (m).
    pub com_err: f64,
    /// Mean relative error of the inertia about the CoM (Frobenius) over bodies.
    pub inertia_err: f64,
    /// Mean relative Frobenius error of the pseudo-inertia `J` over bodies.
    pub j_err: f64,
    /// Per body (links, then rotors): `[mass, CoM (m), inertia, J]` errors as above.
    pub body_errors: Vec<[f64; 4]>,
    /// Every body's `J(π) ≻ 0`.
    pub consistent: bool,
    /// Solver status.
    pub status: String,
    /// Solve time (s).
    pub solve_s: f64,
}

/// A "CAD" prior: the truth with relative errors of size `e`, physically consistent.
pub fn cad_prior<R: ident::Parameterized + ?Sized>(model: &R, e: f64, seed: u64) -> DVector<f64> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let nrm = Normal::new(0.0, 1.0).expect("unit normal");
    let truth = model.parameters();
    let mut prior = truth.clone();
    for (_, c, _) in model.inertial_bodies() {
        let p = InertialParams(truth.fixed_rows::<10>(c).into_owned());
        let (m, com, ic) = (
            p.mass(),
            p.com().unwrap_or_default(),
            p.inertia_about_com().unwrap_or_default(),
        );
        let mut draw = || nrm.sample(&mut rng);
        let m2 = m * (1.0 + e * draw()).max(0.2);
        let c2 = com + nalgebra::Vector3::new(draw(), draw(), draw()) * (e / 10.0);
        let ic2 = ic * (1.0 + e * draw()).max(0.2);
        prior
            .rows_mut(c, 10)
            .copy_from(&InertialParams::from_mass_com_inertia(m2, &c2, &ic2).0);
    }
    for c in model.friction_columns().0..model.parameter_count() {
        prior[c] = (truth[c] * (1.0 + e * nrm.sample(&mut rng))).max(0.0);
    }
    prior
}

/// Per-body parameter errors of `theta` against the model's truth, links then rotors:
/// `[|Δm|/m, ‖Δc‖ (m), ‖ΔI_C‖/‖I_C‖, ‖ΔJ‖/‖J‖]` (Frobenius norms; CoM and inertia about the CoM
/// are NaN when the identified mass is not positive).
pub fn body_errors<R: ident::Parameterized + ?Sized>(
    model: &R,
    theta: &DVector<f64>,
) -> Vec<[f64; 4]> {
    let truth = model.parameters();
    model
        .inertial_bodies()
        .iter()
        .map(|(_, c, _)| {
            let t = InertialParams(truth.fixed_rows::<10>(*c).into_owned());
            let h = InertialParams(theta.fixed_rows::<10>(*c).into_owned());
            [
                ((h.mass() - t.mass()) / t.mass()).abs(),
                match (h.com(), t.com()) {
                    (Some(a), Some(b)) => (a - b).norm(),
                    _ => f64::NAN,
                },
                match (h.inertia_about_com(), t.inertia_about_com()) {
                    (Some(a), Some(b)) => (a - b).norm() / b.norm(),
                    _ => f64::NAN,
                },
                (h.pseudo_inertia() - t.pseudo_inertia()).norm() / t.pseudo_inertia().norm(),
            ]
        })
        .collect()
}

/// Mean of [`body_errors`] over bodies: (mass, CoM, inertia, J).
pub fn parameter_errors<R: ident::Parameterized + ?Sized>(
    model: &R,
    theta: &DVector<f64>,
) -> [f64; 4] {
    let per = body_errors(model, theta);
    std::array::from_fn(|k| per.iter().map(|e| e[k]).sum::<f64>() / per.len() as f64)
}

/// Errors of an experiment.
#[derive(Debug, thiserror::Error)]
pub enum ExperimentError {
    /// A bad value.
    #[error("{0}")]
    Spec(#[from] physid_sim::scenario::ScenarioError),
    /// A simulation failed.
    #[error("seed {seed}: {source}")]
    Sim {
        /// The seed.
        seed: u64,
        /// What failed.
        source: physid_sim::simulate::SimError,
    },
    /// An identification failed.
    #[error("seed {seed}, n_s = {n_s}, {set}: {source}")]
    Ident {
        /// The seed.
        seed: u64,
        /// Training size.
        n_s: usize,
        /// Constraint set.
        set: &'static str,
        /// What failed.
        source: ident::IdentError,
    },
    /// A motion of the excitation axis could not be loaded.
    #[error("experiment.excitations '{name}': {source}")]
    Motion {
        /// Its name.
        name: String,
        /// What failed.
        source: physid_io::IoError,
    },
    /// A motion's scenario describes another robot.
    #[error("experiment.excitations '{name}': {} describes another robot than the experiment's (the motions must share the robot and its ground truth)", path.display())]
    DifferentRobot {
        /// Its name.
        name: String,
        /// Its scenario file.
        path: std::path::PathBuf,
    },
}

/// Runs one seed: simulate, then every (size, set) cell.
pub fn run_seed(
    model: &Model,
    scenario: &Scenario,
    spec: &ExperimentSpec,
    seed: u64,
) -> Result<Vec<Row>, ExperimentError> {
    run_seed_validated_on(model, scenario, spec, seed, None)
}

/// [`run_seed`], validating every cell on the first `spec.validation` samples of `validation`
/// (processed, with q̈) when given instead of on the samples after the training window.
pub fn run_seed_validated_on(
    model: &Model,
    scenario: &Scenario,
    spec: &ExperimentSpec,
    seed: u64,
    validation: Option<&physid_core::trajectory::Trajectory>,
) -> Result<Vec<Row>, ExperimentError> {
    let grid = spec.grid();
    let max_n = *grid.last().expect("validated grid");
    let processed = simulated_run(model, scenario, spec, seed, max_n)?;
    let data = &processed;
    let (n, p) = (model.dof(), model.layout().len);
    let total = (max_n + spec.validation).min(data.len());
    // Every sample's regressor once (n × p each, column-major).
    let ys = regressors(model, data, 0..total);
    let ys_val = validation.map(|v| regressors(model, v, 0..spec.validation.min(v.len())));
    let val_data = validation.unwrap_or(data);
    let prior = cad_prior(model, spec.prior_error, 1_000_003 ^ seed);
    let truth = model.parameters();
    let windows = training_windows(spec, (&grid, seed), (&ys, data), total, (n, p));
    // Every (size, set) cell on its own: in parallel, read back in (size, set) order.
    let cells: Vec<(&Window, ConstraintSet)> = windows
        .iter()
        .flat_map(|w| spec.constraints.iter().map(move |&set| (w, set)))
        .collect();
    cells
        .par_iter()
        .map(|&(w, set)| {
            let (n_s, start) = (w.n_s, w.start);
            // Validation: the samples after the window, or the separate validation run.
            let after = start + n_s..(start + n_s + spec.validation).min(total);
            let (vys, vtr, vrange) = match &ys_val {
                Some(yv) => (yv.as_slice(), val_data, 0..yv.len()),
                None => (ys.as_slice(), data, after),
            };
            let r = identify_with(model, &w.equations, &prior, (spec, set), (seed, n_s))?;
            let (val_rms, val_rms_overall) = torque_rms(vys, vtr, &r.theta, vrange.clone());
            let (_, train_rms_overall) = torque_rms(&ys, data, &r.theta, start..start + n_s);
            Ok(Row {
                seed,
                n_s,
                constraints: set,
                val_rms,
                val_rms_overall,
                train_rms_overall,
                val_truth_rms: model_rms(vys, &(&r.theta - &truth), vrange.clone()),
                ..errors_of(model, &r)
            })
        })
        .collect()
}

/// One training window of a seed: its size, its first sample, its normal equations.
struct Window {
    n_s: usize,
    start: usize,
    equations: NormalEquations,
}

/// The training window of every size of `grid`, in order: windows from the first sample
/// share one running sum, random ones ([`window_start`]) are summed on their own.
fn training_windows(
    spec: &ExperimentSpec,
    (grid, seed): (&[usize], u64),
    (ys, data): (&[DMatrix<f64>], &physid_core::trajectory::Trajectory),
    total: usize,
    (n, p): (usize, usize),
) -> Vec<Window> {
    let mut ne = NormalEquations::new(n, p);
    let mut added = 0;
    let mut window_rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x77_1d0e);
    let mut out = vec![];
    for &n_s in grid {
        // Training samples start..start + n_s, validation on the next `validation` samples.
        let start = window_start(spec, &mut window_rng, n_s, total);
        let equations = if start == 0 {
            while added < n_s.min(total) {
                ne.add(&ys[added], data.tau_at(added));
                added += 1;
            }
            ne.clone().finish()
        } else {
            window_equations(ys, data, start..start + n_s, (n, p))
        };
        out.push(Window {
            n_s,
            start,
            equations,
        });
    }
    out
}

/// The first training sample of the window of `n_s` samples among `total`: the first sample,
/// or (random windows) a draw that leaves room for the validation samples after it.
fn window_start(
    spec: &ExperimentSpec,
    rng: &mut rand_chacha::ChaCha8Rng,
    n_s: usize,
    total: usize,
) -> usize {
    match spec.windows {
        Windows::First => 0,
        // The simulation covers max_n + validation samples, so the room is never negative.
        Windows::Random => {
            rand::Rng::random_range(rng, 0..=total.saturating_sub(n_s + spec.validation))
        }
    }
}

/// Identification of `snapshot` under constraint set `set` with the experiment's prior weight;
/// an error names the seed, training size and set.
fn identify_with(
    model: &Model,
    snapshot: &NormalEquations,
    prior: &DVector<f64>,
    (spec, set): (&ExperimentSpec, ConstraintSet),
    (seed, n_s): (u64, usize),
) -> Result<ident::Identified, ExperimentError> {
    let mut o = Options::new(set);
    o.prior_weight = spec.prior_weight;
    ident::identify(model, snapshot, prior, &o).map_err(|source| ExperimentError::Ident {
        seed,
        n_s,
        set: set.name(),
        source,
    })
}

/// The normal equations of the samples `window` of `tr` (`ys` its regressors, indexed like it;
/// `n` joints, `p` parameters).
fn window_equations(
    ys: &[DMatrix<f64>],
    tr: &physid_core::trajectory::Trajectory,
    window: std::ops::Range<usize>,
    (n, p): (usize, usize),
) -> NormalEquations {
    let mut w = NormalEquations::new(n, p);
    for (k, y) in ys.iter().enumerate().skip(window.start).take(window.len()) {
        w.add(y, tr.tau_at(k));
    }
    w.finish()
}

/// The seed's simulated run, long enough for the largest window `max_n` and the validation
/// samples, processed, with the processing's unsettled ends cut off.
fn simulated_run(
    model: &Model,
    scenario: &Scenario,
    spec: &ExperimentSpec,
    seed: u64,
    max_n: usize,
) -> Result<physid_core::trajectory::Trajectory, ExperimentError> {
    let mut sc = scenario.clone();
    sc.simulation.seed = seed;
    // The processing's ends are left out of every fit and score: the experiment runs that long
    // again at each end.
    let settle = physid_sim::simulate::settle_samples(&sc, sc.simulation.rate);
    sc.simulation.duration = (max_n + spec.validation + 1 + 2 * settle) as f64 / sc.simulation.rate;
    let rec = physid_sim::run(model, &sc, &mut |_| {})
        .map_err(|source| ExperimentError::Sim { seed, source })?;
    Ok(rec.processed.slice(settle..rec.processed.len() - settle))
}

/// Every sample's regressor over `range` of `tr` (n × p each, column-major).
fn regressors(
    model: &Model,
    tr: &physid_core::trajectory::Trajectory,
    range: std::ops::Range<usize>,
) -> Vec<DMatrix<f64>> {
    let mut ys = Vec::with_capacity(range.len());
    ident::normal::for_each_regressor(model, tr, range, &mut |_, y| ys.push(y.clone()));
    ys
}

/// Per joint and overall RMS (N m) of `Y_k θ − τ_k` over the samples `range` of `tr` (`ys`
/// indexed like `tr`).
fn torque_rms(
    ys: &[DMatrix<f64>],
    tr: &physid_core::trajectory::Trajectory,
    theta: &DVector<f64>,
    range: std::ops::Range<usize>,
) -> (Vec<f64>, f64) {
    let n = tr.dof();
    let mut ss = vec![0.0; n];
    for k in range.clone() {
        let pred = &ys[k] * theta;
        for j in 0..n {
            ss[j] += (pred[j] - tr.tau_at(k)[j]).powi(2);
        }
    }
    let c = range.len().max(1) as f64;
    (
        ss.iter().map(|s| (s / c).sqrt()).collect(),
        (ss.iter().sum::<f64>() / (c * n as f64)).sqrt(),
    )
}

/// A row's parameter errors against the truth, consistency and solver fields for the
/// identified `r` (the torque errors left at zero for the caller).
fn errors_of(model: &Model, r: &ident::Identified) -> Row {
    let [mass_err, com_err, inertia_err, j_err] = parameter_errors(model, &r.theta);
    Row {
        seed: 0,
        n_s: 0,
        constraints: ConstraintSet::None,
        val_rms: vec![],
        val_rms_overall: 0.0,
        train_rms_overall: 0.0,
        val_truth_rms: 0.0,
        mass_err,
        com_err,
        inertia_err,
        j_err,
        body_errors: body_errors(model, &r.theta),
        consistent: ident::constraints_hold(model, &r.theta, ConstraintSet::Consistent),
        status: r.solver.status.to_string(),
        solve_s: r.solver.seconds,
    }
}

/// RMS over the samples `range` of `ys` and over joints of `Y_k e` (N m for a parameter error
/// `e`).
fn model_rms(ys: &[DMatrix<f64>], e: &DVector<f64>, range: std::ops::Range<usize>) -> f64 {
    let (mut ss, mut c) = (0.0, 0usize);
    for y in &ys[range] {
        let t = y * e;
        ss += t.norm_squared();
        c += t.len();
    }
    (ss / c.max(1) as f64).sqrt()
}

/// Runs the whole experiment, seeds in parallel on the current rayon pool. `progress(done,
/// total)` is called as seeds finish.
pub fn run(
    model: &Model,
    scenario: &Scenario,
    spec: &ExperimentSpec,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Vec<Row>, ExperimentError> {
    spec.validate()?;
    let seeds: Vec<u64> = (0..spec.seeds as u64)
        .map(|i| spec.first_seed + i)
        .collect();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let per_seed: Vec<Vec<Row>> = seeds
        .par_iter()
        .map(|&s| {
            let r = run_seed(model, scenario, spec, s);
            progress(
                done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1,
                seeds.len(),
            );
            r
        })
        .collect::<Result<_, _>>()?;
    Ok(per_seed.into_iter().flatten().collect())
}

/// The fraction of `xs` that hold (NaN when there are none: a score of nothing is no score).
pub fn fraction(xs: impl IntoIterator<Item = bool>) -> f64 {
    let (hold, all) = xs
        .into_iter()
        .fold((0usize, 0usize), |(h, n), x| (h + usize::from(x), n + 1));
    if all == 0 {
        f64::NAN
    } else {
        hold as f64 / all as f64
    }
}

/// The median of the finite values of `v` (NaN when there are none: a median of nothing is no
/// score, not a perfect one).
pub fn median(v: &[f64]) -> f64 {
    median_iqr(v).1
}

/// Median and interquartile range of `v` (NaN-free values only).
pub fn median_iqr(v: &[f64]) -> (f64, f64, f64) {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if s.is_empty() {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    s.sort_by(f64::total_cmp);
    let q = |f: f64| {
        let x = f * (s.len() - 1) as f64;
        let (i, t) = (x.floor() as usize, x - x.floor());
        s[i] + t * (s[(i + 1).min(s.len() - 1)] - s[i])
    };
    (q(0.25), q(0.5), q(0.75))
}
