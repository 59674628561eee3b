//! `physid simulate-floating` and `physid identify-floating`: the whole robot from its logs
//! (docs/floating-base.md, "From a log").

use crate::robot_args::RobotArgs;
use physid::api::floating::{
    identify_floating, simulate_floating, Foot, IdentifyFloatingOptions, SimulateFloatingOptions,
    StartOptions,
};
use physid::ident::floating::DataSetting;
use physid::ident::ConstraintSet;
use physid::io::floating_mcap::FloatingReadOptions;
use physid::sim::floating_sensors::Sensors;
use std::path::PathBuf;

/// Simulate the built-in quadruped standing and shifting its weight, and log it as its sensors
/// would: joint encoders and motor torques, the trunk's pose and twist from an IMU and a state
/// estimator (noise and bias), the feet's contact forces and states (CSV).
#[derive(clap::Args, Debug)]
pub struct SimulateArgs {
    /// The log to write: CSV, or MCAP (`.mcap`: /joint_states, /odometry, /foot_forces).
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    robot: RobotArgs,
    /// Duration (s).
    #[arg(long, default_value_t = 10.0, allow_negative_numbers = true)]
    duration: f64,
    /// Control and logging rate (Hz).
    #[arg(long, default_value_t = 1000.0, allow_negative_numbers = true)]
    rate: f64,
    /// Seeds the motion and the noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[command(flatten)]
    trot: TrotArgs,
    /// Stand still, holding the standing posture (no weight shifting): how the feet share the
    /// robot's weight.
    #[arg(long)]
    still: bool,
    /// Drop the robot: its lowest foot this high above the ground at the start (m).
    #[arg(
        long,
        value_name = "M",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    drop: f64,
    /// Push the robot: the whole robot's velocity at the start, `VX,VY,VZ` (m/s, world axes).
    #[arg(
        long,
        value_name = "VX,VY,VZ",
        value_delimiter = ',',
        allow_negative_numbers = true
    )]
    push: Option<Vec<f64>>,
    /// The ground's friction coefficient μ.
    #[arg(long, value_name = "MU", default_value_t = StartOptions::default().ground_friction, allow_negative_numbers = true)]
    ground_friction: f64,
    /// Sensor noise, `key=value` pairs, comma-separated (keys: torque_noise, force_noise,
    /// gyro_noise, gyro_bias, velocity_noise, velocity_bias, tilt_noise, position_noise,
    /// accel_noise, accel_bias, encoder_step; and velocities, forces, contacts, accelerometer =
    /// true/false for what is logged);
    /// `exact` for noise-free sensors logging everything.
    #[arg(long, value_delimiter = ',')]
    sensors: Vec<String>,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

/// `--trot`, shared by `simulate-floating` and `whole-robot`.
#[derive(clap::Args, Debug)]
pub struct TrotArgs {
    /// Trot in place instead of standing: `CROUCH,HZ`, each diagonal pair of legs in turn
    /// crouched by up to CROUCH rad of the hip (its feet swing) at HZ steps per second.
    #[arg(
        long,
        value_name = "CROUCH,HZ",
        value_delimiter = ',',
        allow_negative_numbers = true
    )]
    trot: Option<Vec<f64>>,
}

impl TrotArgs {
    /// `(crouch rad, frequency Hz)`, or `None` to stand.
    pub fn step(&self) -> anyhow::Result<Option<(f64, f64)>> {
        match self.trot.as_deref() {
            None => Ok(None),
            Some(&[crouch, hz]) => Ok(Some((crouch, hz))),
            Some(_) => anyhow::bail!("--trot: expected CROUCH,HZ (two numbers)"),
        }
    }
}

