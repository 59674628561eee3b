//! **Where** the residual lies: per joint and motion regime (near-zero velocity and reversals,
//! speed, acceleration and torque terciles, configuration quartiles), and over frequency (the
//! residual's spectrum and its coherence with the motion, [`super::spectrum`]).

use super::spectrum;
use physid_core::model::Model;
use physid_core::trajectory::Trajectory;
use serde::Serialize;

/// One regime of one joint.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema, PartialEq)]
pub struct Regime {
    /// Joint name.
    pub joint: String,
    /// Regime, e.g. `"|qd| low (<= 0.4 rad/s)"`.
    pub regime: String,
    /// Samples in the regime.
    pub samples: usize,
    /// RMS residual in the regime (N m).
    pub rms: f64,
    /// The regime's share of the joint's residual energy (0..1).
    pub share: f64,
}

/// Where a residual lies.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema, PartialEq)]
pub struct Breakdown {
    /// RMS residual per joint (N m).
    pub rms: Vec<f64>,
    /// RMS over all joints (N m).
    pub overall: f64,
    /// Regimes per joint.
    pub regimes: Vec<Regime>,
}

fn terciles(v: &[f64]) -> (f64, f64) {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let at = |f: f64| s[((s.len() - 1) as f64 * f).round() as usize];
    (at(1.0 / 3.0), at(2.0 / 3.0))
}

/// Breaks the residual `res` (sample-major, as from [`super::residuals`]) of samples `range` of `tr`
/// down per joint and regime. Regimes per joint: near-zero velocity (`|q̇|` below 5 % of its
/// peak), reversals (a velocity sign change within ±10 samples), `|q̇|`, `|q̈|` and `|τ|` in
/// terciles, and `q` in quartiles.
pub fn breakdown(tr: &Trajectory, range: std::ops::Range<usize>, res: &[f64]) -> Breakdown {
    let n = tr.dof();
    let m = range.len();
    assert_eq!(res.len(), m * n, "one residual per joint and sample");
    let mut regimes = vec![];
    let mut rms = vec![];
    for j in 0..n {
        let r: Vec<f64> = (0..m).map(|k| res[k * n + j]).collect();
        let mut sink = Regimes::new(&tr.joint_names[j], &r);
        rms.push((sink.energy / m.max(1) as f64).sqrt());
        let col = |f: &dyn Fn(usize) -> f64| (0..m).map(f).collect::<Vec<f64>>();
        let qd = col(&|k| tr.qd_at(range.start + k)[j]);
        let qdd = col(&|k| tr.qdd_at(range.start + k).map_or(0.0, |a| a[j]));
        let tau = col(&|k| tr.tau_at(range.start + k)[j]);
        let q = col(&|k| tr.q_at(range.start + k)[j]);
        sink.slow_and_reversing(&qd);
        for (name, v, unit) in [
            ("|qd|", &qd, "rad/s"),
            ("|qdd|", &qdd, "rad/s^2"),
            ("|tau|", &tau, "N m"),
        ] {
            sink.terciles(name, v, unit);
        }
        sink.quartiles(&q);
        regimes.extend(sink.out);
    }
    let overall = (res.iter().map(|x| x * x).sum::<f64>() / res.len().max(1) as f64).sqrt();
    Breakdown {
        rms,
        overall,
        regimes,
    }
}

/// One joint's residual `r` (N m per sample) split by regime.
struct Regimes<'a> {
    joint: &'a str,
    r: &'a [f64],
    /// `Σ r²`.
    energy: f64,
    out: Vec<Regime>,
}

impl<'a> Regimes<'a> {
    fn new(joint: &'a str, r: &'a [f64]) -> Self {
        let energy = r.iter().map(|x| x * x).sum();
        Regimes {
            joint,
            r,
            energy,
            out: vec![],
        }
    }

