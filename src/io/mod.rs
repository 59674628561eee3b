//! File formats: robot descriptions in (URDF, TOML), models out (MJCF, URDF), and the one
//! place that touches the file system. Every error names the file and the element at fault;
//! every file is written atomically (temporary file, then rename).

pub mod mcap_log;
pub mod mjcf;
pub mod robot_toml;
pub mod samples;
pub mod urdf;

use crate::model::{cheetah3, Model, ModelError};
use std::path::{Path, PathBuf};

/// An input or output failure, naming the file and what in it is wrong.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// The file could not be read or written.
    #[error("{path}: {source}")]
    Fs {
        /// The file.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// The file is not valid in its format (XML, TOML).
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// What the parser reported, with line and key where known.
        message: String,
    },
    /// The description is well formed but not a valid robot (missing link, loop, bad value).
    #[error("{path}: {message}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the element.
        message: String,
    },
    /// The model built from the file is not valid.
    #[error("{path}: {source}")]
    Model {
        /// The file.
        path: PathBuf,
        /// The model error, naming the body, joint or rotor.
        source: ModelError,
    },
    /// An unknown robot name.
    #[error(
        "unknown robot '{0}': give 'cheetah3', a .urdf file or a .toml file with a [robot] table"
    )]
    UnknownRobot(String),
}

impl IoError {
    pub(crate) fn invalid(path: &Path, message: impl Into<String>) -> Self {
        IoError::Invalid {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
}

/// Reads a whole file, naming it on failure.
pub fn read_to_string(path: &Path) -> Result<String, IoError> {
    std::fs::read_to_string(path).map_err(|source| IoError::Fs {
        path: path.to_path_buf(),
        source,
    })
}

/// Writes `contents` to `path` atomically: a temporary file in the same directory, then a rename,
/// so a reader never sees half a file and a failure leaves any old file intact.
pub fn write_atomic(path: &Path, contents: &[u8]) -> Result<(), IoError> {
    use std::io::Write;
    let fs_err = |source| IoError::Fs {
        path: path.to_path_buf(),
        source,
    };
    let mut tmp = new_temp_beside(path)?;
    tmp.write_all(contents).map_err(fs_err)?;
    tmp.as_file().sync_all().map_err(fs_err)?;
    tmp.persist(path).map_err(|e| fs_err(e.error))?;
    Ok(())
}

/// Reads a scenario file: the scenario, its robot (the ground truth), and the file's text.
/// Errors name the file, the line and the key.
pub fn load_scenario(
    path: &Path,
) -> Result<(crate::sim::scenario::Scenario, Model, String), IoError> {
    let text = read_to_string(path)?;
    let sc: crate::sim::scenario::Scenario =
        toml::from_str(&text).map_err(|e| robot_toml::toml_error(path, e))?;
    let model = robot_toml::from_spec(&sc.robot, path)?;
    sc.validate(model.dof())
        .map_err(|e| IoError::invalid(path, e.to_string()))?;
    Ok((sc, model, text))
}

/// A temporary file in the directory of `path` (so the final rename stays on one file system),
/// readable by others like a normally created file (0644 on Unix).
pub fn new_temp_beside(path: &Path) -> Result<tempfile::NamedTempFile, IoError> {
    let fs_err = |source| IoError::Fs {
        path: path.to_path_buf(),
        source,
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let tmp = tempfile::NamedTempFile::new_in(&dir).map_err(fs_err)?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        tmp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644))
            .map_err(fs_err)?;
    }
    Ok(tmp)
}

/// Resolves a `--robot` argument: `cheetah3` (the built-in leg), a `.urdf` file, or a `.toml`
/// file whose `[robot]` table describes the robot (see [`robot_toml`]).
pub fn load_robot(arg: &str) -> Result<Model, IoError> {
    let path = Path::new(arg);
    match path.extension().and_then(|e| e.to_str()) {
        _ if arg == "cheetah3" => Ok(cheetah3::leg()),
        Some("urdf") => urdf::load(path, &robot_toml::RobotExtras::default(), path.parent()),
        Some("toml") => robot_toml::load(path),
        _ => Err(IoError::UnknownRobot(arg.to_string())),
    }
}

/// Loads identification data: the processed signals of a physid MCAP, the joint states of another
/// MCAP, or a CSV; q̈ is derived (zero-phase 20 Hz Butterworth, central differences) if absent.
pub fn load_trajectory(path: &Path, model: &Model) -> anyhow::Result<samples::Trajectory> {
    let names: Vec<String> = model.bodies.iter().map(|b| b.joint_name.clone()).collect();
    let mut tr = match path.extension().and_then(|e| e.to_str()) {
        Some("mcap") => crate::io::mcap_log::read(path)?
            .identification_input()
            .clone(),
        Some("csv") => crate::io::samples::read_csv(path, Some(&names))?,
        _ => anyhow::bail!("{}: give a .mcap or .csv file", path.display()),
    };
    if tr.dof() != model.dof() {
        anyhow::bail!(
            "{}: the data have {} joints, the robot has {}",
            path.display(),
            tr.dof(),
            model.dof()
        );
    }
    tr.validate()
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    if tr.qdd.is_none() {
        let dts: Vec<f64> = tr.t.windows(2).map(|w| w[1] - w[0]).collect();
        let mut sorted = dts.clone();
        sorted.sort_by(f64::total_cmp);
        let dt = sorted.get(sorted.len() / 2).copied().unwrap_or(1e-3);
        let fs = 1.0 / dt;
        let sos = crate::sim::signal::butterworth_lowpass(2, (20.0f64).min(0.4 * fs), fs)?;
        let n = tr.dof();
        let m = tr.len();
        let mut qdd = vec![0.0; m * n];
        for j in 0..n {
            let qd: Vec<f64> = (0..m).map(|k| tr.qd[k * n + j]).collect();
            for (k, v) in sos
                .filtfilt(&crate::sim::signal::differentiate(&qd, dt))
                .into_iter()
                .enumerate()
            {
                qdd[k * n + j] = v;
            }
        }
        tr.qdd = Some(qdd);
        eprintln!("note: {} has no ddq columns; q̈ = zero-phase 20 Hz Butterworth of the central difference of q̇", path.display());
    }
    Ok(tr)
}
