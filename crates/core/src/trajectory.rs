//! Joint data sampled in time: the [`Trajectory`] every floor above reads and writes, the
//! [`Recording`] of one simulated experiment, and the operations on them that must have one
//! definition (sample period, hold-out split, concatenation of runs).
//!
//! Floor 1 (architecture.md §6): imports nothing from physid.

/// Joint data sampled in time, stored sample-major (`q[k * n + j]`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Trajectory {
    /// Joint names (length `n`).
    pub joint_names: Vec<String>,
    /// Sample times (s), increasing.
    pub t: Vec<f64>,
    /// Positions (rad).
    pub q: Vec<f64>,
    /// Velocities (rad/s).
    pub qd: Vec<f64>,
    /// Accelerations (rad/s²), if known.
    pub qdd: Option<Vec<f64>>,
    /// Joint torques (N m).
    pub tau: Vec<f64>,
    /// The samples that begin a new run (increasing, within `1..len`): runs joined end to end
    /// ([`Self::concatenate`]) or a log split at a time jump. No signal is differentiated,
    /// filtered or delayed across them ([`Self::runs`]); empty for one run.
    pub starts: Vec<usize>,
    /// Per run ([`Self::runs`], in order), the logged torque the run continues with beyond its
    /// ends: samples the data's processing saw but this trajectory does not hold (the
    /// pipeline's trimmed filter settling, the other side of a cut by [`Self::slice`]). Empty
    /// (or shorter than the runs) where nothing is known.
    pub margins: Vec<Margins>,
}

/// The logged torque (N m, sample-major, at the trajectory's sample period) of one run beyond
/// its ends. A signal processed over the run (the diagnosis filters and differentiates the
/// torque as the encoder angle was) then continues across its ends as the data's own processing
/// did, instead of starting afresh at them.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Margins {
    /// Torques before the run's first sample, ending at the sample just before it.
    pub before: Vec<f64>,
    /// Torques after the run's last sample, starting at the sample just after it.
    pub after: Vec<f64>,
}

/// A bad sample, naming its index and field.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SampleError {
    /// A non-finite value.
    #[error("sample {sample} (t = {t} s): {field} is {value}")]
    NotFinite {
        /// Sample index (0-based).
        sample: usize,
        /// Its time stamp.
        t: f64,
        /// e.g. `q2`.
        field: String,
        /// The value.
        value: f64,
    },
    /// Time does not increase.
    #[error("sample {sample}: time {t} s does not increase (previous {previous} s)")]
    NonMonotonicTime {
        /// Sample index.
        sample: usize,
        /// Its time.
        t: f64,
        /// The previous time.
        previous: f64,
    },
    /// A value too large to be a measurement of a robot.
    #[error("sample {sample} (t = {t} s): {field} is {value:e}, beyond the ±{limit:e} that a {quantity} can be")]
    OutOfRange {
        /// Sample index (0-based).
        sample: usize,
        /// Its time stamp.
        t: f64,
        /// e.g. `tau2`.
        field: String,
        /// The value.
        value: f64,
        /// The bound ([`max_abs`]).
        limit: f64,
        /// What the field measures.
        quantity: &'static str,
    },
    /// No samples at all.
    #[error("no samples")]
    Empty,
    /// Run starts out of order or outside the samples.
    #[error("{0}")]
    RunStarts(String),
    /// A margin ([`Margins`]) that is not whole samples.
    #[error("{field} has {got} values, not whole samples of {n} joints")]
    Margin {
        /// `margins.before` or `margins.after`.
        field: &'static str,
        /// Its length.
        got: usize,
        /// The joints.
        n: usize,
    },
    /// Inconsistent array lengths.
    #[error("{field} has {got} values, expected {expected}")]
    Length {
        /// The array.
        field: &'static str,
        /// Its length.
        got: usize,
        /// The expected length.
        expected: usize,
    },
}

