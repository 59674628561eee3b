//! MCAP logs of experiments, readable by Foxglove and ROS 2 tools.
//!
//! Channels (CDR-encoded, `ros2msg` schemas, log time = experiment time in ns):
//! - `/joint_states` (`sensor_msgs/msg/JointState`): what the robot logs: encoder positions
//!   (rad), the controller's velocity (rad/s), the logged torque (N m) in `effort`;
//! - `/physid/processed` (`physid_msgs/msg/JointSample`): the offline-processed q, q̇, q̈ and
//!   torque that identification uses;
//! - `/physid/ground_truth` (`physid_msgs/msg/JointSample`): true q, q̇, q̈, the torque the
//!   actuators delivered, the true friction and effect torques.
//!
//! Metadata records: `physid` (format version, engine, rate), `scenario` (`toml`: the scenario
//! text) and `ground_truth_parameters` (`names`, `values`: JSON arrays of θ). Files are written
//! to a temporary file beside the target and renamed when complete.

use super::samples::{Logged, Trajectory};
use super::IoError;
use physid_core::trajectory::Recording;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// `builtin_interfaces/msg/Time`.
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
pub(crate) struct Time {
    pub(crate) sec: i32,
    pub(crate) nanosec: u32,
}

/// `std_msgs/msg/Header`.
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
pub(crate) struct Header {
    pub(crate) stamp: Time,
    pub(crate) frame_id: String,
}

/// `sensor_msgs/msg/JointState`.
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
struct JointState {
    header: Header,
    name: Vec<String>,
    position: Vec<f64>,
    velocity: Vec<f64>,
    effort: Vec<f64>,
}

/// `physid_msgs/msg/JointSample`.
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
pub(super) struct JointSample {
    header: Header,
    pub(super) name: Vec<String>,
    pub(super) position: Vec<f64>,
    pub(super) velocity: Vec<f64>,
    pub(super) acceleration: Vec<f64>,
    pub(super) effort: Vec<f64>,
    friction: Vec<f64>,
    effects: Vec<f64>,
}

/// A `sensor_msgs/msg/JointState` to write, borrowing its arrays: the same CDR as
/// [`JointState`] (serde writes a slice as the sequence a `Vec` is), without copying a sample.
#[derive(Serialize)]
pub(crate) struct JointStateView<'a> {
    pub(crate) header: &'a Header,
    pub(crate) name: &'a [String],
    pub(crate) position: &'a [f64],
    pub(crate) velocity: &'a [f64],
    pub(crate) effort: &'a [f64],
}

/// A `physid_msgs/msg/JointSample` to write, borrowing its arrays (the same CDR as
/// [`JointSample`]).
#[derive(Serialize)]
struct JointSampleView<'a> {
    header: &'a Header,
    name: &'a [String],
    position: &'a [f64],
    velocity: &'a [f64],
    acceleration: &'a [f64],
    effort: &'a [f64],
    friction: &'a [f64],
    effects: &'a [f64],
}

impl<'a> JointSampleView<'a> {
    /// Sample `k` of `tr` (q, q̇, q̈ when logged, τ) for the joints `names`, without friction or
    /// effect torques.
    fn at(header: &'a Header, names: &'a [String], tr: &'a Trajectory, k: usize) -> Self {
        JointSampleView {
            header,
            name: names,
            position: tr.q_at(k),
            velocity: tr.qd_at(k),
            acceleration: tr.qdd_at(k).unwrap_or_default(),
            effort: tr.tau_at(k),
            friction: &[],
            effects: &[],
        }
    }
}

/// A CDR message's payload (after its 4-byte encapsulation header) and whether it is
/// little-endian.
pub(super) fn cdr_payload(data: &[u8]) -> Result<(&[u8], bool), String> {
    let payload = data
        .get(4..)
        .ok_or("shorter than its CDR encapsulation header")?;
    let little = match data[..2] {
        [0, 1] | [0, 3] => true,
        [0, 0] | [0, 2] => false,
        _ => return Err(format!("unknown CDR encapsulation {:02x?}", &data[..2])),
    };
    Ok((payload, little))
}

