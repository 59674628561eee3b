//! `physid identify`: the flags read into [`IdentifyOptions`], the library's
//! [`identify`](physid::api::identify::identify) run, its report printed (text or JSON) and
//! written (URDF, effects, the problem).

use super::RobotArgs;
use anyhow::bail;
use physid::api::data::ReadOptions;
use physid::api::identify::{
    confirmed_effects, identify_reporting, parse_terms, Identification, IdentifyOptions,
    SampleRange,
};
use physid::diagnose::library::Variant;
use physid::ident::{self, analysis, ConstraintSet};
use physid::model::Model;
use std::path::{Path, PathBuf};

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
    /// The library's reading options, as given.
    pub fn options(&self) -> ReadOptions {
        ReadOptions {
            topic: self.topic.clone(),
            stamp: self.stamp,
            cutoff: self.cutoff,
            lock: self.lock.clone(),
            only: self.only.clone(),
            ..Default::default()
        }
    }
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
    // Every kind of the effect table (a kind added there appears here).
    #[arg(long, value_delimiter = ',', help = format!(
        "Effect terms from the diagnosis library, comma-separated: {}; see docs/diagnose.md",
        physid::diagnose::calibrate::term_syntax()))]
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
    /// Hold each body's mass within LO..HI times the description's (0 <= LO <= 1 <= HI, e.g.
    /// 0.5,2): what the data do not determine otherwise goes wherever the constraints allow.
    #[arg(long, value_name = "LO,HI", allow_hyphen_values = true)]
    mass_bounds: Option<physid::api::identify::MassBounds>,
    /// Hold the robot's total moving mass (links and rotors) within LO..HI kg (e.g. 3.5,3.9:
    /// the arm weighed on a scale), where the data weigh only some bodies.
    #[arg(long, value_name = "LO,HI", allow_hyphen_values = true)]
    total_mass: Option<physid::api::identify::TotalMass>,
    /// Print JSON (schema: docs/identify-json.md).
    #[arg(long)]
    json: bool,
    /// Write the identified model as URDF (the robot's own with only `<inertial>`, `<dynamics>`
    /// changed) and a sidecar `<name>.physid.toml` with what URDF cannot carry: ellipsoids,
    /// rotors, effects, the fit's information matrix (`diagnose` reads it as its uncertainty).
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
    let mut out = parse_terms(&a.friction, &a.effects)?;
    if let Some(p) = &a.effects_from {
        out.extend(confirmed_effects(p, model)?);
    }
    Ok(out)
}

/// The library's options from the flags, but for the effect terms (which need the model).
fn options(a: &Args) -> anyhow::Result<IdentifyOptions> {
    let range = |s: &Option<String>, what: &str| {
        s.as_deref()
            .map(|s| SampleRange::parse(s, what))
            .transpose()
    };
    let mut o = IdentifyOptions::new(a.data.clone());
    o.validate_data = a.validate_data.clone();
    o.train = range(&a.train, "--train")?;
    o.validate = range(&a.validate, "--validate")?;
    o.constraints = a.constraints;
    o.prior_weight = a.prior_weight;
    o.eps = a.eps;
    o.regularizer = a.regularizer;
    o.read = a.read.options();
    o.allow_few_samples = a.allow_few_samples;
    o.information = a.out_urdf.is_some();
    o.mass_bounds = a.mass_bounds;
    o.total_mass = a.total_mass;
    Ok(o)
}

/// Runs the identification and prints the report.
pub fn run(a: Args) -> anyhow::Result<()> {
    check_paths(&a)?;
    let mut opts = options(&a)?;
    opts.validate().map_err(super::option_error)?;
    let model = a.robot.load()?;
    let m = &model;
    opts.terms = terms(&a, m)?;
    if a.export_problem.is_some() && !opts.terms.is_empty() {
        bail!("--export-problem writes the model's own problem: leave out the extra --friction terms and --effects");
    }
    if a.export_problem.is_some() && (opts.mass_bounds.is_some() || opts.total_mass.is_some()) {
        bail!("--export-problem writes the problem without mass bounds: leave out --mass-bounds and --total-mass");
    }
    let report = identify_reporting(m, &opts, &mut |notice| eprintln!("{notice}"))
        .map_err(super::option_error)?;
    write_outputs(&a, m, &opts, &report)?;
    if a.json {
        let v = physid::io::versioned("identify", &report.json(m));
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        print_text(&a, m, &report);
    }
    if a.require_consistent {
        require_consistent(&report)?;
    }
    Ok(())
}

