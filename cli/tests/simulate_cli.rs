//! `physid simulate` on a run that diverges: exit code 2, the time and joint named, and no
//! output file (not even a partial one).

#[path = "../../tests/common/mod.rs"]
mod common;

#[test]
fn a_diverging_simulation_names_time_and_joint_and_writes_nothing() {
    let text = common::diverging_shell_scenario();
    let dir = tempfile::tempdir().unwrap();
    // The leg written out without its effort limits, under the diverging [simulation].
    let leg = std::fs::read_to_string(common::root().join("scenarios/cheetah3_leg.toml")).unwrap();
    let robot: String = leg
        .lines()
        .filter(|l| !l.starts_with("limits"))
        .map(|l| format!("{l}\n"))
        .collect();
    let rest = text.split_once("[simulation]").unwrap().1;
    let scenario = dir.path().join("unstable_cli.toml");
    std::fs::write(&scenario, format!("{robot}\n[simulation]{rest}")).unwrap();
    let out = dir.path().join("never.mcap");
    let (code, _, stderr) = common::physid(&[
        "simulate",
        scenario.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--duration",
        "2",
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("diverged at t =") && stderr.contains("joint '"),
        "{stderr}"
    );
    assert!(!out.exists(), "a failed run left {}", out.display());
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "stray temporary files"
    );
}
