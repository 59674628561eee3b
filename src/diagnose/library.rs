//! The effect library, identification side: each unmodelled effect offered to the
//! identification as extra regressor columns `E_k` next to the rigid-body regressor `Y_k`, so
//! that `τ_k ≈ Y_k θ + E_k c` (equations and units in `docs/diagnose.md`). Linear effects are
//! columns of the data; nonlinear ones are linearized about the nominal model `θ̂₀` (gain, tilt,
//! compliance, delay) or searched over a one-dimensional grid (Stribeck velocity, cogging
//! harmonic), each grid point a [`Variant`].
//!
//! Sign convention: a coefficient is the physical magnitude of the injected effect
//! (`crate::sim::effects`), e.g. the columns of an acting friction are `−∂τ_effect/∂c` because the
//! motor torque must overcome it.

use crate::dynamics::{regressor, Data};
use crate::model::Model;
use crate::trajectory::Trajectory;
use nalgebra::{DMatrix, DVector, Vector3};
use serde::Serialize;

/// An effect kind the diagnosis can offer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, PartialOrd, Ord)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// Logged `τ += o` (N m per joint).
    TorqueOffset,
    /// Logged `τ ×= 1 + δ` (per joint; a common δ is a scale of all inertial parameters).
    TorqueGain,
    /// Logged torque lags the kinematics by `d` (s, one for all joints).
    TimeDelay,
    /// `τ_acting = −k (q − q₀)` (N m/rad, rad per joint).
    Spring,
    /// `τ_acting = −F_s exp(−(q̇/v)²) sign(q̇)` (N m per joint; `v` searched).
    Stribeck,
    /// `τ_acting = −δ max(0, sign(q̇))` (N m per joint).
    AsymmetricCoulomb,
    /// `τ_acting = −μ |τ| sign(q̇)` (per joint; `|τ|` from the nominal prediction).
    LoadDependentFriction,
    /// `τ_acting = −A sin(h N q + φ)` (N m per joint; harmonic `h` searched).
    Cogging,
    /// Reflected rotor inertia `I_a q̈` left out of the model (kg m² per joint).
    RotorInertia,
    /// Gravity misaligned by a small base tilt (m/s² of the gravity vector's perpendicular
    /// components; reported as an angle).
    Tilt,
    /// Compliant transmission seen by a motor-side encoder: `q_logged = q + κ τ`
    /// (κ = 1/k, rad/(N m) per joint).
    Compliance,
    /// Backlash read by a motor-side encoder: `q_logged = q + (b/2) sign(τ)` (b = dead-zone
    /// width, rad per joint; the sign from the logged torque).
    Backlash,
    /// An unmodelled payload on the last body: ten inertial parameters `π_p` added to it (the
    /// last body's own regressor columns; reported as its mass, kg). Its columns lie in the
    /// model's span, so only the test against the description can find it.
    Payload,
}

/// How many columns a kind adds for `n` joints.
#[derive(Clone, Copy, Debug, PartialEq)]
enum ColumnCount {
    /// A fixed number, whatever the joint count.
    Fixed(usize),
    /// `k` per joint.
    PerJoint(usize),
}

/// The search grid of a kind's one-dimensional parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Grid {
    /// No parameter (one variant, `param = 0`).
    None,
    /// Stribeck velocities (rad/s): 0.04 · √2^i, i = 0..9.
    StribeckVelocity,
    /// Cogging harmonics per rotor revolution: 1..=8.
    CoggingHarmonic,
}

/// Everything the diagnosis knows about one kind besides its columns and its simulation: one
/// row of [`KIND_TABLE`] per kind.
#[derive(Clone, Copy, Debug)]
struct KindSpec {
    kind: Kind,
    /// snake_case name, as in scenario files.
    name: &'static str,
    columns: ColumnCount,
    /// The coefficients have a physical sign (≥ 0), kept in every fit.
    non_negative: bool,
    /// The magnitude's name and unit.
    magnitude: (&'static str, &'static str),
    /// The columns lie in the span of the model's own (only the description test sees it).
    in_model_span: bool,
    grid: Grid,
}