/// `physid simulate-floating`.
pub fn run_simulate(a: SimulateArgs) -> anyhow::Result<()> {
    let opts = SimulateFloatingOptions {
        robot: a.robot.options(),
        duration: a.duration,
        rate: a.rate,
        seed: a.seed,
        trot: a.trot.step()?,
        still: a.still,
        start: StartOptions {
            drop: a.drop,
            push: match a.push.as_deref() {
                None => [0.0; 3],
                Some(&[x, y, z]) => [x, y, z],
                Some(_) => anyhow::bail!("--push: expected VX,VY,VZ (three numbers)"),
            },
            ground_friction: a.ground_friction,
        },
        sensors: sensors(&a.sensors)?,
        out: a.out,
    };
    let done = simulate_floating(&opts)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&done)?);
    } else {
        println!(
            "wrote {} samples of {} joints and {} feet to {} (feet down {:.1} % of the time), the ground truth to {}",
            done.samples,
            done.joints.len(),
            done.feet.len(),
            done.out.display(),
            100.0 * done.contact_share,
            done.truth.display()
        );
    }
    Ok(())
}

/// The sensors of `--sensors`: `key=value` pairs over the defaults, or `exact`.
fn sensors(pairs: &[String]) -> anyhow::Result<Sensors> {
    let mut table = toml::Table::new();
    let mut base = Sensors::default();
    for p in pairs.iter().map(|p| p.trim()).filter(|p| !p.is_empty()) {
        if p == "exact" {
            base = Sensors::exact();
            continue;
        }
        let (k, v) = p
            .split_once('=')
            .ok_or_else(|| anyhow::anyhow!("--sensors '{p}': expected key=value or exact"))?;
        let value: toml::Value = v
            .trim()
            .parse::<f64>()
            .map(toml::Value::Float)
            .or_else(|_| v.trim().parse::<bool>().map(toml::Value::Boolean))
            .map_err(|_| anyhow::anyhow!("--sensors '{p}': '{v}' is not a number or true/false"))?;
        table.insert(k.trim().to_string(), value);
    }
    let mut merged = toml::Table::try_from(&base)?;
    merged.extend(table);
    let s: Sensors = merged
        .try_into()
        .map_err(|e: toml::de::Error| anyhow::anyhow!("--sensors: {}", e.message()))?;
    s.validate()
        .map_err(|e| anyhow::anyhow!("--sensors: {e}"))?;
    Ok(s)
}