/// The largest magnitude a sample value of `field` (`t`, `q`, `dq`, `ddq`, `tau`) may have, and
/// what it measures: beyond these a value is not a measurement of a robot (10⁶ rad of travel,
/// 10⁵ rad/s, 10⁷ rad/s², 10⁷ N m; 10¹² s), and its square would swamp or overflow the sums of
/// the normal equations.
pub fn max_abs(field: &str) -> (f64, &'static str) {
    match field {
        "t" => (1e12, "time stamp (s)"),
        "q" => (1e6, "joint position (rad or m)"),
        "dq" => (1e5, "joint velocity (rad/s or m/s)"),
        "ddq" => (1e7, "joint acceleration (rad/s² or m/s²)"),
        _ => (1e7, "joint torque (N m or N)"),
    }
}

/// Checks one value of sample `sample`: finite, and within [`max_abs`] of its field `group`
/// (`name` is what errors call it, e.g. `tau2`).
pub fn check_value(
    sample: usize,
    t: f64,
    group: &str,
    name: &str,
    value: f64,
) -> Result<(), SampleError> {
    if !value.is_finite() {
        return Err(SampleError::NotFinite {
            sample,
            t,
            field: name.to_string(),
            value,
        });
    }
    let (limit, quantity) = max_abs(group);
    if value.abs() > limit {
        return Err(SampleError::OutOfRange {
            sample,
            t,
            field: name.to_string(),
            value,
            limit,
            quantity,
        });
    }
    Ok(())
}

