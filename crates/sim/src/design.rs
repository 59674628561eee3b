//! **Excitation design**: a finite Fourier series per joint (Swevers et al.), optimized over its
//! coefficients for the information it carries about the robot's identifiable parameter
//! combinations, within the joints' position, velocity, acceleration and torque limits.
//!
//! - The trajectory `q_j(t) = o_j + Σ_l a_jl sin(ω_l t) + b_jl (cos(ω_l t) − 1)`, `ω_l = 2π l f₀`,
//!   is periodic with period `1/f₀`; with a ramp it fades in from rest at `o` and out to rest
//!   at the end of the run ([`super::excitation::RestWindow`]), so a robot can start and stop
//!   it. The information is that of the periodic part; the limits hold over the ramps too.
//! - **Identifiable combinations.** The regressor `Y(q, q̇, q̈)` (rigid bodies with rotors, then
//!   friction) is stacked over random states inside the limits; its columns are scaled to unit
//!   norm (`D`), and the eigenvectors `V` of `D⁻¹ YᵀY D⁻¹` above `1e-9` of the largest
//!   eigenvalue span what any motion can identify (the rest is structurally unidentifiable).
//! - **Information** of a trajectory: `F = Vᵀ D⁻¹ (Σ_k Y_kᵀ Y_k / K) D⁻¹ V` over `K` samples of one
//!   period. Objectives (all maximized): D-optimal `log det F / r`; E-optimal `log λ_min(F)`;
//!   condition `−log κ(F)^{1/2}` (the regressor's condition number, as most peers optimize).
//! - **Limits.** A start is scaled into the limits: each joint's series by the largest factor
//!   that keeps its position, speed, acceleration and jerk inside the limits (these scale
//!   linearly), then all joints together, by bisection, until the inverse dynamics' torque
//!   (with friction) stays inside the effort limits.
//! - **Optimizer.** Sequential quadratic programming in a trust region (`design/sqp.rs`) from `starts`
//!   random starts (seeded; run in parallel, the best kept, ties to the first start), each for
//!   at most `iterations` steps. Deterministic for a seed whatever the thread count.

mod sqp;

pub use super::excitation::FourierSeries;
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use physid_core::dynamics::{regressor, rnea_with_friction, Data};
use physid_core::model::Model;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Acceleration limit (rad/s²) of a joint whose description gives none: below common arms'
/// (the Panda's smallest is 7.5, a UR arm's default move 1.4–3).
pub const SAFE_ACCELERATION: f64 = 3.0;

/// Jerk limit (rad/s³) of a joint whose description gives none.
pub const SAFE_JERK: f64 = 30.0;

/// Per joint, the acceleration and jerk limits a design keeps: `given` (one for every joint or
/// one per joint) when given, else the model's own where it has them and [`SAFE_ACCELERATION`],
/// [`SAFE_JERK`] where it does not. Also the joints that took a safe default.
pub fn rate_limits(
    model: &Model,
    acceleration: Option<&[f64]>,
    jerk: Option<&[f64]>,
) -> (Vec<f64>, Vec<f64>, Vec<String>) {
    let mut defaulted = vec![];
    let mut pick = |given: Option<&[f64]>, own: &dyn Fn(usize) -> f64, safe: f64| -> Vec<f64> {
        match given {
            Some(v) => v.to_vec(),
            None => (0..model.dof())
                .map(|j| {
                    let v = own(j);
                    if v.is_finite() {
                        v
                    } else {
                        let name = &model.bodies()[j].joint_name;
                        if !defaulted.contains(name) {
                            defaulted.push(name.clone());
                        }
                        safe
                    }
                })
                .collect(),
        }
    };
    let a = pick(
        acceleration,
        &|j| model.bodies()[j].limits.acceleration,
        SAFE_ACCELERATION,
    );
    let k = pick(jerk, &|j| model.bodies()[j].limits.jerk, SAFE_JERK);
    (a, k, defaulted)
}

/// Seed of the random states that define the identifiable basis (fixed, so values compare
/// across designs of one robot).
const BASIS_SEED: u64 = 0x1d_e27a;

/// What the design maximizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Objective {
    /// `log det F / r`: the volume of the confidence ellipsoid of the identifiable combinations.
    DOptimal,
    /// `log λ_min(F)`: its longest axis.
    EOptimal,
    /// `−½ log κ(F)`: the (column-normalized) regressor's condition number.
    Condition,
}

/// Design settings; [`DesignOptions::validate`] checks them.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct DesignOptions {
    /// Harmonics per joint `L`.
    pub harmonics: usize,
    /// Fundamental frequency `f₀` (Hz): the motion repeats every `1/f₀` s.
    pub base_frequency: f64,
    /// What is maximized.
    pub objective: Objective,
    /// Seed of the random starts and steps.
    pub seed: u64,
    /// SQP steps per start at most (0: the random start, scaled into the limits).
    pub iterations: usize,
    /// Random starts.
    pub starts: usize,
    /// Fraction of every limit left free (0.1: peaks at 90 % of each limit).
    pub margin: f64,
    /// Acceleration limits (rad/s²): one for every joint, or one per joint.
    pub max_acceleration: Vec<f64>,
    /// Jerk limits (rad/s³): one for every joint, or one per joint.
    pub max_jerk: Vec<f64>,
    /// Fade in from rest and out to rest over this long at each end (s); 0: periodic from
    /// t = 0, starting mid-motion.
    pub ramp: f64,
    /// The run's length (s): where the ramp out ends.
    pub duration: f64,
    /// Samples per period at which the information is evaluated.
    pub samples: usize,
}

