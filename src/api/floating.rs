//! The whole robot from its logs: a floating-base run simulated and logged as a robot's sensors
//! write it ([`simulate_floating`]), and a floating robot identified from such a log
//! ([`identify_floating`]) in one of the three data settings, under one constraint set, its
//! description the prior (docs/floating-base.md, "From a log").

use super::model::RobotOptions;
use super::ApiError;
use crate::ident::floating::DataSetting;
use crate::ident::floating_log::{log_samples, LogSamples, LogSampling};
use crate::ident::{ConstraintSet, IdentifiedBody, NormalEquations, SolveStatus};
use crate::io::floating_log::{self, FloatingLog};
use crate::io::floating_mcap;
pub use crate::io::floating_mcap::FloatingReadOptions;
use crate::model::floating::FloatingModel;
use crate::sim::floating::{Start, MAX_START_HEIGHT, MAX_START_SPEED};
/// The sensors a floating run is logged through.
pub use crate::sim::floating_sensors::Sensors;
use nalgebra::{DVector, Vector3};
use std::path::{Path, PathBuf};

/// A foot: a point fixed in a body, where the ground pushes.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct Foot {
    /// The body's name (its log columns are `force_<body>_x` … and `contact_<body>`).
    pub body: String,
    /// The point in the body's frame (m).
    pub point: [f64; 3],
}

impl std::str::FromStr for Foot {
    type Err = String;

    /// `BODY:X,Y,Z` (the point in the body's frame, m); `Err` says what is wrong, as `--foot`.
    fn from_str(text: &str) -> Result<Self, String> {
        let (body, xyz) = (text.split_once(':'))
            .ok_or_else(|| format!("--foot '{text}': expected BODY:X,Y,Z"))?;
        let point: Option<[f64; 3]> = (xyz.split(',').map(|x| x.trim().parse::<f64>()))
            .collect::<Result<Vec<f64>, _>>()
            .ok()
            .and_then(|v| v.try_into().ok());
        Ok(Foot {
            body: body.trim().to_string(),
            point: point
                .ok_or_else(|| format!("--foot '{text}': X,Y,Z must be three numbers (m)"))?,
        })
    }
}

/// The built-in quadruped's feet (the shanks' ends).
pub fn quadruped_feet(robot: &FloatingModel) -> Vec<Foot> {
    crate::model::quadruped::feet()
        .into_iter()
        .map(|(b, p)| Foot {
            body: robot.tree().bodies()[b].name.clone(),
            point: p.into(),
        })
        .collect()
}

