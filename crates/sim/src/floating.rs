//! A floating-base robot standing on flat ground and shifting its weight, simulated with a
//! stated contact model, for identification with ground truth.
//!
//! **Contact model.** Each foot is a point; the ground is the plane `z = 0` of the world. A foot
//! below it by `δ > 0` feels a normal force `λ_n = max(0, k δ − c ż)` (a spring and damper,
//! `k` N/m, `c` N s/m) and a tangential force `λ_t = −μ λ_n v_t / max(‖v_t‖, v_s)`: Coulomb
//! friction, regularized below the slip speed `v_s` (m/s) so that a foot at rest is held by a
//! stiff viscous force instead of chattering. Forces act at the foot point, world coordinates.
//!
//! **Robot and controller.** The trunk is free; every joint is driven by a PD law towards a
//! posture `q*(t)` (standing, plus three whole-body modes at distinct frequencies that sway,
//! pitch and lower the trunk while the feet stay down), updated at the control rate and
//! held between updates; the joints feel viscous friction and Coulomb friction smoothed as
//! `B_c tanh(q̇ / v_f)`. The robot is a quadruped with three joints per leg in
//! Cheetah-Software's leg order.
//!
//! **Integration.** Semi-implicit Euler at `substeps` steps per control period:
//! `ν̇ = M⁻¹ ([0; τ − τ_f] + Σ J_cᵀ λ_c − h)` ([`crba_floating`], [`rnea_floating`]), then
//! `ν ← ν + ν̇ dt`, `q ← q + q̇ dt`, `p ← p + R v dt`, `R ← R exp([ω] dt)`.
//!
//! **Recorded**, at every control step: the trunk's pose, twist and acceleration `ν̇` of that
//! instant, `q, q̇, q̈`, the torque each joint's motor applies (the controller's `τ`, friction
//! not subtracted: what a current sensor reads) and each foot's contact force. The truth is
//! the model simulated; nothing is noisy here.

use nalgebra::{DVector, Matrix3, Vector3};
use physid_core::dynamics::{
    crba_floating, kinematics, point_jacobian_floating, rnea_floating, stacked, BaseState, Data,
};
use physid_core::model::floating::FloatingModel;
use physid_core::spatial::{rot_axis_angle, Motion, Transform};

/// The ground and the feet's contact with it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ground {
    /// Normal stiffness `k` (N/m).
    pub stiffness: f64,
    /// Normal damping `c` (N s/m).
    pub damping: f64,
    /// Friction coefficient `μ`.
    pub friction: f64,
    /// Slip speed `v_s` (m/s) below which friction is viscous.
    pub slip_speed: f64,
}

impl Default for Ground {
    fn default() -> Self {
        Self {
            stiffness: 5e4,
            damping: 1e3,
            friction: 0.8,
            slip_speed: 0.01,
        }
    }
}

/// A standing, weight-shifting experiment.
#[derive(Clone, Debug, PartialEq)]
pub struct Standing {
    /// Duration (s).
    pub duration: f64,
    /// Control and recording rate (Hz).
    pub rate: f64,
    /// Integration steps per control period.
    pub substeps: usize,
    /// Standing posture per leg `[ab/ad, hip, knee]` (rad).
    pub posture: [f64; 3],
    /// Amplitudes of the whole-body modes `[sway, pitch, heave]` (rad: of ab/ad, then of the
    /// hip's crouch; see `Targets`).
    pub amplitude: [f64; 3],
    /// PD gains `(k_p N m/rad, k_d N m s/rad)`.
    pub gains: (f64, f64),
    /// Speed of the joints' Coulomb smoothing `v_f` (rad/s).
    pub friction_velocity: f64,
    /// The ground.
    pub ground: Ground,
    /// Trotting in place: each diagonal pair of legs (front right with hind left, front left
    /// with hind right) in turn crouched by up to `step.0` rad of the hip (the knee twice
    /// that: the foot rises under its hip) for half of each cycle of `step.1` Hz, so that its
    /// feet leave the ground while the other pair carries the robot. `(0, 0)`: standing.
    pub step: (f64, f64),
    /// Seeds the frequencies and phases of the sinusoids.
    pub seed: u64,
    /// How the run starts: standing on the ground at rest, or dropped, or pushed.
    pub start: Start,
}

