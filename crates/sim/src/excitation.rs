//! Excitation controllers, evaluated at the control rate on the **measured** state (as on the
//! robot): the paper's Cartesian impedance shell experiment, Fourier-series joint trajectories
//! with PD or computed-torque tracking, and none (passive).

use super::scenario::{ExcitationSpec, ScenarioError};
use nalgebra::Vector3;
use physid_core::dynamics::{gravity_from_transforms, kinematics, rnea, Data};
use physid_core::model::Model;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The shell target (architecture.md §3): the azimuth `φ` and a polar phase `θ` integrate
/// `φ̇ = A_φ sin(ω_φ t)`, `θ̇ = A_θ sin(ω_θ t)` from zero; the polar angle from straight down is
/// `θ_p = polar_mid + polar_amplitude sin θ`, which keeps the target in a band of the shell that
/// a leg with joint limits can reach; the target is `c + r ∘ [sin θ_p cos φ, sin θ_p sin φ,
/// −cos θ_p]`.
#[derive(Clone, Debug)]
pub struct Shell {
    body: usize,
    offset: Vector3<f64>,
    center: Vector3<f64>,
    radii: Vector3<f64>,
    a_phi: f64,
    a_theta: f64,
    w_phi: f64,
    w_theta: f64,
    polar_mid: f64,
    polar_amplitude: f64,
    kp: Vector3<f64>,
    kd: Vector3<f64>,
    joint_damping: f64,
    gravity_compensation: bool,
}

impl Shell {
    /// The Cartesian PD force at the point mapped to the joints, `Jᵀ f − d q̇`, plus `g(q)` if
    /// compensated (N m), at time `t` from the measured `q`, `q̇`; allocates nothing.
    /// `J`'s column `k` (joints in the point's support) is `S_k`'s world motion at the point.
    fn torque_into(
        &self,
        model: &Model,
        data: &mut Data,
        t: f64,
        q: &[f64],
        qd: &[f64],
        tau: &mut [f64],
    ) {
        kinematics::update_world(model, data, q);
        let p = kinematics::point_position(data, self.body, &self.offset);
        let column = |data: &Data, k: usize| kinematics::point_jacobian_column(data, k, &p);
        let support = model.support(self.body);
        // v = J q̇, summed column by column in joint order.
        let mut v = Vector3::zeros();
        for k in (0..qd.len()).filter(|k| support.contains(k)) {
            v += column(data, k) * qd[k];
        }
        let (pd, vd) = self.target(t);
        let f = self.kp.component_mul(&(pd - p)) + self.kd.component_mul(&(vd - v));
        for (k, tau_k) in tau.iter_mut().enumerate() {
            let jtf = if support.contains(&k) {
                let c = column(data, k);
                c.x * f.x + c.y * f.y + c.z * f.z
            } else {
                0.0
            };
            *tau_k = jtf - qd[k] * self.joint_damping;
        }
        if self.gravity_compensation {
            // g(q): the transforms are update_world's, at the same q.
            let g = gravity_from_transforms(model, data);
            tau.iter_mut().zip(g.iter()).for_each(|(t, g)| *t += g);
        }
    }

    /// Target position and velocity (m, m/s; base frame) at time `t` (s).
    pub fn target(&self, t: f64) -> (Vector3<f64>, Vector3<f64>) {
        let phi = self.a_phi / self.w_phi * (1.0 - (self.w_phi * t).cos());
        let phid = self.a_phi * (self.w_phi * t).sin();
        let th = self.a_theta / self.w_theta * (1.0 - (self.w_theta * t).cos());
        let thd = self.a_theta * (self.w_theta * t).sin();
        let tp = self.polar_mid + self.polar_amplitude * th.sin();
        let tpd = self.polar_amplitude * th.cos() * thd;
        let (st, ct) = tp.sin_cos();
        let (sp, cp) = phi.sin_cos();
        let dir = Vector3::new(st * cp, st * sp, -ct);
        let ddir = Vector3::new(
            ct * cp * tpd - st * sp * phid,
            ct * sp * tpd + st * cp * phid,
            st * tpd,
        );
        (
            self.center + self.radii.component_mul(&dir),
            self.radii.component_mul(&ddir),
        )
    }
}