impl Default for DesignOptions {
    fn default() -> Self {
        Self {
            harmonics: 5,
            base_frequency: 0.5,
            objective: Objective::DOptimal,
            seed: 1,
            iterations: 1000,
            starts: 4,
            margin: 0.15,
            max_acceleration: vec![30.0],
            max_jerk: vec![f64::INFINITY],
            ramp: 0.0,
            duration: 20.0,
            samples: 200,
        }
    }
}

/// Why a design cannot be made.
#[derive(Debug, thiserror::Error)]
pub enum DesignError {
    /// An option out of its range.
    #[error("{option} = {value}: expected {expected}")]
    InvalidOption {
        /// The option.
        option: &'static str,
        /// What it must be.
        expected: &'static str,
        /// The value given.
        value: f64,
    },
    /// The box of joint positions has the wrong size or is empty.
    #[error("joint {joint}: the position range [{lower}, {upper}] rad is empty")]
    EmptyRange {
        /// Joint name.
        joint: String,
        /// Lower end (rad).
        lower: f64,
        /// Upper end (rad).
        upper: f64,
    },
    /// Gravity alone, or with the joint's Coulomb friction, exceeds a torque limit at the
    /// centre of the range.
    #[error("joint {joint}: {} at the centre of its range takes {torque:.3} N m, above its torque limit {limit:.3} N m (with the margin){}", if *friction > 0.0 { "moving" } else { "holding still" }, if *friction > 0.0 { format!(": its Coulomb friction is {friction:.3} N m, so no motion of it fits the limit (check the description's <dynamics friction> against its <limit effort>)") } else { String::new() })]
    TorqueInfeasible {
        /// Joint name.
        joint: String,
        /// The torque needed at rest or to start moving (N m).
        torque: f64,
        /// The Coulomb friction counted in `torque` (N m; 0 for holding still).
        friction: f64,
        /// Its limit (N m).
        limit: f64,
    },
    /// The robot has no identifiable parameter.
    #[error("no parameter combination of this robot is identifiable from joint torques")]
    NothingIdentifiable,
    /// No start found a motion whose information is finite: nothing is written.
    #[error("no excitation found with a finite {objective} objective (best {value}): the limits leave no motion that carries information at these settings (base_frequency = {base_frequency} Hz, harmonics = {harmonics}; check the velocity and acceleration limits against them)")]
    NoFiniteDesign {
        /// The objective's name.
        objective: String,
        /// Its best value.
        value: f64,
        /// The base frequency (Hz).
        base_frequency: f64,
        /// Harmonics.
        harmonics: usize,
    },
}

physid_core::options::option_error!(DesignError);

impl DesignOptions {
    /// Joint `j`'s acceleration limit (rad/s²): its own, or the one for every joint.
    pub fn acceleration_limit(&self, j: usize) -> f64 {
        per_joint(&self.max_acceleration, j)
    }

    /// Joint `j`'s jerk limit (rad/s³): its own, or the one for every joint.
    pub fn jerk_limit(&self, j: usize) -> f64 {
        per_joint(&self.max_jerk, j)
    }

    /// The fade to rest, if any.
    pub fn window(&self) -> Option<super::excitation::RestWindow> {
        (self.ramp > 0.0).then_some(super::excitation::RestWindow {
            ramp: self.ramp,
            end: self.duration,
        })
    }

    /// Checks every value against its range.
    pub fn validate(&self) -> Result<(), DesignError> {
        let bad = |option, expected, value: f64| {
            Err(DesignError::InvalidOption {
                option,
                expected,
                value,
            })
        };
        if !(1..=50).contains(&self.harmonics) {
            return bad("harmonics", "1 to 50", self.harmonics as f64);
        }
        let f0 = self.base_frequency;
        if !(f0.is_finite() && f0 > 0.0) {
            return bad("base_frequency", "a positive frequency in Hz", f0);
        }
        if !(1..=64).contains(&self.starts) {
            return bad("starts", "1 to 64", self.starts as f64);
        }
        if self.iterations > 1_000_000 {
            return bad("iterations", "at most 1,000,000", self.iterations as f64);
        }
        if !(self.margin.is_finite() && (0.0..0.9).contains(&self.margin)) {
            return bad("margin", "a fraction in [0, 0.9)", self.margin);
        }
        if self.max_acceleration.is_empty() {
            return bad("max_acceleration", "at least one value", 0.0);
        }
        for &a in &self.max_acceleration {
            if !(a.is_finite() && a > 0.0) {
                return bad("max_acceleration", "a positive number (rad/s²)", a);
            }
        }
        if self.max_jerk.is_empty() {
            return bad("max_jerk", "at least one value", 0.0);
        }
        for &a in &self.max_jerk {
            if a.is_nan() || a <= 0.0 {
                return bad("max_jerk", "a positive number (rad/s³)", a);
            }
        }
        if !(self.duration.is_finite() && self.duration > 0.0) {
            return bad("duration", "a positive number of seconds", self.duration);
        }
        if !(self.ramp.is_finite() && self.ramp >= 0.0 && 2.0 * self.ramp <= self.duration) {
            return bad(
                "ramp",
                "0 or more seconds, at most half the duration",
                self.ramp,
            );
        }
        if !(self.samples >= 4 * self.harmonics && self.samples <= 100_000) {
            return bad(
                "samples",
                "at least 4 per harmonic and at most 100,000",
                self.samples as f64,
            );
        }
        Ok(())
    }
}

