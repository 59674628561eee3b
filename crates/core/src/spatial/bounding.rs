//! Bounding ellipsoids from geometry: the minimum-volume ellipsoid enclosing a body's shapes.
//!
//! Every shape is a union of *pieces* `P = {c + F u : ‖u‖ ≤ 1}` (a point when `F = 0`, a ball
//! when `F = r 1`, a disc of radius `r` when `F = r [e₁ e₂]`): a box is its 8 corners, a
//! cylinder its two end discs, a capsule its two end balls, a mesh its vertices. An ellipsoid
//! contains a convex hull exactly when it contains the pieces, so the bound below is exact for
//! primitives, not a tessellation.
//!
//! The ellipsoid is `E = {x : ‖A x + b‖ ≤ 1}` with `A ≻ 0`; its volume is `(4π/3) / det A`.
//! Boyd & Vandenberghe (Convex Optimization, §8.4.1) give the program
//!
//! ```text
//! maximize   log det A
//! subject to ‖A c + b‖ ≤ 1                                   for each point piece,
//!            [[1₃, A c + b, A F], [·ᵀ, 1 − λ, 0], [·ᵀ, 0, λ 1ₖ]] ⪰ 0, λ ≥ 0   otherwise
//! ```
//!
//! (the second line is the S-procedure for `P ⊆ E`). `log det A` is bounded below through the
//! triangular factor `Z`: `[[A, Z], [Zᵀ, diag Z]] ⪰ 0` and `tᵢ ≤ log Zᵢᵢ` (exponential cones),
//! the same device as the paper's entropic regularizer. Clarabel solves it in a few
//! milliseconds. The paper's `Q_s` follows as `A⁻²` and the centre as `x_s = −A⁻¹ b`.

use super::Ellipsoid;
use crate::conic::{AffineSym, ConeRows};
use clarabel::algebra::CscMatrix;
use clarabel::solver::{DefaultSettings, DefaultSolver, IPSolver, SolverStatus};
use nalgebra::{Matrix3, Matrix3x2, SymmetricEigen, Vector3};

/// A convex piece of a body's geometry: `{center + F u : ‖u‖ ≤ 1}` (m, body frame).
#[derive(Clone, Debug, PartialEq)]
pub enum Piece {
    /// A single point.
    Point(Vector3<f64>),
    /// A solid ball.
    Ball {
        /// Centre (m).
        center: Vector3<f64>,
        /// Radius (m).
        radius: f64,
    },
    /// A flat disc: `center + span u`, `‖u‖ ≤ 1`, with `span` two orthogonal radius vectors.
    Disc {
        /// Centre (m).
        center: Vector3<f64>,
        /// Two orthogonal radius vectors (m) as columns.
        span: Matrix3x2<f64>,
    },
}

/// Why no bounding ellipsoid could be computed.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum BoundingError {
    /// No geometry at all.
    #[error("no geometry")]
    Empty,
    /// A non-finite coordinate or a negative size.
    #[error("invalid geometry: {0}")]
    Invalid(String),
    /// The shapes span no volume (all on a plane or a line).
    #[error("the geometry is flat (it spans no volume: extent {extent:.3e} m across its thinnest direction)")]
    Flat {
        /// The spread along the thinnest direction (m).
        extent: f64,
    },
    /// The solver did not converge.
    #[error("the minimum-volume ellipsoid program did not solve ({0})")]
    Solver(String),
}

impl Piece {
    /// The piece's centre and its `F` columns (none for a point).
    fn center_and_span(&self) -> (Vector3<f64>, Vec<Vector3<f64>>) {
        match self {
            Piece::Point(p) => (*p, vec![]),
            Piece::Ball { center, radius } => {
                (*center, (0..3).map(|i| Vector3::ith(i, *radius)).collect())
            }
            Piece::Disc { center, span } => {
                (*center, vec![span.column(0).into(), span.column(1).into()])
            }
        }
    }

