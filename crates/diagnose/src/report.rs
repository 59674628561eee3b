//! Reports: a diagnosis as one section model (rendered to text, Markdown and HTML), JSON and SVG plots (residual by regime, residual spectrum
//! before and after, validation RMS per joint before and after each effect).

use super::breakdown::Regime;
use super::diagnosis::Diagnosis;
use super::diagnosis::{EffectEstimate, Evidence, Magnitude};
use super::ladder::AlsoFit;
use physid_effect::library::Kind;
use physid_io::document::{escape_html, Block, Document, Section, Table, Text};
use physid_io::plot::{colour, legend_outside, tick, Mark, LEGEND_WIDTH};
use physid_io::IoError;
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

/// Grouped bars ([`physid_io::plot::grouped_bars`]) as SVG; errors name the plot's file `path`.
fn bars(
    path: &Path,
    title: &str,
    ylabel: &str,
    labels: &[String],
    series: &[(String, Vec<f64>)],
) -> Result<String, ReportError> {
    physid_io::plot::grouped_bars(title, ylabel, labels, series).map_err(plot_err(path))
}

/// The extent of the positive points of every spectrum, before and after: the lowest and
/// highest frequency (Hz) and PSD (N² m²/Hz); `None` without a positive point.
fn spectrum_extent(d: &Diagnosis) -> Option<[f64; 4]> {
    let pos = |v: f64| v.is_finite() && v > 0.0;
    let all: Vec<(f64, f64)> = d
        .spectra
        .iter()
        .chain(&d.spectra_after)
        .flat_map(|s| s.frequency.iter().copied().zip(s.psd.iter().copied()))
        .filter(|(f, p)| pos(*f) && pos(*p))
        .collect();
    if all.is_empty() {
        return None;
    }
    Some([
        all.iter().map(|a| a.0).fold(f64::INFINITY, f64::min),
        all.iter().map(|a| a.0).fold(0.0, f64::max),
        all.iter().map(|a| a.1).fold(f64::INFINITY, f64::min),
        all.iter().map(|a| a.1).fold(0.0, f64::max),
    ])
}

/// Residual PSD per joint, before (solid) and after (thin) the selected effects, log-log,
/// written to `path`; returns the SVG (`None`, and no file, without a positive spectrum).
fn spectrum_plot(path: &Path, d: &Diagnosis) -> Result<Option<String>, ReportError> {
    let pos = |v: f64| v.is_finite() && v > 0.0;
    let Some([fmin, fmax, pmin, pmax]) = spectrum_extent(d) else {
        return Ok(None);
    };
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

/// The report as one section model ([`Document`]): the files render all of it (Markdown, HTML),
/// the terminal its condensed view ([`text`]).
pub fn document(d: &Diagnosis) -> Document {
    let mut which = which_section(d);
    untested_blocks(d, &mut which);
    description_blocks(d, &mut which);
    effect_blocks(d, &mut which);
    Document {
        title: format!("Diagnosis of {}", d.robot),
        summary: d.summary.clone(),
        preface: Text::plain(format!(
            "{} joints; {} training and {} validation samples; nominal model: constraint set ",
            d.joints.len(),
            d.samples[0],
            d.samples[1],
        ))
        .code(d.constraints.name())
        .and(format!(
            " (constraints hold: {}).",
            d.nominal_constraints_hold
        )),
        sections: vec![
            where_section(d),
            which,
            from_description_section(d),
            how_far_section(d),
        ],
    }
}

/// The Markdown report.
pub fn markdown(d: &Diagnosis) -> String {
    document(d).markdown()
}

/// The diagnosis as text for a terminal: where, which, from the description, how far, and the
/// summary last.
pub fn text(d: &Diagnosis) -> String {
    document(d).text()
}

/// `text` followed by the names of `kinds` in code type, separated by commas.
fn with_codes<'a>(text: Text, kinds: impl IntoIterator<Item = &'a str>) -> Text {
    let mut t = text;
    for (i, k) in kinds.into_iter().enumerate() {
        if i > 0 {
            t = t.and(", ");
        }
        t = t.code(k);
    }
    t
}