/// One row per kind, in report order ([`Kind::ALL`]).
const KIND_TABLE: [KindSpec; 13] = {
    use ColumnCount::{Fixed, PerJoint};
    const fn row(kind: Kind, name: &'static str, columns: ColumnCount) -> KindSpec {
        KindSpec {
            kind,
            name,
            columns,
            non_negative: false,
            magnitude: ("", ""),
            in_model_span: false,
            grid: Grid::None,
        }
    }
    [
        KindSpec {
            magnitude: ("offset", "N m"),
            ..row(Kind::TorqueOffset, "torque_offset", PerJoint(1))
        },
        KindSpec {
            magnitude: ("gain error relative to the median joint", "-"),
            ..row(Kind::TorqueGain, "torque_gain", PerJoint(1))
        },
        KindSpec {
            magnitude: ("delay", "s"),
            ..row(Kind::TimeDelay, "time_delay", Fixed(1))
        },
        KindSpec {
            magnitude: ("stiffness", "N m/rad"),
            ..row(Kind::Spring, "spring", PerJoint(2))
        },
        KindSpec {
            non_negative: true,
            magnitude: ("static excess F_s", "N m"),
            grid: Grid::StribeckVelocity,
            ..row(Kind::Stribeck, "stribeck", PerJoint(1))
        },
        KindSpec {
            magnitude: ("forward excess delta", "N m"),
            ..row(Kind::AsymmetricCoulomb, "asymmetric_coulomb", PerJoint(1))
        },
        KindSpec {
            non_negative: true,
            magnitude: ("coefficient mu", "-"),
            ..row(
                Kind::LoadDependentFriction,
                "load_dependent_friction",
                PerJoint(1),
            )
        },
        KindSpec {
            magnitude: ("amplitude", "N m"),
            grid: Grid::CoggingHarmonic,
            ..row(Kind::Cogging, "cogging", PerJoint(2))
        },
        KindSpec {
            non_negative: true,
            magnitude: ("reflected inertia", "kg m^2"),
            ..row(Kind::RotorInertia, "rotor_inertia", PerJoint(1))
        },
        KindSpec {
            magnitude: ("tilt angle", "rad"),
            ..row(Kind::Tilt, "tilt", Fixed(2))
        },
        KindSpec {
            non_negative: true,
            magnitude: ("compliance 1/k", "rad/(N m)"),
            ..row(Kind::Compliance, "compliance", PerJoint(1))
        },
        KindSpec {
            non_negative: true,
            magnitude: ("dead-zone width b", "rad"),
            ..row(Kind::Backlash, "backlash", PerJoint(1))
        },
        KindSpec {
            magnitude: ("payload mass on the last body", "kg"),
            in_model_span: true,
            ..row(Kind::Payload, "payload", Fixed(10))
        },
    ]
};

impl Kind {
    /// Every kind, in report order.
    pub const ALL: [Kind; 13] = {
        let mut all = [Kind::TorqueOffset; 13];
        let mut i = 0;
        while i < 13 {
            all[i] = KIND_TABLE[i].kind;
            i += 1;
        }
        all
    };

