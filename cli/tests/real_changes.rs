//! A known change on real logs (issue 26): the KUKA LWR4+ run 3 with the torque of a 2 kg
//! solid fixed to the flange added (the payload's own inverse dynamics at the logged q, q̇, q̈),
//! diagnosed from a description identified on run 1, as files a robot writes (t, q, τ).

#[path = "../../tests/common/mod.rs"]
mod common;

use common::{physid, root};
use physid::bench::semireal::{self, Injection, Slot};
use physid::effect::{Backlash, Compliance, Payload, TimeDelay};
use physid::sim::scenario::EffectSpec;
use std::path::{Path, PathBuf};

/// The description: run 1 identified (consistent, viscous and Coulomb friction) into a URDF.
fn description(dir: &Path) -> PathBuf {
    description_of(dir, 1)
}

/// Run `r` identified (consistent, viscous and Coulomb friction) into a URDF.
fn description_of(dir: &Path, r: usize) -> PathBuf {
    let k = root().join("data/kuka_lwr4");
    let out = dir.join(if r == 1 {
        "described.urdf".to_string()
    } else {
        format!("described_{r}.urdf")
    });
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let args = [
        "identify".to_string(),
        "--data".into(),
        s(&k.join(format!("measurements_{r}.csv"))),
        "--robot".into(),
        s(&k.join("kuka_lwr4.urdf")),
        "--constraints".into(),
        "consistent".into(),
        "--friction".into(),
        "viscous,coulomb".into(),
        "--out-urdf".into(),
        s(&out),
    ];
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let (code, _, err) = physid(&refs);
    assert_eq!(code, 0, "{err}");
    out
}

/// Run `r` as a robot writes it (t, q, τ), with `mass` kg on the flange 6 cm out (0: none).
fn run(dir: &Path, r: usize, mass: f64, robot: &Path) -> PathBuf {
    let n = physid::io::load_robot(robot.to_str().unwrap())
        .unwrap()
        .dof();
    let injection = Injection {
        slot: if mass > 0.0 {
            Slot::Payload
        } else {
            Slot::Clean
        },
        spec: (mass > 0.0).then_some(EffectSpec::Payload(Payload {
            mass,
            com: [0.0, 0.0, 0.06],
            radius: 0.04,
            body: Some(n),
        })),
        magnitudes: vec![mass],
        body: Some(n - 1),
        visible: None,
    };
    changed_run(dir, r, &injection, &format!("{mass}kg"), robot)
}

/// Run `r` with `injection` applied, written as a robot writes it (t, q, τ).
fn changed_run(dir: &Path, r: usize, injection: &Injection, tag: &str, robot: &Path) -> PathBuf {
    let model = physid::io::load_robot(robot.to_str().unwrap()).unwrap();
    let src = root().join(format!("data/kuka_lwr4/measurements_{r}.csv"));
    let (logged, _, _) = physid::io::load_logged(&src, &model, &Default::default()).unwrap();
    let changed = semireal::inject(&logged, &model, injection);
    let path = dir.join(format!("run{r}_{tag}.csv"));
    std::fs::write(&path, semireal::logged_csv(&changed)).unwrap();
    path
}

/// A library effect of `kind` as `spec` gives it.
fn effect(kind: physid::diagnose::library::Kind, spec: EffectSpec) -> Injection {
    Injection {
        slot: Slot::Effect(kind),
        spec: Some(spec),
        magnitudes: vec![],
        body: None,
        visible: None,
    }
}

/// The logged torque lagging the motion by `samples` samples.
fn lag(samples: usize) -> Injection {
    effect(
        physid::diagnose::library::Kind::TimeDelay,
        EffectSpec::TimeDelay(TimeDelay { samples }),
    )
}

/// `path`'s rows but for samples `cut` (the header is row 0), as a log with a gap.
fn with_gap(path: &Path, cut: std::ops::Range<usize>) -> PathBuf {
    let text = std::fs::read_to_string(path).unwrap();
    let kept: Vec<&str> = text
        .lines()
        .enumerate()
        .filter(|(i, _)| !cut.contains(i))
        .map(|(_, l)| l)
        .collect();
    let out = path.with_extension("gap.csv");
    std::fs::write(&out, kept.join("\n") + "\n").unwrap();
    out
}

fn diagnose(robot: &Path, data: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["--description-uncertainty", "0.05"];
    args.extend(extra);
    diagnose_stating(robot, data, &args).0
}

/// The diagnosis's JSON and its stderr, with `extra` flags only.
fn diagnose_stating(robot: &Path, data: &Path, extra: &[&str]) -> (serde_json::Value, String) {
    let mut args = vec![
        "diagnose",
        "--robot",
        robot.to_str().unwrap(),
        "--data",
        data.to_str().unwrap(),
        "--json",
    ];
    args.extend(extra);
    let (code, out, err) = physid(&args);
    assert_eq!(code, 0, "{err}");
    (serde_json::from_str(&out).unwrap(), err)
}

/// The ladder's steps (after the two fixed rungs, before the re-identified one).
fn steps(d: &serde_json::Value) -> Vec<String> {
    let rungs = d["ladder"]["rungs"].as_array().unwrap();
    rungs[2..rungs.len() - 1]
        .iter()
        .map(|r| r["step"].as_str().unwrap().to_string())
        .collect()
}

/// Whether the diagnosis reads any body change as a payload.
fn claims_a_payload(d: &serde_json::Value) -> bool {
    d["ladder"]["bodies"]
        .as_array()
        .unwrap()
        .iter()
        .any(|b| b["payload"].as_bool() == Some(true))
}

/// The payload found on the flange or the body before it (the data tell them apart only by
/// the inertia about the last axis), kg.
fn flange_payload(d: &serde_json::Value) -> Option<f64> {
    d["ladder"]["bodies"]
        .as_array()
        .unwrap()
        .iter()
        .find(|b| {
            b["payload"].as_bool() == Some(true)
                && ["lwr_7_link", "lwr_6_link"].contains(&b["body"].as_str().unwrap())
        })
        .and_then(|b| b["mass"].as_f64())
}

