//! # physid-io
//!
//! File formats: robot descriptions in (URDF, TOML), models out (MJCF, URDF), logs in (CSV,
//! MCAP, rosbag2 in MCAP or SQLite storage) and through the data pipeline ([`prepare`]), and
//! the one place that touches the file system. Every error names the file and the element at
//! fault; every file is written atomically (temporary file, then rename). A floor of physid
//! (docs/architecture.md §6) of its own crate: it stands on `physid-core` only, which Cargo
//! enforces; the `physid` crate re-exports it as `physid::io` (and `physid::prepare`).
#![warn(missing_docs)]

pub mod cache;
pub mod document;
pub mod floating_log;
pub mod floating_mcap;
pub mod geometry;
pub mod mcap_log;
pub mod mcap_stream;
mod mcap_walk;
pub mod mjcf;
pub mod plot;
pub mod prepare;
pub mod robot_spec;
pub mod robot_toml;
pub mod rosbag2;
pub mod samples;
pub mod urdf;
pub mod urdf_patch;
mod urdf_text;

use physid_core::model::{cheetah3, Model, ModelError};
use physid_core::trajectory::Trajectory;
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
    /// An output would overwrite an input (or another output of the same run).
    #[error("{output}: refusing to write over {what} {input}")]
    OutputIsInput {
        /// The output given.
        output: PathBuf,
        /// The file it would replace.
        input: PathBuf,
        /// `the input`, `another output` or `the folder of the input`.
        what: &'static str,
    },
    /// An unknown robot name.
    #[error(
        "unknown robot '{0}': give 'cheetah3', a .urdf file or a .toml file with a [robot] table"
    )]
    UnknownRobot(String),
}

impl IoError {
    /// An error naming `path` and what in it is wrong.
    pub fn invalid(path: &Path, message: impl Into<String>) -> Self {
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

/// `p` as an absolute path: canonical when it exists, else its canonical parent directory and
/// file name (an output not yet written); none when neither resolves.
fn absolute(p: &Path) -> Option<PathBuf> {
    if let Ok(c) = p.canonicalize() {
        return Some(c);
    }
    let parent = match p.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.canonicalize().ok()?,
        _ => std::env::current_dir().ok()?,
    };
    Some(parent.join(p.file_name()?))
}

/// Whether `a` and `b` name the same file: by canonical path when both exist, else by their
/// absolute form (canonical parent directory and file name).
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (absolute(a), absolute(b)) {
        (Some(x), Some(y)) => x == y,
        _ => false,
    }
}

/// Whether `a` and `b` are the same recording: the same file ([`same_file`]), or two regular
/// files of equal bytes (compared up to 64 MiB; larger files only by path).
pub fn same_recording(a: &Path, b: &Path) -> bool {
    if same_file(a, b) {
        return true;
    }
    const MAX: u64 = 64 << 20;
    let size = |p: &Path| {
        std::fs::metadata(p)
            .ok()
            .filter(|m| m.is_file())
            .map(|m| m.len())
    };
    match (size(a), size(b)) {
        (Some(x), Some(y)) if x == y && x <= MAX => {
            matches!((std::fs::read(a), std::fs::read(b)), (Ok(u), Ok(v)) if u == v)
        }
        _ => false,
    }
}

