//! `diagnose`: the diagnosis of a description against its runs (the JSON contract is
//! [`crate::diagnose::Diagnosis`], schema docs/schemas/diagnose.schema.json), or "what
//! changed" against baseline runs of the same robot.

use super::ApiError;
use crate::diagnose::baseline::Baseline;
use crate::diagnose::{self, DiagnoseError, Diagnosis, Options};
use crate::model::Model;
use crate::trajectory::Trajectory;

/// The runs a diagnosis reads, as prepared by the data pipeline.
#[derive(Clone, Debug, Default)]
pub struct Runs {
    /// Training runs (joined end to end; with several, the selection leaves one run out).
    pub train: Vec<Trajectory>,
    /// Validation runs; none: the last `holdout` fraction of the training runs is held out.
    pub validate: Vec<Trajectory>,
    /// Runs of the same robot before the change ("what changed"); none: the diagnosis of the
    /// description itself.
    pub baseline: Vec<Trajectory>,
}

/// A diagnosis, and in "what changed" mode what the baseline contributed.
pub struct Outcome {
    /// The diagnosis.
    pub diagnosis: Diagnosis,
    /// With baseline runs: the standing effects taken out of the changed runs (kind names).
    pub standing: Option<Vec<String>>,
}

/// Diagnoses `model` on `runs` with `opts`, holding out `holdout` of the training runs when no
/// validation run is given. With baseline runs (which need `opts.description_uncertainty`), the
/// description is first calibrated on them with their standing effects, and only what differs
/// is attributed. Options are checked first.
pub fn diagnose(
    model: &Model,
    runs: Runs,
    holdout: f64,
    opts: &Options,
) -> Result<Outcome, ApiError> {
    opts.validate()?;
    if runs.baseline.is_empty() {
        let diagnosis = diagnose::diagnose_runs(model, runs.train, runs.validate, holdout, opts)?;
        return Ok(Outcome {
            diagnosis,
            standing: None,
        });
    }
    if opts.description_uncertainty.is_none() {
        return Err(DiagnoseError::BaselineWithoutUncertainty.into());
    }
    let before = Baseline::calibrate(model, runs.baseline, holdout, opts)
        .map_err(|source| ApiError::Baseline { source })?;
    let standing = before
        .standing
        .iter()
        .map(|v| v.kind.name().to_string())
        .collect();
    let diagnosis = before.diagnose_change(model, runs.train, runs.validate, holdout, opts)?;
    Ok(Outcome {
        diagnosis,
        standing: Some(standing),
    })
}
