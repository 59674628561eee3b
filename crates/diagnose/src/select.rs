//! Which effect: cross-validated forward selection over the effect library.
//!
//! The training samples are cut into `K` contiguous blocks; the normal equations of
//! `[Y | E]` (model columns and every candidate's columns) are accumulated once per block, so
//! any subset of effects is fitted and scored from sums alone: fit on `K − 1` blocks under the
//! nominal constraint set, score `‖Z θ − τ‖²` on the held-out block, sum over blocks.
//!
//! With several training runs the blocks are the runs (leave one run out), so an effect must
//! carry over from run to run.
//!
//! A step adds the effect kind (at its best grid point) with the lowest cross-validated error,
//! if it lowers the error by at least `min_reduction` (relative) and in at least `K − 1` of the
//! `K` held-out blocks (all of them when `K < 4`). Kinds whose error lies within `tie` of the winner's reduction fit the
//! data as well: the one with fewest columns is kept (Occam), and equally simple ones are reported
//! together as ambiguous.

use super::rows::normal_equations;
use super::stats::Ties;
use nalgebra::DVector;
use physid_core::model::Model;
use physid_core::trajectory::Trajectory;
use physid_effect::library::{Context, Kind, Variant};
use physid_ident::{identify, IdentError, NormalEquations, Options};
use rayon::prelude::*;
use serde::Serialize;

/// Selection settings.
#[derive(Clone, Debug)]
pub struct Settings {
    /// Cross-validation blocks `K`.
    pub folds: usize,
    /// Smallest relative reduction of the cross-validated error that selects an effect.
    pub min_reduction: f64,
    /// Kinds within this fraction of the winner's reduction tie with it.
    pub tie: f64,
    /// At most this many effects.
    pub max_effects: usize,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            folds: 5,
            min_reduction: 0.03,
            tie: 0.1,
            max_effects: 3,
        }
    }
}

/// Per-block normal equations of the augmented regressor.
pub struct Folds {
    /// Model parameters `p₀`.
    pub p0: usize,
    /// Joints.
    pub n: usize,
    /// Every candidate variant.
    pub variants: Vec<Variant>,
    /// First augmented column of each variant.
    pub offsets: Vec<usize>,
    /// One block per fold.
    pub blocks: Vec<NormalEquations>,
    /// Rows (joint-samples) fitted per block (rows of slow joints are left out).
    pub rows: Vec<usize>,
    /// Whether the blocks are whole runs.
    pub by_run: bool,
    /// Per block, the sum of the others (what a fold trains on), summed once on first use.
    complements: std::sync::OnceLock<Vec<NormalEquations>>,
}

/// A cross-validated score.
#[derive(Clone, Debug)]
pub struct Cv {
    /// Mean squared held-out error per joint-sample (N² m²).
    pub mse: f64,
    /// Held-out sum of squares per block.
    pub block_sse: Vec<f64>,
    /// The fit of each fold (trained without block `f`), augmented order of the subset.
    pub thetas: Vec<DVector<f64>>,
}

/// The samples of each of `k` contiguous blocks of `range`: equal parts, or one per run when
/// `runs` gives the lengths of the runs joined in it.
fn block_ranges(
    range: std::ops::Range<usize>,
    k: usize,
    runs: Option<&[usize]>,
) -> Vec<std::ops::Range<usize>> {
    let (start, len) = (range.start, range.len());
    let ends: Vec<usize> = runs
        .unwrap_or_default()
        .iter()
        .scan(0, |acc, r| {
            *acc += r;
            Some(*acc)
        })
        .collect();
    let block_of = |s: usize| {
        if runs.is_some() {
            ends.partition_point(|&e| e <= s - start).min(k - 1)
        } else {
            ((s - start) * k / len).min(k - 1)
        }
    };
    (0..k)
        .map(|b| {
            let first = range
                .clone()
                .find(|&s| block_of(s) >= b)
                .unwrap_or(range.end);
            let end = range
                .clone()
                .find(|&s| block_of(s) > b)
                .unwrap_or(range.end);
            first..end
        })
        .collect()
}

impl Folds {
    /// Accumulates samples `range` of `tr` into `k` contiguous blocks, or, when `runs` (the
    /// lengths of the runs joined in `range`) has two or more entries, one block per run
    /// (leave-one-run-out).
    pub fn build(
        ctx: &Context,
        tr: &Trajectory,
        range: std::ops::Range<usize>,
        variants: Vec<Variant>,
        k: usize,
        runs: &[usize],
        min_speed: f64,
    ) -> Self {
        let by_run = runs.len() >= 2 && runs.iter().sum::<usize>() == range.len();
        let k = if by_run { runs.len() } else { k };
        let ranges = block_ranges(range, k, by_run.then_some(runs));
        let model = ctx.model();
        let n = model.dof();
        let p0 = model.layout().len;
        let mut offsets = vec![];
        let mut c = p0;
        for v in &variants {
            offsets.push(c);
            c += v.kind.columns(n);
        }
        // Each block is accumulated on its own (in parallel), in fixed chunks: the same sums
        // whatever the thread count.
        let (blocks, rows): (Vec<NormalEquations>, Vec<usize>) = ranges
            .into_par_iter()
            .map(|r| normal_equations(ctx, tr, r, &variants, min_speed))
            .unzip();
        Self {
            p0,
            n,
            variants,
            offsets,
            blocks,
            rows,
            by_run,
            complements: std::sync::OnceLock::new(),
        }
    }

