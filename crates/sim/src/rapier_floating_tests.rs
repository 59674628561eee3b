//! physid's contact model against rapier's, a second engine: the quadruped standing still,
//! dropped, pushed while its feet stick, and pushed on a slippery ground, under the same PD law
//! from the same start in both.
//!
//! The two contacts differ by design: physid's point foot sinks into a spring and damper
//! (`k` = 5·10⁴ N/m, a few millimetres under load, and a damping spike at touchdown), rapier
//! solves a nearly rigid velocity constraint. So the runs agree to what that difference leaves
//! and no closer: the trunk's height is compared above its own feet (each engine's sinking
//! removed), the feet's forces as 50 ms means once the landing is over. The bounds below are
//! a few millimetres, hundredths of a radian and percent of the weight: above what the runs
//! show with rapier stepping at 0.5 ms, as here, and at 0.1 ms (the gaps move by about 1 mm
//! and 1 % of the weight between the two), physid at its 0.1 ms.

use crate::floating::{standing, FloatingRun, Standing, Start};
use crate::rapier_floating::{standing_in_rapier, EngineRun, FOOT_RADIUS};
use nalgebra::{Matrix3, Vector3};
use physid_core::dynamics::{kinematics, Data};
use physid_core::model::floating::FloatingModel;
use physid_core::model::quadruped::{feet, quadruped};

/// rapier's steps per control period (0.5 ms).
const RAPIER_SUBSTEPS: usize = 2;

/// `start` run for 1.2 s in both engines, the posture held, on a ground of friction `mu`.
fn both(start: Start, mu: f64) -> (FloatingRun, EngineRun) {
    let mut e = Standing {
        duration: 1.2,
        amplitude: [0.0; 3],
        start,
        ..Default::default()
    };
    e.ground.friction = mu;
    run_both(&e)
}

/// `e` run in both engines.
fn run_both(e: &Standing) -> (FloatingRun, EngineRun) {
    let robot = quadruped();
    let ours = standing(&robot, &feet(), e).unwrap();
    let in_rapier = Standing {
        substeps: RAPIER_SUBSTEPS,
        ..e.clone()
    };
    let theirs = standing_in_rapier(&robot, &feet(), &in_rapier, FOOT_RADIUS).unwrap();
    assert_eq!(ours.len(), theirs.t.len());
    (ours, theirs)
}

/// The trunk origin's height above the mean of its feet (m), from its pose and the joints.
fn above_feet(robot: &FloatingModel, (rot, pos): (&Matrix3<f64>, &Vector3<f64>), q: &[f64]) -> f64 {
    let mut data = Data::new(robot.tree());
    kinematics::update_world(robot.tree(), &mut data, q);
    let f = feet();
    let mean_z = f
        .iter()
        .map(|(b, p)| (pos + rot * kinematics::point_position(&data, *b, p)).z)
        .sum::<f64>()
        / f.len() as f64;
    pos.z - mean_z
}

/// How far apart two runs are over their length.
#[derive(Debug)]
struct Gap {
    /// The trunk's height above its feet (m).
    height: f64,
    /// The trunk origin's horizontal position (m).
    horizontal: f64,
    /// Joint angles (rad).
    joints: f64,
    /// Each foot's normal force over 50 ms windows from 0.2 s on (after the landing or the
    /// first settling, whose impacts a rigid contact shares among four feet as its solver
    /// iterates), over the weight.
    normal: f64,
}

