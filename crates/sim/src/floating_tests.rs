//! The standing quadruped: it stays up on its feet, the ground carries its weight, and what is
//! recorded obeys the floating-base equations of motion.

use crate::floating::{standing, FloatingSimError, Standing, Start};
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
    let stand = Standing {
        duration: 2.0,
        ..Default::default()
    };
    let trot = Standing {
        step: (0.15, 2.5),
        ..stand.clone()
    };
    for experiment in [stand, trot] {
        let worst = equations_of_motion_residual(&robot, &feet, &experiment);
        assert!(
            worst < 1e-10,
            "{:?}: relative residual {worst:e}",
            experiment.step
        );
    }
}

/// The largest relative residual of `Y θ = [0; τ] + Σ J_cᵀ λ_c` over a run of `experiment`.
fn equations_of_motion_residual(
    robot: &FloatingModel,
    feet: &[(usize, Vector3<f64>)],
    experiment: &Standing,
) -> f64 {
    let run = standing(robot, feet, experiment).unwrap();
    let theta = robot.parameters();
    let mut data = Data::new(robot.tree());
    let mut y = DMatrix::zeros(robot.dof(), robot.parameter_count());
    let n = robot.joints();
    let mut worst: f64 = 0.0;
    for k in (0..run.len()).step_by(37) {
        let (q, qd, qdd) = run.joints_at(k);
        let base = &run.base[k];
        regressor_floating(robot, &mut data, base, (q, qd, qdd), &mut y);
        let mut rhs = DVector::zeros(6 + n);
        rhs.rows_mut(6, n).copy_from_slice(run.tau_at(k));
        for (&(body, p), f) in feet.iter().zip(run.contact_at(k)) {
            let jac = point_jacobian_floating(robot, &mut data, base, q, (body, &p));
            rhs += jac.transpose() * DVector::from_column_slice(f.as_slice());
        }
        let lhs = &y * &theta;
        let weight = robot.total_mass() * 9.81;
        worst = worst.max((&lhs - &rhs).norm() / rhs.norm().max(weight));
    }
    worst
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
        (
            "step (0.6, 2)",
            Standing {
                step: (0.6, 2.0),
                ..Default::default()
            },
        ),
        (
            "step (0.1, NaN)",
            Standing {
                step: (0.1, f64::NAN),
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

#[test]
fn a_bad_start_is_named() {
    let robot = quadruped();
    for (said, height, velocity) in [
        (
            "start.height must be 0 to 0.5 m, got -0.01",
            -0.01,
            [0.0; 3],
        ),
        (
            "start.height must be 0 to 0.5 m, got NaN",
            f64::NAN,
            [0.0; 3],
        ),
        ("start.velocity [NaN, 0.0, 0.0]", 0.0, [f64::NAN, 0.0, 0.0]),
        ("its speed must be at most 5 m/s", 0.0, [0.0, 0.0, -6.0]),
    ] {
        let e = Standing {
            start: Start { height, velocity },
            ..Default::default()
        };
        match standing(&robot, &feet(&robot), &e) {
            Err(FloatingSimError::Invalid(m)) => assert!(m.contains(said), "{said}: {m}"),
            other => panic!("{said}: {other:?}"),
        }
    }
}

/// Trotting in place: each diagonal pair lifts its feet in turn (two feet carry the robot
/// a good part of the time, each foot is in the air a good part of the time), the trunk stays
/// upright (the log obeys the equations of motion: the test above runs this gait too);
/// a step too high for the gait tips the robot over, which is an error, not a log.
#[test]
fn the_quadruped_trots_in_place_and_a_gait_that_tips_it_over_is_an_error() {
    let robot = quadruped();
    let trot = Standing {
        duration: 6.0,
        step: (0.15, 2.5),
        ..Default::default()
    };
    let run = standing(&robot, &feet(&robot), &trot).unwrap();
    let after_fade = 1000..run.len();
    let down = |k: usize| run.contact_at(k).iter().filter(|f| f.z > 0.0).count();
    let two = after_fade.clone().filter(|&k| down(k) == 2).count() as f64;
    assert!(
        two > 0.25 * after_fade.len() as f64,
        "two feet down in {two} steps"
    );
    for foot in 0..4 {
        let air = (after_fade.clone())
            .filter(|&k| run.contact_at(k)[foot].z == 0.0)
            .count() as f64;
        assert!(
            air > 0.15 * after_fade.len() as f64,
            "foot {foot} in the air {air} steps"
        );
    }
    let tilt = (run.base.iter())
        .map(|b| b.pose.e[(2, 2)].acos().to_degrees())
        .fold(0.0, f64::max);
    assert!(tilt < 25.0, "the trunk tilted {tilt}°");
    let high = Standing {
        step: (0.2, 1.5),
        ..trot
    };
    match standing(&robot, &feet(&robot), &high) {
        Err(FloatingSimError::Fell { t, tilt, .. }) => {
            assert!(t > 1.0 && tilt >= 60.0, "{t} {tilt}")
        }
        other => panic!("a step of 0.2 rad at 1.5 Hz: {:?}", other.map(|r| r.len())),
    }
}

/// The accelerometer an exact log carries is the trunk's specific force `Rᵀ (p̈ − g)`: checked
/// against the second differences of the logged positions (an independent path, through the
/// integration of the run), while the robot sways and bobs on its feet (a trot's touchdowns
/// change the acceleration within a millisecond, faster than positions sampled at 1 kHz tell).
#[test]
fn an_exact_accelerometer_reads_the_second_difference_of_the_trunk_s_position_less_gravity() {
    use crate::floating_sensors::{log, Sensors};
    let robot = quadruped();
    let e = Standing {
        duration: 3.0,
        ..Default::default()
    };
    let run = standing(&robot, &feet(&robot), &e).unwrap();
    let names = |n: usize, p: &str| (0..n).map(|i| format!("{p}{i}")).collect::<Vec<_>>();
    let logged = log(
        &run,
        (&names(12, "j"), &names(4, "f")),
        &Sensors::exact(),
        1,
    );
    let accel = logged.accel.as_ref().expect("logged");
    let dt = 1.0 / e.rate;
    let (mut errors, mut sizes) = (vec![], vec![]);
    for (k, f) in accel.iter().enumerate().take(run.len() - 1).skip(500) {
        let p = |i: usize| logged.position[i];
        let p_ddot = (p(k + 1) - 2.0 * p(k) + p(k - 1)) / (dt * dt);
        let expected = logged.rotation[k].transpose() * (p_ddot - run.gravity);
        errors.push((f - expected).norm());
        sizes.push(p_ddot.norm());
    }
    let at = |mut v: Vec<f64>, q: f64| {
        v.sort_by(f64::total_cmp);
        v[((v.len() - 1) as f64 * q) as usize]
    };
    // The positions are integrated at 0.1 ms by semi-implicit Euler and recorded every 1 ms, and
    // a foot that lifts for a moment changes the acceleration within a step: compared on 99 %
    // of the samples, to what the trunk's own accelerations are (a tilted gravity would be off
    // by 0.1 m/s² per 0.01 rad).
    let (error, size) = (at(errors, 0.99), at(sizes, 0.5));
    assert!(size > 0.05, "the trunk hardly accelerates: {size} m/s²");
    assert!(
        error < 0.02,
        "{error} m/s² off on 1 % of the samples (median acceleration {size})"
    );
}