/// A Fourier trajectory: offsets and coefficients per joint and harmonic (rad),
/// A motion that starts and ends at rest: a deviation `δ(t)` faded in over the first `ramp` s
/// and out over the last `ramp` s before `end`, `q = o + w(t) δ(t)`, by the septic smoothstep
/// `s(x) = 35x⁴ − 84x⁵ + 70x⁶ − 20x⁷` (velocity, acceleration and jerk zero at both ends).
#[derive(
    Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
pub struct RestWindow {
    /// Fade length at each end (s).
    pub ramp: f64,
    /// When the motion has come to rest again (s); after it, `w = 0`.
    pub end: f64,
}

impl RestWindow {
    /// `w` and its first three time derivatives at `t` (s).
    pub fn at(&self, t: f64) -> [f64; 4] {
        let r = self.ramp;
        let s = |x: f64| {
            let x = x.clamp(0.0, 1.0);
            let (x2, x3) = (x * x, x * x * x);
            [
                x2 * x2 * (35.0 - 84.0 * x + 70.0 * x2 - 20.0 * x3),
                x3 * (140.0 - 420.0 * x + 420.0 * x2 - 140.0 * x3),
                x2 * (420.0 - 1680.0 * x + 2100.0 * x2 - 840.0 * x3),
                x * (840.0 - 5040.0 * x + 8400.0 * x2 - 4200.0 * x3),
            ]
        };
        if r <= 0.0 || (t >= r && t <= self.end - r) {
            [1.0, 0.0, 0.0, 0.0]
        } else if t < r {
            let v = s(t / r);
            [v[0], v[1] / r, v[2] / (r * r), v[3] / (r * r * r)]
        } else if t < self.end {
            let v = s((self.end - t) / r);
            [v[0], -v[1] / r, v[2] / (r * r), -v[3] / (r * r * r)]
        } else {
            [0.0; 4]
        }
    }
}

/// `q_j(t) = o_j + Σ_l a_jl sin(ω_l t) + b_jl (cos(ω_l t) − 1)`, `ω_l = 2π l f₀` (Swevers et al.):
/// what a Fourier excitation tracks and what the excitation design (`super::design`) optimizes;
/// with a [`RestWindow`], the deviation from `o` fades in and out so the motion starts and ends
/// at rest.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct FourierSeries {
    /// Fundamental frequency (Hz).
    pub base_frequency: f64,
    /// `o_j` (rad).
    pub offset: Vec<f64>,
    /// `a_jl` (rad).
    pub sin: Vec<Vec<f64>>,
    /// `b_jl` (rad).
    pub cos: Vec<Vec<f64>>,
    /// The fade in and out to rest, if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub window: Option<RestWindow>,
}

impl FourierSeries {
    /// `(q, q̇, q̈)` at time `t` (s).
    pub fn at(&self, t: f64) -> [Vec<f64>; 3] {
        let [q, qd, qdd, _] = self.with_jerk(t);
        [q, qd, qdd]
    }

    /// `(q, q̇, q̈, q⃛)` at time `t` (s): the periodic deviation `δ` and its derivatives, times
    /// the window by the product rule.
    pub fn with_jerk(&self, t: f64) -> [Vec<f64>; 4] {
        let mut out: [Vec<f64>; 4] = Default::default();
        self.with_jerk_into(t, &mut vec![], &mut out);
        out
    }

