//! The blind benchmark: simulated experiments with an effect injected at a random magnitude
//! (or none, or two, or one outside the library), written to the files a user would give
//! (`robot.urdf`, `data.csv`), diagnosed from those files only, then scored against what was
//! injected.
//!
//! Case `i` draws from `ChaCha8(seed, stream i)`: its category cycles through slots
//! ([`category`]: four clean, one per kind the effect table draws alone (`Kind::blind_singles`), one with two effects, one out of
//! the library),
//! its magnitudes are uniform in the ranges of [`draw`], and the excitation seed differs per
//! case. The model given to the diagnosis is the simulated robot's description with
//! inertial-parameter errors drawn from the description prior ([`diagnose::anchor`]), and, for
//! `rotor_inertia`, its rotors frozen into the links they sit on.

use physid_core::model::Model;
use physid_diagnose::{self as diagnose, Diagnosis, Verdict};
use physid_effect::library::Kind;
use physid_experiment::tables;
use physid_sim::scenario::{EffectSpec, Scenario};
use polars::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use std::path::Path;

/// What a case injects.
#[derive(Clone, Debug, Serialize, serde::Deserialize, PartialEq)]
#[serde(rename_all = "snake_case")]
pub enum Category {
    /// Nothing.
    Clean,
    /// One library effect.
    Single,
    /// Two library effects.
    Two,
    /// One effect outside the library (quadratic damping).
    OutOfLibrary,
    /// The robot differs from its description in a way no effect models (its friction, or
    /// its last body's mass): the description's gap must be attributed to the change.
    Changed,
}

/// A change of the simulated robot that its description does not carry.
#[derive(Clone, Debug, Serialize, serde::Deserialize, PartialEq)]
#[serde(rename_all = "snake_case")]
pub enum Change {
    /// Every joint's viscous and Coulomb friction scaled by its factor.
    Friction {
        /// Factor per joint.
        scale: Vec<f64>,
    },
    /// The last body's ten inertial parameters scaled (mass, first and second moments: the
    /// same shape, another density).
    Mass {
        /// The factor.
        scale: f64,
    },
}

impl Change {
    /// The name in the case table.
    pub fn name(&self) -> &'static str {
        match self {
            Change::Friction { .. } => "friction_changed",
            Change::Mass { .. } => "mass_changed",
        }
    }

    /// The robot `model` with the change.
    pub fn apply(&self, model: &Model) -> Model {
        let last = model.dof() - 1;
        let edited = match self {
            Change::Friction { scale } => model.with_bodies_edited(|j, b| {
                if let Some(s) = scale.get(j) {
                    b.friction.viscous *= s;
                    b.friction.coulomb *= s;
                }
            }),
            Change::Mass { scale } => model.with_bodies_edited(|j, b| {
                if j == last {
                    b.inertia.0 *= *scale;
                }
            }),
        };
        edited.expect("positive scales keep a valid model valid")
    }
}

/// An injected effect with the magnitudes the diagnosis should find.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct Injected {
    /// The library kind (`None` outside the library).
    pub kind: Option<Kind>,
    /// The scenario effect (`None` for rotor inertia left out, which is a model change).
    pub spec: Option<EffectSpec>,
    /// True magnitudes in the diagnosis's convention ([`diagnose::magnitudes_of`]; for a mass
    /// change the payload mass it amounts to, kg).
    pub magnitudes: Vec<f64>,
    /// A change of the robot itself (category `changed`).
    pub change: Option<Change>,
}

impl Injected {
    /// Its name in the case table: the change's, the kind's, or the out-of-library effect's.
    pub fn name(&self) -> String {
        match (&self.change, self.kind) {
            (Some(c), _) => c.name().into(),
            (None, Some(k)) => k.name().into(),
            (None, None) => "quadratic_damping (not in library)".into(),
        }
    }
}

