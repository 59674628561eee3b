//! The data pipeline: from joint samples as a robot logs them to the runs that identification
//! and the diagnosis fit and score.
//!
//! Real logs are not the uniform, gap-free, complete signals a simulator writes. This module
//! takes what a reader found ([`Logged`]: time stamps as written, velocities and accelerations
//! only where logged) and, in one place for every command:
//!
//! 1. **splits runs** where the time stamps jump (a dropout longer than the derivative filter
//!    can bridge, a restart that sends time back): each piece is its own run, never
//!    differentiated across;
//! 2. **bridges dropped samples** (a step of a few periods): the derivatives are computed on the
//!    uniform grid with the missing slots interpolated, and only the logged samples are kept;
//! 3. **reads jittered stamps**: a run's stamps are fitted to a uniform clock; when they scatter
//!    about it, the samples are taken either at their stamps or at their clock slots, whichever
//!    the data themselves say (the logged velocity, or the position's smoothness);
//! 4. **derives** q̇ (when not logged) and q̈ (when not logged): central difference on the
//!    uniform grid, zero-phase 2nd-order Butterworth at the cutoff;
//! 5. **trims the ends** of each run by the filter's settling length, where one-sided
//!    differences and padding leave the derived signals wrong, so no fit or score sees them;
//! 6. **holds locked joints** at their logged position (q̇ = q̈ = 0), and names joints that
//!    never move or whose torque is never measured.
//!
//! Every sample dropped, bridged or trimmed is counted in the [`Report`].
//!
//! Floor 2 (architecture.md §6): imports `trajectory` and `signal`.

use physid_core::signal::{butterworth_lowpass, differentiate, FilterError, Sos};
use physid_core::trajectory::{check_value, Margins, SampleError, Trajectory};
use serde::Serialize;

/// Joint samples as read from a log, before the pipeline: time stamps as written (not yet
/// checked for gaps or order), velocities and accelerations only where the log has them.
/// Arrays are sample-major (`q[k * n + j]`); units as in [`Trajectory`].
#[derive(Clone, Debug, PartialEq)]
pub struct Logged {
    /// Joint names (length `n`).
    pub joint_names: Vec<String>,
    /// Time stamps (s) as written.
    pub t: Vec<f64>,
    /// Positions (rad or m).
    pub q: Vec<f64>,
    /// Velocities (rad/s), if logged.
    pub qd: Option<Vec<f64>>,
    /// Accelerations (rad/s²), if logged.
    pub qdd: Option<Vec<f64>>,
    /// Joint torques (N m or N).
    pub tau: Vec<f64>,
}

impl Logged {
    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.joint_names.len()
    }
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }
    /// No samples.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Lengths consistent, every value finite and within [`physid_core::trajectory::max_abs`]; the
    /// time stamps' order is the pipeline's to judge.
    pub fn validate(&self) -> Result<(), SampleError> {
        let (m, n) = (self.len(), self.dof());
        if m == 0 {
            return Err(SampleError::Empty);
        }
        let groups = [
            ("q", Some(&self.q)),
            ("dq", self.qd.as_ref()),
            ("ddq", self.qdd.as_ref()),
            ("tau", Some(&self.tau)),
        ];
        for (name, v) in groups {
            if let Some(v) = v.filter(|v| v.len() != m * n) {
                return Err(SampleError::Length {
                    field: name,
                    got: v.len(),
                    expected: m * n,
                });
            }
        }
        for k in 0..m {
            let t = self.t[k];
            check_value(k, t, "t", "t", t)?;
            for (name, v) in groups {
                let Some(v) = v else { continue };
                let limit = physid_core::trajectory::max_abs(name).0;
                for j in 0..n {
                    let x = v[k * n + j];
                    // The field's name is only written out for a value that fails.
                    if !(x.is_finite() && x.abs() <= limit) {
                        check_value(k, t, name, &format!("{name}{}", j + 1), x)?;
                    }
                }
            }
        }
        Ok(())
    }

    /// The same samples with the joints in the order of `names` (each must be present; `Err`
    /// names the first that is not); joints not named are dropped.
    pub fn with_joints(&self, names: &[String]) -> Result<Logged, String> {
        let columns: Vec<usize> = names
            .iter()
            .map(|n| {
                self.joint_names
                    .iter()
                    .position(|x| x == n)
                    .ok_or_else(|| n.clone())
            })
            .collect::<Result<_, _>>()?;
        let (n, m) = (self.dof(), self.len());
        let pick = |v: &Vec<f64>| -> Vec<f64> {
            (0..m)
                .flat_map(|k| columns.iter().map(move |&j| v[k * n + j]))
                .collect()
        };
        Ok(Logged {
            joint_names: names.to_vec(),
            t: self.t.clone(),
            q: pick(&self.q),
            qd: self.qd.as_ref().map(pick),
            qdd: self.qdd.as_ref().map(pick),
            tau: pick(&self.tau),
        })
    }
}

impl From<Trajectory> for Logged {
    fn from(tr: Trajectory) -> Self {
        Logged {
            joint_names: tr.joint_names,
            t: tr.t,
            q: tr.q,
            qd: Some(tr.qd),
            qdd: tr.qdd,
            tau: tr.tau,
        }
    }
}

/// How the pipeline treats the samples.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Options {
    /// Low-pass cutoff (Hz) of the derived signals; `None`: chosen from the data when a signal
    /// is derived ([`motion_cutoff`]), else [`default_cutoff`] of the rate.
    pub cutoff: Option<f64>,
    /// Joints held at their logged position (q̇ = q̈ = 0): their torque is not fitted.
    pub lock: Vec<String>,
    /// The motion's band edge (Hz) the cutoff is chosen from when `cutoff` is `None`; `None`:
    /// this log's own (the highest of [`band_edges`] gives several logs one).
    pub band_edge: Option<f64>,
}

/// The derived signals' default cutoff (Hz) at sample rate `rate` (Hz): 20 Hz (above a robot
/// arm's excitation, below its structural modes), at most a tenth of the rate.
pub fn default_cutoff(rate: f64) -> f64 {
    20.0f64.min(0.1 * rate)
}

/// The lowest cutoff chosen from the data (Hz): below it the filter's settling eats seconds
/// of every run.
pub const MIN_DATA_CUTOFF: f64 = 2.0;

/// The chosen cutoff over the motion's band edge: the zero-phase 2nd-order Butterworth then
/// passes the band edge's acceleration within 0.4 % (`1/(1 + 4⁻⁴)`).
const CUTOFF_OVER_BAND: f64 = 4.0;

/// Spectral power over the noise floor that still counts as motion (30 dB).
const MOTION_OVER_NOISE: f64 = 1e3;

/// The highest cutoff accepted, as a fraction of the sample rate: above it a 2nd-order
/// Butterworth hardly filters and its bilinear design degenerates near Nyquist.
pub const MAX_CUTOFF_FRACTION: f64 = 0.4;

