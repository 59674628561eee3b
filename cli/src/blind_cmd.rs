//! `physid blind`: the blind benchmark of the diagnosis.

use physid::bench::blind::{self, BlindOptions, CaseResult};
use rayon::prelude::*;
use std::path::PathBuf;

/// The blind benchmark: simulated cases with withheld effects, diagnosed from files only,
/// scored against what was injected.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Number of cases (categories cycle: 4 clean, one per single effect the library draws, 1
    /// with two effects, 1 out of the library, 2 changed robots; 21 slots).
    #[arg(allow_negative_numbers = true, long, default_value_t = 102)]
    cases: usize,
    /// Seed of every draw.
    #[arg(allow_negative_numbers = true, long, default_value_t = 1)]
    seed: u64,
    /// Base scenario (robot, excitation, sensors).
    #[arg(long, default_value = "scenarios/blind.toml")]
    scenario: PathBuf,
    /// Write the case table (CSV, Parquet, Markdown) and scores (JSON) here.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Worker threads (0 = all cores).
    #[arg(allow_negative_numbers = true, long, default_value_t = 0)]
    threads: usize,
    /// Relative error drawn into each case's description's inertial parameters (default 0.1;
    /// not with --real, whose descriptions are identified from real runs).
    #[arg(long, allow_negative_numbers = true, conflicts_with = "real")]
    description_error: Option<f64>,
    /// The description uncertainty the diagnosis is told (default: the error drawn; 0
    /// turns the description test off).
    #[arg(long, allow_negative_numbers = true)]
    description_uncertainty: Option<f64>,
    /// Keep each case's files (`caseI/robot.urdf`, `caseI/data.csv`; with --real also the
    /// sidecar with the description's information) in this folder, to re-diagnose a case by
    /// hand (`physid diagnose --robot DIR/case17/robot.urdf --data DIR/case17/data.csv`, with
    /// the same --description-uncertainty; with --real-baseline the benchmark's baseline is
    /// processed at 20 Hz, the command's at the pipeline's cutoff); default: a temporary
    /// folder, removed.
    #[arg(long)]
    keep_cases: Option<PathBuf>,
    /// Run only these cases (numbers below --cases, comma-separated); the scores cover them.
    #[arg(allow_negative_numbers = true, long, value_delimiter = ',')]
    only: Vec<usize>,
    /// Semi-real benchmark: real runs of the robot `--real-robot` (CSV, MCAP or rosbag2 with
    /// q̇ and q̈; at least two), each case one of them with a change injected and a
    /// description identified on another (docs/diagnose.md, "Semi-real benchmark").
    #[arg(long, value_delimiter = ',', requires = "real_robot", value_parser = non_empty_path)]
    real: Vec<PathBuf>,
    /// The robot of the `--real` runs (URDF, robot TOML or a built-in name).
    #[arg(long, requires = "real")]
    real_robot: Option<String>,
    /// With `--real`: give each case the run its description was identified on as the
    /// baseline ("what changed", `diagnose --baseline-data`).
    #[arg(long, requires = "real")]
    real_baseline: bool,
}

/// A path from a comma-separated list, refused when empty (two commas in a row, or one at the
/// end).
fn non_empty_path(s: &str) -> Result<PathBuf, String> {
    if s.trim().is_empty() {
        Err("an empty entry in the list (two commas in a row, or one at either end)".into())
    } else {
        Ok(PathBuf::from(s))
    }
}

/// One line per finished case, on standard error: its number, the progress, and
/// [`real_case_line`].
fn print_real_case(r: &physid::bench::semireal::RealCase, progress: &super::progress::Progress) {
    eprintln!(
        "case {} ({}): {}",
        r.case,
        progress.status(),
        real_case_line(r)
    );
}

/// What a semi-real case injected on which run (and body) and what the ladder found, with its
/// wall time (`blind --real` and `generalize` print it per case).
pub fn real_case_line(r: &physid::bench::semireal::RealCase) -> String {
    format!(
        "{} on {}{}; found {}; {:.1} s",
        r.injected,
        r.base,
        r.injected_body
            .as_ref()
            .map_or(String::new(), |b| format!(" ({b})")),
        if r.found.is_empty() {
            "nothing".into()
        } else {
            r.found.join(", ")
        },
        r.seconds
    )
}

fn print_case(r: &CaseResult, progress: &super::progress::Progress) {
    let list = |v: &[String]| {
        if v.is_empty() {
            "nothing".to_string()
        } else {
            v.join(" + ")
        }
    };
    eprintln!(
        "case {} ({}): {}; injected {}; found {}; verdict {}; validation RMS {:.3} -> {:.3} N m (noise floor {:.3}); {:.1} s",
        r.case,
        progress.status(),
        physid::io::serde_name(&r.category),
        list(&r.injected),
        list(&r.found),
        physid::io::serde_name(&r.verdict),
        r.rms[0],
        r.rms[1],
        r.rms[2],
        r.seconds
    );
}