/// The kinds' names.
fn kind_names(kinds: &[Kind]) -> impl Iterator<Item = &'static str> + '_ {
    kinds.iter().map(|k| k.name())
}

/// The "Where" section: the nominal model's validation residual per joint and regime, and its
/// spectrum's peaks (the terminal sees each joint's RMS and worst three regimes).
fn where_section(d: &Diagnosis) -> Section {
    let mut s = Section::new("Where");
    s.detail(Block::Paragraph(
        Text::plain("Validation residual of the nominal model per joint and regime, over all samples (RMS in N m, share of the joint's residual energy; ")
            .emphasis("How far")
            .and(" leaves out joint-samples slower than the speed threshold, so its RMS differs). Plot: ")
            .code("where.svg")
            .and("; spectrum: ")
            .code("spectrum.svg")
            .and("."),
    ));
    s.terminal(Block::Paragraph(Text::plain(
        "Validation residual of the nominal model over all samples (How far below leaves out slow joint-samples): RMS (N m), residual spectrum peak, peak coherence with each signal; then each joint's worst regimes.",
    )));
    s.terminal(Block::Table(joint_residuals(d)));
    s.terminal(Block::Table(regimes(d, Some(3))));
    s.detail(Block::Table(regimes(d, None)));
    let mut peaks = Table::new([
        "joint",
        "PSD peak (Hz)",
        "peak coherence with q, qd, qdd, sin(N q)",
    ]);
    for sp in &d.spectra {
        peaks.row([
            sp.joint.clone(),
            format!("{:.2}", sp.peak_frequency),
            sp.peak_coherence
                .iter()
                .map(|(c, f)| format!("{c:.2} @ {f:.1} Hz"))
                .collect::<Vec<_>>()
                .join(", "),
        ]);
    }
    s.detail(Block::Table(peaks));
    s
}

/// Per joint: the residual's RMS over all samples, its spectrum's peak and its peak coherence
/// with each signal.
fn joint_residuals(d: &Diagnosis) -> Table {
    let mut t = Table::new(["joint", "RMS (N m)", "peak (Hz)", "peak coherence"]);
    for (j, name) in d.joints.iter().enumerate() {
        let sp = &d.spectra[j];
        let coherence = sp
            .signals
            .iter()
            .zip(&sp.peak_coherence)
            .map(|(s, (c, f))| format!("{s} {c:.2} @ {f:.1} Hz"))
            .collect::<Vec<_>>()
            .join(", ");
        t.row([
            name.clone(),
            format!("{:.3}", d.breakdown.rms[j]),
            format!("{:.2}", sp.peak_frequency),
            coherence,
        ]);
    }
    t
}

/// The residual per joint and regime: every row in the breakdown's order, or (with `worst`)
/// each joint's `worst` regimes by RMS.
fn regimes(d: &Diagnosis, worst: Option<usize>) -> Table {
    let mut t = Table::new(["joint", "regime", "samples", "RMS", "share"]);
    let rows: Vec<&Regime> = match worst {
        None => d.breakdown.regimes.iter().collect(),
        Some(n) => d
            .joints
            .iter()
            .flat_map(|joint| {
                let mut rows: Vec<&Regime> = d
                    .breakdown
                    .regimes
                    .iter()
                    .filter(|r| &r.joint == joint && r.samples > 0)
                    .collect();
                rows.sort_by(|a, b| b.rms.total_cmp(&a.rms));
                rows.truncate(n);
                rows
            })
            .collect(),
    };
    for r in rows {
        t.row([
            r.joint.clone(),
            r.regime.clone(),
            r.samples.to_string(),
            format!("{:.3}", r.rms),
            format!("{:.2}", r.share),
        ]);
    }
    t
}