/// Names joined by commas, or "none".
fn list_or_none(names: &[String]) -> String {
    if names.is_empty() {
        "none".into()
    } else {
        names.join(", ")
    }
}

/// The lowest cutoff accepted, as a fraction of the sample rate (0.01 Hz at 100 Hz): the
/// filter then settles over about 10⁵ samples.
pub const MIN_CUTOFF_FRACTION: f64 = 1e-4;

/// Relative tolerance at which the derived signals' start-up transient counts as settled.
const SETTLED: f64 = 1e-3;

/// How far the tracked clock's phase moves toward each stamp ([`Clock::fit`]).
const PHASE_GAIN: f64 = 0.05;

/// The slowest joint-state log physid reads (Hz): a slower one is a time unit misread (stamps in
/// milliseconds at 1 kHz read as one sample a second).
pub const MIN_RATE: f64 = 5.0;

/// The fastest joint-state log physid reads (Hz).
pub const MAX_RATE: f64 = 1e5;

/// What stamps with median period `period` (as read, "s") most likely are.
fn unit_guess(period: f64) -> &'static str {
    match period {
        p if p > 1e5 => "stamps in nanoseconds? (divide t by 1e9)",
        p if p > 1e2 => "stamps in microseconds? (divide t by 1e6)",
        p if p > 0.2 => "stamps in milliseconds? (divide t by 1e3)",
        _ => "stamps in minutes or hours? (multiply t to seconds)",
    }
}

/// Stamps within this fraction of a period (RMS) of a uniform clock count as uniform.
const UNIFORM_JITTER: f64 = 0.01;

/// Above this RMS scatter about the clock (fraction of a period) the stamps cannot be read.
const MAX_JITTER: f64 = 0.3;

/// A jump back in time by more than this many periods is a restart (a new run); less is an
/// error (stamps out of order).
pub const RESTART_PERIODS: f64 = 100.0;

/// Samples that may be missing in a row and still be bridged: a tenth of the cutoff's period,
/// at least one.
fn max_bridged(rate: f64, cutoff: f64) -> usize {
    ((0.1 * rate / cutoff).floor() as usize).max(1)
}

/// Why the samples cannot be prepared.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PrepareError {
    /// A bad sample value (the sample is named).
    #[error(transparent)]
    Sample(#[from] SampleError),
    /// Fewer than two distinct time stamps.
    #[error(
        "{0} samples with distinct time stamps: at least 2 are needed to know the sample rate"
    )]
    NoRate(usize),
    /// A median sample period no robot's joint-state log has: stamps in another unit.
    #[error("the median sample period is {period:.4} s ({:.3e} Hz), where joint states are logged at {MIN_RATE} Hz to {MAX_RATE} Hz: {}; physid reads t in seconds", 1.0 / period, unit_guess(*period))]
    TimeUnit {
        /// The median period as read (s).
        period: f64,
    },
    /// The cutoff is not a usable low-pass at this rate.
    #[error("cutoff {} Hz: the data are sampled at {rate:.4} Hz, so the cutoff must be at least {min:.4e} Hz ({MIN_CUTOFF_FRACTION:e} of the rate: below, the filter settles over more samples than a log holds and its coefficients lose their precision) and at most {max:.4} Hz ({MAX_CUTOFF_FRACTION} of the rate)", physid_core::options::readable(*cutoff), min = MIN_CUTOFF_FRACTION * rate)]
    Cutoff {
        /// The cutoff asked for (Hz).
        cutoff: f64,
        /// The data's sample rate (Hz).
        rate: f64,
        /// The largest cutoff accepted (Hz).
        max: f64,
    },
    /// The filter could not be built.
    #[error(transparent)]
    Filter(#[from] FilterError),
    /// A joint to lock that the data do not have.
    #[error("--lock/--only: the data have no joint '{joint}' (they have {have})")]
    UnknownJoint {
        /// The name given.
        joint: String,
        /// The data's joints.
        have: String,
    },
    /// Every joint locked (asked, or its torque never measured): nothing left to fit.
    #[error("every joint is held still: locked as asked ({}) or with a torque column of zeros only ({}); nothing is left to identify or diagnose", list_or_none(asked), list_or_none(unmeasured))]
    AllLocked {
        /// Joints locked as asked (`--lock`, or outside `--only`).
        asked: Vec<String>,
        /// Joints whose logged torque is zero throughout.
        unmeasured: Vec<String>,
    },
    /// Stamps too irregular to read as a sampled signal.
    #[error("run starting at sample {start}: the time stamps scatter by {jitter:.0} % of the median period {period:e} s (RMS, about the best uniform clock): too irregular to differentiate; give header stamps (--stamp header) if the log has them, or resample the data")]
    Irregular {
        /// The run's first sample (index in the log).
        start: usize,
        /// RMS scatter about the clock, percent of the period.
        jitter: f64,
        /// The median period (s).
        period: f64,
    },
    /// Time goes back by less than a restart's jump (out-of-order or corrupt stamps).
    #[error("sample {sample}: time {t} s does not increase (previous {previous} s); only a jump back by more than {RESTART_PERIODS} sample periods is read as a restart (a new run)")]
    NotIncreasing {
        /// The sample (index in the log).
        sample: usize,
        /// Its time (s).
        t: f64,
        /// The previous sample's time (s).
        previous: f64,
    },
    /// Nothing left after splitting and trimming.
    #[error("no run is longer than the {settle} samples trimmed at each end (the derived signals' settling length at {cutoff} Hz): the longest piece between gaps has {longest} samples")]
    NothingLeft {
        /// Samples trimmed at each end of a run.
        settle: usize,
        /// The cutoff (Hz).
        cutoff: f64,
        /// The longest piece's sample count.
        longest: usize,
    },
}

/// One run after the pipeline: samples with q̇ and q̈, each mapped to its index in the log.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    /// The samples.
    pub trajectory: Trajectory,
    /// For each sample, its index in the log as read (0-based).
    pub index: Vec<usize>,
}

impl Run {
    /// The samples whose log index lies in `range`, as a run (`None` if there are none).
    pub fn within(&self, range: &std::ops::Range<usize>) -> Option<Run> {
        self.span_within(range).map(|s| Run {
            trajectory: self.trajectory.slice(s.clone()),
            index: self.index[s].to_vec(),
        })
    }

    /// The samples of this run (indices into its trajectory) whose log samples lie in `range`,
    /// if any: what [`Run::within`] copies, without the copy.
    pub fn span_within(&self, range: &std::ops::Range<usize>) -> Option<std::ops::Range<usize>> {
        let a = self.index.partition_point(|&i| i < range.start);
        let b = self.index.partition_point(|&i| i < range.end);
        (a < b).then_some(a..b)
    }
}

