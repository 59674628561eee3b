//! The **excitation axis** of the sample-size experiment: several motions of one robot (the
//! paper's shell, a random Fourier excitation, a designed one: `physid excite`), each
//! identified at every training size and constraint set, and all validated on one independent
//! run of the same motion (`validate_on`), so that the motions are compared on the same data.

use super::{run_seed_validated_on, ExperimentError, ExperimentSpec, Row};
use physid_core::model::Model;
use physid_sim::scenario::{Scenario, ScenarioError};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// [`Reach::samples_within`]: within this fraction of the reference's validation error.
pub const REACH_TOLERANCE: f64 = 0.02;

/// Seeds of the validation runs are the training seeds plus this.
pub const VALIDATION_SEED_OFFSET: u64 = 1_000_000;

/// One motion of the axis.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ExcitationEntry {
    /// Its name (letters, digits, `-` and `_`: it names the results' folder).
    pub name: String,
    /// Its scenario file, relative to the experiment's scenario file.
    pub scenario: PathBuf,
    /// Only validate on it (`validate_on`): a held-out motion that no model is identified on.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub validation_only: bool,
}

/// A loaded motion.
#[derive(Clone, Debug)]
pub struct Motion {
    /// Its name.
    pub name: String,
    /// Its scenario file as resolved.
    pub path: PathBuf,
    /// The scenario.
    pub scenario: Scenario,
    /// Only validated on (no model is identified on it).
    pub validation_only: bool,
}

/// Names are non-empty, distinct and folder-safe; `validate_on` names one of them.
pub fn validate_entries(
    entries: &[ExcitationEntry],
    validate_on: Option<&str>,
) -> Result<(), ScenarioError> {
    let err = |key: String, reason: String| Err(ScenarioError { key, reason });
    for (i, e) in entries.iter().enumerate() {
        let ok = !e.name.is_empty()
            && e.name.len() <= 64
            && e.name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
        if !ok {
            return err(
                format!("experiment.excitations[{i}].name"),
                format!("'{}' must be letters, digits, '-' or '_'", e.name),
            );
        }
        if entries[..i].iter().any(|f| f.name == e.name) {
            return err(
                format!("experiment.excitations[{i}].name"),
                format!("'{}' is given twice", e.name),
            );
        }
    }
    if entries
        .iter()
        .any(|e| e.validation_only && Some(e.name.as_str()) != validate_on)
    {
        return err(
            "experiment.excitations".into(),
            "an entry with validation_only = true must be the one validate_on names".into(),
        );
    }
    if !entries.is_empty() && entries.iter().all(|e| e.validation_only) {
        return err(
            "experiment.excitations".into(),
            "every entry is validation_only: no motion to identify on".into(),
        );
    }
    if let Some(v) = validate_on {
        if !entries.iter().any(|e| e.name == v) {
            return err(
                "experiment.validate_on".into(),
                format!("'{v}' is not the name of an entry of experiment.excitations"),
            );
        }
    }
    Ok(())
}

/// The motions of `spec.excitations`, their files resolved against the experiment's scenario
/// file `base`; each must describe the same robot as `model`.
pub fn load(
    base: &Path,
    spec: &ExperimentSpec,
    model: &Model,
) -> Result<Vec<Motion>, ExperimentError> {
    let dir = base.parent().unwrap_or(Path::new(""));
    spec.excitations
        .iter()
        .map(|e| {
            let path = dir.join(&e.scenario);
            let (scenario, m, _) =
                physid_sim::scenario::load(&path).map_err(|source| ExperimentError::Motion {
                    name: e.name.clone(),
                    source,
                })?;
            if m.dof() != model.dof() || m.parameters() != model.parameters() {
                return Err(ExperimentError::DifferentRobot {
                    name: e.name.clone(),
                    path,
                });
            }
            Ok(Motion {
                name: e.name.clone(),
                path,
                scenario,
                validation_only: e.validation_only,
            })
        })
        .collect()
}

