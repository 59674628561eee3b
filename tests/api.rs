//! The library's entry points (`physid::api`) on their own, without the binary: a large CSV or
//! MCAP streamed from disk identifies the same model as the same file read into memory, and the
//! ground truth of a physid log scores the fit.

mod common;

use common::root;
use physid::api::data::{locked_joints, Data, Span, Streamed};
use physid::api::identify::{self, fit};
use physid::ident::{ConstraintSet, Options};

#[test]
fn a_streamed_mcap_fits_as_the_same_file_in_memory() {
    let common::ShellRun { model, rec, .. } = common::shell_run(2.0);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("leg.mcap");
    common::write_mcap(&path, &model, &rec, "");
    let opts = physid::io::DataOptions::default();
    let memory = Data::open_all(&[path.as_path()], &model, &opts, true).unwrap();
    let joints: Vec<String> = model.joint_names();
    assert!(physid::io::mcap_stream::mcap_streamable(&path).unwrap());
    let n = physid::io::mcap_stream::stream_mcap(&path, &joints, 0..0, &mut |_, _| {}).unwrap();
    assert_eq!(
        (n, memory[0].len()),
        (rec.processed.len(), rec.processed.len())
    );
    // Every sample as the whole-file reader gives it, bit for bit.
    let whole = memory[0].pieces(&(0..n));
    assert_eq!(whole.len(), 1);
    let mut seen = 0;
    physid::io::mcap_stream::stream_mcap(&path, &joints, 5..n - 5, &mut |k, s| {
        let tr = &whole[0];
        let j = joints.len();
        assert_eq!(s.t, tr.t[k], "sample {k}");
        assert_eq!(s.q, &tr.q[k * j..(k + 1) * j]);
        assert_eq!(s.qd, &tr.qd[k * j..(k + 1) * j]);
        assert_eq!(s.qdd, &tr.qdd.as_ref().unwrap()[k * j..(k + 1) * j]);
        assert_eq!(s.tau, &tr.tau[k * j..(k + 1) * j]);
        seen += 1;
    })
    .unwrap();
    assert_eq!(seen, n - 10);
    let streamed = vec![Data::Stream {
        format: Streamed::Mcap,
        path: path.clone(),
        joints,
        samples: n,
    }];
    let train = [Span {
        file: 0,
        range: 0..n / 2,
    }];
    let opts = Options::new(ConstraintSet::Consistent);
    let a = fit(&model, &memory, &train, &opts, vec![], &[]).unwrap();
    let b = fit(&model, &streamed, &train, &opts, vec![], &[]).unwrap();
    assert_eq!(a.identified.theta, b.identified.theta);
    let validation = [Span {
        file: 0,
        range: n / 2..n,
    }];
    let ea = a.errors(&model, &memory, &validation, &[]).unwrap();
    let eb = b.errors(&model, &streamed, &validation, &[]).unwrap();
    assert!((ea.overall - eb.overall).abs() <= 1e-12 * ea.overall);
}

#[test]
fn a_streamed_csv_fits_as_the_same_file_in_memory() {
    let common::ShellRun {
        scenario: sc,
        model,
        rec,
        ..
    } = common::shell_run(2.0);
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("leg.csv");
    physid::io::samples::write_csv(&csv, &rec.processed).unwrap();
    let opts = physid::io::DataOptions::default();
    let memory = Data::open_all(&[csv.as_path()], &model, &opts, true).unwrap();
    assert!(matches!(memory[0], Data::Memory(_)));
    let joints: Vec<String> = model.joint_names();
    let streamed = vec![Data::Stream {
        format: Streamed::Csv,
        path: csv.clone(),
        joints,
        samples: memory[0].len(),
    }];
    let n = memory[0].len();
    assert_eq!(n, rec.processed.len());
    let train = [Span {
        file: 0,
        range: 0..n * 3 / 4,
    }];
    let validation = [Span {
        file: 0,
        range: n * 3 / 4..n,
    }];
    let set = identify::constraint_set(None, &model);
    assert_eq!(set.set, ConstraintSet::Ellipsoid, "{:?}", set.because);
    let opts = Options::new(ConstraintSet::Consistent);
    let locked = locked_joints(&model, &memory);
    assert!(locked.is_empty());
    let a = fit(&model, &memory, &train, &opts, vec![], &locked).unwrap();
    let b = fit(&model, &streamed, &train, &opts, vec![], &locked).unwrap();
    let scale = a.identified.theta.amax();
    let diff = (&a.identified.theta - &b.identified.theta).amax();
    assert!(
        diff <= 1e-8 * scale,
        "θ differs by {diff:e} (scale {scale:e})"
    );
    assert!(a.identified.constraints_hold);
    // The information matrix for the sidecar: the same from the file read again from disk.
    let ia = a
        .information(&model, &memory, &train, &locked)
        .unwrap()
        .unwrap();
    let ib = b
        .information(&model, &streamed, &train, &locked)
        .unwrap()
        .unwrap();
    let scale = ia.matrix.amax();
    let diff = (&ia.matrix - &ib.matrix).amax();
    assert!(
        diff <= 1e-8 * scale,
        "𝓘 differs by {diff:e} (scale {scale:e})"
    );
    assert_eq!((ia.samples, ib.samples), (n * 3 / 4, n * 3 / 4));
    // Weighed by the fit's own residual, which sits at the torque noise.
    let noise = sc.sensors.torque_noise;
    assert!(ia.correlation_samples >= 1.0 && ia.correlation_samples.is_finite());
    assert_eq!(ia.correlation_samples, ib.correlation_samples);
    let s = ia.residual_rms;
    assert!(s < 3.0 * noise && s > 0.3 * noise, "{s} vs noise {noise}");
    let w = 1.0 / (s * s * ia.correlation_samples);
    let yty = &a.normal_equations.yty;
    assert!((&ia.matrix - yty * w).amax() <= 1e-12 * scale);
    let a = a.errors(&model, &memory, &validation, &locked).unwrap();
    let b = b.errors(&model, &streamed, &validation, &locked).unwrap();
    let (per_a, all_a, per_b, all_b) = (a.per_joint, a.overall, b.per_joint, b.overall);
    assert!((all_a - all_b).abs() <= 1e-9 * all_a, "{all_a} vs {all_b}");
    assert_eq!(per_a.len(), 3);
    assert!(per_b
        .iter()
        .all(|r| r.is_some_and(|r| r > 0.0 && r.is_finite())));
    // The validation error sits at the simulated torque noise, not far above it.
    assert!(
        all_a < 3.0 * noise && all_a > 0.3 * noise,
        "{all_a} vs noise {noise}"
    );
}

