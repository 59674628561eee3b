//! Command-line arguments (clap derive) and their dispatch to library entry points.

mod diagnose_cmd;
mod experiment_cmd;
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
}

#[derive(ValueEnum, Debug, Clone, Copy)]
enum EngineArg {
    Physid,
    Rapier,
}

#[derive(ValueEnum, Debug, Clone, Copy)]
enum RotorArg {
    Full,
    Reflected,
}

impl RobotArgs {
    fn load(&self) -> anyhow::Result<Model> {
        let mut m = physid::io::load_robot(&self.robot)?;
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
    /// Diagnose the gap between a robot model and its data: where the residual lies (joints,
    /// motion regimes, frequency), which unmodelled effect causes it (cross-validated forward
    /// selection over the effect library), and how far it shrinks once modelled.
    Diagnose {
        /// Training data (CSV with ddq, or MCAP); repeat for several runs.
        #[arg(long = "data", required = true, num_args = 1..)]
        data: Vec<std::path::PathBuf>,
        /// Validation data; without it the last --holdout of the data is held out.
        #[arg(long = "validate", num_args = 1..)]
        validate: Vec<std::path::PathBuf>,
        #[command(flatten)]
        robot: RobotArgs,
        /// Constraint set of the nominal model.
        #[arg(long, default_value = "consistent")]
        constraints: physid::ident::ConstraintSet,
        /// Fraction held out for validation when no --validate is given.
        #[arg(long, default_value_t = 0.3)]
        holdout: f64,
        /// Low-pass cutoff (Hz) the data were processed with (for the compliance terms).
        #[arg(long, default_value_t = 20.0)]
        cutoff: f64,
        /// Print the diagnosis as JSON.
        #[arg(long)]
        json: bool,
        /// Write a report (report.md, report.json, SVG plots) into this directory.
        #[arg(long)]
        report: Option<std::path::PathBuf>,
        /// How far the description's inertial parameters can be trusted (relative, 0.1 =
        /// 10 %): tests the identified parameters against it for effects that identification
        /// absorbs (torque gain, tilt, payload). Off without it.
        #[arg(long)]
        description_uncertainty: Option<f64>,
    },
    /// The blind benchmark: simulated cases with withheld effects, diagnosed from files only,
    /// scored against what was injected.
    Blind {
        /// Number of cases (categories cycle in 17: 4 clean, 11 single effects, 1 two, 1 out of
        /// the library).
        #[arg(long, default_value_t = 102)]
        cases: usize,
        /// Seed of every draw.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Base scenario (robot, excitation, sensors).
        #[arg(long, default_value = "scenarios/blind.toml")]
        scenario: std::path::PathBuf,
        /// Write the case table (CSV, Parquet, Markdown) and scores (JSON) here.
        #[arg(long)]
        out: Option<std::path::PathBuf>,
        /// Worker threads (0 = all cores).
        #[arg(long, default_value_t = 0)]
        threads: usize,
        /// Relative error drawn into each case's description's inertial parameters.
        #[arg(long, default_value_t = physid::experiment::blind::DESCRIPTION_ERROR)]
        description_error: f64,
        /// The description uncertainty the diagnosis is told (default: the error drawn; 0
        /// turns the description test off).
        #[arg(long)]
        description_uncertainty: Option<f64>,
    },
    /// Describe a robot: bodies, rotors, mass properties, consistency margins, and its
    /// dynamics at a reference configuration.
    Model {
        #[command(flatten)]
        robot: RobotArgs,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Export a robot to MJCF (rotors as armature) and/or URDF (rotors as mimic joints).
    Export {
        #[command(flatten)]
        robot: RobotArgs,
        /// Write MJCF here.
        #[arg(long)]
        mjcf: Option<std::path::PathBuf>,
        /// Write URDF here.
        #[arg(long)]
        urdf: Option<std::path::PathBuf>,
    },
    /// Simulate a scenario's excitation experiment and log it to MCAP (and CSV).
    Simulate {
        /// Scenario file (TOML).
        scenario: std::path::PathBuf,
        /// Output MCAP file.
        #[arg(long)]
        out: std::path::PathBuf,
        /// Also write the processed samples (t, q, dq, ddq, tau) as CSV.
        #[arg(long)]
        csv: Option<std::path::PathBuf>,
        /// Override the engine.
        #[arg(long, value_enum)]
        engine: Option<EngineArg>,
        /// Override the duration (s).
        #[arg(long)]
        duration: Option<f64>,
        /// Override the seed.
        #[arg(long)]
        seed: Option<u64>,
        /// Print the summary as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Identify inertial and friction parameters under a constraint set.
    Identify {
        /// Samples: a physid MCAP (its processed signals), another MCAP with JointState, or CSV.
        #[arg(long)]
        data: std::path::PathBuf,
        #[command(flatten)]
        robot: RobotArgs,
        /// Constraint set: none, semi, consistent, ellipsoid.
        #[arg(long, default_value = "ellipsoid")]
        constraints: physid::ident::ConstraintSet,
        /// Training samples, `a:b` (indices, end exclusive); default all.
        #[arg(long)]
        train: Option<String>,
        /// Validation samples of the same file, `a:b`.
        #[arg(long)]
        validate: Option<String>,
        /// Validate on another file (all its samples).
        #[arg(long)]
        validate_data: Option<std::path::PathBuf>,
        /// Weight of the prior term w ‖θ − θ̂‖² (θ̂: the robot description's parameters).
        #[arg(long, default_value_t = 1e-6)]
        prior_weight: f64,
        /// Margin ε of the strict matrix inequalities.
        #[arg(long, default_value_t = 1e-6)]
        eps: f64,
        /// Print JSON (schema: docs/identify-json.md).
        #[arg(long)]
        json: bool,
        /// Write the identified model as URDF.
        #[arg(long)]
        out_urdf: Option<std::path::PathBuf>,
        /// Write the optimization problem as JSON (for scripts/check_cvxpy.py).
        #[arg(long)]
        export_problem: Option<std::path::PathBuf>,
        /// Accept fewer equations than parameters (the prior then decides the rest).
        #[arg(long)]
        allow_few_samples: bool,
        /// Prior term: euclidean (w ‖θ − θ̂‖², the paper) or logdet (w Σ Bregman divergence of
        /// −log det between J and the prior's J; Lee, Wensing & Park).
        #[arg(long, default_value = "euclidean")]
        regularizer: physid::ident::Regularizer,
    },
    /// The sample-size experiment of a scenario file (its [experiment] table), in parallel.
    Experiment {
        /// Scenario file (TOML).
        scenario: std::path::PathBuf,
        /// Output directory.
        #[arg(long, default_value = "results/sample_size")]
        out: std::path::PathBuf,
        /// Override the number of seeds.
        #[arg(long)]
        seeds: Option<usize>,
        /// Worker threads (default: all cores). Results do not depend on it.
        #[arg(long)]
        threads: Option<usize>,
    },
    /// A parameter sweep (docs/sweeps.md): a grid over scenario keys crossed with the constraint
    /// sets; resumable (finished cells are skipped) and shardable across machines.
    Sweep {
        /// Sweep file (TOML).
        sweep: std::path::PathBuf,
        /// Output directory (default results/<sweep file name>).
        #[arg(long)]
        out: Option<std::path::PathBuf>,
        /// Run only cells with index ≡ K (mod N), e.g. a job array's task: `--shard 3/16`.
        #[arg(long)]
        shard: Option<String>,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Evaluate the dynamics at random states and write JSON (q, qd, qdd, tau, Y, H) for the
    /// cross-check scripts.
    Dynamics {
        #[command(flatten)]
        robot: RobotArgs,
        /// Number of random states.
        #[arg(long, default_value_t = 20)]
        samples: usize,
        /// Random seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Range of the random joint positions, velocities and accelerations (±).
        #[arg(long, default_value_t = 2.0)]
        scale: f64,
        /// Output JSON file.
        #[arg(long)]
        out: std::path::PathBuf,
    },
}

/// Runs one command.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Diagnose {
            data,
            validate,
            robot,
            constraints,
            holdout,
            cutoff,
            json,
            report,
            description_uncertainty,
        } => diagnose_cmd::run(diagnose_cmd::Args {
            model: robot.load()?,
            data: &data,
            validate: &validate,
            constraints,
            holdout,
            cutoff,
            json,
            report: report.as_deref(),
            description_uncertainty,
        }),
        Command::Blind {
            cases,
            seed,
            scenario,
            out,
            threads,
            description_error,
            description_uncertainty,
        } => diagnose_cmd::blind(diagnose_cmd::BlindArgs {
            cases,
            seed,
            scenario: &scenario,
            out: out.as_deref(),
            threads,
            description_error,
            description_uncertainty,
        }),
        Command::Model { robot, json } => model_cmd::describe(&robot.load()?, json),
        Command::Export { robot, mjcf, urdf } => {
            let m = robot.load()?;
            anyhow::ensure!(
                mjcf.is_some() || urdf.is_some(),
                "give --mjcf FILE and/or --urdf FILE"
            );
            if let Some(p) = mjcf {
                physid::io::write_atomic(&p, physid::io::mjcf::to_string(&m).as_bytes())?;
                eprintln!("wrote {}", p.display());
            }
            if let Some(p) = urdf {
                physid::io::write_atomic(&p, physid::io::urdf::to_string(&m).as_bytes())?;
                eprintln!("wrote {}", p.display());
            }
            Ok(())
        }
        Command::Simulate {
            scenario,
            out,
            csv,
            engine,
            duration,
            seed,
            json,
        } => {
            let engine = engine.map(|e| match e {
                EngineArg::Physid => physid::sim::scenario::Engine::Physid,
                EngineArg::Rapier => physid::sim::scenario::Engine::Rapier,
            });
            simulate_cmd::run(
                &scenario,
                &out,
                csv.as_deref(),
                engine,
                duration,
                seed,
                json,
            )
        }
        Command::Identify {
            data,
            robot,
            constraints,
            train,
            validate,
            validate_data,
            prior_weight,
            eps,
            json,
            out_urdf,
            export_problem,
            allow_few_samples,
            regularizer,
        } => identify_cmd::run(identify_cmd::Args {
            data: &data,
            model: robot.load()?,
            constraints,
            train: train.as_deref(),
            validate: validate.as_deref(),
            validate_data: validate_data.as_deref(),
            prior_weight,
            eps,
            json,
            out_urdf: out_urdf.as_deref(),
            export_problem: export_problem.as_deref(),
            allow_few_samples,
            regularizer,
        }),
        Command::Experiment {
            scenario,
            out,
            seeds,
            threads,
        } => experiment_cmd::run(&scenario, &out, seeds, threads),
        Command::Sweep {
            sweep,
            out,
            shard,
            threads,
        } => {
            let shard = shard.as_deref().map(sweep_cmd::parse_shard).transpose()?;
            sweep_cmd::run(&sweep, out, shard, threads)
        }
        Command::Dynamics {
            robot,
            samples,
            seed,
            scale,
            out,
        } => {
            anyhow::ensure!(
                scale.is_finite() && scale > 0.0,
                "--scale must be a positive number, got {scale}"
            );
            model_cmd::dynamics_json(&robot.load()?, samples, seed, scale, &out)
        }
    }
}
