//! Offline signal processing for the measurement pipeline: Butterworth low-pass filters as
//! second-order sections, zero-phase (forward–backward) filtering, and finite differences.
//!
//! Written here (about a hundred lines) rather than pulling in a signal-processing crate that
//! would bring a second linear-algebra stack; tested against published coefficients and the
//! defining properties (unit DC gain, −3 dB at the cutoff per pass, zero phase).

use std::f64::consts::PI;

/// One biquad `H(z) = (b0 + b1 z⁻¹ + b2 z⁻²) / (1 + a1 z⁻¹ + a2 z⁻²)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Biquad {
    /// Numerator `[b0, b1, b2]`.
    pub b: [f64; 3],
    /// Denominator `[a1, a2]` (`a0 = 1`).
    pub a: [f64; 2],
}

impl Biquad {
    /// DC gain `H(1)`.
    pub fn dc_gain(&self) -> f64 {
        (self.b[0] + self.b[1] + self.b[2]) / (1.0 + self.a[0] + self.a[1])
    }

    /// Magnitude of the frequency response at `f / fs` (cycles per sample).
    pub fn gain_at(&self, f_over_fs: f64) -> f64 {
        let w = 2.0 * PI * f_over_fs;
        let z1 = num_complex(-w);
        let z2 = num_complex(-2.0 * w);
        let num = add3(self.b[0], mul(self.b[1], z1), mul(self.b[2], z2));
        let den = add3(1.0, mul(self.a[0], z1), mul(self.a[1], z2));
        (num.0.hypot(num.1)) / (den.0.hypot(den.1))
    }
}

fn num_complex(angle: f64) -> (f64, f64) {
    (angle.cos(), angle.sin())
}
fn mul(s: f64, z: (f64, f64)) -> (f64, f64) {
    (s * z.0, s * z.1)
}
fn add3(a: f64, b: (f64, f64), c: (f64, f64)) -> (f64, f64) {
    (a + b.0 + c.0, b.1 + c.1)
}

/// A cascade of biquads.
#[derive(Clone, Debug, PartialEq)]
pub struct Sos(pub Vec<Biquad>);

/// Errors in a filter specification.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FilterError {
    /// The cutoff is not strictly between 0 and the Nyquist frequency.
    #[error(
        "cutoff {cutoff} Hz must lie strictly between 0 and the Nyquist frequency {nyquist} Hz"
    )]
    Cutoff {
        /// Requested cutoff (Hz).
        cutoff: f64,
        /// Half the sample rate (Hz).
        nyquist: f64,
    },
    /// Order outside 1..=8.
    #[error("filter order {0} must be between 1 and 8")]
    Order(usize),
}

/// A digital Butterworth low-pass of `order` with cutoff `fc` (Hz) at sample rate `fs` (Hz),
/// by the bilinear transform with pre-warping; each section has unit DC gain.
pub fn butterworth_lowpass(order: usize, fc: f64, fs: f64) -> Result<Sos, FilterError> {
    if !(1..=8).contains(&order) {
        return Err(FilterError::Order(order));
    }
    if !(fc > 0.0 && fc < 0.5 * fs) {
        return Err(FilterError::Cutoff {
            cutoff: fc,
            nyquist: 0.5 * fs,
        });
    }
    let wc = 2.0 * fs * (PI * fc / fs).tan(); // pre-warped analog cutoff (rad/s)
    let k = 2.0 * fs;
    let mut sections = vec![];
    // Analog poles s = wc e^{iπ(2m + N + 1)/(2N)}, m = 0..N−1; take the upper half-plane ones
    // (and the real one for odd N), each mapped by z = (k + s)/(k − s).
    for m in 0..order.div_ceil(2) {
        let theta = PI * (2 * m + order + 1) as f64 / (2 * order) as f64;
        let (sr, si) = (wc * theta.cos(), wc * theta.sin());
        let real_pole = si.abs() < 1e-12 * wc;
        // z = (k + s) / (k − s), complex division.
        let (nr, ni, dr, di) = (k + sr, si, k - sr, -si);
        let den = dr * dr + di * di;
        let (zr, zi) = ((nr * dr + ni * di) / den, (ni * dr - nr * di) / den);
        let bq = if real_pole {
            Biquad {
                b: [1.0, 1.0, 0.0],
                a: [-zr, 0.0],
            }
        } else {
            Biquad {
                b: [1.0, 2.0, 1.0],
                a: [-2.0 * zr, zr * zr + zi * zi],
            }
        };
        let g = 1.0 / bq.dc_gain();
        sections.push(Biquad {
            b: bq.b.map(|x| x * g),
            a: bq.a,
        });
    }
    Ok(Sos(sections))
}

