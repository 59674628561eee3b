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
    if whole_robot_plan(path, seeds)?.is_some() {
        return Err(ApiError::invalid(
            path,
            "a whole-robot scenario ([whole_robot]): `physid experiment` runs it; this entry point runs fixed-base scenarios",
        ));
    }
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

/// A whole-robot scenario: a scenario file whose `[whole_robot]` table asks for the floating
/// quadruped's sample-size experiment ([`crate::experiment::whole_robot`]) instead of a
/// fixed-base robot's (docs/scenario-format.md, "`[whole_robot]`").
#[derive(Clone, Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct WholeRobotScenario {
    whole_robot: WholeRobotTable,
}

/// The `[whole_robot]` table; every key optional, `physid whole-robot`'s defaults.
#[derive(Clone, Debug, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
struct WholeRobotTable {
    sizes: Vec<usize>,
    seeds: u64,
    torque_noise: f64,
    force_noise: f64,
    prior_error: f64,
    prior_weight: f64,
    /// `[crouch rad, frequency Hz]`: trot in place instead of standing.
    trot: Option<[f64; 2]>,
    /// Train on the run as its sensors log it ([`crate::experiment::whole_robot::WholeRobotSpec::logged`]).
    logged: bool,
}

impl Default for WholeRobotTable {
    fn default() -> Self {
        let spec = crate::experiment::whole_robot::WholeRobotSpec::default();
        Self {
            sizes: vec![100, 300, 1000, 3000, 10000],
            seeds: 4,
            torque_noise: spec.torque_noise,
            force_noise: spec.force_noise,
            prior_error: spec.prior_error,
            prior_weight: spec.prior_weight,
            trot: None,
            logged: false,
        }
    }
}

/// The whole-robot experiment the scenario at `path` asks for (`seeds` overriding its seed
/// count), checked, or `None` when the file has no `[whole_robot]` table (a fixed-base
/// scenario: [`plan`]). Errors name the file and the key.
pub fn whole_robot_plan(
    path: &Path,
    seeds: Option<usize>,
) -> Result<Option<crate::experiment::whole_robot::WholeRobotSpec>, ApiError> {
    let text = crate::io::read_to_string(path)?;
    let invalid = |message: String| ApiError::invalid(path, message);
    let table: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| invalid(e.to_string()))?;
    if !table.contains_key("whole_robot") {
        return Ok(None);
    }
    let scenario: WholeRobotScenario =
        toml::from_str(&text).map_err(|e: toml::de::Error| invalid(e.to_string()))?;
    let t = scenario.whole_robot;
    let seed_count = seeds.map_or(t.seeds, |n| n as u64);
    if !(1..=1000).contains(&seed_count) {
        return Err(invalid(format!(
            "[whole_robot] seeds = {seed_count}: expected 1 to 1000"
        )));
    }
    let spec = crate::experiment::whole_robot::WholeRobotSpec {
        motion: crate::sim::floating::Standing {
            step: t.trot.map_or((0.0, 0.0), |[h, f]| (h, f)),
            ..Default::default()
        },
        sizes: t.sizes,
        seeds: (1..=seed_count).collect(),
        torque_noise: t.torque_noise,
        force_noise: t.force_noise,
        prior_error: t.prior_error,
        prior_weight: t.prior_weight,
        logged: t.logged,
        ..Default::default()
    };
    spec.validate()
        .map_err(|e| invalid(format!("[whole_robot]: {e}")))?;
    Ok(Some(spec))
}