    /// [`FourierSeries::with_jerk`] into `out` (cleared first), `waves` a workspace: the same
    /// numbers without allocating once the buffers have grown.
    pub fn with_jerk_into(&self, t: f64, waves: &mut Vec<[f64; 3]>, out: &mut [Vec<f64>; 4]) {
        // Each harmonic's `(ω_l, sin ω_l t, cos ω_l t)`, shared by every joint.
        let harmonics = self.sin.iter().map(Vec::len).max().unwrap_or(0);
        waves.clear();
        waves.extend((0..harmonics).map(|l| {
            let w = self.angular_frequency(l);
            let (s, c) = (w * t).sin_cos();
            [w, s, c]
        }));
        // Per joint, δ and its first three derivatives.
        let deviation = |sin: &[f64], cos: &[f64]| {
            let mut d = [0.0f64; 4];
            for ((a, b), [w, s, c]) in sin.iter().zip(cos).zip(waves.iter()) {
                d[0] += a * s + b * (c - 1.0);
                d[1] += w * (a * c - b * s);
                d[2] -= w * w * (a * s + b * c);
                d[3] -= w * w * w * (a * c - b * s);
            }
            d
        };
        let [w0, w1, w2, w3] = self.window.map_or([1.0, 0.0, 0.0, 0.0], |win| win.at(t));
        out.iter_mut().for_each(Vec::clear);
        for ((o, sin), cos) in self.offset.iter().zip(&self.sin).zip(&self.cos) {
            let d = deviation(sin, cos);
            out[0].push(o + w0 * d[0]);
            out[1].push(w1 * d[0] + w0 * d[1]);
            out[2].push(w2 * d[0] + 2.0 * w1 * d[1] + w0 * d[2]);
            out[3].push(w3 * d[0] + 3.0 * w2 * d[1] + 3.0 * w1 * d[2] + w0 * d[3]);
        }
    }

    /// `ω_l = 2π (l + 1) f₀` (rad/s) of harmonic `l` (from 0).
    pub fn angular_frequency(&self, l: usize) -> f64 {
        2.0 * std::f64::consts::PI * (l + 1) as f64 * self.base_frequency
    }

    /// The periodic series alone, without the fade in and out (the steady motion).
    pub fn steady(&self) -> FourierSeries {
        FourierSeries {
            window: None,
            ..self.clone()
        }
    }

    /// The period `1/f₀` (s).
    pub fn period(&self) -> f64 {
        1.0 / self.base_frequency
    }

    /// Joint `j`'s coefficients times `s`.
    pub fn scale_joint(&mut self, j: usize, s: f64) {
        self.sin[j].iter_mut().for_each(|c| *c *= s);
        self.cos[j].iter_mut().for_each(|c| *c *= s);
    }

    /// Scales each joint so that `max |q_d − offset|` over one period (2,000 points) is its
    /// `amplitude` (rad); a joint that does not move stays still.
    pub fn scale_to(&mut self, amplitude: &[f64]) {
        let period = self.period();
        let mut peak = vec![0.0f64; self.offset.len()];
        for k in 0..2000 {
            let [q, _, _] = self.at(period * k as f64 / 2000.0);
            for (j, p) in peak.iter_mut().enumerate() {
                *p = p.max((q[j] - self.offset[j]).abs());
            }
        }
        for (j, p) in peak.iter().enumerate() {
            self.scale_joint(j, if *p > 0.0 { amplitude[j] / p } else { 0.0 });
        }
    }
}

/// A Fourier series tracked by joint PD or computed torque.
#[derive(Clone, Debug)]
pub struct Fourier {
    series: FourierSeries,
    friction_feedforward: bool,
    kp: Vec<f64>,
    kd: Vec<f64>,
    computed_torque: bool,
}

/// A controller ready to run.
#[derive(Clone, Debug)]
pub enum Controller {
    /// Cartesian impedance on the shell.
    Shell(Shell),
    /// Fourier tracking.
    Fourier(Fourier),
    /// Zero torque.
    Passive,
}

