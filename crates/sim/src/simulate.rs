//! The ground-truth simulator: closed-loop excitation with friction, torque limits, effects,
//! sensors and offline processing, as on the robot (architecture.md §3).
//!
//! Per control period `[t_k, t_k+1)` (default 1 kHz):
//! 1. the encoder reads `q_enc = round((q + n_q) / step) · step`; the controller's velocity is
//!    the backward difference of `q_enc` (or the truth);
//! 2. the controller computes `τ_cmd` from the measured state; the actuators deliver
//!    `τ_mot = clip(τ_cmd)` (effort, and the back-EMF limit when motor constants are given);
//! 3. `τ_mot` is held while Runge–Kutta (RK4, or Ralston's third order) integrates
//!    `H q̈ = τ_mot + τ_effects(q) − τ_f(q̇) − C q̇ − g` over `substeps` steps, with friction
//!    `τ_f = B q̇ + B_c tanh(q̇ / v_s)`: Coulomb friction
//!    regularized over `v_s` (default 0.01 rad/s), a smooth, documented stand-in for stiction
//!    that the regressor's `sign(q̇)` matches away from zero velocity;
//! 4. the log records the commanded (delivered) torque plus torque-sensing noise and sensor
//!    effects, exactly what the robot logs: its noise acts through the feedback.
//!
//! Offline, the encoder signal is processed into q, q̇, q̈ for identification (zero-phase
//! Butterworth or plain differences). The ground truth (true q, q̇, q̈, τ_mot, friction) is kept
//! beside it.

use super::excitation::Controller;
use super::scenario::{
    EffectSpec, Engine, Processing, Scenario, ScenarioError, SensorSpec, SimulationSpec,
    VelocityFeedback,
};
use physid_core::dynamics::Data;
use physid_core::model::Model;
use physid_core::signal::{butterworth_lowpass, differentiate};
use physid_core::trajectory::{Recording, Trajectory};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// A simulation that cannot run or that failed.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A scenario value is invalid.
    #[error("scenario {0}")]
    Scenario(#[from] ScenarioError),
    /// The state blew up.
    #[error("simulation diverged at t = {t:.4} s: joint '{joint}' {what}")]
    Diverged {
        /// Time (s).
        t: f64,
        /// Joint name.
        joint: String,
        /// What happened.
        what: String,
    },
    /// The recording would not fit in the memory available.
    #[error("{samples} samples of {joints} joints need about {needed_gb:.1} GB, but only {available_gb:.1} GB of memory are available: shorten simulation.duration or lower simulation.rate")]
    TooLarge {
        /// Samples asked for.
        samples: usize,
        /// Joints.
        joints: usize,
        /// Estimated need (GB).
        needed_gb: f64,
        /// Available memory (GB).
        available_gb: f64,
    },
    /// The other engine refused the model.
    #[error("{0}")]
    Engine(String),
    /// Stopped by its caller (`stop` returned true) before the end: nothing is returned.
    #[error("cancelled at t = {t:.3} s")]
    Cancelled {
        /// Time reached (s).
        t: f64,
    },
}

/// Joint torque limit for the motor torque-speed curve: at motor speed `ω = N q̇`, a motor with
/// constant `k_t`, resistance `R` and supply `V` delivers at most `k_t (V ∓ k_t ω) / R` (driving /
/// braking); at the joint that is multiplied by `N`.
fn back_emf_limit(tau: f64, qd: f64, n: f64, kt: f64, r: f64, v: f64) -> f64 {
    let w = (n * qd).abs();
    let driving = tau * qd > 0.0;
    let i_max = if driving {
        (v - kt * w).max(0.0) / r
    } else {
        (v + kt * w) / r
    };
    n.abs() * kt * i_max
}

