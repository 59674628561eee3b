//! `physid dynamics`: the dynamics at random states as JSON, for the cross-check scripts.

use super::RobotArgs;
use nalgebra::DMatrix;
use physid::dynamics::{crba, regressor, rnea, Data};
use physid::model::random::random_state;
use physid::model::Model;
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
    let rows = |x: &DMatrix<f64>| -> Vec<Vec<f64>> {
        x.row_iter().map(|r| r.iter().copied().collect()).collect()
    };
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