impl Controller {
    /// Builds the controller of a scenario for `model`; `seed` draws the Fourier coefficients.
    ///
    /// `duration` (s) is the experiment's length: a Fourier excitation with a `ramp` comes to
    /// rest at its end.
    pub fn new(
        model: &Model,
        spec: &ExcitationSpec,
        seed: u64,
        duration: f64,
    ) -> Result<Self, ScenarioError> {
        Ok(match spec {
            ExcitationSpec::Shell {
                point,
                center,
                radii,
                a_phi,
                a_theta,
                w_phi,
                w_theta,
                polar_mid,
                polar_amplitude,
                kp,
                kd,
                joint_damping,
                gravity_compensation,
            } => {
                let (body, offset) = match point {
                    Some(p) => (
                        model
                            .bodies()
                            .iter()
                            .position(|b| b.name == p.body)
                            .ok_or_else(|| ScenarioError {
                                key: "excitation.point.body".into(),
                                reason: format!("'{}' is not a body of the robot", p.body),
                            })?,
                        Vector3::from(p.offset),
                    ),
                    None => (model.dof() - 1, Vector3::zeros()),
                };
                Controller::Shell(Shell {
                    body,
                    offset,
                    center: Vector3::from(*center),
                    radii: Vector3::from(*radii),
                    a_phi: *a_phi,
                    a_theta: *a_theta,
                    w_phi: *w_phi,
                    w_theta: *w_theta,
                    polar_mid: *polar_mid,
                    polar_amplitude: *polar_amplitude,
                    kp: Vector3::from(*kp),
                    kd: Vector3::from(*kd),
                    joint_damping: *joint_damping,
                    gravity_compensation: *gravity_compensation,
                })
            }
            ExcitationSpec::Fourier { .. } => {
                Controller::Fourier(fourier(model, spec, seed, duration))
            }
            ExcitationSpec::Passive => Controller::Passive,
        })
    }

    /// A starting state `(q, q̇)`: on target at rest for the shell (inverse kinematics seeded
    /// with `guess`, then deterministic restarts; the best solution inside the joint limits), on
    /// the desired trajectory for Fourier, `guess` at rest for passive.
    pub fn initial_state(
        &self,
        model: &Model,
        data: &mut Data,
        guess: &[f64],
    ) -> Result<(Vec<f64>, Vec<f64>), ScenarioError> {
        let n = model.dof();
        match self {
            Controller::Shell(s) => {
                let (p, _) = s.target(0.0);
                let mut rng = ChaCha8Rng::seed_from_u64(7);
                let mut seeds = vec![guess.to_vec()];
                for _ in 0..40 {
                    seeds.push(
                        model
                            .bodies()
                            .iter()
                            .map(|b| {
                                let (lo, hi) = (b.limits.lower.max(-3.0), b.limits.upper.min(3.0));
                                rng.random_range(lo..=hi)
                            })
                            .collect(),
                    );
                }
                let mut best: Option<(f64, Vec<f64>)> = None;
                for seed in &seeds {
                    let q = solve_ik(model, data, s.body, &s.offset, &p, seed);
                    kinematics::update_world(model, data, &q);
                    let r = (kinematics::point_position(data, s.body, &s.offset) - p).norm();
                    if best.as_ref().is_none_or(|(rb, _)| r < *rb - 1e-9) {
                        best = Some((r, q));
                    }
                    if r < 1e-8 {
                        break;
                    }
                }
                let (r, q) = best.expect("at least one seed");
                if r > 1e-6 {
                    return Err(ScenarioError {
                        key: "excitation".into(),
                        reason: format!(
                            "the shell target's start ({:.3}, {:.3}, {:.3}) m is out of reach within the joint limits (closest {r:.3} m)",
                            p.x, p.y, p.z
                        ),
                    });
                }
                Ok((q, vec![0.0; n]))
            }
            Controller::Fourier(f) => {
                let [q, qd, _] = f.series.at(0.0);
                Ok((q, qd))
            }
            Controller::Passive => Ok((guess.to_vec(), vec![0.0; n])),
        }
    }

    /// Joint torque command (N m) at time `t` from the measured `q`, `q̇`, written into `tau`
    /// (one entry per joint); the shell controller allocates nothing (the simulator calls it
    /// every period).
    pub fn torque_into(
        &self,
        model: &Model,
        data: &mut Data,
        t: f64,
        q: &[f64],
        qd: &[f64],
        tau: &mut [f64],
    ) {
        let n = model.dof();
        match self {
            Controller::Shell(s) => s.torque_into(model, data, t, q, qd, tau),
            Controller::Fourier(f) => {
                let [qd_d, qdd_d_vel, qdd_d] = f.series.at(t);
                let e: Vec<f64> = (0..n).map(|j| qd_d[j] - q[j]).collect();
                let ed: Vec<f64> = (0..n).map(|j| qdd_d_vel[j] - qd[j]).collect();
                if f.computed_torque {
                    let a: Vec<f64> = (0..n)
                        .map(|j| qdd_d[j] + f.kp[j] * e[j] + f.kd[j] * ed[j])
                        .collect();
                    let id = rnea(model, data, q, qd, &a).clone();
                    let out = if f.friction_feedforward {
                        id + physid_core::dynamics::friction_torque(model, &qdd_d_vel)
                    } else {
                        id
                    };
                    tau.copy_from_slice(out.as_slice());
                } else {
                    for j in 0..n {
                        tau[j] = f.kp[j] * e[j] + f.kd[j] * ed[j];
                    }
                }
            }
            Controller::Passive => tau.fill(0.0),
        }
    }
}

