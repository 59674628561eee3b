//! A dense primal-dual interior-point method for identification's small cone programs.
//!
//! `min ½ xᵀ P x + qᵀ x` subject to `A x + s = b`, `s ∈ K`, where `K` is a product of
//! non-negative orthants and positive semidefinite cones (`svec`, upper triangle column by column,
//! off-diagonal entries times √2: Clarabel's `PSDTriangle`). Identification's programs have about
//! a hundred variables, a dense `P`, one 4×4 (or 6×6) matrix inequality per body over that body's
//! ten columns, and a few non-negative rows. A general sparse solver spends most of its time on
//! that generality here; this one forms the Newton system densely, `P + Ãᵀ Ã` with
//! `Ã = W⁻ᵀ A`, adding each cone's block only on the columns it touches, and factors it by
//! LAPACK's Cholesky.
//!
//! The method is the one of Vandenberghe's `coneqp` (CVXOPT): Nesterov–Todd scaling `W`, with
//! `W z = W⁻ᵀ s = λ`, Mehrotra's predictor–corrector, and CVXOPT's starting point. It stops on
//! Clarabel's default tolerances (relative feasibility 1e-8, gap 1e-8 absolute or relative), so
//! an optimum it returns is one Clarabel would accept. Where it cannot go on (a singular
//! Newton system or cone scaling near a degenerate optimum, a step that stalls, 60 iterations)
//! it returns its last iterate within reduced tolerances (10⁻⁶, a fiftieth of Clarabel's own
//! "almost solved" ones), marked as such; short of those it returns `None` and the caller
//! hands the same program to Clarabel, which stays the reference solver. The diagnosis's
//! cross-validation fits stop short most often: bodies at the boundary `J ⪰ 0`, where the
//! dual residual stalls near 10⁻⁷.

use crate::lmi::{smat, smat4, svec};
use nalgebra::{DMatrix, DVector};

/// A cone of `K`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Cone {
    /// `n` non-negative rows.
    Nonneg(usize),
    /// A `k × k` positive semidefinite matrix in `k(k+1)/2` `svec` rows.
    Psd(usize),
}

impl Cone {
    fn rows(self) -> usize {
        match self {
            Cone::Nonneg(n) => n,
            Cone::Psd(k) => k * (k + 1) / 2,
        }
    }

    /// The cone's degree: its share of `ν` in `μ = sᵀz / ν`.
    fn degree(self) -> usize {
        match self {
            Cone::Nonneg(n) | Cone::Psd(n) => n,
        }
    }
}

/// The program, `A` dense (`m × n`).
pub(crate) struct Program<'a> {
    pub p: &'a DMatrix<f64>,
    pub q: &'a [f64],
    pub a: &'a DMatrix<f64>,
    pub b: &'a [f64],
    pub cones: &'a [Cone],
}

/// An optimum to the tolerances.
pub(crate) struct Optimum {
    pub x: Vec<f64>,
    pub iterations: u32,
    /// Relative primal and dual residuals at the optimum.
    pub residuals: [f64; 2],
    /// Whether only the reduced tolerances ([`REDUCED_TOLERANCE`]) are met: the method
    /// stopped before the full ones, at a point within the reduced ones.
    pub reduced: bool,
}

const TOLERANCE: f64 = 1e-8;
/// The tolerances an iterate must meet to be returned where the method cannot go on (its
/// Newton system or a cone's scaling no longer factors near a degenerate optimum, a step
/// stalls, or the iterations run out): the relative residuals and the gap (absolute or
/// relative) below 10⁻⁶, a fiftieth of Clarabel's own reduced tolerances (5·10⁻⁵ on the gap,
/// 10⁻⁴ on feasibility), under which it reports "almost solved".
const REDUCED_TOLERANCE: f64 = 1e-6;
const MAX_ITERATIONS: u32 = 60;
/// The fraction of the way to the cone's boundary a step goes.
const STEP_FRACTION: f64 = 0.99;

/// One cone's rows, the columns of `A` it touches, `A` on those rows and columns, and its
/// scaling at the current point.
struct Block {
    cone: Cone,
    row0: usize,
    cols: Vec<usize>,
    a: DMatrix<f64>,
    scaling: Scaling,
}

/// Nesterov–Todd scaling of one cone at `(s, z)`, and the scaled point `λ`.
enum Scaling {
    /// `W = diag(w)`, `w = √(s/z)`; `λ = √(s z)`.
    Nonneg { w: Vec<f64>, lambda: Vec<f64> },
    /// `W(Z) = Rᵀ Z R`, `W⁻ᵀ(S) = R⁻¹ S R⁻ᵀ`; `λ = diag(Λ)`, `Λ = W(Z) = W⁻ᵀ(S)`.
    Psd {
        r: DMatrix<f64>,
        r_inv: DMatrix<f64>,
        lambda: Vec<f64>,
    },
}

/// Solves `program` to the full tolerances, or where the method stops short of them, to the
/// reduced ones ([`Optimum::reduced`]); `None` where it reaches neither.
pub(crate) fn solve(program: &Program) -> Option<Optimum> {
    solve_within(program, MAX_ITERATIONS)
}

