//! The whole-robot experiment on the standing quadruped: its rows and targets are consistent
//! with the model in every data setting, and the constraint sets behave as the paper says on
//! little data.

use crate::whole_robot::{run, WholeRobotError, WholeRobotSpec};
use physid_core::model::cheetah3::LegOptions;
use physid_core::model::floating::FloatingModel;
use physid_core::model::quadruped::{quadruped, quadruped_with};
use physid_core::model::JointFriction;
use physid_ident::floating::DataSetting;
use physid_ident::ConstraintSet;

/// The built-in quadruped's feet (every robot these tests build is one).
fn feet(_: &FloatingModel) -> Vec<(usize, nalgebra::Vector3<f64>)> {
    physid_core::model::quadruped::feet()
}

/// Without Coulomb friction (which the simulation smooths and the regressor does not) and
/// without noise, the data are exactly the model's. With the truth as the prior, least squares
/// must return it in every setting (to 1e-5 N m against torques of tens of N m: the trunk rows
/// alone leave many directions to the prior's small weight, and their least squares is
/// ill-conditioned); with a 10 % prior, the setting with torques and contact forces still
/// predicts a new motion's torques exactly, far below the prior's error.
#[test]
fn exact_data_give_back_the_truth_in_every_data_setting() {
    let options = LegOptions {
        friction: [JointFriction {
            viscous: 0.1,
            coulomb: 0.0,
        }; 3],
        ..Default::default()
    };
    let robot = quadruped_with(&options).unwrap();
    let exact = WholeRobotSpec {
        sizes: vec![1500],
        validation: 200,
        sets: vec![ConstraintSet::None],
        torque_noise: 0.0,
        force_noise: 0.0,
        prior_error: 0.0,
        prior_weight: 1e-6,
        ..Default::default()
    };
    for row in run(&robot, &feet(&robot), &exact).unwrap() {
        assert!(row.validation_rms < 1e-5, "{row:?}");
        assert!(row.errors[3] < 1e-5, "{row:?}");
    }
    let cad = WholeRobotSpec {
        prior_error: 0.1,
        settings: vec![DataSetting::TorquesAndContacts],
        ..exact
    };
    for row in run(&robot, &feet(&robot), &cad).unwrap() {
        assert!(row.prior_rms > 0.1, "{row:?}");
        assert!(row.validation_rms < 1e-4, "{row:?}");
    }
}

/// On a hundred noisy samples, every constrained model satisfies its constraints, and the
/// tighter sets predict new motion far better than least squares (the paper's Fig. 4 at its
/// left end), the ellipsoid set best of all.
#[test]
fn on_little_noisy_data_tighter_sets_predict_better() {
    let robot = quadruped();
    let spec = WholeRobotSpec {
        sizes: vec![100],
        validation: 200,
        settings: vec![DataSetting::TorquesAndContacts, DataSetting::BaseOnly],
        ..Default::default()
    };
    let rows = run(&robot, &feet(&robot), &spec).unwrap();
    assert_eq!(rows.len(), 8);
    for setting in [DataSetting::TorquesAndContacts, DataSetting::BaseOnly] {
        let rms = |set: ConstraintSet| {
            let row = rows
                .iter()
                .find(|r| r.setting == setting && r.set == set)
                .unwrap();
            assert!(row.constraints_hold, "{row:?}");
            row.validation_rms
        };
        let none = rms(ConstraintSet::None);
        let ellipsoid = rms(ConstraintSet::Ellipsoid);
        assert!(rms(ConstraintSet::Semi) < none / 5.0);
        assert!(rms(ConstraintSet::Consistent) < none / 5.0);
        assert!(ellipsoid < rms(ConstraintSet::Consistent));
    }
}

#[test]
fn bad_spec_values_are_named() {
    let robot = quadruped();
    let cases = [
        (
            "sizes",
            WholeRobotSpec {
                sizes: vec![300, 100],
                ..Default::default()
            },
        ),
        (
            "sizes",
            WholeRobotSpec {
                sizes: vec![],
                ..Default::default()
            },
        ),
        (
            "torque_noise",
            WholeRobotSpec {
                torque_noise: -1.0,
                ..Default::default()
            },
        ),
        (
            "prior_weight",
            WholeRobotSpec {
                prior_weight: f64::NAN,
                ..Default::default()
            },
        ),
        (
            "seeds",
            WholeRobotSpec {
                seeds: vec![],
                ..Default::default()
            },
        ),
    ];
    for (field, spec) in cases {
        match run(&robot, &feet(&robot), &spec) {
            Err(WholeRobotError::Spec(m)) => assert!(m.contains(field), "{field}: {m}"),
            other => panic!("{field}: {other:?}"),
        }
    }
}

