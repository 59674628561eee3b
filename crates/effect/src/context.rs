//! The effect columns' per-data state: the nominal prediction `Y θ̂₀` and its time derivatives,
//! the logged torque processed like the encoder signal (compliance), the motor's offset across
//! a backlash dead zone at each width of the grid, the tilt directions, over one data set
//! ([`Context`]); a sample as a kind's columns see it ([`Sample`]) and their workspaces
//! ([`Scratch`]). It knows no effect kind: the kinds (`super::kinds`) read it.

use crate::shifted::{Predicting, State};
use nalgebra::{DMatrix, DVector, Vector3};
use physid_core::dynamics::{regressor, Data};
use physid_core::model::Model;
use physid_core::trajectory::Trajectory;

/// The sample period (s) of `tr`, `None` when it has none to give (fewer than two samples, or
/// time stamps that do not advance): then nothing is differentiated or filtered, and the
/// columns made of processed signals (compliance, backlash) are zero, never computed at a
/// made-up rate. The diagnosis refuses such data up front (`stage::check_data`).
pub fn sample_period(tr: &Trajectory) -> Option<f64> {
    tr.sample_period().filter(|dt| dt.is_finite() && *dt > 0.0)
}

/// Where the torque is processed like the encoder angle: each run of the trajectory with the
/// torque it continues with beyond its ends ([`Trajectory::margins`]: the samples the data's
/// own processing saw, trimmed as filter settling or on the other side of a hold-out cut), so
/// that the processing matches the data's instead of starting afresh at those ends.
struct Layout {
    n: usize,
    dt: Option<f64>,
    /// The extended runs, over the extended samples.
    runs: Vec<std::ops::Range<usize>>,
    /// The trajectory's own samples of each run, over the extended samples.
    own: Vec<std::ops::Range<usize>>,
    /// The torque over the extended samples (sample-major).
    tau: Vec<f64>,
}

impl Layout {
    fn of(tr: &Trajectory) -> Self {
        let n = tr.dof();
        let rows = |v: &[f64]| v.len().checked_div(n).unwrap_or(0);
        let (mut runs, mut own, mut tau) = (vec![], vec![], vec![]);
        let mut at = 0;
        for (i, r) in tr.runs().into_iter().enumerate() {
            let m = tr.margin(i);
            let a = at + rows(&m.before);
            let b = a + r.len();
            tau.extend_from_slice(&m.before);
            tau.extend_from_slice(&tr.tau[r.start * n..r.end * n]);
            tau.extend_from_slice(&m.after);
            runs.push(at..b + rows(&m.after));
            own.push(a..b);
            at = b + rows(&m.after);
        }
        Layout {
            n,
            dt: sample_period(tr),
            runs,
            own,
            tau,
        }
    }

    /// The trajectory's own samples of a signal over the extended ones.
    fn inner(&self, v: Vec<f64>) -> Vec<f64> {
        let n = self.n;
        self.own
            .iter()
            .flat_map(|r| v[r.start * n..r.end * n].iter().copied())
            .collect()
    }
}

/// The backlash grid: the dead-zone widths (rad) whose motor offsets [`Context`] runs (the
/// kind table's backlash grid is this).
pub(crate) fn backlash_widths() -> Vec<f64> {
    (0..3).map(|i| 0.01 * 2f64.powi(i)).collect()
}

/// One sample as a kind's columns see it: index `k` of `n` joints, the processed state, and the
/// variant's grid value.
pub(crate) struct Sample<'s> {
    pub k: usize,
    pub n: usize,
    /// Joint angles (rad), velocities (rad/s), accelerations (rad/s²).
    pub q: &'s [f64],
    pub qd: &'s [f64],
    pub qdd: &'s [f64],
    /// Stribeck velocity or cogging harmonic (0 for kinds without a grid).
    pub param: f64,
}

/// Workspaces the columns reuse from sample to sample.
pub(crate) struct Scratch {
    pub data: Data,
    /// A regressor (`n × p₀`).
    pub yg: DMatrix<f64>,
    /// `n` zeros (a state at rest).
    pub zeros: Vec<f64>,
    /// The nominal model under the two tilted gravities, built on first use.
    pub tilted: Option<Vec<(Model, Data)>>,
    /// Workspaces of [`Context::predictors`] (θ̂₀, smooth), when it has them.
    pub predicting: Option<[Predicting; 2]>,
    /// Torques of one sample (N m): shifted by `+h`, by `−h`, unshifted.
    pub shifted: [Vec<f64>; 3],
}

impl Scratch {
    /// Workspaces for the columns of `ctx`.
    pub fn new(ctx: &Context) -> Self {
        let (n, p0) = (ctx.model.dof(), ctx.model.layout().len);
        Self {
            data: Data::new(ctx.model),
            yg: DMatrix::zeros(n, p0),
            zeros: vec![0.0; n],
            tilted: None,
            predicting: ctx
                .predictors
                .as_ref()
                .map(|m| [Predicting::new(&m[0]), Predicting::new(&m[1])]),
            shifted: std::array::from_fn(|_| vec![0.0; n]),
        }
    }
}