/// [`solve`] in at most `max_iterations` iterations.
fn solve_within(program: &Program, max_iterations: u32) -> Option<Optimum> {
    let (m, n) = program.a.shape();
    if program.cones.iter().map(|c| c.rows()).sum::<usize>() != m || program.b.len() != m {
        return None;
    }
    let mut blocks = blocks(program);
    let nu: usize = program.cones.iter().map(|c| c.degree()).sum();
    let (mut x, mut s, mut z) = start(program, &blocks)?;
    let (q, b) = (
        DVector::from_column_slice(program.q),
        DVector::from_column_slice(program.b),
    );
    // The last iterate within the reduced tolerances, returned where the method stops short.
    let mut reduced: Option<Optimum> = None;
    for iteration in 0..=max_iterations {
        let px = program.p * &x;
        let r_x = &px + &q + program.a.tr_mul(&z);
        let r_z = a_times(&blocks, &x, m) + &s - &b;
        let measures = Measures::at(&x, &s, &z, (&px, &q, &b), (&r_x, &r_z));
        if !measures.finite() {
            return reduced;
        }
        let optimum = |reduced| Optimum {
            x: x.as_slice().to_vec(),
            iterations: iteration,
            residuals: measures.residuals,
            reduced,
        };
        if measures.within(TOLERANCE) {
            return Some(optimum(false));
        }
        if measures.within(REDUCED_TOLERANCE) {
            reduced = Some(optimum(true));
        }
        if iteration == max_iterations {
            return reduced;
        }
        let Some(newton) = rescaled(program, &mut blocks, (&s, &z), n) else {
            return reduced;
        };
        let mu = s.dot(&z) / nu as f64;
        let lambda_sq = jordan_self(&blocks, m);
        let affine = newton.solve(&blocks, &r_x, &r_z, &(-&lambda_sq));
        let alpha_affine = step_length(&blocks, &affine.1, &affine.2).min(1.0);
        let sigma = (1.0 - alpha_affine).powi(3);
        let e = identity(&blocks, m);
        let cross = jordan(&blocks, &affine.1, &affine.2);
        let target = e * (sigma * mu) - &lambda_sq - cross;
        let (dx, ds_scaled, dz_scaled) = newton.solve(&blocks, &r_x, &r_z, &target);
        let alpha = (STEP_FRACTION * step_length(&blocks, &ds_scaled, &dz_scaled)).min(1.0);
        if alpha.is_nan() || alpha <= 1e-10 {
            return reduced;
        }
        x += dx * alpha;
        s += unscale_s(&blocks, &ds_scaled) * alpha;
        z += unscale_z(&blocks, &dz_scaled) * alpha;
    }
    reduced
}

/// Clarabel's measures of convergence at `(x, s, z)`: the residuals relative to the data's
/// and the point's norms, and the gap between the primal and dual objectives, absolute and
/// relative to the smaller objective (at least 1).
struct Measures {
    residuals: [f64; 2],
    gap: f64,
    relative_gap: f64,
}

impl Measures {
    fn at(
        x: &DVector<f64>,
        s: &DVector<f64>,
        z: &DVector<f64>,
        (px, q, b): (&DVector<f64>, &DVector<f64>, &DVector<f64>),
        (r_x, r_z): (&DVector<f64>, &DVector<f64>),
    ) -> Measures {
        let (x_norm, s_norm, z_norm) = (x.norm(), s.norm(), z.norm());
        let primal_residual = r_z.norm() / (b.norm() + x_norm + s_norm).max(1.0);
        let dual_residual = r_x.norm() / (q.norm() + x_norm + z_norm).max(1.0);
        let half_xpx = 0.5 * x.dot(px);
        let primal = half_xpx + q.dot(x);
        let dual = -b.dot(z) - half_xpx;
        let gap = (primal - dual).abs();
        Measures {
            residuals: [primal_residual, dual_residual],
            gap,
            relative_gap: gap / primal.abs().min(dual.abs()).max(1.0),
        }
    }

    fn finite(&self) -> bool {
        self.gap.is_finite() && self.residuals.iter().all(|r| r.is_finite())
    }

    /// Whether the relative residuals and the gap (absolute or relative) are below `tolerance`.
    fn within(&self, tolerance: f64) -> bool {
        self.residuals.iter().all(|&r| r < tolerance)
            && (self.gap < tolerance || self.relative_gap < tolerance)
    }
}

/// The cones' row ranges and the columns of `A` each touches.
fn blocks(program: &Program) -> Vec<Block> {
    let mut row0 = 0;
    program
        .cones
        .iter()
        .map(|&cone| {
            let rows = row0..row0 + cone.rows();
            let cols: Vec<usize> = (0..program.a.ncols())
                .filter(|&j| rows.clone().any(|r| program.a[(r, j)] != 0.0))
                .collect();
            let a = DMatrix::from_fn(rows.len(), cols.len(), |r, c| {
                program.a[(rows.start + r, cols[c])]
            });
            row0 += cone.rows();
            let scaling = match cone {
                Cone::Nonneg(_) => Scaling::Nonneg {
                    w: vec![],
                    lambda: vec![],
                },
                Cone::Psd(_) => Scaling::Psd {
                    r: DMatrix::zeros(0, 0),
                    r_inv: DMatrix::zeros(0, 0),
                    lambda: vec![],
                },
            };
            Block {
                cone,
                row0: rows.start,
                cols,
                a,
                scaling,
            }
        })
        .collect()
}

/// `A x` (`m` rows), each cone's rows on the columns it touches (`A` is zero elsewhere): the
/// dense product's terms, added in the same order, without its zeros.
fn a_times(blocks: &[Block], x: &DVector<f64>, m: usize) -> DVector<f64> {
    let mut out = DVector::zeros(m);
    for block in blocks {
        let x_cols = DVector::from_iterator(block.cols.len(), block.cols.iter().map(|&c| x[c]));
        out.rows_mut(block.row0, block.cone.rows())
            .copy_from(&(&block.a * x_cols));
    }
    out
}

