//! MCAP logs, and rosbag2 directories (MCAP or SQLite), of floating-base robots
//! (docs/floating-base.md, "Logs"). Channels (CDR, `ros2msg` schemas):
//!
//! - `/joint_states` (`sensor_msgs/msg/JointState`): encoder positions (rad), velocities if
//!   logged (rad/s), the motors' torques (N m) in `effort`;
//! - `/odometry` (`nav_msgs/msg/Odometry`), as a state estimator publishes it: the trunk's pose
//!   in the world (`header.frame_id`), its twist in trunk coordinates (`child_frame_id`: the
//!   angular velocity, rad/s, and the velocity of the trunk frame's origin, m/s);
//! - `/foot_forces` (`physid_msgs/msg/FootForces`, optional): per foot by name, the ground's
//!   force on it in world coordinates (N, `force` holding x, y, z of each foot in turn) and
//!   whether it is in contact; either array may be empty (not logged);
//! - `/imu` (`sensor_msgs/msg/Imu`, optional): the IMU at the trunk frame's origin, of which
//!   the accelerometer's `linear_acceleration` is read (the specific force, m/s², trunk
//!   coordinates); its orientation and angular velocity are the odometry's business.
//!
//! **Reading** takes the joint states' times as the samples' times and brings the other topics
//! to them: the trunk's position and twist and the feet's forces linearly interpolated between
//! the two messages around each sample, its orientation normalized-linearly, a contact state
//! the last one at or before it. Joint samples before or after what the other topics cover are
//! left out and counted; a topic silent for more than [`GAP_FACTOR`] times its median spacing
//! around a sample is refused (nothing to interpolate). Every value is checked (finite, within
//! 10⁶, unit quaternions), naming the topic and the message.

use super::floating_log::{FloatingLog, QUATERNION_NORM_TOLERANCE};
use super::mcap_log::{self, cdr_into, header_defs, Header, ReadOptions, Stamp, SEP};
use super::IoError;
use crate::prepare::Logged;
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use physid_core::spatial::Motion;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The trunk's topic.
pub const TOPIC_ODOMETRY: &str = "/odometry";
/// The feet's topic.
pub const TOPIC_FOOT_FORCES: &str = "/foot_forces";
/// The feet's message type.
pub const FOOT_FORCES_TYPE: &str = "physid_msgs/msg/FootForces";
/// The IMU's topic.
pub const TOPIC_IMU: &str = "/imu";
/// The message types that are `sensor_msgs/Imu` (ROS 2, and ROS 1 in MCAP).
const IMU_TYPES: [&str; 2] = ["sensor_msgs/msg/Imu", "sensor_msgs/Imu"];
/// The message types that are `nav_msgs/Odometry` (ROS 2, and ROS 1 in MCAP).
const ODOMETRY_TYPES: [&str; 2] = ["nav_msgs/msg/Odometry", "nav_msgs/Odometry"];
/// A topic silent for longer than this many times its median spacing cannot be interpolated.
pub const GAP_FACTOR: f64 = 10.0;
/// Format version in the `physid` metadata record.
pub const FORMAT: &str = "physid-floating-mcap-1";

/// `geometry_msgs/msg/Vector3` (and `Point`).
#[derive(Serialize, Deserialize, Debug, Clone, Copy, PartialEq)]
struct Xyz {
    x: f64,
    y: f64,
    z: f64,
}

/// `geometry_msgs/msg/Quaternion`.
#[derive(Serialize, Deserialize, Debug, Clone, Copy, PartialEq)]
struct Xyzw {
    x: f64,
    y: f64,
    z: f64,
    w: f64,
}

/// A `float64[36]` covariance (serde has no 36-element arrays: two halves, the same CDR).
#[derive(Serialize, Deserialize, Debug, Clone, Copy, PartialEq)]
struct Covariance([f64; 18], [f64; 18]);

/// `nav_msgs/msg/Odometry`.
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
struct Odometry {
    header: Header,
    child_frame_id: String,
    position: Xyz,
    orientation: Xyzw,
    pose_covariance: Covariance,
    linear: Xyz,
    angular: Xyz,
    twist_covariance: Covariance,
}