/// Simulates `scenario` on `model` (the ground truth). `progress(fraction)` is called about a
/// hundred times. Deterministic: the same scenario gives the same numbers.
///
/// The processed signals are wrong near the ends of the recording (the zero-phase filters'
/// one-sided differences and padding, [`settle_samples`] at each end): a fit or a score should
/// leave those samples out, as the sample-size experiment does.
///
/// `stop` is asked at each progress report: when it returns true the run ends with
/// [`SimError::Cancelled`].
pub fn simulate(
    model: &Model,
    scenario: &Scenario,
    progress: &mut dyn FnMut(f64),
    stop: &dyn Fn() -> bool,
) -> Result<Recording, SimError> {
    let n = model.dof();
    scenario.validate(n)?;
    let s = &scenario.simulation;
    let dt = 1.0 / s.rate;
    let h = dt / s.substeps as f64;
    let samples = (s.duration * s.rate).round() as usize;
    check_memory(samples, n)?;
    let controller = Controller::new(model, &scenario.excitation, s.seed, s.duration)?;
    let mut cdata = Data::new(model);
    let guess = initial_guess(model, s);
    let (q0, qd0) = controller.initial_state(model, &mut cdata, &guess)?;
    // The robot as it really is (tilted base, payload); the controller keeps the nominal model.
    let real = super::effects::true_robot(model, &scenario.effects);
    let real = &real;
    let mut engine = integrator(real, s, q0, qd0, h)?;
    let mut sensors = SensorChain::new(model, scenario, dt);
    let motor = motor_of(&scenario.sensors);
    let mut logs = Logs::new(model, samples);
    let loads = Loads { model, scenario };
    // Each period's command, delivered torque and effect torques (N m), reused.
    let (mut cmd, mut tau_mot, mut fx) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut report = Report { samples, done: 0 };
    for k in 0..samples {
        let t = k as f64 / s.rate;
        let (q, qd) = engine.state();
        // 1. Sensors.
        sensors.read(q, qd);
        // 2. Controller and actuators.
        let (q_enc, qd_fb) = (&sensors.q_enc, &sensors.qd_fb);
        controller.torque_into(model, &mut cdata, t, q_enc, qd_fb, &mut cmd);
        actuate_into(model, &cmd, qd, motor, &mut tau_mot);
        // 3. The truth at t_k, then the period integrated with τ_mot held.
        loads.effects_into(q, qd, &tau_mot, &mut fx);
        logs.truth(t, (q, qd), &tau_mot, &loads, &fx);
        let qdd = engine.period(&tau_mot, &loads)?;
        logs.true_acceleration(qdd);
        sensors.log(&tau_mot);
        logs.measured(t, &sensors);
        check_state(model, engine.as_ref(), t + dt, s.max_speed)?;
        report.tick(k, t, progress, stop)?;
    }
    progress(1.0);
    let Logs {
        truth,
        measured,
        friction,
        effects,
        ..
    } = logs;
    recording(truth, (friction, effects), measured, scenario, dt)
}

/// What a run keeps per sample (sample-major): the truth, the friction and effect torques
/// acting on the robot (N m), and the log.
struct Logs {
    truth: Trajectory,
    measured: Trajectory,
    friction: Vec<f64>,
    effects: Vec<f64>,
    /// The log's acceleration, derived after the run ([`recording`]).
    no_qdd: Vec<f64>,
}

impl Logs {
    /// Empty logs with room for `samples` samples of `model`'s joints.
    fn new(model: &Model, samples: usize) -> Self {
        let (names, n) = (model.joint_names(), model.dof());
        Logs {
            truth: Trajectory::with_capacity(names.clone(), true, samples),
            measured: Trajectory::with_capacity(names, true, samples),
            friction: Vec::with_capacity(samples * n),
            effects: Vec::with_capacity(samples * n),
            no_qdd: vec![0.0; n],
        }
    }

    /// The true state, delivered torque, friction and effect torques `fx` at `t`.
    fn truth(
        &mut self,
        t: f64,
        (q, qd): (&[f64], &[f64]),
        tau_mot: &[f64],
        loads: &Loads,
        fx: &[f64],
    ) {
        let friction = (0..qd.len()).map(|j| loads.joint_friction(j, qd[j]));
        self.friction.extend(friction);
        self.effects.extend_from_slice(fx);
        self.truth.push(t, q, qd, None, tau_mot);
    }

    /// The true acceleration at the start of the period just integrated.
    fn true_acceleration(&mut self, qdd: &[f64]) {
        self.truth
            .qdd
            .as_mut()
            .expect("with q̈")
            .extend_from_slice(qdd);
    }

    /// What the robot logged at `t` ([`SensorChain::log`]).
    fn measured(&mut self, t: f64, sensors: &SensorChain) {
        let (q, qd, tau) = (&sensors.q_log, &sensors.qd_fb, &sensors.logged);
        self.measured.push(t, q, qd, Some(&self.no_qdd), tau);
    }
}

