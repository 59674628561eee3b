//! The paper's question for the whole robot: which constraint set gives the best model of a
//! floating quadruped from how much data, in each of the data settings users have
//! ([`DataSetting`]).
//!
//! Per seed the quadruped stands and shifts its weight twice ([`physid_sim::floating`]): a
//! training run (seed `s`) and a validation run (seed `s + 1000`, other frequencies and
//! phases). The training run's motor torques and contact forces are measured with Gaussian
//! noise; a foot is in contact when its measured normal force exceeds `contact_threshold`.
//! For each setting the normal equations grow along the training samples, and at each size of
//! the grid every constraint set identifies the robot with a "CAD" prior (the truth with
//! relative errors `prior_error`, weight `prior_weight`). Each model is scored on the
//! validation run by the joint torques it predicts from the true motion and contact forces
//! (`τ = (Y θ)_q − Σ J_c,qᵀ λ_c`) against the true torques, and by its parameter errors against
//! the truth. Seeds run in parallel; rows come back in (seed, setting, size, set) order.
//!
//! With [`WholeRobotSpec::logged`] the training run is instead logged as its sensors give it
//! (an IMU and a state estimator for the trunk, with noise and bias; joint encoders; noisy
//! torques and forces) and read back as `identify-floating` reads a log: the sizes count the
//! samples the data pipeline keeps (with joint torques alone, those away from a change of the
//! feet down; a size beyond them has no rows), the feet down are the log's contact states.

use super::{cad_prior, parameter_errors};
use nalgebra::{DMatrix, DVector};
use physid_core::dynamics::{point_jacobian_floating, regressor_floating, Data};
use physid_core::model::floating::FloatingModel;
use physid_ident::floating::{Contact, DataSetting, FloatingRows, FloatingSample};
use physid_ident::floating_log::{log_samples, LogSamples, LogSampling};
use physid_ident::{self as ident, ConstraintSet, NormalEquations, Options};
use physid_sim::floating::{standing, FloatingRun, FloatingSimError, Standing};
use physid_sim::floating_sensors::Sensors;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;

/// The whole-robot experiment.
#[derive(Clone, Debug)]
pub struct WholeRobotSpec {
    /// The experiment each run follows (its seed is replaced per run).
    pub motion: Standing,
    /// Training sizes (samples, ascending); the training run lasts as long as the largest.
    pub sizes: Vec<usize>,
    /// Validation samples (every tenth step of a run of ten times as many).
    pub validation: usize,
    /// Constraint sets to compare.
    pub sets: Vec<ConstraintSet>,
    /// Data settings to compare.
    pub settings: Vec<DataSetting>,
    /// Seeds.
    pub seeds: Vec<u64>,
    /// Standard deviation of the motor torques' noise (N m).
    pub torque_noise: f64,
    /// Standard deviation of each contact force component's noise (N).
    pub force_noise: f64,
    /// Relative error of the prior's parameters.
    pub prior_error: f64,
    /// Prior weight `w`.
    pub prior_weight: f64,
    /// Train on the training run as its sensors log it ([`physid_sim::floating_sensors`]: the
    /// trunk's pose and twist from an IMU and a state estimator, and the IMU's accelerometer,
    /// with noise and bias; torque and force noise of this spec's sizes), read back through the data pipeline
    /// ([`physid_ident::floating_log`]: q̇, q̈ and the trunk's acceleration derived, torques and
    /// forces filtered alike), instead of on the true motion with noisy torques and forces.
    pub logged: bool,
}

impl Default for WholeRobotSpec {
    fn default() -> Self {
        Self {
            motion: Standing::default(),
            sizes: vec![100, 300, 1000, 3000],
            validation: 500,
            sets: vec![
                ConstraintSet::None,
                ConstraintSet::Semi,
                ConstraintSet::Consistent,
                ConstraintSet::Ellipsoid,
            ],
            settings: vec![
                DataSetting::TorquesAndContacts,
                DataSetting::TorquesOnly,
                DataSetting::BaseOnly,
            ],
            seeds: vec![1],
            torque_noise: 0.5,
            force_noise: 2.0,
            prior_error: 0.1,
            prior_weight: 1e-4,
            logged: false,
        }
    }
}

