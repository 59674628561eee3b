//! Bounding ellipsoids from a URDF's geometry: every KUKA body gets one (primitives exactly, the
//! wrist from its STL mesh), fixed links merge into their body, a sidecar overrides, a missing
//! mesh leaves the body without a bound and says why, and `identify`'s default follows.

#[path = "../../tests/common/mod.rs"]
mod common;

use common::physid;
use nalgebra::Vector3;
use physid::io::robot_spec::RobotOptions;
use physid::io::{self, urdf};
use physid::spatial::Ellipsoid;
use std::path::PathBuf;

fn kuka() -> PathBuf {
    common::root().join("data/kuka_lwr4/kuka_lwr4.urdf")
}

fn inside(e: &Ellipsoid, x: &Vector3<f64>) -> bool {
    let d = x - e.center;
    (d.transpose() * e.qs.try_inverse().unwrap() * d)[0] <= 1.0 + 1e-9
}

#[test]
fn every_kuka_body_is_bounded_by_its_own_geometry() {
    let (m, warnings) = io::load_robot_with(kuka().to_str().unwrap(), &Default::default()).unwrap();
    assert!(
        m.bodies().iter().all(|b| b.bounding.is_some()),
        "{warnings:?}"
    );
    // lwr_1_link: spheres r = 0.07 at (0,0,0) and (0,0.06,0.2), a tilted cylinder between.
    let e1 = m.bodies()[0].bounding.unwrap();
    for c in [Vector3::zeros(), Vector3::new(0.0, 0.06, 0.2)] {
        for u in [
            Vector3::x(),
            -Vector3::x(),
            Vector3::y(),
            -Vector3::y(),
            Vector3::z(),
            -Vector3::z(),
        ] {
            assert!(inside(&e1, &(c + u * 0.07)), "{}", c + u * 0.07);
        }
    }
    let a = e1.semi_axes();
    assert!(a.x > 0.07 && a.z < 0.07 + 0.2 && a.z > 0.15, "{a}");
    // lwr_6_link has only meshes; its collision mesh is not shipped, its visual STL is: the
    // bound comes from that mesh's hull (the STL spans ±0.071 m in x about the joint axis).
    let e6 = m.bodies()[5].bounding.unwrap();
    assert!(
        e6.semi_axes().x > 0.071 - 1e-3 && e6.semi_axes().z < 0.1,
        "{}",
        e6.semi_axes()
    );
    // The CAD-guess inertias of six links are not inside their own geometry: warned, kept.
    let escaped: Vec<&String> = warnings
        .iter()
        .filter(|w| w.contains("not inside"))
        .collect();
    assert_eq!(escaped.len(), 6, "{warnings:?}");
    assert!(warnings
        .iter()
        .any(|w| w.contains("lwr_7_link") && w.contains("-112.8889")));
}

