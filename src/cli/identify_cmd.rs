//! `physid identify`.

use super::RobotArgs;
use anyhow::{anyhow, bail, Context};
use physid::api::data::{locked_joints, Data, Span};
use physid::api::identify::{
    confirmed_effects, constraint_set, theta_names, truth_errors, DataJson, Fit, Friction,
    IdentifyJson, RunRange, Split, TruthError,
};
use physid::diagnose::calibrate::parse_term;
use physid::diagnose::library::Variant;
use physid::ident::{self, analysis, ConstraintSet, NormalEquations, Options};
use physid::model::Model;
use serde_json::json;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Parses `a:b` (sample indices, end exclusive; either side may be empty).
pub fn parse_range(s: &str, len: usize, what: &str) -> anyhow::Result<Range<usize>> {
    let (a, b) = s
        .split_once(':')
        .with_context(|| format!("{what}: '{s}' is not a range like 0:5000"))?;
    let a: usize = if a.is_empty() {
        0
    } else {
        a.parse()
            .with_context(|| format!("{what}: '{a}' is not a sample index"))?
    };
    let b: usize = if b.is_empty() {
        len
    } else {
        b.parse()
            .with_context(|| format!("{what}: '{b}' is not a sample index"))?
    };
    if a >= b || b > len {
        bail!("{what}: {a}:{b} is not a non-empty range within the {len} samples");
    }
    Ok(a..b)
}

/// How data files are read and prepared: `--topic` and `--stamp` for MCAP files and rosbag2
/// directories; the pipeline's cutoff and locked joints for all.
#[derive(clap::Args, Debug, Clone)]
pub struct ReadArgs {
    /// The `sensor_msgs/msg/JointState` topic of an MCAP file or rosbag2 directory (default:
    /// physid's processed signals if the log has them, else /joint_states).
    #[arg(long)]
    topic: Option<String>,
    /// Which time stamps a joint state: log (the recorder's receive time) or header (the
    /// message's header.stamp, when the driver sampled the joints).
    #[arg(long, default_value = "log")]
    stamp: physid::io::mcap_log::Stamp,
    /// Low-pass cutoff (Hz) of the signals derived from the log (q̈, and q̇ when not logged):
    /// zero-phase 2nd-order Butterworth. Default: 20 Hz, at most a tenth of the sample rate.
    #[arg(long, allow_negative_numbers = true)]
    cutoff: Option<f64>,
    /// Joints to hold at their logged position (q̇ = q̈ = 0; their torque is not fitted), e.g.
    /// a gripper that never moves; comma-separated names.
    #[arg(long, value_delimiter = ',')]
    lock: Vec<String>,
    /// Fit only these joints' torques; every other joint is locked (comma-separated names).
    #[arg(long, value_delimiter = ',', conflicts_with = "lock")]
    only: Vec<String>,
}

impl ReadArgs {
    /// The library's reading options for `model` (`--only` becomes the other joints locked).
    pub fn options(&self, model: &Model) -> anyhow::Result<physid::io::DataOptions> {
        let joints: Vec<String> = model.bodies.iter().map(|b| b.joint_name.clone()).collect();
        for j in self.lock.iter().chain(&self.only) {
            if !joints.contains(j) {
                bail!(
                    "--{}: the robot has no joint '{j}' (its joints: {})",
                    if self.only.is_empty() { "lock" } else { "only" },
                    joints.join(", ")
                );
            }
        }
        let lock = if self.only.is_empty() {
            self.lock.clone()
        } else {
            joints
                .into_iter()
                .filter(|j| !self.only.contains(j))
                .collect()
        };
        if let Some(c) = self.cutoff.filter(|c| !(c.is_finite() && *c > 0.0)) {
            bail!("--cutoff must be a positive frequency in Hz, got {c}");
        }
        Ok(physid::io::DataOptions {
            topic: self.topic.clone(),
            stamp: self.stamp,
            prepare: physid::prepare::Options {
                cutoff: self.cutoff,
                lock,
                band_edge: None,
            },
        })
    }
    /// Whether any reading option applies only to bags (for a warning on other files).
    fn bag_only(&self) -> bool {
        self.topic.is_some() || self.stamp != physid::io::mcap_log::Stamp::Log
    }
}

/// `--topic` and `--stamp` given for no bag at all are an error (they cannot mean what the
/// user meant); given with some bags, a warning for each other file.
fn check_bag_options(paths: &[&Path], read: &ReadArgs) -> anyhow::Result<()> {
    let is_bag = |p: &Path| p.is_dir() || p.extension().and_then(|e| e.to_str()) == Some("mcap");
    if !read.bag_only() {
        return Ok(());
    }
    if let Some(first) = paths.first().filter(|_| !paths.iter().any(|p| is_bag(p))) {
        bail!(
            "{}: --topic and --stamp apply to MCAP files and rosbag2 directories only, and no data file given is one",
            first.display()
        );
    }
    for path in paths.iter().filter(|p| !is_bag(p)) {
        eprintln!(
            "warning: {}: --topic and --stamp apply to MCAP files and rosbag2 directories only",
            path.display()
        );
    }
    Ok(())
}

