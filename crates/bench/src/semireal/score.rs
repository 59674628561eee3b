//! The semi-real benchmark's scores: each case against what was injected ([`RealCase`]),
//! the scores over cases ([`score`]), and the files written ([`write`]).

use super::*;

/// A case's marks.
pub(super) fn score_case(
    i: usize,
    base: &Base,
    inj: &Injection,
    model: &Model,
    d: &Diagnosis,
    seconds: f64,
) -> RealCase {
    let ladder = d.ladder.as_ref();
    let steps: Vec<&diagnose::ladder::Rung> =
        ladder.map_or(vec![], |l| l.rungs[2..l.rungs.len() - 1].iter().collect());
    let found = found_steps(&steps);
    let bodies = ladder.map_or(&[][..], |l| &l.bodies[..]);
    let body_name = inj.body.map(|b| model.bodies()[b].name.clone());
    let first = steps.first();
    let top1 = first_step_names(inj, body_name.as_deref(), first.copied());
    // The injected body's change, where a step chose it.
    let chosen = body_name
        .as_deref()
        .and_then(|b| bodies.iter().find(|c| c.body == b));
    let payload_mass = body_name
        .as_deref()
        .and_then(|b| carried_mass(b, chosen, first.copied()));
    let mass_error = payload_mass.map(|m| (m - inj.magnitudes[0]).abs() / inj.magnitudes[0]);
    let payload_mass_last = chosen.map(|c| c.last.mass);
    let (magnitude_error, magnitude_error_weighted) = match inj.slot {
        Slot::Payload => (mass_error, mass_error),
        Slot::Effect(k) => (
            magnitude_error(d, k, &inj.magnitudes),
            weighted_magnitude_error(d, k, &inj.magnitudes),
        ),
        _ => (None, None),
    };
    RealCase {
        case: i,
        base: file_name(&base.path),
        described_by: file_name(&base.described_by),
        injected: inj.slot.name().into(),
        injected_body: body_name,
        injected_mass: (inj.slot == Slot::Payload).then(|| inj.magnitudes[0]),
        found,
        first_also_fit: first.map_or(vec![], |r| {
            r.also_fit.iter().map(|a| a.name.clone()).collect()
        }),
        verdict: d.verdict,
        top1,
        payload_claimed: bodies.iter().any(|b| b.payload),
        payload_mass,
        payload_mass_last,
        magnitude_error,
        magnitude_error_weighted,
        rms: [d.overall[0], d.overall[d.overall.len() - 1]],
        seconds,
        growth: f64::NAN,
        draws: 1,
        mass_bound: None,
    }
}

/// Each step's name with its ambiguity group, joined by `|`.
pub(super) fn found_steps(steps: &[&diagnose::ladder::Rung]) -> Vec<String> {
    steps
        .iter()
        .map(|r| {
            std::iter::once(r.step.clone())
                .chain(r.ambiguous_with.iter().cloned())
                .collect::<Vec<_>>()
                .join(" | ")
        })
        .collect()
}

pub(super) fn file_name(p: &Path) -> String {
    p.file_name()
        .map_or_else(|| p.display().to_string(), |f| f.to_string_lossy().into())
}

/// The estimate of `kind` the case is scored on: the ladder's (anchored at the description, as
/// the case's steps are) where the ladder chose the kind, else the cross-validated one.
pub(super) fn estimate_of(d: &Diagnosis, kind: Kind) -> Option<&diagnose::EffectEstimate> {
    (d.described_effects.iter())
        .chain(&d.effects)
        .find(|e| e.kind == kind)
}

/// Relative error `‖m̂ − m‖/‖m‖` of the estimate of `kind` over the joints whose estimate is
/// identifiable.
pub(super) fn magnitude_error(d: &Diagnosis, kind: Kind, truth: &[f64]) -> Option<f64> {
    let e = estimate_of(d, kind)?;
    relative_error(e, truth, |_| 1.0)
}

/// The same error with each joint weighted by its estimate's information `1/se²` (joints
/// without a finite positive standard error left out): what the data determine. A joint the
/// data do not see (a compliance on a wrist joint whose torque is a tenth of a newton metre)
/// has an estimate whose standard error exceeds it a hundredfold, and would decide the
/// unweighted error alone.
pub(super) fn weighted_magnitude_error(d: &Diagnosis, kind: Kind, truth: &[f64]) -> Option<f64> {
    let e = estimate_of(d, kind)?;
    relative_error(e, truth, information)
}

/// A magnitude's information `1/se²` (0 without a finite positive standard error).
pub(super) fn information(m: &diagnose::Magnitude) -> f64 {
    if m.se.is_finite() && m.se > 0.0 {
        1.0 / (m.se * m.se)
    } else {
        0.0
    }
}

