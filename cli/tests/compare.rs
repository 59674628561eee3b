//! `physid compare`: a rerun of the same configuration passes; a degraded run (ten times the
//! torque noise) fails with exit 1, a readable Markdown table and a JUnit failure; constraint
//! variants within one run; errors exit 2.

#[path = "../../tests/common/mod.rs"]
mod common;

use common::physid;
use std::path::{Path, PathBuf};

/// The sample-size scenario cut to 8 seeds and sizes 30..300, with `torque_noise` (N m), run
/// into `dir/name`.
fn experiment(dir: &Path, name: &str, torque_noise: f64) -> PathBuf {
    let base = common::root().join("scenarios/sample_size.toml");
    let text = std::fs::read_to_string(base).unwrap();
    let text = text
        .replace(
            "torque_noise = 1.0",
            &format!("torque_noise = {torque_noise}"),
        )
        .replace("seeds = 20 ", "seeds = 8 ")
        .replace("min_size = 10 ", "min_size = 30 ")
        .replace("max_size = 10000", "max_size = 300")
        .replace("points = 12", "points = 2")
        .replace("validation = 10000", "validation = 1000");
    assert!(text.contains("seeds = 8 ") && text.contains("points = 2"));
    let scenario = dir.join(format!("{name}.toml"));
    std::fs::write(&scenario, text).unwrap();
    run_experiment(&scenario, &dir.join(name))
}

