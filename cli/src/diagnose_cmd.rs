//! `physid diagnose`: the sim-to-real diagnosis of a robot description against its data.

use super::RobotArgs;
use anyhow::Context as _;
use physid::api::diagnose::{diagnose_files, DiagnoseOptions};
use physid::diagnose;
use physid::ident::ConstraintSet;
use std::path::PathBuf;

/// Diagnose the gap between a robot model and its data: where the residual lies (joints, motion
/// regimes, frequency), which unmodelled effect causes it (cross-validated forward selection over
/// the effect library), and how far it shrinks once modelled.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Training data (CSV with ddq, or MCAP); repeat for several runs.
    #[arg(long = "data", required = true, num_args = 1..)]
    data: Vec<PathBuf>,
    /// Validation data; without it the last --holdout of the data is held out.
    #[arg(long = "validate", num_args = 1..)]
    validate: Vec<PathBuf>,
    #[command(flatten)]
    read: super::identify_cmd::ReadArgs,
    #[command(flatten)]
    robot: RobotArgs,
    /// Constraint set of the nominal model.
    #[arg(long, default_value = "consistent")]
    constraints: ConstraintSet,
    /// Fraction held out for validation when no --validate is given.
    #[arg(long, default_value_t = 0.3, allow_negative_numbers = true)]
    holdout: f64,
    /// Print the diagnosis as JSON.
    #[arg(long)]
    json: bool,
    /// Write a report (report.html: self-contained, the verdict first, plots inline; report.md, report.json with its schema, SVG plots) into this directory.
    #[arg(long)]
    report: Option<PathBuf>,
    /// How far the description's inertial parameters can be trusted (relative, 0.1 = 10 %):
    /// tests the identified parameters against it for effects that identification absorbs
    /// (torque gain, tilt, payload). Off without it.
    #[arg(long, allow_negative_numbers = true)]
    description_uncertainty: Option<f64>,
    /// Search a payload over every body, not only the last (with --description-uncertainty;
    /// inner bodies are found only where the motion separates their parameters).
    #[arg(long)]
    payload_any_body: bool,
    /// "What changed": runs of the same robot before the change (a tool change, a repair, a
    /// new gripper). The description is calibrated on them with their standing effects, which
    /// are taken out of --data; only what differs is attributed. Needs
    /// --description-uncertainty.
    #[arg(long = "baseline-data", num_args = 1..)]
    baseline_data: Vec<PathBuf>,
    /// Ignore the information matrix in the description's sidecar (`identify --out-urdf`
    /// writes it; read from a sidecar given as --robot, or beside a URDF given as --robot).
    #[arg(long)]
    no_description_information: bool,
}

/// `physid diagnose`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let mut o = DiagnoseOptions::new(a.data.clone());
    o.validate = a.validate.clone();
    o.baseline_data = a.baseline_data.clone();
    o.read = a.read.options();
    o.holdout = a.holdout;
    o.diagnosis = diagnose::Options {
        constraints: a.constraints,
        description_uncertainty: a.description_uncertainty,
        every_body: a.payload_any_body,
        ..Default::default()
    };
    o.diagnosis.validate().map_err(super::option_error)?;
    let model = a.robot.load()?;
    if !a.no_description_information {
        physid::api::information::apply(&a.robot.robot, &model, &mut o.diagnosis)?
            .iter()
            .for_each(|n| eprintln!("{n}"));
    }
    if let Some(dir) = &a.report {
        let inputs: Vec<PathBuf> = a
            .robot
            .files()
            .into_iter()
            .chain(o.files().iter().map(|p| p.to_path_buf()))
            .collect();
        physid::io::check_result_dir(dir, &inputs)?;
        physid::io::check_result_target(dir, physid::diagnose::report::REPORT_MARK)?;
    }
    let outcome =
        diagnose_files(&model, &o, &mut |n| eprintln!("{n}")).map_err(super::option_error)?;
    if let Some(standing) = &outcome.standing {
        eprintln!(
            "baseline: the description calibrated on {} run(s); standing effects taken out of the data: {}",
            outcome.baseline_runs,
            if standing.is_empty() { "none".to_string() } else { standing.join(", ") }
        );
    }
    let d = outcome.diagnosis;
    if let Some(dir) = &a.report {
        diagnose::report::write(dir, &d)
            .with_context(|| format!("writing the report to {}", dir.display()))?;
        eprintln!("wrote the report to {}", dir.display());
    }
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&physid::io::versioned("diagnose", &d))?
        );
    } else {
        print!("{}", diagnose::report::text(&d));
    }
    Ok(())
}
