//! `physid.sweep`: a parameter sweep, resumable and shardable (`physid sweep`).

use crate::convert::*;
use crate::errors::*;
use crate::work::*;
use physid::api;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// A parameter sweep's result (`physid sweep`): its folder, what ran, and once every cell is
/// there the merged tables (`rows()`, `summary()` as pandas DataFrames, `markdown`).
#[pyclass(frozen, module = "physid")]
#[derive(serde::Serialize, serde::Deserialize)]
pub(crate) struct Sweep {
    out: PathBuf,
    cells: usize,
    mine: usize,
    ran: usize,
    missing: usize,
    stale: usize,
    tables: Option<(String, String, String)>,
}

#[pymethods]
impl Sweep {
    /// Pickles (and copies) as its state in physid's binary form.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<crate::pickle::Reduced<'py>> {
        crate::pickle::reduce(py, "Sweep", self)
    }

    /// The notebook's view: the cells, and once merged the summary (summary.csv).
    fn _repr_html_(&self) -> String {
        let tables = match &self.tables {
            Some((_, summary, _)) => {
                vec![("summary over seeds", crate::notebook::csv_table(summary))]
            }
            None => vec![],
        };
        crate::notebook::card(
            &format!("Sweep in {}", self.out.display()),
            &[
                ("cells", self.cells.to_string()),
                ("run now", self.ran.to_string()),
                ("missing (other shards)", self.missing.to_string()),
            ],
            &tables,
        )
    }

    /// The result folder (cells/, and once merged rows.csv, summary.csv/.md/.svg).
    #[getter]
    fn out(&self) -> PathBuf {
        self.out.clone()
    }

    /// Cells of the whole grid, of this shard, run by this call, and still missing (other
    /// shards), as a dict; `stale`: cell files of another configuration, not used.
    #[getter]
    fn cells<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("total", self.cells)?;
        d.set_item("shard", self.mine)?;
        d.set_item("ran", self.ran)?;
        d.set_item("missing", self.missing)?;
        d.set_item("stale", self.stale)?;
        Ok(d)
    }

    /// Every cell is there and the tables are merged.
    #[getter]
    fn merged(&self) -> bool {
        self.tables.is_some()
    }

    /// One row per (grid point, seed, n_s, constraint set): the CLI's rows.csv.
    #[pyo3(signature = (backend = "pandas"))]
    fn rows<'py>(&self, py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyAny>> {
        table_of(py, self.table(0), backend)
    }

    /// Medians and quartiles over seeds per (grid point, n_s, set): summary.csv.
    #[pyo3(signature = (backend = "pandas"))]
    fn summary<'py>(&self, py: Python<'py>, backend: &str) -> PyResult<Bound<'py, PyAny>> {
        table_of(py, self.table(1), backend)
    }

    /// summary.md.
    #[getter]
    fn markdown(&self) -> PyResult<String> {
        self.table(2).map_err(exception)
    }

    fn __repr__(&self) -> String {
        format!(
            "Sweep('{}', {} cells, {} run now, {})",
            self.out.display(),
            self.cells,
            self.ran,
            if self.tables.is_some() {
                "merged".to_string()
            } else {
                format!("{} missing (other shards)", self.missing)
            }
        )
    }
}

impl Sweep {
    fn table(&self, k: usize) -> Result<String, String> {
        let (rows, summary, md) = self.tables.as_ref().ok_or_else(|| {
            format!(
                "{} of {} cells are still missing (other shards): run them, then sweep again without shard to merge",
                self.missing, self.cells
            )
        })?;
        Ok([rows, summary, md][k].clone())
    }
}

/// Runs a parameter sweep (`physid sweep`, docs/sweeps.md): a grid over scenario keys crossed
/// with the constraint sets, written to `out` (default `results/<sweep name>`), resumable
/// (finished cells are skipped) and shardable (`shard=(k, n)`: the cells with index ≡ k mod
/// n); merged once every cell is there. `progress(done, total)` is called after each cell.
/// Ctrl-C stops it: the cells finished stay, none is written after the interrupt and nothing is merged.
#[doc = include_str!("../keywords/sweep.txt")]
#[pyfunction]
#[pyo3(signature = (sweep, *, out = None, shard = None, threads = None, progress = None))]
pub(crate) fn sweep(
    py: Python<'_>,
    sweep: PathBuf,
    out: Option<PathBuf>,
    shard: Option<(usize, usize)>,
    threads: Option<usize>,
    progress: Option<PyObject>,
) -> PyResult<Sweep> {
    let opts = api::sweep::SweepOptions { sweep, out, shard };
    let pool = thread_pool(threads)?;
    let work = move |cancel: Cancel, progress: Progress<usize>| {
        let stop = || is_cancelled(&cancel);
        api::sweep::plan(&opts).and_then(|plan| {
            let total = plan.todo.len();
            let report = || {
                let _ = progress.send(total);
            };
            pool.install(|| plan.run_until(&report, &stop))?;
            if stop() {
                return Err(api::ApiError::Cancelled);
            }
            let merged = plan.merge()?;
            Ok((plan, merged))
        })
    };
    // Cells finish on the pool's threads in any order: counted here, so the callback sees
    // 1, 2, … of the total in order, on the calling thread; an exception in it stops the
    // sweep (no cell written after it, nothing merged) and is raised at once.
    let mut done = 0;
    let result = reporting(py, work, |py, total: usize| {
        done += 1;
        match &progress {
            Some(cb) => cb.call1(py, (done, total)).map(drop),
            None => Ok(()),
        }
    })?;
    let (plan, merged) = result.map_err(api_error)?;
    let tables = match merged {
        None => None,
        Some(mut m) => {
            let csv = |df: &mut polars::prelude::DataFrame| {
                api::experiment::csv_text(df).map_err(exception)
            };
            Some((csv(&mut m.rows)?, csv(&mut m.summary)?, m.markdown))
        }
    };
    Ok(Sweep {
        out: plan.out.clone(),
        cells: plan.cells.len(),
        mine: plan.mine.len(),
        ran: plan.todo.len(),
        missing: plan.missing(),
        stale: plan.stale,
        tables,
    })
}
