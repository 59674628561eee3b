//! Bad input ends in a clear error naming the file, field or sample: never a panic, a hang, a
//! huge allocation, or an output written over an input. Each case here was a crash, a hang or
//! silent damage before (issue 13's list).

#[path = "../../tests/common/mod.rs"]
mod common;

use common::root;
use physid::effect::{Payload, TimeDelay};
use physid::io;
use physid::sim::scenario::{self, EffectSpec};
use std::path::{Path, PathBuf};

/// Runs `physid`: whether it succeeded, and what it said on stderr.
fn physid(args: &[&str]) -> (bool, String) {
    let (code, _, stderr) = common::physid(args);
    (code == 0, stderr)
}

const ONE_JOINT_URDF: &str = r#"<robot name="r">
  <link name="base"/>
  <link name="arm"><inertial><mass value="1"/><origin xyz="0.1 0 0"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="EFFORT" velocity="2"/></joint>
</robot>"#;

#[test]
fn a_negative_effort_limit_is_refused_by_name() {
    // Before: accepted, then `simulate` panicked in f64::clamp.
    let xml = ONE_JOINT_URDF.replace("EFFORT", "-5");
    let err = io::urdf::from_str(&xml, Path::new("r.urdf"), &Default::default()).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("limits.effort") && msg.contains("-5"), "{msg}");
    let ok = ONE_JOINT_URDF.replace("EFFORT", "5");
    assert!(io::urdf::from_str(&ok, Path::new("r.urdf"), &Default::default()).is_ok());
}

#[test]
fn scenario_values_that_hung_or_panicked_are_refused_by_key() {
    let (base, model, _) = scenario::load(&root().join("scenarios/cheetah3_shell.toml")).unwrap();
    let n = model.dof();
    // Before: capacity overflow panic (2^63 − 1) or a 2.4 TB allocation (1e11).
    for samples in [usize::MAX / 2, 100_000_000_000] {
        let mut sc = base.clone();
        sc.effects = vec![EffectSpec::TimeDelay(TimeDelay { samples })];
        let e = sc.validate(n).unwrap_err();
        assert_eq!(e.key, "effects[0].samples", "{e}");
    }
    // Before: a hang (1e9 RK4 steps per period).
    let mut sc = base.clone();
    sc.simulation.substeps = 1_000_000_000;
    assert_eq!(sc.validate(n).unwrap_err().key, "simulation.substeps");
    // Before: a panic on an `expect` in the payload's inertia.
    let mut sc = base.clone();
    sc.effects = vec![EffectSpec::Payload(Payload {
        mass: 1.0,
        com: [0.0, 1e200, 0.0],
        radius: 0.03,
        body: None,
    })];
    assert_eq!(sc.validate(n).unwrap_err().key, "effects[0].com");
    assert!(base.validate(n).is_ok());
}

/// A CSV of `rows` samples of the one-joint robot with `tau` in the row `bad`.
fn csv_with(dir: &Path, rows: usize, bad: usize, tau: &str) -> PathBuf {
    let mut text = String::from("t,q1,dq1,ddq1,tau1\n");
    for k in 0..rows {
        let x = k as f64 * 0.01;
        let t = if k == bad {
            tau.to_string()
        } else {
            format!("{}", x.sin())
        };
        text += &format!("{x},{},{},{},{t}\n", x.sin(), x.cos(), -x.sin());
    }
    let p = dir.join("data.csv");
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn an_absurd_sample_is_an_error_naming_it_whether_read_or_streamed() {
    // Before: 1e300 made Clarabel panic ("Eigval error") or gave NaN objectives and RMS.
    let dir = tempfile::tempdir().unwrap();
    let p = csv_with(dir.path(), 50, 17, "1e300");
    let names = vec!["j1".to_string()];
    let msg = io::samples::read_csv(&p, Some(&names))
        .unwrap_err()
        .to_string();
    assert!(msg.contains("sample 17") && msg.contains("tau1"), "{msg}");
    let streamed = io::samples::stream_csv(&p, &names, 0..50, &mut |_, _| {}).unwrap_err();
    let msg = streamed.to_string();
    assert!(msg.contains("sample 17") && msg.contains("tau1"), "{msg}");
    // An ordinary torque passes.
    let p = csv_with(dir.path(), 50, 17, "12.5");
    assert_eq!(
        io::samples::stream_csv(&p, &names, 0..50, &mut |_, _| {}).unwrap(),
        50
    );
}

#[test]
fn a_streamed_mcap_names_the_file_message_and_joint_of_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let common::ShellRun {
        model,
        mut rec,
        text,
        ..
    } = common::shell_run(0.05);
    let joints = model.joint_names();
    let stream = |p: &std::path::Path, joints: &[String]| {
        io::mcap_stream::stream_mcap(p, joints, 0..usize::MAX, &mut |_, _| {})
    };
    let good = dir.path().join("good.mcap");
    common::write_mcap(&good, &model, &rec, &text);
    assert_eq!(stream(&good, &joints).unwrap(), rec.processed.len());
    // A joint the robot has and the log does not.
    let mut other = joints.clone();
    other[1] = "elbow".into();
    let msg = stream(&good, &other).unwrap_err().to_string();
    assert!(
        msg.contains("good.mcap") && msg.contains("no joint 'elbow'") && msg.contains("message 0"),
        "{msg}"
    );
    // An absurd torque in sample 17.
    let n = joints.len();
    rec.processed.tau[17 * n + 2] = 1e300;
    let absurd = dir.path().join("absurd.mcap");
    common::write_mcap(&absurd, &model, &rec, &text);
    let msg = stream(&absurd, &joints).unwrap_err().to_string();
    assert!(
        msg.contains("absurd.mcap") && msg.contains("sample 17") && msg.contains(&joints[2]),
        "{msg}"
    );
    // Cut short: an error naming the file, never a panic or a partial count.
    let bytes = std::fs::read(&good).unwrap();
    let cut = dir.path().join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let msg = stream(&cut, &joints).unwrap_err().to_string();
    assert!(msg.contains("cut.mcap"), "{msg}");
    // Not an MCAP at all.
    let text_file = dir.path().join("notes.mcap");
    std::fs::write(&text_file, "t,q1\n0,1\n").unwrap();
    let msg = io::mcap_stream::mcap_streamable(&text_file)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("notes.mcap") && msg.contains("MCAP"), "{msg}");
}

#[test]
fn an_output_never_replaces_an_input() {
    let dir = tempfile::tempdir().unwrap();
    // simulate SC.toml --out SC.toml: before, the scenario was replaced by the MCAP.
    let sc = dir.path().join("sc.toml");
    std::fs::copy(root().join("scenarios/cheetah3_shell.toml"), &sc).unwrap();
    let before = std::fs::read(&sc).unwrap();
    let sc_s = sc.to_str().unwrap();
    let (ok, err) = physid(&["simulate", sc_s, "--out", sc_s, "--duration", "0.1"]);
    assert!(
        !ok && err.contains("refusing to write over the input"),
        "{err}"
    );
    assert_eq!(std::fs::read(&sc).unwrap(), before);
    // --out X --csv X: before, the MCAP was lost.
    let x = dir.path().join("x.out");
    let x_s = x.to_str().unwrap();
    let (ok, err) = physid(&["simulate", sc_s, "--out", x_s, "--csv", x_s]);
    assert!(!ok && err.contains("another output"), "{err}");
    assert!(!x.exists());
    // identify --out-urdf onto the robot's URDF or onto the data.
    let urdf = dir.path().join("r.urdf");
    std::fs::write(&urdf, ONE_JOINT_URDF.replace("EFFORT", "5")).unwrap();
    let data = csv_with(dir.path(), 200, usize::MAX, "");
    let (u, d) = (urdf.to_str().unwrap(), data.to_str().unwrap());
    for target in [u, d] {
        let before = std::fs::read(target).unwrap();
        let (ok, err) = physid(&[
            "identify",
            "--robot",
            u,
            "--data",
            d,
            "--constraints",
            "none",
            "--out-urdf",
            target,
        ]);
        assert!(
            !ok && err.contains("refusing to write over the input"),
            "{err}"
        );
        assert_eq!(std::fs::read(target).unwrap(), before);
    }
}

