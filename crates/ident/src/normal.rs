//! Streaming least-squares data: `YᵀY`, `Yᵀτ`, `τᵀτ` and the sample count, accumulated in one
//! pass (architecture.md §5), so memory and the cone program's size do not grow with the number of
//! samples. Rows are buffered in blocks and added with one matrix product per block.

use nalgebra::{DMatrix, DVector};
use physid_core::dynamics::{regressor, Data};
use physid_core::model::Model;
use physid_core::trajectory::{SampleSink, Trajectory};

/// Rows per block before the `YᵀY` update (a multiple of every joint count up to 8).
const BLOCK_SAMPLES: usize = 128;

/// Samples per chunk of a parallel accumulation. Fixed, so that the chunks, the order in which
/// their sums are added, and so every result, do not depend on the thread count.
const CHUNK_SAMPLES: usize = 1024;

pub use physid_core::dynamics::for_each_regressor;

/// The normal equations of `min Σ_k ‖Y_k θ − τ_k‖²` over the samples added so far.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct NormalEquations {
    /// `Σ Y_kᵀ Y_k` (p×p).
    pub yty: DMatrix<f64>,
    /// `Σ Y_kᵀ τ_k`.
    pub ytt: DVector<f64>,
    /// `Σ ‖τ_k‖²`.
    pub tt: f64,
    /// Number of samples added.
    pub samples: usize,
    n: usize,
    /// Joints whose rows are left out (locked joints: their torque is not fitted).
    excluded: Vec<usize>,
    rows: DMatrix<f64>,
    taus: DVector<f64>,
    filled: usize,
}

impl NormalEquations {
    /// Empty normal equations for a model with `n` joints and `p` parameters.
    pub fn new(n: usize, p: usize) -> Self {
        Self {
            yty: DMatrix::zeros(p, p),
            ytt: DVector::zeros(p),
            tt: 0.0,
            samples: 0,
            n,
            excluded: vec![],
            rows: DMatrix::zeros(BLOCK_SAMPLES * n, p),
            taus: DVector::zeros(BLOCK_SAMPLES * n),
            filled: 0,
        }
    }

    /// The same, empty, normal equations leaving out the rows of `joints` (their torques are
    /// not fitted: locked joints).
    pub fn excluding(mut self, joints: &[usize]) -> Self {
        self.excluded = joints.to_vec();
        self
    }

    /// Equations per sample: the joints whose rows are fitted.
    pub fn rows_per_sample(&self) -> usize {
        self.n - self.excluded.len()
    }

    /// Adds one sample's regressor `y` (n×p) and torque `tau`.
    pub fn add(&mut self, y: &DMatrix<f64>, tau: &[f64]) {
        if self.rows.nrows() == 0 {
            // Released by `finish`: the buffer again.
            self.rows = DMatrix::zeros(BLOCK_SAMPLES * self.n, self.yty.ncols());
            self.taus = DVector::zeros(BLOCK_SAMPLES * self.n);
        }
        let r0 = self.filled * self.n;
        self.rows
            .view_mut((r0, 0), (self.n, y.ncols()))
            .copy_from(y);
        for (j, t) in tau.iter().enumerate() {
            self.taus[r0 + j] = *t;
        }
        for &j in &self.excluded {
            self.rows.row_mut(r0 + j).fill(0.0);
            self.taus[r0 + j] = 0.0;
        }
        self.filled += 1;
        self.samples += 1;
        if self.filled == BLOCK_SAMPLES {
            self.flush();
        }
    }

    /// Adds the buffered rows into the sums: the upper triangle of `YᵀY` by BLAS `dsyrk`
    /// (symmetric rank-k update, half the work of a general product).
    fn flush(&mut self) {
        if self.filled == 0 {
            return;
        }
        let m = self.filled * self.n;
        add_gram(Gram::RowsTimesRows, &self.rows, m, &mut self.yty);
        let rows = self.rows.rows(0, m);
        let taus = self.taus.rows(0, m);
        self.ytt.gemv_tr(1.0, &rows, &taus, 1.0);
        self.tt += taus.norm_squared();
        self.filled = 0;
    }

