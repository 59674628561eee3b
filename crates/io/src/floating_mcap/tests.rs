use super::*;
use physid_core::spatial::rot_axis_angle;

/// A message to write: topic, type, log time (ns), CDR bytes.
type Raw = (&'static str, &'static str, u64, Vec<u8>);

/// A two-joint, two-foot log of `m` samples at 1 kHz, every signal linear in time (so that
/// interpolation between messages is exact) except the orientation, which turns at 1 rad/s.
fn log(m: usize) -> FloatingLog {
    let t: Vec<f64> = (0..m).map(|k| 0.001 * k as f64).collect();
    FloatingLog {
        joints: Logged {
            joint_names: vec!["a".into(), "b".into()],
            t: t.clone(),
            q: t.iter().flat_map(|&x| [0.2 + x, 0.3 - x]).collect(),
            qd: Some(t.iter().flat_map(|_| [1.0, -1.0]).collect()),
            qdd: None,
            tau: t.iter().flat_map(|&x| [1.0 + x, -2.5 * x]).collect(),
        },
        rotation: t
            .iter()
            .map(|&x| rot_axis_angle(&Vector3::new(0.6, 0.0, 0.8), 0.3 + x))
            .collect(),
        position: t.iter().map(|&x| Vector3::new(x, -x, 0.45)).collect(),
        twist: t
            .iter()
            .map(|&x| Motion::new(Vector3::new(x, 0.1, -0.2), Vector3::new(0.0, x, 1e-3)))
            .collect(),
        feet: vec!["left".into(), "right".into()],
        force: Some(
            t.iter()
                .flat_map(|&x| {
                    [
                        Vector3::new(x, -1.0, 200.0 - x),
                        Vector3::new(0.0, x, 150.0),
                    ]
                })
                .collect(),
        ),
        contact: Some((0..2 * m).map(|i| i % 3 != 0).collect()),
        accel: Some(
            t.iter()
                .map(|&x| Vector3::new(0.3 * x, -0.2, 9.81 - x))
                .collect(),
        ),
    }
}

fn names(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

fn read_back(path: &Path) -> Result<FloatingRead, String> {
    let opts = FloatingReadOptions::default();
    read(path, &names(&["a", "b"]), &names(&["left", "right"]), &opts).map_err(|e| e.to_string())
}

fn assert_close(got: &FloatingLog, want: &FloatingLog, tol: f64) {
    let close = |a: &[f64], b: &[f64]| {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
    };
    let (g, w) = (&got.joints, &want.joints);
    assert_eq!(g.joint_names, w.joint_names);
    assert!(close(&g.t, &w.t) && close(&g.q, &w.q) && close(&g.tau, &w.tau));
    assert_eq!(g.qd.is_some(), w.qd.is_some());
    let v3 = |v: &[Vector3<f64>]| v.iter().flat_map(|x| x.iter().copied()).collect::<Vec<_>>();
    assert!(close(&v3(&got.position), &v3(&want.position)));
    let tw = |v: &[Motion]| {
        v.iter()
            .flat_map(|m| m.ang.iter().chain(m.lin.iter()).copied())
            .collect::<Vec<_>>()
    };
    assert!(close(&tw(&got.twist), &tw(&want.twist)));
    for (a, b) in got.rotation.iter().zip(&want.rotation) {
        assert!((a - b).abs().max() <= tol.max(1e-12), "{a} {b}");
    }
    assert_eq!(got.rotation.len(), want.rotation.len());
    match (&got.force, &want.force) {
        (Some(a), Some(b)) => assert!(close(&v3(a), &v3(b))),
        (a, b) => assert_eq!(a.is_some(), b.is_some()),
    }
    match (&got.accel, &want.accel) {
        (Some(a), Some(b)) => assert!(close(&v3(a), &v3(b))),
        (a, b) => assert_eq!(a.is_some(), b.is_some()),
    }
    assert_eq!(got.contact, want.contact);
}

#[test]
fn a_log_reads_back_as_written() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.mcap");
    let want = log(50);
    write(&path, &want, "trunk").unwrap();
    let got = read_back(&path).unwrap();
    assert_eq!(got.left_out, (0, 0));
    assert_close(&got.log, &want, 1e-12);
    // Without forces or contacts there is no feet topic, and none is read.
    let bare = FloatingLog {
        force: None,
        contact: None,
        ..want.clone()
    };
    write(&path, &bare, "trunk").unwrap();
    let got = read_back(&path).unwrap();
    assert_eq!((got.log.force, got.log.contact), (None, None));
    // Without an accelerometer there is no IMU topic, and none is read.
    let no_imu = FloatingLog {
        accel: None,
        ..want.clone()
    };
    write(&path, &no_imu, "trunk").unwrap();
    assert_eq!(read_back(&path).unwrap().log.accel, None);
    // The foot order asked for, not the message's.
    let got = read(
        &path,
        &names(&["b", "a"]),
        &names(&["right"]),
        &FloatingReadOptions::default(),
    );
    let got = got.unwrap().log;
    assert_eq!(got.joints.joint_names, names(&["b", "a"]));
    assert_eq!(got.joints.q[..2], [want.joints.q[1], want.joints.q[0]]);
}

