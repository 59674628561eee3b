//! The cone program of identification for Clarabel, in scaled variables `θ = D x`.
//!
//! The constraints come in [`Group`]s, each over a few of θ's columns: one body's matrix
//! inequalities (with its `tr(JQ)` row under the ellipsoid set), or one affine form held
//! non-negative (a friction coefficient, a stated non-negative column, a mass bound, the total
//! mass). [`solve`] hands Clarabel every group; `interior.rs` checks a point against them.

use super::{
    dense, lmi, ConstraintSet, IdentError, Options, Parameterized, Regularizer, SolveStatus,
    SolverInfo,
};
use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSolution, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use lmi::Lmi;
use nalgebra::{DMatrix, DVector};
use physid_core::conic::{AffineSym, ConeRows};
use physid_core::spatial::{Ellipsoid, InertialParams};

/// An affine form over θ, `Σ v θ_c + constant`, held non-negative.
pub(crate) type Affine = (Vec<(usize, f64)>, f64);

/// Constraints that touch only a few of θ's columns.
pub(crate) enum Group {
    /// The set's matrix inequalities of the body (or rotor) whose ten parameters start at
    /// `col`: `I ⪰ ε1` (semi), `J ⪰ ε1` (consistent), and under the ellipsoid set also the
    /// CoM LMI and `tr(J Q) ≥ 0` for its `ellipsoid`.
    Body {
        /// First column of its parameters.
        col: usize,
        /// Its bounding ellipsoid (required by the ellipsoid set).
        ellipsoid: Option<Ellipsoid>,
    },
    /// One affine form held non-negative.
    Row(Affine),
}

/// Every constraint group of `opts` on `model`: the bodies' (in parameter order), then the
/// friction coefficients (under a constraint set), `opts.nonnegative`, the mass bounds (two
/// rows each) and the total mass (two rows). Under the ellipsoid set a body without an
/// ellipsoid is an error.
pub(crate) fn groups<R: Parameterized + ?Sized>(
    model: &R,
    opts: &Options,
) -> Result<Vec<Group>, IdentError> {
    let set = opts.constraints;
    let mut out = vec![];
    if set != ConstraintSet::None {
        for (name, col, ellipsoid) in model.inertial_bodies() {
            if set == ConstraintSet::Ellipsoid && ellipsoid.is_none() {
                return Err(IdentError::MissingEllipsoid(name));
            }
            out.push(Group::Body { col, ellipsoid });
        }
        let friction = model.friction_columns().0..model.parameter_count();
        out.extend(friction.map(|c| Group::Row((vec![(c, 1.0)], 0.0))));
    }
    let row = |terms: Vec<(usize, f64)>, constant: f64| Group::Row((terms, constant));
    out.extend(opts.nonnegative.iter().map(|&c| row(vec![(c, 1.0)], 0.0)));
    for &(c, lo, hi) in &opts.mass_bounds {
        out.push(row(vec![(c, 1.0)], -lo));
        out.push(row(vec![(c, -1.0)], hi));
    }
    if let Some((cols, lo, hi)) = &opts.total_mass {
        out.push(row(cols.iter().map(|&c| (c, 1.0)).collect(), -lo));
        out.push(row(cols.iter().map(|&c| (c, -1.0)).collect(), *hi));
    }
    Ok(out)
}

impl Group {
    /// Whether `theta` satisfies the group's constraints under `opts`, strictly (`λ_min ≥ ε`,
    /// no tolerance).
    pub(crate) fn holds(&self, theta: &DVector<f64>, opts: &Options) -> bool {
        match self {
            Group::Body { col, ellipsoid } => {
                let p = InertialParams(theta.fixed_rows::<10>(*col).into_owned());
                let r = p.consistency(ellipsoid.as_ref());
                match opts.constraints {
                    ConstraintSet::None => true,
                    ConstraintSet::Semi => r.min_eig_spatial >= opts.eps,
                    ConstraintSet::Consistent => r.min_eig_pseudo >= opts.eps,
                    ConstraintSet::Ellipsoid => {
                        r.min_eig_pseudo >= opts.eps
                            && r.trace_jq.is_some_and(|t| t >= opts.eps)
                            && r.min_eig_com.is_some_and(|c| c >= 0.0)
                    }
                }
            }
            Group::Row((terms, constant)) => {
                terms.iter().map(|&(c, v)| v * theta[c]).sum::<f64>() + constant >= 0.0
            }
        }
    }
}

