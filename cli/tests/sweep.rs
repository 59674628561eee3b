//! `physid sweep`: sharded and resumed runs give exactly the single run's table; bad grid values
//! fail before any cell runs, naming the key.

#[path = "../../tests/common/mod.rs"]
mod common;

use std::path::Path;

/// `physid ARGS`: exit code and standard output and error together.
fn physid(args: &[&str]) -> (i32, String) {
    let (code, stdout, stderr) = common::physid(args);
    (code, stdout + &stderr)
}

fn sweep_file(dir: &Path, grid: &str) -> String {
    let base = common::root().join("scenarios/sample_size.toml");
    let p = dir.join("sweep.toml");
    std::fs::write(
        &p,
        format!("scenario = \"{}\"\n[grid]\n{grid}\n[experiment]\nseeds = 2\nsizes = [30, 300]\nvalidation = 300\nconstraints = [\"none\", \"ellipsoid\"]\n", base.display()),
    )
    .unwrap();
    p.to_str().unwrap().to_string()
}

#[test]
fn sharded_and_resumed_sweeps_equal_a_single_run() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = sweep_file(
        dir.path(),
        "\"sensors.torque_noise\" = [0.3, 2.0]\n\"experiment.prior_weight\" = [1e-6, 1e-3]",
    );
    let (one, sharded) = (dir.path().join("one"), dir.path().join("sharded"));
    let (code, out) = physid(&[
        "sweep",
        &sweep,
        "--out",
        one.to_str().unwrap(),
        "--threads",
        "2",
    ]);
    assert_eq!(code, 0, "{out}");
    for k in 0..3 {
        let (code, out) = physid(&[
            "sweep",
            &sweep,
            "--out",
            sharded.to_str().unwrap(),
            "--shard",
            &format!("{k}/3"),
            "--threads",
            "1",
        ]);
        assert_eq!(code, 0, "{out}");
    }
    // Every cell exists after the shards; the merging run must run nothing new.
    let (code, out) = physid(&["sweep", &sweep, "--out", sharded.to_str().unwrap()]);
    assert!(
        code == 0 && out.contains("8 already done, 0 to run"),
        "{out}"
    );
    let svg = std::fs::read_to_string(one.join("summary.svg")).unwrap();
    assert!(svg.contains("sensors.torque_noise=2") && svg.trim_end().ends_with("</svg>"));
    let read = |d: &Path| std::fs::read_to_string(d.join("rows.csv")).unwrap();
    let strip = |csv: String| -> Vec<String> {
        // Drop the wall-clock solve time (last column).
        csv.lines()
            .map(|l| {
                l.rsplit_once(',')
                    .map_or(l.to_string(), |(a, _)| a.to_string())
            })
            .collect()
    };
    let (a, b) = (strip(read(&one)), strip(read(&sharded)));
    assert_eq!(a.len(), 1 + 2 * 2 * 2 * 2 * 2);
    assert_eq!(a, b);
    assert!(
        a[0].starts_with("experiment.prior_weight,sensors.torque_noise,seed,n_s,constraints"),
        "{}",
        a[0]
    );
}