/// One scored case.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct CaseResult {
    /// Case index.
    pub case: usize,
    /// Its category.
    pub category: Category,
    /// What was injected (names).
    pub injected: Vec<String>,
    /// The diagnosis's attributions in order (ambiguous groups joined by `|`).
    pub found: Vec<String>,
    /// The verdict.
    pub verdict: Verdict,
    /// Single: the first attribution is the injected kind (or an ambiguous group containing it).
    pub top1: Option<bool>,
    /// Single: the first attribution is the injected kind alone.
    pub top1_unique: Option<bool>,
    /// Two: both injected kinds are among the attributions.
    pub both_found: Option<bool>,
    /// Changed: the change leads the explanation of the description's gap (friction
    /// re-identified first) or is found (a payload for the last body's mass).
    pub changed_found: Option<bool>,
    /// Relative magnitude error `‖m̂ − m‖/‖m‖` over identifiable joints, when the kind is
    /// attributed.
    pub magnitude_error: Option<f64>,
    /// Fraction of the validation gap closed.
    pub gap_closed: f64,
    /// Validation RMS before and after (N m) and the noise floor.
    pub rms: [f64; 3],
    /// Relative reduction of the final validation residual's mean square by a generic
    /// function of speed and angle (`Diagnosis::structure_left`).
    pub structure_left: f64,
    /// Its t statistic over validation blocks.
    pub structure_t: f64,
    /// Wall time of the diagnosis (s).
    pub seconds: f64,
    /// How much the injected effects raise the nominal model's validation RMS over the same
    /// experiment without them, `√(MS_with − MS_without)` (N m): the benchmark's yardstick of
    /// how visible the effect is after identification has absorbed what it can.
    pub visible_gap: f64,
}

/// Draws one effect of `kind` (its row of the effect table, `Kind::draw`, gives the ranges) or,
/// for `None`, one outside the library ([`physid_effect::QuadraticDamping::draw`]).
pub fn draw(kind: Option<Kind>, model: &Model, rng: &mut ChaCha8Rng, rate: f64) -> Injected {
    let Some(kind) = kind else {
        let (spec, magnitudes) = physid_effect::QuadraticDamping::draw(model, rng);
        return Injected {
            kind: None,
            magnitudes,
            spec: Some(spec),
            change: None,
        };
    };
    let (spec, magnitudes) = kind.draw(model, rng, rate);
    Injected {
        kind: Some(kind),
        spec,
        magnitudes,
        change: None,
    }
}

/// Draws change `slot` (0: friction, 1: the last body's mass) of `model`: every joint's
/// friction ×1.5–2.5, or the last body's parameters ×1.3–1.6 or ×0.6–0.8.
fn draw_change(slot: usize, model: &Model, rng: &mut ChaCha8Rng) -> Injected {
    let change = if slot == 0 {
        Change::Friction {
            scale: (0..model.dof())
                .map(|_| 1.5 + rng.random::<f64>())
                .collect(),
        }
    } else {
        let up = rng.random::<bool>();
        let r = rng.random::<f64>();
        Change::Mass {
            scale: if up { 1.3 + 0.3 * r } else { 0.6 + 0.2 * r },
        }
    };
    let magnitudes = match &change {
        Change::Mass { scale } => {
            vec![(scale - 1.0) * model.bodies()[model.dof() - 1].inertia.mass()]
        }
        Change::Friction { scale } => scale.clone(),
    };
    Injected {
        kind: None,
        spec: None,
        magnitudes,
        change: Some(change),
    }
}

/// Clean slots at the start of each cycle of categories.
const CLEAN_SLOTS: usize = 4;

/// Changed-robot slots at the end of each cycle (friction, the last body's mass).
const CHANGED_SLOTS: usize = 2;

/// The category of case `i`: cycles of four clean slots, one per kind the effect table draws
/// alone (`Kind::blind_singles`), one with two effects, one out of the library and two of a
/// changed robot.
pub fn category(i: usize) -> (Category, Option<usize>) {
    let singles = Kind::blind_singles().len();
    let out = CLEAN_SLOTS + singles + 1;
    match i % (out + 1 + CHANGED_SLOTS) {
        s if s < CLEAN_SLOTS => (Category::Clean, None),
        s if s < CLEAN_SLOTS + singles => (Category::Single, Some(s - CLEAN_SLOTS)),
        s if s == CLEAN_SLOTS + singles => (Category::Two, None),
        s if s == out => (Category::OutOfLibrary, None),
        s => (Category::Changed, Some(s - out - 1)),
    }
}

