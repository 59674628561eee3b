//! Reports: a diagnosis as Markdown, JSON and SVG plots (residual by regime, residual spectrum
//! before and after, validation RMS per joint before and after each effect).

use super::diagnosis::Diagnosis;
use crate::io::plot::{colour, legend_outside, tick, Mark, LEGEND_WIDTH};
use crate::io::{md_cell, IoError};
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Writing a report failed.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A file or the folder could not be written.
    #[error(transparent)]
    Io(#[from] IoError),
    /// A plot could not be drawn.
    #[error("{path}: plot: {message}")]
    Plot {
        /// The plot's file.
        path: PathBuf,
        /// What the plotting library reported.
        message: String,
    },
}

/// The error of drawing the plot at `path`.
fn plot_err<E: std::fmt::Display>(path: &Path) -> impl Fn(E) -> ReportError + '_ {
    move |e| ReportError::Plot {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// Grouped bars ([`crate::io::plot::grouped_bars`]) as SVG; errors name the plot's file `path`.
fn bars(
    path: &Path,
    title: &str,
    ylabel: &str,
    labels: &[String],
    series: &[(String, Vec<f64>)],
) -> Result<String, ReportError> {
    crate::io::plot::grouped_bars(title, ylabel, labels, series).map_err(plot_err(path))
}

/// Residual PSD per joint, before (solid) and after (thin) the selected effects, log-log,
/// written to `path`; returns the SVG (`None`, and no file, without a positive spectrum).
fn spectrum_plot(path: &Path, d: &Diagnosis) -> Result<Option<String>, ReportError> {
    let pos = |v: f64| v.is_finite() && v > 0.0;
    let all: Vec<(f64, f64)> = d
        .spectra
        .iter()
        .chain(&d.spectra_after)
        .flat_map(|s| s.frequency.iter().copied().zip(s.psd.iter().copied()))
        .filter(|(f, p)| pos(*f) && pos(*p))
        .collect();
    if all.is_empty() {
        return Ok(None);
    }
    let fmin = all.iter().map(|a| a.0).fold(f64::INFINITY, f64::min);
    let fmax = all.iter().map(|a| a.0).fold(0.0, f64::max);
    let pmin = all.iter().map(|a| a.1).fold(f64::INFINITY, f64::min);
    let pmax = all.iter().map(|a| a.1).fold(0.0, f64::max);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900 + LEGEND_WIDTH, 540)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err(path))?;
        let (plot_area, legend_area) = root.split_horizontally(900);
        let mut chart = ChartBuilder::on(&plot_area)
            .caption(
                "validation residual spectrum: nominal (thick), with effects (thin)",
                ("sans-serif", 18),
            )
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(80)
            .build_cartesian_2d(
                (fmin..fmax).log_scale(),
                (pmin * 0.5..pmax * 2.0).log_scale(),
            )
            .map_err(plot_err(path))?;
        chart
            .configure_mesh()
            .x_desc("frequency (Hz)")
            .y_desc("PSD (N^2 m^2 / Hz)")
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .draw()
            .map_err(plot_err(path))?;
        let mut entries = vec![];
        for (j, (a, b)) in d.spectra.iter().zip(&d.spectra_after).enumerate() {
            let c = colour(j);
            let pts = |s: &super::spectrum::Spectrum| -> Vec<(f64, f64)> {
                s.frequency
                    .iter()
                    .copied()
                    .zip(s.psd.iter().copied())
                    .filter(|(f, p)| pos(*f) && pos(*p))
                    .collect()
            };
            chart
                .draw_series(LineSeries::new(pts(a), c.stroke_width(2)))
                .map_err(plot_err(path))?;
            entries.push((a.joint.clone(), c, Mark::Line));
            chart
                .draw_series(LineSeries::new(pts(b), c.mix(0.6).stroke_width(1)))
                .map_err(plot_err(path))?;
        }
        legend_outside(&legend_area, &entries).map_err(plot_err(path))?;
        root.present().map_err(plot_err(path))?;
    }
    Ok(Some(svg))
}

/// The Markdown report.
pub fn markdown(d: &Diagnosis) -> String {
    let mut s = format!(
        "# Diagnosis of {}\n\n**{}**\n\n{} joints; {} training and {} validation samples; nominal model: constraint set `{}` (constraints hold: {}).\n\n",
        d.robot,
        d.summary,
        d.joints.len(),
        d.samples[0],
        d.samples[1],
        d.constraints.name(),
        d.nominal_constraints_hold
    );
    s += &where_section(d);
    s += &which_section(d);
    s += &description_section(d);
    s += &effects_section(d);
    s += &from_description_section(d);
    s += "\n";
    s += &how_far_section(d);
    s
}

