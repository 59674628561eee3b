//! One builder of conic programs for Clarabel, used by identification (`ident`: the LMIs of
//! the constraint sets and the log-det regularizer) and by the bounding ellipsoids
//! (`spatial::bounding`: the S-procedure LMIs and `log det A`).
//!
//! A program's constraints are rows `A x + s = b` with `s` in a product of cones, assembled as
//! triplets of `A` in cone order. A symmetric matrix affine in `x`, `M(x) = M₀ + Σ_k x_k M_k`,
//! enters the PSD cone as `s = svec(M(x))`: Clarabel's column-wise upper triangle with the
//! off-diagonal entries times √2 (so that `svec(A)·svec(B) = tr(A B)`), i.e. `b = svec(M₀)` and
//! `A = −svec(M_k)` column by column. The log-det device bounds `log det M ≥ Σ tᵢ` through a
//! triangular factor `F`: `[[M, F], [Fᵀ, diag F]] ⪰ 0` and `(tᵢ, 1, Fᵢᵢ)` in the exponential
//! cone (`tᵢ ≤ log Fᵢᵢ`), with `F` lower or upper triangular as the caller lays it out.

use clarabel::algebra::CscMatrix;
use clarabel::solver::SupportedConeT;

/// The rows `A x + s = b`, `s` in `cones`, as triplets of `A`.
#[derive(Default)]
pub struct ConeRows {
    ai: Vec<usize>,
    aj: Vec<usize>,
    av: Vec<f64>,
    b: Vec<f64>,
    cones: Vec<SupportedConeT<f64>>,
}

/// A symmetric matrix affine in the variables, entry by entry over its upper triangle: per
/// entry the constant and `(variable, coefficient)` terms.
pub struct AffineSym {
    n: usize,
    entries: Vec<(f64, Vec<(usize, f64)>)>,
}

impl AffineSym {
    /// The zero `n × n` matrix.
    pub fn new(n: usize) -> Self {
        Self {
            n,
            entries: vec![(0.0, vec![]); n * (n + 1) / 2],
        }
    }

    /// Entry `(i, j)` (either triangle: the matrix is symmetric), its constant and terms.
    pub fn at(&mut self, i: usize, j: usize) -> &mut (f64, Vec<(usize, f64)>) {
        let (i, j) = (i.min(j), i.max(j));
        &mut self.entries[j * (j + 1) / 2 + i]
    }
}

impl ConeRows {
    /// The index of the next row.
    pub fn next_row(&self) -> usize {
        self.b.len()
    }

    /// `A[row, col] = v` in `A`'s own sign (`s = b − A x`), a zero skipped (no structural
    /// entry).
    pub fn entry(&mut self, row: usize, col: usize, v: f64) {
        if v != 0.0 {
            self.ai.push(row);
            self.aj.push(col);
            self.av.push(v);
        }
    }

    /// Ends a cone over the rows since the last one, with their `b` entries.
    pub fn close(&mut self, b: impl IntoIterator<Item = f64>, cone: SupportedConeT<f64>) {
        self.b.extend(b);
        self.cones.push(cone);
    }

    /// `M(x) ⪰ 0`: `svec(M(x))` in the PSD cone. Every term is kept as given, a zero
    /// coefficient as a structural entry.
    pub fn psd(&mut self, m: &AffineSym) {
        let r0 = self.next_row();
        let s2 = std::f64::consts::SQRT_2;
        let mut b = Vec::with_capacity(m.entries.len());
        for j in 0..m.n {
            for i in 0..=j {
                let k = j * (j + 1) / 2 + i;
                let w = if i == j { 1.0 } else { s2 };
                let (c, terms) = &m.entries[k];
                b.push(w * c);
                for &(v, coef) in terms {
                    self.ai.push(r0 + k);
                    self.aj.push(v);
                    self.av.push(-w * coef);
                }
            }
        }
        self.close(b, SupportedConeT::PSDTriangleConeT(m.n));
    }

    /// `(b₀ + a₀(x), b₁ + a₁(x), …)` in the second-order cone (`‖(s₁, …)‖ ≤ s₀`), each `aᵣ`
    /// a list of `(variable, coefficient)` terms kept as given.
    pub fn second_order(&mut self, b: &[f64], a: &[Vec<(usize, f64)>]) {
        let r0 = self.next_row();
        for (r, terms) in a.iter().enumerate() {
            for &(v, coef) in terms {
                self.ai.push(r0 + r);
                self.aj.push(v);
                self.av.push(-coef);
            }
        }
        self.close(b.iter().copied(), SupportedConeT::SecondOrderConeT(b.len()));
    }

    /// `(x_t, 1, x_z)` in the exponential cone: `x_t ≤ log x_z`.
    pub fn exp_cone(&mut self, t: usize, z: usize) {
        let r = self.next_row();
        self.entry(r, t, -1.0);
        self.entry(r + 2, z, -1.0);
        self.close([0.0, 1.0, 0.0], SupportedConeT::ExponentialConeT());
    }

    /// `log det M ≥ Σ tᵢ` for the `k × k` matrix `m` (see the module docs): `factor(r, c)` is
    /// the variable of the factor's entry `(r, c)`, `None` off its triangle, `t(i)` the
    /// variable bounded by `log Fᵢᵢ`.
    pub fn log_det(
        &mut self,
        mut m: AffineSym,
        factor: impl Fn(usize, usize) -> Option<usize>,
        t: impl Fn(usize) -> usize,
    ) {
        let k = m.n;
        let mut big = AffineSym::new(2 * k);
        for j in 0..k {
            for i in 0..=j {
                *big.at(i, j) = std::mem::take(m.at(i, j));
            }
        }
        for r in 0..k {
            for c in 0..k {
                if let Some(v) = factor(r, c) {
                    big.at(r, k + c).1.push((v, 1.0));
                }
            }
        }
        let diag = |i: usize| factor(i, i).expect("a triangular factor has its diagonal");
        for i in 0..k {
            big.at(k + i, k + i).1.push((diag(i), 1.0));
        }
        self.psd(&big);
        for i in 0..k {
            self.exp_cone(t(i), diag(i));
        }
    }