#[test]
fn a_payload_on_the_real_arm_is_named_first_and_weighed_and_the_control_claims_none() {
    let dir = tempfile::tempdir().unwrap();
    let robot = description(dir.path());
    let report = dir.path().join("loaded_report");
    let loaded = diagnose(
        &robot,
        &run(dir.path(), 3, 2.0, &robot),
        &["--report", report.to_str().unwrap()],
    );
    let control = diagnose(&robot, &run(dir.path(), 3, 0.0, &robot), &[]);
    let (sl, sc) = (steps(&loaded), steps(&control));
    eprintln!("loaded: {sl:?}\ncontrol: {sc:?}");
    eprintln!("bodies: {}", loaded["ladder"]["bodies"]);
    assert!(sl[0].starts_with("+ payload on"), "{sl:?}");
    let mass = flange_payload(&loaded).expect("a payload on the flange");
    assert!((mass - 2.0).abs() <= 0.15 * 2.0, "mass {mass}");
    // A body the step is ambiguous with carries the mass it would add in the step's place: on
    // the wrist link before the flange (told apart only by the inertia about the last axis)
    // the same 2 kg.
    let first = &loaded["ladder"]["rungs"][2];
    let (tied, masses) = (
        first["ambiguous_with"].as_array().unwrap(),
        first["ambiguous_mass"].as_array().unwrap(),
    );
    assert_eq!(tied.len(), masses.len());
    for (name, m) in tied.iter().zip(masses) {
        let name = name.as_str().unwrap();
        let m = m.as_f64().unwrap_or_else(|| panic!("{name}: no mass"));
        eprintln!("tied: {name} {m:+.3} kg");
        if name.ends_with("lwr_6_link") || name.ends_with("lwr_7_link") {
            assert!((m - 2.0).abs() <= 0.15 * 2.0, "{name}: {m} kg");
        }
    }
    // The Markdown report says it too: the ambiguity group with its masses, the payload weighed.
    let md = std::fs::read_to_string(report.join("report.md")).unwrap();
    for (name, m) in tied.iter().zip(masses) {
        let alternative = format!(
            "`{} ({:+.2} kg)`",
            name.as_str().unwrap(),
            m.as_f64().unwrap()
        );
        assert!(md.contains(&alternative), "{alternative} not in the report");
    }
    let on = loaded["ladder"]["bodies"][0]["body"].as_str().unwrap();
    assert!(
        md.contains(&format!("on `{on}`: +")),
        "no weighed body in the report"
    );
    assert!(
        !claims_a_payload(&control),
        "{}",
        control["ladder"]["bodies"]
    );
}

#[test]
fn a_lag_of_the_logged_torque_on_the_real_arm_is_named_first_and_timed() {
    // 20 samples (0.1 s at the log's 200 Hz) between the torque and the motion: the description
    // predicts run 3 at twice its untouched error, yet the model re-identified on the data takes
    // the lag into its friction and parameters (cross-validation then names a spring); the
    // ladder from the description offers the delay whatever cross-validation chose.
    let dir = tempfile::tempdir().unwrap();
    let robot = description(dir.path());
    let samples = 20;
    let lagged = changed_run(dir.path(), 3, &lag(samples), "lag20", &robot);
    let d = diagnose(&robot, &lagged, &[]);
    let s = steps(&d);
    eprintln!("lagged: {s:?}");
    assert_eq!(s[0], "+ time_delay", "{s:?}");
    let delay = found_delay(&d).expect("the delay among the effects");
    let dt = 0.005; // the KUKA logs are written at 200 Hz
    let truth = samples as f64 * dt;
    eprintln!("delay {delay} s against {truth} s");
    assert!(
        (delay - truth).abs() <= 0.25 * truth,
        "delay {delay} s, lag {truth} s"
    );
    // The same run untouched: no delay anywhere in the ladder.
    let control = diagnose(&robot, &run(dir.path(), 3, 0.0, &robot), &[]);
    let sc = steps(&control);
    assert!(!sc.iter().any(|x| x.contains("time_delay")), "{sc:?}");
}

/// The delay found in `d` (s).
fn found_delay(d: &serde_json::Value) -> Option<f64> {
    d["effects"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["kind"] == "time_delay")
        .map(|e| e["magnitudes"][0]["value"].as_f64().unwrap())
}

#[test]
fn a_lag_on_a_real_log_with_a_gap_is_found_as_without_one() {
    // Logs have gaps: the same 20-sample lag with 250 samples (1.25 s) missing after sample
    // 2000 is split into two runs, which the diagnosis joins end to end. Differentiated across
    // that seam, the delay's column (the description's torque rate) once spiked there, and on
    // the held-out data the delay raised the error (the ladder then named a body change, or
    // nothing).
    let dir = tempfile::tempdir().unwrap();
    let robot = description(dir.path());
    let lagged = changed_run(dir.path(), 3, &lag(20), "lag20", &robot);
    let gapped = with_gap(&lagged, 2001..2251);
    let (d, err) = diagnose_stating(&robot, &gapped, &["--description-uncertainty", "0.05"]);
    assert!(err.contains("split into 2 runs"), "{err}");
    let s = steps(&d);
    eprintln!("lagged with a gap: {s:?}");
    assert_eq!(s[0], "+ time_delay", "{s:?}");
    let delay = found_delay(&d).expect("the delay among the effects");
    assert!(
        (delay - 0.1).abs() <= 0.25 * 0.1,
        "delay {delay} s, lag 0.1 s"
    );
}