/// CVXOPT's starting point: `x` minimizing `½ xᵀPx + qᵀx + ½ ‖Ax − b‖²`, and `s = b − Ax`,
/// `z = Ax − b`, each moved into its cone's interior along `e` where it is not inside.
fn start(
    program: &Program,
    blocks: &[Block],
) -> Option<(DVector<f64>, DVector<f64>, DVector<f64>)> {
    let a = program.a;
    let mut h = program.p.clone();
    for block in blocks {
        add_on_columns(&mut h, &block.cols, &block.a.tr_mul(&block.a));
    }
    let rhs =
        a.tr_mul(&DVector::from_column_slice(program.b)) - DVector::from_column_slice(program.q);
    let x = Cholesky::new(h)?.solve(&rhs);
    let s_hat = DVector::from_column_slice(program.b) - a * &x;
    let z_hat = -&s_hat;
    let m = s_hat.len();
    let e = identity(blocks, m);
    let inside = |v: &DVector<f64>| {
        let shortfall = -min_eigenvalue(blocks, v)?;
        Some(if shortfall < 0.0 {
            v.clone()
        } else {
            v + &e * (1.0 + shortfall)
        })
    };
    Some((x, inside(&s_hat)?, inside(&z_hat)?))
}

/// The smallest eigenvalue over every cone of `v` (elements of the orthants).
fn min_eigenvalue(blocks: &[Block], v: &DVector<f64>) -> Option<f64> {
    let mut least = f64::INFINITY;
    for block in blocks {
        let rows = v.rows(block.row0, block.cone.rows());
        let low = match block.cone {
            Cone::Nonneg(_) => rows.min(),
            Cone::Psd(k) => least_eigenvalue(rows.as_slice(), k, |_, _| 1.0, f64::NEG_INFINITY),
        };
        if !low.is_finite() {
            return None;
        }
        least = least.min(low);
    }
    Some(least)
}

/// The least eigenvalue of `M`, `M_ij = smat(v)_ij / divisor(i, j)` (`k × k`), where it is
/// at most `floor`; `+∞` where `M − floor · 1` factors by Cholesky (every eigenvalue is above
/// `floor`; never with `floor = −∞`). By fixed-size arithmetic for the pseudo-inertia's 4 × 4
/// cones: the same algorithm on the same numbers as the general path, without allocating.
fn least_eigenvalue(v: &[f64], k: usize, divisor: impl Fn(usize, usize) -> f64, floor: f64) -> f64 {
    if k == 4 {
        let s = smat4(v);
        let m = nalgebra::Matrix4::from_fn(|i, j| s[(i, j)] / divisor(i, j));
        let above = floor.is_finite()
            && (m - nalgebra::Matrix4::identity() * floor)
                .cholesky()
                .is_some();
        return if above {
            f64::INFINITY
        } else {
            m.symmetric_eigenvalues().min()
        };
    }
    let s = smat(v, k);
    let m = DMatrix::from_fn(k, k, |i, j| s[(i, j)] / divisor(i, j));
    let above = floor.is_finite() && (&m - DMatrix::identity(k, k) * floor).cholesky().is_some();
    if above {
        f64::INFINITY
    } else {
        m.symmetric_eigenvalues().min()
    }
}

/// `R = L_s V Λ^{-1/2}`, `R⁻¹ = Λ^{-1/2} Uᵀ L_zᵀ` and `λ` of the Nesterov–Todd scaling of one
/// PSD cone at `(S, Z)` (square matrices, fixed-size or not); `None` off the cone's interior.
macro_rules! psd_scaling {
    ($s:expr, $z:expr) => {{
        let l_s = $s.cholesky()?.unpack();
        let l_z = $z.cholesky()?.unpack();
        let svd = (l_z.transpose() * &l_s).svd(true, true);
        let (u, v_t) = (svd.u?, svd.v_t?);
        let lambda: Vec<f64> = svd.singular_values.iter().copied().collect();
        if lambda.iter().any(|&l| l.is_nan() || l <= 0.0) {
            return None;
        }
        let mut inv_sqrt = l_s.clone();
        inv_sqrt.fill(0.0);
        for (i, l) in lambda.iter().enumerate() {
            inv_sqrt[(i, i)] = 1.0 / l.sqrt();
        }
        let r = l_s * v_t.transpose() * &inv_sqrt;
        let r_inv = inv_sqrt * u.transpose() * l_z.transpose();
        (r.as_slice().to_vec(), r_inv.as_slice().to_vec(), lambda)
    }};
}

/// The Nesterov–Todd scaling of `block` at `(s, z)`; `None` off the cone's interior.
fn scaling(block: &Block, s: &DVector<f64>, z: &DVector<f64>) -> Option<Scaling> {
    let rows = block.row0..block.row0 + block.cone.rows();
    match block.cone {
        Cone::Nonneg(_) => {
            let (s, z) = (&s.as_slice()[rows.clone()], &z.as_slice()[rows]);
            if s.iter().chain(z).any(|&v| v.is_nan() || v <= 0.0) {
                return None;
            }
            Some(Scaling::Nonneg {
                w: s.iter().zip(z).map(|(s, z)| (s / z).sqrt()).collect(),
                lambda: s.iter().zip(z).map(|(s, z)| (s * z).sqrt()).collect(),
            })
        }
        Cone::Psd(k) => {
            let (s, z) = (&s.as_slice()[rows.clone()], &z.as_slice()[rows]);
            let (r, r_inv, lambda) = if k == 4 {
                psd_scaling!(smat4(s), smat4(z))
            } else {
                psd_scaling!(smat(s, k), smat(z, k))
            };
            Some(Scaling::Psd {
                r: DMatrix::from_vec(k, k, r),
                r_inv: DMatrix::from_vec(k, k, r_inv),
                lambda,
            })
        }
    }
}