/// A jump in the time stamps where a run ends and the next begins.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct Gap {
    /// The first sample after the jump (index in the log).
    pub sample: usize,
    /// The jump (s): positive for a dropout, negative for time going back (a restart).
    pub seconds: f64,
}

/// How the samples' times were read.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum TimeBase {
    /// The stamps fit a uniform clock (within 1 % of a period, RMS).
    Uniform,
    /// Jittered stamps, taken as the sampling times (the data agree better with them).
    Stamps,
    /// Jittered stamps, the samples taken at their uniform clock's slots (the data agree
    /// better with those: the jitter was in the stamping, not in the sampling).
    ClockSlots,
}

/// What the pipeline did, every sample counted.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize, schemars::JsonSchema)]
#[schemars(rename = "DataPipeline")]
pub struct Report {
    /// Samples in the log.
    pub samples_read: usize,
    /// Samples in the runs (read − duplicates − trimmed − dropped with short pieces).
    pub samples_kept: usize,
    /// Runs after splitting at gaps.
    pub runs: usize,
    /// Where runs were split.
    pub gaps: Vec<Gap>,
    /// Samples that repeated the previous one's time stamp and values (dropped).
    pub duplicates: usize,
    /// Missing samples bridged inside runs (steps of a few periods), and in how many places.
    pub missing_bridged: usize,
    /// Steps that bridged missing samples.
    pub dropouts_bridged: usize,
    /// Samples trimmed at the ends of runs (the derived signals' settling).
    pub trimmed: usize,
    /// Samples of pieces shorter than twice the settling length (dropped whole).
    pub dropped_short: usize,
    /// Median sample period (s).
    pub period: f64,
    /// RMS scatter of the stamps about a uniform clock, in periods (largest over runs).
    pub jitter: f64,
    /// How times were read (the least regular run's).
    pub time_base: TimeBase,
    /// q̇ derived from q (not logged).
    pub derived_qd: bool,
    /// q̈ derived (not logged).
    pub derived_qdd: bool,
    /// The derived signals' low-pass cutoff (Hz): the option's, else chosen from the motion's
    /// band edge when a signal was derived, else the rate's default.
    pub cutoff: f64,
    /// The motion's band edge (Hz) the cutoff was chosen from (`None` when it was not).
    pub band_edge: Option<f64>,
    /// This file's own band edge (Hz) when the cutoff was chosen from a band edge shared with
    /// other files read together (`None` otherwise; set by `io::load_all`): a shared edge well
    /// above it comes from another file, and a short one reads its resolution more than its
    /// motion.
    pub own_band_edge: Option<f64>,
    /// Samples trimmed at each end of a run.
    pub settle_samples: usize,
    /// Joints held at their logged position (asked for, or whose torque is never measured).
    pub locked: Vec<String>,
    /// Joints that never move (range of q and of q̇ at the noise level): their friction is not
    /// identifiable.
    pub still: Vec<String>,
    /// Joints whose logged torque is exactly zero in every sample (not measured): locked.
    pub unmeasured: Vec<String>,
}

/// The runs and what was done to get them.
#[derive(Clone, Debug, PartialEq)]
pub struct Prepared {
    /// The runs, in log order.
    pub runs: Vec<Run>,
    /// Counts and decisions.
    pub report: Report,
}

/// Samples the zero-phase filter `sos` needs at each end of a signal before its start-up
/// transient (from one-sided differences and padding) has decayed to [`SETTLED`]; doubled when
/// two derivations are cascaded (q̇ from q, then q̈ from q̇).
pub fn settle_samples(sos: &Sos, cascaded: bool) -> usize {
    let one = (-(SETTLED.ln()) * sos.time_constant()).ceil() as usize + 2;
    if cascaded {
        2 * one
    } else {
        one
    }
}

/// The filter's cutoff (Hz) and the motion's band edge it came from (Hz, when it did): the
/// cutoff asked for; the default when nothing is derived; else from the band edge given (one
/// over several files) or measured on the log split for it ([`band_edge_split`]).
fn cutoff_of(
    logged: &Logged,
    opts: &Options,
    derive: &Derive,
    period: f64,
) -> Result<(f64, Option<f64>), PrepareError> {
    let rate = 1.0 / period;
    Ok(match (opts.cutoff, opts.band_edge) {
        (Some(c), _) => (c, None),
        (None, _) if !(derive.qd || derive.qdd) => (default_cutoff(rate), None),
        (None, Some(edge)) => (motion_cutoff(edge, rate), Some(edge)),
        (None, None) => {
            let split = band_edge_split(logged, period)?;
            let edge = motion_band_edge(logged, &split.pieces, period);
            (motion_cutoff(edge, rate), Some(edge))
        }
    })
}

/// The log split for reading its motion's band edge: holes bridged up to a tenth of the
/// lowest cutoff's period ([`MIN_DATA_CUTOFF`]), the most any cutoff read from the motion
/// bridges, so that scattered drops leave pieces long enough to resolve the motion's band.
/// The runs themselves are split again at the cutoff chosen ([`max_bridged`]).
fn band_edge_split(logged: &Logged, period: f64) -> Result<Split, PrepareError> {
    split_runs(logged, period, max_bridged(1.0 / period, MIN_DATA_CUTOFF))
}

/// A cutoff asked for lies within what the rate allows ([`MIN_CUTOFF_FRACTION`] to
/// [`MAX_CUTOFF_FRACTION`] of it).
fn check_cutoff(cutoff: Option<f64>, rate: f64) -> Result<(), PrepareError> {
    let (min, max) = (MIN_CUTOFF_FRACTION * rate, MAX_CUTOFF_FRACTION * rate);
    match cutoff.filter(|c| !(*c >= min && *c <= max)) {
        Some(cutoff) => Err(PrepareError::Cutoff { cutoff, rate, max }),
        None => Ok(()),
    }
}

/// Some joint is left free after the joints `asked` to be locked and those never measured.
fn check_not_all_locked(
    logged: &Logged,
    report: &Report,
    asked: &[usize],
) -> Result<(), PrepareError> {
    if report.locked.len() < logged.dof() {
        return Ok(());
    }
    Err(PrepareError::AllLocked {
        asked: asked
            .iter()
            .map(|&j| logged.joint_names[j].clone())
            .collect(),
        unmeasured: report.unmeasured.clone(),
    })
}

