//! `physid diagnose` and `physid blind`.

use anyhow::Context as _;
use physid::diagnose::{self, Diagnosis};
use physid::experiment::blind;
use physid::ident::ConstraintSet;
use physid::model::Model;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

fn print_text(d: &Diagnosis) {
    println!(
        "robot {} ({} joints), {} training / {} validation samples, constraints {}",
        d.robot,
        d.joints.len(),
        d.samples[0],
        d.samples[1],
        d.constraints.name()
    );
    println!("\nWHERE (nominal model, validation residual)");
    for (j, name) in d.joints.iter().enumerate() {
        let sp = &d.spectra[j];
        println!(
            "  {name:<12} RMS {:.3} N m; spectrum peak {:.2} Hz; coherence {}",
            d.breakdown.rms[j],
            sp.peak_frequency,
            sp.signals
                .iter()
                .zip(&sp.peak_coherence)
                .map(|(s, (c, f))| format!("{s} {c:.2}@{f:.1}Hz"))
                .collect::<Vec<_>>()
                .join(", ")
        );
        let mut top: Vec<_> = d
            .breakdown
            .regimes
            .iter()
            .filter(|r| &r.joint == name && r.samples > 0)
            .collect();
        top.sort_by(|a, b| b.rms.total_cmp(&a.rms));
        for r in top.iter().take(3) {
            println!(
                "      {:<44} RMS {:.3} ({} samples, {:.0} % of the energy)",
                r.regime,
                r.rms,
                r.samples,
                100.0 * r.share
            );
        }
    }
    println!(
        "\nWHICH (cross-validated over {} {}; nominal CV RMS {:.3} N m)",
        d.selection.blocks,
        if d.selection.by_run {
            "runs, leaving one out"
        } else {
            "contiguous blocks"
        },
        d.selection.nominal_cv_rms
    );
    for (i, s) in d.selection.steps.iter().enumerate() {
        println!(
            "  step {}: {} (CV RMS {:.3} -> {:.3}, -{:.1} % mean square){}{}",
            i + 1,
            s.kind.name(),
            s.cv_rms_before,
            s.cv_rms_after,
            100.0 * s.reduction,
            listed("; AMBIGUOUS with ", &s.ambiguous_with),
            listed("; also fit (more terms): ", &s.also_fit)
        );
    }
    println!("  stop: {}", d.selection.stop);
    if let Some(t) = &d.description_test {
        println!(
            "  against the description (stated uncertainty {:.0} %, correlation time {:.1} samples):",
            100.0 * t.uncertainty,
            t.correlation_samples
        );
        for st in &t.steps {
            println!(
                "    {} absorbed: Δ = {:.1} > χ² threshold {:.1}{}",
                st.kind.name(),
                st.statistic,
                st.threshold,
                listed("; AMBIGUOUS with ", &st.ambiguous_with)
            );
        }
        println!("    stop: {}", t.stop);
    }
    for e in &d.effects {
        println!(
            "  {}{}: {}",
            e.kind.name(),
            if e.param != 0.0 {
                format!(" ({})", e.param)
            } else {
                String::new()
            },
            e.magnitude_name
        );
        for m in &e.magnitudes {
            println!(
                "      {:<12} {:>11.4e} ± {:.1e} {}{}",
                m.joint,
                m.value,
                m.se,
                m.unit,
                if m.identifiable < physid::diagnose::IDENTIFIABLE {
                    " (not identifiable: absorbed by the inertial parameters)"
                } else {
                    ""
                }
            );
        }
        if let Some(s) = &e.separate_by {
            println!("      to separate: {s}");
        }
    }
    println!("\nHOW FAR (validation RMS, N m)");
    for g in &d.gap {
        println!(
            "  {:<12} {:.3} -> {} (noise floor {:.3}, {:.0} % of the gap closed)",
            g.joint,
            g.nominal,
            g.after
                .iter()
                .map(|v| format!("{v:.3}"))
                .collect::<Vec<_>>()
                .join(" -> "),
            g.noise_floor,
            100.0 * g.gap_closed
        );
    }
    println!("\n{}", d.summary);
}

/// `prefix` and the names of `kinds`, or nothing when there are none.
fn listed(prefix: &str, kinds: &[physid::diagnose::library::Kind]) -> String {
    if kinds.is_empty() {
        String::new()
    } else {
        format!("{prefix}{}", physid::diagnose::library::names(kinds, false))
    }
}

/// The arguments of `physid diagnose`.
pub struct Args<'a> {
    /// The robot description.
    pub model: Model,
    /// Training files.
    pub data: &'a [PathBuf],
    /// Validation files (empty: hold out the end of the training data).
    pub validate: &'a [PathBuf],
    /// Constraint set of the nominal model.
    pub constraints: ConstraintSet,
    /// Held-out fraction without validation files.
    pub holdout: f64,
    /// Processing low-pass (Hz).
    pub cutoff: f64,
    /// Print JSON.
    pub json: bool,
    /// Report directory.
    pub report: Option<&'a Path>,
    /// Relative uncertainty of the description's inertial parameters (absorbed-effect test).
    pub description_uncertainty: Option<f64>,
}

