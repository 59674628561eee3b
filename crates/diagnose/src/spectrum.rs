//! Where in frequency: Welch power spectra of the residual and its magnitude-squared coherence
//! with the motion (`q`, `q̇`, `q̈` and the rotor angle's phase `sin(N q)`).
//!
//! Segments of `SEGMENT` samples (halved until at least four fit), Hann window, 50 % overlap,
//! means removed per segment; one-sided density in N² m²/Hz.

use rustfft::{num_complex::Complex, FftPlanner};
use serde::Serialize;

/// Samples per Welch segment (at most).
const SEGMENT: usize = 1024;

/// A residual's spectrum on one joint.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct Spectrum {
    /// Joint name.
    pub joint: String,
    /// Frequencies (Hz).
    pub frequency: Vec<f64>,
    /// One-sided power spectral density (N² m²/Hz).
    pub psd: Vec<f64>,
    /// Coherence (0..1) per frequency with each signal of `signals`.
    pub coherence: Vec<Vec<f64>>,
    /// The signals: `q`, `qd`, `qdd`, `sin(N q)`.
    pub signals: Vec<String>,
    /// Frequency of the largest PSD value (Hz).
    pub peak_frequency: f64,
    /// Per signal, the largest coherence and its frequency (Hz).
    pub peak_coherence: Vec<(f64, f64)>,
}

fn segments(len: usize) -> usize {
    let mut seg = SEGMENT;
    while seg > 16 && len < 2 * seg {
        seg /= 2;
    }
    seg
}

/// Cross spectral densities `S_xy` (one-sided) of equally long signals by Welch's method.
/// Cross spectra `S[a][b][f]`.
type CrossSpectra = Vec<Vec<Vec<Complex<f64>>>>;

fn welch(xs: &[&[f64]], fs: f64) -> (Vec<f64>, CrossSpectra) {
    let len = xs[0].len();
    let seg = segments(len);
    let hop = seg / 2;
    let nf = seg / 2 + 1;
    let win: Vec<f64> = (0..seg)
        .map(|i| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / seg as f64).cos())
        .collect();
    let u: f64 = win.iter().map(|w| w * w).sum();
    let fft = FftPlanner::new().plan_fft_forward(seg);
    let m = xs.len();
    let mut s = vec![vec![vec![Complex::new(0.0, 0.0); nf]; m]; m];
    let mut count = 0usize;
    let mut start = 0;
    while start + seg <= len {
        let spec: Vec<Vec<Complex<f64>>> = xs
            .iter()
            .map(|x| {
                let part = &x[start..start + seg];
                let mean = part.iter().sum::<f64>() / seg as f64;
                let mut buf: Vec<Complex<f64>> = part
                    .iter()
                    .zip(&win)
                    .map(|(v, w)| Complex::new((v - mean) * w, 0.0))
                    .collect();
                fft.process(&mut buf);
                buf.truncate(nf);
                buf
            })
            .collect();
        for a in 0..m {
            for b in 0..m {
                for f in 0..nf {
                    s[a][b][f] += spec[a][f].conj() * spec[b][f];
                }
            }
        }
        count += 1;
        start += hop;
    }
    let scale = 1.0 / (fs * u * count.max(1) as f64);
    for row in s.iter_mut() {
        for col in row.iter_mut() {
            for (f, v) in col.iter_mut().enumerate() {
                let one_sided = if f == 0 || f == nf - 1 { 1.0 } else { 2.0 };
                *v *= scale * one_sided;
            }
        }
    }
    let freq = (0..nf).map(|f| f as f64 * fs / seg as f64).collect();
    (freq, s)
}

/// The spectrum of `residual` and its coherence with each of `signals` (same length), sampled
/// at `fs` Hz.
pub fn spectrum(
    joint: &str,
    residual: &[f64],
    signals: &[(String, Vec<f64>)],
    fs: f64,
) -> Spectrum {
    let mut xs: Vec<&[f64]> = vec![residual];
    xs.extend(signals.iter().map(|(_, v)| v.as_slice()));
    let (frequency, s) = welch(&xs, fs);
    let psd: Vec<f64> = s[0][0].iter().map(|c| c.re).collect();
    let coherence: Vec<Vec<f64>> = (1..xs.len())
        .map(|i| {
            (0..frequency.len())
                .map(|f| {
                    let den = s[0][0][f].re * s[i][i][f].re;
                    if den > 0.0 {
                        (s[0][i][f].norm_sqr() / den).min(1.0)
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect();
    let argmax = |v: &[f64]| {
        v.iter()
            .enumerate()
            .skip(1)
            .fold((0usize, f64::NEG_INFINITY), |a, (i, x)| {
                if *x > a.1 {
                    (i, *x)
                } else {
                    a
                }
            })
    };
    let (ip, _) = argmax(&psd);
    let peak_coherence = coherence
        .iter()
        .map(|c| {
            let (i, v) = argmax(c);
            (v.max(0.0), frequency[i])
        })
        .collect();
    Spectrum {
        joint: joint.to_string(),
        peak_frequency: frequency[ip],
        frequency,
        psd,
        coherence,
        signals: signals.iter().map(|(n, _)| n.clone()).collect(),
        peak_coherence,
    }
}
