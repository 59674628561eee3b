//! Comparing results in CI: a result directory against a baseline (experiment or sweep), or two
//! constraint sets within one run, per grid point, training size `n_s` and set, paired by seed.
//!
//! For each group the statistic is the per-seed ratio `r_i = x_i / y_i` of a metric (default the
//! validation RMS, lower is better) between the candidate `x` and the reference `y`. A group is a
//! **regression** when both hold:
//!
//! - the median ratio exceeds `1 + tolerance` (a difference large enough to matter), and
//! - the one-sided Wilcoxon signed-rank test of `log r_i` (Wilcoxon 1945; exact distribution of
//!   the signed-rank sum, average ranks for ties, zero differences dropped) rejects "no
//!   increase" at level `alpha` (a difference the seeds support).
//!
//! A group needs enough pairs to be able to fail: at least `min_pairs`, and at least the
//! `n` whose smallest exact p-value `2⁻ⁿ` lies below `alpha` ([`CompareOptions::required_pairs`];
//! seven at the default 0.01). With fewer it cannot be judged: the report says so, and the run
//! fails unless `allow_too_few` is set. Non-finite metric values and a comparison that pairs
//! nothing are refused. Rows are read
//! from `rows.parquet` (or `rows.csv`) as `physid experiment` and `physid sweep` write them:
//! the columns before `seed` are grid values, then `seed`, `n_s`, `constraints`, the metrics.

use physid_core::linalg::median;
use physid_io::{md_cell, IoError};
use polars::prelude::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// What a comparison checks.
#[derive(Clone, Debug, PartialEq)]
pub struct CompareOptions {
    /// The metric column (lower is better), e.g. `val_rms` or `j_err`.
    pub metric: String,
    /// Relative tolerance of the median ratio (0.05: 5 % worse is still a pass).
    pub tolerance: f64,
    /// One-sided level of the signed-rank test.
    pub alpha: f64,
    /// Fewest seed pairs a group needs to be able to fail (raised to what `alpha` needs).
    pub min_pairs: usize,
    /// Whether groups with too few pairs to reach `alpha` may pass the run.
    pub allow_too_few: bool,
    /// Only groups with `n_s` at most this (None: all).
    pub max_n_s: Option<u64>,
}

impl Default for CompareOptions {
    fn default() -> Self {
        Self {
            metric: "val_rms".into(),
            tolerance: 0.05,
            alpha: 0.01,
            min_pairs: 6,
            allow_too_few: false,
            max_n_s: None,
        }
    }
}

impl CompareOptions {
    /// Checks every value against its range.
    pub fn validate(&self) -> Result<(), CompareError> {
        let bad = |option, expected, value| CompareError::InvalidOption {
            option,
            expected,
            value,
        };
        if !(self.tolerance.is_finite() && self.tolerance >= 0.0) {
            return Err(bad("tolerance", "a finite fraction >= 0", self.tolerance));
        }
        if !(self.alpha > 0.0 && self.alpha < 1.0) {
            return Err(bad("alpha", "a level in (0, 1)", self.alpha));
        }
        if self.min_pairs < 1 {
            return Err(bad("min_pairs", "at least 1", 0.0));
        }
        if self.max_n_s == Some(0) {
            return Err(bad("max_n_s", "at least 1 sample", 0.0));
        }
        Ok(())
    }

    /// The fewest pairs a group needs to be able to fail: `min_pairs`, raised to the smallest
    /// `n` with `2⁻ⁿ < alpha` (the exact one-sided signed-rank test's smallest p on `n` pairs).
    pub fn required_pairs(&self) -> usize {
        let by_alpha = (1..=64)
            .find(|&n| 0.5f64.powi(n as i32) < self.alpha)
            .unwrap_or(64);
        self.min_pairs.max(by_alpha)
    }
}