/// `sensor_msgs/msg/Imu`.
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
struct Imu {
    header: Header,
    orientation: Xyzw,
    orientation_covariance: [f64; 9],
    angular_velocity: Xyz,
    angular_velocity_covariance: [f64; 9],
    linear_acceleration: Xyz,
    linear_acceleration_covariance: [f64; 9],
}

/// `physid_msgs/msg/FootForces`.
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
struct FootForces {
    header: Header,
    name: Vec<String>,
    force: Vec<f64>,
    contact: Vec<bool>,
}

fn odometry_schema() -> String {
    format!(
        "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist\n{}{SEP}\nMSG: geometry_msgs/PoseWithCovariance\nPose pose\nfloat64[36] covariance\n{SEP}\nMSG: geometry_msgs/Pose\nPoint position\nQuaternion orientation\n{SEP}\nMSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n{SEP}\nMSG: geometry_msgs/Quaternion\nfloat64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n{SEP}\nMSG: geometry_msgs/TwistWithCovariance\nTwist twist\nfloat64[36] covariance\n{SEP}\nMSG: geometry_msgs/Twist\nVector3 linear\nVector3 angular\n{SEP}\nMSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n",
        header_defs()
    )
}

fn imu_schema() -> String {
    format!(
        "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\ngeometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\ngeometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n{}{SEP}\nMSG: geometry_msgs/Quaternion\nfloat64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n{SEP}\nMSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n",
        header_defs()
    )
}

fn foot_forces_schema() -> String {
    format!(
        "# physid: the ground's force on each foot (N, world coordinates: x, y, z of each foot in\n# turn) and whether the foot is in contact; an empty array: not logged\nstd_msgs/Header header\nstring[] name\nfloat64[] force\nbool[] contact\n{}",
        header_defs()
    )
}

/// Writes `log` as MCAP (see the module docs), its odometry's `child_frame_id` `trunk`,
/// atomically.
pub fn write(path: &Path, log: &FloatingLog, trunk: &str) -> Result<(), IoError> {
    mcap_log::write_atomic_mcap(path, |w| {
        let channels = add_channels(w, log)?;
        write_messages(w, log, trunk, channels)?;
        let physid = mcap::records::Metadata {
            name: "physid".into(),
            metadata: [
                ("format", FORMAT.to_string()),
                ("version", env!("CARGO_PKG_VERSION").to_string()),
            ]
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect(),
        };
        w.write_metadata(&physid)
    })
}

/// The channels of `log`: joint states, odometry, the feet's if it logs forces or contacts, the
/// IMU's if it logs an accelerometer.
struct Channels {
    joints: u16,
    odometry: u16,
    feet: Option<u16>,
    imu: Option<u16>,
}

/// Adds [`Channels`] for `log` to `w`.
fn add_channels<W: std::io::Write + std::io::Seek>(
    w: &mut mcap::Writer<W>,
    log: &FloatingLog,
) -> Result<Channels, mcap::McapError> {
    let none = BTreeMap::new();
    let mut channel = |kind: &str, schema: String, topic: &str| -> Result<u16, mcap::McapError> {
        let s = w.add_schema(kind, "ros2msg", schema.as_bytes())?;
        w.add_channel(s, topic, "cdr", &none)
    };
    let joints = channel(
        "sensor_msgs/msg/JointState",
        mcap_log::joint_state_schema(),
        mcap_log::TOPIC_MEASURED,
    )?;
    let odometry = channel(ODOMETRY_TYPES[0], odometry_schema(), TOPIC_ODOMETRY)?;
    let feet = if log.force.is_some() || log.contact.is_some() {
        Some(channel(
            FOOT_FORCES_TYPE,
            foot_forces_schema(),
            TOPIC_FOOT_FORCES,
        )?)
    } else {
        None
    };
    let imu = match log.accel {
        Some(_) => Some(channel(IMU_TYPES[0], imu_schema(), TOPIC_IMU)?),
        None => None,
    };
    Ok(Channels {
        joints,
        odometry,
        feet,
        imu,
    })
}

