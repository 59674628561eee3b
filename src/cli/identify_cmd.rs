//! `physid identify`.

use super::RobotArgs;
use anyhow::{bail, Context};
use physid::ident::{self, analysis, ConstraintSet, NormalEquations, Options};
use physid::io::samples;
use physid::model::Model;
use physid::trajectory::Trajectory;
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

/// Loads identification data (see [`physid::io::load_trajectory`]).
pub fn load_data(path: &Path, model: &Model) -> anyhow::Result<Trajectory> {
    let loaded = physid::io::load_trajectory(path, model)?;
    if !loaded.ignored_joints.is_empty() {
        eprintln!(
            "note: {} has joints the robot does not have, left out: {}",
            path.display(),
            loaded.ignored_joints.join(", ")
        );
    }
    if loaded.derived_qdd {
        eprintln!(
            "note: {} has no ddq columns; q̈ = zero-phase {} Hz Butterworth of the central difference of q̇",
            path.display(),
            physid::signal::DERIVED_QDD_CUTOFF
        );
    }
    Ok(loaded.trajectory)
}

/// Identification data: in memory, or a CSV with q̈ streamed from disk (memory independent of
/// its length).
pub enum Data {
    /// Loaded samples.
    Memory(Trajectory),
    /// A streamable CSV and its sample count.
    Csv(std::path::PathBuf, usize),
}

impl Data {
    /// Opens `path`: CSV files with `ddq` columns stream, everything else is loaded.
    pub fn open(path: &Path, model: &Model) -> anyhow::Result<Data> {
        if path.extension().and_then(|e| e.to_str()) == Some("csv")
            && physid::io::samples::csv_has_ddq(path)?
        {
            let len = physid::io::samples::stream_csv(path, model.dof(), 0..0, &mut |_, _| {})?;
            return Ok(Data::Csv(path.to_path_buf(), len));
        }
        Ok(Data::Memory(load_data(path, model)?))
    }
    fn len(&self) -> usize {
        match self {
            Data::Memory(t) => t.len(),
            Data::Csv(_, n) => *n,
        }
    }
    fn normal_equations(&self, m: &Model, r: Range<usize>) -> anyhow::Result<NormalEquations> {
        Ok(match self {
            Data::Memory(t) => NormalEquations::from_trajectory(m, t, r),
            Data::Csv(p, _) => {
                NormalEquations::from_stream(m, |sink| samples::stream_csv(p, m.dof(), r, sink))?.0
            }
        })
    }
    fn rms(
        &self,
        m: &Model,
        theta: &nalgebra::DVector<f64>,
        r: Range<usize>,
    ) -> anyhow::Result<(Vec<f64>, f64)> {
        Ok(match self {
            Data::Memory(t) => analysis::rms_error(m, theta, t, r),
            Data::Csv(p, _) => analysis::rms_error_stream(m, theta, |sink| {
                samples::stream_csv(p, m.dof(), r, sink)
            })?,
        })
    }
}

/// Identify inertial and friction parameters under a constraint set.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Samples: a physid MCAP (its processed signals), another MCAP with JointState, or CSV.
    #[arg(long)]
    data: PathBuf,
    #[command(flatten)]
    robot: RobotArgs,
    /// Constraint set: none, semi, consistent, ellipsoid.
    #[arg(long, default_value = "ellipsoid")]
    constraints: ConstraintSet,
    /// Training samples, `a:b` (indices, end exclusive); default all.
    #[arg(long, allow_hyphen_values = true)]
    train: Option<String>,
    /// Validation samples of the same file, `a:b`.
    #[arg(long, allow_hyphen_values = true)]
    validate: Option<String>,
    /// Validate on another file (all its samples).
    #[arg(long)]
    validate_data: Option<PathBuf>,
    /// Weight of the prior term w ‖θ − θ̂‖² (θ̂: the robot description's parameters).
    #[arg(long, default_value_t = 1e-6, allow_negative_numbers = true)]
    prior_weight: f64,
    /// Margin ε of the strict matrix inequalities.
    #[arg(long, default_value_t = 1e-6, allow_negative_numbers = true)]
    eps: f64,
    /// Print JSON (schema: docs/identify-json.md).
    #[arg(long)]
    json: bool,
    /// Write the identified model as URDF.
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