/// Runs the pipeline (module docs) on `logged`, which [`Logged::validate`] has passed.
pub fn prepare(logged: &Logged, opts: &Options) -> Result<Prepared, PrepareError> {
    logged.validate()?;
    let period = median_period(&logged.t).ok_or(PrepareError::NoRate(logged.len()))?;
    if !(1.0 / MAX_RATE..=1.0 / MIN_RATE).contains(&period) {
        return Err(PrepareError::TimeUnit { period });
    }
    let rate = 1.0 / period;
    check_cutoff(opts.cutoff, rate)?;
    let locked = lock_columns(logged, &opts.lock)?;
    let derive = Derive {
        qd: logged.qd.is_none(),
        qdd: logged.qdd.is_none(),
    };
    let (cutoff, band_edge) = cutoff_of(logged, opts, &derive, period)?;
    let split = split_runs(logged, period, max_bridged(rate, cutoff))?;
    let sos = butterworth_lowpass(2, cutoff, rate)?;
    let settle = if derive.qd || derive.qdd {
        settle_samples(&sos, derive.qd && derive.qdd)
    } else {
        0
    };
    let mut report = Report::new(logged, &split, period, cutoff, settle, derive);
    report.band_edge = band_edge;
    let mut runs = vec![];
    for piece in &split.pieces {
        let clock = Clock::fit(&logged.t, piece, period);
        let base = clock.time_base(logged, piece);
        if base != TimeBase::Uniform && clock.jitter > MAX_JITTER {
            return Err(PrepareError::Irregular {
                start: piece[0],
                jitter: 100.0 * clock.jitter,
                period,
            });
        }
        report.note_clock(&clock, base);
        if piece.len() < 2 * settle + 2 {
            report.dropped_short += piece.len();
            continue;
        }
        let run = derive.run(logged, piece, &clock, base, &sos, settle);
        report.trimmed += piece.len() - run.index.len();
        runs.push(run);
    }
    if runs.is_empty() {
        return Err(PrepareError::NothingLeft {
            settle,
            cutoff,
            longest: split.pieces.iter().map(Vec::len).max().unwrap_or(0),
        });
    }
    finish(logged, &mut runs, &mut report, &locked);
    check_not_all_locked(logged, &report, &locked)?;
    Ok(Prepared { runs, report })
}

/// The median positive step between time stamps (s).
fn median_period(t: &[f64]) -> Option<f64> {
    let mut steps: Vec<f64> = t
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d > 0.0)
        .collect();
    if steps.is_empty() {
        return None;
    }
    let mid = steps.len() / 2;
    let (_, m, _) = steps.select_nth_unstable_by(mid, f64::total_cmp);
    Some(*m)
}

/// The columns of the joints to lock; an unknown name is an error.
fn lock_columns(logged: &Logged, names: &[String]) -> Result<Vec<usize>, PrepareError> {
    names
        .iter()
        .map(|name| {
            logged
                .joint_names
                .iter()
                .position(|j| j == name)
                .ok_or_else(|| PrepareError::UnknownJoint {
                    joint: name.clone(),
                    have: logged.joint_names.join(", "),
                })
        })
        .collect()
}

/// The log cut into pieces at gaps and restarts, duplicates left out.
struct Split {
    /// Each piece's sample indices (increasing time).
    pieces: Vec<Vec<usize>>,
    gaps: Vec<Gap>,
    duplicates: usize,
    missing: usize,
    dropouts: usize,
}

/// Splits where time jumps back by more than [`RESTART_PERIODS`] (a restart) or a step leaves
/// out more than `bridge` samples (a gap); a sample with its predecessor's stamp and values is a
/// duplicate; any other step that does not advance is an error.
fn split_runs(logged: &Logged, period: f64, bridge: usize) -> Result<Split, PrepareError> {
    let n = logged.dof();
    let same = |a: usize, b: usize| {
        logged.q[a * n..(a + 1) * n] == logged.q[b * n..(b + 1) * n]
            && logged.tau[a * n..(a + 1) * n] == logged.tau[b * n..(b + 1) * n]
    };
    let mut s = Split {
        pieces: vec![vec![0]],
        gaps: vec![],
        duplicates: 0,
        missing: 0,
        dropouts: 0,
    };
    let mut last = 0;
    for k in 1..logged.len() {
        let step = logged.t[k] - logged.t[last];
        if step == 0.0 && same(k, last) {
            s.duplicates += 1;
            continue;
        }
        if step <= 0.0 && step >= -RESTART_PERIODS * period {
            return Err(PrepareError::NotIncreasing {
                sample: k,
                t: logged.t[k],
                previous: logged.t[last],
            });
        }
        let slots = (step / period).round();
        if step < 0.0 || slots - 1.0 > bridge as f64 {
            s.gaps.push(Gap {
                sample: k,
                seconds: step,
            });
            s.pieces.push(vec![]);
        } else if slots >= 2.0 {
            s.missing += slots as usize - 1;
            s.dropouts += 1;
        }
        s.pieces.last_mut().expect("one piece at least").push(k);
        last = k;
    }
    Ok(s)
}

/// A clock tracked through one piece's stamps: sample `i` of the piece sits in a slot of
/// period `h`, at the clock's time `time[i]`.
struct Clock {
    h: f64,
    /// The clock's time of each sample's slot (s): the stamps with their jitter tracked out.
    time: Vec<f64>,
    /// RMS of the stamps about the clock, in periods.
    jitter: f64,
}

impl Clock {
    /// Each stamp is rounded to the nearest slot after the previous one (a step of two or
    /// more periods: samples missing), and the clock's phase is nudged toward it: the clock
    /// follows a slow drift of the stamps while their jitter stays out. Tracked twice, the
    /// second time at the period fitted (least squares of the stamps on their slots) to the
    /// first. A sample late by more than half a period reads as one slot missing: the clock then
    /// carries one phantom slot (interpolated, never a sample), which is harmless, where one
    /// line through all stamps would bend.
    fn fit(t: &[f64], piece: &[usize], period: f64) -> Clock {
        let mut h = period;
        let mut slot = vec![0usize; piece.len()];
        let mut time = vec![t[piece[0]]; piece.len()];
        for _ in 0..2 {
            let mut anchor = (t[piece[0]], 0usize);
            for i in 1..piece.len() {
                let ahead = (t[piece[i]] - anchor.0) / h;
                slot[i] = anchor.1 + (ahead.round() as usize).max(1);
                time[i] = anchor.0 + (slot[i] - anchor.1) as f64 * h;
                anchor = (time[i] + PHASE_GAIN * (t[piece[i]] - time[i]), slot[i]);
            }
            h = line_fit(piece.iter().map(|&k| t[k]), &slot).map_or(h, |(_, h)| h);
        }
        let ms = piece
            .iter()
            .zip(&time)
            .map(|(&k, &c)| (t[k] - c).powi(2))
            .sum::<f64>()
            / piece.len() as f64;
        Clock {
            h,
            time,
            jitter: ms.sqrt() / h,
        }
    }

    /// The time of each sample on the clock.
    fn slot_times(&self) -> Vec<f64> {
        self.time.clone()
    }