#[test]
fn a_simulation_through_the_library_reports_and_logs_what_it_ran() {
    use physid::api::simulate::{simulate, SimulateOptions};
    let opts = SimulateOptions {
        duration: Some(1.0),
        seed: Some(7),
        ..Default::default()
    };
    let path = root().join("scenarios/cheetah3_shell.toml");
    let mut calls = 0;
    let run = simulate(&path, &opts, &mut |_| calls += 1).unwrap();
    assert!(calls > 0);
    assert_eq!(run.scenario.simulation.seed, 7);
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("leg.mcap");
    run.write_mcap(&out).unwrap();
    let report = run.report(&out);
    let rate = run.scenario.simulation.rate;
    assert_eq!(report.samples, (rate * 1.0).round() as usize);
    assert_eq!(report.engine, "physid");
    // physid's own inverse dynamics explains its own integration to round-off.
    let worst = report
        .physid_inverse_dynamics_residual
        .max
        .iter()
        .cloned()
        .fold(0.0, f64::max);
    assert!(worst < 1e-6, "{worst}");
    // The log carries the ground truth the identification scores against.
    let truth = identify::ground_truth(&out, &run.model).unwrap();
    assert_eq!(truth, run.model.parameters());
    // Writing the logs beside the report gives the same files and the same report.
    let (beside, table) = (
        dir.path().join("beside.mcap"),
        dir.path().join("beside.csv"),
    );
    let together = run.write_with_report(&beside, Some(&table)).unwrap();
    assert_eq!(
        std::fs::read(&beside).unwrap(),
        std::fs::read(&out).unwrap()
    );
    let alone = dir.path().join("alone.csv");
    run.write_csv(&alone).unwrap();
    assert_eq!(
        std::fs::read(&table).unwrap(),
        std::fs::read(&alone).unwrap()
    );
    assert_eq!(
        serde_json::to_value(&together.excitation).unwrap(),
        serde_json::to_value(&report.excitation).unwrap()
    );
    assert_eq!(
        together.physid_inverse_dynamics_residual.rms,
        report.physid_inverse_dynamics_residual.rms
    );
    // An output it cannot write is an error naming the file (the log's thread reports it).
    let nowhere = dir.path().join("no/such/dir/leg.mcap");
    let err = run
        .write_with_report(&nowhere, None)
        .unwrap_err()
        .to_string();
    assert!(err.contains("no/such/dir"), "{err}");
    // A bad override is an error naming the scenario, not a panic.
    let bad = SimulateOptions {
        duration: Some(-1.0),
        ..Default::default()
    };
    let err = simulate(&path, &bad, &mut |_| {})
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("cheetah3_shell.toml"), "{err}");
}

#[test]
fn a_robot_described_through_the_library_lists_bodies_then_rotors() {
    let model = physid::io::load_robot("cheetah3").unwrap();
    let v = physid::api::model::describe(&model);
    assert_eq!(v.dof, 3);
    assert_eq!(v.rotors, 3);
    assert_eq!(v.bodies.len(), 6);
    assert_eq!(v.parameters, model.layout().len);
    let total: f64 = v.bodies.iter().map(|b| b.mass).sum();
    assert!((total - v.total_mass).abs() < 1e-12 * total);
    // The gravity torque at q0 is the inverse dynamics at rest there.
    let mut d = physid::dynamics::Data::new(&model);
    let zero = vec![0.0; 3];
    let g = physid::dynamics::rnea(&model, &mut d, &v.q0, &zero, &zero).clone();
    assert_eq!(g.as_slice(), &v.gravity_torque_q0[..]);
}

#[test]
fn a_diagnosis_through_the_library_checks_its_inputs_first() {
    use physid::api::diagnose::{diagnose, Runs};
    let (mut sc, model, _) =
        physid::sim::scenario::load(&root().join("scenarios/cheetah3_shell.toml")).unwrap();
    sc.simulation.duration = 1.0;
    let run = physid::sim::run(&model, &sc, &mut |_| {})
        .unwrap()
        .processed;
    let opts = physid::diagnose::Options::default();
    // Baseline runs without the uncertainty the change is judged within.
    let runs = Runs {
        train: vec![run.clone()],
        validate: vec![],
        baseline: vec![run.clone()],
    };
    let err = diagnose(&model, runs, 0.3, &opts)
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("--description-uncertainty"), "{err}");
    // A holdout that leaves nothing to train or to validate on.
    let runs = Runs {
        train: vec![run],
        ..Default::default()
    };
    let err = diagnose(&model, runs, 1.5, &opts)
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("1.5"), "{err}");
    // No runs at all.
    let err = diagnose(&model, Runs::default(), 0.3, &opts)
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("no training data"), "{err}");
}

#[test]
fn a_design_is_checked_in_simulation_through_the_library() {
    use physid::api::excite::check_in_simulation;
    let path = root().join("scenarios/excitation/base.toml");
    let (_, model, text) = physid::sim::scenario::load(&path).unwrap();
    let text = text.replace("duration = ", "duration = 3.0 #");
    let opts = physid::sim::design::DesignOptions::default();
    let check = check_in_simulation(&model, &text, &opts, 10.0).unwrap();
    assert_eq!(check.joints.len(), model.dof());
    for (u, b) in check.joints.iter().zip(model.bodies()) {
        assert_eq!(u.joint, b.joint_name);
        assert!(u.q_range[0] <= u.q_range[1] && u.velocity.is_finite() && u.torque >= 0.0);
    }
    assert_eq!(check.within, check.joints.iter().all(|u| u.within));
    // A text that is not a scenario is named as the designed scenario, not a panic.
    let err = check_in_simulation(&model, "[robot", &opts, 10.0)
        .err()
        .unwrap()
        .to_string();
    assert!(err.starts_with("the designed scenario"), "{err}");
}