/// A comparison could not be made.
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    /// A table could not be read.
    #[error(transparent)]
    Io(#[from] IoError),
    /// A table lacks a column the comparison needs.
    #[error("{path}: no column '{column}' (columns: {columns})")]
    MissingColumn {
        /// The table.
        path: PathBuf,
        /// The column.
        column: String,
        /// The columns it has.
        columns: String,
    },
    /// Nothing to compare.
    #[error("{0}")]
    Nothing(String),
    /// A metric value that is not a finite number.
    #[error(
        "{table}: {metric} = {value} at {group}, seed {seed}: a comparison needs finite values above 0 (it judges the ratio of the two)"
    )]
    NonFinite {
        /// Which table: the candidate or the reference.
        table: &'static str,
        /// The metric.
        metric: String,
        /// The group, in words.
        group: String,
        /// The seed.
        seed: i64,
        /// The value.
        value: f64,
    },
    /// An option value out of its range.
    #[error("{option} must be {expected}, got {value}")]
    InvalidOption {
        /// The option.
        option: &'static str,
        /// Its valid range.
        expected: &'static str,
        /// The value given.
        value: f64,
    },
}

physid_core::options::option_error!(CompareError);

/// One row of a results table, reduced to what a comparison needs.
#[derive(Clone, Debug)]
struct Sample {
    /// Grid values (`key=value`), `n_s` and the set.
    group: Group,
    seed: i64,
    value: f64,
}

/// A group: the grid point, `n_s`, and the constraint set.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Group {
    point: Vec<String>,
    n_s: u64,
    set: String,
}

/// The verdict of one group.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// Not worse by more than the tolerance, or not significantly.
    Pass,
    /// Worse by more than the tolerance, significantly.
    Regression,
    /// Too few pairs to decide.
    TooFewPairs,
}

/// One compared group.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct GroupResult {
    /// Grid point (`key=value` pairs; empty for an experiment).
    pub point: Vec<String>,
    /// Training samples.
    pub n_s: u64,
    /// The candidate's constraint set (and the reference's, for variants).
    pub set: String,
    /// Seed pairs.
    pub pairs: usize,
    /// Median of the metric, reference and candidate.
    pub reference_median: f64,
    /// Median of the candidate.
    pub candidate_median: f64,
    /// Median per-seed ratio candidate / reference.
    pub median_ratio: f64,
    /// One-sided p-value of "the candidate is not larger".
    pub p_value: f64,
    /// The verdict.
    pub outcome: Outcome,
}

/// A whole comparison.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Comparison {
    /// What was compared, in words.
    pub title: String,
    /// The metric.
    pub metric: String,
    /// Tolerance and level.
    pub tolerance: f64,
    /// One-sided level.
    pub alpha: f64,
    /// Every group.
    pub groups: Vec<GroupResult>,
}

impl Comparison {
    /// Groups with too few pairs to be judged.
    pub fn too_few(&self) -> usize {
        self.groups
            .iter()
            .filter(|g| g.outcome == Outcome::TooFewPairs)
            .count()
    }

    /// Groups that regressed.
    pub fn regressions(&self) -> usize {
        self.groups
            .iter()
            .filter(|g| g.outcome == Outcome::Regression)
            .count()
    }
}

/// The rows table in `dir` (`rows.parquet`, else `rows.csv`).
fn rows_table(dir: &Path) -> Result<(PathBuf, DataFrame), CompareError> {
    let parquet = dir.join("rows.parquet");
    if parquet.exists() {
        return Ok((parquet.clone(), super::tables::read_parquet(&parquet)?));
    }
    let csv = dir.join("rows.csv");
    let df = CsvReadOptions::default()
        .with_has_header(true)
        .try_into_reader_with_file_path(Some(csv.clone()))
        .and_then(|r| r.finish())
        .map_err(|e| IoError::Invalid {
            path: csv.clone(),
            message: format!("reading table: {e} (expected rows.parquet or rows.csv of physid experiment or sweep)"),
        })?;
    Ok((csv, df))
}