    /// Augmented column indices of the model plus `chosen` variants.
    pub fn columns(&self, chosen: &[usize]) -> Vec<usize> {
        let mut cols: Vec<usize> = (0..self.p0).collect();
        for &v in chosen {
            let o = self.offsets[v];
            cols.extend(o..o + self.variants[v].kind.columns(self.n));
        }
        cols
    }

    /// The sum of the blocks except `skip` (`usize::MAX`: all).
    pub fn sum_except(&self, skip: usize) -> NormalEquations {
        let mut it = self
            .blocks
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != skip)
            .map(|(_, b)| b);
        let first = it.next().expect("at least two blocks").clone();
        it.fold(first, |acc, b| acc.merged(b))
    }

    /// The sum of the blocks but `f`: fold `f`'s training data. Every candidate of the forward
    /// selection trains on the same `K` sums, so they are added once (in the order of
    /// [`Folds::sum_except`], the same values) and kept. They are added on the calling thread,
    /// not in parallel: the first caller is a rayon task, and a rayon worker waiting inside the
    /// initializer would steal other folds' tasks, which would enter it again (a deadlock).
    fn trained_without(&self, f: usize) -> &NormalEquations {
        let all = self
            .complements
            .get_or_init(|| (0..self.blocks.len()).map(|f| self.sum_except(f)).collect());
        &all[f]
    }

    /// Fits the model plus `chosen` on `ne` (augmented) with the description as prior.
    pub fn fit(
        &self,
        model: &Model,
        ne: &NormalEquations,
        chosen: &[usize],
        opts: &Options,
    ) -> Result<DVector<f64>, IdentError> {
        let cols = self.columns(chosen);
        let mut sub = ne.select(&cols);
        let mut prior = DVector::zeros(cols.len());
        prior.rows_mut(0, self.p0).copy_from(&model.parameters());
        // Effects with a physical sign keep it (in the subset's column order). These fits only
        // score held-out errors: the dense solver's speed serves them, its looser parameters
        // along flat directions do not matter to them.
        let mut opts = opts.clone();
        opts.dense_solver = true;
        let mut c = self.p0;
        for &v in chosen {
            let kind = self.variants[v].kind;
            let nc = kind.columns(self.n);
            if kind.non_negative() {
                opts.nonnegative.extend(c..c + nc);
            }
            if kind.common_mode_in_span() {
                sub = sub.with_mean_pinned(c..c + nc);
            }
            c += nc;
        }
        Ok(identify(model, &sub, &prior, &opts)?.theta)
    }

    /// The cross-validated error of the model plus `chosen`.
    pub fn cv(&self, model: &Model, chosen: &[usize], opts: &Options) -> Result<Cv, IdentError> {
        let cols = self.columns(chosen);
        // The folds' fits are independent: in parallel, read back in fold order.
        let thetas = (0..self.blocks.len())
            .into_par_iter()
            .map(|f| self.fit(model, self.trained_without(f), chosen, opts))
            .collect::<Result<Vec<_>, _>>()?;
        let block_sse: Vec<f64> = thetas
            .iter()
            .zip(&self.blocks)
            .map(|(theta, block)| block.select(&cols).residual_sum_of_squares(theta))
            .collect();
        let count: usize = self.rows.iter().sum();
        Ok(Cv {
            mse: block_sse.iter().sum::<f64>() / count.max(1) as f64,
            block_sse,
            thetas,
        })
    }
}

/// One kind's best score in a step.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct Score {
    /// The kind.
    pub kind: Kind,
    /// Its best grid value (0 without a grid).
    pub param: f64,
    /// Cross-validated RMS with it added (N m).
    pub cv_rms: f64,
    /// Relative reduction of the cross-validated mean square.
    pub reduction: f64,
    /// Held-out blocks whose error it lowers.
    pub blocks_improved: usize,
}

