//! **Magnitudes** of the selected effects in physical units: from the final fit with
//! block-jackknife standard errors (cross-validation evidence), or from the description test's
//! posterior with first-order propagated errors (description evidence); each with the fraction
//! of its columns that the rigid-body regressor does not explain.

use super::anchor;
use super::diagnosis::{EffectEstimate, Evidence, Magnitude};
use super::select::Selection;
use super::stage::Stage;
use nalgebra::{DMatrix, DVector};
use physid_effect::library::{Kind, Variant};
use physid_effect::separate_by;

/// The physical magnitudes of `kind` from its coefficients `c` for `n` joints under gravity of
/// norm `gravity` (m/s²) (each kind's rule is its row in `kinds`).
pub fn magnitudes_of(kind: Kind, c: &[f64], n: usize, gravity: f64) -> Vec<f64> {
    kind.magnitudes(c, n, gravity)
}

/// How an effect's coefficients read as its magnitudes: which model its columns were built
/// about.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Reading {
    /// About the re-identified model, which carries the effect where its parameters can
    /// (cross-validation, the description test).
    Identified,
    /// About the description within its uncertainty, which does not (the ladder).
    Anchored,
}

impl Reading {
    /// The magnitudes of `kind` from coefficients `c` (`n` joints, gravity of norm `gravity`).
    fn magnitudes(self, kind: Kind, c: &[f64], n: usize, gravity: f64) -> Vec<f64> {
        match self {
            Reading::Identified => kind.magnitudes(c, n, gravity),
            Reading::Anchored => kind.anchored_magnitudes(c, n, gravity),
        }
    }

    /// The magnitude's name and unit.
    fn name(self, kind: Kind) -> (&'static str, &'static str) {
        match self {
            Reading::Identified => kind.magnitude(),
            Reading::Anchored => kind.anchored_magnitude(),
        }
    }
}

/// First-order standard error of magnitude `index` (read as `reading`) from its coefficients'
/// errors.
pub(crate) fn magnitude_se(
    (kind, reading): (Kind, Reading),
    c: &[f64],
    se: &[f64],
    (n, gravity): (usize, f64),
    index: usize,
) -> f64 {
    let base = reading.magnitudes(kind, c, n, gravity)[index];
    let mut v = 0.0;
    for i in 0..c.len() {
        let h = 1e-6 * c[i].abs().max(1e-6);
        let mut cp = c.to_vec();
        cp[i] += h;
        let d = (reading.magnitudes(kind, &cp, n, gravity)[index] - base) / h;
        v += (d * se[i]).powi(2);
    }
    v.sqrt()
}

/// Fraction of the energy of each column `col` of the summed normal equations that lies outside
/// the span of the model's first `p0` columns (1: fully identifiable; 0: absorbed).
pub(crate) struct Identifiable<'a> {
    yty: &'a DMatrix<f64>,
    hyy: DMatrix<f64>,
    p0: usize,
}

impl<'a> Identifiable<'a> {
    pub(crate) fn new(yty: &'a DMatrix<f64>, p0: usize) -> Self {
        let hyy = yty.view((0, 0), (p0, p0)).into_owned()
            + DMatrix::identity(p0, p0) * (1e-12 * yty.diagonal().max());
        Self { yty, hyy, p0 }
    }

