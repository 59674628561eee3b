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
    /// Write URDF here (a URDF robot's own file with its `<inertial>` and `<dynamics>`
    /// rewritten, else a new file), and beside it `<name>.physid.toml` (bounding ellipsoids,
    /// rotor model, sidecar rotors).
    #[arg(long)]
    urdf: Option<PathBuf>,
    /// The robot floating (the built-in `cheetah3` as the quadruped, a URDF's root link as the
    /// trunk): MJCF with a free joint on the trunk, URDF with the trunk as its root link (for
    /// pinocchio's free flyer).
    #[arg(long)]
    floating_base: bool,
}

/// `physid export`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let sidecar = a.urdf.as_deref().map(physid::io::sidecar_path);
    let outputs: Vec<&std::path::Path> = a
        .mjcf
        .iter()
        .chain(&a.urdf)
        .chain(&sidecar)
        .map(|p| p.as_path())
        .collect();
    let inputs = a.robot.files();
    let inputs: Vec<&std::path::Path> = inputs.iter().map(|p| p.as_path()).collect();
    physid::io::check_outputs(&outputs, &inputs)?;
    if a.floating_base {
        return export_floating(&a);
    }
    let m = a.robot.load()?;
    anyhow::ensure!(
        a.mjcf.is_some() || a.urdf.is_some(),
        "give --mjcf FILE and/or --urdf FILE"
    );
    if let Some(p) = &a.mjcf {
        for n in physid::api::export::write_mjcf(&m, p, &a.robot.files())? {
            eprintln!("{n}");
        }
        eprintln!("wrote {}", p.display());
    }
    if let Some(p) = &a.urdf {
        physid::io::export_urdf(p, &a.robot.robot, &m, &m, None)?;
        eprintln!(
            "wrote {} and {}",
            p.display(),
            physid::io::sidecar_path(p).display()
        );
    }
    Ok(())
}

/// `physid export --floating-base`: MJCF with a free joint, URDF with the trunk as its root
/// link and its sidecar (outputs already checked).
fn export_floating(a: &Args) -> anyhow::Result<()> {
    anyhow::ensure!(
        a.mjcf.is_some() || a.urdf.is_some(),
        "give --mjcf FILE and/or --urdf FILE"
    );
    let physid::api::model::LoadedFloatingRobot { robot, notices } =
        a.robot.options().load_floating()?;
    for n in notices {
        eprintln!("{n}");
    }
    if let Some(path) = &a.mjcf {
        let text = physid::io::mjcf::floating_to_string(&robot);
        physid::io::write_atomic(path, text.as_bytes())?;
        eprintln!("wrote {}", path.display());
    }
    if let Some(path) = &a.urdf {
        let inputs = a.robot.files();
        let inputs: Vec<&std::path::Path> = inputs.iter().map(|p| p.as_path()).collect();
        physid::io::export_floating_urdf(path, &robot, &inputs)?;
        eprintln!(
            "wrote {} and {} (its bounding ellipsoids: --robot the sidecar)",
            path.display(),
            physid::io::sidecar_path(path).display()
        );
    }
    Ok(())
}