impl Trajectory {
    /// An empty trajectory for `joint_names`.
    pub fn new(joint_names: Vec<String>, with_qdd: bool) -> Self {
        Self {
            joint_names,
            t: vec![],
            q: vec![],
            qd: vec![],
            qdd: with_qdd.then(Vec::new),
            tau: vec![],
            starts: vec![],
            margins: vec![],
        }
    }
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
    /// An empty trajectory for `joint_names` with room for `samples` samples (pushing them
    /// does not reallocate).
    pub fn with_capacity(joint_names: Vec<String>, with_qdd: bool, samples: usize) -> Self {
        let values = samples * joint_names.len();
        Self {
            t: Vec::with_capacity(samples),
            q: Vec::with_capacity(values),
            qd: Vec::with_capacity(values),
            qdd: with_qdd.then(|| Vec::with_capacity(values)),
            tau: Vec::with_capacity(values),
            ..Self::new(joint_names, with_qdd)
        }
    }
    /// Appends one sample.
    pub fn push(&mut self, t: f64, q: &[f64], qd: &[f64], qdd: Option<&[f64]>, tau: &[f64]) {
        self.t.push(t);
        self.q.extend_from_slice(q);
        self.qd.extend_from_slice(qd);
        if let (Some(v), Some(a)) = (self.qdd.as_mut(), qdd) {
            v.extend_from_slice(a);
        }
        self.tau.extend_from_slice(tau);
    }
    fn row<'a>(&self, v: &'a [f64], k: usize) -> &'a [f64] {
        let n = self.dof();
        &v[k * n..(k + 1) * n]
    }
    /// Positions of sample `k`.
    pub fn q_at(&self, k: usize) -> &[f64] {
        self.row(&self.q, k)
    }
    /// Velocities of sample `k`.
    pub fn qd_at(&self, k: usize) -> &[f64] {
        self.row(&self.qd, k)
    }
    /// Accelerations of sample `k`, if present.
    pub fn qdd_at(&self, k: usize) -> Option<&[f64]> {
        self.qdd.as_ref().map(|v| self.row(v, k))
    }
    /// Torques of sample `k`.
    pub fn tau_at(&self, k: usize) -> &[f64] {
        self.row(&self.tau, k)
    }
    /// Samples `range` as a new trajectory (with the run starts inside it). Each run keeps
    /// the torque of its run beyond the cut as its [`Margins`], after the run's own.
    pub fn slice(&self, range: std::ops::Range<usize>) -> Trajectory {
        let n = self.dof();
        let cut = |v: &Vec<f64>| v[range.start * n..range.end * n].to_vec();
        let tau = |r: std::ops::Range<usize>| &self.tau[r.start * n..r.end * n];
        let margins = self
            .runs()
            .into_iter()
            .enumerate()
            .filter(|(_, r)| r.start < range.end && range.start < r.end)
            .map(|(i, r)| {
                let own = self.margin(i);
                let (a, b) = (r.start.max(range.start), r.end.min(range.end));
                Margins {
                    before: [&own.before[..], tau(r.start..a)].concat(),
                    after: [tau(b..r.end), &own.after[..]].concat(),
                }
            })
            .collect();
        Trajectory {
            joint_names: self.joint_names.clone(),
            t: self.t[range.clone()].to_vec(),
            q: cut(&self.q),
            qd: cut(&self.qd),
            qdd: self.qdd.as_ref().map(cut),
            tau: cut(&self.tau),
            starts: self
                .starts
                .iter()
                .filter(|&&s| s > range.start && s < range.end)
                .map(|s| s - range.start)
                .collect(),
            margins: Self::known(margins),
        }
    }

    /// Run `i`'s [`Margins`] (empty when none are known).
    pub fn margin(&self, i: usize) -> Margins {
        self.margins.get(i).cloned().unwrap_or_default()
    }

    /// `margins`, or none when every one is empty.
    fn known(margins: Vec<Margins>) -> Vec<Margins> {
        let empty = |m: &Margins| m.before.is_empty() && m.after.is_empty();
        if margins.iter().all(empty) {
            vec![]
        } else {
            margins
        }
    }

    /// The runs: consecutive sample ranges between the run starts ([`Self::starts`]), covering
    /// every sample; one range for one run, none without samples.
    pub fn runs(&self) -> Vec<std::ops::Range<usize>> {
        let m = self.len();
        let mut bounds = vec![0];
        bounds.extend(self.starts.iter().copied().filter(|&s| s > 0 && s < m));
        bounds.push(m);
        bounds
            .windows(2)
            .filter(|w| w[1] > w[0])
            .map(|w| w[0]..w[1])
            .collect()
    }

    /// At most one margin per run, each whole samples of `n` joints.
    fn validate_margins(&self) -> Result<(), SampleError> {
        let (runs, n) = (self.runs().len(), self.dof());
        if self.margins.len() > runs {
            return Err(SampleError::RunStarts(format!(
                "{} margins for {runs} runs",
                self.margins.len()
            )));
        }
        for m in &self.margins {
            for (field, v) in [("margins.before", &m.before), ("margins.after", &m.after)] {
                if v.len() % n.max(1) != 0 {
                    return Err(SampleError::Margin {
                        field,
                        got: v.len(),
                        n,
                    });
                }
            }
        }
        Ok(())
    }

    /// Checks lengths, increasing time, and every value finite and within [`max_abs`], naming
    /// the first bad sample.
    pub fn validate(&self) -> Result<(), SampleError> {
        let (m, n) = (self.len(), self.dof());
        if m == 0 {
            return Err(SampleError::Empty);
        }
        let arrays: [(&'static str, Option<&Vec<f64>>); 4] = [
            ("q", Some(&self.q)),
            ("qd", Some(&self.qd)),
            ("qdd", self.qdd.as_ref()),
            ("tau", Some(&self.tau)),
        ];
        for (field, v) in arrays {
            if let Some(v) = v {
                if v.len() != m * n {
                    return Err(SampleError::Length {
                        field,
                        got: v.len(),
                        expected: m * n,
                    });
                }
            }
        }
        self.validate_margins()?;
        if let Some(w) = self.starts.windows(2).find(|w| w[1] <= w[0]) {
            return Err(SampleError::RunStarts(format!(
                "run starts {} and {} do not increase",
                w[0], w[1]
            )));
        }
        if let Some(s) = self.starts.iter().find(|&&s| s == 0 || s >= m) {
            return Err(SampleError::RunStarts(format!(
                "a run starts at sample {s}, outside 1..{m}"
            )));
        }
        for k in 0..m {
            let t = self.t[k];
            check_value(k, t, "t", "t", t)?;
            if k > 0 && t <= self.t[k - 1] {
                return Err(SampleError::NonMonotonicTime {
                    sample: k,
                    t,
                    previous: self.t[k - 1],
                });
            }
            for (name, v) in [
                ("q", Some(&self.q)),
                ("dq", Some(&self.qd)),
                ("ddq", self.qdd.as_ref()),
                ("tau", Some(&self.tau)),
            ] {
                if let Some(v) = v {
                    for j in 0..n {
                        check_value(k, t, name, &format!("{name}{}", j + 1), v[k * n + j])?;
                    }
                }
            }
        }
        Ok(())
    }

    /// Mean sample period (s) from the first and last time stamps, `None` with fewer than two
    /// samples. The one definition of a trajectory's sampling used by every analysis.
    pub fn sample_period(&self) -> Option<f64> {
        let m = self.len();
        (m > 1).then(|| (self.t[m - 1] - self.t[0]) / (m - 1) as f64)
    }

    /// Mean sample rate (Hz): samples per second between the first and last time stamps, the
    /// reciprocal of [`Self::sample_period`] (computed directly, as `(m − 1) / span`).
    pub fn sample_rate(&self) -> Option<f64> {
        let m = self.len();
        (m > 1).then(|| (m - 1) as f64 / (self.t[m - 1] - self.t[0]))
    }

    /// The same samples with the joints in the order of `names`, every one of which the
    /// trajectory must have (`Err` names the first it lacks); joints not named are dropped.
    pub fn with_joints(&self, names: &[String]) -> Result<Trajectory, String> {
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
        let pick_rows = |v: &[f64]| -> Vec<f64> {
            v.chunks(n.max(1))
                .flat_map(|row| columns.iter().map(move |&j| row[j]))
                .collect()
        };
        let pick = |v: &Vec<f64>| -> Vec<f64> { pick_rows(&v[..m * n]) };
        Ok(Trajectory {
            joint_names: names.to_vec(),
            t: self.t.clone(),
            q: pick(&self.q),
            qd: pick(&self.qd),
            qdd: self.qdd.as_ref().map(pick),
            tau: pick(&self.tau),
            starts: self.starts.clone(),
            margins: self
                .margins
                .iter()
                .map(|m| Margins {
                    before: pick_rows(&m.before),
                    after: pick_rows(&m.after),
                })
                .collect(),
        })
    }

    /// Splits into the first `1 − holdout` of the samples (training) and the last `holdout`
    /// (validation), `holdout` in (0, 1); the run the cut falls in continues in each part's
    /// [`Margins`] ([`Self::slice`]).
    pub fn holdout_split(&self, holdout: f64) -> (Trajectory, Trajectory) {
        let cut = ((1.0 - holdout) * self.len() as f64).round() as usize;
        (self.slice(0..cut), self.slice(cut..self.len()))
    }

    /// Joins runs end to end; each run's times are shifted to continue the joined ones by their
    /// mean sample period, or the next run's when the joined ones are a single sample (1 ms
    /// only between two single samples, which no analysis uses: identification and the
    /// diagnosis need many). Each part's first sample becomes a run start ([`Self::starts`]),
    /// and its own starts are kept. `None` for no runs.
    /// Each run keeps its [`Margins`].
    pub fn concatenate(parts: Vec<Trajectory>) -> Option<Trajectory> {
        let mut it = parts.into_iter();
        let mut out = it.next()?;
        for p in it {
            let m = out.len();
            if m == 0 {
                out = p;
                continue;
            }
            if !p.is_empty() {
                let both = (0..out.runs().len()).map(|i| out.margin(i));
                let both = both.chain((0..p.runs().len()).map(|i| p.margin(i)));
                out.margins = Self::known(both.collect());
            }
            let dt = out
                .sample_period()
                .or_else(|| p.sample_period())
                .unwrap_or(1e-3);
            let shift = out.t[m - 1] + dt - p.t[0];
            if !p.is_empty() {
                out.starts.push(m);
                out.starts.extend(p.starts.iter().map(|s| s + m));
            }
            for k in 0..p.len() {
                out.push(
                    p.t[k] + shift,
                    p.q_at(k),
                    p.qd_at(k),
                    p.qdd_at(k),
                    p.tau_at(k),
                );
            }
        }
        Some(out)
    }
}