/// Row `i`'s grid point: `key=value` for each grid column (as text).
fn point_of(grid: &[(String, Column)], i: usize) -> Vec<String> {
    grid.iter()
        .map(|(k, col)| {
            let v = col.str().ok().and_then(|c| c.get(i)).unwrap_or("");
            format!("{k}={v}")
        })
        .collect()
}

/// The samples of `metric` in the rows table of `dir`, each column read strictly (a word among
/// the metric's numbers is an error, not a row dropped).
fn samples(dir: &Path, metric: &str) -> Result<Vec<Sample>, CompareError> {
    let (path, df) = rows_table(dir)?;
    let names: Vec<String> = df
        .get_column_names()
        .iter()
        .map(|s| s.to_string())
        .collect();
    let invalid = |c: &str, e: PolarsError| IoError::Invalid {
        path: path.clone(),
        message: format!("column '{c}': {e}"),
    };
    let cast = |c: &str, t: &DataType| -> Result<Column, CompareError> {
        let column = df.column(c).map_err(|_| CompareError::MissingColumn {
            path: path.clone(),
            column: c.into(),
            columns: names.join(", "),
        })?;
        Ok(column.strict_cast(t).map_err(|e| invalid(c, e))?)
    };
    let seed = check_whole_seeds(&df, &path).and_then(|_| cast("seed", &DataType::Int64))?;
    let n_s = cast("n_s", &DataType::UInt64)?;
    let set = cast("constraints", &DataType::String)?;
    let value = cast(metric, &DataType::Float64)?;
    let grid: Vec<(String, Column)> = names
        .iter()
        .take_while(|n| *n != "seed")
        .map(|n| Ok((n.clone(), cast(n, &DataType::String)?)))
        .collect::<Result<_, CompareError>>()?;
    let (seed, n_s, set, value) = (
        seed.i64().map_err(|e| invalid("seed", e))?,
        n_s.u64().map_err(|e| invalid("n_s", e))?,
        set.str().map_err(|e| invalid("constraints", e))?,
        value.f64().map_err(|e| invalid(metric, e))?,
    );
    let mut out = vec![];
    for i in 0..df.height() {
        let (Some(s), Some(n), Some(c), Some(v)) =
            (seed.get(i), n_s.get(i), set.get(i), value.get(i))
        else {
            continue;
        };
        out.push(Sample {
            group: Group {
                point: point_of(&grid, i),
                n_s: n,
                set: c.to_string(),
            },
            seed: s,
            value: v,
        });
    }
    if out.is_empty() {
        return Err(CompareError::Nothing(format!(
            "{}: no rows with a seed, n_s, constraints and {metric}",
            path.display()
        )));
    }
    check_once(&path, &out)?;
    Ok(out)
}

/// Seeds are whole numbers: a seed `3.5` would be read as seed 3 and paired with it.
fn check_whole_seeds(df: &DataFrame, path: &Path) -> Result<(), CompareError> {
    let Ok(seed) = df.column("seed") else {
        return Ok(());
    };
    if !seed.dtype().is_float() {
        return Ok(());
    }
    let values = seed.f64().map_err(|e| IoError::Invalid {
        path: path.to_path_buf(),
        message: format!("column 'seed': {e}"),
    })?;
    let fractional =
        (0..values.len()).find_map(|i| values.get(i).filter(|v| v.fract() != 0.0).map(|v| (i, v)));
    match fractional {
        Some((row, v)) => Err(CompareError::Nothing(format!(
            "{}: column 'seed' holds {v} in data row {row} (counting from 0): seeds are whole numbers",
            path.display()
        ))),
        None => Ok(()),
    }
}

