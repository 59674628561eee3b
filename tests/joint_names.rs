//! Joint data are matched to the robot's joints by name, not by position: a ROS 2 bag (MCAP,
//! `sensor_msgs/msg/JointState`) written by another writer with its joints in another order,
//! an extra joint and absolute time stamps reads as the same samples as one in the robot's
//! order. Before, names were only counted: a shuffled bag gave a 47 N m model with exit 0.

use physid::io;
use serde::Serialize;
use std::path::Path;

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

/// Writes `tr` as JointState messages with the joints in `order` (indices into `tr`'s joints,
/// `None` for an extra joint), stamped `start_ns` + t.
fn write_bag(
    path: &Path,
    tr: &physid::trajectory::Trajectory,
    order: &[Option<usize>],
    start_ns: u64,
) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut w = mcap::WriteOptions::new().create(file).unwrap();
    let schema = w
        .add_schema("sensor_msgs/msg/JointState", "ros2msg", b"")
        .unwrap();
    let channel = w
        .add_channel(schema, "/joint_states", "cdr", &Default::default())
        .unwrap();
    let name_of =
        |o: &Option<usize>| o.map_or("gripper".to_string(), |j| tr.joint_names[j].clone());
    for k in 0..tr.len() {
        let col = |v: &[f64], o: &Option<usize>| o.map_or(0.01, |j| v[j]);
        let msg = JointState {
            header: Header {
                stamp: Time { sec: 0, nanosec: 0 },
                frame_id: String::new(),
            },
            name: order.iter().map(name_of).collect(),
            position: order.iter().map(|o| col(tr.q_at(k), o)).collect(),
            velocity: order.iter().map(|o| col(tr.qd_at(k), o)).collect(),
            effort: order.iter().map(|o| col(tr.tau_at(k), o)).collect(),
        };
        let data = cdr::serialize::<_, _, cdr::CdrLe>(&msg, cdr::Infinite).unwrap();
        let t = start_ns + (tr.t[k] * 1e9).round() as u64;
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: k as u32,
            log_time: t,
            publish_time: t,
        };
        w.write_to_known_channel(&header, &data).unwrap();
    }
    w.finish().unwrap();
}

#[test]
fn a_bag_in_another_joint_order_with_an_extra_joint_reads_as_the_robot_order() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
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

    let a = io::load_trajectory(&plain, &model).unwrap();
    let b = io::load_trajectory(&shuffled, &model).unwrap();
    assert!(a.ignored_joints.is_empty());
    assert_eq!(b.ignored_joints, vec!["gripper".to_string()]);
    let (a, b) = (a.trajectory, b.trajectory);
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