    /// Uniform when the stamps sit on the clock; otherwise stamps or clock slots, whichever
    /// the samples agree with better ([`roughness`]).
    fn time_base(&self, logged: &Logged, piece: &[usize]) -> TimeBase {
        if self.jitter <= UNIFORM_JITTER {
            return TimeBase::Uniform;
        }
        let stamps: Vec<f64> = piece.iter().map(|&k| logged.t[k]).collect();
        if roughness(logged, piece, &self.slot_times()) < roughness(logged, piece, &stamps) {
            TimeBase::ClockSlots
        } else {
            TimeBase::Stamps
        }
    }
}

/// Least-squares line `t ≈ t0 + h s` through the points `(s, t)`.
fn line_fit(t: impl Iterator<Item = f64>, s: &[usize]) -> Option<(f64, f64)> {
    let t: Vec<f64> = t.collect();
    let m = s.len() as f64;
    let s_mean = s.iter().sum::<usize>() as f64 / m;
    let t_mean = t.iter().sum::<f64>() / m;
    let (mut ss, mut st) = (0.0, 0.0);
    for (&si, &ti) in s.iter().zip(&t) {
        let ds = si as f64 - s_mean;
        ss += ds * ds;
        st += ds * (ti - t_mean);
    }
    (ss > 0.0).then(|| {
        let h = st / ss;
        (t_mean - h * s_mean, h)
    })
}

/// How badly the samples disagree with the times `times` (one per sample of `piece`): the
/// logged velocity against the central difference of the position when there is one, else
/// the position's second divided difference (a jittered time axis makes a smooth motion look
/// rough).
fn roughness(logged: &Logged, piece: &[usize], times: &[f64]) -> f64 {
    let n = logged.dof();
    let q = |i: usize, j: usize| logged.q[piece[i] * n + j];
    let mut sum = 0.0;
    for i in 1..piece.len().saturating_sub(1) {
        let (ta, tb, tc) = (times[i - 1], times[i], times[i + 1]);
        for j in 0..n {
            let slope = (q(i + 1, j) - q(i - 1, j)) / (tc - ta);
            let e = match &logged.qd {
                Some(qd) => slope - qd[piece[i] * n + j],
                None => {
                    let (s1, s2) = (
                        (q(i, j) - q(i - 1, j)) / (tb - ta),
                        (q(i + 1, j) - q(i, j)) / (tc - tb),
                    );
                    (s2 - s1) / (tc - ta)
                }
            };
            sum += e * e;
        }
    }
    sum
}

/// Which signals the pipeline derives.
#[derive(Clone, Copy, Debug)]
struct Derive {
    qd: bool,
    qdd: bool,
}

impl Derive {
    /// One piece as a run: its times on `base`, q̇ and q̈ derived where not logged (on the
    /// clock's uniform grid), `settle` samples trimmed at each end when anything was derived.
    fn run(
        &self,
        logged: &Logged,
        piece: &[usize],
        clock: &Clock,
        base: TimeBase,
        sos: &Sos,
        settle: usize,
    ) -> Run {
        let n = logged.dof();
        let times: Vec<f64> = match base {
            TimeBase::ClockSlots => clock.slot_times(),
            _ => piece.iter().map(|&k| logged.t[k]).collect(),
        };
        let pick = |v: &[f64]| -> Vec<f64> {
            piece
                .iter()
                .flat_map(|&k| v[k * n..(k + 1) * n].iter().copied())
                .collect()
        };
        let q = pick(&logged.q);
        let grid = Grid::new(&times, clock.h);
        let qd = match &logged.qd {
            Some(v) => pick(v),
            None => grid.derivative(&q, n, sos),
        };
        let qdd = match &logged.qdd {
            Some(v) => pick(v),
            None => grid.derivative(&qd, n, sos),
        };
        let keep: Vec<usize> = (0..piece.len())
            .filter(|&i| {
                let from_start = times[i] - times[0];
                let to_end = times[piece.len() - 1] - times[i];
                let margin = settle as f64 * clock.h * (1.0 - 1e-9);
                from_start >= margin && to_end >= margin
            })
            .collect();
        let mut tr = Trajectory::new(logged.joint_names.clone(), true);
        let tau = pick(&logged.tau);
        for &i in &keep {
            let row = |v: &[f64]| v[i * n..(i + 1) * n].to_vec();
            tr.push(times[i], &row(&q), &row(&qd), Some(&row(&qdd)), &row(&tau));
        }
        // The settling trimmed off was processed with the run: the diagnosis processes the
        // torque over it as well (`Trajectory::margins`).
        if let (Some(&first), Some(&last)) = (keep.first(), keep.last()) {
            if first > 0 || last + 1 < piece.len() {
                tr.margins = vec![Margins {
                    before: tau[..first * n].to_vec(),
                    after: tau[(last + 1) * n..].to_vec(),
                }];
            }
        }
        Run {
            trajectory: tr,
            index: keep.iter().map(|&i| piece[i]).collect(),
        }
    }
}

/// A uniform grid over one run's times, for differentiating samples that miss slots or sit
/// off them.
struct Grid<'a> {
    times: &'a [f64],
    t0: f64,
    h: f64,
    len: usize,
}

impl<'a> Grid<'a> {
    fn new(times: &'a [f64], h: f64) -> Self {
        let t0 = times[0];
        let span = times[times.len() - 1] - t0;
        let len = (span / h).round() as usize + 1;
        Grid { times, t0, h, len }
    }

    /// `d/dt` of sample-major `x` (at `times`, `n` columns): linearly interpolated onto the
    /// grid, central difference, zero-phase low-pass, read back at `times`.
    fn derivative(&self, x: &[f64], n: usize, sos: &Sos) -> Vec<f64> {
        let m = self.times.len();
        let mut out = vec![0.0; x.len()];
        for j in 0..n {
            let col: Vec<f64> = (0..m).map(|k| x[k * n + j]).collect();
            let on_grid = self.onto_grid(&col);
            let d = sos.filtfilt(&differentiate(&on_grid, self.h));
            for (k, v) in self.back(&d).into_iter().enumerate() {
                out[k * n + j] = v;
            }
        }
        out
    }

    /// `col` (at `times`) at the grid's points, linear between neighbouring samples.
    fn onto_grid(&self, col: &[f64]) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.len);
        let mut k = 0;
        for g in 0..self.len {
            let tg = self.t0 + g as f64 * self.h;
            while k + 2 < self.times.len() && self.times[k + 1] <= tg {
                k += 1;
            }
            out.push(lerp(
                self.times[k],
                col[k],
                self.times[(k + 1).min(col.len() - 1)],
                col[(k + 1).min(col.len() - 1)],
                tg,
            ));
        }
        out
    }

    /// Grid values `g` at `times`, linear between grid points.
    fn back(&self, g: &[f64]) -> Vec<f64> {
        self.times
            .iter()
            .map(|&t| {
                let x = ((t - self.t0) / self.h).clamp(0.0, (self.len - 1) as f64);
                let i = (x.floor() as usize).min(self.len.saturating_sub(2));
                let f = x - i as f64;
                if self.len < 2 {
                    g[0]
                } else {
                    g[i] + f * (g[i + 1] - g[i])
                }
            })
            .collect()
    }
}