/// The whole cone program of `opts` (every group over every column; the log-det regularizer's
/// variables and cones after θ's), solved in scaled variables.
pub(crate) fn solve<R: Parameterized + ?Sized>(
    model: &R,
    h: &DMatrix<f64>,
    g: &DVector<f64>,
    prior: &DVector<f64>,
    opts: &Options,
) -> Result<(DVector<f64>, SolverInfo), IdentError> {
    let p = h.nrows();
    let logdet = opts.regularizer == Regularizer::LogDet;
    let nb = model.inertial_bodies().len();
    // Log-det extra variables per body: 10 entries of a lower-triangular L, then 4 of u.
    let extra = if logdet { 14 * nb } else { 0 };
    let nv = p + extra;
    let d: Vec<f64> = physid_core::linalg::unit_diagonal_scale(h, 1.0)
        .into_iter()
        .chain(std::iter::repeat_n(1.0, extra))
        .collect();
    let ps = DMatrix::from_fn(nv, nv, |i, j| {
        if i < p && j < p {
            2.0 * d[i] * h[(i, j)] * d[j]
        } else {
            0.0
        }
    });
    let mut q: Vec<f64> = (0..nv)
        .map(|i| if i < p { -2.0 * d[i] * g[i] } else { 0.0 })
        .collect();
    let all = groups(model, opts)?;
    let mut rows = ConeRows::default();
    let nonneg = group_rows(&all, (opts.constraints, opts.eps), &d, &mut rows);
    if logdet {
        logdet_rows(model, prior, opts.prior_weight, &d, &mut q, &mut rows)?;
    }
    nonnegative_rows(&nonneg, &d, &mut rows);
    run_clarabel(&ps, &q, rows, (p, &d), opts.dense_solver)
}

/// The cones of the body groups under `set` appended to `rows` (per body its LMI, then under
/// the ellipsoid set its CoM cone), in order; returns the forms held non-negative: the bodies'
/// `tr(JQ)` rows (ellipsoid set), then the affine groups', in order.
fn group_rows(
    groups: &[Group],
    (set, eps): (ConstraintSet, f64),
    d: &[f64],
    rows: &mut ConeRows,
) -> Vec<Affine> {
    let mut nonneg: Vec<Affine> = vec![];
    for group in groups {
        let Group::Body { col, ellipsoid } = group else {
            continue;
        };
        match (set, ellipsoid) {
            (ConstraintSet::Semi, _) => lmi_rows(rows, Lmi::Spatial, *col, eps, d),
            (ConstraintSet::Ellipsoid, Some(e)) => {
                lmi_rows(rows, Lmi::Pseudo, *col, eps, d);
                com_rows(rows, e, *col, d);
                // `tr(JQ) ≥ ε` (kg): the same margin as `J ⪰ ε 1`, so that a body the data
                // push onto its ellipsoid's boundary is inside it by more than the solver's
                // tolerance (without it, `tr(JQ) = −3e-8` on the quadruped's base rows).
                let form = lmi::trace_jq_form(e);
                nonneg.push(((0..10).map(|k| (col + k, form[k])).collect(), -eps));
            }
            _ => lmi_rows(rows, Lmi::Pseudo, *col, eps, d),
        }
    }
    nonneg.extend(groups.iter().filter_map(|g| match g {
        Group::Row(a) => Some(a.clone()),
        Group::Body { .. } => None,
    }));
    nonneg
}

/// `M(π) − ε 1 ⪰ 0` for the body whose ten parameters start at `col` (scaled by `d`):
/// `s = svec(M(π)) − ε svec(1)`, i.e. `A = −svec(M_k) d_k`, `b = −ε svec(1)`.
fn lmi_rows(rows: &mut ConeRows, lmi: Lmi, col: usize, eps: f64, d: &[f64]) {
    let r0 = rows.next_row();
    for (k, colv) in lmi.basis().iter().enumerate() {
        for (r, v) in colv.iter().enumerate() {
            rows.entry(r0 + r, col + k, -v * d[col + k]);
        }
    }
    let eye = DMatrix::<f64>::identity(lmi.dim(), lmi.dim()) * eps;
    rows.close(
        lmi::svec(&eye).iter().map(|x| -x),
        SupportedConeT::PSDTriangleConeT(lmi.dim()),
    );
}