/// The cones' scalings at `(s, z)` and the Newton system factored there; `None` where a
/// scaling or the factorization fails (a point numerically off a cone's interior).
fn rescaled(
    program: &Program,
    blocks: &mut [Block],
    (s, z): (&DVector<f64>, &DVector<f64>),
    n: usize,
) -> Option<Newton> {
    for block in blocks.iter_mut() {
        block.scaling = scaling(block, s, z)?;
    }
    Newton::factor(program, blocks, n)
}

/// The factored Newton system `P + Ãᵀ Ã`, `Ã = W⁻ᵀ A`, with each cone's `Ã` rows kept on the
/// columns the cone touches.
struct Newton {
    cholesky: Cholesky,
    /// Per block, `W⁻ᵀ A[rows, cols]`.
    scaled: Vec<DMatrix<f64>>,
}

impl Newton {
    fn factor(program: &Program, blocks: &[Block], n: usize) -> Option<Newton> {
        let mut h = program.p.clone();
        let mut scaled = Vec::with_capacity(blocks.len());
        for block in blocks {
            let mut a_scaled = block.a.clone();
            for mut column in a_scaled.column_iter_mut() {
                let v = w_inv_t(&block.scaling, column.as_slice());
                column.copy_from_slice(&v);
            }
            add_on_columns(&mut h, &block.cols, &a_scaled.tr_mul(&a_scaled));
            scaled.push(a_scaled);
        }
        debug_assert_eq!(h.nrows(), n);
        Some(Newton {
            cholesky: Cholesky::new(h)?,
            scaled,
        })
    }

    /// The direction `(dx, W⁻ᵀ ds, W dz)` of `P dx + Aᵀ dz = −r_x`, `A dx + ds = −r_z`,
    /// `λ ∘ (W⁻ᵀ ds + W dz) = target`.
    fn solve(
        &self,
        blocks: &[Block],
        r_x: &DVector<f64>,
        r_z: &DVector<f64>,
        target: &DVector<f64>,
    ) -> (DVector<f64>, DVector<f64>, DVector<f64>) {
        let m = r_z.len();
        // t = W⁻ᵀ r_z + λ ◇ target, per block.
        let mut t = DVector::zeros(m);
        for block in blocks {
            let range = block.row0..block.row0 + block.cone.rows();
            let scaled_rz = w_inv_t(&block.scaling, &r_z.as_slice()[range.clone()]);
            let v = lambda_divide(block, &target.as_slice()[range.clone()]);
            for (k, i) in range.enumerate() {
                t[i] = scaled_rz[k] + v[k];
            }
        }
        let mut rhs = -r_x;
        for (block, a_scaled) in blocks.iter().zip(&self.scaled) {
            let tb = t.rows(block.row0, block.cone.rows());
            let contribution = a_scaled.tr_mul(&tb);
            for (c, &col) in block.cols.iter().enumerate() {
                rhs[col] -= contribution[c];
            }
        }
        let dx = self.cholesky.solve(&rhs);
        let mut dz_scaled = t;
        let mut ds_scaled = DVector::zeros(m);
        for (block, a_scaled) in blocks.iter().zip(&self.scaled) {
            let dx_cols =
                DVector::from_iterator(block.cols.len(), block.cols.iter().map(|&c| dx[c]));
            let a_dx = a_scaled * dx_cols;
            let range = block.row0..block.row0 + block.cone.rows();
            let v = lambda_divide(block, &target.as_slice()[range.clone()]);
            for (k, i) in range.enumerate() {
                dz_scaled[i] += a_dx[k];
                ds_scaled[i] = v[k] - dz_scaled[i];
            }
        }
        (dx, ds_scaled, dz_scaled)
    }
}

/// `h[cols, cols] += gram`.
fn add_on_columns(h: &mut DMatrix<f64>, cols: &[usize], gram: &DMatrix<f64>) {
    for (j, &cj) in cols.iter().enumerate() {
        for (i, &ci) in cols.iter().enumerate() {
            h[(ci, cj)] += gram[(i, j)];
        }
    }
}

/// The Cholesky factor `H = L Lᵀ` of a symmetric positive definite matrix, by LAPACK
/// (`dpotrf`, `dpotrs`, on OpenBLAS's one thread): the Newton system of about a hundred
/// unknowns is factored every iteration, where LAPACK's blocked factorization takes about
/// 60 % of nalgebra's time.
struct Cholesky {
    /// `L` in the lower triangle (column-major, `n × n`); the strict upper triangle is `H`'s.
    l: DMatrix<f64>,
}

impl Cholesky {
    /// `None` where `h` is not numerically positive definite (or holds a NaN).
    fn new(mut h: DMatrix<f64>) -> Option<Cholesky> {
        let n = h.nrows();
        assert_eq!(n, h.ncols(), "a square matrix");
        if n == 0 {
            return Some(Cholesky { l: h });
        }
        physid_core::spatial::single_threaded_blas();
        let mut info = 0;
        // SAFETY: `h` is a column-major n × n buffer with leading dimension n.
        unsafe { lapack::dpotrf(b'L', n as i32, h.as_mut_slice(), n as i32, &mut info) };
        let finite = (0..n).all(|i| h[(i, i)].is_finite() && h[(i, i)] > 0.0);
        (info == 0 && finite).then_some(Cholesky { l: h })
    }

    /// `H⁻¹ b`.
    fn solve(&self, b: &DVector<f64>) -> DVector<f64> {
        let n = self.l.nrows();
        let mut x = b.clone();
        if n == 0 {
            return x;
        }
        let mut info = 0;
        // SAFETY: `l` holds dpotrf's factor of an n × n matrix; `x` has n entries (one column).
        unsafe {
            lapack::dpotrs(
                b'L',
                n as i32,
                1,
                self.l.as_slice(),
                n as i32,
                x.as_mut_slice(),
                n as i32,
                &mut info,
            )
        };
        debug_assert_eq!(info, 0, "dpotrs's arguments");
        x
    }
}