/// The limits a design keeps, per joint, margins applied.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct Limits {
    /// Lowest angle (rad).
    pub lower: Vec<f64>,
    /// Highest angle (rad).
    pub upper: Vec<f64>,
    /// Largest speed (rad/s; infinite: none).
    pub velocity: Vec<f64>,
    /// Largest acceleration (rad/s²).
    pub acceleration: Vec<f64>,
    /// Largest jerk (rad/s³; infinite: none).
    pub jerk: Vec<f64>,
    /// Largest torque (N m; infinite: none).
    pub effort: Vec<f64>,
}

impl Limits {
    /// The model's limits, narrowed to `range` (per joint `(lower, upper)`, rad) when given,
    /// with a fraction `margin` of each left free (positions: of the half-range about its
    /// centre). Joints without position limits get ±π about the centre of `range` or 0.
    pub fn new(
        model: &Model,
        range: Option<&[(f64, f64)]>,
        opts: &DesignOptions,
    ) -> Result<Self, DesignError> {
        let keep = 1.0 - opts.margin;
        for (option, k) in [
            ("max_acceleration", opts.max_acceleration.len()),
            ("max_jerk", opts.max_jerk.len()),
        ] {
            if k != 1 && k != model.dof() {
                return Err(DesignError::InvalidOption {
                    option,
                    expected: "one value, or one per joint",
                    value: k as f64,
                });
            }
        }
        let mut l = Limits {
            lower: vec![],
            upper: vec![],
            velocity: vec![],
            acceleration: vec![],
            jerk: vec![],
            effort: vec![],
        };
        for (j, b) in model.bodies().iter().enumerate() {
            let (mut lo, mut hi) = (b.limits.lower, b.limits.upper);
            if let Some(r) = range.and_then(|r| r.get(j)) {
                lo = lo.max(r.0);
                hi = hi.min(r.1);
            }
            if !lo.is_finite() || !hi.is_finite() {
                let mid = if lo.is_finite() {
                    lo + std::f64::consts::PI
                } else if hi.is_finite() {
                    hi - std::f64::consts::PI
                } else {
                    0.0
                };
                (lo, hi) = (mid - std::f64::consts::PI, mid + std::f64::consts::PI);
            }
            if lo.partial_cmp(&hi) != Some(std::cmp::Ordering::Less) {
                return Err(DesignError::EmptyRange {
                    joint: b.joint_name.clone(),
                    lower: lo,
                    upper: hi,
                });
            }
            let (mid, half) = (0.5 * (lo + hi), 0.5 * (hi - lo) * keep);
            l.lower.push(mid - half);
            l.upper.push(mid + half);
            l.velocity.push(b.limits.velocity * keep);
            l.acceleration.push(opts.acceleration_limit(j) * keep);
            l.jerk.push(opts.jerk_limit(j) * keep);
            l.effort.push(b.limits.effort * keep);
        }
        Ok(l)
    }

    /// The centre of each joint's range (rad): the trajectory's offset.
    pub fn centre(&self) -> Vec<f64> {
        self.lower
            .iter()
            .zip(&self.upper)
            .map(|(a, b)| 0.5 * (a + b))
            .collect()
    }
}

/// A design's timing when the user gives none: the rest ramps and the fundamental chosen with
/// the limits and the run's length ([`Timing::chosen`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timing {
    /// Fundamental frequency `f₀` (Hz).
    pub base_frequency: f64,
    /// Rest ramp at each end (s).
    pub ramp: f64,
}

impl Timing {
    /// The timing for `limits` (margins applied) over a run of `duration` s, each part kept
    /// where given:
    ///
    /// - the **ramp**, the shortest over which fading a joint's whole half-range `R_j` in by the
    ///   septic smoothstep `w` keeps within half its acceleration and jerk limits
    ///   (`R_j max|w''| / r² ≤ A_j / 2`, `R_j max|w'''| / r³ ≤ J_j / 2`), at most a quarter of
    ///   the run;
    /// - the **fundamental**, the fastest at which every joint's first harmonic alone could
    ///   sweep its whole range within its speed, acceleration and jerk limits
    ///   (`ω₀ = min_j min(V_j / R_j, √(A_j / R_j), ∛(J_j / R_j))`), but at least one whole period
    ///   in the run between the ramps (or in half the run, where a given ramp leaves less). A design at a fixed 0.5 Hz over the KUKA's ±2.5 rad and
    ///   3 rad/s² moved each joint within 1-13 % of its range.
    pub fn chosen(
        limits: &Limits,
        duration: f64,
        base_frequency: Option<f64>,
        ramp: Option<f64>,
    ) -> Timing {
        let [w2, w3] = smoothstep_peaks();
        let half: Vec<f64> = (0..limits.lower.len())
            .map(|j| 0.5 * (limits.upper[j] - limits.lower[j]))
            .collect();
        let ramp = ramp.unwrap_or_else(|| {
            let needed = half.iter().enumerate().fold(0.0_f64, |r, (j, &h)| {
                let by_acceleration = (2.0 * h * w2 / limits.acceleration[j]).sqrt();
                let by_jerk = (2.0 * h * w3 / limits.jerk[j]).cbrt();
                r.max(by_acceleration).max(by_jerk)
            });
            needed.min(0.25 * duration)
        });
        let base_frequency = base_frequency.unwrap_or_else(|| {
            let omega = half.iter().enumerate().fold(f64::INFINITY, |w, (j, &h)| {
                w.min(limits.velocity[j] / h)
                    .min((limits.acceleration[j] / h).sqrt())
                    .min((limits.jerk[j] / h).cbrt())
            });
            // (A given ramp may leave little between the ramps: the period then runs into them,
            // over at least half the run, rather than a fundamental no limit allows.)
            let one_period = 1.0 / (duration - 2.0 * ramp).max(0.5 * duration);
            (omega / (2.0 * std::f64::consts::PI)).max(one_period)
        });
        Timing {
            base_frequency,
            ramp,
        }
    }
}