/// `feet` resolved to `(body index, point)` in `robot`'s tree; `Err` names an unknown body.
fn resolve_feet(
    robot: &FloatingModel,
    feet: &[Foot],
) -> Result<Vec<(usize, Vector3<f64>)>, ApiError> {
    let bodies = robot.tree().bodies();
    feet.iter()
        .map(|f| {
            let i = bodies
                .iter()
                .position(|b| b.name == f.body)
                .ok_or_else(|| {
                    ApiError::Options(format!(
                        "foot '{}': the robot has no body of that name (bodies: {})",
                        f.body,
                        bodies
                            .iter()
                            .map(|b| b.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ))
                })?;
            if !f.point.iter().all(|x| x.is_finite() && x.abs() < 10.0) {
                return Err(ApiError::Options(format!(
                    "foot '{}': point {:?} must be finite, within 10 m of the body",
                    f.body, f.point
                )));
            }
            Ok((i, Vector3::from(f.point)))
        })
        .collect()
}

/// `simulate --floating-base`: the built-in quadruped standing and shifting its weight
/// ([`crate::sim::floating::standing`]), logged by `sensors`.
#[derive(Clone, Debug)]
pub struct SimulateFloatingOptions {
    /// The robot: the built-in `cheetah3` as the quadruped, or a floating URDF of the quadruped
    /// (its bodies and joints; its inertial parameters may differ).
    pub robot: RobotOptions,
    /// Duration (s), at most an hour.
    pub duration: f64,
    /// Control and logging rate (Hz), 100 to 10,000.
    pub rate: f64,
    /// Seeds the motion and the sensors' noise.
    pub seed: u64,
    /// Trot in place: `(crouch rad, frequency Hz)` of each diagonal pair's steps
    /// ([`crate::sim::floating::Standing::step`]); `None`: stand.
    pub trot: Option<(f64, f64)>,
    /// Stand still holding the standing posture (no weight shifting, no steps): the robot's
    /// weight and how its feet share it, as a check of the contact model.
    pub still: bool,
    /// How the run starts (dropped, pushed) and the ground's friction.
    pub start: StartOptions,
    /// The sensors.
    pub sensors: Sensors,
    /// The log to write, CSV or MCAP (`.mcap`; docs/floating-base.md, "Logs"); the robot
    /// simulated, the ground truth, is written beside it as a floating URDF ([`truth_path`]).
    pub out: PathBuf,
}

/// How a floating run starts and on what ground: by default standing on it at rest, on the
/// ground of [`crate::sim::floating::Ground::default`].
#[derive(Clone, Debug, PartialEq)]
pub struct StartOptions {
    /// Drop the robot: its lowest foot this high above the ground at the start (m, 0 to 0.5).
    pub drop: f64,
    /// Push it: the whole robot's velocity at the start (m/s, world axes; at most 5 m/s).
    pub push: [f64; 3],
    /// The ground's friction coefficient μ (0 to 2).
    pub ground_friction: f64,
}

impl Default for StartOptions {
    fn default() -> Self {
        Self {
            drop: 0.0,
            push: [0.0; 3],
            ground_friction: crate::sim::floating::Ground::default().friction,
        }
    }
}

impl StartOptions {
    /// The options checked; `Err` names the one at fault.
    pub fn validate(&self) -> Result<(), ApiError> {
        if !(0.0..=MAX_START_HEIGHT).contains(&self.drop) {
            return Err(ApiError::invalid_option("drop", "0 <= m <= 0.5", self.drop));
        }
        let speed = Vector3::from(self.push).norm();
        if !(speed.is_finite() && speed <= MAX_START_SPEED) {
            return Err(ApiError::Options(format!(
                "push: expected a velocity VX,VY,VZ of at most {MAX_START_SPEED} m/s, got {:?}",
                self.push
            )));
        }
        if !(0.0..=2.0).contains(&self.ground_friction) {
            return Err(ApiError::invalid_option(
                "ground_friction",
                "0 <= μ <= 2",
                self.ground_friction,
            ));
        }
        Ok(())
    }
}

/// Where the ground truth of the log `out` is written: `<stem>.truth.urdf` beside it.
pub fn truth_path(out: &Path) -> PathBuf {
    let stem = out
        .file_stem()
        .map_or("log".into(), |s| s.to_string_lossy().into_owned());
    out.with_file_name(format!("{stem}.truth.urdf"))
}

impl SimulateFloatingOptions {
    /// The options checked; `Err` names the one at fault.
    pub fn validate(&self) -> Result<(), ApiError> {
        if !(self.duration > 0.0 && self.duration <= 3600.0) {
            return Err(ApiError::invalid_option(
                "duration",
                "0 < s <= 3600",
                self.duration,
            ));
        }
        if !(100.0..=10_000.0).contains(&self.rate) {
            return Err(ApiError::invalid_option(
                "rate",
                "100 <= Hz <= 10000",
                self.rate,
            ));
        }
        if self.still && self.trot.is_some() {
            return Err(ApiError::Options(
                "still and trot: a robot standing still does not trot; give one".into(),
            ));
        }
        self.start.validate()?;
        self.sensors.validate().map_err(ApiError::Options)
    }
}

impl SimulateFloatingOptions {
    /// The experiment these options ask for.
    fn motion(&self) -> crate::sim::floating::Standing {
        let mut motion = crate::sim::floating::Standing {
            duration: self.duration,
            rate: self.rate,
            seed: self.seed,
            step: self.trot.unwrap_or((0.0, 0.0)),
            start: Start {
                height: self.start.drop,
                velocity: self.start.push,
            },
            ..Default::default()
        };
        motion.ground.friction = self.start.ground_friction;
        if self.still {
            motion.amplitude = [0.0; 3];
        }
        motion
    }
}

/// What [`simulate_floating`] wrote.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct FloatingSimulated {
    /// The log.
    pub out: PathBuf,
    /// The robot simulated (the ground truth), a floating URDF.
    pub truth: PathBuf,
    /// Samples logged.
    pub samples: usize,
    /// The joints, in the log's order.
    pub joints: Vec<String>,
    /// The feet.
    pub feet: Vec<Foot>,
    /// Share of the feet's samples in contact.
    pub contact_share: f64,
    /// The joints' PD law, `τ = k_p (q* − q) + k_d (q̇* − q̇)`: `[k_p N m/rad, k_d N m s/rad]`.
    pub gains: [f64; 2],
    /// The standing posture `q*` of every leg, `[ab/ad, hip, knee]` (rad).
    pub posture: [f64; 3],
    /// The ground: `[k N/m, c N s/m, μ, slip speed m/s]` (docs/floating-base.md).
    pub ground: [f64; 4],
    /// The joints' friction law's speed `v_f` (rad/s): each joint feels `b q̇ + B_c tanh(q̇ /
    /// v_f)` with its URDF `<dynamics damping friction>`.
    pub friction_speed: f64,
    /// The lowest foot's height above the ground at the start (m).
    pub drop: f64,
    /// The whole robot's velocity at the start (m/s, world axes).
    pub push: [f64; 3],
}

