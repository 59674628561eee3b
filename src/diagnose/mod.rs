//! Sim-to-real gap diagnosis: where the residual of a model lies, which unmodelled effect causes
//! it, and how far it shrinks once modelled.
//!
//! - **Where** ([`breakdown`], [`spectrum`]): the validation residual `τ − Y θ̂₀` of the nominal
//!   constrained model per joint, per motion regime (near-zero velocity and reversals, speed,
//!   acceleration and torque levels, configuration) and over frequency (spectrum, coherence with
//!   the motion).
//! - **Which** ([`library`], [`select`]): each effect of the library offered as extra regressor
//!   columns, scored by the cross-validated reduction of the error, forward selection with a
//!   stopping rule; magnitudes with block-jackknife standard errors; effects the data cannot tell
//!   apart reported together.
//! - **How far**: per-joint validation RMS before and after each added effect, the fraction of
//!   the gap to the noise floor ([`noise`]) closed, and whether something unexplained remains.
//!
//! [`diagnose`] runs all three on a training and a validation trajectory; [`blind`] is the
//! benchmark on simulated data with withheld effects.

pub mod anchor;
pub mod blind;
pub mod library;
pub mod noise;
pub mod report;
pub mod select;
pub mod spectrum;

use crate::ident::{self, ConstraintSet, IdentError, NormalEquations};
use crate::io::samples::Trajectory;
use crate::model::Model;
use library::{Context, Kind};
use nalgebra::DVector;
use serde::Serialize;

pub use crate::ident::analysis::residuals;

/// One regime of one joint.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Regime {
    /// Joint name.
    pub joint: String,
    /// Regime, e.g. `"|qd| low (<= 0.4 rad/s)"`.
    pub regime: String,
    /// Samples in the regime.
    pub samples: usize,
    /// RMS residual in the regime (N m).
    pub rms: f64,
    /// The regime's share of the joint's residual energy (0..1).
    pub share: f64,
}

/// Where a residual lies.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Breakdown {
    /// RMS residual per joint (N m).
    pub rms: Vec<f64>,
    /// RMS over all joints (N m).
    pub overall: f64,
    /// Regimes per joint.
    pub regimes: Vec<Regime>,
}

fn terciles(v: &[f64]) -> (f64, f64) {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let at = |f: f64| s[((s.len() - 1) as f64 * f).round() as usize];
    (at(1.0 / 3.0), at(2.0 / 3.0))
}

/// Breaks the residual `res` (sample-major, as from [`residuals`]) of samples `range` of `tr`
/// down per joint and regime. Regimes per joint: near-zero velocity (`|q̇|` below 5 % of its
/// peak), reversals (a velocity sign change within ±10 samples), `|q̇|`, `|q̈|` and `|τ|` in
/// terciles, and `q` in quartiles.
pub fn breakdown(tr: &Trajectory, range: std::ops::Range<usize>, res: &[f64]) -> Breakdown {
    let n = tr.dof();
    let m = range.len();
    assert_eq!(res.len(), m * n, "one residual per joint and sample");
    let col = |f: &dyn Fn(usize) -> f64| (0..m).map(f).collect::<Vec<f64>>();
    let mut regimes = vec![];
    let mut rms = vec![];
    for j in 0..n {
        let r = col(&|k| res[k * n + j]);
        let energy: f64 = r.iter().map(|x| x * x).sum();
        rms.push((energy / m.max(1) as f64).sqrt());
        let qd = col(&|k| tr.qd_at(range.start + k)[j]);
        let qdd = col(&|k| tr.qdd_at(range.start + k).map_or(0.0, |a| a[j]));
        let tau = col(&|k| tr.tau_at(range.start + k)[j]);
        let q = col(&|k| tr.q_at(range.start + k)[j]);
        let mut add = |name: String, member: &dyn Fn(usize) -> bool| {
            let idx: Vec<usize> = (0..m).filter(|&k| member(k)).collect();
            let e: f64 = idx.iter().map(|&k| r[k] * r[k]).sum();
            regimes.push(Regime {
                joint: tr.joint_names[j].clone(),
                regime: name,
                samples: idx.len(),
                rms: if idx.is_empty() {
                    0.0
                } else {
                    (e / idx.len() as f64).sqrt()
                },
                share: if energy > 0.0 { e / energy } else { 0.0 },
            });
        };
        let peak = qd.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let slow = 0.05 * peak;
        add(
            format!("near-zero velocity (|qd| < {slow:.3} rad/s)"),
            &|k| qd[k].abs() < slow,
        );
        let flips: Vec<bool> = (0..m).map(|k| k > 0 && qd[k] * qd[k - 1] < 0.0).collect();
        add("velocity reversal (±10 samples)".into(), &|k| {
            flips[k.saturating_sub(10)..(k + 11).min(m)]
                .iter()
                .any(|f| *f)
        });
        for (name, v, unit) in [
            ("|qd|", &qd, "rad/s"),
            ("|qdd|", &qdd, "rad/s^2"),
            ("|tau|", &tau, "N m"),
        ] {
            let a: Vec<f64> = v.iter().map(|x| x.abs()).collect();
            let (t1, t2) = terciles(&a);
            add(format!("{name} low (<= {t1:.3} {unit})"), &|k| a[k] <= t1);
            add(format!("{name} mid"), &|k| a[k] > t1 && a[k] <= t2);
            add(format!("{name} high (> {t2:.3} {unit})"), &|k| a[k] > t2);
        }
        let mut s = q.clone();
        s.sort_by(f64::total_cmp);
        let qs: Vec<f64> = (1..4).map(|i| s[(m - 1) * i / 4]).collect();
        for b in 0..4 {
            let lo = if b == 0 { f64::NEG_INFINITY } else { qs[b - 1] };
            let hi = if b == 3 { f64::INFINITY } else { qs[b] };
            add(
                format!(
                    "q quartile {} ({:.3}..{:.3} rad)",
                    b + 1,
                    lo.max(s[0]),
                    hi.min(s[m - 1])
                ),
                &|k| q[k] > lo && q[k] <= hi,
            );
        }
    }
    let overall = (res.iter().map(|x| x * x).sum::<f64>() / res.len().max(1) as f64).sqrt();
    Breakdown {
        rms,
        overall,
        regimes,
    }
}

