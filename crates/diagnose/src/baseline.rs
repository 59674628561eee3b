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
use super::options::{DiagnoseError, Options};
use super::pipeline::diagnose_runs;
use super::rows::for_each_row_in_order;
use physid_core::model::Model;
use physid_core::trajectory::Trajectory;
use physid_effect::library::{Context, Variant};

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
            ident: physid_ident::Options::new(opts.constraints),
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
/// about the calibration's nominal model, times their coefficients). Each run's margins
/// (`Trajectory::margins`, torque without its motion) lose the effects' torque at the run's
/// first and last sample, so that the torque stays continuous across the run's ends.
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
    for_each_row_in_order(&ctx, tr, 0..tr.len(), &copts.terms, 0.0, &mut |k, z, _| {
        let e = z.columns(p0, coef.len()) * coef;
        for j in 0..n {
            out.tau[k * n + j] -= e[j];
        }
    });
    let removed = |k: usize, j: usize| tr.tau[k * n + j] - out.tau[k * n + j];
    for (i, run) in tr.runs().into_iter().enumerate() {
        let Some(m) = out.margins.get_mut(i) else {
            break;
        };
        for (v, j) in m.before.iter_mut().zip((0..n).cycle()) {
            *v -= removed(run.start, j);
        }
        for (v, j) in m.after.iter_mut().zip((0..n).cycle()) {
            *v -= removed(run.end - 1, j);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::library::Kind;

    #[test]
    fn a_standing_offset_comes_out_of_the_margins_as_out_of_the_samples() {
        // The leg moving smoothly, its torque the model's plus a standing offset.
        let model = physid_core::model::cheetah3::leg();
        let n = model.dof();
        let offset = [0.5, -0.3, 0.2];
        let mut data = physid_core::dynamics::Data::new(&model);
        let mut tr = Trajectory::new(model.joint_names(), true);
        let w = 2.0 * std::f64::consts::PI * 0.7;
        for k in 0..2000 {
            let t = k as f64 * 1e-3;
            let s = |j: usize| w * t + j as f64;
            let q: Vec<f64> = (0..n).map(|j| 0.3 * s(j).sin()).collect();
            let qd: Vec<f64> = (0..n).map(|j| 0.3 * w * s(j).cos()).collect();
            let qdd: Vec<f64> = (0..n).map(|j| -0.3 * w * w * s(j).sin()).collect();
            let tau = physid_core::dynamics::rnea_with_friction(&model, &mut data, &q, &qd, &qdd);
            let tau: Vec<f64> = (0..n).map(|j| tau[j] + offset[j]).collect();
            tr.push(t, &q, &qd, Some(&qdd), &tau);
        }
        let options = calibrate::Options {
            ident: physid_ident::Options::new(physid_ident::ConstraintSet::None),
            terms: vec![Variant {
                kind: Kind::TorqueOffset,
                param: 0.0,
            }],
            processing_cutoff: 20.0,
            excluded: vec![],
        };
        let run = Run {
            trajectory: &tr,
            range: 0..tr.len(),
        };
        let cal = calibrate::calibrate(&model, &[run], &options).unwrap();
        // The offset the calibration kept in its column (the inertial parameters take part of
        // the first two joints' on this short motion): taken out of every sample alike.
        let p0 = model.layout().len;
        let c: Vec<f64> = cal.identified.theta.rows(p0, n).iter().copied().collect();
        assert!((c[2] - offset[2]).abs() < 0.01, "{c:?}");
        // The validation part: its margin before is the training part's torque.
        let (_, val) = tr.holdout_split(0.3);
        let out = without_effects(&model, &cal, &val, &options);
        let (before, stripped) = (&val.margin(0).before, &out.margin(0).before);
        assert_eq!(before.len(), (tr.len() - val.len()) * n);
        for (k, (a, b)) in val.tau.iter().zip(&out.tau).enumerate() {
            assert!((a - b - c[k % n]).abs() < 1e-9, "sample {k}: {a} {b}");
        }
        for (k, (a, b)) in before.iter().zip(stripped).enumerate() {
            assert!((a - b - c[k % n]).abs() < 1e-9, "margin {k}: {a} {b}");
        }
    }
}
