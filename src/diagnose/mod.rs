//! Sim-to-real gap diagnosis: where the residual of a model lies, which unmodelled effect causes
//! it, and how far it shrinks once modelled.
//!
//! - **Where** ([`mod@breakdown`], [`spectrum`]): the validation residual `τ − Y θ̂₀` of the nominal
//!   constrained model per joint, per motion regime (near-zero velocity and reversals, speed,
//!   acceleration and torque levels, configuration) and over frequency (spectrum, coherence with
//!   the motion).
//! - **Which** ([`library`], [`select`]): each effect of the library offered as extra regressor
//!   columns, scored by the cross-validated reduction of the error, forward selection with a
//!   stopping rule; magnitudes with block-jackknife standard errors; effects the data cannot tell
//!   apart reported together.
//! - **Absorbed** ([`anchor`]): effects identification absorbs, tested against the description.
//! - **How far** (`gap`): per-joint validation RMS before and after each added effect, the
//!   fraction of the gap to the noise floor ([`noise`]) closed, whether each effect is confirmed
//!   on the held-out data, and the verdict (`verdict`).
//!
//! [`diagnose`] runs the steps in that order on a training and a validation trajectory, over a
//! shared `Stage` (the data, the nominal fit and the effect columns); [`diagnose_runs`] joins
//! runs first. The blind benchmark that scores it is `experiment::blind`.

pub mod anchor;
pub mod baseline;
pub mod breakdown;
pub mod calibrate;
pub mod context;
mod diagnosis;
mod explain;
mod gap;
mod kinds;
pub mod ladder;
pub mod library;
pub mod magnitude;
pub mod noise;
mod options;
pub mod report;
mod residual;
pub mod select;
pub mod spectrum;
mod structure;
mod verdict;

use crate::ident::{self, NormalEquations};
use crate::model::Model;
use crate::trajectory::Trajectory;
use library::{Context, Kind};
use nalgebra::DVector;

pub use crate::ident::analysis::residuals;
pub use breakdown::{breakdown, Breakdown, Regime};
pub use diagnosis::{
    DescriptionStep, Diagnosis, EffectEstimate, Evidence, JointGap, Magnitude, Verdict,
};
pub use kinds::separate_by;
pub use magnitude::magnitudes_of;
pub use options::{DiagnoseError, Options};
pub(crate) use residual::{finite_mean_square, mask_slow, mean_square, median, residual_rms};
pub use structure::StructureLeft;

/// Smallest identifiable fraction of a magnitude worth reporting as a number (its column's part
/// outside the rigid-body regressor's span carries at least 3 % of its RMS).
pub const IDENTIFIABLE: f64 = 1e-3;

/// The fewest samples a training or validation set may have.
pub const MIN_SAMPLES: usize = 64;

/// The nominal model: `model`'s parameters identified on `train` under `opts.constraints`,
/// from the rows of joints at or above `opts.min_speed`, with the description as prior.
pub fn fit_nominal(
    model: &Model,
    train: &Trajectory,
    opts: &Options,
) -> Result<ident::Identified, DiagnoseError> {
    let prior = model.parameters();
    let mut ne = NormalEquations::new(model.dof(), model.layout().len);
    Context::new(model, &prior, train, opts.processing_cutoff).for_each_row(
        train,
        0..train.len(),
        &[],
        opts.min_speed,
        &mut |_, z, tau| ne.add(z, tau),
    );
    let iopts = ident::Options::new(opts.constraints);
    Ok(ident::identify(model, &ne.finish(), &prior, &iopts)?)
}

