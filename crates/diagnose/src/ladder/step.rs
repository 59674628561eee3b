//! The ladder's next step: the best-scoring candidate, the ties it is reported with, and
//! when a simpler or a friction explanation is kept instead.

use super::*;

/// A step the ladder takes: the explanation kept, its reduction of the held-out mean square
/// and block t, the explanations of its size tied with it, and those with more columns.
pub(super) struct NextStep {
    pub(super) e: Explanation,
    pub(super) reduction: f64,
    pub(super) t: f64,
    pub(super) ties: Vec<Tie>,
    pub(super) also_fit: Vec<AlsoFit>,
    pub(super) unweighed: Vec<AlsoFit>,
}

/// The next step: every candidate fitted with the set so far and scored on the held-out data;
/// the winner and the candidates tied with it, or why the ladder stops. A body step must weigh
/// its mass: where the data see only a body's first moment `m c`, a description's error
/// carried to another motion fits as well as a payload does.
pub(super) fn next_step(
    problem: &Problem,
    data: &Data,
    selected: &Selected,
    set: &[Explanation],
    sse: &[f64],
    settings: &Settings,
) -> Result<NextStep, (Stop, Vec<AlsoFit>)> {
    let model = problem.stage.model;
    let scored = scored_candidates(problem, data, selected, set, sse);
    let mut scored = significant_if_tied_only(scored, selected, settings);
    scored.sort_by(|a, b| b.1.total_cmp(&a.1));
    let (scored, unweighed): (Vec<Scored>, Vec<Scored>) = scored
        .into_iter()
        .partition(|s| s.0.body(data.n).is_none() || s.3.is_some());
    let Some(&(best, r, t, _)) = scored.first() else {
        let left = unweighed_beside(&unweighed, settings.min_reduction, settings, model);
        return Err((Stop::NoCandidate, left));
    };
    if !significant(&scored[0], settings) {
        let stop = Stop::NotSignificant {
            best: best.name(model, UNREAD),
            reduction: r,
            t,
        };
        let left = unweighed_beside(&unweighed, settings.min_reduction, settings, model);
        return Err((stop, left));
    }
    let widths: Vec<usize> = scored.iter().map(|s| complexity(&s.0, data.n)).collect();
    let parts = (set, sse, settings);
    let (chosen, tied, gave_way) = choose(problem, data, selected, parts, (&scored, &widths));
    let (best, r, t, _) = scored[chosen];
    let (ties, mut also_fit) = tied_with(&scored, &tied, chosen, &widths, model);
    if let Some(compound) = gave_way {
        let (e, reduction, _, mass) = scored[compound];
        let name = e.name(model, UNREAD);
        also_fit.retain(|x| x.name != name);
        also_fit.push(AlsoFit {
            name,
            reduction,
            mass,
        });
    }
    let unweighed = unweighed_beside(
        &unweighed,
        scored[0].1 * (1.0 - settings.tie),
        settings,
        model,
    );
    Ok(NextStep {
        e: best,
        reduction: r,
        t,
        ties,
        also_fit,
        unweighed,
    })
}

/// The step among `scored` (best first), its tie group, and the compound it was taken in place
/// of ([`parts_over_compound`]), if any.
///
/// Ties: within `tie` of the winner's reduction, leaving at most `LEFT_TIE` times what it
/// leaves; the simplest (fewest columns) is kept, the others of its size reported as ambiguous
/// with it. What is left matters once the winner explains most of the gap: on a payload "what
/// changed" case the payload took 99.0 % of the held-out error, a torque gain 92.0 % (eight
/// times the payload's remainder), and the gain, tied by reduction alone, was kept for its
/// fewer columns.
fn choose(
    problem: &Problem,
    data: &Data,
    selected: &Selected,
    (set, sse, settings): (&[Explanation], &[f64], &Settings),
    (scored, widths): (&[Scored], &[usize]),
) -> (usize, Ties, Option<usize>) {
    let reduction: Vec<f64> = scored.iter().map(|s| s.1).collect();
    let t_stats: Vec<f64> = scored.iter().map(|s| s.2).collect();
    let eligible = tie_eligible(&reduction, &t_stats, settings, 0);
    let tied = Ties::of(&reduction, widths, |i| eligible[i], settings.tie);
    let p0 = problem.theta_d.len();
    let compound = simplest_or_best(data, scored, tied.simplest[0], p0);
    let parts = (set, sse, settings);
    let part = parts_over_compound(problem, data, parts, scored, compound, widths);
    let (chosen, tied) = match part {
        Some(part) => (part, ties_around(scored, part, compound, settings)),
        None => (compound, tied),
    };
    let chosen = named_signal_over_body(scored, selected, &tied.within, chosen, data.n);
    let chosen = friction_where_tied(scored, &tied.within, chosen);
    (chosen, tied, part.map(|_| compound))
}

