//! `physid sweep`: a parameter grid crossed with the constraint sets, resumable and shardable.

use anyhow::{bail, Context};
use physid::experiment::{sweep, tables};
use rayon::prelude::*;
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
    #[arg(long)]
    threads: Option<usize>,
}

/// Runs (this shard of) a sweep, then merges if every cell is present.
pub fn run(a: Args) -> anyhow::Result<()> {
    let shard = a.shard.as_deref().map(parse_shard).transpose()?;
    let (path, out, threads) = (a.sweep.as_path(), a.out, a.threads);
    let (spec, scenario_path, base) = sweep::load(path)?;
    spec.experiment
        .validate()
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let out =
        out.unwrap_or_else(|| PathBuf::from("results").join(path.file_stem().unwrap_or_default()));
    let inputs: Vec<PathBuf> = physid::io::scenario_files(&scenario_path)
        .into_iter()
        .chain([path.to_path_buf()])
        .collect();
    physid::io::check_result_dir(&out, &inputs)?;
    // Every grid point is resolved (and checked) before anything is created or run: a bad
    // value fails fast, naming it, and leaves no empty result behind.
    let all = sweep::cells(&spec, &base, &scenario_path)?;
    let cells_dir = out.join("cells");
    std::fs::create_dir_all(&cells_dir)
        .with_context(|| format!("creating {}", cells_dir.display()))?;
    // Cells and merged tables are renamed into place whole; what killed runs left is partial.
    physid::io::remove_partials(&cells_dir);
    physid::io::remove_partials(&out);
    let file = |c: &sweep::Cell| cells_dir.join(format!("{}.parquet", c.id()));
    let mine: Vec<&sweep::Cell> = all
        .iter()
        .filter(|c| shard.is_none_or(|(k, n)| c.index % n == k))
        .collect();
    let todo: Vec<&sweep::Cell> = mine.iter().copied().filter(|c| !file(c).exists()).collect();
    let current: std::collections::BTreeSet<std::path::PathBuf> = all.iter().map(file).collect();
    let stale = std::fs::read_dir(&cells_dir)
        .with_context(|| format!("reading {}", cells_dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "parquet") && !current.contains(p))
        .count();
    if stale > 0 {
        eprintln!(
            "note: {stale} cell files in {} belong to another configuration (changed sweep, scenario, robot or physid version): not used",
            cells_dir.display()
        );
    }
    eprintln!(
        "{}: {} cells{}, {} already done, {} to run",
        path.display(),
        mine.len(),
        shard.map_or(String::new(), |(k, n)| format!(
            " in shard {k}/{n} of {}",
            all.len()
        )),
        mine.len() - todo.len(),
        todo.len()
    );
    let pool = super::thread_pool(threads)?;
    let bar = super::progress::Progress::new("cells", todo.len() as u64);
    let (_, model) = sweep::scenario_at(&base, &scenario_path, &all[0].point)?;
    let joints: Vec<String> = model.bodies.iter().map(|b| b.joint_name.clone()).collect();
    pool.install(|| {
        todo.par_iter().try_for_each(|c| -> anyhow::Result<()> {
            let rows = sweep::run_cell(&base, &scenario_path, &spec, c)
                .with_context(|| format!("cell {}", c.id()))?;
            let consts: Vec<(String, String)> = c
                .point
                .iter()
                .map(|(k, v)| (k.clone(), sweep::value_text(v)))
                .collect();
            let mut df = tables::with_constants(tables::long_table(&rows, &joints)?, &consts)?;
            tables::write_parquet(&file(c), &mut df)?;
            bar.inc();
            Ok(())
        })
    })?;
    bar.finish();
    let missing = all.iter().filter(|c| !file(c).exists()).count();
    if missing > 0 {
        eprintln!("{missing} of {} cells still missing (other shards); merge when all are done by running without --shard", all.len());
        return Ok(());
    }
    // summary.md is written last and marks a complete merge: remove the old one first, so a
    // merge killed half-way never leaves a summary beside tables of another merge.
    let marker = out.join("summary.md");
    if marker.exists() {
        std::fs::remove_file(&marker).with_context(|| format!("removing {}", marker.display()))?;
    }
    let parts = all
        .iter()
        .map(|c| tables::read_parquet(&file(c)))
        .collect::<Result<Vec<_>, _>>()?;
    let mut long = tables::concat(parts)?;
    tables::write_parquet(&out.join("rows.parquet"), &mut long)?;
    tables::write_csv(&out.join("rows.csv"), &mut long)?;
    let keys: Vec<&str> = spec.grid.keys().map(|k| k.as_str()).collect();
    let mut summary = tables::summary_by(&long, &keys)?;
    tables::write_parquet(&out.join("summary.parquet"), &mut summary)?;
    tables::write_csv(&out.join("summary.csv"), &mut summary)?;
    let md = format!(
        "# Sweep {}\n\nGrid: {}; {} seeds; sizes {:?}; sets {:?}. Medians and quartiles over seeds.\n\n{}",
        path.display(),
        keys.join(", "),
        spec.experiment.seeds,
        spec.experiment.grid(),
        spec.experiment.constraints.iter().map(|c| c.name()).collect::<Vec<_>>(),
        tables::markdown(&summary.select(keys.iter().map(|k| k.to_string()).chain(["n_s", "constraints", "val_rms_median", "j_err_median", "consistent_fraction"].map(String::from)))?)
    );
    let svg = sweep::summary_plot(&summary, &keys)
        .map_err(|m| anyhow::anyhow!("{}: plot: {m}", out.join("summary.svg").display()))?;
    physid::io::write_atomic(&out.join("summary.svg"), svg.as_bytes())?;
    physid::io::write_atomic(&marker, md.as_bytes())?;
    println!(
        "{} cells merged into {}/rows.parquet, summary.csv, summary.md, summary.svg",
        all.len(),
        out.display()
    );
    Ok(())
}
