//! The diagnosis as a sequence of steps over one [`Stage`]: the nominal fit, the selection,
//! the description test, how far, the effects' magnitudes, the ladder from the description, the
//! structure left, the verdict and its summary; [`diagnose_runs`] joins the user's runs first.

use super::breakdown::{self, breakdown};
use super::diagnosis::{DescriptionStep, Diagnosis, EffectEstimate, Verdict};
use super::options::{DiagnoseError, Options};
use super::residual::mean_square;
use super::stage::{check_data, fit_nominal, Stage};
use super::structure::{self, StructureLeft};
use super::{anchor, described, explain, gap, magnitude, select, verdict};
use physid_core::model::Model;
use physid_core::trajectory::Trajectory;
use physid_effect::library;
use physid_effect::Kind;

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
    diagnose_recordings(model, (train, &[]), validate, opts)
}

/// [`diagnose`] of training data joined from recordings of `train_runs` samples each (empty:
/// one recording): the selection leaves one recording out at a time, the noise floor's
/// neighbours stay within one.
fn diagnose_recordings(
    model: &Model,
    recorded: (&Trajectory, &[usize]),
    validate: &Trajectory,
    opts: &Options,
) -> Result<Diagnosis, DiagnoseError> {
    let train = recorded.0;
    opts.validate()?;
    check_data(model, train, validate)?;
    let nominal = fit_nominal(model, train, opts)?;
    let stage = Stage::new(model, recorded, validate, opts, nominal.theta.clone());
    let found = find(&stage)?;
    let train_seconds = seconds(train);
    let anchored = found.description_test.as_ref().map_or(0, |r| r.steps.len());
    let steps = (found.selection.steps.len(), anchored);
    let verdict = verdict_of(
        steps,
        &found.how_far,
        &found.structure_left,
        train_seconds,
        opts,
    );
    let description_overall = mean_square(&found.ladder.description_rms).sqrt();
    let at = (
        description_overall,
        train_seconds,
        opts.min_decisive_seconds,
    );
    let summary = summary_text(model, at, &found, verdict);
    let (how_far, ladder) = (found.how_far, found.ladder);
    Ok(Diagnosis {
        confirmed: how_far.confirmed,
        confirmed_only: how_far.confirmed_only,
        robot: model.name().to_string(),
        joints: model.joint_names(),
        samples: [train.len(), validate.len()],
        constraints: opts.constraints,
        nominal_constraints_hold: nominal.constraints_hold,
        breakdown: breakdown(validate, 0..validate.len(), &ladder.nominal_res),
        spectra: breakdown::spectra(model, validate, &ladder.nominal_res),
        spectra_after: breakdown::spectra(model, validate, &ladder.final_res),
        selection: found.selection,
        description_test: found.description_test,
        description_test_skipped: found.description_test_skipped,
        backlash_untested: backlash_untested(&stage),
        ladder: found.from_description,
        described_effects: found.described_effects,
        effects: found.effects,
        gap: how_far.gap,
        description_overall,
        explained_from_description: found.explained_from_description,
        overall: how_far.overall,
        noise_floor: how_far.floor_ms.sqrt(),
        gap_closed: how_far.gap_closed,
        structure_left: found.structure_left,
        verdict,
        summary,
    })
}

/// The time `tr` spans at its sample period (s; 0 without one).
fn seconds(tr: &Trajectory) -> f64 {
    tr.sample_period().map_or(0.0, |dt| dt * tr.len() as f64)
}

/// The joints whose backlash neither data set's columns test (`Context::backlash_untested`).
fn backlash_untested(stage: &Stage) -> Vec<String> {
    let (train, val) = (
        stage.ctx_train.backlash_untested(),
        stage.ctx_val.backlash_untested(),
    );
    (stage.model.joint_names().into_iter().enumerate())
        .filter(|(j, _)| train[*j] || val[*j])
        .map(|(_, name)| name)
        .collect()
}

/// What the steps find on a stage, before the verdict.
struct Found {
    selection: select::Selection,
    description_test: Option<anchor::Report>,
    description_test_skipped: Option<String>,
    ladder: gap::Ladder,
    effects: Vec<EffectEstimate>,
    from_description: Option<super::ladder::Ladder>,
    described_effects: Vec<EffectEstimate>,
    how_far: gap::HowFar,
    explained_from_description: Vec<DescriptionStep>,
    structure_left: StructureLeft,
}

/// What cross-validation and the description test find, with the ladder of the re-identified
/// model and the magnitudes of their effects.
struct CrossValidated {
    selection: select::Selection,
    description_test: Option<anchor::Report>,
    description_test_skipped: Option<String>,
    /// The effects cross-validation chose, then those the description test found (variants).
    chosen: Vec<usize>,
    ladder: gap::Ladder,
    effects: Vec<EffectEstimate>,
}