/// Messages `(topic, type, log time ns, CDR)` written into one MCAP file as they come.
fn write_raw(path: &Path, messages: &[Raw]) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut w = mcap::WriteOptions::new()
        .profile("ros2")
        .create(file)
        .unwrap();
    let mut channels = BTreeMap::new();
    for (k, (topic, kind, ns, data)) in messages.iter().enumerate() {
        let channel = *channels
            .entry((topic.to_string(), kind.to_string()))
            .or_insert_with(|| {
                let s = w.add_schema(kind, "ros2msg", b"").unwrap();
                w.add_channel(s, topic, "cdr", &BTreeMap::new()).unwrap()
            });
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: k as u32,
            log_time: *ns,
            publish_time: *ns,
        };
        w.write_to_known_channel(&header, data).unwrap();
    }
    w.finish().unwrap();
}

/// Sample `k`'s feet as a message listing them in the other order than the robot's.
fn feet_message_of(log: &FloatingLog, k: usize, header: &Header) -> FootForces {
    let f = log.feet.len();
    let (force, contact) = (log.force.as_ref().unwrap(), log.contact.as_ref().unwrap());
    FootForces {
        header: header.clone(),
        name: names(&["right", "left"]),
        force: [1, 0]
            .iter()
            .flat_map(|&i| force[k * f + i].iter().copied().collect::<Vec<_>>())
            .collect(),
        contact: [1, 0].iter().map(|&i| contact[k * f + i]).collect(),
    }
}

/// The messages of `log` on the four topics at their own rates: joint states every sample,
/// odometry every `every[0]`-th from sample `from[0]`, feet every `every[1]`-th from `from[1]`,
/// the IMU every third from sample 2.
fn at_rates(log: &FloatingLog, every: [usize; 2], from: [usize; 2]) -> Vec<Raw> {
    let mut out = vec![];
    let j = &log.joints;
    let n = j.dof();
    let zero = Covariance([0.0; 18], [0.0; 18]);
    let mut buf = vec![];
    for k in 0..log.len() {
        let (header, ns) = mcap_log::stamp(j.t[k]);
        let js = mcap_log::JointStateView {
            header: &header,
            name: &j.joint_names,
            position: &j.q[k * n..(k + 1) * n],
            velocity: &[],
            effort: &j.tau[k * n..(k + 1) * n],
        };
        out.push((
            "/joint_states",
            "sensor_msgs/msg/JointState",
            ns,
            cdr_into(&mut buf, &js).to_vec(),
        ));
        if k >= from[0] && (k - from[0]) % every[0] == 0 {
            let o = odometry_of(log, k, &header, "trunk", zero);
            out.push((
                TOPIC_ODOMETRY,
                ODOMETRY_TYPES[0],
                ns,
                cdr_into(&mut buf, &o).to_vec(),
            ));
        }
        if k >= from[1] && (k - from[1]) % every[1] == 0 {
            let m = feet_message_of(log, k, &header);
            out.push((
                TOPIC_FOOT_FORCES,
                FOOT_FORCES_TYPE,
                ns,
                cdr_into(&mut buf, &m).to_vec(),
            ));
        }
        if let (Some(accel), true) = (&log.accel, k >= 2 && (k - 2) % 3 == 0) {
            let m = imu_of(log, k, &header, "trunk", &accel[k]);
            out.push((TOPIC_IMU, IMU_TYPES[0], ns, cdr_into(&mut buf, &m).to_vec()));
        }
    }
    out
}

