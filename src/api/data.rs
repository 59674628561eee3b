//! The data an entry point identifies from: each file's runs in memory, or a large file with
//! q̇ and q̈ (a CSV with `dq`/`ddq` columns, an MCAP with `/physid/processed` samples) streamed
//! from disk (memory independent of its length); parts of files as [`Span`]s; torque errors
//! summed over them.

use super::ApiError;
use crate::ident::{analysis, NormalEquations};
use crate::io::{mcap_stream, samples, DataOptions, LoadedData};
use crate::model::Model;
use crate::trajectory::{SampleSink, Trajectory};
use nalgebra::DVector;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// CSV files with `ddq` columns and MCAP files with processed samples above this size are
/// streamed when no effect terms are asked for; smaller files are read once into memory.
pub const STREAM_ABOVE_BYTES: u64 = 64 << 20;

/// The format of a streamed file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Streamed {
    /// A CSV with `dq` and `ddq` columns ([`samples::stream_csv`]).
    Csv,
    /// An MCAP with `/physid/processed` samples carrying accelerations
    /// ([`mcap_stream::stream_mcap`]).
    Mcap,
}

/// One file of identification data.
pub enum Data {
    /// Loaded and prepared samples.
    Memory(Box<LoadedData>),
    /// A file streamed from disk.
    Stream {
        /// Its format.
        format: Streamed,
        /// The file.
        path: PathBuf,
        /// The robot's joint names, in its order (the columns read).
        joints: Vec<String>,
        /// Its sample count.
        samples: usize,
    },
}

/// Samples `range` (indices of the file as read) of the file `file` of a data set.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Span {
    /// Index of the file in the data set.
    pub file: usize,
    /// Its samples, `[start, end)`.
    pub range: Range<usize>,
}

impl Data {
    /// Opens `paths` (read together): large CSV files with `dq` and `ddq` columns and large
    /// MCAP files with processed samples stream (unless `in_memory`, joints are locked, or a
    /// topic is asked for), the others are loaded and prepared with one cutoff
    /// ([`crate::io::load_all`]).
    pub fn open_all(
        paths: &[&Path],
        model: &Model,
        read: &DataOptions,
        in_memory: bool,
    ) -> Result<Vec<Data>, ApiError> {
        let mut streamed = vec![];
        for path in paths {
            let large = std::fs::metadata(path).is_ok_and(|m| m.len() > STREAM_ABOVE_BYTES);
            let format = if in_memory || !large || !read.prepare.lock.is_empty() {
                None
            } else {
                streamable(path, read)?
            };
            streamed.push(format);
        }
        let loaded_paths: Vec<&Path> = paths
            .iter()
            .zip(&streamed)
            .filter(|(_, s)| s.is_none())
            .map(|(p, _)| *p)
            .collect();
        let mut loaded = crate::io::load_all(&loaded_paths, model, read)?.into_iter();
        let joints: Vec<String> = model.joint_names();
        paths
            .iter()
            .zip(streamed)
            .map(|(path, format)| {
                Ok(match format {
                    Some(format) => {
                        let mut file = Data::Stream {
                            format,
                            path: path.to_path_buf(),
                            joints: joints.clone(),
                            samples: 0,
                        };
                        let counted = file.stream(0..0, &mut |_, _| {})?;
                        if let Data::Stream { samples, .. } = &mut file {
                            *samples = counted;
                        }
                        file
                    }
                    None => Data::Memory(Box::new(
                        loaded
                            .next()
                            .expect("one loaded file per path not streamed"),
                    )),
                })
            })
            .collect()
    }

    /// Passes the samples `r` of a streamed file to `sink` (none for one in memory); returns
    /// its sample count.
    fn stream(&self, r: Range<usize>, sink: &mut SampleSink) -> Result<usize, ApiError> {
        Ok(match self {
            Data::Memory(_) => 0,
            Data::Stream {
                format: Streamed::Csv,
                path,
                joints,
                ..
            } => samples::stream_csv(path, joints, r, sink)?,
            Data::Stream {
                format: Streamed::Mcap,
                path,
                joints,
                ..
            } => mcap_stream::stream_mcap(path, joints, r, sink)?,
        })
    }