/// One sample while streaming (a file read sample by sample, so that memory does not grow
/// with its length): units as in [`Trajectory`].
pub struct SampleRef<'a> {
    /// Time (s).
    pub t: f64,
    /// Positions.
    pub q: &'a [f64],
    /// Velocities.
    pub qd: &'a [f64],
    /// Accelerations.
    pub qdd: &'a [f64],
    /// Torques.
    pub tau: &'a [f64],
}

/// The groups of a packed sample ([`SampleRef::packed`]), as a checked value names them.
pub const SAMPLE_GROUPS: [&str; 4] = ["q", "dq", "ddq", "tau"];

impl<'a> SampleRef<'a> {
    /// The sample at time `t` (s) whose values are packed joint by joint in the groups
    /// [`SAMPLE_GROUPS`]: `[q | q̇ | q̈ | τ]`, a quarter of `values` each (what a reader fills
    /// one sample at a time).
    pub fn packed(t: f64, values: &'a [f64]) -> Self {
        let n = values.len() / 4;
        Self {
            t,
            q: &values[..n],
            qd: &values[n..2 * n],
            qdd: &values[2 * n..3 * n],
            tau: &values[3 * n..4 * n],
        }
    }
}

/// A source of samples given one at a time: called with a sink, it passes each sample to it
/// as `(index, sample)` and returns the source's total sample count. A CSV streamed from disk is
/// one (`io::samples::stream_csv`); a [`Trajectory`] is another ([`Trajectory::stream`]).
pub type SampleSink<'s> = dyn FnMut(usize, &SampleRef) + 's;

