//! Helpers shared by the integration tests: the library's (`tests/`) and the binary's
//! (`cli/tests/`, which include this file by path).

use std::process::Command;

/// Runs the `physid` binary with `args` (not writing to a CI step summary): exit code (-1 if
/// killed), stdout, stderr.
#[allow(dead_code)]
pub fn physid(args: &[&str]) -> (i32, String, String) {
    let o = command()
        .args(args)
        .env_remove("GITHUB_STEP_SUMMARY")
        .output()
        .unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into(),
        String::from_utf8_lossy(&o.stderr).into(),
    )
}

/// The `physid` binary built for this test run: only the CLI crate's tests (`cli/tests/`) have
/// it, the library's tests run without it.
#[allow(dead_code)]
pub fn exe() -> &'static str {
    match option_env!("CARGO_BIN_EXE_physid") {
        Some(exe) => exe,
        None => panic!("the physid binary exists for the CLI crate's tests (cli/tests/) only"),
    }
}

/// A command running the `physid` binary from the repository's root (where relative defaults
/// such as `scenarios/blind.toml` resolve, as for a user in a checkout).
#[allow(dead_code)]
pub fn command() -> Command {
    let mut command = Command::new(exe());
    command.current_dir(root());
    command
}

/// The repository's root (the workspace's: where `scenarios/` and `data/` are), from the
/// library's tests and the CLI crate's alike.
#[allow(dead_code)]
pub fn root() -> std::path::PathBuf {
    let manifest = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    manifest
        .ancestors()
        .find(|dir| dir.join("scenarios").is_dir())
        .unwrap_or(manifest)
        .to_path_buf()
}

/// A binary STL of one tetrahedron (4 triangles; vertices 0, 0.1 x, 0.1 y, 0.1 z, in m), its
/// header's triangle count `claimed` (4 for a true file).
#[allow(dead_code)]
pub fn tetrahedron_stl(claimed: u32) -> Vec<u8> {
    let v = [
        [0.0f32, 0.0, 0.0],
        [0.1, 0.0, 0.0],
        [0.0, 0.1, 0.0],
        [0.0, 0.0, 0.1],
    ];
    let faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
    let mut out = vec![0u8; 80];
    out.extend(claimed.to_le_bytes());
    for f in faces {
        out.extend([0u8; 12]);
        for i in f {
            for x in v[i] {
                out.extend(x.to_le_bytes());
            }
        }
        out.extend([0u8; 2]);
    }
    out
}

/// `scenarios/cheetah3_shell.toml` made to diverge: stiff PD gains, one RK4 substep, no motor
/// model (voltage limits would tame it). The robot is still the built-in leg, whose effort
/// limits the caller lifts (on the model, or by writing the leg out without them).
#[allow(dead_code)]
pub fn diverging_shell_scenario() -> String {
    std::fs::read_to_string(root().join("scenarios/cheetah3_shell.toml"))
        .unwrap()
        .replace("kp = [1500.0, 1500.0, 1500.0]", "kp = [5e8, 5e8, 5e8]")
        .replace("substeps = 4", "substeps = 1")
        .replace("motor_kt = 0.266", "")
        .replace("motor_resistance = 0.45", "")
        .replace("supply_voltage = 65.0", "")
}

/// The Cheetah-3 leg's shell experiment (`scenarios/cheetah3_shell.toml`) simulated for
/// `duration` s.
#[allow(dead_code)]
pub struct ShellRun {
    /// The scenario, its duration set.
    pub scenario: physid::sim::scenario::Scenario,
    /// The leg.
    pub model: physid::model::Model,
    /// What the simulation logged.
    pub rec: physid::trajectory::Recording,
    /// The scenario file's text.
    pub text: String,
}

/// [`ShellRun`] for `duration` s.
#[allow(dead_code)]
pub fn shell_run(duration: f64) -> ShellRun {
    let (mut scenario, model, text) =
        physid::sim::scenario::load(&root().join("scenarios/cheetah3_shell.toml")).unwrap();
    scenario.simulation.duration = duration;
    let rec = physid::sim::run(&model, &scenario, &mut |_| {}).unwrap();
    ShellRun {
        scenario,
        model,
        rec,
        text,
    }
}

/// Writes `rec` as a physid MCAP log at `path`, with `model`'s parameters as its ground truth
/// and `scenario_toml` as its scenario record.
#[allow(dead_code)]
pub fn write_mcap(
    path: &std::path::Path,
    model: &physid::model::Model,
    rec: &physid::trajectory::Recording,
    scenario_toml: &str,
) {
    let (names, theta) = (model.parameter_names(), model.parameters());
    let meta = physid::io::mcap_log::LogMeta {
        scenario_toml,
        engine: "physid",
        parameters: (&names, theta.as_slice()),
    };
    physid::io::mcap_log::write(path, rec, &meta).unwrap();
}