#[test]
fn batch_dynamics_agree_with_each_other_and_refuse_bad_shapes() {
    use physid::api::dynamics::{inverse_dynamics, mass_matrices, regressors};
    use physid::api::ApiError;
    let model = physid::io::load_robot(
        &root()
            .join("data/kuka_lwr4/kuka_lwr4.urdf")
            .to_string_lossy(),
    )
    .unwrap();
    let (n, p, count) = (model.dof(), model.layout().len, 50);
    let wave = |k: usize, j: usize, s: f64| ((k * 7 + j * 3) as f64 * 0.13 * s).sin() * s;
    let q: Vec<f64> = (0..count * n).map(|i| wave(i / n, i % n, 1.0)).collect();
    let qd: Vec<f64> = (0..count * n).map(|i| wave(i / n, i % n, 1.7)).collect();
    let qdd: Vec<f64> = (0..count * n).map(|i| wave(i / n, i % n, 2.3)).collect();
    let tau = inverse_dynamics(&model, &q, &qd, &qdd).unwrap();
    let y = regressors(&model, &q, &qd, &qdd).unwrap();
    let h = mass_matrices(&model, &q).unwrap();
    assert_eq!(
        (tau.len(), y.len(), h.len()),
        (count * n, count * n * p, count * n * n)
    );
    // Y θ = τ sample by sample (a second algorithm: the regressor against RNEA + friction).
    let theta = model.parameters();
    let mut worst: f64 = 0.0;
    for k in 0..count {
        for i in 0..n {
            let row = &y[(k * n + i) * p..(k * n + i + 1) * p];
            let y_theta: f64 = row.iter().zip(theta.iter()).map(|(a, b)| a * b).sum();
            worst = worst.max((y_theta - tau[k * n + i]).abs());
        }
        // H symmetric and positive on the diagonal.
        for i in 0..n {
            assert!(h[k * n * n + i * n + i] > 0.0);
            for j in 0..n {
                let (a, b) = (h[k * n * n + i * n + j], h[k * n * n + j * n + i]);
                assert!((a - b).abs() <= 1e-12 * a.abs().max(1.0));
            }
        }
    }
    assert!(worst < 1e-9, "Y θ − τ up to {worst:e} N m");
    // The same numbers on one thread as on several.
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    assert_eq!(
        one.install(|| inverse_dynamics(&model, &q, &qd, &qdd).unwrap()),
        tau
    );
    // Shapes and values are checked, naming the array and the sample.
    let err = |r: Result<Vec<f64>, ApiError>| r.err().unwrap().to_string();
    let e = err(inverse_dynamics(&model, &q[..n * 3 + 1], &qd, &qdd));
    assert!(e.contains("q has") && e.contains("whole number"), "{e}");
    let e = err(inverse_dynamics(&model, &q, &qd[..n * 2], &qdd));
    assert!(e.contains("qd has 2 samples, q has 50"), "{e}");
    let mut bad = qdd.clone();
    bad[n * 4 + 2] = f64::NAN;
    let e = err(regressors(&model, &q, &qd, &bad));
    assert!(e.contains("qdd: sample 4, joint 2 is NaN"), "{e}");
    assert!(inverse_dynamics(&model, &[], &[], &[]).unwrap().is_empty());
}

#[test]
fn excite_designs_writes_within_limits_and_names_a_bad_option_as_its_flag() {
    use physid::api::excite::{excite, ExciteOptions};
    use physid::options::OptionError;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("designed.toml");
    let opts = ExciteOptions {
        iterations: 20,
        starts: 2,
        duration: 3.0,
        out: Some(out.clone()),
        ..Default::default()
    };
    let mut notices = vec![];
    let e = excite(&opts, &mut |n| notices.push(n)).unwrap();
    assert!(notices.is_empty(), "{notices:?}");
    assert_eq!(e.within_limits(), Some(true));
    assert_eq!(e.written.as_deref(), Some(out.as_path()));
    assert_eq!(std::fs::read_to_string(&out).unwrap(), e.scenario);
    // The written scenario is one the simulator accepts for this robot, with the design's
    // duration.
    let sc: physid::sim::scenario::Scenario = toml::from_str(&e.scenario).unwrap();
    sc.validate(e.model.dof()).unwrap();
    assert_eq!(sc.simulation.duration, 3.0);
    let json = e.json(Some(out.clone()));
    assert_eq!(json.within_limits, Some(true));
    assert_eq!(json.simulated.as_ref().map(Vec::len), Some(3));

    let bad = ExciteOptions {
        rate: -1.0,
        ..opts.clone()
    };
    let err = excite(&bad, &mut |_| {}).unwrap_err();
    assert_eq!(
        err.flag_message().as_deref(),
        Some("--rate must be a sample rate in (0, 100000] Hz, got -1")
    );
    let bad = ExciteOptions {
        margin: 0.95,
        out: Some(dir.path().join("never.toml")),
        ..opts
    };
    let err = excite(&bad, &mut |_| {}).unwrap_err();
    assert!(err.flag_message().unwrap().starts_with("--margin must be"));
    assert!(!dir.path().join("never.toml").exists());
}

/// The variables are scaled to unit curvature before the solve; Clarabel's equilibration on
/// top once stalled on this problem (the simulated KUKA log of the side-by-side benchmark,
/// `consistent`): "almost solved" after 40 iterations, 2.5e-5 above the optimum it reaches
/// without equilibration. The solve now retries without it and must end solved.
#[test]
fn a_nearly_flat_kuka_problem_is_solved_not_almost() {
    let path = root().join("scenarios/excitation/kuka_base.toml");
    let (mut sc, model, _) = physid::sim::scenario::load(&path).unwrap();
    sc.simulation.duration = 9.0;
    let rec = physid::sim::run(&model, &sc, &mut |_| {}).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("kuka.csv");
    physid::io::samples::write_csv(&csv, &rec.processed).unwrap();
    let mut o = identify::IdentifyOptions::new(vec![csv]);
    o.constraints = Some(ConstraintSet::Consistent);
    let r = identify::identify(&model, &o).unwrap();
    let id = &r.identified;
    let solver = &id.solver;
    assert_eq!(
        solver.status,
        physid::ident::SolveStatus::Solved,
        "{} iterations",
        solver.iterations
    );
    assert!(id.constraints_hold);
}

/// Identification options for the floating log at `data` (the built-in quadruped's
/// description as the prior, every other option at its CLI default).
fn floating_options(data: &std::path::Path) -> physid::api::floating::IdentifyFloatingOptions {
    physid::api::floating::IdentifyFloatingOptions {
        robot: physid::api::model::RobotOptions::new("cheetah3"),
        data: data.to_path_buf(),
        topics: Default::default(),
        feet: vec![],
        setting: physid::ident::floating::DataSetting::TorquesAndContacts,
        constraints: ConstraintSet::Ellipsoid,
        prior_weight: 1e-4,
        cutoff: None,
        contact_force: 10.0,
        out_urdf: None,
        out_mjcf: None,
        truth: None,
        baseline: None,
    }
}