/// Diagnosis options.
#[derive(Clone, Debug)]
pub struct Options {
    /// Constraint set of the nominal model and of every fit with effects.
    pub constraints: ConstraintSet,
    /// The forward selection's settings.
    pub selection: select::Settings,
    /// The kinds offered.
    pub kinds: Vec<Kind>,
    /// Joint-samples slower than this (rad/s) are left out of every fit and error (the
    /// model's `sign(q̇)` Coulomb friction does not describe friction near zero speed).
    pub min_speed: f64,
    /// Lengths of the runs joined in the training data (empty: one run). With two or more,
    /// the cross-validation leaves one run out at a time.
    pub train_runs: Vec<usize>,
    /// Low-pass cutoff (Hz) of the data's processing, for the compliance columns.
    pub processing_cutoff: f64,
    /// The residual counts as unexplained when its validation mean square exceeds the noise
    /// floor's by this factor.
    pub unexplained_ratio: f64,
    /// Relative uncertainty `ε` of the description's inertial parameters: when given, effects
    /// that identification absorbs are tested against the description ([`anchor`]).
    pub description_uncertainty: Option<f64>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            constraints: ConstraintSet::Consistent,
            selection: select::Settings::default(),
            kinds: Kind::ALL.to_vec(),
            min_speed: 0.05,
            processing_cutoff: 20.0,
            train_runs: vec![],
            unexplained_ratio: 1.45,
            description_uncertainty: None,
        }
    }
}

/// A diagnosis failed.
#[derive(Debug, thiserror::Error)]
pub enum DiagnoseError {
    /// Identification failed.
    #[error("identification failed: {0}")]
    Ident(#[from] IdentError),
    /// Data unusable.
    #[error("{0}")]
    Data(String),
}

/// One estimated magnitude.
#[derive(Clone, Debug, Serialize)]
pub struct Magnitude {
    /// Joint name, or `"robot"` for one value for the whole robot.
    pub joint: String,
    /// Value in `unit`.
    pub value: f64,
    /// Standard error: block jackknife (cross-validation evidence) or posterior (description
    /// evidence).
    pub se: f64,
    /// Unit.
    pub unit: String,
    /// Fraction of the effect's column not explained by the rigid-body regressor (1: fully
    /// identifiable; near 0: absorbed by the inertial parameters, the value is meaningless).
    /// Absorbed effects found against the description are identified through it: 1, their
    /// precision is in `se`.
    pub identifiable: f64,
}

/// What an effect was found by.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Evidence {
    /// It lowers the cross-validated torque error ([`select`]).
    CrossValidation,
    /// Identification absorbs it, but the identified parameters depart from the description
    /// as it dictates ([`anchor`]).
    Description,
}

/// One selected effect with its magnitudes.
#[derive(Clone, Debug, Serialize)]
pub struct EffectEstimate {
    /// The kind.
    pub kind: Kind,
    /// What it was found by.
    pub evidence: Evidence,
    /// Its grid value (Stribeck velocity in rad/s, cogging harmonic), 0 otherwise.
    pub param: f64,
    /// What the magnitude is.
    pub magnitude_name: String,
    /// Magnitudes per joint (or one for the robot).
    pub magnitudes: Vec<Magnitude>,
    /// Kinds the data cannot tell apart from this one.
    pub ambiguous_with: Vec<Kind>,
    /// What data would separate them.
    pub separate_by: Option<String>,
}