/// `physid blind`.
pub fn run(a: Args) -> anyhow::Result<()> {
    if let Some(robot) = a.real_robot.clone() {
        return run_real(a, &robot);
    }
    let opts = BlindOptions {
        cases: a.cases,
        seed: a.seed,
        description_error: a.description_error.unwrap_or(blind::DESCRIPTION_ERROR),
        description_uncertainty: a.description_uncertainty,
    };
    opts.validate().map_err(super::option_error)?;
    if let Some(dir) = &a.out {
        physid::io::check_result_dir(dir, &physid::io::scenario_files(&a.scenario))?;
        physid::io::check_result_target(dir, physid::io::SCORES_MARK)?;
    }
    let (base, model, _) = physid::sim::scenario::load(&a.scenario)?;
    let diagnose_opts = opts.diagnose_options();
    let start = std::time::Instant::now();
    let results: Vec<CaseResult> = run_chosen(
        &a,
        |i, case_dir| {
            blind::run_case(
                i,
                a.seed,
                &base,
                &model,
                opts.description_error,
                &diagnose_opts,
                case_dir,
            )
        },
        print_case,
    )?;
    let scores = blind::score(&results);
    let wall = start.elapsed().as_secs_f64();
    println!(
        "{}",
        serde_json::to_string_pretty(&physid::io::versioned("blind_scores", &scores))?
    );
    eprintln!("{} cases in {wall:.1} s", results.len());
    if let Some(dir) = &a.out {
        let description = [opts.description_error, opts.stated_uncertainty()];
        blind::write_blind(
            dir,
            &results,
            &scores,
            a.seed,
            &a.scenario,
            description,
            wall,
        )?;
        eprintln!("wrote {}", dir.display());
    }
    Ok(())
}

/// The chosen cases (`--only`, else all `--cases`) run in parallel on `--threads`, each in its
/// own folder under `--keep-cases` (else a temporary one), each counted on the progress line and
/// then shown by `show`.
fn run_chosen<T, E>(
    a: &Args,
    case: impl Fn(usize, &std::path::Path) -> Result<T, E> + Sync,
    show: impl Fn(&T, &super::progress::Progress) + Sync,
) -> anyhow::Result<Vec<T>>
where
    T: Send,
    E: std::error::Error + Send + Sync + 'static,
{
    if let Some(&i) = a.only.iter().find(|&&i| i >= a.cases) {
        anyhow::bail!("--only {i}: the cases are numbered 0 to {}", a.cases - 1);
    }
    if let Some((k, &i)) = (a.only.iter().enumerate()).find(|(k, i)| a.only[..*k].contains(i)) {
        anyhow::bail!(
            "--only: case {i} given twice (entry {}): each case is run and scored once",
            k + 1
        );
    }
    let temp = tempfile::tempdir()?;
    let work = a
        .keep_cases
        .clone()
        .unwrap_or_else(|| temp.path().to_path_buf());
    let chosen: Vec<usize> = if a.only.is_empty() {
        (0..a.cases).collect()
    } else {
        a.only.clone()
    };
    let pool = super::thread_pool(Some(a.threads))?;
    let progress = super::progress::Progress::counter("cases", chosen.len() as u64);
    let results = pool.install(|| {
        chosen
            .par_iter()
            .map(|&i| {
                let r = case(i, &work.join(format!("case{i}")));
                if let Ok(r) = &r {
                    progress.inc();
                    show(r, &progress);
                }
                r
            })
            .collect::<Result<Vec<T>, E>>()
    })?;
    Ok(results)
}

/// `physid blind --real`: the semi-real benchmark.
fn run_real(a: Args, robot: &str) -> anyhow::Result<()> {
    use physid::bench::semireal::{self, RealCase, RealOptions};
    let opts = RealOptions {
        cases: a.cases,
        seed: a.seed,
        description_uncertainty: a.description_uncertainty.unwrap_or(0.05),
        baseline: a.real_baseline,
    };
    opts.validate().map_err(super::option_error)?;
    if let Some(dir) = &a.out {
        let inputs: Vec<PathBuf> = physid::io::robot_files(robot, &[])
            .into_iter()
            .chain(a.real.iter().cloned())
            .collect();
        physid::io::check_result_dir(dir, &inputs)?;
        physid::io::check_result_target(dir, physid::io::SCORES_MARK)?;
    }
    let model = physid::io::load_robot(robot)?;
    let bases = semireal::bases(&model, &a.real, &opts)?;
    let dopts = opts.diagnose_options();
    let start = std::time::Instant::now();
    let results: Vec<RealCase> = run_chosen(
        &a,
        |i, case_dir| semireal::run_case(i, a.seed, &bases, &dopts, case_dir),
        print_real_case,
    )?;
    let scores = semireal::score(&results);
    let wall = start.elapsed().as_secs_f64();
    println!(
        "{}",
        serde_json::to_string_pretty(&physid::io::versioned("blind_real_scores", &scores))?
    );
    if let Some(dir) = &a.out {
        let runs: Vec<String> = a.real.iter().map(|p| p.display().to_string()).collect();
        let command = format!(
            "physid blind --real {} --real-robot {robot}{} --cases {} --seed {} --description-uncertainty {}",
            runs.join(","),
            if opts.baseline { " --real-baseline" } else { "" },
            a.cases,
            a.seed,
            opts.description_uncertainty
        );
        semireal::write(dir, &results, &scores, &command, wall)?;
        eprintln!("wrote {}", dir.display());
    }
    Ok(())
}