    /// The kind's row of [`KIND_TABLE`].
    fn spec(&self) -> &'static KindSpec {
        KIND_TABLE
            .iter()
            .find(|s| s.kind == *self)
            .expect("every kind has a row")
    }

    /// snake_case name (as in scenario files).
    pub fn name(&self) -> &'static str {
        self.spec().name
    }

    /// Columns for `n` joints.
    pub fn columns(&self, n: usize) -> usize {
        match self.spec().columns {
            ColumnCount::Fixed(c) => c,
            ColumnCount::PerJoint(k) => k * n,
        }
    }

    /// Whether the coefficients have a physical sign (≥ 0), kept in every fit: Stribeck's
    /// static excess, load-dependent friction, reflected rotor inertia, compliance. A fit
    /// that needs the opposite sign is not this effect.
    pub fn non_negative(&self) -> bool {
        self.spec().non_negative
    }

    /// The magnitude's name and unit, per joint (or for the whole robot).
    pub fn magnitude(&self) -> (&'static str, &'static str) {
        self.spec().magnitude
    }

    /// Whether the columns lie in the span of the model's own (its parameters express the
    /// effect exactly): cross-validation cannot see it and does not offer it.
    pub fn in_model_span(&self) -> bool {
        self.spec().in_model_span
    }

    /// The grid of the one-dimensional search, if any: Stribeck velocities (rad/s, ratio √2)
    /// and cogging harmonics (per rotor revolution).
    pub fn grid(&self) -> Vec<f64> {
        match self.spec().grid {
            Grid::StribeckVelocity => (0..10).map(|i| 0.04 * 2f64.powf(i as f64 / 2.0)).collect(),
            Grid::CoggingHarmonic => (1..=8).map(f64::from).collect(),
            Grid::None => vec![0.0],
        }
    }
}

/// Whether a joint moving at `qd` (rad/s) is slower than `min_speed`: its rows are left out of
/// every fit and error of the diagnosis.
pub fn slow(qd: f64, min_speed: f64) -> bool {
    qd.abs() < min_speed
}

/// A consumer of augmented rows: `(sample, Z_k, τ_k)`.
pub type RowSink<'f> = dyn FnMut(usize, &DMatrix<f64>, &[f64]) + 'f;

/// An effect kind at one point of its grid (`param` = Stribeck velocity or cogging harmonic).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Variant {
    /// The kind.
    pub kind: Kind,
    /// The grid value (0 for kinds without one).
    pub param: f64,
}

/// Every variant of `kinds`.
pub fn variants(kinds: &[Kind]) -> Vec<Variant> {
    kinds
        .iter()
        .flat_map(|&kind| {
            kind.grid()
                .into_iter()
                .map(move |param| Variant { kind, param })
        })
        .collect()
}

/// What the columns of one data set need besides the samples: the nominal prediction `Y θ̂₀`
/// and its time derivatives, computed once over the whole trajectory.
pub struct Context<'a> {
    model: &'a Model,
    theta0: DVector<f64>,
    /// `θ̂₀` without Coulomb friction (smooth in time), for the linearized kinematic effects.
    theta_smooth: DVector<f64>,
    /// `Y_k θ̂₀`, sample-major.
    pred: Vec<f64>,
    /// The first derivative (N m/s, central differences) of the prediction without Coulomb
    /// friction.
    pred_d: Vec<f64>,
    /// The prediction processed like the encoder signal (filtered; filtered derivative;
    /// filtered derivative of that), for the deflection of a compliant transmission.
    defl: [Vec<f64>; 3],
    /// Half the sign of the logged torque processed like the encoder signal, for the offset of
    /// a motor-side encoder across a backlash dead zone.
    slack: [Vec<f64>; 3],
    /// Two unit vectors perpendicular to gravity (the tilt directions).
    perp: [Vector3<f64>; 2],
    gear: Vec<f64>,
}

/// `x` (sample-major, `n` columns) processed like an encoder angle: `F(x)`, `F(D x)`,
/// `F(D F(D x))` with `F` the zero-phase 2nd-order Butterworth low-pass at `cutoff` and `D` the
/// central difference; unfiltered differences if the filter cannot be built.
fn processed_like_encoder(x: &[f64], tr: &Trajectory, cutoff: f64) -> [Vec<f64>; 3] {
    let (m, n) = (tr.len(), tr.dof());
    let dt = tr.sample_period().unwrap_or(1e-3);
    let fs = 1.0 / dt;
    let sos = crate::signal::butterworth_lowpass(2, cutoff.min(0.4 * fs), fs).ok();
    let filt = |v: &[f64]| sos.as_ref().map_or_else(|| v.to_vec(), |s| s.filtfilt(v));
    let diff = |v: &[f64]| crate::signal::differentiate(v, dt);
    let mut out = [vec![0.0; x.len()], vec![0.0; x.len()], vec![0.0; x.len()]];
    for j in 0..n {
        let col: Vec<f64> = (0..m).map(|k| x[k * n + j]).collect();
        let d1 = filt(&diff(&col));
        let d2 = filt(&diff(&d1));
        for (o, v) in out.iter_mut().zip([filt(&col), d1, d2]) {
            for k in 0..m {
                o[k * n + j] = v[k];
            }
        }
    }
    out
}