/// One message per sample on each channel, log time = the sample's time.
fn write_messages<W: std::io::Write + std::io::Seek>(
    w: &mut mcap::Writer<W>,
    log: &FloatingLog,
    trunk: &str,
    channels: Channels,
) -> Result<(), mcap::McapError> {
    let j = &log.joints;
    let (n, f) = (j.dof(), log.feet.len());
    let zero = Covariance([0.0; 18], [0.0; 18]);
    let mut buf = Vec::new();
    for k in 0..log.len() {
        let (header, ns) = mcap_log::stamp(j.t[k]);
        let mh = |channel_id| mcap::records::MessageHeader {
            channel_id,
            sequence: k as u32,
            log_time: ns,
            publish_time: ns,
        };
        let msg = mcap_log::JointStateView {
            header: &header,
            name: &j.joint_names,
            position: &j.q[k * n..(k + 1) * n],
            velocity: j.qd.as_ref().map_or(&[][..], |v| &v[k * n..(k + 1) * n]),
            effort: &j.tau[k * n..(k + 1) * n],
        };
        w.write_to_known_channel(&mh(channels.joints), cdr_into(&mut buf, &msg))?;
        let msg = odometry_of(log, k, &header, trunk, zero);
        w.write_to_known_channel(&mh(channels.odometry), cdr_into(&mut buf, &msg))?;
        if let Some(c) = channels.feet {
            let msg = FootForces {
                header: Header {
                    frame_id: "world".into(),
                    ..header.clone()
                },
                name: log.feet.clone(),
                force: (log.force.as_ref()).map_or(vec![], |v| {
                    v[k * f..(k + 1) * f]
                        .iter()
                        .flat_map(|x| x.iter().copied())
                        .collect()
                }),
                contact: log
                    .contact
                    .as_ref()
                    .map_or(vec![], |v| v[k * f..(k + 1) * f].to_vec()),
            };
            w.write_to_known_channel(&mh(c), cdr_into(&mut buf, &msg))?;
        }
        if let (Some(c), Some(accel)) = (channels.imu, &log.accel) {
            let msg = imu_of(log, k, &header, trunk, &accel[k]);
            w.write_to_known_channel(&mh(c), cdr_into(&mut buf, &msg))?;
        }
    }
    Ok(())
}

/// Sample `k`'s IMU in `trunk` coordinates: the odometry's orientation and angular velocity,
/// the accelerometer's `accel`; covariances unknown (zero).
fn imu_of(log: &FloatingLog, k: usize, header: &Header, trunk: &str, accel: &Vector3<f64>) -> Imu {
    let q = UnitQuaternion::from_matrix(&log.rotation[k]);
    let w = log.twist[k].ang;
    Imu {
        header: Header {
            frame_id: trunk.into(),
            ..header.clone()
        },
        orientation: Xyzw {
            x: q.i,
            y: q.j,
            z: q.k,
            w: q.w,
        },
        orientation_covariance: [0.0; 9],
        angular_velocity: Xyz {
            x: w.x,
            y: w.y,
            z: w.z,
        },
        angular_velocity_covariance: [0.0; 9],
        linear_acceleration: Xyz {
            x: accel.x,
            y: accel.y,
            z: accel.z,
        },
        linear_acceleration_covariance: [0.0; 9],
    }
}

/// Sample `k`'s trunk as odometry: pose in `world`, twist in `trunk` coordinates.
fn odometry_of(
    log: &FloatingLog,
    k: usize,
    header: &Header,
    trunk: &str,
    zero: Covariance,
) -> Odometry {
    let q = UnitQuaternion::from_matrix(&log.rotation[k]);
    let (p, v) = (log.position[k], &log.twist[k]);
    let xyz = |a: &Vector3<f64>| Xyz {
        x: a.x,
        y: a.y,
        z: a.z,
    };
    Odometry {
        header: Header {
            frame_id: "world".into(),
            ..header.clone()
        },
        child_frame_id: trunk.into(),
        position: xyz(&p),
        orientation: Xyzw {
            x: q.i,
            y: q.j,
            z: q.k,
            w: q.w,
        },
        pose_covariance: zero,
        linear: xyz(&v.lin),
        angular: xyz(&v.ang),
        twist_covariance: zero,
    }
}

