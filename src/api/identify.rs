//! `identify`'s JSON contract ([`IdentifyJson`], docs/identify-json.md, schema
//! docs/schemas/identify.schema.json), its default constraint set, the ground-truth errors of a
//! physid log, and the effects a diagnosis report confirmed (`--effects-from`).

use super::data::{in_memory, Data, Span, SquaredErrors};
use super::ApiError;
use crate::diagnose::calibrate::{parse_term, Calibration, Options as CalOptions, Run, TermFit};
use crate::diagnose::library::Variant;
use crate::ident::{self, analysis, ConstraintSet, NormalEquations, Options};
use crate::model::Model;
use crate::trajectory::Trajectory;
use nalgebra::DVector;
use std::path::{Path, PathBuf};

/// One data file and what the pipeline did to it.
#[derive(Clone, serde::Serialize, schemars::JsonSchema)]
pub struct DataJson {
    /// The file.
    pub file: PathBuf,
    /// Runs, gaps, bridged, trimmed and dropped samples, derived signals, locked and still
    /// joints.
    pub pipeline: crate::prepare::Report,
}

/// One body's errors against the ground truth.
#[derive(Clone, serde::Serialize, schemars::JsonSchema)]
pub struct TruthError {
    /// Body or rotor name.
    pub name: String,
    /// `|Δm|/m`.
    pub mass_rel: f64,
    /// `‖Δc‖` (m).
    pub com_m: f64,
    /// `‖ΔI_C‖/‖I_C‖`.
    pub inertia_rel: f64,
    /// `‖ΔJ‖/‖J‖`.
    pub j_rel: f64,
}

/// A run and its sample range (`[start, end)`, indices of the file as read).
#[derive(serde::Serialize, schemars::JsonSchema)]
pub struct RunRange {
    /// The data file.
    pub file: PathBuf,
    /// `[start, end)`: sample indices of the file as read.
    pub range: [usize; 2],
    /// Samples of the range that were fitted or scored (after the pipeline's trimming and
    /// splitting).
    pub samples_used: usize,
}

/// The training or validation part of `identify --json`.
#[derive(serde::Serialize, schemars::JsonSchema)]
pub struct Split {
    /// The first run's sample range.
    pub range: Option<[usize; 2]>,
    /// Every run of the split, with its range.
    pub runs: Vec<RunRange>,
    /// RMS of `Y θ − τ` per joint (N m); null for a locked joint (its torque is not fitted).
    pub rms: Vec<Option<f64>>,
    /// Over all joints (N m).
    pub rms_overall: f64,
}

/// Friction per joint.
#[derive(serde::Serialize, schemars::JsonSchema)]
pub struct Friction {
    /// `B` (N m s/rad).
    pub viscous: Vec<f64>,
    /// `B_c` (N m).
    pub coulomb: Vec<f64>,
}

/// `identify --json` (docs/identify-json.md; JSON Schema docs/schemas/identify.schema.json).
#[derive(serde::Serialize, schemars::JsonSchema)]
pub struct IdentifyJson {
    /// The first training file.
    pub data: PathBuf,
    /// The robot's name.
    pub robot: String,
    /// The constraint set identified under.
    pub constraints: ConstraintSet,
    /// Why it was chosen, when the user gave none.
    pub constraints_default_because: Option<String>,
    /// The training runs and their fit.
    pub train: Split,
    /// The validation runs and their error, when any were held out or given.
    pub validation: Option<Split>,
    /// Each body's (and rotor's) identified parameters and whether its constraints hold.
    pub bodies: Vec<ident::IdentifiedBody>,
    /// The joints' viscous and Coulomb friction.
    pub friction: Friction,
    /// The effect terms' fits (`--friction` extras, `--effects`, `--effects-from`).
    pub effects: Vec<TermFit>,
    /// The effect terms as a scenario `[[effects]]` snippet.
    pub scenario_effects: Option<String>,
    /// The optimum of the identification's objective.
    pub objective: f64,
    /// Whether every body satisfies the constraint set (J ≻ 0, tr(JQ) ≥ 0, … as chosen).
    pub constraints_hold: bool,
    /// The conic solver's status, iterations and time.
    pub solver: ident::SolverInfo,
    /// Wall time from start to the report (s).
    pub end_to_end_seconds: f64,
    /// Which parameters the data determine.
    pub identifiability: analysis::Identifiability,
    /// The names of `theta`'s entries.
    pub parameter_names: Vec<String>,
    /// The identified parameter vector: the model's, then the effect coefficients.
    pub theta: Vec<f64>,
    /// Per-body errors against the ground truth, when the data are a physid log carrying it.
    pub truth_errors: Option<Vec<TruthError>>,
    /// What the data pipeline did to each file read in memory.
    pub data_pipeline: Vec<DataJson>,
    /// Joints held at their logged position, whose torque is not fitted.
    pub locked_joints: Vec<String>,
}

