//! `physid.experiment`: the sample-size experiment of a scenario (`physid experiment`).

use crate::convert::*;
use crate::errors::*;
use crate::work::*;
use physid::api;
use pyo3::prelude::*;
use std::path::PathBuf;

/// The sample-size experiment of a scenario (`physid experiment`): every (seed, n_s,
/// constraint set) cell; `rows()` and `summary()` are the CLI's `rows.csv` and `summary.csv`
/// as pandas DataFrames.
#[pyclass(frozen, module = "physid")]
#[derive(serde::Serialize, serde::Deserialize)]
pub(crate) struct Experiment {
    run: api::experiment::ExperimentRun,
    seconds: f64,
}

impl Experiment {
    /// The long table (or, with `summary`, its summary over seeds) as CSV text.
    fn csv(&self, summary: bool) -> Result<String, String> {
        self.run.csv(summary).map_err(|e| e.to_string())
    }
}

#[pymethods]
impl Experiment {
    /// Pickles (and copies) as its state in physid's binary form.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<crate::pickle::Reduced<'py>> {
        crate::pickle::reduce(py, "Experiment", self)
    }

    /// The notebook's view: the cells run and the summary over seeds (summary.csv).
    fn _repr_html_(&self) -> PyResult<String> {
        let summary = self.csv(true).map_err(exception)?;
        Ok(crate::notebook::card(
            "Sample-size experiment",
            &[
                ("cells", self.run.rows.len().to_string()),
                ("constraint sets", self.run.sets.join(", ")),
                ("seconds", crate::notebook::number(self.seconds)),
            ],
            &[(
                "median and quartiles over seeds",
                crate::notebook::csv_table(&summary),
            )],
        ))
    }

    /// One row per (seed, n_s, constraint set): validation and training RMS (N m), parameter
    /// errors against the truth, consistency, solver status and time (the CLI's rows.csv).
    #[pyo3(signature = (backend = "pandas"))]
    fn rows<'py>(&self, py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyAny>> {
        table_of(py, self.csv(false), backend)
    }

    /// Median and quartiles over seeds per n_s × constraint set (the CLI's summary.csv).
    #[pyo3(signature = (backend = "pandas"))]
    fn summary<'py>(&self, py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyAny>> {
        table_of(py, self.csv(true), backend)
    }

    /// The constraint sets compared, loosest first.
    #[getter]
    fn constraints(&self) -> Vec<String> {
        self.run.sets.clone()
    }

    /// Wall time of the run (s).
    #[getter]
    fn seconds(&self) -> f64 {
        self.seconds
    }

    fn __repr__(&self) -> String {
        format!(
            "Experiment({} cells, constraint sets {}, {:.1} s)",
            self.run.rows.len(),
            self.run.sets.join(", "),
            self.seconds
        )
    }
}

/// Runs the sample-size experiment of a scenario file (its `[experiment]` table) as
/// `physid experiment` does, seeds in parallel on `threads` workers (default: all cores; the
/// results do not depend on it); `seeds` overrides the scenario's count. `progress`, if given,
/// is called with (seeds done, seeds). Ctrl-C interrupts it.
#[doc = include_str!("../keywords/experiment.txt")]
#[pyfunction]
#[pyo3(signature = (scenario, *, seeds = None, threads = None, progress = None))]
pub(crate) fn experiment(
    py: Python<'_>,
    scenario: PathBuf,
    seeds: Option<usize>,
    threads: Option<usize>,
    progress: Option<PyObject>,
) -> PyResult<Experiment> {
    let pool = thread_pool(threads)?;
    let start = std::time::Instant::now();
    let work = move |_: Cancel, progress: Progress<usize>| {
        let report = |_done: usize, total: usize| {
            let _ = progress.send(total);
        };
        pool.install(|| api::experiment::run_scenario(&scenario, seeds, &report))
    };
    // Seeds finish on the pool's threads in any order: counted here, so the callback sees
    // 1, 2, … of the total in order, on the calling thread.
    let mut done = 0;
    let run = reporting(py, work, |py, total: usize| {
        done += 1;
        match &progress {
            Some(cb) => cb.call1(py, (done, total)).map(drop),
            None => Ok(()),
        }
    })?
    .map_err(api_error)?;
    Ok(Experiment {
        run,
        seconds: start.elapsed().as_secs_f64(),
    })
}