/// `W⁻ᵀ v` on one cone's rows.
fn w_inv_t(scaling: &Scaling, v: &[f64]) -> Vec<f64> {
    match scaling {
        Scaling::Nonneg { w, .. } => v.iter().zip(w).map(|(v, w)| v / w).collect(),
        Scaling::Psd { r_inv, .. } => congruence(r_inv, v),
    }
}

/// `svec(M smat(v) Mᵀ)` of one PSD cone's rows `v` (`M` is `k × k`): by fixed-size
/// arithmetic for the pseudo-inertia's 4 × 4 cones, without allocating.
fn congruence(m: &DMatrix<f64>, v: &[f64]) -> Vec<f64> {
    let k = m.nrows();
    if k != 4 {
        return svec(&(m * smat(v, k) * m.transpose()));
    }
    let m4 = nalgebra::Matrix4::from_column_slice(m.as_slice());
    svec(&(m4 * smat4(v) * m4.transpose()))
}

/// `ds = Wᵀ d̃s` over every block.
fn unscale_s(blocks: &[Block], ds_scaled: &DVector<f64>) -> DVector<f64> {
    map_blocks(blocks, ds_scaled, |scaling, v| match scaling {
        Scaling::Nonneg { w, .. } => v.iter().zip(w).map(|(v, w)| v * w).collect(),
        Scaling::Psd { r, .. } => congruence(r, v),
    })
}

/// `dz = W⁻¹ d̃z` over every block.
fn unscale_z(blocks: &[Block], dz_scaled: &DVector<f64>) -> DVector<f64> {
    map_blocks(blocks, dz_scaled, |scaling, v| match scaling {
        Scaling::Nonneg { w, .. } => v.iter().zip(w).map(|(v, w)| v / w).collect(),
        Scaling::Psd { r_inv, .. } => congruence(&r_inv.transpose(), v),
    })
}

fn map_blocks(
    blocks: &[Block],
    v: &DVector<f64>,
    f: impl Fn(&Scaling, &[f64]) -> Vec<f64>,
) -> DVector<f64> {
    let mut out = DVector::zeros(v.len());
    for block in blocks {
        let range = block.row0..block.row0 + block.cone.rows();
        let mapped = f(&block.scaling, &v.as_slice()[range.clone()]);
        out.rows_mut(block.row0, mapped.len())
            .copy_from_slice(&mapped);
    }
    out
}

/// `u` with `λ ∘ u = v` on one block (`λ` diagonal in the PSD cones:
/// `u_ij = 2 v_ij / (λ_i + λ_j)`).
fn lambda_divide(block: &Block, v: &[f64]) -> Vec<f64> {
    match &block.scaling {
        Scaling::Nonneg { lambda, .. } => v.iter().zip(lambda).map(|(v, l)| v / l).collect(),
        Scaling::Psd { lambda, .. } => svec_entries(lambda.len())
            .zip(v)
            .map(|((i, j), v)| 2.0 * v / (lambda[i] + lambda[j]))
            .collect(),
    }
}

/// `λ ∘ λ` over every block.
fn jordan_self(blocks: &[Block], m: usize) -> DVector<f64> {
    let mut out = DVector::zeros(m);
    for block in blocks {
        match &block.scaling {
            Scaling::Nonneg { lambda, .. } => {
                for (k, l) in lambda.iter().enumerate() {
                    out[block.row0 + k] = l * l;
                }
            }
            Scaling::Psd { lambda, .. } => {
                for (k, (i, j)) in svec_entries(lambda.len()).enumerate() {
                    if i == j {
                        out[block.row0 + k] = lambda[i] * lambda[i];
                    }
                }
            }
        }
    }
    out
}

/// The Jordan product `u ∘ v` over every block (`(UV + VU)/2` in the PSD cones).
fn jordan(blocks: &[Block], u: &DVector<f64>, v: &DVector<f64>) -> DVector<f64> {
    let mut out = DVector::zeros(u.len());
    for block in blocks {
        let range = block.row0..block.row0 + block.cone.rows();
        let (us, vs) = (&u.as_slice()[range.clone()], &v.as_slice()[range.clone()]);
        let product = match block.cone {
            Cone::Nonneg(_) => us.iter().zip(vs).map(|(a, b)| a * b).collect(),
            Cone::Psd(4) => {
                let (um, vm) = (smat4(us), smat4(vs));
                svec(&((um * vm + vm * um) * 0.5))
            }
            Cone::Psd(k) => {
                let (um, vm) = (smat(us, k), smat(vs, k));
                svec(&((&um * &vm + &vm * &um) * 0.5))
            }
        };
        out.rows_mut(block.row0, block.cone.rows())
            .copy_from_slice(&product);
    }
    out
}

/// The cones' identity `e` (ones; `svec(1)`).
fn identity(blocks: &[Block], m: usize) -> DVector<f64> {
    let mut out = DVector::zeros(m);
    for block in blocks {
        match block.cone {
            Cone::Nonneg(n) => out.rows_mut(block.row0, n).fill(1.0),
            Cone::Psd(k) => {
                for (idx, (i, j)) in svec_entries(k).enumerate() {
                    if i == j {
                        out[block.row0 + idx] = 1.0;
                    }
                }
            }
        }
    }
    out
}

/// A PSD cone's step bound is computed exactly only below this (a step is at most
/// `1 / STEP_FRACTION`); above it, a Cholesky factorization shows the cone does not bind.
const UNBINDING_STEP: f64 = 2.0;