/// Ayusawa, Venture & Nakamura's result on the quadruped: from the trunk's six rows alone
/// (contact forces and the motion, no joint torque) least squares recovers every base
/// parameter of those rows within a few of its standard errors, the standard errors coming
/// from the same data. Their identifiable set is the whole body's but for what only joint
/// torques see: the joints' friction (two columns per joint) and, with geared rotors, one more
/// combination per joint (a rotor's spin inertia enters the joint row reflected by `N²`, the
/// trunk's momentum by `N`). Without rotors the theorem's count is exact.
#[test]
fn the_trunk_rows_alone_recover_their_base_parameters_within_their_standard_errors() {
    let no_rotors = LegOptions {
        rotors: false,
        ..Default::default()
    };
    for (robot, only_joint_rows_see) in [
        (quadruped(), 3 * 12),
        (quadruped_with(&no_rotors).unwrap(), 2 * 12),
    ] {
        let (base_rank, whole_rank, z) = trunk_rows_against_the_truth(&robot);
        let within = |k: f64| z.iter().filter(|v| v.abs() <= k).count() as f64 / z.len() as f64;
        let worst = z.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert_eq!(whole_rank, base_rank + only_joint_rows_see);
        assert!(base_rank > 30, "rank {base_rank}");
        let said = format!(
            "within 2 σ {:.2}, 3 σ {:.2}, worst {worst:.1} σ",
            within(2.0),
            within(3.0)
        );
        assert!(within(3.0) > 0.95, "{said}: {z:?}");
    }
}

/// The trunk rows' rank, the whole body's rank on the same run, and each trunk-row base
/// parameter's error against the truth in units of its standard error (6 s of standing,
/// contact forces with 2 N of noise, least squares with a negligible prior).
fn trunk_rows_against_the_truth(robot: &FloatingModel) -> (usize, usize, Vec<f64>) {
    use crate::whole_robot::{measured, normal_equations};
    use physid_ident::analysis::identifiability;
    use physid_ident::Options;
    use physid_sim::floating::{standing, Standing};
    let motion = Standing {
        duration: 6.0,
        seed: 11,
        ..Default::default()
    };
    let truth = standing(robot, &feet(robot), &motion).unwrap();
    let spec = WholeRobotSpec {
        torque_noise: 0.0,
        force_noise: 2.0,
        ..Default::default()
    };
    let noisy = measured(&truth, &spec, 11);
    let data = (&noisy, &truth);
    let ne = normal_equations(robot, data, DataSetting::BaseOnly, truth.len());
    let prior = crate::cad_prior(robot, 0.1, 11);
    let opts = Options {
        prior_weight: 1e-9,
        ..Options::new(ConstraintSet::None)
    };
    let found = physid_ident::identify(robot, &ne, &prior, &opts).unwrap();
    let idf = identifiability(robot, &ne, &found.theta);
    let whole = normal_equations(robot, data, DataSetting::TorquesAndContacts, truth.len());
    let whole_rank = identifiability(robot, &whole, &found.theta).rank;
    let theta_true = robot.parameters();
    let names = robot.parameter_names();
    let column = |name: &str| names.iter().position(|n| n == name).unwrap();
    let z = (idf.base.iter())
        .map(|b| {
            let truth: f64 = (b.terms.iter())
                .map(|t| t.coefficient * theta_true[column(&t.parameter)])
                .sum();
            (b.value - truth) / b.standard_error
        })
        .collect();
    (idf.rank, whole_rank, z)
}

/// A 5 kg payload strapped to the trunk 10 cm forward and 8 cm up: from the unloaded
/// description and a loaded run (torques and contact forces, with noise), the trunk is named as
/// the body that changed, with the payload's mass and position; the ab/ad rotors, which the
/// trunk carries rigidly, are said to fit almost as well. On an unloaded run of another motion
/// no body is named.
#[test]
fn a_payload_on_the_trunk_is_found_from_the_description() {
    use physid_diagnose::floating::{body_changes, name_change};
    let description = quadruped();
    let (loaded, at) = with_trunk_payload(&description);
    let named_on = |robot: &FloatingModel, seed: u64| {
        let changes = body_changes(&description, &standing_rows(robot, seed));
        name_change(&changes, 10.0, 0.01)
    };
    let found = named_on(&loaded, 3);
    let trunk_change = found.changed.expect("a body is named");
    assert_eq!(trunk_change.body, "trunk");
    assert!((trunk_change.mass - 5.0).abs() < 0.1, "{trunk_change:?}");
    assert!(
        (trunk_change.com.unwrap() - at).norm() < 0.01,
        "{trunk_change:?}"
    );
    assert!(
        found.also_fit.iter().all(|b| b.ends_with("abad_rotor")),
        "{:?}",
        found.also_fit
    );
    assert!(named_on(&description, 4).changed.is_none());
}

