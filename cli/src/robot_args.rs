//! The robot options every command that loads a robot shares.

use clap::ValueEnum;
use physid::api::model::RobotOptions;
use physid::model::{Model, RotorModel};

/// Which robot, and how its rotors are modelled.
#[derive(clap::Args, Debug, Clone)]
pub struct RobotArgs {
    /// `cheetah3` (built-in leg), a .urdf file, or a .toml file with a [robot] table.
    #[arg(long, default_value = "cheetah3")]
    pub(super) robot: String,
    /// Override the rotor treatment: full (spinning rotor bodies) or reflected (armature).
    #[arg(long, value_enum)]
    rotor_model: Option<RotorArg>,
    /// Drop the rotors (the link-only model).
    #[arg(long)]
    no_rotors: bool,
    /// URDF robots: lengthen every semi-axis of the bounding ellipsoids computed from the
    /// geometry by this much (m).
    #[arg(allow_negative_numbers = true, long, value_name = "M")]
    ellipsoid_margin: Option<f64>,
    /// URDF robots: a folder holding ROS packages, for `package://` meshes (repeatable; the
    /// URDF's own folders and ROS_PACKAGE_PATH are searched first).
    #[arg(long, value_name = "DIR")]
    package_dir: Vec<std::path::PathBuf>,
    /// URDF robots: take no bounding ellipsoids from the geometry (only a sidecar's).
    #[arg(long)]
    no_geometry_ellipsoids: bool,
}

#[derive(ValueEnum, Debug, Clone, Copy)]
enum RotorArg {
    Full,
    Reflected,
}

impl RobotArgs {
    /// The library's robot options, as given.
    pub(super) fn options(&self) -> RobotOptions {
        RobotOptions {
            robot: self.robot.clone(),
            rotor_model: self.rotor_model.map(|r| match r {
                RotorArg::Full => RotorModel::Full,
                RotorArg::Reflected => RotorModel::Reflected,
            }),
            no_rotors: self.no_rotors,
            ellipsoid_margin: self.ellipsoid_margin,
            package_dirs: self.package_dir.clone(),
            no_geometry_ellipsoids: self.no_geometry_ellipsoids,
        }
    }

    /// Every file the robot reads (its URDF, sidecar, meshes): inputs no output may replace.
    pub(super) fn files(&self) -> Vec<std::path::PathBuf> {
        self.options().files()
    }

    /// Loads the robot, printing the loader's warnings.
    pub(super) fn load(&self) -> anyhow::Result<Model> {
        let physid::api::model::LoadedRobot { model: m, notices } = self.options().load()?;
        for n in notices {
            eprintln!("{n}");
        }
        Ok(m)
    }
}