impl Trajectory {
    /// Passes samples `range` (which must carry q̈) to `sink` one at a time; returns the
    /// trajectory's length. The in-memory counterpart of a streamed file.
    pub fn stream(&self, range: std::ops::Range<usize>, sink: &mut SampleSink) -> usize {
        let qdd = self
            .qdd
            .as_ref()
            .expect("streamed samples carry accelerations");
        let n = self.dof();
        for k in range {
            let sample = SampleRef {
                t: self.t[k],
                q: self.q_at(k),
                qd: self.qd_at(k),
                qdd: &qdd[k * n..(k + 1) * n],
                tau: self.tau_at(k),
            };
            sink(k, &sample);
        }
        self.len()
    }
}

/// Everything one simulated experiment produces.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Recording {
    /// True state, accelerations and the torque the actuators delivered (τ_mot).
    pub truth: Trajectory,
    /// True friction torque per sample (N m, sample-major).
    pub friction: Vec<f64>,
    /// True torque of the injected physical effects per sample (N m, sample-major).
    pub effects: Vec<f64>,
    /// What the robot logs: encoder positions, the controller's velocity, its difference as
    /// acceleration, and the logged torque.
    pub measured: Trajectory,
    /// Offline-processed q, q̇, q̈ and torque: the identification input.
    pub processed: Trajectory,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(t0: f64, m: usize, dt: f64) -> Trajectory {
        let mut tr = Trajectory::new(vec!["j".into()], false);
        for k in 0..m {
            tr.push(t0 + k as f64 * dt, &[0.0], &[0.0], None, &[0.0]);
        }
        tr
    }

    fn close(a: &[f64], b: &[f64]) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12)
    }

    #[test]
    fn a_single_sample_run_is_continued_at_the_next_run_s_period() {
        let joined = Trajectory::concatenate(vec![run(5.0, 1, 0.0), run(9.0, 3, 2e-3)]).unwrap();
        assert!(
            close(&joined.t, &[5.0, 5.002, 5.004, 5.006]),
            "{:?}",
            joined.t
        );
        // The joined runs' own period when they have one.
        let joined = Trajectory::concatenate(vec![run(0.0, 2, 1e-2), run(3.0, 2, 2e-3)]).unwrap();
        assert!(
            close(&joined.t, &[0.0, 0.01, 0.02, 0.022]),
            "{:?}",
            joined.t
        );
    }

    #[test]
    fn run_starts_follow_concatenation_slicing_and_splitting() {
        let joined = Trajectory::concatenate(vec![
            run(0.0, 3, 1e-2),
            run(7.0, 2, 1e-2),
            run(9.0, 4, 1e-2),
        ])
        .unwrap();
        assert_eq!(joined.starts, vec![3, 5]);
        assert_eq!(joined.runs(), vec![0..3, 3..5, 5..9]);
        assert_eq!(joined.validate(), Ok(()));
        // A slice keeps the starts strictly inside it, shifted; a cut at a start drops it.
        assert_eq!(joined.slice(2..7).starts, vec![1, 3]);
        assert_eq!(joined.slice(3..9).runs(), vec![0..2, 2..6]);
        let (train, validate) = joined.holdout_split(0.4);
        assert_eq!(train.runs(), [0..3, 3..5]);
        assert_eq!(validate.runs(), std::iter::once(0..4).collect::<Vec<_>>());
        let (train, validate) = joined.holdout_split(0.6);
        assert_eq!(
            (train.runs(), validate.runs()),
            (vec![0..3, 3..4], vec![0..1, 1..5])
        );
        // Joining joined data keeps the inner starts.
        let twice = Trajectory::concatenate(vec![joined.clone(), joined.clone()]).unwrap();
        assert_eq!(twice.starts, vec![3, 5, 9, 12, 14]);
        // Bad starts are named.
        let mut bad = joined.clone();
        bad.starts = vec![5, 3];
        assert!(bad
            .validate()
            .unwrap_err()
            .to_string()
            .contains("do not increase"));
        bad.starts = vec![9];
        assert!(bad
            .validate()
            .unwrap_err()
            .to_string()
            .contains("outside 1..9"));
        assert_eq!(
            run(0.0, 0, 1e-2).runs(),
            Vec::<std::ops::Range<usize>>::new()
        );
    }

    /// One joint's run whose torque counts its samples from `first`.
    fn counted(first: usize, m: usize) -> Trajectory {
        let mut tr = Trajectory::new(vec!["j".into()], false);
        for k in 0..m {
            tr.push(k as f64 * 1e-2, &[0.0], &[0.0], None, &[(first + k) as f64]);
        }
        tr
    }

    #[test]
    fn a_cut_run_keeps_the_torque_beyond_each_part_as_its_margins() {
        // Runs of 3, 2 and 5 samples, torques 0..10 in order.
        let joined =
            Trajectory::concatenate(vec![counted(0, 3), counted(3, 2), counted(5, 5)]).unwrap();
        assert_eq!(joined.margins, vec![]);
        let m = |before: &[f64], after: &[f64]| Margins {
            before: before.to_vec(),
            after: after.to_vec(),
        };
        // The cut at sample 7 falls in the last run (5..10).
        let (train, val) = joined.holdout_split(0.3);
        assert_eq!(
            train.margins,
            vec![m(&[], &[]), m(&[], &[]), m(&[], &[7.0, 8.0, 9.0])]
        );
        assert_eq!(val.margins, vec![m(&[5.0, 6.0], &[])]);
        // Cut again, each part keeps the run's own margins at the ends that reach them.
        let (a, b) = val.holdout_split(0.34);
        assert_eq!((a.tau.clone(), b.tau.clone()), (vec![7.0, 8.0], vec![9.0]));
        assert_eq!(a.margins, vec![m(&[5.0, 6.0], &[9.0])]);
        assert_eq!(b.margins, vec![m(&[5.0, 6.0, 7.0, 8.0], &[])]);
        // A cut at a run start: a run's true end is no margin.
        let (a, b) = train.holdout_split(0.3);
        assert_eq!(a.tau, vec![0.0, 1.0, 2.0, 3.0, 4.0]);
        assert_eq!(
            (a.margins.clone(), b.margins.clone()),
            (vec![], vec![m(&[], &[7.0, 8.0, 9.0])])
        );
        // Joined, each run keeps its own.
        let both = Trajectory::concatenate(vec![val.clone(), train.clone()]).unwrap();
        assert_eq!(both.margin(0), m(&[5.0, 6.0], &[]));
        assert_eq!(both.margin(3), m(&[], &[7.0, 8.0, 9.0]));
        assert_eq!(both.validate(), Ok(()));
        // Choosing joints chooses the margins' columns; bad margins are named.
        let mut two = Trajectory::new(vec!["a".into(), "b".into()], false);
        two.push(0.0, &[0.0, 0.0], &[0.0, 0.0], None, &[1.0, 2.0]);
        two.margins = vec![m(&[3.0, 4.0, 5.0, 6.0], &[])];
        let b_only = two.with_joints(&["b".to_string()]).unwrap();
        assert_eq!(b_only.margins, vec![m(&[4.0, 6.0], &[])]);
        two.margins[0].after = vec![1.0];
        assert_eq!(
            two.validate().unwrap_err().to_string(),
            "margins.after has 1 values, not whole samples of 2 joints"
        );
        two.margins = vec![m(&[], &[]), m(&[], &[])];
        assert_eq!(
            two.validate().unwrap_err().to_string(),
            "2 margins for 1 runs"
        );
    }
}
