//! `sweep`: a parameter grid over scenario keys (docs/sweeps.md) crossed with the constraint
//! sets, in three steps the caller can report between: [`plan`] resolves and checks every
//! grid point and sees which cells earlier runs finished; [`SweepPlan::run`] runs the rest (in
//! the current rayon pool, each cell written whole as it finishes, so a killed run resumes);
//! [`SweepPlan::merge`] joins the cells into the tables once every shard's cells are there.

use super::ApiError;
use crate::experiment::sweep::{self, Cell, SweepSpec};
use crate::experiment::tables;
use polars::prelude::DataFrame;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// A sweep's settings (the CLI's).
#[derive(Clone, Debug, Default)]
pub struct SweepOptions {
    /// The sweep file (TOML).
    pub sweep: PathBuf,
    /// The result folder (none: `results/<sweep file name>`).
    pub out: Option<PathBuf>,
    /// Run only the cells with index ≡ k (mod n): `(k, n)`, `0 <= k < n`.
    pub shard: Option<(usize, usize)>,
}

impl SweepOptions {
    /// The shard, if any, is one of its `n`.
    pub fn validate(&self) -> Result<(), ApiError> {
        match self.shard {
            Some((k, n)) if n == 0 || k >= n => Err(ApiError::Options(format!(
                "--shard {k}/{n}: need 0 <= K < N"
            ))),
            _ => Ok(()),
        }
    }

    /// Where the results go.
    pub fn out_dir(&self) -> PathBuf {
        self.out.clone().unwrap_or_else(|| {
            PathBuf::from("results").join(self.sweep.file_stem().unwrap_or_default())
        })
    }
}

/// A sweep resolved: every cell, which are this shard's, which of those are still to run.
pub struct SweepPlan {
    /// The sweep file.
    pub path: PathBuf,
    /// The result folder.
    pub out: PathBuf,
    spec: SweepSpec,
    scenario_path: PathBuf,
    base: String,
    /// Every cell of the grid (all shards).
    pub cells: Vec<Cell>,
    /// Indices into `cells` of this shard's cells.
    pub mine: Vec<usize>,
    /// Indices into `cells` of this shard's cells not finished by an earlier run.
    pub todo: Vec<usize>,
    /// Cell files of another configuration (changed sweep, scenario, robot or physid
    /// version), not used.
    pub stale: usize,
    joints: Vec<String>,
}

/// Reads and checks the sweep, resolves every grid point (a bad value fails here, naming it,
/// before anything is created), creates the result folder and removes what killed runs left.
pub fn plan(opts: &SweepOptions) -> Result<SweepPlan, ApiError> {
    opts.validate()?;
    let path = opts.sweep.as_path();
    let (spec, scenario_path, base) = sweep::load(path)?;
    spec.experiment
        .validate()
        .map_err(|e| ApiError::invalid(path, e.to_string()))?;
    let out = opts.out_dir();
    let inputs: Vec<PathBuf> = crate::io::scenario_files(&scenario_path)
        .into_iter()
        .chain([path.to_path_buf()])
        .collect();
    crate::io::check_result_dir(&out, &inputs)?;
    let cells = sweep::cells(&spec, &base, &scenario_path)?;
    let cells_dir = out.join("cells");
    std::fs::create_dir_all(&cells_dir).map_err(|source| ApiError::Fs {
        action: "creating",
        path: cells_dir.clone(),
        source,
    })?;
    // Cells and merged tables are renamed into place whole; what killed runs left is partial.
    crate::io::remove_partials(&cells_dir);
    crate::io::remove_partials(&out);
    let (_, model) = sweep::scenario_at(&base, &scenario_path, &cells[0].point)?;
    let mut plan = SweepPlan {
        path: path.to_path_buf(),
        out,
        spec,
        scenario_path,
        base,
        cells,
        mine: vec![],
        todo: vec![],
        stale: 0,
        joints: model.joint_names(),
    };
    plan.mine = (0..plan.cells.len())
        .filter(|&i| opts.shard.is_none_or(|(k, n)| plan.cells[i].index % n == k))
        .collect();
    plan.todo = plan
        .mine
        .iter()
        .copied()
        .filter(|&i| !plan.cell_file(&plan.cells[i]).exists())
        .collect();
    plan.stale = plan.stale_files()?;
    Ok(plan)
}

impl SweepPlan {
    /// The file a cell's rows are kept in.
    pub fn cell_file(&self, c: &Cell) -> PathBuf {
        self.out.join("cells").join(format!("{}.parquet", c.id()))
    }

    /// The grid's keys, in the sweep file's order.
    pub fn keys(&self) -> Vec<&str> {
        self.spec.grid.keys().map(|k| k.as_str()).collect()
    }