/// Simulates and logs a floating-base run ([`SimulateFloatingOptions`]).
pub fn simulate_floating(opts: &SimulateFloatingOptions) -> Result<FloatingSimulated, ApiError> {
    opts.validate()?;
    let robot = opts.robot.load_floating()?.robot;
    let files = opts.robot.files();
    let inputs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let truth = truth_path(&opts.out);
    let truth_sidecar = crate::io::sidecar_path(&truth);
    crate::io::check_outputs(&[&opts.out, &truth, &truth_sidecar], &inputs)?;
    let feet = quadruped_feet(&crate::model::quadruped::quadruped());
    let points = resolve_feet(&robot, &feet).map_err(|e| {
        ApiError::Options(format!(
            "--robot {}: the floating-base simulation is the quadruped's (the built-in, or a URDF of it with its bodies and joints): {e}",
            opts.robot.robot
        ))
    })?;
    if robot.joints() != 12 {
        return Err(ApiError::Options(format!(
            "--robot {}: the floating-base simulation is the quadruped's: 12 joints, not {}",
            opts.robot.robot,
            robot.joints()
        )));
    }
    let motion = opts.motion();
    let run = crate::sim::floating::standing(&robot, &points, &motion)
        .map_err(|e| ApiError::Options(e.to_string()))?;
    let joints = robot.tree().joint_names();
    let names: Vec<String> = feet.iter().map(|f| f.body.clone()).collect();
    let log = crate::sim::floating_sensors::log(&run, (&joints, &names), &opts.sensors, opts.seed);
    if crate::io::is_bag(&opts.out) {
        floating_mcap::write(&opts.out, &log, &robot.trunk().name)?;
    } else {
        floating_log::write_csv(&opts.out, &log)?;
    }
    crate::io::export_floating_urdf(&truth, &robot, &inputs)?;
    let down = run.contact.iter().filter(|f| f.z > 0.0).count();
    let g = &motion.ground;
    Ok(FloatingSimulated {
        out: opts.out.clone(),
        truth,
        samples: run.len(),
        joints,
        feet,
        contact_share: down as f64 / run.contact.len().max(1) as f64,
        gains: [motion.gains.0, motion.gains.1],
        posture: motion.posture,
        ground: [g.stiffness, g.damping, g.friction, g.slip_speed],
        friction_speed: motion.friction_velocity,
        drop: motion.start.height,
        push: motion.start.velocity,
    })
}

/// `identify --floating-base`: a floating robot identified from one log.
#[derive(Clone, Debug)]
pub struct IdentifyFloatingOptions {
    /// The robot (its description is the prior).
    pub robot: RobotOptions,
    /// The log: CSV, MCAP or a rosbag2 directory (docs/floating-base.md "Logs").
    pub data: PathBuf,
    /// The topics and clock of an MCAP or rosbag2 log (none may be changed for a CSV).
    pub topics: FloatingReadOptions,
    /// The feet; empty: the built-in quadruped's.
    pub feet: Vec<Foot>,
    /// Which of the log's quantities are used.
    pub setting: DataSetting,
    /// The constraint set.
    pub constraints: ConstraintSet,
    /// Weight of the pull towards the description.
    pub prior_weight: f64,
    /// Low-pass cutoff of the derived signals (Hz); `None`: the pipeline's choice.
    pub cutoff: Option<f64>,
    /// Without `contact_<foot>` columns, a foot is down where its logged normal force exceeds
    /// this (N).
    pub contact_force: f64,
    /// Write the identified robot as URDF (its trunk the root link).
    pub out_urdf: Option<PathBuf>,
    /// Write it as MJCF (a free joint on the trunk).
    pub out_mjcf: Option<PathBuf>,
    /// The ground truth, a floating URDF of the same robot (as `simulate-floating` writes
    /// beside its log): every body's errors against it are reported.
    pub truth: Option<PathBuf>,
    /// A log of the robot before a change: the description is first fitted to it, and which
    /// body changed is asked against that fit instead of the description (whose own errors a
    /// log shows as differences).
    pub baseline: Option<PathBuf>,
}

impl IdentifyFloatingOptions {
    /// The options checked; `Err` names the one at fault.
    pub fn validate(&self) -> Result<(), ApiError> {
        if !(self.prior_weight.is_finite() && self.prior_weight >= 0.0) {
            return Err(ApiError::invalid_option(
                "prior_weight",
                ">= 0",
                self.prior_weight,
            ));
        }
        if let Some(c) = self.cutoff.filter(|c| !(c.is_finite() && *c > 0.0)) {
            return Err(ApiError::invalid_option("cutoff", "> 0 Hz", c));
        }
        if !(self.contact_force.is_finite() && self.contact_force >= 0.0) {
            return Err(ApiError::invalid_option(
                "contact_force",
                ">= 0 N",
                self.contact_force,
            ));
        }
        if self.baseline.as_ref() == Some(&self.data) {
            return Err(ApiError::Options(format!(
                "--baseline-data {}: the log itself; give a log of the robot before the change",
                self.data.display()
            )));
        }
        self.check_topics()?;
        if self.feet.is_empty() && self.robot.robot != "cheetah3" {
            return Err(ApiError::Options(format!(
                "--robot {}: name the feet (--foot BODY:X,Y,Z for each); only the built-in quadruped's are known",
                self.robot.robot
            )));
        }
        Ok(())
    }

    /// The feet given, or the quadruped's (`feet` empty).
    fn feet_or_quadruped(&self, robot: &FloatingModel) -> Vec<Foot> {
        if self.feet.is_empty() {
            quadruped_feet(robot)
        } else {
            self.feet.clone()
        }
    }