/// A kind offered only for its tie in cross-validation competes where it is significant
/// itself: it never ends the ladder in another's place.
pub(super) fn significant_if_tied_only(
    mut scored: Vec<Scored>,
    selected: &Selected,
    settings: &Settings,
) -> Vec<Scored> {
    scored.retain(|s| {
        let tied_only = s.0.variant().is_some_and(|v| selected.tied_only(&v));
        !tied_only || significant(s, settings)
    });
    scored
}

/// Whether a candidate may be a step: it lowers the held-out mean square by at least
/// `min_reduction` with a block t of at least `min_t`.
fn significant(s: &Scored, settings: &Settings) -> bool {
    s.1 >= settings.min_reduction && s.2 >= settings.min_t
}

/// A simpler explanation is kept over the best-fitting one (`scored[0]`) only where it is
/// nested in it (its columns lie in the span of the best's: a spring holds an offset, so it always
/// fits at least as well) or leaves at most [`CLOSE_FIT`] times the held-out error the best
/// leaves. Two explanations that are not nested are told apart by what they fit: a torque gain
/// on one shoulder joint took 92 % of the held-out mean square and a payload on `lwr_4_link` 89 %
/// (semi-real seed 2, case 27: the gain was injected); 1.42 kg on `lwr_5_link` 97.4 % and a gain
/// on every joint 95.2 % (baseline mode, case 13: the payload).
pub(super) fn simplest_or_best(
    data: &Data,
    scored: &[Scored],
    simplest: usize,
    p0: usize,
) -> usize {
    let left = |i: usize| left_after(&scored[i]);
    let nested = || spanned_by(data, &scored[simplest].0, &scored[0].0, p0);
    if simplest == 0 || left(simplest) <= CLOSE_FIT * left(0) || nested() {
        simplest
    } else {
        0
    }
}

/// A compound explanation (`scored[chosen]`) yields to a simpler candidate where that candidate
/// and an explanation nested in the compound, together no wider than it, fit the held-out data
/// better than it does alone: the compound's columns beyond its nested part were standing in for
/// the other candidate. Of the two, the one with the larger reduction of its own is the step
/// where it is significant itself (the next step weighs the other); `None` where no pair does.
/// A spring holds a torque offset; on real KUKA logs with 0.6 kg injected on `lwr_6_link`
/// (semi-real benchmark seed 2, case 46, the run carrying a standing offset against its
/// description's) a spring took 61.6 % of the held-out mean square, a point mass on
/// `lwr_5_link` 51.8 %, an offset 14.5 %, and the offset with the point mass 85.1 % in 11
/// columns against the spring's 14: the payload had been named after the spring.
pub(super) fn parts_over_compound(
    problem: &Problem,
    data: &Data,
    (set, sse, settings): (&[Explanation], &[f64], &Settings),
    scored: &[Scored],
    chosen: usize,
    widths: &[usize],
) -> Option<usize> {
    let p0 = problem.theta_d.len();
    let compound = scored[chosen].0;
    let nested: Vec<usize> = (0..scored.len())
        .filter(|&i| widths[i] < widths[chosen] && spanned_by(data, &scored[i].0, &compound, p0))
        .collect();
    let significant = |i: usize| significant(&scored[i], settings);
    let mut best: Option<(f64, usize)> = None;
    for &s in nested.iter().filter(|&&s| scored[s].1 > 0.0) {
        let room = widths[chosen] - widths[s];
        let others = (0..scored.len())
            .filter(|&c| c != chosen && !nested.contains(&c) && widths[c] <= room && significant(c))
            .take(PARTS_TRIED);
        for c in others {
            let pair = [set, &[scored[s].0, scored[c].0]].concat();
            let fit = problem.fit(data, &pair);
            if !bodies_consistent(data, &fit, &pair, p0, problem.stage.model) {
                continue;
            }
            let (r, _) = improvement(sse, &problem.held_out(data, &fit));
            // A step is significant itself: the nested part only where it is.
            let first = if significant(s) && scored[s].1 > scored[c].1 {
                s
            } else {
                c
            };
            if r >= scored[chosen].1 && best.is_none_or(|(b, _)| r > b) {
                best = Some((r, first));
            }
        }
    }
    best.map(|(_, first)| first)
}

