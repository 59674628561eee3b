//! The ladder's rungs: one step scored on the held-out data, and the fixed rungs (the
//! description as given, every parameter re-identified).

use super::*;

/// What a rung is scored at: the ladder's data, its fit and the explanations freed in it.
pub(super) struct At<'a> {
    pub(super) data: &'a Data,
    pub(super) fit: &'a Fit,
    pub(super) set: &'a [Explanation],
}

pub(super) fn at<'a>(data: &'a Data, fit: &'a Fit, set: &'a [Explanation]) -> At<'a> {
    At { data, fit, set }
}

/// The step a rung adds: its name, the explanation (none on the fixed rungs), its held-out
/// reduction of the mean square and t statistic, and the explanations tied with it.
pub(super) struct Added {
    pub(super) step: String,
    pub(super) e: Option<Explanation>,
    pub(super) score: (f64, f64),
    pub(super) ties: Vec<Tie>,
    pub(super) also_fit: Vec<AlsoFit>,
    pub(super) unweighed: Vec<AlsoFit>,
}

impl Added {
    /// The rung of a step the ladder took.
    pub(super) fn taken(step: NextStep, model: &Model) -> Self {
        Added {
            step: step.e.step_name(model),
            e: Some(step.e),
            score: (step.reduction, step.t),
            ties: step.ties,
            also_fit: step.also_fit,
            unweighed: step.unweighed,
        }
    }

    /// A rung that adds no scored step.
    pub(super) fn fixed(step: &str) -> Self {
        Added {
            step: step.into(),
            e: None,
            score: (0.0, 0.0),
            ties: vec![],
            also_fit: vec![],
            unweighed: vec![],
        }
    }
}

/// The held-out rung of a fit.
pub(super) fn rung(stage: &Stage, at: At, added: Added) -> Rung {
    let Added {
        step,
        e,
        score: (reduction, t),
        ties,
        also_fit,
        unweighed,
    } = added;
    let rms = held_out_rms(stage, at);
    let (kind, param) = match e {
        Some(e) => e.variant().map_or((None, 0.0), |v| (Some(v.kind), v.param)),
        None => (None, 0.0),
    };
    Rung {
        step,
        kind,
        param,
        overall: mean_square(&rms).sqrt(),
        rms,
        reduction,
        t,
        ambiguous_with: ties.iter().map(|x| x.0.clone()).collect(),
        ambiguous_mass: ties.iter().map(|x| x.1).collect(),
        also_fit,
        unweighed,
    }
}

/// Held-out RMS per joint (N m) of a fit: its model with its effects, at the fit's own
/// linearization point.
pub(super) fn held_out_rms(stage: &Stage, at: At) -> Vec<f64> {
    let At { data, fit, set } = at;
    let p0 = stage.model.layout().len;
    let (theta, coefs) = model_of(data, fit, set, p0);
    let variants: Vec<Variant> = set
        .iter()
        .filter_map(|e| match e {
            Explanation::Effect(v) if !v.kind.is_body_change() => Some(*v),
            _ => None,
        })
        .collect();
    let mut full = theta.iter().copied().collect::<Vec<f64>>();
    for (e, c) in set.iter().filter(|e| e.variant().is_some()).zip(&coefs) {
        if let Some(v) = e.variant() {
            if !v.kind.is_body_change() {
                full.extend(c);
            }
        }
    }
    // At the fit's own linearization point: the same columns the held-out score saw.
    let ctx = stage.ctx_val.about(&data.theta_lin, stage.validate);
    let (rms, _) = residual_rms(
        &ctx,
        stage.validate,
        &variants,
        &DVector::from_vec(full),
        stage.opts.min_speed,
    );
    rms
}

/// The description as given, scored on the held-out data.
pub(super) fn given_rung(stage: &Stage) -> Rung {
    let theta = stage.model.parameters();
    let (rms, _) = residual_rms(
        &stage.ctx_val,
        stage.validate,
        &[],
        &theta,
        stage.opts.min_speed,
    );
    fixed_rung("description as given", rms)
}