/// The septic smoothstep's largest `|w''|` and `|w'''|` over one unit-length ramp.
fn smoothstep_peaks() -> [f64; 2] {
    let unit = super::excitation::RestWindow {
        ramp: 1.0,
        end: 10.0,
    };
    (0..=1000).fold([0.0_f64; 2], |[a, j], k| {
        let w = unit.at(k as f64 / 1000.0);
        [a.max(w[2].abs()), j.max(w[3].abs())]
    })
}

/// `m` evenly spaced times over one period of `s`.
fn times(s: &FourierSeries, m: usize) -> impl Iterator<Item = f64> + '_ {
    (0..m).map(move |k| s.period() * k as f64 / m as f64)
}

/// The times at which limits are checked: `m` over one period of the steady motion (after the
/// ramp in), and `m` over each ramp.
fn check_times(s: &FourierSeries, m: usize) -> Vec<f64> {
    let Some(w) = s.window else {
        return times(s, m).collect();
    };
    let steady = (0..m).map(|k| w.ramp + s.period() * k as f64 / m as f64);
    let ramp_in = (0..m).map(|k| w.ramp * k as f64 / m as f64);
    let ramp_out = (0..=m).map(|k| w.end - w.ramp + w.ramp * k as f64 / m as f64);
    steady.chain(ramp_in).chain(ramp_out).collect()
}

/// One value for every joint (one given), or joint `j`'s own.
fn per_joint(v: &[f64], j: usize) -> f64 {
    if v.len() == 1 {
        v[0]
    } else {
        v.get(j).copied().unwrap_or(f64::NAN)
    }
}

/// How much of each limit a trajectory uses, per joint (peak over one period / limit).
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct LimitUse {
    /// Joint name.
    pub joint: String,
    /// Position: the larger of the excursions below and above the centre over the
    /// half-range with the margin (1: touches the narrowed limit).
    pub position: f64,
    /// Peak speed over the speed limit with the margin (0 without a limit).
    pub velocity: f64,
    /// Peak acceleration over its limit with the margin.
    pub acceleration: f64,
    /// Peak jerk over its limit with the margin (0 without a limit).
    pub jerk: f64,
    /// Peak torque (inverse dynamics with friction) over the effort limit with the margin
    /// (0 without a limit).
    pub torque: f64,
}

/// The designed excitation and how good it is.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct Design {
    /// The trajectory.
    pub series: FourierSeries,
    /// The objective maximized.
    pub objective: Objective,
    /// Its value at the optimum.
    pub value: f64,
    /// Its value at the best random start (scaled into the limits, before any step).
    pub start_value: f64,
    /// `log det F / r` of the optimum (comparable across objectives).
    pub d_value: f64,
    /// Condition number of the column-normalized regressor over one period, on the
    /// identifiable combinations (`√(λ_max/λ_min)` of `F`).
    pub condition: f64,
    /// Identifiable parameter combinations `r`, of `p` parameters.
    pub identifiable: usize,
    /// Parameters `p` (inertial with rotors, then friction).
    pub parameters: usize,
    /// Limits kept (margins applied).
    pub limits: Limits,
    /// The optimum's use of each limit (evaluated on 4 × `samples` points per period).
    pub limit_use: Vec<LimitUse>,
    /// Objective evaluations (a value with its gradient counts as one).
    pub evaluations: usize,
    /// Wall time (s).
    pub seconds: f64,
}

/// The information basis: column scales `D` and the identifiable directions `V`.
struct Basis {
    /// `1/‖column‖` of the random-state regressor.
    inv_scale: DVector<f64>,
    /// `p × r`.
    v: DMatrix<f64>,
}

impl Basis {
    /// From `p` × 40 random states inside `limits`.
    fn new(model: &Model, limits: &Limits, seed: u64) -> Result<Self, DesignError> {
        let (n, p) = (model.dof(), model.layout().len);
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xba5e_5eed);
        let states = (0..(40 * p).max(400)).map(|_| {
            let mut draw = |lo: f64, hi: f64| rng.random_range(lo..=hi);
            let q: Vec<f64> = (0..n)
                .map(|j| draw(limits.lower[j], limits.upper[j]))
                .collect();
            let qd: Vec<f64> = (0..n)
                .map(|j| {
                    let v = limits.velocity[j].min(limits.acceleration[j]);
                    draw(-v, v)
                })
                .collect();
            let qdd: Vec<f64> = (0..n)
                .map(|j| draw(-limits.acceleration[j], limits.acceleration[j]))
                .collect();
            [q, qd, qdd]
        });
        let (a, _) = gram(model, &mut Data::new(model), states);
        // A column that no state excites is zero up to round-off (a norm of 1e-14 beside
        // hundreds, e.g. `lwr_2_link.hy` of the KUKA arm): it gets no weight, instead of a scale
        // that would blow its round-off up into the information.
        let largest = (0..p).map(|i| a[(i, i)].sqrt()).fold(0.0, f64::max);
        let inv_scale = DVector::from_iterator(
            p,
            (0..p).map(|i| {
                let s = a[(i, i)].sqrt();
                if s > 1e-9 * largest {
                    1.0 / s
                } else {
                    0.0
                }
            }),
        );
        let scaled = scale(&a, &inv_scale);
        let eig = SymmetricEigen::new(scaled);
        let top = eig.eigenvalues.max();
        let keep: Vec<usize> = (0..p)
            .filter(|&i| eig.eigenvalues[i] > 1e-9 * top)
            .collect();
        if keep.is_empty() || top.is_nan() || top <= 0.0 {
            return Err(DesignError::NothingIdentifiable);
        }
        let v = DMatrix::from_fn(p, keep.len(), |r, c| eig.eigenvectors[(r, keep[c])]);
        Ok(Self { inv_scale, v })
    }

    /// `F = Vᵀ D⁻¹ A D⁻¹ V`.
    fn information(&self, a: &DMatrix<f64>) -> DMatrix<f64> {
        self.v.transpose() * scale(a, &self.inv_scale) * &self.v
    }
}