/// The constraint set: the one given, else the tightest the description supports, and why
/// (`ellipsoid` when every body has a bounding ellipsoid, else `consistent`).
pub fn constraint_set(given: Option<ConstraintSet>, m: &Model) -> (ConstraintSet, Option<String>) {
    if let Some(c) = given {
        return (c, None);
    }
    let missing: Vec<String> = ident::bodies(m)
        .into_iter()
        .filter(|(_, _, e)| e.is_none())
        .map(|(name, _, _)| name)
        .collect();
    if missing.is_empty() {
        (
            ConstraintSet::Ellipsoid,
            Some("every body has a bounding ellipsoid".into()),
        )
    } else {
        (
            ConstraintSet::Consistent,
            Some(format!(
                "no bounding ellipsoid for {} (give them in a sidecar, see docs/robot-format.md)",
                missing.join(", ")
            )),
        )
    }
}

/// The ground truth a physid MCAP log carries (its `ground_truth_parameters` metadata, in
/// `m`'s parameter order), if `path` is one and it matches `m`.
pub fn ground_truth(path: &Path, m: &Model) -> Option<DVector<f64>> {
    if path.extension().and_then(|e| e.to_str()) != Some("mcap") {
        return None;
    }
    let log = crate::io::mcap_log::read(path).ok()?;
    let md = log.metadata.get("ground_truth_parameters")?;
    let names: Vec<String> = serde_json::from_str(md.get("names")?).ok()?;
    let values: Vec<f64> = serde_json::from_str(md.get("values")?).ok()?;
    (names == m.parameter_names()).then(|| DVector::from_vec(values))
}

/// Per-body errors of `theta` against the ground truth, when `data` is a physid log that
/// carries it.
pub fn truth_errors(data: &Path, m: &Model, theta: &DVector<f64>) -> Option<Vec<TruthError>> {
    let truth = ground_truth(data, m)?;
    let tm = m.with_parameters(&truth).ok()?;
    let errs = crate::experiment::body_errors(&tm, theta);
    Some(
        ident::bodies(m)
            .into_iter()
            .zip(errs)
            .map(
                |((name, _, _), [mass_rel, com_m, inertia_rel, j_rel])| TruthError {
                    name,
                    mass_rel,
                    com_m,
                    inertia_rel,
                    j_rel,
                },
            )
            .collect(),
    )
}

/// The effects a diagnosis report of this robot confirmed (its `effects[i]` with
/// `confirmed[i]` true), the report checked first: both arrays of one length, `confirmed` of
/// booleans, made for `model` (its robot name and joints), each term valid as `--effects`
/// would require. Errors name the file and the field.
pub fn confirmed_effects(path: &Path, model: &Model) -> Result<Vec<Variant>, ApiError> {
    let bad = |m: String| ApiError::invalid(path, m);
    let text = crate::io::read_to_string(path)?;
    let v: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| bad(format!("not JSON: {e}")))?;
    let (Some(effects), Some(confirmed)) = (v["effects"].as_array(), v["confirmed"].as_array())
    else {
        return Err(bad("not a diagnosis report (no effects and confirmed arrays; write one with `physid diagnose --out DIR`)".into()));
    };
    if effects.len() != confirmed.len() {
        return Err(bad(format!(
            "{} effects but {} confirmed flags: a report's arrays pair one to one",
            effects.len(),
            confirmed.len()
        )));
    }
    let joints: Vec<&str> = model.bodies.iter().map(|b| b.joint_name.as_str()).collect();
    let theirs: Option<Vec<&str>> = v["joints"]
        .as_array()
        .map(|j| j.iter().filter_map(|x| x.as_str()).collect());
    if v["robot"].as_str() != Some(model.name.as_str()) || theirs.as_deref() != Some(&joints[..]) {
        return Err(bad(format!(
            "the report is for robot {} with joints {:?}, not {} with joints {:?}",
            v["robot"],
            theirs.unwrap_or_default(),
            model.name,
            joints
        )));
    }
    let mut out = vec![];
    for (i, (e, ok)) in effects.iter().zip(confirmed).enumerate() {
        let Some(ok) = ok.as_bool() else {
            return Err(bad(format!("confirmed[{i}] is {ok}, not true or false")));
        };
        let variant = report_term(e, model).map_err(|m| bad(format!("effects[{i}]{m}")))?;
        if ok {
            out.push(variant);
        }
    }
    Ok(out)
}