/// Checks every length of a CDR-encoded `JointState`-like message (header, names, then
/// `float_sequences` sequences of `float64`) against the bytes that remain, before the decoder
/// allocates anything: a corrupt length would otherwise make it reserve up to 4 GB for one
/// string. Alignment follows CDR: each primitive at a multiple of its size from the start of
/// the payload (after the 4-byte encapsulation header).
pub(super) fn check_cdr_lengths(data: &[u8], float_sequences: usize) -> Result<(), String> {
    let (payload, little) = cdr_payload(data)?;
    let mut pos = 0usize;
    let u32_at = |pos: &mut usize, what: &str| -> Result<usize, String> {
        *pos = pos.next_multiple_of(4);
        let bytes: [u8; 4] = payload
            .get(*pos..*pos + 4)
            .and_then(|b| b.try_into().ok())
            .ok_or_else(|| format!("ends before the {what}"))?;
        *pos += 4;
        Ok(if little {
            u32::from_le_bytes(bytes)
        } else {
            u32::from_be_bytes(bytes)
        } as usize)
    };
    let skip = |pos: &mut usize, len: usize, what: &str| -> Result<(), String> {
        let remaining = payload.len().saturating_sub(*pos);
        if len > remaining {
            return Err(format!(
                "its {what} claims {len} bytes, but only {remaining} remain"
            ));
        }
        *pos += len;
        Ok(())
    };
    u32_at(&mut pos, "time stamp")?;
    u32_at(&mut pos, "time stamp")?;
    let len = u32_at(&mut pos, "frame id")?;
    skip(&mut pos, len, "frame id")?;
    let names = u32_at(&mut pos, "joint names")?;
    if names > payload.len() / 4 {
        return Err(format!(
            "it claims {names} joint names in {} bytes",
            payload.len()
        ));
    }
    for _ in 0..names {
        let len = u32_at(&mut pos, "joint name")?;
        skip(&mut pos, len, "joint name")?;
    }
    for _ in 0..float_sequences {
        let count = u32_at(&mut pos, "array length")?;
        if count > 0 {
            pos = pos.next_multiple_of(8);
        }
        skip(&mut pos, count.saturating_mul(8), "array")?;
    }
    Ok(())
}

pub(crate) const SEP: &str =
    "================================================================================";

pub(crate) fn header_defs() -> String {
    format!("{SEP}\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n{SEP}\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n")
}

pub(crate) fn joint_state_schema() -> String {
    format!("std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n{}", header_defs())
}

fn joint_sample_schema() -> String {
    format!(
        "# physid: one sample of joint data (rad, rad/s, rad/s^2, N m)\nstd_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] acceleration\nfloat64[] effort\nfloat64[] friction\nfloat64[] effects\n{}",
        header_defs()
    )
}

/// Topic names.
pub const TOPIC_MEASURED: &str = "/joint_states";
/// Processed signals.
pub const TOPIC_PROCESSED: &str = "/physid/processed";
/// Ground truth.
pub const TOPIC_TRUTH: &str = "/physid/ground_truth";
/// Format version in the `physid` metadata record.
pub const FORMAT: &str = "physid-mcap-1";

pub(crate) fn stamp(t: f64) -> (Header, u64) {
    let ns = (t * 1e9).round().max(0.0) as u64;
    (
        Header {
            stamp: Time {
                sec: (ns / 1_000_000_000) as i32,
                nanosec: (ns % 1_000_000_000) as u32,
            },
            frame_id: String::new(),
        },
        ns,
    )
}

/// `m` as little-endian CDR with its encapsulation header, written into `buf` (emptied first)
/// so that one buffer serves every message.
pub(crate) fn cdr_into<'b, T: Serialize>(buf: &'b mut Vec<u8>, m: &T) -> &'b [u8] {
    buf.clear();
    cdr::serialize_into::<_, _, _, cdr::CdrLe>(&mut *buf, m, cdr::Infinite)
        .expect("CDR of plain structs into memory cannot fail");
    buf
}

/// What to put into a log beside the recording.
pub struct LogMeta<'a> {
    /// Scenario TOML text.
    pub scenario_toml: &'a str,
    /// Engine name.
    pub engine: &'a str,
    /// Ground-truth parameter names and values (θ).
    pub parameters: (&'a [String], &'a [f64]),
}

/// Writes a recording as MCAP (see the module docs), atomically.
pub fn write(path: &Path, rec: &Recording, meta: &LogMeta) -> Result<(), IoError> {
    write_atomic_mcap(path, |w| {
        let js = w.add_schema(
            "sensor_msgs/msg/JointState",
            "ros2msg",
            joint_state_schema().as_bytes(),
        )?;
        let sample = w.add_schema(
            "physid_msgs/msg/JointSample",
            "ros2msg",
            joint_sample_schema().as_bytes(),
        )?;
        let none = BTreeMap::new();
        let c_meas = w.add_channel(js, TOPIC_MEASURED, "cdr", &none)?;
        let c_proc = w.add_channel(sample, TOPIC_PROCESSED, "cdr", &none)?;
        let c_true = w.add_channel(sample, TOPIC_TRUTH, "cdr", &none)?;
        write_samples(w, rec, [c_meas, c_proc, c_true])?;
        write_log_metadata(w, meta)
    })
}