fn gap(ours: &FloatingRun, theirs: &EngineRun) -> Gap {
    let robot = quadruped();
    let weight = robot.total_mass() * 9.81;
    let n = ours.len();
    let mut g = Gap {
        height: 0.0,
        horizontal: 0.0,
        joints: 0.0,
        normal: 0.0,
    };
    for k in 0..n {
        let (rot, pos) = ours.base[k].pose.to_pose();
        let q = |run: &[f64]| run[12 * k..12 * k + 12].to_vec();
        let (r_rot, r_pos) = &theirs.trunk[k];
        let h_ours = above_feet(&robot, (&rot, &pos), &q(&ours.q));
        let h_theirs = above_feet(&robot, (r_rot, r_pos), &q(&theirs.q));
        g.height = g.height.max((h_ours - h_theirs).abs());
        g.horizontal = g.horizontal.max((pos - r_pos).xy().norm());
        let dq = (0..12).map(|j| (ours.q[12 * k + j] - theirs.q[12 * k + j]).abs());
        g.joints = g.joints.max(dq.fold(0.0, f64::max));
    }
    let window = 50;
    for k in (200..=n - window).step_by(window) {
        let mean = |x: &dyn Fn(usize) -> f64| (k..k + window).map(x).sum::<f64>() / window as f64;
        for f in 0..4 {
            let a = mean(&|i| ours.contact[4 * i + f].z);
            let b = mean(&|i| theirs.normal[4 * i + f]);
            g.normal = g.normal.max((a - b).abs() / weight);
        }
    }
    g
}

fn assert_close(what: &str, g: &Gap) {
    assert!(
        g.height < 5e-3 && g.horizontal < 1e-2 && g.joints < 0.02 && g.normal < 0.05,
        "{what}: physid and rapier apart by {g:?}"
    );
}

/// The first recorded time a foot carries load (s).
fn touchdown(normal: &[f64]) -> Option<f64> {
    normal
        .chunks(4)
        .position(|n| n.iter().sum::<f64>() > 0.0)
        .map(|k| k as f64 / 1000.0)
}

#[test]
fn standing_still_and_dropped_the_quadruped_lands_and_settles_as_in_rapier() {
    let robot = quadruped();
    let weight = robot.total_mass() * 9.81;
    let (ours, theirs) = both(Start::default(), 0.8);
    assert_close("standing still", &gap(&ours, &theirs));
    // Settled: each foot's share of the weight within 0.5 % of it.
    let last = ours.len() - 1;
    for f in 0..4 {
        let d = (ours.contact[4 * last + f].z - theirs.normal[4 * last + f]).abs();
        assert!(d < 5e-3 * weight, "foot {f}: {d} N apart at rest");
    }
    let height = 0.03;
    let (ours, theirs) = both(
        Start {
            height,
            velocity: [0.0; 3],
        },
        0.8,
    );
    assert_close("dropped 3 cm", &gap(&ours, &theirs));
    // A free fall of 3 cm lasts √(2h/g) = 78.2 ms in both: the first step with a load.
    let fall = (2.0 * height / 9.81).sqrt();
    let ours_down: Vec<f64> = ours.contact.iter().map(|f| f.z).collect();
    for t in [touchdown(&ours_down), touchdown(&theirs.normal)] {
        let t = t.expect("the robot lands");
        assert!(
            t >= fall && t < fall + 2e-3,
            "touchdown at {t} s, fall {fall} s"
        );
    }
}

#[test]
fn pushed_sideways_the_feet_stick_and_on_ice_they_slide_as_in_rapier() {
    // 0.5 m/s sideways on μ = 0.8: the legs take the push, the feet stay, the trunk comes
    // back within 2 cm of where it started.
    let (ours, theirs) = both(
        Start {
            height: 0.0,
            velocity: [0.0, 0.5, 0.0],
        },
        0.8,
    );
    assert_close("pushed, feet sticking", &gap(&ours, &theirs));
    let last = ours.len() - 1;
    assert!(ours.base[last].pose.r.y.abs() < 0.02 && theirs.trunk[last].1.y.abs() < 0.02);
    // 1 m/s forwards on μ = 0.15: stopping the robot takes more than friction gives, the feet
    // slide about 30 cm, and both engines stop it at the same place.
    let (ours, theirs) = both(
        Start {
            height: 0.0,
            velocity: [1.0, 0.0, 0.0],
        },
        0.15,
    );
    assert_close("pushed on a slippery ground", &gap(&ours, &theirs));
    let (x_ours, x_theirs) = (ours.base[last].pose.r.x, theirs.trunk[last].1.x);
    assert!(x_ours > 0.2, "the feet did not slide: {x_ours} m");
    assert!(
        (x_ours - x_theirs).abs() < 2e-3,
        "stopped at {x_ours} and {x_theirs} m"
    );
}