/// Runs the identification and prints the report.
pub fn run(a: Args) -> anyhow::Result<()> {
    let opts = options(&a)?;
    let robot_file = std::path::Path::new(&a.robot.robot);
    let mut inputs = vec![a.data.as_path(), robot_file];
    inputs.extend(a.validate_data.as_deref());
    let outputs: Vec<&Path> = a
        .out_urdf
        .iter()
        .chain(&a.export_problem)
        .map(|p| p.as_path())
        .collect();
    physid::io::check_outputs(&outputs, &inputs)?;
    let model = a.robot.load()?;
    let m = &model;
    let tr = Data::open(&a.data, m)?;
    let train = match a.train.as_deref() {
        Some(s) => parse_range(s, tr.len(), "--train")?,
        None => 0..tr.len(),
    };
    let vdata;
    let (vtr, vrange) = match (a.validate.as_deref(), a.validate_data.as_deref()) {
        (Some(_), Some(_)) => bail!("give --validate or --validate-data, not both"),
        (Some(s), None) => (Some(&tr), Some(parse_range(s, tr.len(), "--validate")?)),
        (None, Some(p)) => {
            vdata = Data::open(p, m)?;
            let r = 0..vdata.len();
            (Some(&vdata), Some(r))
        }
        (None, None) => (None, None),
    };
    let p = m.layout().len;
    if train.len() * m.dof() < p && !a.allow_few_samples {
        bail!(
            "{}: {} samples give {} equations for {p} parameters: the fit is decided by the prior; give more samples, or --allow-few-samples if that is what you want",
            a.data.display(),
            train.len(),
            train.len() * m.dof()
        );
    }
    let start = std::time::Instant::now();
    let ne = tr.normal_equations(m, train.clone())?;
    let prior = m.parameters();
    let r = ident::identify(m, &ne, &prior, &opts)?;
    let total = start.elapsed().as_secs_f64();
    let (train_rms, train_all) = tr.rms(m, &r.theta, train.clone())?;
    let val = match vtr.zip(vrange.clone()) {
        Some((v, rg)) => Some(v.rms(m, &r.theta, rg)?),
        None => None,
    };
    let idf = analysis::identifiability(m, &ne, &r.theta);
    warn_weak_data(&train, vrange.as_ref(), a.validate.is_some(), &idf);
    let report = Report {
        idf,
        truth_errors: truth_errors(&a.data, m, &r.theta),
        r,
        train,
        train_rms,
        train_all,
        vrange,
        val,
        total,
    };
    if let Some(p) = &a.out_urdf {
        write_urdf(p, &a, m, &report.r)?;
    }
    if let Some(p) = &a.export_problem {
        export_problem(p, &a, m, &ne, &prior, &opts, &report.r)?;
    }
    if a.json {
        print_json(&a, m, &report)
    } else {
        print_text(&a, m, &report);
        Ok(())
    }
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
fn options(a: &Args) -> anyhow::Result<Options> {
    let mut opts = Options::new(a.constraints);
    opts.prior_weight = a.prior_weight;
    opts.eps = a.eps;
    opts.regularizer = a.regularizer;
    opts.validate().map_err(|e| match e {
        ident::IdentError::InvalidOption {
            option,
            expected,
            value,
        } => super::flag_error(option, expected, value),
        e => e.into(),
    })?;
    Ok(opts)
}

/// What one identification found, for the outputs.
struct Report {
    r: ident::Identified,
    train: Range<usize>,
    train_rms: Vec<f64>,
    train_all: f64,
    vrange: Option<Range<usize>>,
    val: Option<(Vec<f64>, f64)>,
    idf: analysis::Identifiability,
    truth_errors: Option<Vec<serde_json::Value>>,
    total: f64,
}

/// Per-body errors against the ground truth, when the data are a physid log that carries it.
fn truth_errors(
    data: &Path,
    m: &Model,
    theta: &nalgebra::DVector<f64>,
) -> Option<Vec<serde_json::Value>> {
    ground_truth(data, m).map(|truth| {
        let tm = m.with_parameters(&truth).expect("same layout");
        let errs = physid::experiment::body_errors(&tm, theta);
        physid::ident::bodies(m)
            .into_iter()
            .zip(errs)
            .map(|((name, _, _), e)| json!({"name": name, "mass_rel": e[0], "com_m": e[1], "inertia_rel": e[2], "j_rel": e[3]}))
            .collect::<Vec<_>>()
    })
}

/// Writes the identified model as URDF, warning when its inertias are not consistent.
fn write_urdf(p: &Path, a: &Args, m: &Model, r: &ident::Identified) -> anyhow::Result<()> {
    let im = m.with_parameters(&r.theta)?;
    physid::io::write_atomic(p, physid::io::urdf::to_string(&im).as_bytes())?;
    if !r.constraints_hold || !ident::constraints_hold(m, &r.theta, ConstraintSet::Consistent) {
        eprintln!(
            "warning: {} holds physically inconsistent inertias (identified with '{}')",
            p.display(),
            a.constraints.name()
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
    m: &Model,
    ne: &NormalEquations,
    prior: &nalgebra::DVector<f64>,
    opts: &Options,
    r: &ident::Identified,
) -> anyhow::Result<()> {
    let ident::Objective { h, g, c } = ident::objective(m, ne, prior, opts);
    let rows: Vec<Vec<f64>> = h.row_iter().map(|r| r.iter().copied().collect()).collect();
    let bodies: Vec<_> = ident::bodies(m)
        .into_iter()
        .map(|(name, col, e)| json!({"name": name, "col": col, "ellipsoid": e.map(|e| json!({"center": e.center.as_slice(), "qs": e.qs.as_slice()}))}))
        .collect();
    let l = m.layout();
    let v = json!({
        "constraints": a.constraints, "eps": a.eps, "H": rows, "g": g.as_slice(), "c": c,
        "regularizer": a.regularizer, "w": a.prior_weight, "prior": prior.as_slice(),
        "bodies": bodies, "friction_cols": (l.viscous_col..l.len).collect::<Vec<_>>(),
        "physid": {"objective": r.objective, "theta": r.theta.as_slice(), "status": r.solver.status},
    });
    physid::io::write_atomic(p, serde_json::to_string(&v)?.as_bytes())?;
    Ok(())
}

/// The JSON report (docs/identify-json.md).
fn print_json(a: &Args, m: &Model, rep: &Report) -> anyhow::Result<()> {
    let r = &rep.r;
    let v = json!({
        "data": a.data, "robot": m.name, "constraints": a.constraints,
        "train": { "range": [rep.train.start, rep.train.end], "rms": rep.train_rms, "rms_overall": rep.train_all },
        "validation": rep.val.as_ref().map(|(rms, all)| json!({ "range": rep.vrange.as_ref().map(|r| [r.start, r.end]), "rms": rms, "rms_overall": all })),
        "bodies": r.bodies, "friction": { "viscous": r.viscous, "coulomb": r.coulomb },
        "objective": r.objective, "constraints_hold": r.constraints_hold,
        "solver": r.solver, "end_to_end_seconds": rep.total,
        "identifiability": rep.idf,
        "parameter_names": m.parameter_names(), "theta": r.theta.as_slice(),
        "truth_errors": rep.truth_errors,
    });
    println!("{}", serde_json::to_string_pretty(&v)?);
    Ok(())
}

/// The text report: bodies, friction, errors, consistency, identifiability, truth.
fn print_text(a: &Args, m: &Model, rep: &Report) {
    let (r, idf, train, train_rms, train_all, val) = (
        &rep.r,
        &rep.idf,
        &rep.train,
        &rep.train_rms,
        rep.train_all,
        &rep.val,
    );
    let (names, total, truth_errors) = (m.parameter_names(), rep.total, &rep.truth_errors);
    println!(
        "{}: '{}' on samples {}..{} of {} ({} parameters), {} in {:.1} ms ({} iterations, {:.1} ms end to end)",
        m.name,
        a.constraints.name(),
        train.start,
        train.end,
        a.data.display(),
        names.len(),
        r.solver.status,
        r.solver.seconds * 1e3,
        r.solver.iterations,
        total * 1e3
    );
    let rows: Vec<_> = r
        .bodies
        .iter()
        .map(|b| {
            (
                b.name.clone(),
                physid::spatial::InertialParams(nalgebra::SVector::from(b.pi)),
                b.consistency.clone(),
            )
        })
        .collect();
    super::model_cmd::print_bodies(&rows);
    println!(
        "\n{:<14} {:>12} {:>12} {:>12} {:>14}",
        "joint", "B [Nms/rad]", "Bc [Nm]", "train RMS", "validation RMS"
    );
    for (j, b) in m.bodies.iter().enumerate() {
        println!(
            "{:<14} {:>12.4} {:>12.4} {:>12.4} {:>14}",
            b.joint_name,
            r.viscous[j],
            r.coulomb[j],
            train_rms[j],
            val.as_ref()
                .map_or("-".into(), |(v, _)| format!("{:.4}", v[j]))
        );
    }
    println!(
        "overall RMS: train {train_all:.4} N m{}",
        val.as_ref()
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
        "constraints of '{}': {}; objective {:.6e}; regressor rank {} of {}, condition {:.2e}; {} unidentifiable directions",
        a.constraints.name(),
        if a.constraints == ConstraintSet::None { "none imposed" } else if r.constraints_hold { "all hold" } else { "do NOT all hold" },
        r.objective,
        idf.rank,
        idf.parameters,
        idf.condition,
        idf.parameters - idf.rank
    );
    for u in idf.unidentifiable.iter().take(5) {
        println!("  unidentifiable: {u}");
    }
    if let Some(errs) = &truth_errors {
        println!("\nagainst the ground truth in the log (relative errors; CoM in m):");
        println!(
            "{:<12} {:>10} {:>10} {:>12} {:>10}",
            "body", "mass", "CoM", "inertia_C", "J"
        );
        for e in errs {
            println!(
                "{:<12} {:>10.4} {:>10.4} {:>12.4} {:>10.4}",
                e["name"].as_str().unwrap_or(""),
                e["mass_rel"].as_f64().unwrap_or(f64::NAN),
                e["com_m"].as_f64().unwrap_or(f64::NAN),
                e["inertia_rel"].as_f64().unwrap_or(f64::NAN),
                e["j_rel"].as_f64().unwrap_or(f64::NAN)
            );
        }
    }
}

/// The ground-truth θ in a physid MCAP's metadata, if its parameter names match the model's.
fn ground_truth(path: &Path, model: &Model) -> Option<nalgebra::DVector<f64>> {
    if path.extension().and_then(|e| e.to_str()) != Some("mcap") {
        return None;
    }
    let log = physid::io::mcap_log::read(path).ok()?;
    let md = log.metadata.get("ground_truth_parameters")?;
    let names: Vec<String> = serde_json::from_str(md.get("names")?).ok()?;
    let values: Vec<f64> = serde_json::from_str(md.get("values")?).ok()?;
    (names == model.parameter_names()).then(|| nalgebra::DVector::from_vec(values))
}