/// The MCAP writer physid's logs are written with (zstd chunks, the `ros2` profile).
pub(crate) type McapWriter<'f> = mcap::Writer<std::io::BufWriter<&'f std::fs::File>>;

/// Writes an MCAP file at `path` atomically: `body` adds its schemas, channels, messages and
/// metadata to a writer on a temporary file beside `path`, which is renamed over `path` once
/// finished; on any error nothing is left at `path`.
pub(crate) fn write_atomic_mcap(
    path: &Path,
    body: impl FnOnce(&mut McapWriter) -> Result<(), mcap::McapError>,
) -> Result<(), IoError> {
    let mcap_err = |e: mcap::McapError| IoError::invalid(path, format!("MCAP: {e}"));
    let tmp = super::new_temp_beside(path)?;
    {
        let file = std::io::BufWriter::new(tmp.as_file());
        let mut w = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .profile("ros2")
            .create(file)
            .map_err(mcap_err)?;
        body(&mut w).map_err(mcap_err)?;
        w.finish().map_err(mcap_err)?;
    }
    tmp.persist(path).map_err(|e| IoError::Fs {
        path: path.to_path_buf(),
        source: e.error,
    })?;
    Ok(())
}

/// The recording's samples, one message per topic per sample: measured on `channels[0]`,
/// processed on `channels[1]`, the truth on `channels[2]`.
fn write_samples<W: std::io::Write + std::io::Seek>(
    w: &mut mcap::Writer<W>,
    rec: &Recording,
    channels: [u16; 3],
) -> Result<(), mcap::McapError> {
    let [c_meas, c_proc, c_true] = channels;
    let names = &rec.truth.joint_names;
    let n = names.len();
    let mut buf = Vec::new();
    for k in 0..rec.truth.len() {
        let (header, ns) = stamp(rec.truth.t[k]);
        let mh = |channel_id| mcap::records::MessageHeader {
            channel_id,
            sequence: k as u32,
            log_time: ns,
            publish_time: ns,
        };
        let m = &rec.measured;
        let msg = JointStateView {
            header: &header,
            name: names,
            position: m.q_at(k),
            velocity: m.qd_at(k),
            effort: m.tau_at(k),
        };
        w.write_to_known_channel(&mh(c_meas), cdr_into(&mut buf, &msg))?;
        let msg = JointSampleView::at(&header, names, &rec.processed, k);
        w.write_to_known_channel(&mh(c_proc), cdr_into(&mut buf, &msg))?;
        let msg = JointSampleView {
            friction: &rec.friction[k * n..(k + 1) * n],
            effects: &rec.effects[k * n..(k + 1) * n],
            ..JointSampleView::at(&header, names, &rec.truth, k)
        };
        w.write_to_known_channel(&mh(c_true), cdr_into(&mut buf, &msg))?;
    }
    Ok(())
}

/// The log's metadata records: format and engine, the scenario, the ground truth.
fn write_log_metadata<W: std::io::Write + std::io::Seek>(
    w: &mut mcap::Writer<W>,
    meta: &LogMeta,
) -> Result<(), mcap::McapError> {
    let md = |name: &str, kv: Vec<(&str, String)>| mcap::records::Metadata {
        name: name.into(),
        metadata: kv.into_iter().map(|(k, v)| (k.to_string(), v)).collect(),
    };
    w.write_metadata(&md(
        "physid",
        vec![
            ("format", FORMAT.into()),
            ("version", env!("CARGO_PKG_VERSION").into()),
            ("engine", meta.engine.into()),
        ],
    ))?;
    w.write_metadata(&md("scenario", vec![("toml", meta.scenario_toml.into())]))?;
    let (pn, pv) = meta.parameters;
    w.write_metadata(&md(
        "ground_truth_parameters",
        vec![
            ("names", serde_json::to_string(pn).expect("strings")),
            ("values", serde_json::to_string(pv).expect("numbers")),
        ],
    ))?;
    Ok(())
}

/// The topic of a reference trajectory ([`write_reference`]).
pub const TOPIC_REFERENCE: &str = "/physid/excitation";