/// A floating run simulated and logged (`simulate-floating`) for `seconds`, of `robot`.
fn floating_log(
    dir: &std::path::Path,
    robot: &str,
    (seconds, seed): (f64, u64),
    sensors: physid::sim::floating_sensors::Sensors,
) -> std::path::PathBuf {
    let out = dir.join(format!("{seconds}_{seed}.csv"));
    floating_log_at(out, robot, (seconds, seed), sensors)
}

/// [`floating_log`] written at `out` (CSV, or MCAP for a `.mcap` name).
fn floating_log_at(
    out: std::path::PathBuf,
    robot: &str,
    (seconds, seed): (f64, u64),
    sensors: physid::sim::floating_sensors::Sensors,
) -> std::path::PathBuf {
    let opts = physid::api::floating::SimulateFloatingOptions {
        start: Default::default(),
        robot: physid::api::model::RobotOptions::new(robot),
        duration: seconds,
        rate: 1000.0,
        seed,
        trot: None,
        still: false,
        sensors,
        out: out.clone(),
    };
    physid::api::floating::simulate_floating(&opts).unwrap();
    out
}

#[test]
fn a_floating_run_logged_as_mcap_identifies_as_its_csv_does() {
    // The same run (seed, sensors, noise) written both ways: MCAP stamps in integer
    // nanoseconds and carries the orientation as a quaternion, as the CSV does; the two
    // identifications agree to rounding.
    use physid::api::floating::{identify_floating, FloatingReadOptions};
    let dir = tempfile::tempdir().unwrap();
    // With the IMU's accelerometer: its own topic in MCAP, three columns in the CSV.
    let sensors = physid::sim::floating_sensors::Sensors {
        accelerometer: true,
        ..Default::default()
    };
    let csv = floating_log(dir.path(), "cheetah3", (2.0, 4), sensors.clone());
    let mcap = dir.path().join("run.mcap");
    floating_log_at(mcap.clone(), "cheetah3", (2.0, 4), sensors);
    let truth = physid::api::floating::truth_path(&mcap);
    assert!(
        truth.ends_with("run.truth.urdf") && truth.is_file(),
        "{truth:?}"
    );
    let from_csv = identify_floating(&floating_options(&csv)).unwrap();
    let from_mcap = identify_floating(&floating_options(&mcap)).unwrap();
    assert_eq!(from_mcap.samples_read, from_csv.samples_read);
    assert_eq!(from_mcap.samples_used, from_csv.samples_used);
    assert!(from_mcap
        .notices
        .iter()
        .all(|n| !n.text.contains("left out")));
    let scale = from_csv.theta.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for (i, (a, b)) in from_mcap.theta.iter().zip(&from_csv.theta).enumerate() {
        assert!(
            (a - b).abs() <= 1e-8 * scale,
            "θ[{i}]: {a} from MCAP, {b} from CSV"
        );
    }
    // Topics other than the log's are named; topics apply to MCAP only; three distinct topics.
    let with = |data: &std::path::Path, topics: FloatingReadOptions| {
        let opts = physid::api::floating::IdentifyFloatingOptions {
            topics,
            ..floating_options(data)
        };
        identify_floating(&opts).unwrap_err().to_string()
    };
    let odometry = |t: &str| FloatingReadOptions {
        odometry_topic: t.into(),
        ..Default::default()
    };
    let err = with(&mcap, odometry("/state_estimator/odom"));
    assert!(
        err.contains("run.mcap: no /state_estimator/odom messages (nav_msgs/msg/Odometry)")
            && err.contains("/odometry (nav_msgs/msg/Odometry)"),
        "{err}"
    );
    let err = with(&csv, odometry("/odom"));
    assert!(
        err.contains("apply to MCAP files and rosbag2 directories only"),
        "{err}"
    );
    let err = with(&mcap, odometry("/joint_states"));
    assert!(
        err.contains("topic and odometry_topic are both /joint_states"),
        "{err}"
    );
    let err = with(&mcap, odometry(" "));
    assert!(err.contains("odometry_topic: empty"), "{err}");
    let imu = FloatingReadOptions {
        imu_topic: "/odometry".into(),
        ..Default::default()
    };
    let err = with(&mcap, imu);
    assert!(
        err.contains("odometry_topic and imu_topic are both /odometry"),
        "{err}"
    );
    let feet = FloatingReadOptions {
        foot_forces_topic: "/contacts".into(),
        ..Default::default()
    };
    // Without the feet's topic, the setting that needs the forces says so.
    let err = with(&mcap, feet);
    assert!(
        err.contains("the torques_and_contacts setting needs the feet's contact forces"),
        "{err}"
    );
}

