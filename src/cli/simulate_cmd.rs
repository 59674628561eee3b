//! `physid simulate`.

use anyhow::Context;
use physid::io::{mcap_log, samples};
use physid::sim::scenario::Engine;
use std::path::PathBuf;

/// `simulate --json` (schema `physid.simulate/1`, docs/schemas/).
#[derive(serde::Serialize, schemars::JsonSchema)]
pub struct SimulateJson {
    scenario: std::path::PathBuf,
    out: std::path::PathBuf,
    engine: String,
    samples: usize,
    /// s.
    simulated_seconds: f64,
    /// s.
    wall_seconds: f64,
    real_time_factor: f64,
    excitation: physid::sim::report::Excitation,
    physid_inverse_dynamics_residual: Residual,
}

/// How well physid's inverse dynamics explains the recording, per joint (N m).
#[derive(serde::Serialize, schemars::JsonSchema)]
pub struct Residual {
    rms: Vec<f64>,
    max: Vec<f64>,
}

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
    #[arg(long)]
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
    let robot_files = physid::io::robot_files(&path.to_string_lossy(), &[]);
    let inputs: Vec<&std::path::Path> = std::iter::once(path.as_path())
        .chain(robot_files.iter().map(|p| p.as_path()))
        .collect();
    physid::io::check_outputs(&outputs, &inputs)?;
    let (mut sc, model, text) = physid::sim::scenario::load(path)?;
    if let Some(e) = engine {
        sc.simulation.engine = e;
    }
    if let Some(d) = duration {
        sc.simulation.duration = d;
    }
    if let Some(s) = seed {
        sc.simulation.seed = s;
    }
    let bar = indicatif::ProgressBar::new(1000);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} simulating [{bar:40}] {percent:>3}% {elapsed}",
        )
        .expect("valid template")
        .progress_chars("=> "),
    );
    let start = std::time::Instant::now();
    let rec = physid::sim::run(&model, &sc, &mut |f| bar.set_position((f * 1000.0) as u64))
        .with_context(|| format!("simulating {}", path.display()))?;
    let wall = start.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let theta = model.parameters();
    let names = model.parameter_names();
    let engine_name = format!("{:?}", sc.simulation.engine).to_lowercase();
    mcap_log::write(
        out,
        &rec,
        &mcap_log::LogMeta {
            scenario_toml: &text,
            engine: &engine_name,
            parameters: (&names, theta.as_slice()),
        },
    )?;
    if let Some(c) = csv {
        samples::write_csv(c, &rec.processed)?;
    }
    let ex = physid::sim::report::excitation(&model, &rec.truth, 10);
    let (cons_rms, cons_max) = physid::sim::report::engine_consistency(&model, &rec);
    let sim_s = sc.simulation.duration;
    if json {
        let v = SimulateJson {
            scenario: path.to_path_buf(),
            out: out.to_path_buf(),
            engine: engine_name.to_string(),
            samples: rec.truth.len(),
            simulated_seconds: sim_s,
            wall_seconds: wall,
            real_time_factor: sim_s / wall,
            excitation: ex,
            physid_inverse_dynamics_residual: Residual {
                rms: cons_rms,
                max: cons_max,
            },
        };
        println!(
            "{}",
            serde_json::to_string_pretty(&physid::io::versioned("simulate", &v))?
        );
        return Ok(());
    }
    println!(
        "{}: {} samples ({sim_s} s at {} Hz, engine {engine_name}) in {wall:.2} s wall = {:.0}x real time",
        path.display(),
        rec.truth.len(),
        sc.simulation.rate,
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
        fmt_e(&cons_rms),
        fmt_e(&cons_max)
    );
    println!(
        "wrote {}{}",
        out.display(),
        csv.map_or(String::new(), |c| format!(" and {}", c.display()))
    );
    Ok(())
}

fn fmt_e(v: &[f64]) -> String {
    let parts: Vec<String> = v.iter().map(|x| format!("{x:.2e}")).collect();
    format!("[{}]", parts.join(", "))
}
