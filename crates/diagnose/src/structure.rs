//! **Structure left** in the final residual: whether a smooth function of each joint's own
//! speed and angle, fitted on the training residual, predicts the validation residual. The
//! library's effects are specific shapes; an effect outside it (quadratic damping, friction
//! that varies along the stroke, a cable's torque) leaves a residual that such a generic
//! function still predicts, and then the verdict cannot be "explained".
//!
//! Per joint `j`, the basis is piecewise linear ("hat" functions) in `q̇_j` and in `q_j`, with
//! knots at quantiles of the training data's fast joint-samples. It is fitted by ridge least
//! squares on the training residual of the final model (whose friction and effect columns the
//! residual is already orthogonal to) and scored on the validation residual: the relative
//! reduction of its mean square, and its significance over contiguous validation blocks (the
//! reduction of each block's sum of squares, mean over its standard error; blocks of 1/10 of
//! the run are far longer than the filtered noise's correlation). Structure remains when the
//! reduction is significant (t ≥ [`T_MIN`]) and not negligible (at least
//! `Options::structure_threshold`).

use super::residual::mask_slow;
use super::stage::Stage;
use nalgebra::{DMatrix, DVector};
use physid_core::trajectory::Trajectory;
use serde::Serialize;

/// Knots per coordinate (speed, angle).
const KNOTS: usize = 8;
/// Ridge weight relative to the mean diagonal of the normal matrix.
const RIDGE: f64 = 1e-6;
/// Contiguous validation blocks of the significance test.
const BLOCKS: usize = 10;
/// Smallest t statistic of the blocks' reductions that counts as significant.
pub const T_MIN: f64 = 2.0;

/// What the generic function found in the final residual.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct StructureLeft {
    /// Relative reduction of the validation residual's mean square over all joints (0: none;
    /// negative: the fit does not carry over).
    pub reduction: f64,
    /// The same per joint.
    pub per_joint: Vec<f64>,
    /// Mean over its standard error of the reduction of each of 10 contiguous validation
    /// blocks' sum of squares.
    pub t: f64,
    /// The smallest reduction that counts (`Options::structure_threshold`).
    pub threshold: f64,
    /// Whether `reduction` reaches the threshold with `t` at least [`T_MIN`]: an effect outside the
    /// library remains.
    pub remains: bool,
}

/// The structure test of the final model's residuals: training (`train_res`) and validation
/// (`val_res`), both sample-major over their trajectories, all joint-samples (slow ones are
/// left out here).
pub(crate) fn structure_left(
    stage: &Stage,
    train_res: &[f64],
    val_res: &[f64],
    threshold: f64,
) -> StructureLeft {
    let (train, validate) = (stage.train, stage.validate);
    let min_speed = stage.opts.min_speed;
    let (rt, rv) = (
        mask_slow(train, train_res, min_speed),
        mask_slow(validate, val_res, min_speed),
    );
    let n = train.dof();
    let len = validate.len().max(1);
    let mut block_gain = [0.0; BLOCKS];
    let (mut before, mut after) = (0.0, 0.0);
    let per_joint: Vec<f64> = (0..n)
        .map(|j| {
            let (mut b, mut a) = (0.0, 0.0);
            for (k, r, pred) in joint_fit(train, validate, &rt, &rv, j) {
                let (sb, sa) = (r * r, (r - pred).powi(2));
                b += sb;
                a += sa;
                block_gain[(k * BLOCKS / len).min(BLOCKS - 1)] += sb - sa;
            }
            before += b;
            after += a;
            if b > 0.0 {
                1.0 - a / b
            } else {
                0.0
            }
        })
        .collect();
    let reduction = if before > 0.0 {
        1.0 - after / before
    } else {
        0.0
    };
    let t = t_statistic(&block_gain);
    StructureLeft {
        reduction,
        per_joint,
        t,
        threshold,
        remains: reduction >= threshold && t >= T_MIN,
    }
}

/// Mean over standard error of `x` (0 when it has no spread).
fn t_statistic(x: &[f64]) -> f64 {
    let m = x.len() as f64;
    let mean = x.iter().sum::<f64>() / m;
    let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (m - 1.0);
    if var > 0.0 {
        mean / (var / m).sqrt()
    } else {
        0.0
    }
}

