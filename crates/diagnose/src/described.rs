//! The ladder from the description read as the diagnosis's results: its explanations as
//! effect estimates, its rungs as the description's steps, and its first explanation added to
//! the effects when neither cross-validation nor the description test named it.

use super::diagnosis::{DescriptionStep, EffectEstimate};
use super::ladder::{self, Explanation, Ladder};
use super::magnitude::{self, Reading};
use super::select::Selection;
use super::stage::Stage;
use physid_effect::library::Variant;

/// The ladder's first rungs, which cross-validation does not change: started beside it
/// (`None` without a stated uncertainty of the description).
pub(crate) fn start<'a>(stage: &'a Stage) -> Option<ladder::Start<'a>> {
    let eps = stage.opts.description_uncertainty?;
    Some(ladder::start(stage, eps, &stage.opts.ladder))
}

/// The ladder from the description when its uncertainty is stated, its first explanation added
/// to `effects` when cross-validation and the description test did not name it (a payload on
/// any body, an absorbed tilt or gain beside a linearized effect); its later steps stay in the
/// ladder (on perturbed simulated descriptions they are mostly the description's own errors).
/// Returns the ladder and every explanation it chose as an effect estimate, anchored at the
/// description ([`estimates`]), from the ladder's [`start`].
pub(crate) fn from_description(
    stage: &Stage,
    selection: &Selection,
    start: Option<ladder::Start>,
    effects: &mut Vec<EffectEstimate>,
) -> Option<(Ladder, Vec<EffectEstimate>)> {
    let selected = selected_or_tied(stage, selection);
    let l = ladder::ladder(start?, &selected, &stage.opts.ladder);
    let described = estimates(&l, stage);
    if let Some(e) = described.first() {
        if !effects.iter().any(|x| x.group().any(|k| k == e.kind)) {
            effects.push(e.clone());
        }
    }
    Some((l, described))
}

/// The variants cross-validation chose and every variant of the kinds it could not tell
/// from them (a step's `ambiguous_with`): the ladder weighs each against the description,
/// where a tie of the re-identified model may part (an offset on every joint and
/// direction-dependent friction tie when the friction is free, not when it is pinned at the
/// description's). A refinement of the friction is not offered for a tie alone: the ladder's
/// friction re-identified is the friction change it weighs (offered for its tie with an
/// offset, direction-dependent friction had taken a doubled friction's place on a real KUKA
/// run, semi-real seed 1, case 15).
fn selected_or_tied(stage: &Stage, selection: &Selection) -> ladder::Selected {
    let variants = &stage.folds.variants;
    let tied: Vec<_> = selection
        .steps
        .iter()
        .flat_map(|s| s.ambiguous_with.iter().copied())
        .filter(|k| !k.refines_friction())
        .collect();
    ladder::Selected {
        chosen: selection.chosen.iter().map(|&v| variants[v]).collect(),
        tied: variants
            .iter()
            .filter(|v| tied.contains(&v.kind))
            .copied()
            .collect(),
    }
}

/// The explanations as the diagnosis's effect estimates (described by the description
/// test's evidence: they depart from the description), friction left out; each as weighed at
/// its step, with its magnitudes in the final fit beside where later steps moved them
/// ([`moved_by_later_steps`]); a body change's mass as the ladder states it
/// ([`ladder::BodyChange::stated`]; identifiable 0 when the data do not see it).
pub(crate) fn estimates(ladder: &Ladder, stage: &Stage) -> Vec<EffectEstimate> {
    let effects = ladder.chosen.iter().filter_map(Explanation::variant);
    let mut bodies = ladder.bodies.iter();
    effects
        .zip(ladder.coefficients.iter().zip(&ladder.coefficient_se))
        .map(|(v, last)| {
            if let Some(b) = v.kind.is_body_change().then(|| bodies.next()).flatten() {
                return body_estimate(stage, v, last, b);
            }
            let anchored = (v, Reading::Anchored);
            let estimate_of = |(c, se): (&Vec<f64>, &Vec<f64>)| {
                magnitude::described_estimate(stage, anchored, c, se, vec![])
            };
            let final_fit = estimate_of(last);
            let Some(step) = ladder.entered(v) else {
                return final_fit;
            };
            let mut estimate = estimate_of(step);
            if moved_by_later_steps(&estimate, &final_fit) {
                estimate.after_later_steps = Some(final_fit.magnitudes);
            }
            estimate
        })
        .collect()
}

/// A body change as an effect estimate: its mass as the ladder states it, its other
/// parameters from the final fit.
fn body_estimate(
    stage: &Stage,
    v: Variant,
    (c, se): (&Vec<f64>, &Vec<f64>),
    b: &ladder::BodyChange,
) -> EffectEstimate {
    let (mut c, mut se) = (c.clone(), se.clone());
    c[0] = b.mass;
    se[0] = b.mass_se.unwrap_or(se[0]);
    let mut estimate =
        magnitude::described_estimate(stage, (v, Reading::Anchored), &c, &se, vec![]);
    if b.mass_se.is_none() {
        estimate.magnitudes[0].identifiable = 0.0;
    }
    estimate
}

/// Whether the final fit moved a magnitude of the step's `at_step` by more than
/// [`ladder::MOVED`] standard errors (the larger of the two).
fn moved_by_later_steps(at_step: &EffectEstimate, final_fit: &EffectEstimate) -> bool {
    (at_step.magnitudes.iter().zip(&final_fit.magnitudes))
        .any(|(a, b)| (a.value - b.value).abs() > ladder::MOVED * a.se.max(b.se))
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnosis::{Evidence, Magnitude};
    use physid_effect::library::Kind;

    fn gains(values: &[(f64, f64)]) -> EffectEstimate {
        EffectEstimate {
            kind: Kind::TorqueGain,
            evidence: Evidence::Description,
            param: 0.0,
            magnitude_name: "gain error against the description".into(),
            magnitudes: values
                .iter()
                .map(|&(value, se)| Magnitude {
                    joint: "j".into(),
                    value,
                    se,
                    unit: "-".into(),
                    identifiable: 1.0,
                })
                .collect(),
            ambiguous_with: vec![],
            separate_by: None,
            after_later_steps: None,
        }
    }

    #[test]
    fn a_magnitude_is_moved_by_later_steps_beyond_two_of_the_larger_standard_error() {
        // The semi-real shoulder gain: −0.242 ± 0.006 at its step, −0.60 ± 0.20 in the final
        // fit: within two of the larger error, not moved (the step's weighing is stated).
        let at_step = gains(&[(-0.242, 0.006), (0.003, 0.012)]);
        assert!(!moved_by_later_steps(
            &at_step,
            &gains(&[(-0.60, 0.20), (0.003, 0.012)])
        ));
        // One joint beyond: moved.
        assert!(moved_by_later_steps(
            &at_step,
            &gains(&[(-0.242, 0.006), (0.03, 0.012)])
        ));
        // The edge: exactly two standard errors is not moved.
        assert!(!moved_by_later_steps(
            &gains(&[(0.5, 0.125)]),
            &gains(&[(1.0, 0.25)])
        ));
        assert!(moved_by_later_steps(
            &gains(&[(0.5, 0.125)]),
            &gains(&[(1.0625, 0.25)])
        ));
    }
}