/// The CoM-in-ellipsoid LMI `C(π) = [[m, dᵀ], [d, m Q_s]] ⪰ 0`, `d = h − m x_s` (paper eq. 22),
/// as the second-order cone it is equal to: with `Q_s = L Lᵀ`, the Schur complement of `m`
/// gives `C ⪰ 0 ⇔ ‖L⁻¹ d‖ ≤ m` (and `m = 0` forces `d = 0` in both). Four rows in a
/// second-order cone instead of a 4×4 PSD block, which the solver handles with no
/// eigen-decompositions; a flat ellipsoid (no `L⁻¹`) keeps the LMI.
fn com_rows(rows: &mut ConeRows, e: &Ellipsoid, col: usize, d: &[f64]) {
    let Some(l_inv) = e.qs.cholesky().and_then(|c| c.l().try_inverse()) else {
        return lmi_rows(rows, Lmi::Com(*e), col, 0.0, d);
    };
    let (m, h) = (col, [col + 1, col + 2, col + 3]);
    let l_inv_x = l_inv * e.center;
    // Row 0: m. Rows 1–3: (L⁻¹ h)_r − m (L⁻¹ x_s)_r. Columns in scaled variables (θ = D x).
    let mut a = vec![vec![(m, d[m])]];
    a.extend((0..3).map(|r| {
        let mut terms = vec![(m, -l_inv_x[r] * d[m])];
        terms.extend((0..3).map(|c| (h[c], l_inv[(r, c)] * d[h[c]])));
        terms
    }));
    rows.second_order(&[0.0; 4], &a);
}

/// The log-det regularizer's variables and cones for every body (Lee, Wensing & Park): per
/// body `w (tr(Ĵ⁻¹ J) − Σ u_i)` in the objective `q`, `[[J, L], [Lᵀ, diag L]] ⪰ 0` (8×8) and
/// `(u_i, 1, L_ii)` in the exponential cone, so that `Σ u_i ≤ log det J`.
/// The extra variables follow θ's `p` entries, 14 per body (L's ten, then the four `u`).
fn logdet_rows<R: Parameterized + ?Sized>(
    model: &R,
    prior: &DVector<f64>,
    w: f64,
    d: &[f64],
    q: &mut [f64],
    rows: &mut ConeRows,
) -> Result<(), IdentError> {
    let p = prior.len();
    let jbasis: Vec<nalgebra::Matrix4<f64>> = (0..10)
        .map(|k| {
            let mut e = nalgebra::SVector::<f64, 10>::zeros();
            e[k] = 1.0;
            InertialParams(e).pseudo_inertia()
        })
        .collect();
    // L's lower-triangular entries (i >= j) in order; `lpos(i, j)` is the variable offset.
    let lentries: Vec<(usize, usize)> = (0..4).flat_map(|j| (j..4).map(move |i| (i, j))).collect();
    let lpos = |i: usize, j: usize| {
        lentries
            .iter()
            .position(|&x| x == (i, j))
            .expect("lower-triangular entry")
    };
    for (bi, (name, col, _)) in model.inertial_bodies().iter().enumerate() {
        let j0 = InertialParams(prior.fixed_rows::<10>(*col).into_owned()).pseudo_inertia();
        let j0inv = j0
            .try_inverse()
            .filter(|_| j0.cholesky().is_some())
            .ok_or_else(|| IdentError::InconsistentPrior(name.clone()))?;
        for (k, m_k) in jbasis.iter().enumerate() {
            q[col + k] += w * (j0inv * m_k).trace() * d[col + k];
        }
        let base = p + 14 * bi;
        for i in 0..4 {
            q[base + 10 + i] = -w;
        }
        // J(π) entry by entry, its terms over the body's scaled parameters (zeros left out).
        let mut j = AffineSym::new(4);
        for (k, m_k) in jbasis.iter().enumerate() {
            for c in 0..4 {
                for r in 0..=c {
                    let v = m_k[(r, c)] * d[col + k];
                    if v != 0.0 {
                        j.at(r, c).1.push((col + k, v));
                    }
                }
            }
        }
        let factor = |r: usize, c: usize| (r >= c).then(|| base + lpos(r, c));
        rows.log_det(j, factor, |i| base + 10 + i);
    }
    Ok(())
}