/// The fraction of each case's data the diagnosis holds out for validation.
const HOLDOUT: f64 = 0.3;

/// What a blind benchmark run is asked for.
#[derive(Clone, Debug, PartialEq)]
pub struct BlindOptions {
    /// Number of cases (1 to 100,000: bounded before anything is allocated).
    pub cases: usize,
    /// Seed of every draw.
    pub seed: u64,
    /// Relative error drawn into each case's description's inertial parameters, in [0, 1).
    pub description_error: f64,
    /// The uncertainty the diagnosis is told (`None`: the error drawn; 0: no description test).
    pub description_uncertainty: Option<f64>,
}

impl BlindOptions {
    /// Checks every value against its range.
    pub fn validate(&self) -> Result<(), BlindError> {
        let invalid = |option, expected, value| BlindError::InvalidOption {
            option,
            expected,
            value,
        };
        if self.cases == 0 || self.cases > crate::semireal::MAX_CASES {
            return Err(invalid("cases", "in 1..=100000", self.cases as f64));
        }
        let e = self.description_error;
        if !(e.is_finite() && (0.0..1.0).contains(&e)) {
            return Err(invalid("description_error", "in [0, 1)", e));
        }
        let stated = self.stated_uncertainty();
        if !(stated.is_finite() && stated >= 0.0) {
            return Err(invalid("description_uncertainty", ">= 0", stated));
        }
        Ok(())
    }

    /// The description uncertainty the diagnosis is told (0: none).
    pub fn stated_uncertainty(&self) -> f64 {
        self.description_uncertainty
            .unwrap_or(self.description_error)
    }

    /// The diagnosis's options for every case.
    pub fn diagnose_options(&self) -> diagnose::Options {
        let stated = self.stated_uncertainty();
        diagnose::Options {
            description_uncertainty: (stated > 0.0).then_some(stated),
            ..Default::default()
        }
    }
}

