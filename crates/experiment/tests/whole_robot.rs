//! The whole-robot experiment on the standing quadruped: its rows and targets are consistent
//! with the model in every data setting, and the constraint sets behave as the paper says on
//! little data.

use physid_core::model::cheetah3::{self, LegOptions};
use physid_core::model::floating::FloatingModel;
use physid_core::model::quadruped::{quadruped, quadruped_with};
use physid_core::model::JointFriction;
use physid_experiment::whole_robot::{run, WholeRobotError, WholeRobotSpec};
use physid_ident::floating::DataSetting;
use physid_ident::ConstraintSet;

fn feet(robot: &FloatingModel) -> Vec<(usize, nalgebra::Vector3<f64>)> {
    (0..robot.joints())
        .filter(|i| i % 3 == 2)
        .map(|i| (i, cheetah3::foot_in_shank()))
        .collect()
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
        eprintln!("{setting:?}: none {none:.1}, semi {:.1}, consistent {:.1}, ellipsoid {ellipsoid:.1} N m",
            rms(ConstraintSet::Semi), rms(ConstraintSet::Consistent));
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