    /// Folds in buffered rows and fills the lower triangle; call before reading the sums. The
    /// row buffer (`BLOCK_SAMPLES · n` rows of `p`) is released: finished sums are cloned and
    /// merged many times over (folds, their complements), and a copy of the buffer each time
    /// would cost more than the sums.
    pub fn finish(mut self) -> Self {
        self.flush();
        self.yty.fill_lower_triangle_with_upper_triangle();
        self.rows = DMatrix::zeros(0, self.yty.ncols());
        self.taus = DVector::zeros(0);
        self
    }

    /// Combines two finished accumulations (for parallel or incremental use).
    pub fn merged(mut self, other: &NormalEquations) -> Self {
        self.absorb(other);
        self
    }

    /// Adds a finished accumulation's sums into these.
    fn absorb(&mut self, other: &NormalEquations) {
        self.yty += &other.yty;
        self.ytt += &other.ytt;
        self.tt += other.tt;
        self.samples += other.samples;
        if self.excluded.is_empty() {
            self.excluded = other.excluded.clone();
        }
    }

    /// Accumulates samples `range` of a trajectory (which must carry q̈) for `model`, in
    /// chunks of fixed length in parallel (the current rayon pool): the same sums whatever the
    /// thread count.
    pub fn from_trajectory(model: &Model, tr: &Trajectory, range: std::ops::Range<usize>) -> Self {
        Self::from_trajectory_excluding(model, tr, range, &[])
    }

    /// [`Self::from_trajectory`] leaving out the rows of `excluded` joints.
    pub fn from_trajectory_excluding(
        model: &Model,
        tr: &Trajectory,
        range: std::ops::Range<usize>,
        excluded: &[usize],
    ) -> Self {
        let empty = Self::new(model.dof(), model.layout().len).excluding(excluded);
        Self::summed_in_chunks(
            range,
            CHUNK_SAMPLES,
            empty.finish(),
            || RowSums::for_model(model, excluded),
            |chunk, sums| {
                for_each_regressor(model, tr, chunk, &mut |k, y| sums.add(y, tr.tau_at(k)))
            },
        )
    }

    /// Sums over samples `range` cut into consecutive chunks of `chunk` samples (fixed from
    /// `range`'s start): each chunk's rows are added by `fill` into fresh sums from `sums`, the
    /// chunks in parallel (the current rayon pool), and their sums added to the finished `empty`
    /// in chunk order: the same numbers whatever the thread count.
    pub fn summed_in_chunks(
        range: std::ops::Range<usize>,
        chunk: usize,
        empty: Self,
        sums: impl Fn() -> RowSums + Sync,
        fill: impl Fn(std::ops::Range<usize>, &mut RowSums) + Sync,
    ) -> Self {
        use rayon::prelude::*;
        let end = range.end;
        let chunks: Vec<std::ops::Range<usize>> = range
            .step_by(chunk.max(1))
            .map(|start| start..(start + chunk).min(end))
            .collect();
        let parts: Vec<Self> = chunks
            .into_par_iter()
            .map(|c| {
                let mut s = sums();
                fill(c, &mut s);
                s.finish()
            })
            .collect();
        parts.iter().fold(empty, |sum, part| sum.merged(part))
    }

