//! `physid dynamics`: the dynamics at random states as JSON, for the cross-check scripts.

use super::RobotArgs;
use nalgebra::DMatrix;
use nalgebra::Vector3;
use physid::dynamics::{
    crba, crba_floating, point_jacobian_floating, regressor, regressor_floating, rnea,
    rnea_floating, BaseState, Data,
};
use physid::model::floating::FloatingModel;
use physid::model::random::random_state;
use physid::model::Model;
use physid::spatial::Motion;
use serde_json::json;
use std::path::PathBuf;

/// Evaluate the dynamics at random states and write JSON (q, qd, qdd, tau, Y, H) for the
/// cross-check scripts.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    robot: RobotArgs,
    /// Number of random states (at most 100,000).
    #[arg(allow_negative_numbers = true, long, default_value_t = 20, value_parser = clap::value_parser!(u64).range(1..=100_000))]
    samples: u64,
    /// Random seed.
    #[arg(allow_negative_numbers = true, long, default_value_t = 1)]
    seed: u64,
    /// Range of the random joint positions, velocities and accelerations (±).
    #[arg(long, default_value_t = 2.0, allow_negative_numbers = true)]
    scale: f64,
    /// Output JSON file.
    #[arg(long)]
    out: PathBuf,
    /// The robot on a floating trunk: the built-in `cheetah3` becomes the Cheetah-3-like
    /// quadruped (trunk and four legs), a URDF's root link (and the links fixed to it) the
    /// trunk; each state also gets a random trunk pose, twist and acceleration, and the JSON
    /// the wrench on the trunk, the floating-base regressor, mass matrix and the Jacobians of
    /// the feet (the quadruped's; a URDF's leaf bodies' centres of mass), with the tree as URDF.
    #[arg(long)]
    floating_base: bool,
}

/// `physid dynamics`.
pub fn run(a: Args) -> anyhow::Result<()> {
    anyhow::ensure!(
        a.scale.is_finite() && a.scale > 0.0,
        "--scale must be a positive number, got {}",
        a.scale
    );
    let inputs = a.robot.files();
    let inputs: Vec<&std::path::Path> = inputs.iter().map(|p| p.as_path()).collect();
    physid::io::check_outputs(&[a.out.as_path()], &inputs)?;
    if a.floating_base {
        let physid::api::model::LoadedFloatingRobot { robot, notices } =
            a.robot.options().load_floating()?;
        for n in notices {
            eprintln!("{n}");
        }
        return floating_json(&robot, a.samples as usize, a.seed, a.scale, &a.out);
    }
    dynamics_json(
        &a.robot.load()?,
        a.samples as usize,
        a.seed,
        a.scale,
        &a.out,
    )
}

/// Writes random-state dynamics as JSON for the check scripts.
pub fn dynamics_json(
    m: &Model,
    samples: usize,
    seed: u64,
    scale: f64,
    out: &std::path::Path,
) -> anyhow::Result<()> {
    let mut d = Data::new(m);
    let mut y = DMatrix::zeros(m.dof(), m.layout().len);
    let mut states = vec![];
    for s in 0..samples {
        let [q, qd, qdd] = random_state(
            seed.wrapping_mul(1_000_003).wrapping_add(s as u64),
            m.dof(),
            scale,
        );
        let tau = rnea(m, &mut d, &q, &qd, &qdd).clone();
        regressor(m, &mut d, &q, &qd, &qdd, &mut y);
        let h = crba(m, &mut d, &q).clone();
        states.push(json!({"q": q, "qd": qd, "qdd": qdd, "tau": tau.as_slice(), "Y": rows(&y), "H": rows(&h)}));
    }
    let v = json!({
        "model": m.name(), "rotor_model": m.rotor_model(),
        "joint_names": m.joint_names(),
        "body_names": m.bodies().iter().map(|b| b.name.clone()).collect::<Vec<_>>(),
        "parameter_names": m.parameter_names(), "theta": m.parameters().as_slice(),
        "samples": states,
    });
    let v = physid::io::versioned("dynamics", &v);
    physid::io::write_atomic(out, serde_json::to_string(&v)?.as_bytes())?;
    eprintln!("wrote {} states to {}", samples, out.display());
    Ok(())
}