/// The largest `α` with `λ + α d̃s` and `λ + α d̃z` in every cone where it is below
/// [`UNBINDING_STEP`] (∞ where nothing binds below it): every step taken is at most 1.
fn step_length(blocks: &[Block], ds_scaled: &DVector<f64>, dz_scaled: &DVector<f64>) -> f64 {
    let mut alpha = f64::INFINITY;
    for block in blocks {
        for d in [ds_scaled, dz_scaled] {
            let rows = &d.as_slice()[block.row0..block.row0 + block.cone.rows()];
            alpha = alpha.min(match &block.scaling {
                Scaling::Nonneg { lambda, .. } => rows
                    .iter()
                    .zip(lambda)
                    .filter(|(d, _)| **d < 0.0)
                    .map(|(d, l)| -l / d)
                    .fold(f64::INFINITY, f64::min),
                Scaling::Psd { lambda, .. } => {
                    // Λ + α D ⪰ 0 ⇔ 1 + α Λ^{-1/2} D Λ^{-1/2} ⪰ 0: α up to −1/λ_min.
                    let low = least_eigenvalue(
                        rows,
                        lambda.len(),
                        |i, j| (lambda[i] * lambda[j]).sqrt(),
                        -1.0 / UNBINDING_STEP,
                    );
                    if low < 0.0 {
                        -1.0 / low
                    } else {
                        f64::INFINITY
                    }
                }
            });
        }
    }
    alpha
}

