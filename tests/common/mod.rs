//! Helpers shared by the integration tests that run the `physid` binary.

use std::process::Command;

/// Runs the `physid` binary with `args` (not writing to a CI step summary): exit code (-1 if
/// killed), stdout, stderr.
#[allow(dead_code)]
pub fn physid(args: &[&str]) -> (i32, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_physid"))
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

/// The repository's root (where `Cargo.toml` is).
#[allow(dead_code)]
pub fn root() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
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