    /// The piece as bytes for a content key: a tag and every coordinate's bits in a fixed
    /// order (equal bytes, equal piece).
    pub fn to_bytes(&self) -> Vec<u8> {
        let (tag, numbers): (u8, Vec<f64>) = match self {
            Piece::Point(p) => (0, p.iter().copied().collect()),
            Piece::Ball { center, radius } => {
                (1, center.iter().copied().chain([*radius]).collect())
            }
            Piece::Disc { center, span } => {
                (2, center.iter().chain(span.iter()).copied().collect())
            }
        };
        std::iter::once(tag)
            .chain(numbers.iter().flat_map(|x| x.to_bits().to_le_bytes()))
            .collect()
    }

    /// The same piece in another frame: `x ↦ rot x + pos`, `rot` a rotation.
    pub fn moved(&self, rot: &Matrix3<f64>, pos: &Vector3<f64>) -> Piece {
        match self {
            Piece::Point(p) => Piece::Point(rot * p + pos),
            Piece::Ball { center, radius } => Piece::Ball {
                center: rot * center + pos,
                radius: *radius,
            },
            Piece::Disc { center, span } => Piece::Disc {
                center: rot * center + pos,
                span: rot * span,
            },
        }
    }

    /// The piece mapped by `x ↦ (x − origin) / scale` (a uniform scaling).
    fn normalized(&self, origin: &Vector3<f64>, scale: f64) -> Piece {
        match self {
            Piece::Point(p) => Piece::Point((p - origin) / scale),
            Piece::Ball { center, radius } => Piece::Ball {
                center: (center - origin) / scale,
                radius: radius / scale,
            },
            Piece::Disc { center, span } => Piece::Disc {
                center: (center - origin) / scale,
                span: span / scale,
            },
        }
    }

    /// Points on the piece's boundary, for checks and for the flatness test: the point, six
    /// poles of a ball, or `n` points on a disc's rim.
    pub fn sample_boundary(&self, n: usize) -> Vec<Vector3<f64>> {
        let (c, f) = self.center_and_span();
        match f.len() {
            0 => vec![c],
            2 => (0..n)
                .map(|k| {
                    let a = std::f64::consts::TAU * k as f64 / n as f64;
                    c + f[0] * a.cos() + f[1] * a.sin()
                })
                .collect(),
            _ => f.iter().flat_map(|v| [c + v, c - v]).collect(),
        }
    }
}

/// The eight corners of a box of full `size` (m) centred at the origin of its frame.
pub fn box_corners(size: &Vector3<f64>) -> Vec<Piece> {
    let h = size / 2.0;
    (0..8)
        .map(|k| {
            let s = |bit: usize| if k >> bit & 1 == 1 { 1.0 } else { -1.0 };
            Piece::Point(Vector3::new(s(0) * h.x, s(1) * h.y, s(2) * h.z))
        })
        .collect()
}

/// A cylinder of `radius` and `length` (m) along its frame's z axis, centred at the origin: its
/// two end discs.
pub fn cylinder_ends(radius: f64, length: f64) -> Vec<Piece> {
    let span = Matrix3x2::new(radius, 0.0, 0.0, radius, 0.0, 0.0);
    [-0.5, 0.5]
        .into_iter()
        .map(|s| Piece::Disc {
            center: Vector3::new(0.0, 0.0, s * length),
            span,
        })
        .collect()
}

/// A capsule (cylinder with hemispherical caps) along z: its two end balls.
pub fn capsule_ends(radius: f64, length: f64) -> Vec<Piece> {
    [-0.5, 0.5]
        .into_iter()
        .map(|s| Piece::Ball {
            center: Vector3::new(0.0, 0.0, s * length),
            radius,
        })
        .collect()
}