impl EffectEstimate {
    /// The kept kind, then those the data cannot tell apart from it.
    pub fn group(&self) -> impl Iterator<Item = Kind> + '_ {
        std::iter::once(self.kind).chain(self.ambiguous_with.iter().copied())
    }
}

/// Validation error of one joint along the selection.
#[derive(Clone, Debug, Serialize)]
pub struct JointGap {
    /// Joint name.
    pub joint: String,
    /// Nominal model's validation RMS (N m).
    pub nominal: f64,
    /// RMS after each selected effect, cumulatively (N m).
    pub after: Vec<f64>,
    /// Estimated noise floor (N m RMS).
    pub noise_floor: f64,
    /// Fraction of the gap `nominal² − floor²` closed by all selected effects.
    pub gap_closed: f64,
}

/// The verdict.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// No effect selected and the residual is at the noise floor.
    NoEffect,
    /// Effects selected and what remains is at the noise floor.
    Explained,
    /// Effects selected but a residual above the noise floor remains.
    PartiallyExplained,
    /// Nothing in the library explains a residual above the noise floor.
    Unexplained,
    /// The residual is at the noise floor, but identification absorbs an effect that the
    /// description reveals.
    Absorbed,
}

/// A whole diagnosis.
#[derive(Clone, Debug, Serialize)]
pub struct Diagnosis {
    /// Robot name.
    pub robot: String,
    /// Joint names.
    pub joints: Vec<String>,
    /// Training and validation samples.
    pub samples: [usize; 2],
    /// Constraint set.
    pub constraints: ConstraintSet,
    /// Whether the nominal model satisfies its constraints.
    pub nominal_constraints_hold: bool,
    /// Where: the nominal validation residual by regime.
    pub breakdown: Breakdown,
    /// Where in frequency: the nominal validation residual per joint.
    pub spectra: Vec<spectrum::Spectrum>,
    /// Spectra of the final residual (after the selected effects).
    pub spectra_after: Vec<spectrum::Spectrum>,
    /// Which: the selection.
    pub selection: select::Selection,
    /// Which, for absorbed effects: the description test (with a stated uncertainty).
    pub description_test: Option<anchor::Report>,
    /// The selected effects and their magnitudes.
    pub effects: Vec<EffectEstimate>,
    /// How far: per joint.
    pub gap: Vec<JointGap>,
    /// Validation RMS over all joints: nominal, then after each effect (N m).
    pub overall: Vec<f64>,
    /// Per selected effect: whether adding it lowered the validation RMS (held-out data, not
    /// used by the selection); an unconfirmed effect fits the training runs only.
    pub confirmed: Vec<bool>,
    /// Noise floor over all joints (N m RMS).
    pub noise_floor: f64,
    /// Fraction of the overall gap closed.
    pub gap_closed: f64,
    /// Validation RMS per joint and overall (N m) with the confirmed effects only (refitted),
    /// when some selected effect is not confirmed.
    pub confirmed_only: Option<(Vec<f64>, f64)>,
    /// The verdict.
    pub verdict: Verdict,
    /// The verdict in words.
    pub summary: String,
}

/// What data separates two kinds the data could not tell apart.
pub fn separate_by(a: Kind, b: Kind) -> String {
    use Kind::*;
    let pair = if a <= b { (a, b) } else { (b, a) };
    match pair {
        (TorqueOffset, AsymmetricCoulomb) => "rests under load (q̇ = 0 with τ ≠ 0): an offset persists at rest, direction-dependent friction vanishes; without rests δ·max(0, sign q̇) = δ/2 + (δ/2) sign q̇ is an offset plus Coulomb friction".into(),
        (TorqueOffset, Spring) => "a wider range of joint angles (the spring's torque varies with q, an offset does not)".into(),
        (TorqueGain, LoadDependentFriction) => "braking motion (τ and q̇ of opposite sign) as often as driving".into(),
        (Stribeck, AsymmetricCoulomb) | (TorqueOffset, Stribeck) => "slow motion in both directions (q̇ within the Stribeck velocity)".into(),
        (RotorInertia, Compliance) | (TimeDelay, Compliance) | (TimeDelay, RotorInertia) => "faster excitation (the terms scale with q̈, τ̇ and τ̈ differently with frequency)".into(),
        _ => "an excitation on which their regressor columns differ more (other joint ranges, speeds and torque levels)".into(),
    }
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let m = s.len();
    if m == 0 {
        0.0
    } else if m % 2 == 1 {
        s[m / 2]
    } else {
        0.5 * (s[m / 2 - 1] + s[m / 2])
    }
}