#[test]
fn a_floating_export_carries_its_ellipsoids_in_a_sidecar_and_reads_back_whole() {
    // The truth simulate-floating writes (and an identified robot) is a URDF without geometry
    // plus its sidecar: read through the sidecar, every body keeps its ellipsoid (the trunk's
    // and the rotors' too), so the ellipsoid set runs on it as on the built-in quadruped.
    use physid::api::floating::{identify_floating, quadruped_feet, IdentifyFloatingOptions};
    let dir = tempfile::tempdir().unwrap();
    let data = floating_log(dir.path(), "cheetah3", (1.0, 6), Default::default());
    let truth = physid::api::floating::truth_path(&data);
    let sidecar = physid::io::sidecar_path(&truth);
    assert!(sidecar.is_file(), "{}", sidecar.display());
    let built_in = physid::model::quadruped::quadruped();
    let arg = sidecar.to_str().unwrap();
    let (read, _) = physid::io::load_floating_robot_with(arg, &Default::default()).unwrap();
    let pairs = |m: &physid::model::floating::FloatingModel| {
        let mut v = vec![(m.trunk().name.clone(), m.trunk().bounding.unwrap())];
        for b in m.tree().bodies() {
            v.push((b.name.clone(), b.bounding.unwrap()));
            if let Some(r) = &b.rotor {
                v.push((r.name.clone(), r.bounding.unwrap()));
            }
        }
        v
    };
    let (want, got) = (pairs(&built_in), pairs(&read));
    assert_eq!(want.len(), got.len());
    for ((name, a), (other, b)) in want.iter().zip(&got) {
        assert_eq!(name, other);
        let gap = (a.qs - b.qs).abs().max() + (a.center - b.center).abs().max();
        assert!(gap < 1e-12 * a.qs.abs().max(), "{name}: {gap:e}");
    }
    let feet = quadruped_feet(&built_in);
    let identify = |robot: &str, out: Option<std::path::PathBuf>| {
        identify_floating(&IdentifyFloatingOptions {
            robot: physid::api::model::RobotOptions::new(robot),
            feet: feet.clone(),
            out_urdf: out,
            ..floating_options(&data)
        })
    };
    let from_builtin = identify("cheetah3", Some(dir.path().join("id.urdf"))).unwrap();
    let from_sidecar = identify(arg, None).unwrap();
    assert!(from_sidecar.constraints_hold);
    let gap = (from_sidecar.description_rms - from_builtin.description_rms).abs();
    assert!(gap < 1e-9 * from_builtin.description_rms, "{gap:e}");
    // The identified robot's sidecar reads back, and identifies again under the ellipsoids.
    let id_sidecar = dir.path().join("id.physid.toml");
    let again = identify(id_sidecar.to_str().unwrap(), None).unwrap();
    assert!(again.constraints_hold);
    // Its URDF alone, without geometry, gets the kinematic tree's ellipsoids (rotors included).
    let urdf_only = identify(dir.path().join("id.urdf").to_str().unwrap(), None).unwrap();
    assert!(urdf_only.constraints_hold);
    // The export never writes over an input; a sidecar that does not name a URDF is refused.
    let err = identify(arg, Some(truth.clone())).unwrap_err().to_string();
    assert!(err.contains("truth.urdf"), "{err}");
    let bare = dir.path().join("bare.toml");
    std::fs::write(&bare, "[robot]\nbuiltin = \"cheetah3\"\n").unwrap();
    let err = identify(bare.to_str().unwrap(), None)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("bare.toml") && err.contains("names its URDF"),
        "{err}"
    );
}

#[test]
fn a_floating_log_of_exact_sensors_obeys_the_description_that_made_it() {
    // The trunk's angular acceleration is differentiated from its logged twist, its linear
    // one read from the accelerometer (exact sensors log everything), the joints' from their
    // positions. The trunk rows hold to a tenth of a newton on 180 N (measured 0.038 and
    // 0.13 on seeds 3 and 2; 0.08 and 10.1 before the force sensors averaged over the two
    // periods around each sample, as an anti-aliasing filter does: seed 2 lifts its feet, and
    // a touchdown's force changes within a substep). The joint rows keep the filter's and the
    // simulation's smoothed Coulomb friction's share, below the default sensors' torque noise
    // (0.5 N m; measured 0.33-0.39 with the forces, 0.24-0.36 without).
    use physid::ident::floating::DataSetting::*;
    let dir = tempfile::tempdir().unwrap();
    let exact = physid::sim::floating_sensors::Sensors {
        velocities: false,
        ..physid::sim::floating_sensors::Sensors::exact()
    };
    for seed in [2, 3] {
        let data = floating_log(dir.path(), "cheetah3", (4.0, seed), exact.clone());
        for (setting, bound) in [
            (TorquesAndContacts, 0.4),
            (TorquesOnly, 0.4),
            (BaseOnly, 0.2),
        ] {
            let found = physid::api::floating::identify_floating(
                &physid::api::floating::IdentifyFloatingOptions {
                    setting,
                    ..floating_options(&data)
                },
            )
            .unwrap();
            let said = format!(
                "seed {seed}, {setting:?}: residual {:.3e} of rows {:.3e}, mass {:.3} kg",
                found.description_rms, found.target_rms, found.identified_mass
            );
            assert!(found.description_rms < bound, "{said}");
            assert!(
                found.identified_rms <= found.description_rms * (1.0 + 1e-9),
                "{said}"
            );
            assert!(found.constraints_hold, "{said}");
            // Torques only: the samples near a foot's touchdown or lift-off are left out
            // (seed 2 lifts its feet now and then, seed 3 never).
            let near = found.samples_near_contact_changes;
            assert!(
                found.contact_share > 0.9 && found.samples_used + near > 3000,
                "{said}"
            );
            let lifts = setting == TorquesOnly && seed == 2;
            assert_eq!(
                near > 0,
                lifts,
                "{said}: {near} samples near contact changes"
            );
        }
    }
}

#[test]
fn a_payload_on_the_trunk_is_weighed_from_a_noisy_log_and_the_outputs_load_back() {
    // The quadruped with 5 kg strapped on its trunk, written as a floating URDF, simulated and
    // logged with the default sensors (IMU and estimator noise and bias, torque and force
    // noise); identified from the unloaded description.
    use physid::spatial::InertialParams;
    let dir = tempfile::tempdir().unwrap();
    let described = physid::model::quadruped::quadruped();
    let payload = InertialParams::from_mass_com_inertia(
        5.0,
        &nalgebra::Vector3::new(0.1, 0.0, 0.08),
        &(nalgebra::Matrix3::identity() * 0.01),
    );
    let mut theta = described.parameters();
    for (i, p) in payload.0.iter().enumerate() {
        theta[i] += p;
    }
    let loaded = described.with_parameters(&theta).unwrap();
    let urdf = dir.path().join("loaded.urdf");
    std::fs::write(&urdf, physid::io::urdf::floating_to_string(&loaded)).unwrap();
    let sensors = physid::sim::floating_sensors::Sensors::default();
    let data = floating_log(dir.path(), urdf.to_str().unwrap(), (6.0, 3), sensors);
    let (out_urdf, out_mjcf) = (dir.path().join("id.urdf"), dir.path().join("id.xml"));
    // The simulation wrote the robot it simulated beside its log: the ground truth.
    let truth = physid::api::floating::truth_path(&data);
    let found =
        physid::api::floating::identify_floating(&physid::api::floating::IdentifyFloatingOptions {
            out_urdf: Some(out_urdf.clone()),
            out_mjcf: Some(out_mjcf.clone()),
            truth: Some(truth.clone()),
            ..floating_options(&data)
        })
        .unwrap();
    let gained = found.identified_mass - found.described_mass;
    assert!((gained - 5.0).abs() < 0.25, "{gained} kg of 5: {found:?}");
    assert!(
        found.identified_rms < found.description_rms * 0.9,
        "{found:?}"
    );
    assert!(found.constraints_hold);
    let scores = found.truth.as_ref().unwrap();
    assert!((scores.mass - 50.0).abs() < 1e-9, "{}", scores.mass);
    assert_eq!(scores.bodies.len(), 25);
    assert_eq!(scores.bodies[0].name, "trunk");
    assert!(scores.bodies.iter().all(|b| b.mass_rel.is_finite()));
    // The URDF reads back as the identified robot (the MJCF is MuJoCo's: scripts/check_mujoco.py).
    let back = physid::io::urdf::load_floating(&out_urdf, &Default::default())
        .unwrap()
        .0;
    let err = (back
        .parameters()
        .rows(0, found.theta.len() - 24)
        .into_owned()
        - nalgebra::DVector::from_vec(found.theta.clone()).rows(0, found.theta.len() - 24))
    .abs()
    .max();
    assert!(err < 1e-9, "{err}");
    assert!(std::fs::read_to_string(&out_mjcf)
        .unwrap()
        .contains("<freejoint"));
    what_the_log_determines(&found, 50.0);
    // Against the description, the trunk changed, by the payload: 5 kg at (0.1, 0, 0.08) m.
    let change = found.change.changed.as_ref().expect("a body named");
    assert_eq!(change.body, "trunk", "{:?}", found.change);
    assert!((change.mass - 5.0).abs() < 0.1, "{change:?}");
    let at = change.com.unwrap() - nalgebra::Vector3::new(0.1, 0.0, 0.08);
    assert!(at.norm() < 0.03, "{change:?}");
    // What fits almost as well is what the trunk carries rigidly (its ab/ad bodies and rotors).
    assert!(
        (found.change.also_fit.iter()).all(|b| b.ends_with("_abad") || b.ends_with("abad_rotor")),
        "{:?}",
        found.change.also_fit
    );
}

