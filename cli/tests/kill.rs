//! `physid experiment` killed at any point leaves either no result or a complete one (the
//! previous run's, or the new run's), never a partial directory or a mix of two runs: the
//! result is built in a hidden staging directory beside the target and renamed into place.

#[path = "../../tests/common/mod.rs"]
mod common;

use std::path::Path;
use std::process::Stdio;
use std::time::Duration;

const FILES: [&str; 8] = [
    "rows.parquet",
    "rows.csv",
    "summary.parquet",
    "summary.csv",
    "summary.md",
    "validation_error.svg",
    "parameter_error.svg",
    "provenance.json",
];

/// `Some(seeds)` when `dir` holds a complete, self-consistent result of `seeds` seeds, `None`
/// when it does not exist; panics on anything else (a partial or mixed result).
fn complete_result(dir: &Path) -> Option<u64> {
    if !dir.exists() {
        return None;
    }
    for f in FILES {
        assert!(dir.join(f).is_file(), "{f} missing from {}", dir.display());
    }
    let prov: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("provenance.json")).unwrap())
            .unwrap();
    let seeds = prov["seeds"].as_array().unwrap().len() as u64;
    let rows = std::fs::read_to_string(dir.join("rows.csv"))
        .unwrap()
        .lines()
        .count()
        - 1;
    let per_seed = 12 * 4; // the scenario's 12 sizes × 4 sets
    assert_eq!(
        rows as u64,
        seeds * per_seed,
        "rows.csv does not match provenance.json"
    );
    let leftovers: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| !FILES.contains(&n.as_str()))
        .collect();
    assert!(
        leftovers.is_empty(),
        "extra files in the result: {leftovers:?}"
    );
    Some(seeds)
}

fn experiment(out: &Path, seeds: &str) -> std::process::Child {
    let scenario = common::root().join("scenarios/sample_size.toml");
    common::command()
        .arg("experiment")
        .arg(scenario)
        .args(["--seeds", seeds, "--threads", "1", "--out"])
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap()
}

#[test]
fn a_killed_experiment_never_leaves_a_partial_or_mixed_result() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("res");
    let mut finished = None;
    let mut kills = 0;
    // Kill times spread over a run (about 0.5–1 s for one seed on one thread).
    for k in 0..24u64 {
        let seeds = if k % 2 == 0 { "1" } else { "2" };
        let mut child = experiment(&out, seeds);
        std::thread::sleep(Duration::from_millis(40 + (k * 137) % 900));
        match child.try_wait().unwrap() {
            Some(status) => {
                assert!(status.success());
                finished = complete_result(&out);
                assert!(finished.is_some());
            }
            None => {
                child.kill().unwrap();
                child.wait().unwrap();
                kills += 1;
                // The previous complete result, a new complete one, or none yet.
                let now = complete_result(&out);
                assert!(now.is_none() == finished.is_none() || now.is_some());
                if now.is_some() {
                    finished = now;
                }
            }
        }
        // Nothing beside the result but hidden staging directories of killed runs.
        for e in std::fs::read_dir(dir.path()).unwrap().flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            assert!(
                name == "res" || name.starts_with(".res.partial-"),
                "left {name}"
            );
        }
    }
    eprintln!("{kills} of 24 runs killed; complete result before the last run: {finished:?}");
    assert!(kills >= 20, "only {kills} runs were killed");
    // The next run clears what the killed ones left and completes.
    let status = experiment(&out, "1").wait().unwrap();
    assert!(status.success());
    assert_eq!(complete_result(&out), Some(1));
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, vec!["res".to_string()]);
}

#[test]
fn a_killed_sweep_leaves_whole_cells_and_never_a_mixed_merge() {
    let dir = tempfile::tempdir().unwrap();
    let root = common::root();
    std::fs::copy(
        root.join("scenarios/sample_size.toml"),
        dir.path().join("sc.toml"),
    )
    .unwrap();
    let sweep = dir.path().join("sweep.toml");
    std::fs::write(
        &sweep,
        "scenario = \"sc.toml\"\n[grid]\n\"sensors.torque_noise\" = [0.3, 1.0, 3.0]\n\
         [experiment]\nseeds = 6\nsizes = [20, 200]\nvalidation = 1000\n\
         constraints = [\"none\", \"consistent\"]\n",
    )
    .unwrap();
    let out = dir.path().join("out");
    let run = || {
        common::command()
            .arg("sweep")
            .arg(&sweep)
            .args(["--threads", "1", "--out"])
            .arg(&out)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap()
    };
    let (mut kills, mut runs, mut merged) = (0, 0, 0);
    // Until 20 kills (at most 60 runs): kill times spread over a whole sweep (about 0.8 s on
    // one thread), results removed every third run so kills land before, between and after cells
    // and during merges.
    for k in 0..60u64 {
        if kills >= 20 {
            break;
        }
        if k % 3 == 0 {
            let _ = std::fs::remove_dir_all(&out);
        }
        runs += 1;
        let mut child = run();
        std::thread::sleep(Duration::from_millis(10 + (k * 137) % 800));
        if child.try_wait().unwrap().is_none() {
            child.kill().unwrap();
            kills += 1;
        }
        child.wait().unwrap();
        // Every visible cell file is a whole table.
        let cells = out.join("cells");
        if let Ok(entries) = std::fs::read_dir(&cells) {
            for e in entries.flatten() {
                let name = e.file_name().to_string_lossy().into_owned();
                if name.starts_with(physid::io::PARTIAL_PREFIX) {
                    continue; // removed by the next run
                }
                assert!(
                    physid::experiment::tables::read_parquet(&e.path()).is_ok(),
                    "{name} is not a whole table"
                );
            }
        }
        // summary.md only with every merged table beside it.
        if out.join("summary.md").exists() {
            merged += 1;
            for f in ["rows.parquet", "rows.csv", "summary.parquet", "summary.csv"] {
                assert!(out.join(f).exists(), "summary.md without {f}");
            }
        }
    }
    eprintln!("{kills} of {runs} sweep runs killed; {merged} times a complete merge was present");
    assert!(kills >= 20, "only {kills} runs were killed");
    // A run to the end merges, and leaves no partial file anywhere.
    assert!(run().wait().unwrap().success());
    assert!(out.join("summary.md").exists());
    for d in [out.clone(), out.join("cells")] {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            assert!(!name.starts_with(physid::io::PARTIAL_PREFIX), "left {name}");
        }
    }
}