    /// Accumulates the samples a source streams (e.g. a CSV read from disk by
    /// `io::samples::stream_csv`): memory does not depend on the source's length. Returns the
    /// sums and what the source returns (its sample count).
    pub fn from_stream<E>(
        model: &Model,
        source: impl FnOnce(&mut SampleSink) -> Result<usize, E>,
    ) -> Result<(Self, usize), E> {
        let (n, p) = (model.dof(), model.layout().len);
        // The same chunks, summed in the same order, as `from_trajectory`: a file streamed
        // gives the sums it gives in memory, bit for bit.
        let mut sum = Self::new(n, p).finish();
        let mut chunk = RowSums::for_model(model, &[]);
        let mut d = Data::new(model);
        let mut y = DMatrix::zeros(n, p);
        let total = source(&mut |_, s| {
            regressor(model, &mut d, s.q, s.qd, s.qdd, &mut y);
            chunk.add(&y, s.tau);
            if chunk.samples == CHUNK_SAMPLES {
                let full = std::mem::replace(&mut chunk, RowSums::for_model(model, &[]));
                sum.absorb(&full.finish());
            }
        })?;
        sum.absorb(&chunk.finish());
        Ok((sum, total))
    }

    /// Finished normal equations from their sums (e.g. a sub-problem or a sum of blocks).
    pub fn from_sums(
        n: usize,
        yty: DMatrix<f64>,
        ytt: DVector<f64>,
        tt: f64,
        samples: usize,
    ) -> Self {
        let p = yty.ncols();
        Self {
            yty,
            ytt,
            tt,
            samples,
            n,
            excluded: vec![],
            rows: DMatrix::zeros(0, p),
            taus: DVector::zeros(0),
            filled: 0,
        }
    }

    /// The normal equations of the columns `cols` only (in that order).
    pub fn select(&self, cols: &[usize]) -> Self {
        let (m, p) = (cols.len(), self.yty.nrows());
        // Runs of consecutive columns `(at, from, len)` are copied as slices: a model's own
        // columns are one run.
        let mut runs: Vec<(usize, usize, usize)> = vec![];
        for (i, &c) in cols.iter().enumerate() {
            match runs.last_mut() {
                Some((at, from, len)) if *from + *len == c && *at + *len == i => *len += 1,
                _ => runs.push((i, c, 1)),
            }
        }
        let mut yty = DMatrix::zeros(m, m);
        for (j, &c) in cols.iter().enumerate() {
            let source = &self.yty.as_slice()[c * p..(c + 1) * p];
            let target = &mut yty.as_mut_slice()[j * m..(j + 1) * m];
            for &(at, from, len) in &runs {
                target[at..at + len].copy_from_slice(&source[from..from + len]);
            }
        }
        let mut out = Self::from_sums(
            self.n,
            yty,
            DVector::from_fn(m, |i, _| self.ytt[cols[i]]),
            self.tt,
            self.samples,
        );
        out.excluded = self.excluded.clone();
        out
    }

    /// These equations with the pseudo-observation `mean(x[seen]) = 0` added over the columns
    /// of `cols` the data see (a column of a locked joint, all zero, keeps its prior), at a
    /// weight that dominates the data along that direction (a hundred times the largest of
    /// their diagonal): for a direction the data do not determine (a gauge, such as a torque
    /// gain common to every joint, which is a scale of all inertial parameters), so that a fit
    /// does not wander along it. For fitting only: the sums no longer are the data's.
    pub fn with_mean_pinned(mut self, cols: std::ops::Range<usize>) -> Self {
        let seen: Vec<usize> = cols.filter(|&c| self.yty[(c, c)] > 0.0).collect();
        if seen.is_empty() {
            return self;
        }
        let largest = seen.iter().map(|&c| self.yty[(c, c)]).fold(0.0, f64::max);
        let weight = 100.0 * largest / seen.len() as f64;
        for &i in &seen {
            for &j in &seen {
                self.yty[(i, j)] += weight;
            }
        }
        self
    }

    /// `Σ ‖Y θ − τ‖²` for parameters `theta`.
    pub fn residual_sum_of_squares(&self, theta: &DVector<f64>) -> f64 {
        (theta.dot(&(&self.yty * theta)) - 2.0 * theta.dot(&self.ytt) + self.tt).max(0.0)
    }
}

/// Which products of a buffer of samples [`add_gram`] sums.
#[derive(Clone, Copy)]
enum Gram {
    /// Samples are the buffer's rows: `G += AᵀA` over its first `k` rows.
    RowsTimesRows,
    /// Samples are the buffer's columns: `G += A Aᵀ` over its first `k` columns.
    ColumnsTimesColumns,
}