/// Identify a floating robot (the built-in quadruped, or a floating URDF) from one log of the
/// trunk's motion, the joints' and the feet's forces (CSV, MCAP or a rosbag2 directory,
/// docs/floating-base.md "Logs"), its description the prior.
#[derive(clap::Args, Debug)]
pub struct IdentifyArgs {
    /// The log: CSV, MCAP or a rosbag2 directory.
    #[arg(long)]
    data: PathBuf,
    /// MCAP and rosbag2 logs: the joint states' topic (sensor_msgs/msg/JointState).
    #[arg(long, default_value = "/joint_states")]
    topic: String,
    /// MCAP and rosbag2 logs: the trunk's topic (nav_msgs/msg/Odometry: pose in the world,
    /// twist in trunk coordinates), interpolated to the joint states' times.
    #[arg(long, default_value = "/odometry")]
    odometry_topic: String,
    /// MCAP and rosbag2 logs: the feet's topic (physid_msgs/msg/FootForces: per foot, the
    /// ground's force in world coordinates and the contact state).
    #[arg(long, default_value = "/foot_forces")]
    foot_forces_topic: String,
    /// MCAP and rosbag2 logs: the IMU's topic (sensor_msgs/msg/Imu at the trunk frame's
    /// origin), whose accelerometer gives the trunk's linear acceleration where the log has it.
    #[arg(long, default_value = "/imu")]
    imu_topic: String,
    /// MCAP and rosbag2 logs: which time stamps a message, log (the recorder's receive time)
    /// or header (its header.stamp); every topic alike.
    #[arg(long, default_value = "log")]
    stamp: physid::io::mcap_log::Stamp,
    #[command(flatten)]
    robot: RobotArgs,
    /// What the log's quantities are used for: torques-and-contacts (every row),
    /// torques-only (contact forces projected out: needs contact states or forces),
    /// base-only (the trunk's six rows from the contact forces; no joint torques).
    #[arg(long, value_enum, default_value = "torques-and-contacts")]
    setting: SettingArg,
    /// Constraint set: none, semi, consistent, ellipsoid.
    #[arg(long, default_value = "ellipsoid")]
    constraints: ConstraintSet,
    /// Weight of the pull towards the description.
    #[arg(long, default_value_t = 1e-4, allow_negative_numbers = true)]
    prior_weight: f64,
    /// Low-pass cutoff of the derived signals (Hz); default: chosen from the motion.
    #[arg(long, allow_negative_numbers = true)]
    cutoff: Option<f64>,
    /// A foot, `BODY:X,Y,Z` (the point in the body's frame, m); repeat for each. Default: the
    /// built-in quadruped's.
    #[arg(long = "foot", value_name = "BODY:X,Y,Z")]
    feet: Vec<String>,
    /// Without contact_<foot> columns, a foot is down where its normal force exceeds this (N).
    #[arg(long, default_value_t = 10.0, allow_negative_numbers = true)]
    contact_force: f64,
    /// A log of the robot before a change: which body changed is asked against the
    /// description fitted to it (without it, against the description, whose own errors show
    /// as differences).
    #[arg(long = "baseline-data", value_name = "LOG")]
    baseline: Option<PathBuf>,
    /// Write the identified robot as URDF (the trunk its root link; pinocchio: free flyer).
    #[arg(long)]
    out_urdf: Option<PathBuf>,
    /// Write the identified robot as MJCF (a free joint on the trunk).
    #[arg(long)]
    out_mjcf: Option<PathBuf>,
    /// The ground truth, a floating URDF of the same robot (`simulate-floating` writes it
    /// beside its log as <log>.truth.urdf): every body's errors against it are reported.
    #[arg(long)]
    truth: Option<PathBuf>,
    /// Print the result as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(clap::ValueEnum, Debug, Clone, Copy)]
enum SettingArg {
    TorquesAndContacts,
    TorquesOnly,
    BaseOnly,
}

/// `physid identify-floating`.
pub fn run_identify(a: IdentifyArgs) -> anyhow::Result<()> {
    let opts = IdentifyFloatingOptions {
        robot: a.robot.options(),
        data: a.data,
        topics: FloatingReadOptions {
            topic: a.topic,
            stamp: a.stamp,
            odometry_topic: a.odometry_topic,
            foot_forces_topic: a.foot_forces_topic,
            imu_topic: a.imu_topic,
        },
        feet: a
            .feet
            .iter()
            .map(|f| f.parse::<Foot>().map_err(anyhow::Error::msg))
            .collect::<anyhow::Result<_>>()?,
        setting: match a.setting {
            SettingArg::TorquesAndContacts => DataSetting::TorquesAndContacts,
            SettingArg::TorquesOnly => DataSetting::TorquesOnly,
            SettingArg::BaseOnly => DataSetting::BaseOnly,
        },
        constraints: a.constraints,
        prior_weight: a.prior_weight,
        cutoff: a.cutoff,
        contact_force: a.contact_force,
        out_urdf: a.out_urdf,
        out_mjcf: a.out_mjcf,
        truth: a.truth,
        baseline: a.baseline,
    };
    let found = identify_floating(&opts)?;
    for notice in &found.notices {
        eprintln!("{notice}");
    }
    if a.json {
        let value = physid::io::versioned("physid.identify_floating/1", &found);
        println!("{}", serde_json::to_string_pretty(&value)?);
        return Ok(());
    }
    print!("{}", summary(&found));
    super::identify_cmd::print_identifiability(&found.identifiability);
    Ok(())
}

/// The text summary of an identification.
fn summary(f: &physid::api::floating::FloatingIdentification) -> String {
    use std::fmt::Write;
    let mut s = format!(
        "{} from {} ({} setting, {} constraints): {} of {} samples, cutoff {:.2} Hz, feet down {:.1} %\n",
        f.robot,
        f.data.display(),
        physid::io::serde_name(&f.setting),
        physid::io::serde_name(&f.constraints),
        f.samples_used,
        f.samples_read,
        f.cutoff,
        100.0 * f.contact_share
    );
    let _ = writeln!(
        s,
        "rows' RMS {:.4}, residual RMS {:.4} (description) -> {:.4} (identified); total mass {:.3} -> {:.3} kg; constraints {}",
        f.target_rms,
        f.description_rms,
        f.identified_rms,
        f.described_mass,
        f.identified_mass,
        if f.constraints_hold { "hold" } else { "VIOLATED" }
    );
    if let Some(t) = &f.truth {
        let worst = (t.bodies.iter()).max_by(|a, b| a.mass_rel.total_cmp(&b.mass_rel));
        let _ = writeln!(
            s,
            "against the truth ({}): total mass {:.3} kg; worst body mass {}",
            t.file.display(),
            t.mass,
            worst.map_or("-".into(), |w| format!(
                "{} ({:.1} % off)",
                w.name,
                100.0 * w.mass_rel
            ))
        );
    }
    s.push_str(&change_text(&f.change));
    s.push_str(&bodies_text(f));
    s
}

/// Each body's mass and consistency margins, `~` where the log does not determine the mass.
fn bodies_text(f: &physid::api::floating::FloatingIdentification) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let undetermined = undetermined_masses(f);
    for (b, &mark) in f.bodies.iter().zip(&undetermined) {
        let c = &b.consistency;
        let _ = writeln!(
            s,
            "{} {:<16} m {:>8.4} kg  min eig J {:>10.3e}  tr(JQ) {}",
            if mark { '~' } else { ' ' },
            b.name,
            b.pi[0],
            c.min_eig_pseudo,
            c.trace_jq.map_or("-".into(), |t| format!("{t:.3e}"))
        );
    }
    let count = undetermined.iter().filter(|u| **u).count();
    if count > 0 {
        let _ = writeln!(
            s,
            "~ {count} of {} masses are not determined by the log on their own (no finite standard error, or one larger than the mass): the prior and the constraints set them; the base parameters below are what the log determines",
            f.bodies.len()
        );
    }
    s
}

