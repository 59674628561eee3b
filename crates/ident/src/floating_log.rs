//! A floating robot's log as samples for its rows ([`super::floating`]): the joints through
//! the data pipeline ([`physid_io::prepare`]), the trunk's acceleration derived from its logged
//! twist (its linear part from the accelerometer where the log has one), and the joint torques
//! and contact forces filtered alike.

use super::floating::{Contact, DataSetting, FloatingRows, FloatingSample};
use super::NormalEquations;
use nalgebra::{DMatrix, DVector, Vector3};
use physid_core::dynamics::BaseState;
use physid_core::model::floating::FloatingModel;
use physid_core::signal::Sos;
use physid_core::spatial::{Motion, Transform};
use physid_io::floating_log::FloatingLog;

/// Why a log gives no samples.
#[derive(Debug, thiserror::Error)]
pub enum LogSamplesError {
    /// The data pipeline refused the joints, or no filter fits the rate.
    #[error("{0}")]
    Pipeline(String),
}

/// How the log is turned into samples.
#[derive(Clone, Debug, PartialEq)]
pub struct LogSampling {
    /// Low-pass cutoff of the derived signals (Hz); `None`: the pipeline's choice.
    pub cutoff: Option<f64>,
    /// The data setting the samples are for (`TorquesOnly` leaves out the samples near a
    /// change of the feet down).
    pub setting: DataSetting,
    /// Without contact columns, a foot is down where its logged normal force exceeds this (N).
    pub contact_force: f64,
    /// Gravity (m/s², world): an accelerometer reads the trunk's acceleration less it.
    pub gravity: Vector3<f64>,
}

/// One sample ready for the rows: the trunk's state, the joints', the feet down.
#[derive(Clone, Debug)]
pub struct LogSample {
    /// The trunk's pose and twist as logged, its acceleration derived and filtered.
    pub base: BaseState,
    /// Joint angles (rad), rates (rad/s) and accelerations (rad/s²), from the pipeline.
    pub q: Vec<f64>,
    /// Joint rates.
    pub qd: Vec<f64>,
    /// Joint accelerations.
    pub qdd: Vec<f64>,
    /// Joint torques (N m), filtered.
    pub tau: Vec<f64>,
    /// The feet down.
    pub down: Vec<bool>,
    /// The ground's force on each foot (N, world), filtered; zero where not logged.
    pub force: Vec<Vector3<f64>>,
}

/// The samples the pipeline kept, and what it chose.
pub struct LogSamples {
    /// The samples, in order.
    pub samples: Vec<LogSample>,
    /// The cutoff used (Hz).
    pub cutoff: f64,
    /// Samples left out near a change of the feet in contact (`TorquesOnly`).
    pub dropped: usize,
}

impl LogSamples {
    /// The share of the feet's samples down.
    pub fn contact_share(&self) -> f64 {
        let (down, all) = self.samples.iter().fold((0, 0), |(d, a), s| {
            (d + s.down.iter().filter(|&&x| x).count(), a + s.down.len())
        });
        down as f64 / all.max(1) as f64
    }
}

/// The log through the data pipeline ([`physid_io::prepare`]): the joints' q̇, q̈ derived where not
/// logged and the runs' ends trimmed. The trunk's acceleration is the derivative of its logged
/// twist filtered alike (the same zero-phase Butterworth at the same cutoff), its linear part
/// the accelerometer's reading with gravity and `ω × v` restored where the log has one (not
/// differentiated: an estimator's velocity noise, differentiated, swamps a slow motion's
/// acceleration), and so are the joint torques and the contact forces: the equations of motion are linear in the
/// accelerations and the forces, so filtering both sides alike keeps them (a stiff contact's
/// forces change faster than any cutoff passes; filtered on one side only, the trunk rows
/// would be off by what the filter takes from them).
pub fn log_samples(log: &FloatingLog, opts: &LogSampling) -> Result<LogSamples, LogSamplesError> {
    let prepared = physid_io::prepare::prepare(
        &log.joints,
        &physid_io::prepare::Options {
            cutoff: opts.cutoff,
            ..Default::default()
        },
    )
    .map_err(|e| LogSamplesError::Pipeline(e.to_string()))?;
    let report = &prepared.report;
    let (period, cutoff, settle) = (report.period, report.cutoff, report.settle_samples);
    let sos = physid_core::signal::butterworth_lowpass(2, cutoff.min(0.4 / period), 1.0 / period)
        .map_err(|e| LogSamplesError::Pipeline(e.to_string()))?;
    let (mut samples, mut dropped) = (vec![], 0);
    for run in &prepared.runs {
        let (first, last) = (run.index[0], *run.index.last().expect("a kept run"));
        let pad = settle.min(first).min(log.len() - 1 - last);
        let span = Filtered::new(log, first - pad..last + pad + 1, (&sos, &opts.gravity));
        let tr = &run.trajectory;
        let run_samples: Vec<LogSample> = (run.index.iter().enumerate())
            .map(|(k, &i)| sample(log, opts, &span, i, (tr, k)))
            .collect();
        if opts.setting == DataSetting::TorquesOnly {
            let kept = away_from_contact_changes(run_samples, settle);
            dropped += run.index.len() - kept.len();
            samples.extend(kept);
        } else {
            samples.extend(run_samples);
        }
    }
    Ok(LogSamples {
        samples,
        cutoff,
        dropped,
    })
}

