//! Which body of a floating robot changed: the description's residual on a new run, and how far
//! freeing one body's ten parameters lowers it.
//!
//! For every body `b` (the trunk, links, rotors) the change `Δπ_b` that best explains the new
//! run's data with everything else at the description `θ_d` is a least-squares fit on the run's
//! normal equations: with `E_b` the body's ten columns, `g = Yᵀτ − YᵀY θ_d` (the data's pull
//! away from the description), `Δπ_b = (E_bᵀ YᵀY E_b)⁻¹ E_bᵀ g` and the residual falls by
//! `ΔRSS_b = gᵀ E_b Δπ_b`. Its evidence is the F statistic
//! `F_b = (ΔRSS_b / k_b) / (RSS_b / (N − k_b))` over `N` rows, `k_b` the rank of the body's
//! columns in these data: a body is named only where `F_b` exceeds the threshold (the change
//! would be noise otherwise), the largest first. A payload rigidly carried by a body is such a
//! change: its mass `Δm` and centre of mass `Δh / Δm` in the body's frame come with it.
//!
//! A joint's friction is asked the same way ([`friction_changes`]): its viscous and Coulomb
//! columns freed (`k ≤ 2`), the rest at the description. A body's ten free parameters absorb a
//! little of any misfit; a friction change that explains the run with more evidence per column
//! (a larger F) than the best body's is the better reading (a joint worn or lubricated, not a
//! payload).

use nalgebra::{DMatrix, DVector, Vector3};
use physid_ident::{NormalEquations, Parameterized};
use serde::Serialize;

/// One body's best change on the new run.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct BodyChange {
    /// Body name.
    pub body: String,
    /// First column of its parameters in `θ`.
    pub column: usize,
    /// The change of its ten parameters (paper order, its own frame).
    pub delta: [f64; 10],
    /// The change of mass (kg).
    pub mass: f64,
    /// The changed mass's centre in the body frame, `Δh / Δm` (m); `None` without a mass change.
    pub com: Option<Vector3<f64>>,
    /// Relative fall of the residual sum of squares.
    pub reduction: f64,
    /// The F statistic of the change.
    pub f: f64,
    /// Columns of the body the data determine (`k_b`).
    pub determined: usize,
}

/// The run's pull away from the description: `g = Yᵀτ − YᵀY θ_d`, the description's residual
/// sum of squares and the number of rows.
struct Pull {
    g: DVector<f64>,
    rss0: f64,
    rows: f64,
}

impl Pull {
    fn of<R: Parameterized + ?Sized>(description: &R, ne: &NormalEquations) -> Self {
        let theta = description.parameters();
        Self {
            g: &ne.ytt - &ne.yty * &theta,
            rss0: ne.residual_sum_of_squares(&theta),
            rows: (ne.samples * ne.rows_per_sample()) as f64,
        }
    }
}

/// Every body's change, largest F first, for the robot described by `description` on a run's
/// normal equations `ne` (the robot's columns, any data setting).
pub fn body_changes<R: Parameterized + ?Sized>(
    description: &R,
    ne: &NormalEquations,
) -> Vec<BodyChange> {
    let Pull { g, rss0, rows } = Pull::of(description, ne);
    let mut changes: Vec<BodyChange> = description
        .inertial_bodies()
        .into_iter()
        .map(|(body, column, _)| body_change(ne, &g, (rss0, rows), body, column))
        .collect();
    changes.sort_by(|a, b| b.f.total_cmp(&a.f));
    changes
}

/// The body at `column`'s least-squares change (see the module docs).
fn body_change(
    ne: &NormalEquations,
    g: &DVector<f64>,
    (rss0, rows): (f64, f64),
    body: String,
    column: usize,
) -> BodyChange {
    let columns: Vec<usize> = (column..column + 10).collect();
    let fit = ColumnsFit::of(ne, g, (rss0, rows), &columns);
    let delta = &fit.delta;
    let mass = delta[0];
    let com = (mass.abs() > 1e-9).then(|| Vector3::new(delta[1], delta[2], delta[3]) / mass);
    BodyChange {
        body,
        column,
        delta: std::array::from_fn(|i| delta[i]),
        mass,
        com,
        reduction: fit.reduction,
        f: fit.f,
        determined: fit.determined,
    }
}

/// The least-squares change of a group of `θ`'s columns with the rest at the description: the
/// change, the F statistic, the share of the residual it removes and the columns determined.
struct ColumnsFit {
    delta: DVector<f64>,
    f: f64,
    reduction: f64,
    determined: usize,
}