/// Writes a reference trajectory (what a controller is to follow: q, q̇, q̈, no torques) as MCAP,
/// `physid_msgs/msg/JointSample` on [`TOPIC_REFERENCE`], log time = the trajectory's time,
/// atomically.
pub fn write_reference(path: &Path, tr: &Trajectory) -> Result<(), IoError> {
    write_atomic_mcap(path, |w| {
        let schema = w.add_schema(
            JOINT_SAMPLE_TYPE,
            "ros2msg",
            joint_sample_schema().as_bytes(),
        )?;
        let channel = w.add_channel(schema, TOPIC_REFERENCE, "cdr", &BTreeMap::new())?;
        let mut buf = Vec::new();
        for k in 0..tr.len() {
            let (header, ns) = stamp(tr.t[k]);
            let msg = JointSampleView {
                effort: &[],
                ..JointSampleView::at(&header, &tr.joint_names, tr, k)
            };
            let mh = mcap::records::MessageHeader {
                channel_id: channel,
                sequence: k as u32,
                log_time: ns,
                publish_time: ns,
            };
            w.write_to_known_channel(&mh, cdr_into(&mut buf, &msg))?;
        }
        Ok(())
    })
}

/// Which time a joint-state sample gets.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Stamp {
    /// The MCAP record's log time (when the recorder received the message).
    #[default]
    Log = 0,
    /// The message's `header.stamp` (when the driver sampled the joints).
    Header = 1,
}

impl std::str::FromStr for Stamp {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "log" => Ok(Stamp::Log),
            "header" => Ok(Stamp::Header),
            _ => Err(format!("unknown stamp '{s}' (log, header)")),
        }
    }
}

/// How joint states are read from an MCAP file or a rosbag2 directory.
#[derive(Clone, Debug)]
pub struct ReadOptions {
    /// The `sensor_msgs/msg/JointState` topic.
    pub topic: String,
    /// Which time stamps the samples.
    pub stamp: Stamp,
    /// The robot's joints, if known: `JointState` messages naming none of them (another
    /// publisher on the same topic, e.g. a gripper) are skipped and counted.
    pub joints: Option<Vec<String>>,
    /// Which of physid's own sample topics to decode and keep (a log of `physid simulate`).
    pub physid_samples: PhysidSamples,
}

/// Which of physid's own sample topics a read keeps: those it does not are not decoded (their
/// log times still set the log clock's origin, as when they are read), so their memory is
/// never spent.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PhysidSamples {
    /// `/physid/processed` and `/physid/ground_truth`.
    #[default]
    All,
    /// `/physid/processed` only (what identification reads when no topic is given).
    Processed,
    /// Neither: the joint-state topic alone.
    None,
}

impl PhysidSamples {
    /// Whether samples of `topic` (one of physid's) are kept.
    fn keeps(self, topic: &str) -> bool {
        match self {
            PhysidSamples::All => true,
            PhysidSamples::Processed => topic == TOPIC_PROCESSED,
            PhysidSamples::None => false,
        }
    }
}

impl Default for ReadOptions {
    fn default() -> Self {
        Self {
            topic: TOPIC_MEASURED.to_string(),
            stamp: Stamp::Log,
            joints: None,
            physid_samples: PhysidSamples::All,
        }
    }
}

/// An MCAP log read back.
#[derive(Clone, Debug)]
pub struct Log {
    /// The joint states (`/joint_states` or the topic asked for), as logged (velocities only if
    /// every message carries them).
    pub measured: Logged,
    /// `/physid/processed`, if present.
    pub processed: Option<Trajectory>,
    /// `/physid/ground_truth`, if present.
    pub truth: Option<Trajectory>,
    /// Metadata records by name.
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
    /// Joint-state messages skipped because they name none of the robot's joints.
    pub skipped_messages: usize,
    /// The files read, in order (one, or those of a rosbag2 directory).
    pub files: Vec<std::path::PathBuf>,
    /// The time on the clock read (ns: the log time, or the header stamps) that `t = 0` of the
    /// joint states stands for.
    pub clock_origin_ns: Option<u64>,
}

impl Log {
    /// The signals identification should use: processed if present, else measured.
    pub fn identification_input(&self) -> Logged {
        match &self.processed {
            Some(p) => Logged::from(p.clone()),
            None => self.measured.clone(),
        }
    }
}

/// Reads a log written by [`write()`] (or any MCAP with `sensor_msgs/msg/JointState` on
/// `/joint_states`). Errors name the file and the message.
pub fn read(path: &Path) -> Result<Log, IoError> {
    read_with(path, &ReadOptions::default())
}

/// The message types that are `sensor_msgs/JointState` (ROS 2, and ROS 1 in MCAP).
const JOINT_STATE_TYPES: [&str; 2] = ["sensor_msgs/msg/JointState", "sensor_msgs/JointState"];
/// physid's own sample type.
pub(super) const JOINT_SAMPLE_TYPE: &str = "physid_msgs/msg/JointSample";