/// The tie group of a `part` [`parts_over_compound`] took in the `compound`'s place: the
/// candidates but the compound within the tie of its reduction, significant, and leaving at
/// most [`LEFT_TIE`] times what it leaves (the neighbouring bodies of a payload).
pub(super) fn ties_around(
    scored: &[Scored],
    part: usize,
    compound: usize,
    settings: &Settings,
) -> Ties {
    let reduction: Vec<f64> = scored.iter().map(|s| s.1).collect();
    let t_stats: Vec<f64> = scored.iter().map(|s| s.2).collect();
    let eligible = tie_eligible(&reduction, &t_stats, settings, part);
    let tied_with_part = |i: usize| eligible[i] && i != compound;
    let within = Ties::within_of(&reduction, tied_with_part, settings.tie, part);
    Ties {
        within,
        simplest: vec![part],
    }
}

/// The candidates (best first) [`parts_over_compound`] pairs with each nested explanation.
pub(super) const PARTS_TRIED: usize = 8;

/// A signal-path effect cross-validation named (a compliance, backlash or lag: kinds
/// [`Kind::offered_from_description`]) in place of a `chosen` body step where it is among the
/// `tied` and fits at least as well. Cross-validation re-identifies every inertial parameter, so
/// a payload is absorbed there and never makes it name such an effect; a transmission's
/// deflection shifts the gravity torque as a mass on a body does, so from the description the
/// two fit alike and the body step's fewer columns had kept it (generalization benchmark,
/// KUKA, seed 1, case 10: a compliance named by cross-validation left 41.3 % of the held-out
/// mean square, a point mass on `lwr_4_link` 42.6 %, and the point mass was kept).
pub(super) fn named_signal_over_body(
    scored: &[Scored],
    selected: &Selected,
    tied: &[usize],
    chosen: usize,
    n: usize,
) -> usize {
    if scored[chosen].0.body(n).is_none() {
        return chosen;
    }
    let named = |e: &Explanation| {
        e.variant()
            .is_some_and(|v| v.kind.offered_from_description() && selected.names(v.kind))
    };
    tied.iter()
        .copied()
        .find(|&i| named(&scored[i].0) && scored[i].1 >= scored[chosen].1)
        .unwrap_or(chosen)
}

/// The friction re-identified in place of the `chosen` explanation where it is among the
/// `tied` and fits practically as well ([`CLOSE_FIT`]): of the changes a real robot goes
/// through, its friction's (temperature, wear, lubrication) is the likeliest, and a friction
/// twice as strong on the KUKA's slow motion fitted as a 24 ms delay of the logged torque does
/// (38.2 % and 37.7 % of the held-out mean square; generalization benchmark, seed 2, case 15),
/// the delay kept for its one column. No injected delay, payload or other effect of the
/// benchmarks had the friction in its tie.
pub(super) fn friction_where_tied(scored: &[Scored], tied: &[usize], chosen: usize) -> usize {
    let left = |i: usize| left_after(&scored[i]);
    tied.iter()
        .copied()
        .find(|&i| scored[i].0 == Explanation::Friction && left(i) <= CLOSE_FIT * left(chosen))
        .unwrap_or(chosen)
}

/// The fraction of the held-out mean square a candidate leaves (kept above zero for ratios).
pub(super) fn left_after(s: &Scored) -> f64 {
    (1.0 - s.1).max(1e-12)
}

/// Two explanations fit practically alike when one leaves at most this many times the held-out
/// error the other leaves. Measured on the semi-real benchmark, seed 2: a compliance left 1.21
/// times what a spring left (case 32: the compliance was injected, and is kept), a point mass
/// 1.49 times what a torque gain left (case 27: the gain was injected).
pub(super) const CLOSE_FIT: f64 = 1.25;

/// An explanation's columns as combinations of the data's (`(column, weight)` lists, one per
/// column): an effect's own, a point mass's four of its body's ten, the friction's.
pub(super) fn column_combinations(
    data: &Data,
    e: &Explanation,
    p0: usize,
) -> Vec<Vec<(usize, f64)>> {
    match e {
        Explanation::Effect(v) => {
            let at = data.offsets[data.index(v)];
            (at..at + v.kind.columns(data.n))
                .map(|c| vec![(c, 1.0)])
                .collect()
        }
        Explanation::PointMass(v, c) => {
            let (at, b) = (data.offsets[data.index(v)], point_mass_map(c));
            (0..4)
                .map(|k| (0..10).map(|r| (at + r, b[(r, k)])).collect())
                .collect()
        }
        // The model's last 2n columns: viscous, then Coulomb coefficients.
        Explanation::Friction => (p0 - 2 * data.n..p0).map(|c| vec![(c, 1.0)]).collect(),
    }
}

