//! The `physid` command line: one clap `Args` struct per command in its own file, each over a
//! library entry point whose options check themselves. Errors are printed once, by `main`.
//!
//! Exit codes, for every command: 0 success; 1 the command ran but its result failed a requirement
//! the user asked for (`identify --require-consistent` with a physically inconsistent body,
//! `compare` with a regression); 2 an error (bad arguments, unreadable or invalid input, a failed
//! identification or simulation), with one message on standard error naming the file or sample.

mod blind_cmd;
mod compare_cmd;
mod diagnose_cmd;
mod dynamics_cmd;
mod excite_cmd;
mod experiment_cmd;
mod export_cmd;
mod floating_cmd;
mod generalize_cmd;
mod identify_cmd;
mod keywords_cmd;
mod model_cmd;
mod progress;
mod robot_args;
mod schema_cmd;
mod simulate_cmd;
mod sweep_cmd;
mod whole_robot_cmd;

use clap::{Parser, Subcommand};
pub use robot_args::RobotArgs;

/// Physically-consistent inertial parameter identification of robots, with ground truth.
#[derive(Parser, Debug)]
#[command(name = "physid", version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    Diagnose(diagnose_cmd::Args),
    Blind(blind_cmd::Args),
    Generalize(generalize_cmd::Args),
    Model(model_cmd::Args),
    Export(export_cmd::Args),
    Simulate(simulate_cmd::Args),
    Identify(identify_cmd::Args),
    Experiment(experiment_cmd::Args),
    Excite(excite_cmd::Args),
    Sweep(sweep_cmd::Args),
    WholeRobot(whole_robot_cmd::Args),
    SimulateFloating(floating_cmd::SimulateArgs),
    IdentifyFloating(floating_cmd::IdentifyArgs),
    Compare(compare_cmd::Args),
    Schema(schema_cmd::Args),
    Dynamics(dynamics_cmd::Args),
    #[command(hide = true)]
    Keywords(keywords_cmd::Args),
}

/// A result that failed a requirement the user asked for: exit code 1 (not 2, an error).
#[derive(Debug)]
pub struct Failed(pub String);

impl std::fmt::Display for Failed {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Failed {}

/// A library error as the binary reports it: an invalid option named as its flag.
fn option_error<E>(e: E) -> anyhow::Error
where
    E: physid::options::OptionError + std::error::Error + Send + Sync + 'static,
{
    match e.flag_message() {
        Some(message) => anyhow::anyhow!(message),
        None => e.into(),
    }
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
        Command::Generalize(a) => generalize_cmd::run(a),
        Command::Model(a) => model_cmd::run(a),
        Command::Export(a) => export_cmd::run(a),
        Command::Simulate(a) => simulate_cmd::run(a),
        Command::Identify(a) => identify_cmd::run(a),
        Command::Experiment(a) => experiment_cmd::run(a),
        Command::Excite(a) => excite_cmd::run(a),
        Command::Sweep(a) => sweep_cmd::run(a),
        Command::WholeRobot(a) => whole_robot_cmd::run(a),
        Command::SimulateFloating(a) => floating_cmd::run_simulate(a),
        Command::IdentifyFloating(a) => floating_cmd::run_identify(a),
        Command::Compare(a) => compare_cmd::run(a),
        Command::Schema(a) => schema_cmd::run(a),
        Command::Dynamics(a) => dynamics_cmd::run(a),
        Command::Keywords(a) => keywords_cmd::run(a),
    }
}

fn main() -> std::process::ExitCode {
    // End quietly when our reader goes away (`physid … | head`), not panic on a broken pipe.
    #[cfg(unix)]
    // SAFETY: restoring the default action of SIGPIPE before any thread is started.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    physid::spatial::single_threaded_blas_without_workers();
    physid::spatial::openblas_kernels_for_this_cpu();
    let args = Cli::parse();
    match run(args) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) if e.downcast_ref::<Failed>().is_some() => {
            eprintln!("failed: {}", message(&e));
            std::process::ExitCode::from(1)
        }
        Err(e) => {
            eprintln!("error: {}", message(&e));
            std::process::ExitCode::from(2)
        }
    }
}

/// The error and its causes on one line, each cause once: library errors already name their
/// cause in their own text (`file: what went wrong`), so a cause is appended only when the text
/// so far does not contain it.
fn message(e: &anyhow::Error) -> String {
    let mut text = e.to_string();
    for cause in e.chain().skip(1) {
        let c = cause.to_string();
        if !text.contains(&c) {
            text = format!("{text}: {c}");
        }
    }
    text
}
