//! A bounded mutation fuzz of every reader (CSV, URDF, robot TOML, scenario TOML, MCAP (joint and
//! floating-base logs), sweep
//! TOML, rosbag2 metadata, STL meshes, diagnosis reports for --effects-from): valid files are mutated (bytes flipped, inserted, deleted and duplicated; numbers
//! replaced by extreme values) from a fixed seed, and each reader must answer with a value or an
//! error, never a panic (or an abort: a failed allocation ends the whole test binary).
//! Deterministic: the same inputs every run, so a crash once found stays tested. Found so far,
//! and fixed: an MCAP chunk whose inner record claimed ~8e18 bytes (the mcap message stream
//! reserved it and aborted; now every record length is bounded before reading), and a CDR string
//! length of 4 GB (bounded by the message's own size).

#[path = "../../tests/common/mod.rs"]
mod common;

use common::root;
use physid::io;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

/// Mutated inputs per reader and run.
const EXECUTIONS: usize = 2000;

const EXTREMES: [&str; 10] = [
    "1e300",
    "-1e300",
    "NaN",
    "inf",
    "-1",
    "0",
    "9223372036854775807",
    "1e-320",
    "",
    "-0",
];

/// One random mutation of `bytes`.
fn mutate(bytes: &[u8], rng: &mut ChaCha8Rng) -> Vec<u8> {
    let mut b = bytes.to_vec();
    if b.is_empty() {
        return vec![rng.random()];
    }
    for _ in 0..rng.random_range(1..=4) {
        let i = rng.random_range(0..b.len().max(1));
        match rng.random_range(0..6) {
            0 => {
                let last = b.len() - 1;
                b[i.min(last)] = rng.random();
            }
            1 => b.insert(i, rng.random()),
            2 => {
                let end = (i + rng.random_range(1..64)).min(b.len());
                b.drain(i..end);
            }
            3 => {
                let end = (i + rng.random_range(1..256)).min(b.len());
                let chunk = b[i..end].to_vec();
                b.splice(i..i, chunk);
            }
            4 => {
                // Replace the number that starts at or after `i` by an extreme one.
                let start = (i..b.len()).find(|&k| b[k].is_ascii_digit()).unwrap_or(i);
                let end = (start..b.len())
                    .find(|&k| !(b[k].is_ascii_digit() || b[k] == b'.' || b[k] == b'e'))
                    .unwrap_or(b.len());
                let x = EXTREMES[rng.random_range(0..EXTREMES.len())].as_bytes();
                b.splice(start..end, x.iter().copied());
            }
            _ => {
                // Overwrite four bytes with a large little-endian length (binary formats).
                let v: u32 = rng.random_range(u32::MAX / 2..=u32::MAX);
                for (k, x) in v.to_le_bytes().iter().enumerate() {
                    if let Some(slot) = b.get_mut(i + k) {
                        *slot = *x;
                    }
                }
            }
        }
        if b.is_empty() {
            break;
        }
    }
    b
}

/// Runs `read` on `EXECUTIONS` mutations of `seed` written to `file`; returns (inputs, errors).
fn fuzz(name: &str, seed: &[u8], file: &Path, read: &dyn Fn(&Path) -> bool) -> (usize, usize) {
    let mut rng = ChaCha8Rng::seed_from_u64(0xf022 ^ name.len() as u64);
    let mut rejected = 0;
    for k in 0..EXECUTIONS {
        let input = mutate(seed, &mut rng);
        std::fs::write(file, &input).unwrap();
        match catch_unwind(AssertUnwindSafe(|| read(file))) {
            Ok(ok) => rejected += usize::from(!ok),
            Err(_) => {
                let keep = file.with_extension(format!("crash{k}"));
                std::fs::write(&keep, &input).unwrap();
                panic!("{name}: input {k} panicked (kept as {})", keep.display());
            }
        }
    }
    (EXECUTIONS, rejected)
}