/// Loads data files read together (see [`physid::io::load_all`]: one cutoff for all),
/// printing what the pipeline did to each and warnings.
pub fn load_data(
    paths: &[&Path],
    model: &Model,
    read: &ReadArgs,
) -> anyhow::Result<Vec<physid::io::LoadedData>> {
    check_bag_options(paths, read)?;
    let loaded = physid::io::load_all(paths, model, &read.options(model)?)?;
    for (path, l) in paths.iter().zip(&loaded) {
        print_notes(path, l);
    }
    Ok(loaded)
}

/// Opens data files read together, large CSV files streamed unless `in_memory`
/// ([`Data::open_all`]), printing what the pipeline did to each file read in memory.
fn open_data(
    paths: &[&Path],
    model: &Model,
    read: &ReadArgs,
    in_memory: bool,
) -> anyhow::Result<Vec<Data>> {
    check_bag_options(paths, read)?;
    let data = Data::open_all(paths, model, &read.options(model)?, in_memory)?;
    for (path, d) in paths.iter().zip(&data) {
        if let Data::Memory(loaded) = d {
            print_notes(path, loaded);
        }
    }
    Ok(data)
}

/// What the pipeline did to one file, on standard error.
fn print_notes(path: &Path, loaded: &physid::io::LoadedData) {
    if !loaded.ignored_joints.is_empty() {
        eprintln!(
            "note: {} has joints the robot does not have, left out: {}",
            path.display(),
            loaded.ignored_joints.join(", ")
        );
    }
    if loaded.skipped_messages > 0 {
        eprintln!(
            "note: {}: {} joint-state messages name none of the robot's joints (another publisher on the topic), skipped",
            path.display(),
            loaded.skipped_messages
        );
    }
    for line in data_notes(&loaded.report) {
        eprintln!(
            "{}: {}: {line}",
            if line.starts_with("joint") {
                "warning"
            } else {
                "note"
            },
            path.display()
        );
    }
}