/// The recording of a run: the truth, the friction and effect torques per sample (N m,
/// sample-major), what was logged (its acceleration the online velocity's difference) and that
/// log processed as the scenario says.
fn recording(
    truth: Trajectory,
    (friction, effects): (Vec<f64>, Vec<f64>),
    mut measured: Trajectory,
    scenario: &Scenario,
    dt: f64,
) -> Result<Recording, SimError> {
    let n = measured.dof();
    measured.qdd = Some(column_map(&measured.qd, n, |x| differentiate(x, dt)));
    let processed = process(&measured, scenario, dt)?;
    Ok(Recording {
        truth,
        friction,
        effects,
        measured,
        processed,
    })
}

/// The motor's torque constant (N m/A), winding resistance (Ω) and supply voltage (V), when
/// the scenario gives all three (the actuators then saturate at the back-EMF limit).
fn motor_of(se: &super::scenario::SensorSpec) -> Option<(f64, f64, f64)> {
    match (se.motor_kt, se.motor_resistance, se.supply_voltage) {
        (Some(kt), Some(r), Some(v)) => Some((kt, r, v)),
        _ => None,
    }
}

/// What the robot's sensors and its log make of the true state and torque: encoder noise and
/// quantization, the controller's velocity feedback, a torque logged `delay` periods late
/// through the sensor effects plus current-sensing noise, and a motor-side angle through
/// compliance or backlash. Draws its noise from one generator, angles first each sample.
struct SensorChain<'a> {
    spec: &'a SensorSpec,
    effects: &'a [EffectSpec],
    dt: f64,
    rng: ChaCha8Rng,
    enc_noise: Normal<f64>,
    tau_noise: Normal<f64>,
    /// The encoder's angles and the velocity feedback read last (rad, rad/s).
    q_enc: Vec<f64>,
    qd_fb: Vec<f64>,
    /// The angles read the period before, once there is one.
    q_enc_prev: Vec<f64>,
    has_prev: bool,
    /// The angle and torque logged last (rad, N m).
    q_log: Vec<f64>,
    logged: Vec<f64>,
    delay: usize,
    delivered: std::collections::VecDeque<Vec<f64>>,
    dead_zone: Option<super::effects::DeadZone>,
}

impl<'a> SensorChain<'a> {
    fn new(model: &Model, scenario: &'a Scenario, dt: f64) -> Self {
        let spec = &scenario.sensors;
        let n = model.dof();
        let delay = super::effects::delay_samples(&scenario.effects);
        SensorChain {
            spec,
            effects: &scenario.effects,
            dt,
            rng: ChaCha8Rng::seed_from_u64(scenario.simulation.seed),
            enc_noise: Normal::new(0.0, spec.encoder_noise).expect("validated"),
            tau_noise: Normal::new(0.0, spec.torque_noise).expect("validated"),
            q_enc: vec![0.0; n],
            qd_fb: vec![0.0; n],
            q_enc_prev: vec![0.0; n],
            has_prev: false,
            q_log: vec![0.0; n],
            logged: vec![0.0; n],
            delay,
            delivered: std::collections::VecDeque::with_capacity(delay + 1),
            dead_zone: super::effects::DeadZone::new(model, &scenario.effects),
        }
    }

    /// The encoder's angles (noisy, quantized) and the controller's velocity feedback, into
    /// `self.q_enc` and `self.qd_fb`.
    fn read(&mut self, q: &[f64], qd: &[f64]) {
        let step = self.spec.encoder_step;
        let quantize = |x: f64| {
            if step > 0.0 {
                (x / step).round() * step
            } else {
                x
            }
        };
        for (e, &x) in self.q_enc.iter_mut().zip(q) {
            *e = quantize(x + self.enc_noise.sample(&mut self.rng));
        }
        match (self.spec.velocity_feedback, self.has_prev) {
            (VelocityFeedback::FiniteDifference, true) => {
                for ((v, a), b) in self.qd_fb.iter_mut().zip(&self.q_enc).zip(&self.q_enc_prev) {
                    *v = (a - b) / self.dt;
                }
            }
            _ => self.qd_fb.copy_from_slice(qd),
        }
    }