/// One identification of the experiment.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct WholeRobotRow {
    /// Seed.
    pub seed: u64,
    /// The contact forces' noise (N) of the run.
    pub force_noise: f64,
    /// Data setting.
    pub setting: DataSetting,
    /// Training samples.
    pub samples: usize,
    /// Constraint set.
    pub set: ConstraintSet,
    /// Validation RMS of the predicted joint torques (N m).
    pub validation_rms: f64,
    /// The same for the prior's parameters (N m): where identification starts from.
    pub prior_rms: f64,
    /// How the solver finished.
    pub status: ident::SolveStatus,
    /// Mean over bodies of `[|Δm|/m, ‖Δc‖ (m), ‖ΔI_C‖/‖I_C‖, ‖ΔJ‖/‖J‖]`.
    pub errors: [f64; 4],
    /// Whether the identified model satisfies its set.
    pub constraints_hold: bool,
}

/// Why the experiment failed.
#[derive(Debug, thiserror::Error)]
pub enum WholeRobotError {
    /// A bad value in the spec.
    #[error("whole-robot experiment: {0}")]
    Spec(String),
    /// A run diverged.
    #[error("seed {seed}: {source}")]
    Sim {
        /// Seed.
        seed: u64,
        /// What failed.
        source: FloatingSimError,
    },
    /// An identification failed.
    #[error("seed {seed}, {samples} samples, {set:?}: {source}")]
    Ident {
        /// Seed.
        seed: u64,
        /// Training samples.
        samples: usize,
        /// Constraint set.
        set: ConstraintSet,
        /// What failed.
        source: ident::IdentError,
    },
}

/// Runs `spec` on `robot`, whose feet are `feet` (`(body, point)`).
pub fn run(
    robot: &FloatingModel,
    feet: &[(usize, nalgebra::Vector3<f64>)],
    spec: &WholeRobotSpec,
) -> Result<Vec<WholeRobotRow>, WholeRobotError> {
    check(spec)?;
    let per_seed: Vec<Vec<WholeRobotRow>> = spec
        .seeds
        .par_iter()
        .map(|&seed| run_seed(robot, feet, spec, seed))
        .collect::<Result<_, _>>()?;
    Ok(per_seed.into_iter().flatten().collect())
}

impl WholeRobotSpec {
    /// Checks every value against its range.
    pub fn validate(&self) -> Result<(), WholeRobotError> {
        check(self)
    }
}

fn check(spec: &WholeRobotSpec) -> Result<(), WholeRobotError> {
    let bad = |m: String| Err(WholeRobotError::Spec(m));
    if spec.sizes.is_empty() || spec.sizes.windows(2).any(|w| w[0] >= w[1]) || spec.sizes[0] == 0 {
        return bad(format!(
            "sizes must be positive and ascending, got {:?}",
            spec.sizes
        ));
    }
    let nonnegative = [
        ("torque_noise", spec.torque_noise),
        ("force_noise", spec.force_noise),
        ("prior_error", spec.prior_error),
        ("prior_weight", spec.prior_weight),
    ];
    if let Some((name, v)) = nonnegative
        .iter()
        .find(|(_, v)| !(v.is_finite() && *v >= 0.0))
    {
        return bad(format!("{name} must be a number >= 0, got {v}"));
    }
    if spec.validation == 0
        || spec.sets.is_empty()
        || spec.settings.is_empty()
        || spec.seeds.is_empty()
    {
        return bad("validation, sets, settings and seeds must not be empty".into());
    }
    Ok(())
}

/// One seed: its two runs, then every setting, size and set.
fn run_seed(
    robot: &FloatingModel,
    feet: &[(usize, nalgebra::Vector3<f64>)],
    spec: &WholeRobotSpec,
    seed: u64,
) -> Result<Vec<WholeRobotRow>, WholeRobotError> {
    let simulate = |s: u64, seconds: f64| {
        let motion = Standing {
            seed: s,
            duration: seconds,
            ..spec.motion.clone()
        };
        standing(robot, feet, &motion).map_err(|source| WholeRobotError::Sim { seed, source })
    };
    let rate = spec.motion.rate;
    let largest = *spec.sizes.last().expect("checked non-empty");
    // A logged run loses its ends to the pipeline's filter: a second more covers them.
    let margin = if spec.logged { rate } else { 0.0 };
    let truth = simulate(seed, (largest as f64 + margin) / rate)?;
    let validation = simulate(seed + 1000, 10.0 * spec.validation as f64 / rate)?;
    let prior = cad_prior(robot, spec.prior_error, seed);
    let scorer = Scorer::new(robot, &validation, 10);
    let train = (!spec.logged).then(|| measured(&truth, spec, seed));
    let mut rows = vec![];
    for &setting in &spec.settings {
        let grown = match &train {
            Some(train) => grown_from_run(robot, (train, &truth), setting, &spec.sizes),
            None => {
                let samples = logged(robot, &truth, spec, (seed, setting))?;
                grown_from_log(robot, feet, samples, setting, &spec.sizes)
            }
        };
        for (size, ne) in grown {
            let cell = Cell {
                seed,
                setting,
                samples: size,
            };
            rows.extend(identify_sets(robot, &ne, (&prior, &scorer), spec, cell)?);
        }
    }
    Ok(rows)
}