/// `description` with 5 kg strapped to its trunk 10 cm forward and 8 cm up (inertia 0.01 kg m²
/// about its centre on each axis), and that centre in the trunk's frame (m).
fn with_trunk_payload(description: &FloatingModel) -> (FloatingModel, nalgebra::Vector3<f64>) {
    use physid_core::model::floating::Trunk;
    use physid_core::spatial::InertialParams;
    let at = nalgebra::Vector3::new(0.10, 0.0, 0.08);
    let inertia = nalgebra::Matrix3::identity() * 0.01;
    let payload = InertialParams::from_mass_com_inertia(5.0, &at, &inertia);
    let trunk = Trunk {
        inertia: InertialParams(description.trunk().inertia.0 + payload.0),
        ..description.trunk().clone()
    };
    (
        FloatingModel::new(trunk, description.tree().clone()).unwrap(),
        at,
    )
}

/// The normal equations of a standing run of `robot` (torques and contact forces, with noise).
fn standing_rows(robot: &FloatingModel, seed: u64) -> physid_ident::NormalEquations {
    use crate::whole_robot::{measured, normal_equations};
    use physid_sim::floating::{standing, Standing};
    let motion = Standing {
        duration: 4.0,
        seed,
        ..Default::default()
    };
    let truth = standing(robot, &feet(robot), &motion).unwrap();
    let noisy = measured(&truth, &WholeRobotSpec::default(), seed);
    normal_equations(
        robot,
        (&noisy, &truth),
        DataSetting::TorquesAndContacts,
        truth.len(),
    )
}

/// A joint whose friction changed (front-right knee: viscous +0.8 N m s/rad, Coulomb +3 N m)
/// is named with its two changes, and no body is; a 5 kg payload on the trunk is still named
/// as the trunk, not as any joint's friction; on an unloaded run neither is named.
#[test]
fn a_joint_s_changed_friction_is_named_and_a_payload_is_not_read_as_one() {
    use physid_diagnose::floating::{body_changes, friction_changes, name_change, name_friction};
    let description = quadruped();
    let names = description.parameter_names();
    let column = |name: &str| names.iter().position(|n| n == name).unwrap();
    let mut theta = description.parameters();
    theta[column("fr_knee_joint.B")] += 0.8;
    theta[column("fr_knee_joint.Bc")] += 3.0;
    let worn = description.with_parameters(&theta).unwrap();
    let (loaded, _) = with_trunk_payload(&description);
    let thresholds = (10.0, 0.05);
    let read = |robot: &FloatingModel, seed: u64| {
        let ne = standing_rows(robot, seed);
        let bodies = body_changes(&description, &ne);
        let body = name_change(&bodies, thresholds.0, thresholds.1).changed;
        let frictions = friction_changes(&description, &ne);
        let friction = name_friction(&frictions, body.as_ref(), thresholds);
        (body, friction)
    };
    let (body, friction) = read(&worn, 5);
    let friction = friction.expect("a friction change is named");
    assert_eq!(friction.joint, "fr_knee_joint");
    // The friction torque the change adds at 1 rad/s is found closely; its split between the
    // viscous and Coulomb terms less so (the simulator's Coulomb friction is smoothed below
    // `v_f`, where it looks partly viscous to the `sign(q̇)` column; measured 1.04 and 2.78).
    let at_one = friction.viscous + friction.coulomb;
    assert!((at_one - 3.8).abs() < 0.05 * 3.8, "{friction:?}");
    assert!((friction.coulomb - 3.0).abs() < 0.15 * 3.0, "{friction:?}");
    assert!(body.as_ref().is_none_or(|b| b.f < friction.f), "{body:?}");
    let (body, friction) = read(&loaded, 6);
    assert_eq!(body.expect("the trunk is named").body, "trunk");
    assert!(friction.is_none(), "{friction:?}");
    let (body, friction) = read(&description, 7);
    assert!(
        body.is_none() && friction.is_none(),
        "{body:?} {friction:?}"
    );
}