    /// The logged angle and torque (into `self.q_log`, `self.logged`) for the motor torque
    /// `tau_mot` delivered now: the torque delivered `delay` periods ago through the sensor
    /// effects, plus noise; the angle read last ([`SensorChain::read`]) through them.
    fn log(&mut self, tau_mot: &[f64]) {
        // A ring of `delay + 1` torques: the oldest's buffer takes the newest.
        let mut slot = match self.delivered.len() > self.delay {
            true => self.delivered.pop_front().expect("non-empty"),
            false => vec![0.0; tau_mot.len()],
        };
        slot.copy_from_slice(tau_mot);
        self.delivered.push_back(slot);
        let lagged = self.delivered.front().expect("just pushed");
        super::effects::logged_torque_into(self.effects, lagged, &mut self.logged);
        for t in self.logged.iter_mut() {
            *t += self.tau_noise.sample(&mut self.rng);
        }
        let offsets = self.dead_zone.as_mut().map(|d| d.step(tau_mot, self.dt));
        super::effects::logged_angle_into(
            self.effects,
            (&self.q_enc, tau_mot),
            offsets.as_deref(),
            &mut self.q_log,
        );
        self.q_enc_prev.copy_from_slice(&self.q_enc);
        self.has_prev = true;
    }
}

/// A run's progress, reported to its caller at each percent.
struct Report {
    samples: usize,
    /// Percent reported so far.
    done: usize,
}

impl Report {
    /// After sample `k` (time `t`, s): `progress(fraction)` at each new percent, then the end
    /// ([`SimError::Cancelled`]) where `stop` says so.
    fn tick(
        &mut self,
        k: usize,
        t: f64,
        progress: &mut dyn FnMut(f64),
        stop: &dyn Fn() -> bool,
    ) -> Result<(), SimError> {
        let percent = k * 100 / self.samples;
        if percent > self.done {
            self.done = percent;
            progress(k as f64 / self.samples as f64);
            if stop() {
                return Err(SimError::Cancelled { t });
            }
        }
        Ok(())
    }
}

/// Samples the offline processing ([`process`]) needs at each end before what it derives has
/// settled: the filter's settling length for q̈ (two cascaded derivations), 2 for plain
/// differences.
pub fn settle_samples(scenario: &Scenario, rate: f64) -> usize {
    let p = &scenario.processing;
    match p.method {
        Processing::FiniteDifference => 2,
        Processing::Butterworth => butterworth_lowpass(p.order, p.cutoff, rate)
            .map_or(0, |sos| physid_io::prepare::settle_samples(&sos, true)),
    }
}

/// Joint arrays a simulation keeps per sample and joint: the truth (q, q̇, q̈, τ), friction
/// and effects, the measurement and the processed signals (5 each), and the offline
/// processing's working copies, with margin.
const ARRAYS_PER_SAMPLE: usize = 24;

/// Refuses, before allocating, a recording larger than the memory available (Linux's
/// `MemAvailable`; unchecked where it cannot be read).
fn check_memory(samples: usize, joints: usize) -> Result<(), SimError> {
    let needed = (samples as f64) * (joints.max(1) * ARRAYS_PER_SAMPLE * 8 + 8) as f64;
    match physid_io::available_memory() {
        Some(bytes) if needed > bytes => Err(SimError::TooLarge {
            samples,
            joints,
            needed_gb: needed / 1e9,
            available_gb: bytes / 1e9,
        }),
        _ => Ok(()),
    }
}

/// The configuration the controller starts from without `initial_q`: alternating 0.3 and
/// −0.6 rad, within the joint limits.
fn initial_guess(model: &Model, s: &SimulationSpec) -> Vec<f64> {
    match &s.initial_q {
        Some(q) => q.clone(),
        None => model
            .bodies()
            .iter()
            .enumerate()
            .map(|(i, b)| {
                (if i % 2 == 0 { 0.3f64 } else { -0.6 }).clamp(b.limits.lower, b.limits.upper)
            })
            .collect(),
    }
}

/// The engine that integrates the real robot from `(q0, q̇0)` with step `h`.
fn integrator<'a>(
    real: &'a Model,
    s: &SimulationSpec,
    q0: Vec<f64>,
    qd0: Vec<f64>,
    h: f64,
) -> Result<Box<dyn Integrator + 'a>, SimError> {
    Ok(match s.engine {
        Engine::Physid => Box::new(PhysidIntegrator {
            model: real,
            data: Data::new(real),
            stepper: super::RungeKutta::with_method(real.dof(), s.method()),
            qdd: vec![0.0; q0.len()],
            q: q0,
            qd: qd0,
            h,
            substeps: s.substeps,
        }),
        Engine::Rapier => {
            let sim = super::rapier::RapierSim::new(real, &q0, &qd0, h)
                .map_err(|e| SimError::Engine(e.to_string()))?;
            let (q, qd) = sim.state();
            Box::new(RapierIntegrator {
                sim,
                qdd: vec![0.0; q.len()],
                q,
                qd,
                substeps: s.substeps,
                h,
            })
        }
    })
}