/// The Markdown "Where" section: residual per joint and regime, spectrum peaks.
fn where_section(d: &Diagnosis) -> String {
    let mut s = String::new();
    s += "## Where\n\nValidation residual of the nominal model per joint and regime, over all samples (RMS in N m, share of the joint's residual energy; *How far* leaves out joint-samples slower than the speed threshold, so its RMS differs). Plot: `where.svg`; spectrum: `spectrum.svg`.\n\n| joint | regime | samples | RMS | share |\n|---|---|---|---|---|\n";
    for r in &d.breakdown.regimes {
        s += &format!(
            "| {} | {} | {} | {:.3} | {:.2} |\n",
            md_cell(&r.joint),
            md_cell(&r.regime),
            r.samples,
            r.rms,
            r.share
        );
    }
    s += "\n| joint | PSD peak (Hz) | peak coherence with q, qd, qdd, sin(N q) |\n|---|---|---|\n";
    for sp in &d.spectra {
        s += &format!(
            "| {} | {:.2} | {} |\n",
            md_cell(&sp.joint),
            sp.peak_frequency,
            sp.peak_coherence
                .iter()
                .map(|(c, f)| format!("{c:.2} @ {f:.1} Hz"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    s
}

/// The "Which" section: the cross-validated selection, step by step.
fn which_section(d: &Diagnosis) -> String {
    let mut s = String::new();
    s += &format!(
        "\n## Which\n\nCross-validated forward selection over {} {} (nominal CV RMS {:.3} N m).\n\n",
        d.selection.blocks,
        if d.selection.by_run {
            "training runs, leaving one run out"
        } else {
            "contiguous blocks of the training data"
        },
        d.selection.nominal_cv_rms
    );
    for (i, st) in d.selection.steps.iter().enumerate() {
        s += &format!(
            "### Step {}: `{}` (CV RMS {:.3} → {:.3} N m, −{:.1} % mean square)\n\n",
            i + 1,
            st.kind.name(),
            st.cv_rms_before,
            st.cv_rms_after,
            100.0 * st.reduction
        );
        if !st.ambiguous_with.is_empty() {
            s += &format!(
                "**Ambiguous** with {}: the data fit them equally well.\n\n",
                crate::effect::library::names(&st.ambiguous_with, true)
            );
        }
        s +=
            "| kind | grid value | CV RMS | reduction | blocks improved |\n|---|---|---|---|---|\n";
        for sc in &st.scores {
            s += &format!(
                "| {} | {} | {:.4} | {:.1} % | {} |\n",
                sc.kind.name(),
                sc.param,
                sc.cv_rms,
                100.0 * sc.reduction,
                sc.blocks_improved
            );
        }
        s += "\n";
    }
    s += &format!("Stopped: {}.\n\n", d.selection.stop);
    s
}

/// The test against the description, when it ran (or why it did not).
fn description_section(d: &Diagnosis) -> String {
    let mut s = String::new();
    if let Some(why) = &d.description_test_skipped {
        s += &format!(
            "### Absorbed effects: the test against the description\n\nThe test was {why}.\n\n"
        );
    }
    if let Some(t) = &d.description_test {
        s += &format!(
            "### Absorbed effects: the test against the description (stated uncertainty {:.0} %)\n\nResidual mean square {:.4} N² m², correlation time {:.1} samples.\n\n",
            100.0 * t.uncertainty,
            t.residual_ms,
            t.correlation_samples
        );
        for (i, st) in t.steps.iter().enumerate() {
            s += &format!(
                "Step {}: `{}` (Δ = {:.1} > χ² threshold {:.1}){}\n\n| kind | Δ | threshold | columns | visible |\n|---|---|---|---|---|\n",
                i + 1,
                st.kind.name(),
                st.statistic,
                st.threshold,
                if st.ambiguous_with.is_empty() {
                    String::new()
                } else {
                    format!(
                        "; **ambiguous** with {}",
                        crate::effect::library::names(&st.ambiguous_with, true)
                    )
                }
            );
            for x in &st.tests {
                s += &format!(
                    "| {} | {:.1} | {:.1} | {} | {:.3} |\n",
                    x.kind.name(),
                    x.statistic,
                    x.threshold,
                    x.columns,
                    x.visible
                );
            }
            s += "\n";
        }
        s += &format!("Stopped: {}.\n\n", t.stop);
    }
    s
}

/// Each selected effect with its magnitudes.
fn effects_section(d: &Diagnosis) -> String {
    let mut s = String::new();
    for e in &d.effects {
        s += &format!(
            "### `{}`{}: {}\n\n| joint | value | std. error | unit | identifiable |\n|---|---|---|---|---|\n",
            e.kind.name(),
            if e.param != 0.0 {
                format!(" at {}", e.param)
            } else {
                String::new()
            },
            match e.evidence {
                super::diagnosis::Evidence::CrossValidation => e.magnitude_name.clone(),
                super::diagnosis::Evidence::Description =>
                    format!("{} (found against the description)", e.magnitude_name),
            }
        );
        for m in &e.magnitudes {
            s += &format!(
                "| {} | {:.4e} | {:.1e} | {} | {:.2} |\n",
                md_cell(&m.joint),
                m.value,
                m.se,
                m.unit,
                m.identifiable
            );
        }
        if let Some(sep) = &e.separate_by {
            s += &format!("\nTo separate them: {sep}.\n");
        }
        s += "\n";
    }
    s
}

/// The "From the description" section: the description's gap explained step by step.
fn from_description_section(d: &Diagnosis) -> String {
    let mut s = String::from("## From the description

The sim-to-real gap itself: validation RMS per joint (N m; joint-samples slower than the speed threshold left out) of the description as given, then with each explanation freed while the description's inertial parameters stay pinned (the one that lowers the training residual most first), then with the inertial parameters re-identified too.

| step |");
    for j in &d.joints {
        s += &format!(" {} |", md_cell(j));
    }
    s += " all |\n|---|";
    s += &"---|".repeat(d.joints.len() + 1);
    s += "\n| description as given |";
    for g in &d.gap {
        s += &format!(" {:.3} |", g.description);
    }
    s += &format!(" {:.3} |\n", d.description_overall);
    for st in &d.explained_from_description {
        s += &format!("| {} |", st.step);
        for r in &st.rms {
            s += &format!(" {r:.3} |");
        }
        s += &format!(" {:.3} |\n", st.overall);
    }
    if let Some(l) = &d.ladder {
        s += &ladder_notes(l);
    }
    s
}

/// What the ladder's table cannot show: the explanations the held-out data fit as well as a
/// step's (its ambiguity group, a body with the mass it would add in the step's place), and
/// each body a step freed, weighed (mass ± standard error, centre of mass in its frame).
fn ladder_notes(l: &super::ladder::Ladder) -> String {
    let mut s = String::new();
    for r in l.rungs.iter().filter(|r| !r.ambiguous_with.is_empty()) {
        let alternatives: Vec<String> = r
            .alternatives()
            .iter()
            .map(|a| format!("`{}`", md_cell(a)))
            .collect();
        s += &format!(
            "\n**Ambiguous**: the data fit {} as well as `{}`.\n",
            alternatives.join(", "),
            md_cell(&r.step)
        );
    }
    for b in &l.bodies {
        let what = if b.payload { "Payload" } else { "Change" };
        s += &format!("\n{what} on `{}`: {}.\n", md_cell(&b.body), b.weighed());
    }
    s
}

/// The "How far" section: validation RMS along the selection, the confirmed-only refit.
fn how_far_section(d: &Diagnosis) -> String {
    let mut s = String::new();
    s += "## How far\n\nValidation RMS per joint (N m; joint-samples slower than the speed threshold left out): the description as given (the sim-to-real gap), the description re-identified on the training data (nominal), then after each effect (cumulative); plot `how_far.svg`.\n\n| joint | description | nominal |";
    for e in &d.effects {
        s += &format!(" + {} |", e.kind.name());
    }
    s += " noise floor | gap closed |\n|---|---|---|";
    s += &"---|".repeat(d.effects.len() + 2);
    s += "\n";
    for g in &d.gap {
        s += &format!(
            "| {} | {:.3} | {:.3} |",
            md_cell(&g.joint),
            g.description,
            g.nominal
        );
        for a in &g.after {
            s += &format!(" {a:.3} |");
        }
        s += &format!(" {:.3} | {:.0} % |\n", g.noise_floor, 100.0 * g.gap_closed);
    }
    s += &format!(
        "| all | {:.3} | {} | {:.3} | {:.0} % |\n",
        d.description_overall,
        d.overall
            .iter()
            .map(|v| format!("{v:.3}"))
            .collect::<Vec<_>>()
            .join(" | "),
        d.noise_floor,
        100.0 * d.gap_closed
    );
    let st = &d.structure_left;
    s += &format!(
        "\nStructure left: a smooth function of each joint's own speed and angle (piecewise linear), fitted on the training residual of the final model, changes its validation mean square by {:+.1} % ({}; t = {:.1} over 10 contiguous validation blocks); {} (counts when at least −{:.1} % with t ≥ 2).\n",
        -100.0 * st.reduction,
        d.joints
            .iter()
            .zip(&st.per_joint)
            .map(|(j, r)| format!("{} {:+.1} %", md_cell(j), -100.0 * r))
            .collect::<Vec<_>>()
            .join(", "),
        st.t,
        if st.remains {
            "**an effect outside the library remains**"
        } else {
            "no structure left"
        },
        100.0 * st.threshold
    );
    if let Some((rms, o)) = &d.confirmed_only {
        s += &format!(
            "\nNot confirmed on the validation data: {}. Refitted with the confirmed effects only, the validation RMS is {o:.3} N m ({}).\n",
            d.effects
                .iter()
                .zip(&d.confirmed)
                .filter(|(_, c)| !**c)
                .map(|(e, _)| format!("`{}`", e.kind.name()))
                .collect::<Vec<_>>()
                .join(", "),
            d.joints
                .iter()
                .zip(rms)
                .map(|(j, r)| format!("{j} {r:.3}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    s
}

/// Writes `report.json`, `report.md`, `where.svg`, `spectrum.svg`, `how_far.svg` and
/// `report.html` (self-contained: the verdict first, the report's tables, the plots inline) into
/// `dir`.
pub fn write(dir: &Path, d: &Diagnosis) -> Result<(), ReportError> {
    std::fs::create_dir_all(dir).map_err(|source| IoError::Fs {
        path: dir.to_path_buf(),
        source,
    })?;
    let json = serde_json::to_string_pretty(&crate::io::versioned("diagnose", d))
        .expect("a diagnosis serializes");
    crate::io::write_atomic(&dir.join("report.json"), json.as_bytes())?;
    crate::io::write_atomic(&dir.join("report.md"), markdown(d).as_bytes())?;
    let plots = draw(d, dir)?;
    for (name, svg) in &plots {
        crate::io::write_atomic(&dir.join(name), svg.as_bytes())?;
    }
    crate::io::write_atomic(&dir.join("report.html"), html(d, &plots).as_bytes())?;
    Ok(())
}

/// The report's plots as `(file name, SVG)`, in the order the HTML report shows them: how far
/// each step takes the gap, where the residual lies, its spectrum (when there is one).
pub fn plots(d: &Diagnosis) -> Result<Vec<(String, String)>, ReportError> {
    draw(d, Path::new(""))
}

/// The residual's RMS per regime kind (the breakdown's order) and joint: the kinds, and per
/// joint its RMS in each.
fn regime_series(d: &Diagnosis) -> (Vec<String>, Vec<(String, Vec<f64>)>) {
    let mut regimes: Vec<String> = vec![];
    for r in &d.breakdown.regimes {
        let short = r.regime.split(" (").next().unwrap_or(&r.regime).to_string();
        if !regimes.contains(&short) {
            regimes.push(short);
        }
    }
    let series: Vec<(String, Vec<f64>)> = d
        .joints
        .iter()
        .map(|j| {
            let v = regimes
                .iter()
                .map(|name| {
                    d.breakdown
                        .regimes
                        .iter()
                        .find(|r| &r.joint == j && r.regime.starts_with(name.as_str()))
                        .map_or(0.0, |r| r.rms)
                })
                .collect();
            (j.clone(), v)
        })
        .collect();
    (regimes, series)
}

/// The validation RMS per joint along the diagnosis: the description, re-identified, after
/// each effect, the confirmed effects' refit, the noise floor.
fn how_far_series(d: &Diagnosis) -> Vec<(String, Vec<f64>)> {
    let mut steps = vec![
        (
            "description as given".to_string(),
            d.gap.iter().map(|g| g.description).collect(),
        ),
        (
            "nominal (re-identified)".to_string(),
            d.gap.iter().map(|g| g.nominal).collect(),
        ),
    ];
    for (i, e) in d.effects.iter().enumerate() {
        steps.push((
            format!("+ {}", e.kind.name()),
            d.gap.iter().map(|g| g.after[i]).collect(),
        ));
    }
    if let Some((rms, _)) = &d.confirmed_only {
        steps.push(("confirmed effects only (refit)".into(), rms.clone()));
    }
    steps.push((
        "noise floor".into(),
        d.gap.iter().map(|g| g.noise_floor).collect(),
    ));
    steps
}

/// [`plots`], errors naming the plot's file in `dir`.
fn draw(d: &Diagnosis, dir: &Path) -> Result<Vec<(String, String)>, ReportError> {
    // Where: RMS per regime kind (rows) and joint (series), regimes in the breakdown's order.
    let (regimes, series) = regime_series(d);
    let short: Vec<String> = regimes
        .iter()
        .map(|r| r.replace("velocity", "vel.").replace("quartile", "q."))
        .collect();
    let where_svg = bars(
        &dir.join("where.svg"),
        "nominal validation residual by motion regime",
        "RMS (N m)",
        &short,
        &series,
    )?;
    let spectrum_svg = spectrum_plot(&dir.join("spectrum.svg"), d)?;
    let steps = how_far_series(d);
    let how_far_svg = bars(
        &dir.join("how_far.svg"),
        "validation RMS per joint: the description, re-identified, after each effect",
        "RMS (N m)",
        &d.joints,
        &steps,
    )?;
    // How far first (the answer), then where the residual lies.
    let plots: Vec<(String, String)> = [
        ("how_far.svg", Some(how_far_svg)),
        ("where.svg", Some(where_svg)),
        ("spectrum.svg", spectrum_svg),
    ]
    .into_iter()
    .filter_map(|(name, svg)| svg.map(|s| (name.to_string(), s)))
    .collect();
    Ok(plots)
}

/// Text escaped for HTML.
fn escape_html(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A self-contained HTML report, in the order a reader wants it: the verdict and summary, the
/// `plots` (file name, SVG text) inline, then each section of the Markdown report (CommonMark
/// with tables) folded under its title. No script, no external resource.
pub fn html(d: &Diagnosis, plots: &[(String, String)]) -> String {
    let verdict = crate::io::serde_name(&d.verdict);
    // The Markdown without its title and summary paragraph, which the page puts first.
    let md = markdown(d);
    let rest = md.splitn(3, "\n\n").nth(2).unwrap_or("");
    let body = folded_sections(rest);
    let figures: String = plots
        .iter()
        .map(|(name, svg)| {
            format!(
                "<figure>{svg}<figcaption>{}</figcaption></figure>\n",
                escape_html(name)
            )
        })
        .collect();
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>Diagnosis of {robot}</title>\n<style>\nbody {{ font-family: sans-serif; max-width: 1150px; margin: 2em auto; padding: 0 1em; color: #222; }}\ntable {{ border-collapse: collapse; font-size: 13px; margin: 0.5em 0 1.5em; }}\nth, td {{ border: 1px solid #ccc; padding: 2px 6px; }}\nth {{ background: #f2f2f2; }}\n.verdict {{ font-size: 1.1em; background: #f6f8fa; border-left: 5px solid #3465a4; padding: 0.6em 1em; }}\nfigure {{ margin: 1em 0; }} svg {{ max-width: 100%; height: auto; }} figcaption {{ color: #555; font-size: 12px; }}\ndetails {{ margin: 0.4em 0; }} summary {{ cursor: pointer; font-weight: bold; font-size: 1.05em; }}\n</style>\n</head>\n<body>\n<h1>Diagnosis of {robot}</h1>\n<p class=\"verdict\">Verdict: <b>{verdict}</b>. {summary}</p>\n<h2>Plots</h2>\n{figures}<h2>Tables</h2>\n{body}</body>\n</html>\n",
        robot = escape_html(&d.robot),
        verdict = escape_html(&verdict),
        summary = escape_html(&d.summary),
    )
}

/// Markdown text with `## ` sections, rendered to HTML with each section folded
/// (`<details>`) under its title.
fn folded_sections(md: &str) -> String {
    let render = |text: &str| {
        let mut out = String::new();
        pulldown_cmark::html::push_html(
            &mut out,
            pulldown_cmark::Parser::new_ext(text, pulldown_cmark::Options::ENABLE_TABLES),
        );
        out
    };
    let mut html = String::new();
    for (k, section) in md.split("\n## ").enumerate() {
        let section = if k == 0 {
            section.strip_prefix("## ").unwrap_or(section)
        } else {
            section
        };
        if section.trim().is_empty() {
            continue;
        }
        let (title, content) = section.split_once('\n').unwrap_or((section, ""));
        html += &format!(
            "<details>\n<summary>{}</summary>\n{}</details>\n",
            escape_html(title.trim()),
            render(content)
        );
    }
    html
}