/// The robot's state at `t = 0`: its standing posture, the trunk level, its lowest foot
/// `height` above the ground and the whole robot moving at `velocity` (a drop, a push).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Start {
    /// The lowest foot's height above the ground (m; 0: on it).
    pub height: f64,
    /// The trunk's velocity, world axes (m/s); the joints at rest.
    pub velocity: [f64; 3],
}

impl Start {
    /// `Err` naming the field out of range.
    fn check(&self) -> Result<(), FloatingSimError> {
        let Start { height, velocity } = *self;
        let speed = Vector3::from(velocity).norm();
        if !(height.is_finite() && (0.0..=MAX_START_HEIGHT).contains(&height)) {
            return Err(FloatingSimError::Invalid(format!(
                "start.height must be 0 to {MAX_START_HEIGHT} m, got {height}"
            )));
        }
        if !(speed.is_finite() && speed <= MAX_START_SPEED) {
            return Err(FloatingSimError::Invalid(format!(
                "start.velocity {velocity:?}: its speed must be at most {MAX_START_SPEED} m/s"
            )));
        }
        Ok(())
    }
}

/// The highest start [`Start::height`] (m).
pub const MAX_START_HEIGHT: f64 = 0.5;
/// The fastest start [`Start::velocity`] (m/s).
pub const MAX_START_SPEED: f64 = 5.0;

impl Default for Standing {
    fn default() -> Self {
        Self {
            duration: 5.0,
            rate: 1000.0,
            substeps: 10,
            posture: [0.0, -0.8, 1.6],
            amplitude: [0.1, 0.06, 0.1],
            gains: (400.0, 8.0),
            friction_velocity: 0.01,
            ground: Ground::default(),
            step: (0.0, 0.0),
            seed: 1,
            start: Start::default(),
        }
    }
}

/// What a floating-base run records, one entry per control step.
#[derive(Clone, Debug, Default)]
pub struct FloatingRun {
    /// Time (s).
    pub t: Vec<f64>,
    /// The trunk's pose, twist and acceleration.
    pub base: Vec<BaseState>,
    /// Joint positions (rad), `n` per step.
    pub q: Vec<f64>,
    /// Joint velocities (rad/s).
    pub qd: Vec<f64>,
    /// Joint accelerations (rad/s²).
    pub qdd: Vec<f64>,
    /// Motor torques at the joints (N m).
    pub tau: Vec<f64>,
    /// Contact force of each foot at the step's instant (world coordinates, N), `feet` per
    /// step.
    pub contact: Vec<Vector3<f64>>,
    /// Each foot's contact force averaged over the two control periods around the step (the
    /// integration's substeps from `t − 1/rate` to `t + 1/rate`): what a force sensor read
    /// through an anti-aliasing filter reports. A stiff contact's force changes within a
    /// substep; sampled at the instant it aliases, and the twist's central difference over the
    /// same two periods is the mean acceleration this force produces.
    pub contact_mean: Vec<Vector3<f64>>,
    /// The trunk's specific force `Rᵀ (p̈ − g)` at its frame's origin (trunk coordinates,
    /// m/s²) averaged over the same two control periods around the step: what an IMU's
    /// accelerometer reports through its anti-aliasing filter (a touchdown changes the
    /// acceleration within a substep, as it does the force).
    pub specific_force_mean: Vec<Vector3<f64>>,
    /// Joints per step.
    pub joints: usize,
    /// Feet: `(body, point in the body)`, in the order of `contact`.
    pub feet: Vec<(usize, Vector3<f64>)>,
    /// Gravity (m/s², world).
    pub gravity: Vector3<f64>,
}

impl FloatingRun {
    /// Steps recorded.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// Whether nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// `(q, q̇, q̈)` of step `k`.
    pub fn joints_at(&self, k: usize) -> (&[f64], &[f64], &[f64]) {
        let r = k * self.joints..(k + 1) * self.joints;
        (&self.q[r.clone()], &self.qd[r.clone()], &self.qdd[r])
    }

    /// Motor torques of step `k`.
    pub fn tau_at(&self, k: usize) -> &[f64] {
        &self.tau[k * self.joints..(k + 1) * self.joints]
    }

    /// Contact forces of step `k`, one per foot.
    pub fn contact_at(&self, k: usize) -> &[Vector3<f64>] {
        let f = self.feet.len();
        &self.contact[k * f..(k + 1) * f]
    }
}