/// The normal equations of the first `size` steps of `measured` in `setting`, for each of
/// `sizes`, the feet in contact where `truth` (the same run before noise) has them loaded.
fn grown_from_run(
    robot: &FloatingModel,
    (measured, truth): (&FloatingRun, &FloatingRun),
    setting: DataSetting,
    sizes: &[usize],
) -> Vec<(usize, NormalEquations)> {
    let mut acc = Accumulator::new(robot, setting);
    let mut added = 0;
    let mut out = vec![];
    for &size in sizes {
        for k in added..size.min(measured.len()) {
            let down: Vec<bool> = truth.contact_at(k).iter().map(|f| f.z > 0.0).collect();
            acc.add(robot, measured, k, &down);
        }
        added = size.min(measured.len());
        out.push((size, acc.ne.clone().finish()));
    }
    out
}

/// The normal equations of the first `size` of the log's `samples` in `setting`, for each of
/// `sizes` the log fills: a size beyond the samples the pipeline kept is not claimed (with
/// joint torques alone, a trot keeps only the samples away from its many touchdowns).
fn grown_from_log(
    robot: &FloatingModel,
    feet: &[(usize, nalgebra::Vector3<f64>)],
    mut samples: LogSamples,
    setting: DataSetting,
    sizes: &[usize],
) -> Vec<(usize, NormalEquations)> {
    let largest = *sizes.last().expect("checked non-empty");
    samples.samples.truncate(largest);
    let per_sample = physid_ident::floating::rows_per_sample(robot, setting);
    let mut ne = NormalEquations::new(per_sample, robot.parameter_count());
    let (mut added, mut out) = (0, vec![]);
    samples.for_each_rows(robot, feet, setting, |y, target, _| {
        ne.add(y, target.as_slice());
        added += 1;
        if sizes.contains(&added) {
            out.push((added, ne.clone().finish()));
        }
    });
    out
}

/// The training run `truth` as its sensors log it (the default sensors with the IMU's
/// accelerometer, torque and force noise of `spec`'s sizes, seeded by `seed`) and read back
/// through the data pipeline for `setting`.
fn logged(
    robot: &FloatingModel,
    truth: &FloatingRun,
    spec: &WholeRobotSpec,
    (seed, setting): (u64, DataSetting),
) -> Result<LogSamples, WholeRobotError> {
    let sensors = Sensors {
        torque_noise: spec.torque_noise,
        force_noise: spec.force_noise,
        accelerometer: true,
        ..Sensors::default()
    };
    let joints = robot.tree().joint_names();
    let feet: Vec<String> = (0..truth.feet.len()).map(|f| format!("foot{f}")).collect();
    let log = physid_sim::floating_sensors::log(truth, (&joints, &feet), &sensors, seed);
    let sampling = LogSampling {
        cutoff: None,
        setting,
        contact_force: 10.0,
        gravity: robot.tree().gravity(),
    };
    log_samples(&log, &sampling).map_err(|e| WholeRobotError::Spec(format!("seed {seed}: {e}")))
}

/// Where in the experiment an identification is.
#[derive(Clone, Copy)]
struct Cell {
    seed: u64,
    setting: DataSetting,
    samples: usize,
}

/// Every constraint set of `spec` on the normal equations `ne` of one cell, scored.
fn identify_sets(
    robot: &FloatingModel,
    ne: &NormalEquations,
    (prior, scorer): (&DVector<f64>, &Scorer),
    spec: &WholeRobotSpec,
    cell: Cell,
) -> Result<Vec<WholeRobotRow>, WholeRobotError> {
    spec.sets
        .iter()
        .map(|&set| {
            let opts = Options {
                prior_weight: spec.prior_weight,
                ..Options::new(set)
            };
            let found = ident::identify(robot, ne, prior, &opts).map_err(|source| {
                WholeRobotError::Ident {
                    seed: cell.seed,
                    samples: cell.samples,
                    set,
                    source,
                }
            })?;
            Ok(WholeRobotRow {
                seed: cell.seed,
                force_noise: spec.force_noise,
                setting: cell.setting,
                samples: cell.samples,
                set,
                validation_rms: scorer.rms(&found.theta),
                prior_rms: scorer.rms(prior),
                status: found.solver.status,
                errors: parameter_errors(robot, &found.theta),
                constraints_hold: found.constraints_hold,
            })
        })
        .collect()
}