#[test]
fn negative_option_values_reach_the_option_check() {
    // Before: "unexpected argument '-1' found" without naming the option's rule.
    let (ok, err) = physid(&["identify", "--data", "x.csv", "--eps", "-1"]);
    assert!(
        !ok && err.contains("--eps must be a margin in [0, 1]"),
        "{err}"
    );
    let (ok, err) = physid(&["identify", "--data", "x.csv", "--prior-weight", "-1"]);
    assert!(!ok && err.contains("--prior-weight"), "{err}");
    for bounds in ["-1,2", "2,0.5", "0.5,inf", "1.5,2"] {
        let (ok, err) = physid(&["identify", "--data", "x.csv", "--mass-bounds", bounds]);
        let rule = format!("--mass-bounds {bounds}: give factors of the description's masses with 0 <= LO <= 1 <= HI");
        assert!(!ok && err.contains(&rule), "{bounds}: {err}");
    }
    for bounds in ["0.5", "a,b", "", "1,2,3"] {
        let (ok, err) = physid(&["identify", "--data", "x.csv", "--mass-bounds", bounds]);
        let said =
            err.contains("give two numbers LO,HI") || err.contains("is not a number (give LO,HI");
        assert!(!ok && said, "{bounds}: {err}");
    }
    for total in ["-1,2", "0,1", "2,1", "1,inf", "NaN,2"] {
        let (ok, err) = physid(&["identify", "--data", "x.csv", "--total-mass", total]);
        let rule = format!("--total-mass {total}: give the robot's moving mass in kg as LO,HI");
        assert!(!ok && err.contains(&rule), "{total}: {err}");
    }
    for total in ["3.7", "a,b", "", "1,2,3"] {
        let (ok, err) = physid(&["identify", "--data", "x.csv", "--total-mass", total]);
        let said = err.contains("give two numbers LO,HI (e.g. 3.5,3.9 kg)")
            || err.contains("is not a number (give LO,HI, e.g. 3.5,3.9 kg)");
        assert!(!ok && said, "{total}: {err}");
    }
    let (ok, err) = physid(&["diagnose", "--data", "x.csv", "--cutoff", "-5"]);
    assert!(
        !ok && err.contains("--cutoff must be a positive frequency"),
        "{err}"
    );
    let (ok, err) = physid(&["blind", "--description-error", "-1"]);
    assert!(
        !ok && err.contains("--description-error must be in [0, 1)"),
        "{err}"
    );
    let (ok, err) = physid(&["dynamics", "--samples", "1000000000000", "--out", "x.json"]);
    assert!(!ok && err.contains("--samples"), "{err}");
    for (args, said) in [
        (
            &["--sizes", "300,100"][..],
            "sizes must be positive and ascending",
        ),
        (
            &["--sizes", "0,100"][..],
            "sizes must be positive and ascending",
        ),
        (
            &["--torque-noise", "-1"][..],
            "torque_noise must be a number >= 0",
        ),
        (
            &["--prior-weight", "NaN"][..],
            "prior_weight must be a number >= 0",
        ),
        (&["--seeds", "0"][..], "--seeds must be in 1..=1000"),
    ] {
        let (ok, err) = physid(&[&["whole-robot", "--out", "never"][..], args].concat());
        assert!(!ok && err.contains(said), "{args:?}: {err}");
        assert!(!std::path::Path::new("never").exists());
    }
    // A floating robot's export needs a file to write, and says so before writing anything.
    let (ok, err) = physid(&["export", "--floating-base"]);
    assert!(
        !ok && err.contains("give --mjcf FILE and/or --urdf FILE"),
        "{err}"
    );
    // Only the root of a tree may float: a floating joint below a link with mass is named, and
    // nothing is written.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("floating.json");
    let urdf = dir.path().join("mid_floating.urdf");
    let heavy_root = ONE_JOINT_URDF
        .replace("EFFORT", "10")
        .replace(r#"<link name="base"/>"#, r#"<link name="base"><inertial><mass value="2"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>"#)
        .replace(r#"type="revolute""#, r#"type="floating""#);
    std::fs::write(&urdf, heavy_root).unwrap();
    let args = [
        "dynamics",
        "--floating-base",
        "--robot",
        urdf.to_str().unwrap(),
        "--out",
    ];
    let (ok, err) = physid(&[&args[..], &[out.to_str().unwrap()]].concat());
    assert!(
        !ok && err.contains(
            "joint 'j1' is floating but does not hang the robot from a massless root link"
        ) && err.contains("mid_floating.urdf"),
        "{err}"
    );
    assert!(!out.exists());
}

#[test]
fn a_recording_larger_than_memory_is_refused_before_allocating() {
    // Before: `duration = 99999` s (inside the documented cap) asked for 2.4 GB in one block and
    // about 44 GB in all.
    // 1e8 samples of 3 joints need about 58 GB: more than this machine kind has (24 GB).
    let available_gb = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|m| {
            let line = m
                .lines()
                .find(|l| l.starts_with("MemAvailable:"))?
                .to_string();
            line.split_whitespace().nth(1)?.parse::<f64>().ok()
        })
        .map(|kb| kb * 1024.0 / 1e9);
    assert!(
        available_gb.is_some_and(|gb| gb < 50.0),
        "this test needs a machine with less than 50 GB available ({available_gb:?})"
    );
    let (mut sc, model, _) = scenario::load(&root().join("scenarios/cheetah3_shell.toml")).unwrap();
    sc.simulation.duration = 99_999.0;
    let err = physid::sim::run(&model, &sc, &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("GB of memory are available"), "{err}");
}

#[test]
fn an_xml_file_that_is_not_a_robot_is_named_as_such() {
    // Before: reported as a closed kinematic loop.
    let p = Path::new("page.urdf");
    let html = "<?xml version=\"1.0\"?>\n<!-- a page --><html><body>hi</body></html>";
    let msg = io::urdf::from_str(html, p, &Default::default())
        .unwrap_err()
        .to_string();
    assert!(msg.contains("root element is <html>, not <robot>"), "{msg}");
    let empty = "<robot name=\"r\"></robot>";
    let msg = io::urdf::from_str(empty, p, &Default::default())
        .unwrap_err()
        .to_string();
    assert!(msg.contains("no <link> elements"), "{msg}");
}

#[test]
fn non_finite_normal_equations_are_an_error_not_a_solver_panic() {
    // Before: one torque sample of 1e300 made Clarabel panic ("Eigval error") under
    // `consistent` and `ellipsoid`, and gave NaN objectives under `none`.
    use physid::ident::{self, ConstraintSet, IdentError, NormalEquations, Options};
    let model = physid::model::cheetah3::leg();
    let p = model.layout().len;
    let mut yty = nalgebra::DMatrix::<f64>::identity(p, p);
    yty[(3, 3)] = f64::INFINITY;
    let ne = NormalEquations::from_sums(model.dof(), yty, nalgebra::DVector::zeros(p), 1.0, 100);
    for set in [
        ConstraintSet::None,
        ConstraintSet::Consistent,
        ConstraintSet::Ellipsoid,
    ] {
        let r = ident::identify(&model, &ne, &model.parameters(), &Options::new(set));
        assert!(matches!(r, Err(IdentError::NonFinite(_))), "{set:?}: {r:?}");
    }
}

#[test]
fn an_mcap_chunk_record_claiming_exabytes_is_an_error_naming_the_file() {
    // tests/fuzz_readers.rs found a compressed chunk whose inner record claimed ~8e18 bytes: the
    // mcap message stream reserved them and aborted (its deterministic inputs keep that case).
    // Here the same length in an uncompressed chunk: refused by the record-length bound.
    let mut buf = std::io::Cursor::new(Vec::new());
    let mut w = mcap::WriteOptions::new()
        .compression(None)
        .create(&mut buf)
        .unwrap();
    let schema = w.add_schema("s", "ros2msg", b"int32 x").unwrap();
    let channel = w
        .add_channel(schema, "/joint_states", "cdr", &Default::default())
        .unwrap();
    let payload = b"MARKERMARKER";
    let header = mcap::records::MessageHeader {
        channel_id: channel,
        sequence: 0,
        log_time: 1,
        publish_time: 1,
    };
    w.write_to_known_channel(&header, payload).unwrap();
    w.finish().unwrap();
    drop(w);
    let mut bytes = buf.into_inner();
    // The message record inside the (uncompressed) chunk: opcode 0x05, then its u64 length.
    let at = bytes
        .windows(payload.len())
        .position(|x| x == payload)
        .unwrap();
    let record = (0..at).rev().find(|&i| bytes[i] == 0x05).unwrap();
    bytes[record + 1..record + 9].copy_from_slice(&0x7300_0000_0000_0000u64.to_le_bytes());
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("huge.mcap");
    std::fs::write(&p, &bytes).unwrap();
    let err = io::mcap_log::read(&p).unwrap_err().to_string();
    assert!(
        err.contains("huge.mcap") && err.contains("not a readable MCAP"),
        "{err}"
    );
}

#[test]
fn logs_and_designs_as_robots_use_them_refuse_what_they_cannot_be() {
    let dir = tempfile::tempdir().unwrap();
    let kuka = root().join("data/kuka_lwr4/kuka_lwr4.urdf");
    let kuka = kuka.to_str().unwrap();
    // A cutoff above what the data's rate allows, naming the rate.
    let data = root().join("data/kuka_lwr4/measurements_1.csv");
    let (ok, err) = physid(&[
        "identify",
        "--data",
        data.to_str().unwrap(),
        "--robot",
        kuka,
        "--cutoff",
        "5000",
    ]);
    assert!(
        !ok && err.contains("cutoff 5000 Hz: the data are sampled at 200.04"),
        "{err}"
    );
    // One far below any filter the data can hold (before: blamed on "absurd values" in the
    // data).
    let (ok, err) = physid(&[
        "identify",
        "--data",
        data.to_str().unwrap(),
        "--robot",
        kuka,
        "--cutoff",
        "1e-300",
    ]);
    assert!(
        !ok && err.contains("cutoff 1e-300 Hz: the data are sampled at 200.04")
            && err.contains("must be at least 2.0004e-2 Hz"),
        "{err}"
    );
    // physid's own ground-truth channel is not a JointState topic: refused with its type and
    // the topics that are (before: its JointSample arrays were read as joint states).
    let sc = root().join("scenarios/cheetah3_shell.toml");
    let log = dir.path().join("shell.mcap");
    let (ok, err) = physid(&[
        "simulate",
        sc.to_str().unwrap(),
        "--out",
        log.to_str().unwrap(),
        "--duration",
        "0.5",
    ]);
    assert!(ok, "{err}");
    let (ok, err) = physid(&[
        "identify",
        "--data",
        log.to_str().unwrap(),
        "--topic",
        "/physid/ground_truth",
        "--allow-few-samples",
    ]);
    assert!(
        !ok && err.contains("topic /physid/ground_truth carries physid_msgs/msg/JointSample, not sensor_msgs/msg/JointState")
            && err.contains("topics with sensor_msgs/msg/JointState: /joint_states"),
        "{err}"
    );
    // --topic or --stamp on CSV data alone: refused (before: a warning, then read anyway).
    let csv = root().join("data/kuka_lwr4/measurements_1.csv");
    let urdf = root().join("data/kuka_lwr4/kuka_lwr4.urdf");
    for flag in [["--topic", "/joint_states"], ["--stamp", "header"]] {
        let (ok, err) = physid(&[
            "identify",
            "--robot",
            urdf.to_str().unwrap(),
            "--data",
            csv.to_str().unwrap(),
            flag[0],
            flag[1],
        ]);
        assert!(
            !ok && err.contains("measurements_1.csv") && err.contains("no data file given is one"),
            "{flag:?}: {err}"
        );
    }
    // Excitation designs: a ramp longer than half the run, a zero jerk limit, a zero export
    // rate, an export onto the base scenario.
    for (args, words) in [
        (
            vec!["--ramp", "50"],
            "--ramp must be 0 or more seconds, at most half the duration, got 50",
        ),
        (
            vec!["--max-jerk", "0"],
            "--max-jerk must be a positive number (rad/s³), got 0",
        ),
        (
            vec!["--rate", "0", "--csv", "never-written.csv"],
            "--rate must be a sample rate in (0, 100000] Hz, got 0",
        ),
        // A rate for no reference output (before: accepted without a word).
        (
            vec!["--rate", "500"],
            "the following required arguments were not provided:\n  <--csv <CSV>|--mcap <MCAP>>",
        ),
    ] {
        let mut a = vec!["excite", "--robot", "cheetah3", "--iterations", "1"];
        a.extend(args);
        let (ok, err) = physid(&a);
        assert!(!ok && err.contains(words), "{err}");
    }
    let base = dir.path().join("base.toml");
    std::fs::copy(root().join("scenarios/excitation/base.toml"), &base).unwrap();
    let before = std::fs::read(&base).unwrap();
    let b = base.to_str().unwrap();
    let (ok, err) = physid(&["excite", "--scenario", b, "--iterations", "1", "--csv", b]);
    assert!(
        !ok && err.contains("refusing to write over the input"),
        "{err}"
    );
    assert_eq!(std::fs::read(&base).unwrap(), before);
}

/// Each command is refused, its message holding every one of its words.
fn refused_naming(cases: &[(&[&str], &[&str])]) {
    for (args, words) in cases {
        let (ok, err) = physid(args);
        assert!(
            !ok && words.iter().all(|w| err.contains(w)),
            "{args:?} should be refused naming {words:?}: {err}"
        );
    }
}

#[test]
fn the_ladder_s_new_inputs_are_checked_by_name() {
    let k = root().join("data/kuka_lwr4");
    let s = |p: PathBuf| p.to_str().unwrap().to_string();
    let (urdf, m1, m2) = (
        s(k.join("kuka_lwr4.urdf")),
        s(k.join("measurements_1.csv")),
        s(k.join("measurements_2.csv")),
    );
    let dir = tempfile::tempdir().unwrap();
    // The same recording under another name.
    let copy = s(dir.path().join("copy.csv"));
    std::fs::copy(&m1, &copy).unwrap();
    // A base run without accelerations: the injected torques need the logged motion.
    let bare = s(dir.path().join("bare.csv"));
    let text = std::fs::read_to_string(&m1).unwrap();
    let mut out = String::new();
    for line in text.lines() {
        let cols: Vec<&str> = line.split(',').collect();
        out += &format!("{},{}\n", cols[..8].join(","), cols[22..29].join(","));
    }
    std::fs::write(&bare, out).unwrap();
    let (d, u) = ("--description-uncertainty", "0.05");
    let diagnose = ["diagnose", "--robot", &urdf, "--data", &m1];
    let real = ["blind", "--real", &m1, "--real", &m2, "--real-robot", &urdf];
    refused_naming(&[
        // A baseline without the uncertainty the change is judged within.
        (
            &[&diagnose[..], &["--baseline-data", &m2]].concat(),
            &["--baseline-data", d],
        ),
        // A baseline that is not there.
        (
            &[
                &diagnose[..],
                &["--baseline-data", "/nonexistent/before.csv", d, u],
            ]
            .concat(),
            &["/nonexistent/before.csv"],
        ),
        // The same recording in two roles, naming both.
        (
            &[&diagnose[..], &["--baseline-data", &copy, d, u]].concat(),
            &["copy.csv", "--baseline-data", "twice"],
        ),
        (
            &[
                "identify",
                "--robot",
                &urdf,
                "--data",
                &m1,
                "--validate-data",
                &m1,
            ],
            &["--validate-data", "twice"],
        ),
        (
            &[
                "blind",
                "--real",
                &m1,
                "--real",
                &copy,
                "--real-robot",
                &urdf,
                "--cases",
                "1",
            ],
            &["twice", "--real"],
        ),
        // The semi-real benchmark needs another run for the description, and its robot.
        (
            &[
                "blind",
                "--real",
                &m1,
                "--real-robot",
                &urdf,
                "--cases",
                "1",
            ],
            &["at least two runs"],
        ),
        (&["blind", "--real", &m1, "--cases", "1"], &["--real-robot"]),
        (&["blind", "--real-baseline", "--cases", "1"], &["--real"]),
        (
            &[
                "blind",
                "--real",
                &bare,
                "--real",
                &m2,
                "--real-robot",
                &urdf,
                "--cases",
                "1",
            ],
            &["bare.csv", "q̈"],
        ),
        // Out-of-range counts and uncertainties are refused before any work.
        (
            &[&real[..], &["--cases", "1000000000"]].concat(),
            &["cases"],
        ),
        (
            &[&real[..], &["--cases", "2", d, "-1"]].concat(),
            &["description", "uncertainty"],
        ),
    ]);
}

#[test]
fn counts_from_the_user_are_bounded_before_anything_is_allocated() {
    // Before: `blind --cases 1e9` ran for an hour (8 GB of case numbers, then cases one by
    // one); a 10^6-cell sweep grid aborted on allocation.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("b");
    let (ok, err) = physid(&[
        "blind",
        "--cases",
        "1000000000",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        !ok && err.contains("--cases") && err.contains("1000000000"),
        "{err}"
    );
    assert!(!out.exists());
    // Before: `--description-error` with `--real` was ignored without a word.
    let (ok, err) = physid(&[
        "blind",
        "--real",
        "a.csv,b.csv",
        "--real-robot",
        "r.urdf",
        "--description-error",
        "0.2",
    ]);
    assert!(
        !ok && err.contains("'--real <REAL>' cannot be used with '--description-error"),
        "{err}"
    );
    // Before: `--only 0,0` ran case 0 twice and scored it as two cases.
    let (ok, err) = physid(&[
        "blind",
        "--cases",
        "5",
        "--only",
        "0,0",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!ok && err.contains("--only: case 0 given twice"), "{err}");
    assert!(!out.exists());
    let values = format!(
        "[{}]",
        (1..=100)
            .map(|i| i.to_string())
            .collect::<Vec<_>>()
            .join(",")
    );
    let sweep = dir.path().join("big.toml");
    let scenario = root().join("scenarios/cheetah3_fourier.toml");
    std::fs::write(
        &sweep,
        format!(
            "scenario = {:?}\n[grid]\n\"sensors.torque_noise\" = {values}\n\"simulation.seed\" = {values}\n\"processing.cutoff\" = {values}\n",
            scenario.to_str().unwrap()
        ),
    )
    .unwrap();
    let out = dir.path().join("sw");
    let (ok, err) = physid(&[
        "sweep",
        sweep.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        !ok && err.contains("big.toml") && err.contains("cells"),
        "{err}"
    );
    assert!(!out.exists());
    // A grid of a hundred points (times the default seeds) is within the bound.
    let small = dir.path().join("small.toml");
    std::fs::write(
        &small,
        format!(
            "scenario = {:?}\n[grid]\n\"sensors.torque_noise\" = {values}\n",
            scenario.to_str().unwrap()
        ),
    )
    .unwrap();
    assert!(physid::experiment::sweep::load(&small).is_ok());
    // The same value twice on an axis (before: two cells of one configuration, accepted).
    let twice = dir.path().join("twice.toml");
    std::fs::write(
        &twice,
        format!(
            "scenario = {:?}\n[grid]\n\"sensors.torque_noise\" = [0.1, 0.3, 0.1]\n",
            scenario.to_str().unwrap()
        ),
    )
    .unwrap();
    let e = physid::experiment::sweep::load(&twice)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("twice.toml")
            && e.contains(
                "grid.\"sensors.torque_noise\": the value 0.1 is listed twice (entries 1 and 3)"
            ),
        "{e}"
    );
}

#[test]
fn a_design_without_finite_information_is_never_written() {
    // Before: exit 0, objective -inf, and a scenario written. (An acceleration limit of 1e12,
    // once a case here, now gets a finite design limited by the jerk: its -inf had come from a
    // round-off column in the information's basis. A limit that leaves no motion is the case.)
    let dir = tempfile::tempdir().unwrap();
    let scenario = root().join("scenarios/cheetah3_fourier.toml");
    for flag in [["--base-frequency", "1e9"], ["--max-acceleration", "1e-12"]] {
        let out = dir.path().join("design.toml");
        let (ok, err) = physid(&[
            "excite",
            "--scenario",
            scenario.to_str().unwrap(),
            flag[0],
            flag[1],
            "--iterations",
            "20",
            "--starts",
            "1",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(
            !ok && err.contains("no excitation found with a finite"),
            "{flag:?}: {err}"
        );
        assert!(!out.exists(), "{flag:?}");
    }
}

#[test]
fn outputs_never_replace_a_robot_s_sidecar_or_meshes() {
    // Before: `identify --out-effects` replaced the input URDF's own sidecar, and `export
    // --mjcf` a mesh the robot reads; a --package-dir that does not exist was accepted.
    let dir = tempfile::tempdir().unwrap();
    let kuka = root().join("data/kuka_lwr4");
    let copy = dir.path().join("kuka");
    std::fs::create_dir_all(copy.join("lwr_description/meshes/kuka")).unwrap();
    std::fs::copy(kuka.join("kuka_lwr4.urdf"), copy.join("kuka_lwr4.urdf")).unwrap();
    let meshes = kuka.join("lwr_description/meshes/kuka");
    for e in std::fs::read_dir(&meshes).unwrap() {
        let e = e.unwrap();
        if e.path().is_file() {
            std::fs::copy(
                e.path(),
                copy.join("lwr_description/meshes/kuka").join(e.file_name()),
            )
            .unwrap();
        }
    }
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let urdf = copy.join("kuka_lwr4.urdf");
    let mesh = copy.join("lwr_description/meshes/kuka/link_6.STL");
    let before = std::fs::read(&mesh).unwrap();
    let (ok, err) = physid(&["export", "--robot", &s(&urdf), "--mjcf", &s(&mesh)]);
    assert!(
        !ok && err.contains("refusing to write over the input"),
        "{err}"
    );
    assert_eq!(std::fs::read(&mesh).unwrap(), before);
    // An exported URDF with its sidecar, then identify's effects aimed at that sidecar.
    let arm = copy.join("arm.urdf");
    let (ok, err) = physid(&["export", "--robot", &s(&urdf), "--urdf", &s(&arm)]);
    assert!(ok, "{err}");
    let sidecar = copy.join("arm.physid.toml");
    let side = std::fs::read(&sidecar).unwrap();
    let (ok, err) = physid(&[
        "identify",
        "--robot",
        &s(&arm),
        "--data",
        &s(&kuka.join("measurements_1.csv")),
        "--out-effects",
        &s(&sidecar),
    ]);
    assert!(
        !ok && err.contains("refusing to write over the input"),
        "{err}"
    );
    assert_eq!(std::fs::read(&sidecar).unwrap(), side);
    let (ok, err) = physid(&[
        "model",
        "--robot",
        &s(&urdf),
        "--package-dir",
        &s(&copy.join("nowhere")),
    ]);
    assert!(
        !ok && err.contains("--package-dir") && err.contains("does not exist"),
        "{err}"
    );
}

#[test]
fn a_diagnosis_report_is_checked_before_its_effects_are_used() {
    // Before: `--effects-from` dropped effects when `confirmed` was shorter, skipped all when
    // it held strings, applied a report made for another robot, turned a negative compliance
    // into the default term, and took compliance:1e308 to "normal equations are not finite".
    let dir = tempfile::tempdir().unwrap();
    let k = root().join("data/kuka_lwr4");
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("results/kuka_diagnosis/report.json")).unwrap(),
    )
    .unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let try_report = |name: &str, edit: &dyn Fn(&mut serde_json::Value)| {
        let mut r = report.clone();
        edit(&mut r);
        let p = dir.path().join(format!("{name}.json"));
        std::fs::write(&p, serde_json::to_string(&r).unwrap()).unwrap();
        physid(&[
            "identify",
            "--robot",
            &s(&k.join("kuka_lwr4.urdf")),
            "--data",
            &s(&k.join("measurements_1.csv")),
            "--effects-from",
            &s(&p),
        ])
    };
    let (ok, err) = try_report("short", &|r| {
        r["confirmed"].as_array_mut().unwrap().pop();
    });
    assert!(
        !ok && err.contains("3 effects but 2 confirmed flags"),
        "{err}"
    );
    let (ok, err) = try_report("strings", &|r| r["confirmed"][0] = "true".into());
    assert!(
        !ok && err.contains("confirmed[0]") && err.contains("not true or false"),
        "{err}"
    );
    let (ok, err) = try_report("other", &|r| r["robot"] = "panda".into());
    assert!(
        !ok && err.contains("the report is for robot \"panda\""),
        "{err}"
    );
    for value in [-0.001, 1e308] {
        let (ok, err) = try_report("compliance", &|r| {
            r["effects"][0]["kind"] = "compliance".into();
            r["effects"][0]["param"] = value.into();
        });
        assert!(
            !ok && err.contains("effects[0]") && err.contains("out of range"),
            "{value}: {err}"
        );
    }
    let (ok, err) = try_report("param", &|r| r["effects"][0]["param"] = "big".into());
    assert!(!ok && err.contains("effects[0].param"), "{err}");
    // The report as written still works.
    let (ok, err) = try_report("same", &|_| {});
    assert!(ok, "{err}");
}

#[test]
fn meshes_and_masses_no_robot_has_are_named() {
    // Before: an STL header claiming 2^32 - 1 triangles and a mesh scale of 1e30 were accepted
    // without a word (or called "flat"), and a mass of 1e-300 kg was taken as a body.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("tet.stl"), common::tetrahedron_stl(4)).unwrap();
    std::fs::write(
        dir.path().join("bad.stl"),
        common::tetrahedron_stl(u32::MAX),
    )
    .unwrap();
    let urdf = |mesh: &str, scale: &str, mass: &str| {
        format!(
            r#"<robot name="r">
  <link name="base"/>
  <link name="arm"><inertial><mass value="{mass}"/><origin xyz="0.02 0.02 0.02"/>
    <inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial>
    <collision><geometry><mesh filename="{mesh}" scale="{scale}"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="5" velocity="2"/></joint>
</robot>"#
        )
    };
    let path = dir.path().join("r.urdf");
    let load = |xml: String| io::urdf::from_str(&xml, &path, &Default::default());
    // The sound mesh gives the link its ellipsoid, without a warning.
    let (m, warnings) = load(urdf("tet.stl", "1 1 1", "1")).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert!(m.bodies()[0].bounding.is_some());
    let (_, warnings) = load(urdf("bad.stl", "1 1 1", "1")).unwrap();
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("bad.stl") && w.contains("claims 4294967295 triangles")),
        "{warnings:?}"
    );
    let (_, warnings) = load(urdf("tet.stl", "1e30 1e30 1e30", "1")).unwrap();
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("tet.stl") && w.contains("mesh scale")),
        "{warnings:?}"
    );
    // A mass below 1e-9 kg is read as none: alone on its joint, that joint moves nothing.
    let err = load(urdf("tet.stl", "1 1 1", "1e-300"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("joint 'j1' moves only massless links") && err.contains("'arm' (1e-300 kg)"),
        "{err}"
    );
    // Fixed to a link that weighs (a camera frame of 1e-10 kg, as PR2's URDF gives them), it
    // is left out with a warning, and the body's mass is the link's own.
    let framed = urdf("tet.stl", "1 1 1", "1").replace(
        "</robot>",
        r#"<link name="frame"><inertial><mass value="1e-10"/><inertia ixx="1e-12" ixy="0" ixz="0" iyy="1e-12" iyz="0" izz="1e-12"/></inertial></link>
  <joint name="f" type="fixed"><parent link="arm"/><child link="frame"/><origin xyz="0 0 0.1"/></joint>
</robot>"#,
    );
    let (m, warnings) = load(framed).unwrap();
    assert_eq!(m.bodies()[0].inertia.mass(), 1.0);
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("read as massless: 'frame' (1e-10 kg)")),
        "{warnings:?}"
    );
}