/// A joint's torque gain or friction the log shows differing from the reference, where one is
/// named or set aside (`None`: the bodies tell the story). A gain named comes first: it is
/// weighed after the baseline set a friction change aside.
fn joint_text(c: &physid::api::floating::DescriptionCheck) -> Option<String> {
    let line = |f: &physid::diagnose::floating::FrictionChange| {
        format!(
            "the friction of {} (viscous {:+.3} N m s/rad, Coulomb {:+.3} N m; F {:.1}, residual -{:.1} %)",
            f.joint,
            f.viscous,
            f.coulomb,
            f.f,
            100.0 * f.reduction
        )
    };
    let against = c.baseline.as_ref().map_or("the description".into(), |b| {
        format!("the baseline log {}", b.display())
    });
    if let Some(g) = &c.gain_changed {
        return Some(format!(
            "against {against}: the log differs most in the torque gain of {} ({:+.1} %: the logged torque is {:.3} times the motor's; F {:.1}, residual -{:.1} %), no body or friction\n",
            g.joint,
            100.0 * g.gain,
            1.0 + g.gain,
            g.f,
            100.0 * g.reduction
        ));
    }
    if let (Some(f), Some(seen)) = (&c.friction_unseen_by_baseline, c.baseline_visibility) {
        return Some(format!(
            "against {against}: the log differs most in {}, which the baseline's motion hardly moves ({:.1} % of this log's): no change is named (record the baseline with this log's motion)\n",
            line(f),
            100.0 * seen
        ));
    }
    let f = c.friction_changed.as_ref()?;
    Some(match c.baseline {
        Some(_) => format!("against {against}: {} changed, no body\n", line(f)),
        None => format!(
            "against {against}: the log differs most in {}, no body; a change of the joint or the description's own friction (--baseline-data, a log of the robot before the change, tells them apart)\n",
            line(f)
        ),
    })
}