#[test]
fn a_compliant_transmission_and_backlash_on_the_real_arm_are_named_first() {
    // The encoder reads q + τ/k (k = 400 N m/rad, joint 2's deflection about 0.05 rad), or a
    // dead zone of 0.05 rad: q and its derivatives shift by the processed torque. The columns
    // process the logged torque as the pipeline processed q, over the same samples: until
    // 2026-11-27 they were zeroed for 3/f_c = 1.5 s at every end of the diagnosis's own
    // processing (the trimmed run's ends and the hold-out cut, a quarter of these data), the
    // compliance candidate then raised the held-out error, and a body change or a spring was
    // named instead.
    use physid::diagnose::library::Kind;
    let dir = tempfile::tempdir().unwrap();
    let robot = description(dir.path());
    let n = 7;
    // Run 3 with `injection`, its ladder's first step `want`; the file written.
    let named_first = |injection: Injection, tag: &str, want: &str| -> PathBuf {
        let path = changed_run(dir.path(), 3, &injection, tag, &robot);
        let s = steps(&diagnose(&robot, &path, &[]));
        eprintln!("{tag}: {s:?}");
        assert_eq!(s[0], want, "{s:?}");
        path
    };
    let compliant = EffectSpec::Compliance(Compliance {
        stiffness: vec![400.0; n],
    });
    let path = named_first(effect(Kind::Compliance, compliant), "k400", "+ compliance");
    // The same with 250 samples missing: two runs, each processed with its own trimmed ends.
    let (d, err) = diagnose_stating(
        &robot,
        &with_gap(&path, 2001..2251),
        &["--description-uncertainty", "0.05"],
    );
    assert!(err.contains("split into 2 runs"), "{err}");
    let s = steps(&d);
    eprintln!("compliant, with a gap: {s:?}");
    assert_eq!(s[0], "+ compliance", "{s:?}");
    let backlash = EffectSpec::Backlash(Backlash {
        width: vec![0.05; n],
    });
    named_first(effect(Kind::Backlash, backlash), "b005", "+ backlash");
    // Untouched, neither is claimed.
    let control = steps(&diagnose(&robot, &run(dir.path(), 3, 0.0, &robot), &[]));
    eprintln!("control: {control:?}");
    assert!(
        !control
            .iter()
            .any(|x| x.contains("compliance") || x.contains("backlash")),
        "{control:?}"
    );
}

#[test]
fn a_description_stated_too_loose_is_warned_about_and_the_payload_is_then_not_named() {
    // At 100 % the description's parameters take in the 2 kg payload before the ladder offers
    // it (measured: a spring comes first); the warning says so, and 5 % gives no warning.
    let dir = tempfile::tempdir().unwrap();
    let robot = description(dir.path());
    let loaded = run(dir.path(), 3, 2.0, &robot);
    let loose = [
        "--description-uncertainty",
        "1",
        "--no-description-information",
    ];
    let (d, err) = diagnose_stating(&robot, &loaded, &loose);
    assert!(
        err.contains(
            "warning: --description-uncertainty 1: the description's parameters may move by 100 %"
        ),
        "{err}"
    );
    let s = steps(&d);
    eprintln!("stated 100 %: {s:?}");
    assert!(!s[0].starts_with("+ payload"), "{s:?}");
    let stated = [
        "--description-uncertainty",
        "0.05",
        "--no-description-information",
    ];
    let (d, err) = diagnose_stating(&robot, &loaded, &stated);
    assert!(!err.contains("may move by"), "{err}");
    assert!(steps(&d)[0].starts_with("+ payload on"), "{:?}", steps(&d));
}

/// `path` (`t, q1..qn, tau1..taun`, as `logged_csv` writes it) rewritten as a driver logs it:
/// columns named by joint (`q_<joint>`, `tau_<joint>`) in reverse order, a gripper joint the
/// robot does not have, every stamp moved by up to ±1 ms (a fixed pseudo-random sequence: the
/// KUKA logs at 5 ms) and the rows `cut` (0 is the first sample) missing.
fn as_a_driver_writes_it(path: &Path, joints: &[String], cut: std::ops::Range<usize>) -> PathBuf {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let n = joints.len();
    let mut out = String::from("t,q_gripper_finger,tau_gripper_finger");
    for j in joints.iter().rev() {
        out += &format!(",tau_{j},q_{j}");
    }
    out.push('\n');
    let text = std::fs::read_to_string(path).unwrap();
    for (k, line) in text.lines().skip(1).enumerate() {
        let jitter: f64 = rng.random_range(-1e-3..1e-3);
        if cut.contains(&k) {
            continue;
        }
        let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        out += &format!("{},0.01,{}", v[0] + jitter, 0.2 * (k as f64 * 0.01).sin());
        for j in (0..n).rev() {
            out += &format!(",{},{}", v[1 + n + j], v[1 + j]);
        }
        out.push('\n');
    }
    let written = path.with_extension("driver.csv");
    std::fs::write(&written, out).unwrap();
    written
}

#[test]
fn the_payload_is_named_and_weighed_from_a_log_written_as_a_driver_writes_it() {
    // The KUKA case (2 kg on the flange of run 3, described by run 1) with what robots'
    // logs have and the KUKA files do not: named columns in another order, a joint the robot
    // does not have, stamps jittered by ±1 ms on a 5 ms period, 250 samples (1.25 s) missing,
    // and no q̇ or q̈. The answer is the same: the payload first, on the flange or the link
    // before it, within 15 %; the control written the same way claims none.
    let dir = tempfile::tempdir().unwrap();
    let robot = description(dir.path());
    let joints = physid::io::load_robot(robot.to_str().unwrap())
        .unwrap()
        .joint_names();
    let shaped =
        |mass| as_a_driver_writes_it(&run(dir.path(), 3, mass, &robot), &joints, 2000..2250);
    let (loaded, err) =
        diagnose_stating(&robot, &shaped(2.0), &["--description-uncertainty", "0.05"]);
    // What the reader made of it: the extra joint left out, the gap a seam, the jitter seen.
    for said in [
        "left out: gripper_finger",
        "split into 2 runs",
        "time stamps scatter",
    ] {
        assert!(err.contains(said), "'{said}' not said: {err}");
    }
    let sl = steps(&loaded);
    eprintln!("loaded, as a driver writes it: {sl:?}");
    assert!(sl[0].starts_with("+ payload on"), "{sl:?}");
    let mass = flange_payload(&loaded).expect("a payload on the flange");
    eprintln!("{err}\nweighed: {mass:.3} kg");
    assert!((mass - 2.0).abs() <= 0.15 * 2.0, "mass {mass}");
    let control = diagnose(&robot, &shaped(0.0), &[]);
    assert!(
        !claims_a_payload(&control),
        "{}",
        control["ladder"]["bodies"]
    );
}