/// Outputs never onto inputs or each other.
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
    Ok(())
}

/// `--require-consistent`: every body physically consistent (`J(π) ≻ 0`), or exit code 1
/// naming the bodies that are not.
fn require_consistent(rep: &Identification) -> anyhow::Result<()> {
    let bad = rep.inconsistent_bodies();
    if bad.is_empty() {
        return Ok(());
    }
    Err(super::Failed(format!(
        "--require-consistent: {} of {} bodies are not physically consistent: {}",
        bad.len(),
        rep.identified.bodies.len(),
        bad.join(", ")
    ))
    .into())
}

/// `--out-urdf`, `--out-effects` and `--export-problem`.
fn write_outputs(
    a: &Args,
    m: &Model,
    opts: &IdentifyOptions,
    rep: &Identification,
) -> anyhow::Result<()> {
    if let Some(p) = &a.out_urdf {
        for notice in rep.write_urdf(p, &a.robot.robot, m)? {
            eprintln!("{notice}");
        }
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
        let ident = opts.ident(m, rep.set)?;
        let v =
            physid::api::identify::problem_json(m, &rep.normal_equations, &ident, &rep.identified);
        let v = physid::io::versioned("problem", &v);
        physid::io::write_atomic(p, serde_json::to_string(&v)?.as_bytes())?;
    }
    Ok(())
}

/// The text report: bodies, friction, effects, errors, consistency, identifiability, truth.
fn print_text(a: &Args, m: &Model, rep: &Identification) {
    print_header(a, m, rep);
    print_identified_bodies(m, rep);
    print_joints(m, rep);
    print_terms(&rep.terms, m);
    print_fit(rep);
    print_identifiability(&rep.identifiability);
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
fn print_header(a: &Args, m: &Model, rep: &Identification) {
    let r = &rep.identified;
    let used: usize = rep.train.runs.iter().map(|r| r.samples_used).sum();
    let on = if a.data.len() == 1 {
        format!(
            "samples {}..{} of {} ({used} used)",
            rep.train.runs[0].range[0],
            rep.train.runs[0].range[1],
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
        m.name(),
        rep.set.name(),
        r.solver.status,
        r.solver.seconds * 1e3,
        r.solver.iterations,
        rep.total_seconds * 1e3
    );
    if let Some(why) = &rep.set_note {
        println!("constraints '{}' by default: {why}", rep.set.name());
    }
}

/// Each body's identified mass properties; a mass the data do not determine is marked `~`.
fn print_identified_bodies(m: &Model, rep: &Identification) {
    let names = m.parameter_names();
    let se = &rep.identifiability.standard_errors;
    let mut undetermined = 0;
    let (rows, marks): (Vec<_>, Vec<char>) = rep
        .identified
        .bodies
        .iter()
        .map(|b| {
            let pi = physid::spatial::InertialParams(nalgebra::SVector::from(b.pi));
            let col = physid::api::identify::mass_column(&names, &b.name);
            let mark = match col.map(|c| se[c]) {
                Some(e) if physid::api::identify::mass_determined(e, pi.mass()) => ' ',
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
fn print_joints(m: &Model, rep: &Identification) {
    let r = &rep.identified;
    let width = m
        .bodies()
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
    for (j, b) in m.bodies().iter().enumerate() {
        let known = rep.train.rms[j].is_some() && !still.contains(&&b.joint_name);
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
            cell(rep.train.rms[j]),
            rep.validation
                .as_ref()
                .map_or("-".into(), |v| cell(v.rms[j]))
        );
    }
}

/// Overall RMS, consistency and the constraints' state.
fn print_fit(rep: &Identification) {
    let r = &rep.identified;
    println!(
        "overall RMS: train {:.4} N m{}",
        rep.train.rms_overall,
        rep.validation.as_ref().map_or(String::new(), |v| format!(
            ", validation {:.4} N m",
            v.rms_overall
        ))
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
pub(crate) fn print_identifiability(idf: &analysis::Identifiability) {
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
        let (what, unit) = (&t.magnitude.0, &t.magnitude.1);
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
