//! Parameter sweeps: a grid over any scenario keys, crossed with the constraint sets and the
//! training sizes of the sample-size experiment.
//!
//! A sweep file names a base scenario and a grid of dotted scenario keys:
//!
//! ```toml
//! scenario = "cheetah3_shell.toml"      # relative to this file
//! [grid]
//! "sensors.torque_noise" = [0.3, 1.0, 3.0]
//! "simulation.engine" = ["physid", "rapier"]
//! "experiment.prior_weight" = [1e-6, 1e-3]  # the sweep's [experiment] keys too (not seeds)
//! [experiment]                           # as a scenario's [experiment] table
//! seeds = 3
//! sizes = [100, 1000]
//! validation = 2000
//! ```
//!
//! Each cell (one grid point and one seed) is independent and deterministic; its rows are written
//! to `cells/<cell id>.parquet` when it finishes, so an interrupted sweep resumes by skipping the
//! cells already present. A cell's id ends in a hash of everything that determines it (the
//! resolved scenario and robot at its grid point, the experiment settings, the seed, physid's
//! version): a changed configuration never reuses a cell, and the merge reads only the current
//! configuration's cells (stale ones are counted and left alone); and `--shard K/N` runs only the cells with index ≡ K (mod N), which is
//! how a cluster job array splits a large sweep (see docs/sweeps.md). The final merge reads every
//! cell file with polars.

use super::{run_seed, ExperimentError, ExperimentSpec, Row};
use physid_io::IoError;
use physid_sim::scenario::Scenario;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// A sweep file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepSpec {
    /// Base scenario, relative to the sweep file.
    pub scenario: PathBuf,
    /// Dotted scenario keys and their values.
    pub grid: toml::Table,
    /// The experiment settings for every grid point.
    #[serde(default)]
    pub experiment: ExperimentSpec,
}

/// One grid point: `(key, value)` pairs.
pub type Point = Vec<(String, toml::Value)>;

/// A cell: a grid point and a seed.
#[derive(Clone, Debug)]
pub struct Cell {
    /// Position in the sweep's cell order.
    pub index: usize,
    /// The grid point.
    pub point: Point,
    /// The seed.
    pub seed: u64,
    /// Hash (hex, 16 digits) of everything that determines the cell's rows ([`cell_key`]).
    pub key: String,
}

/// The hash of what determines a cell's rows: the resolved scenario and robot at its grid
/// point, the experiment settings, the seed and physid's version (BLAKE3, first 16 hex digits).
pub fn cell_key(
    sc: &Scenario,
    model: &physid_core::model::Model,
    experiment: &ExperimentSpec,
    seed: u64,
) -> String {
    let text = format!(
        "{sc:?}\n{model:?}\n{experiment:?}\nseed {seed}\nphysid {}",
        env!("CARGO_PKG_VERSION")
    );
    blake3::hash(text.as_bytes()).to_hex()[..16].to_string()
}

impl Cell {
    /// A stable file-name-safe id, e.g. `0007_sensors.torque_noise=1_seed=2_3f2a…` (the last
    /// part its [`Cell::key`]).
    pub fn id(&self) -> String {
        let kv: Vec<String> = self
            .point
            .iter()
            .map(|(k, v)| format!("{k}={}", value_text(v)))
            .collect();
        let raw = format!(
            "{:04}_{}_seed={}_{}",
            self.index,
            kv.join("_"),
            self.seed,
            self.key
        );
        raw.chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || "._=-".contains(c) {
                    c
                } else {
                    '-'
                }
            })
            .collect()
    }
}