/// The whole diagnosis: the nominal model fitted on `train` (its constraint set
/// `opts.constraints`), effects selected by cross-validation on `train` and, when the
/// description's uncertainty is stated and cross-validation finds nothing, against the
/// description; everything scored on `validate` (where, how far, noise floor). Both
/// trajectories must carry q̈.
pub fn diagnose(
    model: &Model,
    train: &Trajectory,
    validate: &Trajectory,
    opts: &Options,
) -> Result<Diagnosis, DiagnoseError> {
    opts.validate()?;
    check_data(model, train, validate)?;
    let nominal = fit_nominal(model, train, opts)?;
    let stage = Stage::new(model, train, validate, opts, nominal.theta.clone());
    let selection =
        select::forward_select(&stage.folds, model, &stage.ident_opts, &opts.selection)?;
    let (description_test, description_test_skipped) = run_description_test(&stage, &selection)?;
    let anchored: &[anchor::Step] = description_test.as_ref().map_or(&[], |r| &r.steps);
    let n_cv = selection.chosen.len();
    let chosen: Vec<usize> = selection
        .chosen
        .iter()
        .copied()
        .chain(anchored.iter().map(|s| s.variant))
        .collect();
    let ladder = gap::ladder(&stage, &chosen)?;
    let mut effects = magnitude::cross_validated(&stage, &selection, &ladder.final_theta);
    effects.extend(magnitude::against_description(&stage, anchored));
    let from_description = ladder::from_description(&stage, &selection, &mut effects);
    let how_far = gap::how_far(&stage, &chosen, n_cv, &ladder)?;
    let explained_from_description = match &from_description {
        Some(l) => l.description_steps(),
        None => explain::from_description(&stage, &chosen, &ladder),
    };
    let final_variants: Vec<_> = chosen.iter().map(|&v| stage.folds.variants[v]).collect();
    let (_, final_train_res) = residual_rms(
        &stage.ctx_train,
        train,
        &final_variants,
        &ladder.final_theta,
        opts.min_speed,
    );
    let structure_left = structure::structure_left(
        &stage,
        &final_train_res,
        &ladder.final_res,
        opts.structure_threshold,
    );
    let train_seconds = train
        .sample_period()
        .map_or(0.0, |dt| dt * train.len() as f64);
    let verdict = match verdict::verdict(
        selection.steps.len(),
        anchored.len(),
        &how_far,
        opts.unexplained_ratio,
        structure_left.remains,
    ) {
        Verdict::Unexplained | Verdict::NoEffect if train_seconds < opts.min_decisive_seconds => {
            Verdict::Undecided
        }
        v => v,
    };
    let description_overall = mean_square(&ladder.description_rms).sqrt();
    let summary = summary_text(
        model,
        (
            description_overall,
            train_seconds,
            opts.min_decisive_seconds,
        ),
        &how_far,
        verdict,
        (&effects, n_cv),
        description_test.as_ref(),
        (&structure_left, &explained_from_description),
    );
    Ok(Diagnosis {
        confirmed: how_far.confirmed,
        confirmed_only: how_far.confirmed_only,
        robot: model.name.clone(),
        joints: model_joint_names(model),
        samples: [train.len(), validate.len()],
        constraints: opts.constraints,
        nominal_constraints_hold: nominal.constraints_hold,
        breakdown: breakdown(validate, 0..validate.len(), &ladder.nominal_res),
        spectra: breakdown::spectra(model, validate, &ladder.nominal_res),
        spectra_after: breakdown::spectra(model, validate, &ladder.final_res),
        selection,
        description_test,
        description_test_skipped,
        ladder: from_description,
        effects,
        gap: how_far.gap,
        description_overall,
        explained_from_description,
        overall: how_far.overall,
        noise_floor: how_far.floor_ms.sqrt(),
        gap_closed: how_far.gap_closed,
        structure_left,
        verdict,
        summary,
    })
}

/// Absorbed effects, against the description when its uncertainty is stated, beside what
/// cross-validation chose, unless a chosen effect's columns only approximate it (a delay to
/// first order, a rotor without its gyroscopic terms): what they miss biases θ in ways the
/// prior test would misread as an absorbed effect. Returns the test, or why it did not run.
fn run_description_test(
    stage: &Stage,
    selection: &select::Selection,
) -> Result<(Option<anchor::Report>, Option<String>), DiagnoseError> {
    // Absorbed effects, against the description when its uncertainty is stated, beside what
    // cross-validation chose, unless a chosen effect's columns only approximate it (a delay to
    // first order, a rotor without its gyroscopic terms): what they miss biases θ in ways the
    // prior test would misread as an absorbed effect.
    let linearized: Vec<Kind> = selection
        .chosen
        .iter()
        .map(|&v| stage.folds.variants[v].kind)
        .filter(|k| k.approximate())
        .collect();
    let description_test = match stage.opts.description_uncertainty {
        Some(eps) if linearized.is_empty() => {
            Some(anchor::test_description(stage, eps, &selection.chosen)?)
        }
        _ => None,
    };
    let description_test_skipped = (stage.opts.description_uncertainty.is_some()
        && description_test.is_none())
    .then(|| {
        format!(
            "not run: cross-validation selected {}, whose columns only approximate it (linearized about the nominal model, or a rotor without its gyroscopic terms); what they miss would bias the parameters the test compares",
            library::names(&linearized, false)
        )
    });
    Ok((description_test, description_test_skipped))
}

/// The diagnosis's one-paragraph summary.
#[allow(clippy::too_many_arguments)]
fn summary_text(
    model: &Model,
    (description_overall, train_seconds, min_decisive): (f64, f64, f64),
    how_far: &gap::HowFar,
    verdict: Verdict,
    (effects, n_cv): (&[EffectEstimate], usize),
    description_test: Option<&anchor::Report>,
    (structure_left, explained): (&StructureLeft, &[DescriptionStep]),
) -> String {
    let mut summary = format!(
        "the description as given predicts the validation data with {:.3} N m RMS (re-identified: {:.3} N m); {}",
        description_overall,
        how_far.overall[0],
        verdict::summary(verdict, effects, n_cv, how_far, description_test)
    );
    summary += &verdict::structure_summary(structure_left, &model_joint_names(model));
    summary += &explain::summary(explained, description_overall);
    if verdict == Verdict::Undecided {
        summary += &format!(
            " (only {train_seconds:.1} s of training data, below the {} s on which a verdict of \"unexplained\" or \"no effect\" can be trusted: record longer runs)",
            min_decisive
        );
    }
    summary
}