/// One accepted step.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct Step {
    /// The kind kept.
    pub kind: Kind,
    /// Its grid value.
    pub param: f64,
    /// Cross-validated RMS before and after (N m).
    pub cv_rms_before: f64,
    /// After.
    pub cv_rms_after: f64,
    /// Relative reduction of the mean square.
    pub reduction: f64,
    /// Equally simple kinds that fit as well: the data cannot tell them apart (empty when the
    /// attribution is unique).
    pub ambiguous_with: Vec<Kind>,
    /// Kinds with more columns that fit as well (they contain the kept one's effect).
    pub also_fit: Vec<Kind>,
    /// Every kind's score in this step, best first.
    pub scores: Vec<Score>,
}

/// The outcome of the forward selection.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct Selection {
    /// Cross-validation blocks (the runs when several training runs are given).
    pub blocks: usize,
    /// Whether the blocks are whole runs (leave one run out).
    pub by_run: bool,
    /// Cross-validated RMS of the nominal model (N m).
    pub nominal_cv_rms: f64,
    /// Accepted steps in order.
    pub steps: Vec<Step>,
    /// Why it stopped, with the best rejected candidate's score.
    #[schemars(with = "String")]
    pub stop: SelectionStop,
    /// Indices of the chosen variants (into [`Folds::variants`]).
    #[serde(skip)]
    pub chosen: Vec<usize>,
    /// Cross-validation of the final set.
    #[serde(skip)]
    pub final_cv: Option<Cv>,
}

/// Why the forward selection stopped. Serialized as its sentence ([`std::fmt::Display`]).
#[derive(Clone, Debug, PartialEq)]
pub enum SelectionStop {
    /// The maximum number of effects was reached.
    MaxEffects(usize),
    /// Every kind was tried or none could be fitted.
    NoCandidate,
    /// The best remaining candidate did not lower the cross-validated error enough in enough
    /// blocks.
    NotSignificant {
        /// The candidate.
        kind: Kind,
        /// Its relative reduction of the cross-validated mean square.
        reduction: f64,
        /// Blocks it improved, of `blocks`.
        improved: usize,
        /// Cross-validation blocks.
        blocks: usize,
        /// The reduction a step needs.
        min_reduction: f64,
        /// The blocks a step must improve.
        needed: usize,
    },
    /// A stop as a report states it, read back from its JSON (its sentence).
    Stated(String),
}

impl std::fmt::Display for SelectionStop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Stated(sentence) => f.write_str(sentence),
            Self::MaxEffects(max) => write!(f, "reached the maximum of {max} effects"),
            Self::NoCandidate => f.write_str("no candidate left"),
            Self::NotSignificant {
                kind,
                reduction,
                improved,
                blocks,
                min_reduction,
                needed,
            } => write!(
                f,
                "best remaining candidate {} lowers the cross-validated error by {:.1} % in {improved}/{blocks} blocks (needs {:.1} % in {needed}/{blocks})",
                kind.name(),
                100.0 * reduction,
                100.0 * min_reduction,
            ),
        }
    }
}

impl Serialize for SelectionStop {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

impl<'de> serde::Deserialize<'de> for SelectionStop {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        <String as serde::Deserialize>::deserialize(d).map(Self::Stated)
    }
}

/// Per kind not `used` (nor in the model's span), its variant of the least cross-validated
/// error added to `chosen`; a fit that fails or is infeasible does not compete.
fn best_per_kind(
    folds: &Folds,
    model: &Model,
    opts: &Options,
    chosen: &[usize],
    used: &[Kind],
) -> Vec<(usize, Cv)> {
    let candidates: Vec<(usize, Kind)> = folds
        .variants
        .iter()
        .enumerate()
        .filter(|(_, v)| !used.contains(&v.kind) && !v.kind.in_model_span())
        .map(|(vi, v)| (vi, v.kind))
        .collect();
    // Every candidate's cross-validation at once (independent fits); the choice below reads
    // them in the variants' order, so it is the same whatever the thread count.
    let cvs: Vec<Option<Cv>> = candidates
        .par_iter()
        .map(|&(vi, _)| folds.cv(model, &[chosen, &[vi]].concat(), opts).ok())
        .collect();
    let mut best = vec![];
    for kind in Kind::ALL {
        let mut top: Option<(usize, Cv)> = None;
        for ((vi, k), cv) in candidates.iter().zip(&cvs) {
            let Some(cv) = cv.as_ref().filter(|_| *k == kind) else {
                continue;
            };
            if top.as_ref().is_none_or(|(_, t)| cv.mse < t.mse) {
                top = Some((*vi, cv.clone()));
            }
        }
        best.extend(top);
    }
    best
}