/// Each (grid point, `n_s`, constraint set, seed) once in the table at `path`: a repeated row
/// would make the verdict depend on which copy is read last.
fn check_once(path: &Path, samples: &[Sample]) -> Result<(), CompareError> {
    let mut seen = std::collections::BTreeMap::new();
    for (row, s) in samples.iter().enumerate() {
        if let Some(first) = seen.insert((&s.group, s.seed), row) {
            return Err(CompareError::Nothing(format!(
                "{}: rows {first} and {row} (counting data rows from 0) are both seed {}, n_s {}, {}{}: a table holds each seed of a group once (concatenated runs?)",
                path.display(),
                s.seed,
                s.group.n_s,
                s.group.set,
                if s.group.point.is_empty() { String::new() } else { format!(" at {}", s.group.point.join(", ")) }
            )));
        }
    }
    Ok(())
}

/// `P(W⁺ ≥ w)` for the signed-rank sum of `ranks` (each rank times two, so that average ranks
/// of ties are integers) under the null (every sign equally likely): exact, by counting the
/// sign patterns per sum.
fn signed_rank_upper_p(ranks2: &[u64], w2: u64) -> f64 {
    let total: u64 = ranks2.iter().sum();
    let mut counts = vec![0f64; total as usize + 1];
    counts[0] = 1.0;
    let mut reach = 0usize;
    for &r in ranks2 {
        let r = r as usize;
        for s in (0..=reach).rev() {
            if counts[s] > 0.0 {
                counts[s + r] += counts[s];
            }
        }
        reach += r;
    }
    let all: f64 = counts.iter().sum();
    counts[w2.min(total) as usize..].iter().sum::<f64>() / all
}

/// One-sided Wilcoxon signed-rank p-value that the differences `d` are not shifted upwards
/// (zeros dropped, average ranks for ties of `|d|`); 1 without nonzero differences.
pub fn wilcoxon_upper_p(d: &[f64]) -> f64 {
    let mut nz: Vec<f64> = d.iter().copied().filter(|x| *x != 0.0).collect();
    if nz.is_empty() {
        return 1.0;
    }
    nz.sort_by(|a, b| a.abs().total_cmp(&b.abs()));
    // Twice the average rank of each tie group of |d|.
    let mut ranks2 = vec![0u64; nz.len()];
    let mut i = 0;
    while i < nz.len() {
        let mut j = i;
        while j + 1 < nz.len() && nz[j + 1].abs() == nz[i].abs() {
            j += 1;
        }
        let twice_avg = (i + 1 + j + 1) as u64; // (first + last rank), 1-based
        for r in ranks2.iter_mut().take(j + 1).skip(i) {
            *r = twice_avg;
        }
        i = j + 1;
    }
    let w2: u64 = nz
        .iter()
        .zip(&ranks2)
        .filter(|(x, _)| **x > 0.0)
        .map(|(_, r)| *r)
        .sum();
    signed_rank_upper_p(&ranks2, w2)
}

/// Compares paired values (candidate, reference) of one group.
fn judge(pairs: &[(f64, f64)], opts: &CompareOptions) -> (f64, f64, f64, f64, Outcome) {
    let x: Vec<f64> = pairs.iter().map(|p| p.0).collect();
    let y: Vec<f64> = pairs.iter().map(|p| p.1).collect();
    let logs: Vec<f64> = pairs
        .iter()
        .map(|(a, b)| (a / b).ln())
        .filter(|l| l.is_finite())
        .collect();
    let ratios: Vec<f64> = logs.iter().map(|l| l.exp()).collect();
    let ratio = median(&ratios);
    let p = wilcoxon_upper_p(&logs);
    let outcome = if logs.len() < opts.required_pairs() {
        Outcome::TooFewPairs
    } else if ratio > 1.0 + opts.tolerance && p < opts.alpha {
        Outcome::Regression
    } else {
        Outcome::Pass
    };
    (median(&y), median(&x), ratio, p, outcome)
}

