//! Joint data are matched to the robot's joints by name, not by position: a ROS 2 bag (MCAP,
//! `sensor_msgs/msg/JointState`) written by another writer with its joints in another order,
//! an extra joint and absolute time stamps reads as the same samples as one in the robot's
//! order. Before, names were only counted: a shuffled bag gave a 47 N m model with exit 0.

mod common;

use physid::io;
use serde::Serialize;
use std::path::Path;

/// The samples of a data file as the readers give them (before the pipeline), the file's
/// joints the robot lacks, and the messages skipped.
fn read(
    path: &Path,
    model: &physid::model::Model,
    opts: &io::DataOptions,
) -> (io::samples::Logged, Vec<String>, usize) {
    io::load_logged(path, model, opts).unwrap()
}

#[derive(Serialize)]
struct Time {
    sec: i32,
    nanosec: u32,
}

#[derive(Serialize)]
struct Header {
    stamp: Time,
    frame_id: String,
}

/// `sensor_msgs/msg/JointState`, as any ROS 2 writer lays it out in CDR.
#[derive(Serialize)]
struct JointState {
    header: Header,
    name: Vec<String>,
    position: Vec<f64>,
    velocity: Vec<f64>,
    effort: Vec<f64>,
}

/// How a test bag is written.
struct Bag<'a> {
    topic: &'a str,
    /// Samples written.
    range: std::ops::Range<usize>,
    /// `header.stamp` = start + t; the log time lags it by a jitter of up to 0.9 ms.
    header_stamps: bool,
    /// A gripper-only message from another publisher after every sample.
    other_publisher: bool,
    /// The message whose velocity array is left empty.
    empty_velocity_at: Option<usize>,
    /// Rotate the joint order by one more place in every message.
    rotate_each: bool,
}

impl Default for Bag<'_> {
    fn default() -> Self {
        Self {
            topic: "/joint_states",
            range: 0..usize::MAX,
            header_stamps: false,
            other_publisher: false,
            empty_velocity_at: None,
            rotate_each: false,
        }
    }
}

/// Writes `tr` as JointState messages with the joints in `order` (indices into `tr`'s joints,
/// `None` for an extra joint), stamped `start_ns` + t.
fn write_bag(
    path: &Path,
    tr: &physid::trajectory::Trajectory,
    order: &[Option<usize>],
    start_ns: u64,
) {
    write_bag_with(path, tr, order, start_ns, &Bag::default());
}

fn write_bag_with(
    path: &Path,
    tr: &physid::trajectory::Trajectory,
    order: &[Option<usize>],
    start_ns: u64,
    bag: &Bag,
) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut w = mcap::WriteOptions::new().create(file).unwrap();
    let schema = w
        .add_schema("sensor_msgs/msg/JointState", "ros2msg", b"")
        .unwrap();
    let channel = w
        .add_channel(schema, bag.topic, "cdr", &Default::default())
        .unwrap();
    let name_of =
        |o: &Option<usize>| o.map_or("gripper".to_string(), |j| tr.joint_names[j].clone());
    let mut sequence = 0u32;
    let mut write = |w: &mut mcap::Writer<_>, msg: &JointState, log_time: u64| {
        let data = cdr::serialize::<_, _, cdr::CdrLe>(msg, cdr::Infinite).unwrap();
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence,
            log_time,
            publish_time: log_time,
        };
        sequence += 1;
        w.write_to_known_channel(&header, &data).unwrap();
    };
    for k in bag.range.start..bag.range.end.min(tr.len()) {
        let mut order = order.to_vec();
        if bag.rotate_each {
            let shift = k % order.len();
            order.rotate_left(shift);
        }
        let order = &order[..];
        let col = |v: &[f64], o: &Option<usize>| o.map_or(0.01, |j| v[j]);
        let stamp_ns = start_ns + (tr.t[k] * 1e9).round() as u64;
        let jitter = if bag.header_stamps {
            (k as u64 * 7_919_993) % 900_000
        } else {
            0
        };
        let stamp = Time {
            sec: if bag.header_stamps {
                (stamp_ns / 1_000_000_000) as i32
            } else {
                0
            },
            nanosec: if bag.header_stamps {
                (stamp_ns % 1_000_000_000) as u32
            } else {
                0
            },
        };
        let mut msg = JointState {
            header: Header {
                stamp,
                frame_id: String::new(),
            },
            name: order.iter().map(name_of).collect(),
            position: order.iter().map(|o| col(tr.q_at(k), o)).collect(),
            velocity: order.iter().map(|o| col(tr.qd_at(k), o)).collect(),
            effort: order.iter().map(|o| col(tr.tau_at(k), o)).collect(),
        };
        if bag.empty_velocity_at == Some(k) {
            msg.velocity.clear();
        }
        write(&mut w, &msg, stamp_ns + jitter);
        if bag.other_publisher {
            let gripper = JointState {
                header: Header {
                    stamp: Time { sec: 0, nanosec: 0 },
                    frame_id: String::new(),
                },
                name: vec!["gripper".into()],
                position: vec![0.02],
                velocity: vec![0.0],
                effort: vec![1.0],
            };
            write(&mut w, &gripper, stamp_ns + jitter + 100);
        }
    }
    w.finish().unwrap();
}

