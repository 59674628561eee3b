//! `export`: a robot (as described, or as identified) written for other tools: MJCF for MuJoCo
//! (rotors as joint armature) and URDF with its physid sidecar (rotors as mimic joints).

use super::data::Notice;
use super::ApiError;
use crate::model::Model;
use std::path::{Path, PathBuf};

/// Writes `model` as MJCF at `path` (whole, atomically), never over one of `inputs`. The
/// meshes MuJoCo cannot read (only STL and OBJ are written) come back as a warning.
pub fn write_mjcf(model: &Model, path: &Path, inputs: &[PathBuf]) -> Result<Vec<Notice>, ApiError> {
    let inputs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
    crate::io::check_outputs(&[path], &inputs)?;
    crate::io::write_atomic(path, crate::io::mjcf::to_string(model).as_bytes())?;
    let lost = crate::io::mjcf::unwritten(model);
    Ok(if lost.is_empty() {
        vec![]
    } else {
        vec![Notice::warning(format!(
            "{}: {} meshes are in a format MuJoCo does not read (STL and OBJ only) and are not in the MJCF: {}",
            path.display(),
            lost.len(),
            lost.join(", ")
        ))]
    })
}

/// Writes `model`, described by `robot` (`cheetah3`, a URDF or a robot TOML), as URDF at `path`
/// with its sidecar `<name>.physid.toml` (a URDF robot's own file with its `<inertial>` and
/// `<dynamics>` rewritten, else a new file), never over one of `inputs`.
pub fn write_urdf(
    model: &Model,
    robot: &str,
    path: &Path,
    inputs: &[PathBuf],
) -> Result<(), ApiError> {
    let sidecar = crate::io::sidecar_path(path);
    let inputs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
    crate::io::check_outputs(&[path, &sidecar], &inputs)?;
    crate::io::export_urdf(path, robot, model, model, None)?;
    Ok(())
}