/// What the columns of one data set need besides the samples: the nominal prediction `Y θ̂₀`
/// and its time derivatives, computed once over the whole trajectory.
pub struct Context<'a> {
    pub(crate) model: &'a Model,
    pub(crate) theta0: DVector<f64>,
    /// `θ̂₀` without Coulomb friction (smooth in time), for the linearized kinematic effects.
    pub(crate) theta_smooth: DVector<f64>,
    /// The model with parameters `θ̂₀` and with `θ̂₀` smooth: inverse dynamics with friction on
    /// them is `Y θ̂₀` (and its smooth part) at the cost of one RNEA instead of a regressor and
    /// a product. `None` when a parameter is not finite (then the regressor is used).
    pub(crate) predictors: Option<Box<[Model; 2]>>,
    /// `Y_k θ̂₀`, sample-major.
    pub(crate) pred: Vec<f64>,
    /// The first derivative (N m/s, central differences) of the prediction without Coulomb
    /// friction.
    pub(crate) pred_d: Vec<f64>,
    /// The logged torque processed like the encoder signal (filtered; filtered derivative;
    /// filtered derivative of that), for the deflection of a compliant transmission.
    pub(crate) defl: [Vec<f64>; 3],
    /// The offset of a motor-side encoder across a backlash dead zone of unit width, processed
    /// like the encoder signal, per width of the backlash grid (`(0, ½ sign)` for the tangent
    /// first): see [`Context::slack`].
    pub(crate) slack: Vec<(f64, [Vec<f64>; 3])>,
    /// Two unit vectors perpendicular to gravity (the tilt directions).
    pub(crate) perp: [Vector3<f64>; 2],
    pub(crate) gear: Vec<f64>,
    /// Per joint, whether it has no backlash columns: no rotor, and its dead zone's side the
    /// torque noise's on most samples ([`side_is_noise`]).
    pub(crate) backlash_untested: Vec<bool>,
}

/// `x` (sample-major, `n` columns) processed like an encoder angle: `F(x)`, `F(D x)`,
/// `F(D F(D x))` with `F` the zero-phase 2nd-order Butterworth low-pass at `cutoff` and `D` the
/// central difference; unfiltered differences if the filter cannot be built. Each run of `tr`
/// on its own ([`Trajectory::runs`]): nothing is filtered across a seam.
fn processed_like_encoder(x: &[f64], at: &Layout, cutoff: f64) -> [Vec<f64>; 3] {
    let n = at.n;
    let mut out = [vec![0.0; x.len()], vec![0.0; x.len()], vec![0.0; x.len()]];
    let Some(dt) = at.dt else {
        return out;
    };
    for run in &at.runs {
        for j in 0..n {
            let col: Vec<f64> = run.clone().map(|k| x[k * n + j]).collect();
            for (o, v) in out.iter_mut().zip(process_column(&col, dt, cutoff)) {
                for (k, vk) in run.clone().zip(v) {
                    o[k * n + j] = vk;
                }
            }
        }
    }
    out
}

/// One signal processed like an encoder angle (see [`processed_like_encoder`]).
fn process_column(col: &[f64], dt: f64, cutoff: f64) -> [Vec<f64>; 3] {
    let fs = 1.0 / dt;
    let sos = physid_core::signal::butterworth_lowpass(2, cutoff.min(0.4 * fs), fs).ok();
    let filt = |v: &[f64]| sos.as_ref().map_or_else(|| v.to_vec(), |s| s.filtfilt(v));
    let diff = |v: &[f64]| physid_core::signal::differentiate(v, dt);
    let d1 = filt(&diff(col));
    let d2 = filt(&diff(&d1));
    [filt(col), d1, d2]
}

/// Samples on either side of its own that [`processed_without_own`] leaves out.
const OWN_LAGS: usize = 2;

/// The encoder processing's impulse response (angle, rate, acceleration) at lags
/// `−OWN_LAGS..=OWN_LAGS` (time-invariant away from the ends), for [`without_own`].
type OwnTaps = [[f64; 2 * OWN_LAGS + 1]; 3];

/// [`OwnTaps`] at sample period `dt` (s) and `cutoff` (Hz); zero without a period.
fn own_taps(dt: Option<f64>, cutoff: f64) -> OwnTaps {
    let Some(dt) = dt else {
        return [[0.0; 2 * OWN_LAGS + 1]; 3];
    };
    let centre = 2000;
    let mut impulse = vec![0.0; 2 * centre + 1];
    impulse[centre] = 1.0;
    let h = process_column(&impulse, dt, cutoff);
    std::array::from_fn(|c| std::array::from_fn(|i| h[c][centre - OWN_LAGS + i]))
}

/// `processed` (= [`processed_like_encoder`] of `x`) with each output sample made blind to
/// the input's own sample and its [`OWN_LAGS`] neighbours on either side (replaced by the
/// straight line across them). A column made of the logged torque is regressed against that
/// same torque: through the processing's centre tap it would carry the sample's own noise
/// (differentiated twice, the tap is large and negative), which fits the residual's noise (on
/// clean blind data compliance was then claimed in 6 of 16 cases). White noise is then
/// uncorrelated with the column. Only the joints marked `blind` are; every joint's columns are
/// zeroed over the filter's start-up.
fn without_own(
    mut out: [Vec<f64>; 3],
    x: &[f64],
    at: &Layout,
    (cutoff, taps): (f64, &OwnTaps),
    blind: &[bool],
) -> [Vec<f64>; 3] {
    let n = at.n;
    let Some(dt) = at.dt else {
        return out;
    };
    let w = OWN_LAGS;
    // The zero-phase filter's start-up transient at the ends of each run (not of the data's own
    // processing, which saw the whole run, but of this one): columns there are left at zero.
    let ends = ((3.0 / cutoff) / dt).ceil() as usize;
    for run in at.runs.iter().cloned() {
        let inner = |k: &usize| k - run.start >= ends && k + ends < run.end;
        for o in out.iter_mut() {
            for k in run.clone().filter(|k| !inner(k)) {
                o[k * n..(k + 1) * n].fill(0.0);
            }
        }
        if run.len() < 2 * w + 3 {
            continue;
        }
        for j in (0..n).filter(|&j| blind[j]) {
            let at = |k: usize| x[k * n + j];
            for k in (run.start + w + 1..run.end - w - 1).filter(inner) {
                let (a, b) = (at(k - w - 1), at(k + w + 1));
                for (t, i) in (k - w..=k + w).rev().enumerate() {
                    let frac = (i - (k - w - 1)) as f64 / (2 * w + 2) as f64;
                    let own = at(i) - (a + (b - a) * frac);
                    for (o, hc) in out.iter_mut().zip(taps) {
                        o[k * n + j] -= hc[t] * own;
                    }
                }
            }
        }
    }
    out
}