    /// Samples in the file as read.
    pub fn len(&self) -> usize {
        match self {
            Data::Memory(d) => d.report.samples_read,
            Data::Stream { samples, .. } => *samples,
        }
    }

    /// Whether the file holds no sample.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The pipeline's report (none for a streamed file).
    pub fn report(&self) -> Option<&crate::prepare::Report> {
        match self {
            Data::Memory(d) => Some(&d.report),
            Data::Stream { .. } => None,
        }
    }

    /// Joints locked by the pipeline (their rows are not fitted).
    pub fn locked(&self, m: &Model) -> Vec<usize> {
        let names = self.report().map_or(&[][..], |r| &r.locked[..]);
        m.bodies()
            .iter()
            .enumerate()
            .filter(|(_, b)| names.contains(&b.joint_name))
            .map(|(j, _)| j)
            .collect()
    }

    /// The runs' trajectories with their samples within `r` (indices into each), uncopied: what
    /// [`Data::pieces`] copies out (none for a streamed file).
    pub fn spans<'a>(
        &'a self,
        r: &'a Range<usize>,
    ) -> impl Iterator<Item = (&'a Trajectory, Range<usize>)> + 'a {
        let runs = match self {
            Data::Memory(d) => &d.runs[..],
            Data::Stream { .. } => &[],
        };
        runs.iter()
            .filter_map(move |run| run.span_within(r).map(|s| (&run.trajectory, s)))
    }

    /// The runs' samples whose index in the file lies in `r` (in memory; none when streamed).
    pub fn pieces(&self, r: &Range<usize>) -> Vec<Trajectory> {
        match self {
            Data::Memory(d) => d
                .runs
                .iter()
                .filter_map(|run| run.within(r))
                .map(|run| run.trajectory)
                .collect(),
            Data::Stream { .. } => vec![],
        }
    }

    /// Samples of `r` that the fit and the scores use.
    pub fn used(&self, r: &Range<usize>) -> usize {
        match self {
            Data::Memory(_) => self.spans(r).map(|(_, s)| s.len()).sum(),
            Data::Stream { .. } => r.len(),
        }
    }

    /// The model's normal equations over the samples `r`, the `excluded` joints' rows left out.
    pub fn normal_equations(
        &self,
        m: &Model,
        r: Range<usize>,
        excluded: &[usize],
    ) -> Result<NormalEquations, ApiError> {
        Ok(match self {
            Data::Memory(_) => {
                let mut ne = NormalEquations::new(m.dof(), m.layout().len)
                    .excluding(excluded)
                    .finish();
                for (t, span) in self.spans(&r) {
                    ne = ne.merged(&NormalEquations::from_trajectory_excluding(
                        m, t, span, excluded,
                    ));
                }
                ne
            }
            Data::Stream { .. } => NormalEquations::from_stream(m, |sink| self.stream(r, sink))?.0,
        })
    }

    /// Passes `(t, Y θ − τ)` (s, N m per joint) of every sample of `r` the fit uses to
    /// `each` (streamed files read again).
    pub fn for_each_residual(
        &self,
        m: &Model,
        theta: &DVector<f64>,
        r: Range<usize>,
        each: &mut dyn FnMut(f64, &[f64]),
    ) -> Result<(), ApiError> {
        match self {
            Data::Memory(_) => {
                for (t, span) in self.spans(&r) {
                    analysis::residual_stream(
                        m,
                        theta,
                        |sink| Ok::<usize, ApiError>(t.stream(span, sink)),
                        each,
                    )?;
                }
            }
            Data::Stream { .. } => {
                analysis::residual_stream(m, theta, |sink| self.stream(r, sink), each)?;
            }
        }
        Ok(())
    }

    /// The squared torque errors of `theta` over the samples `r`.
    pub fn squared_errors(
        &self,
        m: &Model,
        theta: &DVector<f64>,
        r: Range<usize>,
    ) -> Result<SquaredErrors, ApiError> {
        Ok(match self {
            Data::Memory(_) => {
                let mut acc = SquaredErrors::new(m.dof());
                for (t, span) in self.spans(&r) {
                    let (per, _) = analysis::rms_error(m, theta, t, span.clone());
                    acc = acc + SquaredErrors::from_rms(&per, span.len());
                }
                acc
            }
            Data::Stream { .. } => {
                let (per, _) =
                    analysis::rms_error_stream(m, theta, |sink| self.stream(r.clone(), sink))?;
                SquaredErrors::from_rms(&per, r.len())
            }
        })
    }
}

