//! `provenance.json`, the mark of every experiment result (schema
//! docs/schemas/provenance.schema.json): the scenario, the settings and seeds, the git
//! revision, the dependencies' versions, threads and wall time.

use super::ApiError;
use crate::experiment::ExperimentSpec;
use std::path::Path;

/// The git revision of the working directory, or `unknown`.
pub fn git_revision() -> String {
    std::process::Command::new("git")
        .args(["rev-parse", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|| "unknown".into())
}

/// `provenance.json` of an experiment (schema `physid.provenance/1`, docs/schemas/).
#[derive(serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct Provenance {
    /// The scenario file as given.
    pub scenario_file: std::path::PathBuf,
    /// Its text.
    pub scenario: String,
    /// The experiment settings used.
    pub experiment: ExperimentSpec,
    /// The seeds run.
    pub seeds: Vec<u64>,
    /// `git rev-parse HEAD` of the working directory, or `unknown`.
    pub git_revision: String,
    /// Versions of the numerical dependencies (from Cargo.lock) and the OpenBLAS linked.
    pub dependencies: serde_json::Map<String, serde_json::Value>,
    /// Worker threads.
    pub threads: usize,
    /// Wall time of the experiment (s).
    pub wall_seconds: f64,
}

impl Provenance {
    /// The provenance of an experiment on the scenario at `path` (its `text`), run with
    /// `spec` on `threads` threads in `wall` seconds; the git revision of the working directory
    /// and the dependencies' versions recorded.
    pub fn new(path: &Path, text: &str, spec: &ExperimentSpec, threads: usize, wall: f64) -> Self {
        Provenance {
            scenario_file: path.to_path_buf(),
            scenario: text.to_string(),
            experiment: spec.clone(),
            seeds: (spec.first_seed..spec.first_seed + spec.seeds as u64).collect(),
            git_revision: git_revision(),
            dependencies: dependency_versions(),
            threads,
            wall_seconds: wall,
        }
    }

    /// Writes `provenance.json` into the result folder `out` (atomically).
    pub fn write(&self, out: &Path) -> Result<(), ApiError> {
        let text = serde_json::to_string_pretty(&crate::io::versioned("provenance", self))
            .map_err(|e| ApiError::invalid(out, format!("provenance.json: {e}")))?;
        crate::io::write_atomic(&out.join(crate::io::RESULT_MARK), text.as_bytes())?;
        Ok(())
    }
}

/// Versions of the numerical dependencies, read from the Cargo.lock the binary was built with.
pub fn dependency_versions() -> serde_json::Map<String, serde_json::Value> {
    const LOCK: &str = include_str!("../../Cargo.lock");
    let wanted = [
        "nalgebra",
        "clarabel",
        "rapier3d-f64",
        "polars",
        "rayon",
        "mcap",
    ];
    let mut out = serde_json::Map::new();
    let mut name = "";
    for line in LOCK.lines() {
        if let Some(n) = line.strip_prefix("name = \"") {
            name = n.trim_end_matches('"');
        } else if let Some(v) = line.strip_prefix("version = \"") {
            if wanted.contains(&name) {
                out.insert(
                    name.to_string(),
                    serde_json::Value::String(v.trim_end_matches('"').to_string()),
                );
            }
        }
    }
    // The BLAS/LAPACK is the system's, linked by crates/core/build.rs: record which library file.
    out.insert(
        "openblas".to_string(),
        serde_json::Value::String(physid_core::OPENBLAS_LIBRARY.to_string()),
    );
    out
}