/// Reads joint states from one MCAP file (a rosbag2 directory, MCAP or SQLite, is read by
/// [`super::read_joint_log`]). Times are integer nanoseconds from the first message of the
/// log (absolute stamps, ~1.7e18 ns, would lose their last digits in an f64). The topic must
/// carry `sensor_msgs/msg/JointState`; otherwise the error names its type and the topics that
/// do. Errors name the file, the topic and the message.
pub fn read_with(path: &Path, opts: &ReadOptions) -> Result<Log, IoError> {
    let mut reader = Reader::new(opts);
    reader.mcap_file(path)?;
    let mut log = reader.finish(path)?;
    log.files = vec![path.to_path_buf()];
    Ok(log)
}

/// The running state of reading one log (possibly split over several files).
pub(crate) struct Reader<'a> {
    opts: &'a ReadOptions,
    /// The first time (ns) seen on each clock, [log time, header stamp]: the origin of every
    /// sample's time on that clock (the two clocks need not agree).
    t0: [Option<u64>; 2],
    measured: Option<Logged>,
    processed: Option<Trajectory>,
    truth: Option<Trajectory>,
    metadata: BTreeMap<String, BTreeMap<String, String>>,
    skipped: usize,
    /// Every topic seen, with its message type.
    topics: BTreeMap<String, String>,
    /// Where the messages of other topics go (a floating robot's trunk and feet), if anywhere.
    others: Option<&'a mut OtherMessages<'a>>,
}

/// A sink for the messages of topics the joint reader does not decode: `(topic, message type,
/// CDR bytes, log time ns, sequence)`; `Err` says what is wrong with the message.
pub(crate) type OtherMessages<'a> =
    dyn FnMut(&str, &str, &[u8], u64, u64) -> Result<(), String> + 'a;

impl<'a> Reader<'a> {
    /// A reader that has seen nothing yet.
    pub(crate) fn new(opts: &'a ReadOptions) -> Self {
        Self {
            opts,
            t0: [None; 2],
            measured: None,
            processed: None,
            truth: None,
            metadata: BTreeMap::new(),
            skipped: 0,
            topics: BTreeMap::new(),
            others: None,
        }
    }

    /// A reader that passes the messages of every other topic to `others`.
    pub(crate) fn with_others(opts: &'a ReadOptions, others: &'a mut OtherMessages<'a>) -> Self {
        Self {
            others: Some(others),
            ..Self::new(opts)
        }
    }

    /// Reads the messages of the MCAP file `path` in blocks ([`super::mcap_walk::each_message`]:
    /// the file is never held whole) and its metadata through its summary.
    pub(crate) fn mcap_file(&mut self, path: &Path) -> Result<(), IoError> {
        use super::mcap_walk::{each_message, Flow};
        each_message(path, &mut |m| {
            let sequence = u64::from(m.sequence);
            self.message(m.topic, m.schema, m.data, m.log_time, sequence)
                .map(|_| Flow::Go)
        })
        .map_err(|e| e.into_io(path))?;
        self.metadata.extend(super::mcap_walk::all_metadata(path)?);
        Ok(())
    }

    /// One message of `topic` (of type `kind`): a joint state of the topic asked for, one of
    /// physid's own samples, or another topic (only its type is noted). A message of the topic
    /// asked for that is not a JointState is not decoded ([`Self::finish`] names the types).
    pub(crate) fn message(
        &mut self,
        topic: &str,
        kind: &str,
        data: &[u8],
        log_time: u64,
        sequence: u64,
    ) -> Result<(), String> {
        if !self.topics.contains_key(topic) {
            self.topics.insert(topic.to_string(), kind.to_string());
        }
        let at = |e: String| format!("{topic} message {sequence}: {e}");
        if topic == self.opts.topic {
            if JOINT_STATE_TYPES.contains(&kind) {
                self.joint_state(data, log_time).map_err(at)?;
            }
        } else if (topic == TOPIC_PROCESSED || topic == TOPIC_TRUTH) && kind == JOINT_SAMPLE_TYPE {
            if self.opts.physid_samples.keeps(topic) {
                self.joint_sample(topic, data, log_time).map_err(at)?;
            } else {
                self.seconds(Stamp::Log, log_time).map_err(at)?;
            }
        } else if let Some(others) = self.others.as_mut() {
            others(topic, kind, data, log_time, sequence).map_err(at)?;
        }
        Ok(())
    }

    /// The topics of the messages read so far: name → message type.
    pub(crate) fn topics(&self) -> &BTreeMap<String, String> {
        &self.topics
    }

    /// Which topics carry joint states, for an error.
    fn joint_state_topics(&self) -> String {
        let states: Vec<&str> = (self.topics.iter())
            .filter(|(_, k)| JOINT_STATE_TYPES.contains(&k.as_str()))
            .map(|(t, _)| t.as_str())
            .collect();
        if states.is_empty() {
            "no topic carries sensor_msgs/msg/JointState".to_string()
        } else {
            format!(
                "topics with sensor_msgs/msg/JointState: {} (give one with --topic)",
                states.join(", ")
            )
        }
    }