/// The normal equations of the first `samples` steps of `measured` in `setting`, the feet in
/// contact where `truth` (the same run before noise) has them loaded.
pub fn normal_equations(
    robot: &FloatingModel,
    (measured, truth): (&FloatingRun, &FloatingRun),
    setting: DataSetting,
    samples: usize,
) -> NormalEquations {
    let mut grown = grown_from_run(robot, (measured, truth), setting, &[samples]);
    grown.pop().expect("one size").1
}

/// The run as the sensors give it: motor torques and contact forces with Gaussian noise of
/// `spec`'s sizes (seeded), the motion as simulated.
pub fn measured(run: &FloatingRun, spec: &WholeRobotSpec, seed: u64) -> FloatingRun {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed.wrapping_mul(7919).wrapping_add(3));
    let unit = Normal::new(0.0, 1.0).expect("unit normal");
    let mut out = run.clone();
    for t in out.tau.iter_mut() {
        *t += spec.torque_noise * unit.sample(&mut rng);
    }
    for f in out.contact.iter_mut() {
        for c in f.iter_mut() {
            *c += spec.force_noise * unit.sample(&mut rng);
        }
    }
    out
}

/// Normal equations of one data setting, grown sample by sample.
struct Accumulator {
    rows: FloatingRows,
    ne: NormalEquations,
    setting: DataSetting,
}

impl Accumulator {
    fn new(robot: &FloatingModel, setting: DataSetting) -> Self {
        let per_sample = physid_ident::floating::rows_per_sample(robot, setting);
        Self {
            rows: FloatingRows::new(robot),
            ne: NormalEquations::new(per_sample, robot.parameter_count()),
            setting,
        }
    }

    /// Adds step `k` of `run`, the feet marked in `down` in contact.
    fn add(&mut self, robot: &FloatingModel, run: &FloatingRun, k: usize, down: &[bool]) {
        let (q, qd, qdd) = run.joints_at(k);
        let contacts: Vec<Contact> = run
            .feet
            .iter()
            .zip(run.contact_at(k))
            .zip(down)
            .filter(|(_, &d)| d)
            .map(|((&(body, point), &force), _)| Contact { body, point, force })
            .collect();
        let sample = FloatingSample {
            base: &run.base[k],
            q,
            qd,
            qdd,
            tau: run.tau_at(k),
            contacts: &contacts,
        };
        let (y, target) = self.rows.rows(robot, &sample, self.setting);
        self.ne.add(&y, target.as_slice());
    }
}

/// Predicted joint torques on a validation run: per kept step the joint rows of `Y` and the
/// true torques plus the contact forces' share, `τ + Σ J_c,qᵀ λ_c`, so that the prediction
/// error of `θ` is `Y_q θ − target`.
struct Scorer {
    y: Vec<DMatrix<f64>>,
    target: Vec<DVector<f64>>,
}

impl Scorer {
    fn new(robot: &FloatingModel, run: &FloatingRun, every: usize) -> Self {
        let n = robot.joints();
        let mut data = Data::new(robot.tree());
        let mut y = DMatrix::zeros(robot.dof(), robot.parameter_count());
        let (mut ys, mut targets) = (vec![], vec![]);
        for k in (0..run.len()).step_by(every) {
            let (q, qd, qdd) = run.joints_at(k);
            let base = &run.base[k];
            regressor_floating(robot, &mut data, base, (q, qd, qdd), &mut y);
            let mut target = DVector::from_column_slice(run.tau_at(k));
            for (&(body, p), f) in run.feet.iter().zip(run.contact_at(k)) {
                let jac = point_jacobian_floating(robot, &mut data, base, q, (body, &p));
                target += jac.columns(6, n).transpose() * DVector::from_column_slice(f.as_slice());
            }
            ys.push(y.rows(6, n).into_owned());
            targets.push(target);
        }
        Self {
            y: ys,
            target: targets,
        }
    }

