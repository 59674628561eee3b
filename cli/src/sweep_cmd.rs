//! `physid sweep`: a parameter grid crossed with the constraint sets, resumable and shardable.

use anyhow::{bail, Context};
use physid::api::sweep::{self, SweepOptions};
use std::path::PathBuf;

/// Parses `K/N`.
pub fn parse_shard(s: &str) -> anyhow::Result<(usize, usize)> {
    let (k, n) = s
        .split_once('/')
        .with_context(|| format!("--shard: '{s}' is not K/N"))?;
    let (k, n): (usize, usize) = (
        k.parse().context("--shard K")?,
        n.parse().context("--shard N")?,
    );
    if n == 0 || k >= n {
        bail!("--shard {k}/{n}: need 0 <= K < N");
    }
    Ok((k, n))
}

/// A parameter sweep (docs/sweeps.md): a grid over scenario keys crossed with the constraint
/// sets; resumable (finished cells are skipped) and shardable across machines.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Sweep file (TOML).
    sweep: PathBuf,
    /// Output directory (default results/<sweep file name>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Run only cells with index ≡ K (mod N), e.g. a job array's task: `--shard 3/16`.
    #[arg(long)]
    shard: Option<String>,
    /// Worker threads (default: all cores).
    #[arg(allow_negative_numbers = true, long)]
    threads: Option<usize>,
}

/// Runs (this shard of) a sweep, then merges if every cell is present.
pub fn run(a: Args) -> anyhow::Result<()> {
    let opts = SweepOptions {
        shard: a.shard.as_deref().map(parse_shard).transpose()?,
        sweep: a.sweep,
        out: a.out,
    };
    let plan = sweep::plan(&opts)?;
    if plan.stale > 0 {
        eprintln!(
            "note: {} cell files in {} belong to another configuration (changed sweep, scenario, robot or physid version): not used",
            plan.stale,
            plan.out.join("cells").display()
        );
    }
    eprintln!(
        "{}: {} cells{}, {} already done, {} to run",
        plan.path.display(),
        plan.mine.len(),
        opts.shard.map_or(String::new(), |(k, n)| format!(
            " in shard {k}/{n} of {}",
            plan.cells.len()
        )),
        plan.mine.len() - plan.todo.len(),
        plan.todo.len()
    );
    let pool = super::thread_pool(a.threads)?;
    let bar = super::progress::Progress::new("cells", plan.todo.len() as u64);
    pool.install(|| plan.run(&|| bar.inc()))?;
    bar.finish();
    let Some(_) = plan.merge()? else {
        eprintln!(
            "{} of {} cells still missing (other shards); merge when all are done by running without --shard",
            plan.missing(),
            plan.cells.len()
        );
        return Ok(());
    };
    println!(
        "{} cells merged into {}/rows.parquet, summary.csv, summary.md, summary.svg",
        plan.cells.len(),
        plan.out.display()
    );
    Ok(())
}