impl Sos {
    /// Causal filtering (direct form II transposed), starting from the steady state of a
    /// constant input equal to `x[0]`.
    pub fn filter(&self, x: &[f64]) -> Vec<f64> {
        let mut y = x.to_vec();
        for s in &self.0 {
            let x0 = y.first().copied().unwrap_or(0.0);
            // Steady state for constant input x0 with output g x0.
            let g = s.dc_gain();
            let mut z2 = (s.b[2] - s.a[1] * g) * x0;
            let mut z1 = (s.b[1] - s.a[0] * g) * x0 + z2;
            for v in y.iter_mut() {
                let xin = *v;
                let out = s.b[0] * xin + z1;
                z1 = s.b[1] * xin - s.a[0] * out + z2;
                z2 = s.b[2] * xin - s.a[1] * out;
                *v = out;
            }
        }
        y
    }

    /// The slowest pole's time constant in samples, `−1 / ln |z|max`.
    pub fn time_constant(&self) -> f64 {
        let rmax = self
            .0
            .iter()
            .map(|s| {
                let disc = s.a[0] * s.a[0] - 4.0 * s.a[1];
                if disc < 0.0 {
                    s.a[1].sqrt() // complex pair: |z|² = a2
                } else {
                    let r = disc.sqrt();
                    (0.5 * (-s.a[0] + r)).abs().max((0.5 * (-s.a[0] - r)).abs())
                }
            })
            .fold(0.0f64, f64::max);
        if rmax <= 0.0 {
            0.0
        } else {
            -1.0 / rmax.ln()
        }
    }

    /// Zero-phase filtering: odd extension at each end, then forward and backward passes (the
    /// magnitude response squared, no phase shift), as scipy's `sosfiltfilt`, but padded by 25
    /// time constants of the slowest pole (at least `3 (2 n_sections + 1)` samples) so the
    /// start-up transient has decayed to ~1e-11 before the data begin: a ramp passes unchanged
    /// up to the last sample. Signals shorter than that are padded as far as possible.
    pub fn filtfilt(&self, x: &[f64]) -> Vec<f64> {
        let n = x.len();
        if n < 2 {
            return x.to_vec();
        }
        let by_tau = (25.0 * self.time_constant()).ceil() as usize;
        let pad = by_tau.max(3 * (2 * self.0.len() + 1)).min(n - 1);
        let mut ext = Vec::with_capacity(n + 2 * pad);
        ext.extend((1..=pad).rev().map(|i| 2.0 * x[0] - x[i]));
        ext.extend_from_slice(x);
        ext.extend((1..=pad).map(|i| 2.0 * x[n - 1] - x[n - 1 - i]));
        let mut y = self.filter(&ext);
        y.reverse();
        let mut y = self.filter(&y);
        y.reverse();
        y[pad..pad + n].to_vec()
    }
}

/// Derivative of uniformly sampled `x` (step `h`): central differences inside, second-order
/// one-sided differences at both ends.
pub fn differentiate(x: &[f64], h: f64) -> Vec<f64> {
    let n = x.len();
    match n {
        0 => vec![],
        1 => vec![0.0],
        2 => vec![(x[1] - x[0]) / h; 2],
        _ => (0..n)
            .map(|k| {
                if k == 0 {
                    (-3.0 * x[0] + 4.0 * x[1] - x[2]) / (2.0 * h)
                } else if k == n - 1 {
                    (3.0 * x[n - 1] - 4.0 * x[n - 2] + x[n - 3]) / (2.0 * h)
                } else {
                    (x[k + 1] - x[k - 1]) / (2.0 * h)
                }
            })
            .collect(),
    }
}

/// Cutoff (Hz) of the low-pass applied when accelerations are derived from velocities.
pub const DERIVED_QDD_CUTOFF: f64 = 20.0;