/// The format `path` streams in, if it does: a CSV with `dq` and `ddq` columns, or an MCAP with
/// processed samples carrying accelerations when no topic is asked for.
fn streamable(path: &Path, read: &DataOptions) -> Result<Option<Streamed>, ApiError> {
    let extension = path.extension().and_then(|e| e.to_str());
    Ok(match extension {
        Some("csv") => samples::csv_streamable(path)?.then_some(Streamed::Csv),
        Some("mcap") if read.topic.is_none() => {
            mcap_stream::mcap_streamable(path)?.then_some(Streamed::Mcap)
        }
        _ => None,
    })
}

/// The joints any data file locks (union, in joint order).
pub fn locked_joints(m: &Model, data: &[Data]) -> Vec<usize> {
    let mut out: Vec<usize> = data.iter().flat_map(|d| d.locked(m)).collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// The spans' samples in memory (each file's runs within its range).
pub fn in_memory(data: &[Data], spans: &[Span]) -> Vec<Trajectory> {
    spans
        .iter()
        .flat_map(|s| data[s.file].pieces(&s.range))
        .collect()
}

impl std::ops::Add for SquaredErrors {
    type Output = Self;
    /// Both sums together.
    fn add(mut self, other: SquaredErrors) -> Self {
        for (a, b) in self.sum.iter_mut().zip(&other.sum) {
            *a += b;
        }
        self.samples += other.samples;
        self
    }
}

/// Sums of squared torque errors per joint over several runs (N² m²).
#[derive(Clone, Debug)]
pub struct SquaredErrors {
    sum: Vec<f64>,
    samples: usize,
}

impl SquaredErrors {
    /// Nothing summed yet, for `n` joints.
    pub fn new(n: usize) -> Self {
        Self {
            sum: vec![0.0; n],
            samples: 0,
        }
    }

    /// The sums behind per-joint RMS values `rms` (N m) over `samples` samples.
    pub fn from_rms(rms: &[f64], samples: usize) -> Self {
        Self {
            sum: rms.iter().map(|r| r * r * samples as f64).collect(),
            samples,
        }
    }

    /// Per-joint RMS (N m; `None` for the `locked` joints, whose torque is not fitted) and the
    /// RMS over the other joints.
    pub fn rms(&self, locked: &[usize]) -> Rms {
        let k = self.samples.max(1) as f64;
        let per_joint = (0..self.sum.len())
            .map(|j| (!locked.contains(&j)).then(|| (self.sum[j] / k).sqrt()))
            .collect();
        let fitted: Vec<f64> = (0..self.sum.len())
            .filter(|j| !locked.contains(j))
            .map(|j| self.sum[j])
            .collect();
        let overall = (fitted.iter().sum::<f64>() / (k * fitted.len().max(1) as f64)).sqrt();
        Rms { per_joint, overall }
    }
}

/// RMS torque errors of a fit over some runs.
#[derive(Clone, Debug, PartialEq)]
pub struct Rms {
    /// Per joint (N m; `None` for a locked joint, whose torque is not fitted).
    pub per_joint: Vec<Option<f64>>,
    /// Over the fitted joints (N m).
    pub overall: f64,
}

/// A note or warning about the data or the run, for the user (the binary prints each on
/// standard error as `note: …` or `warning: …`; Python issues warnings).
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Notice {
    /// A warning (the answer may be wrong), or a note (what was done).
    pub warning: bool,
    /// What happened, naming the file.
    pub text: String,
}

impl Notice {
    /// A note: what was done.
    pub fn note(text: impl Into<String>) -> Self {
        Notice {
            warning: false,
            text: text.into(),
        }
    }

    /// A warning: the answer may not be what the user meant.
    pub fn warning(text: impl Into<String>) -> Self {
        Notice {
            warning: true,
            text: text.into(),
        }
    }
}

impl std::fmt::Display for Notice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let level = if self.warning { "warning" } else { "note" };
        write!(f, "{level}: {}", self.text)
    }
}