/// Runs every motion over the seeds of `spec` (seeds in parallel on the current rayon pool):
/// the rows of each motion, in the order of `motions` (none for a validation-only motion).
/// `progress(done, total)` counts seeds.
pub fn run(
    model: &Model,
    motions: &[Motion],
    spec: &ExperimentSpec,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Vec<Vec<Row>>, ExperimentError> {
    spec.validate()?;
    let seeds: Vec<u64> = (0..spec.seeds as u64)
        .map(|i| spec.first_seed + i)
        .collect();
    let validator = spec
        .validate_on
        .as_ref()
        .and_then(|v| motions.iter().find(|m| &m.name == v));
    let done = std::sync::atomic::AtomicUsize::new(0);
    let per_seed: Vec<Vec<Vec<Row>>> = seeds
        .par_iter()
        .map(|&seed| {
            let validation = validator
                .map(|m| validation_run(model, &m.scenario, spec, seed))
                .transpose()?;
            let rows = motions
                .iter()
                .map(|m| {
                    if m.validation_only {
                        Ok(vec![])
                    } else {
                        run_seed_validated_on(model, &m.scenario, spec, seed, validation.as_ref())
                    }
                })
                .collect::<Result<Vec<_>, _>>();
            progress(
                done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1,
                seeds.len(),
            );
            rows
        })
        .collect::<Result<_, _>>()?;
    Ok((0..motions.len())
        .map(|k| per_seed.iter().flat_map(|s| s[k].clone()).collect())
        .collect())
}

/// The processed data of an independent run of `scenario` for `seed`: `spec.validation`
/// samples, simulated with seed + [`VALIDATION_SEED_OFFSET`].
fn validation_run(
    model: &Model,
    scenario: &Scenario,
    spec: &ExperimentSpec,
    seed: u64,
) -> Result<physid_core::trajectory::Trajectory, ExperimentError> {
    let mut sc = scenario.clone();
    let vseed = seed + VALIDATION_SEED_OFFSET;
    sc.simulation.seed = vseed;
    // Longer by the processing's settling at each end, which is left out.
    let settle = physid_sim::simulate::settle_samples(&sc, sc.simulation.rate);
    sc.simulation.duration = (spec.validation + 1 + 2 * settle) as f64 / sc.simulation.rate;
    let rec = physid_sim::run(model, &sc, &mut |_| {}).map_err(|source| ExperimentError::Sim {
        seed: vseed,
        source,
    })?;
    Ok(rec.processed.slice(settle..rec.processed.len() - settle))
}

/// The smallest training size at which `errors` (per size, ascending sizes `ns`) first
/// reaches `target`, interpolated log-log between the grid points around the crossing; `None`
/// if it never does.
pub fn samples_to_reach(ns: &[usize], errors: &[f64], target: f64) -> Option<f64> {
    let i = errors.iter().position(|e| *e <= target)?;
    if i == 0 {
        return Some(ns[0] as f64);
    }
    let (n0, n1) = ((ns[i - 1] as f64).ln(), (ns[i] as f64).ln());
    let (e0, e1) = (errors[i - 1].ln(), errors[i].ln());
    let t = if e1 < e0 {
        (e0 - target.ln()) / (e0 - e1)
    } else {
        1.0
    };
    Some((n0 + t * (n1 - n0)).exp())
}

/// One motion's medians over seeds, per training size, for one constraint set.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct MedianCurve {
    /// The motion.
    pub excitation: String,
    /// The constraint set.
    pub constraints: physid_ident::ConstraintSet,
    /// Training sizes, ascending.
    pub n_s: Vec<usize>,
    /// Median validation RMS over all joints (N m).
    pub val_rms: Vec<f64>,
    /// Median validation RMS against the true model, `Y (θ̂ − θ)` (N m).
    pub val_truth_rms: Vec<f64>,
    /// Median relative pseudo-inertia error (mean over bodies).
    pub j_err: Vec<f64>,
}

/// The median curves of every motion (`names`, rows in the same order) and set.
pub fn median_curves(
    names: &[String],
    rows: &[Vec<Row>],
    spec: &ExperimentSpec,
) -> Vec<MedianCurve> {
    let grid = spec.grid();
    let mut out = vec![];
    for &set in &spec.constraints {
        for (name, rows) in names.iter().zip(rows) {
            let at = |n_s: usize, f: &dyn Fn(&Row) -> f64| {
                let v: Vec<f64> = rows
                    .iter()
                    .filter(|r| r.n_s == n_s && r.constraints == set)
                    .map(f)
                    .collect();
                super::median_iqr(&v).1
            };
            out.push(MedianCurve {
                excitation: name.clone(),
                constraints: set,
                n_s: grid.clone(),
                val_rms: grid
                    .iter()
                    .map(|&n| at(n, &|r| r.val_rms_overall))
                    .collect(),
                val_truth_rms: grid.iter().map(|&n| at(n, &|r| r.val_truth_rms)).collect(),
                j_err: grid.iter().map(|&n| at(n, &|r| r.j_err)).collect(),
            });
        }
    }
    out
}