/// `sqrt(Σ w (m̂ − m)² / Σ w m²)` over the identifiable joints, `w` per magnitude.
pub(super) fn relative_error(
    e: &diagnose::EffectEstimate,
    truth: &[f64],
    weight: impl Fn(&diagnose::Magnitude) -> f64,
) -> Option<f64> {
    let (mut num, mut den) = (0.0, 0.0);
    for (m, t) in e.magnitudes.iter().zip(truth) {
        if m.is_identifiable() {
            let w = weight(m);
            num += w * (m.value - t).powi(2);
            den += w * t * t;
        }
    }
    (den > 0.0).then(|| (num / den).sqrt())
}

/// The semi-real benchmark's scores.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct RealScores {
    /// Cases run.
    pub cases: usize,
    /// Cases whose first draw the run did not show (hidden by the base's standing gap, or a
    /// payload's mass it cannot weigh) and were drawn again ([`draw_visible`]).
    pub redrawn: usize,
    /// Payload cases.
    pub payload: usize,
    /// Fraction whose first step is the payload on its body.
    pub payload_found: f64,
    /// Fraction whose payload mass on that body is within 15 % of the truth.
    pub payload_mass_within_15: f64,
    /// Median relative error of the payload mass.
    pub median_payload_mass_error: f64,
    /// Payload cases whose payload raised the description's torque RMS by at least
    /// `VISIBLE.0` (a payload near the base barely moves the torque).
    pub payload_visible: usize,
    /// Fraction of those whose first step is the payload on its body.
    pub payload_found_visible: f64,
    /// Untouched real runs.
    pub clean: usize,
    /// Fraction of them with no payload or body change claimed.
    pub clean_no_payload: f64,
    /// Fraction of them with no step at all.
    pub clean_no_claim: f64,
    /// Cases without a payload injected (untouched runs and every other change).
    pub without_payload: usize,
    /// Fraction of them in which no step of the ladder names a body (`+ payload on …`, `+
    /// change of …`), first or later.
    pub without_payload_no_body_step: f64,
    /// Cases with one injected change (payload and friction included).
    pub single: usize,
    /// Fraction whose first step names it.
    pub top1: f64,
    /// Of them, the cases whose change raised the description's torque RMS by at least
    /// `VISIBLE.0` (1.5 times: [`RealCase::growth`]).
    pub visible_single: usize,
    /// Fraction of those whose first step names it.
    pub top1_visible: f64,
    /// Median relative magnitude error over them, where attributed.
    pub median_magnitude_error: f64,
    /// Median of the information-weighted error ([`RealCase::magnitude_error_weighted`]).
    pub median_magnitude_error_weighted: f64,
}

/// Whether a ladder step (`+ payload on lwr_5_link | payload or change on lwr_6_link`) names a
/// body change.
pub(crate) fn names_a_body(step: &str) -> bool {
    step.starts_with("+ payload on") || step.starts_with("+ change of")
}

/// Scores of a set of cases.
pub fn score(results: &[RealCase]) -> RealScores {
    let payload: Vec<&RealCase> = results.iter().filter(|r| r.injected == "payload").collect();
    let clean: Vec<&RealCase> = results.iter().filter(|r| r.injected == "clean").collect();
    let mass_err: Vec<f64> = payload.iter().filter_map(|r| r.magnitude_error).collect();
    let visible: Vec<bool> = results
        .iter()
        .filter(|r| r.growth >= VISIBLE.0)
        .filter_map(|r| r.top1)
        .collect();
    RealScores {
        cases: results.len(),
        redrawn: results.iter().filter(|r| r.draws > 1).count(),
        payload: payload.len(),
        payload_found: physid_experiment::fraction(payload.iter().map(|r| r.top1 == Some(true))),
        payload_mass_within_15: physid_experiment::fraction(
            payload
                .iter()
                .map(|r| r.magnitude_error.is_some_and(|e| e <= 0.15)),
        ),
        median_payload_mass_error: physid_experiment::median(&mass_err),
        payload_visible: payload.iter().filter(|r| r.growth >= VISIBLE.0).count(),
        payload_found_visible: physid_experiment::fraction(
            payload
                .iter()
                .filter(|r| r.growth >= VISIBLE.0)
                .map(|r| r.top1 == Some(true)),
        ),
        clean: clean.len(),
        clean_no_payload: physid_experiment::fraction(clean.iter().map(|r| !r.payload_claimed)),
        clean_no_claim: physid_experiment::fraction(clean.iter().map(|r| r.found.is_empty())),
        without_payload: results.len() - payload.len(),
        without_payload_no_body_step: physid_experiment::fraction(
            (results.iter())
                .filter(|r| r.injected != "payload")
                .map(|r| !r.found.iter().any(|s| names_a_body(s))),
        ),
        single: results.iter().filter(|r| r.top1.is_some()).count(),
        top1: physid_experiment::fraction(results.iter().filter_map(|r| r.top1)),
        visible_single: visible.len(),
        top1_visible: physid_experiment::fraction(visible),
        median_magnitude_error: physid_experiment::median(
            &results
                .iter()
                .filter_map(|r| r.magnitude_error)
                .collect::<Vec<_>>(),
        ),
        median_magnitude_error_weighted: physid_experiment::median(
            &results
                .iter()
                .filter_map(|r| r.magnitude_error_weighted)
                .collect::<Vec<_>>(),
        ),
    }
}