/// What the pipeline did to one file, one line per kind of change (nothing for clean data
/// with accelerations).
pub fn data_notes(r: &physid::prepare::Report) -> Vec<String> {
    use physid::prepare::TimeBase;
    let mut out = vec![];
    if !r.gaps.is_empty() {
        let gaps: Vec<String> = r
            .gaps
            .iter()
            .take(5)
            .map(|g| format!("{:+.3} s before sample {}", g.seconds, g.sample))
            .collect();
        out.push(format!(
            "split into {} runs at {} time jump{} ({}{}): no signal is differentiated across them",
            r.runs + usize::from(r.dropped_short > 0),
            r.gaps.len(),
            if r.gaps.len() == 1 { "" } else { "s" },
            gaps.join(", "),
            if r.gaps.len() > 5 { ", …" } else { "" }
        ));
    }
    if r.missing_bridged > 0 {
        out.push(format!(
            "{} missing samples bridged at {} places (the derivatives interpolate across them)",
            r.missing_bridged, r.dropouts_bridged
        ));
    }
    if r.duplicates > 0 {
        out.push(format!("{} duplicated samples dropped", r.duplicates));
    }
    match r.time_base {
        TimeBase::Uniform => {}
        TimeBase::Stamps => out.push(format!("time stamps scatter by {:.1} % of the period (RMS); the samples agree with their stamps, which are used", 100.0 * r.jitter)),
        TimeBase::ClockSlots => out.push(format!("time stamps scatter by {:.1} % of the period (RMS); the samples agree with a uniform clock, so each is placed at its clock slot", 100.0 * r.jitter)),
    }
    if r.derived_qd || r.derived_qdd {
        let what = match (r.derived_qd, r.derived_qdd) {
            (true, true) => "no velocities or accelerations: q̇ and q̈ derived",
            (true, false) => "no velocities: q̇ derived",
            _ => "no accelerations: q̈ derived",
        };
        out.push(format!(
            "{what} (central difference, zero-phase {:.3} Hz Butterworth{}); {} samples trimmed at the ends of the runs ({} at each end, the filter's settling){}",
            r.cutoff,
            r.band_edge.map_or(String::new(), |e| format!(", 4 times the motion's band edge {e:.3} Hz over all files read")),
            r.trimmed,
            r.settle_samples,
            if r.dropped_short > 0 { format!(", {} samples of pieces too short to keep", r.dropped_short) } else { String::new() }
        ));
    }
    if r.samples_kept < r.samples_read {
        out.push(format!(
            "{} of {} samples used",
            r.samples_kept, r.samples_read
        ));
    }
    for j in &r.unmeasured {
        out.push(format!("joint '{j}': its torque is zero in every sample (not measured): locked, its torque is not fitted"));
    }
    let asked: Vec<&String> = r
        .locked
        .iter()
        .filter(|j| !r.unmeasured.contains(j))
        .collect();
    if !asked.is_empty() {
        out.push(format!(
            "locked (held at their logged position, torque not fitted): {}",
            asked
                .iter()
                .map(|s| s.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    for j in r.still.iter().filter(|j| !r.locked.contains(j)) {
        out.push(format!("joint '{j}' never moves: its friction cannot be identified from these data (lock it with --lock {j}, or record a motion that moves it)"));
    }
    out
}

/// Identify inertial and friction parameters under a constraint set.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Samples, one or more runs: physid MCAP logs (their processed signals), other MCAP files
    /// or rosbag2 directories with JointState, or CSV. Runs are joined without differentiating
    /// across their seams.
    #[arg(long, num_args = 1.., required = true)]
    data: Vec<PathBuf>,
    #[command(flatten)]
    read: ReadArgs,
    #[command(flatten)]
    robot: RobotArgs,
    /// Constraint set: none, semi, consistent, ellipsoid. Default: the tightest the
    /// description supports (ellipsoid when every body has a bounding ellipsoid, else
    /// consistent).
    #[arg(long)]
    constraints: Option<ConstraintSet>,
    /// Exit with code 1 (after writing every output) when an identified body is not
    /// physically consistent (J(π) not positive definite), e.g. under `--constraints none`.
    #[arg(long)]
    require_consistent: bool,
    /// Training samples, `a:b` (indices, end exclusive); default all. One --data file only.
    #[arg(long, allow_hyphen_values = true)]
    train: Option<String>,
    /// Validation samples of the same file, `a:b`. One --data file only.
    #[arg(long, allow_hyphen_values = true)]
    validate: Option<String>,
    /// Validate on other runs (all their samples).
    #[arg(long, num_args = 1..)]
    validate_data: Vec<PathBuf>,
    /// Friction terms per joint, comma-separated: viscous and coulomb (always; the model's own,
    /// paper eq. 9), plus any of offset (a torque offset), direction (direction-dependent
    /// Coulomb), stribeck:<v> (Stribeck excess with velocity v rad/s).
    #[arg(long, value_delimiter = ',', default_value = "viscous,coulomb")]
    friction: Vec<String>,
    /// Effect terms from the diagnosis library, comma-separated (e.g. tilt,time_delay,
    /// torque_gain,payload; cogging:<harmonic>; compliance:<1/k of the secant>, default the tangent); see docs/diagnose.md.
    #[arg(long, value_delimiter = ',')]
    effects: Vec<String>,
    /// Take the effects a diagnosis confirmed: its report.json (`physid diagnose --out`).
    #[arg(long)]
    effects_from: Option<PathBuf>,
    /// Write the identified effects as a scenario `[[effects]]` snippet (TOML), so `simulate`
    /// replays the calibrated robot.
    #[arg(long)]
    out_effects: Option<PathBuf>,
    /// Weight of the prior term w ‖θ − θ̂‖² (θ̂: the robot description's parameters).
    #[arg(long, default_value_t = 1e-6, allow_negative_numbers = true)]
    prior_weight: f64,
    /// Margin ε of the strict matrix inequalities.
    #[arg(long, default_value_t = 1e-6, allow_negative_numbers = true)]
    eps: f64,
    /// Print JSON (schema: docs/identify-json.md).
    #[arg(long)]
    json: bool,
    /// Write the identified model as URDF: the robot's own URDF with only its `<inertial>` and
    /// `<dynamics>` changed (a new file for a built-in robot), plus a sidecar `<name>.physid.toml`
    /// with what URDF cannot carry (bounding ellipsoids, sidecar rotors, identified effects).
    #[arg(long)]
    out_urdf: Option<PathBuf>,
    /// Write the optimization problem as JSON (for scripts/check_cvxpy.py).
    #[arg(long)]
    export_problem: Option<PathBuf>,
    /// Accept fewer equations than parameters (the prior then decides the rest).
    #[arg(long)]
    allow_few_samples: bool,
    /// Prior term: euclidean (w ‖θ − θ̂‖², the paper) or logdet (w Σ Bregman divergence of
    /// −log det between J and the prior's J; Lee, Wensing & Park).
    #[arg(long, default_value = "euclidean")]
    regularizer: ident::Regularizer,
}

/// The effect terms from `--friction`, `--effects` and `--effects-from`.
fn terms(a: &Args, model: &Model) -> anyhow::Result<Vec<Variant>> {
    let mut out = vec![];
    let mut has = [false; 2];
    for f in &a.friction {
        match f.trim() {
            "viscous" => has[0] = true,
            "coulomb" => has[1] = true,
            t if t == "offset" || t == "direction" || t.starts_with("stribeck") => {
                out.push(parse_term(t).map_err(|e| anyhow!("--friction: {e}"))?)
            }
            t => bail!("--friction: unknown term '{t}' (viscous, coulomb, offset, direction, stribeck:<v>)"),
        }
    }
    if has != [true, true] {
        bail!("--friction: viscous and coulomb are the model's own friction (paper eq. 9) and always identified; list them, then the terms to add (e.g. viscous,coulomb,offset)");
    }
    for e in &a.effects {
        out.push(parse_term(e.trim()).map_err(|e| anyhow!("--effects: {e}"))?);
    }
    if let Some(p) = &a.effects_from {
        out.extend(confirmed_effects(p, model)?);
    }
    Ok(out)
}

/// Runs the identification and prints the report.
pub fn run(a: Args) -> anyhow::Result<()> {
    check_paths(&a)?;
    let model = a.robot.load()?;
    let m = &model;
    let (set, set_note) = constraint_set(a.constraints, m);
    let opts = options(&a, set)?;
    let terms = terms(&a, m)?;
    if a.export_problem.is_some() && !terms.is_empty() {
        bail!("--export-problem writes the model's own problem: leave out the extra --friction terms and --effects");
    }
    let in_memory = !terms.is_empty();
    let paths: Vec<&Path> = a
        .data
        .iter()
        .chain(&a.validate_data)
        .map(PathBuf::as_path)
        .collect();
    let roles: Vec<(&str, &Path)> = (a.data.iter().map(|p| ("--data", p.as_path())))
        .chain(
            a.validate_data
                .iter()
                .map(|p| ("--validate-data", p.as_path())),
        )
        .collect();
    physid::io::check_distinct_recordings(&roles)?;
    // Training files first, then the validation files: one data set, parts of it as spans.
    let data = open_data(&paths, m, &a.read, in_memory)?;
    let n_train = a.data.len();
    let train: Vec<Span> = match a.train.as_deref() {
        Some(s) => vec![Span {
            file: 0,
            range: parse_range(s, data[0].len(), "--train")?,
        }],
        None => (0..n_train)
            .map(|file| Span {
                file,
                range: 0..data[file].len(),
            })
            .collect(),
    };
    let validation: Vec<Span> = match a.validate.as_deref() {
        Some(s) => vec![Span {
            file: 0,
            range: parse_range(s, data[0].len(), "--validate")?,
        }],
        None => (n_train..data.len())
            .map(|file| Span {
                file,
                range: 0..data[file].len(),
            })
            .collect(),
    };
    let locked = locked_joints(m, &data);
    let samples: usize = train.iter().map(|s| data[s.file].used(&s.range)).sum();
    let p = m.layout().len + physid::diagnose::calibrate::columns(&terms, m.dof());
    let equations = samples * (m.dof() - locked.len());
    if equations < p && !a.allow_few_samples {
        bail!(
            "{}: {samples} samples give {equations} equations for {p} parameters: the fit is decided by the prior; give more samples, or --allow-few-samples if that is what you want",
            a.data[0].display(),
        );
    }
    let start = std::time::Instant::now();
    let fit = physid::api::identify::fit(m, &data, &train, &opts, terms, &locked)?;
    let total = start.elapsed().as_secs_f64();
    let report = score(
        &a,
        m,
        fit,
        (set, set_note),
        &data,
        (&train, &validation),
        &locked,
        total,
    )?;
    write_outputs(&a, m, &report)?;
    if a.json {
        print_json(&a, m, &report)?;
    } else {
        print_text(&a, m, &report);
    }
    if a.require_consistent {
        require_consistent(&report.r)?;
    }
    Ok(())
}

/// Outputs never onto inputs or each other; `--train`/`--validate` with one data file and
/// without `--validate-data`.
fn check_paths(a: &Args) -> anyhow::Result<()> {
    let robot_file = Path::new(&a.robot.robot);
    let mut inputs: Vec<&Path> = a.data.iter().map(PathBuf::as_path).collect();
    inputs.push(robot_file);
    inputs.extend(a.validate_data.iter().map(PathBuf::as_path));
    inputs.extend(a.effects_from.as_deref());
    let robot_files = a.robot.files();
    inputs.extend(robot_files.iter().map(PathBuf::as_path));
    let sidecar = a.out_urdf.as_deref().map(physid::io::sidecar_path);
    let outputs: Vec<&Path> = [&a.out_urdf, &a.export_problem, &a.out_effects, &sidecar]
        .into_iter()
        .flatten()
        .map(PathBuf::as_path)
        .collect();
    physid::io::check_outputs(&outputs, &inputs)?;
    if a.data.len() > 1 && (a.train.is_some() || a.validate.is_some()) {
        bail!("--train and --validate pick samples of one --data file; with several runs, give whole runs (--validate-data for held-out runs)");
    }
    if a.validate.is_some() && !a.validate_data.is_empty() {
        bail!("give --validate or --validate-data, not both");
    }
    Ok(())
}

/// The data files read: training and held-out.
/// The fit scored on the training and validation spans, with its identifiability and what
/// the data pipeline did.
#[allow(clippy::too_many_arguments)]
fn score(
    a: &Args,
    m: &Model,
    fit: Fit,
    (set, set_note): (ConstraintSet, Option<String>),
    data: &[Data],
    (train, validation): (&[Span], &[Span]),
    locked: &[usize],
    total: f64,
) -> anyhow::Result<Report> {
    let (train_rms, train_all) = fit.errors(m, data, train, locked)?;
    let val = if validation.is_empty() {
        None
    } else {
        Some(fit.errors(m, data, validation, locked)?)
    };
    let idf = analysis::identifiability(m, &fit.normal_equations, &fit.model_theta(m));
    let ranges =
        |spans: &[Span]| -> Vec<Range<usize>> { spans.iter().map(|s| s.range.clone()).collect() };
    let used = |spans: &[Span]| -> Vec<usize> {
        spans.iter().map(|s| data[s.file].used(&s.range)).collect()
    };
    let vrange = validation
        .first()
        .map(|s| &s.range)
        .filter(|_| a.data.len() == 1);
    warn_weak_data(&train[0].range, vrange, a.validate.is_some(), &idf);
    let dt = data[0].report().map_or(1e-3, |r| r.period);
    let snippet = (!fit.terms.is_empty())
        .then(|| physid::diagnose::calibrate::scenario_snippet(m, &fit.terms, dt));
    let pipelines = a
        .data
        .iter()
        .chain(&a.validate_data)
        .zip(data)
        .filter_map(|(f, d)| {
            d.report().map(|r| DataJson {
                file: f.clone(),
                pipeline: r.clone(),
            })
        })
        .collect();
    Ok(Report {
        idf,
        truth_errors: (a.data.len() == 1)
            .then(|| truth_errors(&a.data[0], m, &fit.identified.theta))
            .flatten(),
        r: fit.identified.clone(),
        terms: fit.terms.clone(),
        snippet,
        set,
        set_note,
        train: ranges(train),
        train_rms,
        train_all,
        vranges: ranges(validation),
        val,
        total,
        used: (used(train), used(validation)),
        data: pipelines,
        locked: locked
            .iter()
            .map(|&j| m.bodies[j].joint_name.clone())
            .collect(),
        fit,
    })
}

/// `--require-consistent`: every body physically consistent (`J(π) ≻ 0`), or exit code 1
/// naming the bodies that are not.
fn require_consistent(r: &ident::Identified) -> anyhow::Result<()> {
    let bad: Vec<String> = r
        .bodies
        .iter()
        .filter(|b| b.consistency.min_eig_pseudo.is_nan() || b.consistency.min_eig_pseudo <= 0.0)
        .map(|b| {
            format!(
                "{} (min eig J = {:.3e})",
                b.name, b.consistency.min_eig_pseudo
            )
        })
        .collect();
    if bad.is_empty() {
        Ok(())
    } else {
        Err(super::Failed(format!(
            "--require-consistent: {} of {} bodies are not physically consistent: {}",
            bad.len(),
            r.bodies.len(),
            bad.join(", ")
        ))
        .into())
    }
}

/// `--out-urdf`, `--out-effects` and `--export-problem`.
fn write_outputs(a: &Args, m: &Model, rep: &Report) -> anyhow::Result<()> {
    if let Some(p) = &a.out_urdf {
        write_urdf(p, &a.robot.robot, rep, m)?;
    }
    match (&a.out_effects, &rep.snippet) {
        (Some(p), Some(s)) => physid::io::write_atomic(p, s.as_bytes())?,
        (Some(p), None) => bail!(
            "--out-effects {}: no effect terms were identified (give --friction extras, --effects or --effects-from)",
            p.display()
        ),
        _ => {}
    }
    if let Some(p) = &a.export_problem {
        let opts = options(a, rep.set)?;
        export_problem(p, a, rep.set, m, &rep.fit.normal_equations, &opts, &rep.r)?;
    }
    Ok(())
}

/// Warnings where the data cannot support the answer: validation samples that are also
/// training samples, and data that excite far fewer parameter directions than the model has.
fn warn_weak_data(
    train: &Range<usize>,
    validate: Option<&Range<usize>>,
    same_file: bool,
    idf: &analysis::Identifiability,
) {
    if let Some(v) = validate.filter(|_| same_file) {
        let overlap = v
            .end
            .min(train.end)
            .saturating_sub(v.start.max(train.start));
        if overlap > 0 {
            eprintln!(
                "warning: --train {}:{} and --validate {}:{} share {overlap} samples: the validation error is not a held-out error",
                train.start, train.end, v.start, v.end
            );
        }
    }
    if 2 * idf.rank < idf.parameters {
        eprintln!(
            "warning: the data excite {} of {} parameter directions: the rest comes from the prior (the robot description), not from the data; record a motion that moves every joint",
            idf.rank, idf.parameters
        );
    }
}

/// The identification's options from the flags, checked.
fn options(a: &Args, set: ConstraintSet) -> anyhow::Result<Options> {
    let mut opts = Options::new(set);
    opts.prior_weight = a.prior_weight;
    opts.eps = a.eps;
    opts.regularizer = a.regularizer;
    opts.validate().map_err(super::option_error)?;
    Ok(opts)
}

/// What one identification found, for the outputs.
struct Report {
    r: ident::Identified,
    /// The effect terms' fits (empty without terms).
    terms: Vec<physid::diagnose::calibrate::TermFit>,
    /// The terms as a scenario `[[effects]]` snippet.
    snippet: Option<String>,
    set: ConstraintSet,
    /// Why the default constraint set was chosen (when none was given).
    set_note: Option<String>,
    /// Training samples per run.
    train: Vec<Range<usize>>,
    train_rms: Vec<Option<f64>>,
    train_all: f64,
    /// Validation samples per validation run.
    vranges: Vec<Range<usize>>,
    val: Option<(Vec<Option<f64>>, f64)>,
    idf: analysis::Identifiability,
    truth_errors: Option<Vec<TruthError>>,
    total: f64,
    /// Samples fitted per training run and scored per validation run (after the pipeline).
    used: (Vec<usize>, Vec<usize>),
    /// What the pipeline did to each file read in memory.
    data: Vec<DataJson>,
    /// Joints whose torque is not fitted.
    locked: Vec<String>,
    /// The fit itself (normal equations, calibration), for the outputs.
    fit: Fit,
}

/// Writes the identified model as URDF, warning when its inertias are not consistent.
fn write_urdf(p: &Path, robot: &str, rep: &Report, m: &Model) -> anyhow::Result<()> {
    let r = &rep.r;
    let theta = r.theta.rows(0, m.layout().len).into_owned();
    let mut im = m.with_parameters(&theta)?;
    for (j, b) in im.bodies.iter_mut().enumerate() {
        b.friction.viscous = r.viscous[j];
        b.friction.coulomb = r.coulomb[j];
    }
    physid::io::export_urdf(p, robot, m, &im, rep.snippet.as_deref())?;
    if !r.constraints_hold || !ident::constraints_hold(m, &theta, ConstraintSet::Consistent) {
        eprintln!(
            "warning: {} holds physically inconsistent inertias (identified with '{}')",
            p.display(),
            rep.set.name()
        );
    }
    Ok(())
}

/// The problem as data, for independent solvers (scripts/check_cvxpy.py): the objective
/// `θᵀ H θ − 2 gᵀ θ + c` as identification builds it ([`ident::objective`]) and, per body, its
/// parameter columns and ellipsoid.
fn export_problem(
    p: &Path,
    a: &Args,
    set: ConstraintSet,
    m: &Model,
    ne: &NormalEquations,
    opts: &Options,
    r: &ident::Identified,
) -> anyhow::Result<()> {
    let prior = &m.parameters();
    let ident::Objective { h, g, c } = ident::objective(m, ne, prior, opts);
    let rows: Vec<Vec<f64>> = h.row_iter().map(|r| r.iter().copied().collect()).collect();
    let bodies: Vec<_> = ident::bodies(m)
        .into_iter()
        .map(|(name, col, e)| json!({"name": name, "col": col, "ellipsoid": e.map(|e| json!({"center": e.center.as_slice(), "qs": e.qs.as_slice()}))}))
        .collect();
    let l = m.layout();
    let v = json!({
        "constraints": set, "eps": a.eps, "H": rows, "g": g.as_slice(), "c": c,
        "regularizer": a.regularizer, "w": a.prior_weight, "prior": prior.as_slice(),
        "bodies": bodies, "friction_cols": (l.viscous_col..l.len).collect::<Vec<_>>(),
        "physid": {"objective": r.objective, "theta": r.theta.as_slice(), "status": r.solver.status},
    });
    let v = physid::io::versioned("problem", &v);
    physid::io::write_atomic(p, serde_json::to_string(&v)?.as_bytes())?;
    Ok(())
}

/// The JSON report (docs/identify-json.md).
fn print_json(a: &Args, m: &Model, rep: &Report) -> anyhow::Result<()> {
    let r = &rep.r;
    let runs = |files: &[PathBuf], ranges: &[Range<usize>], used: &[usize]| -> Vec<RunRange> {
        files
            .iter()
            .zip(ranges)
            .zip(used)
            .map(|((f, r), &u)| RunRange {
                file: f.clone(),
                range: [r.start, r.end],
                samples_used: u,
            })
            .collect()
    };
    let vfiles: &[PathBuf] = if a.validate.is_some() {
        &a.data[..1]
    } else {
        &a.validate_data
    };
    let v = IdentifyJson {
        data: a.data[0].clone(),
        robot: m.name.clone(),
        constraints: rep.set,
        constraints_default_because: rep.set_note.clone(),
        train: Split {
            range: Some([rep.train[0].start, rep.train[0].end]),
            runs: runs(&a.data, &rep.train, &rep.used.0),
            rms: rep.train_rms.clone(),
            rms_overall: rep.train_all,
        },
        validation: rep.val.as_ref().map(|(rms, all)| Split {
            range: rep.vranges.first().map(|r| [r.start, r.end]),
            runs: runs(vfiles, &rep.vranges, &rep.used.1),
            rms: rms.clone(),
            rms_overall: *all,
        }),
        bodies: r.bodies.clone(),
        friction: Friction {
            viscous: r.viscous.clone(),
            coulomb: r.coulomb.clone(),
        },
        effects: rep.terms.clone(),
        scenario_effects: rep.snippet.clone(),
        objective: r.objective,
        constraints_hold: r.constraints_hold,
        solver: r.solver.clone(),
        end_to_end_seconds: rep.total,
        identifiability: rep.idf.clone(),
        parameter_names: theta_names(m, &rep.terms),
        theta: r.theta.as_slice().to_vec(),
        truth_errors: rep.truth_errors.clone(),
        data_pipeline: rep.data.clone(),
        locked_joints: rep.locked.clone(),
    };
    let v = physid::io::versioned("identify", &v);
    println!("{}", serde_json::to_string_pretty(&v)?);
    Ok(())
}

/// The text report: bodies, friction, effects, errors, consistency, identifiability, truth.
fn print_text(a: &Args, m: &Model, rep: &Report) {
    print_header(a, m, rep);
    print_identified_bodies(m, rep);
    print_joints(m, rep);
    print_terms(&rep.terms, m);
    print_fit(rep);
    print_identifiability(&rep.idf);
    if let Some(errs) = &rep.truth_errors {
        println!("\nagainst the ground truth in the log (relative errors; CoM in m):");
        println!(
            "{:<12} {:>10} {:>10} {:>12} {:>10}",
            "body", "mass", "CoM", "inertia_C", "J"
        );
        for e in errs {
            println!(
                "{:<12} {:>10.4} {:>10.4} {:>12.4} {:>10.4}",
                e.name, e.mass_rel, e.com_m, e.inertia_rel, e.j_rel
            );
        }
    }
}

/// Robot, set, data, parameter count and solve time.
fn print_header(a: &Args, m: &Model, rep: &Report) {
    let r = &rep.r;
    let used: usize = rep.used.0.iter().sum();
    let on = if a.data.len() == 1 {
        format!(
            "samples {}..{} of {} ({used} used)",
            rep.train[0].start,
            rep.train[0].end,
            a.data[0].display()
        )
    } else {
        let files: Vec<String> = a.data.iter().map(|p| p.display().to_string()).collect();
        format!(
            "{used} samples of {} runs ({})",
            a.data.len(),
            files.join(", ")
        )
    };
    let own = m.layout().len;
    let extra = r.theta.len() - own;
    let count = if extra > 0 {
        format!("{own} parameters of the model + {extra} effect coefficients")
    } else {
        format!("{own} parameters")
    };
    println!(
        "{}: '{}' on {on} ({count}), {} in {:.1} ms ({} iterations, {:.1} ms end to end)",
        m.name,
        rep.set.name(),
        r.solver.status,
        r.solver.seconds * 1e3,
        r.solver.iterations,
        rep.total * 1e3
    );
    if let Some(why) = &rep.set_note {
        println!("constraints '{}' by default: {why}", rep.set.name());
    }
}

/// Each body's identified mass properties; a mass the data do not determine is marked `~`.
fn print_identified_bodies(m: &Model, rep: &Report) {
    let names = m.parameter_names();
    let se = &rep.idf.standard_errors;
    let mut undetermined = 0;
    let (rows, marks): (Vec<_>, Vec<char>) = rep
        .r
        .bodies
        .iter()
        .map(|b| {
            let pi = physid::spatial::InertialParams(nalgebra::SVector::from(b.pi));
            let col = names.iter().position(|n| *n == format!("{}.m", b.name));
            let mark = match col.map(|c| se[c]) {
                Some(e) if e.is_finite() && e < pi.mass().abs() => ' ',
                _ => {
                    undetermined += 1;
                    '~'
                }
            };
            ((b.name.clone(), pi, b.consistency.clone()), mark)
        })
        .unzip();
    super::model_cmd::print_bodies_marked(&rows, &marks);
    if undetermined > 0 {
        println!(
            "~ {undetermined} of {} masses are not determined by the data on their own (no finite standard error, or one larger than the mass): the prior and the constraints set them; the base parameters below are what the data determine",
            rows.len()
        );
    }
}

/// Friction and RMS per joint; friction the data cannot determine (a locked joint, or one that
/// never moves) shows `—`.
fn print_joints(m: &Model, rep: &Report) {
    let r = &rep.r;
    let width = m
        .bodies
        .iter()
        .map(|b| b.joint_name.len())
        .max()
        .unwrap_or(5)
        .max(14);
    println!(
        "\n{:<width$} {:>12} {:>12} {:>12} {:>14}",
        "joint", "B [Nms/rad]", "Bc [Nm]", "train RMS", "validation RMS"
    );
    let cell = |x: Option<f64>| x.map_or("locked".to_string(), |v| format!("{v:.4}"));
    let still: Vec<&String> = rep
        .data
        .iter()
        .flat_map(|d| d.pipeline.still.iter())
        .collect();
    for (j, b) in m.bodies.iter().enumerate() {
        let known = rep.train_rms[j].is_some() && !still.contains(&&b.joint_name);
        let friction = |v: f64| {
            if known {
                format!("{v:.4}")
            } else {
                "—".into()
            }
        };
        println!(
            "{:<width$} {:>12} {:>12} {:>12} {:>14}",
            b.joint_name,
            friction(r.viscous[j]),
            friction(r.coulomb[j]),
            cell(rep.train_rms[j]),
            rep.val.as_ref().map_or("-".into(), |(v, _)| cell(v[j]))
        );
    }
}

/// Overall RMS, consistency and the constraints' state.
fn print_fit(rep: &Report) {
    let r = &rep.r;
    println!(
        "overall RMS: train {:.4} N m{}",
        rep.train_all,
        rep.val
            .as_ref()
            .map_or(String::new(), |(_, v)| format!(", validation {v:.4} N m"))
    );
    let inconsistent: Vec<&str> = r
        .bodies
        .iter()
        .filter(|b| b.consistency.min_eig_pseudo <= 0.0)
        .map(|b| b.name.as_str())
        .collect();
    println!(
        "physically consistent (J > 0 for every body): {}",
        if inconsistent.is_empty() {
            "yes".to_string()
        } else {
            format!("NO ({})", inconsistent.join(", "))
        }
    );
    println!(
        "constraints of '{}': {}; objective {:.6e}",
        rep.set.name(),
        if rep.set == ConstraintSet::None {
            "none imposed"
        } else if r.constraints_hold {
            "all hold"
        } else {
            "do NOT all hold"
        },
        r.objective
    );
}

/// Rank, conditioning, the base parameters with their errors, and the null directions.
fn print_identifiability(idf: &analysis::Identifiability) {
    println!(
        "\nidentifiability on the training samples: the model's {} parameters have rank {} (condition number {:.2e}; unit-norm columns, singular values above 3.2e-5 of the largest), {} unidentifiable directions",
        idf.parameters, idf.rank, idf.condition, idf.unidentifiable_total
    );
    println!("base parameters (what the data determine), value ± standard error:");
    for (i, b) in idf.base.iter().enumerate() {
        println!(
            "  β{:<3} {:>12.5e} ± {:<10.2e} {}",
            i + 1,
            b.value,
            b.standard_error,
            b.expression
        );
    }
    for u in &idf.unidentifiable {
        println!("  unidentifiable: {u}");
    }
    if idf.unidentifiable.len() < idf.unidentifiable_total {
        println!(
            "  (and {} more unidentifiable directions; all in --json)",
            idf.unidentifiable_total - idf.unidentifiable.len()
        );
    }
}

/// The ground-truth θ in a physid MCAP's metadata, if its parameter names match the model's.
/// Below this identifiable fraction an effect coefficient is reported as absorbed.
const ABSORBED: f64 = 0.1;

/// The identified effect terms, one line per magnitude.
fn print_terms(terms: &[physid::diagnose::calibrate::TermFit], m: &Model) {
    if terms.is_empty() {
        return;
    }
    println!("\neffect terms (identified with the model):");
    for t in terms {
        let (what, unit) = t.magnitude;
        let values: Vec<String> = t.magnitudes.iter().map(|v| format!("{v:.4}")).collect();
        let per = if t.magnitudes.len() == m.dof() {
            "per joint"
        } else {
            "robot"
        };
        let param = if t.param > 0.0 {
            format!(" ({})", t.param)
        } else {
            String::new()
        };
        println!(
            "  {}{param}: {what} [{unit}], {per}: {}",
            t.kind.name(),
            values.join(" ")
        );
        let fractions: Vec<String> = t.identifiable.iter().map(|f| format!("{f:.2}")).collect();
        println!(
            "    identifiable fraction per coefficient: {}",
            fractions.join(" ")
        );
        if t.identifiable.iter().any(|&f| f < ABSORBED) {
            eprintln!(
                "warning: {} is largely absorbed by the inertial parameters on these data (identifiable fraction below {ABSORBED}): its value there is not meaningful; test it against the description with `physid diagnose --description-uncertainty`",
                t.kind.name()
            );
        }
    }
}
