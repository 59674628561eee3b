//! The **verdict** and the one-paragraph summary of a diagnosis.

use super::anchor;
use super::diagnosis::{EffectEstimate, Verdict};
use super::gap::HowFar;
use super::structure::StructureLeft;
use physid_effect::library::{self, Kind};

/// The verdict from what was selected and whether the final residual stays above the noise
/// floor by more than `unexplained_ratio` (in mean square) or still has structure a generic
/// function of speed and angle predicts (`structure_left`).
pub(crate) fn verdict(
    cross_validated: usize,
    absorbed: usize,
    how_far: &HowFar,
    unexplained_ratio: f64,
    structure_left: bool,
) -> Verdict {
    let last = how_far.overall[how_far.overall.len() - 1].powi(2);
    let above = last > unexplained_ratio * how_far.floor_ms || structure_left;
    match (cross_validated == 0, above) {
        (true, false) if absorbed == 0 => Verdict::NoEffect,
        (true, false) => Verdict::Absorbed,
        (true, true) => Verdict::Unexplained,
        (false, false) => Verdict::Explained,
        (false, true) => Verdict::PartiallyExplained,
    }
}

/// The sentence on structure left in the final residual (empty when none is).
pub(crate) fn structure_summary(s: &StructureLeft, joints: &[String]) -> String {
    if !s.remains {
        return String::new();
    }
    let at: Vec<String> = joints
        .iter()
        .zip(&s.per_joint)
        .filter(|(_, r)| **r >= s.threshold)
        .map(|(j, r)| format!("{j} {:.0} %", 100.0 * r))
        .collect();
    format!(
        "; structure remains outside the library: a smooth function of each joint's speed and angle, fitted on the training residual, lowers the final validation error by {:.0} % ({})",
        100.0 * s.reduction,
        at.join(", ")
    )
}

/// An effect's name, or its ambiguity group's.
fn name_of(e: &EffectEstimate) -> String {
    if e.ambiguous_with.is_empty() {
        e.kind.name().to_string()
    } else {
        let group: Vec<Kind> = e.group().collect();
        format!("one of {{{}}} (ambiguous)", library::names(&group))
    }
}

/// What the summary adds after the verdict: the effects found against the description (those
/// after the first `n_cv`), and the effects the validation data did not confirm.
fn addenda(
    effects: &[EffectEstimate],
    n_cv: usize,
    how_far: &HowFar,
    description_test: Option<&anchor::Report>,
) -> String {
    let mut summary = String::new();
    if let Some(rep) = description_test.filter(|r| !r.steps.is_empty()) {
        let absorbed: Vec<String> = effects[n_cv..].iter().map(name_of).collect();
        summary += &format!(
            "; absorbed by identification but revealed by the description (stated uncertainty {:.0} %): {}",
            100.0 * rep.uncertainty,
            absorbed.join(" + ")
        );
    }
    if let Some((_, o)) = &how_far.confirmed_only {
        let unconfirmed: Vec<&str> = effects
            .iter()
            .zip(&how_far.confirmed)
            .filter(|(_, c)| !**c)
            .map(|(e, _)| e.kind.name())
            .collect();
        summary += &format!(
            "; NOT confirmed on the validation data (its error rose when added): {}; with the confirmed effects only the validation RMS is {o:.3} N m",
            unconfirmed.join(", ")
        );
    }
    summary
}

/// The summary sentence: the verdict with its numbers, what the description test revealed, and
/// which effects the held-out data did not confirm. The first `n_cv` of `effects` come from
/// cross-validation.
pub(crate) fn summary(
    verdict: Verdict,
    effects: &[EffectEstimate],
    n_cv: usize,
    how_far: &HowFar,
    description_test: Option<&anchor::Report>,
) -> String {
    let overall = &how_far.overall;
    let floor = how_far.floor_ms.sqrt();
    let last = overall[overall.len() - 1].powi(2);
    let names: Vec<String> = effects[..n_cv].iter().map(name_of).collect();
    let mut summary = match verdict {
        Verdict::NoEffect => format!(
            "no effect found: the validation RMS {:.3} N m is at the noise floor {floor:.3} N m",
            overall[0],
        ),
        Verdict::Absorbed => format!(
            "no gap: the validation RMS {:.3} N m is at the noise floor {floor:.3} N m",
            overall[0],
        ),
        Verdict::Explained => format!(
            "{} explain(s) the gap: validation RMS {:.3} -> {:.3} N m (noise floor {floor:.3}), {:.0} % of the gap closed",
            names.join(" + "),
            overall[0],
            last.sqrt(),
            100.0 * how_far.gap_closed
        ),
        Verdict::PartiallyExplained => format!(
            "{} explain(s) part of the gap: validation RMS {:.3} -> {:.3} N m, {:.0} % closed; {:.3} N m RMS above the noise floor {floor:.3} N m remains unexplained",
            names.join(" + "),
            overall[0],
            last.sqrt(),
            100.0 * how_far.gap_closed,
            (last - how_far.floor_ms).max(0.0).sqrt(),
        ),
        Verdict::Unexplained => format!(
            "unexplained: the validation RMS {:.3} N m lies above the noise floor {floor:.3} N m and no effect in the library lowers the cross-validated error enough",
            overall[0],
        ),
        Verdict::Undecided => format!(
            "cannot decide: no effect selected, validation RMS {:.3} N m against a noise floor of {floor:.3} N m",
            overall[0],
        ),
    };
    summary += &addenda(effects, n_cv, how_far, description_test);
    summary
}
