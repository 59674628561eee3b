//! The noise floor: how much of a residual no function of the robot's state can explain,
//! estimated by the Gamma test (Stefánsson, Končar & Jones, 1997).
//!
//! For samples `x_i = (q, q̇, q̈)` (each coordinate standardized) and residuals `r_i`, the mean
//! half squared difference of `r` between `k`-th nearest neighbours, `γ(k)`, grows linearly with
//! their mean squared distance `δ(k)`; the intercept of the line through `(δ(k), γ(k))`,
//! `k = 1..p`, is the variance of the part of `r` that is not a smooth function of `x`. Neighbours
//! closer in time than `exclude` samples are skipped (filtered noise is correlated in time), so
//! on a periodic excitation the neighbours are the same phase of other periods.

use physid_core::trajectory::Trajectory;
use rayon::prelude::*;

/// At most this many samples enter the test (evenly spaced).
const MAX_POINTS: usize = 2500;
/// Neighbours per point.
const NEIGHBOURS: usize = 10;

/// The noise variance (N² m²) per joint of residual `res` (sample-major, indexed like `tr`;
/// NaN entries are left out) over samples `range` of `tr`; neighbours closer than `exclude`
/// samples in time are skipped.
pub fn gamma_test(
    tr: &Trajectory,
    range: std::ops::Range<usize>,
    res: &[f64],
    exclude: usize,
) -> Vec<f64> {
    let n = tr.dof();
    let m = range.len();
    let stride = m.div_ceil(MAX_POINTS).max(1);
    let idx: Vec<usize> = (0..m).step_by(stride).collect();
    let dim = 3 * n;
    let x = standardized_states(tr, &range, &idx);
    let np = idx.len();
    let mut delta = [0.0; NEIGHBOURS];
    let mut gamma = vec![[0.0; NEIGHBOURS]; n];
    let mut pairs = vec![[0usize; NEIGHBOURS]; n];
    let mut counted = 0usize;
    // The neighbour searches are independent (in parallel); the sums below run in sample
    // order, so they are the same whatever the thread count.
    let neighbours: Vec<_> = (0..np)
        .into_par_iter()
        .map(|i| nearest(&x, dim, &idx, i, exclude))
        .collect();
    for (i, near) in neighbours.iter().enumerate() {
        if near.len() < NEIGHBOURS {
            continue;
        }
        counted += 1;
        for (kk, &(d2, jx)) in near.iter().enumerate() {
            delta[kk] += d2;
            for (j, g) in gamma.iter_mut().enumerate() {
                let d = res[(range.start + idx[i]) * n + j] - res[(range.start + idx[jx]) * n + j];
                // NaN marks a left-out joint-sample: count it as the mean of the others.
                if d.is_finite() {
                    g[kk] += 0.5 * d * d;
                    pairs[j][kk] += 1;
                }
            }
        }
    }
    if counted == 0 {
        return vec![f64::NAN; n];
    }
    let c = counted as f64;
    let dx: Vec<f64> = delta.iter().map(|d| d / c).collect();
    gamma
        .iter()
        .zip(&pairs)
        .map(|(g, p)| intercept(&dx, g, p))
        .collect()
}

/// The gamma test's intercept for one joint: the line through its mean half squared
/// differences `g / p` (sums over `p` pairs) against the mean squared distances `dx` of the
/// 1st to k-th neighbours, at distance zero; NaN when a rank has no pair.
fn intercept(dx: &[f64], g: &[f64; NEIGHBOURS], p: &[usize; NEIGHBOURS]) -> f64 {
    if p.contains(&0) {
        return f64::NAN;
    }
    let mx = dx.iter().sum::<f64>() / NEIGHBOURS as f64;
    let sxx: f64 = dx.iter().map(|d| (d - mx).powi(2)).sum();
    let gy: Vec<f64> = g.iter().zip(p).map(|(v, &c)| v / c as f64).collect();
    let my = gy.iter().sum::<f64>() / NEIGHBOURS as f64;
    let slope = if sxx > 0.0 {
        dx.iter()
            .zip(&gy)
            .map(|(a, b)| (a - mx) * (b - my))
            .sum::<f64>()
            / sxx
    } else {
        0.0
    };
    // The intercept, kept within [γ(1)/2, γ(1)]: the nearest neighbours' half squared
    // difference bounds it from above, and an intercept far below it means the line is
    // dominated by a steep state dependence (then γ(1)/2 is the safer estimate).
    (my - slope * mx).clamp(0.5 * gy[0], gy[0])
}

/// The states `(q, q̇, q̈)` of samples `range.start + idx[i]`, each coordinate standardized over
/// them (mean 0, deviation 1), point-major: `x[i · 3n + d]`.
fn standardized_states(tr: &Trajectory, range: &std::ops::Range<usize>, idx: &[usize]) -> Vec<f64> {
    let n = tr.dof();
    let dim = 3 * n;
    let feature = |k: usize, d: usize| {
        let s = range.start + k;
        let j = d % n;
        match d / n {
            0 => tr.q_at(s)[j],
            1 => tr.qd_at(s)[j],
            _ => tr.qdd_at(s).map_or(0.0, |a| a[j]),
        }
    };
    let mut x = vec![0.0; idx.len() * dim];
    for d in 0..dim {
        let v: Vec<f64> = idx.iter().map(|&k| feature(k, d)).collect();
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        let sd = (v.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / v.len() as f64).sqrt();
        let sd = if sd > 0.0 { sd } else { 1.0 };
        for (i, a) in v.iter().enumerate() {
            x[i * dim + d] = (a - mean) / sd;
        }
    }
    x
}

/// The [`NEIGHBOURS`] points nearest point `i` in `x` (squared distance, index), nearest first,
/// skipping those closer than `exclude` samples in time (by insertion into a short sorted list).
fn nearest(x: &[f64], dim: usize, idx: &[usize], i: usize, exclude: usize) -> Vec<(f64, usize)> {
    let mut near: Vec<(f64, usize)> = Vec::with_capacity(NEIGHBOURS + 1);
    for jx in 0..idx.len() {
        if idx[i].abs_diff(idx[jx]) < exclude.max(1) {
            continue;
        }
        // Squares summed in coordinate order; a partial sum never decreases, so once it
        // reaches the k-th distance so far the point cannot enter (the same list as the full
        // sum would give, bit for bit).
        let bound = if near.len() < NEIGHBOURS {
            f64::INFINITY
        } else {
            near[NEIGHBOURS - 1].0
        };
        let (xi, xj) = (&x[i * dim..(i + 1) * dim], &x[jx * dim..(jx + 1) * dim]);
        let mut d2 = 0.0;
        for (a, b) in xi.iter().zip(xj) {
            d2 += (a - b).powi(2);
            if d2 >= bound {
                break;
            }
        }
        if d2 < bound {
            let pos = near.partition_point(|a| a.0 < d2);
            near.insert(pos, (d2, jx));
            near.truncate(NEIGHBOURS);
        }
    }
    near
}
