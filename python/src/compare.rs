//! `physid.compare`: experiment and sweep results compared (`physid compare`).

use crate::convert::*;
use crate::errors::*;
use physid::api;
use pyo3::prelude::*;
use std::path::PathBuf;

/// A comparison of experiment or sweep results (`physid compare`): per group (grid point, n_s,
/// constraint set) the paired seeds' medians, ratio, one-sided p-value and outcome.
#[pyclass(frozen, module = "physid")]
#[derive(serde::Serialize, serde::Deserialize)]
pub(crate) struct Comparison {
    cmp: api::compare::Comparison,
}

#[pymethods]
impl Comparison {
    /// Pickles (and copies) as its state in physid's binary form.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<crate::pickle::Reduced<'py>> {
        crate::pickle::reduce(py, "Comparison", self)
    }

    /// The notebook's view: the verdict counts and every group's test.
    fn _repr_html_(&self) -> String {
        use crate::notebook::{card, number, table};
        let rows: Vec<Vec<String>> = (self.cmp.groups.iter())
            .map(|g| {
                vec![
                    g.point.join(" "),
                    g.n_s.to_string(),
                    g.set.clone(),
                    g.pairs.to_string(),
                    number(g.reference_median),
                    number(g.candidate_median),
                    number(g.median_ratio),
                    number(g.p_value),
                    api::files::serde_name(&g.outcome),
                ]
            })
            .collect();
        let header = [
            "point",
            "n_s",
            "set",
            "pairs",
            "reference median",
            "candidate median",
            "ratio",
            "p",
            "outcome",
        ];
        card(
            &format!("Comparison: {}", self.cmp.title),
            &[
                ("groups", self.cmp.groups.len().to_string()),
                ("regressions", self.cmp.regressions().to_string()),
                ("too few pairs", self.cmp.too_few().to_string()),
            ],
            &[("groups", table(&header, &rows))],
        )
    }

    /// Groups that regressed.
    #[getter]
    fn regressions(&self) -> usize {
        self.cmp.regressions()
    }

    /// Groups with too few seed pairs to be judged.
    #[getter]
    fn too_few(&self) -> usize {
        self.cmp.too_few()
    }

    /// Every group as a pandas DataFrame: point, n_s, set, pairs, reference_median,
    /// candidate_median, median_ratio, p_value, outcome.
    #[pyo3(signature = (backend = "pandas"))]
    fn groups<'py>(&self, py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyAny>> {
        frame(py, plain(py, &self.cmp.groups)?, backend)
    }

    /// The comparison as `physid compare` prints it (Markdown).
    fn markdown(&self) -> String {
        self.cmp.markdown()
    }

    /// The comparison as a JUnit XML report (`physid compare --junit`).
    fn junit(&self) -> String {
        self.cmp.junit()
    }

    /// The comparison as a dict (title, metric, tolerance, alpha, groups).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        plain(py, &self.cmp)
    }

    fn __repr__(&self) -> String {
        format!(
            "Comparison('{}', {} groups, {} regressions, {} with too few pairs)",
            self.cmp.title,
            self.cmp.groups.len(),
            self.cmp.regressions(),
            self.cmp.too_few()
        )
    }
}

/// Compares experiment or sweep results as `physid compare` does: `result` (a results folder)
/// against `baseline` (another), or two constraint sets within it with `variant="A<=B"` ("A is
/// no worse than B"); `metric`, `tolerance`, `alpha`, `min_pairs`, `allow_too_few`, `max_n_s` as
/// its flags (defaults: val_rms, 0.05, 0.01, 6).
#[doc = include_str!("../keywords/compare.txt")]
#[pyfunction]
#[pyo3(signature = (result, *, baseline = None, variant = None, metric = None, tolerance = None,
    alpha = None, min_pairs = None, allow_too_few = false, max_n_s = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn compare(
    py: Python<'_>,
    result: PathBuf,
    baseline: Option<PathBuf>,
    variant: Option<String>,
    metric: Option<String>,
    tolerance: Option<f64>,
    alpha: Option<f64>,
    min_pairs: Option<usize>,
    allow_too_few: bool,
    max_n_s: Option<u64>,
) -> PyResult<Comparison> {
    use api::compare::{self, CompareOptions};
    let d = CompareOptions::default();
    let opts = CompareOptions {
        metric: metric.unwrap_or(d.metric),
        tolerance: tolerance.unwrap_or(d.tolerance),
        alpha: alpha.unwrap_or(d.alpha),
        min_pairs: min_pairs.unwrap_or(d.min_pairs),
        allow_too_few,
        max_n_s,
    };
    opts.validate().map_err(api_error)?;
    let cmp = match (&baseline, &variant) {
        (Some(_), Some(_)) => {
            return Err(exception("give baseline or variant, not both"));
        }
        (Some(b), None) => py
            .allow_threads(|| compare::against_baseline(&result, b, &opts))
            .map_err(api_error)?,
        (None, Some(v)) => {
            let Some((better, reference)) = v.split_once("<=") else {
                return Err(exception(format!(
                    "--variant '{v}': give two constraint sets as A<=B, e.g. ellipsoid<=consistent"
                )));
            };
            py.allow_threads(|| compare::variants(&result, better.trim(), reference.trim(), &opts))
                .map_err(api_error)?
        }
        (None, None) => return Err(exception("give baseline=DIR or variant=\"A<=B\"")),
    };
    Ok(Comparison { cmp })
}