/// The vertices of the convex hull of `points` (parry's quickhull), which bound exactly what
/// the points bound; all distinct points when the hull is degenerate (flat or too few points).
pub fn hull_vertices(points: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    use parry3d_f64::{math::Vector3 as P, transformation::try_convex_hull};
    let input: Vec<P> = points.iter().map(|p| P::new(p.x, p.y, p.z)).collect();
    let mut out: Vec<Vector3<f64>> = match try_convex_hull(&input) {
        Ok((vertices, faces)) => {
            let mut used = vec![false; vertices.len()];
            for f in &faces {
                for &i in f {
                    used[i as usize] = true;
                }
            }
            vertices
                .iter()
                .zip(used)
                .filter(|(_, u)| *u)
                .map(|(v, _)| Vector3::new(v.x, v.y, v.z))
                .collect()
        }
        Err(_) => points.to_vec(),
    };
    out.sort_by(|a, b| {
        a.iter()
            .zip(b.iter())
            .map(|(x, y)| x.total_cmp(y))
            .find(|o| o.is_ne())
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    out.dedup();
    out
}

/// Checks finiteness and that the pieces span a volume.
/// Returns boundary samples of every piece (eight per disc rim, six poles per ball).
fn check(pieces: &[Piece]) -> Result<Vec<Vector3<f64>>, BoundingError> {
    if pieces.is_empty() {
        return Err(BoundingError::Empty);
    }
    let mut pts = vec![];
    for p in pieces {
        let (c, f) = p.center_and_span();
        if !c
            .iter()
            .chain(f.iter().flat_map(|v| v.iter()))
            .all(|x| x.is_finite())
        {
            return Err(BoundingError::Invalid(format!(
                "non-finite coordinates in {p:?}"
            )));
        }
        if let Piece::Ball { radius, .. } = p {
            if *radius < 0.0 {
                return Err(BoundingError::Invalid(format!("negative radius {radius}")));
            }
        }
        pts.extend(p.sample_boundary(8));
    }
    let n = pts.len() as f64;
    let mean: Vector3<f64> = pts.iter().sum::<Vector3<f64>>() / n;
    let cov: Matrix3<f64> = pts
        .iter()
        .map(|p| (p - mean) * (p - mean).transpose())
        .sum::<Matrix3<f64>>()
        / n;
    let eig = SymmetricEigen::new(cov).eigenvalues;
    let (lo, hi) = (eig.min().max(0.0), eig.max().max(0.0));
    if hi == 0.0 || lo < 1e-10 * hi {
        return Err(BoundingError::Flat {
            extent: 2.0 * lo.sqrt(),
        });
    }
    Ok(pts)
}

/// Variable layout of the program: `A` (6, upper triangle), `b` (3), `Z` (6, lower triangle),
/// `t` (3), then one `λ` per non-point piece.
const A0: usize = 0;
const B0: usize = 6;
const Z0: usize = 9;
const T0: usize = 15;
const L0: usize = 18;

/// Index of `A[(i, j)]` among the six upper-triangle variables.
fn a_var(i: usize, j: usize) -> usize {
    let (i, j) = (i.min(j), i.max(j));
    A0 + [[0, 1, 2], [1, 3, 4], [2, 4, 5]][i][j]
}

/// Index of `Z[(i, j)]`, `i ≥ j`, among the six lower-triangle variables.
fn z_var(i: usize, j: usize) -> usize {
    Z0 + i * (i + 1) / 2 + j
}

/// `(A p + b)_r` as `(variable, coefficient)` terms.
fn affine_image(p: &Vector3<f64>, r: usize) -> Vec<(usize, f64)> {
    let mut t: Vec<(usize, f64)> = (0..3).map(|k| (a_var(r, k), p[k])).collect();
    t.push((B0 + r, 1.0));
    t
}

/// `(A v)_r` for a direction `v`.
fn linear_image(v: &Vector3<f64>, r: usize) -> Vec<(usize, f64)> {
    (0..3).map(|k| (a_var(r, k), v[k])).collect()
}

/// `log det A ≥ Σ tᵢ` ([`crate::conic`]'s device, the factor `Zᵀ` upper triangular).
fn push_log_det(rows: &mut ConeRows) {
    let mut a = AffineSym::new(3);
    for i in 0..3 {
        for j in i..3 {
            a.at(i, j).1.push((a_var(i, j), 1.0));
        }
    }
    // The factor's entry (row j, column i), j ≤ i, is Z[(i, j)].
    let factor = |j: usize, i: usize| (j <= i).then(|| z_var(i, j));
    rows.log_det(a, factor, |i| T0 + i);
}

/// `‖A p + b‖ ≤ 1` (a second-order cone).
fn push_point(p: &Vector3<f64>, rows: &mut ConeRows) {
    let image: Vec<Vec<(usize, f64)>> = std::iter::once(vec![])
        .chain((0..3).map(|r| affine_image(p, r)))
        .collect();
    rows.second_order(&[1.0, 0.0, 0.0, 0.0], &image);
}

/// The S-procedure LMI for `{c + F u} ⊆ E` with multiplier variable `lambda`, and `λ ≥ 0` is
/// implied by the LMI's lower-right block.
fn push_piece(c: &Vector3<f64>, f: &[Vector3<f64>], lambda: usize, rows: &mut ConeRows) {
    let k = f.len();
    let mut m = AffineSym::new(4 + k);
    for r in 0..3 {
        m.at(r, r).0 = 1.0;
        m.at(r, 3).1 = affine_image(c, r);
        for (col, v) in f.iter().enumerate() {
            m.at(r, 4 + col).1 = linear_image(v, r);
        }
    }
    *m.at(3, 3) = (1.0, vec![(lambda, -1.0)]);
    for col in 0..k {
        m.at(4 + col, 4 + col).1.push((lambda, 1.0));
    }
    rows.psd(&m);
}

/// Indices of the points extreme along the 26 directions of a cube's faces, edges and corners.
fn extreme_points(points: &[Vector3<f64>]) -> Vec<usize> {
    let mut out: Vec<usize> = vec![];
    for d in (0..27).filter(|&k| k != 13) {
        let dir = Vector3::new(
            (d % 3) as f64 - 1.0,
            (d / 3 % 3) as f64 - 1.0,
            (d / 9) as f64 - 1.0,
        );
        let best =
            (0..points.len()).max_by(|&i, &j| points[i].dot(&dir).total_cmp(&points[j].dot(&dir)));
        if let Some(i) = best.filter(|i| !out.contains(i)) {
            out.push(i);
        }
    }
    out
}

/// Solves the program of the module docs for `pieces` (normalized coordinates): `(A, b)`.
fn solve_program(pieces: &[Piece]) -> Result<(Matrix3<f64>, Vector3<f64>), BoundingError> {
    let mut rows = ConeRows::default();
    push_log_det(&mut rows);
    let mut lambdas = 0;
    for p in pieces {
        let (c, f) = p.center_and_span();
        if f.is_empty() {
            push_point(&c, &mut rows);
        } else {
            push_piece(&c, &f, L0 + lambdas, &mut rows);
            lambdas += 1;
        }
    }
    let nv = L0 + lambdas;
    let mut q = vec![0.0; nv];
    q[T0..T0 + 3].fill(-1.0);
    let (a, b, cones) = rows.into_parts(nv);
    let p = CscMatrix::zeros((nv, nv));
    let settings = DefaultSettings {
        verbose: false,
        max_iter: 200,
        tol_gap_abs: 1e-11,
        tol_gap_rel: 1e-11,
        tol_feas: 1e-11,
        ..DefaultSettings::default()
    };
    let mut solver = DefaultSolver::new(&p, &q, &a, &b, &cones, settings)
        .map_err(|e| BoundingError::Solver(e.to_string()))?;
    solver.solve();
    let sol = &solver.solution;
    if !matches!(
        sol.status,
        SolverStatus::Solved | SolverStatus::AlmostSolved
    ) {
        return Err(BoundingError::Solver(format!("{:?}", sol.status)));
    }
    let x = &sol.x;
    Ok((
        Matrix3::from_fn(|i, j| x[a_var(i, j)]),
        Vector3::new(x[B0], x[B0 + 1], x[B0 + 2]),
    ))
}

/// The minimum-volume ellipsoid containing every piece (see the module docs), in the pieces'
/// frame. Errors: no pieces, non-finite coordinates, flat geometry, solver failure.
pub fn minimum_volume_ellipsoid(pieces: &[Piece]) -> Result<Ellipsoid, BoundingError> {
    let pts = check(pieces)?;
    super::single_threaded_blas();
    // Work in a frame centred on the geometry and scaled to unit size, so that the program is
    // well conditioned whatever the units of the description.
    let mean: Vector3<f64> = pts.iter().sum::<Vector3<f64>>() / pts.len() as f64;
    let scale = pts.iter().map(|p| (p - mean).norm()).fold(0.0, f64::max);
    let shifted: Vec<Piece> = pieces.iter().map(|p| p.normalized(&mean, scale)).collect();
    // Active set over the points (a mesh's hull may have hundreds of vertices, while at most
    // nine points touch the optimum): start from the extreme points in 26 directions, solve,
    // add the points left outside, until none is.
    let (points, others): (Vec<&Piece>, Vec<&Piece>) =
        shifted.iter().partition(|p| matches!(p, Piece::Point(_)));
    let points: Vec<Vector3<f64>> = points.iter().map(|p| p.center_and_span().0).collect();
    let mut active = extreme_points(&points);
    let (a_unit, b_unit) = loop {
        let mut set: Vec<Piece> = others.iter().map(|p| (*p).clone()).collect();
        set.extend(active.iter().map(|&i| Piece::Point(points[i])));
        let (a, b) = match solve_program(&set) {
            Ok(ab) => ab,
            // A flat start (unbounded program) falls back to every point.
            Err(_) if active.len() < points.len() => {
                active = (0..points.len()).collect();
                continue;
            }
            Err(e) => return Err(e),
        };
        let mut outside: Vec<(f64, usize)> = (0..points.len())
            .filter(|i| !active.contains(i))
            .map(|i| ((a * points[i] + b).norm(), i))
            .filter(|(r, _)| *r > 1.0 + 1e-9)
            .collect();
        if outside.is_empty() {
            break (a, b);
        }
        outside.sort_by(|x, y| y.0.total_cmp(&x.0));
        active.extend(outside.iter().take(32).map(|(_, i)| *i));
    };
    let a_inv = a_unit
        .try_inverse()
        .ok_or_else(|| BoundingError::Solver("singular shape matrix".into()))?;
    // Back to the description's frame: x = scale·y + mean.
    let center = mean - a_inv * b_unit * scale;
    let qs = a_inv * a_inv * (scale * scale);
    let e = Ellipsoid {
        center,
        qs: (qs + qs.transpose()) / 2.0,
    };
    Ok(enclose(e, pieces))
}

/// Whether `e` could be the minimum-volume ellipsoid of `pieces` (a cached answer checked
/// without solving again): it contains every piece (to 10⁻⁷ of its size) and its volume is at
/// most that of the ellipsoid through the corners of the pieces' bounding box (which contains
/// them, so the minimum is no larger). A planted or corrupted cache entry fails one of them.
pub fn could_bound(e: &Ellipsoid, pieces: &[Piece]) -> bool {
    let Some(worst) = largest_norm(e, pieces) else {
        return false;
    };
    let (mut lo, mut hi) = (
        Vector3::repeat(f64::INFINITY),
        Vector3::repeat(f64::NEG_INFINITY),
    );
    for p in pieces {
        let (c, f) = p.center_and_span();
        let reach = Vector3::from_fn(|k, _| f.iter().map(|v| v[k] * v[k]).sum::<f64>().sqrt());
        lo = lo.inf(&(c - reach));
        hi = hi.sup(&(c + reach));
    }
    let box_volume = ((hi - lo) / 2.0 * 3f64.sqrt()).product();
    let volume = e.qs.determinant().max(0.0).sqrt();
    worst <= 1.0 + 1e-7 && volume <= box_volume * (1.0 + 1e-9)
}

/// The largest `‖L (x − x_s)‖` over the pieces (`Lᵀ L = Q_s⁻¹`; at most 1 when all are inside),
/// `None` for a degenerate ellipsoid.
fn largest_norm(e: &Ellipsoid, pieces: &[Piece]) -> Option<f64> {
    let l = e.qs.try_inverse()?.cholesky()?.l().transpose();
    Some(
        pieces
            .iter()
            .map(|p| {
                let (c, f) = p.center_and_span();
                let g = l * (c - e.center);
                let gf: Vec<Vector3<f64>> = f.iter().map(|v| l * v).collect();
                max_norm_on_unit_ball(&g, &gf)
            })
            .fold(0.0, f64::max),
    )
}

/// Grows `e` about its centre just enough to contain every piece exactly (closing the solver's
/// tolerance): the largest `‖L (x − x_s)‖` over each piece, with `Lᵀ L = Q_s⁻¹`.
fn enclose(e: Ellipsoid, pieces: &[Piece]) -> Ellipsoid {
    let Some(worst) = largest_norm(&e, pieces) else {
        return e;
    };
    let worst = worst.max(1.0);
    Ellipsoid {
        center: e.center,
        qs: e.qs * (worst * worst),
    }
}

/// `max ‖g + G u‖` over `‖u‖ ≤ 1`, `G`'s columns given: the maximum of a convex quadratic on
/// the unit ball lies on its sphere, where `u = (μ 1 − GᵀG)⁻¹ Gᵀ g` with the multiplier
/// `μ ≥ λ_max(GᵀG)` found by bisection on `‖u(μ)‖ = 1` (the trust-region secular equation; in
/// its "hard case" the top eigenvector fills `u` up to unit length).
pub fn max_norm_on_unit_ball(g: &Vector3<f64>, cols: &[Vector3<f64>]) -> f64 {
    let k = cols.len();
    if k == 0 {
        return g.norm();
    }
    let gm = nalgebra::DMatrix::from_fn(3, k, |i, j| cols[j][i]);
    let eig = SymmetricEigen::new(gm.transpose() * &gm);
    let (lam, v) = (eig.eigenvalues, eig.eigenvectors);
    let top = lam.imax();
    let c: Vec<f64> = (0..k)
        .map(|i| v.column(i).dot(&(gm.transpose() * g)))
        .collect();
    let norm_u = |mu: f64| -> f64 {
        (0..k)
            .map(|i| (c[i] / (mu - lam[i])).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let value = |u: &nalgebra::DVector<f64>| (g + &gm * u).norm();
    let u_of = |mu: f64| -> nalgebra::DVector<f64> {
        (0..k).fold(nalgebra::DVector::zeros(k), |acc, i| {
            acc + v.column(i) * (c[i] / (mu - lam[i]))
        })
    };
    let (mut lo, mut hi) = (
        lam[top],
        lam[top] + gm.norm() * g.norm() + gm.norm_squared() + 1.0,
    );
    if norm_u(lo + 1e-15 * (1.0 + lo.abs())) <= 1.0 || c[top].abs() < 1e-300 {
        // Hard case: the part off the top eigenvector, topped up along it.
        let rest: nalgebra::DVector<f64> = (0..k)
            .filter(|&i| (lam[top] - lam[i]) > 0.0)
            .fold(nalgebra::DVector::zeros(k), |acc, i| {
                acc + v.column(i) * (c[i] / (lam[top] - lam[i]))
            });
        let tau = (1.0 - rest.norm_squared()).max(0.0).sqrt();
        let vt: nalgebra::DVector<f64> = v.column(top).into();
        return value(&(&rest + &vt * tau)).max(value(&(&rest - &vt * tau)));
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if norm_u(mid) > 1.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    value(&u_of(hi))
}

#[cfg(test)]
/// Unit vectors on a latitude-longitude grid of `n` rings.
fn sphere_directions(n: usize) -> impl Iterator<Item = Vector3<f64>> {
    (0..=n).flat_map(move |i| {
        let th = std::f64::consts::PI * i as f64 / n as f64;
        (0..2 * n).map(move |j| {
            let ph = std::f64::consts::PI * j as f64 / n as f64;
            Vector3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos())
        })
    })
}

/// The ellipsoid with every semi-axis lengthened by `margin` (m), same centre and axes.
pub fn with_margin(e: &Ellipsoid, margin: f64) -> Ellipsoid {
    if margin == 0.0 {
        return *e;
    }
    let eig = SymmetricEigen::new(e.qs);
    let grown = eig
        .eigenvalues
        .map(|l| (l.max(0.0).sqrt() + margin).powi(2));
    Ellipsoid {
        center: e.center,
        qs: eig.eigenvectors * Matrix3::from_diagonal(&grown) * eig.eigenvectors.transpose(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sorted_axes(e: &Ellipsoid) -> Vector3<f64> {
        e.semi_axes()
    }

    #[test]
    fn box_gets_root_three_times_its_half_sizes() {
        // The MVEE of a box is axis-aligned with semi-axes √3·(a, b, c) (by symmetry and the
        // AM-GM bound on its corners).
        let e = minimum_volume_ellipsoid(&box_corners(&Vector3::new(0.2, 0.4, 1.0))).unwrap();
        let want = Vector3::new(0.1, 0.2, 0.5) * 3f64.sqrt();
        assert!(
            (sorted_axes(&e) - want).norm() < 1e-6,
            "{}",
            sorted_axes(&e)
        );
        assert!(e.center.norm() < 1e-7);
    }

    #[test]
    fn cylinder_gets_the_analytic_optimum() {
        // Axis-aligned (R, R, Z) containing the rim: r²/R² + h²/Z² ≤ 1; minimizing R²Z gives
        // R = r √(3/2), Z = h √3 (h the half length).
        let (r, len) = (0.07, 0.208);
        let e = minimum_volume_ellipsoid(&cylinder_ends(r, len)).unwrap();
        let mut want = [
            r * 1.5f64.sqrt(),
            r * 1.5f64.sqrt(),
            len / 2.0 * 3f64.sqrt(),
        ];
        want.sort_by(f64::total_cmp);
        let got = sorted_axes(&e);
        for k in 0..3 {
            assert!(
                (got[k] - want[k]).abs() < 1e-6 * want[k].max(0.1),
                "{got} vs {want:?}"
            );
        }
    }

    #[test]
    fn one_ball_is_its_own_bound_and_moves_with_its_frame() {
        let rot = crate::spatial::rpy_to_matrix(&Vector3::new(0.3, -0.2, 1.1));
        let c = Vector3::new(0.1, -0.3, 2.0);
        let ball = Piece::Ball {
            center: Vector3::zeros(),
            radius: 0.05,
        };
        let e = minimum_volume_ellipsoid(&[ball.moved(&rot, &c)]).unwrap();
        assert!((e.center - c).norm() < 1e-7);
        assert!((e.semi_axes() - Vector3::repeat(0.05)).norm() < 1e-7);
    }

    #[test]
    fn union_contains_every_piece_and_matches_khachiyan_on_samples() {
        let mut pieces = capsule_ends(0.07, 0.2);
        pieces.extend(cylinder_ends(0.03, 0.3).iter().map(|p| {
            p.moved(
                &crate::spatial::rpy_to_matrix(&Vector3::new(1.2, 0.0, 0.0)),
                &Vector3::new(0.0, 0.1, 0.05),
            )
        }));
        pieces.push(Piece::Point(Vector3::new(0.15, 0.0, 0.0)));
        let e = minimum_volume_ellipsoid(&pieces).unwrap();
        let inside = |x: &Vector3<f64>| {
            let d = x - e.center;
            (d.transpose() * e.qs.try_inverse().unwrap() * d)[0] <= 1.0 + 1e-12
        };
        for p in &pieces {
            for x in p.sample_boundary(3600) {
                assert!(inside(&x), "{x} of {p:?} escapes");
            }
            if let Piece::Ball { center, radius } = p {
                for u in sphere_directions(90) {
                    assert!(inside(&(center + u * *radius)));
                }
            }
        }
        // A second algorithm: Khachiyan's MVEE of dense samples of the same pieces. The
        // samples lie in the union, so their ellipsoid is at most ours, and close to it.
        let mut samples = vec![];
        for p in &pieces {
            match p {
                Piece::Ball { center, radius } => {
                    samples.extend(sphere_directions(24).map(|u| center + u * *radius))
                }
                _ => samples.extend(p.sample_boundary(240)),
            }
        }
        let volume = |e: &Ellipsoid| e.qs.determinant().sqrt();
        let k = khachiyan(&samples, 1e-7);
        let ratio = volume(&e) / volume(&k);
        assert!((ratio - 1.0).abs() < 0.01, "volume ratio {ratio}");
        assert!(
            (e.center - k.center).norm() < 1e-3,
            "{} vs {}",
            e.center,
            k.center
        );
    }

    /// Khachiyan's algorithm for the minimum-volume ellipsoid of points (Todd & Yildirim's
    /// form): weights `u` on the points, lifted `q = [x; 1]`, until the largest
    /// `qᵀ (Σ uᵢ qᵢ qᵢᵀ)⁻¹ q` is within `tol` of 4.
    fn khachiyan(points: &[Vector3<f64>], tol: f64) -> Ellipsoid {
        let n = points.len();
        let lift = |p: &Vector3<f64>| nalgebra::Vector4::new(p.x, p.y, p.z, 1.0);
        let mut u = vec![1.0 / n as f64; n];
        for _ in 0..100_000 {
            let x: nalgebra::Matrix4<f64> = points
                .iter()
                .zip(&u)
                .map(|(p, w)| lift(p) * lift(p).transpose() * *w)
                .sum();
            let xi = x.try_inverse().unwrap();
            let (j, m) = points
                .iter()
                .map(|p| (lift(p).transpose() * xi * lift(p))[0])
                .enumerate()
                .fold((0, 0.0), |a, (i, v)| if v > a.1 { (i, v) } else { a });
            let step = (m - 4.0) / (4.0 * (m - 1.0));
            if step < tol {
                break;
            }
            for w in u.iter_mut() {
                *w *= 1.0 - step;
            }
            u[j] += step;
        }
        let c: Vector3<f64> = points.iter().zip(&u).map(|(p, w)| p * *w).sum();
        let cov: Matrix3<f64> = points
            .iter()
            .zip(&u)
            .map(|(p, w)| (p - c) * (p - c).transpose() * *w)
            .sum();
        // Grown to contain every point (the iteration stops short of the optimum).
        let qi = (cov * 3.0).try_inverse().unwrap();
        let worst = points
            .iter()
            .map(|p| ((p - c).transpose() * qi * (p - c))[0])
            .fold(1.0, f64::max);
        Ellipsoid {
            center: c,
            qs: cov * 3.0 * worst,
        }
    }

    #[test]
    fn flat_and_empty_geometry_are_refused() {
        assert_eq!(minimum_volume_ellipsoid(&[]), Err(BoundingError::Empty));
        let square: Vec<Piece> = box_corners(&Vector3::new(1.0, 1.0, 0.0));
        assert!(matches!(
            minimum_volume_ellipsoid(&square),
            Err(BoundingError::Flat { .. })
        ));
        let nan = [Piece::Point(Vector3::new(f64::NAN, 0.0, 0.0))];
        assert!(matches!(
            minimum_volume_ellipsoid(&nan),
            Err(BoundingError::Invalid(_))
        ));
    }

    #[test]
    fn max_norm_on_unit_ball_matches_a_fine_search() {
        let g = Vector3::new(0.3, -0.1, 0.2);
        let cases = [
            vec![Vector3::new(0.5, 0.1, 0.0), Vector3::new(0.0, 0.2, 0.4)],
            vec![Vector3::x(), Vector3::y(), Vector3::z()],
            // Hard case: g orthogonal to the span's top direction.
            vec![Vector3::new(0.0, 0.0, 1.0), Vector3::new(0.0, 0.1, 0.0)],
        ];
        for cols in cases {
            let exact = max_norm_on_unit_ball(&g, &cols);
            let searched = if cols.len() == 2 {
                (0..100_000)
                    .map(|k| {
                        let a = std::f64::consts::TAU * k as f64 / 1e5;
                        (g + cols[0] * a.cos() + cols[1] * a.sin()).norm()
                    })
                    .fold(0.0, f64::max)
            } else {
                sphere_directions(400)
                    .map(|u| (g + cols[0] * u.x + cols[1] * u.y + cols[2] * u.z).norm())
                    .fold(0.0, f64::max)
            };
            assert!(exact >= searched - 1e-12, "{exact} < {searched}");
            assert!(exact - searched < 1e-5, "{exact} vs {searched}");
        }
    }

    #[test]
    fn margin_lengthens_each_semi_axis() {
        let e = Ellipsoid::axis_aligned(Vector3::zeros(), Vector3::new(0.1, 0.2, 0.3));
        let g = with_margin(&e, 0.01);
        assert!((g.semi_axes() - Vector3::new(0.11, 0.21, 0.31)).norm() < 1e-12);
    }
}