    pub(crate) fn fraction(&self, col: usize) -> f64 {
        let zc = self.yty.column(col).rows(0, self.p0).into_owned();
        let x = physid_core::linalg::least_squares(&self.hyy, &zc);
        let zz = self.yty[(col, col)];
        if zz > 0.0 {
            ((zz - zc.dot(&x)) / zz).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }
}

/// The joint a magnitude belongs to, or `"robot"` for a single robot-wide value.
/// A single magnitude of a kind searched over bodies belongs to that body (named by its
/// joint).
pub(crate) fn joint_label(stage: &Stage, single: bool, i: usize, variant: Variant) -> String {
    let n = stage.model.dof();
    match (single, variant.kind.body(variant.param, n)) {
        (true, Some(b)) => stage.model.bodies()[b].joint_name.clone(),
        (true, None) => "robot".to_string(),
        (false, _) => stage.model.bodies()[i].joint_name.clone(),
    }
}

/// The columns (from `offset`, the kind's first) that magnitude `i` of `n` joints depends on:
/// all of the kind's when it has a `single` magnitude; otherwise cogging's both, a spring's
/// stiffness only its q column (the constant is its rest position).
fn value_columns(kind: Kind, (single, i, n): (bool, usize, usize), offset: usize) -> Vec<usize> {
    if single {
        (0..kind.columns(n)).map(|c| offset + c).collect()
    } else {
        kind.magnitude_columns(i, n)
            .into_iter()
            .map(|c| offset + c)
            .collect()
    }
}

/// The estimates of the effects cross-validation selected, from the final parameters
/// `final_theta` (effect coefficients after the model's), with block-jackknife errors from the
/// selection's per-fold fits.
pub(crate) fn cross_validated(
    stage: &Stage,
    selection: &Selection,
    final_theta: &DVector<f64>,
) -> Vec<EffectEstimate> {
    let n = stage.model.dof();
    let g = stage.model.gravity().norm().max(1e-12);
    let folds = &stage.folds;
    let p0 = stage.model.layout().len;
    let identifiable = Identifiable::new(&stage.all.yty, p0);
    let fold_thetas = selection
        .final_cv
        .as_ref()
        .map(|c| c.thetas.clone())
        .unwrap_or_default();
    let mut effects = vec![];
    let mut offset = p0;
    for (si, &vi) in selection.chosen.iter().enumerate() {
        let v = folds.variants[vi];
        let columns = v.kind.columns(n);
        let coefficients = |t: &DVector<f64>| t.as_slice()[offset..offset + columns].to_vec();
        let values = magnitudes_of(v.kind, &coefficients(final_theta), n, g);
        let jackknife: Vec<Vec<f64>> = fold_thetas
            .iter()
            .map(|t| magnitudes_of(v.kind, &coefficients(t), n, g))
            .collect();
        let (name, unit) = v.kind.magnitude();
        let single = values.len() == 1;
        let magnitudes = values
            .iter()
            .enumerate()
            .map(|(i, &value)| {
                let cols = value_columns(v.kind, (single, i, n), folds.offsets[vi]);
                Magnitude {
                    joint: joint_label(stage, single, i, v),
                    value,
                    se: jackknife_se(&jackknife, i),
                    unit: unit.into(),
                    identifiable: cols
                        .iter()
                        .map(|&c| identifiable.fraction(c))
                        .fold(1.0, f64::min),
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
            after_later_steps: None,
        });
        offset += columns;
    }
    effects
}

/// Block-jackknife standard error of entry `i` over the per-fold values.
fn jackknife_se(per_fold: &[Vec<f64>], i: usize) -> f64 {
    let folds = per_fold.len() as f64;
    let mean = per_fold.iter().map(|m| m[i]).sum::<f64>() / folds.max(1.0);
    ((folds - 1.0) / folds.max(1.0) * per_fold.iter().map(|m| (m[i] - mean).powi(2)).sum::<f64>())
        .sqrt()
}

/// The estimates of the effects found against the description: posterior magnitudes, errors
/// propagated to first order, identified through the description (identifiable fraction 1).
pub(crate) fn against_description(stage: &Stage, steps: &[anchor::Step]) -> Vec<EffectEstimate> {
    steps
        .iter()
        .map(|st| {
            let v = stage.folds.variants[st.variant];
            let found = (v, Reading::Identified);
            described_estimate(stage, found, &st.beta, &st.se, st.ambiguous_with.clone())
        })
        .collect()
}

/// The estimate of variant `v` found against the description, from its coefficients `beta`
/// (read as `reading`) and their posterior standard errors `se`: magnitudes with errors
/// propagated to first order, identified through the description (identifiable fraction 1);
/// what the data could not tell it apart from, with the data that would.
pub(crate) fn described_estimate(
    stage: &Stage,
    (v, reading): (Variant, Reading),
    beta: &[f64],
    se: &[f64],
    ambiguous_with: Vec<Kind>,
) -> EffectEstimate {
    let n = stage.model.dof();
    let g = stage.model.gravity().norm().max(1e-12);
    let (name, unit) = reading.name(v.kind);
    let values = reading.magnitudes(v.kind, beta, n, g);
    let single = values.len() == 1;
    let magnitudes = values
        .iter()
        .enumerate()
        .map(|(i, &value)| Magnitude {
            joint: joint_label(stage, single, i, v),
            value,
            se: magnitude_se((v.kind, reading), beta, se, (n, g), i),
            unit: unit.into(),
            identifiable: 1.0,
        })
        .collect();
    EffectEstimate {
        kind: v.kind,
        evidence: Evidence::Description,
        param: v.param,
        magnitude_name: name.into(),
        magnitudes,
        separate_by: ambiguous_with.first().map(|&b| separate_by(v.kind, b)),
        ambiguous_with,
        after_later_steps: None,
    }
}