/// How a floating log is read from MCAP or a rosbag2 directory.
#[derive(Clone, Debug, PartialEq)]
pub struct FloatingReadOptions {
    /// The joint states' topic (`sensor_msgs/msg/JointState`).
    pub topic: String,
    /// Which time stamps a message: the recorder's log time or the header's stamp (every topic
    /// alike).
    pub stamp: Stamp,
    /// The trunk's topic (`nav_msgs/msg/Odometry`).
    pub odometry_topic: String,
    /// The feet's topic (`physid_msgs/msg/FootForces`).
    pub foot_forces_topic: String,
    /// The IMU's topic (`sensor_msgs/msg/Imu`): its accelerometer, where the log has the topic.
    pub imu_topic: String,
}

impl Default for FloatingReadOptions {
    fn default() -> Self {
        Self {
            topic: mcap_log::TOPIC_MEASURED.into(),
            stamp: Stamp::Log,
            odometry_topic: TOPIC_ODOMETRY.into(),
            foot_forces_topic: TOPIC_FOOT_FORCES.into(),
            imu_topic: TOPIC_IMU.into(),
        }
    }
}

/// A floating log read from MCAP or a rosbag2 directory.
#[derive(Clone, Debug)]
pub struct FloatingRead {
    /// The samples, at the joint states' times.
    pub log: FloatingLog,
    /// Joint samples left out before the first and after the last time the trunk's (and the
    /// feet's) messages cover.
    pub left_out: (usize, usize),
    /// The files read.
    pub files: Vec<PathBuf>,
}

/// One trunk message: its two clocks' times (ns: log, header) and what it says.
struct TrunkMessage {
    ns: [u64; 2],
    sequence: u64,
    position: Vector3<f64>,
    orientation: UnitQuaternion<f64>,
    twist: Motion,
}

/// One feet message, in the order of the feet asked for.
struct FeetMessage {
    ns: [u64; 2],
    sequence: u64,
    force: Option<Vec<Vector3<f64>>>,
    contact: Option<Vec<bool>>,
}

/// One accelerometer reading.
struct ImuMessage {
    ns: [u64; 2],
    sequence: u64,
    accel: Vector3<f64>,
}

/// The trunk's, the feet's and the IMU's messages collected while the joint states are read.
struct Collector<'a> {
    opts: &'a FloatingReadOptions,
    feet: &'a [String],
    trunk: Vec<TrunkMessage>,
    feet_messages: Vec<FeetMessage>,
    imu: Vec<ImuMessage>,
    /// The other topics seen (name → type), for errors.
    topics: BTreeMap<String, String>,
}

impl Collector<'_> {
    fn message(
        &mut self,
        topic: &str,
        kind: &str,
        data: &[u8],
        (log_time, sequence): (u64, u64),
    ) -> Result<(), String> {
        self.topics
            .entry(topic.into())
            .or_insert_with(|| kind.into());
        if topic == self.opts.odometry_topic {
            if !ODOMETRY_TYPES.contains(&kind) {
                return Err(format!("carries {kind}, not nav_msgs/msg/Odometry"));
            }
            self.trunk.push(trunk_message(data, (log_time, sequence))?);
        } else if topic == self.opts.foot_forces_topic {
            if kind != FOOT_FORCES_TYPE {
                return Err(format!("carries {kind}, not {FOOT_FORCES_TYPE}"));
            }
            let first = self.feet_messages.first();
            let m = feet_message(data, (log_time, sequence), self.feet, first)?;
            self.feet_messages.push(m);
        } else if topic == self.opts.imu_topic {
            if !IMU_TYPES.contains(&kind) {
                return Err(format!("carries {kind}, not sensor_msgs/msg/Imu"));
            }
            check_string_lengths(data, &["header.frame_id"])?;
            let m: Imu = cdr::deserialize(data).map_err(|e| e.to_string())?;
            self.imu.push(ImuMessage {
                ns: [log_time, mcap_log::header_ns(&m.header)?],
                sequence,
                accel: vector("linear_acceleration", m.linear_acceleration)?,
            });
        }
        Ok(())
    }
}