/// The upper triangle of `g` (`c × c`) plus the Gram matrix of the first `k` samples of the
/// buffer `a`, by BLAS `dsyrk` (a symmetric rank-k update: half the work of a general
/// product), on one BLAS thread.
fn add_gram(layout: Gram, a: &DMatrix<f64>, k: usize, g: &mut DMatrix<f64>) {
    let (c, lda) = (g.ncols(), a.nrows());
    let (trans, samples_fit) = match layout {
        Gram::RowsTimesRows => (b'T', a.nrows() >= k && a.ncols() == c),
        Gram::ColumnsTimesColumns => (b'N', a.ncols() >= k && a.nrows() == c),
    };
    assert!(samples_fit && g.nrows() == c, "Gram buffer shapes");
    physid_core::spatial::single_threaded_blas();
    // SAFETY: `a` is column-major (`lda` rows) and holds at least `k` samples of `c` entries
    // (checked above); `g` is c×c.
    unsafe {
        blas::dsyrk(
            b'U',
            trans,
            c as i32,
            k as i32,
            1.0,
            a.as_slice(),
            lda as i32,
            1.0,
            g.as_mut_slice(),
            c as i32,
        );
    }
}

/// One joint's rows of the regressor over the columns they can touch ([`row_columns`]),
/// buffered transposed (column `s` of `rows` is the `s`-th buffered sample's row), and their
/// sums over those columns.
struct JointRows {
    joint: usize,
    cols: Vec<usize>,
    rows: DMatrix<f64>,
    taus: DVector<f64>,
    /// `Σ y yᵀ` over `cols` (upper triangle).
    gram: DMatrix<f64>,
    /// `Σ y τ` over `cols`.
    ytt: DVector<f64>,
}

/// Normal equations accumulated joint by joint: row `k` of each sample's `Y` is zero outside
/// the columns `C_k` (a model's regressor: `k`'s subtree and friction, [`row_columns`]; an
/// augmented regressor adds the effect columns row `k` can touch), so
/// `YᵀY = Σ_k Σ_s y_k y_kᵀ` costs `Σ_k |C_k|²` per sample instead of `n p²` (on a 3-joint leg
/// with rotors, 5,900 against 13,100). Entries outside `C_k` are not read: they must be zero.
///
/// [`row_columns`]: physid_core::dynamics::row_columns
pub struct RowSums {
    n: usize,
    p: usize,
    excluded: Vec<usize>,
    joints: Vec<JointRows>,
    filled: usize,
    samples: usize,
    tt: f64,
}

impl RowSums {
    /// Empty sums for `model`'s regressor, leaving out the rows of `excluded` joints.
    pub fn for_model(model: &Model, excluded: &[usize]) -> Self {
        let cols = physid_core::dynamics::row_columns(model);
        Self::new(model.dof(), model.layout().len, cols, excluded)
    }

    /// Empty sums for `n` joints' rows over `p` columns, row `k` nonzero only in the columns
    /// `row_columns[k]` (each below `p`, none repeated), leaving out the rows of `excluded`
    /// joints.
    pub fn new(n: usize, p: usize, row_columns: Vec<Vec<usize>>, excluded: &[usize]) -> Self {
        assert!(
            row_columns.len() == n && row_columns.iter().flatten().all(|&c| c < p),
            "row columns: one list per joint, each column below p"
        );
        let joints = row_columns
            .into_iter()
            .enumerate()
            .filter(|(k, _)| !excluded.contains(k))
            .map(|(joint, cols)| {
                let c = cols.len();
                JointRows {
                    joint,
                    cols,
                    rows: DMatrix::zeros(c, BLOCK_SAMPLES),
                    taus: DVector::zeros(BLOCK_SAMPLES),
                    gram: DMatrix::zeros(c, c),
                    ytt: DVector::zeros(c),
                }
            })
            .collect();
        Self {
            n,
            p,
            excluded: excluded.to_vec(),
            joints,
            filled: 0,
            samples: 0,
            tt: 0.0,
        }
    }