/// The two sets `variants` compares are two, and both in the rows.
fn check_variants(
    dir: &Path,
    rows: &[Sample],
    better: &str,
    reference: &str,
) -> Result<(), CompareError> {
    let nothing = |m: String| Err(CompareError::Nothing(format!("{}: {m}", dir.display())));
    if better == reference {
        return nothing(format!(
            "--variant {better}<={reference} compares a set with itself: give two sets"
        ));
    }
    let mut sets: Vec<&str> = rows.iter().map(|s| s.group.set.as_str()).collect();
    sets.sort_unstable();
    sets.dedup();
    match [better, reference].into_iter().find(|v| !sets.contains(v)) {
        Some(missing) => nothing(format!(
            "no rows of the set '{missing}' (the rows' sets: {})",
            sets.join(", ")
        )),
        None => Ok(()),
    }
}

/// Per seed: the candidate's and the reference's value.
type BySeed = BTreeMap<i64, (Option<f64>, Option<f64>)>;

/// The result of one group from its values per seed.
fn group_result(
    point: Vec<String>,
    n_s: u64,
    set: String,
    seeds: &BySeed,
    opts: &CompareOptions,
) -> Result<GroupResult, CompareError> {
    for (&seed, (a, b)) in seeds {
        for (table, v) in [("candidate", a), ("reference", b)] {
            if let Some(v) = v.filter(|v| !(v.is_finite() && *v > 0.0)) {
                return Err(CompareError::NonFinite {
                    table,
                    metric: opts.metric.clone(),
                    group: format!("{} n_s={n_s} {set}", point.join(","))
                        .trim()
                        .to_string(),
                    seed,
                    value: v,
                });
            }
        }
    }
    let pairs: Vec<(f64, f64)> = seeds
        .values()
        .filter_map(|(a, b)| Some(((*a)?, (*b)?)))
        .collect();
    let (reference_median, candidate_median, median_ratio, p_value, outcome) = judge(&pairs, opts);
    Ok(GroupResult {
        point,
        n_s,
        set,
        pairs: pairs.len(),
        reference_median,
        candidate_median,
        median_ratio,
        p_value,
        outcome,
    })
}

/// The groups, refused when none pairs a candidate row with a reference row (results of
/// different kinds, or of disjoint seeds).
fn paired(groups: Vec<GroupResult>, what: &str) -> Result<Vec<GroupResult>, CompareError> {
    if groups.iter().all(|g| g.pairs == 0) {
        return Err(CompareError::Nothing(format!(
            "{what}: no group pairs a candidate row with a reference row (the same grid point, n_s, set and seed): results of different kinds (an experiment against a sweep) or of disjoint seeds cannot be compared"
        )));
    }
    Ok(groups)
}

fn in_scope(g: &Group, opts: &CompareOptions) -> bool {
    opts.max_n_s.is_none_or(|m| g.n_s <= m)
}

/// (a) The results in `candidate` against those in `baseline`: every group of the baseline,
/// paired by seed.
pub fn against_baseline(
    candidate: &Path,
    baseline: &Path,
    opts: &CompareOptions,
) -> Result<Comparison, CompareError> {
    opts.validate()?;
    let (cand, base) = (
        samples(candidate, &opts.metric)?,
        samples(baseline, &opts.metric)?,
    );
    let mut by: BTreeMap<Group, BySeed> = BTreeMap::new();
    for s in &cand {
        by.entry(s.group.clone())
            .or_default()
            .entry(s.seed)
            .or_default()
            .0 = Some(s.value);
    }
    for s in &base {
        by.entry(s.group.clone())
            .or_default()
            .entry(s.seed)
            .or_default()
            .1 = Some(s.value);
    }
    let groups = by
        .into_iter()
        .filter(|(g, _)| in_scope(g, opts))
        .map(|(g, seeds)| group_result(g.point, g.n_s, g.set, &seeds, opts))
        .collect::<Result<Vec<_>, _>>()?;
    let groups = paired(
        groups,
        &format!("{} against {}", candidate.display(), baseline.display()),
    )?;
    Ok(Comparison {
        title: format!(
            "{} against the baseline {}",
            candidate.display(),
            baseline.display()
        ),
        metric: opts.metric.clone(),
        tolerance: opts.tolerance,
        alpha: opts.alpha,
        groups,
    })
}