/// One non-negative cone over the affine forms `nonneg` (none when empty): `s = Σ v θ_c +
/// constant`, i.e. `A = −v d_c`, `b = constant`.
fn nonnegative_rows(nonneg: &[Affine], d: &[f64], rows: &mut ConeRows) {
    let r0 = rows.next_row();
    for (r, (terms, _)) in nonneg.iter().enumerate() {
        for &(c, v) in terms {
            rows.entry(r0 + r, c, -v * d[c]);
        }
    }
    rows.close(
        nonneg.iter().map(|(_, constant)| *constant),
        SupportedConeT::NonnegativeConeT(nonneg.len()),
    );
}

/// Upper triangle of a symmetric matrix as CSC (Clarabel needs the upper triangle).
fn upper_csc(m: &DMatrix<f64>) -> CscMatrix<f64> {
    let n = m.nrows();
    let (mut colptr, mut rowval, mut nzval) = (vec![0], vec![], vec![]);
    for j in 0..n {
        for i in 0..=j {
            let v = m[(i, j)];
            if v != 0.0 {
                rowval.push(i);
                nzval.push(v);
            }
        }
        colptr.push(rowval.len());
    }
    CscMatrix::new(n, n, colptr, rowval, nzval)
}

/// The program in `δ = x − x₀` about the unconstrained minimizer `x₀ = −P⁻¹q` of θ's `p`
/// entries (the others 0): `min ½ δᵀPδ + (q + P x₀)ᵀδ` s.t. `A δ + s = b − A x₀`, the same
/// program for any `x₀`. Its optimal value is what the constraints cost above least squares,
/// near 0, instead of `−Σ τ²`-sized: Clarabel's relative gap (and so the optimum's accuracy in
/// the fit's objective) is then measured on that excess. Returns `x₀`, `q + P x₀`, `b − A x₀`;
/// `x₀ = 0` where `P`'s block is not positive definite.
fn shifted_to_unconstrained(
    ps: &DMatrix<f64>,
    q: &[f64],
    a: &CscMatrix<f64>,
    mut b: Vec<f64>,
    p: usize,
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let nv = q.len();
    let pp = ps.view((0, 0), (p, p)).into_owned();
    let minus_q = DVector::from_iterator(p, q[..p].iter().map(|v| -v));
    let mut x0 = vec![0.0; nv];
    if let Some(ch) = pp.cholesky() {
        let xp = ch.solve(&minus_q);
        if xp.iter().all(|v| v.is_finite()) {
            x0[..p].copy_from_slice(xp.as_slice());
        }
    }
    let x0v = DVector::from_column_slice(&x0);
    let q_shift: Vec<f64> = (ps * &x0v).iter().zip(q).map(|(px, q)| q + px).collect();
    subtract_a_x(a, &x0, &mut b);
    (x0, q_shift, b)
}

/// `b ← b − A x` for a CSC matrix `A` (Clarabel's own product is private to it).
fn subtract_a_x(a: &CscMatrix<f64>, x: &[f64], b: &mut [f64]) {
    for (j, &xj) in x.iter().enumerate() {
        for k in a.colptr[j]..a.colptr[j + 1] {
            b[a.rowval[k]] -= a.nzval[k] * xj;
        }
    }
}

/// Solves the scaled cone program `min ½ xᵀ P x + qᵀ x` s.t. `rows`, shifted to the
/// unconstrained minimizer: by the dense method where `dense` asks for it, its cones allow and
/// it converges, else by Clarabel. θ = D x on success, an [`IdentError`] otherwise. No
/// Clarabel type leaves here.
fn run_clarabel(
    ps: &DMatrix<f64>,
    q: &[f64],
    rows: ConeRows,
    (p, d): (usize, &[f64]),
    dense: bool,
) -> Result<(DVector<f64>, SolverInfo), IdentError> {
    let nv = q.len();
    let (a, b, cones) = rows.into_parts(nv);
    let shifted = shifted_to_unconstrained(ps, q, &a, b.clone(), p);
    let start = std::time::Instant::now();
    let found = dense
        .then(|| dense_optimum(ps, &a, &shifted, &cones))
        .flatten();
    if let Some(found) = found {
        let info = SolverInfo {
            status: if found.reduced {
                SolveStatus::AlmostSolved
            } else {
                SolveStatus::Solved
            },
            iterations: found.iterations,
            seconds: start.elapsed().as_secs_f64(),
            residuals: found.residuals,
        };
        return Ok((theta_of(&found.x, &shifted.0, p, d), info));
    }
    clarabel_optimum(ps, (&a, &cones), shifted, (q, b), (p, d))
}