#[test]
fn what_real_urdfs_leave_out_or_write_loosely_is_read_as_urdf_means_it() {
    // Before: "missing field `velocity`" (Drake's gripper), "missing field `xyz`" for a fixed
    // joint's misspelt axis (a Pioneer base), "duplicate field `material`" (xacro output), and
    // SDF's velocity = effort = -1 ("no limit") refused; a moving joint's axis without xyz was
    // "missing field `xyz`" with no joint named.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("r.urdf");
    let urdf = |elbow_axis: &str, limit: &str| {
        format!(
            r#"<robot name="r">
  <material name="red"><color rgba="1 0 0 1"/></material>
  <link name="base"><visual><geometry><box size="0.1 0.1 0.1"/></geometry><material name=""/><material name="red"/></visual></link>
  <link name="plate"/>
  <joint name="plate_joint" type="fixed"><parent link="base"/><child link="plate"/><axis xzy="0 0 1"/></joint>
  <link name="arm"><inertial><mass value="2"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="shoulder" type="revolute"><parent link="plate"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1"/></joint>
  <link name="hand"><inertial><mass value="1"/><origin xyz="0.1 0 0"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="elbow" type="revolute"><parent link="arm"/><child link="hand"/><origin xyz="0.3 0 0"/>{elbow_axis}
    {limit}</joint>
</robot>"#
        )
    };
    let load = |xml: String| io::urdf::from_str(&xml, &path, &Default::default());
    let (m, warnings) = load(urdf(
        r#"<axis xyz="0 1 0"/>"#,
        r#"<limit lower="-2" upper="2" effort="-1" velocity="-1.0"/>"#,
    ))
    .unwrap();
    assert_eq!(m.dof(), 2);
    for b in m.bodies() {
        assert!(b.limits.velocity.is_infinite() && b.limits.effort.is_infinite());
    }
    assert_eq!(m.bodies()[1].limits.upper, 2.0);
    for field in [r#"velocity="-1""#, r#"effort="-1""#] {
        assert!(
            warnings
                .iter()
                .any(|w| w.contains("joint 'elbow'") && w.contains(field)),
            "{field}: {warnings:?}"
        );
    }
    let err = load(urdf(r#"<axis xzy="0 1 0"/>"#, ""))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("r.urdf") && err.contains("joint 'elbow' (revolute): its <axis> has no xyz"),
        "{err}"
    );
    // A gripper's linkage coupled by <mimic> is named, with what to do about it.
    let gripper = urdf(r#"<axis xyz="0 1 0"/>"#, "").replace(
        "</robot>",
        r#"<link name="knuckle"><inertial><mass value="0.1"/><inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0" izz="1e-5"/></inertial></link>
  <joint name="knuckle_joint" type="revolute"><parent link="hand"/><child link="knuckle"/><axis xyz="1 0 0"/><mimic joint="elbow" multiplier="-1"/></joint>
  <link name="finger"/>
  <joint name="finger_joint" type="fixed"><parent link="knuckle"/><child link="finger"/></joint>
</robot>"#,
    );
    let err = load(gripper).unwrap_err().to_string();
    assert!(
        err.contains("joint 'knuckle_joint' mimics 'elbow'")
            && err.contains("a linkage coupled by <mimic>")
            && err.contains(r#"type="fixed""#),
        "{err}"
    );
}

#[test]
fn a_zero_gear_ratio_is_named_as_such() {
    // Before: blamed on `limits.effort` (the ratio scales the joint's limits).
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(root().join("scenarios/cheetah3_leg.toml")).unwrap();
    assert!(text.contains("gear_ratio = 10.6"));
    let path = dir.path().join("leg.toml");
    std::fs::write(
        &path,
        text.replacen("gear_ratio = 10.6", "gear_ratio = 0.0", 1),
    )
    .unwrap();
    let (ok, err) = physid(&["model", "--robot", path.to_str().unwrap()]);
    assert!(
        !ok && err.contains("rotor 'abad_rotor'") && err.contains("gear_ratio"),
        "{err}"
    );
    assert!(!err.contains("limits.effort"), "{err}");
}

#[test]
fn an_empty_joint_range_is_named() {
    // Before: lower = upper = 0 written out was read as unlimited without a word.
    let xml = ONE_JOINT_URDF
        .replace("EFFORT", "5")
        .replace(r#"lower="-1" upper="1""#, r#"lower="0" upper="0""#);
    let (m, warnings) = io::urdf::from_str(&xml, Path::new("r.urdf"), &Default::default()).unwrap();
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("joint 'j1'") && w.contains("empty range")),
        "{warnings:?}"
    );
    assert!(m.bodies()[0].limits.lower.is_infinite());
    let ok = ONE_JOINT_URDF.replace("EFFORT", "5");
    let (_, warnings) = io::urdf::from_str(&ok, Path::new("r.urdf"), &Default::default()).unwrap();
    assert!(
        warnings.iter().all(|w| !w.contains("range")),
        "{warnings:?}"
    );
}

/// A result folder that cannot be made is named as the user gave it, never as the hidden
/// staging folder beside it (/proc takes no new directory, even for root).
#[cfg(target_os = "linux")]
#[test]
fn a_result_folder_that_cannot_be_made_is_named_not_its_staging() {
    let scenario = root().join("scenarios/ci.toml");
    let (ok, err) = physid(&[
        "experiment",
        scenario.to_str().unwrap(),
        "--out",
        "/proc/physid-results",
    ]);
    assert!(
        !ok && err.contains("/proc/physid-results") && !err.contains("partial"),
        "{err}"
    );
}

/// A result folder never takes its inputs with it: an experiment's folder is replaced whole,
/// so giving the scenario's own folder (or any folder physid did not write) is refused before
/// any work, and the folder is left as it was; the same holds for sweep, blind and diagnose
/// reports, and for simulate onto a file the scenario's robot reads.
#[test]
fn a_result_folder_never_holds_or_replaces_an_input() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let scenarios = d.join("scenarios");
    std::fs::create_dir(&scenarios).unwrap();
    let sc = scenarios.join("ci.toml");
    std::fs::copy(root().join("scenarios/ci.toml"), &sc).unwrap();
    let listing = |p: &Path| {
        let mut v: Vec<String> = std::fs::read_dir(p)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    // Before: exit 0, and the folder held the results instead of the scenario.
    let (ok, err) = physid(&["experiment", &s(&sc), "--out", &s(&scenarios)]);
    assert!(
        !ok && err.contains("refusing to write over the folder of the input"),
        "{err}"
    );
    assert_eq!(listing(&scenarios), vec!["ci.toml"]);
    let sweep = scenarios.join("sweep.toml");
    std::fs::write(
        &sweep,
        "scenario = \"ci.toml\"\n[grid]\n\"sensors.torque_noise\" = [0.3]\n",
    )
    .unwrap();
    let (ok, err) = physid(&["sweep", &s(&sweep), "--out", &s(&scenarios)]);
    assert!(!ok && err.contains("folder of the input"), "{err}");
    assert_eq!(listing(&scenarios), vec!["ci.toml", "sweep.toml"]);
    // A folder physid did not write is not replaced.
    let notes = d.join("notes");
    std::fs::create_dir(&notes).unwrap();
    std::fs::write(notes.join("todo.txt"), "keep me").unwrap();
    let (ok, err) = physid(&["experiment", &s(&sc), "--out", &s(&notes)]);
    assert!(
        !ok && err.contains("notes") && err.contains("did not write"),
        "{err}"
    );
    assert_eq!(listing(&notes), vec!["todo.txt"]);
    // simulate onto the URDF its scenario's robot reads.
    let kuka = d.join("kuka");
    std::fs::create_dir(&kuka).unwrap();
    let urdf = kuka.join("kuka_lwr4.urdf");
    std::fs::copy(root().join("data/kuka_lwr4/kuka_lwr4.urdf"), &urdf).unwrap();
    let text = std::fs::read_to_string(root().join("scenarios/excitation/kuka_base.toml"))
        .unwrap()
        .replace("../../data/kuka_lwr4/kuka_lwr4.urdf", "kuka/kuka_lwr4.urdf");
    let ksc = d.join("kuka.toml");
    std::fs::write(&ksc, text).unwrap();
    let before = std::fs::read(&urdf).unwrap();
    let (ok, err) = physid(&["simulate", &s(&ksc), "--out", &s(&urdf)]);
    assert!(
        !ok && err.contains("refusing to write over the input"),
        "{err}"
    );
    assert_eq!(std::fs::read(&urdf).unwrap(), before);
    // excite --scenario onto the URDF its base scenario's robot reads (was overwritten).
    let (ok, err) = physid(&[
        "excite",
        "--scenario",
        &s(&ksc),
        "--duration",
        "4",
        "--no-check",
        "--out",
        &s(&urdf),
    ]);
    assert!(
        !ok && err.contains("refusing to write over the input"),
        "{err}"
    );
    assert_eq!(std::fs::read(&urdf).unwrap(), before);
    // blind and diagnose results into the folder of their inputs.
    let (ok, err) = physid(&[
        "blind",
        "--cases",
        "1",
        "--out",
        &s(&kuka),
        "--scenario",
        &s(&ksc),
    ]);
    assert!(!ok && err.contains("folder of the input"), "{err}");
    let m1 = root().join("data/kuka_lwr4/measurements_1.csv");
    let (ok, err) = physid(&[
        "diagnose",
        "--robot",
        &s(&urdf),
        "--data",
        &s(&m1),
        "--report",
        &s(&kuka),
    ]);
    assert!(!ok && err.contains("folder of the input"), "{err}");
    assert_eq!(listing(&kuka), vec!["kuka_lwr4.urdf"]);
}

#[test]
fn a_report_folder_is_written_whole_never_into_a_user_s_folder_or_a_missing_one() {
    let dir = tempfile::tempdir().unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let k = root().join("data/kuka_lwr4");
    let (urdf, m1) = (k.join("kuka_lwr4.urdf"), k.join("measurements_1.csv"));
    let report = |out: &Path| {
        physid(&[
            "diagnose",
            "--robot",
            &s(&urdf),
            "--data",
            &s(&m1),
            "--only",
            "lwr_1_joint,lwr_3_joint",
            "--report",
            &s(out),
        ])
    };
    // A folder of the user's own files: refused before the work, the files untouched.
    let own = dir.path().join("mine");
    std::fs::create_dir(&own).unwrap();
    std::fs::write(own.join("report.md"), "my notes").unwrap();
    let (ok, err) = report(&own);
    assert!(
        !ok && err.contains("is a folder physid did not write (no report.json)"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_to_string(own.join("report.md")).unwrap(),
        "my notes"
    );
    // A folder under one that does not exist: refused, nothing created.
    let (ok, err) = report(&dir.path().join("missing/rep"));
    assert!(!ok && err.contains("does not exist"), "{err}");
    assert!(!dir.path().join("missing").exists());
    // Written, then written again over itself: the same files, nothing left beside them.
    let out = dir.path().join("rep");
    for _ in 0..2 {
        let (ok, err) = report(&out);
        assert!(ok, "{err}");
    }
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["mine", "rep"]);
    assert!(out.join("report.json").is_file() && out.join("report.html").is_file());
}

#[test]
fn an_excitation_reference_too_large_for_memory_or_of_one_sample_is_refused_before_anything_is_written(
) {
    // Before: `--duration 1e5 --rate 1e5 --csv` aborted on allocation with the scenario
    // already written; `--rate 0.01` wrote a one-sample CSV.
    let dir = tempfile::tempdir().unwrap();
    let (out, csv) = (dir.path().join("sc.toml"), dir.path().join("ref.csv"));
    let s = |p: &Path| p.to_str().unwrap().to_string();
    for (args, words) in [
        (
            ["--duration", "1e5", "--rate", "1e5"],
            "samples of --csv/--mcap, about",
        ),
        (
            ["--duration", "10", "--rate", "0.01"],
            "--rate 0.01 Hz over --duration 10 s gives 1 samples of --csv/--mcap; give a rate of at least 0.9 Hz",
        ),
    ] {
        let mut a = vec!["excite", "--robot", "cheetah3", "--iterations", "1"];
        a.extend(args);
        let (o, c) = (s(&out), s(&csv));
        a.extend(["--out", &o, "--csv", &c]);
        let (ok, err) = physid(&a);
        assert!(!ok && err.contains(words), "{args:?}: {err}");
        assert!(!out.exists() && !csv.exists(), "{args:?}: written");
    }
}

#[test]
fn absurd_margins_and_a_folder_as_an_output_file_are_refused_by_name() {
    // Before: --eps/--ellipsoid-margin 1e300 reached the cone solver ("NumericalError", no
    // option named); `excite --csv .` failed with "Device or resource busy" after writing.
    let k = root().join("data/kuka_lwr4");
    let (urdf, m1) = (k.join("kuka_lwr4.urdf"), k.join("measurements_1.csv"));
    let (urdf, m1) = (urdf.to_str().unwrap(), m1.to_str().unwrap());
    let identify = ["identify", "--robot", urdf, "--data", m1];
    refused_naming(&[
        (
            &[&identify[..], &["--eps", "1e300"]].concat(),
            &["--eps must be a margin in [0, 1]", "got 1e300"],
        ),
        (
            &[&identify[..], &["--ellipsoid-margin", "1e300"]].concat(),
            &["ellipsoid margin 1e300 m must be", "at most 10 m"],
        ),
    ]);
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sc.toml");
    let (ok, err) = physid(&[
        "excite",
        "--robot",
        "cheetah3",
        "--iterations",
        "1",
        "--out",
        out.to_str().unwrap(),
        "--csv",
        dir.path().to_str().unwrap(),
    ]);
    assert!(
        !ok && err.contains("is a folder: give a file name for this output"),
        "{err}"
    );
    assert!(!out.exists());
}

#[test]
fn a_semi_real_run_too_short_for_a_diagnosis_is_refused_at_once_naming_it() {
    // Before: "case 1: training data have 20 samples" after 6 s, no file named.
    let dir = tempfile::tempdir().unwrap();
    let k = root().join("data/kuka_lwr4");
    let text = std::fs::read_to_string(k.join("measurements_1.csv")).unwrap();
    let short = dir.path().join("short.csv");
    std::fs::write(
        &short,
        text.lines().take(101).collect::<Vec<_>>().join("\n") + "\n",
    )
    .unwrap();
    let runs = format!(
        "{},{}",
        k.join("measurements_2.csv").display(),
        short.display()
    );
    let urdf = k.join("kuka_lwr4.urdf");
    let (ok, err) = physid(&[
        "blind",
        "--real",
        &runs,
        "--real-robot",
        urdf.to_str().unwrap(),
        "--cases",
        "2",
    ]);
    assert!(
        !ok && err.contains(
            "short.csv: 100 samples: a run of the semi-real benchmark needs at least 640"
        ),
        "{err}"
    );
    // An empty entry in the list (before: clap's "a value is required").
    let runs = format!(",{}", k.join("measurements_2.csv").display());
    let (ok, err) = physid(&[
        "blind",
        "--real",
        &runs,
        "--real-robot",
        urdf.to_str().unwrap(),
    ]);
    assert!(
        !ok && err.contains("invalid value '' for '--real <REAL>': an empty entry in the list"),
        "{err}"
    );
}

#[test]
fn every_joint_locked_is_said_as_such() {
    // Before: "no joint moves faster than 0.05 rad/s often enough to estimate the noise floor".
    let k = root().join("data/kuka_lwr4");
    let all = (0..7)
        .map(|j| format!("lwr_{j}_joint"))
        .collect::<Vec<_>>()
        .join(",");
    let (urdf, m1) = (k.join("kuka_lwr4.urdf"), k.join("measurements_1.csv"));
    for command in ["identify", "diagnose"] {
        let (ok, err) = physid(&[
            command,
            "--robot",
            urdf.to_str().unwrap(),
            "--data",
            m1.to_str().unwrap(),
            "--lock",
            &all,
        ]);
        assert!(
            !ok && err.contains(
                "measurements_1.csv: every joint is held still: locked as asked (lwr_0_joint,"
            ),
            "{command}: {err}"
        );
    }
}

#[test]
fn a_cutoff_that_filters_nothing_is_warned_about() {
    // Before: accepted without a word on a log that carries q̇ and q̈.
    let k = root().join("data/kuka_lwr4");
    let (urdf, m1) = (k.join("kuka_lwr4.urdf"), k.join("measurements_1.csv"));
    let run = |data: &Path| {
        common::command()
            .args(["identify", "--robot", urdf.to_str().unwrap(), "--data"])
            .arg(data)
            .args(["--cutoff", "5"])
            .output()
            .unwrap()
    };
    let o = run(&m1);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("warning: --cutoff 5 Hz filters nothing: every file logs q̇ and q̈"),
        "{err}"
    );
    // The same run as t, q, τ: the cutoff filters the derived q̇ and q̈, no warning.
    let dir = tempfile::tempdir().unwrap();
    let model = io::load_robot(urdf.to_str().unwrap()).unwrap();
    let (logged, _, _) = io::load_logged(&m1, &model, &Default::default()).unwrap();
    let tq = dir.path().join("tq.csv");
    std::fs::write(&tq, physid::bench::semireal::logged_csv(&logged)).unwrap();
    let o = run(&tq);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.success() && !err.contains("filters nothing"),
        "{err}"
    );
}