/// [`processed_like_encoder`] of `x` made blind to each sample's own on the joints marked
/// `blind` ([`without_own`]).
fn processed_without_own(
    x: &[f64],
    at: &Layout,
    filter: (f64, &OwnTaps),
    blind: &[bool],
) -> [Vec<f64>; 3] {
    without_own(
        processed_like_encoder(x, at, filter.0),
        x,
        at,
        filter,
        blind,
    )
}

/// Per joint, whether its motor sits behind a rotor (a motor inertia of its own).
fn behind_rotor(model: &Model) -> Vec<bool> {
    (super::dead_zone::motor_inertia(model).iter())
        .map(|&j| j > 0.0)
        .collect()
}

/// The torque (N m, sample-major) that carries each joint's motor across a backlash dead zone:
/// behind a rotor, the logged torque low-passed (`low_passed`), since the rotor's inertia
/// averages the sensor's chatter about zero and crosses once in tens of ms; without one, the
/// logged torque itself (`raw`), since a motor without inertia sits on the side of each
/// torque it is given, so a torque that chatters about zero (a feedback loop closed on the
/// motor-side encoder) moves the encoder across the whole gap each time, and the processed
/// offset is the filtered chatter rather than one step at the low-passed torque's zero.
fn dead_zone_drive(behind_rotor: &[bool], low_passed: &[f64], raw: &[f64]) -> Vec<f64> {
    let n = behind_rotor.len();
    (low_passed.iter().zip(raw).enumerate())
        .map(|(i, (&lp, &r))| if behind_rotor[i % n] { lp } else { r })
        .collect()
}

/// Per joint, whether the side of its backlash dead zone is the torque sensor's noise on most
/// samples: no rotor (`behind_rotor` false: behind one the motor averages the torque it is
/// given), and its low-passed torque (`low_passed`, over `at`'s extended samples) within one
/// noise deviation of zero on more than half of them. The deviation is the logged torque's
/// robust scale of second differences within each run (`MAD / 0.6745 / √6`, white noise's;
/// a motion sampled well adds little to them, and the sparse jumps of friction or chatter
/// nothing to a median). The columns of such a joint (a wheel in the air) would be the sign of
/// the residual's own noise, which they fit where cross-validation cannot see it: an unchanged
/// simulated Husky run was read as backlash on 4 of 5 seeds.
fn side_is_noise(at: &Layout, low_passed: &[f64], behind_rotor: &[bool]) -> Vec<bool> {
    let n = at.n;
    (0..n)
        .map(|j| {
            if behind_rotor[j] {
                return false;
            }
            let x = |k: usize| at.tau[k * n + j];
            let second: Vec<f64> = (at.runs.iter())
                .flat_map(|r| {
                    (r.start + 1..r.end.saturating_sub(1)).map(|k| x(k - 1) - 2.0 * x(k) + x(k + 1))
                })
                .collect();
            if second.is_empty() {
                return false;
            }
            let centre = physid_core::linalg::median(&second);
            let spread: Vec<f64> = second.iter().map(|d| (d - centre).abs()).collect();
            let sd = physid_core::linalg::median(&spread) / 0.6745 / 6f64.sqrt();
            let samples = low_passed.len() / n;
            let near_zero = (0..samples)
                .filter(|&k| low_passed[k * n + j].abs() < sd)
                .count();
            2 * near_zero > samples
        })
        .collect()
}

/// `columns` (sample-major, `n` per sample) with the joints marked `zero` set to zero.
fn zeroed(mut columns: [Vec<f64>; 3], n: usize, zero: &[bool]) -> [Vec<f64>; 3] {
    for c in columns.iter_mut() {
        for (i, v) in c.iter_mut().enumerate() {
            if zero[i % n] {
                *v = 0.0;
            }
        }
    }
    columns
}

/// The motor's offset in a backlash dead zone of `width` (rad) driven by the torque `tau`
/// (sample-major), divided by the width: `effect::DeadZone` with the model's rotors.
fn dead_zone_offsets(model: &Model, tau: &[f64], at: &Layout, width: f64) -> Vec<f64> {
    let n = at.n;
    let Some(dt) = at.dt else {
        return vec![0.0; tau.len()];
    };
    let mut out = Vec::with_capacity(tau.len());
    for run in at.runs.iter().cloned() {
        // Each run starts afresh, the motor against the side its first torque pushes it to.
        let mut zone = super::dead_zone::DeadZone::of_widths(model, vec![width; n]);
        let run_tau = &tau[run.start * n..run.end * n];
        out.extend(
            run_tau
                .chunks(n)
                .flat_map(|t| zone.step(t, dt))
                .map(|s| s / width),
        );
    }
    out
}

/// The time derivative of `x` (sample-major, `n` columns) over `tr`'s time stamps: central
/// differences, first-order one-sided at each run's ends (never across a seam: a jump between
/// runs joined end to end is not a rate); zero in a run of one sample.
fn derivative(x: &[f64], tr: &Trajectory, n: usize) -> Vec<f64> {
    let t = &tr.t;
    let mut out = vec![0.0; x.len()];
    for run in tr.runs().into_iter().filter(|r| r.len() >= 2) {
        for k in run.clone() {
            let (a, b) = (k.saturating_sub(1).max(run.start), (k + 1).min(run.end - 1));
            let dt = t[b] - t[a];
            for j in 0..n {
                out[k * n + j] = (x[b * n + j] - x[a * n + j]) / dt;
            }
        }
    }
    out
}

/// `model` carrying each of two parameter vectors (for inverse dynamics that is `Y θ`); `None`
/// when one of them is not a model's (a parameter not finite).
fn predictors(model: &Model, a: &DVector<f64>, b: &DVector<f64>) -> Option<Box<[Model; 2]>> {
    let (a, b) = (
        model.with_parameters(a).ok()?,
        model.with_parameters(b).ok()?,
    );
    Some(Box::new([a, b]))
}