/// `S A S` for diagonal `S = diag(s)`.
fn scale(a: &DMatrix<f64>, s: &DVector<f64>) -> DMatrix<f64> {
    DMatrix::from_fn(a.nrows(), a.ncols(), |i, j| s[i] * a[(i, j)] * s[j])
}

/// Everything an evaluation needs.
struct Problem<'a> {
    model: &'a Model,
    limits: Limits,
    basis: Basis,
    opts: &'a DesignOptions,
    watch: &'a Watch<'a>,
    /// Evaluations of the objective so far, over every start.
    evaluations: std::sync::atomic::AtomicUsize,
}

/// What a design tells its caller as it goes, and asks it: `evaluated(done, total)` after each
/// evaluation of the objective (from the pool's threads; `total` over every start), `stop()`
/// between evaluations (a stopped design ends early with the best found so far).
pub struct Watch<'a> {
    /// Called after each evaluation with the evaluations done and their total.
    pub evaluated: &'a (dyn Fn(usize, usize) + Sync),
    /// Whether to stop.
    pub stop: &'a (dyn Fn() -> bool + Sync),
}

fn unwatched(_: usize, _: usize) {}

fn never() -> bool {
    false
}

impl Watch<'static> {
    /// Nothing told, never stopped.
    pub const NONE: Watch<'static> = Watch {
        evaluated: &unwatched,
        stop: &never,
    };
}

impl Problem<'_> {
    /// Counts one evaluation and tells the watcher.
    fn evaluated(&self) {
        let done = 1 + (self.evaluations).fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let total = self.opts.starts * (self.opts.iterations + 1);
        (self.watch.evaluated)(done, total);
    }
}

/// The three objectives of an information matrix (−∞ when it is singular).
fn objectives(f: &DMatrix<f64>) -> [f64; 3] {
    let eig = SymmetricEigen::new(f.clone());
    let r = f.nrows() as f64;
    let (lo, hi) = (eig.eigenvalues.min(), eig.eigenvalues.max());
    if !(lo > 0.0 && lo.is_finite() && hi.is_finite()) {
        return [f64::NEG_INFINITY; 3];
    }
    let log_det = eig.eigenvalues.iter().map(|l| l.ln()).sum::<f64>() / r;
    [log_det, lo.ln(), -0.5 * (hi / lo).ln()]
}