/// Which effects (cross-validation, then the description test), how far each takes the
/// validation residual, their magnitudes, the ladder from the description and the structure
/// left. The ladder from the description starts beside cross-validation (its first rungs do not
/// depend on it), and is climbed beside how far the selected effects go: the same numbers as
/// one after the other, whatever the thread count.
fn find(stage: &Stage) -> Result<Found, DiagnoseError> {
    let (cross_validated, start) =
        rayon::join(|| select_effects(stage), || described::start(stage));
    let CrossValidated {
        selection,
        description_test,
        description_test_skipped,
        chosen,
        ladder,
        mut effects,
    } = cross_validated?;
    let n_cv = selection.chosen.len();
    let (described, after) = rayon::join(
        || described::from_description(stage, &selection, start, &mut effects),
        || {
            let train_res = gap::final_train_residual(stage, &chosen, &ladder);
            let how_far = gap::how_far(stage, (&chosen, n_cv), &ladder, &train_res);
            (how_far, structure_after(stage, &train_res, &ladder))
        },
    );
    let (how_far, structure_left) = (after.0?, after.1);
    let (from_description, described_effects) = match described {
        Some((l, described)) => (Some(l), described),
        None => (None, vec![]),
    };
    let explained_from_description = match &from_description {
        Some(l) => described::description_steps(l),
        None => explain::from_description(stage, &chosen, &ladder),
    };
    Ok(Found {
        selection,
        description_test,
        description_test_skipped,
        ladder,
        effects,
        from_description,
        described_effects,
        how_far,
        explained_from_description,
        structure_left,
    })
}

/// Cross-validation's selection, the description test beside it, the re-identified ladder of
/// what they chose and their effects' magnitudes.
fn select_effects(stage: &Stage) -> Result<CrossValidated, DiagnoseError> {
    let selection = select::forward_select(
        &stage.folds,
        stage.model,
        &stage.ident_opts,
        &stage.opts.selection,
    )?;
    let (description_test, description_test_skipped) = run_description_test(stage, &selection)?;
    let anchored: &[anchor::Step] = description_test.as_ref().map_or(&[], |r| &r.steps);
    let chosen: Vec<usize> = [&selection.chosen[..], &variants_of(anchored)].concat();
    let ladder = gap::ladder(stage, &chosen)?;
    let mut effects = magnitude::cross_validated(stage, &selection, &ladder.final_theta);
    effects.extend(magnitude::against_description(stage, anchored));
    Ok(CrossValidated {
        selection,
        description_test,
        description_test_skipped,
        chosen,
        ladder,
        effects,
    })
}

/// The verdict of the steps of cross-validation and of the description test given how far
/// they closed the gap and the structure left, held back on too little data.
fn verdict_of(
    (selected, anchored): (usize, usize),
    how_far: &gap::HowFar,
    structure_left: &StructureLeft,
    train_seconds: f64,
    opts: &Options,
) -> Verdict {
    let v = verdict::verdict(
        selected,
        anchored,
        how_far,
        opts.unexplained_ratio,
        structure_left.remains,
    );
    decisive_verdict(v, train_seconds, opts)
}

/// The variants of the description test's steps.
fn variants_of(steps: &[anchor::Step]) -> Vec<usize> {
    steps.iter().map(|s| s.variant).collect()
}

/// What structure is left after the chosen effects: a smooth function of each joint's speed
/// and angle fitted on the final training residual `train_res`, scored on the final validation
/// residual.
fn structure_after(
    stage: &Stage,
    train_res: &[f64],
    ladder: &gap::Ladder,
) -> structure::StructureLeft {
    structure::structure_left(
        stage,
        train_res,
        &ladder.final_res,
        stage.opts.structure_threshold,
    )
}

/// A verdict of "nothing" or "unexplained" on less training data than
/// `opts.min_decisive_seconds` (s) is undecided.
fn decisive_verdict(v: Verdict, train_seconds: f64, opts: &Options) -> Verdict {
    match v {
        Verdict::Unexplained | Verdict::NoEffect if train_seconds < opts.min_decisive_seconds => {
            Verdict::Undecided
        }
        v => v,
    }
}

/// Absorbed effects, against the description when its uncertainty is stated, beside what
/// cross-validation chose, unless a chosen effect's columns only approximate it (a delay to
/// first order, a rotor without its gyroscopic terms): what they miss biases θ in ways the
/// prior test would misread as an absorbed effect. Returns the test, or why it did not run.
fn run_description_test(
    stage: &Stage,
    selection: &select::Selection,
) -> Result<(Option<anchor::Report>, Option<String>), DiagnoseError> {
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
            library::names(&linearized)
        )
    });
    Ok((description_test, description_test_skipped))
}

/// The diagnosis's one-paragraph summary of what was `found` and its `verdict`, given the
/// description's overall validation RMS (N m), the training data's length (s) and the shortest
/// on which a verdict of "nothing" or "unexplained" is decisive (s).
fn summary_text(
    model: &Model,
    (description_overall, train_seconds, min_decisive): (f64, f64, f64),
    found: &Found,
    verdict: Verdict,
) -> String {
    let n_cv = found.selection.chosen.len();
    let mut summary = format!(
        "the description as given predicts the validation data with {:.3} N m RMS (re-identified: {:.3} N m); {}",
        description_overall,
        found.how_far.overall[0],
        verdict::summary(
            verdict,
            &found.effects,
            n_cv,
            &found.how_far,
            found.description_test.as_ref()
        )
    );
    summary += &verdict::structure_summary(&found.structure_left, &model.joint_names());
    summary += &explain::summary(&found.explained_from_description, description_overall);
    if verdict == Verdict::Undecided {
        summary += &format!(
            " (only {train_seconds:.1} s of training data, below the {} s on which a verdict of \"unexplained\" or \"no effect\" can be trusted: record longer runs)",
            min_decisive
        );
    }
    summary
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
    match Trajectory::concatenate(validate_runs) {
        None => {
            if !(holdout > 0.0 && holdout < 1.0) {
                return Err(DiagnoseError::Holdout(holdout));
            }
            let (train, val) = all.holdout_split(holdout);
            diagnose(model, &train, &val, opts)
        }
        Some(val) => diagnose_recordings(model, (&all, &lens), &val, opts),
    }
}