/// The `(row, column)` of each `svec` entry of a `k × k` matrix, in order.
fn svec_entries(k: usize) -> impl Iterator<Item = (usize, usize)> {
    (0..k).flat_map(|j| (0..=j).map(move |i| (i, j)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lmi::{self, Lmi};
    use clarabel::algebra::CscMatrix;
    use clarabel::solver::{
        DefaultSettings, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
    };
    use rand::{Rng, SeedableRng};

    struct Owned {
        p: DMatrix<f64>,
        q: Vec<f64>,
        a: DMatrix<f64>,
        b: Vec<f64>,
        cones: Vec<Cone>,
    }

    impl Owned {
        fn program(&self) -> Program<'_> {
            Program {
                p: &self.p,
                q: &self.q,
                a: &self.a,
                b: &self.b,
                cones: &self.cones,
            }
        }

        fn objective(&self, x: &[f64]) -> f64 {
            let x = DVector::from_column_slice(x);
            0.5 * x.dot(&(&self.p * &x)) + x.dot(&DVector::from_column_slice(&self.q))
        }

        /// The least eigenvalue of the slack `b − A x` over its cones.
        fn least_slack(&self, x: &[f64]) -> f64 {
            let s = DVector::from_column_slice(&self.b) - &self.a * DVector::from_column_slice(x);
            let blocks = blocks(&self.program());
            min_eigenvalue(&blocks, &s).unwrap()
        }
    }

    /// Identification's shape: `bodies` bodies of ten columns, each with its `lmi` held
    /// `⪰ 1e-6 · 1`, then `extra` columns held non-negative; `P = 2 (YᵀY/rows + 1e-6 · 1)` for a
    /// random regressor `Y`, and `q = −P θ*` for a random `θ*` that breaks most bodies' LMIs.
    fn identification_like(seed: u64, bodies: usize, extra: usize, lmi: Lmi) -> Owned {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let n = 10 * bodies + extra;
        let rows = 3 * n;
        let y = DMatrix::from_fn(rows, n, |_, _| rng.random_range(-1.0..1.0));
        let p = (y.tr_mul(&y) / rows as f64 + DMatrix::identity(n, n) * 1e-6) * 2.0;
        let theta: DVector<f64> = DVector::from_fn(n, |_, _| rng.random_range(-1.0..1.0));
        let q = -(&p * theta);
        let k = lmi.dim();
        let svec_rows = k * (k + 1) / 2;
        let m = bodies * svec_rows + extra;
        let mut a = DMatrix::zeros(m, n);
        let mut b = vec![0.0; m];
        let eye = lmi::svec(&DMatrix::identity(k, k));
        let mut cones = vec![];
        for body in 0..bodies {
            for (c, column) in lmi.basis().iter().enumerate() {
                for (r, v) in column.iter().enumerate() {
                    a[(body * svec_rows + r, 10 * body + c)] = -v;
                }
            }
            for (r, e) in eye.iter().enumerate() {
                b[body * svec_rows + r] = -1e-6 * e;
            }
            cones.push(Cone::Psd(k));
        }
        for e in 0..extra {
            a[(bodies * svec_rows + e, 10 * bodies + e)] = -1.0;
        }
        if extra > 0 {
            cones.push(Cone::Nonneg(extra));
        }
        Owned {
            p,
            q: q.as_slice().to_vec(),
            a,
            b,
            cones,
        }
    }

    /// Clarabel's optimum at its default tolerances (at 1e-9 it stalls on some of these programs).
    fn clarabel(program: &Owned) -> Vec<f64> {
        let (m, n) = program.a.shape();
        let upper = |mat: &DMatrix<f64>| {
            let t: Vec<_> = (0..n)
                .flat_map(|j| (0..=j).map(move |i| (i, j)))
                .filter(|&(i, j)| mat[(i, j)] != 0.0)
                .collect();
            let (ri, ci): (Vec<usize>, Vec<usize>) = t.iter().copied().unzip();
            let v = t.iter().map(|&(i, j)| mat[(i, j)]).collect();
            CscMatrix::new_from_triplets(n, n, ri, ci, v)
        };
        let nonzero: Vec<_> = (0..n)
            .flat_map(|j| (0..m).map(move |i| (i, j)))
            .filter(|&(i, j)| program.a[(i, j)] != 0.0)
            .collect();
        let (ri, ci): (Vec<usize>, Vec<usize>) = nonzero.iter().copied().unzip();
        let v = nonzero.iter().map(|&(i, j)| program.a[(i, j)]).collect();
        let a = CscMatrix::new_from_triplets(m, n, ri, ci, v);
        let cones: Vec<SupportedConeT<f64>> = program
            .cones
            .iter()
            .map(|c| match *c {
                Cone::Nonneg(k) => SupportedConeT::NonnegativeConeT(k),
                Cone::Psd(k) => SupportedConeT::PSDTriangleConeT(k),
            })
            .collect();
        // With Clarabel's equilibration, then without it (as `cone.rs` retries: on some of
        // these programs the equilibrated one stalls at a dual residual of ~5e-8).
        for equilibrate_enable in [true, false] {
            let settings = DefaultSettings {
                verbose: false,
                equilibrate_enable,
                ..DefaultSettings::default()
            };
            let (p, q, b) = (upper(&program.p), &program.q, &program.b);
            let mut solver = DefaultSolver::new(&p, q, &a, b, &cones, settings).unwrap();
            solver.solve();
            if solver.solution.status == SolverStatus::Solved {
                return solver.solution.x.clone();
            }
        }
        panic!("Clarabel does not solve the reference program");
    }

    #[test]
    fn it_reaches_clarabels_optimum_on_identification_shaped_programs() {
        let mut active = 0;
        let shapes = [(1, 0), (3, 6), (6, 12), (7, 21), (8, 30)];
        for (seed, &(bodies, extra)) in shapes.iter().enumerate() {
            for lmi in [Lmi::Pseudo, Lmi::Spatial] {
                let program = identification_like(seed as u64, bodies, extra, lmi);
                let found = solve(&program.program()).expect("converges");
                let reference = clarabel(&program);
                let (f, f_ref) = (program.objective(&found.x), program.objective(&reference));
                // Both against the unconstrained minimum `−½ θ*ᵀ P θ*`: the constraints' cost.
                let scale = f_ref.abs().max(1.0);
                assert!(
                    (f - f_ref).abs() <= 1e-7 * scale,
                    "{bodies} bodies: objective {f} against Clarabel's {f_ref}"
                );
                let distance = (DVector::from_column_slice(&found.x)
                    - DVector::from_column_slice(&reference))
                .norm();
                let size = DVector::from_column_slice(&reference).norm();
                assert!(distance <= 1e-5 * (1.0 + size), "x off by {distance:e}");
                let least = program.least_slack(&found.x);
                assert!(least >= -1e-9, "slack eigenvalue {least:e}");
                assert!(found.residuals.iter().all(|&r| r < TOLERANCE));
                if program.least_slack(&reference) < 1e-4 {
                    active += 1;
                }
            }
        }
        // The optimum sits on some cone's boundary in most programs.
        assert!(active >= 8, "{active} of 10 with an active constraint");
    }

    #[test]
    fn stopped_short_it_returns_its_last_iterate_within_the_reduced_tolerances_only() {
        let program = identification_like(2, 6, 12, Lmi::Pseudo);
        let full = solve(&program.program()).expect("converges");
        assert!(!full.reduced && full.iterations > 4, "{}", full.iterations);
        let reference = program.objective(&clarabel(&program));
        let scale = reference.abs().max(1.0);
        // Cut off one iteration short of the full tolerances, then earlier and earlier: the
        // last cut that is still within the reduced ones returns an iterate marked reduced,
        // near Clarabel's optimum; before any iterate gets there, nothing.
        let mut reduced_seen = 0;
        for cut in (0..full.iterations).rev() {
            match solve_within(&program.program(), cut) {
                Some(found) => {
                    assert!(found.reduced && found.iterations == cut);
                    let worst = found.residuals.iter().copied().fold(0.0, f64::max);
                    assert!(worst < REDUCED_TOLERANCE, "residual {worst:e}");
                    let f = program.objective(&found.x);
                    assert!(
                        (f - reference).abs() <= 1e-4 * scale,
                        "{f} against {reference}"
                    );
                    reduced_seen += 1;
                }
                None => {
                    // Every earlier cut stops short of the reduced tolerances too.
                    assert!((0..cut).all(|c| solve_within(&program.program(), c).is_none()));
                    break;
                }
            }
        }
        assert!(reduced_seen >= 1, "no iterate between the tolerances");
    }

    #[test]
    fn an_unbounded_program_is_left_to_the_other_solver() {
        // min −x₁ with x₀ ≥ 0 only: nothing bounds x₁.
        let program = Owned {
            p: DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 0.0])),
            q: vec![0.0, -1.0],
            a: DMatrix::from_row_slice(1, 2, &[-1.0, 0.0]),
            b: vec![0.0],
            cones: vec![Cone::Nonneg(1)],
        };
        assert!(solve(&program.program()).is_none());
    }

    #[test]
    fn an_infeasible_program_is_left_to_the_other_solver() {
        // x ≥ 1 and x ≤ 0.
        let program = Owned {
            p: DMatrix::identity(1, 1),
            q: vec![0.0],
            a: DMatrix::from_row_slice(2, 1, &[-1.0, 1.0]),
            b: vec![-1.0, 0.0],
            cones: vec![Cone::Nonneg(2)],
        };
        assert!(solve(&program.program()).is_none());
    }

    #[test]
    fn cones_that_do_not_cover_the_rows_are_refused() {
        let mut program = identification_like(3, 2, 2, Lmi::Pseudo);
        program.cones.pop();
        assert!(solve(&program.program()).is_none());
    }

    #[test]
    fn a_cone_s_least_eigenvalue_is_exact_below_its_floor_and_unbounded_only_above_it() {
        // The step length computes a cone's least eigenvalue only where it may bind; where the
        // shifted matrix factors it reports +∞. Below the floor the value is the eigenvalue,
        // bit for bit, by the fixed-size path (4 × 4) as by the general one.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (mut skipped, mut exact) = (0, 0);
        for k in [4, 6] {
            for _ in 0..200 {
                let v: Vec<f64> = (0..k * (k + 1) / 2)
                    .map(|_| rng.random_range(-0.4..0.4))
                    .collect();
                let lambda: Vec<f64> = (0..k).map(|_| rng.random_range(0.3..3.0)).collect();
                let divisor = |i: usize, j: usize| (lambda[i] * lambda[j]).sqrt();
                let m = smat(&v, k);
                let scaled = DMatrix::from_fn(k, k, |i, j| m[(i, j)] / divisor(i, j));
                let truth = scaled.clone().symmetric_eigenvalues().min();
                let floor = -1.0 / UNBINDING_STEP;
                let found = least_eigenvalue(&v, k, divisor, floor);
                if found == f64::INFINITY {
                    assert!(truth > floor, "skipped a binding cone: {truth}");
                    skipped += 1;
                } else {
                    assert_eq!(found, truth, "k = {k}");
                    exact += 1;
                }
                assert_eq!(least_eigenvalue(&v, k, divisor, f64::NEG_INFINITY), truth);
            }
        }
        assert!(
            skipped > 50 && exact > 50,
            "{skipped} skipped, {exact} exact"
        );
    }

    #[test]
    fn a_4x4_cone_s_congruence_equals_the_general_path_bit_for_bit() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for _ in 0..20 {
            let m = DMatrix::from_fn(4, 4, |_, _| rng.random_range(-2.0..2.0));
            let v: Vec<f64> = (0..10).map(|_| rng.random_range(-1.0..1.0)).collect();
            let general = svec(&(&m * smat(&v, 4) * m.transpose()));
            assert_eq!(congruence(&m, &v), general);
            // Against the definition, entry by entry: (M X Mᵀ)_ij = Σ_kl M_ik X_kl M_jl.
            let x = smat(&v, 4);
            let by_sums = DMatrix::from_fn(4, 4, |i, j| {
                (0..4)
                    .flat_map(|k| (0..4).map(move |l| (k, l)))
                    .map(|(k, l)| m[(i, k)] * x[(k, l)] * m[(j, l)])
                    .sum::<f64>()
            });
            for (a, b) in congruence(&m, &v).iter().zip(svec(&by_sums)) {
                assert!((a - b).abs() <= 1e-12 * (1.0 + b.abs()), "{a} against {b}");
            }
        }
        // A 6 × 6 cone (the spatial inertia's) takes the general path.
        let m = DMatrix::from_fn(6, 6, |i, j| (i + 2 * j) as f64 * 0.1 - 0.4);
        let v: Vec<f64> = (0..21).map(|k| k as f64 * 0.05 - 0.5).collect();
        assert_eq!(
            congruence(&m, &v),
            svec(&(&m * smat(&v, 6) * m.transpose()))
        );
    }

    #[test]
    fn the_lapack_cholesky_solves_as_nalgebra_s_and_refuses_what_is_not_definite() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for n in [1, 7, 40, 101] {
            let g = DMatrix::from_fn(n, n, |_, _| rng.random_range(-1.0..1.0));
            let h = &g * g.transpose() + DMatrix::identity(n, n) * 0.01;
            let b = DVector::from_fn(n, |_, _| rng.random_range(-1.0..1.0));
            let ours = Cholesky::new(h.clone())
                .expect("positive definite")
                .solve(&b);
            let theirs = h.clone().cholesky().expect("positive definite").solve(&b);
            let scale = theirs.norm();
            assert!((&ours - &theirs).norm() < 1e-9 * scale, "n = {n}");
            assert!((&h * &ours - &b).norm() < 1e-9 * scale, "n = {n}");
        }
        let indefinite = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        assert!(Cholesky::new(indefinite).is_none());
        let mut with_nan = DMatrix::<f64>::identity(3, 3);
        with_nan[(2, 2)] = f64::NAN;
        assert!(Cholesky::new(with_nan).is_none());
        assert!(Cholesky::new(DMatrix::<f64>::zeros(3, 3)).is_none());
    }

    #[test]
    fn the_scaling_maps_both_points_to_lambda() {
        // W z = W⁻ᵀ s = λ for a random pair of positive definite 4×4 matrices.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let random_pd = |rng: &mut rand_chacha::ChaCha8Rng| {
            let g = DMatrix::from_fn(4, 4, |_, _| rng.random_range(-1.0..1.0));
            &g * g.transpose() + DMatrix::identity(4, 4) * 0.1
        };
        let (s_mat, z_mat) = (random_pd(&mut rng), random_pd(&mut rng));
        let block = Block {
            cone: Cone::Psd(4),
            row0: 0,
            cols: vec![],
            a: DMatrix::zeros(10, 0),
            scaling: Scaling::Nonneg {
                w: vec![],
                lambda: vec![],
            },
        };
        let (s, z) = (
            DVector::from_vec(svec(&s_mat)),
            DVector::from_vec(svec(&z_mat)),
        );
        let Some(Scaling::Psd { r, r_inv, lambda }) = scaling(&block, &s, &z) else {
            panic!("no scaling");
        };
        let lambda_mat = DMatrix::from_diagonal(&DVector::from_vec(lambda));
        assert!((r.transpose() * &z_mat * &r - &lambda_mat).norm() < 1e-12);
        assert!((&r_inv * &s_mat * r_inv.transpose() - &lambda_mat).norm() < 1e-12);
        assert!((&r * &r_inv - DMatrix::identity(4, 4)).norm() < 1e-12);
    }
}