#[test]
fn topics_at_other_rates_are_brought_to_the_joint_samples() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bag.mcap");
    let full = log(60);
    // Odometry at 500 Hz from sample 3 (to sample 59: its last is 57), the feet at 250 Hz
    // from sample 1 (last 57).
    write_raw(&path, &at_rates(&full, [2, 4], [3, 1]));
    let got = read_back(&path).unwrap();
    assert_eq!(got.left_out, (3, 2));
    let k = 3..58;
    let kept = |v: &[f64], n: usize| v[k.start * n..k.end * n].to_vec();
    let f = full.feet.len();
    // The contact state held from the last feet message at or before each sample.
    let held: Vec<bool> = k
        .clone()
        .flat_map(|s| {
            let last = 1 + (s - 1) / 4 * 4;
            full.contact.as_ref().unwrap()[last * f..(last + 1) * f].to_vec()
        })
        .collect();
    let want = FloatingLog {
        joints: Logged {
            joint_names: full.joints.joint_names.clone(),
            t: full.joints.t[k.clone()].to_vec(),
            q: kept(&full.joints.q, 2),
            qd: None,
            qdd: None,
            tau: kept(&full.joints.tau, 2),
        },
        rotation: full.rotation[k.clone()].to_vec(),
        position: full.position[k.clone()].to_vec(),
        twist: full.twist[k.clone()].to_vec(),
        feet: full.feet.clone(),
        force: Some(full.force.as_ref().unwrap()[k.start * f..k.end * f].to_vec()),
        contact: Some(held),
        accel: Some(full.accel.as_ref().unwrap()[k.clone()].to_vec()),
    };
    // Linear signals exactly (to rounding); the orientation's chord over 2 ms: 1e-7 rad.
    assert_close(
        &got.log,
        &FloatingLog {
            rotation: got.log.rotation.clone(),
            ..want.clone()
        },
        1e-9,
    );
    for (a, b) in got.log.rotation.iter().zip(&want.rotation) {
        assert!((a - b).abs().max() < 2e-7, "{a} {b}");
    }
}

fn error_of(messages: &[Raw]) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.mcap");
    write_raw(&path, messages);
    let err = read_back(&path).unwrap_err();
    assert!(err.contains("bad.mcap"), "{err}");
    err
}

/// The messages of a 30-sample log without an accelerometer, every topic at every sample.
fn good() -> Vec<Raw> {
    let without = FloatingLog {
        accel: None,
        ..log(30)
    };
    at_rates(&without, [1, 1], [0, 0])
}

/// [`good`] with the fifth message of `topic` (at sample 4) replaced by `data` of type `kind`.
fn replaced(topic: &str, kind: &'static str, data: Vec<u8>) -> Vec<Raw> {
    let mut m = good();
    let (i, _) = (m.iter().enumerate())
        .filter(|(_, x)| x.0 == topic)
        .nth(4)
        .unwrap();
    m[i] = (m[i].0, kind, m[i].2, data);
    m
}