/// The "Which" section: the cross-validated selection, step by step (each candidate's score
/// in the files).
fn which_section(d: &Diagnosis) -> Section {
    let mut s = Section::new("Which");
    s.push(Block::Paragraph(Text::plain(format!(
        "Cross-validated forward selection over {} {} (nominal CV RMS {:.3} N m).",
        d.selection.blocks,
        if d.selection.by_run {
            "training runs, leaving one run out"
        } else {
            "contiguous blocks of the training data"
        },
        d.selection.nominal_cv_rms
    ))));
    for (i, st) in d.selection.steps.iter().enumerate() {
        s.push(Block::Heading(
            Text::plain(format!("Step {}: ", i + 1))
                .code(st.kind.name())
                .and(format!(
                    " (CV RMS {:.3} → {:.3} N m, −{:.1} % mean square)",
                    st.cv_rms_before,
                    st.cv_rms_after,
                    100.0 * st.reduction
                )),
        ));
        if !st.ambiguous_with.is_empty() {
            let t = with_codes(
                Text::default().strong("Ambiguous").and(" with "),
                kind_names(&st.ambiguous_with),
            );
            s.push(Block::Paragraph(t.and(": the data fit them equally well.")));
        }
        if !st.also_fit.is_empty() {
            let t = with_codes(
                Text::plain("Also fit (with more terms): "),
                kind_names(&st.also_fit),
            );
            s.push(Block::Paragraph(t.and(".")));
        }
        s.detail(Block::Table(scores_table(&st.scores)));
    }
    s.push(Block::Paragraph(Text::plain(format!(
        "Stopped: {}.",
        d.selection.stop
    ))));
    s
}

/// Every candidate's score at one step of the selection.
fn scores_table(scores: &[super::select::Score]) -> Table {
    let mut t = Table::new([
        "kind",
        "grid value",
        "CV RMS",
        "reduction",
        "blocks improved",
    ]);
    for sc in scores {
        t.row([
            sc.kind.name().to_string(),
            sc.param.to_string(),
            format!("{:.4}", sc.cv_rms),
            format!("{:.1} %", 100.0 * sc.reduction),
            sc.blocks_improved.to_string(),
        ]);
    }
    t
}

/// The joints whose backlash was not tested, and why.
fn untested_blocks(d: &Diagnosis, s: &mut Section) {
    if !d.backlash_untested.is_empty() {
        s.push(Block::Paragraph(
            format!(
                "Backlash was not tested on {}: without a rotor, their torque is within its \
                 noise of zero on most samples, so the log cannot tell the side of a dead zone \
                 from that noise.",
                d.backlash_untested.join(", ")
            )
            .into(),
        ));
    }
}

/// The test against the description, when it ran (each candidate's statistic in the files),
/// or why it did not.
fn description_blocks(d: &Diagnosis, s: &mut Section) {
    let title = "Absorbed effects: the test against the description";
    if let Some(why) = &d.description_test_skipped {
        s.push(Block::Heading(title.into()));
        s.push(Block::Paragraph(format!("The test was {why}.").into()));
    }
    let Some(t) = &d.description_test else {
        return;
    };
    s.push(Block::Heading(
        format!(
            "{title} (stated uncertainty {:.0} %)",
            100.0 * t.uncertainty
        )
        .into(),
    ));
    s.push(Block::Paragraph(
        format!(
            "Residual mean square {:.4} N² m², correlation time {:.1} samples.",
            t.residual_ms, t.correlation_samples
        )
        .into(),
    ));
    for (i, st) in t.steps.iter().enumerate() {
        let mut line = Text::plain(format!("Step {}: ", i + 1))
            .code(st.kind.name())
            .and(format!(
                " (Δ = {:.1} > χ² threshold {:.1}",
                st.statistic, st.threshold
            ));
        if let Some(held_out) = st.held_out {
            line = line.and(format!("; on the held-out data Δ = {held_out:.1}"));
        }
        line = line.and(")");
        if !st.ambiguous_with.is_empty() {
            line = with_codes(
                line.and("; ").strong("ambiguous").and(" with "),
                kind_names(&st.ambiguous_with),
            );
        }
        s.push(Block::Paragraph(line));
        let mut tests = Table::new(["kind", "Δ", "threshold", "columns", "visible"]);
        for x in &st.tests {
            tests.row([
                x.kind.name().to_string(),
                format!("{:.1}", x.statistic),
                format!("{:.1}", x.threshold),
                x.columns.to_string(),
                format!("{:.3}", x.visible),
            ]);
        }
        s.detail(Block::Table(tests));
    }
    s.push(Block::Paragraph(format!("Stopped: {}.", t.stop).into()));
}