impl Problem<'_> {
    /// The information matrix of `s`'s steady motion (the periodic series, without the
    /// ramps) over `samples` points of one period.
    fn information(&self, s: &FourierSeries, data: &mut Data) -> DMatrix<f64> {
        let steady = s.steady();
        let states = times(&steady, self.opts.samples).map(|t| steady.at(t));
        let (a, m) = gram(self.model, data, states);
        self.basis.information(&(a / m as f64))
    }

    /// The objective's value at the information matrix `f`.
    fn objective_of(&self, f: &DMatrix<f64>) -> f64 {
        let o = objectives(f);
        match self.opts.objective {
            Objective::DOptimal => o[0],
            Objective::EOptimal => o[1],
            Objective::Condition => o[2],
        }
    }

    /// The objective value of `s` (already inside the limits).
    fn value(&self, s: &FourierSeries, data: &mut Data) -> f64 {
        self.objective_of(&self.information(s, data))
    }

    /// Peaks over one period and the ramps: per joint `[below centre, above centre, |q̇|, |q̈|,
    /// |q⃛|]`.
    fn kinematic_peaks(&self, s: &FourierSeries) -> Vec<[f64; 5]> {
        let n = s.offset.len();
        let mut peaks = vec![[0.0f64; 5]; n];
        let (mut waves, mut at) = (vec![], Default::default());
        for t in check_times(s, 4 * self.opts.samples) {
            s.with_jerk_into(t, &mut waves, &mut at);
            let [q, qd, qdd, jerk] = &at;
            for j in 0..n {
                let e = q[j] - s.offset[j];
                let pk = &mut peaks[j];
                pk[0] = pk[0].max(-e);
                pk[1] = pk[1].max(e);
                pk[2] = pk[2].max(qd[j].abs());
                pk[3] = pk[3].max(qdd[j].abs());
                pk[4] = pk[4].max(jerk[j].abs());
            }
        }
        peaks
    }

    /// Largest |τ_j| / effort_j over one period (0 without effort limits).
    fn torque_ratio(&self, s: &FourierSeries, data: &mut Data, points: usize) -> Vec<f64> {
        let n = s.offset.len();
        let mut r = vec![0.0f64; n];
        if self.limits.effort.iter().all(|e| !e.is_finite()) {
            return r;
        }
        for t in check_times(s, points) {
            let [q, qd, qdd] = s.at(t);
            let tau = rnea_with_friction(self.model, data, &q, &qd, &qdd);
            for j in 0..n {
                if self.limits.effort[j].is_finite() {
                    r[j] = r[j].max(tau[j].abs() / self.limits.effort[j]);
                }
            }
        }
        r
    }

    /// Per joint, the largest factor by which its series may be scaled within its position,
    /// speed, acceleration and jerk limits (∞ for a joint that does not move).
    fn kinematic_factors(&self, s: &FourierSeries) -> Vec<f64> {
        let l = &self.limits;
        let peaks = self.kinematic_peaks(s);
        (0..peaks.len())
            .map(|j| {
                let o = s.offset[j];
                let room = [
                    o - l.lower[j],
                    l.upper[j] - o,
                    l.velocity[j],
                    l.acceleration[j],
                    l.jerk[j],
                ];
                room.iter()
                    .zip(&peaks[j])
                    .filter(|(_, p)| **p > 0.0)
                    .map(|(r, p)| r / p)
                    .fold(f64::INFINITY, f64::min)
            })
            .collect()
    }

    /// `s` scaled into the limits: each joint by the largest factor its position, speed and
    /// acceleration allow, then all joints by bisection until the torque fits.
    fn scaled_into_limits(&self, mut s: FourierSeries, data: &mut Data) -> FourierSeries {
        for (j, f) in self.kinematic_factors(&s).into_iter().enumerate() {
            if f.is_finite() {
                s.scale_joint(j, f);
            }
        }
        let points = self.opts.samples;
        let worst = |s: &FourierSeries, data: &mut Data| {
            self.torque_ratio(s, data, points)
                .into_iter()
                .fold(0.0, f64::max)
        };
        if worst(&s, data) <= 1.0 {
            return s;
        }
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..12 {
            let mid = 0.5 * (lo + hi);
            let mut t = s.clone();
            (0..t.offset.len()).for_each(|j| t.scale_joint(j, mid));
            if worst(&t, data) <= 1.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        (0..s.offset.len()).for_each(|j| s.scale_joint(j, lo));
        s
    }

    /// The use of each limit by `s`.
    fn limit_use(&self, s: &FourierSeries, data: &mut Data) -> Vec<LimitUse> {
        let l = &self.limits;
        let peaks = self.kinematic_peaks(s);
        let torque = self.torque_ratio(s, data, 4 * self.opts.samples);
        let ratio = |a: f64, b: f64| if b.is_finite() { a / b } else { 0.0 };
        self.model
            .bodies()
            .iter()
            .enumerate()
            .map(|(j, b)| {
                let o = s.offset[j];
                LimitUse {
                    joint: b.joint_name.clone(),
                    position: (peaks[j][0] / (o - l.lower[j])).max(peaks[j][1] / (l.upper[j] - o)),
                    velocity: ratio(peaks[j][2], l.velocity[j]),
                    acceleration: ratio(peaks[j][3], l.acceleration[j]),
                    jerk: ratio(peaks[j][4], l.jerk[j]),
                    torque: torque[j],
                }
            })
            .collect()
    }

    /// Random coefficients (uniform, decaying as 1/l) about the centre.
    fn random_start(&self, rng: &mut ChaCha8Rng) -> FourierSeries {
        let (n, h) = (self.limits.lower.len(), self.opts.harmonics);
        let mut draw = |l: usize| rng.random_range(-1.0..1.0) / (l + 1) as f64;
        let mut coeffs =
            || -> Vec<Vec<f64>> { (0..n).map(|_| (0..h).map(&mut draw).collect()).collect() };
        let sin = coeffs();
        let cos = coeffs();
        FourierSeries {
            base_frequency: self.opts.base_frequency,
            offset: self.limits.centre(),
            sin,
            cos,
            window: self.opts.window(),
        }
    }

    /// One start: a random draw scaled into the limits, then up to `iterations` SQP steps
    /// ([`sqp`]). Returns the start's and the end's values, the end, and the evaluations made.
    fn run_start(&self, k: usize) -> (f64, f64, FourierSeries, usize) {
        let mut rng = ChaCha8Rng::seed_from_u64(self.opts.seed);
        rng.set_stream(k as u64);
        let mut data = Data::new(self.model);
        let x = self.scaled_into_limits(self.random_start(&mut rng), &mut data);
        let start = self.value(&x, &mut data);
        self.evaluated();
        if self.opts.iterations == 0 {
            return (start, start, x, 1);
        }
        let (value, end, evaluations) = self.improve(x, &mut data);
        (start, value, end, evaluations + 1)
    }
}

/// Designs an excitation for `model` within its limits (narrowed to `range`, per joint
/// `(lower, upper)` in rad, when given). Starts run on the current rayon pool.
pub fn design(
    model: &Model,
    range: Option<&[(f64, f64)]>,
    opts: &DesignOptions,
) -> Result<Design, DesignError> {
    design_watched(model, range, opts, &Watch::NONE)
}

