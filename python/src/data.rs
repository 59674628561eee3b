//! `physid.Data`: a run held in memory (arrays a user already has), read through physid's data
//! pipeline as a logged file is, and taken wherever a data file is.

use crate::arrays::*;
use crate::errors::*;
use api::Logged;
use physid::api;
use physid::api::MemoryLog;
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

/// A run held in memory, as a robot logs it: positions and torques, velocities and
/// accelerations where logged (else derived by the pipeline, as for a file), time stamps or a
/// sample rate.
#[pyclass(frozen, module = "physid")]
#[derive(Clone)]
pub(crate) struct Data {
    /// What names the run in options and messages (its `name`, else `<arrays K>`).
    label: String,
    t: Vec<f64>,
    q: Vec<f64>,
    qd: Option<Vec<f64>>,
    qdd: Option<Vec<f64>>,
    tau: Vec<f64>,
    samples: usize,
    joints: usize,
}

/// Runs made in this process, for their default labels.
static MADE: AtomicUsize = AtomicUsize::new(0);

#[pymethods]
impl Data {
    /// A run from arrays: `q` (rad or m) and `tau` (N m or N) of shape `(samples, n)`, `qd`
    /// (rad/s) and `qdd` (rad/s²) likewise where logged (else derived, low-pass filtered at
    /// `cutoff` as for a file); `t` the time stamps (s, `(samples,)`) or `rate` the sample rate
    /// (Hz), one of them; `name` what messages call it (default `<arrays K>`).
    #[new]
    #[pyo3(signature = (q, tau, *, qd = None, qdd = None, t = None, rate = None, name = None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        q: &Bound<'_, PyAny>,
        tau: &Bound<'_, PyAny>,
        qd: Option<&Bound<'_, PyAny>>,
        qdd: Option<&Bound<'_, PyAny>>,
        t: Option<&Bound<'_, PyAny>>,
        rate: Option<f64>,
        name: Option<String>,
    ) -> PyResult<Self> {
        let q = table("q", q)?;
        let (samples, joints) = (q.samples, q.joints);
        let same = |what: &str, a: &Bound<'_, PyAny>| -> PyResult<Vec<f64>> {
            let v = table(what, a)?;
            if (v.samples, v.joints) != (samples, joints) {
                return Err(exception(format!(
                    "{what} has shape ({}, {}): q has shape ({samples}, {joints})",
                    v.samples, v.joints
                )));
            }
            Ok(v.values)
        };
        let data = Data {
            label: name
                .unwrap_or_else(|| format!("<arrays {}>", MADE.fetch_add(1, Ordering::SeqCst) + 1)),
            t: stamps(t, rate, samples)?,
            tau: same("tau", tau)?,
            qd: qd.map(|v| same("qd", v)).transpose()?,
            qdd: qdd.map(|v| same("qdd", v)).transpose()?,
            q: q.values,
            samples,
            joints,
        };
        Ok(data)
    }

    /// What names the run in options and messages.
    #[getter]
    fn name(&self) -> &str {
        &self.label
    }

    /// Number of samples.
    fn __len__(&self) -> usize {
        self.samples
    }

    fn __repr__(&self) -> String {
        let logged: Vec<&str> = [("qd", self.qd.is_some()), ("qdd", self.qdd.is_some())]
            .iter()
            .filter_map(|(k, there)| there.then_some(*k))
            .collect();
        format!(
            "Data('{}', {} samples of {} joints, q, tau{})",
            self.label,
            self.samples,
            self.joints,
            logged.iter().map(|k| format!(", {k}")).collect::<String>()
        )
    }
}