/// `--cutoff` given to an identification without effect terms where no file has a signal to
/// derive (each logs q̇ and q̈): the filter it sets is applied to nothing, which the user should
/// know. (The diagnosis and effect terms process their columns at the cutoff.)
pub fn unused_cutoff_notice<'a>(
    read: &DataOptions,
    reports: impl IntoIterator<Item = &'a crate::prepare::Report>,
) -> Option<Notice> {
    let cutoff = read.prepare.cutoff?;
    let derives = reports.into_iter().any(|r| r.derived_qd || r.derived_qdd);
    (!derives).then(|| {
        Notice::warning(format!(
            "--cutoff {cutoff} Hz filters nothing: every file logs q̇ and q̈, and the cutoff applies only to what the pipeline derives"
        ))
    })
}

/// `--topic` and `--stamp` (options of bags) given for no bag at all are an error (they cannot
/// mean what the user meant); given with some bags, a warning for each other file.
pub fn bag_option_notices(paths: &[&Path], read: &DataOptions) -> Result<Vec<Notice>, ApiError> {
    if read.topic.is_none() && read.stamp == crate::io::mcap_log::Stamp::Log {
        return Ok(vec![]);
    }
    if let Some(first) = paths
        .first()
        .filter(|_| !paths.iter().any(|p| crate::io::is_bag(p)))
    {
        return Err(ApiError::invalid(
            first,
            "--topic and --stamp apply to MCAP files and rosbag2 directories only, and no data file given is one",
        ));
    }
    Ok(paths
        .iter()
        .filter(|p| !crate::io::is_bag(p))
        .map(|p| {
            Notice::warning(format!(
                "{}: --topic and --stamp apply to MCAP files and rosbag2 directories only",
                p.display()
            ))
        })
        .collect())
}

/// What reading did to one file: joints and messages left out, and the pipeline's changes
/// ([`pipeline_notes`]).
pub fn file_notices(path: &Path, loaded: &LoadedData) -> Vec<Notice> {
    let mut out = vec![];
    if !loaded.ignored_joints.is_empty() {
        out.push(Notice::note(format!(
            "{} has joints the robot does not have, left out: {}",
            path.display(),
            loaded.ignored_joints.join(", ")
        )));
    }
    if loaded.skipped_messages > 0 {
        out.push(Notice::note(format!(
            "{}: {} joint-state messages name none of the robot's joints (another publisher on the topic), skipped",
            path.display(),
            loaded.skipped_messages
        )));
    }
    for line in pipeline_notes(&loaded.report) {
        let text = format!("{}: {line}", path.display());
        out.push(if line.starts_with("joint") {
            Notice::warning(text)
        } else {
            Notice::note(text)
        });
    }
    if let Some(w) = shared_cutoff_warning(&loaded.report) {
        out.push(Notice::warning(format!("{}: {w}", path.display())));
    }
    out
}

/// The shared cutoff above this ratio of the file's own cutoff is worth a warning.
const SHARED_CUTOFF_RATIO: f64 = 1.5;

