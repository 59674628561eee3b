//! `physid experiment`: the sample-size experiment, written to `results/NAME/`.

use anyhow::Context;
use physid::experiment::{self, median_iqr, ExperimentSpec, Row};
use physid::ident::ConstraintSet;
use std::fmt::Write;
use std::path::Path;

/// The long table as CSV: one row per (seed, n_s, set).
pub fn rows_csv(rows: &[Row], joints: &[String]) -> String {
    let mut w = csv::Writer::from_writer(vec![]);
    let mut header: Vec<String> = ["seed", "n_s", "constraints"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    header.extend(joints.iter().map(|j| format!("val_rms_{j}")));
    header.extend(
        [
            "val_rms",
            "train_rms",
            "mass_err",
            "com_err_m",
            "inertia_err",
            "j_err",
            "consistent",
            "status",
            "solve_s",
        ]
        .iter()
        .map(|s| s.to_string()),
    );
    w.write_record(&header).expect("memory");
    for r in rows {
        let mut rec = vec![
            r.seed.to_string(),
            r.n_s.to_string(),
            r.constraints.name().to_string(),
        ];
        rec.extend(r.val_rms.iter().map(|v| v.to_string()));
        rec.extend([
            r.val_rms_overall.to_string(),
            r.train_rms_overall.to_string(),
            r.mass_err.to_string(),
            r.com_err.to_string(),
            r.inertia_err.to_string(),
            r.j_err.to_string(),
            r.consistent.to_string(),
            r.status.clone(),
            r.solve_s.to_string(),
        ]);
        w.write_record(&rec).expect("memory");
    }
    String::from_utf8(w.into_inner().expect("memory")).expect("utf-8")
}

/// The Markdown summary: median [IQR] over seeds per n_s × set.
pub fn summary_md(rows: &[Row], spec: &ExperimentSpec, title: &str) -> String {
    let sets: Vec<ConstraintSet> = spec.constraints.clone();
    let mut s = String::new();
    let _ = writeln!(s, "# {title}\n");
    let _ = writeln!(
        s,
        "{} seeds, training on the first n_s samples, validation on the next {}. Median [interquartile range] over seeds.\n",
        spec.seeds, spec.validation
    );
    let table =
        |s: &mut String, label: &str, f: &dyn Fn(&Row) -> f64, fmt: &dyn Fn(f64) -> String| {
            let _ = writeln!(s, "## {label}\n");
            let _ = write!(s, "| n_s |");
            for set in &sets {
                let _ = write!(s, " {} |", set.name());
            }
            let _ = write!(s, "\n|---|");
            for _ in &sets {
                let _ = write!(s, "---|");
            }
            let _ = writeln!(s);
            for n in spec.grid() {
                let _ = write!(s, "| {n} |");
                for set in &sets {
                    let v: Vec<f64> = rows
                        .iter()
                        .filter(|r| r.n_s == n && r.constraints == *set)
                        .map(f)
                        .collect();
                    let (lo, med, hi) = median_iqr(&v);
                    let _ = write!(s, " {} [{}, {}] |", fmt(med), fmt(lo), fmt(hi));
                }
                let _ = writeln!(s);
            }
            let _ = writeln!(s);
        };
    let g = |x: f64| format!("{x:.3}");
    table(
        &mut s,
        "Validation RMS torque error (N m, all joints)",
        &|r| r.val_rms_overall,
        &g,
    );
    table(
        &mut s,
        "Relative pseudo-inertia error ‖Ĵ − J‖/‖J‖ (mean over bodies)",
        &|r| r.j_err,
        &g,
    );
    table(
        &mut s,
        "Physically consistent results (fraction of seeds)",
        &|r| if r.consistent { 1.0 } else { 0.0 },
        &|x| format!("{x:.2}"),
    );
    table(&mut s, "Solve time (ms)", &|r| r.solve_s * 1e3, &|x| {
        format!("{x:.2}")
    });
    s
}

/// Runs the experiment of a scenario file and writes the results directory.
pub fn run(
    path: &Path,
    out: &Path,
    seeds: Option<usize>,
    threads: Option<usize>,
) -> anyhow::Result<()> {
    let (sc, model, text) = physid::io::load_scenario(path)?;
    let mut spec = sc.experiment.clone().unwrap_or_default();
    if let Some(n) = seeds {
        spec.seeds = n;
    }
    spec.validate()
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()?;
    let cells = spec.seeds * spec.grid().len() * spec.constraints.len();
    let bar = indicatif::ProgressBar::new(spec.seeds as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{spinner} seeds [{bar:40}] {pos}/{len} {elapsed}")
            .expect("valid")
            .progress_chars("=> "),
    );
    let start = std::time::Instant::now();
    let rows = pool
        .install(|| experiment::run(&model, &sc, &spec, &|done, _| bar.set_position(done as u64)))
        .with_context(|| format!("running the experiment of {}", path.display()))?;
    let wall = start.elapsed().as_secs_f64();
    bar.finish_and_clear();
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let joints: Vec<String> = model.bodies.iter().map(|b| b.joint_name.clone()).collect();
    physid::io::write_atomic(&out.join("rows.csv"), rows_csv(&rows, &joints).as_bytes())?;
    let title = format!("Validation error versus training size: {}", path.display());
    let mut md = summary_md(&rows, &spec, &title);
    let _ = writeln!(
        md,
        "{cells} cells ({} seeds × {} sizes × {} sets) in {wall:.1} s on {} threads.",
        spec.seeds,
        spec.grid().len(),
        spec.constraints.len(),
        pool.current_num_threads()
    );
    physid::io::write_atomic(&out.join("summary.md"), md.as_bytes())?;
    let git = std::process::Command::new("git")
        .args(["rev-parse", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_else(|| "unknown".into());
    let prov = serde_json::json!({
        "scenario_file": path, "scenario": text, "experiment": spec,
        "seeds": (spec.first_seed..spec.first_seed + spec.seeds as u64).collect::<Vec<_>>(),
        "git_revision": git, "physid_version": env!("CARGO_PKG_VERSION"),
        "threads": pool.current_num_threads(), "wall_seconds": wall,
    });
    physid::io::write_atomic(
        &out.join("provenance.json"),
        serde_json::to_string_pretty(&prov)?.as_bytes(),
    )?;
    println!(
        "{cells} cells in {wall:.1} s; wrote {}/rows.csv, summary.md, provenance.json",
        out.display()
    );
    print!(
        "{}",
        summary_md(&rows, &spec, &title)
            .split("## Relative")
            .next()
            .unwrap_or("")
    );
    Ok(())
}
