//! **How far** the gap shrinks: the validation RMS per joint of the nominal model and after each
//! selected effect (refitted on all training data), the noise floor it can shrink to (Gamma
//! test, [`super::noise`]), the fraction of the gap closed, and whether each cross-validated
//! effect is confirmed on the held-out data.

use super::diagnosis::JointGap;
use super::noise;
use super::options::DiagnoseError;
use super::residual::{mask_slow, mean_square, residual_rms};
use super::stage::Stage;
use nalgebra::DVector;
use physid_core::trajectory::Trajectory;

/// Nearest neighbours closer in time than this (s) are not used by the noise floor.
const NEIGHBOUR_EXCLUSION: f64 = 0.2;

/// The validation residuals along the selection: the nominal model, then each effect added.
pub(crate) struct Ladder {
    /// Validation RMS per joint (N m) of the description as given (its own parameters and
    /// friction, nothing refitted): the sim-to-real gap itself.
    pub description_rms: Vec<f64>,
    /// Validation RMS per joint (N m), one entry per step (nominal first).
    pub per_step_rms: Vec<Vec<f64>>,
    /// The nominal model's validation residual (sample-major, N m).
    pub nominal_res: Vec<f64>,
    /// The final model's validation residual.
    pub final_res: Vec<f64>,
    /// The final model's parameters (the model's, then the effects' coefficients).
    pub final_theta: DVector<f64>,
}

/// Scores the description as given on the validation data, then refits on all training data
/// with the first `i` of `chosen` effects, for every `i`, and scores each fit.
pub(crate) fn ladder(stage: &Stage, chosen: &[usize]) -> Result<Ladder, DiagnoseError> {
    let (folds, validate) = (&stage.folds, stage.validate);
    let mut per_step_rms = vec![];
    let (mut nominal_res, mut final_res) = (vec![], vec![]);
    let mut final_theta = stage.theta0.clone();
    for i in 0..=chosen.len() {
        let first = &chosen[..i];
        let theta = if i == 0 {
            stage.theta0.clone()
        } else {
            folds.fit(stage.model, &stage.all, first, &stage.ident_opts)?
        };
        let variants: Vec<_> = first.iter().map(|&v| folds.variants[v]).collect();
        let (rms, res) = residual_rms(
            &stage.ctx_val,
            validate,
            &variants,
            &theta,
            stage.opts.min_speed,
        );
        per_step_rms.push(rms);
        if i == 0 {
            nominal_res = res.clone();
        }
        if i == chosen.len() {
            final_res = res;
            final_theta = theta;
        }
    }
    let (description_rms, _) = residual_rms(
        &stage.ctx_val,
        validate,
        &[],
        &stage.model.parameters(),
        stage.opts.min_speed,
    );
    Ok(Ladder {
        description_rms,
        per_step_rms,
        nominal_res,
        final_res,
        final_theta,
    })
}

/// The gap and how much of it the selection closed.
pub(crate) struct HowFar {
    /// Per joint: nominal and after-each-step RMS, noise floor, fraction closed.
    pub gap: Vec<JointGap>,
    /// RMS over all joints per step (N m).
    pub overall: Vec<f64>,
    /// Mean square of the noise floor over the joints that have one (N² m²).
    pub floor_ms: f64,
    /// Fraction of the overall gap to the floor closed (−1..1).
    pub gap_closed: f64,
    /// Per selected effect: its addition lowered the validation error (description evidence is
    /// confirmed before it is kept).
    pub confirmed: Vec<bool>,
    /// When some effect is not confirmed: per-joint and overall validation RMS with the
    /// confirmed effects only.
    pub confirmed_only: Option<(Vec<f64>, f64)>,
}

/// The final model's residual on the training data (sample-major, N m): the `chosen` effects
/// with the ladder's final parameters.
pub(crate) fn final_train_residual(stage: &Stage, chosen: &[usize], ladder: &Ladder) -> Vec<f64> {
    let variants: Vec<_> = chosen.iter().map(|&v| stage.folds.variants[v]).collect();
    let (train, ms) = (stage.train, stage.opts.min_speed);
    residual_rms(&stage.ctx_train, train, &variants, &ladder.final_theta, ms).1
}

/// The gap per joint and overall, against the noise floor of the final residual (on the
/// training data `train_res`, [`final_train_residual`], and the validation data); `n_cv` of
/// the `chosen` effects come from cross-validation (the rest from the description test).
pub(crate) fn how_far(
    stage: &Stage,
    (chosen, n_cv): (&[usize], usize),
    ladder: &Ladder,
    train_res: &[f64],
) -> Result<HowFar, DiagnoseError> {
    let floor_var = noise_floor(stage, ladder, train_res);
    let gap = joint_gaps(stage, ladder, &floor_var);
    let overall: Vec<f64> = ladder
        .per_step_rms
        .iter()
        .map(|r| mean_square(r).sqrt())
        .collect();
    // A joint that never moves faster than the threshold has no floor (NaN): left out.
    let finite: Vec<f64> = floor_var
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .collect();
    if finite.is_empty() {
        return Err(DiagnoseError::NoNoiseFloor {
            min_speed: stage.opts.min_speed,
        });
    }
    let floor_ms = finite.iter().sum::<f64>() / finite.len() as f64;
    let (first, last) = (overall[0].powi(2), overall[overall.len() - 1].powi(2));
    let gap_closed = if first > floor_ms {
        ((first - last) / (first - floor_ms)).clamp(-1.0, 1.0)
    } else {
        0.0
    };
    // Held-out confirmation of cross-validation evidence: the validation error falls.
    // Description evidence was confirmed on the validation data before it was kept.
    let confirmed: Vec<bool> = overall
        .windows(2)
        .enumerate()
        .map(|(i, w)| i >= n_cv || w[1] < w[0])
        .collect();
    let confirmed_only = if confirmed.iter().all(|c| *c) {
        None
    } else {
        Some(confirmed_only(stage, chosen, &confirmed)?)
    };
    Ok(HowFar {
        gap,
        overall,
        floor_ms,
        gap_closed,
        confirmed,
        confirmed_only,
    })
}

