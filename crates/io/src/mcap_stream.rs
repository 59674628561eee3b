//! An MCAP log's processed samples streamed from disk, in memory that does not grow with the
//! file: the counterpart of [`super::samples::stream_csv`] for `physid simulate`'s logs and any
//! MCAP carrying `/physid/processed` (`physid_msgs/msg/JointSample` with accelerations). The
//! same block-wise walk ([`super::mcap_walk::each_message`]) feeds the reader of whole logs
//! ([`super::mcap_log::read`], rosbag2's MCAP storage), which so never holds the file itself.
//!
//! The file is read in blocks of at most 1 MiB through the `mcap` crate's sans-io reader (chunks
//! decompressed one at a time, every record's length bounded before anything is allocated for
//! it: [`super::mcap_walk::record_length_limit`]), and each processed message is decoded,
//! checked (finite values, increasing time) and handed on; nothing else is kept but the schema
//! and channel tables.

use super::mcap_log::{check_cdr_lengths, JointSample, JOINT_SAMPLE_TYPE, TOPIC_PROCESSED};
use super::mcap_walk::{each_message, Flow, Summary};
use super::IoError;
use physid_core::trajectory::{check_value, SampleRef, SampleSink, SAMPLE_GROUPS};
use std::ops::Range;
use std::path::Path;

/// Whether `path` carries processed samples with accelerations (so it can be streamed:
/// nothing to derive). Reads up to the first processed message.
pub fn mcap_streamable(path: &Path) -> Result<bool, IoError> {
    let mut with_acceleration = false;
    walk(path, &mut |_, s| {
        with_acceleration = !s.acceleration.is_empty();
        Ok(Flow::Stop)
    })?;
    Ok(with_acceleration)
}

/// `log_time` (ns) in seconds after `first` (ns), negative when before.
fn seconds_after(first: u64, log_time: u64) -> f64 {
    if log_time >= first {
        (log_time - first) as f64 / 1e9
    } else {
        -((first - log_time) as f64 / 1e9)
    }
}

/// Checks that a joint-state message carries accelerations and one value per name in each
/// array.
fn check_arrays(s: &JointSample) -> Result<(), String> {
    if s.acceleration.is_empty() {
        return Err("no accelerations: streaming needs them".into());
    }
    let names = s.name.len();
    let lengths = [
        s.position.len(),
        s.velocity.len(),
        s.acceleration.len(),
        s.effort.len(),
    ];
    if lengths != [names; 4] {
        return Err(format!("arrays of other lengths than its {names} names"));
    }
    Ok(())
}

/// Streams the processed samples of the MCAP file `path` (`/physid/processed`, q, q̇, q̈, τ in
/// rad, rad/s, rad/s², N m; time in s from the first message's log time) sample by sample
/// without loading it, checking each (finite values, increasing time, the robot's joints
/// present, accelerations logged); `f(k, sample)` sees samples `range` only, the joints in
/// `robot`'s order. Returns the number of processed samples in the file. Errors name the file
/// and the message.
pub fn stream_mcap(
    path: &Path,
    robot: &[String],
    range: Range<usize>,
    f: &mut SampleSink,
) -> Result<usize, IoError> {
    let n = robot.len();
    let mut index: Option<Vec<usize>> = None;
    let mut vals = vec![0.0; 4 * n];
    let (mut k, mut t0, mut prev) = (0usize, None::<u64>, f64::NEG_INFINITY);
    walk(path, &mut |log_time, s| {
        let at = |e: String| format!("{TOPIC_PROCESSED} message {k}: {e}");
        check_arrays(s).map_err(at)?;
        let names = s.name.len();
        let ix = match &index {
            Some(ix) => ix,
            None => index.insert(robot_order(&s.name, robot).map_err(at)?),
        };
        if ix.iter().any(|&i| i >= names) {
            return Err(at("names fewer joints than the first message".into()));
        }
        // As the whole-file reader counts: integer nanoseconds from the first message first.
        let t = seconds_after(*t0.get_or_insert(log_time), log_time);
        check_value(k, t, "t", "t", t).map_err(|e| at(e.to_string()))?;
        if t <= prev {
            return Err(at(format!(
                "time {t} s does not increase (previous {prev} s)"
            )));
        }
        prev = t;
        if range.contains(&k) {
            let groups = [&s.position, &s.velocity, &s.acceleration, &s.effort];
            for (g, values) in groups.iter().enumerate() {
                for (j, &i) in ix.iter().enumerate() {
                    let v = values[i];
                    check_value(k, t, SAMPLE_GROUPS[g], &robot[j], v)
                        .map_err(|e| at(e.to_string()))?;
                    vals[g * n + j] = v;
                }
            }
            f(k, &SampleRef::packed(t, &vals));
        }
        k += 1;
        Ok(Flow::Go)
    })?;
    if k == 0 {
        return Err(IoError::invalid(
            path,
            format!("no {TOPIC_PROCESSED} messages to stream"),
        ));
    }
    Ok(k)
}

/// Where each of the robot's joints sits in a message naming `names`; an error naming a joint
/// the message lacks.
fn robot_order(names: &[String], robot: &[String]) -> Result<Vec<usize>, String> {
    robot
        .iter()
        .map(|j| {
            names
                .iter()
                .position(|x| x == j)
                .ok_or_else(|| format!("no joint '{j}' among its joints ({})", names.join(", ")))
        })
        .collect()
}

/// Reads every record of `path` in blocks, passing each decoded processed message and its log
/// time (ns) to `each` until it says stop.
fn walk(
    path: &Path,
    each: &mut dyn FnMut(u64, &JointSample) -> Result<Flow, String>,
) -> Result<(), IoError> {
    each_message(path, &mut |m| {
        if m.topic != TOPIC_PROCESSED || m.schema != JOINT_SAMPLE_TYPE {
            return Ok(Flow::Go);
        }
        let at = |e: String| format!("{TOPIC_PROCESSED} message {}: {e}", m.sequence);
        check_cdr_lengths(m.data, 6).map_err(at)?;
        let s: JointSample = cdr::deserialize(m.data).map_err(|e| at(e.to_string()))?;
        each(m.log_time, &s)
    })
    .map_err(|e| e.into_io(path))
}

/// The metadata record `name` of the MCAP file `path` (its key-value map), found through the
/// file's summary section (read from the end of the file, then the one record): memory and
/// time independent of the file's length. `None` when the file has no summary or no such
/// record (as [`super::mcap_log::read`], which reads metadata through the summary too).
pub fn metadata(
    path: &Path,
    name: &str,
) -> Result<Option<std::collections::BTreeMap<String, String>>, IoError> {
    let Some(mut summary) = Summary::open(path)? else {
        return Ok(None);
    };
    let Some(index) = summary.indexes.iter().position(|i| i.name == name) else {
        return Ok(None);
    };
    let index = summary.indexes.swap_remove(index);
    summary.record(&index).map(Some)
}