    /// `A` over `nv` variables, `b` and the cones, for the solver.
    pub fn into_parts(self, nv: usize) -> (CscMatrix<f64>, Vec<f64>, Vec<SupportedConeT<f64>>) {
        let a = CscMatrix::new_from_triplets(self.b.len(), nv, self.ai, self.aj, self.av);
        (a, self.b, self.cones)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clarabel::solver::{DefaultSettings, DefaultSolver, IPSolver, SolverStatus};

    fn solve(rows: ConeRows, q: &[f64]) -> Vec<f64> {
        let nv = q.len();
        let (a, b, cones) = rows.into_parts(nv);
        let p = CscMatrix::zeros((nv, nv));
        // Tight tolerances: the tests check the formulation. At 1e-11 the exponential cones stall
        // at "almost solved" on some CPUs (OpenBLAS's AVX-512 kernels), a hair short of the gap.
        let settings = DefaultSettings {
            verbose: false,
            tol_gap_abs: 1e-10,
            tol_gap_rel: 1e-10,
            tol_feas: 1e-10,
            ..DefaultSettings::default()
        };
        let mut solver = DefaultSolver::new(&p, q, &a, &b, &cones, settings).unwrap();
        solver.solve();
        assert_eq!(solver.solution.status, SolverStatus::Solved);
        solver.solution.x.clone()
    }

    /// `svec` rows: `[[x₀, x₁], [x₁, x₂]] ⪰ 0` with `x₀ + x₂ = 2` (two non-negative rows
    /// against each other) maximizing `x₁` gives the rank-one `[[1, 1], [1, 1]]`.
    #[test]
    fn psd_rows_carry_the_svec_layout() {
        let mut rows = ConeRows::default();
        let mut m = AffineSym::new(2);
        m.at(0, 0).1.push((0, 1.0));
        m.at(1, 0).1.push((1, 1.0));
        m.at(1, 1).1.push((2, 1.0));
        rows.psd(&m);
        let r = rows.next_row();
        assert_eq!(r, 3);
        rows.entry(r, 0, 1.0);
        rows.entry(r, 2, 1.0);
        rows.entry(r, 1, 0.0);
        rows.close([2.0], SupportedConeT::ZeroConeT(1));
        let x = solve(rows, &[0.0, -1.0, 0.0]);
        for (xi, want) in x.iter().zip([1.0, 1.0, 1.0]) {
            assert!((xi - want).abs() < 1e-7, "{x:?}");
        }
    }

    /// The log-det device, both triangles: `log det diag(x₀, x₁)` at its maximum on
    /// `x₀ + x₁ ≤ 3` is `2 log 1.5`, reached at `x₀ = x₁ = 1.5`.
    #[test]
    fn log_det_bounds_the_determinant_with_either_triangle() {
        for lower in [true, false] {
            let mut rows = ConeRows::default();
            let mut m = AffineSym::new(2);
            m.at(0, 0).1.push((0, 1.0));
            m.at(1, 1).1.push((1, 1.0));
            // Variables: x₀, x₁, F's three entries (2..5), t₀, t₁ (5, 6).
            let factor = move |r: usize, c: usize| match (r, c) {
                (0, 0) => Some(2),
                (1, 1) => Some(4),
                (1, 0) if lower => Some(3),
                (0, 1) if !lower => Some(3),
                _ => None,
            };
            rows.log_det(m, factor, |i| 5 + i);
            let r = rows.next_row();
            rows.entry(r, 0, 1.0);
            rows.entry(r, 1, 1.0);
            rows.close([3.0], SupportedConeT::NonnegativeConeT(1));
            let x = solve(rows, &[0.0, 0.0, 0.0, 0.0, 0.0, -1.0, -1.0]);
            // The objective to the solver's tolerance; the point only to its square root (the
            // optimum is flat to second order along x₀ − x₁).
            assert!((x[5] + x[6] - 2.0 * 1.5f64.ln()).abs() < 1e-9, "{x:?}");
            assert!(
                (x[0] - 1.5).abs() < 1e-4 && (x[1] - 1.5).abs() < 1e-4,
                "{x:?}"
            );
            assert!((x[0] + x[1] - 3.0).abs() < 1e-9, "{x:?}");
        }
    }

    /// `‖(x₀ − 3, x₁ − 4)‖ ≤ 1` closest to the origin: `(3, 4) · (1 − 1/5)`.
    #[test]
    fn second_order_rows_bound_a_norm() {
        let mut rows = ConeRows::default();
        rows.second_order(
            &[1.0, -3.0, -4.0],
            &[vec![], vec![(0, 1.0)], vec![(1, 1.0)]],
        );
        // Minimize t with ‖(x₀, x₁)‖ ≤ t: t is variable 2.
        rows.second_order(&[0.0; 3], &[vec![(2, 1.0)], vec![(0, 1.0)], vec![(1, 1.0)]]);
        let x = solve(rows, &[0.0, 0.0, 1.0]);
        assert!(
            (x[0] - 2.4).abs() < 1e-6 && (x[1] - 3.2).abs() < 1e-6,
            "{x:?}"
        );
    }
}