    /// The topics named, distinct, and changed only where a log (or the baseline) is MCAP or a
    /// rosbag2 directory.
    fn check_topics(&self) -> Result<(), ApiError> {
        let t = &self.topics;
        let named = [
            ("topic", &t.topic),
            ("odometry_topic", &t.odometry_topic),
            ("foot_forces_topic", &t.foot_forces_topic),
            ("imu_topic", &t.imu_topic),
        ];
        if let Some((name, _)) = named.iter().find(|(_, v)| v.trim().is_empty()) {
            return Err(ApiError::Options(format!(
                "{name}: empty; give a topic name (e.g. /odometry)"
            )));
        }
        if let Some((i, j)) = crate::io::first_repeat_by(&named, |a, b| a.1 == b.1) {
            return Err(ApiError::Options(format!(
                "{} and {} are both {}: the joint states, the trunk, the feet and the IMU come on four topics",
                named[i].0, named[j].0, named[i].1
            )));
        }
        let csv = |p: &Path| !crate::io::is_bag(p);
        let all_csv = csv(&self.data) && self.baseline.as_deref().is_none_or(csv);
        if all_csv && *t != FloatingReadOptions::default() {
            return Err(ApiError::Options(format!(
                "{}: the topics and the stamp apply to MCAP files and rosbag2 directories only",
                self.data.display()
            )));
        }
        Ok(())
    }
}

/// Reads the floating log `path` (CSV, MCAP or a rosbag2 directory) for the robot's `joints`
/// and `feet`; the note says which joint samples the other topics did not cover.
fn read_floating_log(
    path: &Path,
    joints: &[String],
    feet: &[String],
    topics: &FloatingReadOptions,
) -> Result<(FloatingLog, Option<String>), ApiError> {
    if !crate::io::is_bag(path) {
        return Ok((floating_log::read_csv(path, joints, feet)?, None));
    }
    let read = floating_mcap::read(path, joints, feet, topics)?;
    let note = match read.left_out {
        (0, 0) => None,
        (before, after) => Some(format!(
            "{}: {before} joint samples before and {after} after the span of {}{} left out (nothing to interpolate the trunk from)",
            path.display(),
            topics.odometry_topic,
            [
                (read.log.force.is_some() || read.log.contact.is_some())
                    .then(|| format!(" and {}", topics.foot_forces_topic)),
                read.log.accel.is_some().then(|| format!(" and {}", topics.imu_topic)),
            ]
            .into_iter()
            .flatten()
            .collect::<String>()
        )),
    };
    Ok((read.log, note))
}

/// The identified floating robot (`identify --floating-base --json`).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct FloatingIdentification {
    /// The robot's name.
    pub robot: String,
    /// The log.
    pub data: PathBuf,
    /// The data setting.
    pub setting: DataSetting,
    /// The constraint set.
    pub constraints: ConstraintSet,
    /// Samples in the log.
    pub samples_read: usize,
    /// Samples used (after the pipeline's trimming).
    pub samples_used: usize,
    /// The derived signals' cutoff (Hz).
    pub cutoff: f64,
    /// Share of the used samples' feet in contact.
    pub contact_share: f64,
    /// Samples left out because a foot touched down or lifted off within the filter's settling
    /// length (`torques_only`: the projection changes there).
    pub samples_near_contact_changes: usize,
    /// RMS of the rows' targets (N m and N: joint torques, the trunk's wrench).
    pub target_rms: f64,
    /// RMS of the rows' residual with the description's parameters.
    pub description_rms: f64,
    /// RMS of the rows' residual with the identified parameters.
    pub identified_rms: f64,
    /// The trunk, then the tree's links and rotors.
    pub bodies: Vec<IdentifiedBody>,
    /// Viscous friction per joint (N m s/rad).
    pub viscous: Vec<f64>,
    /// Coulomb friction per joint (N m).
    pub coulomb: Vec<f64>,
    /// The whole robot's mass as described (kg).
    pub described_mass: f64,
    /// The whole robot's mass as identified (kg).
    pub identified_mass: f64,
    /// Whether every constraint of the set holds (checked from the parameters).
    pub constraints_hold: bool,
    /// The solver's verdict.
    pub status: SolveStatus,
    /// θ, the trunk's ten parameters first.
    pub theta: Vec<f64>,
    /// Against the ground truth (`truth`), when given: its total mass (kg) and every body's
    /// errors.
    pub truth: Option<TruthScores>,
    /// What the log determines, as `identify` reports it: rank and conditioning of the rows,
    /// the base parameters with their standard errors, the unidentifiable directions, and each
    /// parameter's standard error (infinite where the log does not determine it).
    pub identifiability: crate::ident::analysis::Identifiability,
    /// Per body (as `bodies`), its mass's standard error (kg); `None` (null) where the log
    /// does not determine the mass on its own.
    pub mass_standard_errors: Vec<Option<f64>>,
    /// Which body the log shows differing from the reference, if any (a payload strapped on
    /// the trunk, a changed link, or the description's own error): each body's ten parameters
    /// freed in turn with the rest at the reference ([`crate::diagnose::floating`]). The
    /// reference is the description, or its fit to the baseline log (`baseline`): only then
    /// does a difference read as a change of the robot.
    pub change: DescriptionCheck,
    /// Warnings about the result: a body's mass far from the description's, saying whether
    /// the log determines it.
    pub notices: Vec<super::data::Notice>,
}

