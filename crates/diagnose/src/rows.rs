//! The augmented rows of a range of samples computed in parallel and handed on in sample
//! order: sums over them (normal equations) are the same, bit for bit, as one pass's, whatever
//! the thread count.

use nalgebra::DMatrix;
use physid_core::model::Model;
use physid_core::trajectory::Trajectory;
use physid_effect::library::{slow, Context, RowSink, Variant};
use physid_ident::{NormalEquations, RowSums};
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

/// The normal equations of `Z = [Y | E]` (the model's columns, then `variants`' in order)
/// over samples `range`, rows of joints slower than `min_speed` (rad/s) left out, and the
/// number of joint-samples kept. Each row is accumulated over only the columns it can touch
/// ([`row_columns`]); chunks of [`CHUNK`] samples, fixed from `range`'s start, run in parallel
/// and their sums are added in chunk order: the same numbers whatever the thread count.
pub(crate) fn normal_equations(
    ctx: &Context,
    tr: &Trajectory,
    range: Range<usize>,
    variants: &[Variant],
    min_speed: f64,
) -> (NormalEquations, usize) {
    let model = ctx.model();
    let (n, p, cols) = (
        model.dof(),
        columns(model, variants),
        row_columns(model, variants),
    );
    let ne = NormalEquations::summed_in_chunks(
        range.clone(),
        CHUNK,
        NormalEquations::new(n, p).finish(),
        || RowSums::new(n, p, cols.clone(), &[]),
        |r, sums| {
            ctx.for_each_row(tr, r, variants, min_speed, &mut |_, z, tau| {
                sums.add(z, tau)
            })
        },
    );
    let kept = range
        .map(|k| tr.qd_at(k).iter().filter(|w| !slow(**w, min_speed)).count())
        .sum();
    (ne, kept)
}

/// The number of columns of `Z = [Y | E]`: the model's, then `variants'`.
pub(crate) fn columns(model: &Model, variants: &[Variant]) -> usize {
    let n = model.dof();
    model.layout().len + variants.iter().map(|v| v.kind.columns(n)).sum::<usize>()
}

/// The columns of `Z = [Y | E]` (the model's, then `variants`' in order) that can be nonzero
/// in each joint's row: the regressor's ([`physid_core::dynamics::row_columns`]) and each
/// variant's ([`Kind::columns_of_row`](physid_effect::Kind::columns_of_row)).
pub(crate) fn row_columns(model: &Model, variants: &[Variant]) -> Vec<Vec<usize>> {
    let n = model.dof();
    let mut cols = physid_core::dynamics::row_columns(model);
    for (j, row) in cols.iter_mut().enumerate() {
        let mut offset = model.layout().len;
        for v in variants {
            row.extend(v.kind.columns_of_row(n, j).into_iter().map(|c| offset + c));
            offset += v.kind.columns(n);
        }
    }
    cols
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

    #[test]
    fn every_kind_s_columns_are_zero_outside_the_rows_they_are_declared_to_touch() {
        let model = cheetah3::leg();
        let n = model.dof();
        let tr = swing(n, 300);
        let ctx = Context::new(&model, &model.parameters(), &tr, 20.0);
        let variants = library::variants(&Kind::ALL, n);
        let cols = row_columns(&model, &variants);
        let p = columns(&model, &variants);
        // The declaration leaves columns out of every row (friction-like kinds are local).
        assert!(cols.iter().all(|c| c.len() < p));
        let (mut outside, mut inside_nonzero) = (0usize, 0usize);
        ctx.for_each_row(&tr, 0..tr.len(), &variants, 0.0, &mut |_, z, _| {
            for (j, row) in cols.iter().enumerate() {
                for c in 0..p {
                    let declared = row.contains(&c);
                    outside += usize::from(!declared && z[(j, c)] != 0.0);
                    inside_nonzero += usize::from(declared && z[(j, c)] != 0.0);
                }
            }
        });
        assert_eq!(outside, 0, "nonzero entries outside the declared columns");
        assert!(inside_nonzero > 300 * n * p / 4);
    }

    #[test]
    fn row_sums_are_the_dense_sums_and_the_same_on_any_thread_count() {
        let model = cheetah3::leg();
        let n = model.dof();
        let tr = swing(n, 3 * CHUNK + 77);
        let ctx = Context::new(&model, &model.parameters(), &tr, 20.0);
        let variants = library::variants(&Kind::ALL, n);
        let range = 5..tr.len() - 3;
        let p = columns(&model, &variants);
        let mut dense = NormalEquations::new(n, p);
        let mut kept = 0;
        ctx.for_each_row(&tr, range.clone(), &variants, 0.3, &mut |k, z, tau| {
            dense.add(z, tau);
            kept += tr.qd_at(k).iter().filter(|w| w.abs() >= 0.3).count();
        });
        let dense = dense.finish();
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build();
            pool.expect("a pool")
                .install(|| normal_equations(&ctx, &tr, range.clone(), &variants, 0.3))
        };
        let (sparse, sparse_kept) = on(1);
        assert_eq!(sparse_kept, kept);
        assert!(kept < n * range.len(), "some rows are slow");
        assert_eq!(sparse.samples, range.len());
        let scale = dense.yty.amax();
        assert!((&sparse.yty - &dense.yty).amax() <= 1e-13 * scale);
        assert!((&sparse.ytt - &dense.ytt).amax() <= 1e-13 * dense.ytt.amax());
        assert!((sparse.tt - dense.tt).abs() <= 1e-13 * dense.tt);
        assert!(sparse.yty == sparse.yty.transpose());
        let (two, _) = on(2);
        assert!(two
            .yty
            .iter()
            .zip(sparse.yty.iter())
            .all(|(a, b)| a.to_bits() == b.to_bits()));
        assert_eq!(two.ytt, sparse.ytt);
        assert_eq!(two.tt.to_bits(), sparse.tt.to_bits());
    }
}