#[test]
fn a_bag_in_another_joint_order_with_an_extra_joint_reads_as_the_robot_order() {
    let root = common::root();
    let (mut sc, model, _) =
        physid::sim::scenario::load(&root.join("scenarios/cheetah3_shell.toml")).unwrap();
    sc.simulation.duration = 0.5;
    let rec = physid::sim::run(&model, &sc, &mut |_| {}).unwrap();
    let measured = &rec.measured;
    let dir = tempfile::tempdir().unwrap();
    let (plain, shuffled, missing) = (
        dir.path().join("plain.mcap"),
        dir.path().join("shuffled.mcap"),
        dir.path().join("missing.mcap"),
    );
    write_bag(&plain, measured, &[Some(0), Some(1), Some(2)], 0);
    // Another order, a gripper joint the robot lacks, stamps from 2023 (absolute ns).
    write_bag(
        &shuffled,
        measured,
        &[Some(2), None, Some(0), Some(1)],
        1_700_000_000_123_456_789,
    );
    write_bag(&missing, measured, &[Some(2), Some(0)], 0);

    let a = read(&plain, &model, &Default::default());
    let b = read(&shuffled, &model, &Default::default());
    assert!(a.1.is_empty());
    assert_eq!(b.1, vec!["gripper".to_string()]);
    let (a, b) = (a.0, b.0);
    assert_eq!(a.joint_names, b.joint_names);
    assert_eq!(a.q, b.q);
    assert_eq!(a.qd, b.qd);
    assert_eq!(a.tau, b.tau);
    // Times from the first stamp, in integer nanoseconds: no precision lost to the epoch.
    let dt =
        a.t.iter()
            .zip(&b.t)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
    assert!(dt < 1e-12, "time stamps differ by {dt:e} s");
    // And the data are the simulation's measurement, joint for joint.
    assert_eq!(a.q, measured.q);

    let err = io::load_trajectory(&missing, &model)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("missing.mcap") && err.contains("joint 'hip_joint' is not in the data"),
        "{err}"
    );
}

fn short_recording() -> (physid::model::Model, physid::trajectory::Trajectory) {
    let root = common::root();
    let (mut sc, model, _) =
        physid::sim::scenario::load(&root.join("scenarios/cheetah3_shell.toml")).unwrap();
    sc.simulation.duration = 0.3;
    let rec = physid::sim::run(&model, &sc, &mut |_| {}).unwrap();
    (model, rec.measured)
}