impl Data {
    /// The run as a log of `joint_names`' joints, for the data pipeline.
    fn log(&self, joint_names: &[String]) -> PyResult<MemoryLog> {
        if self.joints != joint_names.len() {
            return Err(exception(format!(
                "{}: {} joints (columns of q), the robot has {}",
                self.label,
                self.joints,
                joint_names.len()
            )));
        }
        Ok(MemoryLog {
            label: PathBuf::from(&self.label),
            logged: Logged {
                joint_names: joint_names.to_vec(),
                t: self.t.clone(),
                q: self.q.clone(),
                qd: self.qd.clone(),
                qdd: self.qdd.clone(),
                tau: self.tau.clone(),
            },
        })
    }
}

/// A keyword's runs: a path, a `Data`, or a list of them, as the paths that name them and the
/// runs held in memory among them (as logs of the robot's `joint_names`).
pub(crate) fn runs(
    what: &str,
    v: Option<&Bound<'_, PyAny>>,
    joint_names: &[String],
) -> PyResult<(Vec<PathBuf>, Vec<MemoryLog>)> {
    let Some(v) = v else {
        return Ok((vec![], vec![]));
    };
    let one = |x: &Bound<'_, PyAny>| -> PyResult<(PathBuf, Option<MemoryLog>)> {
        if let Ok(d) = x.downcast::<Data>() {
            let log = d.get().log(joint_names)?;
            return Ok((log.label.clone(), Some(log)));
        }
        x.extract::<PathBuf>().map(|p| (p, None)).map_err(|_| {
            exception(format!(
                "{what}: give a path, a physid.Data or a list of them"
            ))
        })
    };
    if v.hasattr("shape")? {
        return Err(exception(format!(
            "{what}: an array or table is not a run: hold arrays as physid.Data(q, tau, qd=…, qdd=…, t=… or rate=…)"
        )));
    }
    let single = v.is_instance_of::<Data>() || v.extract::<PathBuf>().is_ok();
    let items: Vec<Bound<'_, PyAny>> = match single {
        true => vec![v.clone()],
        false => v
            .try_iter()
            .map_err(|_| {
                exception(format!(
                    "{what}: give a path, a physid.Data or a list of them"
                ))
            })?
            .collect::<PyResult<_>>()?,
    };
    let (mut paths, mut logs) = (vec![], vec![]);
    for x in &items {
        let (path, log) = one(x)?;
        paths.push(path);
        logs.extend(log);
    }
    Ok((paths, logs))
}

/// The runs of several keywords (`(keyword, value)`, as [`runs`]): per keyword its paths, and
/// every run held in memory among them, for the reading options.
pub(crate) fn runs_of<const K: usize>(
    roles: [(&str, Option<&Bound<'_, PyAny>>); K],
    joint_names: &[String],
) -> PyResult<([Vec<PathBuf>; K], Vec<MemoryLog>)> {
    let mut memory = vec![];
    let mut paths: [Vec<PathBuf>; K] = std::array::from_fn(|_| vec![]);
    for ((what, v), out) in roles.into_iter().zip(&mut paths) {
        let (p, m) = runs(what, v, joint_names)?;
        *out = p;
        memory.extend(m);
    }
    Ok((paths, memory))
}

/// Time stamps from `t`, or from `rate` (Hz) as `k / rate`: one of them.
fn stamps(t: Option<&Bound<'_, PyAny>>, rate: Option<f64>, samples: usize) -> PyResult<Vec<f64>> {
    match (t, rate) {
        (Some(_), Some(_)) => Err(exception("give t (time stamps) or rate (Hz), not both")),
        (None, None) => Err(exception(
            "give t (time stamps, s) or rate (the sample rate, Hz)",
        )),
        (None, Some(r)) if !(r.is_finite() && r > 0.0) => Err(exception(format!(
            "rate must be a sample rate in Hz (finite, > 0), got {r}"
        ))),
        (None, Some(r)) => Ok((0..samples).map(|k| k as f64 / r).collect()),
        (Some(t), None) => {
            let t = vector("t", t)?;
            if t.len() != samples {
                return Err(exception(format!(
                    "t has {} time stamps for {samples} samples of q",
                    t.len()
                )));
            }
            Ok(t)
        }
    }
}