fn derivative(x: &[f64], t: &[f64], n: usize) -> Vec<f64> {
    let m = t.len();
    let mut out = vec![0.0; x.len()];
    if m < 2 {
        return out;
    }
    for k in 0..m {
        let (a, b) = (k.saturating_sub(1), (k + 1).min(m - 1));
        let dt = t[b] - t[a];
        for j in 0..n {
            out[k * n + j] = (x[b * n + j] - x[a * n + j]) / dt;
        }
    }
    out
}

impl<'a> Context<'a> {
    /// The context of trajectory `tr` (with q̈) for nominal parameters `theta0` (the model's
    /// layout, no extra columns).
    ///
    /// `cutoff` (Hz) is the low-pass of the data's processing (zero-phase 2nd-order
    /// Butterworth of q and of each derivative, as `physid simulate` and `load_trajectory` do),
    /// applied to the predicted torque for the compliance columns; capped at 0.4 × the rate.
    pub fn new(model: &'a Model, theta0: &DVector<f64>, tr: &Trajectory, cutoff: f64) -> Self {
        let n = model.dof();
        let l = model.layout();
        let theta0 = theta0.rows(0, l.len).into_owned();
        let mut theta_smooth = theta0.clone();
        for j in 0..n {
            theta_smooth[l.coulomb_col + j] = 0.0;
        }
        let mut pred = Vec::with_capacity(tr.len() * n);
        let mut smooth = Vec::with_capacity(tr.len() * n);
        crate::ident::normal::for_each_regressor(model, tr, 0..tr.len(), &mut |_, y| {
            pred.extend((y * &theta0).iter());
            smooth.extend((y * &theta_smooth).iter());
        });
        // Without the Coulomb jumps: a delayed jump only matters within the masked slow rows,
        // and differencing it would put spikes into every fitted row next to a reversal.
        let pred_d = derivative(&smooth, &tr.t, n);
        let defl = processed_like_encoder(&pred, tr, cutoff);
        // The side of the dead zone follows the torque actually delivered: the logged torque's
        // sign, a step that is then filtered and differenced like the encoder signal (the
        // prediction's sign switches a few samples off and lost the attribution).
        let half_sign: Vec<f64> = tr
            .tau
            .iter()
            .map(|t| 0.5 * crate::dynamics::sign(*t))
            .collect();
        let slack = processed_like_encoder(&half_sign, tr, cutoff);
        let g = model.gravity.try_normalize(1e-12).unwrap_or(-Vector3::z());
        let a = if g.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let u1 = (a - g * g.dot(&a)).normalize();
        let u2 = g.cross(&u1);
        let gear = model
            .bodies
            .iter()
            .map(|b| b.rotor.as_ref().map_or(1.0, |r| r.gear_ratio))
            .collect();
        Self {
            model,
            theta0,
            theta_smooth,
            pred,
            pred_d,
            defl,
            slack,
            perp: [u1, u2],
            gear,
        }
    }