/// The line through `(ta, a)` and `(tb, b)` at `t` (`a` when the two times coincide).
fn lerp(ta: f64, a: f64, tb: f64, b: f64, t: f64) -> f64 {
    if tb == ta {
        a
    } else {
        a + (b - a) * (t - ta) / (tb - ta)
    }
}

impl Report {
    fn new(
        logged: &Logged,
        split: &Split,
        period: f64,
        cutoff: f64,
        settle: usize,
        derive: Derive,
    ) -> Self {
        Report {
            samples_read: logged.len(),
            samples_kept: 0,
            runs: 0,
            gaps: split.gaps.clone(),
            duplicates: split.duplicates,
            missing_bridged: split.missing,
            dropouts_bridged: split.dropouts,
            trimmed: 0,
            dropped_short: 0,
            period,
            jitter: 0.0,
            time_base: TimeBase::Uniform,
            derived_qd: derive.qd,
            derived_qdd: derive.qdd,
            cutoff,
            band_edge: None,
            own_band_edge: None,
            settle_samples: settle,
            locked: vec![],
            still: vec![],
            unmeasured: vec![],
        }
    }

    /// Keeps the least regular run's clock.
    fn note_clock(&mut self, clock: &Clock, base: TimeBase) {
        if clock.jitter > self.jitter {
            self.jitter = clock.jitter;
            self.time_base = base;
        }
    }
}

/// The cutoff for a motion whose band ends at `edge` Hz: [`CUTOFF_OVER_BAND`] times the edge,
/// at least [`MIN_DATA_CUTOFF`], at most [`default_cutoff`] of the rate.
pub fn motion_cutoff(edge: f64, rate: f64) -> f64 {
    (CUTOFF_OVER_BAND * edge).clamp(
        MIN_DATA_CUTOFF.min(default_cutoff(rate)),
        default_cutoff(rate),
    )
}

/// Each log's own motion band edge (Hz; `None` for a log that needs no signal derived, or
/// cannot be read); the highest of them gives logs read together (training, validation and
/// baseline runs) one cutoff, and each file's own is kept in its report
/// ([`Report::own_band_edge`]).
pub fn band_edges(logs: &[&Logged]) -> Vec<Option<f64>> {
    logs.iter()
        .map(|l| {
            if l.qd.is_some() && l.qdd.is_some() {
                return None;
            }
            let period = median_period(&l.t)?;
            let split = band_edge_split(l, period).ok()?;
            Some(motion_band_edge(l, &split.pieces, period))
        })
        .collect()
}

/// The highest frequency (Hz) at which any joint's motion stands [`MOTION_OVER_NOISE`] above
/// the noise floor, in the longest piece: the periodogram (Blackman–Harris window) of the logged velocity
/// (of the position's first difference when no velocity is logged) on the uniform grid, its
/// noise floor the median power above a quarter of the rate.
fn motion_band_edge(logged: &Logged, pieces: &[Vec<usize>], period: f64) -> f64 {
    let Some(piece) = pieces.iter().max_by_key(|p| p.len()) else {
        return 0.0;
    };
    let n = logged.dof();
    let times: Vec<f64> = piece.iter().map(|&k| logged.t[k]).collect();
    if times.len() < 64 {
        return f64::INFINITY;
    }
    let grid = Grid::new(&times, period);
    let mut edge = 0.0f64;
    for j in 0..n {
        let col: Vec<f64> = match &logged.qd {
            Some(qd) => piece.iter().map(|&k| qd[k * n + j]).collect(),
            None => piece.iter().map(|&k| logged.q[k * n + j]).collect(),
        };
        let mut x = grid.onto_grid(&col);
        if logged.qd.is_none() {
            x = x.windows(2).map(|w| (w[1] - w[0]) / period).collect();
        }
        edge = edge.max(band_edge(&x, 1.0 / period));
    }
    edge
}

/// The band edge (Hz) of one uniformly sampled signal at `rate` ([`motion_band_edge`]); 0 for
/// a signal that is all noise.
fn band_edge(x: &[f64], rate: f64) -> f64 {
    use rustfft::{num_complex::Complex, FftPlanner};
    let m = x.len();
    let mean = x.iter().sum::<f64>() / m as f64;
    // 4-term Blackman–Harris: side lobes 92 dB down, so a strong slow motion does not leak
    // above the noise floor far from its own frequencies (a Hann window's leakage reached 5 Hz
    // from a 0.4 Hz motion).
    let window = |k: usize| {
        let x = 2.0 * std::f64::consts::PI * k as f64 / m as f64;
        0.35875 - 0.48829 * x.cos() + 0.14128 * (2.0 * x).cos() - 0.01168 * (3.0 * x).cos()
    };
    let mut buf: Vec<Complex<f64>> = x
        .iter()
        .enumerate()
        .map(|(k, v)| Complex::new((v - mean) * window(k), 0.0))
        .collect();
    FftPlanner::new().plan_fft_forward(m).process(&mut buf);
    let power: Vec<f64> = buf[..m / 2].iter().map(|c| c.norm_sqr()).collect();
    let bins = power.len();
    let mut high: Vec<f64> = power[bins / 2..].to_vec();
    high.sort_by(f64::total_cmp);
    let floor = high[high.len() / 2].max(f64::MIN_POSITIVE);
    // A periodogram bin of noise alone exceeds 1000 times the median with probability
    // e^(−1000 ln 2): no smoothing is needed (smoothing would spread the motion's peaks).
    (1..bins / 2)
        .rev()
        .find(|&k| power[k] > MOTION_OVER_NOISE * floor)
        .map_or(0.0, |k| k as f64 * rate / m as f64)
}

/// Joints that never move, joints whose torque is never measured (locked with those asked
/// for), and the counts.
fn finish(logged: &Logged, runs: &mut [Run], report: &mut Report, asked: &[usize]) {
    let n = logged.dof();
    let names = &logged.joint_names;
    let mut lock: Vec<usize> = asked.to_vec();
    for (j, name) in names.iter().enumerate() {
        let m = logged.len();
        let (lo, hi) = (0..m)
            .map(|k| logged.q[k * n + j])
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(x), b.max(x))
            });
        let fast = runs
            .iter()
            .flat_map(|r| (0..r.trajectory.len()).map(move |k| r.trajectory.qd_at(k)[j].abs()))
            .fold(0.0f64, f64::max);
        if hi - lo <= STILL_RANGE && fast <= STILL_SPEED {
            report.still.push(name.clone());
        }
        if (0..m).all(|k| logged.tau[k * n + j] == 0.0) {
            report.unmeasured.push(name.clone());
            if !lock.contains(&j) {
                lock.push(j);
            }
        }
    }
    for run in runs.iter_mut() {
        let tr = &mut run.trajectory;
        for k in 0..tr.len() {
            for &j in &lock {
                tr.qd[k * n + j] = 0.0;
                if let Some(a) = tr.qdd.as_mut() {
                    a[k * n + j] = 0.0;
                }
            }
        }
    }
    lock.sort_unstable();
    report.locked = lock.iter().map(|&j| names[j].clone()).collect();
    report.runs = runs.len();
    report.samples_kept = runs.iter().map(|r| r.index.len()).sum();
}