/// Noise-floor variance per joint (N² m², NaN for a joint that never moves fast enough) of the
/// final residual, on training (`train_res`) and validation data, each run on its own when the
/// training runs are given (`train_runs`; the validation data then are runs of their own), else
/// as one recording (the fit's own training samples bias it by p/N, negligible here).
fn noise_floor(stage: &Stage, ladder: &Ladder, train_res: &[f64]) -> Vec<f64> {
    let (train, validate, ms) = (stage.train, stage.validate, stage.opts.min_speed);
    let rate = validate.sample_rate().unwrap_or(1.0);
    let exclude = (NEIGHBOUR_EXCLUSION * rate).ceil() as usize;
    let both =
        Trajectory::concatenate(vec![train.clone(), validate.clone()]).expect("two trajectories");
    let joined: Vec<f64> = train_res.iter().chain(&ladder.final_res).copied().collect();
    let masked = mask_slow(&both, &joined, ms);
    // Neighbours only within one run: two runs of the same motion under different conditions
    // (unloaded, loaded) put the same instant of the other run next to each sample, and the
    // difference between the runs, the very gap in question, would count as noise.
    // Without `train_runs`, training and validation data are the two parts of one recording
    // (a hold-out split): one segment.
    let mut bounds = vec![0];
    let runs = stage.train_runs;
    if !runs.is_empty() && runs.iter().sum::<usize>() == train.len() {
        bounds.extend(runs.iter().scan(0, |acc, r| {
            *acc += r;
            Some(*acc)
        }));
    }
    bounds.push(both.len());
    pooled_gamma(&both, &bounds, &masked, exclude)
}

/// The Gamma test within each segment `bounds[i]..bounds[i + 1]`, pooled per joint by the
/// segments' lengths (segments too short for neighbours are left out).
fn pooled_gamma(tr: &Trajectory, bounds: &[usize], res: &[f64], exclude: usize) -> Vec<f64> {
    let n = tr.dof();
    let (mut sum, mut weight) = (vec![0.0; n], vec![0.0; n]);
    for w in bounds.windows(2).filter(|w| w[1] > w[0]) {
        let g = noise::gamma_test(tr, w[0]..w[1], res, exclude);
        for j in 0..n {
            if g[j].is_finite() {
                sum[j] += g[j] * (w[1] - w[0]) as f64;
                weight[j] += (w[1] - w[0]) as f64;
            }
        }
    }
    sum.iter()
        .zip(&weight)
        .map(|(s, w)| if *w > 0.0 { s / w } else { f64::NAN })
        .collect()
}

/// The gap of each joint: nominal RMS, RMS after each step, floor, fraction closed.
fn joint_gaps(stage: &Stage, ladder: &Ladder, floor_var: &[f64]) -> Vec<JointGap> {
    let per_step_rms = &ladder.per_step_rms;
    (0..stage.model.dof())
        .map(|j| {
            let nominal = per_step_rms[0][j];
            let last = per_step_rms[per_step_rms.len() - 1][j];
            let floor = floor_var[j];
            let den = nominal * nominal - floor;
            JointGap {
                joint: stage.model.bodies()[j].joint_name.clone(),
                description: ladder.description_rms[j],
                nominal,
                after: per_step_rms[1..].iter().map(|r| r[j]).collect(),
                noise_floor: floor.sqrt(), // NaN: the joint never moved fast enough
                gap_closed: if den > 0.0 {
                    ((nominal * nominal - last * last) / den).clamp(-1.0, 1.0)
                } else {
                    0.0
                },
            }
        })
        .collect()
}

/// Validation RMS per joint and overall of the refit with the confirmed effects only.
fn confirmed_only(
    stage: &Stage,
    chosen: &[usize],
    confirmed: &[bool],
) -> Result<(Vec<f64>, f64), DiagnoseError> {
    let keep: Vec<usize> = chosen
        .iter()
        .zip(confirmed)
        .filter(|(_, c)| **c)
        .map(|(v, _)| *v)
        .collect();
    let theta = stage
        .folds
        .fit(stage.model, &stage.all, &keep, &stage.ident_opts)?;
    let variants: Vec<_> = keep.iter().map(|&v| stage.folds.variants[v]).collect();
    let (rms, _) = residual_rms(
        &stage.ctx_val,
        stage.validate,
        &variants,
        &theta,
        stage.opts.min_speed,
    );
    let overall = mean_square(&rms).sqrt();
    Ok((rms, overall))
}