    /// The model.
    pub fn model(&self) -> &'a Model {
        self.model
    }

    /// The columns `−∂ID/∂ε_j` of inverse dynamics with joint `j`'s encoder signals shifted by
    /// `ε_j · shift_j` (angle, velocity, acceleration of sample `k`, whose state is `[q, q̇, q̈]`;
    /// `data`, `yg` the caller's workspaces), one per joint: how a
    /// motor-side encoder offset (compliance, backlash) enters the rigid-body prediction.
    fn encoder_shift_columns(
        &self,
        shift: &[Vec<f64>; 3],
        k: usize,
        [q, qd, qdd]: [&[f64]; 3],
        data: &mut Data,
        yg: &mut DMatrix<f64>,
    ) -> DMatrix<f64> {
        let model = self.model;
        let n = model.dof();
        let eps = 1e-7;
        let mut out = DMatrix::zeros(n, n);
        for j in 0..n {
            let s = [
                shift[0][k * n + j],
                shift[1][k * n + j],
                shift[2][k * n + j],
            ];
            let mut at = |h: f64| {
                let (mut a, mut b, mut c) = (q.to_vec(), qd.to_vec(), qdd.to_vec());
                a[j] -= h * s[0];
                b[j] -= h * s[1];
                c[j] -= h * s[2];
                regressor(model, data, &a, &b, &c, yg);
                &*yg * &self.theta_smooth
            };
            let d = (at(eps) - at(-eps)) / (2.0 * eps);
            out.column_mut(j).copy_from(&d);
        }
        out
    }

    /// Calls `f(k, Z_k, τ_k)` for every sample `k` in `range` with `Z_k = [Y_k | E_k]`, the
    /// effect columns of `variants` in order after the model's. Rows of joints slower than
    /// `min_speed` (rad/s) are zero in `Z_k` and `τ_k` (friction near zero speed is outside the
    /// model); [`slow`] tells which.
    pub fn for_each_row(
        &self,
        tr: &Trajectory,
        range: std::ops::Range<usize>,
        variants: &[Variant],
        min_speed: f64,
        f: &mut RowSink,
    ) {
        let model = self.model;
        let n = model.dof();
        let p0 = model.layout().len;
        let extra: usize = variants.iter().map(|v| v.kind.columns(n)).sum();
        let mut z = DMatrix::zeros(n, p0 + extra);
        let needs = |k: Kind| variants.iter().any(|v| v.kind == k);
        let gravity_models: Vec<Model> = if needs(Kind::Tilt) {
            self.perp
                .iter()
                .map(|u| model.clone().with_gravity(*u))
                .collect()
        } else {
            vec![]
        };
        let mut gdata: Vec<Data> = gravity_models.iter().map(Data::new).collect();
        let mut data = Data::new(model);
        let mut yg = DMatrix::zeros(n, p0);
        let mut y = DMatrix::zeros(n, p0);
        let mut tau_m = vec![0.0; n];
        let zeros = vec![0.0; n];
        let sign = crate::dynamics::sign;
        for k in range {
            let (q, qd, qdd, tau) = (
                tr.q_at(k),
                tr.qd_at(k),
                tr.qdd_at(k).expect("q̈ present"),
                tr.tau_at(k),
            );
            z.fill(0.0);
            regressor(model, &mut data, q, qd, qdd, &mut y);
            z.columns_mut(0, p0).copy_from(&y);
            let mut c = p0;
            for v in variants {
                match v.kind {
                    Kind::TorqueOffset => (0..n).for_each(|j| z[(j, c + j)] = 1.0),
                    Kind::TorqueGain => (0..n).for_each(|j| z[(j, c + j)] = self.pred[k * n + j]),
                    Kind::TimeDelay => (0..n).for_each(|j| z[(j, c)] = -self.pred_d[k * n + j]),
                    Kind::Spring => (0..n).for_each(|j| {
                        z[(j, c + j)] = q[j];
                        z[(j, c + n + j)] = 1.0;
                    }),
                    Kind::Stribeck => (0..n).for_each(|j| {
                        z[(j, c + j)] = (-(qd[j] / v.param).powi(2)).exp() * sign(qd[j])
                    }),
                    Kind::AsymmetricCoulomb => {
                        (0..n).for_each(|j| z[(j, c + j)] = sign(qd[j]).max(0.0))
                    }
                    Kind::LoadDependentFriction => {
                        // The predicted torque, not the measured one: a column carrying the
                        // measurement's own noise would "explain" it.
                        (0..n)
                            .for_each(|j| z[(j, c + j)] = self.pred[k * n + j].abs() * sign(qd[j]))
                    }
                    Kind::Cogging => (0..n).for_each(|j| {
                        let a = v.param * self.gear[j] * q[j];
                        z[(j, c + j)] = a.sin();
                        z[(j, c + n + j)] = a.cos();
                    }),
                    Kind::RotorInertia => (0..n).for_each(|j| z[(j, c + j)] = qdd[j]),
                    Kind::Payload => {
                        let last = 10 * (n - 1);
                        for i in 0..n {
                            for m in 0..10 {
                                z[(i, c + m)] = z[(i, last + m)];
                            }
                        }
                    }
                    Kind::Tilt => {
                        for (i, (gm, gd)) in gravity_models.iter().zip(gdata.iter_mut()).enumerate()
                        {
                            regressor(gm, gd, q, &zeros, &zeros, &mut yg);
                            let col = &yg * &self.theta0;
                            (0..n).for_each(|j| z[(j, c + i)] = col[j]);
                        }
                    }
                    Kind::Compliance => {
                        // −d/dκ_j ID(q − κ_j τ_j e_j, q̇ − κ_j τ̇_j e_j, q̈ − κ_j τ̈_j e_j).
                        let cols = self.encoder_shift_columns(
                            &self.defl,
                            k,
                            [q, qd, qdd],
                            &mut data,
                            &mut yg,
                        );
                        z.columns_mut(c, n).copy_from(&cols);
                    }
                    Kind::Backlash => {
                        // −d/db_j ID(q − b_j s_j, q̇ − b_j ṡ_j, q̈ − b_j s̈_j), s = ½ sign(τ)
                        // processed like the encoder: a motor-side encoder leads the link by
                        // half the dead zone in the direction of the torque.
                        let cols = self.encoder_shift_columns(
                            &self.slack,
                            k,
                            [q, qd, qdd],
                            &mut data,
                            &mut yg,
                        );
                        z.columns_mut(c, n).copy_from(&cols);
                    }
                }
                c += v.kind.columns(n);
            }
            tau_m.copy_from_slice(tau);
            for j in 0..n {
                if slow(qd[j], min_speed) {
                    z.row_mut(j).fill(0.0);
                    tau_m[j] = 0.0;
                }
            }
            f(k, &z, &tau_m);
        }
    }
}

/// The names of `kinds` joined by ", " (in Markdown code spans with `code`).
pub fn names(kinds: &[Kind], code: bool) -> String {
    kinds
        .iter()
        .map(|k| {
            if code {
                format!("`{}`", k.name())
            } else {
                k.name().to_string()
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod table_tests {
    use super::*;

    #[test]
    fn every_kind_has_one_row_with_a_unique_name() {
        for k in Kind::ALL {
            assert_eq!(
                KIND_TABLE.iter().filter(|s| s.kind == k).count(),
                1,
                "{k:?}"
            );
            assert!(
                !k.magnitude().0.is_empty() && !k.magnitude().1.is_empty(),
                "{k:?}"
            );
        }
        let mut names: Vec<&str> = Kind::ALL.iter().map(|k| k.name()).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), Kind::ALL.len());
        // The names are serde's: the JSON report spells kinds the same way.
        for k in Kind::ALL {
            assert_eq!(
                serde_json::to_string(&k).unwrap(),
                format!("\"{}\"", k.name())
            );
        }
        assert_eq!(Kind::Cogging.columns(3), 6);
        assert_eq!(Kind::Payload.columns(7), 10);
        assert_eq!(Kind::Stribeck.grid().len(), 10);
    }
}
