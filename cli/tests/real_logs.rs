//! Real KUKA LWR4+ logs reshaped as robots write them (issue 25): no accelerations, a 0.5 s
//! dropout, 2 % of the samples dropped at random, time stamps jittered by ±1 ms (a fifth of the
//! period), columns named by joint in another order, and a gripper joint the robot does not
//! have. `identify` must give the held-out error of the clean files, and say what it did.

#[path = "../../tests/common/mod.rs"]
mod common;

use common::{physid, root};
use rand::{Rng, SeedableRng};
use std::path::{Path, PathBuf};

/// Run `r` of the KUKA logs rewritten as a robot would log it (see the module docs); `gap`
/// removes 0.5 s from t = 10 s.
fn reshaped(dir: &Path, r: usize, gap: bool) -> PathBuf {
    let src = root().join(format!("data/kuka_lwr4/measurements_{r}.csv"));
    let mut rd = csv::Reader::from_path(&src).unwrap();
    let header: Vec<String> = rd.headers().unwrap().iter().map(String::from).collect();
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let order = [3usize, 0, 6, 1, 5, 2, 4];
    let mut out_header = vec!["t".to_string()];
    for g in ["q", "dq", "tau"] {
        out_header.extend(order.iter().map(|j| format!("{g}_lwr_{j}_joint")));
        out_header.push(format!("{g}_gripper"));
    }
    let path = dir.join(format!("robot_{r}.csv"));
    let mut w = csv::Writer::from_path(&path).unwrap();
    w.write_record(&out_header).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(r as u64);
    for rec in rd.records() {
        let rec = rec.unwrap();
        let v = |name: &str| rec[col(name)].to_string();
        let t: f64 = v("t").parse().unwrap();
        let dropped = rng.random_bool(0.02);
        let jitter = rng.random_range(-1e-3..1e-3);
        if dropped || (gap && (10.0..10.5).contains(&t)) {
            continue;
        }
        let mut row = vec![format!("{}", t + jitter)];
        for (g, still) in [("q", "0.02"), ("dq", "0"), ("tau", "0")] {
            row.extend(order.iter().map(|j| v(&format!("{g}{}", j + 1))));
            row.push(still.to_string());
        }
        w.write_record(&row).unwrap();
    }
    w.flush().unwrap();
    path
}

fn identify_json(train: &Path, validate: &Path, extra: &[&str]) -> (serde_json::Value, String) {
    let urdf = root().join("data/kuka_lwr4/kuka_lwr4.urdf");
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let mut args = vec![
        "identify".to_string(),
        "--data".into(),
        s(train),
        "--validate-data".into(),
        s(validate),
        "--robot".into(),
        s(&urdf),
        "--constraints".into(),
        "consistent".into(),
        "--friction".into(),
        "viscous,coulomb,offset".into(),
        "--json".into(),
    ];
    args.extend(extra.iter().map(|a| a.to_string()));
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let (code, out, err) = physid(&refs);
    assert_eq!(code, 0, "{err}");
    (serde_json::from_str(&out).unwrap(), err)
}

#[test]
fn kuka_logs_as_a_robot_writes_them_identify_like_the_clean_files() {
    let dir = tempfile::tempdir().unwrap();
    let k = root().join("data/kuka_lwr4");
    let (clean, _) = identify_json(
        &k.join("measurements_1.csv"),
        &k.join("measurements_3.csv"),
        &[],
    );
    let (train, val) = (
        reshaped(dir.path(), 1, true),
        reshaped(dir.path(), 3, false),
    );
    let (rough, err) = identify_json(&train, &val, &[]);
    let rms = |v: &serde_json::Value| v["validation"]["rms_overall"].as_f64().unwrap();
    let (a, b) = (rms(&clean), rms(&rough));
    eprintln!("held-out RMS: clean {a:.4}, as a robot writes them {b:.4}");
    assert!((b / a - 1.0).abs() < 0.02, "clean {a}, reshaped {b}");
    // What the pipeline did, counted: the dropout split the run, drops bridged, the stamps'
    // scatter read as a clock's, q̈ derived and the ends trimmed, the gripper left out.
    let p = &rough["data_pipeline"][0]["pipeline"];
    let gaps: Vec<f64> = p["gaps"]
        .as_array()
        .unwrap()
        .iter()
        .map(|g| g["seconds"].as_f64().unwrap())
        .collect();
    assert!(gaps.iter().any(|g| (g - 0.5).abs() < 0.02), "{gaps:?}");
    assert!(p["missing_bridged"].as_u64().unwrap() > 50, "{p}");
    assert_eq!(p["time_base"], "clock_slots", "{p}");
    assert!(p["derived_qdd"].as_bool().unwrap() && !p["derived_qd"].as_bool().unwrap());
    let (read, kept) = (
        p["samples_read"].as_u64().unwrap(),
        p["samples_kept"].as_u64().unwrap(),
    );
    let counted = kept
        + p["trimmed"].as_u64().unwrap()
        + p["dropped_short"].as_u64().unwrap()
        + p["duplicates"].as_u64().unwrap();
    assert_eq!(counted, read, "{p}");
    assert!(err.contains("left out: gripper"), "{err}");
    assert!(
        err.contains("split into") && err.contains("bridged"),
        "{err}"
    );
}

