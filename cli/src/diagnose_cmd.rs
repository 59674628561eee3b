//! `physid diagnose`: the sim-to-real diagnosis of a robot description against its data.

use super::RobotArgs;
use anyhow::Context as _;
use physid::api::diagnose::{diagnose_files, DiagnoseOptions};
use physid::diagnose::{self, Diagnosis};
use physid::ident::ConstraintSet;
use std::path::PathBuf;

/// Diagnose the gap between a robot model and its data: where the residual lies (joints, motion
/// regimes, frequency), which unmodelled effect causes it (cross-validated forward selection over
/// the effect library), and how far it shrinks once modelled.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Training data (CSV with ddq, or MCAP); repeat for several runs.
    #[arg(long = "data", required = true, num_args = 1..)]
    data: Vec<PathBuf>,
    /// Validation data; without it the last --holdout of the data is held out.
    #[arg(long = "validate", num_args = 1..)]
    validate: Vec<PathBuf>,
    #[command(flatten)]
    read: super::identify_cmd::ReadArgs,
    #[command(flatten)]
    robot: RobotArgs,
    /// Constraint set of the nominal model.
    #[arg(long, default_value = "consistent")]
    constraints: ConstraintSet,
    /// Fraction held out for validation when no --validate is given.
    #[arg(long, default_value_t = 0.3, allow_negative_numbers = true)]
    holdout: f64,
    /// Print the diagnosis as JSON.
    #[arg(long)]
    json: bool,
    /// Write a report (report.html: self-contained, the verdict first, plots inline; report.md, report.json with its schema, SVG plots) into this directory.
    #[arg(long)]
    report: Option<PathBuf>,
    /// How far the description's inertial parameters can be trusted (relative, 0.1 = 10 %):
    /// tests the identified parameters against it for effects that identification absorbs
    /// (torque gain, tilt, payload). Off without it.
    #[arg(long, allow_negative_numbers = true)]
    description_uncertainty: Option<f64>,
    /// Search a payload over every body, not only the last (with --description-uncertainty;
    /// inner bodies are found only where the motion separates their parameters).
    #[arg(long)]
    payload_any_body: bool,
    /// "What changed": runs of the same robot before the change (a tool change, a repair, a
    /// new gripper). The description is calibrated on them with their standing effects, which
    /// are taken out of --data; only what differs is attributed. Needs
    /// --description-uncertainty.
    #[arg(long = "baseline-data", num_args = 1..)]
    baseline_data: Vec<PathBuf>,
    /// Ignore the information matrix in the description's sidecar (`identify --out-urdf`
    /// writes it; read from a sidecar given as --robot, or beside a URDF given as --robot).
    #[arg(long)]
    no_description_information: bool,
}

/// `physid diagnose`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let mut o = DiagnoseOptions::new(a.data.clone());
    o.validate = a.validate.clone();
    o.baseline_data = a.baseline_data.clone();
    o.read = a.read.options();
    o.holdout = a.holdout;
    o.diagnosis = diagnose::Options {
        constraints: a.constraints,
        description_uncertainty: a.description_uncertainty,
        every_body: a.payload_any_body,
        ..Default::default()
    };
    o.diagnosis.validate().map_err(super::option_error)?;
    let model = a.robot.load()?;
    if !a.no_description_information {
        physid::api::information::apply(&a.robot.robot, &model, &mut o.diagnosis)?
            .iter()
            .for_each(|n| eprintln!("{n}"));
    }
    if let Some(dir) = &a.report {
        let inputs: Vec<PathBuf> = a
            .robot
            .files()
            .into_iter()
            .chain(o.files().iter().map(|p| p.to_path_buf()))
            .collect();
        physid::io::check_result_dir(dir, &inputs)?;
    }
    let outcome =
        diagnose_files(&model, &o, &mut |n| eprintln!("{n}")).map_err(super::option_error)?;
    if let Some(standing) = &outcome.standing {
        eprintln!(
            "baseline: the description calibrated on {} run(s); standing effects taken out of the data: {}",
            outcome.baseline_runs,
            if standing.is_empty() { "none".to_string() } else { standing.join(", ") }
        );
    }
    let d = outcome.diagnosis;
    if let Some(dir) = &a.report {
        diagnose::report::write(dir, &d)
            .with_context(|| format!("writing the report to {}", dir.display()))?;
        eprintln!("wrote the report to {}", dir.display());
    }
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&physid::io::versioned("diagnose", &d))?
        );
    } else {
        print_text(&d);
    }
    Ok(())
}