/// Why a floating-base simulation stopped.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FloatingSimError {
    /// An option out of its range.
    #[error("floating-base simulation: {0}")]
    Invalid(String),
    /// The robot fell over: the run no longer stands for the motion asked.
    #[error("the robot fell at t = {t:.3} s (trunk tilted {tilt:.0}°, its origin {height:.3} m above the ground): ask for a gentler motion")]
    Fell {
        /// Time (s).
        t: f64,
        /// The trunk's tilt from upright (degrees).
        tilt: f64,
        /// The trunk origin's height (m).
        height: f64,
    },
    /// The mass matrix lost positive definiteness or the state became non-finite.
    #[error("floating-base simulation diverged at t = {t:.4} s ({what})")]
    Diverged {
        /// Time (s).
        t: f64,
        /// What went wrong.
        what: &'static str,
    },
}

/// The simulation's state: the trunk's pose and twist, the joints'.
struct State {
    rot: Matrix3<f64>,
    pos: Vector3<f64>,
    v: Motion,
    q: Vec<f64>,
    qd: Vec<f64>,
}

impl State {
    fn base(&self, a: Motion) -> BaseState {
        BaseState {
            pose: Transform::from_pose(&self.rot, &self.pos),
            v: self.v,
            a,
        }
    }
}

/// Runs `experiment` on `robot`, whose feet are the points `feet` (`(body, point in the body)`).
pub fn standing(
    robot: &FloatingModel,
    feet: &[(usize, Vector3<f64>)],
    experiment: &Standing,
) -> Result<FloatingRun, FloatingSimError> {
    check(robot, feet, experiment)?;
    let n = robot.joints();
    let mut data = Data::new(robot.tree());
    let targets = experiment.targets(n);
    let mut state = initial_state(robot, &mut data, feet, experiment);
    let mut run = FloatingRun {
        joints: n,
        feet: feet.to_vec(),
        gravity: robot.tree().gravity(),
        ..Default::default()
    };
    let steps = (experiment.duration * experiment.rate).round() as usize;
    let dt = 1.0 / (experiment.rate * experiment.substeps as f64);
    let mut period_means = Vec::with_capacity(steps * feet.len());
    let mut period_forces = Vec::with_capacity(steps);
    for k in 0..steps {
        let t = k as f64 / experiment.rate;
        let tau = experiment.motor_torques(&state.q, &state.qd, &targets.at(t));
        let mut sum = vec![Vector3::zeros(); feet.len()];
        let mut specific = Vector3::zeros();
        for s in 0..experiment.substeps {
            let (nu_dot, contact) = accelerations(robot, &mut data, &state, &tau, feet, experiment)
                .ok_or(FloatingSimError::Diverged {
                    t: t + s as f64 * dt,
                    what: "the mass matrix is not positive definite or the state is not finite",
                })?;
            if s == 0 {
                record(&mut run, t, &state, &nu_dot, &tau, &contact);
            }
            sum.iter_mut().zip(&contact).for_each(|(a, f)| *a += f);
            specific += specific_force(&state, &nu_dot, &run.gravity);
            step(&mut state, &nu_dot, dt);
        }
        period_means.extend(sum.iter().map(|f| f / experiment.substeps as f64));
        period_forces.push(specific / experiment.substeps as f64);
        fallen(&state, t)?;
    }
    run.contact_mean = around_steps(&period_means, feet.len());
    run.specific_force_mean = around_steps(&period_forces, 1);
    Ok(run)
}

/// The trunk's specific force `Rᵀ (p̈ − g) = a + ω × v − Rᵀ g` at `state` with accelerations
/// `nu_dot` (trunk coordinates, m/s²; `a`, `ω`, `v` the spatial acceleration and twist).
fn specific_force(state: &State, nu_dot: &DVector<f64>, g: &Vector3<f64>) -> Vector3<f64> {
    let a = Motion::from_vec6(&nu_dot.fixed_rows::<6>(0).into_owned());
    a.lin + state.v.ang.cross(&state.v.lin) - state.rot.transpose() * g
}

/// `Err` when the robot has fallen: its trunk tilted more than 60° or its origin below 5 cm.
fn fallen(state: &State, t: f64) -> Result<(), FloatingSimError> {
    let up = state.rot[(2, 2)];
    if up < 0.5 || state.pos.z < 0.05 {
        return Err(FloatingSimError::Fell {
            t,
            tilt: up.clamp(-1.0, 1.0).acos().to_degrees(),
            height: state.pos.z,
        });
    }
    Ok(())
}