/// The first recording given twice among `inputs` (each with the option that named it), as
/// an error naming both options and the file.
pub fn check_distinct_recordings(inputs: &[(&str, &Path)]) -> Result<(), IoError> {
    for (i, (role_a, a)) in inputs.iter().enumerate() {
        for (role_b, b) in &inputs[i + 1..] {
            if same_recording(a, b) {
                return Err(IoError::invalid(
                    b,
                    format!(
                        "the same recording is given twice ({role_a} {} and {role_b} {}): each run counts once, and a baseline or validation run must be another recording",
                        a.display(),
                        b.display()
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Refuses, before any work, outputs that would overwrite one of `inputs` or each other, or
/// whose directory does not exist.
pub fn check_outputs(outputs: &[&Path], inputs: &[&Path]) -> Result<(), IoError> {
    for (i, out) in outputs.iter().enumerate() {
        if out.is_dir() {
            return Err(IoError::invalid(
                out,
                "is a folder: give a file name for this output",
            ));
        }
        if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
            if !dir.is_dir() {
                return Err(IoError::invalid(
                    out,
                    format!("its directory {} does not exist", dir.display()),
                ));
            }
        }
        let clash = |input: &Path, what| IoError::OutputIsInput {
            output: out.to_path_buf(),
            input: input.to_path_buf(),
            what,
        };
        if let Some(input) = inputs.iter().find(|input| same_file(out, input)) {
            return Err(clash(input, "the input"));
        }
        if let Some(other) = outputs[..i].iter().find(|o| same_file(out, o)) {
            return Err(clash(other, "another output"));
        }
    }
    Ok(())
}

/// Refuses, before any work, a result directory `dir` that is one of `inputs` or holds one of
/// them (a result folder is written into, and an experiment's is replaced whole: given the
/// folder of the scenario, it would take the scenario with it).
pub fn check_result_dir(dir: &Path, inputs: &[PathBuf]) -> Result<(), IoError> {
    let Some(dir_abs) = absolute(dir) else {
        return Ok(());
    };
    for input in inputs {
        if absolute(input).is_some_and(|i| i.starts_with(&dir_abs)) {
            return Err(IoError::OutputIsInput {
                output: dir.to_path_buf(),
                input: input.clone(),
                what: "the folder of the input",
            });
        }
    }
    Ok(())
}

/// A tempfile error's text without the temporary file's path it ends in (`… at path "…"`):
/// the user gave another path, which the caller names.
fn without_temp_path(e: &std::io::Error) -> String {
    let text = e.to_string();
    text.split(" at path ").next().unwrap_or(&text).to_string()
}

/// The file every physid result folder holds; a folder without it (and not empty) is not
/// replaced by a new result.
pub const RESULT_MARK: &str = "provenance.json";

/// The file every benchmark result folder (`blind --out`, `generalize --out`) holds.
pub const SCORES_MARK: &str = "scores.json";

/// Whether `target` can take a result folder marked by `mark`: absent, an empty folder, or an
/// earlier result holding `mark` (a folder of the user's own files is never replaced).
fn check_replaceable(target: &Path, mark: &str) -> Result<(), IoError> {
    if target.exists() && !target.is_dir() {
        return Err(IoError::invalid(
            target,
            "exists and is not a directory; give a directory for the results",
        ));
    }
    let foreign = std::fs::read_dir(target)
        .map(|mut entries| entries.next().is_some())
        .unwrap_or(false)
        && !target.join(mark).is_file();
    if foreign {
        return Err(IoError::invalid(
            target,
            format!(
                "is a folder physid did not write (no {mark}), and a result replaces its folder whole; give a new or empty folder, or an earlier result to replace"
            ),
        ));
    }
    Ok(())
}

/// Checked before any work: `dir` can take a result folder marked by `mark`
/// ([`StagingDir::marked`]) and its parent folder exists (an output's folder is never created
/// on a typo).
pub fn check_result_target(dir: &Path, mark: &str) -> Result<(), IoError> {
    check_replaceable(dir, mark)?;
    let parent = match dir.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !parent.is_dir() {
        return Err(IoError::invalid(
            dir,
            format!("its folder {} does not exist", parent.display()),
        ));
    }
    Ok(())
}

/// Writes a result folder whole: `write` fills a staging folder beside `dir` that replaces
/// `dir` in one rename once complete ([`StagingDir::marked`]), so an interrupted run leaves the
/// older result (or nothing), never a mix of two.
pub fn write_result_dir<E: From<IoError>>(
    dir: &Path,
    mark: &str,
    write: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), E> {
    let staging = StagingDir::marked(dir, mark)?;
    write(staging.path())?;
    staging.commit()?;
    Ok(())
}

/// A result directory built beside its final place and moved there whole by [`Self::commit`],
/// so a reader never sees half a result or a mix of two runs: until the commit, the files live
/// in a hidden `.NAME.partial-XXXX` directory beside the target (removed on drop, and by the
/// next run if a kill left it behind); the commit renames it into place, replacing an older
/// result only once the new one is complete.
pub struct StagingDir {
    target: PathBuf,
    dir: tempfile::TempDir,
}

impl StagingDir {
    /// Stages a result for `target`, checking before any work that it can be written: `target`
    /// is a directory or absent, and its parent directory can hold a new one.
    pub fn new(target: &Path) -> Result<Self, IoError> {
        Self::marked(target, RESULT_MARK)
    }

    /// [`Self::new`] for a result whose folder holds `mark` (`report.json` for a diagnosis
    /// report, `scores.json` for a benchmark): a non-empty folder without it is refused.
    pub fn marked(target: &Path, mark: &str) -> Result<Self, IoError> {
        check_replaceable(target, mark)?;
        let name = target
            .file_name()
            .ok_or_else(|| IoError::invalid(target, "has no directory name"))?
            .to_string_lossy()
            .into_owned();
        let parent = match target.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        create_dir_all(&parent)?;
        let prefix = format!(".{name}.partial-");
        // What a killed run left behind is not a result: remove it.
        if let Ok(entries) = std::fs::read_dir(&parent) {
            for e in entries.flatten() {
                if e.file_name().to_string_lossy().starts_with(&prefix) {
                    let _ = std::fs::remove_dir_all(e.path());
                }
            }
        }
        let dir = tempfile::Builder::new()
            .prefix(&prefix)
            .tempdir_in(&parent)
            .map_err(|e| {
                let text = without_temp_path(&e);
                IoError::invalid(
                    target,
                    format!(
                        "cannot be created: its folder {} does not take a new directory ({text})",
                        parent.display()
                    ),
                )
            })?;
        Ok(Self {
            target: target.to_path_buf(),
            dir,
        })
    }

    /// Where to write the result's files.
    pub fn path(&self) -> &Path {
        self.dir.path()
    }

    /// Moves the complete result into place (replacing an older one).
    pub fn commit(self) -> Result<(), IoError> {
        let fs_err = |path: &Path| {
            let path = path.to_path_buf();
            move |source| IoError::Fs { path, source }
        };
        let staged = self.dir.keep();
        if self.target.exists() {
            // The older result steps aside under the staging name (`.NAME.partial-XXXX.old`):
            // a kill while it is removed leaves what the next run clears, never a stray
            // `.NAME.old` (`with_extension` would cut the name at its first dot).
            let mut old_name = staged.file_name().unwrap_or_default().to_os_string();
            old_name.push(".old");
            let old = staged.with_file_name(old_name);
            std::fs::rename(&self.target, &old).map_err(fs_err(&self.target))?;
            std::fs::rename(&staged, &self.target).map_err(fs_err(&self.target))?;
            std::fs::remove_dir_all(&old).map_err(fs_err(&old))?;
        } else {
            std::fs::rename(&staged, &self.target).map_err(fs_err(&self.target))?;
        }
        Ok(())
    }
}

/// The first item of `items` (among those `counted`) that repeats an earlier one: the earlier
/// one's index and its own.
pub fn first_repeat<T: PartialEq>(
    items: &[T],
    counted: impl Fn(&T) -> bool,
) -> Option<(usize, usize)> {
    first_repeat_by(items, |y, x| counted(x) && y == x)
}

/// The first item of `items` that `equal` finds equal to an earlier one: the earlier one's
/// index and its own.
pub fn first_repeat_by<T>(items: &[T], equal: impl Fn(&T, &T) -> bool) -> Option<(usize, usize)> {
    (items.iter().enumerate())
        .find_map(|(i, x)| items[..i].iter().position(|y| equal(y, x)).map(|j| (j, i)))
}

/// The memory available to a new allocation (bytes; Linux's `MemAvailable`, `None` where it
/// cannot be read).
pub fn available_memory() -> Option<f64> {
    std::fs::read_to_string("/proc/meminfo").ok().and_then(|m| {
        m.lines()
            .find_map(|l| l.strip_prefix("MemAvailable:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
            .map(|kb| kb * 1024.0)
    })
}

/// Creates a directory and its parents, naming it on failure.
pub fn create_dir_all(dir: &Path) -> Result<(), IoError> {
    std::fs::create_dir_all(dir).map_err(|source| IoError::Fs {
        path: dir.to_path_buf(),
        source,
    })
}

/// `value` as a JSON object stamped with physid's version and the output's schema name, e.g.
/// `physid.identify/1` (the fields of `value` follow at the top level; a value that is not an
/// object is put under `data`). Every JSON physid writes carries these two fields.
pub fn versioned<T: serde::Serialize>(schema: &str, value: &T) -> serde_json::Value {
    let mut out = serde_json::Map::new();
    out.insert("physid_version".into(), env!("CARGO_PKG_VERSION").into());
    out.insert("schema".into(), format!("physid.{schema}/1").into());
    match serde_json::to_value(value) {
        Ok(serde_json::Value::Object(fields)) => out.extend(fields),
        Ok(other) => {
            out.insert("data".into(), other);
        }
        Err(e) => {
            out.insert("error".into(), e.to_string().into());
        }
    }
    serde_json::Value::Object(out)
}

/// Serde's spelling of a unit enum value (what the JSON writes, e.g. `partially_explained`), so
/// tables and text spell it the same way; empty for a value that is not a string.
pub fn serde_name<T: serde::Serialize>(v: &T) -> String {
    serde_json::to_value(v)
        .ok()
        .and_then(|v| v.as_str().map(String::from))
        .unwrap_or_default()
}

/// A Markdown table cell: `|` escaped (a regime like `|qd| low`, an ambiguity group `a|b`, a
/// user's joint name), line breaks as spaces.
pub fn md_cell(s: &str) -> String {
    s.replace('|', "\\|").replace(['\n', '\r'], " ")
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

/// The name prefix of every file physid writes before renaming it into place.
pub const PARTIAL_PREFIX: &str = ".physid-partial-";

/// Removes what killed runs left in `dir`: files named with [`PARTIAL_PREFIX`] (never a result:
/// a result is renamed away from that name once complete).
pub fn remove_partials(dir: &Path) {
    if let Ok(entries) = std::fs::read_dir(dir) {
        for e in entries.flatten() {
            if e.file_name().to_string_lossy().starts_with(PARTIAL_PREFIX) {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
}

/// A temporary file in the directory of `path` (so the final rename stays on one file system),
/// named with [`PARTIAL_PREFIX`], readable by others like a normally created file (0644 on
/// Unix).
pub fn new_temp_beside(path: &Path) -> Result<tempfile::NamedTempFile, IoError> {
    let fs_err = |source| IoError::Fs {
        path: path.to_path_buf(),
        source,
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let tmp = tempfile::Builder::new()
        .prefix(PARTIAL_PREFIX)
        .tempfile_in(&dir)
        .map_err(|e| fs_err(std::io::Error::new(e.kind(), without_temp_path(&e))))?;
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
    load_robot_with(arg, &robot_spec::RobotOptions::default()).map(|(m, _)| m)
}

/// [`load_robot`] with options (bounding ellipsoids from geometry: margin, package folders),
/// returning the loader's warnings too (for example a body whose meshes were not found, so
/// that it has no bounding ellipsoid).
pub fn load_robot_with(
    arg: &str,
    opts: &robot_spec::RobotOptions,
) -> Result<(Model, Vec<String>), IoError> {
    let path = Path::new(arg);
    opts.validate().map_err(|m| IoError::invalid(path, m))?;
    match path.extension().and_then(|e| e.to_str()) {
        _ if arg == "cheetah3" => Ok((cheetah3::leg(), vec![])),
        Some("urdf") => {
            let extras = robot_spec::RobotExtras {
                geometry: opts.over(&Default::default()),
                ..Default::default()
            };
            urdf::load(path, &extras)
        }
        Some("toml") => robot_toml::load_with(path, opts),
        _ => Err(IoError::UnknownRobot(arg.to_string())),
    }
}

/// Loads a floating robot from a `--robot` argument: the built-in `cheetah3` as the
/// Cheetah-3-like quadruped (four of its legs on a trunk), or a URDF whose root link (with the
/// links fixed to it) is the trunk ([`urdf::load_floating`]), or a robot TOML naming such a
/// URDF ([`robot_toml::load_floating_with`]: the sidecar of a floating export).
pub fn load_floating_robot_with(
    arg: &str,
    opts: &robot_spec::RobotOptions,
) -> Result<(physid_core::model::floating::FloatingModel, Vec<String>), IoError> {
    let path = Path::new(arg);
    opts.validate().map_err(|m| IoError::invalid(path, m))?;
    match path.extension().and_then(|e| e.to_str()) {
        _ if arg == "cheetah3" => Ok((physid_core::model::quadruped::quadruped(), vec![])),
        Some("urdf") => {
            let extras = robot_spec::RobotExtras {
                geometry: opts.over(&Default::default()),
                ..Default::default()
            };
            urdf::load_floating(path, &extras)
        }
        Some("toml") => robot_toml::load_floating_with(path, opts),
        _ => Err(IoError::UnknownRobot(arg.to_string())),
    }
}

/// Writes the floating robot `robot` as URDF at `out` ([`urdf::floating_to_string`]: the
/// trunk its root link, rotors as mimic joints) and beside it the sidecar ([`sidecar_path`])
/// carrying what URDF cannot: every body's bounding ellipsoid, the trunk's and the rotors'
/// among them, gravity and the rotor model (`--robot` the sidecar to read it back whole).
/// Neither output may be one of `inputs`.
pub fn export_floating_urdf(
    out: &Path,
    robot: &physid_core::model::floating::FloatingModel,
    inputs: &[&Path],
) -> Result<(), IoError> {
    let side = sidecar_path(out);
    check_outputs(&[out, side.as_path()], inputs)?;
    let text = urdf::floating_to_string(robot);
    let name = out
        .file_name()
        .map_or("robot.urdf".into(), |n| n.to_string_lossy().into_owned());
    let trunk = robot.trunk();
    let trunk_ellipsoid = (trunk.bounding.as_ref()).map(|e| {
        format!(
            "\n{}",
            urdf_patch::ellipsoid_toml(&trunk.name, e, &trunk.inertia)
        )
    });
    let side_text = urdf_patch::sidecar(
        robot.tree(),
        &name,
        &urdf_patch::mimic_links(&text),
        trunk_ellipsoid.as_deref(),
    );
    write_atomic(out, text.as_bytes())?;
    write_atomic(&side, side_text.as_bytes())
}

/// The URDF file behind a `--robot` argument: the file itself, or a robot TOML's `urdf`; `None`
/// for the built-in leg and explicit trees.
pub fn robot_urdf(arg: &str) -> Result<Option<PathBuf>, IoError> {
    let path = Path::new(arg);
    match path.extension().and_then(|e| e.to_str()) {
        Some("urdf") if arg != "cheetah3" => Ok(Some(path.to_path_buf())),
        Some("toml") => Ok(robot_toml::read_spec(path)?
            .urdf
            .map(|u| path.parent().unwrap_or(Path::new(".")).join(u))),
        _ => Ok(None),
    }
}

/// Every file a `--robot` argument reads: the file itself, the URDF behind it, that URDF's
/// sidecar (`arm.physid.toml`) and the meshes it names (found with `package_dirs`). An output
/// must replace none of them.
pub fn robot_files(arg: &str, package_dirs: &[PathBuf]) -> Vec<PathBuf> {
    if arg == "cheetah3" {
        return vec![];
    }
    let mut out = vec![PathBuf::from(arg)];
    if let Ok(Some(urdf)) = robot_urdf(arg) {
        let sidecar = sidecar_path(&urdf);
        if sidecar.is_file() {
            out.push(sidecar);
        }
        out.extend(geometry::referenced_meshes(&urdf, package_dirs));
        out.push(urdf);
    }
    out
}

/// Every file a scenario (or robot TOML) file reads: itself, and its robot's URDF, sidecar
/// and meshes ([`robot_files`]).
pub fn scenario_files(path: &Path) -> Vec<PathBuf> {
    robot_files(&path.to_string_lossy(), &[])
}

/// The sidecar written beside an exported URDF: `arm.urdf` → `arm.physid.toml`.
pub fn sidecar_path(urdf: &Path) -> PathBuf {
    let stem = urdf
        .file_stem()
        .map_or("robot".into(), |s| s.to_string_lossy().into_owned());
    urdf.with_file_name(format!("{stem}.physid.toml"))
}

/// Writes `identified` (a model with `model`'s structure) as URDF at `out`: the URDF behind
/// `robot` patched in place ([`urdf_patch::patch`]) when there is one, else a new file
/// ([`urdf::to_string`]); and beside it the sidecar ([`sidecar_path`], [`urdf_patch::sidecar`])
/// with `extra` TOML tables appended if given. Neither output may be an input.
pub fn export_urdf(
    out: &Path,
    robot: &str,
    model: &Model,
    identified: &Model,
    extra: Option<&str>,
) -> Result<(), IoError> {
    let source = robot_urdf(robot)?;
    let side = sidecar_path(out);
    let inputs: Vec<&Path> = [Path::new(robot)]
        .into_iter()
        .chain(source.as_deref())
        .collect();
    check_outputs(&[out, side.as_path()], &inputs)?;
    let text = match &source {
        Some(src) => urdf_patch::patch(&read_to_string(src)?, src, model, identified)?,
        None => urdf::to_string(identified),
    };
    let name = out
        .file_name()
        .map_or("robot.urdf".into(), |n| n.to_string_lossy().into_owned());
    let side_text = urdf_patch::sidecar(identified, &name, &urdf_patch::mimic_links(&text), extra);
    let text = if side_text.contains("\n[information]\n") {
        with_sidecar_mark(&text, &side)
    } else {
        text
    };
    write_atomic(out, text.as_bytes())?;
    write_atomic(&side, side_text.as_bytes())
}

/// The comment an identified URDF carries when its sidecar holds the identification's
/// information matrix: a copy without the sidecar is then told, not silently held looser.
pub const SIDECAR_MARK: &str = "physid identify: this description's uncertainty";

/// `urdf` with the [`SIDECAR_MARK`] comment naming its sidecar `side`, after the XML
/// declaration (or first).
fn with_sidecar_mark(urdf: &str, side: &Path) -> String {
    let name = side
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let mark = format!(
        "<!-- {SIDECAR_MARK} (its [information] table) is in {name} beside this file -->\n"
    );
    match urdf
        .strip_prefix("<?xml")
        .and_then(|rest| rest.find('\n').map(|i| i + 6))
    {
        Some(end) => format!("{}{mark}{}", &urdf[..end], &urdf[end..]),
        None => format!("{mark}{urdf}"),
    }
}

/// Identification data read from one file and put through the pipeline ([`crate::prepare`]).
#[derive(Clone, Debug)]
pub struct LoadedData {
    /// The runs (split at gaps, q̇ and q̈ derived where not logged, ends trimmed).
    pub runs: Vec<crate::prepare::Run>,
    /// What the pipeline did, every sample counted.
    pub report: crate::prepare::Report,
    /// Joints in the file that the robot does not have (left out).
    pub ignored_joints: Vec<String>,
    /// Joint-state messages naming none of the robot's joints (skipped).
    pub skipped_messages: usize,
}

impl LoadedData {
    /// The runs' trajectories.
    pub fn trajectories(&self) -> Vec<Trajectory> {
        self.runs.iter().map(|r| r.trajectory.clone()).collect()
    }
    /// The runs joined end to end ([`Trajectory::concatenate`]); for data known to be one run.
    pub fn joined(&self) -> Trajectory {
        Trajectory::concatenate(self.trajectories()).expect("the pipeline keeps at least one run")
    }
}

/// How identification data are read ([`load_trajectory_with`]).
#[derive(Clone, Debug, Default)]
pub struct DataOptions {
    /// The `JointState` topic of an MCAP file or rosbag2 directory; `None`: physid's processed
    /// signals if the log has them, else `/joint_states`.
    pub topic: Option<String>,
    /// Which time stamps a joint-state sample.
    pub stamp: mcap_log::Stamp,
    /// The pipeline's options (cutoff, locked joints).
    pub prepare: crate::prepare::Options,
    /// Runs held in memory, each read where its label is given as a data file.
    pub memory: std::sync::Arc<[MemoryLog]>,
}

/// A run held in memory (arrays a caller already has): read through the pipeline as a file
/// is, its `label` standing for the file's path in the options that name runs and in every
/// message. Labels are not paths (`<arrays 1>`), so no file is taken for one.
#[derive(Clone, Debug)]
pub struct MemoryLog {
    /// What names the run (as a data file's path would).
    pub label: PathBuf,
    /// Its samples as logged.
    pub logged: crate::prepare::Logged,
}

/// [`load_trajectory_with`] with the default options.
pub fn load_trajectory(path: &Path, model: &Model) -> Result<LoadedData, IoError> {
    load_trajectory_with(path, model, &DataOptions::default())
}

/// Loads identification data: the processed signals of a physid MCAP, the joint states of
/// another MCAP or of a rosbag2 directory (matched to `model`'s joints by name, in any order,
/// extra joints left out), or a CSV (numbered columns in the robot's joint order, or columns
/// named by joint); then the pipeline ([`crate::prepare::prepare`]: runs split at gaps, q̇ and
/// q̈ derived where not logged, ends trimmed). Errors name the file and the sample.
pub fn load_trajectory_with(
    path: &Path,
    model: &Model,
    opts: &DataOptions,
) -> Result<LoadedData, IoError> {
    let (logged, ignored_joints, skipped_messages) = load_logged(path, model, opts)?;
    let prepared = crate::prepare::prepare(&logged, &opts.prepare)
        .map_err(|e| IoError::invalid(path, e.to_string()))?;
    Ok(LoadedData {
        runs: prepared.runs,
        report: prepared.report,
        ignored_joints,
        skipped_messages,
    })
}

/// Loads several data files read together (training and validation runs): each through the
/// pipeline, with one cutoff for all (chosen from the motion of all of them when not given), so
/// that every run is processed alike.
pub fn load_all(
    paths: &[&Path],
    model: &Model,
    opts: &DataOptions,
) -> Result<Vec<LoadedData>, IoError> {
    // Files read side by side; the first error in the files' order is the one reported.
    let read: Vec<_> = {
        use rayon::prelude::*;
        let each: Vec<_> = paths
            .par_iter()
            .map(|p| load_logged(p, model, opts))
            .collect();
        each.into_iter().collect::<Result<_, _>>()?
    };
    let logs: Vec<&crate::prepare::Logged> = read.iter().map(|(l, _, _)| l).collect();
    check_distinct_samples(paths, &logs)?;
    let mut popts = opts.prepare.clone();
    let own_edges = match popts.cutoff {
        None => crate::prepare::band_edges(&logs),
        Some(_) => vec![None; read.len()],
    };
    popts.band_edge = own_edges.iter().flatten().copied().reduce(f64::max);
    // Each file prepared on its own (side by side); the first error in the files' order.
    use rayon::prelude::*;
    let each: Vec<Result<LoadedData, IoError>> = (paths.par_iter().zip(read).zip(own_edges))
        .map(
            |((path, (logged, ignored_joints, skipped_messages)), own)| {
                let mut prepared = crate::prepare::prepare(&logged, &popts)
                    .map_err(|e| IoError::invalid(path, e.to_string()))?;
                if prepared.report.band_edge.is_some() {
                    prepared.report.own_band_edge = own;
                }
                Ok(LoadedData {
                    runs: prepared.runs,
                    report: prepared.report,
                    ignored_joints,
                    skipped_messages,
                })
            },
        )
        .collect();
    each.into_iter().collect()
}

/// Refuses two runs of `paths` whose samples are the same (every angle and torque equal): one
/// recording in two files (an MCAP bag and its SQLite conversion, a CSV export), which
/// [`check_distinct_recordings`] cannot see from the files' bytes and which would count each
/// sample twice.
fn check_distinct_samples(
    paths: &[&Path],
    logs: &[&crate::prepare::Logged],
) -> Result<(), IoError> {
    let same = |a: &crate::prepare::Logged, b: &crate::prepare::Logged| {
        !a.is_empty() && a.q == b.q && a.tau == b.tau
    };
    let Some((i, j)) = first_repeat_by(logs, |a, b| same(a, b)) else {
        return Ok(());
    };
    Err(IoError::invalid(
        paths[j],
        format!(
            "holds the same {} samples as {} (every angle and torque equal): one recording given twice, in two files or formats; each run counts once",
            logs[j].len(),
            paths[i].display()
        ),
    ))
}

/// Reads joint states from an MCAP file or a rosbag2 directory (its `metadata.yaml` and the
/// files it lists, in order; MCAP or SQLite storage) into one log, times from its first
/// message ([`mcap_log::read_with`] for one file). Errors name the file, the topic and the
/// message.
pub fn read_joint_log(path: &Path, opts: &mcap_log::ReadOptions) -> Result<mcap_log::Log, IoError> {
    read_log(path, mcap_log::Reader::new(opts))
}

/// [`read_joint_log`] with `reader`, which may pass other topics' messages on.
pub(crate) fn read_log(
    path: &Path,
    mut reader: mcap_log::Reader,
) -> Result<mcap_log::Log, IoError> {
    let bag = path.is_dir().then(|| rosbag2::open(path)).transpose()?;
    let (files, storage) = match &bag {
        Some(b) => (b.files.clone(), b.storage),
        None => (vec![path.to_path_buf()], rosbag2::Storage::Mcap),
    };
    for file in &files {
        match storage {
            rosbag2::Storage::Mcap => reader.mcap_file(file)?,
            rosbag2::Storage::Sqlite3 => rosbag2::read_sqlite(file, &mut reader)?,
        }
    }
    if let Some(b) = &bag {
        b.check_listed_topics(reader.topics())?;
    }
    let mut log = reader.finish(path)?;
    log.files = files;
    Ok(log)
}

/// Whether `path` is read as a bag (an MCAP file or a rosbag2 directory) rather than CSV.
pub fn is_bag(path: &Path) -> bool {
    path.is_dir() || path.extension().and_then(|e| e.to_str()) == Some("mcap")
}

/// The samples of a data file as logged, matched to `model`'s joints: the samples, the file's
/// joints the robot lacks, and the joint-state messages skipped (naming none of its joints).
pub fn load_logged(
    path: &Path,
    model: &Model,
    opts: &DataOptions,
) -> Result<(crate::prepare::Logged, Vec<String>, usize), IoError> {
    let names: Vec<String> = model.joint_names();
    let is_mcap = is_bag(path);
    let in_memory = opts.memory.iter().find(|m| m.label == path);
    let (read, mut ignored, skipped) = if let Some(m) = in_memory {
        (m.logged.clone(), vec![], 0)
    } else if is_mcap {
        let ropts = mcap_log::ReadOptions {
            topic: opts
                .topic
                .clone()
                .unwrap_or_else(|| mcap_log::TOPIC_MEASURED.into()),
            stamp: opts.stamp,
            joints: Some(names.clone()),
            // The ground truth is not read here; the processed samples only without a topic.
            physid_samples: match opts.topic {
                None => mcap_log::PhysidSamples::Processed,
                Some(_) => mcap_log::PhysidSamples::None,
            },
        };
        let log = read_joint_log(path, &ropts)?;
        let logged = match (&opts.topic, log.processed) {
            (None, Some(processed)) => processed.into(),
            _ => log.measured,
        };
        (logged, vec![], log.skipped_messages)
    } else if path.extension().and_then(|e| e.to_str()) == Some("csv") {
        let (logged, ignored) = samples::read_csv_logged(path, Some(&names))?;
        (logged, ignored, 0)
    } else {
        return Err(IoError::invalid(
            path,
            "give a .mcap file, a rosbag2 directory or a .csv file",
        ));
    };
    let (logged, more_ignored) =
        match_joints(read, &names).map_err(|m| IoError::invalid(path, m))?;
    ignored.extend(more_ignored);
    check_angle_unit(&logged, model).map_err(|m| IoError::invalid(path, m))?;
    Ok((logged, ignored, skipped))
}

/// Positions of a revolute joint with limits that lie far outside them (by half the range and
/// 0.2 rad) while the same numbers read as degrees fit them: the log is in degrees.
fn check_angle_unit(logged: &crate::prepare::Logged, model: &Model) -> Result<(), String> {
    let n = logged.dof();
    for (j, b) in model.bodies().iter().enumerate() {
        let (lo, hi) = (b.limits.lower, b.limits.upper);
        let revolute = matches!(b.joint, physid_core::model::Joint::Revolute { .. });
        if !(revolute && lo.is_finite() && hi.is_finite()) || logged.is_empty() {
            continue;
        }
        let column = (0..logged.len()).map(|k| logged.q[k * n + j]);
        let (min, max) = column.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), q| {
            (a.min(q), b.max(q))
        });
        let range = hi - lo;
        let outside = |a: f64, b: f64, slack: f64| a < lo - slack || b > hi + slack;
        let degrees = std::f64::consts::PI / 180.0;
        if outside(min, max, 0.5 * range + 0.2)
            && !outside(min * degrees, max * degrees, 0.1 * range + 0.05)
        {
            return Err(format!(
                "joint '{}': positions from {min:.4} to {max:.4} rad, far outside its limits {lo:.4}..{hi:.4} rad, while as degrees ({:.4} to {:.4} rad) they fit: the log is in degrees? physid reads revolute positions in radians (multiply by π/180)",
                b.joint_name,
                min * degrees,
                max * degrees
            ));
        }
    }
    Ok(())
}

/// The data's joints matched to the robot's `names` by name (reordered; joints the robot does
/// not have are dropped and returned); data that name no joints are taken in the robot's order
/// when the counts agree. An error names a robot joint the data lack.
pub(crate) fn match_joints(
    tr: crate::prepare::Logged,
    names: &[String],
) -> Result<(crate::prepare::Logged, Vec<String>), String> {
    if tr.joint_names.iter().all(|n| n.is_empty()) {
        if tr.dof() != names.len() {
            return Err(format!(
                "the data have {} unnamed joints, the robot has {}",
                tr.dof(),
                names.len()
            ));
        }
        let mut tr = tr;
        tr.joint_names = names.to_vec();
        return Ok((tr, vec![]));
    }
    let ignored: Vec<String> = tr
        .joint_names
        .iter()
        .filter(|n| !names.contains(n))
        .cloned()
        .collect();
    let matched = tr.with_joints(names).map_err(|missing| {
        format!(
            "the robot's joint '{missing}' is not in the data (the data have {})",
            tr.joint_names.join(", ")
        )
    })?;
    Ok((matched, ignored))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn listing(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn a_result_folder_is_replaced_whole_or_not_at_all() {
        let root = tempfile::tempdir().unwrap();
        let out = root.path().join("res");
        let write = |files: &[&str], fail_after: Option<usize>| {
            write_result_dir(&out, "scores.json", |dir| {
                for (i, f) in files.iter().enumerate() {
                    if fail_after == Some(i) {
                        return Err(IoError::invalid(dir, "cut short"));
                    }
                    write_atomic(&dir.join(f), f.as_bytes())?;
                }
                Ok(())
            })
        };
        write(&["scores.json", "a.csv"], None).unwrap();
        assert_eq!(listing(&out), ["a.csv", "scores.json"]);
        // A run that fails after one file leaves the earlier result as it was.
        assert!(write(&["scores.json", "b.csv"], Some(1)).is_err());
        assert_eq!(listing(&out), ["a.csv", "scores.json"]);
        assert_eq!(listing(root.path()), ["res"]);
        // A complete run replaces it whole: nothing of the earlier one is left beside it.
        write(&["scores.json", "b.csv"], None).unwrap();
        assert_eq!(listing(&out), ["b.csv", "scores.json"]);
        assert_eq!(listing(root.path()), ["res"]);
        // A folder of the user's own files is never replaced; a missing parent is refused.
        let own = root.path().join("own");
        std::fs::create_dir(&own).unwrap();
        std::fs::write(own.join("notes.md"), "mine").unwrap();
        let e = check_result_target(&own, "scores.json").unwrap_err();
        assert!(e.to_string().contains("no scores.json"), "{e}");
        let e = check_result_target(&root.path().join("no/res"), "scores.json").unwrap_err();
        assert!(e.to_string().contains("does not exist"), "{e}");
        assert_eq!(listing(&own), ["notes.md"]);
    }
}