#[test]
fn trotting_in_place_the_feet_touch_down_and_lift_off_as_in_rapier() {
    let e = Standing {
        duration: 2.0,
        step: (0.15, 2.5),
        ..Default::default()
    };
    let (ours, theirs) = run_both(&e);
    // The gait drifts (about half a metre in 2 s, in both): positions part by centimetres as
    // it goes. The trunk's height (each engine's sinking in it) and tilt, and the joints, stay
    // close; a swinging foot's height and a foot's load around its touchdown differ by what a
    // millisecond's shift of the touchdown gives, so they are not compared sample by sample.
    let (mut height, mut horizontal, mut tilt, mut joints) = (0.0_f64, 0.0_f64, 0.0_f64, 0.0_f64);
    for k in 0..ours.len() {
        let (rot, pos) = ours.base[k].pose.to_pose();
        let (r_rot, r_pos) = &theirs.trunk[k];
        height = height.max((pos.z - r_pos.z).abs());
        horizontal = horizontal.max((pos - r_pos).xy().norm());
        tilt = tilt.max((rot.column(2) - r_rot.column(2)).norm());
        let dq = (0..12).map(|j| (ours.q[12 * k + j] - theirs.q[12 * k + j]).abs());
        joints = joints.max(dq.fold(0.0, f64::max));
    }
    assert!(
        height < 1e-2 && horizontal < 5e-2 && tilt < 0.05 && joints < 0.07,
        "trotting: physid and rapier apart by {height} m, {horizontal} m, {tilt} rad, {joints} rad"
    );
    // Each foot is down for the same share of the run, within 2 % of it: touchdowns and
    // lift-offs at the same instants, cycle after cycle.
    let n = ours.len();
    for f in 0..4 {
        let down = |load: &dyn Fn(usize) -> f64| (0..n).filter(|&k| load(k) > 0.0).count();
        let (a, b) = (
            down(&|k| ours.contact[4 * k + f].z),
            down(&|k| theirs.normal[4 * k + f]),
        );
        assert!(a < n * 9 / 10, "foot {f} never lifts ({a} of {n})");
        assert!(
            a.abs_diff(b) < n / 50,
            "foot {f} down {a} and {b} of {n} samples"
        );
    }
}

#[test]
fn a_bad_ground_or_start_is_named_not_a_panic() {
    use crate::rapier_floating::RapierFloating;
    use nalgebra::Vector3;
    let robot = quadruped();
    let q = vec![0.0; 12];
    let start = (Vector3::new(0.0, 0.0, 0.5), Vector3::zeros());
    for ((mu, radius, dt), said) in [
        ((0.8, 0.0, 1e-4), "the feet's radius must be above 0"),
        ((0.8, f64::NAN, 1e-4), "the feet's radius must be above 0"),
        (
            (-0.1, 0.001, 1e-4),
            "the ground's friction must be finite and >= 0",
        ),
        ((0.8, 0.001, 0.0), "the step must be above 0"),
    ] {
        let err = RapierFloating::new(&robot, &feet(), (start.0, start.1, &q), (mu, radius), dt);
        let err = err.err().expect("refused").to_string();
        assert!(err.contains(said), "{said}: {err}");
    }
    let err = RapierFloating::new(
        &robot,
        &feet(),
        (start.0, start.1, &q[..3]),
        (0.8, 0.001),
        1e-4,
    );
    assert!(err
        .err()
        .expect("refused")
        .to_string()
        .contains("with 12 joint angles (got 3)"));
    let e = Standing {
        substeps: 0,
        ..Default::default()
    };
    let err = standing_in_rapier(&robot, &feet(), &e, FOOT_RADIUS).expect_err("refused");
    assert!(
        err.to_string().contains("substeps must be at least 1"),
        "{err}"
    );
}