/// The torque `Y θ` two parameter vectors predict at every sample of `tr` (sample-major).
fn predictions(
    model: &Model,
    tr: &Trajectory,
    (theta_a, theta_b): (&DVector<f64>, &DVector<f64>),
) -> (Vec<f64>, Vec<f64>) {
    let n = model.dof();
    let mut a = Vec::with_capacity(tr.len() * n);
    let mut b = Vec::with_capacity(tr.len() * n);
    physid_core::dynamics::for_each_regressor(model, tr, 0..tr.len(), &mut |_, y| {
        a.extend((y * theta_a).iter());
        b.extend((y * theta_b).iter());
    });
    (a, b)
}

/// What a [`Context`] takes from its nominal parameters: `θ̂₀`, its smooth part, the models
/// carrying them, and the prediction with its derivative over the trajectory.
struct Predicted {
    theta0: DVector<f64>,
    theta_smooth: DVector<f64>,
    predictors: Option<Box<[Model; 2]>>,
    pred: Vec<f64>,
    pred_d: Vec<f64>,
}

impl Predicted {
    /// The predictions of `model` with parameters `theta0` over `tr`.
    fn of(model: &Model, theta0: &DVector<f64>, tr: &Trajectory) -> Self {
        let (n, l) = (model.dof(), model.layout());
        let theta0 = theta0.rows(0, l.len).into_owned();
        let mut theta_smooth = theta0.clone();
        for j in 0..n {
            theta_smooth[l.coulomb_col + j] = 0.0;
        }
        let (pred, smooth) = predictions(model, tr, (&theta0, &theta_smooth));
        // Without the Coulomb jumps: a delayed jump only matters within the masked slow rows,
        // and differencing it would put spikes into every fitted row next to a reversal.
        let pred_d = derivative(&smooth, tr, n);
        let predictors = predictors(model, &theta0, &theta_smooth);
        Self {
            theta0,
            theta_smooth,
            predictors,
            pred,
            pred_d,
        }
    }
}

impl<'a> Context<'a> {
    /// The context of trajectory `tr` (with q̈) for nominal parameters `theta0` (the model's
    /// layout, no extra columns).
    ///
    /// `cutoff` (Hz) is the low-pass of the data's processing (zero-phase 2nd-order
    /// Butterworth of q and of each derivative, as `physid simulate` and `load_trajectory` do),
    /// applied to the predicted torque for the compliance columns; capped at 0.4 × the rate.
    pub fn new(model: &'a Model, theta0: &DVector<f64>, tr: &Trajectory, cutoff: f64) -> Self {
        // The deflection follows the torque actually delivered, jumps of friction at the
        // reversals included: the logged torque, processed like the encoder. Its noise,
        // differentiated twice through the 20 Hz filter, adds ~0.05 N m on the blind scenario;
        // the prediction's friction jumps fall a few samples off the delivered torque's and its
        // column lost the attribution to delay, cogging and spring.
        let at = Layout::of(tr);
        let taps = own_taps(at.dt, cutoff);
        let inner = |v: [Vec<f64>; 3]| v.map(|s| at.inner(s));
        let logged = processed_like_encoder(&at.tau, &at, cutoff);
        // The side of the dead zone follows the torque actually delivered
        // ([`dead_zone_drive`]), which carries the motor across the gap as the simulator's
        // dead zone does (`effect::DeadZone`), at each width of the grid; the tangent takes
        // half its sign (an instant crossing).
        let behind_rotor = behind_rotor(model);
        let drive = dead_zone_drive(&behind_rotor, &logged[0], &at.tau);
        let half_sign: Vec<f64> = drive
            .iter()
            .map(|t| 0.5 * physid_core::dynamics::sign(*t))
            .collect();
        // Blind to each sample's own torque behind a rotor, whose offset follows the low-passed
        // torque; without one the offset at a sample is the side of that sample's own torque
        // (the effect itself), and leaving it out kept a fifth of the effect (generalization
        // benchmark, KUKA seed 1, case 9: backlash −9 % of the CV mean square, −93 % with it).
        let filter = (cutoff, &taps);
        // A joint whose dead zone's side is its torque noise's has no backlash columns.
        let noise_sided = side_is_noise(&at, &logged[0], &behind_rotor);
        let processed = |x: &[f64]| {
            let columns = inner(processed_without_own(x, &at, filter, &behind_rotor));
            zeroed(columns, at.n, &noise_sided)
        };
        let mut slack = vec![(0.0, processed(&half_sign))];
        for width in backlash_widths() {
            slack.push((
                width,
                processed(&dead_zone_offsets(model, &drive, &at, width)),
            ));
        }
        let defl = inner(without_own(logged, &at.tau, &at, filter, &vec![true; at.n]));
        let gear = model
            .bodies()
            .iter()
            .map(|b| b.rotor.as_ref().map_or(1.0, |r| r.gear_ratio))
            .collect();
        let p = Predicted::of(model, theta0, tr);
        Self {
            model,
            theta0: p.theta0,
            theta_smooth: p.theta_smooth,
            predictors: p.predictors,
            pred: p.pred,
            pred_d: p.pred_d,
            defl,
            slack,
            perp: perpendiculars(&model.gravity()),
            gear,
            backlash_untested: noise_sided,
        }
    }

    /// The context of the same trajectory `tr` about other nominal parameters `theta0`: the
    /// predictions recomputed, the logged torque's processing (deflection, backlash offsets)
    /// kept, as it does not depend on the parameters.
    pub fn about(&self, theta0: &DVector<f64>, tr: &Trajectory) -> Self {
        let p = Predicted::of(self.model, theta0, tr);
        Self {
            model: self.model,
            theta0: p.theta0,
            theta_smooth: p.theta_smooth,
            predictors: p.predictors,
            pred: p.pred,
            pred_d: p.pred_d,
            defl: self.defl.clone(),
            slack: self.slack.clone(),
            perp: self.perp,
            gear: self.gear.clone(),
            backlash_untested: self.backlash_untested.clone(),
        }
    }