#[test]
fn a_locked_joint_is_not_fitted_and_lock_names_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let (train, val) = (
        reshaped(dir.path(), 1, false),
        reshaped(dir.path(), 3, false),
    );
    let (v, _) = identify_json(&train, &val, &["--lock", "lwr_6_joint"]);
    assert_eq!(v["locked_joints"], serde_json::json!(["lwr_6_joint"]));
    assert!(
        v["validation"]["rms"][6].is_null(),
        "{}",
        v["validation"]["rms"]
    );
    assert!(v["validation"]["rms"][5].as_f64().unwrap() > 0.0);
    // `--only` one joint: every other joint locked.
    let (v, _) = identify_json(&train, &val, &["--only", "lwr_1_joint"]);
    assert_eq!(v["locked_joints"].as_array().unwrap().len(), 6);
    // Unknown names are refused, naming the robot's joints.
    let urdf = root().join("data/kuka_lwr4/kuka_lwr4.urdf");
    for flag in ["--lock", "--only"] {
        let (code, _, err) = physid(&[
            "identify",
            "--data",
            train.to_str().unwrap(),
            "--robot",
            urdf.to_str().unwrap(),
            flag,
            "gripper",
        ]);
        assert_eq!(code, 2, "{err}");
        assert!(
            err.contains(&format!("{flag}: the robot has no joint 'gripper'"))
                && err.contains("lwr_0_joint"),
            "{err}"
        );
    }
}

/// Run `r` of the KUKA logs as `t, q, τ` (no velocities or accelerations), its first `seconds`
/// only when given: the semi-real benchmark's writer (`semireal::logged_csv`).
fn positions_and_torques(dir: &Path, r: usize, seconds: Option<f64>) -> PathBuf {
    let k = root().join("data/kuka_lwr4");
    let model = physid::io::load_robot(k.join("kuka_lwr4.urdf").to_str().unwrap()).unwrap();
    let src = k.join(format!("measurements_{r}.csv"));
    let (mut logged, _, _) = physid::io::load_logged(&src, &model, &Default::default()).unwrap();
    if let Some(s) = seconds {
        let keep = logged
            .t
            .iter()
            .take_while(|t| **t - logged.t[0] < s)
            .count();
        let n = logged.dof();
        logged.t.truncate(keep);
        logged.q.truncate(keep * n);
        logged.tau.truncate(keep * n);
    }
    let path = dir.join(format!("run{r}_{}.csv", seconds.map_or(0.0, |s| s)));
    std::fs::write(&path, physid::bench::semireal::logged_csv(&logged)).unwrap();
    path
}

/// The derived signals' cutoff of each file read (Hz), and the stderr.
fn cutoffs(train: &Path, validate: Option<&Path>) -> (Vec<f64>, String) {
    let urdf = root().join("data/kuka_lwr4/kuka_lwr4.urdf");
    let mut args = vec!["identify", "--robot", urdf.to_str().unwrap(), "--json"];
    args.extend(["--data", train.to_str().unwrap()]);
    if let Some(v) = validate {
        args.extend(["--validate-data", v.to_str().unwrap()]);
    }
    let (code, out, err) = physid(&args);
    assert_eq!(code, 0, "{err}");
    let json: serde_json::Value = serde_json::from_str(&out).unwrap();
    let files = json["data_pipeline"].as_array().unwrap();
    let cut = files
        .iter()
        .map(|f| f["pipeline"]["cutoff"].as_f64().unwrap())
        .collect();
    (cut, err)
}