/// A warning when the cutoff shared with the files read together is well above the one this
/// file's own motion gives: the shared band edge came from another file, and a short file
/// reads its resolution more than its motion (the KUKA run 2's first 3 s read 3.0 Hz, the
/// whole run 0.20 Hz; read together, the cutoff of both went from 2 to 12 Hz).
fn shared_cutoff_warning(r: &crate::prepare::Report) -> Option<String> {
    let (shared, own) = (r.band_edge?, r.own_band_edge?);
    let alone = crate::prepare::motion_cutoff(own, 1.0 / r.period);
    (r.cutoff > SHARED_CUTOFF_RATIO * alone).then(|| {
        format!(
            "its own motion reads a band edge of {own:.3} Hz (alone: a {alone:.3} Hz cutoff), but a file read with it reads {shared:.3} Hz, which sets the cutoff of all to {:.3} Hz: a short file reads its resolution more than its motion (docs/data-pipeline.md); if the files record alike motions, give --cutoff {alone:.1}",
            r.cutoff
        )
    })
}

/// What the pipeline did to one file, one line per kind of change (nothing for clean data
/// with accelerations).
pub fn pipeline_notes(r: &crate::prepare::Report) -> Vec<String> {
    let mut out = vec![];
    if !r.gaps.is_empty() {
        out.push(gap_note(r));
    }
    if r.missing_bridged > 0 {
        out.push(format!(
            "{} missing samples bridged at {} places (the derivatives interpolate across them)",
            r.missing_bridged, r.dropouts_bridged
        ));
    }
    if r.duplicates > 0 {
        out.push(format!("{} duplicated samples dropped", r.duplicates));
    }
    out.extend(time_base_note(r));
    if r.derived_qd || r.derived_qdd {
        out.push(derived_note(r));
    }
    if r.samples_kept < r.samples_read {
        out.push(format!(
            "{} of {} samples used",
            r.samples_kept, r.samples_read
        ));
    }
    out.extend(joint_notes(r));
    out
}

/// The time jumps a file was split at (the first five).
fn gap_note(r: &crate::prepare::Report) -> String {
    let gaps: Vec<String> = r
        .gaps
        .iter()
        .take(5)
        .map(|g| format!("{:+.3} s before sample {}", g.seconds, g.sample))
        .collect();
    format!(
        "split into {} runs at {} time jump{} ({}{}): no signal is differentiated across them",
        r.runs + usize::from(r.dropped_short > 0),
        r.gaps.len(),
        if r.gaps.len() == 1 { "" } else { "s" },
        gaps.join(", "),
        if r.gaps.len() > 5 { ", …" } else { "" }
    )
}

/// How scattered time stamps were placed (nothing for a uniform clock).
fn time_base_note(r: &crate::prepare::Report) -> Option<String> {
    use crate::prepare::TimeBase;
    match r.time_base {
        TimeBase::Uniform => None,
        TimeBase::Stamps => Some(format!("time stamps scatter by {:.1} % of the period (RMS); the samples agree with their stamps, which are used", 100.0 * r.jitter)),
        TimeBase::ClockSlots => Some(format!("time stamps scatter by {:.1} % of the period (RMS); the samples agree with a uniform clock, so each is placed at its clock slot", 100.0 * r.jitter)),
    }
}

/// Which signals were derived, with which filter, and what the filter's settling cost.
fn derived_note(r: &crate::prepare::Report) -> String {
    let what = match (r.derived_qd, r.derived_qdd) {
        (true, true) => "no velocities or accelerations: q̇ and q̈ derived",
        (true, false) => "no velocities: q̇ derived",
        _ => "no accelerations: q̈ derived",
    };
    format!(
        "{what} (central difference, zero-phase {:.3} Hz Butterworth{}); {} samples trimmed at the ends of the runs ({} at each end, the filter's settling){}",
        r.cutoff,
        r.band_edge.map_or(String::new(), |e| format!(", 4 times the motion's band edge {e:.3} Hz over all files read")),
        r.trimmed,
        r.settle_samples,
        if r.dropped_short > 0 { format!(", {} samples of pieces too short to keep", r.dropped_short) } else { String::new() }
    )
}

