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

use super::samples::Trajectory;
use super::IoError;
use crate::trajectory::Recording;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// `builtin_interfaces/msg/Time`.
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
struct Time {
    sec: i32,
    nanosec: u32,
}

/// `std_msgs/msg/Header`.
#[derive(Serialize, Deserialize, Debug, Clone, PartialEq)]
struct Header {
    stamp: Time,
    frame_id: String,
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
struct JointSample {
    header: Header,
    name: Vec<String>,
    position: Vec<f64>,
    velocity: Vec<f64>,
    acceleration: Vec<f64>,
    effort: Vec<f64>,
    friction: Vec<f64>,
    effects: Vec<f64>,
}

/// Walks every record of an MCAP file, chunks decompressed, with each record's length bounded
/// (by 100 times the file's size, at least 64 MiB) before anything is allocated for it: a
/// corrupt length inside a chunk would otherwise make the message stream reserve exabytes and
/// abort. The stream that reads the messages afterwards meets the same, checked records.
fn prevalidate(bytes: &[u8]) -> Result<(), mcap::McapError> {
    use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
    let limit = bytes.len().saturating_mul(100).max(64 << 20);
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default().with_record_length_limit(limit),
    );
    let mut pos = 0;
    while let Some(event) = reader.next_event() {
        if let LinearReadEvent::ReadRequest(wanted) = event? {
            let n = wanted.min(bytes.len() - pos).min(1 << 20);
            reader.insert(n).copy_from_slice(&bytes[pos..pos + n]);
            reader.notify_read(n);
            pos += n;
        }
    }
    Ok(())
}