/// Each effect found, with its magnitudes.
fn effect_blocks(d: &Diagnosis, s: &mut Section) {
    for e in &d.effects {
        let found = match e.evidence {
            Evidence::CrossValidation => e.magnitude_name.clone(),
            Evidence::Description => {
                format!("{} (found against the description)", e.magnitude_name)
            }
        };
        let at = grid_point(e);
        s.push(Block::Heading(
            Text::default()
                .code(e.kind.name())
                .and(format!("{at}: {found}")),
        ));
        s.push(Block::Table(magnitude_table(e, true)));
        let hidden = e.magnitudes.iter().filter(|m| !m.is_identifiable());
        let hidden: Vec<&str> = hidden.map(|m| m.joint.as_str()).collect();
        if !hidden.is_empty() {
            s.push(Block::Paragraph(Text::plain(format!(
                "Not identifiable (identifiable below {}: absorbed by the inertial parameters): {}.",
                super::diagnosis::IDENTIFIABLE,
                hidden.join(", ")
            ))));
        }
        if let Some(sep) = &e.separate_by {
            s.push(Block::Paragraph(format!("To separate them: {sep}.").into()));
        }
    }
}

/// ` at <param>` for an effect with a grid value (a Stribeck velocity, a cogging harmonic),
/// else nothing.
fn grid_point(e: &EffectEstimate) -> String {
    if e.param != 0.0 {
        format!(" at {}", e.param)
    } else {
        String::new()
    }
}

/// An effect's magnitudes: joint, value, standard error, unit (and the identifiable fraction).
fn magnitude_table(e: &EffectEstimate, identifiable: bool) -> Table {
    let mut header = vec!["joint", "value", "std. error", "unit"];
    if identifiable {
        header.push("identifiable");
    }
    let mut t = Table::new(header);
    for m in &e.magnitudes {
        let mut row = vec![
            m.joint.clone(),
            format!("{:.4e}", m.value),
            format!("{:.1e}", m.se),
            m.unit.clone(),
        ];
        if identifiable {
            row.push(format!("{:.2}", m.identifiable));
        }
        t.row(row);
    }
    t
}

/// The ladder's effects (payloads are weighed in its notes) with their magnitudes from the
/// description, and the joints whose value is within two standard errors of zero.
fn described_effect_blocks(d: &Diagnosis, s: &mut Section) {
    for e in d
        .described_effects
        .iter()
        .filter(|e| !e.kind.is_body_change())
    {
        let at = grid_point(e);
        s.push(Block::Heading(Text::default().code(e.kind.name()).and(
            format!("{at} from the description: {}", e.magnitude_name),
        )));
        s.push(Block::Table(magnitude_table(e, false)));
        if let Some(after) = &e.after_later_steps {
            s.push(Block::Paragraph(Text::plain(traded_off(after))));
        }
        let near_zero: Vec<&str> = (e.magnitudes.iter())
            .filter(|m| m.value.abs() < 2.0 * m.se || m.se == 0.0 && m.value == 0.0)
            .map(|m| m.joint.as_str())
            .collect();
        if !near_zero.is_empty() {
            s.push(Block::Paragraph(Text::plain(format!(
                "Within two standard errors of zero (not determined by these data, or absent): {}.",
                near_zero.join(", ")
            ))));
        }
    }
}