/// `samples` (one run's, in order) less those within `guard` samples of a change of the feet
/// in contact. Projecting out the contact forces is exact sample by sample, but the filtered
/// torques and accelerations mix each sample with its neighbours: across a touchdown or a
/// lift-off the neighbours obey another projection.
fn away_from_contact_changes(samples: Vec<LogSample>, guard: usize) -> Vec<LogSample> {
    let changes: Vec<usize> = (1..samples.len())
        .filter(|&k| samples[k].down != samples[k - 1].down)
        .collect();
    samples
        .into_iter()
        .enumerate()
        .filter(|(k, _)| {
            let at = changes.partition_point(|&c| c + guard <= *k);
            changes.get(at).is_none_or(|&c| c > k + guard)
        })
        .map(|(_, s)| s)
        .collect()
}

/// A stretch of the log with its trunk acceleration derived and its joint torques and contact
/// forces filtered.
struct Filtered {
    start: usize,
    accel: Vec<Motion>,
    tau: Vec<f64>,
    force: Option<Vec<Vector3<f64>>>,
}

impl Filtered {
    /// Rows `span` of `log`, filtered by `sos`.
    fn new(
        log: &FloatingLog,
        span: std::ops::Range<usize>,
        (sos, g): (&Sos, &Vector3<f64>),
    ) -> Self {
        let t = &log.joints.t[span.clone()];
        let measured = (log.accel.as_ref()).map(|f| accelerometer_linear(log, span.clone(), f, g));
        let accel = twist_derivative(&log.twist[span.clone()], t, measured.as_deref(), sos);
        let n = log.joints.dof();
        let tau = filtered_columns(&log.joints.tau[span.start * n..span.end * n], n, sos);
        let f = log.feet.len();
        let force = log.force.as_ref().map(|force| {
            let flat: Vec<f64> = force[span.start * f..span.end * f]
                .iter()
                .flat_map(|v| v.iter().copied())
                .collect();
            let out = filtered_columns(&flat, 3 * f, sos);
            out.chunks(3)
                .map(|c| Vector3::new(c[0], c[1], c[2]))
                .collect()
        });
        Self {
            start: span.start,
            accel,
            tau,
            force,
        }
    }
}

/// The linear part of the trunk's spatial acceleration (trunk axes, m/s², sample-major `x, y,
/// z`) over `span` from the accelerometer's specific force `f`: `a = f + Rᵀ g − ω × v`.
fn accelerometer_linear(
    log: &FloatingLog,
    span: std::ops::Range<usize>,
    f: &[Vector3<f64>],
    g: &Vector3<f64>,
) -> Vec<f64> {
    span.flat_map(|k| {
        let v = &log.twist[k];
        let a = f[k] + log.rotation[k].transpose() * g - v.ang.cross(&v.lin);
        [a.x, a.y, a.z]
    })
    .collect()
}

/// Each of the `n` columns of sample-major `x` filtered forwards and backwards by `sos`.
fn filtered_columns(x: &[f64], n: usize, sos: &Sos) -> Vec<f64> {
    let m = x.len() / n.max(1);
    let mut out = vec![0.0; x.len()];
    for j in 0..n {
        let column: Vec<f64> = (0..m).map(|k| x[k * n + j]).collect();
        for (k, v) in sos.filtfilt(&column).into_iter().enumerate() {
            out[k * n + j] = v;
        }
    }
    out
}