/// Checks every length of a CDR-encoded `JointState`-like message (header, names, then
/// `float_sequences` sequences of `float64`) against the bytes that remain, before the decoder
/// allocates anything: a corrupt length would otherwise make it reserve up to 4 GB for one
/// string. Alignment follows CDR: each primitive at a multiple of its size from the start of
/// the payload (after the 4-byte encapsulation header).
fn check_cdr_lengths(data: &[u8], float_sequences: usize) -> Result<(), String> {
    let payload = data
        .get(4..)
        .ok_or("shorter than its CDR encapsulation header")?;
    let little = match data[..2] {
        [0, 1] | [0, 3] => true,
        [0, 0] | [0, 2] => false,
        _ => return Err(format!("unknown CDR encapsulation {:02x?}", &data[..2])),
    };
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

const SEP: &str =
    "================================================================================";

fn header_defs() -> String {
    format!("{SEP}\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n{SEP}\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n")
}

fn joint_state_schema() -> String {
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

fn stamp(t: f64) -> (Header, u64) {
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

fn cdr_bytes<T: Serialize>(m: &T) -> Vec<u8> {
    cdr::serialize::<_, _, cdr::CdrLe>(m, cdr::Infinite).expect("CDR of plain structs cannot fail")
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
    let fs_err = |source| IoError::Fs {
        path: path.to_path_buf(),
        source,
    };
    let mcap_err = |e: mcap::McapError| IoError::Invalid {
        path: path.to_path_buf(),
        message: format!("MCAP: {e}"),
    };
    let tmp = super::new_temp_beside(path)?;
    {
        let file = std::io::BufWriter::new(tmp.as_file());
        let mut w = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .profile("ros2")
            .create(file)
            .map_err(mcap_err)?;
        let js = w
            .add_schema(
                "sensor_msgs/msg/JointState",
                "ros2msg",
                joint_state_schema().as_bytes(),
            )
            .map_err(mcap_err)?;
        let sample = w
            .add_schema(
                "physid_msgs/msg/JointSample",
                "ros2msg",
                joint_sample_schema().as_bytes(),
            )
            .map_err(mcap_err)?;
        let none = BTreeMap::new();
        let c_meas = w
            .add_channel(js, TOPIC_MEASURED, "cdr", &none)
            .map_err(mcap_err)?;
        let c_proc = w
            .add_channel(sample, TOPIC_PROCESSED, "cdr", &none)
            .map_err(mcap_err)?;
        let c_true = w
            .add_channel(sample, TOPIC_TRUTH, "cdr", &none)
            .map_err(mcap_err)?;
        let names = rec.truth.joint_names.clone();
        let n = names.len();
        let row = |v: &[f64], k: usize| v[k * n..(k + 1) * n].to_vec();
        for k in 0..rec.truth.len() {
            let (header, ns) = stamp(rec.truth.t[k]);
            let mh = |channel_id| mcap::records::MessageHeader {
                channel_id,
                sequence: k as u32,
                log_time: ns,
                publish_time: ns,
            };
            let m = &rec.measured;
            let msg = JointState {
                header: header.clone(),
                name: names.clone(),
                position: m.q_at(k).to_vec(),
                velocity: m.qd_at(k).to_vec(),
                effort: m.tau_at(k).to_vec(),
            };
            w.write_to_known_channel(&mh(c_meas), &cdr_bytes(&msg))
                .map_err(mcap_err)?;
            let p = &rec.processed;
            let msg = JointSample {
                header: header.clone(),
                name: names.clone(),
                position: p.q_at(k).to_vec(),
                velocity: p.qd_at(k).to_vec(),
                acceleration: p.qdd_at(k).map(<[f64]>::to_vec).unwrap_or_default(),
                effort: p.tau_at(k).to_vec(),
                friction: vec![],
                effects: vec![],
            };
            w.write_to_known_channel(&mh(c_proc), &cdr_bytes(&msg))
                .map_err(mcap_err)?;
            let t = &rec.truth;
            let msg = JointSample {
                header,
                name: names.clone(),
                position: t.q_at(k).to_vec(),
                velocity: t.qd_at(k).to_vec(),
                acceleration: t.qdd_at(k).map(<[f64]>::to_vec).unwrap_or_default(),
                effort: t.tau_at(k).to_vec(),
                friction: row(&rec.friction, k),
                effects: row(&rec.effects, k),
            };
            w.write_to_known_channel(&mh(c_true), &cdr_bytes(&msg))
                .map_err(mcap_err)?;
        }
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
        ))
        .map_err(mcap_err)?;
        w.write_metadata(&md("scenario", vec![("toml", meta.scenario_toml.into())]))
            .map_err(mcap_err)?;
        let (pn, pv) = meta.parameters;
        w.write_metadata(&md(
            "ground_truth_parameters",
            vec![
                ("names", serde_json::to_string(pn).expect("strings")),
                ("values", serde_json::to_string(pv).expect("numbers")),
            ],
        ))
        .map_err(mcap_err)?;
        w.finish().map_err(mcap_err)?;
    }
    tmp.persist(path).map_err(|e| fs_err(e.error))?;
    Ok(())
}

/// An MCAP log read back.
#[derive(Clone, Debug)]
pub struct Log {
    /// `/joint_states`.
    pub measured: Trajectory,
    /// `/physid/processed`, if present.
    pub processed: Option<Trajectory>,
    /// `/physid/ground_truth`, if present.
    pub truth: Option<Trajectory>,
    /// Metadata records by name.
    pub metadata: BTreeMap<String, BTreeMap<String, String>>,
}

impl Log {
    /// The signals identification should use: processed if present, else measured.
    pub fn identification_input(&self) -> &Trajectory {
        self.processed.as_ref().unwrap_or(&self.measured)
    }
}

/// Reads a log written by [`write()`] (or any MCAP with `sensor_msgs/msg/JointState` on
/// `/joint_states`). Errors name the file and the message.
pub fn read(path: &Path) -> Result<Log, IoError> {
    let bytes = std::fs::read(path).map_err(|source| IoError::Fs {
        path: path.to_path_buf(),
        source,
    })?;
    let bad = |m: String| IoError::invalid(path, m);
    let mut measured: Option<Trajectory> = None;
    let mut processed: Option<Trajectory> = None;
    let mut truth: Option<Trajectory> = None;
    prevalidate(&bytes).map_err(|e| bad(format!("not a readable MCAP file: {e}")))?;
    let stream =
        mcap::MessageStream::new(&bytes).map_err(|e| bad(format!("not an MCAP file: {e}")))?;
    let mut t0: Option<u64> = None;
    for (i, m) in stream.enumerate() {
        let m = m.map_err(|e| bad(format!("record {i}: {e}")))?;
        // Integer nanoseconds from the first message: absolute stamps (~1.7e18 ns) would lose
        // their last digits in an f64.
        let first = *t0.get_or_insert(m.log_time);
        let t = m.log_time.saturating_sub(first) as f64 / 1e9;
        match m.channel.topic.as_str() {
            TOPIC_MEASURED => {
                check_cdr_lengths(&m.data, 3)
                    .map_err(|e| bad(format!("{TOPIC_MEASURED} message {}: {e}", m.sequence)))?;
                let js: JointState = cdr::deserialize(&m.data)
                    .map_err(|e| bad(format!("{TOPIC_MEASURED} message {}: {e}", m.sequence)))?;
                // A writer may leave the names out: the joints are then unnamed (matched to
                // the robot by order, when the counts agree).
                let names = if js.name.is_empty() {
                    vec![String::new(); js.position.len()]
                } else {
                    js.name.clone()
                };
                let tr = measured.get_or_insert_with(|| Trajectory::new(names.clone(), false));
                let lengths = [js.position.len(), js.velocity.len(), js.effort.len()];
                if names != tr.joint_names || lengths.iter().any(|&l| l != tr.dof()) {
                    return Err(bad(format!(
                        "{TOPIC_MEASURED} message {}: {} names, {} positions, {} velocities and {} efforts; the first message has {} joints ({})",
                        m.sequence,
                        names.len(),
                        lengths[0],
                        lengths[1],
                        lengths[2],
                        tr.dof(),
                        tr.joint_names.join(", ")
                    )));
                }
                tr.push(t, &js.position, &js.velocity, None, &js.effort);
            }
            topic @ (TOPIC_PROCESSED | TOPIC_TRUTH) => {
                check_cdr_lengths(&m.data, 6)
                    .map_err(|e| bad(format!("{topic} message {}: {e}", m.sequence)))?;
                let s: JointSample = cdr::deserialize(&m.data)
                    .map_err(|e| bad(format!("{topic} message {}: {e}", m.sequence)))?;
                let slot = if topic == TOPIC_PROCESSED {
                    &mut processed
                } else {
                    &mut truth
                };
                let tr = slot.get_or_insert_with(|| {
                    Trajectory::new(s.name.clone(), !s.acceleration.is_empty())
                });
                tr.push(
                    t,
                    &s.position,
                    &s.velocity,
                    (!s.acceleration.is_empty()).then_some(&s.acceleration[..]),
                    &s.effort,
                );
            }
            _ => {}
        }
    }
    let mut metadata = BTreeMap::new();
    if let Ok(Some(summary)) = mcap::Summary::read(&bytes) {
        for idx in &summary.metadata_indexes {
            let md = mcap::read::metadata(&bytes, idx)
                .map_err(|e| bad(format!("metadata '{}': {e}", idx.name)))?;
            metadata.insert(md.name, md.metadata);
        }
    }
    let measured = measured.ok_or_else(|| bad(format!("no {TOPIC_MEASURED} messages")))?;
    for (name, tr) in [
        ("measured", Some(&measured)),
        ("processed", processed.as_ref()),
        ("ground truth", truth.as_ref()),
    ] {
        if let Some(tr) = tr {
            tr.validate().map_err(|e| bad(format!("{name}: {e}")))?;
        }
    }
    Ok(Log {
        measured,
        processed,
        truth,
        metadata,
    })
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