    /// Adds one sample's rows `y` (n×p) and torque `tau` (one per joint).
    pub fn add(&mut self, y: &DMatrix<f64>, tau: &[f64]) {
        let (n, s) = (self.n, self.filled);
        let y = y.as_slice();
        for jr in &mut self.joints {
            let column = &mut jr.rows.as_mut_slice()[s * jr.cols.len()..][..jr.cols.len()];
            for (out, &c) in column.iter_mut().zip(&jr.cols) {
                *out = y[c * n + jr.joint];
            }
            jr.taus[s] = tau[jr.joint];
        }
        self.filled += 1;
        self.samples += 1;
        if self.filled == BLOCK_SAMPLES {
            self.flush();
        }
    }

    /// Adds the buffered rows into each joint's sums (`gram` by BLAS `dsyrk`).
    fn flush(&mut self) {
        let k = self.filled;
        if k == 0 {
            return;
        }
        for jr in &mut self.joints {
            add_gram(Gram::ColumnsTimesColumns, &jr.rows, k, &mut jr.gram);
            let rows = jr.rows.columns(0, k);
            let taus = jr.taus.rows(0, k);
            jr.ytt.gemv(1.0, &rows, &taus, 1.0);
            self.tt += taus.norm_squared();
        }
        self.filled = 0;
    }