/// Damped-least-squares inverse kinematics of a point: joint positions putting `offset` on
/// `body` at `target` (base frame), starting from `guess`, clamped to the joint limits.
pub fn solve_ik(
    model: &Model,
    data: &mut Data,
    body: usize,
    offset: &Vector3<f64>,
    target: &Vector3<f64>,
    guess: &[f64],
) -> Vec<f64> {
    let mut q = guess.to_vec();
    let lambda2 = 1e-4;
    for _ in 0..200 {
        kinematics::update_world(model, data, &q);
        let e = target - kinematics::point_position(data, body, offset);
        if e.norm() < 1e-10 {
            break;
        }
        let j = kinematics::point_jacobian(model, data, body, offset);
        let jjt = &j * j.transpose() + nalgebra::Matrix3::identity() * lambda2;
        let Some(inv) = jjt.try_inverse() else { break };
        let dq = j.transpose() * (inv * e);
        for (i, b) in model.bodies().iter().enumerate() {
            q[i] = (q[i] + dq[i]).clamp(b.limits.lower, b.limits.upper);
        }
    }
    q
}

/// A Fourier series of `harmonics` per joint of `n` about `offset` (rad) with random
/// coefficients decaying as 1/l (seeded by `seed`), not yet scaled.
fn random_series(
    n: usize,
    harmonics: usize,
    base_frequency: f64,
    offset: &[f64],
    seed: u64,
) -> FourierSeries {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_f00d);
    let mut a = vec![vec![0.0; harmonics]; n];
    let mut b = vec![vec![0.0; harmonics]; n];
    for j in 0..n {
        for l in 0..harmonics {
            a[j][l] = rng.random_range(-1.0..1.0) / (l + 1) as f64;
            b[j][l] = rng.random_range(-1.0..1.0) / (l + 1) as f64;
        }
    }
    FourierSeries {
        base_frequency,
        offset: offset.to_vec(),
        sin: a,
        cos: b,
        window: None,
    }
}

/// The Fourier tracking controller of `spec` (given coefficients, or a random draw from `seed`
/// scaled to the amplitudes), its motion coming to rest at `duration` when it has a ramp.
fn fourier(model: &Model, spec: &ExcitationSpec, seed: u64, duration: f64) -> Fourier {
    let ExcitationSpec::Fourier {
        harmonics,
        base_frequency,
        amplitude,
        offset,
        coefficients,
        kp,
        kd,
        computed_torque,
        ramp,
        friction_feedforward,
    } = spec
    else {
        unreachable!("called for a Fourier excitation")
    };
    let ramp = *ramp;
    let tracked = |series| Fourier {
        series,
        friction_feedforward: *friction_feedforward,
        kp: kp.clone(),
        kd: kd.clone(),
        computed_torque: *computed_torque,
    };
    if let Some(c) = coefficients {
        return tracked(FourierSeries {
            base_frequency: *base_frequency,
            offset: offset.clone(),
            sin: c.sin.clone(),
            cos: c.cos.clone(),
            window: ramp.map(|ramp| RestWindow {
                ramp,
                end: duration,
            }),
        });
    }
    let mut series = random_series(model.dof(), *harmonics, *base_frequency, offset, seed);
    series.scale_to(amplitude);
    series.window = ramp.map(|ramp| RestWindow {
        ramp,
        end: duration,
    });
    tracked(series)
}