#[test]
fn margin_missing_meshes_fixed_links_and_sidecar() {
    let dir = tempfile::tempdir().unwrap();
    let urdf_text = r#"<robot name="r">
  <link name="base"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/></joint>
  <link name="l1"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><geometry><box size="0.1 0.1 0.4"/></geometry></collision></link>
  <joint name="tool" type="fixed"><parent link="l1"/><child link="t"/><origin xyz="0 0 0.5"/></joint>
  <link name="t"><inertial><mass value="0.1"/><inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><geometry><sphere radius="0.05"/></geometry></collision></link>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><axis xyz="0 1 0"/><origin xyz="0 0 0.2"/>
    <limit lower="-1" upper="1" effort="10" velocity="1"/></joint>
  <link name="l2"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><geometry><mesh filename="package://gone/meshes/l2.stl"/></geometry></visual></link>
</robot>"#;
    let path = dir.path().join("r.urdf");
    std::fs::write(&path, urdf_text).unwrap();
    let (m, warnings) = urdf::load(&path, &Default::default()).unwrap();
    // l1 and the tool sphere fixed 0.5 m above it are one body: the bound covers both.
    let e = m.bodies()[0].bounding.unwrap();
    assert!(
        inside(&e, &Vector3::new(0.0, 0.0, 0.55)) && inside(&e, &Vector3::new(0.05, 0.05, -0.2))
    );
    // l2's mesh is nowhere: no bound, and a warning naming the link and the file.
    assert!(m.bodies()[1].bounding.is_none());
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("'l2'") && w.contains("package://gone/meshes/l2.stl")),
        "{warnings:?}"
    );
    // A margin lengthens each semi-axis by exactly that much.
    let opts = RobotOptions {
        ellipsoid_margin: Some(0.01),
        ..Default::default()
    };
    let (wide, _) = io::load_robot_with(path.to_str().unwrap(), &opts).unwrap();
    let grown = wide.bodies()[0].bounding.unwrap().semi_axes() - e.semi_axes();
    assert!((grown - Vector3::repeat(0.01)).norm() < 1e-12, "{grown}");
    // The mesh found through --package-dir gives l2 its bound.
    let pkg = dir.path().join("pkgs/gone/meshes");
    std::fs::create_dir_all(&pkg).unwrap();
    std::fs::write(pkg.join("l2.stl"), common::tetrahedron_stl(4)).unwrap();
    let opts = RobotOptions {
        package_dirs: vec![dir.path().join("pkgs")],
        ..Default::default()
    };
    let (found, _) = io::load_robot_with(path.to_str().unwrap(), &opts).unwrap();
    let e2 = found.bodies()[1].bounding.unwrap();
    for v in [
        [0.0, 0.0, 0.0],
        [0.1, 0.0, 0.0],
        [0.0, 0.1, 0.0],
        [0.0, 0.0, 0.1],
    ] {
        assert!(inside(&e2, &Vector3::from(v)));
    }
    // A sidecar ellipsoid wins over the geometry's.
    let toml = dir.path().join("r.toml");
    std::fs::write(
        &toml,
        "[robot]\nurdf = \"r.urdf\"\n[[robot.ellipsoid]]\nbody = \"l1\"\ncenter = [0, 0, 0]\nsemi_axes = [0.3, 0.3, 0.6]\n",
    )
    .unwrap();
    let (side, _) = io::load_robot_with(toml.to_str().unwrap(), &Default::default()).unwrap();
    assert!(
        (side.bodies()[0].bounding.unwrap().semi_axes() - Vector3::new(0.3, 0.3, 0.6)).norm()
            < 1e-12
    );

    // `physid model` lists the bounds, and a body without one as "none".
    let (code, text, err) = physid(&["model", "--robot", path.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(
        text.lines()
            .any(|l| l.starts_with("l2") && l.contains("none")),
        "{text}"
    );
    assert!(err.contains("package://gone/meshes/l2.stl"), "{err}");
}

/// Runs identify on the KUKA logs (runs 1 + 2 train, run 3 held out) and returns its JSON.
fn identify_kuka(extra: &[&str]) -> serde_json::Value {
    let k = common::root().join("data/kuka_lwr4");
    let f = |n: &str| k.join(n).to_string_lossy().into_owned();
    let (r, d1, d2, d3) = (
        f("kuka_lwr4.urdf"),
        f("measurements_1.csv"),
        f("measurements_2.csv"),
        f("measurements_3.csv"),
    );
    let mut args = vec![
        "identify",
        "--robot",
        &r,
        "--data",
        &d1,
        &d2,
        "--validate-data",
        &d3,
        "--json",
    ];
    args.extend(extra);
    let (code, out, err) = physid(&args);
    assert_eq!(code, 0, "{err}");
    serde_json::from_str(&out).unwrap()
}

#[test]
fn kuka_ellipsoids_from_geometry_give_plausible_masses_and_a_better_held_out_fit() {
    let friction = ["--friction", "viscous,coulomb,offset"];
    let default = identify_kuka(&friction);
    assert_eq!(default["constraints"], "ellipsoid");
    assert!(default["constraints_default_because"]
        .as_str()
        .unwrap()
        .contains("every body"));
    let consistent = identify_kuka(&[&friction[..], &["--constraints", "consistent"]].concat());
    let mass =
        |v: &serde_json::Value, i: usize| v["bodies"][i]["consistency"]["mass"].as_f64().unwrap();
    let rms = |v: &serde_json::Value| v["validation"]["rms_overall"].as_f64().unwrap();
    // `consistent` puts 0.09 kg on the wrist link lwr_6 with its CoM 0.25 m off its geometry;
    // the geometry's ellipsoids hold every body's mass where its shape is.
    assert!(mass(&consistent, 5) < 0.1, "{}", mass(&consistent, 5));
    assert!(mass(&default, 5) > 0.2 && mass(&default, 6) > 0.4);
    for i in 0..7 {
        let t = default["bodies"][i]["consistency"]["trace_jq"]
            .as_f64()
            .unwrap();
        assert!(t >= -1e-9, "body {i}: tr(JQ) = {t}");
    }
    // And the held-out error drops: 0.422 -> 0.395 N m overall.
    assert!(
        rms(&default) < 0.40 && rms(&consistent) > 0.42,
        "{} vs {}",
        rms(&default),
        rms(&consistent)
    );
}

#[test]
fn a_relative_robot_path_finds_the_same_meshes_as_the_absolute_one() {
    // Before: `--robot panda_description/urdf/panda.urdf` run from the package's `robots`
    // folder walked up only through the path as written, missed the `package://` meshes two
    // folders above that the absolute path finds, and lost every bounding ellipsoid (the default
    // constraint set and the diagnosis's ties changed with how the path was written).
    let robots = common::root().join("data/panda/example-robot-data/robots");
    let model = |cwd: &std::path::Path, robot: &str| {
        let o = common::command()
            .current_dir(cwd)
            .args(["model", "--robot", robot, "--json"])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "{err}");
        (
            serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap(),
            err,
        )
    };
    let absolute = robots.join("panda_description/urdf/panda.urdf");
    let (a, _) = model(&common::root(), absolute.to_str().unwrap());
    let (r, err) = model(&robots, "panda_description/urdf/panda.urdf");
    assert!(!err.contains("not found"), "{err}");
    assert_eq!(a["bodies"], r["bodies"]);
    let bounded = |v: &serde_json::Value| {
        v["bodies"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|b| !b["ellipsoid"].is_null())
            .count()
    };
    assert!(bounded(&r) >= 7, "{}", r["bodies"]);
}
