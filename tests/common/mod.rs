//! Helpers shared by the integration tests that run the `physid` binary.

use std::process::Command;

/// Runs the `physid` binary with `args`: exit code (-1 if killed), stdout, stderr.
#[allow(dead_code)]
pub fn physid(args: &[&str]) -> (i32, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_physid"))
        .args(args)
        .output()
        .unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into(),
        String::from_utf8_lossy(&o.stderr).into(),
    )
}

/// The repository's root (where `Cargo.toml` is).
#[allow(dead_code)]
pub fn root() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}