#[test]
fn a_rosbag2_directory_split_in_two_files_on_another_topic_reads_whole() {
    let (model, measured) = short_recording();
    let dir = tempfile::tempdir().unwrap();
    let bag = dir.path().join("run_2026");
    std::fs::create_dir(&bag).unwrap();
    let order = [Some(1), Some(0), Some(2)];
    let half = measured.len() / 2;
    let start = 1_763_000_000_000_000_007;
    for (file, range) in [
        ("run_2026_0.mcap", 0..half),
        ("run_2026_1.mcap", half..usize::MAX),
    ] {
        let b = Bag {
            topic: "/leg/joint_states",
            range,
            ..Bag::default()
        };
        write_bag_with(&bag.join(file), &measured, &order, start, &b);
    }
    std::fs::write(
        bag.join("metadata.yaml"),
        "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n  relative_file_paths:\n    - run_2026_0.mcap\n    - run_2026_1.mcap\n  duration:\n    nanoseconds: 300000000\n",
    )
    .unwrap();
    let opts = io::DataOptions {
        topic: Some("/leg/joint_states".into()),
        ..Default::default()
    };
    let whole = read(&bag, &model, &opts).0;
    assert_eq!(whole.q, measured.q);
    assert_eq!(whole.tau, measured.tau);
    assert_eq!(whole.len(), measured.len());
    // Without the topic, the default /joint_states is named as missing.
    // Without the topic, the default /joint_states is named as missing, with the topics that
    // do carry joint states.
    let err = io::load_trajectory(&bag, &model).unwrap_err().to_string();
    assert!(
        err.contains("no /joint_states messages")
            && err.contains("topics with sensor_msgs/msg/JointState: /leg/joint_states")
            && err.contains("--topic"),
        "{err}"
    );
    // The same messages in a bag stored in SQLite (ROS 2's older default), metadata.yaml with
    // a flow-style list, read the same.
    let db_bag = dir.path().join("run_sqlite");
    std::fs::create_dir(&db_bag).unwrap();
    let db = db_bag.join("run_sqlite_0.db3");
    for file in ["run_2026_0.mcap", "run_2026_1.mcap"] {
        mcap_into_sqlite(&bag.join(file), &db);
    }
    std::fs::write(
        db_bag.join("metadata.yaml"),
        "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n  relative_file_paths: [run_sqlite_0.db3]\n",
    )
    .unwrap();
    let from_db = read(&db_bag, &model, &opts).0;
    assert_eq!(from_db.q, measured.q);
    assert_eq!(from_db.tau, measured.tau);
    // The one recording given as its MCAP bag and as its SQLite conversion: the files differ,
    // the samples do not (before: every sample counted twice).
    let err = io::load_all(&[&bag, &db_bag], &model, &opts)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("run_sqlite")
            && err.contains(&format!("holds the same {} samples as", measured.len()))
            && err.contains("run_2026"),
        "{err}"
    );
    // metadata.yaml of another recording: the topic listed with another type, or a topic
    // listed with messages that no file holds (before: read without a word).
    for (listed, says) in [
        (
            "name: /leg/joint_states\n        type: std_msgs/msg/Float64MultiArray\n      message_count: 300",
            "lists /leg/joint_states as std_msgs/msg/Float64MultiArray, but the bag's files store it as sensor_msgs/msg/JointState",
        ),
        (
            "name: /joint_states\n        type: sensor_msgs/msg/JointState\n      message_count: 300",
            "lists /joint_states (sensor_msgs/msg/JointState) with 300 messages, but none of the bag's files has a message on it",
        ),
    ] {
        std::fs::write(
            db_bag.join("metadata.yaml"),
            format!("rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n  relative_file_paths: [run_sqlite_0.db3]\n  topics_with_message_count:\n    - topic_metadata:\n        {listed}\n"),
        )
        .unwrap();
        let err = io::load_trajectory_with(&db_bag, &model, &opts)
            .unwrap_err()
            .to_string();
        assert!(err.contains("metadata.yaml") && err.contains(says), "{err}");
    }
    // The metadata rosbag2 writes for these files (the topic, its type, a count) reads.
    std::fs::write(
        db_bag.join("metadata.yaml"),
        "rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n  relative_file_paths: [run_sqlite_0.db3]\n  topics_with_message_count:\n    - topic_metadata:\n        name: /leg/joint_states\n        type: sensor_msgs/msg/JointState\n        serialization_format: cdr\n      message_count: 300\n    - topic_metadata:\n        name: /rosout\n        type: rcl_interfaces/msg/Log\n      message_count: 0\n",
    )
    .unwrap();
    assert_eq!(read(&db_bag, &model, &opts).0.q, measured.q);
    // A message stored as text, and the database compressed whole: each named.
    let saved = std::fs::read(&db).unwrap();
    let conn = rusqlite::Connection::open(&db).unwrap();
    conn.execute(
        "UPDATE messages SET data = CAST(data AS TEXT) WHERE id = 3",
        [],
    )
    .unwrap();
    drop(conn);
    let err = io::load_trajectory_with(&db_bag, &model, &opts)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("run_sqlite_0.db3") && err.contains("message 2: its data column holds text"),
        "{err}"
    );
    let mut zstd = vec![0x28, 0xb5, 0x2f, 0xfd];
    zstd.extend_from_slice(&saved[..64]);
    std::fs::write(&db, &zstd).unwrap();
    let err = io::load_trajectory_with(&db_bag, &model, &opts)
        .unwrap_err()
        .to_string();
    assert!(err.contains("is zstd-compressed"), "{err}");
    std::fs::write(&db, &saved).unwrap();
    // The same file listed twice (before: its messages read twice).
    std::fs::write(
        db_bag.join("metadata.yaml"),
        "rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n  relative_file_paths: [run_sqlite_0.db3, run_sqlite_0.db3]\n",
    )
    .unwrap();
    let err = io::load_trajectory_with(&db_bag, &model, &opts)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("metadata.yaml")
            && err
                .contains("lists run_sqlite_0.db3 twice in relative_file_paths (entries 1 and 2)"),
        "{err}"
    );
    // A storage physid cannot read is named.
    std::fs::write(
        db_bag.join("metadata.yaml"),
        "rosbag2_bagfile_information:\n  storage_identifier: parquet\n  relative_file_paths: [run_sqlite_0.db3]\n",
    )
    .unwrap();
    let err = io::load_trajectory_with(&db_bag, &model, &opts)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("metadata.yaml") && err.contains("'parquet'"),
        "{err}"
    );
}

