//! `physid simulate`.

use physid::api::simulate::{simulate, SimulateOptions};
use physid::sim::scenario::Engine;
use std::path::PathBuf;

/// Simulate a scenario's excitation experiment and log it to MCAP (and CSV).
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Scenario file (TOML).
    scenario: PathBuf,
    /// Output MCAP file.
    #[arg(long)]
    out: PathBuf,
    /// Also write the processed samples (t, q, dq, ddq, tau) as CSV.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Override the engine.
    #[arg(long, value_enum)]
    engine: Option<EngineArg>,
    /// Override the duration (s).
    #[arg(long, allow_negative_numbers = true)]
    duration: Option<f64>,
    /// Override the seed.
    #[arg(allow_negative_numbers = true, long)]
    seed: Option<u64>,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(clap::ValueEnum, Debug, Clone, Copy)]
enum EngineArg {
    Physid,
    Rapier,
}

/// Simulates, writes the MCAP (and CSV) and prints a summary.
pub fn run(a: Args) -> anyhow::Result<()> {
    let (path, out, csv, json) = (&a.scenario, &a.out, a.csv.as_deref(), a.json);
    let engine = a.engine.map(|e| match e {
        EngineArg::Physid => Engine::Physid,
        EngineArg::Rapier => Engine::Rapier,
    });
    let (duration, seed) = (a.duration, a.seed);
    let outputs: Vec<&std::path::Path> = std::iter::once(out.as_path()).chain(csv).collect();
    // The scenario and every file its robot reads (URDF, sidecar, meshes) are inputs.
    let files = physid::io::scenario_files(path);
    let inputs: Vec<&std::path::Path> = files.iter().map(|p| p.as_path()).collect();
    physid::io::check_outputs(&outputs, &inputs)?;
    let bar = indicatif::ProgressBar::new(1000);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} simulating [{bar:40}] {percent:>3}% {elapsed}",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    let opts = SimulateOptions {
        engine,
        duration,
        seed,
    };
    let run = simulate(path, &opts, &mut |f| bar.set_position((f * 1000.0) as u64));
    bar.finish_and_clear();
    let run = run?;
    let report = run.write_with_report(out, csv)?;
    if json {
        println!(
            "{}",
            serde_json::to_string_pretty(&physid::io::versioned("simulate", &report))?
        );
        return Ok(());
    }
    print_summary(path, &run, &report, out, csv);
    Ok(())
}

/// The text summary of a simulation: rate and speed, joint ranges and peaks, the regressor's
/// rank and condition, how well physid's inverse dynamics explains the run, what was written.
fn print_summary(
    path: &std::path::Path,
    run: &physid::api::simulate::Simulation,
    report: &physid::api::simulate::SimulateJson,
    out: &std::path::Path,
    csv: Option<&std::path::Path>,
) {
    let (rec, ex, wall) = (&run.recording, &report.excitation, report.wall_seconds);
    let sim_s = report.simulated_seconds;
    let engine_name = match &report.integrator {
        Some(method) => format!("{} ({method} x{})", report.engine, report.substeps),
        None => format!("{} (x{})", report.engine, report.substeps),
    };
    let (cons_rms, cons_max) = (
        &report.physid_inverse_dynamics_residual.rms,
        &report.physid_inverse_dynamics_residual.max,
    );
    println!(
        "{}: {} samples ({sim_s} s at {} Hz, engine {engine_name}) in {wall:.2} s wall = {:.0}x real time",
        path.display(),
        rec.truth.len(),
        run.scenario.simulation.rate,
        sim_s / wall
    );
    println!(
        "{:<14} {:>22} {:>12} {:>12}",
        "joint", "q range [rad]", "|qd| max", "|tau| max"
    );
    for (j, name) in rec.truth.joint_names.iter().enumerate() {
        println!(
            "{:<14} {:>22} {:>12.2} {:>12.2}",
            name,
            format!("[{:.3}, {:.3}]", ex.q_range[j][0], ex.q_range[j][1]),
            ex.qd_peak[j],
            ex.tau_peak[j]
        );
    }
    println!(
        "regressor on the true motion (every 10th sample): rank {} of {} parameters, condition number {:.3e} (unit-norm columns; singular values above 3.2e-5 of the largest)",
        ex.rank, ex.parameters, ex.condition
    );
    println!(
        "physid inverse dynamics on this trajectory: residual RMS {} N m, max {} N m",
        fmt_e(cons_rms),
        fmt_e(cons_max)
    );
    println!(
        "wrote {}{}",
        out.display(),
        csv.map_or(String::new(), |c| format!(" and {}", c.display()))
    );
}

fn fmt_e(v: &[f64]) -> String {
    let parts: Vec<String> = v.iter().map(|x| format!("{x:.2e}")).collect();
    format!("[{}]", parts.join(", "))
}