/// Everything re-identified: the stage's nominal model.
pub(super) fn reidentified_rung(stage: &Stage) -> Rung {
    let (rms, _) = residual_rms(
        &stage.ctx_val,
        stage.validate,
        &[],
        &stage.theta0,
        stage.opts.min_speed,
    );
    fixed_rung("inertial parameters re-identified", rms)
}

pub(super) fn fixed_rung(step: &str, rms: Vec<f64>) -> Rung {
    Rung {
        step: step.into(),
        kind: None,
        param: 0.0,
        overall: mean_square(&rms).sqrt(),
        rms,
        reduction: 0.0,
        t: 0.0,
        ambiguous_with: vec![],
        ambiguous_mass: vec![],
        also_fit: vec![],
        unweighed: vec![],
    }
}

/// The library effect a step just chose (the last of `set`) with its coefficients and their
/// standard errors in `fit` (`None` for friction and a body change, weighed by
/// [`body_mass`]).
pub(super) fn weighed_at_entry(
    data: &Data,
    fit: &Fit,
    set: &[Explanation],
    p0: usize,
) -> Option<(Explanation, Vec<f64>, Vec<f64>)> {
    let e = *set.last()?;
    let v = e.variant()?;
    if v.kind.is_body_change() {
        return None;
    }
    let (_, mut c) = model_of(data, fit, set, p0);
    let mut se = standard_errors(data, fit, set, p0);
    Some((e, c.pop()?, se.pop()?))
}

/// The body change `e` weighed in a fit over `set` (`None` for an effect that is not a body
/// change).
pub(super) fn body_mass(
    n: usize,
    fit: &Fit,
    set: &[Explanation],
    e: Explanation,
    p0: usize,
) -> Option<Weighing> {
    let (_, v, cols) =
        (effect_columns(set, n, p0).into_iter()).find(|x| x.0.variant() == e.variant())?;
    v.kind.is_body_change().then(|| weighing(fit, cols.start))
}

/// The body change whose ten columns start at `c` in `fit`, weighed.
pub(super) fn weighing(fit: &Fit, c: usize) -> Weighing {
    let mass = fit.w[c];
    let h = nalgebra::Vector3::new(fit.w[c + 1], fit.w[c + 2], fit.w[c + 3]);
    let seen = !fit.unseen[c];
    Weighing {
        mass,
        mass_se: seen.then(|| fit.var[c].max(0.0).sqrt()),
        com: (seen && mass > 0.0).then(|| (h / mass).into()),
    }
}

/// The bodies a payload step freed: their change, read as a payload when its mass is positive
/// beyond three standard errors and its centre lies on or near the body.
pub(super) fn body_changes(
    stage: &Stage,
    fit: &Fit,
    set: &[Explanation],
    entered: &[(Explanation, Weighing)],
) -> Vec<BodyChange> {
    let n = stage.model.dof();
    let p0 = stage.model.layout().len;
    let mut out = vec![];
    for (e, v, cols) in effect_columns(set, n, p0) {
        let Some(b) = v.kind.body(v.param, n).filter(|_| v.kind.is_body_change()) else {
            continue;
        };
        let last = weighing(fit, cols.start);
        let entered = (entered.iter())
            .find(|x| x.0.variant() == e.variant())
            .map_or(last, |x| x.1);
        let pi = fit.w.as_slice()[cols].try_into().unwrap_or([0.0; 10]);
        let mut change = BodyChange::new(stage.model.bodies()[b].name.clone(), entered, last, pi);
        // Its second moments are seldom determined by the data (a payload's inertia about the
        // joint axes trades with its neighbours'): judged by its mass and centre only.
        let com_ok = change
            .com
            .is_some_and(|x| on_body(stage.model, b, &nalgebra::Vector3::from(x)));
        change.payload = change.mass_se.is_some_and(|se| change.mass > 3.0 * se) && com_ok;
        out.push(change);
    }
    out
}