/// The physical magnitudes of an effect from its coefficients `c` (in column order).
pub fn magnitudes_of(kind: Kind, c: &[f64], n: usize, gravity: f64) -> Vec<f64> {
    match kind {
        Kind::TorqueGain => {
            // The column is the nominal prediction, which already carries the gain:
            // τ = Y θ + β τ̂ with τ̂ ≈ τ gives 1 + g = 1/(1 − β).
            let g: Vec<f64> = c.iter().map(|b| b / (1.0 - b)).collect();
            let m = median(&g);
            g.iter().map(|x| x - m).collect()
        }
        Kind::TimeDelay => vec![c[0]],
        Kind::Spring => c[..n].to_vec(),
        Kind::Cogging => (0..n).map(|j| c[j].hypot(c[n + j])).collect(),
        Kind::Tilt => vec![(c[0].hypot(c[1]) / gravity).atan()],
        Kind::Payload => vec![c[0]],
        _ => c.to_vec(),
    }
}

/// First-order standard error of magnitude `index` from its coefficients' errors.
fn magnitude_se(kind: Kind, c: &[f64], se: &[f64], n: usize, gravity: f64, index: usize) -> f64 {
    let base = magnitudes_of(kind, c, n, gravity)[index];
    let mut v = 0.0;
    for i in 0..c.len() {
        let h = 1e-6 * c[i].abs().max(1e-6);
        let mut cp = c.to_vec();
        cp[i] += h;
        let d = (magnitudes_of(kind, &cp, n, gravity)[index] - base) / h;
        v += (d * se[i]).powi(2);
    }
    v.sqrt()
}

/// The residual `res` (sample-major over `tr`) with the joint-samples slower than `min_speed`
/// set to NaN (left out of every fit and error).
fn mask_slow(tr: &Trajectory, res: &[f64], min_speed: f64) -> Vec<f64> {
    let n = tr.dof();
    res.iter()
        .enumerate()
        .map(|(i, r)| {
            if library::slow(tr.qd_at(i / n)[i % n], min_speed) {
                f64::NAN
            } else {
                *r
            }
        })
        .collect()
}

/// The mean square of the finite entries of `v` (0 without any).
fn finite_mean_square(v: &[f64]) -> f64 {
    let (s, c) = v
        .iter()
        .filter(|x| x.is_finite())
        .fold((0.0, 0usize), |(s, c), x| (s + x * x, c + 1));
    s / c.max(1) as f64
}

/// Sample rate of `tr` (Hz) from its first and last time stamps.
fn sample_rate(tr: &Trajectory) -> f64 {
    let m = tr.len();
    if m > 1 {
        (m - 1) as f64 / (tr.t[m - 1] - tr.t[0])
    } else {
        1.0
    }
}

/// The residual `τ − Z θ` over `tr` for the model plus `variants` (all rows), and its per-joint
/// RMS over the joint-samples at or above `min_speed`.
pub(crate) fn residual_rms(
    ctx: &Context,
    tr: &Trajectory,
    variants: &[library::Variant],
    theta: &DVector<f64>,
    min_speed: f64,
) -> (Vec<f64>, Vec<f64>) {
    let n = tr.dof();
    let mut res = Vec::with_capacity(tr.len() * n);
    ctx.for_each_row(tr, 0..tr.len(), variants, 0.0, &mut |_, z, tau| {
        let pred = z * theta;
        res.extend((0..n).map(|j| tau[j] - pred[j]));
    });
    let rms = (0..n)
        .map(|j| {
            let (mut s, mut c) = (0.0, 0usize);
            for k in 0..tr.len() {
                if !library::slow(tr.qd_at(k)[j], min_speed) {
                    s += res[k * n + j].powi(2);
                    c += 1;
                }
            }
            (s / c.max(1) as f64).sqrt()
        })
        .collect();
    (rms, res)
}

fn mean_square(rms: &[f64]) -> f64 {
    rms.iter().map(|r| r * r).sum::<f64>() / rms.len().max(1) as f64
}

/// Spectra of a residual per joint with the coherence signals of `tr`.
fn spectra(model: &Model, tr: &Trajectory, res: &[f64]) -> Vec<spectrum::Spectrum> {
    let n = tr.dof();
    let m = tr.len();
    let fs = if m > 1 {
        (m - 1) as f64 / (tr.t[m - 1] - tr.t[0])
    } else {
        1.0
    };
    (0..n)
        .map(|j| {
            let col = |f: &dyn Fn(usize) -> f64| (0..m).map(f).collect::<Vec<f64>>();
            let gear = model.bodies[j].rotor.as_ref().map_or(1.0, |r| r.gear_ratio);
            let signals = vec![
                ("q".to_string(), col(&|k| tr.q_at(k)[j])),
                ("qd".to_string(), col(&|k| tr.qd_at(k)[j])),
                (
                    "qdd".to_string(),
                    col(&|k| tr.qdd_at(k).map_or(0.0, |a| a[j])),
                ),
                (
                    "sin(N q)".to_string(),
                    col(&|k| (gear * tr.q_at(k)[j]).sin()),
                ),
            ];
            spectrum::spectrum(&tr.joint_names[j], &col(&|k| res[k * n + j]), &signals, fs)
        })
        .collect()
}

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