/// Which body differs from the reference ([`FloatingIdentification::change`]).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct DescriptionCheck {
    /// The log of the robot before the change the reference was fitted to; `None`: the
    /// reference is the description.
    pub baseline: Option<PathBuf>,
    /// The F statistic a change must exceed to be named.
    pub min_f: f64,
    /// The share of the description's residual a change must remove to be named.
    pub min_reduction: f64,
    /// The body whose change explains the log best, where it passes both.
    pub changed: Option<crate::diagnose::floating::BodyChange>,
    /// Bodies whose change explains the log almost as well as the named one's (the data
    /// cannot tell them apart: a rotor the trunk carries rigidly).
    pub also_fit: Vec<String>,
    /// The five bodies whose change explains the log best, the best first (named or not).
    pub candidates: Vec<crate::diagnose::floating::BodyChange>,
    /// With a baseline: how much the baseline's rows see the best change per sample, as a
    /// share of how much this log's rows see it.
    pub baseline_visibility: Option<f64>,
    /// With a baseline: the best change, set aside unnamed because the baseline's motion
    /// hardly excites it (visibility below [`MIN_BASELINE_VISIBILITY`]): there the baseline
    /// cannot tell a change from the description's own error.
    pub unseen_by_baseline: Option<crate::diagnose::floating::BodyChange>,
    /// The joint whose friction (viscous and Coulomb) differs, where its change passes both
    /// thresholds and carries more evidence (F) than the best body's change: then no body is
    /// named (a worn or freshly lubricated joint, not a payload).
    pub friction_changed: Option<crate::diagnose::floating::FrictionChange>,
    /// The three joints whose friction change explains the log best, the best first.
    pub friction_candidates: Vec<crate::diagnose::floating::FrictionChange>,
    /// With a baseline: the named friction change, set aside because the baseline's motion
    /// hardly moves that joint (as `unseen_by_baseline`).
    pub friction_unseen_by_baseline: Option<crate::diagnose::floating::FrictionChange>,
    /// The joint whose logged torque is scaled against the reference (a current sensor's or
    /// torque constant's error), where its change passes `min_f`, removes
    /// [`GAIN_MIN_JOINT_REDUCTION`](crate::diagnose::floating::GAIN_MIN_JOINT_REDUCTION) of its
    /// joint's residual and carries more evidence (F) than the body or friction change named:
    /// then neither is.
    /// Asked with torques and contact forces only (`torques-and-contacts`).
    pub gain_changed: Option<crate::diagnose::floating::GainChange>,
    /// The three joints whose gain change explains the log best, the best first.
    pub gain_candidates: Vec<crate::diagnose::floating::GainChange>,
}

/// A change is named against a baseline only where the baseline's rows see it per sample at
/// least this share of what the new log's rows do. Measured with a description of 10 %
/// errors: unchanged robots, baseline standing and the new log trotting, 0.009 and 0.014 (their
/// differences named otherwise); payloads 0.19 (0.5 kg shank, standing baseline, trotting log)
/// to 1.22.
pub const MIN_BASELINE_VISIBILITY: f64 = 0.05;

impl DescriptionCheck {
    /// Names the best gain change `gains` (largest F first) where it passes its thresholds and
    /// outweighs the body or friction change named; those are then unnamed.
    fn weigh_gains(&mut self, gains: Vec<crate::diagnose::floating::GainChange>) {
        let others: Vec<f64> = (self.changed.as_ref().map(|b| b.f).into_iter())
            .chain(self.friction_changed.as_ref().map(|f| f.f))
            .collect();
        self.gain_changed = crate::diagnose::floating::name_gain(&gains, &others, self.min_f);
        if self.gain_changed.is_some() {
            self.changed = None;
            self.also_fit.clear();
            self.friction_changed = None;
        }
        self.gain_candidates = gains.into_iter().take(3).collect();
    }

    /// Sets the best change aside when the baseline (rows `base`) hardly sees it against the
    /// new log's rows `ne`.
    fn set_aside_if_unseen(&mut self, base: &NormalEquations, ne: &NormalEquations) {
        if let Some(f) = &self.friction_changed {
            let seen = baseline_visibility((&f.columns, &[f.viscous, f.coulomb]), base, ne);
            self.baseline_visibility = Some(seen);
            if seen < MIN_BASELINE_VISIBILITY {
                self.friction_unseen_by_baseline = self.friction_changed.take();
            }
            return;
        }
        let Some(best) = self.candidates.first() else {
            return;
        };
        let columns: Vec<usize> = (best.column..best.column + 10).collect();
        let seen = baseline_visibility((&columns, &best.delta), base, ne);
        self.baseline_visibility = Some(seen);
        if seen < MIN_BASELINE_VISIBILITY {
            self.unseen_by_baseline = self.changed.take();
            self.also_fit.clear();
        }
    }
}

/// A body's change is named above this F statistic...
pub const CHANGE_MIN_F: f64 = 10.0;
/// ...and where it removes at least this share of the description's residual. A log carries
/// residual no body explains (the filter's, the contacts', friction's other form), which every
/// body's ten free parameters absorb a little of: on unchanged 6 s trotting logs the best body
/// removed up to 1.4 % (F 144), a 0.5 kg payload on a shank 17.5 % or more.
pub const CHANGE_MIN_REDUCTION: f64 = 0.05;

