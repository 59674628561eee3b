//! The standing quadruped: it stays up on its feet, the ground carries its weight, and what is
//! recorded obeys the floating-base equations of motion.

use crate::floating::{standing, FloatingSimError, Standing};
use nalgebra::{DMatrix, DVector, Vector3};
use physid_core::dynamics::{point_jacobian_floating, regressor_floating, Data};
use physid_core::model::cheetah3::LegOptions;
use physid_core::model::floating::FloatingModel;
use physid_core::model::quadruped::{quadruped, quadruped_with};
use physid_core::model::JointFriction;

/// The built-in quadruped's feet (every robot these tests build is one).
fn feet(_: &FloatingModel) -> Vec<(usize, nalgebra::Vector3<f64>)> {
    physid_core::model::quadruped::feet()
}

#[test]
fn the_quadruped_stands_and_sways_on_its_feet_and_the_ground_carries_its_weight() {
    let robot = quadruped();
    let experiment = Standing {
        duration: 8.0,
        ..Default::default()
    };
    let run = standing(&robot, &feet(&robot), &experiment).unwrap();
    assert_eq!(run.len(), 8000);
    let heights: Vec<f64> = run.base.iter().map(|b| b.pose.r.z).collect();
    let (lo, hi) = heights[1000..]
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &h| {
            (a.min(h), b.max(h))
        });
    assert!(lo > 0.2 && hi < 0.8, "trunk height {lo}..{hi} m");
    assert!(hi - lo > 0.02, "the trunk hardly moves: {lo}..{hi} m");
    // Over the run the ground carries the weight on average (the trunk's mean vertical
    // acceleration is small), and every foot stays loaded.
    let weight = robot.total_mass() * 9.81;
    let mean_normal: f64 = (0..run.len())
        .map(|k| run.contact_at(k).iter().map(|f| f.z).sum::<f64>())
        .sum::<f64>()
        / run.len() as f64;
    assert!(
        (mean_normal - weight).abs() < 0.05 * weight,
        "{mean_normal} vs {weight}"
    );
    // A foot may lift for a moment when the modes add up; all four carry most of the time.
    let all_down = (1000..run.len())
        .filter(|&k| run.contact_at(k).iter().all(|f| f.z > 0.0))
        .count();
    let share = all_down as f64 / (run.len() - 1000) as f64;
    assert!(
        share > 0.9,
        "all four feet down in only {share} of the steps"
    );
}

/// With Coulomb friction zero (the simulation smooths it, the regressor does not), every
/// recorded step satisfies `Y θ = [0; τ] + Σ J_cᵀ λ_c` to round-off: the log is consistent with
/// the model that made it.
#[test]
fn the_recorded_run_obeys_the_floating_base_equations_of_motion() {
    let options = LegOptions {
        friction: [JointFriction {
            viscous: 0.1,
            coulomb: 0.0,
        }; 3],
        ..Default::default()
    };
    let robot = quadruped_with(&options).unwrap();
    let feet = feet(&robot);
    let experiment = Standing {
        duration: 1.5,
        ..Default::default()
    };
    let run = standing(&robot, &feet, &experiment).unwrap();
    let theta = robot.parameters();
    let mut data = Data::new(robot.tree());
    let mut y = DMatrix::zeros(robot.dof(), robot.parameter_count());
    let n = robot.joints();
    let mut worst: f64 = 0.0;
    for k in (0..run.len()).step_by(37) {
        let (q, qd, qdd) = run.joints_at(k);
        let base = &run.base[k];
        regressor_floating(&robot, &mut data, base, (q, qd, qdd), &mut y);
        let mut rhs = DVector::zeros(6 + n);
        rhs.rows_mut(6, n).copy_from_slice(run.tau_at(k));
        for (&(body, p), f) in feet.iter().zip(run.contact_at(k)) {
            let jac = point_jacobian_floating(&robot, &mut data, base, q, (body, &p));
            rhs += jac.transpose() * DVector::from_column_slice(f.as_slice());
        }
        let lhs = &y * &theta;
        let weight = robot.total_mass() * 9.81;
        worst = worst.max((&lhs - &rhs).norm() / rhs.norm().max(weight));
    }
    assert!(worst < 1e-10, "relative residual {worst:e}");
}

#[test]
fn bad_experiment_values_are_named() {
    let robot = quadruped();
    for (field, e) in [
        (
            "duration",
            Standing {
                duration: f64::NAN,
                ..Default::default()
            },
        ),
        (
            "rate",
            Standing {
                rate: 0.0,
                ..Default::default()
            },
        ),
        (
            "ground.friction",
            Standing {
                ground: crate::floating::Ground {
                    friction: -1.0,
                    ..Default::default()
                },
                ..Default::default()
            },
        ),
        (
            "substeps",
            Standing {
                substeps: 0,
                ..Default::default()
            },
        ),
    ] {
        match standing(&robot, &feet(&robot), &e) {
            Err(FloatingSimError::Invalid(m)) => assert!(m.contains(field), "{field}: {m}"),
            other => panic!("{field}: {other:?}"),
        }
    }
    let far = vec![(99, Vector3::zeros())];
    let err = standing(&robot, &far, &Standing::default()).unwrap_err();
    assert!(err.to_string().contains("body 99"), "{err}");
}