fn model_joint_names(model: &Model) -> Vec<String> {
    model.bodies.iter().map(|b| b.joint_name.clone()).collect()
}

/// Both data sets fit the robot and the diagnosis: same joints, accelerations present, at least
/// [`MIN_SAMPLES`] samples.
fn check_data(
    model: &Model,
    train: &Trajectory,
    validate: &Trajectory,
) -> Result<(), DiagnoseError> {
    let n = model.dof();
    for (which, tr) in [("training", train), ("validation", validate)] {
        if tr.dof() != n {
            return Err(DiagnoseError::JointCount {
                which,
                data: tr.dof(),
                robot: n,
            });
        }
        if tr.qdd.is_none() {
            return Err(DiagnoseError::NoAcceleration { which });
        }
        if tr.len() < MIN_SAMPLES {
            return Err(DiagnoseError::TooShort {
                which,
                samples: tr.len(),
                min: MIN_SAMPLES,
            });
        }
    }
    Ok(())
}

/// What every step after the nominal fit works on: the data, the nominal parameters `θ₀`, the
/// effect columns' context on both data sets, and the training data's per-fold and summed
/// normal equations of `[Y | effect columns]`.
pub(crate) struct Stage<'a> {
    pub model: &'a Model,
    pub train: &'a Trajectory,
    pub validate: &'a Trajectory,
    pub opts: &'a Options,
    /// Identification options of every fit (the nominal model's constraint set).
    pub ident_opts: ident::Options,
    /// The nominal model's parameters.
    pub theta0: DVector<f64>,
    pub ctx_train: Context<'a>,
    pub ctx_val: Context<'a>,
    pub folds: select::Folds,
    /// The folds summed: all training data.
    pub all: NormalEquations,
}

impl<'a> Stage<'a> {
    fn new(
        model: &'a Model,
        train: &'a Trajectory,
        validate: &'a Trajectory,
        opts: &'a Options,
        theta0: DVector<f64>,
    ) -> Self {
        let cutoff = opts.processing_cutoff;
        let ctx_train = Context::new(model, &theta0, train, cutoff);
        let ctx_val = Context::new(model, &theta0, validate, cutoff);
        let folds = select::Folds::build(
            &ctx_train,
            train,
            0..train.len(),
            offered_variants(opts, model),
            opts.selection.folds.max(2),
            &opts.train_runs,
            opts.min_speed,
        );
        let all = folds.sum_except(usize::MAX);
        Self {
            model,
            train,
            validate,
            opts,
            ident_opts: ident::Options::new(opts.constraints),
            theta0,
            ctx_train,
            ctx_val,
            folds,
            all,
        }
    }
}

/// The variants of `opts.kinds` offered for `model`: kinds that act on one body on the last
/// body only unless `opts.every_body`; kinds at the rotor's angle only when the description
/// has rotors.
fn offered_variants(opts: &Options, model: &Model) -> Vec<library::Variant> {
    let n = model.dof();
    let rotors = model.rotor_count() > 0;
    library::variants(&opts.kinds, n)
        .into_iter()
        .filter(|v| {
            v.kind
                .body(v.param, n)
                .is_none_or(|b| opts.every_body || b == n - 1)
        })
        .filter(|v| rotors || !v.kind.needs_rotor())
        .collect()
}

/// The diagnosis of runs as a user gives them: training runs and validation runs, each joined
/// end to end. With several training runs the selection leaves one run out; without validation
/// runs the last `holdout` fraction of the joined training runs is held out.
pub fn diagnose_runs(
    model: &Model,
    train_runs: Vec<Trajectory>,
    validate_runs: Vec<Trajectory>,
    holdout: f64,
    opts: &Options,
) -> Result<Diagnosis, DiagnoseError> {
    let lens: Vec<usize> = train_runs.iter().map(|r| r.len()).collect();
    let all = Trajectory::concatenate(train_runs).ok_or(DiagnoseError::NoData)?;
    let mut opts = opts.clone();
    let (train, val) = match Trajectory::concatenate(validate_runs) {
        None => {
            if !(holdout > 0.0 && holdout < 1.0) {
                return Err(DiagnoseError::Holdout(holdout));
            }
            all.holdout_split(holdout)
        }
        Some(val) => {
            opts.train_runs = lens;
            (all, val)
        }
    };
    diagnose(model, &train, &val, &opts)
}