/// [`design`], telling `watch` of each evaluation and stopping early when it asks.
pub fn design_watched(
    model: &Model,
    range: Option<&[(f64, f64)]>,
    opts: &DesignOptions,
    watch: &Watch<'_>,
) -> Result<Design, DesignError> {
    opts.validate()?;
    let clock = std::time::Instant::now();
    let limits = Limits::new(model, range, opts)?;
    check_holding_torque(model, &limits)?;
    let basis = Basis::new(model, &limits, BASIS_SEED)?;
    let problem = Problem {
        model,
        limits,
        basis,
        opts,
        watch,
        evaluations: Default::default(),
    };
    let runs: Vec<(f64, f64, FourierSeries, usize)> = (0..opts.starts)
        .into_par_iter()
        .map(|k| problem.run_start(k))
        .collect();
    let best = runs
        .iter()
        .enumerate()
        .fold(0, |b, (k, r)| if r.1 > runs[b].1 { k } else { b });
    let start_value = runs.iter().map(|r| r.0).fold(f64::NEG_INFINITY, f64::max);
    let (_, value, series, _) = runs[best].clone();
    let mut data = Data::new(model);
    let f = problem.information(&series, &mut data);
    let [d_value, _, neg_half_log_kappa] = objectives(&f);
    if !(value.is_finite() && d_value.is_finite()) {
        return Err(DesignError::NoFiniteDesign {
            objective: physid_io::serde_name(&opts.objective),
            value,
            base_frequency: opts.base_frequency,
            harmonics: opts.harmonics,
        });
    }
    Ok(Design {
        limit_use: problem.limit_use(&series, &mut data),
        series,
        objective: opts.objective,
        value,
        start_value,
        d_value,
        condition: (-neg_half_log_kappa).exp(),
        identifiable: problem.basis.v.ncols(),
        parameters: model.layout().len,
        limits: problem.limits,
        evaluations: runs.iter().map(|r| r.3).sum(),
        seconds: clock.elapsed().as_secs_f64(),
    })
}

/// The torque that holds the robot at the centre of its ranges fits every effort limit, and
/// so does the torque that starts each joint moving from there either way (the holding torque
/// and its Coulomb friction): a periodic motion moves every joint both ways, and one whose
/// friction alone exceeds its limit cannot move at all (Drake's Allegro hand: 10 N m of
/// friction under a 0.7 N m limit), which the design would otherwise find only as a motion
/// scaled to nothing.
fn check_holding_torque(model: &Model, limits: &Limits) -> Result<(), DesignError> {
    let n = model.dof();
    let mut data = Data::new(model);
    let zero = vec![0.0; n];
    let tau = rnea_with_friction(model, &mut data, &limits.centre(), &zero, &zero);
    for (j, b) in model.bodies().iter().enumerate() {
        let infeasible = |torque: f64, friction: f64| DesignError::TorqueInfeasible {
            joint: b.joint_name.clone(),
            torque,
            friction,
            limit: limits.effort[j],
        };
        if tau[j].abs() > limits.effort[j] {
            return Err(infeasible(tau[j].abs(), 0.0));
        }
        let moving = tau[j].abs() + b.friction.coulomb.abs();
        if moving > limits.effort[j] {
            return Err(infeasible(moving, b.friction.coulomb.abs()));
        }
    }
    Ok(())
}

/// The objective values `[D, E, condition]` of any series for `model` (the same basis as
/// [`design`] with `opts`, the series sampled as the design samples it): to score a motion
/// that was not designed here.
pub fn score(
    model: &Model,
    range: Option<&[(f64, f64)]>,
    series: &FourierSeries,
    opts: &DesignOptions,
) -> Result<[f64; 3], DesignError> {
    let states: Vec<[Vec<f64>; 3]> = times(series, opts.samples).map(|t| series.at(t)).collect();
    score_states(
        model,
        range,
        opts,
        states
            .iter()
            .map(|[q, qd, qdd]| [&q[..], &qd[..], &qdd[..]]),
    )
}

/// The objective values `[D, E, condition]` of a recorded motion: the information of the
/// samples `states` (`(q, q̇, q̈)` each, rad, rad/s, rad/s²) in the same basis as [`design`]
/// with `range` and `opts`, so a motion designed elsewhere (the shell) compares with a design.
pub fn score_states<'s>(
    model: &Model,
    range: Option<&[(f64, f64)]>,
    opts: &DesignOptions,
    states: impl Iterator<Item = [&'s [f64]; 3]>,
) -> Result<[f64; 3], DesignError> {
    let limits = Limits::new(model, range, opts)?;
    let basis = Basis::new(model, &limits, BASIS_SEED)?;
    let (a, m) = gram(model, &mut Data::new(model), states);
    Ok(objectives(&basis.information(&(a / m.max(1) as f64))))
}

/// Speed (rad/s) over which the design's Coulomb columns change sign.
const COULOMB_SPEED: f64 = 0.01;

/// The regressor at `(q, q̇, q̈)` as the design sees it: the Coulomb columns `tanh(q̇/v_c)`
/// instead of `sign(q̇)` (the same away from rest), so that the information is a smooth function
/// of the coefficients.
fn design_regressor(
    model: &Model,
    data: &mut Data,
    [q, qd, qdd]: [&[f64]; 3],
    y: &mut DMatrix<f64>,
) {
    regressor(model, data, q, qd, qdd, y);
    let c = model.layout().coulomb_col;
    for (j, v) in qd.iter().enumerate() {
        y[(j, c + j)] = (v / COULOMB_SPEED).tanh();
    }
}

