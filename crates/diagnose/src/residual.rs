//! Residuals of a model with effect columns, and the masking and averaging every step applies
//! to them: joint-samples slower than the speed threshold are left out (NaN) of every fit and
//! error.

use nalgebra::DVector;
use physid_core::trajectory::Trajectory;
use physid_effect::library::{self, Context};
use rayon::prelude::*;

/// The residual `res` (sample-major over `tr`) with the joint-samples slower than `min_speed`
/// set to NaN (left out of every fit and error).
pub fn mask_slow(tr: &Trajectory, res: &[f64], min_speed: f64) -> Vec<f64> {
    let n = tr.dof();
    res.iter()
        .enumerate()
        .map(|(i, r)| {
            if library::slow(tr.qd_at(i / n)[i % n], min_speed) {
                f64::NAN
            } else {
                *r
            }
        })
        .collect()
}

/// The mean square of the finite entries of `v` (0 without any).
pub fn finite_mean_square(v: &[f64]) -> f64 {
    let (s, c) = v
        .iter()
        .filter(|x| x.is_finite())
        .fold((0.0, 0usize), |(s, c), x| (s + x * x, c + 1));
    s / c.max(1) as f64
}

/// Samples per parallel task of [`residual_rms`].
const RESIDUAL_CHUNK: usize = 256;

/// The residual `τ − Z θ` over `tr` for the model plus `variants` (all rows), and its per-joint
/// RMS over the joint-samples at or above `min_speed`.
pub fn residual_rms(
    ctx: &Context,
    tr: &Trajectory,
    variants: &[library::Variant],
    theta: &DVector<f64>,
    min_speed: f64,
) -> (Vec<f64>, Vec<f64>) {
    let n = tr.dof();
    // Each sample's residual is its own: chunks in parallel, joined in sample order.
    let parts: Vec<Vec<f64>> = super::rows::chunks(0..tr.len(), RESIDUAL_CHUNK)
        .into_par_iter()
        .map(|range| {
            let mut part = Vec::with_capacity(range.len() * n);
            ctx.for_each_row(tr, range, variants, 0.0, &mut |_, z, tau| {
                let pred = z * theta;
                part.extend((0..n).map(|j| tau[j] - pred[j]));
            });
            part
        })
        .collect();
    let res = parts.concat();
    let rms = (0..n)
        .map(|j| {
            let (mut s, mut c) = (0.0, 0usize);
            for k in 0..tr.len() {
                if !library::slow(tr.qd_at(k)[j], min_speed) {
                    s += res[k * n + j].powi(2);
                    c += 1;
                }
            }
            (s / c.max(1) as f64).sqrt()
        })
        .collect();
    (rms, res)
}

pub(crate) fn mean_square(rms: &[f64]) -> f64 {
    rms.iter().map(|r| r * r).sum::<f64>() / rms.len().max(1) as f64
}