    /// RMS over steps and joints of the predicted minus the true torques (N m).
    fn rms(&self, theta: &DVector<f64>) -> f64 {
        let (sum, count) = self
            .y
            .iter()
            .zip(&self.target)
            .fold((0.0, 0usize), |(s, c), (y, t)| {
                (s + (y * theta - t).norm_squared(), c + t.len())
            });
        (sum / count.max(1) as f64).sqrt()
    }
}

/// The rows as a long table: `force_noise` (N), `setting`, `n_s`, `constraints`, `seed`, `val_rms` and
/// `prior_rms` (N m), `m_err`, `com_err` (m), `inertia_err`, `j_err`, `consistent`, `status`.
pub fn long_table(
    rows: &[WholeRobotRow],
) -> polars::prelude::PolarsResult<polars::prelude::DataFrame> {
    use polars::prelude::*;
    let col_f = |name: &str, f: &dyn Fn(&WholeRobotRow) -> f64| {
        Column::new(name.into(), rows.iter().map(f).collect::<Vec<f64>>())
    };
    let setting: Vec<String> = rows
        .iter()
        .map(|r| setting_name(r.setting).to_string())
        .collect();
    let set: Vec<String> = rows.iter().map(|r| r.set.name().to_string()).collect();
    DataFrame::new_infer_height(vec![
        col_f("force_noise", &|r| r.force_noise),
        Column::new("setting".into(), setting),
        Column::new(
            "n_s".into(),
            rows.iter().map(|r| r.samples as u64).collect::<Vec<_>>(),
        ),
        Column::new("constraints".into(), set),
        Column::new(
            "seed".into(),
            rows.iter().map(|r| r.seed).collect::<Vec<_>>(),
        ),
        col_f("val_rms", &|r| r.validation_rms),
        col_f("prior_rms", &|r| r.prior_rms),
        col_f("m_err", &|r| r.errors[0]),
        col_f("com_err", &|r| r.errors[1]),
        col_f("inertia_err", &|r| r.errors[2]),
        col_f("j_err", &|r| r.errors[3]),
        col_f("consistent", &|r| f64::from(u8::from(r.constraints_hold))),
        Column::new(
            "status".into(),
            rows.iter()
                .map(|r| r.status.to_string())
                .collect::<Vec<_>>(),
        ),
    ])
}

/// Median and quartiles over seeds per (force noise, setting, n_s, set), in first-appearance
/// order.
pub fn summary(
    long: &polars::prelude::DataFrame,
) -> polars::prelude::PolarsResult<polars::prelude::DataFrame> {
    use crate::tables::{
        group_stats,
        Stat::{Count, Mean, Median, Quantile},
    };
    group_stats(
        long,
        &["force_noise", "setting", "n_s", "constraints"],
        &[
            ("", Count, "seeds"),
            ("val_rms", Quantile(0.25), "val_rms_q25"),
            ("val_rms", Median, "val_rms_median"),
            ("val_rms", Quantile(0.75), "val_rms_q75"),
            ("prior_rms", Median, "prior_rms_median"),
            ("j_err", Quantile(0.25), "j_err_q25"),
            ("j_err", Median, "j_err_median"),
            ("j_err", Quantile(0.75), "j_err_q75"),
            ("consistent", Mean, "consistent_fraction"),
        ],
    )
}

/// The data setting's name in tables and files: `torques_and_contacts`, `torques_only`,
/// `base_only`.
pub fn setting_name(s: DataSetting) -> &'static str {
    match s {
        DataSetting::TorquesAndContacts => "torques_and_contacts",
        DataSetting::TorquesOnly => "torques_only",
        DataSetting::BaseOnly => "base_only",
    }
}

/// The sweep's table for one data setting and training size: a row per contact-force noise
/// (N), a column per set, the median validation RMS (N m) of `summary` ([`summary`]'s columns).
pub fn noise_table(
    summary: &polars::prelude::DataFrame,
    setting: &str,
    samples: usize,
    sets: &[&str],
) -> polars::prelude::PolarsResult<String> {
    use crate::tables::{floats, strings};
    let noise = floats(summary, "force_noise")?;
    let settings = strings(summary, "setting")?;
    let sizes = floats(summary, "n_s")?;
    let set_of = strings(summary, "constraints")?;
    let value = floats(summary, "val_rms_median")?;
    let mut levels: Vec<f64> = vec![];
    for &v in &noise {
        if !levels.contains(&v) {
            levels.push(v);
        }
    }
    let mut md = format!(
        "| force noise (N) | {} |\n|---|{}\n",
        sets.join(" | "),
        "---|".repeat(sets.len())
    );
    for level in levels {
        let cell = |set: &str| {
            (0..value.len())
                .find(|&i| {
                    noise[i] == level
                        && settings[i] == setting
                        && sizes[i] == samples as f64
                        && set_of[i] == set
                })
                .map_or("".to_string(), |i| format!("{:.3}", value[i]))
        };
        let cells: Vec<String> = sets.iter().map(|s| cell(s)).collect();
        md.push_str(&format!("| {level} | {} |\n", cells.join(" | ")));
    }
    Ok(md)
}