impl ColumnsFit {
    /// The fit of `columns` on `ne`, `g = Yᵀτ − YᵀY θ_d`, the description's residual sum of
    /// squares `rss0` over `rows` rows.
    fn of(
        ne: &NormalEquations,
        g: &DVector<f64>,
        (rss0, rows): (f64, f64),
        columns: &[usize],
    ) -> Self {
        let k = columns.len();
        let block = DMatrix::from_fn(k, k, |i, j| ne.yty[(columns[i], columns[j])]);
        let pull = DVector::from_iterator(k, columns.iter().map(|&c| g[c]));
        let (delta, determined) = pseudo_solve(&block, &pull);
        let fall = pull.dot(&delta).max(0.0);
        let rss = (rss0 - fall).max(0.0);
        let k = determined.max(1) as f64;
        let f = if rss > 0.0 {
            (fall / k) / (rss / (rows - k).max(1.0))
        } else {
            f64::INFINITY
        };
        let reduction = if rss0 > 0.0 { fall / rss0 } else { 0.0 };
        Self {
            delta,
            f,
            reduction,
            determined,
        }
    }
}

/// One joint's best friction change on the new run.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct FrictionChange {
    /// Joint name.
    pub joint: String,
    /// Its viscous and Coulomb columns in `θ`.
    pub columns: [usize; 2],
    /// The change of its viscous coefficient (N m s/rad, N s/m for a prismatic joint).
    pub viscous: f64,
    /// The change of its Coulomb friction (N m, N for a prismatic joint).
    pub coulomb: f64,
    /// Relative fall of the residual sum of squares.
    pub reduction: f64,
    /// The F statistic of the change.
    pub f: f64,
    /// Columns of the joint's friction the data determine (`k`, at most 2).
    pub determined: usize,
}

/// Every joint's friction change, largest F first, for the robot described by `description`
/// on a run's normal equations `ne` (see the module docs).
pub fn friction_changes<R: Parameterized + ?Sized>(
    description: &R,
    ne: &NormalEquations,
) -> Vec<FrictionChange> {
    let Pull { g, rss0, rows } = Pull::of(description, ne);
    let names = description.parameter_names();
    let (viscous, coulomb) = description.friction_columns();
    let mut changes: Vec<FrictionChange> = (0..description.joints())
        .map(|j| {
            let columns = [viscous + j, coulomb + j];
            let fit = ColumnsFit::of(ne, &g, (rss0, rows), &columns);
            let name = &names[viscous + j];
            FrictionChange {
                joint: name
                    .rsplit_once('.')
                    .map_or(name.as_str(), |(j, _)| j)
                    .into(),
                columns,
                viscous: fit.delta[0],
                coulomb: fit.delta[1],
                reduction: fit.reduction,
                f: fit.f,
                determined: fit.determined,
            }
        })
        .collect();
    changes.sort_by(|a, b| b.f.total_cmp(&a.f));
    changes
}

/// The friction change [`friction_changes`] ranks first, named when it passes `min_f` and
/// `min_reduction` (as [`name_change`]) and carries more evidence than the best body change
/// (`best_body`, its F statistic): then it, not the body, reads the run.
pub fn name_friction(
    frictions: &[FrictionChange],
    best_body: Option<&BodyChange>,
    (min_f, min_reduction): (f64, f64),
) -> Option<FrictionChange> {
    frictions
        .first()
        .filter(|c| c.f > min_f && c.reduction >= min_reduction)
        .filter(|c| best_body.is_none_or(|b| c.f > b.f))
        .cloned()
}

/// One joint's sums for its torque gain on a run: over its rows, `Σ τ̂²` (`cc`, the predicted
/// motor torque squared), `Σ τ̂ r` (`cr`, against the row's residual `r`) and `Σ r²` (`rr`).
#[derive(Clone, Debug, PartialEq)]
pub struct GainSums {
    /// Joint name.
    pub joint: String,
    /// `Σ τ̂_j²` (N² m²).
    pub cc: f64,
    /// `Σ τ̂_j r_j` (N² m²).
    pub cr: f64,
    /// `Σ r_j²` (N² m²).
    pub rr: f64,
}

/// One joint's best torque gain change on the new run: the logged torque `(1 + β)` times
/// the motor's (a current sensor's scale, a torque constant).
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct GainChange {
    /// Joint name.
    pub joint: String,
    /// The gain error `β` (–): `Σ τ̂ r / Σ τ̂²`.
    pub gain: f64,
    /// Relative fall of the residual sum of squares, `(Σ τ̂ r)² / Σ τ̂² / RSS`.
    pub reduction: f64,
    /// Relative fall of the joint's own rows' residual sum of squares, `(Σ τ̂ r)² / Σ τ̂² / Σ r²`.
    pub joint_reduction: f64,
    /// The F statistic of the change (one column).
    pub f: f64,
}