/// Sample 4's odometry, edited.
fn odometry_at_4(edit: &dyn Fn(&mut Odometry)) -> Vec<u8> {
    let l = log(30);
    let (header, _) = mcap_log::stamp(l.joints.t[4]);
    let mut o = odometry_of(&l, 4, &header, "trunk", Covariance([0.0; 18], [0.0; 18]));
    edit(&mut o);
    cdr_into(&mut vec![], &o).to_vec()
}

/// Sample 4's feet, edited.
fn feet_at_4(edit: &dyn Fn(&mut FootForces)) -> Vec<u8> {
    let (header, _) = mcap_log::stamp(0.004);
    let mut m = FootForces {
        header,
        name: names(&["left", "right"]),
        force: vec![0.0; 6],
        contact: vec![true; 2],
    };
    edit(&mut m);
    cdr_into(&mut vec![], &m).to_vec()
}

fn assert_refused(cases: Vec<(Vec<Raw>, &str)>) {
    for (messages, said) in cases {
        let err = error_of(&messages);
        assert!(err.contains(said), "{said}: {err}");
    }
}

#[test]
fn a_bad_odometry_message_is_refused_naming_the_topic_and_the_message() {
    let without: Vec<Raw> = good()
        .into_iter()
        .filter(|m| m.0 != TOPIC_ODOMETRY)
        .collect();
    let err = error_of(&without);
    assert!(
        err.contains("no /odometry messages")
            && err.contains("/foot_forces (physid_msgs/msg/FootForces)"),
        "{err}"
    );
    let odometry = |edit: &dyn Fn(&mut Odometry)| {
        replaced(TOPIC_ODOMETRY, ODOMETRY_TYPES[0], odometry_at_4(edit))
    };
    let mut corrupt = odometry_at_4(&|_| {});
    corrupt[4 + 8..4 + 12].copy_from_slice(&u32::MAX.to_le_bytes());
    let at = "/odometry message 13: ";
    assert_refused(vec![
        (
            replaced(TOPIC_ODOMETRY, "std_msgs/msg/String", vec![0, 1, 0, 0]),
            "/odometry message 13: carries std_msgs/msg/String, not nav_msgs/msg/Odometry",
        ),
        (
            odometry(&|o| o.orientation.w = 3.0),
            &format!("{at}pose.orientation's norm is"),
        ),
        (
            odometry(&|o| o.linear.y = f64::NAN),
            &format!("{at}twist.linear.y is NaN, not a finite value"),
        ),
        (
            replaced(TOPIC_ODOMETRY, ODOMETRY_TYPES[0], corrupt),
            &format!("{at}its header.frame_id claims 4294967295 bytes"),
        ),
    ]);
}

#[test]
fn a_bad_feet_message_is_refused_naming_the_topic_and_the_message() {
    let feet = |edit: &dyn Fn(&mut FootForces)| {
        replaced(TOPIC_FOOT_FORCES, FOOT_FORCES_TYPE, feet_at_4(edit))
    };
    let at = "/foot_forces message 14: ";
    assert_refused(vec![
        (
            feet(&|m| m.name[1] = "hind".into()),
            &format!("{at}names the feet [\"left\", \"hind\"], not the foot 'right'"),
        ),
        (
            feet(&|m| m.force.truncate(5)),
            &format!("{at}5 forces and 2 contacts for 2 feet"),
        ),
        (
            feet(&|m| m.contact.clear()),
            &format!("{at}logs forces or contacts where the first message did not"),
        ),
        (
            feet(&|m| m.force[2] = f64::INFINITY),
            &format!("{at}force of 'left'.z is inf"),
        ),
    ]);
}