    /// The log read, or an error naming what the topic asked for is and which topics carry
    /// joint states.
    pub(crate) fn finish(self, path: &Path) -> Result<Log, IoError> {
        let bad = |m: String| IoError::invalid(path, m);
        let topic = &self.opts.topic;
        let offer = self.joint_state_topics();
        if let Some(kind) = self
            .topics
            .get(topic)
            .filter(|k| !JOINT_STATE_TYPES.contains(&k.as_str()))
        {
            let kind = if kind.is_empty() {
                "a channel without a schema"
            } else {
                kind
            };
            return Err(bad(format!(
                "topic {topic} carries {kind}, not sensor_msgs/msg/JointState; {offer}"
            )));
        }
        let measured = self.measured.ok_or_else(|| {
            bad(match (self.skipped, &self.opts.joints) {
                (0, _) | (_, None) => format!("no {topic} messages; {offer}"),
                (k, Some(j)) => format!(
                    "none of the {k} {topic} messages names a joint of the robot ({})",
                    j.join(", ")
                ),
            })
        })?;
        measured
            .validate()
            .map_err(|e| bad(format!("{topic}: {e}")))?;
        for (name, tr) in [
            ("processed", self.processed.as_ref()),
            ("ground truth", self.truth.as_ref()),
        ] {
            if let Some(tr) = tr {
                tr.validate().map_err(|e| bad(format!("{name}: {e}")))?;
            }
        }
        Ok(Log {
            measured,
            processed: self.processed,
            truth: self.truth,
            metadata: self.metadata,
            skipped_messages: self.skipped,
            files: vec![],
            clock_origin_ns: self.t0[self.opts.stamp as usize],
        })
    }

    /// Seconds since the first message on the clock `stamp` for a time in ns (integer
    /// arithmetic first).
    fn seconds(&mut self, stamp: Stamp, ns: u64) -> Result<f64, String> {
        let first = *self.t0[stamp as usize].get_or_insert(ns);
        // Before the first message (a restart, stamps out of order): negative, for the
        // pipeline to judge.
        Ok(if ns >= first {
            (ns - first) as f64 / 1e9
        } else {
            -((first - ns) as f64 / 1e9)
        })
    }

    fn joint_state(&mut self, data: &[u8], log_time: u64) -> Result<(), String> {
        check_cdr_lengths(data, 3)?;
        let js: JointState = cdr::deserialize(data).map_err(|e| e.to_string())?;
        if let Some(wanted) = &self.opts.joints {
            if !js.name.is_empty() && !js.name.iter().any(|n| wanted.contains(n)) {
                self.skipped += 1;
                return Ok(());
            }
        }
        let has_velocity = check_arrays(&js)?;
        let names = if js.name.is_empty() {
            // A writer may leave the names out: the joints are then unnamed (matched to the
            // robot by order, when the counts agree).
            vec![String::new(); js.position.len()]
        } else {
            js.name.clone()
        };
        let ns = match self.opts.stamp {
            Stamp::Log => log_time,
            Stamp::Header => header_ns(&js.header)?,
        };
        let t = self.seconds(self.opts.stamp, ns)?;
        let first = self.measured.as_ref();
        if let Some(f) = first {
            if f.qd.is_some() != has_velocity {
                return Err(format!(
                    "its velocity array is {}, the first message's was {}: velocities must be logged in every message or in none",
                    if has_velocity { "filled" } else { "empty" },
                    if has_velocity { "empty" } else { "filled" }
                ));
            }
        }
        let index = order_like_first(first.map(|f| &f.joint_names[..]), &names)?;
        let pick = |v: &[f64]| -> Vec<f64> {
            match &index {
                Some(ix) => ix.iter().map(|&i| v[i]).collect(),
                None => v.to_vec(),
            }
        };
        let names = first.map_or(names, |f| f.joint_names.clone());
        let log = self.measured.get_or_insert_with(|| Logged {
            joint_names: names,
            t: vec![],
            q: vec![],
            qd: has_velocity.then(Vec::new),
            qdd: None,
            tau: vec![],
        });
        log.t.push(t);
        log.q.extend(pick(&js.position));
        if let Some(v) = log.qd.as_mut() {
            v.extend(pick(&js.velocity));
        }
        log.tau.extend(pick(&js.effort));
        Ok(())
    }