/// The body the log shows differing from the reference (the description, or its fit to the
/// baseline log), or that none does.
fn change_text(c: &physid::api::floating::DescriptionCheck) -> String {
    if let Some(text) = joint_text(c) {
        return text;
    }
    let line = |b: &physid::diagnose::floating::BodyChange| {
        let at = b.com.map_or(String::new(), |p| {
            format!(" at ({:.3}, {:.3}, {:.3}) m in its frame", p.x, p.y, p.z)
        });
        format!(
            "{} {:+.3} kg{at} (F {:.1}, residual -{:.1} %)",
            b.body,
            b.mass,
            b.f,
            100.0 * b.reduction
        )
    };
    let also = if c.also_fit.is_empty() {
        String::new()
    } else {
        format!("; fitting almost as well: {}", c.also_fit.join(", "))
    };
    if let (Some(b), Some(base), Some(seen)) =
        (&c.unseen_by_baseline, &c.baseline, c.baseline_visibility)
    {
        return format!(
            "against the baseline log {}: the log differs most in {}, which the baseline's motion hardly excites ({:.1} % of this log's): there the baseline cannot tell a change from the description's own error; no change is named (record the baseline with this log's motion)\n",
            base.display(),
            line(b),
            100.0 * seen
        );
    }
    match (&c.changed, &c.baseline) {
        (Some(b), Some(base)) => format!(
            "against the baseline log {}: {} changed{also}\n",
            base.display(),
            line(b)
        ),
        (Some(b), None) => format!(
            "against the description: the log differs most in {}{also}; a change of the robot or the description's own error (--baseline-data, a log of the robot before the change, tells them apart)\n",
            line(b)
        ),
        (None, base) => format!(
            "against the {}: no body differs (F above {} and residual -{} % needed; best {})\n",
            base.as_ref().map_or("description".into(), |b| format!("baseline log {}", b.display())),
            c.min_f,
            100.0 * c.min_reduction,
            c.candidates.first().map_or("-".into(), line)
        ),
    }
}

/// Per body, whether the log leaves its mass undetermined (no finite standard error, or one
/// larger than the mass), as `identify` marks it.
fn undetermined_masses(f: &physid::api::floating::FloatingIdentification) -> Vec<bool> {
    (f.bodies.iter().zip(&f.mass_standard_errors))
        .map(|(b, se)| !se.is_some_and(|e| physid::api::identify::mass_determined(e, b.pi[0])))
        .collect()
}

#[cfg(test)]
mod tests {
    use physid::api::floating::DescriptionCheck;
    use physid::diagnose::floating::{FrictionChange, GainChange};

    /// A check against a baseline that set a friction change aside and then named a gain.
    fn gain_after_unseen_friction() -> DescriptionCheck {
        DescriptionCheck {
            baseline: Some("before.csv".into()),
            min_f: 10.0,
            min_reduction: 0.05,
            changed: None,
            also_fit: vec![],
            candidates: vec![],
            baseline_visibility: Some(0.01),
            unseen_by_baseline: None,
            friction_changed: None,
            friction_candidates: vec![],
            friction_unseen_by_baseline: Some(FrictionChange {
                joint: "fr_knee_joint".into(),
                columns: [0, 1],
                viscous: 0.1,
                coulomb: 0.2,
                reduction: 0.06,
                f: 50.0,
                determined: 2,
            }),
            gain_changed: Some(GainChange {
                joint: "hl_abad_joint".into(),
                gain: -0.15,
                reduction: 0.02,
                joint_reduction: 0.7,
                f: 900.0,
            }),
            gain_candidates: vec![],
        }
    }

    #[test]
    fn a_gain_named_is_said_even_where_the_baseline_set_a_friction_change_aside() {
        let text = super::change_text(&gain_after_unseen_friction());
        assert!(
            text.contains("torque gain of hl_abad_joint (-15.0 %"),
            "{text}"
        );
        assert!(!text.contains("no change is named"), "{text}");
        let mut without_gain = gain_after_unseen_friction();
        without_gain.gain_changed = None;
        let text = super::change_text(&without_gain);
        assert!(
            text.contains("fr_knee_joint") && text.contains("no change is named"),
            "{text}"
        );
    }
}