/// The quadruped with `mass` kg more on `body`, at `at` in its frame, as a floating URDF.
fn loaded_quadruped(
    dir: &std::path::Path,
    body: &str,
    mass: f64,
    at: [f64; 3],
) -> std::path::PathBuf {
    use physid::ident::Parameterized;
    use physid::spatial::InertialParams;
    let described = physid::model::quadruped::quadruped();
    let payload = InertialParams::from_mass_com_inertia(
        mass,
        &nalgebra::Vector3::from(at),
        &nalgebra::Matrix3::zeros(),
    );
    let column = (described.inertial_bodies().into_iter())
        .find(|(name, _, _)| name == body)
        .expect("a body of the quadruped")
        .1;
    let mut theta = described.parameters();
    for (i, p) in payload.0.iter().enumerate() {
        theta[column + i] += p;
    }
    let urdf = dir.join(format!("{body}_{mass}.urdf"));
    let loaded = described.with_parameters(&theta).unwrap();
    std::fs::write(&urdf, physid::io::urdf::floating_to_string(&loaded)).unwrap();
    urdf
}

#[test]
fn standing_still_the_feet_carry_the_robot_s_weight_and_the_trunk_rests() {
    // `still`: the posture held, no weight shifting. After the first second the four feet's
    // normal forces sum to the weight (45 kg) and the trunk does not move.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("still.csv");
    physid::api::floating::simulate_floating(&physid::api::floating::SimulateFloatingOptions {
        start: Default::default(),
        robot: physid::api::model::RobotOptions::new("cheetah3"),
        duration: 2.0,
        rate: 1000.0,
        seed: 1,
        trot: None,
        still: true,
        sensors: physid::sim::floating_sensors::Sensors::exact(),
        out: out.clone(),
    })
    .unwrap();
    let text = std::fs::read_to_string(&out).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let last: Vec<f64> = (text.lines().last().unwrap().split(','))
        .map(|v| v.parse().unwrap())
        .collect();
    let feet = ["fr_shank", "fl_shank", "hr_shank", "hl_shank"];
    let normal: f64 = feet
        .iter()
        .map(|f| last[col(&format!("force_{f}_z"))])
        .sum();
    let weight = 45.0 * physid::model::STANDARD_GRAVITY;
    assert!(
        (normal / weight - 1.0).abs() < 1e-3,
        "{normal} N of {weight}"
    );
    for f in feet {
        let share = last[col(&format!("force_{f}_z"))] / weight;
        assert!((0.15..0.35).contains(&share), "{f}: {share}");
    }
    for v in [
        "base_vx", "base_vy", "base_vz", "base_wx", "base_wy", "base_wz",
    ] {
        assert!(last[col(v)].abs() < 1e-3, "{v} = {}", last[col(v)]);
    }
    // Standing still and trotting are two different runs.
    let both = physid::api::floating::SimulateFloatingOptions {
        start: Default::default(),
        robot: physid::api::model::RobotOptions::new("cheetah3"),
        duration: 2.0,
        rate: 1000.0,
        seed: 1,
        trot: Some((0.15, 2.5)),
        still: true,
        sensors: Default::default(),
        out: dir.path().join("never.csv"),
    };
    let err = physid::api::floating::simulate_floating(&both).unwrap_err();
    assert!(err.to_string().contains("still and trot"), "{err}");
    assert!(!dir.path().join("never.csv").exists());
}

/// Which change `identify-floating` reads in the quadruped's log `data` (consistent set)
/// against `robot` (default: the built-in quadruped) or its fit to `baseline`.
fn floating_change(
    robot: Option<&std::path::Path>,
    data: &std::path::Path,
    baseline: Option<&std::path::Path>,
) -> physid::api::floating::DescriptionCheck {
    use physid::api::floating::{identify_floating, quadruped_feet, IdentifyFloatingOptions};
    let defaults = floating_options(data);
    let robot = robot.map_or(defaults.robot.clone(), |r| {
        physid::api::model::RobotOptions::new(r.to_str().unwrap())
    });
    identify_floating(&IdentifyFloatingOptions {
        robot,
        feet: quadruped_feet(&physid::model::quadruped::quadruped()),
        constraints: ConstraintSet::Consistent,
        baseline: baseline.map(|b| b.to_path_buf()),
        ..defaults
    })
    .unwrap()
    .change
}