#[test]
fn a_short_file_that_widens_the_shared_cutoff_is_warned_about() {
    // Read alone, run 3 (t, q, τ) gets a 2 Hz cutoff; the first 3 s of run 2 read beside it
    // reads its periodogram's resolution (3 Hz) as motion and sets the cutoff of both to
    // 12 Hz. The long file is warned about with its own cutoff; a long file beside it is not.
    let dir = tempfile::tempdir().unwrap();
    let run3 = positions_and_torques(dir.path(), 3, None);
    let (alone, err) = cutoffs(&run3, None);
    assert_eq!(alone, [2.0], "{err}");
    assert!(!err.contains("reads a band edge"), "{err}");
    let short = positions_and_torques(dir.path(), 2, Some(3.0));
    let (both, err) = cutoffs(&run3, Some(&short));
    eprintln!("cutoffs with the short file: {both:?}");
    assert!(both.iter().all(|c| *c > 6.0), "{both:?}");
    let warning = format!(
        "warning: {}: its own motion reads a band edge of",
        run3.display()
    );
    assert!(err.contains(&warning), "{err}");
    assert!(err.contains("give --cutoff 2.0"), "{err}");
    let whole = positions_and_torques(dir.path(), 2, None);
    let (both, err) = cutoffs(&run3, Some(&whole));
    assert!(both.iter().all(|c| *c < 2.5), "{both:?}");
    assert!(!err.contains("reads a band edge"), "{err}");
}

/// The real KUKA run 1 (as distributed) and the URDF, as arguments.
fn run1_and_urdf() -> (String, String) {
    let k = root().join("data/kuka_lwr4");
    let s = |p: PathBuf| p.to_str().unwrap().to_string();
    (s(k.join("measurements_1.csv")), s(k.join("kuka_lwr4.urdf")))
}

#[test]
fn a_mass_far_from_the_description_is_flagged_and_a_description_of_the_same_data_is_not() {
    // The real KUKA run 1 identified from the URDF: the slow run does not determine every
    // link's mass, and the constraints put the wrist link at a fifth of the URDF's 1.6 kg.
    let dir = tempfile::tempdir().unwrap();
    let (run1_s, urdf) = run1_and_urdf();
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let described = dir.path().join("described.urdf");
    let identify = |robot: &str, out: Option<&str>| {
        let mut args = vec!["identify", "--data", &run1_s, "--robot", robot];
        args.extend([
            "--constraints",
            "consistent",
            "--friction",
            "viscous,coulomb",
        ]);
        if let Some(out) = out {
            args.extend(["--out-urdf", out]);
        }
        let (code, _, err) = common::physid(&args);
        assert_eq!(code, 0, "{err}");
        err
    };
    let err = identify(&urdf, Some(&s(&described)));
    let far: Vec<&str> = err
        .lines()
        .filter(|l| l.contains("times the description's"))
        .collect();
    eprintln!("{}", far.join("\n"));
    assert!(
        far.iter()
            .any(|l| l.starts_with("warning: 'lwr_6_link': identified mass ")
                && l.contains("the description's 1.600 kg; the data do not determine it")),
        "{err}"
    );
    // Its own identification as the description: every mass where the description has it.
    let again = identify(&s(&described), None);
    assert!(!again.contains("times the description's"), "{again}");
}

#[test]
fn mass_bounds_hold_every_mass_and_are_not_exported_silently() {
    // Held within 0.5..2 times the URDF's masses, run 1's fit keeps each link there (the free
    // fit puts lwr_6_link at 0.35 of 1.6 kg) and says which masses sit on a bound.
    let dir = tempfile::tempdir().unwrap();
    let (run1, urdf) = run1_and_urdf();
    let (run1, urdf) = (run1.as_str(), urdf.as_str());
    let args = [
        "identify",
        "--data",
        run1,
        "--robot",
        urdf,
        "--constraints",
        "consistent",
        "--mass-bounds",
        "0.5,2",
        "--json",
    ];
    let (code, out, err) = common::physid(&args);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let model = physid::io::load_robot(urdf).unwrap();
    for (body, fitted) in model.bodies().iter().zip(v["bodies"].as_array().unwrap()) {
        assert_eq!(fitted["name"], body.name.as_str());
        let (m, d) = (fitted["pi"][0].as_f64().unwrap(), body.inertia.mass());
        assert!(
            m >= 0.5 * d * (1.0 - 1e-6) && m <= 2.0 * d * (1.0 + 1e-6),
            "{}: {m} of {d}",
            body.name
        );
    }
    assert!(
        err.contains("note: 'lwr_6_link': mass 0.800 kg at the lower bound, 0.5 times the description's 1.600 kg"),
        "{err}"
    );
    assert!(
        !err.contains("times the description's 1.600 kg; the data"),
        "{err}"
    );
    let problem = dir.path().join("p.json");
    let mut bounded_export = args[..args.len() - 1].to_vec();
    bounded_export.extend(["--export-problem", problem.to_str().unwrap()]);
    let (code, _, err) = common::physid(&bounded_export);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("--export-problem writes the problem without mass bounds"),
        "{err}"
    );
    assert!(!problem.exists());
    // The same for a total mass.
    let (run1, urdf) = run1_and_urdf();
    let p = problem.to_str().unwrap();
    let args = [
        "identify",
        "--data",
        &run1,
        "--robot",
        &urdf,
        "--total-mass",
        "13,15",
        "--export-problem",
        p,
    ];
    let (code, _, err) = common::physid(&args);
    assert!(
        code == 2 && err.contains("leave out --mass-bounds and --total-mass"),
        "{err}"
    );
    assert!(!problem.exists());
}