    /// The regime `name` of the samples `k` that are `member(k)`.
    fn add(&mut self, name: String, member: &dyn Fn(usize) -> bool) {
        let idx: Vec<usize> = (0..self.r.len()).filter(|&k| member(k)).collect();
        let e: f64 = idx.iter().map(|&k| self.r[k] * self.r[k]).sum();
        self.out.push(Regime {
            joint: self.joint.to_string(),
            regime: name,
            samples: idx.len(),
            rms: if idx.is_empty() {
                0.0
            } else {
                (e / idx.len() as f64).sqrt()
            },
            share: if self.energy > 0.0 {
                e / self.energy
            } else {
                0.0
            },
        });
    }

    /// Near-zero velocity (under 5 % of the peak `|q̇|`) and ±10 samples about a reversal.
    fn slow_and_reversing(&mut self, qd: &[f64]) {
        let m = qd.len();
        let peak = qd.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let slow = 0.05 * peak;
        self.add(
            format!("near-zero velocity (|qd| < {slow:.3} rad/s)"),
            &|k| qd[k].abs() < slow,
        );
        let flips: Vec<bool> = (0..m).map(|k| k > 0 && qd[k] * qd[k - 1] < 0.0).collect();
        self.add("velocity reversal (±10 samples)".into(), &|k| {
            flips[k.saturating_sub(10)..(k + 11).min(m)]
                .iter()
                .any(|f| *f)
        });
    }

    /// Low, mid and high thirds of `|v|` (`name`, in `unit`).
    fn terciles(&mut self, name: &str, v: &[f64], unit: &str) {
        let a: Vec<f64> = v.iter().map(|x| x.abs()).collect();
        let (t1, t2) = terciles(&a);
        self.add(format!("{name} low (<= {t1:.3} {unit})"), &|k| a[k] <= t1);
        self.add(format!("{name} mid"), &|k| a[k] > t1 && a[k] <= t2);
        self.add(format!("{name} high (> {t2:.3} {unit})"), &|k| a[k] > t2);
    }

    /// The four quartiles of the angle `q` (rad).
    fn quartiles(&mut self, q: &[f64]) {
        let m = q.len();
        let mut s = q.to_vec();
        s.sort_by(f64::total_cmp);
        for b in 0..4 {
            let (lo, hi) = quartile(&s, b);
            self.add(
                format!(
                    "q quartile {} ({:.3}..{:.3} rad)",
                    b + 1,
                    lo.max(s[0]),
                    hi.min(s[m - 1])
                ),
                &|k| q[k] > lo && q[k] <= hi,
            );
        }
    }
}

/// The bounds of quartile `b` (0 to 3) of `sorted` values, the cuts at the sorted values a
/// quarter, half and three quarters in: open below the first quartile, above the last.
fn quartile(sorted: &[f64], b: usize) -> (f64, f64) {
    let cut = |i: usize| sorted[(sorted.len() - 1) * i / 4];
    let lo = if b == 0 { f64::NEG_INFINITY } else { cut(b) };
    let hi = if b == 3 { f64::INFINITY } else { cut(b + 1) };
    (lo, hi)
}

/// Spectra of a residual per joint with the coherence signals of `tr`.
pub(crate) fn spectra(model: &Model, tr: &Trajectory, res: &[f64]) -> Vec<spectrum::Spectrum> {
    let n = tr.dof();
    let m = tr.len();
    let fs = tr.sample_rate().unwrap_or(1.0);
    (0..n)
        .map(|j| {
            let col = |f: &dyn Fn(usize) -> f64| (0..m).map(f).collect::<Vec<f64>>();
            let gear = model.bodies()[j]
                .rotor
                .as_ref()
                .map_or(1.0, |r| r.gear_ratio);
            let signals = vec![
                ("q".to_string(), col(&|k| tr.q_at(k)[j])),
                ("qd".to_string(), col(&|k| tr.qd_at(k)[j])),
                (
                    "qdd".to_string(),
                    col(&|k| tr.qdd_at(k).map_or(0.0, |a| a[j])),
                ),
                (
                    "sin(N q)".to_string(),
                    col(&|k| (gear * tr.q_at(k)[j]).sin()),
                ),
            ];
            spectrum::spectrum(&tr.joint_names[j], &col(&|k| res[k * n + j]), &signals, fs)
        })
        .collect()
}
