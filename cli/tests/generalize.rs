//! `physid generalize`: a robot the diagnosis was never built around, simulated as a real robot,
//! run end to end from a benchmark file; its bad inputs refused by name.

#[path = "../../tests/common/mod.rs"]
mod common;

use std::path::Path;

/// A benchmark file of the low-cost arm alone (runs of `duration` s at 100 Hz), in `dir`.
fn so100_bench(dir: &Path, duration: f64) -> String {
    let urdf = common::root().join("data/so100/so100.urdf");
    let text = format!(
        "duration = {duration:?}\n[[robot]]\nname = \"so100\"\nrobot = \"{}\"\nrate = 100.0\ntorque_noise = 0.01\nencoder_step = 1.5e-3\nheld_out = true\n",
        urdf.display()
    );
    let path = dir.join("bench.toml");
    std::fs::write(&path, text).unwrap();
    path.to_string_lossy().into_owned()
}

#[test]
fn a_held_out_robot_is_run_scored_and_reported_apart_the_same_on_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let bench = so100_bench(dir.path(), 10.0);
    let mut tables = vec![];
    for threads in ["1", "2"] {
        let out = dir.path().join(format!("out{threads}"));
        let keep = dir.path().join(format!("keep{threads}"));
        let (code, stdout, stderr) = common::physid(&[
            "generalize",
            "--robots",
            &bench,
            "--cases",
            "3",
            "--threads",
            threads,
            "--out",
            out.to_str().unwrap(),
            "--keep-cases",
            keep.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{stderr}");
        let scores: serde_json::Value = serde_json::from_str(&stdout).unwrap();
        assert_eq!(scores["schema"], "physid.generalize_scores/1");
        let robot = &scores["robots"][0];
        assert_eq!(
            (robot["robot"].as_str(), robot["held_out"].as_bool()),
            (Some("so100"), Some(true))
        );
        // Cases 0, 1 unchanged, 2 a payload: all three held out, none tuning.
        assert_eq!(scores["held_out"]["cases"], 3);
        assert_eq!(scores["held_out"]["unchanged"], 2);
        assert_eq!(scores["held_out"]["payload"], 1);
        assert_eq!(scores["tuning"]["cases"], 0);
        // Both runs as a robot writes them, and each case's files.
        for f in [
            "so100_motion_a.csv",
            "so100_motion_b.csv",
            "case2/robot.urdf",
            "case2/injected.json",
        ] {
            assert!(keep.join("so100/seed1").join(f).is_file(), "{f}");
        }
        let readme = std::fs::read_to_string(out.join("README.md")).unwrap();
        assert!(readme.contains("so100 (held out)") && readme.contains("all held-out robots"));
        tables.push(std::fs::read_to_string(out.join("cases.csv")).unwrap());
    }
    assert_eq!(
        tables[0], tables[1],
        "the case table depends on the thread count"
    );
}

#[test]
fn the_benchmark_s_bad_inputs_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let bench = so100_bench(dir.path(), 10.0);
    let bad = dir.path().join("bad.toml");
    std::fs::write(
        &bad,
        std::fs::read_to_string(&bench)
            .unwrap()
            .replace("rate = 100.0", "rate = 1.0"),
    )
    .unwrap();
    let unknown = dir.path().join("unknown.toml");
    std::fs::write(
        &unknown,
        std::fs::read_to_string(&bench).unwrap() + "colour = 3\n",
    )
    .unwrap();
    let (bad, unknown) = (bad.to_str().unwrap(), unknown.to_str().unwrap());
    let missing = dir.path().join("none.toml");
    let cases: [(&[&str], &[&str]); 6] = [
        (
            &["generalize", "--robots", bad],
            &["bad.toml", "robot[0].rate"],
        ),
        (
            &["generalize", "--robots", unknown],
            &["unknown.toml", "colour"],
        ),
        (
            &["generalize", "--robots", missing.to_str().unwrap()],
            &["none.toml"],
        ),
        (
            &["generalize", "--robots", &bench, "--cases", "0"],
            &["cases"],
        ),
        (
            &["generalize", "--robots", &bench, "--cases", "-1"],
            &["cases"],
        ),
        (
            &[
                "generalize",
                "--robots",
                &bench,
                "--description-uncertainty",
                "-1",
            ],
            &["--description-uncertainty"],
        ),
    ];
    for (args, words) in cases {
        let (code, _, err) = common::physid(args);
        assert!(
            code == 2 && words.iter().all(|w| err.contains(w)),
            "{args:?}: {err}"
        );
    }
    // The result folder is the benchmark file's own: refused before any work.
    let (code, _, err) = common::physid(&[
        "generalize",
        "--robots",
        &bench,
        "--cases",
        "1",
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert!(code == 2 && err.contains("bench.toml"), "{err}");
}

#[test]
fn no_payload_the_description_test_claims_leaves_its_body_without_mass() {
    // The benchmark's held-out SO-100, 30 s runs, seed 1, case 2: a 0.113 kg payload on the
    // wrist. The description test once also claimed −0.025 kg on the gripper (which weighs
    // less), "revealed by the description".
    let dir = tempfile::tempdir().unwrap();
    let bench = so100_bench(dir.path(), 30.0);
    let (out, keep) = (dir.path().join("out"), dir.path().join("keep"));
    let p = |p: &Path| p.to_str().unwrap().to_string();
    let (code, _, stderr) = common::physid(&[
        "generalize",
        "--robots",
        &bench,
        "--cases",
        "3",
        "--seeds",
        "1",
        "--out",
        &p(&out),
        "--keep-cases",
        &p(&keep),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let case = keep.join("so100/seed1/case2");
    let report = dir.path().join("report");
    let (code, _, stderr) = common::physid(&[
        "diagnose",
        "--robot",
        &p(&case.join("robot.urdf")),
        "--data",
        &p(&case.join("data.csv")),
        "--description-uncertainty",
        "0.05",
        "--report",
        &p(&report),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let injected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(case.join("injected.json")).unwrap())
            .unwrap();
    let true_mass = injected["injection"]["magnitudes"][0].as_f64().unwrap();
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(report.join("report.json")).unwrap())
            .unwrap();
    let described = physid::io::load_robot(case.join("robot.urdf").to_str().unwrap()).unwrap();
    let mass_of = |joint: &str| {
        let b = described.bodies().iter().find(|b| b.joint_name == joint);
        b.expect("a payload's joint is the description's")
            .inertia
            .mass()
    };
    let payloads: Vec<(String, f64)> = (r["effects"].as_array().unwrap().iter())
        .filter(|e| e["kind"] == "payload")
        .map(|e| {
            let m = &e["magnitudes"][0];
            (
                m["joint"].as_str().unwrap().to_string(),
                m["value"].as_f64().unwrap(),
            )
        })
        .collect();
    for (joint, dm) in &payloads {
        assert!(
            mass_of(joint) + dm > 0.0,
            "{dm} kg on {joint}: {payloads:?}"
        );
    }
    // The true payload is still named, on the wrist, within 10 % of its mass.
    assert!(
        (payloads.iter()).any(|(j, m)| j == "wrist_flex" && (m / true_mass - 1.0).abs() < 0.1),
        "{payloads:?} against {true_mass} kg on the wrist"
    );
}
