//! `identify`'s JSON contract ([`IdentifyJson`], docs/identify-json.md, schema
//! docs/schemas/identify.schema.json), its default constraint set, the ground-truth errors of a
//! physid log, and the effects a diagnosis report confirmed (`--effects-from`).

use super::data::{
    bag_option_notices, file_notices, in_memory, locked_joints, Data, Notice, ReadOptions, Rms,
    Span, SquaredErrors,
};
use super::ApiError;
use crate::diagnose::calibrate::{parse_term, Calibration, Options as CalOptions, Run, TermFit};
use crate::effect::library::Variant;
use crate::ident::information::{Information, InformationError, ResidualStats};
use crate::ident::{self, analysis, ConstraintSet, NormalEquations, Options};
use crate::model::Model;
use crate::trajectory::Trajectory;
use nalgebra::DVector;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// One data file and what the pipeline did to it.
#[derive(Clone, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct DataJson {
    /// The file.
    pub file: PathBuf,
    /// Runs, gaps, bridged, trimmed and dropped samples, derived signals, locked and still
    /// joints.
    pub pipeline: crate::prepare::Report,
}

/// One body's errors against the ground truth.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
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
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
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
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
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
#[derive(serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct Friction {
    /// `B` (N m s/rad).
    pub viscous: Vec<f64>,
    /// `B_c` (N m).
    pub coulomb: Vec<f64>,
}

/// `identify --json` (docs/identify-json.md; JSON Schema docs/schemas/identify.schema.json).
#[derive(serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
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

/// A constraint set and, when it was chosen for the user, why.
#[derive(Clone, Debug, PartialEq)]
pub struct ChosenSet {
    /// The set identified under.
    pub set: ConstraintSet,
    /// Why it was the default (`None`: the user gave it).
    pub because: Option<String>,
}

/// The constraint set: the one given, else the tightest the description supports, and why
/// (`ellipsoid` when every body has a bounding ellipsoid, else `consistent`).
pub fn constraint_set(given: Option<ConstraintSet>, m: &Model) -> ChosenSet {
    if let Some(set) = given {
        return ChosenSet { set, because: None };
    }
    let missing: Vec<String> = ident::bodies(m)
        .into_iter()
        .filter(|(_, _, e)| e.is_none())
        .map(|(name, _, _)| name)
        .collect();
    if missing.is_empty() {
        ChosenSet {
            set: ConstraintSet::Ellipsoid,
            because: Some("every body has a bounding ellipsoid".into()),
        }
    } else {
        ChosenSet {
            set: ConstraintSet::Consistent,
            because: Some(format!(
                "no bounding ellipsoid for {} (give them in a sidecar, see docs/robot-format.md)",
                missing.join(", ")
            )),
        }
    }
}

