//! The ladder from the description read as the diagnosis's results: its explanations as
//! effect estimates, its rungs as the description's steps, and its first explanation added to
//! the effects when neither cross-validation nor the description test named it.

use super::diagnosis::{DescriptionStep, EffectEstimate};
use super::ladder::{self, Explanation, Ladder};
use super::magnitude;
use super::select::Selection;
use super::stage::Stage;
use crate::effect::library::Variant;

/// The ladder from the description when its uncertainty is stated, its first explanation added
/// to `effects` when cross-validation and the description test did not name it (a payload on
/// any body, an absorbed tilt or gain beside a linearized effect); its later steps stay in the
/// ladder (on perturbed simulated descriptions they are mostly the description's own errors).
/// Returns the ladder and every explanation it chose as an effect estimate, anchored at the
/// description ([`estimates`]).
pub(crate) fn from_description(
    stage: &Stage,
    selection: &Selection,
    effects: &mut Vec<EffectEstimate>,
) -> Option<(Ladder, Vec<EffectEstimate>)> {
    let selected: Vec<Variant> = selection
        .chosen
        .iter()
        .map(|&v| stage.folds.variants[v])
        .collect();
    let eps = stage.opts.description_uncertainty?;
    let l = ladder::ladder(stage, eps, &selected, &stage.opts.ladder);
    let described = estimates(&l, stage);
    if let Some(e) = described.first() {
        if !effects.iter().any(|x| x.group().any(|k| k == e.kind)) {
            effects.push(e.clone());
        }
    }
    Some((l, described))
}

/// The explanations as the diagnosis's effect estimates (described by the description
/// test's evidence: they depart from the description), friction left out; a body change's
/// mass as the ladder states it ([`ladder::BodyChange::stated`]; identifiable 0 when the data
/// do not see it).
pub(crate) fn estimates(ladder: &Ladder, stage: &Stage) -> Vec<EffectEstimate> {
    let effects = ladder.chosen.iter().filter_map(|e| match e {
        Explanation::Effect(v) => Some(*v),
        Explanation::Friction => None,
    });
    let mut bodies = ladder.bodies.iter();
    effects
        .zip(ladder.coefficients.iter().zip(&ladder.coefficient_se))
        .map(|(v, (c, se))| {
            let (mut c, mut se) = (c.clone(), se.clone());
            let mut unseen = false;
            if let Some(b) = v.kind.is_body_change().then(|| bodies.next()).flatten() {
                c[0] = b.mass;
                se[0] = b.mass_se.unwrap_or(se[0]);
                unseen = b.mass_se.is_none();
            }
            let mut estimate = magnitude::described_estimate(stage, v, &c, &se, vec![]);
            if unseen {
                estimate.magnitudes[0].identifiable = 0.0;
            }
            estimate
        })
        .collect()
}

/// The rungs from the first explanation on (the description as given and within its
/// uncertainty left out), as the diagnosis's description steps.
pub(crate) fn description_steps(ladder: &Ladder) -> Vec<DescriptionStep> {
    ladder
        .rungs
        .iter()
        .skip(2)
        .map(|r| DescriptionStep {
            step: r.step.clone(),
            kind: r.kind,
            param: r.param,
            rms: r.rms.clone(),
            overall: r.overall,
        })
        .collect()
}
