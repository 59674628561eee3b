//! The `physid` command line: one clap `Args` struct per command in its own file, each over a
//! library entry point whose options check themselves. Errors are printed once, by `main`.
//!
//! Exit codes: 0 success; 2 any error (bad arguments, unreadable or invalid input, a failed
//! identification or simulation), with one message on standard error naming the file, field
//! or sample.

mod blind_cmd;
mod diagnose_cmd;
mod dynamics_cmd;
mod experiment_cmd;
mod export_cmd;
mod identify_cmd;
mod model_cmd;
mod simulate_cmd;
mod sweep_cmd;

use clap::{Parser, Subcommand, ValueEnum};
use physid::model::{Model, RotorModel};

/// Physically-consistent inertial parameter identification of robots, with ground truth.
#[derive(Parser, Debug)]
#[command(name = "physid", version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// Which robot, and how its rotors are modelled.
#[derive(clap::Args, Debug, Clone)]
pub struct RobotArgs {
    /// `cheetah3` (built-in leg), a .urdf file, or a .toml file with a [robot] table.
    #[arg(long, default_value = "cheetah3")]
    robot: String,
    /// Override the rotor treatment: full (spinning rotor bodies) or reflected (armature).
    #[arg(long, value_enum)]
    rotor_model: Option<RotorArg>,
    /// Drop the rotors (the link-only model).
    #[arg(long)]
    no_rotors: bool,
    /// URDF robots: lengthen every semi-axis of the bounding ellipsoids computed from the
    /// geometry by this much (m).
    #[arg(long, value_name = "M")]
    ellipsoid_margin: Option<f64>,
    /// URDF robots: a folder holding ROS packages, for `package://` meshes (repeatable; the
    /// URDF's own folders and ROS_PACKAGE_PATH are searched first).
    #[arg(long, value_name = "DIR")]
    package_dir: Vec<std::path::PathBuf>,
    /// URDF robots: take no bounding ellipsoids from the geometry (only a sidecar's).
    #[arg(long)]
    no_geometry_ellipsoids: bool,
}

#[derive(ValueEnum, Debug, Clone, Copy)]
enum RotorArg {
    Full,
    Reflected,
}

impl RobotArgs {
    fn load(&self) -> anyhow::Result<Model> {
        let opts = physid::io::robot_spec::RobotOptions {
            ellipsoid_margin: self.ellipsoid_margin,
            package_dirs: self.package_dir.clone(),
            geometry_ellipsoids: self.no_geometry_ellipsoids.then_some(false),
        };
        let (mut m, warnings) = physid::io::load_robot_with(&self.robot, &opts)?;
        for w in warnings {
            eprintln!("warning: {}: {w}", self.robot);
        }
        if self.no_rotors {
            m = m.without_rotors();
        }
        if let Some(r) = self.rotor_model {
            m = m.with_rotor_model(match r {
                RotorArg::Full => RotorModel::Full,
                RotorArg::Reflected => RotorModel::Reflected,
            });
        }
        Ok(m)
    }
}

#[derive(Subcommand, Debug)]
enum Command {
    Diagnose(diagnose_cmd::Args),
    Blind(blind_cmd::Args),
    Model(model_cmd::Args),
    Export(export_cmd::Args),
    Simulate(simulate_cmd::Args),
    Identify(identify_cmd::Args),
    Experiment(experiment_cmd::Args),
    Sweep(sweep_cmd::Args),
    Dynamics(dynamics_cmd::Args),
}

/// An option error from a library `Options::validate()`, with the option named as its flag
/// (`processing_cutoff` is `--cutoff`, other fields `--field-name`).
fn flag_error(option: &str, expected: &str, value: f64) -> anyhow::Error {
    let flag = match option {
        "processing_cutoff" => "cutoff".to_string(),
        other => other.replace('_', "-"),
    };
    anyhow::anyhow!("--{flag} must be {expected}, got {value}")
}

/// A worker pool of `requested` threads (0 or none: all cores), never more than the machine's
/// cores: more threads than cores only add contention (and a huge count would hang the start).
fn thread_pool(requested: Option<usize>) -> anyhow::Result<rayon::ThreadPool> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads = match requested {
        None | Some(0) => cores,
        Some(t) if t > cores => {
            eprintln!("note: {t} threads requested, using the {cores} cores");
            cores
        }
        Some(t) => t,
    };
    Ok(rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?)
}

/// Runs one command.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Diagnose(a) => diagnose_cmd::run(a),
        Command::Blind(a) => blind_cmd::run(a),
        Command::Model(a) => model_cmd::run(a),
        Command::Export(a) => export_cmd::run(a),
        Command::Simulate(a) => simulate_cmd::run(a),
        Command::Identify(a) => identify_cmd::run(a),
        Command::Experiment(a) => experiment_cmd::run(a),
        Command::Sweep(a) => sweep_cmd::run(a),
        Command::Dynamics(a) => dynamics_cmd::run(a),
    }
}