/// A random trunk state for sample `seed`: orientation about a random axis, position, twist
/// and acceleration within `scale`.
fn random_base(seed: u64, scale: f64) -> BaseState {
    let [a, b, c] = random_state(seed, 6, scale);
    let axis = Vector3::new(a[0], a[1], a[2]);
    let axis = if axis.norm() > 1e-9 {
        axis.normalize()
    } else {
        Vector3::z()
    };
    let rot = physid::spatial::rot_axis_angle(&axis, a[3]);
    let m = |x: &[f64]| {
        Motion::new(
            Vector3::new(x[0], x[1], x[2]),
            Vector3::new(x[3], x[4], x[5]),
        )
    };
    BaseState {
        pose: physid::spatial::Transform::from_pose(&rot, &Vector3::new(a[4], a[5], 0.5)),
        v: m(&b),
        a: m(&c),
    }
}

/// `x` as a list of rows.
fn rows(x: &DMatrix<f64>) -> Vec<Vec<f64>> {
    x.row_iter().map(|r| r.iter().copied().collect()).collect()
}

/// The points whose Jacobians the JSON gives: the quadruped's feet; for another robot each leaf
/// body's centre of mass (its origin if massless).
fn feet_of(robot: &FloatingModel) -> Vec<(usize, Vector3<f64>)> {
    let tree = robot.tree();
    if robot.name() == "cheetah3_quadruped" {
        return physid::model::quadruped::feet();
    }
    let bodies = tree.bodies();
    (0..bodies.len())
        .filter(|&i| !bodies.iter().any(|b| b.parent == Some(i)))
        .map(|i| (i, bodies[i].inertia.com().unwrap_or_default()))
        .collect()
}

/// One state's floating-base dynamics as JSON (see [`floating_json`]), with the Jacobians of
/// the points `feet`.
fn floating_state(
    robot: &FloatingModel,
    d: &mut Data,
    (base, q, qd, qdd): (&BaseState, &[f64], &[f64], &[f64]),
    feet: &[(usize, Vector3<f64>)],
) -> serde_json::Value {
    let f_b = rnea_floating(robot, d, base, q, qd, qdd);
    let tau = d.tau.clone();
    let mut y = DMatrix::zeros(robot.dof(), robot.parameter_count());
    regressor_floating(robot, d, base, (q, qd, qdd), &mut y);
    let m = crba_floating(robot, d, q);
    let jacobians: Vec<_> = feet
        .iter()
        .map(|(b, p)| rows(&point_jacobian_floating(robot, d, base, q, (*b, p))))
        .collect();
    let (rot, pos) = base.pose.to_pose();
    json!({
        "rotation": rows(&DMatrix::from_column_slice(3, 3, rot.as_slice())),
        "position": pos.as_slice(), "v": base.v.to_vec6().as_slice(), "a": base.a.to_vec6().as_slice(),
        "q": q, "qd": qd, "qdd": qdd, "f_trunk": f_b.to_vec6().as_slice(), "tau": tau.as_slice(),
        "Y": rows(&y), "M": rows(&m), "foot_jacobians": jacobians,
    })
}

/// Writes random-state floating-base dynamics as JSON for the check scripts: per state the
/// trunk's pose (rotation matrix, trunk axes in world coordinates, and position), twist and
/// acceleration (`[ω; v]`, trunk coordinates), the joint state, the wrench on the trunk and the
/// joint torques, the regressor, the mass matrix and the four feet's Jacobians.
fn floating_json(
    robot: &FloatingModel,
    samples: usize,
    seed: u64,
    scale: f64,
    out: &std::path::Path,
) -> anyhow::Result<()> {
    let tree = robot.tree();
    let n = tree.dof();
    let mut d = Data::new(tree);
    let feet = feet_of(robot);
    let states: Vec<_> = (0..samples)
        .map(|s| {
            let k = seed.wrapping_mul(1_000_003).wrapping_add(s as u64);
            let base = random_base(k.wrapping_add(7), scale);
            let [q, qd, qdd] = random_state(k, n, scale);
            floating_state(robot, &mut d, (&base, &q, &qd, &qdd), &feet)
        })
        .collect();
    let v = json!({
        "model": robot.name(), "rotor_model": tree.rotor_model(),
        "joint_names": tree.joint_names(), "trunk": robot.trunk().name,
        "trunk_pi": robot.trunk().inertia.0.as_slice(),
        "parameter_names": robot.parameter_names(), "theta": robot.parameters().as_slice(),
        "feet": feet.iter().map(|f| f.0).collect::<Vec<_>>(),
        "foot_points": feet.iter().map(|f| f.1.as_slice().to_vec()).collect::<Vec<_>>(),
        "tree_urdf": physid::io::urdf::to_string(tree),
        "samples": states,
    });
    let v = physid::io::versioned("dynamics", &v);
    physid::io::write_atomic(out, serde_json::to_string(&v)?.as_bytes())?;
    eprintln!(
        "wrote {} floating-base states to {}",
        samples,
        out.display()
    );
    Ok(())
}