/// Appends the messages of an MCAP file to a rosbag2 SQLite database (created with the tables
/// rosbag2 writes when absent).
fn mcap_into_sqlite(mcap_file: &Path, db: &Path) {
    let conn = rusqlite::Connection::open(db).unwrap();
    conn.execute_batch(
        "CREATE TABLE IF NOT EXISTS topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);
         CREATE TABLE IF NOT EXISTS messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL, data BLOB NOT NULL);",
    )
    .unwrap();
    let bytes = std::fs::read(mcap_file).unwrap();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let kind = m.channel.schema.as_ref().unwrap().name.clone();
        conn.execute(
            "INSERT OR IGNORE INTO topics(id, name, type, serialization_format, offered_qos_profiles) VALUES (1, ?1, ?2, 'cdr', '')",
            (&m.channel.topic, &kind),
        )
        .unwrap();
        conn.execute(
            "INSERT INTO messages(topic_id, timestamp, data) VALUES (1, ?1, ?2)",
            (m.log_time as i64, &m.data[..]),
        )
        .unwrap();
    }
}

#[test]
fn header_stamps_give_the_sampling_times_and_another_publisher_is_skipped() {
    let (model, measured) = short_recording();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("jitter.mcap");
    let b = Bag {
        header_stamps: true,
        other_publisher: true,
        ..Bag::default()
    };
    write_bag_with(
        &p,
        &measured,
        &[Some(0), Some(1), Some(2)],
        1_700_000_000_000_000_000,
        &b,
    );
    let header = io::DataOptions {
        stamp: io::mcap_log::Stamp::Header,
        ..Default::default()
    };
    let by_header = read(&p, &model, &header);
    assert_eq!(by_header.2, measured.len());
    let t0 = measured.t[0];
    let worst = by_header
        .0
        .t
        .iter()
        .zip(&measured.t)
        .map(|(a, b)| (a - (b - t0)).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-9, "header times off by {worst:e} s");
    // The log times carry the recorder's jitter (up to 0.9 ms).
    let by_log = read(&p, &model, &Default::default()).0;
    let off = by_log
        .t
        .iter()
        .zip(&measured.t)
        .map(|(a, b)| (a - (b - t0)).abs())
        .fold(0.0, f64::max);
    assert!(
        off > 1e-4,
        "log times should show the jitter, off by {off:e} s"
    );
}