/// A value as a log may hold it: finite, within 10⁶.
fn checked(what: &str, v: f64) -> Result<f64, String> {
    if v.is_finite() && v.abs() <= 1e6 {
        Ok(v)
    } else {
        Err(format!("{what} is {v}, not a finite value"))
    }
}

fn vector(what: &str, a: Xyz) -> Result<Vector3<f64>, String> {
    Ok(Vector3::new(
        checked(&format!("{what}.x"), a.x)?,
        checked(&format!("{what}.y"), a.y)?,
        checked(&format!("{what}.z"), a.z)?,
    ))
}

/// Checks the lengths of the strings that open a message after its header's stamp (the
/// header's frame, and an odometry's child frame) against the bytes that remain, before the
/// decoder allocates them.
fn check_string_lengths(data: &[u8], strings: &[&str]) -> Result<(), String> {
    let (payload, little) = mcap_log::cdr_payload(data)?;
    let mut pos = 8usize;
    for what in strings {
        pos = pos.next_multiple_of(4);
        let bytes: [u8; 4] = payload
            .get(pos..pos + 4)
            .and_then(|b| b.try_into().ok())
            .ok_or_else(|| format!("ends before its {what}"))?;
        let len = if little {
            u32::from_le_bytes(bytes)
        } else {
            u32::from_be_bytes(bytes)
        } as usize;
        pos += 4;
        if len > payload.len().saturating_sub(pos) {
            return Err(format!("its {what} claims {len} bytes, more than remain"));
        }
        pos += len;
    }
    Ok(())
}

fn trunk_message(data: &[u8], (log_time, sequence): (u64, u64)) -> Result<TrunkMessage, String> {
    check_string_lengths(data, &["header.frame_id", "child_frame_id"])?;
    let m: Odometry = cdr::deserialize(data).map_err(|e| e.to_string())?;
    let o = m.orientation;
    let quaternion = Quaternion::new(
        checked("pose.orientation.w", o.w)?,
        checked("pose.orientation.x", o.x)?,
        checked("pose.orientation.y", o.y)?,
        checked("pose.orientation.z", o.z)?,
    );
    if (quaternion.norm() - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
        return Err(format!(
            "pose.orientation's norm is {:.4}, not 1 (a unit quaternion)",
            quaternion.norm()
        ));
    }
    Ok(TrunkMessage {
        ns: [log_time, mcap_log::header_ns(&m.header)?],
        sequence,
        position: vector("pose.position", m.position)?,
        orientation: UnitQuaternion::from_quaternion(quaternion),
        twist: Motion::new(
            vector("twist.angular", m.angular)?,
            vector("twist.linear", m.linear)?,
        ),
    })
}