/// Every joint's torque gain change from its [`GainSums`], largest F first, against the
/// description's residual on the run's normal equations `ne` (`θ_d` = `description`).
pub fn gain_changes<R: Parameterized + ?Sized>(
    description: &R,
    ne: &NormalEquations,
    sums: &[GainSums],
) -> Vec<GainChange> {
    let Pull { rss0, rows, .. } = Pull::of(description, ne);
    let mut changes: Vec<GainChange> = (sums.iter())
        .filter(|s| s.cc > 0.0)
        .map(|s| {
            let fall = (s.cr * s.cr / s.cc).min(rss0);
            let rss = rss0 - fall;
            GainChange {
                joint: s.joint.clone(),
                gain: s.cr / s.cc,
                reduction: if rss0 > 0.0 { fall / rss0 } else { 0.0 },
                joint_reduction: if s.rr > 0.0 {
                    (fall / s.rr).min(1.0)
                } else {
                    0.0
                },
                f: if rss > 0.0 {
                    fall / (rss / (rows - 1.0).max(1.0))
                } else {
                    f64::INFINITY
                },
            }
        })
        .collect();
    changes.sort_by(|a, b| b.f.total_cmp(&a.f));
    changes
}

/// A gain change is named where it removes at least this share of its own joint's residual (a
/// gain acts on one joint's rows only, so the whole log's residual, most of it other joints',
/// would hide one on a lightly loaded joint). Measured on 6 s quadruped logs (standing and
/// trotting, seeds 1-3): unchanged, the best joint's gain removed 0.2-6.3 % of its joint's
/// residual; an ab/ad joint's torque logged at 0.95 times, 18-47 %.
pub const GAIN_MIN_JOINT_REDUCTION: f64 = 0.15;

/// The gain change [`gain_changes`] ranks first, named when its F statistic exceeds `min_f`,
/// it removes [`GAIN_MIN_JOINT_REDUCTION`] of its joint's residual, and it carries more
/// evidence than the changes already named (their F statistics in `others`).
pub fn name_gain(gains: &[GainChange], others: &[f64], min_f: f64) -> Option<GainChange> {
    gains
        .first()
        .filter(|c| c.f > min_f && c.joint_reduction >= GAIN_MIN_JOINT_REDUCTION)
        .filter(|c| others.iter().all(|&f| c.f > f))
        .cloned()
}

/// The minimum-norm solution of `a x = b` for symmetric positive semidefinite `a`, on the
/// eigen-directions above round-off relative to the largest (after unit-diagonal scaling),
/// and how many there are.
fn pseudo_solve(a: &DMatrix<f64>, b: &DVector<f64>) -> (DVector<f64>, usize) {
    let d = physid_core::linalg::unit_diagonal_scale(a, 0.0);
    let n = a.nrows();
    let scaled = DMatrix::from_fn(n, n, |i, j| d[i] * a[(i, j)] * d[j]);
    let eig = nalgebra::SymmetricEigen::new(scaled);
    let largest = eig.eigenvalues.max().max(0.0);
    let bs = DVector::from_iterator(n, (0..n).map(|i| d[i] * b[i]));
    let mut x = DVector::zeros(n);
    let mut kept = 0;
    for k in 0..n {
        let lambda = eig.eigenvalues[k];
        if lambda > 1e-10 * largest && largest > 0.0 {
            let v = eig.eigenvectors.column(k);
            x += v * (v.dot(&bs) / lambda);
            kept += 1;
        }
    }
    (DVector::from_iterator(n, (0..n).map(|i| d[i] * x[i])), kept)
}

/// What the changes name: the body whose change explains the run best, if its evidence is
/// strong enough, with the bodies that explain it almost as well.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct Named {
    /// The changed body, if any passes `min_f` and `min_reduction`.
    pub changed: Option<BodyChange>,
    /// Bodies whose change leaves at most `1.5` times the named one's unexplained residual and
    /// removes at least `0.8` of what it removes: the data cannot tell them apart from it (e.g.
    /// a rotor carried rigidly by the same body). Both: where the named change removes a small
    /// share, the first alone admits every body.
    pub also_fit: Vec<String>,
}

/// The change [`body_changes`] ranks first, named when its F statistic exceeds `min_f` and it
/// lowers the residual by at least `min_reduction` (a share of it): a large F alone comes with
/// any small systematic misfit on long runs, a large reduction alone with few rows.
pub fn name_change(changes: &[BodyChange], min_f: f64, min_reduction: f64) -> Named {
    let Some(top) = changes
        .first()
        .filter(|c| c.f > min_f && c.reduction >= min_reduction)
    else {
        return Named {
            changed: None,
            also_fit: vec![],
        };
    };
    let left = 1.0 - top.reduction;
    let also_fit = changes[1..]
        .iter()
        .filter(|c| 1.0 - c.reduction <= 1.5 * left && c.reduction >= 0.8 * top.reduction)
        .map(|c| c.body.clone())
        .collect();
    Named {
        changed: Some(top.clone()),
        also_fit,
    }
}