#[test]
fn against_a_baseline_run_the_payload_is_named_and_nothing_else() {
    let dir = tempfile::tempdir().unwrap();
    let robot = description(dir.path());
    let before = run(dir.path(), 2, 0.0, &robot);
    let before = before.to_str().unwrap().to_string();
    let (d, err) = diagnose_stating(
        &robot,
        &run(dir.path(), 3, 2.0, &robot),
        &[
            "--baseline-data",
            &before,
            "--description-uncertainty",
            "0.05",
        ],
    );
    // Run 3 is another trajectory than run 2's, about twice as fast: said, joint by joint.
    assert!(
        err.contains("warning: the baseline runs move unlike the runs after the change")
            && err.contains("lwr_4_joint"),
        "{err}"
    );
    let s = steps(&d);
    eprintln!(
        "against the baseline: {s:?}; bodies {}",
        d["ladder"]["bodies"]
    );
    // The payload, then at most the friction re-identified (run 3 is twice as fast as the
    // baseline: a friction the baseline's speeds fixed) and nothing else: until the description
    // test held physical signs a negative joint armature followed it, and until the payload was
    // a point mass first, a ten-parameter change took the friction's share with second moments
    // of −0.42 kg m² (no body has them).
    assert!(s[0].starts_with("+ payload on"), "{s:?}");
    assert!(
        s[1..].iter().all(|x| x == "friction re-identified"),
        "{s:?}"
    );
    let kinds: Vec<&str> = d["effects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["kind"].as_str().unwrap())
        .collect();
    assert!(!kinds.contains(&"rotor_inertia"), "{kinds:?}");
    let bodies = d["ladder"]["bodies"].as_array().unwrap();
    assert_eq!(bodies.len(), 1, "{bodies:?}");
    let mass = flange_payload(&d).expect("a payload on the flange");
    assert!((mass - 2.0).abs() <= 0.15 * 2.0, "mass {mass}");
    assert!(is_a_body(&bodies[0]["pi"]), "{}", bodies[0]["pi"]);
}

/// Whether ten parameters `[m, h, Ixx, Ixy, Ixz, Iyy, Iyz, Izz]` (inertia about the frame's
/// origin) are those of a body: `J = [[tr(I)/2 − I, h], [hᵀ, m]] ⪰ 0` (its smallest eigenvalue
/// above −10⁻⁹ of its trace: a point mass's `J` has rank one).
fn is_a_body(pi: &serde_json::Value) -> bool {
    let p: Vec<f64> = pi
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let i = nalgebra::Matrix3::new(p[4], p[5], p[6], p[5], p[7], p[8], p[6], p[8], p[9]);
    let sigma = nalgebra::Matrix3::identity() * (i.trace() / 2.0) - i;
    let mut j = nalgebra::Matrix4::zeros();
    j.fixed_view_mut::<3, 3>(0, 0).copy_from(&sigma);
    for k in 0..3 {
        j[(k, 3)] = p[1 + k];
        j[(3, k)] = p[1 + k];
    }
    j[(3, 3)] = p[0];
    j.symmetric_eigenvalues().min() >= -1e-9 * j.trace()
}

#[test]
fn a_payload_whose_mass_the_run_cannot_weigh_is_named_without_a_mass() {
    // 2.1 kg on lwr_3_link of run 1, described by run 2 (seed 2's first draw of semi-real
    // case 24). The link's origin lies on the shoulder's axes: the slow KUKA runs see the
    // payload's first moment in the gravity torque, not its mass (the benchmark's Cramér–Rao
    // bound on it is 22 %, and the benchmark now draws such a payload again). The diagnosis
    // must still name a payload first, list lwr_3_link with it, and state no mass for it
    // rather than one the data do not hold. (On run 3 described by run 1 a spring comes first
    // instead: it also takes a standing difference on lwr_0_joint the payload cannot.)
    let dir = tempfile::tempdir().unwrap();
    let robot = description_of(dir.path(), 2);
    let shoulder = Injection {
        slot: Slot::Payload,
        spec: Some(EffectSpec::Payload(Payload {
            mass: 2.1,
            com: [-0.021, -0.008, -0.025],
            radius: 0.04,
            body: Some(3),
        })),
        magnitudes: vec![2.1],
        body: Some(2),
        visible: None,
    };
    let data = changed_run(dir.path(), 1, &shoulder, "shoulder", &robot);
    let d = diagnose(&robot, &data, &[]);
    let first = &d["ladder"]["rungs"][2];
    eprintln!("first step: {first}");
    assert_eq!(first["kind"], "payload", "{first}");
    let tied: Vec<&str> = first["ambiguous_with"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    let chosen = first["step"].as_str().unwrap();
    if chosen.ends_with("lwr_3_link") {
        // Chosen itself: no standard error (the mass unseen), or one the ladder's own rule says
        // does not hold the mass.
        let body = &d["ladder"]["bodies"][0];
        let mass = body["mass"].as_f64().unwrap();
        let se = body["mass_se"].as_f64().unwrap_or(f64::INFINITY);
        assert!(
            !physid::diagnose::ladder::mass_determined(mass, se),
            "{body}"
        );
    } else if let Some(i) = tied.iter().position(|t| t.ends_with("lwr_3_link")) {
        assert!(first["ambiguous_mass"][i].is_null(), "{first}");
    } else {
        // Said beside the step as not claimed: a body step must weigh its mass.
        let said = first["unweighed"].as_array().unwrap();
        let lwr_3 = said
            .iter()
            .find(|u| u["name"].as_str().unwrap().ends_with("lwr_3_link"))
            .unwrap_or_else(|| panic!("lwr_3_link neither chosen, tied nor said: {first}"));
        assert!(lwr_3["mass"].is_null(), "{first}");
    }
}

#[test]
fn the_description_s_own_information_from_its_sidecar_alone_weighs_the_payload() {
    // identify --out-urdf wrote the fit's information matrix into the sidecar: with no
    // --description-uncertainty the diagnosis runs the ladder on it (plus 5 % stated).
    let dir = tempfile::tempdir().unwrap();
    let robot = description(dir.path());
    let loaded = run(dir.path(), 3, 2.0, &robot);
    let (d, err) = diagnose_stating(&robot, &loaded, &[]);
    assert!(
        err.contains("described.physid.toml: the description's uncertainty from its identification's information matrix (5027 samples"),
        "{err}"
    );
    assert!(err.contains("plus 5 % stated"), "{err}");
    let s = steps(&d);
    eprintln!("information alone: {s:?}; bodies {}", d["ladder"]["bodies"]);
    assert!(s[0].starts_with("+ payload on"), "{s:?}");
    let mass = flange_payload(&d).expect("a payload on the flange");
    assert!((mass - 2.0).abs() <= 0.15 * 2.0, "mass {mass}");
    // Told to ignore it, and given no uncertainty, there is no ladder from the description.
    let (d, err) = diagnose_stating(&robot, &loaded, &["--no-description-information"]);
    assert!(!err.contains("information matrix"), "{err}");
    assert!(d["ladder"].is_null(), "{}", d["ladder"]);
    // The URDF copied without its sidecar: said, not silently held by the stated 5 % alone.
    let copy = dir.path().join("copied.urdf");
    std::fs::copy(&robot, &copy).unwrap();
    let (_, err) = diagnose_stating(&copy, &loaded, &["--description-uncertainty", "0.05"]);
    assert!(
        err.contains("copied.urdf: written by physid identify with its information matrix in")
            && err.contains("copied.physid.toml, which is not there"),
        "{err}"
    );
    let (_, err) = diagnose_stating(&robot, &loaded, &["--description-uncertainty", "0.05"]);
    assert!(!err.contains("which is not there"), "{err}");
}

/// The semi-real benchmark on the three KUKA runs, seed 1, with `extra` flags (which cases,
/// which mode), its cases kept: the temporary directory (kept alive by the caller), the kept
/// cases' folder and the case table.
fn kept_semi_real_cases(extra: &[&str]) -> (tempfile::TempDir, PathBuf, String) {
    kept_semi_real_cases_of("1", extra)
}

/// [`kept_semi_real_cases`] with the benchmark's `seed`.
fn kept_semi_real_cases_of(seed: &str, extra: &[&str]) -> (tempfile::TempDir, PathBuf, String) {
    let k = root().join("data/kuka_lwr4");
    let runs: Vec<String> = (1..=3)
        .map(|r| {
            k.join(format!("measurements_{r}.csv"))
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let (keep, out) = (dir.path().join("keep"), dir.path().join("out"));
    let urdf = k.join("kuka_lwr4.urdf");
    let runs = runs.join(",");
    let mut args = vec![
        "blind",
        "--real",
        &runs,
        "--real-robot",
        urdf.to_str().unwrap(),
        "--cases",
        "55",
        "--seed",
        seed,
        "--keep-cases",
        keep.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(extra);
    let (code, _, err) = physid(&args);
    assert_eq!(code, 0, "{err}");
    let table = std::fs::read_to_string(out.join("cases.csv")).unwrap();
    (dir, keep, table)
}

/// A kept semi-real case diagnosed again from its files (with the benchmark's description
/// uncertainty and `extra` flags), its report written beside them: the JSON and `report.md`.
fn rediagnosed(case: &Path, extra: &[&str]) -> (serde_json::Value, String) {
    let report = case.join("report");
    let mut args = vec![
        "--description-uncertainty",
        "0.05",
        "--report",
        report.to_str().unwrap(),
    ];
    args.extend(extra);
    let (d, _) = diagnose_stating(&case.join("robot.urdf"), &case.join("data.csv"), &args);
    let text = std::fs::read_to_string(report.join("report.md")).unwrap();
    (d, text)
}

/// A kept "what changed" case (its `row` of the case `table`) diagnosed again from its files
/// with its baseline run, the KUKA run its description was identified on.
fn rediagnosed_in_what_changed_mode(
    keep: &Path,
    table: &str,
    row: &str,
) -> (serde_json::Value, String) {
    let case = format!("case{}", csv_field(row, 0));
    let baseline = root()
        .join("data/kuka_lwr4")
        .join(field(table, row, "described_by"));
    rediagnosed(
        &keep.join(case),
        &["--baseline-data", baseline.to_str().unwrap()],
    )
}

/// The ladder's estimate of `kind` in a diagnosis's JSON (`described_effects`).
fn described_effect<'a>(d: &'a serde_json::Value, kind: &str) -> &'a serde_json::Value {
    d["described_effects"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["kind"] == kind)
        .unwrap_or_else(|| panic!("no {kind} among the ladder's estimates"))
}

/// The change injected into the kept case in `case` (its `injected.json`, the truth).
fn injected(case: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(case.join("injected.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["schema"], "physid.injection/1");
    v
}

/// The first explanation of the first step in a case table's `found` field.
fn first_found(found: &str) -> &str {
    found
        .split(", ")
        .next()
        .unwrap()
        .split(" | ")
        .next()
        .unwrap()
}

#[test]
fn a_kept_semi_real_case_re_diagnosed_from_its_files_is_the_benchmark_s_case() {
    // The case's description carries its information in the sidecar beside its URDF, which
    // the command reads back, and the benchmark diagnoses the case as the command does (the
    // effect columns at the pipeline's cutoff, over the samples the pipeline's processing
    // saw): cases 13 (2.9 kg on lwr_4_link) and 43 (a compliance; until 2026-11-27 read as a
    // payload on lwr_4_link, its columns zeroed over a quarter of the data) of seed 1
    // re-diagnosed from their files name what the benchmark named first.
    let (_dir, keep, table) =
        kept_semi_real_cases(&["--description-uncertainty", "0.05", "--only", "13,43"]);
    let rows: Vec<&str> = table.lines().skip(1).collect();
    assert!(
        rows[0].starts_with("13,") && rows[0].contains(",payload,lwr_4_link,"),
        "{}",
        rows[0]
    );
    assert!(
        rows[1].starts_with("43,") && rows[1].contains(",compliance,"),
        "{}",
        rows[1]
    );
    for row in rows {
        let case = keep.join(format!("case{}", row.split(',').next().unwrap()));
        let side = std::fs::read_to_string(case.join("robot.physid.toml")).unwrap();
        assert!(side.contains("\n[information]\n"), "{side}");
        let (d, err) = diagnose_stating(
            &case.join("robot.urdf"),
            &case.join("data.csv"),
            &["--description-uncertainty", "0.05"],
        );
        assert!(err.contains("information matrix"), "{err}");
        let s = steps(&d);
        let found = field(&table, row, "found");
        assert_eq!(s[0], first_found(&found), "{s:?} vs {found}");
        let injected = field(&table, row, "injected");
        let named = if injected == "payload" {
            "+ payload on lwr_4_link"
        } else {
            "+ compliance"
        };
        assert_eq!(s[0], named, "{injected}");
    }
}

/// The field of a case table's `row` in the column the table's header names `name`.
fn field(table: &str, row: &str, name: &str) -> String {
    let header = table.lines().next().unwrap();
    let i = header
        .split(',')
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("no column {name} in {header}"));
    csv_field(row, i)
}

/// Field `i` of a CSV row (quotes around fields that hold commas).
fn csv_field(row: &str, i: usize) -> String {
    let (mut fields, mut cur, mut quoted) = (vec![], String::new(), false);
    for c in row.chars() {
        match c {
            '"' => quoted = !quoted,
            ',' if !quoted => fields.push(std::mem::take(&mut cur)),
            _ => cur.push(c),
        }
    }
    fields.push(cur);
    fields[i].clone()
}

#[test]
fn a_spring_yields_to_a_payload_and_an_offset_that_fit_better_together() {
    // Seed 2, case 46: 0.6 kg on lwr_6_link of run 2, whose description (identified on run 3)
    // it differs from by a standing torque offset as well. A spring (an offset and a stiffness
    // per joint: 14 columns) took 61.6 % of the held-out mean square, a point mass 51.8 %, the
    // offset alone 14.5 %, and the point mass with the offset 85.1 % in 11 columns: the spring
    // was named first, the payload second. Case 10, a compliance on run 2: the spring first too.
    let (_dir, _keep, table) = kept_semi_real_cases_of("2", &["--only", "10,46"]);
    let row = |case: &str| {
        let prefix = format!("{case},");
        table
            .lines()
            .find(|r| r.starts_with(&prefix))
            .unwrap()
            .to_string()
    };
    let (payload, compliance) = (row("46"), row("10"));
    assert!(payload.contains(",payload,lwr_6_link,"), "{payload}");
    let found = field(&table, &payload, "found");
    assert!(
        first_found(&found).starts_with("+ payload on lwr_"),
        "{found}"
    );
    assert!(found.contains("+ torque_offset"), "{found}");
    // The spring is said beside the step it gave way to.
    let beside = field(&table, &payload, "first_also_fit");
    assert!(beside.split(" | ").any(|x| x == "spring"), "{beside}");
    assert!(compliance.contains(",compliance,"), "{compliance}");
    let found = field(&table, &compliance, "found");
    assert_eq!(first_found(&found), "+ compliance", "{found}");
}

#[test]
fn a_kept_semi_real_case_in_the_what_changed_mode_is_the_command_s_case() {
    // The "what changed" mode diagnoses a case as `physid diagnose --baseline-data` does: the
    // baseline the run its description was identified on, the effect columns at the data
    // pipeline's cutoff. Case 9 of seed 1 (backlash on run 1, the description from run 2) was
    // read as a change of lwr_2_link while its torque was processed at 20 Hz against q̇, q̈
    // derived at 2 Hz; the command named backlash first.
    let (_dir, keep, table) = kept_semi_real_cases(&["--real-baseline", "--only", "9"]);
    let row = table.lines().nth(1).unwrap();
    assert!(row.starts_with("9,") && row.contains(",backlash,"), "{row}");
    let baseline = root()
        .join("data/kuka_lwr4")
        .join(field(&table, row, "described_by"));
    let case = keep.join("case9");
    let d = diagnose(
        &case.join("robot.urdf"),
        &case.join("data.csv"),
        &["--baseline-data", baseline.to_str().unwrap()],
    );
    let s = steps(&d);
    let found = field(&table, row, "found");
    eprintln!("command: {s:?}; benchmark: {found}");
    assert_eq!(s[0], first_found(&found), "{s:?} vs {found}");
    assert_eq!(s[0], "+ backlash");
}

#[test]
fn in_the_what_changed_mode_a_payload_is_not_passed_over_for_a_gain_that_explains_less() {
    // Case 25 of seed 1 (1.9 kg on lwr_7_link of run 2, run 3 the baseline): the payload takes
    // nearly all of the held-out error, a torque gain on every joint less (it leaves several
    // times what the payload leaves). Until 2026-11-27 the two were tied by their reductions
    // alone (within 10 %) and the gain was named first for its fewer columns.
    let (_dir, _keep, table) = kept_semi_real_cases(&["--real-baseline", "--only", "25"]);
    let row = table.lines().nth(1).unwrap();
    assert!(
        row.starts_with("25,") && row.contains(",payload,lwr_7_link,"),
        "{row}"
    );
    let found = field(&table, row, "found");
    assert_eq!(first_found(&found), "+ payload on lwr_7_link", "{found}");
    assert!(!found.contains("torque_gain"), "{found}");
}

#[test]
fn a_torque_offset_on_the_real_arm_is_weighed_from_the_description_with_bounded_errors() {
    // Offsets of 1–2 N m added to run 3's logged torque. The ladder's estimate from the
    // description carries each joint's value; until 2026-11-27 a spring chosen after the
    // offset split the constant term with it (the two columns are one), the offsets came out
    // at half their size with standard errors of 10⁴ N m, and the benchmark read the
    // cross-validated estimate instead, which the re-identified model had partly absorbed.
    use physid::diagnose::library::Kind;
    use physid::effect::TorqueOffset;
    let dir = tempfile::tempdir().unwrap();
    let robot = description(dir.path());
    let offset = vec![1.5, -2.0, 2.0, -1.5, 1.5, -1.0, 1.0];
    let spec = EffectSpec::TorqueOffset(TorqueOffset {
        offset: offset.clone(),
    });
    let path = changed_run(
        dir.path(),
        3,
        &effect(Kind::TorqueOffset, spec),
        "off",
        &robot,
    );
    let report = dir.path().join("report");
    let d = diagnose(&robot, &path, &["--report", report.to_str().unwrap()]);
    let s = steps(&d);
    eprintln!("offset: {s:?}");
    assert_eq!(s[0], "+ torque_offset", "{s:?}");
    let e = described_effect(&d, "torque_offset");
    let magnitudes = e["magnitudes"].as_array().unwrap();
    assert_eq!(magnitudes.len(), offset.len());
    for (m, truth) in magnitudes.iter().zip(&offset) {
        let (value, se) = (m["value"].as_f64().unwrap(), m["se"].as_f64().unwrap());
        eprintln!("{}: {value:.3} ± {se:.3} (injected {truth})", m["joint"]);
        // Bounded: a joint whose offset a freed body's gravity can mimic has an error of about
        // 1 N m; the split with a spring's constant had 10⁴.
        assert!(se.is_finite() && se > 0.0 && se < 2.0, "{m}");
        // Within the run's own standing offset (the control's, up to 0.9 N m) of the truth.
        assert!((value - truth).abs() < 1.0, "{m}");
    }
    // The report (one section model behind the text, Markdown and HTML) shows the estimate
    // from the description.
    let md = std::fs::read_to_string(report.join("report.md")).unwrap();
    assert!(
        md.contains("`torque_offset` from the description: offset"),
        "{md}"
    );
}

#[test]
fn in_the_what_changed_mode_a_mass_later_steps_trade_off_with_is_stated_as_weighed_at_its_step() {
    // Case 2 of seed 1: 2.8 kg on lwr_5_link of run 3, the baseline run 1. The payload is named
    // first and weighed within 15 % at its step; a torque gain freed after it trades off with
    // its mass (the fit with every explanation free put 8.2 kg on the body, 1.7 kg standard
    // error, and until 2026-11-27 that was the mass stated). The benchmark's table and the
    // command's report state the mass of the payload's step and say the later fit moved it.
    let (_dir, keep, table) = kept_semi_real_cases(&["--real-baseline", "--only", "2"]);
    let row = table.lines().nth(1).unwrap();
    assert!(row.starts_with("2,"), "{row}");
    assert_eq!(field(&table, row, "injected_body"), "lwr_5_link");
    let found = field(&table, row, "found");
    assert_eq!(first_found(&found), "+ payload on lwr_5_link", "{found}");
    let number = |name: &str| field(&table, row, name).parse::<f64>().unwrap();
    let (truth, stated, last) = (
        number("injected_mass"),
        number("payload_mass"),
        number("payload_mass_last"),
    );
    eprintln!("true {truth} kg; stated {stated}, with later steps free {last}");
    assert!(
        (stated - truth).abs() <= 0.15 * truth,
        "{stated} vs {truth}"
    );
    let (d, text) = rediagnosed_in_what_changed_mode(&keep, &table, row);
    let body = &d["ladder"]["bodies"][0];
    assert_eq!(body["body"], "lwr_5_link", "{body}");
    assert_eq!(body["payload"], true, "{body}");
    let number = |v: &serde_json::Value| v.as_f64().unwrap();
    let (mass, se) = (number(&body["mass"]), number(&body["mass_se"]));
    let (last, last_se) = (
        number(&body["last"]["mass"]),
        number(&body["last"]["mass_se"]),
    );
    eprintln!("command: {mass} ± {se} kg; with later steps free {last} ± {last_se}");
    assert!((mass - truth).abs() <= 0.15 * truth, "{mass} vs {truth}");
    if body["moved"] == true {
        assert!((last - mass).abs() > 2.0 * se.max(last_se), "{body}");
        let said = format!("{mass:+.3} ± {se:.3} kg");
        assert!(text.contains(&said), "{said} not in the report");
        assert!(
            text.contains("later steps trade off with its mass"),
            "{text}"
        );
    } else {
        // Not moved: the final fit within two standard errors of the step's weighing, which
        // is the mass stated.
        assert!((last - mass).abs() <= 2.0 * se.max(last_se), "{body}");
    }
}

#[test]
fn a_body_whose_mass_no_joint_torque_feels_is_never_a_step() {
    // Case 10 of seed 1 (compliance on run 2, the description from run 3). Until issue 54 a
    // later step freed lwr_2_link, whose frame origin lies on the axes of both joints before
    // it, so that no joint torque changes with mass there: the step was stated with its mass
    // unseen. A body step must now weigh its mass (only the first moment `m c` of such a body
    // is seen, which a description's error changes as well): lwr_2_link is no step, every body
    // a step freed carries a standard error, and where lwr_2_link is said it is as not claimed,
    // without a mass.
    let (_dir, keep, table) =
        kept_semi_real_cases(&["--description-uncertainty", "0.05", "--only", "10"]);
    let row = table.lines().nth(1).unwrap();
    assert!(
        row.starts_with("10,") && row.contains(",compliance,"),
        "{row}"
    );
    assert!(!field(&table, row, "found").contains("lwr_2_link"), "{row}");
    let (d, _) = rediagnosed(&keep.join("case10"), &[]);
    let ladder = &d["ladder"];
    for b in ladder["bodies"].as_array().unwrap() {
        assert!(b["mass_se"].as_f64().is_some_and(|s| s > 0.0), "{b}");
        assert!(
            b["last"]["mass_se"].as_f64().is_some_and(|s| s > 0.0),
            "{b}"
        );
    }
    let rungs = ladder["rungs"].as_array().unwrap();
    let mut said = vec![&ladder["unweighed"]];
    for r in rungs {
        assert!(!r["step"].as_str().unwrap().contains("lwr_2_link"), "{r}");
        said.push(&r["unweighed"]);
    }
    for u in said.iter().flat_map(|u| u.as_array().unwrap()) {
        assert!(u["mass"].is_null(), "{u}");
    }
}

#[test]
fn in_the_what_changed_mode_a_payload_that_fits_better_than_a_simpler_step_is_said_to() {
    // Case 13 of seed 2: 1.42 kg on lwr_5_link of run 2, the baseline run 3. A torque gain
    // (fewer columns) takes 95.2 % of the held-out mean square and the payload 97.4 %: within
    // the ladder's tie, so the simpler gain is the step. Until 2026-11-27 nothing said that a
    // payload on lwr_5_link fits these data better; now the step lists the explanations with
    // more columns that it was preferred to, the payload weighed in the step's place.
    let (_dir, keep, table) = kept_semi_real_cases_of("2", &["--real-baseline", "--only", "13"]);
    let row = table.lines().nth(1).unwrap();
    assert!(row.starts_with("13,"), "{row}");
    assert_eq!(field(&table, row, "injected_body"), "lwr_5_link");
    let truth: f64 = field(&table, row, "injected_mass").parse().unwrap();
    let (d, text) = rediagnosed_in_what_changed_mode(&keep, &table, row);
    let first = &d["ladder"]["rungs"][2];
    let on_body = |name: &str| name.ends_with("on lwr_5_link");
    let named = first["step"].as_str().is_some_and(on_body)
        || first["ambiguous_with"]
            .as_array()
            .unwrap()
            .iter()
            .any(|s| s.as_str().is_some_and(on_body));
    if named {
        return; // the payload itself is the step, or tied with it at its size
    }
    let also = first["also_fit"].as_array().unwrap();
    let payload = also
        .iter()
        .find(|a| a["name"].as_str().is_some_and(on_body))
        .unwrap_or_else(|| panic!("no payload on lwr_5_link beside {first}"));
    let (reduction, mass) = (
        payload["reduction"].as_f64().unwrap(),
        payload["mass"].as_f64().unwrap(),
    );
    eprintln!(
        "{}: {reduction} against {}; {mass} kg of {truth}",
        first["step"], first["reduction"]
    );
    assert!(reduction > first["reduction"].as_f64().unwrap(), "{first}");
    assert!((mass - truth).abs() <= 0.15 * truth, "{mass} vs {truth}");
    assert!(
        text.contains("**Also fit**") && text.contains("`payload or change on lwr_5_link` (+"),
        "{text}"
    );
}

#[test]
fn a_torque_constant_off_on_one_real_joint_is_weighed_against_the_description() {
    // Case 5 of seed 2: the logged torque of lwr_1_joint (the shoulder) scaled by 0.75 on run 3,
    // the description from run 1. The ladder names the gain first. Its column is the
    // prediction of a model without the gain, so each joint's coefficient is its gain error;
    // until 2026-11-27 it was read as the re-identified model's (`β/(1 − β)`, relative to the
    // median joint) and the shoulder came out at −0.06 ± 0.20, the fit with four later steps
    // free (the joints the real robot's own standing gap reads as gains pulled the median).
    let (_dir, keep, table) = kept_semi_real_cases_of("2", &["--only", "5"]);
    let row = table.lines().nth(1).unwrap();
    assert!(
        row.starts_with("5,") && row.contains(",torque_gain,"),
        "{row}"
    );
    let found = field(&table, row, "found");
    assert_eq!(first_found(&found), "+ torque_gain", "{found}");
    // The truth the case was scored against, kept beside its files.
    let injected = injected(&keep.join("case5"));
    let gain = injected["injection"]["spec"]["gain"].as_array().unwrap();
    let truth = gain[1].as_f64().unwrap() - 1.0;
    assert!((truth + 0.248).abs() < 1e-3, "{injected}");
    let (d, text) = rediagnosed(&keep.join("case5"), &[]);
    let e = described_effect(&d, "torque_gain");
    let shoulder = &e["magnitudes"][1];
    assert_eq!(shoulder["joint"], "lwr_1_joint");
    let (value, se) = (
        shoulder["value"].as_f64().unwrap(),
        shoulder["se"].as_f64().unwrap(),
    );
    eprintln!("shoulder gain error {value:.4} ± {se:.4} against {truth:.4}");
    assert!(
        (value - truth).abs() <= 0.15 * truth.abs(),
        "{value} vs {truth}"
    );
    assert!(se > 0.0 && se < 0.05 * truth.abs(), "{se}");
    assert!(
        text.contains("`torque_gain` from the description: gain error against the description"),
        "{text}"
    );
}

#[test]
fn in_the_what_changed_mode_a_tilt_is_weighed_against_a_baseline_with_a_standing_gain() {
    // Case 7 of seed 1: run 2 tilted by 15°, the baseline run 3, whose own diagnosis keeps a
    // torque gain among its standing effects. The baseline's calibration fits the gain beside
    // the inertial parameters; until 2026-11-27 nothing pinned the gain common to every joint
    // (a scale of all of θ), the calibrated description carried 38 and 34 kg on two links, and
    // every linearized change was weighed about it at a tenth of its size (this tilt at
    // 0.024 rad, the delay, compliance and gain cases of the same pair alike).
    let (_dir, keep, table) = kept_semi_real_cases(&["--real-baseline", "--only", "7"]);
    let row = table.lines().nth(1).unwrap();
    assert!(row.starts_with("7,") && row.contains(",tilt,"), "{row}");
    let found = field(&table, row, "found");
    assert_eq!(first_found(&found), "+ tilt", "{found}");
    let injected = injected(&keep.join("case7"));
    let truth = injected["injection"]["magnitudes"][0].as_f64().unwrap();
    let error: f64 = field(&table, row, "magnitude_error").parse().unwrap();
    eprintln!("tilt {truth} rad, relative error {error}");
    assert!(truth > 0.2, "{injected}");
    assert!(error <= 0.2, "{row}");
    // The command on the kept files, with its baseline: the same tilt.
    let (d, _) = rediagnosed_in_what_changed_mode(&keep, &table, row);
    let tilt = described_effect(&d, "tilt")["magnitudes"][0]["value"]
        .as_f64()
        .unwrap();
    assert!(
        (tilt - truth).abs() <= 0.2 * truth,
        "{tilt} rad against {truth}"
    );
}

/// The diagnosis's steps that name a body (a payload or a change of a body).
fn body_steps(d: &serde_json::Value) -> Vec<String> {
    steps(d)
        .into_iter()
        .filter(|s| s.starts_with("+ payload on") || s.starts_with("+ change of"))
        .collect()
}

#[test]
fn a_description_identified_on_another_motion_reads_no_change_into_unchanged_runs() {
    // Issue 54's transfer case: the description identified on run 3 (another trajectory, about
    // twice as fast); runs 1 and 2 of the unchanged arm are diagnosed from its URDF (the
    // sidecar's information and normal equations) with 5 % stated.
    let dir = tempfile::tempdir().unwrap();
    let robot = description_of(dir.path(), 3);
    for r in [1, 2] {
        let d = diagnose(&robot, &run(dir.path(), r, 0.0, &robot), &[]);
        eprintln!(
            "run {r} unchanged: {:?}; bodies {}",
            steps(&d),
            d["ladder"]["bodies"]
        );
        assert!(body_steps(&d).is_empty(), "run {r}: {:?}", steps(&d));
        assert!(!claims_a_payload(&d), "run {r}: {}", d["ladder"]["bodies"]);
    }
}

#[test]
fn a_description_identified_on_another_motion_still_names_a_payload_first() {
    let dir = tempfile::tempdir().unwrap();
    let robot = description_of(dir.path(), 3);
    let d = diagnose(&robot, &run(dir.path(), 1, 1.0, &robot), &[]);
    let s = steps(&d);
    eprintln!("run 1 with 1 kg: {s:?}; bodies {}", d["ladder"]["bodies"]);
    assert!(s[0].starts_with("+ payload on"), "{s:?}");
    let mass = flange_payload(&d).expect("a payload on the flange");
    assert!((mass - 1.0).abs() <= 0.25, "mass {mass}");
}