#[test]
fn experiment_sizes_beyond_one_run_are_blamed_on_the_sizes_before_anything_is_made() {
    // Before: "scenario simulation.duration: more than 1e8 samples" for a cell, and an empty
    // cells/ folder left.
    let dir = tempfile::tempdir().unwrap();
    let sweep = dir.path().join("s.toml");
    let base = root().join("scenarios/sample_size.toml");
    std::fs::write(
        &sweep,
        format!(
            "scenario = {:?}\n[grid]\n\"sensors.torque_noise\" = [0.1]\n[experiment]\nseeds = 1\nsizes = [30, 300000000]\n",
            base.to_str().unwrap()
        ),
    )
    .unwrap();
    let out = dir.path().join("res");
    let (ok, err) = physid(&[
        "sweep",
        sweep.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        !ok && err.contains("experiment.sizes: the largest training size 300000000"),
        "{err}"
    );
    assert!(!out.exists());
}

/// `physid <command> <args>` must fail saying `said`, writing nothing at `never`.
fn refused(command: &[&str], args: &[&str], said: &str, never: &Path) {
    let (ok, err) = physid(&[command, args].concat());
    assert!(
        !ok && err.contains(said),
        "{args:?}: expected '{said}' in: {err}"
    );
    assert!(!never.exists(), "{args:?} wrote {}", never.display());
}

#[test]
fn a_floating_log_and_its_options_are_checked_naming_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("standing.csv");
    let log_arg = log.to_str().unwrap();
    let never = dir.path().join("never.urdf");
    let never_arg = never.to_str().unwrap();
    // The simulation's options.
    let sim = ["simulate-floating", "--out", never_arg];
    for (args, said) in [
        (
            &["--duration", "0"][..],
            "duration = 0: expected 0 < s <= 3600",
        ),
        (
            &["--rate", "50"][..],
            "rate = 50: expected 100 <= Hz <= 10000",
        ),
        (
            &["--sensors", "tilt_noise=1"][..],
            "tilt_noise = 1 rad is no state estimator's",
        ),
        (
            &["--sensors", "gyro_noise=-1"][..],
            "gyro_noise = -1 must be finite and >= 0",
        ),
        (&["--sensors", "bogus=1"][..], "unknown field `bogus`"),
        (
            &["--sensors", "accel_noise=-0.1"][..],
            "accel_noise = -0.1 must be finite and >= 0",
        ),
        (
            &["--sensors", "accelerometer=maybe"][..],
            "'maybe' is not a number or true/false",
        ),
        (
            &["--sensors", "torque_noise"][..],
            "expected key=value or exact",
        ),
        (
            &["--sensors", "torque_noise=abc"][..],
            "'abc' is not a number or true/false",
        ),
        (
            &["--trot", "0.1"][..],
            "--trot: expected CROUCH,HZ (two numbers)",
        ),
        (
            &["--trot", "1,2"][..],
            "the crouch must be 0 to 0.5 rad and the frequency 0 to 5 Hz",
        ),
        (
            &["--trot", "0.2,1.5", "--duration", "4"][..],
            "the robot fell at t = ",
        ),
        (&["--trot", "0.15,2.5", "--still"][..], "still and trot"),
        (&["--drop", "0.6"][..], "drop = 0.6: expected 0 <= m <= 0.5"),
        (
            &["--drop", "-0.01"][..],
            "drop = -0.01: expected 0 <= m <= 0.5",
        ),
        (&["--drop", "nan"][..], "drop = NaN: expected 0 <= m <= 0.5"),
        (
            &["--push", "1,2"][..],
            "--push: expected VX,VY,VZ (three numbers)",
        ),
        (
            &["--push", "3,3,3"][..],
            "push: expected a velocity VX,VY,VZ of at most 5 m/s",
        ),
        (
            &["--push", "inf,0,0"][..],
            "push: expected a velocity VX,VY,VZ of at most 5 m/s",
        ),
        (
            &["--push", "0,4,0", "--duration", "2"][..],
            "the robot fell at t = ",
        ),
        (
            &["--ground-friction", "-1"][..],
            "ground_friction = -1: expected 0 <= μ <= 2",
        ),
        (
            &["--ground-friction", "nan"][..],
            "ground_friction = NaN: expected 0 <= μ <= 2",
        ),
        (
            &[
                "--robot",
                concat!(
                    env!("CARGO_MANIFEST_DIR"),
                    "/../data/kuka_lwr4/kuka_lwr4.urdf"
                ),
            ][..],
            "the floating-base simulation is the quadruped's",
        ),
    ] {
        refused(&sim, args, said, &never);
    }
    let (ok, err) = physid(&["simulate-floating", "--out", log_arg, "--duration", "2"]);
    assert!(ok, "{err}");
    // The text report: which body changed against the description (none: the log is of the
    // description), the bodies with the masses the log does not determine marked, the base
    // parameters.
    let (code, out, err) = common::physid(&["identify-floating", "--data", log_arg]);
    assert_eq!(code, 0, "{err}");
    for said in [
        "against the description: no body differs",
        "masses are not determined by the log on their own",
        "base parameters (what the data determine)",
        "\n  β1 ",
    ] {
        assert!(out.contains(said), "{said}: {out}");
    }
    // The ground truth written beside a log never replaces the robot simulated.
    let twin = dir.path().join("twin.truth.urdf");
    let (ok, err) = physid(&[
        "export",
        "--floating-base",
        "--urdf",
        twin.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let twin_log = dir.path().join("twin.csv");
    let twin_args = [
        "--robot",
        twin.to_str().unwrap(),
        "--out",
        twin_log.to_str().unwrap(),
    ];
    refused(
        &["simulate-floating"],
        &twin_args,
        "refusing to write over the input",
        &twin_log,
    );
    // The identification's options and the log.
    let id = [
        "identify-floating",
        "--data",
        log_arg,
        "--out-urdf",
        never_arg,
    ];
    for (args, said) in [
        (&["--baseline-data", log_arg][..], "the log itself"),
        (
            &["--baseline-data", "/nonexistent/before.csv"][..],
            "/nonexistent/before.csv",
        ),
        (
            &["--foot", "fr_shank"][..],
            "--foot 'fr_shank': expected BODY:X,Y,Z",
        ),
        (
            &["--foot", "fr_shank:0,0"][..],
            "X,Y,Z must be three numbers",
        ),
        (
            &["--foot", "paw:0,0,0"][..],
            "foot 'paw': the robot has no body of that name",
        ),
        (
            &["--foot", "fr_shank:0,0,1e9"][..],
            "must be finite, within 10 m of the body",
        ),
        (
            &["--prior-weight", "-1"][..],
            "prior_weight = -1: expected >= 0",
        ),
        (
            &["--contact-force", "NaN"][..],
            "contact_force = NaN: expected >= 0 N",
        ),
        (&["--cutoff", "0"][..], "cutoff = 0: expected > 0 Hz"),
        (
            &[
                "--robot",
                concat!(env!("CARGO_MANIFEST_DIR"), "/../data/solo12/solo12.urdf"),
            ][..],
            "name the feet (--foot BODY:X,Y,Z for each)",
        ),
        (
            &["--out-mjcf", log_arg][..],
            "refusing to write over the input",
        ),
        (
            &[
                "--truth",
                concat!(env!("CARGO_MANIFEST_DIR"), "/../data/solo12/solo12.urdf"),
            ][..],
            "the ground truth is not a description of cheetah3_quadruped",
        ),
        (
            &["--truth", never_arg][..],
            "refusing to write over the input",
        ),
    ] {
        refused(&id, args, said, &never);
    }
    // A log without the trunk, or without what the setting needs.
    let text = std::fs::read_to_string(&log).unwrap();
    let strip = |prefix: &str| -> String {
        let rows: Vec<Vec<&str>> = text.lines().map(|l| l.split(',').collect()).collect();
        let keep: Vec<usize> = (0..rows[0].len())
            .filter(|&i| !rows[0][i].starts_with(prefix))
            .collect();
        rows.iter()
            .map(|r| keep.iter().map(|&i| r[i]).collect::<Vec<_>>().join(",") + "\n")
            .collect()
    };
    let bare = dir.path().join("bare.csv");
    let bare_arg = bare.to_str().unwrap();
    std::fs::write(&bare, strip("base_")).unwrap();
    let id_bare = [
        "identify-floating",
        "--data",
        bare_arg,
        "--out-urdf",
        never_arg,
    ];
    refused(&id_bare, &[], "bare.csv: no column 'base_x'", &never);
    let no_feet = strip("force_")
        .lines()
        .map(|l| l.to_string() + "\n")
        .collect::<String>();
    std::fs::write(&bare, no_feet).unwrap();
    refused(
        &id_bare,
        &[],
        "the torques_and_contacts setting needs the feet's contact forces",
        &never,
    );
    refused(
        &id_bare,
        &["--setting", "base-only"],
        "the base_only setting needs the feet's contact forces",
        &never,
    );
    let (ok, err) = physid(&[&id_bare[..2], &[bare_arg, "--setting", "torques-only"]].concat());
    assert!(ok, "contact states are enough for torques-only: {err}");
    let none = dir.path().join("none.csv");
    let blind: String = {
        let rows: Vec<Vec<&str>> = text.lines().map(|l| l.split(',').collect()).collect();
        let keep: Vec<usize> = (0..rows[0].len())
            .filter(|&i| !rows[0][i].starts_with("force_") && !rows[0][i].starts_with("contact_"))
            .collect();
        rows.iter()
            .map(|r| keep.iter().map(|&i| r[i]).collect::<Vec<_>>().join(",") + "\n")
            .collect()
    };
    std::fs::write(&none, blind).unwrap();
    let id_none = [
        "identify-floating",
        "--data",
        none.to_str().unwrap(),
        "--setting",
        "torques-only",
        "--out-urdf",
        never_arg,
    ];
    refused(
        &id_none,
        &[],
        "the torques_only setting needs which feet are down",
        &never,
    );
}

#[test]
fn a_whole_robot_scenario_is_the_whole_robot_command_and_its_bad_keys_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = dir.path().join("quadruped.toml");
    std::fs::write(&scenario, "[whole_robot]\nsizes = [100, 300]\nseeds = 1\n").unwrap();
    let (from_scenario, from_command) = (dir.path().join("a"), dir.path().join("b"));
    let (ok, err) = physid(&[
        "experiment",
        scenario.to_str().unwrap(),
        "--out",
        from_scenario.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let (ok, err) = physid(&[
        "whole-robot",
        "--sizes",
        "100,300",
        "--seeds",
        "1",
        "--out",
        from_command.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let rows = |d: &Path| std::fs::read_to_string(d.join("rows.csv")).unwrap();
    assert_eq!(rows(&from_scenario), rows(&from_command));
    // 2 sizes x 4 sets x 3 data settings, and the header.
    assert_eq!(rows(&from_scenario).lines().count(), 25);
    // Under each setting's table the samples each set needs for least squares' error at the
    // second size (one row: a crossing, a bound at the first size, or not reached) and the
    // spread; at the end the ellipsoid set's saving per setting against the paper's.
    let md = std::fs::read_to_string(from_scenario.join("summary.md")).unwrap();
    assert_eq!(
        md.matches("| least squares at | its error |").count(),
        3,
        "{md}"
    );
    let reach_rows: Vec<&str> = md.lines().filter(|l| l.starts_with("| 300 | ")).collect();
    assert_eq!(
        reach_rows.len(),
        6,
        "3 medians tables and 3 reach tables: {md}"
    );
    assert!(
        (reach_rows.iter()).any(|l| l.contains("x)") || l.contains("not reached")),
        "{md}"
    );
    assert_eq!(
        md.matches("spread (largest median error over smallest): ")
            .count(),
        3
    );
    let paper = md
        .split("## Against the paper")
        .nth(1)
        .expect("the paper's section");
    for setting in ["torques_and_contacts", "torques_only", "base_only"] {
        assert!(paper.contains(&format!("- {setting}: ")), "{paper}");
    }
    let never = dir.path().join("never");
    let experiment = [
        "experiment",
        scenario.to_str().unwrap(),
        "--out",
        never.to_str().unwrap(),
    ];
    for (text, said) in [
        ("[whole_robot]\nbogus = 1\n", "unknown field `bogus`"),
        (
            "[whole_robot]\nsizes = [300, 100]\n",
            "sizes must be positive and ascending",
        ),
        (
            "[whole_robot]\nseeds = 0\n",
            "[whole_robot] seeds = 0: expected 1 to 1000",
        ),
        (
            "[whole_robot]\nsizes = [100]\nseeds = 1\ntrot = [0.9, 2.0]\n",
            "the crouch must be 0 to 0.5 rad",
        ),
        (
            "[whole_robot]\ntrot = [0.1]\n",
            "invalid length 1, expected an array of length 2",
        ),
        (
            "[whole_robot]\nlogged = \"yes\"\n",
            "invalid type: string \"yes\", expected a boolean",
        ),
    ] {
        std::fs::write(&scenario, text).unwrap();
        refused(&experiment, &[], said, &never);
    }
}