/// A joint whose position spans at most this (rad or m) never moves.
const STILL_RANGE: f64 = 1e-3;
/// ... and whose speed never exceeds this (rad/s or m/s).
const STILL_SPEED: f64 = 1e-2;

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth two-joint motion sampled at `times`, velocities logged or not.
    fn motion(times: &[f64], with_qd: bool) -> Logged {
        let f = |t: f64| {
            [
                (1.3 * t).sin() + 0.2 * (4.1 * t).cos(),
                0.5 * (2.2 * t).sin(),
            ]
        };
        let fd = |t: f64| {
            [
                1.3 * (1.3 * t).cos() - 0.82 * (4.1 * t).sin(),
                1.1 * (2.2 * t).cos(),
            ]
        };
        let mut l = Logged {
            joint_names: vec!["a".into(), "b".into()],
            t: times.to_vec(),
            q: vec![],
            qd: with_qd.then(Vec::new),
            qdd: None,
            tau: vec![],
        };
        for &t in times {
            l.q.extend(f(t));
            if let Some(v) = l.qd.as_mut() {
                v.extend(fd(t));
            }
            l.tau.extend([1.0, 2.0]);
        }
        l
    }

    fn true_qdd(t: f64) -> [f64; 2] {
        [
            -1.69 * (1.3 * t).sin() - 3.362 * (4.1 * t).cos(),
            -2.42 * (2.2 * t).sin(),
        ]
    }

    fn max_qdd_error(p: &Prepared) -> f64 {
        let mut e = 0.0f64;
        for r in &p.runs {
            let tr = &r.trajectory;
            for k in 0..tr.len() {
                let want = true_qdd(tr.t[k]);
                for (got, want) in tr.qdd_at(k).unwrap().iter().zip(want) {
                    e = e.max((got - want).abs());
                }
            }
        }
        e
    }

    #[test]
    fn uniform_data_keep_every_sample_but_the_trimmed_ends() {
        let times: Vec<f64> = (0..4000).map(|k| k as f64 * 1e-3).collect();
        let p = prepare(&motion(&times, true), &Options::default()).unwrap();
        let r = &p.report;
        assert_eq!((r.runs, r.gaps.len(), r.missing_bridged), (1, 0, 0));
        assert_eq!(r.time_base, TimeBase::Uniform);
        assert_eq!(r.cutoff, 20.0);
        assert!(r.derived_qdd && !r.derived_qd);
        assert_eq!(r.samples_kept + r.trimmed, 4000);
        assert_eq!(r.trimmed, 2 * r.settle_samples);
        // Away from the trimmed ends the derived q̈ is the true one up to the 20 Hz filter's
        // attenuation of this slow motion.
        assert!(max_qdd_error(&p) < 2e-2, "{}", max_qdd_error(&p));
        assert_eq!(p.runs[0].index[0], r.settle_samples);
    }

    #[test]
    fn the_trimmed_ends_torque_is_kept_as_the_run_s_margins() {
        let times: Vec<f64> = (0..4000).map(|k| k as f64 * 1e-3).collect();
        let mut l = motion(&times, false);
        l.tau
            .iter_mut()
            .enumerate()
            .for_each(|(i, v)| *v = i as f64);
        let p = prepare(&l, &Options::default()).unwrap();
        let s = p.report.settle_samples;
        assert!(s > 10, "{s}");
        let tr = &p.runs[0].trajectory;
        let count = |r: std::ops::Range<usize>| r.map(|i| i as f64).collect::<Vec<_>>();
        assert_eq!(tr.margin(0).before, count(0..2 * s));
        assert_eq!(tr.margin(0).after, count(2 * (4000 - s)..8000));
        assert_eq!(tr.tau[0], (2 * s) as f64);
        // With q̇ and q̈ logged nothing is derived or trimmed, and no margin is known.
        l.qd = Some(vec![0.0; 8000]);
        l.qdd = Some(vec![0.0; 8000]);
        let p = prepare(&l, &Options::default()).unwrap();
        assert_eq!(
            (p.report.trimmed, p.runs[0].trajectory.margins.len()),
            (0, 0)
        );
    }

    #[test]
    fn the_trim_removes_what_the_ends_get_wrong() {
        // With the logged velocity noisy (as an encoder's difference is), the derived q̈ is
        // wrong near the ends (one-sided differences, padding) and right past the trim.
        let times: Vec<f64> = (0..6000).map(|k| k as f64 * 1e-3).collect();
        let mut l = motion(&times, true);
        let noise = |k: usize| 0.02 * (((k as f64) * 12.9898).sin() * 43758.5453).fract();
        for (k, v) in l.qd.as_mut().unwrap().iter_mut().enumerate() {
            *v += noise(k);
        }
        let sos = butterworth_lowpass(2, 20.0, 1000.0).unwrap();
        let piece: Vec<usize> = (0..6000).collect();
        let clock = Clock::fit(&l.t, &piece, 1e-3);
        let d = Derive {
            qd: false,
            qdd: true,
        };
        let whole = d.run(&l, &piece, &clock, TimeBase::Uniform, &sos, 0);
        let tr = &whole.trajectory;
        let err = |k: usize| (tr.qdd_at(k).unwrap()[0] - true_qdd(tr.t[k])[0]).abs();
        let settle = settle_samples(&sos, false);
        let worst = |r: std::ops::Range<usize>| r.map(err).fold(0.0f64, f64::max);
        let edge = worst(0..5).max(worst(5995..6000));
        let inside = worst(settle..6000 - settle);
        let middle = worst(2000..4000);
        assert!(edge > 5.0 * middle, "edge {edge}, middle {middle}");
        assert!(
            inside < 2.0 * middle,
            "past the trim {inside}, middle {middle}"
        );
    }

    #[test]
    fn a_dropout_splits_and_scattered_drops_are_bridged() {
        let mut times: Vec<f64> = (0..6000).map(|k| k as f64 * 1e-3).collect();
        // 0.5 s missing after sample 3000; every 37th sample dropped.
        times.retain(|t| !(3.0..3.5).contains(t));
        let times: Vec<f64> = times
            .into_iter()
            .enumerate()
            .filter(|(i, _)| i % 37 != 5)
            .map(|(_, t)| t)
            .collect();
        let p = prepare(&motion(&times, true), &Options::default()).unwrap();
        let r = &p.report;
        assert_eq!(r.runs, 2);
        assert_eq!(r.gaps.len(), 1);
        assert!((r.gaps[0].seconds - 0.501).abs() < 1e-9, "{:?}", r.gaps);
        assert!(r.dropouts_bridged > 100 && r.missing_bridged == r.dropouts_bridged);
        assert!(max_qdd_error(&p) < 2e-2, "{}", max_qdd_error(&p));
        assert_eq!(r.samples_kept + r.trimmed + r.dropped_short, times.len());
    }

    #[test]
    fn holes_are_bridged_up_to_a_tenth_of_the_applied_cutoff_s_period() {
        // 200 Hz, a fifth of the samples dropped at random (holes of up to six in a row): the
        // cutoff read from the motion (about 2.6 Hz) bridges seven, the 20 Hz default only one.
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let times: Vec<f64> = (0..4000)
            .map(|k| k as f64 / 200.0)
            .filter(|_| next() >= 0.2)
            .collect();
        let p = prepare(&motion(&times, false), &Options::default()).unwrap();
        let r = &p.report;
        assert!(r.cutoff < 4.0, "cutoff {}", r.cutoff);
        assert_eq!((r.runs, r.gaps.len()), (1, 0), "{:?}", r.gaps.len());
        assert!(r.missing_bridged > 700, "{}", r.missing_bridged);
        assert_eq!(r.samples_kept + r.trimmed, times.len());
        assert!(max_qdd_error(&p) < 2e-2, "{}", max_qdd_error(&p));
    }

    #[test]
    fn jittered_stamps_are_read_on_the_base_the_data_agree_with() {
        // Sampled on a uniform clock, stamped with ±0.3 ms of jitter: the clock slots.
        let clock: Vec<f64> = (0..3000).map(|k| k as f64 * 1e-3).collect();
        let jitter = |k: usize| 3e-4 * ((k as f64 * 12.9898).sin() * 43758.5453).fract();
        let mut l = motion(&clock, true);
        l.t = clock
            .iter()
            .enumerate()
            .map(|(k, t)| t + jitter(k))
            .collect();
        let p = prepare(&l, &Options::default()).unwrap();
        assert_eq!(p.report.time_base, TimeBase::ClockSlots);
        assert!(max_qdd_error(&p) < 2e-2, "{}", max_qdd_error(&p));
        // Sampled at the jittered times themselves: the stamps.
        let stamps: Vec<f64> = clock
            .iter()
            .enumerate()
            .map(|(k, t)| t + jitter(k))
            .collect();
        for with_qd in [true, false] {
            let p = prepare(&motion(&stamps, with_qd), &Options::default()).unwrap();
            assert_eq!(p.report.time_base, TimeBase::Stamps, "qd logged: {with_qd}");
            assert!(max_qdd_error(&p) < 3e-2, "{}", max_qdd_error(&p));
        }
    }

    #[test]
    fn velocities_are_derived_when_not_logged() {
        let times: Vec<f64> = (0..4000).map(|k| k as f64 * 1e-3).collect();
        let p = prepare(&motion(&times, false), &Options::default()).unwrap();
        assert!(p.report.derived_qd && p.report.derived_qdd);
        assert!(max_qdd_error(&p) < 3e-2, "{}", max_qdd_error(&p));
    }

    #[test]
    fn restarts_split_and_duplicates_are_dropped() {
        let mut times: Vec<f64> = (0..2000).map(|k| k as f64 * 1e-3).collect();
        times.extend((0..2000).map(|k| k as f64 * 1e-3));
        let mut l = motion(&times, true);
        // Sample 100 repeated.
        let n = 2;
        l.t.insert(101, l.t[100]);
        for v in [&mut l.q, l.qd.as_mut().unwrap(), &mut l.tau] {
            let row: Vec<f64> = v[100 * n..101 * n].to_vec();
            for (i, x) in row.into_iter().enumerate() {
                v.insert(101 * n + i, x);
            }
        }
        let p = prepare(&l, &Options::default()).unwrap();
        assert_eq!(p.report.duplicates, 1);
        assert_eq!(p.report.runs, 2);
        assert!(p.report.gaps[0].seconds < 0.0);
    }

    #[test]
    fn stamps_out_of_order_are_refused_by_sample() {
        let mut times: Vec<f64> = (0..500).map(|k| k as f64 * 1e-3).collect();
        times.swap(40, 41);
        let err = prepare(&motion(&times, true), &Options::default()).unwrap_err();
        assert!(
            err.to_string()
                .contains("sample 41: time 0.04 s does not increase"),
            "{err}"
        );
    }

    #[test]
    fn locked_and_unmeasured_joints_hold_still() {
        let times: Vec<f64> = (0..2000).map(|k| k as f64 * 1e-3).collect();
        let mut l = motion(&times, true);
        for k in 0..l.len() {
            l.tau[2 * k + 1] = 0.0;
        }
        let p = prepare(&l, &Options::default()).unwrap();
        assert_eq!(p.report.unmeasured, vec!["b".to_string()]);
        assert_eq!(p.report.locked, vec!["b".to_string()]);
        let tr = &p.runs[0].trajectory;
        assert!((0..tr.len()).all(|k| tr.qd_at(k)[1] == 0.0 && tr.qdd_at(k).unwrap()[1] == 0.0));
        assert!(tr.qd_at(10)[0] != 0.0);
        let err = prepare(
            &motion(&times, true),
            &Options {
                lock: vec!["c".into()],
                ..Default::default()
            },
        )
        .unwrap_err();
        assert!(
            err.to_string().contains("no joint 'c' (they have a, b)"),
            "{err}"
        );
    }

    #[test]
    fn bad_cutoffs_and_rates_are_refused() {
        let times: Vec<f64> = (0..500).map(|k| k as f64 * 5e-3).collect();
        let l = motion(&times, true);
        let err = prepare(
            &l,
            &Options {
                cutoff: Some(5000.0),
                ..Default::default()
            },
        )
        .unwrap_err();
        assert!(err.to_string().contains("sampled at 200"), "{err}");
        let mut one = motion(&[0.0, 0.0], true);
        one.q[0] = 1.0;
        assert!(matches!(
            prepare(&one, &Options::default()),
            Err(PrepareError::NoRate(2))
        ));
    }

    #[test]
    fn a_short_piece_between_gaps_is_dropped_and_counted() {
        let mut times: Vec<f64> = (0..3000).map(|k| k as f64 * 1e-3).collect();
        times.extend((0..50).map(|k| 10.0 + k as f64 * 1e-3));
        let p = prepare(&motion(&times, true), &Options::default()).unwrap();
        assert_eq!(p.report.dropped_short, 50);
        assert_eq!(p.report.runs, 1);
    }
}