/// Per step `k` and foot, the mean of the periods before and after it (`period_means` holds
/// period `k`'s, which starts at step `k`; before the first step, the first period's).
fn around_steps(period_means: &[Vector3<f64>], feet: usize) -> Vec<Vector3<f64>> {
    (0..period_means.len())
        .map(|i| {
            let before = if i >= feet { i - feet } else { i };
            (period_means[before] + period_means[i]) * 0.5
        })
        .collect()
}

/// Checks an experiment on `robot` with `feet` (`Err` naming the field out of range).
pub fn check(
    robot: &FloatingModel,
    feet: &[(usize, Vector3<f64>)],
    e: &Standing,
) -> Result<(), FloatingSimError> {
    let bad = |m: String| Err(FloatingSimError::Invalid(m));
    let positive = [
        ("duration", e.duration),
        ("rate", e.rate),
        ("friction_velocity", e.friction_velocity),
        ("ground.stiffness", e.ground.stiffness),
        ("ground.slip_speed", e.ground.slip_speed),
    ];
    if let Some((name, v)) = positive.iter().find(|(_, v)| !(v.is_finite() && *v > 0.0)) {
        return bad(format!("{name} must be a positive number, got {v}"));
    }
    let nonnegative = [
        ("ground.damping", e.ground.damping),
        ("ground.friction", e.ground.friction),
        ("gains.kp", e.gains.0),
        ("gains.kd", e.gains.1),
    ];
    if let Some((name, v)) = nonnegative
        .iter()
        .find(|(_, v)| !(v.is_finite() && *v >= 0.0))
    {
        return bad(format!("{name} must be a number >= 0, got {v}"));
    }
    let (height, hz) = e.step;
    if !(height.is_finite()
        && (0.0..=0.5).contains(&height)
        && hz.is_finite()
        && (0.0..=5.0).contains(&hz))
    {
        return bad(format!(
            "step ({height}, {hz}): the crouch must be 0 to 0.5 rad and the frequency 0 to 5 Hz"
        ));
    }
    e.start.check()?;
    if e.substeps == 0 || e.duration * e.rate > 1e7 {
        return bad("substeps must be at least 1 and duration × rate at most 1e7".into());
    }
    if robot.joints() % 3 != 0 {
        return bad(format!(
            "the robot has {} joints, not three per leg",
            robot.joints()
        ));
    }
    if let Some((b, _)) = feet.iter().find(|(b, _)| *b >= robot.joints()) {
        return bad(format!(
            "foot on body {b}, but the robot has {} bodies",
            robot.joints()
        ));
    }
    Ok(())
}

/// The posture's motion: three whole-body modes, each a sinusoid of its own frequency and
/// phase (from the seed) that moves every leg's joints together so that the feet can stay where
/// they are: sway (every ab/ad turning the same way, which pushes the trunk sideways and rolls
/// it), pitch (front legs crouch as hind legs extend) and heave (all legs crouch; a crouch of
/// `d` is `Δhip = −d`, `Δknee = 2d`, which keeps a two-link foot under its hip). The
/// amplitudes are `amplitude`'s: `[sway, pitch, heave]` (rad). A roll mode (left legs against
/// right) was tried: with the ab/ad joints held, it tipped the robot over within two seconds.
pub struct Targets {
    posture: Vec<f64>,
    amplitude: [f64; 3],
    omega: [f64; 3],
    phase: [f64; 3],
    step: (f64, f64),
}

/// Leg `l`'s signs in Cheetah-Software order (front right, front left, hind right, hind left):
/// `(front, left)`.
fn leg_signs(l: usize) -> (f64, f64) {
    let front = if l < 2 { 1.0 } else { -1.0 };
    let left = if l % 2 == 1 { 1.0 } else { -1.0 };
    (front, left)
}

impl Targets {
    fn new(n: usize, e: &Standing) -> Self {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(e.seed);
        let tau = std::f64::consts::TAU;
        let base_hz = [0.45, 0.65, 0.85];
        Self {
            posture: (0..n).map(|j| e.posture[j % 3]).collect(),
            amplitude: e.amplitude,
            omega: base_hz.map(|f| tau * f * rng.random_range(0.85..1.15)),
            phase: [(); 3].map(|_| rng.random_range(0.0..tau)),
            step: (e.step.0, tau * e.step.1),
        }
    }