/// θ = D (x₀ + δ), the first `p` entries.
fn theta_of(delta: &[f64], x0: &[f64], p: usize, d: &[f64]) -> DVector<f64> {
    let x = delta.iter().zip(x0).map(|(dx, x0)| x0 + dx);
    DVector::from_iterator(p, x.zip(d).take(p).map(|(x, s)| x * s))
}

/// Clarabel's optimum of the program, shifted (`(x₀, q + P x₀, b − A x₀)`) and about the
/// origin (`q`, `b`).
fn clarabel_optimum(
    ps: &DMatrix<f64>,
    (a, cones): (&CscMatrix<f64>, &[SupportedConeT<f64>]),
    shifted: (Vec<f64>, Vec<f64>, Vec<f64>),
    (q, b): (&[f64], Vec<f64>),
    (p, d): (usize, &[f64]),
) -> Result<(DVector<f64>, SolverInfo), IdentError> {
    let nv = q.len();
    let p_upper = upper_csc(ps);
    let origin = (vec![0.0; nv], q.to_vec(), b);
    // In `x − x₀` first, then about the origin; each with Clarabel's equilibration, then
    // without it. The variables are already scaled to unit curvature; the equilibration on top
    // can stall in the nearly flat directions only the prior weight holds (a simulated KUKA log
    // under `consistent`: "almost solved" after 40 iterations, 2.5e-5 relative above the
    // optimum it reaches without in 13). About the origin is the fallback for the rare program
    // whose shift the solver cannot follow (the sample-size experiment at 19 samples, seed 13,
    // `semi`: a numerical error both ways about `x₀`). The first "solved" answer is kept, else
    // the first "almost solved", else the first attempt's status; the time is all attempts'.
    let attempts = [
        (&shifted, true),
        (&shifted, false),
        (&origin, true),
        (&origin, false),
    ];
    let mut seconds = 0.0;
    let mut kept: Option<(Vec<f64>, DefaultSolution<f64>)> = None;
    for ((x0, q, b), equilibrate) in attempts {
        let settings = DefaultSettings {
            verbose: false,
            max_iter: 200,
            equilibrate_enable: equilibrate,
            ..DefaultSettings::default()
        };
        let mut solver = DefaultSolver::new(&p_upper, q, a, b, cones, settings)
            .map_err(|e| IdentError::Rejected(e.to_string()))?;
        solver.solve();
        let sol = solver.solution;
        seconds += sol.solve_time;
        let better = |k: &DefaultSolution<f64>| {
            sol.status == SolverStatus::Solved
                || (sol.status == SolverStatus::AlmostSolved
                    && k.status != SolverStatus::AlmostSolved)
        };
        if kept.as_ref().is_none_or(|(_, k)| better(k)) {
            kept = Some((x0.clone(), sol));
        }
        if kept
            .as_ref()
            .is_some_and(|(_, k)| k.status == SolverStatus::Solved)
        {
            break;
        }
    }
    let (x0, sol) = kept.expect("at least one attempt");
    solution(sol, &x0, p, d, seconds)
}

/// The shifted program's optimum by the dense method (`dense.rs`), where its cones are only
/// orthants and PSD cones and the method converges; `None` sends it to Clarabel.
fn dense_optimum(
    ps: &DMatrix<f64>,
    a: &CscMatrix<f64>,
    (_, q, b): &(Vec<f64>, Vec<f64>, Vec<f64>),
    cones: &[SupportedConeT<f64>],
) -> Option<dense::Optimum> {
    let cones: Vec<dense::Cone> = cones
        .iter()
        .map(|c| match c {
            SupportedConeT::NonnegativeConeT(n) => Some(dense::Cone::Nonneg(*n)),
            SupportedConeT::PSDTriangleConeT(k) => Some(dense::Cone::Psd(*k)),
            _ => None,
        })
        .collect::<Option<_>>()?;
    let mut dense_a = DMatrix::zeros(a.m, a.n);
    for j in 0..a.n {
        for k in a.colptr[j]..a.colptr[j + 1] {
            dense_a[(a.rowval[k], j)] = a.nzval[k];
        }
    }
    dense::solve(&dense::Program {
        p: ps,
        q,
        a: &dense_a,
        b,
        cones: &cones,
    })
}

