//! `physid compare`: a result against a baseline, or two constraint sets within one run, with a
//! stated test; exit 1 on a regression.

use anyhow::{bail, Context};
use physid::experiment::compare::{self, CompareOptions};
use std::path::PathBuf;

/// Compare results in CI (docs/ci.md): RESULT against --baseline DIR (every grid point, n_s and
/// set, paired by seed), or two constraint sets within RESULT (--variant A<=B). A group
/// regresses when its median per-seed ratio exceeds 1 + tolerance and a one-sided Wilcoxon
/// signed-rank test gives p < alpha. Exit 0 pass, 1 regression, 2 error.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Result directory: rows.parquet (or rows.csv) of `physid experiment` or `physid sweep`.
    result: PathBuf,
    /// Baseline result directory to compare against.
    #[arg(long, conflicts_with = "variant", required_unless_present = "variant")]
    baseline: Option<PathBuf>,
    /// Two constraint sets within RESULT: `ellipsoid<=consistent` (the first no worse).
    #[arg(long)]
    variant: Option<String>,
    /// Metric column, lower is better (default val_rms).
    #[arg(long)]
    metric: Option<String>,
    /// Relative tolerance of the median ratio (default 0.05).
    #[arg(allow_negative_numbers = true, long)]
    tolerance: Option<f64>,
    /// One-sided level of the signed-rank test (default 0.01).
    #[arg(allow_negative_numbers = true, long)]
    alpha: Option<f64>,
    /// Fewest seed pairs a group needs to be able to fail (default 6; raised to what --alpha
    /// needs: the exact test's smallest p on n pairs is 2^-n, so 7 at 0.01).
    #[arg(allow_negative_numbers = true, long)]
    min_pairs: Option<usize>,
    /// Let groups with too few pairs to reach --alpha pass (by default they fail the run with
    /// exit 2: a group that cannot fail is not a pass).
    #[arg(long)]
    allow_too_few: bool,
    /// Only groups with n_s at most this.
    #[arg(allow_negative_numbers = true, long)]
    max_n_s: Option<u64>,
    /// TOML with any of metric, tolerance, alpha, min_pairs, max_n_s (flags override it).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Also write the Markdown report here (it is printed, and appended to
    /// $GITHUB_STEP_SUMMARY when that is set).
    #[arg(long)]
    markdown: Option<PathBuf>,
    /// Write JUnit XML here (one test case per group).
    #[arg(long)]
    junit: Option<PathBuf>,
}

/// The optional TOML of `--config`.
#[derive(serde::Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct Config {
    metric: Option<String>,
    tolerance: Option<f64>,
    alpha: Option<f64>,
    min_pairs: Option<usize>,
    max_n_s: Option<u64>,
}

fn options(a: &Args) -> anyhow::Result<CompareOptions> {
    let file: Config = match &a.config {
        Some(p) => {
            let text = std::fs::read_to_string(p).with_context(|| p.display().to_string())?;
            toml::from_str(&text).with_context(|| p.display().to_string())?
        }
        None => Config::default(),
    };
    let d = CompareOptions::default();
    let opts = CompareOptions {
        metric: a.metric.clone().or(file.metric).unwrap_or(d.metric),
        tolerance: a.tolerance.or(file.tolerance).unwrap_or(d.tolerance),
        alpha: a.alpha.or(file.alpha).unwrap_or(d.alpha),
        min_pairs: a.min_pairs.or(file.min_pairs).unwrap_or(d.min_pairs),
        allow_too_few: a.allow_too_few,
        max_n_s: a.max_n_s.or(file.max_n_s),
    };
    opts.validate().map_err(super::option_error)?;
    Ok(opts)
}

/// `physid compare`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let opts = options(&a)?;
    let summary = std::env::var_os("GITHUB_STEP_SUMMARY").map(std::path::PathBuf::from);
    check_files(&a, summary.as_deref())?;
    let cmp = match (&a.baseline, &a.variant) {
        (Some(b), _) => compare::against_baseline(&a.result, b, &opts)?,
        (None, Some(v)) => {
            let Some((better, reference)) = v.split_once("<=") else {
                bail!(
                    "--variant '{v}': give two constraint sets as A<=B, e.g. ellipsoid<=consistent"
                );
            };
            compare::variants(&a.result, better.trim(), reference.trim(), &opts)?
        }
        (None, None) => bail!("give --baseline DIR or --variant A<=B"),
    };
    write(&a, &cmp, summary.as_deref())?;
    verdict(&cmp, &opts)
}

/// Refuses outputs (`--markdown`, `--junit`, the CI step summary) that are inputs: the result
/// and baseline directories and every file in them (rows.parquet, rows.csv, provenance).
fn check_files(a: &Args, summary: Option<&std::path::Path>) -> anyhow::Result<()> {
    let outputs: Vec<&std::path::Path> = (a.markdown.iter().chain(a.junit.iter()))
        .map(|p| p.as_path())
        .chain(summary)
        .collect();
    let dirs: Vec<&std::path::Path> = [Some(a.result.as_path()), a.baseline.as_deref()]
        .into_iter()
        .flatten()
        .collect();
    let files: Vec<std::path::PathBuf> = (dirs.iter())
        .filter_map(|d| std::fs::read_dir(d).ok())
        .flatten()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .collect();
    let inputs: Vec<&std::path::Path> = dirs
        .into_iter()
        .chain(files.iter().map(|p| p.as_path()))
        .collect();
    physid::io::check_outputs(&outputs, &inputs)?;
    Ok(())
}

/// Prints the Markdown and writes it, the JUnit XML and the CI step summary where asked.
fn write(
    a: &Args,
    cmp: &compare::Comparison,
    summary: Option<&std::path::Path>,
) -> anyhow::Result<()> {
    let md = cmp.markdown();
    print!("{md}");
    if let Some(p) = &a.markdown {
        physid::io::write_atomic(p, md.as_bytes())?;
    }
    if let Some(p) = &a.junit {
        physid::io::write_atomic(p, cmp.junit().as_bytes())?;
    }
    if let Some(summary) = summary {
        use std::io::Write;
        let mut f = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(summary)
            .with_context(|| format!("$GITHUB_STEP_SUMMARY {}", summary.display()))?;
        f.write_all(md.as_bytes())?;
    }
    Ok(())
}

/// Exit 1 on a regression; an error where groups cannot reach alpha (unless allowed).
fn verdict(cmp: &compare::Comparison, opts: &CompareOptions) -> anyhow::Result<()> {
    let n = cmp.regressions();
    if n > 0 {
        return Err(super::Failed(format!(
            "{n} of {} groups regressed ({})",
            cmp.groups.len(),
            cmp.metric
        ))
        .into());
    }
    let few = cmp.too_few();
    if few > 0 && !opts.allow_too_few {
        bail!(
            "{few} of {} groups have fewer than {} seed pairs and cannot reach alpha = {} (the exact test's smallest p on n pairs is 2^-n): run more seeds, raise --alpha, or pass --allow-too-few",
            cmp.groups.len(),
            opts.required_pairs(),
            opts.alpha
        );
    }
    Ok(())
}
