//! A cache of minimum-volume bounding ellipsoids, keyed by the content of the geometry they
//! bound, so that repeated runs on one robot solve each body's ellipsoid program once.
//!
//! The key is a BLAKE3 hash of the pieces (every coordinate's bits), the program's version and
//! physid's: equal keys, equal programs, so a cached answer is the answer. A process keeps
//! what it computed in memory; on disk, each ellipsoid is one small JSON file in the cache
//! folder ([`CacheDir::default`]: `$PHYSID_CACHE_DIR`, else `$XDG_CACHE_HOME/physid`, else
//! `~/.cache/physid`; `PHYSID_CACHE_DIR=off` turns the disk cache off), written atomically.
//! A file that cannot be read, does not parse or holds a non-finite or non-positive-definite
//! shape is ignored and replaced: the cache can make a run faster, never its answer different.

use nalgebra::{Matrix3, Vector3};
use physid_core::spatial::bounding::Piece;
use physid_core::spatial::Ellipsoid;
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Mutex;

/// Bumped whenever the bounding program or its settings change, so that older answers are
/// not reused.
const PROGRAM_VERSION: &str = "mvee-1";

/// Where cached ellipsoids are kept on disk.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum CacheDir {
    /// `$PHYSID_CACHE_DIR` (`off`: none), else `$XDG_CACHE_HOME/physid`, else
    /// `$HOME/.cache/physid`.
    #[default]
    FromEnvironment,
    /// No disk cache (the process's memory only).
    Off,
    /// This folder.
    Dir(PathBuf),
}

impl CacheDir {
    /// The folder of the ellipsoid files, if any.
    pub fn folder(&self) -> Option<PathBuf> {
        let base = match self {
            CacheDir::Off => return None,
            CacheDir::Dir(d) => d.clone(),
            CacheDir::FromEnvironment => match std::env::var_os("PHYSID_CACHE_DIR") {
                Some(v) if v == "off" || v.is_empty() => return None,
                Some(v) => PathBuf::from(v),
                None => std::env::var_os("XDG_CACHE_HOME")
                    .filter(|v| !v.is_empty())
                    .map(|x| PathBuf::from(x).join("physid"))
                    .or_else(|| {
                        std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache/physid"))
                    })?,
            },
        };
        Some(base.join("ellipsoids"))
    }
}

/// The content key of the bounding program over `pieces`.
pub fn key(pieces: &[Piece]) -> String {
    let mut h = blake3::Hasher::new();
    h.update(PROGRAM_VERSION.as_bytes());
    h.update(env!("CARGO_PKG_VERSION").as_bytes());
    h.update(&(pieces.len() as u64).to_le_bytes());
    for p in pieces {
        h.update(&p.to_bytes());
    }
    h.finalize().to_hex().to_string()
}

static MEMORY: Mutex<Option<HashMap<String, Ellipsoid>>> = Mutex::new(None);

/// The ellipsoid under `key`, from memory or from `dir`, if a valid one is there.
pub fn get(key: &str, dir: &CacheDir) -> Option<Ellipsoid> {
    if let Some(e) = MEMORY
        .lock()
        .ok()
        .and_then(|m| m.as_ref().and_then(|m| m.get(key).copied()))
    {
        return Some(e);
    }
    let path = dir.folder()?.join(format!("{key}.json"));
    let e = parse(&std::fs::read_to_string(path).ok()?)?;
    remember(key, &e);
    Some(e)
}

/// Keeps `e` under `key` in memory and, when a folder is set and can be written, on disk
/// (a cache that cannot be written only makes the next run slower).
pub fn put(key: &str, e: &Ellipsoid, dir: &CacheDir) {
    remember(key, e);
    let Some(folder) = dir.folder() else { return };
    if std::fs::create_dir_all(&folder).is_err() {
        return;
    }
    // The bits of every number (JSON's decimal text is not parsed back bit-exactly), and the
    // values for a reader.
    let bits =
        |v: &[f64]| -> Vec<String> { v.iter().map(|x| format!("{:016x}", x.to_bits())).collect() };
    let text = serde_json::json!({
        "center": bits(e.center.as_slice()),
        "qs": bits(e.qs.as_slice()),
        "center_m": e.center.as_slice(),
        "qs_m2": e.qs.as_slice(),
    })
    .to_string();
    let _ = crate::write_atomic(&folder.join(format!("{key}.json")), text.as_bytes());
}

/// Forgets what this process computed (the disk cache stays): for a long-lived process, and
/// for tests of the disk cache.
pub fn clear_memory() {
    if let Ok(mut m) = MEMORY.lock() {
        *m = None;
    }
}

fn remember(key: &str, e: &Ellipsoid) {
    if let Ok(mut m) = MEMORY.lock() {
        m.get_or_insert_with(HashMap::new)
            .insert(key.to_string(), *e);
    }
}

/// A cached file's ellipsoid: a finite centre and a finite, symmetric, positive-definite
/// shape, else none.
fn parse(text: &str) -> Option<Ellipsoid> {
    let v: serde_json::Value = serde_json::from_str(text).ok()?;
    let numbers = |name: &str, n: usize| -> Option<Vec<f64>> {
        let a = v.get(name)?.as_array()?;
        let x: Vec<f64> = a
            .iter()
            .map(|x| {
                u64::from_str_radix(x.as_str()?, 16)
                    .ok()
                    .map(f64::from_bits)
            })
            .collect::<Option<_>>()?;
        (x.len() == n && x.iter().all(|x| x.is_finite())).then_some(x)
    };
    let center = Vector3::from_column_slice(&numbers("center", 3)?);
    let qs = Matrix3::from_column_slice(&numbers("qs", 9)?);
    let symmetric = (qs - qs.transpose()).amax() <= 1e-12 * qs.amax();
    let definite = qs.cholesky().is_some();
    (symmetric && definite).then_some(Ellipsoid { center, qs })
}