#[test]
fn against_a_baseline_log_a_description_with_errors_names_the_payload_and_not_its_own_errors() {
    // A description with 10 % errors on every body's mass and inertia. Against it, an
    // unchanged robot's log differs (its own errors); against its fit to a baseline log of the
    // unchanged robot standing, the same robot standing again differs in nothing, 5 kg on the
    // trunk is named and weighed, and a trot (which the standing baseline hardly excites in the
    // directions it differs in) is set aside unnamed.
    let dir = tempfile::tempdir().unwrap();
    let truth = physid::model::quadruped::quadruped();
    let mut theta = truth.parameters();
    for (b, (_, column, _)) in physid::ident::Parameterized::inertial_bodies(&truth)
        .into_iter()
        .enumerate()
    {
        let factor = if b % 2 == 0 { 1.1 } else { 0.9 };
        for k in 0..10 {
            theta[column + k] *= factor;
        }
    }
    let described = dir.path().join("cad.urdf");
    let cad = truth.with_parameters(&theta).unwrap();
    std::fs::write(&described, physid::io::urdf::floating_to_string(&cad)).unwrap();
    let log = |robot: &str, seed: u64, trot: Option<(f64, f64)>| {
        let out = dir
            .path()
            .join(format!("{seed}_{}_{}.csv", robot.len(), trot.is_some()));
        physid::api::floating::simulate_floating(&physid::api::floating::SimulateFloatingOptions {
            start: Default::default(),
            robot: physid::api::model::RobotOptions::new(robot),
            duration: 6.0,
            rate: 1000.0,
            seed,
            trot,
            still: false,
            sensors: Default::default(),
            out: out.clone(),
        })
        .unwrap();
        out
    };
    let baseline = log("cheetah3", 1, None);
    let check = |data: &std::path::Path, baseline: Option<&std::path::Path>| {
        floating_change(Some(&described), data, baseline)
    };
    let unchanged = log("cheetah3", 2, None);
    let against_description = check(&unchanged, None);
    assert!(
        against_description.changed.is_some(),
        "{against_description:?}"
    );
    let against_baseline = check(&unchanged, Some(&baseline));
    assert!(against_baseline.changed.is_none(), "{against_baseline:?}");
    assert!(against_baseline.unseen_by_baseline.is_none());
    let loaded = loaded_quadruped(dir.path(), "trunk", 5.0, [0.1, 0.0, 0.08]);
    let payload = check(&log(loaded.to_str().unwrap(), 2, None), Some(&baseline));
    let named = payload.changed.as_ref().expect("the trunk named");
    assert_eq!(named.body, "trunk");
    assert!((named.mass - 5.0).abs() < 0.15, "{named:?}");
    assert!(payload.baseline_visibility.unwrap() > 0.5, "{payload:?}");
    let trot = check(&log("cheetah3", 2, Some((0.15, 2.5))), Some(&baseline));
    assert!(trot.changed.is_none(), "{trot:?}");
    let seen = trot.baseline_visibility.unwrap();
    assert!(
        seen < physid::api::floating::MIN_BASELINE_VISIBILITY,
        "{seen}"
    );
    assert!(trot.unseen_by_baseline.is_some());
}

#[test]
fn a_worn_knee_is_named_by_its_friction_against_the_description_and_a_baseline_not_as_a_body() {
    // The front right knee's friction raised (viscous +0.8 N m s/rad, Coulomb +3 N m): against
    // the exact description and against its fit to a standing baseline log of the unchanged
    // robot, the knee's friction is named with its size and no body is; the unchanged robot
    // standing again gets neither against the baseline.
    let dir = tempfile::tempdir().unwrap();
    let truth = physid::model::quadruped::quadruped();
    let names = truth.parameter_names();
    let column = |name: &str| names.iter().position(|n| n == name).unwrap();
    let mut theta = truth.parameters();
    theta[column("fr_knee_joint.B")] += 0.8;
    theta[column("fr_knee_joint.Bc")] += 3.0;
    let worn = dir.path().join("worn.urdf");
    let worn_robot = truth.with_parameters(&theta).unwrap();
    std::fs::write(&worn, physid::io::urdf::floating_to_string(&worn_robot)).unwrap();
    let log = |robot: &str, seed: u64| {
        let out = dir.path().join(format!("{seed}_{}.csv", robot.len()));
        floating_log_at(out, robot, (6.0, seed), Default::default())
    };
    let check = |data: &std::path::Path, baseline: Option<&std::path::Path>| {
        floating_change(None, data, baseline)
    };
    let baseline = log("cheetah3", 1);
    let worn_log = log(worn.to_str().unwrap(), 2);
    for against in [None, Some(baseline.as_path())] {
        let found = check(&worn_log, against);
        let knee = found
            .friction_changed
            .as_ref()
            .expect("a joint's friction named");
        assert_eq!(knee.joint, "fr_knee_joint", "{found:?}");
        assert!(
            ((knee.viscous + knee.coulomb) - 3.8).abs() < 0.2,
            "{knee:?}"
        );
        assert!(
            found.changed.is_none() && found.also_fit.is_empty(),
            "{found:?}"
        );
    }
    let unchanged = check(&log("cheetah3", 3), Some(&baseline));
    assert!(unchanged.friction_changed.is_none(), "{unchanged:?}");
    assert!(unchanged.changed.is_none(), "{unchanged:?}");
}

/// `path`'s CSV with column `name` scaled by `factor`, written to `out`.
fn scaled_column(path: &std::path::Path, name: &str, factor: f64, out: &std::path::Path) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let at = header.split(',').position(|h| h == name).unwrap();
    let mut scaled = vec![header.to_string()];
    for line in lines {
        let mut cells: Vec<String> = line.split(',').map(String::from).collect();
        cells[at] = (cells[at].parse::<f64>().unwrap() * factor).to_string();
        scaled.push(cells.join(","));
    }
    std::fs::write(out, scaled.join("\n") + "\n").unwrap();
}