/// Of the candidates `best` (scored as `scores`, best first), those within `tie` of the
/// winner's reduction ([`Ties`]): the one kept (the fewest columns, then the best score), the
/// kinds of its size ambiguous with it, and the kinds with more columns that also fit.
fn resolve_ties(
    folds: &Folds,
    best: &[(usize, Cv)],
    scores: &[Score],
    tie: f64,
) -> (usize, Vec<Kind>, Vec<Kind>) {
    let reduction: Vec<f64> = scores.iter().map(|s| s.reduction).collect();
    let columns: Vec<usize> = best
        .iter()
        .map(|(vi, _)| folds.variants[*vi].kind.columns(folds.n))
        .collect();
    let ties = Ties::of(&reduction, &columns, |_| true, tie);
    let ambiguous_with = ties.simplest[1..].iter().map(|&i| scores[i].kind).collect();
    let also_fit = ties.wider(&columns).map(|i| scores[i].kind).collect();
    (ties.simplest[0], ambiguous_with, also_fit)
}

/// Each candidate `(variant, cross-validation)` scored against the `current` model.
fn scored(folds: &Folds, best: &[(usize, Cv)], current: &Cv) -> Vec<Score> {
    let k = folds.blocks.len();
    best.iter()
        .map(|(vi, cv)| Score {
            kind: folds.variants[*vi].kind,
            param: folds.variants[*vi].param,
            cv_rms: cv.mse.sqrt(),
            reduction: 1.0 - cv.mse / current.mse,
            blocks_improved: (0..k)
                .filter(|&f| cv.block_sse[f] < current.block_sse[f])
                .count(),
        })
        .collect()
}

/// Why the best candidate `top` over `k` blocks is not taken, if it is not: it lowers the
/// mean square by less than the settings' minimum, or fewer blocks improve than all but one
/// (with fewer than four blocks, all of them).
fn not_significant(top: &Score, k: usize, settings: &Settings) -> Option<SelectionStop> {
    let needed = if k >= 4 { k - 1 } else { k };
    (top.reduction < settings.min_reduction || top.blocks_improved < needed).then_some({
        SelectionStop::NotSignificant {
            kind: top.kind,
            reduction: top.reduction,
            improved: top.blocks_improved,
            blocks: k,
            min_reduction: settings.min_reduction,
            needed,
        }
    })
}

/// Forward selection with the stopping rule of the module documentation.
pub fn forward_select(
    folds: &Folds,
    model: &Model,
    opts: &Options,
    settings: &Settings,
) -> Result<Selection, IdentError> {
    let k = folds.blocks.len();
    let mut chosen: Vec<usize> = vec![];
    let mut current = folds.cv(model, &chosen, opts)?;
    let nominal_cv_rms = current.mse.sqrt();
    let mut steps = vec![];
    let stop = loop {
        if steps.len() >= settings.max_effects {
            break SelectionStop::MaxEffects(settings.max_effects);
        }
        let used: Vec<Kind> = chosen
            .iter()
            .map(|&v| folds.variants[v].kind)
            .chain(steps.iter().flat_map(|s: &Step| s.ambiguous_with.clone()))
            .collect();
        let mut best = best_per_kind(folds, model, opts, &chosen, &used);
        if best.is_empty() {
            break SelectionStop::NoCandidate;
        }
        best.sort_by(|a, b| a.1.mse.total_cmp(&b.1.mse));
        let scores = scored(folds, &best, &current);
        if let Some(stop) = not_significant(&scores[0], k, settings) {
            break stop;
        }
        let (keep, ambiguous_with, also_fit) = resolve_ties(folds, &best, &scores, settings.tie);
        let (vi, cv) = best[keep].clone();
        let step = Step {
            kind: folds.variants[vi].kind,
            param: folds.variants[vi].param,
            cv_rms_before: current.mse.sqrt(),
            cv_rms_after: cv.mse.sqrt(),
            reduction: 1.0 - cv.mse / current.mse,
            ambiguous_with,
            also_fit,
            scores,
        };
        chosen.push(vi);
        current = cv;
        steps.push(step);
    };
    Ok(Selection {
        blocks: k,
        by_run: folds.by_run,
        nominal_cv_rms,
        steps,
        stop,
        chosen,
        final_cv: Some(current),
    })
}

#[cfg(test)]
mod stop_tests {
    use super::*;

    #[test]
    fn a_stop_reads_and_serializes_as_its_sentence() {
        let stop = SelectionStop::NotSignificant {
            kind: Kind::Cogging,
            reduction: 0.0104,
            improved: 3,
            blocks: 5,
            min_reduction: 0.03,
            needed: 4,
        };
        let text = "best remaining candidate cogging lowers the cross-validated error by 1.0 % in 3/5 blocks (needs 3.0 % in 4/5)";
        assert_eq!(stop.to_string(), text);
        assert_eq!(serde_json::to_string(&stop).unwrap(), format!("\"{text}\""));
        assert_eq!(
            serde_json::to_string(&SelectionStop::MaxEffects(3)).unwrap(),
            "\"reached the maximum of 3 effects\""
        );
    }
}