/// A grid value as text (strings without quotes).
pub fn value_text(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// Reads a sweep file and its base scenario text.
pub fn load(path: &Path) -> Result<(SweepSpec, PathBuf, String), IoError> {
    let text = physid_io::read_to_string(path)?;
    let spec: SweepSpec =
        toml::from_str(&text).map_err(|e| physid_io::robot_toml::toml_error(path, e))?;
    let scenario = path.parent().unwrap_or(Path::new(".")).join(&spec.scenario);
    let base = physid_io::read_to_string(&scenario)?;
    for (k, v) in &spec.grid {
        if k == "experiment" || k == "experiment.seeds" || k == "experiment.first_seed" {
            return Err(IoError::invalid(
                path,
                format!(
                    "grid.\"{k}\": the seeds are the sweep's cells, set once in its [experiment] table; a grid cannot vary them"
                ),
            ));
        }
        if !matches!(v, toml::Value::Array(a) if !a.is_empty()) {
            return Err(IoError::invalid(
                path,
                format!("grid.\"{k}\": give a non-empty list of values"),
            ));
        }
        let values = v.as_array().expect("an array, checked above");
        if let Some((j, i)) = physid_io::first_repeat(values, |_| true) {
            return Err(IoError::invalid(
                path,
                format!(
                    "grid.\"{k}\": the value {} is listed twice (entries {} and {}): each grid point is one cell per seed",
                    values[i],
                    j + 1,
                    i + 1
                ),
            ));
        }
    }
    let points = spec.grid.values().try_fold(1usize, |n, v| {
        n.checked_mul(v.as_array().map_or(1, Vec::len))
    });
    let cells = points.and_then(|p| p.checked_mul(spec.experiment.seeds.max(1)));
    if cells.is_none_or(|c| c > MAX_CELLS) {
        let count = cells.map_or("more than 2^64".to_string(), |c| c.to_string());
        return Err(IoError::invalid(
            path,
            format!(
                "grid: {count} cells (grid points times experiment.seeds); at most {MAX_CELLS} per sweep (shard a larger one)"
            ),
        ));
    }
    Ok((spec, scenario, base))
}

/// The most cells a sweep may have (checked before any is allocated).
pub const MAX_CELLS: usize = 100_000;

/// All cells, grid points in lexicographic order of the keys (last key fastest), then seeds,
/// each keyed by its resolved configuration ([`cell_key`]; the base scenario `base` read from
/// `scenario_path`). Errors name the grid point whose scenario is invalid.
pub fn cells(spec: &SweepSpec, base: &str, scenario_path: &Path) -> Result<Vec<Cell>, IoError> {
    let keys: Vec<(&String, &Vec<toml::Value>)> = spec
        .grid
        .iter()
        .map(|(k, v)| (k, v.as_array().expect("checked in load")))
        .collect();
    let mut points: Vec<Point> = vec![vec![]];
    for (k, values) in &keys {
        points = points
            .into_iter()
            .flat_map(|p| {
                values
                    .iter()
                    .map(move |v| [p.clone(), vec![((*k).clone(), v.clone())]].concat())
            })
            .collect();
    }
    let seeds: Vec<u64> = (0..spec.experiment.seeds as u64)
        .map(|i| spec.experiment.first_seed + i)
        .collect();
    let mut out = vec![];
    for p in points {
        let (sc, model) = scenario_at(base, scenario_path, &p)?;
        let experiment = experiment_at(spec, &p, scenario_path)?;
        for &s in &seeds {
            out.push(Cell {
                index: out.len(),
                point: p.clone(),
                seed: s,
                key: cell_key(&sc, &model, &experiment, s),
            });
        }
    }
    Ok(out)
}

/// The base scenario with a grid point applied (each dotted key set in the TOML tree, then the
/// whole scenario parsed and validated: errors name the key).
pub fn scenario_at(
    base: &str,
    scenario_path: &Path,
    point: &Point,
) -> Result<(Scenario, physid_core::model::Model), IoError> {
    let mut doc: toml::Table =
        toml::from_str(base).map_err(|e| physid_io::robot_toml::toml_error(scenario_path, e))?;
    for (key, value) in point.iter().filter(|(k, _)| !is_experiment_key(k)) {
        let parts: Vec<&str> = key.split('.').collect();
        let mut t = &mut doc;
        for p in &parts[..parts.len() - 1] {
            t = t
                .entry(p.to_string())
                .or_insert_with(|| toml::Value::Table(toml::Table::new()))
                .as_table_mut()
                .ok_or_else(|| {
                    IoError::invalid(
                        scenario_path,
                        format!("sweep key '{key}': '{p}' is not a table"),
                    )
                })?;
        }
        t.insert(parts[parts.len() - 1].to_string(), value.clone());
    }
    let text = toml::to_string(&doc)
        .map_err(|e| IoError::invalid(scenario_path, format!("sweep: {e}")))?;
    let sc: Scenario = toml::from_str(&text).map_err(|e| IoError::Parse {
        path: scenario_path.to_path_buf(),
        message: format!("with sweep values {point:?}: {}", e.to_string().trim_end()),
    })?;
    let model = physid_io::robot_toml::from_spec(&sc.robot, scenario_path)?;
    sc.validate(model.dof()).map_err(|e| {
        IoError::invalid(scenario_path, format!("with sweep values {point:?}: {e}"))
    })?;
    Ok((sc, model))
}

/// Whether a grid key sets the sweep's experiment settings (`experiment.…`), not the scenario.
fn is_experiment_key(key: &str) -> bool {
    key.starts_with("experiment.")
}

/// The sweep's experiment settings at a grid point: its `experiment.…` keys set over the
/// sweep's `[experiment]` table, then parsed and checked (errors name the key and the point).
pub fn experiment_at(
    spec: &SweepSpec,
    point: &Point,
    scenario_path: &Path,
) -> Result<ExperimentSpec, IoError> {
    let keys: Vec<&(String, toml::Value)> =
        point.iter().filter(|(k, _)| is_experiment_key(k)).collect();
    if keys.is_empty() {
        return Ok(spec.experiment.clone());
    }
    let bad =
        |m: String| IoError::invalid(scenario_path, format!("with sweep values {point:?}: {m}"));
    let mut table = toml::Table::try_from(&spec.experiment).map_err(|e| bad(e.to_string()))?;
    for (key, value) in keys {
        table.insert(key["experiment.".len()..].to_string(), value.clone());
    }
    let experiment: ExperimentSpec = table
        .try_into()
        .map_err(|e: toml::de::Error| bad(e.to_string().trim_end().to_string()))?;
    experiment.validate().map_err(|e| bad(e.to_string()))?;
    Ok(experiment)
}

/// Runs one cell.
pub fn run_cell(
    base: &str,
    scenario_path: &Path,
    spec: &SweepSpec,
    cell: &Cell,
) -> Result<Vec<Row>, SweepError> {
    let (sc, model) = scenario_at(base, scenario_path, &cell.point)?;
    let experiment = experiment_at(spec, &cell.point, scenario_path)?;
    Ok(run_seed(&model, &sc, &experiment, cell.seed)?)
}

/// `summary.svg` of a merged sweep: per grid point (labels `key=value, …`), the median
/// validation RMS of each constraint set at the largest training size, as grouped bars.
pub fn summary_plot(summary: &polars::prelude::DataFrame, keys: &[&str]) -> Result<String, String> {
    use super::tables::{floats, strings};
    let e = |e: polars::prelude::PolarsError| e.to_string();
    let n_s = floats(summary, "n_s").map_err(e)?;
    let top = n_s.iter().copied().fold(0.0, f64::max);
    let text = |c: &str| strings(summary, c).map_err(e);
    let sets = text("constraints")?;
    let rms = floats(summary, "val_rms_median").map_err(e)?;
    let grid: Vec<Vec<String>> = keys.iter().map(|k| text(k)).collect::<Result<_, _>>()?;
    let point = |i: usize| -> String {
        keys.iter()
            .zip(&grid)
            .map(|(k, g)| format!("{k}={}", g[i]))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let (mut labels, mut names): (Vec<String>, Vec<String>) = (vec![], vec![]);
    for i in (0..summary.height()).filter(|&i| n_s[i] == top) {
        if !labels.contains(&point(i)) {
            labels.push(point(i));
        }
        if !names.contains(&sets[i]) {
            names.push(sets[i].clone());
        }
    }
    let series: Vec<(String, Vec<f64>)> = names
        .iter()
        .map(|set| {
            let vals = labels
                .iter()
                .map(|l| {
                    (0..summary.height())
                        .find(|&i| n_s[i] == top && &sets[i] == set && &point(i) == l)
                        .map_or(f64::NAN, |i| rms[i])
                })
                .collect();
            (set.clone(), vals)
        })
        .collect();
    physid_io::plot::grouped_bars(
        &format!("median validation RMS at n_s = {top:.0}, per grid point"),
        "validation RMS (N m)",
        &labels,
        &series,
    )
}

/// Sweep errors.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    /// A file problem.
    #[error(transparent)]
    Io(#[from] IoError),
    /// An experiment cell failed.
    #[error(transparent)]
    Experiment(#[from] ExperimentError),
}
