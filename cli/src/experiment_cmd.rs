//! `physid experiment`: the sample-size experiment, written to `results/NAME/`.

use anyhow::Context;
use physid::api::provenance::Provenance;
use physid::experiment::{self, plots, tables};
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// The sample-size experiment of a scenario file (its [experiment] table), in parallel.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Scenario file (TOML).
    scenario: PathBuf,
    /// Output directory.
    #[arg(long, default_value = "results/sample_size")]
    out: PathBuf,
    /// Override the number of seeds.
    #[arg(allow_negative_numbers = true, long)]
    seeds: Option<usize>,
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(allow_negative_numbers = true, long)]
    threads: Option<usize>,
}

/// Runs the experiment of a scenario file and writes the results directory: `rows.parquet` and
/// `rows.csv` (the long table), `summary.parquet` and `summary.csv` (median and quartiles over
/// seeds per n_s × set), `summary.md` (pivots), `validation_error.svg`, `parameter_error.svg`
/// and `provenance.json`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let (path, seeds, threads) = (&a.scenario, a.seeds, a.threads);
    if let Some(spec) = physid::api::experiment::whole_robot_plan(path, seeds)? {
        let command = format!("physid experiment {}", path.display());
        let run = super::whole_robot_cmd::Run {
            out: &a.out,
            inputs: std::slice::from_ref(path),
            command: &command,
            threads,
        };
        return super::whole_robot_cmd::run_spec(&spec, &[spec.force_noise], &run);
    }
    let physid::api::experiment::PlannedExperiment {
        scenario: sc,
        model,
        text,
        spec,
    } = physid::api::experiment::plan(path, seeds)?;
    let base = path.parent().unwrap_or(std::path::Path::new("."));
    let inputs: Vec<std::path::PathBuf> = physid::io::scenario_files(path)
        .into_iter()
        .chain(spec.excitations.iter().map(|e| base.join(&e.scenario)))
        .collect();
    physid::io::check_result_dir(&a.out, &inputs)?;
    let pool = super::thread_pool(threads)?;
    if !spec.excitations.is_empty() {
        return run_motions(&a, &text, &model, &spec, &pool);
    }
    // Checked before the run; written beside the target and moved into place whole.
    let staging = physid::io::StagingDir::new(&a.out)?;
    let out = staging.path();
    let cells = spec.seeds * spec.grid().len() * spec.constraints.len();
    let bar = super::progress::Progress::new("seeds", spec.seeds as u64);
    let start = std::time::Instant::now();
    let rows = pool
        .install(|| experiment::run(&model, &sc, &spec, &|done, _| bar.set(done as u64)))
        .with_context(|| format!("running the experiment of {}", path.display()))?;
    let wall = start.elapsed().as_secs_f64();
    bar.finish();
    let threads = pool.current_num_threads();
    let (_, summary) = write_run(out, path, &text, &spec, &rows, &model, wall, threads)?;
    staging.commit()?;
    println!(
        "{cells} cells in {wall:.1} s on {} threads; wrote {}/",
        threads,
        a.out.display()
    );
    let sets: Vec<&str> = spec.constraints.iter().map(|s| s.name()).collect();
    let p = tables::pivot(&summary, "val_rms_median", &sets)?;
    println!("median validation RMS (N m):\n{}", tables::markdown(&p));
    Ok(())
}

/// Writes one run's results into `out`: `rows.parquet` and `rows.csv` (the long table),
/// `summary.parquet` and `summary.csv`, `summary.md`, the two plots and `provenance.json`.
/// Returns the long table and the summary.
#[allow(clippy::too_many_arguments)]
fn write_run(
    out: &Path,
    path: &Path,
    text: &str,
    spec: &experiment::ExperimentSpec,
    rows: &[experiment::Row],
    model: &physid::model::Model,
    wall: f64,
    threads: usize,
) -> anyhow::Result<(polars::prelude::DataFrame, polars::prelude::DataFrame)> {
    let joints: Vec<String> = model.joint_names();
    let body_names: Vec<String> = physid::ident::bodies(model)
        .into_iter()
        .map(|(n, _, _)| n)
        .collect();
    let mut long = tables::long_table_with_bodies(rows, &joints, &body_names)?;
    let provenance = provenance_metadata(path, spec);
    tables::write_parquet_with(&out.join("rows.parquet"), &mut long, &provenance)?;
    tables::write_csv(&out.join("rows.csv"), &mut long)?;
    let mut summary = tables::summary(&long)?;
    tables::write_parquet_with(&out.join("summary.parquet"), &mut summary, &provenance)?;
    tables::write_csv(&out.join("summary.csv"), &mut summary)?;
    let sets: Vec<&str> = spec.constraints.iter().map(|s| s.name()).collect();
    let md = summary_markdown(path, spec, &summary, &sets, wall, threads)?;
    physid::io::write_atomic(&out.join("summary.md"), md.as_bytes())?;
    write_plots(&summary, &sets, out)?;
    Provenance::new(path, text, spec, threads, wall).write(out)?;
    Ok((long, summary))
}

