//! The sample-size experiment of a scenario file (`physid experiment`, the paper's last figure):
//! every (seed, n_s, constraint set) cell, seeds in parallel on the caller's pool, and its
//! tables.

use super::ApiError;
use crate::experiment::{tables, ExperimentSpec};
use crate::model::Model;
use crate::sim::scenario::Scenario;
use std::path::Path;

pub use crate::experiment::tables::csv_text;
pub use crate::experiment::Row;

/// An experiment run: its cells and what names their columns.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct ExperimentRun {
    /// One row per (seed, n_s, constraint set).
    pub rows: Vec<Row>,
    /// The robot's joints (the per-joint columns).
    pub joints: Vec<String>,
    /// Its bodies and rotors (the per-body columns).
    pub bodies: Vec<String>,
    /// The constraint sets compared, loosest first.
    pub sets: Vec<String>,
}

/// A scenario file's experiment, read and checked: what `physid experiment` and
/// [`run_scenario`] run.
pub struct PlannedExperiment {
    /// The scenario.
    pub scenario: Scenario,
    /// Its robot.
    pub model: Model,
    /// The scenario file's text (for provenance).
    pub text: String,
    /// Its `[experiment]` table, `seeds` applied, validated.
    pub spec: ExperimentSpec,
}

/// Reads the scenario at `path` and its `[experiment]` (`seeds` overriding its seed count),
/// checked; errors name the file.
pub fn plan(path: &Path, seeds: Option<usize>) -> Result<PlannedExperiment, ApiError> {
    let (scenario, model, text) = crate::sim::scenario::load(path)?;
    let invalid = |message: String| ApiError::invalid(path, message);
    let mut spec = ExperimentSpec::from_scenario(&scenario)
        .map_err(|e| invalid(format!("[experiment]: {e}")))?;
    if let Some(n) = seeds {
        spec.seeds = n;
    }
    spec.validate().map_err(|e| invalid(e.to_string()))?;
    Ok(PlannedExperiment {
        scenario,
        model,
        text,
        spec,
    })
}

/// Runs the `[experiment]` of the scenario at `path` (`seeds` overrides its seed count) on the
/// current rayon pool, calling `report(done, total)` as seeds finish (from the pool's threads).
/// Experiments over several excitation motions are the binary's (`physid experiment`).
pub fn run_scenario(
    path: &Path,
    seeds: Option<usize>,
    report: &(dyn Fn(usize, usize) + Sync),
) -> Result<ExperimentRun, ApiError> {
    let PlannedExperiment {
        scenario,
        model,
        spec,
        ..
    } = plan(path, seeds)?;
    let invalid = |message: String| ApiError::invalid(path, message);
    if !spec.excitations.is_empty() {
        return Err(invalid(format!(
            "an experiment over several excitation motions ([[experiment.excitations]]) is not in the Python package yet: run `physid experiment {}`",
            path.display()
        )));
    }
    let rows = crate::experiment::run(&model, &scenario, &spec, report)
        .map_err(|e| invalid(format!("running the experiment: {e}")))?;
    Ok(ExperimentRun {
        rows,
        joints: model.joint_names(),
        bodies: crate::ident::bodies(&model)
            .into_iter()
            .map(|(n, _, _)| n)
            .collect(),
        sets: spec
            .constraints
            .iter()
            .map(|s| s.name().to_string())
            .collect(),
    })
}

impl ExperimentRun {
    /// The long table (`rows.csv`), or with `summary` its median and quartiles over seeds
    /// (`summary.csv`), as CSV text.
    pub fn csv(&self, summary: bool) -> Result<String, ApiError> {
        let long = tables::long_table_with_bodies(&self.rows, &self.joints, &self.bodies)?;
        let mut table = if summary {
            tables::summary(&long)?
        } else {
            long
        };
        Ok(tables::csv_text(&mut table)?)
    }
}