/// Sample `k` of `tr`, log row `i` (in `span`).
fn sample(
    log: &FloatingLog,
    opts: &LogSampling,
    span: &Filtered,
    i: usize,
    (tr, k): (&physid_core::trajectory::Trajectory, usize),
) -> LogSample {
    let (f, n, r) = (log.feet.len(), log.joints.dof(), i - span.start);
    let down = match (&log.contact, &log.force) {
        (Some(c), _) => c[i * f..(i + 1) * f].to_vec(),
        (None, Some(force)) => force[i * f..(i + 1) * f]
            .iter()
            .map(|x| x.z > opts.contact_force)
            .collect(),
        (None, None) => vec![false; f],
    };
    LogSample {
        base: BaseState {
            pose: Transform::from_pose(&log.rotation[i], &log.position[i]),
            v: log.twist[i],
            a: span.accel[r],
        },
        q: tr.q_at(k).to_vec(),
        qd: tr.qd_at(k).to_vec(),
        qdd: tr.qdd_at(k).expect("the pipeline derives q̈").to_vec(),
        tau: span.tau[r * n..(r + 1) * n].to_vec(),
        down,
        force: match &span.force {
            Some(v) => v[r * f..(r + 1) * f].to_vec(),
            None => vec![Vector3::zeros(); f],
        },
    }
}

/// The time derivative of the trunk's twist (trunk coordinates: in a body's own frame the
/// spatial acceleration is the derivative of the twist's components), by central differences on
/// the stamps `t`, then `sos` forwards and backwards; its linear part `measured` instead where
/// given (sample-major `x, y, z`: [`accelerometer_linear`]), filtered alike, not differentiated.
fn twist_derivative(
    twist: &[Motion],
    t: &[f64],
    measured: Option<&[f64]>,
    sos: &Sos,
) -> Vec<Motion> {
    let m = twist.len();
    let column = |c: usize| -> Vec<f64> {
        if let (Some(linear), 3..) = (measured, c) {
            let x: Vec<f64> = linear.iter().skip(c - 3).step_by(3).copied().collect();
            return sos.filtfilt(&x);
        }
        let x: Vec<f64> = twist.iter().map(|v| v.to_vec6()[c]).collect();
        let d: Vec<f64> = (0..m)
            .map(|k| {
                let (a, b) = (k.saturating_sub(1), (k + 1).min(m - 1));
                if b > a {
                    (x[b] - x[a]) / (t[b] - t[a])
                } else {
                    0.0
                }
            })
            .collect();
        sos.filtfilt(&d)
    };
    let columns: Vec<Vec<f64>> = (0..6).map(column).collect();
    (0..m)
        .map(|k| Motion::from_vec6(&nalgebra::Vector6::from_fn(|c, _| columns[c][k])))
        .collect()
}

impl LogSamples {
    /// The normal equations of the samples' rows in `setting`, `robot`'s feet at `feet`
    /// (`(body, point in the body)`, the log's order).
    pub fn normal_equations(
        &self,
        robot: &FloatingModel,
        feet: &[(usize, Vector3<f64>)],
        setting: DataSetting,
    ) -> NormalEquations {
        let per_sample = super::floating::rows_per_sample(robot, setting);
        let mut ne = NormalEquations::new(per_sample, robot.parameter_count());
        self.for_each_rows(robot, feet, setting, |y, target, _| {
            ne.add(y, target.as_slice())
        });
        ne.finish()
    }

    /// Each sample's rows and targets in `setting` (and its joint torques), in order.
    pub fn for_each_rows(
        &self,
        robot: &FloatingModel,
        feet: &[(usize, Vector3<f64>)],
        setting: DataSetting,
        each: impl FnMut(&DMatrix<f64>, &DVector<f64>, &[f64]),
    ) {
        for_each_rows(robot, feet, &self.samples, setting, each)
    }
}

/// Each of `samples`' rows and targets in `setting` (and its joint torques), in order.
fn for_each_rows(
    robot: &FloatingModel,
    feet: &[(usize, Vector3<f64>)],
    samples: &[LogSample],
    setting: DataSetting,
    mut each: impl FnMut(&DMatrix<f64>, &DVector<f64>, &[f64]),
) {
    let mut rows = FloatingRows::new(robot);
    // With forces measured every foot's force enters the targets, down or not: filtered, a
    // force is smeared across touchdown and lift-off, and a foot in the air pushes nothing (its
    // sensor's noise aside). Only the projection of `TorquesOnly` needs which feet are down.
    let projected = setting == DataSetting::TorquesOnly;
    for s in samples {
        let contacts: Vec<Contact> = (feet.iter().zip(&s.force).zip(&s.down))
            .filter(|(_, &d)| d || !projected)
            .map(|((&(body, point), &force), _)| Contact { body, point, force })
            .collect();
        let sample = FloatingSample {
            base: &s.base,
            q: &s.q,
            qd: &s.qd,
            qdd: &s.qdd,
            tau: &s.tau,
            contacts: &contacts,
        };
        let (y, target) = rows.rows(robot, &sample, setting);
        each(&y, &target, &s.tau);
    }
}