/// Whether every column of `a` lies in the span of `b`'s on the training data (its residual
/// curvature after them below [`ALIASED`]-like 10⁻⁶ of its own).
pub(super) fn spanned_by(data: &Data, a: &Explanation, b: &Explanation, p0: usize) -> bool {
    let (ca, cb) = (
        column_combinations(data, a, p0),
        column_combinations(data, b, p0),
    );
    let h = &data.train.yty;
    let gram = |x: &[(usize, f64)], y: &[(usize, f64)]| -> f64 {
        x.iter()
            .flat_map(|&(i, u)| y.iter().map(move |&(j, v)| u * v * h[(i, j)]))
            .sum()
    };
    let hbb = DMatrix::from_fn(cb.len(), cb.len(), |i, j| gram(&cb[i], &cb[j]));
    let scale: Vec<f64> = (0..cb.len())
        .map(|i| 1.0 / hbb[(i, i)].max(1e-300).sqrt())
        .collect();
    let hbb = DMatrix::from_fn(cb.len(), cb.len(), |i, j| scale[i] * hbb[(i, j)] * scale[j]);
    let Some(ch) = (hbb + DMatrix::identity(cb.len(), cb.len()) * 1e-12).cholesky() else {
        return false;
    };
    ca.iter().all(|x| {
        let own = gram(x, x);
        let hb = DVector::from_fn(cb.len(), |i, _| scale[i] * gram(&cb[i], x));
        own <= 0.0 || own - hb.dot(&ch.solve(&hb)) <= 1e-6 * own
    })
}

/// Of the `tied` candidates (`scored` best first, `widths` their complexity), those of the
/// `chosen` one's complexity are its ambiguity group, the others (simpler or wider) set aside
/// for it; each named once (other grid points of the chosen kind are not another explanation;
/// of another kind's, the best is named).
pub(super) fn tied_with(
    scored: &[Scored],
    tied: &Ties,
    chosen: usize,
    widths: &[usize],
    model: &Model,
) -> (Vec<Tie>, Vec<AlsoFit>) {
    let own = scored[chosen].0.name(model, UNREAD);
    let name = |i: usize| scored[i].0.name(model, UNREAD);
    let mut ties: Vec<Tie> = vec![];
    let mut also_fit: Vec<AlsoFit> = vec![];
    for &i in tied.within.iter().filter(|&&i| i != chosen) {
        let name = name(i);
        let known = name == own
            || ties.iter().any(|x| x.0 == name)
            || also_fit.iter().any(|x| x.name == name);
        if known {
            continue;
        }
        if widths[i] == widths[chosen] {
            ties.push((name, scored[i].3));
        } else {
            let (reduction, mass) = (scored[i].1, scored[i].3);
            also_fit.push(AlsoFit {
                name,
                reduction,
                mass,
            });
        }
    }
    (ties, also_fit)
}

/// The body changes whose mass the data do not weigh (`unweighed`, best first) that lower the
/// held-out mean square by at least `least` with a significant t, each body once: said beside
/// the step (or the stop), never taken as one.
pub(super) fn unweighed_beside(
    unweighed: &[Scored],
    least: f64,
    settings: &Settings,
    model: &Model,
) -> Vec<AlsoFit> {
    let mut out: Vec<AlsoFit> = vec![];
    for &(e, reduction, t, _) in unweighed {
        let name = e.name(model, UNREAD);
        let known = out.iter().any(|x| x.name == name);
        if reduction >= least && t >= settings.min_t && !known {
            out.push(AlsoFit {
                name,
                reduction,
                mass: None,
            });
        }
    }
    out
}

/// A candidate that leaves more than this many times the held-out error the best leaves does
/// not fit the data as well, whatever its reduction.
pub(super) const LEFT_TIE: f64 = 2.0;

/// Which candidates (with their `reduction` and block `t`) may tie with candidate `reference`
/// (the best, 0, where they are sorted best first): significant themselves, and leaving at most
/// [`LEFT_TIE`] times the held-out error it leaves (the reduction's own cut is [`Ties::of`]'s).
pub(super) fn tie_eligible(
    reduction: &[f64],
    t: &[f64],
    settings: &Settings,
    reference: usize,
) -> Vec<bool> {
    let left_cut = (1.0 - reduction[reference]) * LEFT_TIE;
    reduction
        .iter()
        .zip(t)
        .map(|(r, t)| *t >= settings.min_t && 1.0 - r <= left_cut)
        .collect()
}

/// Per chosen effect, the posterior standard errors of its coefficients (in `set` order,
/// friction skipped), from the fit's covariance and the data weight's scale.
pub(super) fn standard_errors(
    data: &Data,
    fit: &Fit,
    set: &[Explanation],
    p0: usize,
) -> Vec<Vec<f64>> {
    effect_columns(set, data.n, p0)
        .into_iter()
        .map(|(_, _, cols)| cols.map(|i| fit.var[i].max(0.0).sqrt()).collect())
        .collect()
}
