//! **From the description**: the sim-to-real gap itself, the description as given scored on the
//! validation data, explained step by step. The description's inertial parameters stay pinned;
//! each explanation frees only its own columns: a selected effect (its coefficients), or the
//! friction (the viscous and Coulomb coefficients re-identified). The explanations are added
//! greedily, the one that lowers the training residual most first, so the step that carries
//! most of the gap (a payload, a friction change, a sensor offset) leads. The last step
//! re-identifies the inertial parameters too: the final model of the diagnosis.
//!
//! Each step is a least-squares fit on the training data's normal equations,
//! `min ‖τ − Y_p θ_d,p − Y_f x_f‖²` over the free columns `f` with the pinned ones `p` at the
//! description's values, then scored on the validation data.

use super::diagnosis::DescriptionStep;
use super::gap::Ladder;
use super::residual::{mean_square, residual_rms};
use super::stage::Stage;
use nalgebra::{DMatrix, DVector};
use physid_core::linalg::least_squares;
use physid_effect::library::Variant;

/// What one step frees.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Explanation {
    /// A selected effect: variant index into `stage.folds`.
    Effect(usize),
    /// The friction coefficients.
    Friction,
}

/// The parameters of the description with `set` freed and fitted on the training data: the
/// model's columns, then each effect's in the order of `set` (`θ`), the effects' variants, and
/// the training residual's sum of squares (N² m²).
fn fit(stage: &Stage, set: &[Explanation]) -> (DVector<f64>, Vec<Variant>, f64) {
    let (model, folds) = (stage.model, &stage.folds);
    let (n, layout) = (model.dof(), model.layout());
    let p0 = layout.len;
    let mut cols: Vec<usize> = (0..p0).collect();
    let mut free: Vec<usize> = vec![];
    let mut variants = vec![];
    for e in set {
        match *e {
            Explanation::Friction => {
                free.extend(layout.viscous_col..layout.viscous_col + n);
                free.extend(layout.coulomb_col..layout.coulomb_col + n);
            }
            Explanation::Effect(v) => {
                let d = folds.variants[v].kind.columns(n);
                let at = folds.offsets[v];
                free.extend(cols.len()..cols.len() + d);
                cols.extend(at..at + d);
                variants.push(folds.variants[v]);
            }
        }
    }
    let ne = stage.all.select(&cols);
    let mut theta = DVector::zeros(cols.len());
    theta.rows_mut(0, p0).copy_from(&model.parameters());
    for &f in &free {
        theta[f] = 0.0;
    }
    if !free.is_empty() {
        // A_ff x = b_f − A_f· θ (θ zero on the free columns).
        let a_ff = DMatrix::from_fn(free.len(), free.len(), |i, j| ne.yty[(free[i], free[j])]);
        let rhs = DVector::from_fn(free.len(), |i, _| {
            ne.ytt[free[i]] - ne.yty.row(free[i]).transpose().dot(&theta)
        });
        let ridge = 1e-12 * a_ff.diagonal().max().max(1e-300);
        let x = least_squares(
            &(a_ff + DMatrix::identity(free.len(), free.len()) * ridge),
            &rhs,
        );
        for (i, &f) in free.iter().enumerate() {
            theta[f] = x[i];
        }
    }
    let ss = ne.tt - 2.0 * ne.ytt.dot(&theta) + (&ne.yty * &theta).dot(&theta);
    (theta, variants, ss)
}

/// The gap from the description explained: the selected effects `chosen` and the friction in
/// greedy order (description pinned), then the inertial parameters re-identified (the last rung
/// of `ladder`). Each step's validation RMS per joint (N m), joint-samples slower than the
/// speed threshold left out.
pub(crate) fn from_description(
    stage: &Stage,
    chosen: &[usize],
    ladder: &Ladder,
) -> Vec<DescriptionStep> {
    let mut remaining: Vec<Explanation> = chosen
        .iter()
        .map(|&v| Explanation::Effect(v))
        .chain([Explanation::Friction])
        .collect();
    let mut set = vec![];
    let mut steps = vec![];
    while !remaining.is_empty() {
        // Each remaining explanation tried; the winner's fit is the step's.
        let (best, (theta, variants, _)) = (0..remaining.len())
            .map(|i| {
                let mut trial = set.clone();
                trial.push(remaining[i]);
                (i, fit(stage, &trial))
            })
            .min_by(|a, b| a.1 .2.total_cmp(&b.1 .2))
            .expect("a remaining explanation");
        set.push(remaining.remove(best));
        let (rms, _) = residual_rms(
            &stage.ctx_val,
            stage.validate,
            &variants,
            &theta,
            stage.opts.min_speed,
        );
        let (step, kind, param) = match set[set.len() - 1] {
            Explanation::Friction => ("friction re-identified".to_string(), None, 0.0),
            Explanation::Effect(v) => {
                let var = stage.folds.variants[v];
                (format!("+ {}", var.kind.name()), Some(var.kind), var.param)
            }
        };
        steps.push(DescriptionStep {
            step,
            kind,
            param,
            overall: mean_square(&rms).sqrt(),
            rms,
        });
    }
    let last = ladder
        .per_step_rms
        .last()
        .expect("the nominal rung")
        .clone();
    steps.push(DescriptionStep {
        step: "inertial parameters re-identified".into(),
        kind: None,
        param: 0.0,
        overall: mean_square(&last).sqrt(),
        rms: last,
    });
    steps
}

/// The summary's sentence on the description's gap: `; from the description (X N m): + a → Y,
/// friction re-identified → Z, …`.
pub(crate) fn summary(steps: &[DescriptionStep], description: f64) -> String {
    let path: Vec<String> = steps
        .iter()
        .map(|s| format!("{} -> {:.3}", s.step, s.overall))
        .collect();
    format!(
        "; from the description ({description:.3} N m): {}",
        path.join(", ")
    )
}
