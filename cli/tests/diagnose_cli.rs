//! `physid diagnose` over a file: the report, the JSON, and bad input named.

#[path = "../../tests/common/mod.rs"]
mod common;

use physid::effect::Spring;
use physid::sim::scenario::EffectSpec;

#[test]
fn the_cli_diagnoses_a_file_and_names_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let sc = common::root().join("scenarios/blind.toml");
    let (mut s, m, _) = physid::sim::scenario::load(&sc).unwrap();
    s.simulation.duration = 8.0;
    s.effects = vec![EffectSpec::Spring(Spring {
        stiffness: vec![6.0, 6.0, 6.0],
        rest: vec![0.0, -0.5, 1.2],
    })];
    let rec = physid::sim::run(&m, &s, &mut |_| {}).unwrap();
    let csv = dir.path().join("run.csv");
    physid::io::samples::write_csv(&csv, &rec.processed).unwrap();
    let report = dir.path().join("report");
    let out = common::command()
        .args(["diagnose", "--robot", "cheetah3", "--json", "--data"])
        .arg(&csv)
        .arg("--report")
        .arg(&report)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(j["effects"][0]["kind"], "spring");
    assert_eq!(
        j["samples"][0].as_u64().unwrap() + j["samples"][1].as_u64().unwrap(),
        8000
    );
    for f in [
        "report.md",
        "report.json",
        "where.svg",
        "spectrum.svg",
        "how_far.svg",
    ] {
        assert!(report.join(f).exists(), "{f} missing");
    }
    // The JSON on standard output and in the report name physid's version and their schema.
    assert_eq!(j["schema"], "physid.diagnose/1");
    assert_eq!(j["physid_version"], env!("CARGO_PKG_VERSION"));
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(report.join("report.json")).unwrap())
            .unwrap();
    assert_eq!(file["schema"], "physid.diagnose/1");
    // A robot with another joint count: the error names the file.
    let out = common::command()
        .args(["diagnose", "--robot", "cheetah3", "--no-rotors", "--data"])
        .arg(dir.path().join("missing.csv"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.csv"));
    // A negative description uncertainty is refused by name.
    let out = common::command()
        .args([
            "diagnose",
            "--robot",
            "cheetah3",
            "--description-uncertainty=-0.1",
            "--data",
        ])
        .arg(&csv)
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("--description-uncertainty"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