/// One effect of a report as a term (`kind` or `kind:param`), checked as `--effects` would;
/// the error continues `effects[i]`.
fn report_term(e: &serde_json::Value, model: &Model) -> Result<Variant, String> {
    let kind = e["kind"].as_str().ok_or(".kind is not a string")?;
    let term = match &e["param"] {
        serde_json::Value::Null => kind.to_string(),
        p => match p.as_f64() {
            Some(0.0) => kind.to_string(),
            Some(p) => format!("{kind}:{p}"),
            None => return Err(format!(".param is {p}, not a number")),
        },
    };
    let variant = parse_term(&term).map_err(|m| format!(": {m}"))?;
    if variant.kind.gridded() && !variant.kind.valid_param(variant.param, model.dof()) {
        return Err(format!(
            ": {term}: {} out of range",
            variant.kind.grid_meaning()
        ));
    }
    Ok(variant)
}

/// The names of θ's entries: the model's, then each effect coefficient as `kind[i]`.
pub fn theta_names(m: &Model, terms: &[TermFit]) -> Vec<String> {
    let mut names = m.parameter_names();
    for t in terms {
        names.extend((0..t.coefficients.len()).map(|i| format!("{}[{i}]", t.kind.name())));
    }
    names
}

/// An identification and what scores it.
pub struct Fit {
    /// The identified model (and effect coefficients after it in `theta`).
    pub identified: ident::Identified,
    /// The model's own normal equations over the training spans.
    pub normal_equations: NormalEquations,
    /// The effect terms' fits (empty without terms).
    pub terms: Vec<TermFit>,
    /// The calibration (with its options), when there are effect terms.
    calibration: Option<(Calibration, CalOptions)>,
}

impl Fit {
    /// θ of the model's layout (without effect coefficients).
    pub fn model_theta(&self, m: &Model) -> DVector<f64> {
        self.identified.theta.rows(0, m.layout().len).into_owned()
    }

    /// Per-joint (`None` for locked joints) and overall RMS torque error over `spans` of
    /// `data` (N m), every sample the pipeline kept scored.
    pub fn errors(
        &self,
        m: &Model,
        data: &[Data],
        spans: &[Span],
        locked: &[usize],
    ) -> Result<(Vec<Option<f64>>, f64), ApiError> {
        if let Some((cal, copts)) = &self.calibration {
            let pieces = in_memory(data, spans);
            let (per, _) = crate::diagnose::calibrate::rms_error(m, cal, &as_runs(&pieces), copts);
            let count = pieces.iter().map(Trajectory::len).sum();
            return Ok(SquaredErrors::from_rms(&per, count).rms(locked));
        }
        let mut acc = SquaredErrors::new(m.dof());
        for s in spans {
            acc = acc + data[s.file].squared_errors(m, &self.identified.theta, s.range.clone())?;
        }
        Ok(acc.rms(locked))
    }
}

/// Identifies `m` from the `train` spans of `data` under `opts`: the model's own problem
/// (normal equations summed over the spans, streamed files included), or with effect `terms`
/// the calibration of [`crate::diagnose::calibrate`] (in memory); the `locked` joints' rows
/// left out.
pub fn fit(
    m: &Model,
    data: &[Data],
    train: &[Span],
    opts: &Options,
    terms: Vec<Variant>,
    locked: &[usize],
) -> Result<Fit, ApiError> {
    if terms.is_empty() {
        let mut ne = NormalEquations::new(m.dof(), m.layout().len)
            .excluding(locked)
            .finish();
        for s in train {
            ne = ne.merged(&data[s.file].normal_equations(m, s.range.clone(), locked)?);
        }
        let identified = ident::identify(m, &ne, &m.parameters(), opts)?;
        return Ok(Fit {
            identified,
            normal_equations: ne,
            terms: vec![],
            calibration: None,
        });
    }
    let pieces = in_memory(data, train);
    let cutoff = train
        .iter()
        .find_map(|s| data[s.file].report())
        .map_or(crate::prepare::default_cutoff(1e3), |r| r.cutoff);
    let copts = CalOptions {
        ident: opts.clone(),
        terms,
        processing_cutoff: cutoff,
        excluded: locked.to_vec(),
    };
    let cal = crate::diagnose::calibrate::calibrate(m, &as_runs(&pieces), &copts)?;
    Ok(Fit {
        identified: cal.identified.clone(),
        normal_equations: cal.rigid.clone(),
        terms: cal.terms.clone(),
        calibration: Some((cal, copts)),
    })
}

/// Whole trajectories as the calibration's runs.
fn as_runs(pieces: &[Trajectory]) -> Vec<Run<'_>> {
    pieces
        .iter()
        .map(|t| Run {
            trajectory: t,
            range: 0..t.len(),
        })
        .collect()
}