    /// The model.
    pub fn model(&self) -> &'a Model {
        self.model
    }

    /// Per joint, whether its backlash is not tested on this data: a joint without a rotor
    /// whose torque is within its noise of zero on most samples, so the log cannot tell its
    /// dead zone's side from that noise (its backlash columns are zero).
    pub fn backlash_untested(&self) -> &[bool] {
        &self.backlash_untested
    }

    /// The processed unit-width dead-zone offset for backlash at grid width `width` (the
    /// nearest computed; 0: half the torque's sign, for the tangent).
    pub(crate) fn slack(&self, width: f64) -> &[Vec<f64>; 3] {
        let nearest = self
            .slack
            .iter()
            .min_by(|a, b| (a.0 - width).abs().total_cmp(&(b.0 - width).abs()))
            .expect("the tangent's is always there");
        &nearest.1
    }

    /// `Y θ` (N m) at sample `s` with joint `j`'s angle, velocity and acceleration shifted by
    /// `−by · shift_j`, for `θ` = θ̂₀ (`which` 0) or its smooth part (1), by the regressor: where
    /// [`Context::predictors`] are missing (a non-finite θ̂₀).
    fn shifted_by_regressor(
        &self,
        (which, j, by): (usize, usize, f64),
        shift: &[Vec<f64>; 3],
        s: &Sample,
        w: &mut Scratch,
    ) -> DVector<f64> {
        let at = s.k * s.n + j;
        let (mut q, mut qd, mut qdd) = (s.q.to_vec(), s.qd.to_vec(), s.qdd.to_vec());
        q[j] -= by * shift[0][at];
        qd[j] -= by * shift[1][at];
        qdd[j] -= by * shift[2][at];
        let theta = [&self.theta0, &self.theta_smooth][which];
        regressor(self.model, &mut w.data, &q, &qd, &qdd, &mut w.yg);
        &w.yg * theta
    }

    /// The columns `−∂ID/∂ε_j` of inverse dynamics with joint `j`'s encoder signals shifted by
    /// `ε_j · shift_j` (angle, velocity, acceleration of sample `s`), one per joint: how a
    /// motor-side encoder offset (compliance, backlash) enters the prediction. At `secant = 0`
    /// the tangent of the smooth prediction (no Coulomb friction); at `secant > 0` the secant
    /// `(ID(x − secant · shift_j e_j) − ID(x)) / secant` of the whole prediction, Coulomb
    /// friction included: where the shift reverses the velocity (a link at rest while the
    /// encoder moves with the torque) the friction term changes sign, which no tangent sees.
    pub(crate) fn encoder_shift_columns(
        &self,
        shift: &[Vec<f64>; 3],
        secant: f64,
        s: &Sample,
        w: &mut Scratch,
    ) -> DMatrix<f64> {
        let n = s.n;
        let (h, which) = if secant > 0.0 { (secant, 0) } else { (1e-7, 1) };
        let mut out = DMatrix::zeros(n, n);
        let (Some(models), Some(predicting)) = (&self.predictors, &mut w.predicting) else {
            let id =
                |j, by, w: &mut Scratch| self.shifted_by_regressor((which, j, by), shift, s, w);
            let base = id(0, 0.0, w);
            for j in (0..n).rev() {
                let d = if secant > 0.0 {
                    (id(j, h, w) - &base) / h
                } else {
                    (id(j, h, w) - id(j, -h, w)) / (2.0 * h)
                };
                out.column_mut(j).copy_from(&d);
            }
            return out;
        };
        let (model, p) = (&models[which], &mut predicting[which]);
        let [plus, minus, base] = &mut w.shifted;
        // The unshifted state first (every body's motion), then the joints from the last to
        // the first: each shifted pass leaves the bodies before its joint as they were.
        let s = &State {
            k: s.k,
            q: s.q,
            qd: s.qd,
            qdd: s.qdd,
        };
        base.copy_from_slice(p.unshifted(model, s));
        for j in (0..n).rev() {
            p.shifted(model, (j, h), shift, s, plus);
            if secant > 0.0 {
                for i in 0..n {
                    out[(i, j)] = (plus[i] - base[i]) / h;
                }
            } else {
                p.shifted(model, (j, -h), shift, s, minus);
                for i in 0..n {
                    out[(i, j)] = (plus[i] - minus[i]) / (2.0 * h);
                }
            }
        }
        out
    }
}

