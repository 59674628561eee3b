//! An MCAP log's processed samples streamed from disk, in memory that does not grow with the
//! file: the counterpart of [`super::samples::stream_csv`] for `physid simulate`'s logs and any
//! MCAP carrying `/physid/processed` (`physid_msgs/msg/JointSample` with accelerations).
//!
//! The file is read in blocks of at most 1 MiB through the `mcap` crate's sans-io reader (chunks
//! decompressed one at a time, every record's length bounded before anything is allocated for
//! it: [`super::mcap_log::record_length_limit`]), and each processed message is decoded,
//! checked (finite values, increasing time) and handed on; nothing else is kept but the schema
//! and channel tables.

use super::mcap_log::{
    check_cdr_lengths, record_length_limit, JointSample, JOINT_SAMPLE_TYPE, TOPIC_PROCESSED,
};
use super::IoError;
use crate::trajectory::{check_value, SampleRef, SampleSink, SAMPLE_GROUPS};
use mcap::records::Record;
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use std::collections::HashMap;
use std::io::Read;
use std::ops::Range;
use std::path::Path;

/// Bytes read from the file at a time.
const BLOCK: usize = 1 << 20;

/// What the walk does after a processed message.
enum Flow {
    Go,
    Stop,
}

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
    let fs_error = |source| IoError::Fs {
        path: path.to_path_buf(),
        source,
    };
    let mut file = std::fs::File::open(path).map_err(fs_error)?;
    let size = file.metadata().map_err(fs_error)?.len();
    let bad = |m: String| IoError::invalid(path, m);
    let options =
        LinearReaderOptions::default().with_record_length_limit(record_length_limit(size));
    let mut reader = LinearReader::new_with_options(options);
    let mut schemas: HashMap<u16, bool> = HashMap::new();
    let mut processed: HashMap<u16, bool> = HashMap::new();
    let mut i = 0usize;
    while let Some(event) = reader.next_event() {
        let event = event.map_err(|e| bad(format!("not a readable MCAP file: {e}")))?;
        let (opcode, data) = match event {
            LinearReadEvent::ReadRequest(wanted) => {
                let buf = reader.insert(wanted.min(BLOCK));
                let got = file.read(buf).map_err(fs_error)?;
                reader.notify_read(got);
                continue;
            }
            LinearReadEvent::Record { opcode, data } => (opcode, data),
        };
        let record =
            mcap::parse_record(opcode, data).map_err(|e| bad(format!("record {i}: {e}")))?;
        i += 1;
        match record {
            Record::Schema { header, .. } => {
                schemas.insert(header.id, header.name == JOINT_SAMPLE_TYPE);
            }
            Record::Channel(c) => {
                let sample = schemas.get(&c.schema_id).copied().unwrap_or(false);
                processed.insert(c.id, sample && c.topic == TOPIC_PROCESSED);
            }
            Record::Message { header, data } => {
                if !processed.get(&header.channel_id).copied().unwrap_or(false) {
                    continue;
                }
                let at = |e: String| {
                    bad(format!(
                        "{TOPIC_PROCESSED} message {}: {e}",
                        header.sequence
                    ))
                };
                check_cdr_lengths(&data, 6).map_err(at)?;
                let s: JointSample = cdr::deserialize(&data).map_err(|e| at(e.to_string()))?;
                if let Flow::Stop = each(header.log_time, &s).map_err(&bad)? {
                    return Ok(());
                }
            }
            _ => {}
        }
    }
    Ok(())
}

/// The metadata record `name` of the MCAP file `path` (its key-value map), found through the
/// file's summary section (read from the end of the file, then the one record): memory and
/// time independent of the file's length. `None` when the file has no summary or no such
/// record (as [`super::mcap_log::read`], which reads metadata through the summary too).
pub fn metadata(
    path: &Path,
    name: &str,
) -> Result<Option<std::collections::BTreeMap<String, String>>, IoError> {
    use mcap::sans_io::{SummaryReadEvent, SummaryReader, SummaryReaderOptions};
    use std::io::Seek;
    let fs_error = |source| IoError::Fs {
        path: path.to_path_buf(),
        source,
    };
    let bad = |m: String| IoError::invalid(path, m);
    let mut file = std::fs::File::open(path).map_err(fs_error)?;
    let size = file.metadata().map_err(fs_error)?.len();
    // The summary's records are not compressed: none is longer than the file.
    let limit = usize::try_from(size).unwrap_or(usize::MAX).max(1 << 20);
    let mut reader = SummaryReader::new_with_options(
        SummaryReaderOptions::default()
            .with_file_size(size)
            .with_record_length_limit(limit),
    );
    while let Some(event) = reader.next_event() {
        match event.map_err(|e| bad(format!("not a readable MCAP file: {e}")))? {
            SummaryReadEvent::ReadRequest(wanted) => {
                let got = file.read(reader.insert(wanted)).map_err(fs_error)?;
                reader.notify_read(got);
            }
            SummaryReadEvent::SeekRequest(to) => {
                reader.notify_seeked(file.seek(to).map_err(fs_error)?);
            }
        }
    }
    let Some(summary) = reader.finish() else {
        return Ok(None);
    };
    let Some(index) = summary.metadata_indexes.iter().find(|i| i.name == name) else {
        return Ok(None);
    };
    let length = usize::try_from(index.length)
        .ok()
        .filter(|&l| (9..=limit).contains(&l) && index.offset.saturating_add(index.length) <= size)
        .ok_or_else(|| {
            bad(format!(
                "metadata '{name}': its index points outside the file"
            ))
        })?;
    let mut record = vec![0; length];
    file.seek(std::io::SeekFrom::Start(index.offset))
        .and_then(|_| file.read_exact(&mut record))
        .map_err(fs_error)?;
    match mcap::parse_record(record[0], &record[9..]) {
        Ok(Record::Metadata(m)) => Ok(Some(m.metadata)),
        Ok(_) => Err(bad(format!(
            "metadata '{name}': its index points at another record"
        ))),
        Err(e) => Err(bad(format!("metadata '{name}': {e}"))),
    }
}