#[test]
fn bad_grid_values_fail_before_running_and_name_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let sweep = sweep_file(dir.path(), "\"sensors.torque_noise\" = [0.3, -1.0]");
    let (code, out) = physid(&[
        "sweep",
        &sweep,
        "--out",
        dir.path().join("o").to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert!(
        out.contains("sensors.torque_noise") && out.contains("-1"),
        "{out}"
    );
    assert!(
        !dir.path().join("o/cells").exists()
            || std::fs::read_dir(dir.path().join("o/cells"))
                .unwrap()
                .count()
                == 0
    );
    let sweep = sweep_file(dir.path(), "\"sensors.torque_nois\" = [0.3]");
    let (code, out) = physid(&[
        "sweep",
        &sweep,
        "--out",
        dir.path().join("p").to_str().unwrap(),
    ]);
    assert!(code == 2 && out.contains("torque_nois"), "{out}");
    // The experiment settings are the sweep's own: a grid over them would be overridden while
    // the rows carried the grid's value.
    let sweep = sweep_file(dir.path(), "\"experiment.seeds\" = [1, 3]");
    let (code, out) = physid(&[
        "sweep",
        &sweep,
        "--out",
        dir.path().join("q").to_str().unwrap(),
    ]);
    assert!(
        code == 2 && out.contains("experiment.seeds") && out.contains("[experiment]"),
        "{out}"
    );
}

#[test]
fn a_grid_over_experiment_keys_sets_each_point_s_experiment() {
    // Without the grid the sizes are [30, 300]; each grid point runs its own sizes.
    let dir = tempfile::tempdir().unwrap();
    let sweep = sweep_file(dir.path(), "\"experiment.sizes\" = [[30], [50]]");
    let out_dir = dir.path().join("out");
    let (code, log) = physid(&["sweep", &sweep, "--out", out_dir.to_str().unwrap()]);
    assert_eq!(code, 0, "{log}");
    let df = physid::experiment::tables::read_parquet(&out_dir.join("rows.parquet")).unwrap();
    let n_s = physid::experiment::tables::floats(&df, "n_s").unwrap();
    let sizes: std::collections::BTreeSet<u64> = n_s.iter().map(|&n| n as u64).collect();
    assert_eq!(sizes.into_iter().collect::<Vec<_>>(), vec![30, 50]);
    // 2 points x 2 seeds x 2 sets x 1 size.
    assert_eq!(df.height(), 8);
    // A value the experiment refuses is named with its point before anything runs.
    let sweep = sweep_file(dir.path(), "\"experiment.prior_weight\" = [1e-6, -1.0]");
    let (code, log) = physid(&[
        "sweep",
        &sweep,
        "--out",
        dir.path().join("p").to_str().unwrap(),
    ]);
    assert!(
        code == 2 && log.contains("prior_weight") && log.contains("-1"),
        "{log}"
    );
    assert!(!dir.path().join("p/cells").exists(), "{log}");
}

#[test]
fn a_changed_configuration_never_reuses_a_cell() {
    // The same --out, sizes changed from [30, 300] to [50]: the new cells are computed, the
    // old ones are reported as another configuration's and left out of the merged table.
    let dir = tempfile::tempdir().unwrap();
    let sweep = sweep_file(dir.path(), "\"sensors.torque_noise\" = [0.3]");
    let out_dir = dir.path().join("out");
    let out = out_dir.to_str().unwrap();
    let (code, log) = physid(&["sweep", &sweep, "--out", out, "--threads", "1"]);
    assert!(
        code == 0 && log.contains("2 cells, 0 already done, 2 to run"),
        "{log}"
    );
    let text = std::fs::read_to_string(&sweep)
        .unwrap()
        .replace("sizes = [30, 300]", "sizes = [50]");
    std::fs::write(&sweep, text).unwrap();
    let (code, log) = physid(&["sweep", &sweep, "--out", out, "--threads", "1"]);
    assert!(
        code == 0
            && log.contains("2 cells, 0 already done, 2 to run")
            && log.contains("2 cell files")
            && log.contains("another configuration"),
        "{log}"
    );
    let rows = std::fs::read_to_string(out_dir.join("rows.csv")).unwrap();
    let header: Vec<&str> = rows.lines().next().unwrap().split(',').collect();
    let n_s = header.iter().position(|h| *h == "n_s").unwrap();
    let sizes: std::collections::BTreeSet<&str> = rows
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(n_s).unwrap())
        .collect();
    assert_eq!(sizes.into_iter().collect::<Vec<_>>(), vec!["50"], "{rows}");
    // Not on a terminal, progress comes as plain lines (here the last one).
    assert!(log.contains("cells: 2 of 2 done"), "{log}");
    // Run again unchanged: everything is reused.
    let (code, log) = physid(&["sweep", &sweep, "--out", out, "--threads", "1"]);
    assert!(
        code == 0 && log.contains("2 already done, 0 to run"),
        "{log}"
    );
}