/// Where a table's rows come from, as Parquet key-value metadata (provenance.json has it all).
fn provenance_metadata(path: &Path, spec: &experiment::ExperimentSpec) -> Vec<(String, String)> {
    vec![(
        "physid.provenance".to_string(),
        serde_json::json!({
            "scenario_file": path, "git_revision": physid::api::provenance::git_revision(),
            "seeds": (spec.first_seed..spec.first_seed + spec.seeds as u64).collect::<Vec<_>>(),
        })
        .to_string(),
    )]
}

/// The excitation axis: every motion of `spec.excitations` into `out/NAME/` (as a single
/// run), then their comparison: `excitations.{parquet,csv}` (summary per motion, size and
/// set), `excitations.md` and `excitations.json` (samples to reach the first motion's
/// largest-size validation error; parameter errors), `validation_SET.svg` and
/// `parameter_SET.svg` (one line per motion).
fn run_motions(
    a: &Args,
    text: &str,
    model: &physid::model::Model,
    spec: &experiment::ExperimentSpec,
    pool: &rayon::ThreadPool,
) -> anyhow::Result<()> {
    use experiment::motions;
    let path = &a.scenario;
    let motions = motions::load(path, spec, model)?;
    let staging = physid::io::StagingDir::new(&a.out)?;
    let out = staging.path();
    let bar = super::progress::Progress::new("seeds", spec.seeds as u64);
    let start = std::time::Instant::now();
    let rows = pool
        .install(|| motions::run(model, &motions, spec, &|done, _| bar.set(done as u64)))
        .with_context(|| format!("running the experiment of {}", path.display()))?;
    let wall = start.elapsed().as_secs_f64();
    bar.finish();
    let threads = pool.current_num_threads();
    // Validation-only motions have no rows.
    let (motions, rows): (Vec<_>, Vec<_>) = motions
        .into_iter()
        .zip(rows)
        .filter(|(m, _)| !m.validation_only)
        .unzip();
    let names: Vec<String> = motions.iter().map(|m| m.name.clone()).collect();
    let mut longs = vec![];
    for (m, r) in motions.iter().zip(&rows) {
        let dir = out.join(&m.name);
        std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
        let m_text = physid::io::read_to_string(&m.path)?;
        let (long, _) = write_run(&dir, &m.path, &m_text, spec, r, model, wall, threads)?;
        longs.push(tables::with_constants(
            long,
            &[("excitation".to_string(), m.name.clone())],
        )?);
    }
    let mut summary = tables::summary_by(&tables::concat(longs)?, &["excitation"])?;
    let provenance = provenance_metadata(path, spec);
    tables::write_parquet_with(&out.join("excitations.parquet"), &mut summary, &provenance)?;
    tables::write_csv(&out.join("excitations.csv"), &mut summary)?;
    plot_motions(out, &summary, spec, &names)?;
    let reach = write_reach(out, path, spec, &names, &rows, (wall, threads))?;
    Provenance::new(path, text, spec, threads, wall).write(out)?;
    staging.commit()?;
    println!(
        "{} motions × {} seeds in {wall:.1} s on {threads} threads; wrote {}/",
        names.len(),
        spec.seeds,
        a.out.display()
    );
    print!("{}", reach_markdown(&names[0], &reach));
    Ok(())
}

/// `excitations.md` and `excitations.json`: the median curves of the motions (`names`, their
/// `rows`) and the samples each needs to reach the first one's largest-size errors, which it
/// returns; `(wall, threads)` the run's.
fn write_reach(
    out: &Path,
    path: &Path,
    spec: &experiment::ExperimentSpec,
    names: &[String],
    rows: &[Vec<experiment::Row>],
    (wall, threads): (f64, usize),
) -> anyhow::Result<Vec<experiment::motions::Reach>> {
    use experiment::motions;
    let curves = motions::median_curves(names, rows, spec);
    let reach = motions::reach(&curves, &names[0]);
    let md = excitations_markdown(path, spec, names, &curves, &reach, wall, threads);
    physid::io::write_atomic(&out.join("excitations.md"), md.as_bytes())?;
    let json = serde_json::json!({ "reference": names[0], "reach": reach, "curves": curves });
    physid::io::write_atomic(
        &out.join("excitations.json"),
        serde_json::to_string_pretty(&physid::io::versioned("excitations", &json))?.as_bytes(),
    )?;
    Ok(reach)
}