    /// Leg `l`'s step crouch `(d, ḋ)` at `t` (rad, rad/s): `h sin²(ω t / 2 + φ)` over the half
    /// cycles where it is positive-going for its diagonal pair, zero otherwise (`φ` puts the
    /// two pairs half a cycle apart), faded in with the modes.
    fn step(&self, l: usize, t: f64, fade: (f64, f64)) -> (f64, f64) {
        let (h, omega) = self.step;
        if h == 0.0 || omega == 0.0 {
            return (0.0, 0.0);
        }
        let pair = if l == 0 || l == 3 {
            0.0
        } else {
            std::f64::consts::PI
        };
        let x = omega * t + pair;
        let (s, c) = x.sin_cos();
        if s <= 0.0 {
            return (0.0, 0.0);
        }
        // h s² lifts from and returns to zero with zero slope.
        let (d, dd) = (h * s * s, 2.0 * h * s * c * omega);
        (fade.0 * d, fade.0 * dd + fade.1 * d)
    }

    /// `(q*, q̇*)` at `t` (s), faded in over the first second.
    pub fn at(&self, t: f64) -> (Vec<f64>, Vec<f64>) {
        let half_pi = std::f64::consts::FRAC_PI_2;
        let fade = (t.min(1.0) * half_pi).sin().powi(2);
        let fade_rate = if t < 1.0 {
            half_pi * (2.0 * t * half_pi).sin()
        } else {
            0.0
        };
        let mode = |m: usize| {
            let x = self.omega[m] * t + self.phase[m];
            (fade * x.sin(), fade * self.omega[m] * x.cos())
        };
        let [sway, pitch, heave] = [0, 1, 2].map(mode);
        let [a_sway, a_pitch, a_heave] = self.amplitude;
        let (mut q, mut qd) = (self.posture.clone(), vec![0.0; self.posture.len()]);
        for l in 0..q.len() / 3 {
            let (front, left) = leg_signs(l);
            let crouch = |k: usize| {
                a_heave * [heave.0, heave.1][k] + a_pitch * front * [pitch.0, pitch.1][k]
            };
            // Mirrored ab/ad axes: the same physical turn is +s on the left, −s on the right.
            q[3 * l] += left * a_sway * sway.0;
            qd[3 * l] = left * a_sway * sway.1;
            let (d, dd) = self.step(l, t, (fade, fade_rate));
            q[3 * l + 1] -= crouch(0) + d;
            qd[3 * l + 1] = -crouch(1) - dd;
            q[3 * l + 2] += 2.0 * (crouch(0) + d);
            qd[3 * l + 2] = 2.0 * (crouch(1) + dd);
        }
        (q, qd)
    }
}

impl Standing {
    /// The controller's posture targets for a robot of `joints` joints (three per leg).
    pub fn targets(&self, joints: usize) -> Targets {
        Targets::new(joints, self)
    }

    /// The PD law's motor torques (N m) at joint angles `q` (rad) and rates `qd` (rad/s)
    /// towards the targets `(q*, q̇*)`: `k_p (q* − q) + k_d (q̇* − q̇)`.
    pub fn motor_torques(
        &self,
        q: &[f64],
        qd: &[f64],
        (q_star, qd_star): &(Vec<f64>, Vec<f64>),
    ) -> Vec<f64> {
        let (kp, kd) = self.gains;
        (0..q.len())
            .map(|j| kp * (q_star[j] - q[j]) + kd * (qd_star[j] - qd[j]))
            .collect()
    }

    /// The joints' friction torques (N m) at rates `qd` (rad/s): each body's viscous term and
    /// its Coulomb term smoothed as `B_c tanh(q̇ / v_f)`.
    pub fn joint_friction(&self, robot: &FloatingModel, qd: &[f64]) -> Vec<f64> {
        robot
            .tree()
            .bodies()
            .iter()
            .zip(qd)
            .map(|(b, w)| {
                b.friction.viscous * w + b.friction.coulomb * (w / self.friction_velocity).tanh()
            })
            .collect()
    }

    /// Where the run starts: the trunk origin's world position (m; the trunk level) and the
    /// joint angles (rad, the standing posture), the lowest foot [`Start::height`] above the
    /// ground.
    pub fn initial_pose(
        &self,
        robot: &FloatingModel,
        data: &mut Data,
        feet: &[(usize, Vector3<f64>)],
    ) -> (Vector3<f64>, Vec<f64>) {
        let q: Vec<f64> = (0..robot.joints()).map(|j| self.posture[j % 3]).collect();
        kinematics::update_world(robot.tree(), data, &q);
        let lowest = feet
            .iter()
            .map(|(b, p)| kinematics::point_position(data, *b, p).z)
            .fold(f64::INFINITY, f64::min);
        (Vector3::new(0.0, 0.0, self.start.height - lowest), q)
    }
}