/// Accelerations of sample-major velocities `qd` (`n` columns, step `dt` s): the zero-phase
/// 2nd-order Butterworth at [`DERIVED_QDD_CUTOFF`] (at most 0.4 of the sample rate) of the
/// central difference, per joint.
pub fn derive_acceleration(qd: &[f64], n: usize, dt: f64) -> Result<Vec<f64>, FilterError> {
    let fs = 1.0 / dt;
    let sos = butterworth_lowpass(2, DERIVED_QDD_CUTOFF.min(0.4 * fs), fs)?;
    let m = qd.len().checked_div(n).unwrap_or(0);
    let mut qdd = vec![0.0; m * n];
    for j in 0..n {
        let column: Vec<f64> = (0..m).map(|k| qd[k * n + j]).collect();
        for (k, v) in sos
            .filtfilt(&differentiate(&column, dt))
            .into_iter()
            .enumerate()
        {
            qdd[k * n + j] = v;
        }
    }
    Ok(qdd)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn second_order_coefficients_match_the_published_design() {
        // scipy.signal.butter(2, 0.2) (cutoff 0.1 fs): b = [0.06745527, 0.13491055, 0.06745527],
        // a = [1, -1.1429805, 0.4128016].
        let s = butterworth_lowpass(2, 100.0, 1000.0).unwrap();
        assert_eq!(s.0.len(), 1);
        let q = s.0[0];
        for (got, want) in q.b.iter().zip([0.06745527, 0.13491055, 0.06745527]) {
            assert!((got - want).abs() < 1e-8, "{q:?}");
        }
        assert!(
            (q.a[0] + 1.1429805).abs() < 1e-7 && (q.a[1] - 0.4128016).abs() < 1e-7,
            "{q:?}"
        );
    }

    #[test]
    fn butterworth_is_minus_3db_at_cutoff_and_flat_at_dc() {
        for order in 1..=6 {
            let s = butterworth_lowpass(order, 30.0, 1000.0).unwrap();
            let g = |f: f64| s.0.iter().map(|b| b.gain_at(f / 1000.0)).product::<f64>();
            assert!((g(0.0) - 1.0).abs() < 1e-12);
            assert!(
                (g(30.0) - 0.5f64.sqrt()).abs() < 1e-9,
                "order {order}: {}",
                g(30.0)
            );
            // Maximally flat: the gain falls off monotonically, 20·order dB per decade.
            assert!(g(300.0) < 1.2 * (0.1f64).powi(order as i32));
        }
    }

    #[test]
    fn filtfilt_has_zero_phase_and_squared_magnitude() {
        let fs = 1000.0;
        let s = butterworth_lowpass(2, 20.0, fs).unwrap();
        let f = 8.0;
        let x: Vec<f64> = (0..4000)
            .map(|k| (2.0 * PI * f * k as f64 / fs).sin())
            .collect();
        let y = s.filtfilt(&x);
        let g2 = s.0[0].gain_at(f / fs).powi(2);
        // Away from the ends, y = g² x exactly in phase.
        for k in 1000..3000 {
            assert!(
                (y[k] - g2 * x[k]).abs() < 1e-6,
                "k {k}: {} vs {}",
                y[k],
                g2 * x[k]
            );
        }
        // A constant and a ramp pass unchanged (odd extension + steady-state start).
        let ramp: Vec<f64> = (0..500).map(|k| 0.3 + 0.01 * k as f64).collect();
        let yr = s.filtfilt(&ramp);
        let err: Vec<f64> = ramp.iter().zip(&yr).map(|(a, b)| (a - b).abs()).collect();
        let edge = err[..10]
            .iter()
            .chain(&err[490..])
            .fold(0.0f64, |m, e| m.max(*e));
        assert!(
            edge < 1e-9 && err.iter().all(|e| *e < 1e-9),
            "ramp edge error {edge:e}"
        );
        let constant = vec![1.7; 300];
        assert!(s
            .filtfilt(&constant)
            .iter()
            .all(|v| (v - 1.7).abs() < 1e-12));
    }

    #[test]
    fn differences_are_exact_for_quadratics() {
        let h = 0.01;
        let x: Vec<f64> = (0..50)
            .map(|k| 2.0 + 3.0 * (k as f64 * h) - 4.0 * (k as f64 * h).powi(2))
            .collect();
        let d = differentiate(&x, h);
        for (k, v) in d.iter().enumerate() {
            assert!((v - (3.0 - 8.0 * k as f64 * h)).abs() < 1e-9);
        }
    }

    #[test]
    fn bad_specifications_are_rejected() {
        assert!(matches!(
            butterworth_lowpass(2, 600.0, 1000.0),
            Err(FilterError::Cutoff { .. })
        ));
        assert!(matches!(
            butterworth_lowpass(0, 10.0, 1000.0),
            Err(FilterError::Order(0))
        ));
    }
}