#[test]
fn blind_progress_is_plain_text_with_counts() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("b");
    let (code, log) = physid(&["blind", "--cases", "2", "--out", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{log}");
    // One line per case with "k of N", the category and verdict as in the JSON, no Rust
    // debug text.
    assert!(
        log.contains("(1 of 2 done") && log.contains("(2 of 2 done"),
        "{log}"
    );
    assert!(
        log.contains(": clean; injected nothing; found nothing; verdict "),
        "{log}"
    );
    assert!(!log.contains("Some(") && !log.contains("None"), "{log}");
    // Parquet holds lists as lists and flags as booleans.
    let df = physid::experiment::tables::read_parquet(&out.join("cases.parquet")).unwrap();
    let dtype = |c: &str| format!("{:?}", df.column(c).unwrap().dtype());
    assert!(
        dtype("found").starts_with("List") && dtype("injected").starts_with("List"),
        "{}",
        dtype("found")
    );
    assert_eq!(dtype("top1"), "Boolean");
    // The summary plot is drawn.
    let svg = std::fs::read_to_string(out.join("blind.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("top-1") && svg.trim_end().ends_with("</svg>"));
}

#[test]
fn a_blind_case_can_be_kept_and_rediagnosed_by_hand() {
    // `--only 4 --keep-cases DIR`: case 4 alone (the first single effect of a cycle, a torque
    // offset), its files kept where the user can run the diagnosis on them again, which then
    // finds the same first effect.
    let dir = tempfile::tempdir().unwrap();
    let keep = dir.path().join("cases");
    let (code, log) = physid(&[
        "blind",
        "--only",
        "4",
        "--keep-cases",
        keep.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{log}");
    assert!(log.contains("case 4 (1 of 1 done"), "{log}");
    assert!(
        log.contains("injected torque_offset; found torque_offset"),
        "{log}"
    );
    let case = keep.join("case4");
    let (code, text) = physid(&[
        "diagnose",
        "--robot",
        case.join("robot.urdf").to_str().unwrap(),
        "--data",
        case.join("data.csv").to_str().unwrap(),
        "--description-uncertainty",
        "0.1",
    ]);
    assert_eq!(code, 0, "{text}");
    assert!(text.contains("Step 1: torque_offset (CV RMS"), "{text}");
    // A case beyond --cases is named.
    let (code, log) = physid(&["blind", "--cases", "21", "--only", "21"]);
    assert!(
        code != 0 && log.contains("--only 21: the cases are numbered 0 to 20"),
        "{log}"
    );
}

#[test]
fn an_axis_the_experiment_ignores_is_refused_before_anything_is_written() {
    // Before: a grid over experiment.min_size with `sizes` given ran, and both values gave the
    // same rows (sizes replace the log grid); min_size above max_size was accepted too.
    let dir = tempfile::tempdir().unwrap();
    let base = common::root().join("scenarios/sample_size.toml");
    let cases = [
        ("\"experiment.min_size\" = [10, 60]", "sizes = [30, 300]", "experiment.sizes: given with min_size/max_size/points (60, 10000, 12), which it replaces"),
        ("\"sensors.torque_noise\" = [0.3]", "min_size = 500\nmax_size = 100", "experiment.min_size: 500 is above max_size 100"),
    ];
    for (k, (grid, experiment, said)) in cases.iter().enumerate() {
        let sweep = dir.path().join(format!("s{k}.toml"));
        std::fs::write(
            &sweep,
            format!("scenario = \"{}\"\n[grid]\n{grid}\n[experiment]\nseeds = 2\n{experiment}\nvalidation = 300\nconstraints = [\"none\"]\n", base.display()),
        )
        .unwrap();
        let out = dir.path().join(format!("out{k}"));
        let (code, _, err) = common::physid(&[
            "sweep",
            sweep.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(code == 2 && err.contains(said), "{err}");
        assert!(!out.exists());
    }
}