    fn stale_files(&self) -> Result<usize, ApiError> {
        let current: std::collections::BTreeSet<PathBuf> =
            self.cells.iter().map(|c| self.cell_file(c)).collect();
        let dir = self.out.join("cells");
        let entries = std::fs::read_dir(&dir).map_err(|source| ApiError::Fs {
            action: "reading",
            path: dir.clone(),
            source,
        })?;
        Ok(entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "parquet") && !current.contains(p))
            .count())
    }

    /// Runs the cells still to do, in parallel in the current rayon pool; `done()` is called
    /// after each cell is written.
    pub fn run(&self, done: &(dyn Fn() + Sync)) -> Result<(), ApiError> {
        self.run_until(done, &|| false)
    }

    /// [`Self::run`], ending with [`ApiError::Cancelled`] once `stop` returns true: asked
    /// before each cell and before its file is written, so no cell is written after it.
    pub fn run_until(
        &self,
        done: &(dyn Fn() + Sync),
        stop: &(dyn Fn() -> bool + Sync),
    ) -> Result<(), ApiError> {
        let cancelled = || {
            if stop() {
                Err(ApiError::Cancelled)
            } else {
                Ok(())
            }
        };
        self.todo.par_iter().try_for_each(|&i| {
            cancelled()?;
            let c = &self.cells[i];
            let cell_error = |source| ApiError::Cell {
                id: c.id(),
                source: Box::new(source),
            };
            let rows = sweep::run_cell(&self.base, &self.scenario_path, &self.spec, c)
                .map_err(cell_error)?;
            let consts: Vec<(String, String)> = c
                .point
                .iter()
                .map(|(k, v)| (k.clone(), sweep::value_text(v)))
                .collect();
            let mut df = tables::with_constants(tables::long_table(&rows, &self.joints)?, &consts)?;
            cancelled()?;
            tables::write_parquet(&self.cell_file(c), &mut df)?;
            done();
            Ok(())
        })
    }

    /// Cells of the grid without their file (other shards not yet run).
    pub fn missing(&self) -> usize {
        self.cells
            .iter()
            .filter(|c| !self.cell_file(c).exists())
            .count()
    }

    /// Joins every cell into `rows.parquet`/`.csv`, `summary.parquet`/`.csv`, `summary.svg` and
    /// `summary.md` (written last: it marks a complete merge, and is removed first so that a
    /// merge killed half-way never leaves a summary beside tables of another). None while
    /// cells are missing.
    pub fn merge(&self) -> Result<Option<SweepTables>, ApiError> {
        if self.missing() > 0 {
            return Ok(None);
        }
        let marker = self.out.join("summary.md");
        if marker.exists() {
            std::fs::remove_file(&marker).map_err(|source| ApiError::Fs {
                action: "removing",
                path: marker.clone(),
                source,
            })?;
        }
        let parts = self
            .cells
            .iter()
            .map(|c| tables::read_parquet(&self.cell_file(c)))
            .collect::<Result<Vec<_>, _>>()?;
        let mut rows = tables::concat(parts)?;
        tables::write_parquet(&self.out.join("rows.parquet"), &mut rows)?;
        tables::write_csv(&self.out.join("rows.csv"), &mut rows)?;
        let keys = self.keys();
        let mut summary = tables::summary_by(&rows, &keys)?;
        tables::write_parquet(&self.out.join("summary.parquet"), &mut summary)?;
        tables::write_csv(&self.out.join("summary.csv"), &mut summary)?;
        let markdown = self.summary_markdown(&summary)?;
        let svg_path = self.out.join("summary.svg");
        let svg = sweep::summary_plot(&summary, &keys)
            .map_err(|m| ApiError::invalid(&svg_path, format!("plot: {m}")))?;
        crate::io::write_atomic(&svg_path, svg.as_bytes())?;
        crate::io::write_atomic(&marker, markdown.as_bytes())?;
        Ok(Some(SweepTables {
            rows,
            summary,
            markdown,
        }))
    }

    /// `summary.md`: the grid, the experiment's settings, and the summary's main columns.
    fn summary_markdown(&self, summary: &DataFrame) -> Result<String, ApiError> {
        let keys = self.keys();
        let e = &self.spec.experiment;
        let columns = keys.iter().map(|k| k.to_string()).chain(
            [
                "n_s",
                "constraints",
                "val_rms_median",
                "j_err_median",
                "consistent_fraction",
            ]
            .map(String::from),
        );
        Ok(format!(
            "# Sweep {}\n\nGrid: {}; {} seeds; sizes {:?}; sets {:?}. Medians and quartiles over seeds.\n\n{}",
            self.path.display(),
            keys.join(", "),
            e.seeds,
            e.grid(),
            e.constraints.iter().map(|c| c.name()).collect::<Vec<_>>(),
            tables::markdown(&summary.select(columns)?)
        ))
    }
}

/// A merged sweep's tables (as written to its folder).
pub struct SweepTables {
    /// One row per (grid point, seed, n_s, constraint set, body) — `rows.csv`.
    pub rows: DataFrame,
    /// Medians and quartiles over seeds per (grid point, n_s, set) — `summary.csv`.
    pub summary: DataFrame,
    /// `summary.md`.
    pub markdown: String,
}

/// Whether `dir` holds a completely merged sweep (its `summary.md` is written last).
pub fn is_merged(dir: &Path) -> bool {
    dir.join("summary.md").is_file()
}