/// The diagnosis as text: where, which, how far, and the summary.
fn print_text(d: &Diagnosis) {
    print_where(d);
    print_which(d);
    print_how_far(d);
}

/// WHERE: the nominal model's validation residual per joint, its spectrum and worst regimes.
fn print_where(d: &Diagnosis) {
    println!(
        "robot {} ({} joints), {} training / {} validation samples, constraints {}",
        d.robot,
        d.joints.len(),
        d.samples[0],
        d.samples[1],
        d.constraints.name()
    );
    println!("\nWHERE (nominal model, validation residual, all samples; HOW FAR below leaves out slow joint-samples)");
    for (j, name) in d.joints.iter().enumerate() {
        let sp = &d.spectra[j];
        println!(
            "  {name:<12} RMS (all samples) {:.3} N m; spectrum peak {:.2} Hz; coherence {}",
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
}

/// WHICH: the selection's steps, the description test, and each effect's magnitudes.
fn print_which(d: &Diagnosis) {
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
    if let Some(why) = &d.description_test_skipped {
        println!("  against the description: {why}");
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
}

/// FROM THE DESCRIPTION: the description's gap explained step by step.
fn print_from_description(d: &Diagnosis) {
    println!(
        "\nFROM THE DESCRIPTION (validation RMS, N m, joint-samples slower than the speed threshold left out; its inertial parameters pinned until the last step)"
    );
    let row = |label: &str, rms: &[f64], all: f64| {
        let per: Vec<String> = rms.iter().map(|v| format!("{v:.3}")).collect();
        println!("  {label:<36} {} (all {all:.3})", per.join(" "));
    };
    row(
        "description as given",
        &d.gap.iter().map(|g| g.description).collect::<Vec<_>>(),
        d.description_overall,
    );
    match &d.ladder {
        Some(l) => {
            for r in l.rungs.iter().skip(1) {
                row(&r.step, &r.rms, r.overall);
                if !r.ambiguous_with.is_empty() {
                    println!("    the data fit as well: {}", r.alternatives().join("; "));
                }
            }
            for b in &l.bodies {
                let what = if b.payload { "payload" } else { "change" };
                println!("  {what} on {}: {}", b.body, b.weighed());
            }
        }
        None => {
            for st in &d.explained_from_description {
                row(&st.step, &st.rms, st.overall);
            }
        }
    }
}

/// HOW FAR: validation RMS per joint along the selection, and the summary.
fn print_how_far(d: &Diagnosis) {
    print_from_description(d);
    println!(
        "\nHOW FAR (validation RMS, N m, joint-samples slower than the speed threshold left out): the description as given -> re-identified (nominal) -> + each effect"
    );
    for g in &d.gap {
        println!(
            "  {:<12} {:.3} -> {:.3} -> {} (noise floor {:.3}, {:.0} % of the gap closed)",
            g.joint,
            g.description,
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
    let st = &d.structure_left;
    println!(
        "  structure left (a smooth function of each joint's speed and angle, fitted on training): validation mean square {:+.1} % overall [{}]; t = {:.1} over 10 validation blocks; {} (needs at least {:.1} % with t >= 2)",
        -100.0 * st.reduction,
        st.per_joint
            .iter()
            .map(|r| format!("{:+.1} %", -100.0 * r))
            .collect::<Vec<_>>()
            .join(", "),
        st.t,
        if st.remains { "REMAINS: an effect outside the library" } else { "none" },
        100.0 * st.threshold
    );
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