    fn joint_sample(&mut self, topic: &str, data: &[u8], log_time: u64) -> Result<(), String> {
        check_cdr_lengths(data, 6)?;
        let s: JointSample = cdr::deserialize(data).map_err(|e| e.to_string())?;
        let n = s.name.len();
        let qdd_ok = s.acceleration.is_empty() || s.acceleration.len() == n;
        if [s.position.len(), s.velocity.len(), s.effort.len()] != [n; 3] || !qdd_ok {
            return Err(format!("arrays of other lengths than its {n} names"));
        }
        let t = self.seconds(Stamp::Log, log_time)?;
        let slot = if topic == TOPIC_PROCESSED {
            &mut self.processed
        } else {
            &mut self.truth
        };
        let tr =
            slot.get_or_insert_with(|| Trajectory::new(s.name.clone(), !s.acceleration.is_empty()));
        if tr.joint_names != s.name || tr.qdd.is_some() == s.acceleration.is_empty() {
            return Err("names other joints than the first message".into());
        }
        tr.push(
            t,
            &s.position,
            &s.velocity,
            (!s.acceleration.is_empty()).then_some(&s.acceleration[..]),
            &s.effort,
        );
        Ok(())
    }
}

/// Publishers may list the joints in another order from one message to the next: the
/// positions of the first message's joints in this message's `names` (`None` when the order
/// is the same, or for the first message); a different set of joints is an error.
fn order_like_first(
    first: Option<&[String]>,
    names: &[String],
) -> Result<Option<Vec<usize>>, String> {
    let Some(first) = first.filter(|f| *f != names) else {
        return Ok(None);
    };
    let index: Option<Vec<usize>> = (names.len() == first.len())
        .then(|| {
            first
                .iter()
                .map(|f| names.iter().position(|n| n == f))
                .collect()
        })
        .flatten();
    match index.filter(|_| !names.iter().any(String::is_empty)) {
        Some(ix) => Ok(Some(ix)),
        None => Err(format!(
            "names joints {}; the first message named {}",
            names.join(", "),
            first.join(", ")
        )),
    }
}

/// A `JointState` must carry a position and an effort per joint, and a velocity per joint or
/// none at all (then the pipeline derives it); an empty or ragged array is named. Returns
/// whether the message carries velocities.
fn check_arrays(js: &JointState) -> Result<bool, String> {
    let n = if js.name.is_empty() {
        js.position.len()
    } else {
        js.name.len()
    };
    if n == 0 {
        return Err("names no joints and has no positions".into());
    }
    let has_velocity = !js.velocity.is_empty();
    for (what, len, needed) in [
        ("position", js.position.len(), true),
        ("velocity", js.velocity.len(), has_velocity),
        ("effort", js.effort.len(), true),
    ] {
        if len == 0 && needed {
            return Err(format!(
                "its {what} array is empty (physid needs the position and effort of every joint)"
            ));
        }
        if needed && len != n {
            return Err(format!(
                "{} names, {} positions, {} velocities and {} efforts: the {what} array has {len} entries for {n} joints",
                js.name.len(),
                js.position.len(),
                js.velocity.len(),
                js.effort.len()
            ));
        }
    }
    Ok(has_velocity)
}

