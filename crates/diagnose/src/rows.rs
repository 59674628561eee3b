//! The augmented rows of a range of samples computed in parallel and handed on in sample
//! order: sums over them (normal equations) are the same, bit for bit, as one pass's, whatever
//! the thread count.

use nalgebra::DMatrix;
use physid_core::trajectory::Trajectory;
use physid_effect::library::{Context, RowSink, Variant};
use rayon::prelude::*;
use std::ops::Range;

/// One sample's augmented row: `(sample, Z_k, τ_k)`.
type Row = (usize, DMatrix<f64>, Vec<f64>);

/// Samples per parallel task.
const CHUNK: usize = 128;
/// Samples computed before they are handed on: bounds the rows held at once.
const WINDOW: usize = 8 * CHUNK;

/// [`Context::for_each_row`] over `range`, the rows computed in parallel, `f` called in sample
/// order.
pub(crate) fn for_each_row_in_order(
    ctx: &Context,
    tr: &Trajectory,
    range: Range<usize>,
    variants: &[Variant],
    min_speed: f64,
    f: &mut RowSink,
) {
    for window in chunks(range, WINDOW) {
        let computed: Vec<Vec<Row>> = chunks(window, CHUNK)
            .into_par_iter()
            .map(|r| {
                let mut rows = Vec::with_capacity(r.len());
                ctx.for_each_row(tr, r, variants, min_speed, &mut |k, z, tau| {
                    rows.push((k, z.clone(), tau.to_vec()))
                });
                rows
            })
            .collect();
        for (k, z, tau) in computed.iter().flatten() {
            f(*k, z, tau);
        }
    }
}

/// `range` cut into consecutive pieces of `size` samples (the last one shorter).
pub(crate) fn chunks(range: Range<usize>, size: usize) -> Vec<Range<usize>> {
    let end = range.end;
    range
        .step_by(size)
        .map(|s| s..(s + size).min(end))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use physid_core::model::cheetah3;
    use physid_effect::library::{self, Kind};

    /// A swing of every joint at 500 Hz, torques a smooth function of time.
    fn swing(n: usize, samples: usize) -> Trajectory {
        let names = (0..n).map(|j| format!("j{j}")).collect();
        let mut tr = Trajectory::new(names, true);
        for k in 0..samples {
            let t = k as f64 * 2e-3;
            let w = |j: usize| 1.0 + 0.3 * j as f64;
            let q: Vec<f64> = (0..n).map(|j| 0.8 * (w(j) * t).sin()).collect();
            let qd: Vec<f64> = (0..n).map(|j| 0.8 * w(j) * (w(j) * t).cos()).collect();
            let qdd: Vec<f64> = (0..n).map(|j| -w(j) * w(j) * q[j]).collect();
            let tau: Vec<f64> = (0..n).map(|j| (t * (2.0 + j as f64)).cos()).collect();
            tr.push(t, &q, &qd, Some(&qdd), &tau);
        }
        tr
    }

    #[test]
    fn rows_in_order_are_one_pass_s_rows_bit_for_bit_in_sample_order() {
        let model = cheetah3::leg();
        let tr = swing(model.dof(), 3 * WINDOW + 77);
        let ctx = Context::new(&model, &model.parameters(), &tr, 20.0);
        let variants = library::variants(&Kind::ALL, model.dof());
        let range = 5..tr.len() - 3;
        let mut one_pass = vec![];
        ctx.for_each_row(&tr, range.clone(), &variants, 0.05, &mut |k, z, tau| {
            one_pass.push((k, z.clone(), tau.to_vec()))
        });
        let mut in_order = vec![];
        for_each_row_in_order(
            &ctx,
            &tr,
            range.clone(),
            &variants,
            0.05,
            &mut |k, z, tau| in_order.push((k, z.clone(), tau.to_vec())),
        );
        assert_eq!(one_pass.len(), range.len());
        assert_eq!(in_order.len(), one_pass.len());
        for (a, b) in one_pass.iter().zip(&in_order) {
            assert_eq!(a.0, b.0, "sample order");
            assert!(a
                .1
                .iter()
                .zip(b.1.iter())
                .all(|(x, y)| x.to_bits() == y.to_bits()));
            assert_eq!(a.2, b.2);
        }
    }
}