/// One feet message, its feet in the order of `feet`; what it logs (forces, contacts) must be
/// what the `first` message logged.
fn feet_message(
    data: &[u8],
    (log_time, sequence): (u64, u64),
    feet: &[String],
    first: Option<&FeetMessage>,
) -> Result<FeetMessage, String> {
    mcap_log::check_cdr_lengths(data, 1)?;
    let m: FootForces = cdr::deserialize(data).map_err(|e| e.to_string())?;
    let index: Vec<usize> = (feet.iter())
        .map(|f| {
            m.name
                .iter()
                .position(|n| n == f)
                .ok_or_else(|| format!("names the feet {:?}, not the foot '{f}'", m.name))
        })
        .collect::<Result<_, _>>()?;
    let n = m.name.len();
    if !(m.force.is_empty() || m.force.len() == 3 * n)
        || !(m.contact.is_empty() || m.contact.len() == n)
    {
        return Err(format!(
            "{} forces and {} contacts for {n} feet (3 and 1 per foot, or none)",
            m.force.len(),
            m.contact.len()
        ));
    }
    let force = (!m.force.is_empty())
        .then(|| {
            (index.iter())
                .map(|&i| {
                    let f = &m.force[3 * i..3 * i + 3];
                    vector(
                        &format!("force of '{}'", m.name[i]),
                        Xyz {
                            x: f[0],
                            y: f[1],
                            z: f[2],
                        },
                    )
                })
                .collect::<Result<Vec<_>, _>>()
        })
        .transpose()?;
    let contact = (!m.contact.is_empty()).then(|| index.iter().map(|&i| m.contact[i]).collect());
    if let Some(f) = first {
        if f.force.is_some() != force.is_some() || f.contact.is_some() != contact.is_some() {
            return Err("logs forces or contacts where the first message did not, or not where it did: every message alike".into());
        }
    }
    Ok(FeetMessage {
        ns: [log_time, mcap_log::header_ns(&m.header)?],
        sequence,
        force,
        contact,
    })
}

/// Reads a floating log from an MCAP file or a rosbag2 directory: the joint states matched to
/// `joints` by name, the trunk and the feet (those of `feet`) at the joint states' times (see
/// the module docs). Errors name the file, the topic and the message.
pub fn read(
    path: &Path,
    joints: &[String],
    feet: &[String],
    opts: &FloatingReadOptions,
) -> Result<FloatingRead, IoError> {
    let bad = |m: String| IoError::invalid(path, m);
    let joint_opts = ReadOptions {
        topic: opts.topic.clone(),
        stamp: opts.stamp,
        joints: Some(joints.to_vec()),
        physid_samples: mcap_log::PhysidSamples::None,
    };
    let mut collector = Collector {
        opts,
        feet,
        trunk: vec![],
        feet_messages: vec![],
        imu: vec![],
        topics: BTreeMap::new(),
    };
    let log = {
        let mut sink = |topic: &str, kind: &str, data: &[u8], log_time: u64, seq: u64| {
            collector.message(topic, kind, data, (log_time, seq))
        };
        let reader = mcap_log::Reader::with_others(&joint_opts, &mut sink);
        super::read_log(path, reader)?
    };
    let (measured, _) = super::match_joints(log.measured, joints).map_err(bad)?;
    if collector.trunk.is_empty() {
        return Err(bad(format!(
            "no {} messages (nav_msgs/msg/Odometry): a floating-base log has the trunk's pose and twist; other topics: {}",
            opts.odometry_topic,
            topic_list(&collector.topics)
        )));
    }
    let origin = log.clock_origin_ns.unwrap_or(0);
    let aligned = Aligned::new(&measured.t, &collector, opts, origin).map_err(bad)?;
    Ok(FloatingRead {
        log: aligned.log(measured, &collector),
        left_out: aligned.left_out(),
        files: log.files,
    })
}