/// The ground truth a physid MCAP log carries (its `ground_truth_parameters` metadata, in
/// `m`'s parameter order), if `path` is one and it matches `m`.
pub fn ground_truth(path: &Path, m: &Model) -> Option<DVector<f64>> {
    if path.extension().and_then(|e| e.to_str()) != Some("mcap") {
        return None;
    }
    // From the summary alone: a log of millions of samples is not read for it.
    let md = crate::io::mcap_stream::metadata(path, "ground_truth_parameters").ok()??;
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
    let joints: Vec<&str> = model
        .bodies()
        .iter()
        .map(|b| b.joint_name.as_str())
        .collect();
    let theirs: Option<Vec<&str>> = v["joints"]
        .as_array()
        .map(|j| j.iter().filter_map(|x| x.as_str()).collect());
    if v["robot"].as_str() != Some(model.name()) || theirs.as_deref() != Some(&joints[..]) {
        return Err(bad(format!(
            "the report is for robot {} with joints {:?}, not {} with joints {:?}",
            v["robot"],
            theirs.unwrap_or_default(),
            model.name(),
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
    ) -> Result<Rms, ApiError> {
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

impl Fit {
    /// The fit's information matrix over the model's parameters: `YᵀY` of the `train` spans
    /// (the `locked` joints' rows left out) over the noise `s² τ_c` of the fit's own residual
    /// (effect terms included), read in one more pass (streamed files again from disk); the
    /// inner error when the fit leaves no residual to weigh the data by.
    pub fn information(
        &self,
        m: &Model,
        data: &[Data],
        train: &[Span],
        locked: &[usize],
    ) -> Result<Result<Information, InformationError>, ApiError> {
        let mut stats = ResidualStats::new(m.dof());
        let mut fitted = vec![0.0; m.dof()];
        let mut push = |t: f64, r: &[f64]| {
            fitted.copy_from_slice(r);
            locked.iter().for_each(|&j| fitted[j] = f64::NAN);
            stats.push(t, &fitted);
        };
        if let Some((cal, copts)) = &self.calibration {
            let pieces = in_memory(data, train);
            crate::diagnose::calibrate::for_each_residual(
                m,
                cal,
                &as_runs(&pieces),
                copts,
                &mut push,
            );
        } else {
            let theta = self.model_theta(m);
            for s in train {
                data[s.file].for_each_residual(m, &theta, s.range.clone(), &mut push)?;
            }
        }
        let ne = &self.normal_equations;
        Ok(Information::new(
            m.parameter_names(),
            self.model_theta(m),
            &ne.yty,
            ne.samples,
            &stats,
        ))
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

/// The effect terms of `friction` (viscous and coulomb, the model's own and always listed,
/// plus any of `offset`, `direction`, `stribeck:<v>`) and `effects` (library terms such as
/// `tilt`, `cogging:<harmonic>`); errors name the flag.
pub fn parse_terms(friction: &[String], effects: &[String]) -> Result<Vec<Variant>, ApiError> {
    let mut out = vec![];
    let mut has = [false; 2];
    for f in friction {
        match f.trim() {
            "viscous" => has[0] = true,
            "coulomb" => has[1] = true,
            t if t == "offset" || t == "direction" || t.starts_with("stribeck") => out.push(
                parse_term(t).map_err(|e| ApiError::Options(format!("--friction: {e}")))?,
            ),
            t => return Err(ApiError::Options(format!("--friction: unknown term '{t}' (viscous, coulomb, offset, direction, stribeck:<v>)"))),
        }
    }
    if has != [true, true] {
        return Err(ApiError::Options("--friction: viscous and coulomb are the model's own friction (paper eq. 9) and always identified; list them, then the terms to add (e.g. viscous,coulomb,offset)".into()));
    }
    for e in effects {
        out.push(parse_term(e.trim()).map_err(|e| ApiError::Options(format!("--effects: {e}")))?);
    }
    Ok(out)
}

/// Samples `[start, end)` of a file as read (indices, end exclusive); an open side is the
/// file's first or last sample.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SampleRange {
    /// The first sample (default 0).
    pub start: Option<usize>,
    /// One past the last sample (default: the file's length).
    pub end: Option<usize>,
}

impl SampleRange {
    /// Parses `a:b` (either side may be empty); `what` names the option in errors.
    pub fn parse(s: &str, what: &str) -> Result<Self, ApiError> {
        let (a, b) = s.split_once(':').ok_or_else(|| {
            ApiError::Options(format!("{what}: '{s}' is not a range like 0:5000"))
        })?;
        let index = |x: &str| -> Result<Option<usize>, ApiError> {
            if x.is_empty() {
                return Ok(None);
            }
            x.parse()
                .map(Some)
                .map_err(|e| ApiError::Options(format!("{what}: '{x}' is not a sample index: {e}")))
        };
        Ok(SampleRange {
            start: index(a)?,
            end: index(b)?,
        })
    }

    /// The range within a file of `len` samples, or an error naming `what` when it is empty or
    /// reaches past the file.
    pub fn within(&self, len: usize, what: &str) -> Result<Range<usize>, ApiError> {
        let (a, b) = (self.start.unwrap_or(0), self.end.unwrap_or(len));
        if a >= b || b > len {
            return Err(ApiError::Options(format!(
                "{what}: {a}:{b} is not a non-empty range within the {len} samples"
            )));
        }
        Ok(a..b)
    }
}

/// What `identify` is asked: the runs, which samples train and validate, the constraint set,
/// the effect terms and the prior.
#[derive(Clone, Debug)]
pub struct IdentifyOptions {
    /// Training runs: physid MCAP logs, other MCAP files or rosbag2 directories with
    /// `JointState`, or CSV; joined without differentiating across their seams.
    pub data: Vec<PathBuf>,
    /// Held-out runs (all their samples).
    pub validate_data: Vec<PathBuf>,
    /// Training samples of the one training run (default all).
    pub train: Option<SampleRange>,
    /// Validation samples of the one training run (not with `validate_data`).
    pub validate: Option<SampleRange>,
    /// The constraint set; `None`: the tightest the description supports.
    pub constraints: Option<ConstraintSet>,
    /// Effect terms identified with the model (friction extras, library effects).
    pub terms: Vec<Variant>,
    /// Weight `w` of the prior term (the description's parameters as the prior).
    pub prior_weight: f64,
    /// Margin `ε` of the strict matrix inequalities.
    pub eps: f64,
    /// The prior term's form.
    pub regularizer: ident::Regularizer,
    /// How the files are read.
    pub read: ReadOptions,
    /// Accept fewer equations than parameters (the prior decides the rest).
    pub allow_few_samples: bool,
    /// Compute the fit's information matrix ([`Identification::information`]; one more pass
    /// over the training samples), which [`Identification::write_urdf`] writes into the
    /// sidecar as the description's uncertainty.
    pub information: bool,
    /// Each body's mass held within `[lo, hi]` times the description's (`0 ≤ lo ≤ 1 ≤ hi`):
    /// directions the data do not determine otherwise go wherever the constraints allow.
    pub mass_bounds: Option<MassBounds>,
    /// The robot's total moving mass (links and rotors) held within `lo..hi` kg: a scale's
    /// reading, where the data weigh only some bodies.
    pub total_mass: Option<TotalMass>,
}

impl IdentifyOptions {
    /// Training on `data`, every other option at its default (the CLI's).
    pub fn new(data: Vec<PathBuf>) -> Self {
        let defaults = Options::new(ConstraintSet::Consistent);
        IdentifyOptions {
            data,
            validate_data: vec![],
            train: None,
            validate: None,
            constraints: None,
            terms: vec![],
            prior_weight: defaults.prior_weight,
            eps: defaults.eps,
            regularizer: defaults.regularizer,
            read: ReadOptions::default(),
            allow_few_samples: false,
            information: false,
            mass_bounds: None,
            total_mass: None,
        }
    }

    /// The options checked against each other: at least one run; sample ranges only of one
    /// run; `validate` or `validate_data`, not both; the same recording never twice.
    pub fn validate(&self) -> Result<(), ApiError> {
        if self.data.is_empty() {
            return Err(ApiError::Options("--data: give at least one run".into()));
        }
        if self.data.len() > 1 && (self.train.is_some() || self.validate.is_some()) {
            return Err(ApiError::Options("--train and --validate pick samples of one --data file; with several runs, give whole runs (--validate-data for held-out runs)".into()));
        }
        if self.validate.is_some() && !self.validate_data.is_empty() {
            return Err(ApiError::Options(
                "give --validate or --validate-data, not both".into(),
            ));
        }
        super::data::check_distinct_runs(&[
            ("--data", &self.data),
            ("--validate-data", &self.validate_data),
        ])?;
        if let Some(MassBounds { lo, hi }) = self.mass_bounds {
            if !(lo.is_finite() && hi.is_finite() && (0.0..=1.0).contains(&lo) && hi >= 1.0) {
                return Err(ApiError::Options(format!(
                    "--mass-bounds {lo},{hi}: give factors of the description's masses with 0 <= LO <= 1 <= HI (e.g. 0.5,2), so that the description itself lies within them"
                )));
            }
        }
        if let Some(TotalMass { lo, hi }) = self.total_mass {
            if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo <= hi) {
                return Err(ApiError::Options(format!(
                    "--total-mass {lo},{hi}: give the robot's moving mass in kg as LO,HI with 0 < LO <= HI (e.g. 3.5,3.9)"
                )));
            }
        }
        Ok(())
    }

    /// The identification's options for `m` under `set`, checked.
    pub fn ident(&self, m: &Model, set: ConstraintSet) -> Result<Options, ApiError> {
        let mut opts = Options::new(set);
        opts.prior_weight = self.prior_weight;
        opts.eps = self.eps;
        opts.regularizer = self.regularizer;
        if let Some(MassBounds { lo, hi }) = self.mass_bounds {
            opts.mass_bounds = (m.bodies().iter().enumerate())
                .map(|(i, b)| (10 * i, lo * b.inertia.mass(), hi * b.inertia.mass()))
                .collect();
        }
        if let Some(TotalMass { lo, hi }) = self.total_mass {
            opts.total_mass = Some((mass_columns(m), lo, hi));
        }
        opts.validate()?;
        Ok(opts)
    }

    /// Every data file, training runs first.
    fn files(&self) -> Vec<&Path> {
        self.data
            .iter()
            .chain(&self.validate_data)
            .map(PathBuf::as_path)
            .collect()
    }
}

/// The data read for an identification: the files, and which samples train and validate.
struct Opened {
    data: Vec<Data>,
    train: Vec<Span>,
    validation: Vec<Span>,
    locked: Vec<usize>,
    notices: Vec<Notice>,
}

/// Opens the runs (large CSV files streamed unless effect terms need them in memory) and
/// picks the training and validation spans.
fn open(m: &Model, o: &IdentifyOptions) -> Result<Opened, ApiError> {
    let paths = o.files();
    let read = o.read.resolve(m)?;
    let mut notices = bag_option_notices(&paths, &read)?;
    let data = Data::open_all(&paths, m, &read, !o.terms.is_empty())?;
    for (path, d) in paths.iter().zip(&data) {
        if let Data::Memory(loaded) = d {
            notices.extend(file_notices(path, loaded));
        }
    }
    let reports = data.iter().filter_map(|d| match d {
        Data::Memory(loaded) => Some(&loaded.report),
        _ => None,
    });
    if o.terms.is_empty() {
        // With effect terms the cutoff also processes their columns (as the diagnosis does).
        notices.extend(super::data::unused_cutoff_notice(&read, reports));
    }
    let whole = |files: Range<usize>| -> Vec<Span> {
        files
            .map(|file| Span {
                file,
                range: 0..data[file].len(),
            })
            .collect()
    };
    let first = |r: &SampleRange, what: &str| -> Result<Vec<Span>, ApiError> {
        Ok(vec![Span {
            file: 0,
            range: r.within(data[0].len(), what)?,
        }])
    };
    let n_train = o.data.len();
    let train = match &o.train {
        Some(r) => first(r, "--train")?,
        None => whole(0..n_train),
    };
    let validation = match &o.validate {
        Some(r) => first(r, "--validate")?,
        None => whole(n_train..data.len()),
    };
    let locked = locked_joints(m, &data);
    Ok(Opened {
        data,
        train,
        validation,
        locked,
        notices,
    })
}

/// What one identification found, with its scores and what the data pipeline did: the
/// report behind `identify`'s text and JSON.
#[derive(serde::Serialize, serde::Deserialize)]
pub struct Identification {
    /// The identified model (effect coefficients after the model's parameters in `theta`).
    pub identified: ident::Identified,
    /// The effect terms' fits (empty without terms).
    pub terms: Vec<TermFit>,
    /// The terms as a scenario `[[effects]]` snippet.
    pub snippet: Option<String>,
    /// The constraint set identified under.
    pub set: ConstraintSet,
    /// Why the default constraint set was chosen (when none was given).
    pub set_note: Option<String>,
    /// The training runs (files, sample ranges, samples fitted) and the RMS torque error on
    /// them.
    pub train: Split,
    /// The validation runs and the RMS error on them, when anything was held out.
    pub validation: Option<Split>,
    /// Which parameters the data determine.
    pub identifiability: analysis::Identifiability,
    /// Errors against the ground truth a physid log carries (one training run only).
    pub truth_errors: Option<Vec<TruthError>>,
    /// Wall time of the fit (s): normal equations (streamed files read again), solve.
    pub total_seconds: f64,
    /// What the pipeline did to each file read in memory.
    pub data: Vec<DataJson>,
    /// Joints whose torque is not fitted.
    pub locked: Vec<String>,
    /// The model's own normal equations over the training samples.
    pub normal_equations: NormalEquations,
    /// Notes and warnings about the data and the answer, in the order they arose.
    pub notices: Vec<Notice>,
    /// The fit's information matrix over the model's parameters when asked
    /// ([`IdentifyOptions::information`]), or why there is none (a fit without residual).
    pub information: Option<Result<Information, InformationError>>,
}

/// Identifies `m` from the runs of `o`: reads them, fits under the constraint set, scores the
/// fit on the training and validation samples and reports identifiability and (for a physid
/// log) the errors against its ground truth.
pub fn identify(m: &Model, o: &IdentifyOptions) -> Result<Identification, ApiError> {
    identify_reporting(m, o, &mut |_| {})
}

/// [`identify`], handing each notice to `notify` as it arises (what the pipeline did to each
/// file before the fit, warnings about the answer after it), so a caller shows them even when
/// the fit then fails; the report keeps them all in `notices` too.
pub fn identify_reporting(
    m: &Model,
    o: &IdentifyOptions,
    notify: &mut dyn FnMut(&Notice),
) -> Result<Identification, ApiError> {
    o.validate()?;
    let chosen = constraint_set(o.constraints, m);
    let opts = o.ident(m, chosen.set)?;
    let opened = open(m, o)?;
    opened.notices.iter().for_each(&mut *notify);
    check_equations(m, o, &opened)?;
    check_validation(o, &opened)?;
    let start = std::time::Instant::now();
    let fit = fit(
        m,
        &opened.data,
        &opened.train,
        &opts,
        o.terms.clone(),
        &opened.locked,
    )?;
    let total = start.elapsed().as_secs_f64();
    let seen = opened.notices.len();
    let information = match o.information {
        true => Some(fit.information(m, &opened.data, &opened.train, &opened.locked)),
        false => None,
    };
    let mut report = score(m, o, fit, chosen, opened, total)?;
    report.information = information.transpose()?;
    report.notices[seen..].iter().for_each(notify);
    Ok(report)
}

/// Enough equations for the parameters, unless the user accepts a fit decided by the prior.
fn check_equations(m: &Model, o: &IdentifyOptions, d: &Opened) -> Result<(), ApiError> {
    let samples: usize = d.train.iter().map(|s| d.data[s.file].used(&s.range)).sum();
    let p = m.layout().len + crate::diagnose::calibrate::columns(&o.terms, m.dof());
    let equations = samples * (m.dof() - d.locked.len());
    if equations < p && !o.allow_few_samples {
        return Err(ApiError::invalid(
            &o.data[0],
            format!("{samples} samples give {equations} equations for {p} parameters: the fit is decided by the prior; give more samples, or --allow-few-samples if that is what you want"),
        ));
    }
    Ok(())
}

/// Validation samples that the data pipeline keeps, when any were asked for: a range inside
/// the trimmed ends scored "0.0000 N m" from no sample.
fn check_validation(o: &IdentifyOptions, d: &Opened) -> Result<(), ApiError> {
    let used: usize = (d.validation.iter())
        .map(|s| d.data[s.file].used(&s.range))
        .sum();
    if d.validation.is_empty() || used > 0 {
        return Ok(());
    }
    let what = match &o.validate {
        Some(r) => format!(
            "--validate {}:{}",
            r.start.unwrap_or(0),
            r.end.map_or(String::new(), |e| e.to_string())
        ),
        None => "--validate-data".into(),
    };
    Err(ApiError::invalid(
        o.files()[d.validation[0].file],
        format!("{what}: none of these samples is kept by the data pipeline (the ends trimmed for the filter's settling, gaps, or joints too slow): nothing to validate on; pick samples further from the ends"),
    ))
}

/// The samples `spans` of `data` (read from `files`) and their torque error `rms`, as the
/// report states a split.
fn split_of(files: &[&Path], data: &[Data], spans: &[Span], rms: Rms) -> Split {
    Split {
        range: spans.first().map(|s| [s.range.start, s.range.end]),
        runs: spans
            .iter()
            .map(|s| RunRange {
                file: files[s.file].to_path_buf(),
                range: [s.range.start, s.range.end],
                samples_used: data[s.file].used(&s.range),
            })
            .collect(),
        rms: rms.per_joint,
        rms_overall: rms.overall,
    }
}

/// Each file read whole with its pipeline's report (a streamed file has none).
fn data_reports(files: &[&Path], data: &[Data]) -> Vec<DataJson> {
    files
        .iter()
        .zip(data)
        .filter_map(|(f, data)| {
            data.report().map(|r| DataJson {
                file: f.to_path_buf(),
                pipeline: r.clone(),
            })
        })
        .collect()
}

/// The fit scored on the training and validation spans, with its identifiability, what the
/// data pipeline did and warnings where the data cannot support the answer.
fn score(
    m: &Model,
    o: &IdentifyOptions,
    fit: Fit,
    chosen: ChosenSet,
    d: Opened,
    total_seconds: f64,
) -> Result<Identification, ApiError> {
    let train_rms = fit.errors(m, &d.data, &d.train, &d.locked)?;
    let validation_rms = if d.validation.is_empty() {
        None
    } else {
        Some(fit.errors(m, &d.data, &d.validation, &d.locked)?)
    };
    let identifiability = analysis::identifiability(m, &fit.normal_equations, &fit.model_theta(m));
    let files = o.files();
    let split = |spans: &[Span], rms: Rms| split_of(&files, &d.data, spans, rms);
    let train = split(&d.train, train_rms);
    let validation = validation_rms.map(|rms| split(&d.validation, rms));
    let mut notices = d.notices.clone();
    notices.extend(weak_data_warnings(o, &d, &identifiability));
    notices.extend(far_mass_warnings(m, &fit.identified, &identifiability));
    notices.extend(bound_mass_notes(m, o, &fit.identified));
    notices.extend(total_mass_notes(m, o, &fit.identified));
    // Effect terms are fitted on data read whole (never streamed), whose report holds the
    // sample period the snippet's delays are counted in.
    let snippet = d.data[0]
        .report()
        .filter(|_| !fit.terms.is_empty())
        .map(|r| crate::diagnose::calibrate::scenario_snippet(m, &fit.terms, r.period));
    let data = data_reports(&files, &d.data);
    Ok(Identification {
        truth_errors: (o.data.len() == 1)
            .then(|| truth_errors(&o.data[0], m, &fit.identified.theta))
            .flatten(),
        identified: fit.identified,
        terms: fit.terms,
        snippet,
        set: chosen.set,
        set_note: chosen.because,
        train,
        validation,
        identifiability,
        total_seconds,
        data,
        locked: d
            .locked
            .iter()
            .map(|&j| m.bodies()[j].joint_name.clone())
            .collect(),
        normal_equations: fit.normal_equations,
        notices,
        information: None,
    })
}

/// Warnings where the data cannot support the answer: validation samples that are also
/// training samples, and data that excite far fewer parameter directions than the model has.
fn weak_data_warnings(
    o: &IdentifyOptions,
    d: &Opened,
    idf: &analysis::Identifiability,
) -> Vec<Notice> {
    let mut out = vec![];
    let train = &d.train[0].range;
    if let (Some(_), Some(v)) = (&o.validate, d.validation.first()) {
        let v = &v.range;
        let overlap = v
            .end
            .min(train.end)
            .saturating_sub(v.start.max(train.start));
        if overlap > 0 {
            out.push(Notice::warning(format!(
                "--train {}:{} and --validate {}:{} share {overlap} samples: the validation error is not a held-out error",
                train.start, train.end, v.start, v.end
            )));
        }
    }
    if 2 * idf.rank < idf.parameters {
        out.push(Notice::warning(format!(
            "the data excite {} of {} parameter directions: the rest comes from the prior (the robot description), not from the data; record a motion that moves every joint",
            idf.rank, idf.parameters
        )));
    }
    out
}

/// The problem as data, for independent solvers (scripts/check_cvxpy.py): the objective
/// `θᵀ H θ − 2 gᵀ θ + c` as identification builds it ([`ident::objective`]) and, per body, its
/// parameter columns and ellipsoid; `r` is physid's answer to it.
pub fn problem_json(
    m: &Model,
    ne: &crate::ident::NormalEquations,
    opts: &Options,
    r: &ident::Identified,
) -> serde_json::Value {
    use serde_json::json;
    let prior = &m.parameters();
    let ident::Objective { h, g, c } = ident::objective(m, ne, prior, opts);
    let rows: Vec<Vec<f64>> = h.row_iter().map(|r| r.iter().copied().collect()).collect();
    let bodies: Vec<_> = ident::bodies(m)
        .into_iter()
        .map(|(name, col, e)| json!({"name": name, "col": col, "ellipsoid": e.map(|e| json!({"center": e.center.as_slice(), "qs": e.qs.as_slice()}))}))
        .collect();
    let l = m.layout();
    json!({
        "constraints": opts.constraints, "eps": opts.eps, "H": rows, "g": g.as_slice(), "c": c,
        "regularizer": opts.regularizer, "w": opts.prior_weight, "prior": prior.as_slice(),
        "bodies": bodies, "friction_cols": (l.viscous_col..l.len).collect::<Vec<_>>(),
        "physid": {"objective": r.objective, "theta": r.theta.as_slice(), "status": r.solver.status},
    })
}

/// The robot's total moving mass held within `[lo, hi]` kg (`--total-mass LO,HI`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TotalMass {
    /// The lowest total (kg, > 0).
    pub lo: f64,
    /// The highest total (kg, ≥ lo).
    pub hi: f64,
}

impl std::str::FromStr for TotalMass {
    type Err = String;

    /// Two numbers `LO,HI` in kg; their range is checked by [`IdentifyOptions::validate`].
    fn from_str(s: &str) -> Result<Self, String> {
        let MassBounds { lo, hi } = s
            .parse::<MassBounds>()
            .map_err(|e| e.replace("0.5,2", "3.5,3.9 kg"))?;
        Ok(TotalMass { lo, hi })
    }
}

/// Each body's mass held within `[lo, hi]` times the description's (`--mass-bounds LO,HI`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MassBounds {
    /// The lowest factor (0 ≤ lo ≤ 1).
    pub lo: f64,
    /// The highest factor (hi ≥ 1).
    pub hi: f64,
}

impl std::str::FromStr for MassBounds {
    type Err = String;

    /// Two numbers `LO,HI`; their range is checked by [`IdentifyOptions::validate`].
    fn from_str(s: &str) -> Result<Self, String> {
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        let [lo, hi] = parts.as_slice() else {
            return Err(format!("'{s}': give two numbers LO,HI (e.g. 0.5,2)"));
        };
        let number = |x: &str| {
            x.parse::<f64>()
                .map_err(|_| format!("'{x}' in '{s}' is not a number (give LO,HI, e.g. 0.5,2)"))
        };
        Ok(MassBounds {
            lo: number(lo)?,
            hi: number(hi)?,
        })
    }
}

/// Each body of `m` with its described and identified mass (kg).
fn masses<'a>(
    m: &'a Model,
    identified: &'a ident::Identified,
) -> impl Iterator<Item = (&'a crate::model::Body, f64, f64)> + 'a {
    m.bodies().iter().filter_map(|body| {
        let fitted = identified.bodies.iter().find(|b| b.name == body.name)?;
        Some((body, body.inertia.mass(), fitted.pi[0]))
    })
}

/// A body's identified mass is far from its description's beyond this factor (either way).
pub const FAR_MASS: f64 = 2.0;

/// Warnings for each body whose identified mass is more than [`FAR_MASS`] times its
/// description's, or less than its inverse (bodies the description gives less than 1 g are
/// left out), each saying whether the data determine that mass or the constraints placed it
/// (standard error finite and below the mass). Directions the data do not determine go where
/// the constraints allow: on a low-cost arm a 0.65 kg link came out at 9.4 kg, consistent and
/// absurd.
fn far_mass_warnings(
    m: &Model,
    identified: &ident::Identified,
    idf: &analysis::Identifiability,
) -> Vec<Notice> {
    let names = m.parameter_names();
    let masses = masses(m, identified).map(|(body, described, mass)| {
        let se = mass_column(&names, &body.name).map_or(f64::INFINITY, |c| idf.standard_errors[c]);
        (body.name.as_str(), described, mass, se)
    });
    let remedy = "bound it (a prior: --regularizer logdet --prior-weight, or geometry for the ellipsoid set) or record a motion that moves this body";
    far_masses(masses, remedy)
}

/// The column of `body`'s mass (`"<body>.m"`) among the parameters' `names`.
pub fn mass_column(names: &[String], body: &str) -> Option<usize> {
    names.iter().position(|n| *n == format!("{body}.m"))
}

/// Whether the data determine a body's `mass` (kg) on their own: its standard error `se` is
/// finite and smaller than the mass.
pub fn mass_determined(se: f64, mass: f64) -> bool {
    se.is_finite() && se < mass.abs()
}

/// [`far_mass_warnings`] for any robot: `masses` gives each body's name, described and
/// identified mass and the identified mass's standard error (kg, infinite where the data do
/// not determine it); `remedy` what the user can do about a mass the data do not determine.
pub(crate) fn far_masses<'a>(
    masses: impl Iterator<Item = (&'a str, f64, f64, f64)>,
    remedy: &str,
) -> Vec<Notice> {
    let mut out = vec![];
    for (body, described, mass, se) in masses {
        let ratio = mass / described;
        if described < 1e-3 || (1.0 / FAR_MASS..=FAR_MASS).contains(&ratio) {
            continue;
        }
        let why = if mass_determined(se, mass) {
            format!("the data determine it (standard error {se:.3} kg): the description's mass or the data's torque scale is off")
        } else {
            format!("the data do not determine it: the constraints placed it where they allow; {remedy}")
        };
        out.push(Notice::warning(format!(
            "'{body}': identified mass {mass:.3} kg is {ratio:.2} times the description's {described:.3} kg; {why}"
        )));
    }
    out
}

/// A note for each body whose identified mass lies on a bound of `o.mass_bounds` (within 10⁻⁴
/// of the bound's width): the data, or the constraints, would have put it beyond; a warning
/// where a mass lies outside its bounds (the solver did not hold them: checked from the
/// parameters, as the constraint set is).
fn bound_mass_notes(m: &Model, o: &IdentifyOptions, identified: &ident::Identified) -> Vec<Notice> {
    let Some(MassBounds { lo, hi }) = o.mass_bounds else {
        return vec![];
    };
    let mut out = vec![];
    for (body, described, mass) in masses(m, identified) {
        let near = |factor: f64| (mass - factor * described).abs() <= 1e-4 * (hi - lo) * described;
        let slack = 1e-6 * described;
        if mass < lo * described - slack || mass > hi * described + slack {
            out.push(Notice::warning(format!(
                "'{}': mass {mass:.6} kg is outside its bounds {lo}..{hi} times the description's {described:.6} kg: the solver did not hold them",
                body.name
            )));
            continue;
        }
        for (factor, which) in [(lo, "lower"), (hi, "upper")] {
            if described > 0.0 && near(factor) {
                out.push(Notice::note(format!(
                    "'{}': mass {mass:.3} kg at the {which} bound, {factor} times the description's {described:.3} kg (--mass-bounds): the fit would put it beyond",
                    body.name
                )));
            }
        }
    }
    out
}

/// The columns of θ holding a mass: each link's, then each rotor's (their sum is the robot's
/// moving mass, `--total-mass`).
fn mass_columns(m: &Model) -> Vec<usize> {
    let rotors = m.layout().rotor_col.iter().flatten().copied();
    (0..m.dof()).map(|i| 10 * i).chain(rotors).collect()
}

/// A note when the identified total moving mass (links and rotors) lies on a bound of
/// `o.total_mass` (within 10⁻⁴ of the bounds' width), a warning when outside it (checked from
/// the parameters) or when the description's own total is outside it.
fn total_mass_notes(m: &Model, o: &IdentifyOptions, identified: &ident::Identified) -> Vec<Notice> {
    let Some(TotalMass { lo, hi }) = o.total_mass else {
        return vec![];
    };
    let total: f64 = mass_columns(m).iter().map(|&c| identified.theta[c]).sum();
    let described = m.total_mass();
    let mut out = vec![];
    if !(lo..=hi).contains(&described) {
        out.push(Notice::warning(format!(
            "--total-mass {lo},{hi}: the description's own total is {described:.3} kg, outside the bounds: check the scale's reading and what it weighed (links and rotors that move, not the base)"
        )));
    }
    let slack = 1e-6 * hi;
    if total < lo - slack || total > hi + slack {
        out.push(Notice::warning(format!(
            "total moving mass {total:.6} kg is outside --total-mass {lo},{hi}: the solver did not hold it"
        )));
    } else if let Some(which) = [(lo, "lower"), (hi, "upper")]
        .into_iter()
        .find(|(b, _)| (total - b).abs() <= 1e-4 * (hi - lo).max(1e-3 * hi))
        .map(|(_, w)| w)
    {
        out.push(Notice::note(format!(
            "total moving mass {total:.3} kg at the {which} bound of --total-mass {lo},{hi}: the fit would put it beyond"
        )));
    }
    out
}

impl Identification {
    /// θ of the model's layout (without effect coefficients).
    pub fn model_theta(&self, m: &Model) -> DVector<f64> {
        self.identified.theta.rows(0, m.layout().len).into_owned()
    }

    /// The identified model: `m` with the identified inertias and friction.
    pub fn model(&self, m: &Model) -> Result<Model, ApiError> {
        let r = &self.identified;
        let im = m
            .with_parameters(&self.model_theta(m))?
            .with_bodies_edited(|j, b| {
                b.friction.viscous = r.viscous[j];
                b.friction.coulomb = r.coulomb[j];
            })?;
        Ok(im)
    }

    /// Writes the identified model as URDF at `path`: the URDF of `robot` (as given to load
    /// `m`) with only its `<inertial>` and `<dynamics>` changed, plus the sidecar; a warning
    /// when its inertias are not physically consistent.
    pub fn write_urdf(&self, path: &Path, robot: &str, m: &Model) -> Result<Vec<Notice>, ApiError> {
        let im = self.model(m)?;
        let extra = [
            self.snippet.as_ref().map(|fx| {
                format!("\n# Identified effects (physid identify), as a scenario's [[effects]] tables.\n{fx}")
            }),
            self.information
                .as_ref()
                .and_then(|i| i.as_ref().ok())
                .map(Information::sidecar_table),
        ]
        .into_iter()
        .flatten()
        .collect::<String>();
        crate::io::export_urdf(
            path,
            robot,
            m,
            &im,
            Some(extra.as_str()).filter(|s| !s.is_empty()),
        )?;
        let consistent =
            ident::constraints_hold(m, &self.model_theta(m), ConstraintSet::Consistent);
        let mut notices = vec![];
        if !self.identified.constraints_hold || !consistent {
            notices.push(Notice::warning(format!(
                "{} holds physically inconsistent inertias (identified with '{}')",
                path.display(),
                self.set.name()
            )));
        }
        if let Some(Err(e)) = &self.information {
            notices.push(Notice::warning(format!(
                "{}: no information matrix in the sidecar ({e}): a diagnosis of it takes the description's uncertainty from --description-uncertainty alone",
                path.display()
            )));
        }
        Ok(notices)
    }

    /// The bodies that are not physically consistent (`J(π)` not positive definite), each
    /// with its smallest eigenvalue of `J`.
    pub fn inconsistent_bodies(&self) -> Vec<String> {
        self.identified
            .bodies
            .iter()
            .filter(|b| {
                b.consistency.min_eig_pseudo.is_nan() || b.consistency.min_eig_pseudo <= 0.0
            })
            .map(|b| {
                format!(
                    "{} (min eig J = {:.3e})",
                    b.name, b.consistency.min_eig_pseudo
                )
            })
            .collect()
    }

    /// The report as `identify --json` (docs/identify-json.md).
    pub fn json(&self, m: &Model) -> IdentifyJson {
        let r = &self.identified;
        IdentifyJson {
            data: self.train.runs[0].file.clone(),
            robot: m.name().to_string(),
            constraints: self.set,
            constraints_default_because: self.set_note.clone(),
            train: self.train.clone(),
            validation: self.validation.clone(),
            bodies: r.bodies.clone(),
            friction: Friction {
                viscous: r.viscous.clone(),
                coulomb: r.coulomb.clone(),
            },
            effects: self.terms.clone(),
            scenario_effects: self.snippet.clone(),
            objective: r.objective,
            constraints_hold: r.constraints_hold,
            solver: r.solver.clone(),
            end_to_end_seconds: self.total_seconds,
            identifiability: self.identifiability.clone(),
            parameter_names: theta_names(m, &self.terms),
            theta: r.theta.as_slice().to_vec(),
            truth_errors: self.truth_errors.clone(),
            data_pipeline: self.data.clone(),
            locked_joints: self.locked.clone(),
        }
    }
}