/// Unmeasured, locked and still joints.
fn joint_notes(r: &crate::prepare::Report) -> Vec<String> {
    let mut out = vec![];
    for j in &r.unmeasured {
        out.push(format!("joint '{j}': its torque is zero in every sample (not measured): locked, its torque is not fitted"));
    }
    let asked: Vec<&str> = r
        .locked
        .iter()
        .filter(|j| !r.unmeasured.contains(j))
        .map(String::as_str)
        .collect();
    if !asked.is_empty() {
        out.push(format!(
            "locked (held at their logged position, torque not fitted): {}",
            asked.join(", ")
        ));
    }
    for j in r.still.iter().filter(|j| !r.locked.contains(j)) {
        out.push(format!("joint '{j}' never moves: its friction cannot be identified from these data (lock it with --lock {j}, or record a motion that moves it)"));
    }
    out
}

/// How data files are read, as a user gives it: the bag options, the pipeline's cutoff and
/// the joints to lock (or the only joints to fit).
#[derive(Clone, Debug, Default)]
pub struct ReadOptions {
    /// The `JointState` topic of an MCAP file or rosbag2 directory (default: physid's
    /// processed signals if the log has them, else `/joint_states`).
    pub topic: Option<String>,
    /// Which time stamps a joint state: the recorder's or the message header's.
    pub stamp: crate::io::mcap_log::Stamp,
    /// Low-pass cutoff (Hz) of the derived signals; default 20 Hz, at most a tenth of the
    /// sample rate.
    pub cutoff: Option<f64>,
    /// Joints held at their logged position (their torque not fitted).
    pub lock: Vec<String>,
    /// Fit only these joints' torques (every other joint locked); not with `lock`.
    pub only: Vec<String>,
    /// Runs held in memory, each read where its label is given as a data file.
    pub memory: std::sync::Arc<[crate::io::MemoryLog]>,
}

impl ReadOptions {
    /// The library's reading options for `model`, checked: joints named exist, `only`
    /// becomes the other joints locked, the cutoff is a positive frequency.
    pub fn resolve(&self, model: &Model) -> Result<DataOptions, ApiError> {
        let joints: Vec<String> = model.joint_names();
        if !self.lock.is_empty() && !self.only.is_empty() {
            return Err(ApiError::Options(
                "--lock and --only: give one of them (--only locks every other joint)".into(),
            ));
        }
        let flag = if self.only.is_empty() { "lock" } else { "only" };
        if let Some(j) = self
            .lock
            .iter()
            .chain(&self.only)
            .find(|j| !joints.contains(j))
        {
            return Err(ApiError::Options(format!(
                "--{flag}: the robot has no joint '{j}' (its joints: {})",
                joints.join(", ")
            )));
        }
        let lock = if self.only.is_empty() {
            self.lock.clone()
        } else {
            joints
                .into_iter()
                .filter(|j| !self.only.contains(j))
                .collect()
        };
        if let Some(c) = self.cutoff.filter(|c| !(c.is_finite() && *c > 0.0)) {
            return Err(ApiError::Options(format!(
                "--cutoff must be a positive frequency in Hz, got {c}"
            )));
        }
        Ok(DataOptions {
            topic: self.topic.clone(),
            stamp: self.stamp,
            prepare: crate::prepare::Options {
                cutoff: self.cutoff,
                lock,
                band_edge: None,
            },
            memory: self.memory.clone(),
        })
    }
}

/// The runs of a command's roles (`("--data", runs)`, `("--validate-data", runs)`, …) are
/// distinct recordings: the same file (or a copy of it) in two places is an error naming both
/// flags, as it would score a fit on its own training data.
pub fn check_distinct_runs(roles: &[(&str, &[PathBuf])]) -> Result<(), ApiError> {
    let files: Vec<(&str, &Path)> = roles
        .iter()
        .flat_map(|(flag, runs)| runs.iter().map(move |p| (*flag, p.as_path())))
        .collect();
    crate::io::check_distinct_recordings(&files)?;
    Ok(())
}