/// The robot in its standing posture, trunk level, its lowest foot on the ground or
/// [`Start::height`] above it, moving at [`Start::velocity`].
fn initial_state(
    robot: &FloatingModel,
    data: &mut Data,
    feet: &[(usize, Vector3<f64>)],
    e: &Standing,
) -> State {
    let (pos, q) = e.initial_pose(robot, data, feet);
    // Level: the trunk's axes are the world's, so its twist's linear part is the velocity.
    State {
        rot: Matrix3::identity(),
        pos,
        v: Motion::new(Vector3::zeros(), Vector3::from(e.start.velocity)),
        qd: vec![0.0; q.len()],
        q,
    }
}

/// `ν̇` at `state` under the motor torques `tau` and the contact forces it causes (returned,
/// one per foot); `None` if the mass matrix is not positive definite or a value not finite.
fn accelerations(
    robot: &FloatingModel,
    data: &mut Data,
    state: &State,
    tau: &[f64],
    feet: &[(usize, Vector3<f64>)],
    e: &Standing,
) -> Option<(DVector<f64>, Vec<Vector3<f64>>)> {
    let n = robot.joints();
    let base = state.base(Motion::zero());
    let nu = DVector::from_iterator(6 + n, base.v.to_vec6().iter().chain(&state.qd).copied());
    let mut generalized = DVector::zeros(6 + n);
    for (j, f) in e.joint_friction(robot, &state.qd).iter().enumerate() {
        generalized[6 + j] = tau[j] - f;
    }
    let mut contact = Vec::with_capacity(feet.len());
    for &(body, ref p) in feet {
        let jac = point_jacobian_floating(robot, data, &base, &state.q, (body, p));
        let p_w = base
            .pose
            .point_to_a(&kinematics::point_position(data, body, p));
        let v_w = &jac * &nu;
        let force = ground_force(&e.ground, &p_w, &Vector3::new(v_w[0], v_w[1], v_w[2]));
        generalized += jac.transpose() * DVector::from_column_slice(force.as_slice());
        contact.push(force);
    }
    let h_b = rnea_floating(robot, data, &base, &state.q, &state.qd, &vec![0.0; n]);
    let h = stacked(&h_b, &data.tau);
    let m = crba_floating(robot, data, &state.q);
    let nu_dot = m.cholesky()?.solve(&(generalized - h));
    nu_dot
        .iter()
        .all(|v| v.is_finite())
        .then_some((nu_dot, contact))
}

/// The ground's force on a foot at world position `p` (m) moving at `v` (m/s).
fn ground_force(g: &Ground, p: &Vector3<f64>, v: &Vector3<f64>) -> Vector3<f64> {
    let depth = -p.z;
    if depth <= 0.0 {
        return Vector3::zeros();
    }
    let normal = (g.stiffness * depth - g.damping * v.z).max(0.0);
    let slip = Vector3::new(v.x, v.y, 0.0);
    let tangential = -slip * (g.friction * normal / slip.norm().max(g.slip_speed));
    tangential + Vector3::z() * normal
}

fn record(
    run: &mut FloatingRun,
    t: f64,
    state: &State,
    nu_dot: &DVector<f64>,
    tau: &[f64],
    contact: &[Vector3<f64>],
) {
    let a = Motion::from_vec6(&nu_dot.fixed_rows::<6>(0).into_owned());
    run.t.push(t);
    run.base.push(state.base(a));
    run.q.extend(&state.q);
    run.qd.extend(&state.qd);
    run.qdd.extend(nu_dot.rows(6, state.q.len()).iter());
    run.tau.extend(tau);
    run.contact.extend(contact);
}

/// Semi-implicit Euler: velocities first, then positions with the new velocities.
fn step(state: &mut State, nu_dot: &DVector<f64>, dt: f64) {
    let a = Motion::from_vec6(&nu_dot.fixed_rows::<6>(0).into_owned());
    state.v += a * dt;
    for j in 0..state.q.len() {
        state.qd[j] += nu_dot[6 + j] * dt;
        state.q[j] += state.qd[j] * dt;
    }
    state.pos += state.rot * state.v.lin * dt;
    let w = state.v.ang * dt;
    if w.norm() > 0.0 {
        state.rot *= rot_axis_angle(&w.normalize(), w.norm());
    }
}