/// Which body of `reference` differs on the rows `ne`, as [`DescriptionCheck`] tells it.
fn description_check(
    reference: &FloatingModel,
    ne: &NormalEquations,
    baseline: Option<PathBuf>,
) -> DescriptionCheck {
    use crate::diagnose::floating::{body_changes, friction_changes, name_change, name_friction};
    let changes = body_changes(reference, ne);
    let mut named = name_change(&changes, CHANGE_MIN_F, CHANGE_MIN_REDUCTION);
    let frictions = friction_changes(reference, ne);
    let thresholds = (CHANGE_MIN_F, CHANGE_MIN_REDUCTION);
    let friction_changed = name_friction(&frictions, changes.first(), thresholds);
    if friction_changed.is_some() {
        named.changed = None;
        named.also_fit.clear();
    }
    DescriptionCheck {
        baseline,
        min_f: CHANGE_MIN_F,
        min_reduction: CHANGE_MIN_REDUCTION,
        changed: named.changed,
        also_fit: named.also_fit,
        candidates: changes.into_iter().take(5).collect(),
        baseline_visibility: None,
        unseen_by_baseline: None,
        friction_changed,
        friction_candidates: frictions.into_iter().take(3).collect(),
        friction_unseen_by_baseline: None,
        gain_changed: None,
        gain_candidates: vec![],
    }
}

/// The identified robot against the ground truth.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct TruthScores {
    /// The truth's file.
    pub file: PathBuf,
    /// The truth's total mass (kg).
    pub mass: f64,
    /// Per body (the trunk first): relative mass, CoM (m), inertia and pseudo-inertia errors.
    pub bodies: Vec<super::identify::TruthError>,
}

/// `theta` against the floating URDF at `path`, which must have `robot`'s parameters.
fn truth_scores(
    robot: &FloatingModel,
    path: &Path,
    theta: &DVector<f64>,
) -> Result<TruthScores, ApiError> {
    let (truth, _) = crate::io::urdf::load_floating(path, &Default::default())?;
    if truth.parameter_names() != robot.parameter_names() {
        return Err(ApiError::invalid(
            path,
            format!(
                "the ground truth is not a description of {} (its bodies, rotors or joints differ)",
                robot.name()
            ),
        ));
    }
    let errors = crate::experiment::body_errors(&truth, theta);
    let bodies = (crate::ident::Parameterized::inertial_bodies(robot).into_iter())
        .zip(errors)
        .map(
            |((name, _, _), [mass_rel, com_m, inertia_rel, j_rel])| super::identify::TruthError {
                name,
                mass_rel,
                com_m,
                inertia_rel,
                j_rel,
            },
        )
        .collect();
    Ok(TruthScores {
        file: path.to_path_buf(),
        mass: truth.total_mass(),
        bodies,
    })
}

/// Identifies a floating robot from a log ([`IdentifyFloatingOptions`]).
pub fn identify_floating(
    opts: &IdentifyFloatingOptions,
) -> Result<FloatingIdentification, ApiError> {
    opts.validate()?;
    let robot = opts.robot.load_floating()?.robot;
    check_outputs(opts)?;
    let (log, samples, ne) = rows_of_log(&robot, opts)?;
    let prior = robot.parameters();
    let found = fit_description(&robot, &ne, opts)?;
    let truth = (opts.truth.as_deref())
        .map(|p| truth_scores(&robot, p, &found.theta))
        .transpose()?;
    // Every input read (the baseline too) before anything is written.
    let change = change_check(&robot, opts, (&samples, &ne))?;
    let identified = robot.with_parameters(&found.theta)?;
    write_models(opts, &identified)?;
    let identifiability = crate::ident::analysis::identifiability(&robot, &ne, &found.theta);
    let columns = mass_columns(&robot, &found.bodies);
    let mass_standard_errors = mass_errors(&columns, &identifiability);
    let notices = (samples.read_note.iter().map(super::data::Notice::note))
        .chain(far_masses(
            &found.bodies,
            &columns,
            &prior,
            &mass_standard_errors,
        ))
        .collect();
    let rows = (ne.samples * crate::ident::floating::rows_per_sample(&robot, opts.setting)).max(1);
    let rms = |theta: &DVector<f64>| (ne.residual_sum_of_squares(theta) / rows as f64).sqrt();
    let n = robot.joints();
    let k = found.theta.len() - 2 * n;
    Ok(FloatingIdentification {
        robot: robot.name().to_string(),
        data: opts.data.clone(),
        setting: opts.setting,
        constraints: opts.constraints,
        samples_read: log.len(),
        samples_used: samples.log.samples.len(),
        cutoff: samples.log.cutoff,
        contact_share: samples.log.contact_share(),
        samples_near_contact_changes: samples.log.dropped,
        target_rms: (ne.tt / rows as f64).sqrt(),
        description_rms: rms(&prior),
        identified_rms: rms(&found.theta),
        bodies: found.bodies.clone(),
        viscous: found.theta.rows(k, n).iter().copied().collect(),
        coulomb: found.theta.rows(k + n, n).iter().copied().collect(),
        described_mass: robot.total_mass(),
        identified_mass: identified.total_mass(),
        constraints_hold: found.constraints_hold,
        status: found.solver.status,
        theta: found.theta.iter().copied().collect(),
        truth,
        identifiability,
        mass_standard_errors,
        change,
        notices,
    })
}

