//! What every step of the diagnosis works on ([`Stage`]): the data, the nominal fit and the
//! effect columns over both data sets; the nominal fit itself ([`fit_nominal`]) and the checks
//! of the data it starts from.

use super::options::{DiagnoseError, Options};
use super::select;
use nalgebra::DVector;
use physid_core::model::Model;
use physid_core::trajectory::Trajectory;
use physid_effect::context::Context;
use physid_effect::library;
use physid_ident::{self as ident, NormalEquations};

/// The fewest samples a training or validation set may have.
pub const MIN_SAMPLES: usize = 64;

/// The nominal model: `model`'s parameters identified on `train` under `opts.constraints`,
/// from the rows of joints at or above `opts.min_speed`, with the description as prior.
pub fn fit_nominal(
    model: &Model,
    train: &Trajectory,
    opts: &Options,
) -> Result<ident::Identified, DiagnoseError> {
    let prior = model.parameters();
    let ctx = Context::new(model, &prior, train, opts.processing_cutoff);
    let (ne, _) = super::rows::normal_equations(&ctx, train, 0..train.len(), &[], opts.min_speed);
    let iopts = ident::Options::new(opts.constraints);
    Ok(ident::identify(model, &ne, &prior, &iopts)?)
}

/// Both data sets fit the robot and the diagnosis: same joints, accelerations present, at least
/// [`MIN_SAMPLES`] samples, time stamps that advance.
pub(super) fn check_data(
    model: &Model,
    train: &Trajectory,
    validate: &Trajectory,
) -> Result<(), DiagnoseError> {
    let n = model.dof();
    for (which, tr) in [("training", train), ("validation", validate)] {
        if tr.dof() != n {
            return Err(DiagnoseError::JointCount {
                which,
                data: tr.dof(),
                robot: n,
            });
        }
        if tr.qdd.is_none() {
            return Err(DiagnoseError::NoAcceleration { which });
        }
        if tr.len() < MIN_SAMPLES {
            return Err(DiagnoseError::TooShort {
                which,
                samples: tr.len(),
                min: MIN_SAMPLES,
            });
        }
        if physid_effect::context::sample_period(tr).is_none() {
            return Err(DiagnoseError::NoSamplePeriod {
                which,
                span: tr.t[tr.len() - 1] - tr.t[0],
                samples: tr.len(),
            });
        }
    }
    Ok(())
}

/// What every step after the nominal fit works on: the data, the nominal parameters `θ₀`, the
/// effect columns' context on both data sets, and the training data's per-fold and summed
/// normal equations of `[Y | effect columns]`.
pub(crate) struct Stage<'a> {
    pub model: &'a Model,
    pub train: &'a Trajectory,
    /// Lengths of the recordings joined in `train` (empty: one recording). With two or more,
    /// the cross-validation leaves one recording out at a time.
    pub train_runs: &'a [usize],
    pub validate: &'a Trajectory,
    pub opts: &'a Options,
    /// Identification options of every fit (the nominal model's constraint set).
    pub ident_opts: ident::Options,
    /// The nominal model's parameters.
    pub theta0: DVector<f64>,
    pub ctx_train: Context<'a>,
    pub ctx_val: Context<'a>,
    pub folds: select::Folds,
    /// The folds summed: all training data.
    pub all: NormalEquations,
}

impl<'a> Stage<'a> {
    pub(super) fn new(
        model: &'a Model,
        (train, train_runs): (&'a Trajectory, &'a [usize]),
        validate: &'a Trajectory,
        opts: &'a Options,
        theta0: DVector<f64>,
    ) -> Self {
        let cutoff = opts.processing_cutoff;
        // The validation context is built beside the training columns.
        let ((ctx_train, folds), ctx_val) = rayon::join(
            || {
                let ctx_train = Context::new(model, &theta0, train, cutoff);
                let folds = select::Folds::build(
                    &ctx_train,
                    train,
                    0..train.len(),
                    offered_variants(opts, model),
                    opts.selection.folds.max(2),
                    train_runs,
                    opts.min_speed,
                );
                (ctx_train, folds)
            },
            || Context::new(model, &theta0, validate, cutoff),
        );
        let all = folds.sum_except(usize::MAX);
        Self {
            model,
            train,
            train_runs,
            validate,
            opts,
            ident_opts: ident::Options::new(opts.constraints),
            theta0,
            ctx_train,
            ctx_val,
            folds,
            all,
        }
    }
}

/// The variants of `opts.kinds` offered for `model`: kinds that act on one body on the last
/// body only unless `opts.every_body`; kinds at the rotor's angle only when the description
/// has rotors.
fn offered_variants(opts: &Options, model: &Model) -> Vec<library::Variant> {
    let n = model.dof();
    let rotors = model.rotor_count() > 0;
    library::variants(&opts.kinds, n)
        .into_iter()
        .filter(|v| {
            v.kind
                .body(v.param, n)
                .is_none_or(|b| opts.every_body || b == n - 1)
        })
        .filter(|v| rotors || !v.kind.needs_rotor())
        .collect()
}