fn topic_list(topics: &BTreeMap<String, String>) -> String {
    if topics.is_empty() {
        return "none".into();
    }
    (topics.iter())
        .map(|(t, k)| format!("{t} ({k})"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Where each joint sample falls among a topic's messages: `(i, s)` for `(1 − s)` of message `i`
/// and `s` of message `i + 1` (`s = 0` when the message is alone), `None` outside their span.
type Bracket = Option<(usize, f64)>;

/// The joint samples' places among the trunk's and the feet's messages.
struct Aligned {
    trunk: Vec<Bracket>,
    /// Message indices of the trunk sorted by time.
    trunk_order: Vec<usize>,
    feet: Option<(Vec<Bracket>, Vec<usize>)>,
    imu: Option<(Vec<Bracket>, Vec<usize>)>,
    /// The joint samples kept.
    kept: std::ops::Range<usize>,
    samples: usize,
}

impl Aligned {
    fn new(
        t: &[f64],
        c: &Collector,
        opts: &FloatingReadOptions,
        origin: u64,
    ) -> Result<Self, String> {
        let clock = opts.stamp as usize;
        let seconds = |ns: u64| (ns as i128 - origin as i128) as f64 / 1e9;
        let trunk_times: Vec<(f64, u64)> = (c.trunk.iter())
            .map(|m| (seconds(m.ns[clock]), m.sequence))
            .collect();
        let hint = |e: String| stamp_hint(e, opts.stamp);
        let (trunk_order, trunk) = brackets(t, &trunk_times, &opts.odometry_topic).map_err(hint)?;
        let optional = |times: Vec<(f64, u64)>, topic: &str| {
            (!times.is_empty())
                .then(|| brackets(t, &times, topic).map(|(order, b)| (b, order)))
                .transpose()
                .map_err(hint)
        };
        let feet_times = (c.feet_messages.iter()).map(|m| (seconds(m.ns[clock]), m.sequence));
        let feet = optional(feet_times.collect(), &opts.foot_forces_topic)?;
        let imu_times = (c.imu.iter()).map(|m| (seconds(m.ns[clock]), m.sequence));
        let imu = optional(imu_times.collect(), &opts.imu_topic)?;
        let covered = |o: &Option<(Vec<Bracket>, Vec<usize>)>, k: usize| {
            o.as_ref().is_none_or(|(b, _)| b[k].is_some())
        };
        let inside = |k: usize| trunk[k].is_some() && covered(&feet, k) && covered(&imu, k);
        let first = (0..t.len()).find(|&k| inside(k));
        let Some(first) = first else {
            let others: String = [
                feet.as_ref()
                    .map(|_| format!(" with {}", opts.foot_forces_topic)),
                imu.as_ref().map(|_| format!(" and {}", opts.imu_topic)),
            ]
            .into_iter()
            .flatten()
            .collect();
            return Err(format!(
                "the joint states ({} samples) and {} do not overlap in time{others}",
                t.len(),
                opts.odometry_topic,
            ));
        };
        let end = (first..t.len()).find(|&k| !inside(k)).unwrap_or(t.len());
        if let Some(k) = (end..t.len()).find(|&k| inside(k)) {
            return Err(format!(
                "joint sample {k} (t = {:.6} s) lies inside the span of the trunk's and feet's messages after sample {end} lay outside: the joint states' times go back",
                t[k]
            ));
        }
        Ok(Self {
            trunk,
            trunk_order,
            feet,
            imu,
            kept: first..end,
            samples: t.len(),
        })
    }

    fn left_out(&self) -> (usize, usize) {
        (self.kept.start, self.samples - self.kept.end)
    }

    /// The floating log of the kept samples.
    fn log(&self, measured: Logged, c: &Collector) -> FloatingLog {
        let n = measured.dof();
        let r = self.kept.clone();
        let flat = |v: &[f64]| v[r.start * n..r.end * n].to_vec();
        let joints = Logged {
            t: measured.t[r.clone()].to_vec(),
            q: flat(&measured.q),
            qd: measured.qd.as_deref().map(flat),
            qdd: measured.qdd.as_deref().map(flat),
            tau: flat(&measured.tau),
            joint_names: measured.joint_names,
        };
        let mut log = FloatingLog {
            joints,
            rotation: vec![],
            position: vec![],
            twist: vec![],
            feet: c.feet.to_vec(),
            force: None,
            contact: None,
            accel: None,
        };
        for k in r {
            let (i, s) = self.trunk[k].expect("kept samples lie inside");
            let (a, b) = (
                &c.trunk[self.trunk_order[i]],
                &c.trunk[self.trunk_order[(i + 1).min(self.trunk_order.len() - 1)]],
            );
            log.position.push(a.position.lerp(&b.position, s));
            log.rotation.push(
                nlerp(&a.orientation, &b.orientation, s)
                    .to_rotation_matrix()
                    .into_inner(),
            );
            log.twist.push(Motion::new(
                a.twist.ang.lerp(&b.twist.ang, s),
                a.twist.lin.lerp(&b.twist.lin, s),
            ));
            if let Some((brackets, order)) = &self.feet {
                let (i, s) = brackets[k].expect("kept samples lie inside");
                let a = &c.feet_messages[order[i]];
                let b = &c.feet_messages[order[(i + 1).min(order.len() - 1)]];
                if let (Some(fa), Some(fb)) = (&a.force, &b.force) {
                    let out = log.force.get_or_insert_with(Vec::new);
                    out.extend(fa.iter().zip(fb).map(|(x, y)| x.lerp(y, s)));
                }
                // The state last reported (`s < 1`: message `i` is at or before the sample).
                if let Some(held) = &a.contact {
                    log.contact.get_or_insert_with(Vec::new).extend(held);
                }
            }
            if let Some((brackets, order)) = &self.imu {
                let (i, s) = brackets[k].expect("kept samples lie inside");
                let a = &c.imu[order[i]].accel;
                let b = &c.imu[order[(i + 1).min(order.len() - 1)]].accel;
                log.accel.get_or_insert_with(Vec::new).push(a.lerp(b, s));
            }
        }
        log
    }
}

/// The orientation a share `s` of the way from `a` to `b` (normalized linear interpolation on
/// the shorter arc: for the small turns between two messages, slerp to within `O(θ³)`).
fn nlerp(a: &UnitQuaternion<f64>, b: &UnitQuaternion<f64>, s: f64) -> UnitQuaternion<f64> {
    let (qa, mut qb) = (a.into_inner(), b.into_inner());
    if qa.dot(&qb) < 0.0 {
        qb = -qb;
    }
    UnitQuaternion::from_quaternion(qa * (1.0 - s) + qb * s)
}

/// `error` (of [`brackets`]) with, where messages share a time under header stamps, what
/// usually causes it.
fn stamp_hint(error: String, stamp: Stamp) -> String {
    if stamp == Stamp::Header && error.starts_with("two ") {
        format!("{error}: with --stamp header a message's time is its header.stamp, and a publisher that leaves it unset stamps every message alike (--stamp log takes the recorder's times)")
    } else {
        error
    }
}

/// The messages' order by time and each sample's bracket among them (`times`: each message's
/// time, s, and sequence number); `Err` for two messages at one time or a sample inside a gap
/// of more than [`GAP_FACTOR`] times the median spacing.
fn brackets(
    t: &[f64],
    times: &[(f64, u64)],
    topic: &str,
) -> Result<(Vec<usize>, Vec<Bracket>), String> {
    let mut order: Vec<usize> = (0..times.len()).collect();
    order.sort_by(|&a, &b| times[a].0.total_cmp(&times[b].0));
    let sorted: Vec<f64> = order.iter().map(|&i| times[i].0).collect();
    if let Some(w) = sorted.windows(2).position(|w| w[1] <= w[0]) {
        let (a, b) = (times[order[w]].1, times[order[w + 1]].1);
        return Err(format!(
            "two {topic} messages at the same time, {:.9} s (messages {} and {})",
            sorted[w],
            a.min(b),
            a.max(b)
        ));
    }
    let mut spacing: Vec<f64> = sorted.windows(2).map(|w| w[1] - w[0]).collect();
    spacing.sort_by(f64::total_cmp);
    let gap = spacing
        .get(spacing.len() / 2)
        .map_or(f64::INFINITY, |m| GAP_FACTOR * m);
    let mut out = Vec::with_capacity(t.len());
    for (k, &tk) in t.iter().enumerate() {
        let i = sorted.partition_point(|&x| x <= tk);
        out.push(match i {
            0 => None,
            i if i == sorted.len() => (sorted[i - 1] == tk).then_some((i - 1, 0.0)),
            i => {
                let (a, b) = (sorted[i - 1], sorted[i]);
                if b - a > gap {
                    return Err(format!(
                        "{topic} is silent for {:.4} s around joint sample {k} (t = {tk:.6} s), more than {GAP_FACTOR} times its median spacing of {:.4} s: nothing to interpolate the sample from",
                        b - a,
                        gap / GAP_FACTOR
                    ));
                }
                Some((i - 1, (tk - a) / (b - a)))
            }
        });
    }
    Ok((order, out))
}

#[cfg(test)]
mod tests;