/// Which body, joint friction or torque gain differs on the rows `ne` (of `samples`) from the
/// description, or, given `opts.baseline`, from its fit to that log (a change is set aside
/// where the baseline hardly sees it).
fn change_check(
    robot: &FloatingModel,
    opts: &IdentifyFloatingOptions,
    (samples, ne): (&Samples, &NormalEquations),
) -> Result<DescriptionCheck, ApiError> {
    let fitted;
    let (reference, mut change) = match &opts.baseline {
        None => (robot, description_check(robot, ne, None)),
        Some(path) => {
            let base_ne;
            (fitted, base_ne) = baseline_fit(robot, opts, path)?;
            let mut change = description_check(&fitted, ne, Some(path.clone()));
            change.set_aside_if_unseen(&base_ne, ne);
            (&fitted, change)
        }
    };
    if opts.setting == DataSetting::TorquesAndContacts {
        let feet = resolve_feet(robot, &opts.feet_or_quadruped(robot))?;
        let sums = gain_sums(reference, &feet, samples);
        change.weigh_gains(crate::diagnose::floating::gain_changes(
            reference, ne, &sums,
        ));
    }
    Ok(change)
}

/// The description fitted to the baseline log `path` under `opts` (its setting, constraints,
/// prior and cutoff): the robot before the change.
fn baseline_fit(
    robot: &FloatingModel,
    opts: &IdentifyFloatingOptions,
    path: &Path,
) -> Result<(FloatingModel, NormalEquations), ApiError> {
    let at_baseline = IdentifyFloatingOptions {
        data: path.to_path_buf(),
        ..opts.clone()
    };
    let (_, _, ne) = rows_of_log(robot, &at_baseline)?;
    let found = fit_description(robot, &ne, opts)?;
    Ok((robot.with_parameters(&found.theta)?, ne))
}

/// `robot` identified on the rows `ne` under `opts`' constraint set, its description the
/// prior of weight `opts.prior_weight`.
fn fit_description(
    robot: &FloatingModel,
    ne: &NormalEquations,
    opts: &IdentifyFloatingOptions,
) -> Result<crate::ident::Identified, ApiError> {
    let options = crate::ident::Options {
        prior_weight: opts.prior_weight,
        ..crate::ident::Options::new(opts.constraints)
    };
    Ok(crate::ident::identify(
        robot,
        ne,
        &robot.parameters(),
        &options,
    )?)
}

/// How much the baseline log's rows see a change (`delta` of `columns`) per sample, as a share
/// of how much the new log's rows `ne` see it: `Δπᵀ (YᵀY)_c Δπ / N` of each over the columns.
fn baseline_visibility(
    (columns, delta): (&[usize], &[f64]),
    base: &NormalEquations,
    ne: &NormalEquations,
) -> f64 {
    let seen = |e: &NormalEquations| {
        let quad: f64 = (columns.iter().zip(delta))
            .map(|(&i, di)| {
                (columns.iter().zip(delta))
                    .map(|(&j, dj)| di * e.yty[(i, j)] * dj)
                    .sum::<f64>()
            })
            .sum();
        quad / e.samples.max(1) as f64
    };
    let new = seen(ne);
    if new > 0.0 {
        seen(base) / new
    } else {
        1.0
    }
}

/// The log at `opts.data` for `robot`'s feet (`opts.feet`, or the quadruped's), its samples,
/// and their rows' normal equations in `opts.setting`.
fn rows_of_log(
    robot: &FloatingModel,
    opts: &IdentifyFloatingOptions,
) -> Result<(FloatingLog, Samples, NormalEquations), ApiError> {
    let feet = opts.feet_or_quadruped(robot);
    let points = resolve_feet(robot, &feet)?;
    let names: Vec<String> = feet.iter().map(|f| f.body.clone()).collect();
    let joints = robot.tree().joint_names();
    let (log, note) = read_floating_log(&opts.data, &joints, &names, &opts.topics)?;
    check_setting(opts, &log)?;
    let samples = Samples {
        read_note: note,
        log: samples_of(&log, opts, robot.tree().gravity())?,
    };
    let ne = samples.log.normal_equations(robot, &points, opts.setting);
    Ok((log, samples, ne))
}

/// Per body, the column of its mass in `θ`.
fn mass_columns(robot: &FloatingModel, bodies: &[IdentifiedBody]) -> Vec<Option<usize>> {
    let names = robot.parameter_names();
    (bodies.iter())
        .map(|b| super::identify::mass_column(&names, &b.name))
        .collect()
}

/// Each body's mass's standard error (kg), `None` where it is not finite.
fn mass_errors(
    columns: &[Option<usize>],
    idf: &crate::ident::analysis::Identifiability,
) -> Vec<Option<f64>> {
    (columns.iter())
        .map(|c| Some(idf.standard_errors[(*c)?]).filter(|e| e.is_finite()))
        .collect()
}