/// What the steps after an explanation made of its magnitudes `after` (with every explanation
/// free), stated beside its own step's.
fn traded_off(after: &[Magnitude]) -> String {
    let values: Vec<String> = after
        .iter()
        .map(|m| format!("{} {:.4e} ± {:.1e}", m.joint, m.value, m.se))
        .collect();
    format!(
        "As weighed at its step; later steps trade off with it (with them free: {}).",
        values.join(", ")
    )
}

/// The "From the description" section: the description's gap explained step by step, with
/// the ladder's ambiguity groups and weighed bodies.
fn from_description_section(d: &Diagnosis) -> Section {
    let mut s = Section::new("From the description");
    s.push(Block::Paragraph("The sim-to-real gap itself: validation RMS per joint (N m; joint-samples slower than the speed threshold left out) of the description as given, then with each explanation freed while the description's inertial parameters stay pinned (the one that lowers the training residual most first), then with the inertial parameters re-identified too.".into()));
    let header = std::iter::once("step".to_string())
        .chain(d.joints.iter().cloned())
        .chain(std::iter::once("all".to_string()));
    let mut t = Table::new(header);
    let row = |step: &str, rms: &mut dyn Iterator<Item = f64>, all: f64| {
        std::iter::once(step.to_string())
            .chain(rms.map(|r| format!("{r:.3}")))
            .chain(std::iter::once(format!("{all:.3}")))
            .collect::<Vec<_>>()
    };
    t.row(row(
        "description as given",
        &mut d.gap.iter().map(|g| g.description),
        d.description_overall,
    ));
    for st in &d.explained_from_description {
        t.row(row(&st.step, &mut st.rms.iter().copied(), st.overall));
    }
    s.push(Block::Table(t));
    if let Some(l) = &d.ladder {
        ladder_notes(l, &mut s);
    }
    described_effect_blocks(d, &mut s);
    s
}

/// What the ladder's table cannot show: the explanations the held-out data fit as well as a
/// step's (its ambiguity group, a body with the mass it would add in the step's place), and
/// each body a step freed, weighed (mass ± standard error, centre of mass in its frame).
fn ladder_notes(l: &super::ladder::Ladder, s: &mut Section) {
    for r in l.rungs.iter().filter(|r| !r.ambiguous_with.is_empty()) {
        let alternatives = r.alternatives();
        let t = with_codes(
            Text::default().strong("Ambiguous").and(": the data fit "),
            alternatives.iter().map(String::as_str),
        );
        s.push(Block::Paragraph(
            t.and(" as well as ").code(&r.step).and("."),
        ));
    }
    for r in l.rungs.iter().filter(|r| !r.also_fit.is_empty()) {
        let mut t = Text::default()
            .strong("Also fit")
            .and(" (set aside for ")
            .code(&r.step)
            .and(format!(
                ", which takes {:.1} % of the held-out mean square): ",
                100.0 * r.reduction
            ));
        for (i, a) in r.also_fit.iter().enumerate() {
            t = if i > 0 { t.and(", ") } else { t };
            t = t.code(&a.name).and(format!(" {}", a.detail()));
        }
        s.push(Block::Paragraph(t.and(".")));
    }
    let steps = l
        .rungs
        .iter()
        .map(|r| (Some(r.step.as_str()), &r.unweighed));
    for (step, unweighed) in steps.chain([(None, &l.unweighed)]) {
        if !unweighed.is_empty() {
            s.push(Block::Paragraph(not_weighed(step, unweighed)));
        }
    }
    for b in &l.bodies {
        let what = if b.payload { "Payload" } else { "Change" };
        s.push(Block::Paragraph(
            Text::plain(format!("{what} on "))
                .code(&b.body)
                .and(format!(": {}.", b.weighed())),
        ));
    }
}