/// A summary table of one setting with the given medians per set (sizes 100, 300, 1000).
fn summary_of(curves: &[(&str, [f64; 3])]) -> polars::prelude::DataFrame {
    use polars::prelude::*;
    let mut cols: [Vec<f64>; 3] = Default::default();
    let mut sets = vec![];
    for (set, values) in curves {
        for (n, v) in [100.0, 300.0, 1000.0].iter().zip(values) {
            cols[0].push(*n);
            cols[1].push(*v);
            cols[2].push(2.0);
            sets.push(set.to_string());
        }
    }
    let settings = vec!["torques_only".to_string(); sets.len()];
    DataFrame::new_infer_height(vec![
        Column::new("force_noise".into(), &cols[2]),
        Column::new("setting".into(), settings),
        Column::new("n_s".into(), &cols[0]),
        Column::new("constraints".into(), sets),
        Column::new("val_rms_median".into(), &cols[1]),
    ])
    .unwrap()
}

#[test]
fn the_samples_a_set_needs_for_least_squares_error_are_interpolated_log_log() {
    use crate::whole_robot::{set_reach, spread};
    // Least squares 100, 10, 1 N m at 100, 300, 1000 samples; the ellipsoid set 10, 1, 0.9.
    let s = summary_of(&[
        ("none", [100.0, 10.0, 1.0]),
        ("ellipsoid", [10.0, 1.0, 0.9]),
    ]);
    let reach = set_reach(&s, "torques_only", "ellipsoid").unwrap();
    assert_eq!(reach.len(), 2);
    // At 300 samples least squares has 10, which the ellipsoid set has at 100 already.
    assert_eq!((reach[0].at, reach[0].target), (300, 10.0));
    assert_eq!(reach[0].samples, Some(100.0));
    assert!(reach[0].at_first_size);
    assert!((reach[0].fewer().unwrap() - 3.0).abs() < 1e-12);
    // At 1000 least squares has 1, which the ellipsoid set reaches at 300.
    assert!(
        (reach[1].samples.unwrap() - 300.0).abs() < 1e-9,
        "{:?}",
        reach[1]
    );
    assert!(!reach[1].at_first_size);
    // A target below the set's floor (least squares 0.5 at 1000, the set 0.9) is never reached.
    let s = summary_of(&[
        ("none", [100.0, 10.0, 0.5]),
        ("ellipsoid", [10.0, 1.0, 0.9]),
    ]);
    let reach = set_reach(&s, "torques_only", "ellipsoid").unwrap();
    assert_eq!(reach[1].samples, None);
    assert_eq!(reach[1].fewer(), None);
    // The spread: 100/10, 10/1, 0.9/0.5 at the three sizes.
    let spread = spread(&s, "torques_only", &["none", "ellipsoid"]).unwrap();
    let expected = [(100, 10.0), (300, 10.0), (1000, 1.8)];
    for ((n, k), (m, l)) in spread.iter().zip(expected) {
        assert!(*n == m && (k - l).abs() < 1e-12, "{spread:?}");
    }
}

/// Trained on the run as its sensors log it (an IMU and an estimator for the trunk, read back
/// through the data pipeline) with joint torques and contact forces, the whole robot predicts a
/// new motion's torques as well as when trained on the true motion (within a quarter), and
/// both far better than the prior. The sizes count the samples the pipeline keeps.
#[test]
fn trained_on_the_logged_run_the_robot_predicts_as_from_the_true_motion() {
    let robot = quadruped();
    let spec = WholeRobotSpec {
        sizes: vec![3000],
        validation: 200,
        sets: vec![ConstraintSet::Consistent],
        settings: vec![DataSetting::TorquesAndContacts],
        ..Default::default()
    };
    let truth = run(&robot, &feet(&robot), &spec).unwrap();
    let logged = WholeRobotSpec {
        logged: true,
        ..spec
    };
    let from_log = run(&robot, &feet(&robot), &logged).unwrap();
    let (a, b) = (&truth[0], &from_log[0]);
    assert_eq!((a.samples, b.samples), (3000, 3000));
    assert!(b.constraints_hold, "{b:?}");
    assert!(
        (b.validation_rms / a.validation_rms - 1.0).abs() < 0.25,
        "logged {} N m against the true motion's {} N m",
        b.validation_rms,
        a.validation_rms
    );
    assert!(b.validation_rms < 0.7 * b.prior_rms, "{b:?}");
}
