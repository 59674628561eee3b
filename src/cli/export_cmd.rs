//! `physid export`: a robot as MJCF and/or URDF.

use super::RobotArgs;
use std::path::PathBuf;

/// Export a robot to MJCF (rotors as armature) and/or URDF (rotors as mimic joints).
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    robot: RobotArgs,
    /// Write MJCF here.
    #[arg(long)]
    mjcf: Option<PathBuf>,
    /// Write URDF here.
    #[arg(long)]
    urdf: Option<PathBuf>,
}

/// `physid export`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let outputs: Vec<&std::path::Path> =
        a.mjcf.iter().chain(&a.urdf).map(|p| p.as_path()).collect();
    physid::io::check_outputs(&outputs, &[std::path::Path::new(&a.robot.robot)])?;
    let m = a.robot.load()?;
    anyhow::ensure!(
        a.mjcf.is_some() || a.urdf.is_some(),
        "give --mjcf FILE and/or --urdf FILE"
    );
    if let Some(p) = &a.mjcf {
        physid::io::write_atomic(p, physid::io::mjcf::to_string(&m).as_bytes())?;
        eprintln!("wrote {}", p.display());
    }
    if let Some(p) = &a.urdf {
        physid::io::write_atomic(p, physid::io::urdf::to_string(&m).as_bytes())?;
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}