/// `Σ_k Y_kᵀ Y_k` of the regressors at `states` (`(q, q̇, q̈)` each), and their count.
fn gram<S: AsRef<[f64]>>(
    model: &Model,
    data: &mut Data,
    states: impl Iterator<Item = [S; 3]>,
) -> (DMatrix<f64>, usize) {
    let (n, p) = (model.dof(), model.layout().len);
    let mut y = DMatrix::zeros(n, p);
    let mut sum = GramSum::new(n, p);
    for [q, qd, qdd] in states {
        design_regressor(model, data, [q.as_ref(), qd.as_ref(), qdd.as_ref()], &mut y);
        sum.add(&y);
    }
    sum.finish()
}

/// `Σ_k Y_kᵀ Y_k` over blocks of samples' rows: one product per block of [`GramSum::BLOCK`]
/// samples, not one per sample.
struct GramSum {
    rows: DMatrix<f64>,
    filled: usize,
    count: usize,
    a: DMatrix<f64>,
}

impl GramSum {
    const BLOCK: usize = 64;

    /// Empty, for `n × p` regressors.
    fn new(n: usize, p: usize) -> Self {
        Self {
            rows: DMatrix::zeros(Self::BLOCK * n, p),
            filled: 0,
            count: 0,
            a: DMatrix::zeros(p, p),
        }
    }

    /// Adds one sample's regressor `y`.
    fn add(&mut self, y: &DMatrix<f64>) {
        let n = y.nrows();
        self.rows
            .view_mut((self.filled * n, 0), y.shape())
            .copy_from(y);
        (self.filled, self.count) = (self.filled + 1, self.count + 1);
        if self.filled == Self::BLOCK {
            self.flush(n);
        }
    }

    fn flush(&mut self, n: usize) {
        let block = self.rows.rows(0, self.filled * n);
        // (`gemm` on the transpose: nalgebra's `gemm_tr` takes dot products one entry at a
        // time, `gemm` the blocked kernel.)
        self.a.gemm(1.0, &block.transpose(), &block, 1.0);
        self.filled = 0;
    }

    /// The sum and the samples' count.
    fn finish(mut self) -> (DMatrix<f64>, usize) {
        if self.filled > 0 {
            let n = self.rows.nrows() / Self::BLOCK;
            self.flush(n);
        }
        (self.a, self.count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One joint of half-range 2 rad about 0 with the given rate limits (margins applied).
    fn one_joint(velocity: f64, acceleration: f64, jerk: f64) -> Limits {
        Limits {
            lower: vec![-2.0],
            upper: vec![2.0],
            velocity: vec![velocity],
            acceleration: vec![acceleration],
            jerk: vec![jerk],
            effort: vec![f64::INFINITY],
        }
    }

    #[test]
    fn the_smoothstep_peaks_are_those_of_its_polynomial() {
        // w'' = 420x² − 1680x³ + 2100x⁴ − 840x⁵ peaks at 7.5132 (x ≈ 0.276); w''' at x = ½,
        // 840/2 − 5040/4 + 8400/8 − 4200/16 = −52.5.
        let [w2, w3] = smoothstep_peaks();
        assert!((w2 - 7.5132).abs() < 1e-3, "{w2}");
        assert!((w3 - 52.5).abs() < 1e-9, "{w3}");
    }

    #[test]
    fn the_timing_sweeps_the_range_within_the_limits_unless_given() {
        let [w2, w3] = smoothstep_peaks();
        let pi2 = 2.0 * std::f64::consts::PI;
        // Speed binds (V/R = 0.5 < √(A/R) = 1.22 < ∛(J/R) = 2.47); the ramp by acceleration.
        let t = Timing::chosen(&one_joint(1.0, 3.0, 30.0), 100.0, None, None);
        assert!((t.base_frequency - 0.5 / pi2).abs() < 1e-12, "{t:?}");
        assert!(
            (t.ramp - (2.0 * 2.0 * w2 / 3.0).sqrt()).abs() < 1e-12,
            "{t:?}"
        );
        // Acceleration binds the fundamental (√1.5 < ∛2.5), jerk the ramp (∛42 > 3.17 s).
        let t = Timing::chosen(&one_joint(f64::INFINITY, 3.0, 5.0), 1000.0, None, None);
        assert!(
            (t.base_frequency - 1.5f64.sqrt() / pi2).abs() < 1e-12,
            "{t:?}"
        );
        assert!(
            (t.ramp - (2.0 * 2.0 * w3 / 5.0).cbrt()).abs() < 1e-12,
            "{t:?}"
        );
        // A short run: the ramp at a quarter of it, one whole period between the ramps.
        let t = Timing::chosen(&one_joint(1.0, 3.0, 30.0), 10.0, None, None);
        assert_eq!(t.ramp, 2.5);
        assert!((t.base_frequency - 0.2).abs() < 1e-12, "{t:?}");
        // What is given is kept.
        let t = Timing::chosen(&one_joint(1.0, 3.0, 30.0), 10.0, Some(0.7), Some(0.0));
        assert_eq!((t.base_frequency, t.ramp), (0.7, 0.0));
        // A given ramp of half the run leaves nothing between the ramps: one period over half
        // the run (before: an infinite fundamental, refused as if the user had given it).
        let t = Timing::chosen(&one_joint(1.0, 3.0, 30.0), 10.0, None, Some(5.0));
        assert_eq!(t.ramp, 5.0);
        assert!((t.base_frequency - 0.2).abs() < 1e-12, "{t:?}");
    }
}