/// The torque the actuators deliver for the command `cmd` (N m at the joint): clipped to the
/// effort limit and, with motor constants `(k_t, R, V)`, to the back-EMF limit at speed `q̇`.
fn actuate_into(
    model: &Model,
    cmd: &[f64],
    qd: &[f64],
    motor: Option<(f64, f64, f64)>,
    tau_mot: &mut [f64],
) {
    for (j, out) in tau_mot.iter_mut().enumerate() {
        let b = &model.bodies()[j];
        let mut lim = b.limits.effort;
        if let (Some((kt, r, v)), Some(rot)) = (motor, &b.rotor) {
            lim = lim.min(back_emf_limit(cmd[j], qd[j], rot.gear_ratio, kt, r, v));
        }
        *out = cmd[j].clamp(-lim, lim);
    }
}

/// The engine's state at time `t` is finite and below `max_speed`, or the simulation diverged.
fn check_state(
    model: &Model,
    engine: &dyn Integrator,
    t: f64,
    max_speed: f64,
) -> Result<(), SimError> {
    let (q, qd) = engine.state();
    for j in 0..model.dof() {
        if !q[j].is_finite() || !qd[j].is_finite() || qd[j].abs() > max_speed {
            return Err(SimError::Diverged {
                t,
                joint: model.bodies()[j].joint_name.clone(),
                what: format!(
                    "reached q = {:.4} rad, q̇ = {:.4} rad/s (limit {} rad/s)",
                    q[j], qd[j], max_speed
                ),
            });
        }
    }
    Ok(())
}

/// Friction and physical effects, shared by the engines.
pub(crate) struct Loads<'a> {
    model: &'a Model,
    scenario: &'a Scenario,
}

impl Loads<'_> {
    /// `B q̇ + B_c tanh(q̇ / v_s)` of joint `j` at speed `w` (N m).
    fn joint_friction(&self, j: usize, w: f64) -> f64 {
        let f = &self.model.bodies()[j].friction;
        f.viscous * w + f.coulomb * (w / self.scenario.simulation.friction_velocity).tanh()
    }
    /// Torque of the injected physical effects (N m), into `out`.
    fn effects_into(&self, q: &[f64], qd: &[f64], tau_mot: &[f64], out: &mut [f64]) {
        let vs = self.scenario.simulation.friction_velocity;
        let effects = &self.scenario.effects;
        super::effects::physical_torque_into(effects, self.model, (q, qd), tau_mot, vs, out);
    }
    /// Net generalized force on the joints for a held motor torque.
    fn net(&self, tau_mot: &[f64], q: &[f64], qd: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; q.len()];
        self.net_into(tau_mot, q, qd, &mut out);
        out
    }
    /// [`Loads::net`] written into `out`, without allocating: `τ_mot + τ_effects − τ_f` (N m).
    fn net_into(&self, tau_mot: &[f64], q: &[f64], qd: &[f64], out: &mut [f64]) {
        self.effects_into(q, qd, tau_mot, out);
        for j in 0..qd.len() {
            out[j] = tau_mot[j] + out[j] - self.joint_friction(j, qd[j]);
        }
    }
}

/// An engine that advances the robot one control period at a time.
trait Integrator {
    /// Current `(q, q̇)`.
    fn state(&self) -> (&[f64], &[f64]);
    /// Integrates one control period with `tau_mot` held; returns the true `q̈` at its start.
    fn period(&mut self, tau_mot: &[f64], loads: &Loads) -> Result<&[f64], SimError>;
}

/// physid's forward dynamics with an explicit Runge–Kutta method (the scenario's
/// `integrator`); the true `q̈` at the start of a period is the first substep's first slope.
struct PhysidIntegrator<'a> {
    model: &'a Model,
    data: Data,
    stepper: super::RungeKutta,
    q: Vec<f64>,
    qd: Vec<f64>,
    /// The true `q̈` at the start of the last period.
    qdd: Vec<f64>,
    h: f64,
    substeps: usize,
}