/// Diagnoses `model` on `train` (identification and cross-validated selection) and
/// `validate` (before/after errors, where, noise floor). Both must carry q̈.
pub fn diagnose(
    model: &Model,
    train: &Trajectory,
    validate: &Trajectory,
    opts: &Options,
) -> Result<Diagnosis, DiagnoseError> {
    let n = model.dof();
    for (what, tr) in [("training", train), ("validation", validate)] {
        if tr.dof() != n {
            return Err(DiagnoseError::Data(format!(
                "{what} data have {} joints, the robot {n}",
                tr.dof()
            )));
        }
        if tr.qdd.is_none() {
            return Err(DiagnoseError::Data(format!(
                "{what} data carry no accelerations (ddq columns)"
            )));
        }
        if tr.len() < 64 {
            return Err(DiagnoseError::Data(format!(
                "{what} data have {} samples; the diagnosis needs at least 64",
                tr.len()
            )));
        }
    }
    let iopts = ident::Options::new(opts.constraints);
    let ms = opts.min_speed;
    let cut = opts.processing_cutoff;
    let nominal = fit_nominal(model, train, opts)?;
    let theta0 = nominal.theta.clone();
    let ctx_train = Context::new(model, &theta0, train, cut);
    let ctx_val = Context::new(model, &theta0, validate, cut);
    let variants = library::variants(&opts.kinds);
    let k = opts.selection.folds.max(2);
    let folds = select::Folds::build(
        &ctx_train,
        train,
        0..train.len(),
        variants,
        k,
        &opts.train_runs,
        ms,
    );
    let selection = select::forward_select(&folds, model, &iopts, &opts.selection)?;
    let all = folds.sum_except(usize::MAX);
    let g = model.gravity.norm().max(1e-12);
    // Absorbed effects, against the description when its uncertainty is stated and the
    // cross-validation claims nothing: a visible effect's columns are linearized (a delay to
    // first order, a rotor without its gyroscopic terms), and what they miss biases θ in ways
    // the prior test would misread as an absorbed effect.
    let description_test = match opts.description_uncertainty {
        Some(eps) if selection.chosen.is_empty() => {
            let (_, res) = residual_rms(&ctx_train, train, &[], &theta0, ms);
            let masked = mask_slow(train, &res, ms);
            let s2 = finite_mean_square(&masked);
            let tau_c = anchor::correlation_time(&masked, n, sample_rate(train));
            let anchor = anchor::Anchor {
                ne: &all,
                weight: 1.0 / (s2 * tau_c).max(1e-300),
                mean: model.parameters(),
                precision: anchor::prior_precision(model, eps),
            };
            // A kind that is one of the model's parameters (rotor inertia, when the model
            // has rotors) would test the description, not an unmodelled effect.
            let exclude: Vec<Kind> = if model.rotor_count() > 0 {
                vec![Kind::RotorInertia]
            } else {
                vec![]
            };
            let (mut steps, mut stop) = anchor::select(
                &anchor,
                &folds,
                &[],
                &exclude,
                opts.selection.max_effects,
                opts.selection.tie,
            );
            // The test is in-sample: each step must pass again on the held-out data alone.
            if !steps.is_empty() {
                let vs: Vec<_> = steps.iter().map(|st| folds.variants[st.variant]).collect();
                let vfolds =
                    select::Folds::build(&ctx_val, validate, 0..validate.len(), vs, 2, &[], ms);
                let vall = vfolds.sum_except(usize::MAX);
                let held = anchor::Anchor {
                    ne: &vall,
                    ..anchor
                };
                let passed = (0..steps.len())
                    .take_while(|&k| {
                        let base = vfolds.columns(&(0..k).collect::<Vec<_>>());
                        let d = steps[k].kind.columns(n);
                        let cand: Vec<usize> = (vfolds.offsets[k]..vfolds.offsets[k] + d).collect();
                        held.fit(&base, &cand).statistic
                            >= anchor::chi2_upper_quantile(d, anchor::CONFIRM_ALPHA)
                    })
                    .count();
                if passed < steps.len() {
                    stop = format!(
                        "{} passed on the training data but not again on the held-out data (dropped)",
                        steps[passed].kind.name()
                    );
                    steps.truncate(passed);
                }
            }
            Some(anchor::Report {
                uncertainty: eps,
                residual_ms: s2,
                correlation_samples: tau_c,
                steps,
                stop,
            })
        }
        _ => None,
    };
    let anchored: &[anchor::Step] = description_test.as_ref().map_or(&[], |r| &r.steps);
    let chosen: Vec<usize> = selection
        .chosen
        .iter()
        .copied()
        .chain(anchored.iter().map(|s| s.variant))
        .collect();
    let n_cv = selection.chosen.len();
    // How far: refit on all training data with the first i effects.
    let mut per_step_rms = vec![];
    let (mut nominal_res, mut final_res) = (vec![], vec![]);
    let mut final_theta = theta0.clone();
    for i in 0..=chosen.len() {
        let first = &chosen[..i];
        let theta = if i == 0 {
            theta0.clone()
        } else {
            folds.fit(model, &all, first, &iopts)?
        };
        let vs: Vec<_> = first.iter().map(|&v| folds.variants[v]).collect();
        let (rms, res) = residual_rms(&ctx_val, validate, &vs, &theta, ms);
        per_step_rms.push(rms);
        if i == 0 {
            nominal_res = res.clone();
        }
        if i == chosen.len() {
            final_res = res;
            final_theta = theta;
        }
    }
    // Identifiable fraction of each effect column against the model's columns.
    let p0 = model.layout().len;
    let hyy = all.yty.view((0, 0), (p0, p0)).into_owned()
        + nalgebra::DMatrix::identity(p0, p0) * (1e-12 * all.yty.diagonal().max());
    let identifiable = |col: usize| {
        let zc = all.yty.column(col).rows(0, p0).into_owned();
        let x = ident::analysis::least_squares(&hyy, &zc);
        let zz = all.yty[(col, col)];
        if zz > 0.0 {
            ((zz - zc.dot(&x)) / zz).clamp(0.0, 1.0)
        } else {
            0.0
        }
    };
    let joint_of = |single: bool, i: usize| {
        if single {
            "robot".to_string()
        } else {
            model.bodies[i].joint_name.clone()
        }
    };
    // Magnitudes with block-jackknife errors.
    let mut effects = vec![];
    let mut off = p0;
    let fold_thetas = selection
        .final_cv
        .as_ref()
        .map(|c| c.thetas.clone())
        .unwrap_or_default();
    for (si, &vi) in selection.chosen.iter().enumerate() {
        let v = folds.variants[vi];
        let nc = v.kind.columns(n);
        let mags = magnitudes_of(v.kind, &final_theta.as_slice()[off..off + nc], n, g);
        let jk: Vec<Vec<f64>> = fold_thetas
            .iter()
            .map(|t| magnitudes_of(v.kind, &t.as_slice()[off..off + nc], n, g))
            .collect();
        let kf = jk.len() as f64;
        let (name, unit) = v.kind.magnitude();
        let single = mags.len() == 1;
        let magnitudes = mags
            .iter()
            .enumerate()
            .map(|(i, &value)| {
                let mean = jk.iter().map(|m| m[i]).sum::<f64>() / kf.max(1.0);
                let se = ((kf - 1.0) / kf.max(1.0)
                    * jk.iter().map(|m| (m[i] - mean).powi(2)).sum::<f64>())
                .sqrt();
                let cols: Vec<usize> = if single {
                    (0..nc).map(|c| folds.offsets[vi] + c).collect()
                } else {
                    let mut c = vec![folds.offsets[vi] + i];
                    // Cogging's magnitude needs both of its columns; a spring's stiffness only
                    // its q column (the constant is its rest position).
                    if v.kind == Kind::Cogging {
                        c.push(folds.offsets[vi] + n + i);
                    }
                    c
                };
                Magnitude {
                    joint: joint_of(single, i),
                    value,
                    se,
                    unit: unit.into(),
                    identifiable: cols.iter().map(|&c| identifiable(c)).fold(1.0, f64::min),
                }
            })
            .collect();
        let step = &selection.steps[si];
        effects.push(EffectEstimate {
            kind: v.kind,
            evidence: Evidence::CrossValidation,
            param: v.param,
            magnitude_name: name.into(),
            magnitudes,
            separate_by: step.ambiguous_with.first().map(|&b| separate_by(v.kind, b)),
            ambiguous_with: step.ambiguous_with.clone(),
        });
        off += nc;
    }
    // Absorbed effects: posterior magnitudes; errors propagated to first order.
    for st in anchored {
        let v = folds.variants[st.variant];
        let (name, unit) = v.kind.magnitude();
        let mags = magnitudes_of(v.kind, &st.beta, n, g);
        let single = mags.len() == 1;
        let magnitudes = mags
            .iter()
            .enumerate()
            .map(|(i, &value)| {
                let se = magnitude_se(v.kind, &st.beta, &st.se, n, g, i);
                Magnitude {
                    joint: joint_of(single, i),
                    value,
                    se,
                    unit: unit.into(),
                    // Identified through the description; its precision is in `se`.
                    identifiable: 1.0,
                }
            })
            .collect();
        effects.push(EffectEstimate {
            kind: v.kind,
            evidence: Evidence::Description,
            param: v.param,
            magnitude_name: name.into(),
            magnitudes,
            separate_by: st.ambiguous_with.first().map(|&b| separate_by(v.kind, b)),
            ambiguous_with: st.ambiguous_with.clone(),
        });
    }
    // Noise floor of the final residual (neighbours at least 0.2 s apart).
    let rate = (validate.len() - 1) as f64 / (validate.t[validate.len() - 1] - validate.t[0]);
    let exclude = (0.2 * rate).ceil() as usize;
    // On training and validation data together: more repetitions of each motion, so closer
    // neighbours (the fit's own training samples bias it by p/N, negligible here).
    let final_vs: Vec<_> = chosen.iter().map(|&v| folds.variants[v]).collect();
    let (_, train_res) = residual_rms(&ctx_train, train, &final_vs, &final_theta, ms);
    let both = concatenate(vec![train.clone(), validate.clone()]);
    let joined: Vec<f64> = train_res.iter().chain(&final_res).copied().collect();
    let masked_res = mask_slow(&both, &joined, ms);
    let floor_var = noise::gamma_test(&both, 0..both.len(), &masked_res, exclude);
    let gap: Vec<JointGap> = (0..n)
        .map(|j| {
            let nom = per_step_rms[0][j];
            let last = per_step_rms[per_step_rms.len() - 1][j];
            let f2 = floor_var[j];
            let den = nom * nom - f2;
            JointGap {
                joint: model.bodies[j].joint_name.clone(),
                nominal: nom,
                after: per_step_rms[1..].iter().map(|r| r[j]).collect(),
                noise_floor: f2.sqrt(), // NaN: the joint never moved fast enough
                gap_closed: if den > 0.0 {
                    ((nom * nom - last * last) / den).clamp(-1.0, 1.0)
                } else {
                    0.0
                },
            }
        })
        .collect();
    let overall: Vec<f64> = per_step_rms.iter().map(|r| mean_square(r).sqrt()).collect();
    // A joint that never moves faster than the threshold has no floor (NaN): left out.
    let finite: Vec<f64> = floor_var
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .collect();
    if finite.is_empty() {
        return Err(DiagnoseError::Data(format!(
            "no joint moves faster than {ms} rad/s often enough to estimate the noise floor"
        )));
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
        let keep: Vec<usize> = chosen
            .iter()
            .zip(&confirmed)
            .filter(|(_, c)| **c)
            .map(|(v, _)| *v)
            .collect();
        let theta = folds.fit(model, &all, &keep, &iopts)?;
        let vs: Vec<_> = keep.iter().map(|&v| folds.variants[v]).collect();
        let (rms, _) = residual_rms(&ctx_val, validate, &vs, &theta, ms);
        let o = mean_square(&rms).sqrt();
        Some((rms, o))
    };
    let above = last > opts.unexplained_ratio * floor_ms;
    let verdict = match (selection.steps.is_empty(), above) {
        (true, false) if anchored.is_empty() => Verdict::NoEffect,
        (true, false) => Verdict::Absorbed,
        (true, true) => Verdict::Unexplained,
        (false, false) => Verdict::Explained,
        (false, true) => Verdict::PartiallyExplained,
    };
    let name_of = |e: &EffectEstimate| {
        if e.ambiguous_with.is_empty() {
            e.kind.name().to_string()
        } else {
            let g: Vec<Kind> = e.group().collect();
            format!("one of {{{}}} (ambiguous)", library::names(&g, false))
        }
    };
    let names: Vec<String> = effects[..n_cv].iter().map(name_of).collect();
    let unconfirmed: Vec<&str> = effects
        .iter()
        .zip(&confirmed)
        .filter(|(_, c)| !**c)
        .map(|(e, _)| e.kind.name())
        .collect();
    let mut summary = match verdict {
        Verdict::NoEffect => format!(
            "no effect found: the validation RMS {:.3} N m is at the noise floor {:.3} N m",
            overall[0],
            floor_ms.sqrt()
        ),
        Verdict::Absorbed => format!(
            "no gap: the validation RMS {:.3} N m is at the noise floor {:.3} N m",
            overall[0],
            floor_ms.sqrt()
        ),
        Verdict::Explained => format!(
            "{} explain(s) the gap: validation RMS {:.3} -> {:.3} N m (noise floor {:.3}), {:.0} % of the gap closed",
            names.join(" + "),
            overall[0],
            last.sqrt(),
            floor_ms.sqrt(),
            100.0 * gap_closed
        ),
        Verdict::PartiallyExplained => format!(
            "{} explain(s) part of the gap: validation RMS {:.3} -> {:.3} N m, {:.0} % closed; {:.3} N m RMS above the noise floor {:.3} N m remains unexplained",
            names.join(" + "),
            overall[0],
            last.sqrt(),
            100.0 * gap_closed,
            (last - floor_ms).max(0.0).sqrt(),
            floor_ms.sqrt()
        ),
        Verdict::Unexplained => format!(
            "unexplained: the validation RMS {:.3} N m lies above the noise floor {:.3} N m and no effect in the library lowers the cross-validated error enough",
            overall[0],
            floor_ms.sqrt()
        ),
    };
    if let Some(rep) = description_test.as_ref().filter(|r| !r.steps.is_empty()) {
        let absorbed: Vec<String> = effects[n_cv..].iter().map(name_of).collect();
        summary += &format!(
            "; absorbed by identification but revealed by the description (stated uncertainty {:.0} %): {}",
            100.0 * rep.uncertainty,
            absorbed.join(" + ")
        );
    }
    if let Some((_, o)) = &confirmed_only {
        summary += &format!(
            "; NOT confirmed on the validation data (its error rose when added): {}; with the confirmed effects only the validation RMS is {o:.3} N m",
            unconfirmed.join(", ")
        );
    }
    Ok(Diagnosis {
        confirmed,
        confirmed_only,
        robot: model.name.clone(),
        joints: model.bodies.iter().map(|b| b.joint_name.clone()).collect(),
        samples: [train.len(), validate.len()],
        constraints: opts.constraints,
        nominal_constraints_hold: nominal.constraints_hold,
        breakdown: breakdown(validate, 0..validate.len(), &nominal_res),
        spectra: spectra(model, validate, &nominal_res),
        spectra_after: spectra(model, validate, &final_res),
        selection,
        description_test,
        effects,
        gap,
        overall,
        noise_floor: floor_ms.sqrt(),
        gap_closed,
        verdict,
        summary,
    })
}

