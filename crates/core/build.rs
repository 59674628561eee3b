//! Links the system OpenBLAS, which provides the BLAS and LAPACK routines behind Clarabel's PSD
//! cones and physid's normal equations (docs/architecture.md, "Building").
//!
//! The library is found by `PHYSID_OPENBLAS_LIB_DIR`, then pkg-config, then the usual system
//! directories, and linked dynamically. A missing library stops the build with one line that
//! says what to install; because the script then fails, Cargo never caches a result from a
//! machine without OpenBLAS, and installing the library later re-runs it. Once found, the
//! script re-runs whenever that library file changes.

use std::env;
use std::path::{Path, PathBuf};

const DIR_VAR: &str = "PHYSID_OPENBLAS_LIB_DIR";

fn main() {
    println!("cargo::rerun-if-changed=build.rs");
    println!("cargo::rerun-if-env-changed={DIR_VAR}");
    println!("cargo::rerun-if-env-changed=PKG_CONFIG_PATH");
    match find_openblas() {
        Some(library) => {
            let dir = library.parent().unwrap_or(Path::new("/"));
            println!("cargo::rustc-link-search=native={}", dir.display());
            println!("cargo::rustc-link-lib=dylib=openblas");
            println!("cargo::rerun-if-changed={}", library.display());
            println!("cargo::rustc-env=PHYSID_OPENBLAS={}", library.display());
        }
        None => println!(
            "cargo::error=physid needs the system OpenBLAS and found no {}: install the Debian \
             package libopenblas-dev (`bash scripts/setup.sh` does it, as root), or set {DIR_VAR} \
             to the directory that holds it",
            library_file_name()
        ),
    }
}

/// The shared library to link against, by the first source that has it.
fn find_openblas() -> Option<PathBuf> {
    let name = library_file_name();
    if let Some(dir) = env::var_os(DIR_VAR) {
        // An explicit directory is the user's choice: no fallback past it.
        return Some(PathBuf::from(dir).join(name)).filter(|p| p.is_file());
    }
    pkg_config_dirs()
        .into_iter()
        .chain(system_dirs())
        .map(|dir| dir.join(name))
        .find(|p| p.is_file())
}

fn library_file_name() -> &'static str {
    match env::var("CARGO_CFG_TARGET_OS").as_deref() {
        Ok("macos") => "libopenblas.dylib",
        _ => "libopenblas.so",
    }
}

/// Library directories that pkg-config names for `openblas` (none when pkg-config or its
/// `openblas.pc` is absent).
fn pkg_config_dirs() -> Vec<PathBuf> {
    pkg_config::Config::new()
        .cargo_metadata(false)
        .env_metadata(false)
        .probe("openblas")
        .map(|lib| lib.link_paths)
        .unwrap_or_default()
}

/// Where distributions put OpenBLAS: Debian's multiarch directories (and its pthread variant),
/// the plain library directories, and Homebrew's prefixes.
fn system_dirs() -> Vec<PathBuf> {
    let arch = env::var("CARGO_CFG_TARGET_ARCH").unwrap_or_default();
    let multiarch = format!("/usr/lib/{arch}-linux-gnu");
    [
        multiarch.clone(),
        format!("{multiarch}/openblas-pthread"),
        format!("{multiarch}/openblas-openmp"),
        format!("{multiarch}/openblas-serial"),
        "/usr/lib64".into(),
        "/usr/lib".into(),
        "/usr/local/lib".into(),
        "/opt/homebrew/opt/openblas/lib".into(),
        "/usr/local/opt/openblas/lib".into(),
    ]
    .into_iter()
    .map(PathBuf::from)
    .collect()
}