#[test]
fn messages_that_cannot_be_interpolated_are_refused() {
    // Two odometry messages at one time.
    let mut twice = good();
    let dup = twice.iter().position(|m| m.0 == TOPIC_ODOMETRY).unwrap();
    twice.insert(dup + 1, twice[dup].clone());
    let err = error_of(&twice);
    assert!(
        err.contains("two /odometry messages at the same time, 0.000000000 s (messages 1 and 2)"),
        "{err}"
    );
    // A gap of 20 samples among 1 ms messages.
    let gap: Vec<Raw> = (good().into_iter().enumerate())
        .filter(|(i, m)| m.0 != TOPIC_ODOMETRY || !(20..80).contains(i))
        .map(|(_, m)| m)
        .collect();
    let err = error_of(&gap);
    assert!(
        err.contains("/odometry is silent for 0.0")
            && err.contains("more than 10 times its median spacing of 0.0010 s"),
        "{err}"
    );
    // Odometry entirely after the joint states.
    let late: Vec<Raw> = (good().into_iter())
        .map(|(topic, kind, ns, data)| match topic {
            TOPIC_ODOMETRY => (topic, kind, ns + 1_000_000_000, data),
            _ => (topic, kind, ns, data),
        })
        .collect();
    let err = error_of(&late);
    assert!(
        err.contains(
            "the joint states (30 samples) and /odometry do not overlap in time with /foot_forces"
        ),
        "{err}"
    );
}

#[test]
fn unset_header_stamps_are_named_as_the_likely_cause() {
    // Every odometry message stamped 0: under --stamp header the error says why.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("unset.mcap");
    let unset: Vec<Raw> = (good().into_iter())
        .map(|(topic, kind, ns, data)| match topic {
            TOPIC_ODOMETRY => (
                topic,
                kind,
                ns,
                odometry_at_4(&|o| o.header.stamp.nanosec = 0),
            ),
            _ => (topic, kind, ns, data),
        })
        .collect();
    write_raw(&path, &unset);
    let opts = FloatingReadOptions {
        stamp: Stamp::Header,
        ..Default::default()
    };
    let err = read(
        &path,
        &names(&["a", "b"]),
        &names(&["left", "right"]),
        &opts,
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("two /odometry messages at the same time")
            && err.contains("a publisher that leaves it unset stamps every message alike"),
        "{err}"
    );
}

#[test]
fn a_bad_imu_message_is_refused_naming_the_topic_and_the_message() {
    let l = log(30);
    let messages = at_rates(&l, [1, 1], [0, 0]);
    let fifth = |kind: &'static str, data: Vec<u8>| {
        let mut m = messages.clone();
        let (i, _) = (m.iter().enumerate())
            .filter(|(_, x)| x.0 == TOPIC_IMU)
            .nth(4)
            .unwrap();
        m[i] = (m[i].0, kind, m[i].2, data);
        m
    };
    let imu = |edit: &dyn Fn(&mut Imu)| {
        let (header, _) = mcap_log::stamp(l.joints.t[14]);
        let mut m = imu_of(&l, 14, &header, "trunk", &Vector3::new(0.0, 0.0, 9.81));
        edit(&mut m);
        fifth(IMU_TYPES[0], cdr_into(&mut vec![], &m).to_vec())
    };
    let mut corrupt = cdr_into(
        &mut vec![],
        &imu_of(
            &l,
            14,
            &mcap_log::stamp(0.014).0,
            "trunk",
            &Vector3::zeros(),
        ),
    )
    .to_vec();
    corrupt[4 + 8..4 + 12].copy_from_slice(&u32::MAX.to_le_bytes());
    assert_refused(vec![
        (
            fifth("std_msgs/msg/String", vec![0, 1, 0, 0]),
            "carries std_msgs/msg/String, not sensor_msgs/msg/Imu",
        ),
        (
            imu(&|m| m.linear_acceleration.y = f64::NAN),
            "linear_acceleration.y is NaN, not a finite value",
        ),
        (
            fifth(IMU_TYPES[0], corrupt),
            "its header.frame_id claims 4294967295 bytes, more than remain",
        ),
    ]);
}