#[test]
fn text_readers_never_panic_on_mutated_files() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let names = vec!["j1".to_string(), "j2".to_string()];
    let mut csv = String::from("t,q1,q2,dq1,dq2,ddq1,ddq2,tau1,tau2\n");
    for k in 0..40 {
        let x = k as f64 * 0.01;
        csv += &format!("{x},{},{},1,2,0.5,0.5,3.25,-1\n", x.sin(), x.cos());
    }
    let urdf = std::fs::read(root().join("data/kuka_lwr4/kuka_lwr4.urdf")).unwrap();
    let robot = std::fs::read(root().join("scenarios/cheetah3_leg.toml")).unwrap();
    let scenario = std::fs::read(root().join("scenarios/cheetah3_shell.toml")).unwrap();
    // The sweep refers to its scenario by a relative path: give it one beside it.
    std::fs::copy(
        root().join("scenarios/sample_size.toml"),
        d.join("sample_size.toml"),
    )
    .unwrap();
    let sweep = std::fs::read_to_string(root().join("scenarios/sweeps/noise.toml"))
        .unwrap()
        .replace("../sample_size.toml", "sample_size.toml");
    let mut report = vec![];
    report.push(fuzz("csv", csv.as_bytes(), &d.join("a.csv"), &|p| {
        let read = io::samples::read_csv(p, Some(&names)).is_ok();
        let streamed = io::samples::stream_csv(p, &names, 0..usize::MAX, &mut |_, _| {}).is_ok();
        read && streamed
    }));
    report.push(fuzz("urdf", &urdf, &d.join("a.urdf"), &|p| {
        io::load_robot(&p.to_string_lossy()).is_ok()
    }));
    report.push(fuzz("robot toml", &robot, &d.join("robot.toml"), &|p| {
        io::robot_toml::load(p).is_ok()
    }));
    report.push(fuzz("scenario toml", &scenario, &d.join("sc.toml"), &|p| {
        physid::sim::scenario::load(p).is_ok()
    }));
    report.push(fuzz(
        "sweep toml",
        sweep.as_bytes(),
        &d.join("sweep.toml"),
        &|p| physid::experiment::sweep::load(p).is_ok(),
    ));
    for (name, (runs, rejected)) in ["csv", "urdf", "robot toml", "scenario toml", "sweep toml"]
        .iter()
        .zip(&report)
    {
        eprintln!("{name}: {runs} mutated inputs, {rejected} rejected with an error, 0 panics");
        // The mutations must reach the readers' error paths, or the fuzz tests nothing.
        assert!(
            *rejected > runs / 10,
            "{name}: only {rejected} of {runs} rejected"
        );
    }
}

#[test]
fn the_mcap_reader_never_panics_on_mutated_logs() {
    let dir = tempfile::tempdir().unwrap();
    let common::ShellRun {
        model, rec, text, ..
    } = common::shell_run(0.03);
    let log = dir.path().join("seed.mcap");
    common::write_mcap(&log, &model, &rec, &text);
    let seed = std::fs::read(&log).unwrap();
    assert!(io::mcap_log::read(&log).is_ok());
    let joints = model.joint_names();
    assert!(io::mcap_stream::stream_mcap(&log, &joints, 0..usize::MAX, &mut |_, _| {}).is_ok());
    // The whole-file reader and the streaming one (the leg's joints' processed samples).
    let (runs, rejected) = fuzz("mcap", &seed, &dir.path().join("a.mcap"), &|p| {
        let read = io::mcap_log::read(p).is_ok();
        let streamed =
            io::mcap_stream::stream_mcap(p, &joints, 0..usize::MAX, &mut |_, _| {}).is_ok();
        read && streamed
    });
    eprintln!("mcap: {runs} mutated inputs, {rejected} rejected with an error, 0 panics");
    assert!(rejected > runs / 10, "only {rejected} of {runs} rejected");
}

#[test]
fn the_floating_mcap_reader_never_panics_on_mutated_logs() {
    // A short quadruped log (joint states, odometry, feet), its three topics interpolated to
    // the joint states' times by the reader.
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("seed.mcap");
    let opts = physid::api::floating::SimulateFloatingOptions {
        start: Default::default(),
        robot: physid::api::model::RobotOptions::new("cheetah3"),
        duration: 0.05,
        rate: 1000.0,
        seed: 1,
        trot: None,
        still: false,
        sensors: Default::default(),
        out: log.clone(),
    };
    let wrote = physid::api::floating::simulate_floating(&opts).unwrap();
    let feet: Vec<String> = wrote.feet.iter().map(|f| f.body.clone()).collect();
    let read = |p: &Path| {
        let topics = io::floating_mcap::FloatingReadOptions::default();
        io::floating_mcap::read(p, &wrote.joints, &feet, &topics).is_ok()
    };
    assert!(read(&log));
    let seed = std::fs::read(&log).unwrap();
    let (runs, rejected) = fuzz("floating mcap", &seed, &dir.path().join("a.mcap"), &read);
    eprintln!("floating mcap: {runs} mutated inputs, {rejected} rejected with an error, 0 panics");
    assert!(rejected > runs / 10, "only {rejected} of {runs} rejected");
}