/// The case table.
pub fn case_table(results: &[RealCase]) -> PolarsResult<DataFrame> {
    let s = |f: &dyn Fn(&RealCase) -> String| results.iter().map(f).collect::<Vec<_>>();
    df!(
        "case" => results.iter().map(|r| r.case as u64).collect::<Vec<_>>(),
        "base" => s(&|r| r.base.clone()),
        "described_by" => s(&|r| r.described_by.clone()),
        "injected" => s(&|r| r.injected.clone()),
        "injected_body" => results.iter().map(|r| r.injected_body.clone()).collect::<Vec<_>>(),
        "injected_mass" => results.iter().map(|r| r.injected_mass).collect::<Vec<_>>(),
        "found" => s(&|r| r.found.join(", ")),
        "verdict" => s(&|r| physid_io::serde_name(&r.verdict)),
        "top1" => results.iter().map(|r| r.top1).collect::<Vec<_>>(),
        "payload_claimed" => results.iter().map(|r| r.payload_claimed).collect::<Vec<_>>(),
        "payload_mass" => results.iter().map(|r| r.payload_mass).collect::<Vec<_>>(),
        "payload_mass_last" => results.iter().map(|r| r.payload_mass_last).collect::<Vec<_>>(),
        "magnitude_error" => results.iter().map(|r| r.magnitude_error).collect::<Vec<_>>(),
        "magnitude_error_weighted" => results.iter().map(|r| r.magnitude_error_weighted).collect::<Vec<_>>(),
        "rms_description" => results.iter().map(|r| r.rms[0]).collect::<Vec<_>>(),
        "rms_final" => results.iter().map(|r| r.rms[1]).collect::<Vec<_>>(),
        "growth" => results.iter().map(|r| r.growth).collect::<Vec<_>>(),
        "draws" => results.iter().map(|r| r.draws as u64).collect::<Vec<_>>(),
        "mass_bound" => results.iter().map(|r| r.mass_bound).collect::<Vec<_>>(),
        "first_also_fit" => s(&|r| r.first_also_fit.join(" | ")),
    )
}

/// Writes `cases.csv`, `README.md` (command, scores, per-kind table, cases) and `scores.json`
/// into `dir`.
pub fn write(
    dir: &Path,
    results: &[RealCase],
    scores: &RealScores,
    command: &str,
    wall: f64,
) -> Result<(), RealError> {
    physid_io::write_result_dir(dir, physid_io::SCORES_MARK, |staged| {
        write_files(staged, results, scores, command, wall)
    })
}

/// The files of [`write`] written into `dir`.
pub(super) fn write_files(
    dir: &Path,
    results: &[RealCase],
    scores: &RealScores,
    command: &str,
    wall: f64,
) -> Result<(), RealError> {
    let mut df = case_table(results)?;
    tables::write_csv(&dir.join("cases.csv"), &mut df)?;
    use tables::Stat::{Count, Mean, Median};
    let per_kind = tables::group_stats(
        &df,
        &["injected"],
        &[
            ("", Count, "cases"),
            ("top1", Mean, "top1"),
            ("growth", Median, "median_growth"),
            ("payload_claimed", Mean, "payload_claimed"),
            ("magnitude_error", Median, "median_magnitude_error"),
            (
                "magnitude_error_weighted",
                Median,
                "median_magnitude_error_weighted",
            ),
        ],
    )?
    .sort(["injected"], Default::default())?;
    let md = format!(
        "# Semi-real blind benchmark\n\n`{command}` ({wall:.0} s wall).\n\nReal runs as the base, the description identified on another run, one change injected per case (docs/diagnose.md, \"Semi-real benchmark\").\n\n## Scores\n\n```json\n{}\n```\n\n## By injected change\n\n{}\n## Cases\n\n{}",
        serde_json::to_string_pretty(scores)?,
        tables::markdown(&per_kind),
        tables::markdown(&df)
    );
    physid_io::write_atomic(&dir.join("README.md"), md.as_bytes())?;
    physid_io::write_atomic(
        &dir.join("scores.json"),
        serde_json::to_string_pretty(&physid_io::versioned("blind_real_scores", scores))?
            .as_bytes(),
    )?;
    Ok(())
}