#[test]
fn a_validation_range_the_pipeline_trims_away_is_refused_not_scored_as_zero() {
    // Before: run 1 cut to t, q, τ (q̇, q̈ derived, 316 samples trimmed at each end) with
    // `--validate 0:50` reported "validation 0.0000 N m" from no sample.
    let dir = tempfile::tempdir().unwrap();
    let (_, urdf) = run1_and_urdf();
    let tq = tq_csv(dir.path(), "tq.csv", 1.0);
    let tq = tq.to_str().unwrap();
    let args = |v: &'static str| {
        [
            "identify",
            "--robot",
            &urdf,
            "--data",
            tq,
            "--train",
            "400:3000",
            "--validate",
            v,
        ]
        .map(String::from)
    };
    let (code, _, err) =
        common::physid(&args("0:50").iter().map(String::as_str).collect::<Vec<_>>());
    assert!(
        code == 2
            && err.contains(
                "tq.csv: --validate 0:50: none of these samples is kept by the data pipeline"
            ),
        "{err}"
    );
    let (code, out, err) = common::physid(
        &args("3000:3500")
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
    );
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("validation") && !out.contains("validation 0.0000"),
        "{out}"
    );
}

/// Run 1 cut to `t, q, τ` (as a robot without velocity logging writes it) into `dir/name`, its
/// stamps multiplied by `time_scale` (1e3: milliseconds).
fn tq_csv(dir: &std::path::Path, name: &str, time_scale: f64) -> std::path::PathBuf {
    tq_csv_scaled(dir, name, time_scale, 1.0)
}

/// [`tq_csv`] with the positions multiplied by `angle_scale` too (180/π: degrees).
fn tq_csv_scaled(
    dir: &std::path::Path,
    name: &str,
    time_scale: f64,
    angle_scale: f64,
) -> std::path::PathBuf {
    let (run1, _) = run1_and_urdf();
    let text = std::fs::read_to_string(&run1).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let keep: Vec<usize> = (0..header.len())
        .filter(|&i| header[i] == "t" || header[i].starts_with('q') || header[i].starts_with("tau"))
        .filter(|&i| !header[i].starts_with("q_"))
        .collect();
    let mut cut = String::new();
    for (k, l) in text.lines().enumerate() {
        let cells: Vec<String> = l.split(',').map(String::from).collect();
        let mut row: Vec<String> = keep.iter().map(|&i| cells[i].clone()).collect();
        if k > 0 {
            row[0] = (row[0].parse::<f64>().unwrap() * time_scale).to_string();
            for (c, &i) in keep.iter().enumerate() {
                if header[i].starts_with('q') {
                    row[c] = (row[c].parse::<f64>().unwrap() * angle_scale).to_string();
                }
            }
        }
        cut += &(row.join(",") + "\n");
    }
    let path = dir.join(name);
    std::fs::write(&path, cut).unwrap();
    path
}