#[test]
fn a_knee_torque_logged_at_85_percent_is_named_a_gain_not_a_body_or_friction() {
    // The front right knee's logged torque scaled by 0.85 (a current sensor's scale): against
    // the description the knee's gain is named, -0.15, and no body or friction; the same log
    // unscaled names nothing, and a payload's log names the body, not a gain.
    use physid::api::floating::identify_floating;
    let dir = tempfile::tempdir().unwrap();
    let log = |robot: &str, name: &str| {
        floating_log_at(dir.path().join(name), robot, (6.0, 3), Default::default())
    };
    let check = |data: &std::path::Path| identify_floating(&floating_options(data)).unwrap().change;
    let plain = log("cheetah3", "plain.csv");
    let scaled = dir.path().join("scaled.csv");
    scaled_column(&plain, "tau_fr_knee_joint", 0.85, &scaled);
    let found = check(&scaled);
    let gain = found.gain_changed.as_ref().expect("a gain named");
    assert_eq!(gain.joint, "fr_knee_joint", "{found:?}");
    assert!((gain.gain + 0.15).abs() < 0.01, "{gain:?}");
    assert!(
        found.changed.is_none() && found.friction_changed.is_none(),
        "{found:?}"
    );
    let unscaled = check(&plain);
    assert!(
        unscaled.gain_changed.is_none() && unscaled.changed.is_none(),
        "{unscaled:?}"
    );
    let loaded = loaded_quadruped(dir.path(), "fr_shank", 0.5, [0.0, 0.0, -0.1]);
    let payload = check(&log(loaded.to_str().unwrap(), "loaded.csv"));
    assert!(payload.gain_changed.is_none(), "{payload:?}");
    assert_eq!(
        payload.changed.as_ref().expect("the shank named").body,
        "fr_shank"
    );
}

#[test]
fn a_trotting_log_names_the_shank_that_carries_half_a_kilogram_and_no_body_when_unchanged() {
    // Trotting in place, default sensors, 6 s, identified from the unloaded description. On
    // unchanged logs the best body's change removes about 1 % of the residual (the filter's,
    // the contacts' and the smoothed friction's share, which any body absorbs a little of):
    // nothing is named. With 0.5 kg on the front right shank that body is named and weighed.
    let dir = tempfile::tempdir().unwrap();
    let trot = |robot: &str, seed: u64| {
        let out = dir.path().join(format!("trot_{seed}_{}.csv", robot.len()));
        physid::api::floating::simulate_floating(&physid::api::floating::SimulateFloatingOptions {
            start: Default::default(),
            robot: physid::api::model::RobotOptions::new(robot),
            duration: 6.0,
            rate: 1000.0,
            seed,
            trot: Some((0.15, 2.5)),
            still: false,
            sensors: Default::default(),
            out: out.clone(),
        })
        .unwrap();
        physid::api::floating::identify_floating(&floating_options(&out)).unwrap()
    };
    for seed in [1, 2] {
        let unchanged = trot("cheetah3", seed);
        let check = &unchanged.change;
        assert!(check.changed.is_none(), "seed {seed}: {check:?}");
        assert!(
            check.candidates[0].reduction < 0.5 * check.min_reduction,
            "{check:?}"
        );
    }
    let urdf = loaded_quadruped(dir.path(), "fr_shank", 0.5, [0.0, 0.0, -0.2]);
    let loaded = trot(urdf.to_str().unwrap(), 3);
    let change = loaded.change.changed.as_ref().expect("a body named");
    assert_eq!(change.body, "fr_shank", "{:?}", loaded.change);
    assert!((change.mass - 0.5).abs() < 0.1, "{change:?}");
    assert!(change.reduction > 0.3, "{change:?}");
}

/// The identifiability `identify-floating` reports: the robot's total mass is a base parameter
/// (the sum of every body's mass) that the log determines, within 0.1 kg of `truth_mass`,
/// while standing leaves single bodies' masses undetermined; every warning about a far mass
/// says why. (The standard errors take the rows as independent; the filtered signals are not,
/// so they understate: measured 49.963 ± 0.0037 kg of 50.)
fn what_the_log_determines(found: &physid::api::floating::FloatingIdentification, truth_mass: f64) {
    let idf = &found.identifiability;
    assert_eq!(idf.parameters, 274);
    assert_eq!(idf.unidentifiable_total, 274 - idf.rank);
    assert!((150..274).contains(&idf.rank), "rank {}", idf.rank);
    assert_eq!(idf.base.len(), idf.rank);
    let is_total = |e: &str| {
        let terms: Vec<&str> = e.split(" + ").collect();
        terms.len() == 25 && terms.iter().all(|t| t.ends_with(".m") && !t.contains(' '))
    };
    let total = (idf.base.iter())
        .find(|b| is_total(&b.expression))
        .unwrap_or_else(|| panic!("no base parameter is the total mass: {:?}", idf.base[0]));
    let said = format!("{} ± {} kg", total.value, total.standard_error);
    assert!(
        total.standard_error > 0.0 && total.standard_error < 0.1,
        "{said}"
    );
    assert!((total.value - truth_mass).abs() < 0.1, "{said}");
    assert!((total.value - found.identified_mass).abs() < 1e-6, "{said}");
    assert_eq!(found.mass_standard_errors.len(), found.bodies.len());
    let undetermined = (found.bodies.iter().zip(&found.mass_standard_errors))
        .filter(|(b, se)| !se.is_some_and(|e| e < b.pi[0].abs()))
        .count();
    assert!(undetermined > 20, "{undetermined} of 25 undetermined");
    for n in &found.notices {
        assert!(
            n.warning && n.text.contains("identified mass"),
            "{}",
            n.text
        );
        assert!(n.text.contains("the data do"), "{}", n.text);
    }
}

/// With joint torques alone (the contact forces projected out) the trunk's acceleration carries
/// the rows, and an estimator's velocity, differentiated, brings its noise into every one of
/// them: the robot comes out light (errors in the regressor shrink what it finds). The IMU's
/// accelerometer gives that acceleration without differentiating: the robot's 45 kg come back.
#[test]
fn with_joint_torques_alone_the_accelerometer_weighs_the_robot_where_differentiated_velocity_cannot(
) {
    use physid::api::floating::identify_floating;
    use physid::sim::floating_sensors::Sensors;
    let dir = tempfile::tempdir().unwrap();
    let weigh = |name: &str, accelerometer: bool| {
        let sensors = Sensors {
            accelerometer,
            ..Default::default()
        };
        let log = floating_log_at(dir.path().join(name), "cheetah3", (6.0, 3), sensors);
        let opts = physid::api::floating::IdentifyFloatingOptions {
            setting: physid::ident::floating::DataSetting::TorquesOnly,
            constraints: ConstraintSet::None,
            ..floating_options(&log)
        };
        identify_floating(&opts).unwrap().identified_mass
    };
    let truth = physid::model::quadruped::quadruped().total_mass();
    let (with, without) = (weigh("imu.csv", true), weigh("estimator.csv", false));
    assert!((with / truth - 1.0).abs() < 0.01, "{with} kg of {truth}");
    assert!(
        without < 0.95 * truth,
        "{without} kg of {truth}: the velocity noise no longer costs"
    );
}