/// Two unit vectors perpendicular to gravity `g` and to each other (the directions a small
/// tilt moves it in); about −z when `g` is zero.
fn perpendiculars(g: &Vector3<f64>) -> [Vector3<f64>; 2] {
    let g = g.try_normalize(1e-12).unwrap_or(-Vector3::z());
    let a = if g.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let u1 = (a - g * g.dot(&a)).normalize();
    [u1, g.cross(&u1)]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one_joint(x: &[f64]) -> Trajectory {
        let mut tr = Trajectory::new(vec!["j".into()], true);
        for (k, v) in x.iter().enumerate() {
            tr.push(k as f64 * 1e-3, &[0.0], &[0.0], Some(&[0.0]), &[*v]);
        }
        tr
    }

    #[test]
    fn nothing_is_differentiated_or_filtered_across_a_seam() {
        // Two runs joined end to end, each a constant torque (0 and 10 N m): within each run
        // the rate is zero and the low-passed signal the constant, up to the seam itself.
        let (a, b) = (one_joint(&[0.0; 400]), one_joint(&[10.0; 400]));
        let joined = Trajectory::concatenate(vec![a, b]).unwrap();
        let d = derivative(&joined.tau, &joined, 1);
        assert!(
            d.iter().all(|v| *v == 0.0),
            "largest rate {:?}",
            d.iter().cloned().fold(0.0, f64::max)
        );
        let [f, f1, f2] = processed_like_encoder(&joined.tau, &Layout::of(&joined), 20.0);
        for k in 0..800 {
            let want = if k < 400 { 0.0 } else { 10.0 };
            assert!((f[k] - want).abs() < 1e-9, "sample {k}: {}", f[k]);
            assert!(
                f1[k].abs() < 1e-6 && f2[k].abs() < 1e-3,
                "sample {k}: {} {}",
                f1[k],
                f2[k]
            );
        }
        // Without the seam (one run) the step rings through the filter on both sides.
        let mut one = joined.clone();
        one.starts.clear();
        let [f, _, _] = processed_like_encoder(&one.tau, &Layout::of(&one), 20.0);
        assert!((f[399] - 0.0).abs() > 0.1 && (f[400] - 10.0).abs() > 0.1);
        assert!(derivative(&one.tau, &one, 1)[400] > 1000.0);
    }

    #[test]
    fn processing_without_own_samples_is_blind_to_them_and_keeps_smooth_signals() {
        let m = 3000;
        let smooth: Vec<f64> = (0..m)
            .map(|k| (2.0 * std::f64::consts::PI * 1.3 * k as f64 * 1e-3).sin())
            .collect();
        let tr = one_joint(&smooth);
        let full = processed_like_encoder(&smooth, &Layout::of(&tr), 20.0);
        let taps = own_taps(Some(1e-3), 20.0);
        let own = processed_without_own(&smooth, &Layout::of(&tr), (20.0, &taps), &[true]);
        // A 1.3 Hz sine is nearly a straight line over seven samples: the same processing
        // (angle, rate, acceleration: amplitudes 1, 8.2, 67) where the ends are not zeroed, but
        // for the acceleration, whose large centre taps see the line's missing curvature: 0.3 %
        // of it (the bias the columns carry).
        for c in 0..3 {
            let scale = (2.0 * std::f64::consts::PI * 1.3f64).powi(c as i32);
            let tol = [1e-4, 1e-4, 5e-3][c];
            for k in 200..m - 200 {
                assert!(
                    (full[c][k] - own[c][k]).abs() < tol * scale,
                    "channel {c} sample {k}: {} vs {}",
                    full[c][k],
                    own[c][k]
                );
            }
            assert_eq!(own[c][10], 0.0, "the start-up transient is zeroed");
        }
        // A spike at sample k changes every channel's output elsewhere but not at k.
        let k = 1500;
        let mut spiked = smooth.clone();
        spiked[k] += 1.0;
        let own_spiked = processed_without_own(
            &spiked,
            &Layout::of(&one_joint(&spiked)),
            (20.0, &taps),
            &[true],
        );
        let full_spiked = processed_like_encoder(&spiked, &Layout::of(&one_joint(&spiked)), 20.0);
        for c in 0..3 {
            assert!((own_spiked[c][k] - own[c][k]).abs() < 1e-9 * (1.0 + own[c][k].abs()));
            // (The rate's response at its own sample is zero: an odd impulse response.)
            if c != 1 {
                assert!((full_spiked[c][k] - full[c][k]).abs() > 1e-3, "channel {c}");
            }
            assert!(
                (own_spiked[c][k + 5] - own[c][k + 5]).abs() > 1e-6,
                "channel {c}"
            );
        }
    }

    #[test]
    fn a_motor_without_a_rotor_crosses_the_gap_with_each_torque_it_is_given() {
        // A torque that chatters about zero (a feedback loop on the motor-side encoder): behind
        // a rotor the dead zone is driven by the low-passed torque (one crossing), without one
        // by the torque as logged, so the unit-width offset flips with every sign change.
        let leg = physid_core::model::cheetah3::leg();
        let bare = leg.without_rotors();
        let n = leg.dof();
        let raw: Vec<f64> = (0..600 * n)
            .map(|i| if (i / n) % 2 == 0 { 1.3 } else { -0.7 })
            .collect();
        let low_passed = vec![0.1; raw.len()];
        assert_eq!(
            dead_zone_drive(&behind_rotor(&leg), &low_passed, &raw),
            low_passed
        );
        assert_eq!(
            dead_zone_drive(&behind_rotor(&bare), &low_passed, &raw),
            raw
        );
        let mut tr = Trajectory::new(bare.joint_names(), true);
        for k in 0..600 {
            let tau = &raw[k * n..(k + 1) * n];
            tr.push(k as f64 * 1e-3, &[0.0; 3], &[0.0; 3], Some(&[0.0; 3]), tau);
        }
        let at = Layout::of(&tr);
        let offsets = dead_zone_offsets(&bare, &raw, &at, 0.02);
        // (The offset of a period is the one its start had: the previous torque's side.)
        let flips = offsets.chunks(n).map(|s| s[0]).collect::<Vec<_>>();
        assert!(flips[1..]
            .windows(2)
            .all(|w| w[0] == -w[1] && w[0].abs() == 0.5));
        // Filtered at 20 Hz the 500 Hz chatter averages out: the processed offset is zero (each
        // sample's own side kept; leaving it out had left 0.13), where the low-passed torque
        // (0.3 N m throughout) would hold the motor at +½.
        let taps = own_taps(at.dt, 20.0);
        let angle = &processed_without_own(&offsets, &at, (20.0, &taps), &behind_rotor(&bare))[0];
        let most = angle
            .chunks(n)
            .skip(200)
            .take(200)
            .map(|s| s[0].abs())
            .fold(0.0, f64::max);
        assert!(most < 1e-6, "{most}");
        // A torque that is its chatter on every sample (the low-passed 0.3 N m under a 2.4 N m
        // scale of second differences) is one whose side the log cannot tell from its noise:
        // the context gives it no backlash columns.
        let ctx = Context::new(&bare, &bare.parameters(), &tr, 20.0);
        assert!(ctx
            .slack
            .iter()
            .all(|(_, s)| s.iter().flatten().all(|v| *v == 0.0)));
    }

    /// `m` draws of zero-mean normal noise of deviation `sd`, from `seed`.
    fn normal_noise(m: usize, sd: f64, seed: u64) -> Vec<f64> {
        use rand::SeedableRng;
        use rand_distr::Distribution;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let normal = rand_distr::Normal::new(0.0, sd).unwrap();
        (0..m).map(|_| normal.sample(&mut rng)).collect()
    }

    /// The correlation of `a` and `b` over `inside`.
    fn correlation(a: &[f64], b: &[f64], inside: std::ops::Range<usize>) -> f64 {
        let (x, y) = (&a[inside.clone()], &b[inside]);
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let (mx, my) = (mean(x), mean(y));
        let cov: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
        let var = |v: &[f64], c: f64| v.iter().map(|a| (a - c).powi(2)).sum::<f64>();
        cov / (var(x, mx) * var(y, my)).sqrt()
    }

    #[test]
    fn a_joint_whose_torque_is_its_noise_has_no_backlash_columns() {
        // Three joints without rotors under 0.3 N m of sensor noise, 1 kHz: a wheel in the air
        // (0.05 N m of motion), an arm joint (5 N m), and a joint of 2 N m near its noise only
        // about its 40 reversals. The wheel's dead-zone side is its noise's: the processed half
        // sign of its torque fits that noise (correlation −0.18, against ±0.016 by chance), the
        // residual's own noise, which cross-validation cannot see. It gets no columns; the
        // others keep theirs, and so does the wheel behind a rotor, whose motor averages the
        // torque it is given.
        let (m, dt) = (4000, 1e-3);
        let noise: Vec<Vec<f64>> = (0..3).map(|j| normal_noise(m, 0.3, 7 + j)).collect();
        let amplitude = [0.05, 5.0, 2.0];
        let bare = physid_core::model::cheetah3::leg().without_rotors();
        let mut tr = Trajectory::new(bare.joint_names(), true);
        for k in 0..m {
            let wave = (k as f64 * dt * 5.0 * std::f64::consts::TAU).sin();
            let tau: Vec<f64> = (amplitude.iter().zip(&noise))
                .map(|(a, e)| a * wave + e[k])
                .collect();
            tr.push(k as f64 * dt, &[0.0; 3], &[0.0; 3], Some(&[0.0; 3]), &tau);
        }
        let at = Layout::of(&tr);
        let low_passed = processed_like_encoder(&at.tau, &at, 20.0);
        assert_eq!(
            side_is_noise(&at, &low_passed[0], &[false; 3]),
            [true, false, false]
        );
        let wheel: Vec<f64> = (0..m).map(|k| 0.5 * tr.tau[k * 3].signum()).collect();
        let processed = processed_like_encoder(&wheel, &Layout::of(&one_joint(&wheel)), 20.0);
        let r = correlation(&processed[2], &noise[0], 200..m - 200);
        assert!(r < -0.1, "{r}");
        let ctx = Context::new(&bare, &bare.parameters(), &tr, 20.0);
        for (width, s) in &ctx.slack {
            for (c, channel) in s.iter().enumerate() {
                let largest =
                    |j: usize| (0..m).map(|k| channel[k * 3 + j].abs()).fold(0.0, f64::max);
                assert_eq!(largest(0), 0.0, "width {width}, channel {c}");
                assert!(
                    largest(1) > 0.0 && largest(2) > 0.0,
                    "width {width}, channel {c}"
                );
            }
        }
        let leg = physid_core::model::cheetah3::leg();
        let ctx = Context::new(&leg, &leg.parameters(), &tr, 20.0);
        let wheel_angle = ctx.slack(0.02)[0].iter().step_by(3);
        assert!(wheel_angle.fold(0.0, |a: f64, v| a.max(v.abs())) > 0.0);
    }

    #[test]
    fn a_motor_without_a_rotor_keeps_each_sample_s_own_side_in_the_column() {
        // One torque sample of the other sign (k): without a rotor the motor sits on that
        // sample's side for one period (the offset of period k + 1), and the processed offset
        // there moves by the processing's own centre tap times the unit width's flip. Behind a
        // rotor the drive is the low-passed torque, which one sample does not turn over.
        let leg = physid_core::model::cheetah3::leg();
        let bare = leg.without_rotors();
        let n = leg.dof();
        let (m, k) = (800, 400);
        let run = |flip: bool, model: &Model| {
            let mut tr = Trajectory::new(model.joint_names(), true);
            for i in 0..m {
                let tau = if flip && i == k { -1.0 } else { 1.0 };
                tr.push(
                    i as f64 * 1e-3,
                    &[0.0; 3],
                    &[0.0; 3],
                    Some(&[0.0; 3]),
                    &[tau; 3],
                );
            }
            Context::new(model, &model.parameters(), &tr, 20.0)
                .slack(0.02)
                .clone()
        };
        let taps = own_taps(Some(1e-3), 20.0);
        let (steady, flipped) = (run(false, &bare), run(true, &bare));
        for c in [0, 2] {
            let moved = flipped[c][(k + 1) * n] - steady[c][(k + 1) * n];
            let want = -taps[c][OWN_LAGS];
            assert!(
                (moved - want).abs() < 1e-9 * want.abs(),
                "channel {c}: {moved} vs {want}"
            );
        }
        let (steady, flipped) = (run(false, &leg), run(true, &leg));
        let moved = (flipped[2][(k + 1) * n] - steady[2][(k + 1) * n]).abs();
        assert!(moved < 1e-3 * taps[2][OWN_LAGS].abs(), "{moved}");
    }

    #[test]
    fn the_shifted_predictions_by_inverse_dynamics_equal_the_regressor_times_the_parameters() {
        // The encoder-shift columns come from inverse dynamics on a model carrying θ̂₀, with only
        // the shifted joint's transform recomputed; without that model (a non-finite θ̂₀ would
        // have none) they come from Y θ̂₀. Both, on the leg with its rotors (full model: the
        // rotor spins with the shifted joint) and without, tangent and secant.
        for model in [
            physid_core::model::cheetah3::leg(),
            physid_core::model::cheetah3::leg().without_rotors(),
        ] {
            let tr = moving_leg(&model, 400);
            let theta0 = model.parameters() * 1.1;
            let fast = Context::new(&model, &theta0, &tr, 20.0);
            assert!(fast.predictors.is_some());
            let mut slow = Context::new(&model, &theta0, &tr, 20.0);
            slow.predictors = None;
            let (mut wf, mut ws) = (Scratch::new(&fast), Scratch::new(&slow));
            let mut largest = 0.0_f64;
            for k in [3, 150, 222, 377] {
                let sample = sample_at(&tr, k);
                for secant in [0.0, 0.02] {
                    let a = fast.encoder_shift_columns(&fast.defl, secant, &sample, &mut wf);
                    let b = slow.encoder_shift_columns(&slow.defl, secant, &sample, &mut ws);
                    let scale = b.amax().max(1.0);
                    // Central differences at h = 1e-7 carry round-off of ~1e-9 relative.
                    assert!((&a - &b).amax() < 1e-6 * scale, "k {k}, secant {secant}");
                    largest = largest.max(b.amax());
                }
            }
            assert!(largest > 1e-3, "the columns are not all zero: {largest:e}");
        }
    }

    #[test]
    fn encoder_shift_columns_are_the_same_bit_for_bit_whatever_ran_before_on_the_workspace() {
        // A sample's unshifted pass is kept for its other variants (and restored between
        // them): every variant's columns equal those of a fresh workspace, bit for bit, in any
        // order, with rotors (full model) and without.
        for model in [
            physid_core::model::cheetah3::leg(),
            physid_core::model::cheetah3::leg().without_rotors(),
        ] {
            let tr = moving_leg(&model, 600);
            let ctx = Context::new(&model, &(model.parameters() * 1.1), &tr, 20.0);
            let mut shared = Scratch::new(&ctx);
            let mut distinct = 0;
            for k in [200, 201, 300, 300, 400] {
                let sample = sample_at(&tr, k);
                let mut last: Option<DMatrix<f64>> = None;
                for (shift, secant) in [
                    (&ctx.defl, 0.02),
                    (ctx.slack(0.01), 0.01),
                    (&ctx.defl, 0.0),
                    (&ctx.defl, 0.004),
                    (&ctx.defl, 0.02),
                ] {
                    let again = ctx.encoder_shift_columns(shift, secant, &sample, &mut shared);
                    let fresh =
                        ctx.encoder_shift_columns(shift, secant, &sample, &mut Scratch::new(&ctx));
                    assert!(
                        again
                            .iter()
                            .zip(fresh.iter())
                            .all(|(a, b)| a.to_bits() == b.to_bits()),
                        "k {k}, secant {secant}"
                    );
                    distinct += usize::from(last.as_ref() != Some(&again));
                    last = Some(again);
                }
            }
            // Every variant differs from the one before it: the comparison sees a stale state.
            assert_eq!(distinct, 25);
        }
    }

    /// Sample `k` of `tr` (which carries q̈), for a kind without a grid value.
    fn sample_at(tr: &Trajectory, k: usize) -> Sample<'_> {
        Sample {
            k,
            n: tr.dof(),
            q: tr.q_at(k),
            qd: tr.qd_at(k),
            qdd: tr.qdd_at(k).expect("q̈ present"),
            param: 0.0,
        }
    }

    /// The leg moving smoothly for `m` samples at 1 kHz, its torque smooth with a fast ripple.
    fn moving_leg(model: &Model, m: usize) -> Trajectory {
        let n = model.dof();
        let mut tr = Trajectory::new(model.joint_names(), true);
        let w = 2.0 * std::f64::consts::PI * 0.7;
        for k in 0..m {
            let t = k as f64 * 1e-3;
            let phase = |j: usize| w * t + j as f64;
            let q: Vec<f64> = (0..n).map(|j| 0.3 * phase(j).sin()).collect();
            let qd: Vec<f64> = (0..n).map(|j| 0.3 * w * phase(j).cos()).collect();
            let qdd: Vec<f64> = (0..n).map(|j| -0.3 * w * w * phase(j).sin()).collect();
            let tau: Vec<f64> = (0..n)
                .map(|j| 5.0 * (1.1 * phase(j)).sin() + 0.2 * (60.0 * t * (j + 1) as f64).sin())
                .collect();
            tr.push(t, &q, &qd, Some(&qdd), &tau);
        }
        tr
    }

    #[test]
    fn a_held_out_part_is_processed_as_the_whole_run_was() {
        let model = physid_core::model::cheetah3::leg();
        let n = model.dof();
        let theta0 = model.parameters();
        let tr = moving_leg(&model, 3000);
        let whole = Context::new(&model, &theta0, &tr, 20.0);
        let (train, val) = tr.holdout_split(0.3);
        let largest = |a: &[Vec<f64>; 3], b: &[Vec<f64>; 3], offset: usize| -> f64 {
            (0..3)
                .flat_map(|c| a[c].iter().enumerate().map(move |(i, x)| (c, i, x)))
                .map(|(c, i, x)| (x - b[c][offset * n + i]).abs())
                .fold(0.0, f64::max)
        };
        for (part, offset) in [(&train, 0), (&val, train.len())] {
            let ctx = Context::new(&model, &theta0, part, 20.0);
            assert!(largest(&ctx.defl, &whole.defl, offset) < 1e-9);
            for (s, w) in ctx.slack.iter().zip(&whole.slack) {
                assert!(largest(&s.1, &w.1, offset) < 1e-9, "width {}", s.0);
            }
        }
        // Cut without its margins, the validation part starts afresh: its first samples are
        // left at zero and the rest near the cut filtered from an edge.
        let mut bare = val.clone();
        bare.margins = Default::default();
        let ctx = Context::new(&model, &theta0, &bare, 20.0);
        assert!(largest(&ctx.defl, &whole.defl, train.len()) > 1.0);
    }
}