/// `physid diagnose`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let Args {
        model,
        data,
        validate,
        constraints,
        holdout,
        cutoff,
        json,
        report,
        description_uncertainty,
    } = a;
    if let Some(e) = description_uncertainty {
        anyhow::ensure!(
            e.is_finite() && e > 0.0,
            "--description-uncertainty must be a positive fraction (0.1 = 10 %), got {e}"
        );
    }
    anyhow::ensure!(
        cutoff.is_finite() && cutoff > 0.0,
        "--cutoff must be a positive frequency in Hz, got {cutoff}"
    );
    let opts = diagnose::Options {
        constraints,
        processing_cutoff: cutoff,
        description_uncertainty,
        ..Default::default()
    };
    let load = |files: &[std::path::PathBuf]| -> anyhow::Result<Vec<_>> {
        files
            .iter()
            .map(|f| super::identify_cmd::load_data(f, &model))
            .collect()
    };
    let d = diagnose::diagnose_runs(&model, load(data)?, load(validate)?, holdout, &opts)?;
    if let Some(dir) = report {
        diagnose::report::write(dir, &d)
            .with_context(|| format!("writing the report to {}", dir.display()))?;
        eprintln!("wrote the report to {}", dir.display());
    }
    if json {
        println!("{}", serde_json::to_string_pretty(&d)?);
    } else {
        print_text(&d);
    }
    Ok(())
}

/// The arguments of `physid blind`.
pub struct BlindArgs<'a> {
    /// Number of cases.
    pub cases: usize,
    /// Seed of every draw.
    pub seed: u64,
    /// Base scenario.
    pub scenario: &'a Path,
    /// Output directory.
    pub out: Option<&'a Path>,
    /// Worker threads (0: all cores).
    pub threads: usize,
    /// Relative error of the description's inertial parameters.
    pub description_error: f64,
    /// The uncertainty the diagnosis is told (None: the error itself; 0: no description test).
    pub description_uncertainty: Option<f64>,
}

/// `physid blind`.
pub fn blind(a: BlindArgs) -> anyhow::Result<()> {
    let BlindArgs {
        cases,
        seed,
        scenario,
        out,
        threads,
        description_error,
        description_uncertainty,
    } = a;
    anyhow::ensure!(cases > 0, "--cases must be at least 1");
    anyhow::ensure!(
        description_error.is_finite() && (0.0..1.0).contains(&description_error),
        "--description-error must lie in [0, 1), got {description_error}"
    );
    let stated = description_uncertainty.unwrap_or(description_error);
    anyhow::ensure!(
        stated.is_finite() && stated >= 0.0,
        "--description-uncertainty must be >= 0, got {stated}"
    );
    let (base, model, _) = physid::sim::scenario::load(scenario)?;
    let work = tempfile::tempdir()?;
    let opts = diagnose::Options {
        description_uncertainty: (stated > 0.0).then_some(stated),
        ..Default::default()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?;
    let start = std::time::Instant::now();
    let results: Vec<blind::CaseResult> = pool.install(|| {
        (0..cases)
            .into_par_iter()
            .map(|i| {
                let r = blind::run_case(
                    i,
                    seed,
                    &base,
                    &model,
                    description_error,
                    &opts,
                    &work.path().join(format!("case{i}")),
                );
                if let Ok(r) = &r {
                    eprintln!(
                        "case {:>3} {:<14} injected [{}] visible {:.3} found [{}] {:?} top1 {:?} mag {:?} rms {:.3}->{:.3} floor {:.3} ({:.1} s)",
                        r.case,
                        format!("{:?}", r.category),
                        r.injected.join(", "),
                        r.visible_gap,
                        r.found.join(", "),
                        r.verdict,
                        r.top1,
                        r.magnitude_error.map(|m| (m * 1000.0).round() / 1000.0),
                        r.rms[0],
                        r.rms[1],
                        r.rms[2],
                        r.seconds
                    );
                }
                r
            })
            .collect::<Result<Vec<_>, blind::BlindError>>()
    })?;
    let scores = blind::score(&results);
    let wall = start.elapsed().as_secs_f64();
    println!("{}", serde_json::to_string_pretty(&scores)?);
    eprintln!("{cases} cases in {wall:.1} s");
    if let Some(dir) = out {
        blind::write_blind(
            dir,
            &results,
            &scores,
            seed,
            scenario,
            [description_error, stated],
            wall,
        )?;
        eprintln!("wrote {}", dir.display());
    }
    Ok(())
}