/// How many samples a constraint set needs to reach least squares' median validation error at
/// one training size ([`set_reach`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SetReach {
    /// Least squares' training size (samples).
    pub at: usize,
    /// Least squares' median validation RMS there (N m).
    pub target: f64,
    /// The samples at which the set's median first reaches it, log-log interpolated between
    /// the grid's sizes; at the grid's first size when it is already below there (then a
    /// bound: it may need fewer). `None`: not within the grid.
    pub samples: Option<f64>,
    /// Whether `samples` is the grid's first size (a bound, not a crossing).
    pub at_first_size: bool,
}

impl SetReach {
    /// How many times fewer samples the set needs (`at / samples`), a lower bound when
    /// `at_first_size`.
    pub fn fewer(&self) -> Option<f64> {
        self.samples.map(|s| self.at as f64 / s)
    }
}

/// The median validation RMS per training size (ascending) of `set` in `setting`, from
/// [`summary`]'s columns, at its first force noise.
fn median_curve(
    summary: &polars::prelude::DataFrame,
    setting: &str,
    set: &str,
) -> polars::prelude::PolarsResult<(Vec<usize>, Vec<f64>)> {
    use crate::tables::{floats, strings};
    let noise = floats(summary, "force_noise")?;
    let settings = strings(summary, "setting")?;
    let sizes = floats(summary, "n_s")?;
    let sets = strings(summary, "constraints")?;
    let value = floats(summary, "val_rms_median")?;
    let mut curve: Vec<(usize, f64)> = (0..value.len())
        .filter(|&i| noise[i] == noise[0] && settings[i] == setting && sets[i] == set)
        .map(|i| (sizes[i] as usize, value[i]))
        .collect();
    curve.sort_by_key(|c| c.0);
    Ok(curve.into_iter().unzip())
}

/// For each training size after the first, the samples `set` needs in `setting` to reach
/// least squares' (`none`) median validation error at that size: the paper's "tighter
/// constraints reach a good model with fewer samples", measured.
pub fn set_reach(
    summary: &polars::prelude::DataFrame,
    setting: &str,
    set: &str,
) -> polars::prelude::PolarsResult<Vec<SetReach>> {
    let (ns, least_squares) = median_curve(summary, setting, "none")?;
    let (set_ns, errors) = median_curve(summary, setting, set)?;
    if set_ns != ns {
        return Ok(vec![]);
    }
    Ok((1..ns.len())
        .map(|i| {
            let target = least_squares[i];
            let samples = crate::motions::samples_to_reach(&ns, &errors, target);
            SetReach {
                at: ns[i],
                target,
                samples,
                at_first_size: samples == Some(ns[0] as f64),
            }
        })
        .collect())
}

/// Per training size (ascending), the largest over the smallest median validation error of
/// `sets` in `setting`: how far apart the constraint sets are at that size (1: alike).
pub fn spread(
    summary: &polars::prelude::DataFrame,
    setting: &str,
    sets: &[&str],
) -> polars::prelude::PolarsResult<Vec<(usize, f64)>> {
    let curves: Vec<(Vec<usize>, Vec<f64>)> = (sets.iter())
        .map(|set| median_curve(summary, setting, set))
        .collect::<Result<_, _>>()?;
    let Some((ns, _)) = curves.first() else {
        return Ok(vec![]);
    };
    if curves.iter().any(|(n, _)| n != ns) {
        return Ok(vec![]);
    }
    Ok((0..ns.len())
        .map(|i| {
            let at = curves.iter().map(|(_, e)| e[i]);
            let (lo, hi) = at.fold((f64::INFINITY, 0.0_f64), |(lo, hi), e| {
                (lo.min(e), hi.max(e))
            });
            (ns[i], hi / lo)
        })
        .collect())
}