/// Splits `tr` into its first `1 − holdout` (training) and its last `holdout` (validation).
pub fn holdout_split(tr: &Trajectory, holdout: f64) -> (Trajectory, Trajectory) {
    let cut = ((1.0 - holdout) * tr.len() as f64).round() as usize;
    (tr.slice(0..cut), tr.slice(cut..tr.len()))
}

/// Joins trajectories end to end (times shifted so they keep increasing by the first one's
/// median step).
pub fn concatenate(parts: Vec<Trajectory>) -> Trajectory {
    let mut it = parts.into_iter();
    let mut out = it.next().expect("at least one trajectory");
    for p in it {
        let m = out.len();
        let dt = if m > 1 {
            (out.t[m - 1] - out.t[0]) / (m - 1) as f64
        } else {
            1e-3
        };
        let shift = out.t[m - 1] + dt - p.t[0];
        for k in 0..p.len() {
            out.push(
                p.t[k] + shift,
                p.q_at(k),
                p.qd_at(k),
                p.qdd_at(k),
                p.tau_at(k),
            );
        }
    }
    out
}

/// The diagnosis from data files as a user gives them (CSV or MCAP, read by
/// [`crate::io::load_trajectory`]): training files and validation files. Without validation
/// files the last `holdout` fraction of the training data is held out.
pub fn diagnose_files(
    model: &Model,
    data: &[std::path::PathBuf],
    validate: &[std::path::PathBuf],
    holdout: f64,
    opts: &Options,
) -> anyhow::Result<Diagnosis> {
    if data.is_empty() {
        anyhow::bail!("no data files given");
    }
    let load = |files: &[std::path::PathBuf]| -> anyhow::Result<(Trajectory, Vec<usize>)> {
        let parts = files
            .iter()
            .map(|f| crate::io::load_trajectory(f, model))
            .collect::<anyhow::Result<Vec<_>>>()?;
        let lens = parts.iter().map(|p| p.len()).collect();
        Ok((concatenate(parts), lens))
    };
    let (all, lens) = load(data)?;
    let mut opts = opts.clone();
    let (train, val) = if validate.is_empty() {
        if !(holdout > 0.0 && holdout < 1.0) {
            anyhow::bail!("the held-out fraction {holdout} must lie strictly between 0 and 1");
        }
        holdout_split(&all, holdout)
    } else {
        // Several training runs: leave one run out in the selection.
        opts.train_runs = lens;
        (all, load(validate)?.0)
    };
    Ok(diagnose(model, &train, &val, &opts)?)
}