impl Integrator for PhysidIntegrator<'_> {
    fn state(&self) -> (&[f64], &[f64]) {
        (&self.q, &self.qd)
    }
    fn period(&mut self, tau_mot: &[f64], loads: &Loads) -> Result<&[f64], SimError> {
        let mut force =
            |_t: f64, q: &[f64], qd: &[f64], u: &mut [f64]| loads.net_into(tau_mot, q, qd, u);
        for m in 0..self.substeps {
            self.stepper
                .step(
                    self.model,
                    &mut self.data,
                    0.0,
                    &mut self.q,
                    &mut self.qd,
                    self.h,
                    &mut force,
                )
                .map_err(|e| SimError::Engine(e.to_string()))?;
            if m == 0 {
                self.qdd.copy_from_slice(self.stepper.start_acceleration());
            }
        }
        Ok(&self.qdd)
    }
}

/// rapier3d's multibody solver (first-order); the true `q̈` at the start of a period is the
/// velocity change of its first step over the step, constraint impulses (the gears) included.
struct RapierIntegrator {
    sim: super::rapier::RapierSim,
    /// The state read from `sim` after the last period (rad, rad/s).
    q: Vec<f64>,
    qd: Vec<f64>,
    /// The true `q̈` at the start of the last period.
    qdd: Vec<f64>,
    substeps: usize,
    h: f64,
}

impl Integrator for RapierIntegrator {
    fn state(&self) -> (&[f64], &[f64]) {
        (&self.q, &self.qd)
    }
    fn period(&mut self, tau_mot: &[f64], loads: &Loads) -> Result<&[f64], SimError> {
        for m in 0..self.substeps {
            self.sim
                .step_with_torque(&loads.net(tau_mot, &self.q, &self.qd));
            let (q, qd) = self.sim.state();
            if m == 0 {
                for ((a, v1), v0) in self.qdd.iter_mut().zip(&qd).zip(&self.qd) {
                    *a = (v1 - v0) / self.h;
                }
            }
            (self.q, self.qd) = (q, qd);
        }
        Ok(&self.qdd)
    }
}

/// Applies `f` to each joint's column of sample-major data.
fn column_map(v: &[f64], n: usize, f: impl Fn(&[f64]) -> Vec<f64>) -> Vec<f64> {
    let m = v.len() / n;
    let mut out = vec![0.0; v.len()];
    for j in 0..n {
        let col: Vec<f64> = (0..m).map(|k| v[k * n + j]).collect();
        for (k, x) in f(&col).into_iter().enumerate() {
            out[k * n + j] = x;
        }
    }
    out
}

/// Offline processing of the logged encoder positions and torques (see [`Processing`]).
pub fn process(
    measured: &Trajectory,
    scenario: &Scenario,
    dt: f64,
) -> Result<Trajectory, SimError> {
    let n = measured.dof();
    let p = &scenario.processing;
    // The times, names and torque as logged; q, q̇, q̈ (and τ if filtered) replaced below.
    let mut out = Trajectory {
        joint_names: measured.joint_names.clone(),
        t: measured.t.clone(),
        q: vec![],
        qd: vec![],
        qdd: None,
        tau: measured.tau.clone(),
        starts: measured.starts.clone(),
        margins: measured.margins.clone(),
    };
    match p.method {
        Processing::FiniteDifference => {
            out.q = measured.q.clone();
            out.qd = column_map(&measured.q, n, |x| differentiate(x, dt));
            out.qdd = Some(column_map(&out.qd, n, |x| differentiate(x, dt)));
        }
        Processing::Butterworth => {
            let sos =
                butterworth_lowpass(p.order, p.cutoff, 1.0 / dt).map_err(|e| ScenarioError {
                    key: "processing".into(),
                    reason: e.to_string(),
                })?;
            out.q = column_map(&measured.q, n, |x| sos.filtfilt(x));
            out.qd = column_map(&measured.q, n, |x| sos.filtfilt(&differentiate(x, dt)));
            out.qdd = Some(column_map(&out.qd, n, |x| {
                sos.filtfilt(&differentiate(x, dt))
            }));
            if p.filter_torque {
                out.tau = column_map(&measured.tau, n, |x| sos.filtfilt(x));
            }
        }
    }
    Ok(out)
}