/// `header.stamp` in nanoseconds; negative seconds or nanoseconds ≥ 1e9 are refused.
pub(crate) fn header_ns(h: &Header) -> Result<u64, String> {
    if h.stamp.sec < 0 || h.stamp.nanosec >= 1_000_000_000 {
        return Err(format!(
            "header.stamp {} s {} ns is not a valid time",
            h.stamp.sec, h.stamp.nanosec
        ));
    }
    Ok(h.stamp.sec as u64 * 1_000_000_000 + h.stamp.nanosec as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(names: &[&str]) -> JointState {
        JointState {
            header: Header {
                stamp: Time { sec: 3, nanosec: 7 },
                frame_id: "base".into(),
            },
            name: names.iter().map(|s| s.to_string()).collect(),
            position: vec![0.5; names.len()],
            velocity: vec![-1.0; names.len()],
            effort: vec![2.0; names.len()],
        }
    }

    #[test]
    fn the_borrowed_views_encode_as_the_owned_messages_do() {
        // What the readers decode (the owned messages, through `cdr::serialize`) against what
        // the writers encode (the views, through one reused buffer): the same bytes, with and
        // without accelerations, friction and effects, for names of every length.
        let names: Vec<String> = ["a", "knee_joint", "hip"].map(String::from).to_vec();
        let mut tr = Trajectory::new(names.clone(), true);
        tr.push(
            0.5,
            &[1.0, -2.0, 3.5],
            &[0.1, 0.2, 0.3],
            Some(&[9.0, 8.0, 7.0]),
            &[4.0, 5.0, 6.0],
        );
        let header = state(&[]).header;
        let owned = |friction: Vec<f64>, acceleration: Vec<f64>| JointSample {
            header: header.clone(),
            name: names.clone(),
            position: tr.q_at(0).to_vec(),
            velocity: tr.qd_at(0).to_vec(),
            acceleration,
            effort: tr.tau_at(0).to_vec(),
            effects: friction.iter().map(|f| -f).collect(),
            friction,
        };
        let encode =
            |m: &JointSample| cdr::serialize::<_, _, cdr::CdrLe>(m, cdr::Infinite).unwrap();
        let mut buf = vec![0xff; 7];
        let view = JointSampleView::at(&header, &names, &tr, 0);
        assert_eq!(
            cdr_into(&mut buf, &view),
            encode(&owned(vec![], vec![9.0, 8.0, 7.0]))
        );
        let friction = [0.25, -0.5, 1.0];
        let effects = friction.map(|f| -f);
        let view = JointSampleView {
            friction: &friction,
            effects: &effects,
            acceleration: &[],
            ..view
        };
        assert_eq!(
            cdr_into(&mut buf, &view),
            encode(&owned(friction.to_vec(), vec![]))
        );
        for n in [&[][..], &["a"], &["hip", "knee_joint", "x"]] {
            let s = state(n);
            let view = JointStateView {
                header: &s.header,
                name: &s.name,
                position: &s.position,
                velocity: &s.velocity,
                effort: &s.effort,
            };
            let want = cdr::serialize::<_, _, cdr::CdrLe>(&s, cdr::Infinite).unwrap();
            assert_eq!(cdr_into(&mut buf, &view), want);
        }
    }

    #[test]
    fn valid_messages_pass_the_length_check_in_both_byte_orders() {
        for names in [&[][..], &["a"], &["hip", "knee_joint", "x"]] {
            let s = state(names);
            let le = cdr::serialize::<_, _, cdr::CdrLe>(&s, cdr::Infinite).unwrap();
            let be = cdr::serialize::<_, _, cdr::CdrBe>(&s, cdr::Infinite).unwrap();
            assert_eq!(check_cdr_lengths(&le, 3), Ok(()));
            assert_eq!(check_cdr_lengths(&be, 3), Ok(()));
        }
        let sample = JointSample {
            header: state(&[]).header,
            name: vec!["a".into(), "bc".into()],
            position: vec![1.0; 2],
            velocity: vec![1.0; 2],
            acceleration: vec![],
            effort: vec![1.0; 2],
            friction: vec![1.0; 2],
            effects: vec![1.0; 2],
        };
        let bytes = cdr::serialize::<_, _, cdr::CdrLe>(&sample, cdr::Infinite).unwrap();
        assert_eq!(check_cdr_lengths(&bytes, 6), Ok(()));
    }

    #[test]
    fn log_times_and_header_stamps_each_count_from_their_own_first_value() {
        // physid's processed channel runs on log time while the joint states may be read by
        // header stamps from the epoch: one shared origin would put them 1.7e9 s apart.
        let opts = ReadOptions::default();
        let mut r = Reader::new(&opts);
        assert_eq!(r.seconds(Stamp::Log, 5_000), Ok(0.0));
        assert_eq!(r.seconds(Stamp::Header, 1_700_000_000_000_000_000), Ok(0.0));
        assert_eq!(r.seconds(Stamp::Log, 1_005_000), Ok(0.001));
        assert_eq!(
            r.seconds(Stamp::Header, 1_700_000_000_002_000_000),
            Ok(0.002)
        );
        // Before the first message: negative, for the pipeline to judge (a restart).
        assert_eq!(r.seconds(Stamp::Log, 4_999), Ok(-1e-9));
    }

    #[test]
    fn a_corrupt_string_length_is_refused_before_decoding() {
        // Before: cdr's decoder reserved the claimed 4.2 GB for the frame id.
        let mut bytes = cdr::serialize::<_, _, cdr::CdrLe>(&state(&["a"]), cdr::Infinite).unwrap();
        bytes[4 + 8..4 + 12].copy_from_slice(&u32::MAX.to_le_bytes());
        let err = check_cdr_lengths(&bytes, 3).unwrap_err();
        assert!(err.contains("frame id claims 4294967295 bytes"), "{err}");
        // A truncated message and a wrong encapsulation are named too.
        let whole = cdr::serialize::<_, _, cdr::CdrLe>(&state(&["a"]), cdr::Infinite).unwrap();
        assert!(check_cdr_lengths(&whole[..whole.len() - 3], 3).is_err());
        assert!(check_cdr_lengths(&[9, 9, 0, 0, 0], 3).is_err());
        assert!(check_cdr_lengths(&[0, 1], 3).is_err());
    }
}