/// A warning for each body whose identified mass is far from the description's (`prior`),
/// as `identify` gives them (`columns` each body's mass column, `errors` its standard error).
fn far_masses(
    bodies: &[IdentifiedBody],
    columns: &[Option<usize>],
    prior: &DVector<f64>,
    errors: &[Option<f64>],
) -> Vec<super::data::Notice> {
    let masses = (bodies.iter().zip(columns).zip(errors)).filter_map(|((b, c), se)| {
        let se = se.unwrap_or(f64::INFINITY);
        Some((b.name.as_str(), prior[(*c)?], b.pi[0], se))
    });
    let remedy = "bound it (a stronger prior: --prior-weight) or log a motion that moves this body (swing phases: a trot, steps)";
    super::identify::far_masses(masses, remedy)
}

/// Neither output may be an input or the other.
fn check_outputs(opts: &IdentifyFloatingOptions) -> Result<(), ApiError> {
    let sidecar = opts.out_urdf.as_deref().map(crate::io::sidecar_path);
    let outputs: Vec<&Path> = [&opts.out_urdf, &sidecar, &opts.out_mjcf]
        .into_iter()
        .flatten()
        .map(PathBuf::as_path)
        .collect();
    let inputs = input_files(opts);
    let inputs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
    Ok(crate::io::check_outputs(&outputs, &inputs)?)
}

/// Every file `opts` reads.
fn input_files(opts: &IdentifyFloatingOptions) -> Vec<PathBuf> {
    let mut inputs = opts.robot.files();
    inputs.push(opts.data.clone());
    inputs.extend(opts.truth.clone());
    inputs.extend(opts.baseline.clone());
    inputs
}

/// Writes the identified robot where asked.
fn write_models(
    opts: &IdentifyFloatingOptions,
    identified: &FloatingModel,
) -> Result<(), ApiError> {
    if let Some(p) = &opts.out_urdf {
        let inputs = input_files(opts);
        let inputs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
        crate::io::export_floating_urdf(p, identified, &inputs)?;
    }
    if let Some(p) = &opts.out_mjcf {
        crate::io::write_atomic(
            p,
            crate::io::mjcf::floating_to_string(identified).as_bytes(),
        )?;
    }
    Ok(())
}

/// The log has what the setting needs; `Err` says what is missing.
fn check_setting(opts: &IdentifyFloatingOptions, log: &FloatingLog) -> Result<(), ApiError> {
    let missing = |what: &str| {
        Err(ApiError::invalid(
            &opts.data,
            format!(
                "the {} setting needs {what}",
                crate::io::serde_name(&opts.setting)
            ),
        ))
    };
    match opts.setting {
        DataSetting::TorquesOnly if log.force.is_none() && log.contact.is_none() => {
            missing("which feet are down: contact_<foot> columns, or force_<foot>_x, _y, _z (MCAP: the feet's topic)")
        }
        DataSetting::TorquesAndContacts | DataSetting::BaseOnly if log.force.is_none() => {
            missing("the feet's contact forces: force_<foot>_x, _y, _z columns (MCAP: the force array of the feet's topic)")
        }
        _ => Ok(()),
    }
}

/// The log's samples, and what reading it left out (joint samples the trunk's topic did not
/// cover).
struct Samples {
    log: LogSamples,
    read_note: Option<String>,
}

/// The log's samples for `opts` ([`log_samples`]).
fn samples_of(
    log: &FloatingLog,
    opts: &IdentifyFloatingOptions,
    gravity: Vector3<f64>,
) -> Result<LogSamples, ApiError> {
    let sampling = LogSampling {
        cutoff: opts.cutoff,
        setting: opts.setting,
        contact_force: opts.contact_force,
        gravity,
    };
    log_samples(log, &sampling).map_err(|e| ApiError::invalid(&opts.data, e.to_string()))
}

/// Each joint's [`GainSums`](crate::diagnose::floating::GainSums) on `samples` against
/// `reference` (rows with torques and contact forces): the predicted motor torque `τ̂_j` (the
/// joint row's prediction less the contact forces' share of its target) and the row's
/// residual.
fn gain_sums(
    reference: &FloatingModel,
    feet: &[(usize, Vector3<f64>)],
    samples: &Samples,
) -> Vec<crate::diagnose::floating::GainSums> {
    let n = reference.joints();
    let theta = reference.parameters();
    let mut sums = vec![(0.0, 0.0, 0.0); n];
    let setting = DataSetting::TorquesAndContacts;
    samples
        .log
        .for_each_rows(reference, feet, setting, |y, target, tau| {
            let predicted = y * &theta;
            for (j, (cc, cr, rr)) in sums.iter_mut().enumerate() {
                let row = 6 + j;
                let motor = predicted[row] - (target[row] - tau[j]);
                let residual = target[row] - predicted[row];
                *cc += motor * motor;
                *cr += motor * residual;
                *rr += residual * residual;
            }
        });
    (reference.tree().joint_names().into_iter().zip(sums))
        .map(|(joint, (cc, cr, rr))| crate::diagnose::floating::GainSums { joint, cc, cr, rr })
        .collect()
}