/// Joint `j`'s generic fit on the training residual `rt`, applied to the validation residual
/// `rv`: `(sample, residual, prediction)` for each of its fast validation samples (none when
/// the training data are too few).
fn joint_fit(
    train: &Trajectory,
    validate: &Trajectory,
    rt: &[f64],
    rv: &[f64],
    j: usize,
) -> Vec<(usize, f64, f64)> {
    let n = train.dof();
    let rows = |tr: &Trajectory, r: &[f64]| -> Vec<(usize, f64, f64, f64)> {
        (0..tr.len())
            .filter(|&k| r[k * n + j].is_finite())
            .map(|k| (k, tr.qd_at(k)[j], tr.q_at(k)[j], r[k * n + j]))
            .collect()
    };
    let (fit_rows, val_rows) = (rows(train, rt), rows(validate, rv));
    if fit_rows.len() < 4 * KNOTS || val_rows.is_empty() {
        return vec![];
    }
    let speed_knots = quantile_knots(fit_rows.iter().map(|r| r.1).collect());
    let angle_knots = quantile_knots(fit_rows.iter().map(|r| r.2).collect());
    let basis = |qd: f64, q: f64| -> Vec<f64> {
        let mut b = hats(&speed_knots, qd);
        b.extend(hats(&angle_knots, q));
        b
    };
    let p = 2 * KNOTS;
    let mut ata = DMatrix::<f64>::zeros(p, p);
    let mut atb = DVector::<f64>::zeros(p);
    for &(_, qd, q, r) in &fit_rows {
        let b = DVector::from_vec(basis(qd, q));
        ata += &b * b.transpose();
        atb += &b * r;
    }
    let ridge = RIDGE * ata.trace() / p as f64;
    for i in 0..p {
        ata[(i, i)] += ridge.max(f64::MIN_POSITIVE);
    }
    let Some(c) = ata.cholesky().map(|ch| ch.solve(&atb)) else {
        return vec![];
    };
    val_rows
        .iter()
        .map(|&(k, qd, q, r)| {
            let pred: f64 = basis(qd, q).iter().zip(c.iter()).map(|(x, y)| x * y).sum();
            (k, r, pred)
        })
        .collect()
}

/// `KNOTS` knots at evenly spaced quantiles of `v` (first and last at its extremes), strictly
/// increasing (ties spread by a tiny step).
fn quantile_knots(mut v: Vec<f64>) -> Vec<f64> {
    v.sort_by(f64::total_cmp);
    let m = v.len();
    let mut k: Vec<f64> = (0..KNOTS).map(|i| v[(i * (m - 1)) / (KNOTS - 1)]).collect();
    for i in 1..KNOTS {
        if k[i] <= k[i - 1] {
            k[i] = k[i - 1] + 1e-9 * (1.0 + k[i - 1].abs());
        }
    }
    k
}

/// The hat functions on `knots` at `x` (clamped to the end knots): they sum to 1.
fn hats(knots: &[f64], x: f64) -> Vec<f64> {
    let m = knots.len();
    let mut h = vec![0.0; m];
    let x = x.clamp(knots[0], knots[m - 1]);
    let i = knots.partition_point(|&k| k <= x).clamp(1, m - 1);
    let (a, b) = (knots[i - 1], knots[i]);
    let w = (x - a) / (b - a);
    h[i - 1] = 1.0 - w;
    h[i] = w;
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hats_interpolate_linearly_and_sum_to_one() {
        let knots = [0.0, 1.0, 3.0];
        let h = hats(&knots, 2.0);
        assert_eq!(h, vec![0.0, 0.5, 0.5]);
        assert_eq!(hats(&knots, -5.0), vec![1.0, 0.0, 0.0]);
        assert_eq!(hats(&knots, 9.0), vec![0.0, 0.0, 1.0]);
        // A linear function is reproduced exactly from its knot values.
        let f = |x: f64| 2.0 * x - 1.0;
        let x = 0.3;
        let v: f64 = hats(&knots, x)
            .iter()
            .zip(knots)
            .map(|(h, k)| h * f(k))
            .sum();
        assert!((v - f(x)).abs() < 1e-12);
    }

    #[test]
    fn t_statistic_of_known_samples() {
        // mean 2, sample sd 1 (values 1, 2, 3), n = 3: t = 2 / (1 / √3).
        assert!((t_statistic(&[1.0, 2.0, 3.0]) - 2.0 * 3f64.sqrt()).abs() < 1e-12);
        assert_eq!(t_statistic(&[1.0, 1.0]), 0.0);
    }

    #[test]
    fn knots_are_strictly_increasing_on_ties() {
        let k = quantile_knots(vec![1.0; 100]);
        assert!(k.windows(2).all(|w| w[1] > w[0]), "{k:?}");
    }
}