/// `physid experiment SCENARIO --out OUT`, which must succeed; returns `out`.
fn run_experiment(scenario: &Path, out: &Path) -> PathBuf {
    let (code, _, err) = physid(&[
        "experiment",
        scenario.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    out.to_path_buf()
}

#[test]
fn compare_passes_a_rerun_and_fails_a_degraded_run() {
    let dir = tempfile::tempdir().unwrap();
    let base = experiment(dir.path(), "base", 1.0);
    let rerun = experiment(dir.path(), "rerun", 1.0);
    let noisy = experiment(dir.path(), "noisy", 10.0);
    let s = |p: &Path| p.to_str().unwrap().to_string();
    // The Parquet tables carry their writer and each column's unit.
    let kv = physid::experiment::tables::parquet_key_values(&base.join("rows.parquet")).unwrap();
    let get = |k: &str| kv.iter().find(|(key, _)| key == k).map(|(_, v)| v.clone());
    assert_eq!(
        get("physid.writer"),
        Some(format!("physid {}", env!("CARGO_PKG_VERSION")))
    );
    let units: serde_json::Value = serde_json::from_str(&get("physid.units").unwrap()).unwrap();
    assert_eq!(units["val_rms"], "N m");
    assert_eq!(units["com_err_m"], "m");
    assert_eq!(units["n_s"], "samples");
    let prov: serde_json::Value = serde_json::from_str(&get("physid.provenance").unwrap()).unwrap();
    assert_eq!(prov["seeds"].as_array().unwrap().len(), 8);
    assert!(prov["scenario_file"]
        .as_str()
        .unwrap()
        .ends_with("base.toml"));
    let (code, out, err) = physid(&["compare", &s(&rerun), "--baseline", &s(&base)]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("**PASS**: 0 of 8 groups regressed"), "{out}");
    let md = dir.path().join("cmp.md");
    let junit = dir.path().join("cmp.xml");
    let (code, out, err) = physid(&[
        "compare",
        &s(&noisy),
        "--baseline",
        &s(&base),
        "--markdown",
        &s(&md),
        "--junit",
        &s(&junit),
    ]);
    assert_eq!(code, 1, "{out}{err}");
    assert!(
        err.contains("failed:") && err.contains("groups regressed"),
        "{err}"
    );
    let text = std::fs::read_to_string(&md).unwrap();
    assert_eq!(text, out);
    assert!(
        text.contains("**FAIL**") && text.contains("| **regression** |"),
        "{text}"
    );
    // Every table row has the header's number of cells (unescaped pipes).
    let rows: Vec<&str> = text.lines().filter(|l| l.starts_with('|')).collect();
    let cells = |l: &str| l.replace("\\|", "").matches('|').count();
    assert_eq!(rows.len(), 2 + 8, "{text}");
    assert!(rows.iter().all(|l| cells(l) == cells(rows[0])), "{text}");
    let xml = std::fs::read_to_string(&junit).unwrap();
    assert!(xml.contains("<testsuite name=\"physid compare\" tests=\"8\""));
    assert!(xml.matches("<failure").count() >= 1, "{xml}");
    // Variants within one run: consistent is no worse than least squares at these sizes; the
    // converse regresses.
    let (code, out, err) = physid(&["compare", &s(&base), "--variant", "consistent<=none"]);
    assert_eq!(code, 0, "{out}{err}");
    let (code, out, _) = physid(&["compare", &s(&base), "--variant", "none<=consistent"]);
    assert_eq!(code, 1, "{out}");
    // Errors exit 2, naming what is wrong.
    let (code, _, err) = physid(&[
        "compare",
        &s(&base),
        "--baseline",
        &s(&base),
        "--metric",
        "nope",
    ]);
    assert!(code == 2 && err.contains("no column 'nope'"), "{err}");
    let (code, _, err) = physid(&["compare", &s(&base), "--variant", "consistent"]);
    assert!(code == 2 && err.contains("A<=B"), "{err}");
    let (code, _, err) = physid(&[
        "compare",
        &s(&base),
        "--baseline",
        &s(&base),
        "--alpha",
        "2",
    ]);
    assert!(code == 2 && err.contains("--alpha"), "{err}");
}

/// A copy of the committed CI baseline's rows (CSV only) in `dir/name`, each row passed
/// through `edit` (None: dropped).
fn baseline_copy(dir: &Path, name: &str, edit: &dyn Fn(&str) -> Option<String>) -> PathBuf {
    let src = common::root().join("results/ci_baseline/rows.csv");
    let text = std::fs::read_to_string(src).unwrap();
    let mut lines = text.lines();
    let mut out = vec![lines.next().unwrap().to_string()];
    out.extend(lines.filter_map(edit));
    let d = dir.join(name);
    std::fs::create_dir_all(&d).unwrap();
    std::fs::write(d.join("rows.csv"), out.join("\n") + "\n").unwrap();
    d
}

/// The row with its seed replaced by `f(seed)`.
fn with_seed(line: &str, f: &dyn Fn(i64) -> i64) -> String {
    let (seed, rest) = line.split_once(',').unwrap();
    format!("{},{rest}", f(seed.parse().unwrap()))
}

#[test]
fn compare_refuses_what_it_cannot_judge() {
    let dir = tempfile::tempdir().unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let same = baseline_copy(dir.path(), "same", &|l| Some(l.to_string()));
    let base = baseline_copy(dir.path(), "base", &|l| Some(l.to_string()));
    let (code, out, err) = physid(&["compare", &s(&same), "--baseline", &s(&base)]);
    assert_eq!(code, 0, "{out}{err}");
    // Before: a NaN metric made its group "too few pairs" and the run passed.
    let nan = baseline_copy(dir.path(), "nan", &|l| {
        Some(if l.starts_with("3,311,consistent,") {
            let mut cells: Vec<&str> = l.split(',').collect();
            cells[6] = "NaN";
            cells.join(",")
        } else {
            l.to_string()
        })
    });
    let (code, _, err) = physid(&["compare", &s(&nan), "--baseline", &s(&base)]);
    assert!(
        code == 2
            && err.contains("val_rms = NaN")
            && err.contains("seed 3")
            && err.contains("candidate"),
        "{code} {err}"
    );
    // Before: results that pair nothing (here disjoint seeds) passed with exit 0.
    let shifted = baseline_copy(dir.path(), "shifted", &|l| Some(with_seed(l, &|s| s + 100)));
    let (code, _, err) = physid(&["compare", &s(&shifted), "--baseline", &s(&base)]);
    assert!(code == 2 && err.contains("no group pairs"), "{code} {err}");
    // Before: six seeds at alpha 0.01 could never fail (smallest p = 1/64), yet passed. Five
    // times the metric on every row is not a pass now: it cannot be judged (exit 2), unless
    // allowed, and a looser alpha lets it fail.
    let six = |l: &str| {
        (l.split(',').next().unwrap().parse::<i64>().unwrap() <= 6).then(|| l.to_string())
    };
    let base6 = baseline_copy(dir.path(), "base6", &six);
    let worse6 = baseline_copy(dir.path(), "worse6", &|l| {
        six(l).map(|l| {
            let mut cells: Vec<String> = l.split(',').map(String::from).collect();
            let v: f64 = cells[6].parse().unwrap();
            cells[6] = (5.0 * v).to_string();
            cells.join(",")
        })
    });
    let (code, out, err) = physid(&["compare", &s(&worse6), "--baseline", &s(&base6)]);
    assert!(
        code == 2 && err.contains("cannot reach alpha = 0.01"),
        "{code} {err}"
    );
    assert!(out.contains("cannot reach alpha"), "{out}");
    let (code, _, err) = physid(&[
        "compare",
        &s(&worse6),
        "--baseline",
        &s(&base6),
        "--allow-too-few",
    ]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = physid(&[
        "compare",
        &s(&worse6),
        "--baseline",
        &s(&base6),
        "--alpha",
        "0.05",
    ]);
    assert_eq!(code, 1, "{err}");
    // Before: --markdown/--junit could replace the baseline's own table.
    let before = std::fs::read(base.join("rows.csv")).unwrap();
    for flag in ["--markdown", "--junit"] {
        let target = s(&base.join("rows.csv"));
        let (code, _, err) =
            physid(&["compare", &s(&same), "--baseline", &s(&base), flag, &target]);
        assert!(code == 2 && err.contains("rows.csv"), "{flag}: {err}");
    }
    // Before: $GITHUB_STEP_SUMMARY pointing at the baseline's table appended the report to it.
    let target = s(&base.join("rows.csv"));
    let o = common::command()
        .args(["compare", &s(&same), "--baseline", &s(&base)])
        .env("GITHUB_STEP_SUMMARY", &target)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.code() == Some(2) && err.contains("rows.csv"),
        "{err}"
    );
    assert_eq!(std::fs::read(base.join("rows.csv")).unwrap(), before);
    // Before: a row repeated with another value let the later copy win (pass or 16
    // regressions by row order).
    let twice = baseline_copy(dir.path(), "twice", &|l| {
        Some(if l.starts_with("3,311,consistent,") {
            format!("{l}\n{}", with_seed(l, &|s| s))
        } else {
            l.to_string()
        })
    });
    let (code, _, err) = physid(&["compare", &s(&twice), "--baseline", &s(&base)]);
    assert!(
        code == 2 && err.contains("are both seed 3, n_s 311, consistent"),
        "{code} {err}"
    );
    // Before: a negative metric value dropped its pair ("fewer than 7 seed pairs" with 8);
    // a set compared with itself, an unknown set and --max-n-s 0 all read "no group pairs".
    let negative = baseline_copy(dir.path(), "negative", &|l| {
        Some(if l.starts_with("3,311,consistent,") {
            let mut cells: Vec<String> = l.split(',').map(String::from).collect();
            cells[6] = format!("-{}", cells[6]);
            cells.join(",")
        } else {
            l.to_string()
        })
    });
    let (code, _, err) = physid(&["compare", &s(&negative), "--baseline", &s(&base)]);
    assert!(
        code == 2 && err.contains("seed 3: a comparison needs finite values above 0"),
        "{code} {err}"
    );
    // Before: a word among the metric's numbers dropped its row, and a seed 3.5 paired with
    // seed 3, without a word.
    let word = baseline_copy(dir.path(), "word", &|l| {
        Some(if l.starts_with("3,311,consistent,") {
            let mut cells: Vec<String> = l.split(',').map(String::from).collect();
            cells[6] = "n/a".into();
            cells.join(",")
        } else {
            l.to_string()
        })
    });
    let (code, _, err) = physid(&["compare", &s(&word), "--baseline", &s(&base)]);
    assert!(
        code == 2 && err.contains("column 'val_rms'"),
        "{code} {err}"
    );
    let half = baseline_copy(dir.path(), "half", &|l| {
        Some(if l.starts_with("3,") {
            format!("3.5{}", &l[1..])
        } else {
            l.to_string()
        })
    });
    let (code, _, err) = physid(&["compare", &s(&half), "--baseline", &s(&base)]);
    assert!(
        code == 2 && err.contains("column 'seed' holds 3.5 in data row"),
        "{code} {err}"
    );
    for (args, words) in [
        (
            vec!["--variant", "consistent<=consistent"],
            "compares a set with itself",
        ),
        (
            vec!["--variant", "consistent<=nope"],
            "no rows of the set 'nope' (the rows' sets: consistent, ellipsoid, none, semi)",
        ),
        (
            vec!["--variant", "consistent<=none", "--max-n-s", "0"],
            "--max-n-s must be at least 1 sample, got 0",
        ),
    ] {
        let mut a = vec!["compare".to_string(), s(&base)];
        a.extend(args.iter().map(|x| x.to_string()));
        let refs: Vec<&str> = a.iter().map(String::as_str).collect();
        let (code, _, err) = physid(&refs);
        assert!(code == 2 && err.contains(words), "{args:?}: {code} {err}");
    }
}

#[test]
fn every_cell_of_the_committed_sample_size_experiment_is_solved() {
    // The committed scenario whole (20 seeds, 10 to 10,000 samples, four sets). Below 22
    // samples the leg's 66 parameters outnumber the equations and only the prior holds 28
    // directions: there, under `semi`, Clarabel can stop with a numerical error on the program
    // about the least-squares minimizer (identification's first attempt), and identification
    // then solves it about the origin. Without that fallback one build stopped at its first
    // such cell, every run ("seed 13, n_s = 19, semi: … NumericalError after 16 iterations");
    // another build of the same code never met one (the failure follows rounding), so this
    // guards the fallback but does not reproduce the failure on every build.
    let dir = tempfile::tempdir().unwrap();
    let scenario = common::root().join("scenarios/sample_size.toml");
    let out = run_experiment(&scenario, &dir.path().join("sample_size"));
    let rows = std::fs::read_to_string(out.join("rows.csv")).unwrap();
    let header: Vec<&str> = rows.lines().next().unwrap().split(',').collect();
    let status = header.iter().position(|h| *h == "status").unwrap();
    let statuses: Vec<&str> = rows
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(status).unwrap())
        .collect();
    assert_eq!(statuses.len(), 960);
    assert!(
        statuses.iter().all(|s| *s == "solved" || *s == "direct"),
        "{statuses:?}"
    );
}