/// How many samples a motion needs to reach the reference motion's validation error at its
/// largest training size, per set.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct Reach {
    /// The constraint set.
    pub constraints: physid_ident::ConstraintSet,
    /// The motion.
    pub excitation: String,
    /// The reference's median validation RMS at its largest size (N m).
    pub target: f64,
    /// Training samples at which this motion's median first reaches it (log-log interpolated
    /// between grid sizes); `None`: not within the grid.
    pub samples: Option<f64>,
    /// The reference's largest size over `samples`: how many times fewer samples it needs.
    pub fewer: Option<f64>,
    /// Training samples at which it first comes within [`REACH_TOLERANCE`] of the target
    /// (every motion's error levels off at a bias set by the data processing, a few per cent
    /// apart between motions: the strict crossing measures that level, this one the approach).
    pub samples_within: Option<f64>,
    /// The reference's largest size over `samples_within`.
    pub fewer_within: Option<f64>,
    /// The reference's median pseudo-inertia error at its largest size.
    pub j_err_target: f64,
    /// Training samples at which this motion's median pseudo-inertia error first reaches it.
    pub samples_j_err: Option<f64>,
    /// The reference's largest size over `samples_j_err`.
    pub fewer_j_err: Option<f64>,
    /// The smallest training size from which on its median pseudo-inertia error stays below
    /// the reference's at the same size (`None`: not even at the largest).
    pub lower_parameter_error_from: Option<usize>,
    /// Whether its median pseudo-inertia error is below the reference's at every size.
    pub lower_parameter_error_everywhere: bool,
}

/// [`Reach`] of every curve against the curves of motion `reference` (same set).
pub fn reach(curves: &[MedianCurve], reference: &str) -> Vec<Reach> {
    curves
        .iter()
        .filter_map(|c| {
            let r = curves
                .iter()
                .find(|r| r.excitation == reference && r.constraints == c.constraints)?;
            let (&n_max, &target) = (r.n_s.last()?, r.val_rms.last()?);
            let j_err_target = *r.j_err.last()?;
            let fewer = |s: Option<f64>| s.map(|s| n_max as f64 / s);
            let samples = samples_to_reach(&c.n_s, &c.val_rms, target);
            let samples_within =
                samples_to_reach(&c.n_s, &c.val_rms, target * (1.0 + REACH_TOLERANCE));
            let samples_j_err = samples_to_reach(&c.n_s, &c.j_err, j_err_target);
            let below: Vec<bool> = c.j_err.iter().zip(&r.j_err).map(|(a, b)| a < b).collect();
            let from = (0..below.len())
                .find(|&i| below[i..].iter().all(|b| *b))
                .map(|i| c.n_s[i]);
            Some(Reach {
                constraints: c.constraints,
                excitation: c.excitation.clone(),
                target,
                samples,
                fewer: fewer(samples),
                samples_within,
                fewer_within: fewer(samples_within),
                j_err_target,
                samples_j_err,
                fewer_j_err: fewer(samples_j_err),
                lower_parameter_error_from: from,
                lower_parameter_error_everywhere: c.j_err.iter().zip(&r.j_err).all(|(a, b)| a < b),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_to_reach_interpolates_log_log() {
        // Errors 10 at 100 and 1 at 10,000: 10^(1/2) ≈ 3.16 is reached at 1,000.
        let n = samples_to_reach(&[100, 10_000], &[10.0, 1.0], 10f64.sqrt()).unwrap();
        assert!((n - 1000.0).abs() < 1e-6, "{n}");
        assert_eq!(samples_to_reach(&[100, 10_000], &[10.0, 1.0], 0.5), None);
        assert_eq!(
            samples_to_reach(&[100, 10_000], &[0.1, 1.0], 0.5),
            Some(100.0)
        );
    }

    #[test]
    fn entry_names_are_checked() {
        let e = |n: &str| ExcitationEntry {
            name: n.into(),
            scenario: "x.toml".into(),
            validation_only: false,
        };
        assert!(validate_entries(&[e("shell"), e("opt-1")], Some("shell")).is_ok());
        assert!(validate_entries(&[e("a b")], None).is_err());
        assert!(validate_entries(&[e("a"), e("a")], None).is_err());
        assert!(validate_entries(&[e("a")], Some("b")).is_err());
    }
}