/// A blind case or the benchmark's report that could not be made, naming the case.
#[derive(Debug, thiserror::Error)]
pub enum BlindError {
    /// The case's scenario is invalid.
    #[error("case {case}: {source}")]
    Scenario {
        /// Case index.
        case: usize,
        /// What is wrong.
        source: physid_sim::scenario::ScenarioError,
    },
    /// The case's simulation failed (`twin`: the clean twin without the effects).
    #[error("case {case}: {}simulation: {source}", if *twin { "clean twin " } else { "" })]
    Simulation {
        /// Case index.
        case: usize,
        /// The clean twin's simulation.
        twin: bool,
        /// The failure.
        source: physid_sim::simulate::SimError,
    },
    /// The case's files could not be written or read back.
    #[error("case {case}: {source}")]
    Io {
        /// Case index.
        case: usize,
        /// The file error.
        source: physid_io::IoError,
    },
    /// The diagnosis (or the nominal fit of the yardstick) failed.
    #[error("case {case}: {source}")]
    Diagnose {
        /// Case index.
        case: usize,
        /// The failure.
        source: diagnose::DiagnoseError,
    },
    /// Writing the benchmark's tables.
    #[error("{0}")]
    Report(#[from] physid_io::IoError),
    /// Building the case table.
    #[error("case table: {0}")]
    Table(#[from] PolarsError),
    /// Serializing the scores.
    #[error("scores: {0}")]
    Json(#[from] serde_json::Error),
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
}

physid_core::options::option_error!(BlindError);

/// The nominal model's validation mean square (the last [`HOLDOUT`]), fitted as the diagnosis
/// does.
fn nominal_validation_ms(
    model: &Model,
    tr: &physid_core::trajectory::Trajectory,
    opts: &diagnose::Options,
) -> Result<f64, diagnose::DiagnoseError> {
    let (train, val) = tr.holdout_split(HOLDOUT);
    let fit = diagnose::fit_nominal(model, &train, opts)?;
    let ctx = physid_effect::library::Context::new(model, &fit.theta, &val, opts.processing_cutoff);
    let (_, res) = diagnose::residual_rms(&ctx, &val, &[], &fit.theta, opts.min_speed);
    // Pooled over every joint-sample at or above the speed threshold.
    Ok(diagnose::finite_mean_square(&diagnose::mask_slow(
        &val,
        &res,
        opts.min_speed,
    )))
}

pub use physid_diagnose::IDENTIFIABLE;

/// Relative error over the joints whose estimate is identifiable (see [`IDENTIFIABLE`]).
fn magnitude_error(d: &Diagnosis, kind: Kind, truth: &[f64]) -> Option<f64> {
    let e = d.effects.iter().find(|e| e.kind == kind)?;
    let (mut num, mut den) = (0.0, 0.0);
    for (m, t) in e.magnitudes.iter().zip(truth) {
        if m.identifiable >= IDENTIFIABLE {
            num += (m.value - t).powi(2);
            den += t * t;
        }
    }
    (den > 0.0).then(|| (num / den).sqrt())
}

/// The relative error of the inertial parameters of the description the benchmark gives by
/// default (drawn by [`diagnose::anchor::perturbed_description`]); the diagnosis is told the
/// same uncertainty unless said otherwise.
pub const DESCRIPTION_ERROR: f64 = 0.1;

/// Case `i`'s category and the effects drawn for it (from the case's own random stream).
fn injections(i: usize, seed: u64, model: &Model, rate: f64) -> (Category, Vec<Injected>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(i as u64);
    let (category, slot) = category(i);
    let injected: Vec<Injected> = match category {
        Category::Clean => vec![],
        Category::Single => vec![draw(
            Some(Kind::blind_singles()[slot.expect("single")]),
            model,
            &mut rng,
            rate,
        )],
        Category::Two => {
            // Two effects that act on the torque (no model change), distinct.
            let pool = Kind::blind_pairs();
            let a = pool[rng.random_range(0..pool.len())];
            let mut b = a;
            while b == a {
                b = pool[rng.random_range(0..pool.len())];
            }
            vec![
                draw(Some(a), model, &mut rng, rate),
                draw(Some(b), model, &mut rng, rate),
            ]
        }
        Category::OutOfLibrary => vec![draw(None, model, &mut rng, rate)],
        Category::Changed => vec![draw_change(slot.expect("changed"), model, &mut rng)],
    };
    (category, injected)
}

/// The description the user gives for case `i`: without the rotors' spin when their inertia
/// is left out (their mass frozen into the bodies they sit on), with errors of relative size
/// `description_error` in its inertial parameters (from their own random stream).
fn description(
    i: usize,
    seed: u64,
    model: &Model,
    injected: &[Injected],
    description_error: f64,
) -> Model {
    let exact = injected
        .iter()
        .filter_map(|x| x.kind)
        .fold(model.clone(), |m, k| k.description(&m));
    if description_error > 0.0 {
        let mut drng = ChaCha8Rng::seed_from_u64(seed ^ 0x00de_5c41_b710);
        drng.set_stream(i as u64);
        diagnose::anchor::perturbed_description(&exact, description_error, &mut drng)
    } else {
        exact
    }
}

/// Runs case `i` of the benchmark with base scenario `base` and its robot `model`, writing its
/// files into `dir`. The description given to the diagnosis carries inertial-parameter errors
/// of relative size `description_error` (0: the simulated robot's own parameters), drawn from
/// their own random stream.
pub fn run_case(
    i: usize,
    seed: u64,
    base: &Scenario,
    model: &Model,
    description_error: f64,
    opts: &diagnose::Options,
    dir: &Path,
) -> Result<CaseResult, BlindError> {
    let (category, injected) = injections(i, seed, model, base.simulation.rate);
    let mut sc = base.clone();
    sc.simulation.seed = seed.wrapping_mul(1_000_003).wrapping_add(i as u64);
    sc.effects = injected.iter().filter_map(|x| x.spec.clone()).collect();
    sc.validate(model.dof())
        .map_err(|source| BlindError::Scenario { case: i, source })?;
    let truth = injected
        .iter()
        .filter_map(|x| x.change.as_ref())
        .fold(model.clone(), |m, c| c.apply(&m));
    let rec =
        physid_sim::run(&truth, &sc, &mut |_| {}).map_err(|source| BlindError::Simulation {
            case: i,
            twin: false,
            source,
        })?;
    let description = description(i, seed, model, &injected, description_error);
    let visible_gap = if injected.is_empty() {
        0.0
    } else {
        visible_gap(i, &sc, model, &description, &rec, opts)?
    };
    let (d, seconds) = diagnose_files(i, &description, rec, opts, dir)?;
    let found: Vec<String> = d
        .effects
        .iter()
        .map(|e| e.group().map(|k| k.name()).collect::<Vec<_>>().join("|"))
        .collect();
    let marks = Marks::of(category.clone(), &injected, &d);
    let last = d.overall[d.overall.len() - 1];
    Ok(CaseResult {
        case: i,
        category,
        injected: injected.iter().map(Injected::name).collect(),
        changed_found: marks.changed_found,
        found,
        verdict: d.verdict,
        top1: marks.top1,
        top1_unique: marks.top1_unique,
        both_found: marks.both_found,
        magnitude_error: marks.magnitude_error,
        gap_closed: d.gap_closed,
        rms: [d.overall[0], last, d.noise_floor],
        structure_left: d.structure_left.reduction,
        structure_t: d.structure_left.t,
        seconds,
        visible_gap,
    })
}

/// Case `i` diagnosed as a user would: `description` and the recording `rec` written to `dir`
/// as `robot.urdf` and `data.csv`, read back and diagnosed; the diagnosis and its wall time
/// (s, reading included).
fn diagnose_files(
    i: usize,
    description: &Model,
    rec: physid_core::trajectory::Recording,
    opts: &diagnose::Options,
    dir: &Path,
) -> Result<(diagnose::Diagnosis, f64), BlindError> {
    let io_err = |source| BlindError::Io { case: i, source };
    physid_io::create_dir_all(dir).map_err(io_err)?;
    let robot = dir.join("robot.urdf");
    let data = dir.join("data.csv");
    physid_io::write_atomic(&robot, physid_io::urdf::to_string(description).as_bytes())
        .map_err(io_err)?;
    physid_io::samples::write_csv(&data, &rec.processed).map_err(io_err)?;
    drop(rec);
    let start = std::time::Instant::now();
    let given = physid_io::load_robot(&robot.to_string_lossy()).map_err(io_err)?;
    let given_data = physid_io::load_trajectory(&data, &given)
        .map_err(io_err)?
        .trajectories();
    let d = diagnose::diagnose_runs(&given, given_data, vec![], HOLDOUT, opts)
        .map_err(|source| BlindError::Diagnose { case: i, source })?;
    Ok((d, start.elapsed().as_secs_f64()))
}

/// The benchmark's own yardstick (the diagnosis never sees it): how much the injected effects
/// of case `i` raise the nominal model's validation error (RMS, N m) over the same experiment
/// `sc` without them.
fn visible_gap(
    i: usize,
    sc: &Scenario,
    model: &Model,
    description: &Model,
    rec: &physid_core::trajectory::Recording,
    opts: &diagnose::Options,
) -> Result<f64, BlindError> {
    let diag_err = |source| BlindError::Diagnose { case: i, source };
    let mut twin = sc.clone();
    twin.effects.clear();
    let clean =
        physid_sim::run(model, &twin, &mut |_| {}).map_err(|source| BlindError::Simulation {
            case: i,
            twin: true,
            source,
        })?;
    let with = nominal_validation_ms(description, &rec.processed, opts).map_err(diag_err)?;
    // Rotor inertia left out changes the description, not the data.
    let without = if description.rotor_count() < model.rotor_count() {
        nominal_validation_ms(model, &rec.processed, opts)
    } else {
        nominal_validation_ms(description, &clean.processed, opts)
    }
    .map_err(diag_err)?;
    Ok((with - without).max(0.0).sqrt())
}

/// How a case's diagnosis scores against what was injected.
#[derive(Default)]
struct Marks {
    top1: Option<bool>,
    top1_unique: Option<bool>,
    both_found: Option<bool>,
    changed_found: Option<bool>,
    magnitude_error: Option<f64>,
}

impl Marks {
    fn of(category: Category, injected: &[Injected], d: &Diagnosis) -> Marks {
        let in_first = |k: Kind| d.effects.first().is_some_and(|e| e.group().any(|g| g == k));
        let anywhere = |k: Kind| d.effects.iter().any(|e| e.group().any(|g| g == k));
        let mut m = Marks::default();
        match category {
            Category::Single => {
                let k = injected[0].kind.expect("library kind");
                m.top1 = Some(in_first(k));
                m.top1_unique = Some(
                    d.effects
                        .first()
                        .is_some_and(|e| e.kind == k && e.ambiguous_with.is_empty()),
                );
                m.magnitude_error = magnitude_error(d, k, &injected[0].magnitudes);
            }
            Category::Two => {
                m.both_found = Some(
                    injected
                        .iter()
                        .all(|x| anywhere(x.kind.expect("library kind"))),
                );
            }
            Category::Changed => {
                // The change must lead the explanation of the description's gap: friction
                // re-identified first, or a payload (the last body's mass) found.
                let first = d
                    .explained_from_description
                    .first()
                    .map(|s| s.step.as_str());
                let found = match injected[0].change.as_ref().expect("a change") {
                    Change::Friction { .. } => first == Some("friction re-identified"),
                    Change::Mass { .. } => Kind::body_change().is_some_and(anywhere),
                };
                m.changed_found = Some(found);
                if matches!(injected[0].change, Some(Change::Mass { .. })) {
                    m.magnitude_error = Kind::body_change()
                        .and_then(|k| magnitude_error(d, k, &injected[0].magnitudes));
                }
            }
            _ => {}
        }
        m
    }
}

/// A visible gap (N m) of half the benchmark's torque noise.
pub const VISIBLE: f64 = 0.15;

/// The benchmark's scores.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct Scores {
    /// Cases run.
    pub cases: usize,
    /// Single-effect cases and the fraction whose first attribution is right (ambiguous group
    /// containing the truth included).
    pub single: usize,
    /// Top-1 accuracy.
    pub top1: f64,
    /// Top-1 accuracy counting ambiguous groups as wrong.
    pub top1_unique: f64,
    /// Single cases whose visible gap is at least half the torque noise (0.15 N m).
    pub single_visible: usize,
    /// Top-1 accuracy over those.
    pub top1_visible: f64,
    /// Median relative magnitude error over single cases with the kind attributed.
    pub median_magnitude_error: f64,
    /// Median fraction of the gap closed over single cases.
    pub median_gap_closed: f64,
    /// Clean cases and the fraction with no effect claimed.
    pub clean: usize,
    /// No claim on clean data.
    pub clean_no_claim: f64,
    /// Two-effect cases and the fraction with both found.
    pub two: usize,
    /// Both found.
    pub two_both_found: f64,
    /// Out-of-library cases and the fraction reported as (partly) unexplained.
    pub out_of_library: usize,
    /// Reported unexplained rather than explained by a library effect.
    pub out_of_library_unexplained: f64,
    /// Changed-robot cases and the fraction whose change is found.
    pub changed: usize,
    /// Found fraction.
    pub changed_found: f64,
    /// Median relative error of the payload mass found for a mass change.
    pub changed_mass_error: f64,
}

/// Scores of a set of cases.
pub fn score(results: &[CaseResult]) -> Scores {
    let of = |c: Category| results.iter().filter(move |r| r.category == c);
    let mut mags: Vec<f64> = of(Category::Single)
        .filter_map(|r| r.magnitude_error)
        .collect();
    let mut gaps: Vec<f64> = of(Category::Single).map(|r| r.gap_closed).collect();
    Scores {
        cases: results.len(),
        single: of(Category::Single).count(),
        top1: physid_experiment::fraction(of(Category::Single).filter_map(|r| r.top1)),
        top1_unique: physid_experiment::fraction(
            of(Category::Single).filter_map(|r| r.top1_unique),
        ),
        single_visible: of(Category::Single)
            .filter(|r| r.visible_gap >= VISIBLE)
            .count(),
        top1_visible: physid_experiment::fraction(
            of(Category::Single)
                .filter(|r| r.visible_gap >= VISIBLE)
                .filter_map(|r| r.top1),
        ),
        median_magnitude_error: physid_experiment::median(&std::mem::take(&mut mags)),
        median_gap_closed: physid_experiment::median(&std::mem::take(&mut gaps)),
        clean: of(Category::Clean).count(),
        clean_no_claim: physid_experiment::fraction(
            of(Category::Clean).map(|r| r.found.is_empty()),
        ),
        two: of(Category::Two).count(),
        two_both_found: physid_experiment::fraction(of(Category::Two).filter_map(|r| r.both_found)),
        out_of_library: of(Category::OutOfLibrary).count(),
        out_of_library_unexplained: physid_experiment::fraction(
            of(Category::OutOfLibrary).map(|r| r.verdict != Verdict::Explained),
        ),
        changed: of(Category::Changed).count(),
        changed_found: physid_experiment::fraction(
            of(Category::Changed).filter_map(|r| r.changed_found),
        ),
        changed_mass_error: physid_experiment::median(
            &of(Category::Changed)
                .filter_map(|r| r.magnitude_error)
                .collect::<Vec<_>>(),
        ),
    }
}

/// The case table with `injected` and `found` as list columns (for Parquet; CSV and Markdown
/// take [`case_table`]'s joined strings).
pub fn case_table_with_lists(results: &[CaseResult]) -> PolarsResult<DataFrame> {
    let mut df = case_table(results)?;
    let list = |name: &str, items: &dyn Fn(&CaseResult) -> &Vec<String>| -> Column {
        let rows: Vec<Series> = results
            .iter()
            .map(|r| Series::new("".into(), items(r).clone()))
            .collect();
        Series::new(name.into(), rows).into_column()
    };
    df.replace("injected", list("injected", &|r| &r.injected))?;
    df.replace("found", list("found", &|r| &r.found))?;
    Ok(df)
}

/// The case table as a polars frame (`injected`, `found` joined by ` + `).
pub fn case_table(results: &[CaseResult]) -> PolarsResult<DataFrame> {
    // Enums spelled as in the JSON (snake_case), booleans as booleans (null: not scored).
    df!(
        "case" => results.iter().map(|r| r.case as u32).collect::<Vec<_>>(),
        "category" => results.iter().map(|r| physid_io::serde_name(&r.category)).collect::<Vec<_>>(),
        "injected" => results.iter().map(|r| r.injected.join(" + ")).collect::<Vec<_>>(),
        "visible_gap" => results.iter().map(|r| r.visible_gap).collect::<Vec<_>>(),
        "found" => results.iter().map(|r| r.found.join(" + ")).collect::<Vec<_>>(),
        "verdict" => results.iter().map(|r| physid_io::serde_name(&r.verdict)).collect::<Vec<_>>(),
        "top1" => results.iter().map(|r| r.top1).collect::<Vec<_>>(),
        "both_found" => results.iter().map(|r| r.both_found).collect::<Vec<_>>(),
        "changed_found" => results.iter().map(|r| r.changed_found).collect::<Vec<_>>(),
        "magnitude_error" => results.iter().map(|r| r.magnitude_error).collect::<Vec<_>>(),
        "gap_closed" => results.iter().map(|r| r.gap_closed).collect::<Vec<_>>(),
        "rms_before" => results.iter().map(|r| r.rms[0]).collect::<Vec<_>>(),
        "rms_after" => results.iter().map(|r| r.rms[1]).collect::<Vec<_>>(),
        "noise_floor" => results.iter().map(|r| r.rms[2]).collect::<Vec<_>>(),
        "structure_left" => results.iter().map(|r| r.structure_left).collect::<Vec<_>>(),
        "structure_t" => results.iter().map(|r| r.structure_t).collect::<Vec<_>>(),
    )
}

/// Writes the blind benchmark's case table (CSV, Parquet, Markdown with the scores),
/// `scores.json` and the plot `blind.svg` into `dir`.
pub fn write_blind(
    dir: &Path,
    results: &[CaseResult],
    scores: &Scores,
    seed: u64,
    scenario: &Path,
    description: [f64; 2],
    wall: f64,
) -> Result<(), BlindError> {
    physid_io::write_result_dir(dir, physid_io::SCORES_MARK, |staged| {
        write_blind_files(staged, results, scores, seed, scenario, description, wall)
    })
}

/// The files of [`write_blind`] written into `dir`.
fn write_blind_files(
    dir: &Path,
    results: &[CaseResult],
    scores: &Scores,
    seed: u64,
    scenario: &Path,
    description: [f64; 2],
    wall: f64,
) -> Result<(), BlindError> {
    let mut df = case_table(results)?;
    tables::write_csv(&dir.join("cases.csv"), &mut df)?;
    tables::write_parquet(
        &dir.join("cases.parquet"),
        &mut case_table_with_lists(results)?,
    )?;
    // Per injected kind (single cases): count, top-1, median magnitude error.
    use tables::Stat::{Count, Mean, Median};
    let singles = tables::filter_eq(&df, "category", "single")?;
    let per_kind = tables::group_stats(
        &singles,
        &["injected"],
        &[
            ("", Count, "cases"),
            ("top1", Mean, "top1"),
            ("magnitude_error", Median, "median_magnitude_error"),
            ("gap_closed", Median, "median_gap_closed"),
            ("visible_gap", Median, "median_visible_gap"),
        ],
    )?
    .sort(["injected"], Default::default())?;
    let md = format!(
        "# Blind benchmark\n\n`physid blind --cases {} --seed {seed} --description-error {} --description-uncertainty {}` on `{}` ({:.0} s wall).\n\nEach case's description carries inertial-parameter errors of relative size `--description-error`; the diagnosis is told `--description-uncertainty` (0: no test against the description).\n\n## Scores\n\n```json\n{}\n```\n\n## Single effects by kind\n\n{}\n## Cases\n\n{}",
        scores.cases,
        description[0],
        description[1],
        scenario.display(),
        wall,
        serde_json::to_string_pretty(scores)?,
        tables::markdown(&per_kind),
        tables::markdown(&df)
    );
    physid_io::write_atomic(&dir.join("README.md"), md.as_bytes())?;
    physid_io::write_atomic(
        &dir.join("scores.json"),
        serde_json::to_string_pretty(&physid_io::versioned("blind_scores", scores))?.as_bytes(),
    )?;
    let svg = summary_plot(results, scores).map_err(|message| {
        BlindError::Report(physid_io::IoError::Invalid {
            path: dir.join("blind.svg"),
            message: format!("plot: {message}"),
        })
    })?;
    physid_io::write_atomic(&dir.join("blind.svg"), svg.as_bytes())?;
    Ok(())
}

/// `blind.svg`: per single kind the fraction attributed first (top-1) and the median fraction
/// of the gap closed, then the other categories' scores, as fractions of their cases.
fn summary_plot(results: &[CaseResult], scores: &Scores) -> Result<String, String> {
    let mut labels = vec![];
    let (mut top1, mut closed) = (vec![], vec![]);
    for k in Kind::ALL {
        let cases: Vec<&CaseResult> = results
            .iter()
            .filter(|r| r.category == Category::Single && r.injected == [k.name()])
            .collect();
        if cases.is_empty() {
            continue;
        }
        let hits = cases.iter().filter(|r| r.top1 == Some(true)).count();
        labels.push(format!("{} ({})", k.name(), cases.len()));
        top1.push(hits as f64 / cases.len() as f64);
        let gaps: Vec<f64> = cases.iter().map(|r| r.gap_closed).collect();
        closed.push(physid_core::linalg::median(&gaps).max(0.0));
    }
    for (name, count, value) in [
        ("clean: no claim", scores.clean, scores.clean_no_claim),
        ("two: both found", scores.two, scores.two_both_found),
        (
            "out of library: unexplained",
            scores.out_of_library,
            scores.out_of_library_unexplained,
        ),
        ("changed robot: found", scores.changed, scores.changed_found),
    ] {
        if count > 0 {
            labels.push(format!("{name} ({count})"));
            top1.push(value);
            closed.push(f64::NAN);
        }
    }
    physid_io::plot::grouped_bars(
        "blind benchmark: scores per injected kind (cases in brackets)",
        "fraction of cases (-)",
        &labels,
        &[
            ("top-1 / found / no claim".into(), top1),
            ("median gap closed (single)".into(), closed),
        ],
    )
}