    /// The finished normal equations: each joint's sums added into `YᵀY` and `Yᵀτ` at its
    /// columns, joints in order.
    pub fn finish(mut self) -> NormalEquations {
        self.flush();
        let mut yty = DMatrix::zeros(self.p, self.p);
        let mut ytt = DVector::zeros(self.p);
        for jr in &self.joints {
            for (b, &cb) in jr.cols.iter().enumerate() {
                ytt[cb] += jr.ytt[b];
                for (a, &ca) in jr.cols.iter().enumerate().take(b + 1) {
                    yty[(ca, cb)] += jr.gram[(a, b)];
                }
            }
        }
        yty.fill_lower_triangle_with_upper_triangle();
        let mut ne = NormalEquations::from_sums(self.n, yty, ytt, self.tt, self.samples);
        ne.excluded = self.excluded;
        ne
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_selection_copies_each_chosen_entry_in_the_order_given() {
        // Runs of consecutive columns are copied as slices: the result must be the entrywise
        // definition for runs, gaps, repeats and columns out of order.
        let p = 9;
        let yty = DMatrix::from_fn(p, p, |i, j| (i * p + j) as f64 + 0.5 * (i + j) as f64);
        let ytt = DVector::from_fn(p, |i, _| 10.0 * i as f64);
        let ne = NormalEquations::from_sums(2, yty.clone(), ytt.clone(), 3.0, 7);
        for cols in [
            vec![0, 1, 2, 3, 4, 5, 6, 7, 8],
            vec![0, 1, 2, 5, 6, 8],
            vec![4, 5, 0, 1, 1, 2, 7],
            vec![8, 3],
            vec![],
        ] {
            let sub = ne.select(&cols);
            let m = cols.len();
            assert_eq!(
                sub.yty,
                DMatrix::from_fn(m, m, |i, j| yty[(cols[i], cols[j])])
            );
            assert_eq!(sub.ytt, DVector::from_fn(m, |i, _| ytt[cols[i]]));
            assert_eq!((sub.tt, sub.samples), (3.0, 7));
        }
    }

    #[test]
    fn sums_finished_then_added_to_are_the_sums_of_one_pass() {
        // `finish` releases the row buffer; samples added after it take a new one, and the sums
        // are those of one pass over every sample (the same flushes, bit for bit).
        let (n, p) = (2, 3);
        let sample = |k: usize| {
            let y = DMatrix::from_fn(n, p, |i, j| ((k * 7 + i * 3 + j) as f64 * 0.37).sin());
            let tau: Vec<f64> = (0..n).map(|i| ((k + i) as f64 * 0.11).cos()).collect();
            (y, tau)
        };
        let mut whole = NormalEquations::new(n, p);
        let mut parts = NormalEquations::new(n, p);
        for k in 0..BLOCK_SAMPLES {
            let (y, tau) = sample(k);
            whole.add(&y, &tau);
            parts.add(&y, &tau);
        }
        let mut parts = parts.finish();
        assert_eq!(parts.rows.nrows(), 0, "the buffer is released");
        for k in BLOCK_SAMPLES..BLOCK_SAMPLES + 40 {
            let (y, tau) = sample(k);
            whole.add(&y, &tau);
            parts.add(&y, &tau);
        }
        let (whole, parts) = (whole.finish(), parts.finish());
        assert_eq!(parts.samples, BLOCK_SAMPLES + 40);
        assert!(whole.yty.amax() > 1.0);
        assert_eq!(whole.yty, parts.yty);
        assert_eq!(whole.ytt, parts.ytt);
        assert_eq!(whole.tt, parts.tt);
    }

    #[test]
    fn a_pinned_mean_fixes_the_direction_the_data_leave_free_and_no_other() {
        // τ = (a − b) x + c d: the data see a − b and c; the mean of a and b is free (as a gain
        // common to every joint is free beside θ).
        let rows = [(1.0, 2.0), (2.0, -1.0), (3.0, 0.5), (-1.0, 1.0)];
        let (a, b, c) = (0.7, -0.3, -2.0);
        let mut yty = DMatrix::zeros(3, 3);
        let mut ytt = DVector::zeros(3);
        let mut tt = 0.0;
        for (x, d) in rows {
            let y = DVector::from_vec(vec![x, -x, d]);
            let t = (a - b) * x + c * d;
            yty += &y * y.transpose();
            ytt += &y * t;
            tt += t * t;
        }
        let ne = NormalEquations::from_sums(1, yty, ytt, tt, rows.len());
        assert_eq!(ne.yty.rank(1e-9), 2, "singular before");
        let pinned = ne.clone().with_mean_pinned(0..2);
        let x = pinned
            .yty
            .clone()
            .cholesky()
            .expect("pinned")
            .solve(&pinned.ytt);
        // The mean at its pin, the difference and c the data's; the data's sums (for scoring)
        // untouched.
        assert!(
            (x[0] - 0.5).abs() < 1e-9 && (x[1] + 0.5).abs() < 1e-9,
            "{x}"
        );
        assert!((x[2] - c).abs() < 1e-9, "{x}");
        assert!(ne.residual_sum_of_squares(&x) < 1e-12 * ne.tt);
        assert_eq!(pinned.ytt, ne.ytt);
        assert_eq!(pinned.tt, ne.tt);
        // A column the data never see (a locked joint's gain) stays out of the mean: pinned in,
        // it would take the pin's whole weight and leave the gauge free (on the KUKA with one
        // joint locked it read 15.7 while the six others kept a common −2.8).
        let mut yty4 = DMatrix::zeros(4, 4);
        yty4.view_mut((0, 0), (3, 3)).copy_from(&ne.yty);
        let mut ytt4 = DVector::zeros(4);
        ytt4.rows_mut(0, 3).copy_from(&ne.ytt);
        let mut four = NormalEquations::from_sums(1, yty4, ytt4, ne.tt, rows.len());
        // The unseen column moved to 2, `d` to 3; columns 0–2 pinned: only 0 and 1 enter.
        four.yty.swap_rows(2, 3);
        four.yty.swap_columns(2, 3);
        four.ytt.swap_rows(2, 3);
        let pinned = four.clone().with_mean_pinned(0..3);
        assert_eq!(pinned.yty.row(2).iter().filter(|v| **v != 0.0).count(), 0);
        assert!(pinned.yty[(0, 1)] > four.yty[(0, 1)]);
    }
}