/// A rosbag2 `metadata.yaml`, the meshes a URDF names (binary STL) and a diagnosis report given
/// to `identify --effects-from`: each mutated, answered with a value or an error, never a
/// panic (the report through the binary: exit 0 or 2, never 101 or a signal).
#[test]
fn bag_metadata_meshes_and_reports_never_panic_when_mutated() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // rosbag2: the metadata lists a storage file that exists.
    let bag = d.join("bag");
    std::fs::create_dir(&bag).unwrap();
    std::fs::write(bag.join("run_0.db3"), b"").unwrap();
    let metadata = "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n  duration:\n    nanoseconds: 1000000000\n  relative_file_paths:\n    - run_0.db3\n  topics_with_message_count:\n    - topic_metadata:\n        name: /joint_states\n        type: sensor_msgs/msg/JointState\n      message_count: 100\n";
    let (bags, bag_rejected) = fuzz(
        "rosbag2 metadata",
        metadata.as_bytes(),
        &bag.join("metadata.yaml"),
        &|_| io::rosbag2::files(&bag).is_ok(),
    );
    // A URDF whose link is bounded by a mutated STL.
    let urdf = d.join("r.urdf");
    std::fs::write(
        &urdf,
        r#"<robot name="r"><link name="base"/>
  <link name="arm"><inertial><mass value="1"/><origin xyz="0.02 0.02 0.02"/>
    <inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial>
    <collision><geometry><mesh filename="tet.stl"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="5" velocity="2"/></joint></robot>"#,
    )
    .unwrap();
    let (meshes, _) = fuzz(
        "stl",
        &common::tetrahedron_stl(4),
        &d.join("tet.stl"),
        &|_| io::load_robot(&urdf.to_string_lossy()).is_ok(),
    );
    eprintln!("rosbag2 metadata: {bags} mutated, {bag_rejected} rejected; stl: {meshes} mutated; 0 panics");
    assert!(
        bag_rejected > bags / 10,
        "only {bag_rejected} of {bags} rejected"
    );
    // A diagnosis report of the KUKA arm, reduced to what identify reads from it.
    let k = root().join("data/kuka_lwr4");
    let short = d.join("short.csv");
    let text = std::fs::read_to_string(k.join("measurements_1.csv")).unwrap();
    std::fs::write(
        &short,
        text.lines().take(400).collect::<Vec<_>>().join("\n"),
    )
    .unwrap();
    let report = r#"{"robot":"kuka-lwr","joints":["lwr_0_joint","lwr_1_joint","lwr_2_joint","lwr_3_joint","lwr_4_joint","lwr_5_joint","lwr_6_joint"],"effects":[{"kind":"torque_offset","param":null},{"kind":"stribeck","param":0.05},{"kind":"compliance","param":0.001}],"confirmed":[true,false,true]}"#;
    let mut rng = ChaCha8Rng::seed_from_u64(0x5e907);
    let file = d.join("report.json");
    let (mut accepted, runs) = (0, 150);
    for i in 0..runs {
        let bytes = if i == 0 {
            report.as_bytes().to_vec()
        } else {
            mutate(report.as_bytes(), &mut rng)
        };
        std::fs::write(&file, &bytes).unwrap();
        let (code, _, err) = common::physid(&[
            "identify",
            "--robot",
            &k.join("kuka_lwr4.urdf").to_string_lossy(),
            "--data",
            &short.to_string_lossy(),
            "--constraints",
            "none",
            "--no-geometry-ellipsoids",
            "--friction",
            "viscous,coulomb",
            "--effects-from",
            &file.to_string_lossy(),
        ]);
        assert!(
            code == 0 || code == 2,
            "report mutation {i} ({}): exit {code}: {err}",
            String::from_utf8_lossy(&bytes)
        );
        accepted += usize::from(code == 0);
    }
    eprintln!("reports: {runs} mutated, {accepted} accepted, the rest refused; 0 panics");
    assert!(
        accepted >= 1 && accepted < runs / 2,
        "{accepted} of {runs} accepted"
    );
}
