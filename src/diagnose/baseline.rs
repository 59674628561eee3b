//! **What changed**: the diagnosis of a change against a recording of the same robot before it
//! (a tool change, a repair, a new gripper), so that only what differs between the two
//! recordings is attributed and the robot's own standing effects cancel.
//!
//! 1. The baseline runs are diagnosed as usual; the description is then calibrated on them
//!    with the effects that diagnosis selected ([`super::calibrate`]): the inertial parameters
//!    and friction as the robot had them, and each standing effect's coefficients.
//! 2. The standing effects' torque (their columns about the calibrated model, times their
//!    coefficients) is taken out of the changed runs' logged torque.
//! 3. The changed runs are diagnosed against the calibrated description, its uncertainty the
//!    one stated: the ladder from it ([`super::ladder`]) names what changed.

use super::calibrate::{self, Calibration, Run};
use super::diagnosis::Diagnosis;
use super::library::{Context, Variant};
use super::options::{DiagnoseError, Options};
use super::pipeline::diagnose_runs;
use crate::model::Model;
use crate::trajectory::Trajectory;

/// The baseline's calibration: the description as the robot had it before the change.
#[derive(Clone, Debug)]
pub struct Baseline {
    /// The diagnosis of the baseline runs alone (its standing effects).
    pub diagnosis: Diagnosis,
    /// The description calibrated on the baseline (inertial parameters and friction).
    pub calibrated: Model,
    /// The standing effects taken out of the changed runs.
    pub standing: Vec<Variant>,
    /// The calibration (its nominal model and the standing effects' coefficients).
    calibration: Calibration,
    /// The calibration's options (the standing effects' columns).
    options: calibrate::Options,
    /// The calibrated description's information on the baseline (standing effects out).
    information: nalgebra::DMatrix<f64>,
}

/// The baseline's calibration and the change's diagnosis.
pub struct WhatChanged {
    /// The baseline's calibration.
    pub baseline: Baseline,
    /// The diagnosis of the changed runs against the calibrated description.
    pub change: Diagnosis,
}

impl Baseline {
    /// Step 1 (module docs): `baseline_runs` (before the change) diagnosed on `model`, and
    /// `model` calibrated on them with the standing effects that diagnosis selected.
    pub fn calibrate(
        model: &Model,
        baseline_runs: Vec<Trajectory>,
        holdout: f64,
        opts: &Options,
    ) -> Result<Baseline, DiagnoseError> {
        if opts.description_uncertainty.is_none() {
            return Err(DiagnoseError::BaselineWithoutUncertainty);
        }
        let diagnosis = diagnose_runs(model, baseline_runs.clone(), vec![], holdout, opts)?;
        let standing: Vec<Variant> = diagnosis
            .effects
            .iter()
            .filter(|e| e.evidence == super::diagnosis::Evidence::CrossValidation)
            .map(|e| Variant {
                kind: e.kind,
                param: e.param,
            })
            .collect();
        let runs: Vec<Run> = baseline_runs
            .iter()
            .map(|t| Run {
                trajectory: t,
                range: 0..t.len(),
            })
            .collect();
        let options = calibrate::Options {
            ident: crate::ident::Options::new(opts.constraints),
            terms: standing.clone(),
            processing_cutoff: opts.processing_cutoff,
            excluded: vec![],
        };
        let calibration = calibrate::calibrate(model, &runs, &options)?;
        let calibrated = calibrated_model(model, &calibration)?;
        let stripped: Vec<Trajectory> = baseline_runs
            .iter()
            .map(|t| without_effects(model, &calibration, t, &options))
            .collect();
        let joined = Trajectory::concatenate(stripped).ok_or(DiagnoseError::NoData)?;
        // What the baseline determined is held, what it did not is free to move.
        let information = super::anchor::information(&calibrated, &joined, opts)?.matrix;
        Ok(Baseline {
            diagnosis,
            calibrated,
            standing,
            calibration,
            options,
            information,
        })
    }

    /// Steps 2 and 3: the standing effects taken out of `train_runs`/`validate_runs` (after
    /// the change), then the change diagnosed against the calibrated description (`model` is
    /// the description the baseline was calibrated from).
    pub fn diagnose_change(
        &self,
        model: &Model,
        train_runs: Vec<Trajectory>,
        validate_runs: Vec<Trajectory>,
        holdout: f64,
        opts: &Options,
    ) -> Result<Diagnosis, DiagnoseError> {
        let strip = |runs: Vec<Trajectory>| -> Vec<Trajectory> {
            runs.iter()
                .map(|t| without_effects(model, &self.calibration, t, &self.options))
                .collect()
        };
        let change_opts = Options {
            description_information: Some(self.information.clone()),
            ..opts.clone()
        };
        diagnose_runs(
            &self.calibrated,
            strip(train_runs),
            strip(validate_runs),
            holdout,
            &change_opts,
        )
    }
}

/// Diagnoses `train_runs`/`validate_runs` (after the change) against `model` calibrated on
/// `baseline_runs` (before it), with the standing effects of the baseline taken out (module
/// docs). `opts.description_uncertainty` must be stated: the ladder from the calibrated
/// description is what names the change.
pub fn what_changed(
    model: &Model,
    baseline_runs: Vec<Trajectory>,
    train_runs: Vec<Trajectory>,
    validate_runs: Vec<Trajectory>,
    holdout: f64,
    opts: &Options,
) -> Result<WhatChanged, DiagnoseError> {
    let baseline = Baseline::calibrate(model, baseline_runs, holdout, opts)?;
    let change = baseline.diagnose_change(model, train_runs, validate_runs, holdout, opts)?;
    Ok(WhatChanged { baseline, change })
}

/// The description with the calibration's inertial parameters and friction.
fn calibrated_model(model: &Model, cal: &Calibration) -> Result<Model, DiagnoseError> {
    let p0 = model.layout().len;
    let theta = cal.identified.theta.rows(0, p0).into_owned();
    Ok(model.with_parameters(&theta)?)
}

/// `tr` with the calibrated effects' torque taken out of its logged torque (their columns
/// about the calibration's nominal model, times their coefficients).
fn without_effects(
    model: &Model,
    cal: &Calibration,
    tr: &Trajectory,
    copts: &calibrate::Options,
) -> Trajectory {
    let p0 = model.layout().len;
    let n = model.dof();
    let coef = cal
        .identified
        .theta
        .rows(p0, cal.identified.theta.len() - p0);
    let ctx = Context::new(model, &cal.nominal, tr, copts.processing_cutoff);
    let mut out = tr.clone();
    ctx.for_each_row(tr, 0..tr.len(), &copts.terms, 0.0, &mut |k, z, _| {
        let e = z.columns(p0, coef.len()) * coef;
        for j in 0..n {
            out.tau[k * n + j] -= e[j];
        }
    });
    out
}