/// The body changes a step (`None`: the ladder's stop) did not claim because the data do not
/// weigh their mass.
fn not_weighed(step: Option<&str>, unweighed: &[AlsoFit]) -> Text {
    let mut t = Text::default().strong("Not claimed").and(": ");
    for (i, a) in unweighed.iter().enumerate() {
        t = if i > 0 { t.and(", ") } else { t };
        t = t
            .code(&a.name)
            .and(format!(" ({:.1} %)", 100.0 * a.reduction));
    }
    t = t.and(" would lower the held-out mean square significantly");
    t = match step {
        Some(step) => t.and(" in the place of ").code(step),
        None => t.and(" where the ladder stopped"),
    };
    t.and(", but these data do not weigh the mass: they see only its first moment m c, which the description's own error, carried to a motion it was not identified on, changes as well. Record a motion that weighs it (faster, over a wider range of the joints between the body and the base), or diagnose against a baseline run of the same motion (--baseline-data).")
}

/// The "How far" section: validation RMS along the selection, the structure left, the
/// confirmed-only refit.
fn how_far_section(d: &Diagnosis) -> Section {
    let mut s = Section::new("How far");
    s.push(Block::Paragraph(Text::plain("Validation RMS per joint (N m; joint-samples slower than the speed threshold left out): the description as given (the sim-to-real gap), the description re-identified on the training data (nominal), then after each effect (cumulative); plot ").code("how_far.svg").and(".")));
    s.push(Block::Table(how_far_table(d)));
    s.push(Block::Paragraph(structure_left(d)));
    if let Some((rms, o)) = &d.confirmed_only {
        let unconfirmed = d
            .effects
            .iter()
            .zip(&d.confirmed)
            .filter(|(_, c)| !**c)
            .map(|(e, _)| e.kind.name());
        let per_joint: Vec<String> = d
            .joints
            .iter()
            .zip(rms)
            .map(|(j, r)| format!("{j} {r:.3}"))
            .collect();
        let t = with_codes(
            Text::plain("Not confirmed on the validation data: "),
            unconfirmed,
        );
        s.push(Block::Paragraph(t.and(format!(
            ". Refitted with the confirmed effects only, the validation RMS is {o:.3} N m ({}).",
            per_joint.join(", ")
        ))));
    }
    s
}

/// Per joint: the description, nominal, after each effect, noise floor, gap closed; then all.
fn how_far_table(d: &Diagnosis) -> Table {
    let header = ["joint", "description", "nominal"]
        .into_iter()
        .map(String::from)
        .chain(
            d.how_far_effects()
                .iter()
                .map(|e| format!("+ {}", e.kind.name())),
        )
        .chain(["noise floor".to_string(), "gap closed".to_string()]);
    let mut t = Table::new(header);
    let f3 = |v: &f64| format!("{v:.3}");
    for g in &d.gap {
        let cells = [g.joint.clone(), f3(&g.description), f3(&g.nominal)]
            .into_iter()
            .chain(g.after.iter().map(f3))
            .chain([f3(&g.noise_floor), format!("{:.0} %", 100.0 * g.gap_closed)]);
        t.row(cells);
    }
    let all = ["all".to_string(), f3(&d.description_overall)]
        .into_iter()
        .chain(d.overall.iter().map(f3))
        .chain([f3(&d.noise_floor), format!("{:.0} %", 100.0 * d.gap_closed)]);
    t.row(all);
    t
}

/// The structure left after the final model, in a sentence.
fn structure_left(d: &Diagnosis) -> Text {
    let st = &d.structure_left;
    let per_joint: Vec<String> = d
        .joints
        .iter()
        .zip(&st.per_joint)
        .map(|(j, r)| format!("{j} {:+.1} %", -100.0 * r))
        .collect();
    let t = Text::plain(format!(
        "Structure left: a smooth function of each joint's own speed and angle (piecewise linear), fitted on the training residual of the final model, changes its validation mean square by {:+.1} % ({}; t = {:.1} over 10 contiguous validation blocks); ",
        -100.0 * st.reduction,
        per_joint.join(", "),
        st.t,
    ));
    let t = if st.remains {
        t.strong("an effect outside the library remains")
    } else {
        t.and("no structure left")
    };
    t.and(format!(
        " (counts when at least −{:.1} % with t ≥ 2).",
        100.0 * st.threshold
    ))
}

