//! The cache of bounding ellipsoids (crates/io/src/cache.rs): a warm cache gives the very ellipsoids a
//! cold one computes, a file is what the next run reads, and a cache file that is garbage,
//! non-finite or not positive definite is ignored and replaced, never used.

mod common;

use physid::io::cache::{self, CacheDir};
use physid::io::geometry::GeometryOptions;
use physid::io::robot_spec::RobotExtras;
use physid::spatial::bounding::Piece;
use physid::spatial::Ellipsoid;
use std::path::Path;

fn kuka_ellipsoids(dir: &Path) -> Vec<Option<Ellipsoid>> {
    let extras = RobotExtras {
        geometry: GeometryOptions {
            cache: CacheDir::Dir(dir.to_path_buf()),
            ..Default::default()
        },
        ..Default::default()
    };
    let urdf = common::root().join("data/kuka_lwr4/kuka_lwr4.urdf");
    let (m, _) = physid::io::urdf::load(&urdf, &extras).unwrap();
    m.bodies().iter().map(|b| b.bounding).collect()
}

fn files(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut f: Vec<_> = std::fs::read_dir(dir.join("ellipsoids"))
        .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    f.sort();
    f
}

/// A planted shape's factor: larger, yet within the check's tolerance of the minimum.
const HAIR: f64 = 1.0 + 1e-10;

#[test]
fn a_warm_cache_gives_the_cold_answer_and_bad_files_are_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let cold = kuka_ellipsoids(dir.path());
    let computed = cold.iter().flatten().count();
    assert!(
        computed >= 5,
        "{computed} ellipsoids from the KUKA's geometry"
    );
    let written = files(dir.path());
    assert_eq!(written.len(), computed, "{written:?}");

    // From disk (memory forgotten): bit for bit the same.
    cache::clear_memory();
    assert_eq!(kuka_ellipsoids(dir.path()), cold);

    // The disk is what is read: a valid ellipsoid planted in one file (a hair larger: it still
    // bounds the geometry and is no larger than its box's) is what the next load gives for that
    // body (the key is the geometry's content, so only a hand-made file can disagree with the
    // program; one that cannot bound the geometry is refused, see below).
    cache::clear_memory();
    let text = std::fs::read_to_string(&written[0]).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut planted = v.clone();
    let enlarged: Vec<String> = v["qs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| {
            let x = f64::from_bits(u64::from_str_radix(x.as_str().unwrap(), 16).unwrap());
            format!("{:016x}", (HAIR * x).to_bits())
        })
        .collect();
    planted["qs"] = serde_json::json!(enlarged);
    std::fs::write(&written[0], planted.to_string()).unwrap();
    let read = kuka_ellipsoids(dir.path());
    let changed: Vec<usize> = (0..read.len()).filter(|&i| read[i] != cold[i]).collect();
    assert_eq!(changed.len(), 1, "{changed:?}");
    let i = changed[0];
    let (r, c) = (read[i].unwrap(), cold[i].unwrap());
    assert!((r.qs - HAIR * c.qs).amax() == 0.0 && r.center == c.center);

    // Garbage, a NaN, a non-positive-definite shape, a truncated file: ignored, recomputed,
    // and the file replaced by a good one.
    let bad = [
        "not json".to_string(),
        text.replacen(&v["center"][0].as_str().unwrap().to_string(), &format!("{:016x}", f64::NAN.to_bits()), 1),
        serde_json::json!({"center": v["center"], "qs": vec![format!("{:016x}", (-1.0f64).to_bits()); 9]}).to_string(),
        text[..text.len() / 2].to_string(),
    ];
    for garbage in bad {
        cache::clear_memory();
        for f in &written {
            std::fs::write(f, &garbage).unwrap();
        }
        assert_eq!(kuka_ellipsoids(dir.path()), cold, "{garbage}");
        assert_eq!(std::fs::read_to_string(&written[0]).unwrap(), text);
    }
    a_planted_entry_that_cannot_bound_its_geometry_is_ignored_and_said();
}