/// One line per motion against the training size, per constraint set: the validation error
/// (`validation_SET.svg`) and the pseudo-inertia error (`parameter_SET.svg`).
fn plot_motions(
    out: &std::path::Path,
    summary: &polars::prelude::DataFrame,
    spec: &experiment::ExperimentSpec,
    names: &[String],
) -> anyhow::Result<()> {
    let name_refs: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    for set in &spec.constraints {
        let s = tables::filter_eq(summary, "constraints", set.name())?;
        plots::plot_vs_ns_by(
            &s,
            "excitation",
            "val_rms",
            &name_refs,
            &format!(
                "Validation error vs training samples, {} (median, IQR band)",
                set.name()
            ),
            "validation RMS torque error [N m]",
            &out.join(format!("validation_{}.svg", set.name())),
        )?;
        plots::plot_vs_ns_by(
            &s,
            "excitation",
            "j_err",
            &name_refs,
            &format!(
                "Pseudo-inertia error vs training samples, {} (median, IQR band)",
                set.name()
            ),
            "‖Ĵ − J‖ / ‖J‖ (mean over bodies)",
            &out.join(format!("parameter_{}.svg", set.name())),
        )?;
    }
    Ok(())
}

/// The table of samples needed to reach the reference's largest-size validation error.
fn reach_markdown(reference: &str, reach: &[experiment::motions::Reach]) -> String {
    use physid::io::md_cell;
    let tol = 100.0 * experiment::motions::REACH_TOLERANCE;
    let mut s = format!(
        "\nTraining samples each motion needs to reach what `{r}` reaches with its largest training size (medians over seeds; ×: how many times fewer samples than `{r}`): its validation RMS, the same within {tol:.0} %, and its pseudo-inertia error; then the smallest size from which the motion's parameter error stays below `{r}`'s at every size.\n\n| set | motion | validation RMS target (N m) | samples | within {tol:.0} % | J error target | samples | parameter error lower from n_s |\n|---|---|---|---|---|---|---|---|\n",
        r = md_cell(reference)
    );
    let n = |v: Option<f64>, f: Option<f64>| match (v, f) {
        (Some(v), Some(f)) => format!("{v:.0} ({f:.1}×)"),
        _ => "not reached".into(),
    };
    for r in reach {
        s += &format!(
            "| {} | {} | {:.3} | {} | {} | {:.3} | {} | {} |\n",
            r.constraints.name(),
            md_cell(&r.excitation),
            r.target,
            n(r.samples, r.fewer),
            n(r.samples_within, r.fewer_within),
            r.j_err_target,
            n(r.samples_j_err, r.fewer_j_err),
            r.lower_parameter_error_from
                .map_or("never".into(), |n| n.to_string()),
        );
    }
    s
}

/// One table of `excitations.md`: a median (`pick`: 0 validation RMS, 1 pseudo-inertia
/// error, 2 validation against the true model) per training size and motion, under `set`.
fn median_table(
    label: &str,
    pick: usize,
    set: physid::ident::ConstraintSet,
    names: &[String],
    curves: &[experiment::motions::MedianCurve],
    spec: &experiment::ExperimentSpec,
) -> String {
    use physid::io::md_cell;
    let mut md = format!("\n## {label}, {}\n\n| n_s |", set.name());
    for n in names {
        md += &format!(" {} |", md_cell(n));
    }
    md += &format!("\n|---|{}\n", "---|".repeat(names.len()));
    let of_set: Vec<&experiment::motions::MedianCurve> =
        curves.iter().filter(|c| c.constraints == set).collect();
    for (i, n_s) in spec.grid().iter().enumerate() {
        md += &format!("| {n_s} |");
        for c in &of_set {
            let v = [c.val_rms[i], c.j_err[i], c.val_truth_rms[i]][pick];
            md += &format!(" {v:.4} |");
        }
        md += "\n";
    }
    if pick < 2 {
        md += &format!(
            "\n![{label}, {set}]({}_{set}.svg)\n",
            if pick == 0 { "validation" } else { "parameter" },
            set = set.name()
        );
    }
    md
}