/// Writes `report.json`, `report.md`, `where.svg`, `spectrum.svg`, `how_far.svg` and
/// `report.html` (self-contained: the verdict first, the report's tables, the plots inline) into
/// `dir`.
/// `dir` is replaced whole once every file is written (an earlier report, or an empty or new
/// folder in an existing one: [`physid_io::check_result_target`]).
pub fn write(dir: &Path, d: &Diagnosis) -> Result<(), ReportError> {
    physid_io::check_result_target(dir, REPORT_MARK)?;
    physid_io::write_result_dir(dir, REPORT_MARK, |staged| write_files(staged, d))
}

/// The file that marks a report folder.
pub const REPORT_MARK: &str = "report.json";

/// The report's files written into `dir`.
fn write_files(dir: &Path, d: &Diagnosis) -> Result<(), ReportError> {
    let json = serde_json::to_string_pretty(&physid_io::versioned("diagnose", d))
        .expect("a diagnosis serializes");
    physid_io::write_atomic(&dir.join("report.json"), json.as_bytes())?;
    physid_io::write_atomic(&dir.join("report.md"), markdown(d).as_bytes())?;
    let plots = draw(d, dir)?;
    for (name, svg) in &plots {
        physid_io::write_atomic(&dir.join(name), svg.as_bytes())?;
    }
    physid_io::write_atomic(&dir.join("report.html"), html(d, &plots).as_bytes())?;
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
    for (i, e) in d.how_far_effects().iter().enumerate() {
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

/// The report's style, every rule scoped to the report's own `div.physid-report` so that the
/// report embedded in a page (a notebook's output) restyles nothing around it.
const REPORT_CSS: &str = ".physid-report { font-family: sans-serif; color: #222; }
.physid-report table { border-collapse: collapse; font-size: 13px; margin: 0.5em 0 1.5em; }
.physid-report th, .physid-report td { border: 1px solid #ccc; padding: 2px 6px; }
.physid-report th { background: #f2f2f2; }
.physid-report .verdict { font-size: 1.1em; background: #f6f8fa; border-left: 5px solid #3465a4; padding: 0.6em 1em; }
.physid-report figure { margin: 1em 0; } .physid-report svg { max-width: 100%; height: auto; } .physid-report figcaption { color: #555; font-size: 12px; }
.physid-report details { margin: 0.4em 0; } .physid-report summary { cursor: pointer; font-weight: bold; font-size: 1.05em; }
";

/// The report as one `div.physid-report` with its own scoped style and the plots inline (SVG):
/// what a notebook shows, and the body of [`html`]'s page.
pub fn html_fragment(d: &Diagnosis, plots: &[(String, String)]) -> String {
    fragment(d, &document(d), plots)
}

/// [`html_fragment`] of the report's document `doc`.
fn fragment(d: &Diagnosis, doc: &Document, plots: &[(String, String)]) -> String {
    let verdict = physid_io::serde_name(&d.verdict);
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
        "<div class=\"physid-report\">\n<style>\n{REPORT_CSS}</style>\n<h1>{title}</h1>\n<p class=\"verdict\">Verdict: <b>{verdict}</b>. {summary}</p>\n<p>{preface}</p>\n<h2>Plots</h2>\n{figures}<h2>Tables</h2>\n{body}</div>\n",
        title = escape_html(&doc.title),
        verdict = escape_html(&verdict),
        summary = escape_html(&d.summary),
        preface = doc.preface.to_html(),
        body = doc.html_sections(),
    )
}

/// A self-contained HTML report, in the order a reader wants it: the verdict and summary, the
/// `plots` (file name, SVG text) inline, then each section of the report folded under its
/// title. No script, no external resource.
pub fn html(d: &Diagnosis, plots: &[(String, String)]) -> String {
    let doc = document(d);
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{title}</title>\n<style>\nbody {{ max-width: 1150px; margin: 2em auto; padding: 0 1em; }}\n</style>\n</head>\n<body>\n{report}</body>\n</html>\n",
        title = escape_html(&doc.title),
        report = fragment(d, &doc, plots),
    )
}
