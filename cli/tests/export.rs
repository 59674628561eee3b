//! Exporting an identified model into the user's own URDF: only `<inertial>` and `<dynamics>`
//! change, the sidecar carries the ellipsoids and effects, and loading the pair gives back the
//! identified model exactly.

#[path = "../../tests/common/mod.rs"]
mod common;

use common::physid;
use physid::io;
use std::path::Path;

/// The text with every `<inertial>…</inertial>`, `<dynamics …/>` and comment removed.
fn without_patched_elements(xml: &str) -> String {
    let mut s = xml.to_string();
    for (open, close) in [
        ("<inertial>", "</inertial>"),
        ("<dynamics", "/>"),
        ("<!--", "-->"),
    ] {
        while let Some(i) = s.find(open) {
            let j = s[i..].find(close).unwrap() + i + close.len();
            s.replace_range(i..j, "");
        }
    }
    s.lines()
        .map(str::trim_end)
        .filter(|l| !l.trim().is_empty())
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn identified_kuka_patches_its_own_urdf_and_round_trips() {
    let root = common::root();
    let k = root.join("data/kuka_lwr4");
    let urdf = k.join("kuka_lwr4.urdf");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("kuka_id.urdf");
    let (s, o) = (
        |p: &Path| p.to_str().unwrap().to_string(),
        out.to_str().unwrap(),
    );
    let (code, json, err) = physid(&[
        "identify",
        "--robot",
        &s(&urdf),
        "--data",
        &s(&k.join("measurements_1.csv")),
        "--friction",
        "viscous,coulomb,offset",
        "--json",
        "--out-urdf",
        o,
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();

    // Everything but the inertial and dynamics elements is the user's file, line for line
    // (geometry, meshes, frame names, transmissions, the duplicated <origin>).
    let before = std::fs::read_to_string(&urdf).unwrap();
    let after = std::fs::read_to_string(&out).unwrap();
    assert_eq!(
        without_patched_elements(&before),
        without_patched_elements(&after)
    );
    assert!(
        after.contains("<transmission")
            && after.contains("package://lwr_description/meshes/kuka/link_6.STL")
    );

    // The pair loads back to the identified parameters and friction, and the ellipsoids the
    // identification used.
    let side = io::sidecar_path(&out);
    let text = std::fs::read_to_string(&side).unwrap();
    assert!(
        text.contains("[[effects]]") && text.contains("kind = \"torque_offset\""),
        "{text}"
    );
    let (back, _) = io::load_robot_with(side.to_str().unwrap(), &Default::default()).unwrap();
    let (orig, _) = io::load_robot_with(urdf.to_str().unwrap(), &Default::default()).unwrap();
    for (i, b) in back.bodies().iter().enumerate() {
        let pi: Vec<f64> = v["bodies"][i]["pi"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        for (k, want) in pi.iter().enumerate() {
            let got = b.inertia.0[k];
            assert!(
                (got - want).abs() <= 1e-12 * (1.0 + want.abs()),
                "{} pi[{k}]: {got} vs {want}",
                b.name
            );
        }
        let fr = &v["friction"];
        let (bv, bc) = (
            fr["viscous"][i].as_f64().unwrap(),
            fr["coulomb"][i].as_f64().unwrap(),
        );
        assert!((b.friction.viscous - bv).abs() < 1e-12 && (b.friction.coulomb - bc).abs() < 1e-12);
        let (e, e0) = (b.bounding.unwrap(), orig.bodies()[i].bounding.unwrap());
        assert!((e.qs - e0.qs).norm() < 1e-12 && (e.center - e0.center).norm() < 1e-12);
    }

    // The sidecar carries the fit's information matrix (the offsets' residual weighs it),
    // read back onto the model whether the sidecar or the URDF beside it is the robot.
    for robot in [side.to_str().unwrap(), o] {
        let (m, _) = io::load_robot_with(robot, &Default::default()).unwrap();
        let read = physid::api::information::for_description(robot, &m).unwrap();
        let (info, notes) = (read.matrix.expect("an information matrix"), read.notices);
        assert_eq!(info.nrows(), m.layout().len);
        assert!(notes[0].text.contains("5027 samples"), "{}", notes[0]);
        let sym = (&info - info.transpose()).amax();
        assert_eq!(sym, 0.0);
        let eig = info.clone().symmetric_eigen().eigenvalues;
        assert!(eig.min() >= -1e-9 * eig.max(), "{}", eig.min());
        // The first link turns about the vertical: its mass is not seen (no information).
        assert_eq!(info[(0, 0)], 0.0);
        assert!(info.trace() > 0.0);
    }

    // An output may not land on an input.
    let (code, _, err) = physid(&[
        "identify",
        "--robot",
        &s(&urdf),
        "--data",
        &s(&k.join("measurements_1.csv")),
        "--out-urdf",
        &s(&k.join("kuka_lwr4.urdf")),
    ]);
    assert!(code != 0 && err.contains("kuka_lwr4.urdf"), "{err}");
}

#[test]
fn fixed_links_hand_their_inertia_to_the_body_and_rotors_keep_their_links() {
    let dir = tempfile::tempdir().unwrap();
    let built = dir.path().join("leg.urdf");
    // The built-in leg has rotors: export writes a new URDF with mimic rotor links.
    let (code, _, err) = physid(&["export", "--urdf", built.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    // Add a tool fixed to the shank, then export that file again (patched in place).
    let mut xml = std::fs::read_to_string(&built).unwrap();
    let tool = r#"<link name="tool"><inertial><origin xyz="0 0 -0.3"/><mass value="0.2"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial></link>
  <joint name="tool_fix" type="fixed"><parent link="shank"/><child link="tool"/></joint>
</robot>"#;
    xml = xml.replace("</robot>", tool);
    let with_tool = dir.path().join("leg_tool.urdf");
    std::fs::write(&with_tool, &xml).unwrap();
    let (m, _) = io::load_robot_with(with_tool.to_str().unwrap(), &Default::default()).unwrap();
    let out = dir.path().join("leg_out.urdf");
    let (code, _, err) = physid(&[
        "export",
        "--robot",
        with_tool.to_str().unwrap(),
        "--urdf",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let patched = std::fs::read_to_string(&out).unwrap();
    assert!(
        patched.contains("inertial merged into link 'shank'"),
        "{patched}"
    );
    let (back, _) = io::load_robot_with(out.to_str().unwrap(), &Default::default()).unwrap();
    assert_eq!(back.rotor_count(), m.rotor_count());
    let d = (back.parameters() - m.parameters()).norm();
    assert!(
        d <= 1e-12 * m.parameters().norm(),
        "parameters differ by {d}"
    );
}

#[test]
fn dynamics_keeps_its_other_attributes_when_friction_is_written() {
    // The Panda's <dynamics D="1" K="7000" damping="0.003" friction="0.0" mu_coulomb="0"
    // mu_viscous="16"/> carries a simulator's joint stiffness and friction: only damping and
    // friction change. Before, the element was rewritten whole and the rest was lost.
    let root = common::root();
    let urdf = root.join("data/panda/example-robot-data/robots/panda_description/urdf/panda.urdf");
    let xml = std::fs::read_to_string(&urdf).unwrap();
    let model = io::load_robot(urdf.to_str().unwrap()).unwrap();
    let identified = model
        .with_bodies_edited(|j, b| {
            b.friction.viscous = 0.25 + 0.01 * j as f64;
            b.friction.coulomb = 0.5;
        })
        .unwrap();
    let out = io::urdf_patch::patch(&xml, &urdf, &model, &identified).unwrap();
    let joint1 = &out[out.find("<joint name=\"panda_joint1\"").unwrap()..];
    let dynamics = &joint1[joint1.find("<dynamics").unwrap()..];
    let dynamics = &dynamics[..dynamics.find("/>").unwrap() + 2];
    assert_eq!(
        dynamics,
        "<dynamics D=\"1\" K=\"7000\" damping=\"0.25\" friction=\"0.5\" mu_coulomb=\"0\" mu_viscous=\"16\"/>"
    );
    // A <dynamics> without damping gets it added, keeping what it has.
    let trimmed = xml.replacen("damping=\"0.003\" ", "", 1);
    let out = io::urdf_patch::patch(&trimmed, &urdf, &model, &identified).unwrap();
    let joint1 = &out[out.find("<joint name=\"panda_joint1\"").unwrap()..];
    assert!(
        joint1.contains("<dynamics damping=\"0.25\" D=\"1\" K=\"7000\" friction=\"0.5\""),
        "{}",
        &joint1[..400]
    );
}