#[test]
fn an_empty_velocity_array_is_named_with_its_message() {
    let (model, measured) = short_recording();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("novel.mcap");
    let b = Bag {
        empty_velocity_at: Some(5),
        ..Bag::default()
    };
    write_bag_with(&p, &measured, &[Some(0), Some(1), Some(2)], 0, &b);
    let err = io::load_trajectory(&p, &model).unwrap_err().to_string();
    assert!(
        err.contains("novel.mcap")
            && err.contains("message 5")
            && err.contains("velocity array is empty"),
        "{err}"
    );
}

#[test]
fn csv_columns_named_by_joint_in_any_order_read_as_numbered_ones() {
    let (model, measured) = short_recording();
    let dir = tempfile::tempdir().unwrap();
    let numbered = dir.path().join("numbered.csv");
    io::samples::write_csv(&numbered, &measured).unwrap();
    // The same data with columns named by joint, shuffled, and an extra joint.
    let text = std::fs::read_to_string(&numbered).unwrap();
    let mut rows = csv::Reader::from_reader(text.as_bytes());
    let header: Vec<String> = rows.headers().unwrap().iter().map(String::from).collect();
    let names = ["abad_joint", "hip_joint", "knee_joint"];
    let renamed: Vec<String> = header
        .iter()
        .map(|h| {
            let digits = h.trim_start_matches(|c: char| c.is_ascii_alphabetic());
            match digits.parse::<usize>() {
                Ok(j) => format!("{}_{}", &h[..h.len() - digits.len()], names[j - 1]),
                Err(_) => h.clone(),
            }
        })
        .collect();
    let order: Vec<usize> = (0..header.len()).rev().collect();
    let mut w = csv::Writer::from_path(dir.path().join("named.csv")).unwrap();
    let mut head: Vec<String> = order.iter().map(|&i| renamed[i].clone()).collect();
    head.push("q_gripper".into());
    w.write_record(&head).unwrap();
    for r in rows.records() {
        let r = r.unwrap();
        let mut rec: Vec<String> = order.iter().map(|&i| r[i].to_string()).collect();
        rec.push("0.5".into());
        w.write_record(&rec).unwrap();
    }
    w.flush().unwrap();
    let joints: Vec<String> = model.joint_names();
    assert_eq!(joints, names);
    let a = read(&numbered, &model, &Default::default()).0;
    let b = read(&dir.path().join("named.csv"), &model, &Default::default());
    assert_eq!(b.1, vec!["gripper".to_string()]);
    assert_eq!(a.q, b.0.q);
    assert_eq!(a.qd, b.0.qd);
    assert_eq!(a.tau, b.0.tau);
}

#[test]
fn a_joint_order_that_changes_from_message_to_message_reads_the_same() {
    let (model, measured) = short_recording();
    let dir = tempfile::tempdir().unwrap();
    let (steady, rotating) = (dir.path().join("a.mcap"), dir.path().join("b.mcap"));
    let order = [Some(2), None, Some(0), Some(1)];
    write_bag(&steady, &measured, &order, 1_700_000_000_000_000_000);
    let b = Bag {
        rotate_each: true,
        ..Bag::default()
    };
    write_bag_with(&rotating, &measured, &order, 1_700_000_000_000_000_000, &b);
    let a = read(&steady, &model, &Default::default()).0;
    let r = read(&rotating, &model, &Default::default()).0;
    assert_eq!(a.q, r.q);
    assert_eq!(a.qd, r.qd);
    assert_eq!(a.tau, r.tau);
}