/// θ = D (x₀ + δ) from Clarabel's solution `δ`, or the error its status names.
fn solution(
    sol: DefaultSolution<f64>,
    x0: &[f64],
    p: usize,
    d: &[f64],
    seconds: f64,
) -> Result<(DVector<f64>, SolverInfo), IdentError> {
    let info = |status: SolveStatus| SolverInfo {
        status,
        iterations: sol.iterations,
        seconds,
        residuals: [sol.r_prim, sol.r_dual],
    };
    match sol.status {
        SolverStatus::Solved | SolverStatus::AlmostSolved => {
            let theta = theta_of(&sol.x, x0, p, d);
            let status = if sol.status == SolverStatus::Solved {
                SolveStatus::Solved
            } else {
                SolveStatus::AlmostSolved
            };
            Ok((theta, info(status)))
        }
        SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible => {
            Err(IdentError::Infeasible(format!("{:?}", sol.status)))
        }
        s => Err(IdentError::SolverFailed {
            status: format!("{s:?}"),
            iterations: sol.iterations,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, Vector3};
    use physid_core::spatial::Ellipsoid;
    use rand::{Rng, SeedableRng};

    /// `s = b − A x` of the only cone in `rows`.
    fn slack(rows: ConeRows, x: &[f64]) -> Vec<f64> {
        let (a, mut s, _) = rows.into_parts(x.len());
        subtract_a_x(&a, x, &mut s);
        s
    }

    #[test]
    fn the_com_cone_holds_exactly_where_the_com_lmi_does() {
        // Random rotated ellipsoids and bodies (mass, CoM inside or outside), in scaled
        // variables: the second-order cone of `com_rows` and the 4×4 LMI agree on membership,
        // and the cone's margin has the LMI's sign.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (mut inside, mut outside) = (0, 0);
        for _ in 0..400 {
            let axes = Vector3::from_fn(|_, _| rng.random_range(0.02..0.4));
            let rot =
                Rotation3::from_scaled_axis(Vector3::from_fn(|_, _| rng.random_range(-2.0..2.0)));
            let center = Vector3::from_fn(|_, _| rng.random_range(-0.3..0.3));
            let e = Ellipsoid {
                center,
                qs: rot.matrix()
                    * nalgebra::Matrix3::from_diagonal(&axes.component_mul(&axes))
                    * rot.matrix().transpose(),
            };
            let m = rng.random_range(0.0..5.0);
            let dir = Vector3::from_fn(|_, _| rng.random_range(-1.0..1.0));
            let com = center + rot.matrix() * axes.component_mul(&dir) * rng.random_range(0.0..1.6);
            let h = com * m;
            let d: Vec<f64> = (0..10).map(|_| rng.random_range(0.5..2.0)).collect();
            let x: Vec<f64> = [m, h.x, h.y, h.z]
                .iter()
                .zip(&d)
                .map(|(t, s)| t / s)
                .chain([0.0; 6])
                .collect();
            let lmi_min = nalgebra::SymmetricEigen::new(e.com_lmi(m, &h))
                .eigenvalues
                .min();
            if lmi_min.abs() < 1e-9 {
                continue;
            }
            let mut rows = ConeRows::default();
            com_rows(&mut rows, &e, 0, &d);
            let s = slack(rows, &x);
            assert_eq!(s.len(), 4);
            let margin = s[0] - (s[1] * s[1] + s[2] * s[2] + s[3] * s[3]).sqrt();
            assert_eq!(
                margin >= 0.0,
                lmi_min >= 0.0,
                "margin {margin:e}, λ_min {lmi_min:e}"
            );
            if lmi_min >= 0.0 {
                inside += 1;
            } else {
                outside += 1;
            }
        }
        assert!(
            inside > 100 && outside > 100,
            "{inside} inside, {outside} outside"
        );
    }

    #[test]
    fn a_flat_ellipsoid_keeps_the_com_lmi() {
        let flat = Ellipsoid::axis_aligned(Vector3::zeros(), Vector3::new(0.1, 0.1, 0.0));
        let mut rows = ConeRows::default();
        com_rows(&mut rows, &flat, 0, &[1.0; 10]);
        let (_, b, cones) = rows.into_parts(10);
        assert_eq!(b.len(), 10);
        assert!(matches!(cones[0], SupportedConeT::PSDTriangleConeT(4)));
    }
}
