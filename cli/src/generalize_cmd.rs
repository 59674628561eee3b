//! `physid generalize`: the diagnosis on robots of several makers and sizes, some held out of
//! tuning.

use physid::bench::generalize::{self, Case, Spec};
use physid::bench::semireal::RealOptions;
use std::path::PathBuf;

/// The generalization benchmark: each robot of the benchmark file simulated as a real robot,
/// its description identified on one motion, semi-real cases on the other, scores per robot
/// and for the held-out robots apart (docs/diagnose.md, "Generalization benchmark").
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The benchmark file: run length and robots (URDF or built-in, rate, noise, held out).
    #[arg(long, default_value = "scenarios/generalize.toml")]
    robots: PathBuf,
    /// Cases per robot and seed (slots cycle over 2 unchanged, 2 payloads, the friction
    /// changed and 6 library effects, alternating the two runs; 22 covers each slot on each).
    #[arg(long, default_value_t = 22, allow_negative_numbers = true)]
    cases: usize,
    /// Seeds: each draws another real robot and other runs per robot.
    #[arg(
        allow_negative_numbers = true,
        long,
        value_delimiter = ',',
        default_value = "1"
    )]
    seeds: Vec<u64>,
    /// The description's relative uncertainty the diagnosis is told.
    #[arg(long, default_value_t = 0.05, allow_negative_numbers = true)]
    description_uncertainty: f64,
    /// Write the case table, per-robot scores (Markdown) and scores (JSON) here.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Keep the simulated runs and each case's files here (default: a temporary folder).
    #[arg(long)]
    keep_cases: Option<PathBuf>,
    /// Worker threads (0 = all cores).
    #[arg(allow_negative_numbers = true, long, default_value_t = 0)]
    threads: usize,
}

fn print_case(c: &Case) {
    let line = super::blind_cmd::real_case_line(&c.case);
    eprintln!("{} seed {} case {}: {line}", c.robot, c.seed, c.case.case);
}

/// `physid generalize`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let opts = RealOptions {
        cases: a.cases,
        seed: 0,
        description_uncertainty: a.description_uncertainty,
        baseline: false,
    };
    opts.validate().map_err(super::option_error)?;
    if a.seeds.is_empty() {
        anyhow::bail!("--seeds: give at least one seed");
    }
    let spec = Spec::load(&a.robots)?;
    if let Some(dir) = &a.out {
        let inputs: Vec<PathBuf> = std::iter::once(a.robots.clone())
            .chain(
                spec.robots
                    .iter()
                    .flat_map(|r| physid::io::robot_files(&r.robot, &[])),
            )
            .collect();
        physid::io::check_result_dir(dir, &inputs)?;
        physid::io::check_result_target(dir, physid::io::SCORES_MARK)?;
    }
    let temp = tempfile::tempdir()?;
    let work = a.keep_cases.clone().unwrap_or_else(|| temp.path().into());
    let pool = super::thread_pool(Some(a.threads))?;
    let start = std::time::Instant::now();
    let cases =
        pool.install(|| generalize::run(&spec, &a.seeds, a.cases, &opts, &work, &print_case))?;
    let scores = generalize::score(&spec, &cases);
    let wall = start.elapsed().as_secs_f64();
    println!(
        "{}",
        serde_json::to_string_pretty(&physid::io::versioned("generalize_scores", &scores))?
    );
    if let Some(dir) = &a.out {
        let seeds: Vec<String> = a.seeds.iter().map(u64::to_string).collect();
        let command = format!(
            "physid generalize --robots {} --cases {} --seeds {} --description-uncertainty {}",
            a.robots.display(),
            a.cases,
            seeds.join(","),
            a.description_uncertainty
        );
        generalize::write(dir, &cases, &scores, &command, wall)?;
        eprintln!("wrote {}", dir.display());
    }
    Ok(())
}