/// (b) Constraint set `better` against `reference` within the results in `dir` ("`better` is
/// no worse than `reference`"), per grid point and `n_s`, paired by seed.
pub fn variants(
    dir: &Path,
    better: &str,
    reference: &str,
    opts: &CompareOptions,
) -> Result<Comparison, CompareError> {
    opts.validate()?;
    let rows = samples(dir, &opts.metric)?;
    check_variants(dir, &rows, better, reference)?;
    let mut by: BTreeMap<(Vec<String>, u64), BySeed> = BTreeMap::new();
    for s in &rows {
        let slot = if s.group.set == better {
            0
        } else if s.group.set == reference {
            1
        } else {
            continue;
        };
        if !in_scope(&s.group, opts) {
            continue;
        }
        let e = by
            .entry((s.group.point.clone(), s.group.n_s))
            .or_default()
            .entry(s.seed)
            .or_default();
        if slot == 0 {
            e.0 = Some(s.value);
        } else {
            e.1 = Some(s.value);
        }
    }
    if by.is_empty() {
        return Err(CompareError::Nothing(format!(
            "{}: no rows of the sets '{better}' and '{reference}'",
            dir.display()
        )));
    }
    let groups = by
        .into_iter()
        .map(|((point, n_s), seeds)| {
            group_result(point, n_s, format!("{better} vs {reference}"), &seeds, opts)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let groups = paired(groups, &dir.display().to_string())?;
    Ok(Comparison {
        title: format!("{better} <= {reference} in {}", dir.display()),
        metric: opts.metric.clone(),
        tolerance: opts.tolerance,
        alpha: opts.alpha,
        groups,
    })
}

impl Comparison {
    /// A Markdown report (a heading, the rule, one table row per group, regressions first).
    pub fn markdown(&self) -> String {
        let regressions = self.regressions();
        let mut s = format!(
            "## physid compare: {}\n\n**{}**: {} of {} groups regressed. Metric `{}` (lower is better); a group regresses when the median per-seed ratio exceeds {:.3} and the one-sided Wilcoxon signed-rank test of the log ratios gives p < {}.\n\n",
            md_cell(&self.title),
            if regressions == 0 { "PASS" } else { "FAIL" },
            regressions,
            self.groups.len(),
            self.metric,
            1.0 + self.tolerance,
            self.alpha
        );
        s += "| outcome | grid point | n_s | sets | pairs | reference median | candidate median | median ratio | p |\n|---|---|---|---|---|---|---|---|---|\n";
        let mut order: Vec<&GroupResult> = self.groups.iter().collect();
        order.sort_by_key(|g| g.outcome != Outcome::Regression);
        for g in order {
            s += &format!(
                "| {} | {} | {} | {} | {} | {:.4} | {:.4} | {:.3} | {:.2e} |\n",
                match g.outcome {
                    Outcome::Pass => "pass",
                    Outcome::Regression => "**regression**",
                    Outcome::TooFewPairs => "cannot reach alpha with these pairs",
                },
                if g.point.is_empty() {
                    "-".to_string()
                } else {
                    md_cell(&g.point.join(", "))
                },
                g.n_s,
                md_cell(&g.set),
                g.pairs,
                g.reference_median,
                g.candidate_median,
                g.median_ratio,
                g.p_value
            );
        }
        s
    }

    /// JUnit XML: one test case per group, a `<failure>` for each regression.
    pub fn junit(&self) -> String {
        let esc = |s: &str| {
            s.replace('&', "&amp;")
                .replace('<', "&lt;")
                .replace('>', "&gt;")
                .replace('"', "&quot;")
        };
        let mut s = format!(
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites>\n<testsuite name=\"physid compare\" tests=\"{}\" failures=\"{}\">\n",
            self.groups.len(),
            self.regressions()
        );
        for g in &self.groups {
            let name = format!("{} n_s={} {}", g.point.join(","), g.n_s, g.set);
            s += &format!(
                "<testcase classname=\"{}\" name=\"{}\">",
                esc(&self.metric),
                esc(name.trim())
            );
            match g.outcome {
                Outcome::Regression => {
                    s += &format!(
                        "<failure message=\"median ratio {:.3} &gt; {:.3}, p = {:.2e}\">reference median {:.4}, candidate median {:.4}, {} pairs</failure>",
                        g.median_ratio,
                        1.0 + self.tolerance,
                        g.p_value,
                        g.reference_median,
                        g.candidate_median,
                        g.pairs
                    )
                }
                Outcome::TooFewPairs => {
                    s += &format!(
                        "<skipped message=\"{} pairs cannot reach alpha = {}\"/>",
                        g.pairs, self.alpha
                    )
                }
                Outcome::Pass => {}
            }
            s += "</testcase>\n";
        }
        s += "</testsuite>\n</testsuites>\n";
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signed_rank_p_values_match_the_tables() {
        // n = 10 without ties: P(W+ <= 10) = 0.0420 (Wilcoxon's tables); by symmetry
        // P(W+ >= 55 - 10) is the same.
        let ranks2: Vec<u64> = (1..=10).map(|r| 2 * r).collect();
        let p = signed_rank_upper_p(&ranks2, 2 * 45);
        assert!((p - 0.0420).abs() < 5e-4, "{p}");
        // All positive of n = 8: 1/256.
        let d: Vec<f64> = (1..=8).map(|i| i as f64).collect();
        assert!((wilcoxon_upper_p(&d) - 1.0 / 256.0).abs() < 1e-12);
        // Symmetric differences give p > 0.5; zeros only give 1.
        assert!(wilcoxon_upper_p(&[1.0, -1.0, 2.0, -2.0]) > 0.5);
        assert_eq!(wilcoxon_upper_p(&[0.0, 0.0]), 1.0);
        // Ties get average ranks: |d| = 1, 1, 2 -> ranks 1.5, 1.5, 3.
        let p = wilcoxon_upper_p(&[1.0, -1.0, 2.0]);
        // W+ = 4.5 of 6; of the 8 sign patterns, sums >= 4.5: 1.5 + 3 (twice) and 6.
        assert!((p - 3.0 / 8.0).abs() < 1e-12, "{p}");
    }

    #[test]
    fn a_clear_increase_regresses_and_noise_does_not() {
        let opts = CompareOptions::default();
        let worse: Vec<(f64, f64)> = (0..8).map(|i| (1.3 + 0.01 * i as f64, 1.0)).collect();
        assert_eq!(judge(&worse, &opts).4, Outcome::Regression);
        let same: Vec<(f64, f64)> = (0..8)
            .map(|i| (1.0 + if i % 2 == 0 { 0.2 } else { -0.2 }, 1.0))
            .collect();
        assert_eq!(judge(&same, &opts).4, Outcome::Pass);
        assert_eq!(judge(&worse[..3], &opts).4, Outcome::TooFewPairs);
        // Six pairs, every one worse: the smallest exact p is 1/64 > 0.01, so six pairs cannot
        // fail at the default level and count as too few; seven can.
        assert_eq!(opts.required_pairs(), 7);
        assert!(wilcoxon_upper_p(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]) > opts.alpha);
        assert_eq!(judge(&worse[..6], &opts).4, Outcome::TooFewPairs);
        assert_eq!(judge(&worse[..7], &opts).4, Outcome::Regression);
        let loose = CompareOptions {
            alpha: 0.05,
            min_pairs: 1,
            ..opts
        };
        assert_eq!(loose.required_pairs(), 5);
    }
}