/// `excitations.md`.
fn excitations_markdown(
    path: &Path,
    spec: &experiment::ExperimentSpec,
    names: &[String],
    curves: &[experiment::motions::MedianCurve],
    reach: &[experiment::motions::Reach],
    wall: f64,
    threads: usize,
) -> String {
    use physid::io::md_cell;
    let mut md = format!(
        "# Excitations compared: {}\n\n{} seeds (first {}), training on the first n_s samples of each motion; {}. Prior weight {}, prior error {}. Each motion's own tables are in its folder.\n",
        path.display(),
        spec.seeds,
        spec.first_seed,
        match &spec.validate_on {
            Some(v) => format!("every model validated on {} samples of an independent run of `{}` (seed + {})", spec.validation, md_cell(v), experiment::motions::VALIDATION_SEED_OFFSET),
            None => format!("validation on the next {} samples of the same run", spec.validation),
        },
        spec.prior_weight,
        spec.prior_error
    );
    md += &reach_markdown(&names[0], reach);
    for (label, pick) in [
        ("Median validation RMS (N m)", 0),
        (
            "Median validation RMS against the true model, Y (θ̂ − θ) on the validation states (N m)",
            2,
        ),
        ("Median pseudo-inertia error ‖Ĵ − J‖/‖J‖ (mean over bodies)", 1),
    ] {
        for set in &spec.constraints {
            md += &median_table(label, pick, *set, names, curves, spec);
        }
    }
    md += &format!(
        "\n{} motions in {wall:.1} s on {threads} threads.\n",
        names.len()
    );
    md
}

/// `summary.md`: the pivots of the summary over sets and sizes.
fn summary_markdown(
    path: &Path,
    spec: &experiment::ExperimentSpec,
    summary: &polars::prelude::DataFrame,
    sets: &[&str],
    wall: f64,
    threads: usize,
) -> anyhow::Result<String> {
    let cells = spec.seeds * spec.grid().len() * spec.constraints.len();
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Validation error versus training size: {}\n",
        path.display()
    );
    let _ = writeln!(
        md,
        "{} seeds (first {}), training on the first n_s samples, validation on the next {}; prior weight {}, prior error {}. Median and quartiles over seeds (all statistics in summary.csv).\n",
        spec.seeds, spec.first_seed, spec.validation, spec.prior_weight, spec.prior_error
    );
    let iqr_tables = [
        (
            "val_rms",
            "Validation RMS torque error (N m, all joints): median [q25, q75]",
        ),
        (
            "j_err",
            "Relative pseudo-inertia error ‖Ĵ − J‖/‖J‖ (mean over bodies): median [q25, q75]",
        ),
    ];
    for (value, label) in iqr_tables {
        let p = tables::pivot_with_iqr(summary, value, sets)?;
        let _ = writeln!(md, "## {label}\n\n{}", tables::markdown(&p));
    }
    let plain_tables = [
        (
            "consistent_fraction",
            "Fraction of physically consistent results",
        ),
        ("solve_ms_median", "Solve time (ms), median"),
    ];
    for (value, label) in plain_tables {
        let p = tables::pivot(summary, value, sets)?;
        let _ = writeln!(md, "## {label}\n\n{}", tables::markdown(&p));
    }
    let _ = writeln!(
        md,
        "![validation error](validation_error.svg)\n\n![parameter error](parameter_error.svg)\n"
    );
    let _ = writeln!(
        md,
        "{cells} cells ({} seeds × {} sizes × {} sets) in {wall:.1} s on {} threads.",
        spec.seeds,
        spec.grid().len(),
        spec.constraints.len(),
        threads
    );
    Ok(md)
}

/// The validation-error and parameter-error plots.
fn write_plots(
    summary: &polars::prelude::DataFrame,
    sets: &[&str],
    out: &Path,
) -> anyhow::Result<()> {
    plots::plot_vs_ns(
        summary,
        "val_rms",
        sets,
        "Validation error vs training samples (median, IQR band)",
        "validation RMS torque error [N m]",
        &out.join("validation_error.svg"),
    )?;
    plots::plot_vs_ns(
        summary,
        "j_err",
        sets,
        "Pseudo-inertia error vs training samples (median, IQR band)",
        "‖Ĵ − J‖ / ‖J‖ (mean over bodies)",
        &out.join("parameter_error.svg"),
    )?;
    Ok(())
}