#[test]
fn the_key_is_the_geometrys_content_and_off_writes_nothing() {
    let ball = |r: f64| Piece::Ball {
        center: nalgebra::Vector3::new(0.1, 0.0, 0.2),
        radius: r,
    };
    let a = cache::key(&[ball(0.05), Piece::Point(nalgebra::Vector3::zeros())]);
    assert_eq!(
        a,
        cache::key(&[ball(0.05), Piece::Point(nalgebra::Vector3::zeros())])
    );
    // One ulp of one coordinate, the order of the pieces: another program, another key.
    assert_ne!(
        a,
        cache::key(&[
            ball(f64::from_bits(0.05f64.to_bits() + 1)),
            Piece::Point(nalgebra::Vector3::zeros())
        ])
    );
    assert_ne!(
        a,
        cache::key(&[Piece::Point(nalgebra::Vector3::zeros()), ball(0.05)])
    );
    assert_eq!(CacheDir::Off.folder(), None);
    let dir = tempfile::tempdir().unwrap();
    assert_eq!(
        CacheDir::Dir(dir.path().to_path_buf()).folder(),
        Some(dir.path().join("ellipsoids"))
    );
}

/// A planted entry that cannot bound its geometry is ignored and said (run inside
/// [`a_warm_cache_gives_the_cold_answer_and_bad_files_are_replaced`]: the in-memory cache is
/// the process's, shared by tests running side by side).
fn a_planted_entry_that_cannot_bound_its_geometry_is_ignored_and_said() {
    // Before: a valid-looking file shrunk in place was trusted (lwr_1_link's mass came out at
    // 0.002 kg of 2.7). A cached answer must contain its geometry and be no larger than the
    // ellipsoid of the geometry's box; else it is solved again, replaced, and said.
    let dir = tempfile::tempdir().unwrap();
    cache::clear_memory();
    let cold = kuka_ellipsoids(dir.path());
    let written = files(dir.path());
    let text = std::fs::read_to_string(&written[0]).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let scaled = |s: f64| {
        let mut planted = v.clone();
        let qs: Vec<String> = (v["qs"].as_array().unwrap().iter())
            .map(|x| {
                let x = f64::from_bits(u64::from_str_radix(x.as_str().unwrap(), 16).unwrap());
                format!("{:016x}", (s * x).to_bits())
            })
            .collect();
        planted["qs"] = serde_json::json!(qs);
        planted.to_string()
    };
    let extras = RobotExtras {
        geometry: GeometryOptions {
            cache: CacheDir::Dir(dir.path().to_path_buf()),
            ..Default::default()
        },
        ..Default::default()
    };
    let urdf = common::root().join("data/kuka_lwr4/kuka_lwr4.urdf");
    // A quarter of the shape (half the semi-axes): pieces outside; a hundred times (ten times
    // the semi-axes): larger than the box's ellipsoid.
    for s in [0.25, 100.0] {
        cache::clear_memory();
        std::fs::write(&written[0], scaled(s)).unwrap();
        let (m, warnings) = physid::io::urdf::load(&urdf, &extras).unwrap();
        let read: Vec<Option<Ellipsoid>> = m.bodies().iter().map(|b| b.bounding).collect();
        assert_eq!(read, cold, "planted ×{s} was used");
        assert!(
            warnings
                .iter()
                .any(|w| w.contains("does not bound this geometry")
                    && w.contains("ignored, solved again and replaced")),
            "×{s}: {warnings:?}"
        );
        assert_eq!(std::fs::read_to_string(&written[0]).unwrap(), text);
    }
    // The cold answers pass the check themselves: a warm load says nothing.
    cache::clear_memory();
    let (_, warnings) = physid::io::urdf::load(&urdf, &extras).unwrap();
    assert!(
        !warnings.iter().any(|w| w.contains("does not bound")),
        "{warnings:?}"
    );
}