#[test]
fn stamps_in_another_unit_than_seconds_are_refused_naming_the_likely_one() {
    // Before: run 1's stamps in milliseconds were read as seconds without a word (viscous
    // friction up to 49 N m s/rad); in nanoseconds the cutoff came out at 2e-7 Hz.
    let dir = tempfile::tempdir().unwrap();
    let (_, urdf) = run1_and_urdf();
    for (scale, unit) in [
        (1e3, "milliseconds? (divide t by 1e3)"),
        (1e9, "nanoseconds? (divide t by 1e9)"),
    ] {
        let tq = tq_csv(dir.path(), &format!("tq_{scale}.csv"), scale);
        let (code, _, err) =
            common::physid(&["identify", "--robot", &urdf, "--data", tq.to_str().unwrap()]);
        assert!(
            code == 2
                && err.contains(&format!("tq_{scale}.csv: the median sample period"))
                && err.contains(unit),
            "{err}"
        );
    }
    let tq = tq_csv(dir.path(), "tq_s.csv", 1.0);
    let (code, _, err) =
        common::physid(&["identify", "--robot", &urdf, "--data", tq.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
}

#[test]
fn positions_in_degrees_are_refused_naming_the_joint() {
    // Before: run 1 in degrees was accepted, positions 20 times outside the URDF's limits.
    let dir = tempfile::tempdir().unwrap();
    let (_, urdf) = run1_and_urdf();
    let deg = tq_csv_scaled(dir.path(), "deg.csv", 1.0, 180.0 / std::f64::consts::PI);
    let (code, _, err) = common::physid(&[
        "identify",
        "--robot",
        &urdf,
        "--data",
        deg.to_str().unwrap(),
    ]);
    assert!(
        code == 2
            && err.contains("deg.csv: joint 'lwr_0_joint': positions from")
            && err.contains("the log is in degrees?"),
        "{err}"
    );
}

/// `src` with every row but the header dropped with probability `p` (a fixed seed).
fn with_rows_dropped(src: &Path, dst: &Path, p: f64) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(20);
    let text = std::fs::read_to_string(src).unwrap();
    let kept: Vec<&str> = text
        .lines()
        .enumerate()
        .filter(|(k, _)| *k == 0 || !rng.random_bool(p))
        .map(|(_, l)| l)
        .collect();
    std::fs::write(dst, kept.join("\n") + "\n").unwrap();
}

/// `identify` on `data` (consistent, viscous and Coulomb friction): the JSON.
fn identified(data: &Path) -> serde_json::Value {
    let (_, urdf) = run1_and_urdf();
    let (code, out, err) = physid(&[
        "identify",
        "--robot",
        &urdf,
        "--data",
        data.to_str().unwrap(),
        "--constraints",
        "consistent",
        "--friction",
        "viscous,coulomb",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    serde_json::from_str(&out).unwrap()
}

#[test]
fn samples_dropped_at_random_are_bridged_at_the_cutoff_applied_and_the_fit_holds() {
    // Run 1 as t, q, τ with a fifth of its rows dropped at random (holes of one to six
    // samples at 200 Hz): the 2 Hz cutoff read from the motion bridges up to ten, so the log
    // stays one run; bridging only what the 20 Hz default allows (one) had cut it into pieces
    // shorter than the filter settles, kept 154 of 4009 samples and put 36.9 kg on lwr_2_link.
    let dir = tempfile::tempdir().unwrap();
    let full = tq_csv(dir.path(), "tq.csv", 1.0);
    let dropped = dir.path().join("tq_dropped.csv");
    with_rows_dropped(&full, &dropped, 0.2);
    let (a, b) = (identified(&full), identified(&dropped));
    let p = &b["data_pipeline"][0]["pipeline"];
    assert_eq!(p["runs"], 1, "{p}");
    assert_eq!(p["cutoff"], 2.0, "{p}");
    assert!(p["missing_bridged"].as_u64().unwrap() > 700, "{p}");
    let used = p["samples_kept"].as_f64().unwrap() / p["samples_read"].as_f64().unwrap();
    assert!(used > 0.85, "{p}");
    let masses = |j: &serde_json::Value| -> Vec<f64> {
        let bodies = j["bodies"].as_array().unwrap();
        bodies
            .iter()
            .map(|x| x["pi"][0].as_f64().unwrap())
            .collect()
    };
    // Each mass as far from the full log's fit as a fifth fewer samples moves it (lwr_5_link,
    // which this run barely weighs, 1.9 -> 1.4 kg), the total within 5 %.
    let (full, thinned) = (masses(&a), masses(&b));
    for (m_full, m_dropped) in full.iter().zip(&thinned) {
        assert!(
            (m_dropped / m_full - 1.0).abs() < 0.3,
            "{full:?} vs {thinned:?}"
        );
    }
    let total = |m: &[f64]| m.iter().sum::<f64>();
    assert!(
        (total(&thinned) / total(&full) - 1.0).abs() < 0.05,
        "{full:?} vs {thinned:?}"
    );
    let rms = |j: &serde_json::Value| j["train"]["rms_overall"].as_f64().unwrap();
    assert!(
        (rms(&a) - rms(&b)).abs() < 0.02 * rms(&a),
        "{} {}",
        rms(&a),
        rms(&b)
    );
}
