//! Robot descriptions in and out: the TOML leg equals the built-in, URDF import of the real
//! KUKA LWR4+ file, URDF and MJCF export round trips, and clear errors for bad input.

mod common;

use physid::dynamics::{regressor, rnea, Data};
use physid::io::{self, robot_toml, urdf, IoError};
use physid::model::random::random_state;
use physid::model::{cheetah3, Model};
use std::path::{Path, PathBuf};

fn kuka_path() -> PathBuf {
    common::root().join("data/kuka_lwr4/kuka_lwr4.urdf")
}

/// Two models describe the same dynamics: equal torques and regressors on random states.
fn assert_same_dynamics(a: &Model, b: &Model, tol: f64) {
    assert_eq!(a.dof(), b.dof());
    assert_eq!(a.layout(), b.layout());
    let (mut da, mut db) = (Data::new(a), Data::new(b));
    let p = a.layout().len;
    let (mut ya, mut yb) = (
        nalgebra::DMatrix::zeros(a.dof(), p),
        nalgebra::DMatrix::zeros(a.dof(), p),
    );
    for s in 0..10 {
        let [q, qd, qdd] = random_state(s, a.dof(), 2.0);
        let ta = rnea(a, &mut da, &q, &qd, &qdd).clone();
        let tb = rnea(b, &mut db, &q, &qd, &qdd).clone();
        assert!(
            (&ta - &tb).norm() <= tol * (1.0 + ta.norm()),
            "{ta} vs {tb}"
        );
        regressor(a, &mut da, &q, &qd, &qdd, &mut ya);
        regressor(b, &mut db, &q, &qd, &qdd, &mut yb);
        assert!((&ya - &yb).norm() <= tol * (1.0 + ya.norm()));
    }
    assert!((a.parameters() - b.parameters()).norm() <= tol * a.parameters().norm());
}

#[test]
fn toml_leg_is_the_builtin_leg() {
    let path = common::root().join("scenarios/cheetah3_leg.toml");
    let from_file = robot_toml::load(&path).unwrap();
    let builtin = cheetah3::leg();
    assert_same_dynamics(&from_file, &builtin, 1e-14);
    for (a, b) in from_file.bodies().iter().zip(builtin.bodies()) {
        assert_eq!(a.name, b.name);
        assert_eq!(a.friction, b.friction);
        assert!((a.limits.effort - b.limits.effort).abs() < 1e-12);
        assert!((a.limits.velocity - b.limits.velocity).abs() < 1e-12);
        let (ea, eb) = (a.bounding.unwrap(), b.bounding.unwrap());
        assert!((ea.qs - eb.qs).norm() < 1e-15 && (ea.center - eb.center).norm() < 1e-15);
        let (ra, rb) = (a.rotor.as_ref().unwrap(), b.rotor.as_ref().unwrap());
        assert_eq!(ra.name, rb.name);
        assert!((ra.bounding.unwrap().qs - rb.bounding.unwrap().qs).norm() < 1e-15);
    }
}

#[test]
fn kuka_urdf_loads_with_seven_joints_and_merged_fixed_links() {
    let m = io::load_robot(kuka_path().to_str().unwrap()).unwrap();
    assert_eq!(m.dof(), 7);
    let names: Vec<_> = m.bodies().iter().map(|b| b.joint_name.as_str()).collect();
    assert_eq!(
        names,
        [
            "lwr_0_joint",
            "lwr_1_joint",
            "lwr_2_joint",
            "lwr_3_joint",
            "lwr_4_joint",
            "lwr_5_joint",
            "lwr_6_joint"
        ]
    );
    // A serial chain.
    for (i, b) in m.bodies().iter().enumerate() {
        assert_eq!(b.parent, i.checked_sub(1));
    }
    assert!(
        m.total_mass() > 10.0 && m.total_mass() < 30.0,
        "{}",
        m.total_mass()
    );
    // The file has a joint with two <origin> elements; like urdfdom we take the first.
    let xml = std::fs::read_to_string(kuka_path()).unwrap();
    let (_, warnings) = urdf::from_str(&xml, &kuka_path(), &Default::default()).unwrap();
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("box_lwr_base_joint") && w.contains("<origin")),
        "{warnings:?}"
    );
}

#[test]
fn urdf_export_round_trips_links_rotors_and_friction() {
    for m in [cheetah3::leg(), physid::model::random::random_tree(3, 6)] {
        let text = urdf::to_string(&m);
        let (back, _) =
            urdf::from_str(&text, Path::new("roundtrip.urdf"), &Default::default()).unwrap();
        assert_eq!(back.rotor_count(), m.rotor_count());
        assert_same_dynamics(&back, &m, 1e-12);
    }
}

#[test]
fn mjcf_export_lumps_rotors_and_writes_armature() {
    let m = cheetah3::leg();
    let text = io::mjcf::to_string(&m);
    // Three moving bodies and the ab/ad rotor welded to the world (the file's mass is the
    // model's: 5.199 kg, not 4.699).
    assert_eq!(text.matches("<body ").count(), 4);
    assert!(text.contains("<body name=\"abad_rotor\""), "{text}");
    assert_eq!(text.matches("armature=").count(), 3);
    // Knee armature N² I_yy of the knee rotor, about 10.6² × 1.4e-3 kg m².
    let r = m.bodies()[2].rotor.as_ref().unwrap();
    let arm = 10.6f64.powi(2) * r.inertia.ibar()[(1, 1)];
    assert!(text.contains(&format!("armature=\"{arm}\"")), "{text}");
    // Lumping conserves mass: the abad rotor sits on the base, the others are lumped.
    let lumped = io::mjcf::lumped_inertias(&m);
    let total: f64 = lumped.iter().map(|p| p.mass()).sum();
    let abad_rotor = m.bodies()[0].rotor.as_ref().unwrap().inertia.mass();
    assert!((total + abad_rotor - m.total_mass()).abs() < 1e-12);
}

fn urdf_err(xml: &str) -> String {
    match urdf::from_str(xml, Path::new("bad.urdf"), &Default::default()) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("accepted a bad URDF"),
    }
}

const LINK: &str = r#"<inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>"#;

fn robot(body: &str) -> String {
    format!("<robot name=\"r\">{body}</robot>")
}

#[test]
fn bad_urdfs_get_errors_that_name_the_element() {
    let two = format!(
        r#"<link name="base"/><link name="a">{LINK}</link>
           <joint name="j1" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>"#
    );
    // Missing link.
    let e = urdf_err(&robot(
        &two.replace("<child link=\"a\"/>", "<child link=\"ghost\"/>"),
    ));
    assert!(
        e.contains("bad.urdf") && e.contains("'j1'") && e.contains("'ghost'"),
        "{e}"
    );
    // A loop: a second joint makes 'a' a child twice.
    let looped = format!(
        r#"{two}<link name="b">{LINK}</link>
           <joint name="j2" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/></joint>
           <joint name="j3" type="revolute"><parent link="b"/><child link="a"/><axis xyz="0 0 1"/></joint>"#
    );
    let e = urdf_err(&robot(&looped));
    assert!(e.contains("loop") && e.contains("'a'"), "{e}");
    // Non-positive mass.
    let e = urdf_err(&robot(
        &two.replace("<mass value=\"1\"/>", "<mass value=\"-2\"/>"),
    ));
    assert!(e.contains("link 'a'") && e.contains("-2"), "{e}");
    // Inertia violating the triangle inequality: Izz > Ixx + Iyy.
    let e = urdf_err(&robot(&two.replace("izz=\"0.01\"", "izz=\"0.05\"")));
    assert!(e.contains("body 'a'") && e.contains("triangle"), "{e}");
    // A rank-one inertia (Drake's Robotiq tensioner: every entry 0.01, eigenvalues 0.03, 0, 0)
    // breaks the triangle inequality; its spatial inertia is PSD but for rounding (−3e-18),
    // which named the wrong matrix.
    let rank_one = two.replace(
        r#"ixy="0" ixz="0" iyy="0.01" iyz="0""#,
        r#"ixy="0.01" ixz="0.01" iyy="0.01" iyz="0.01""#,
    );
    let e = urdf_err(&robot(&rank_one));
    assert!(e.contains("body 'a'") && e.contains("triangle"), "{e}");
    // A massless moving chain.
    let e = urdf_err(&robot(&two.replace(LINK, "")));
    assert!(e.contains("'j1'") && e.contains("massless"), "{e}");
    // Floating joint.
    let e = urdf_err(&robot(
        &two.replace("type=\"revolute\"", "type=\"floating\""),
    ));
    assert!(e.contains("'j1'") && e.contains("fixed-base"), "{e}");
    // Not XML at all.
    let e = urdf_err("<robot name=");
    assert!(e.contains("bad.urdf"), "{e}");
}

#[test]
fn bad_toml_gets_file_line_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let p = write(
        "typo.toml",
        "[robot]\nbuiltin = \"cheetah3\"\ngear_ratio = [1, 2, 3]\n",
    );
    let e = robot_toml::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("typo.toml") && e.contains("line 3") && e.contains("gear_ratio"),
        "{e}"
    );
    let p = write("unknown.toml", "[robot]\nbuiltin = \"cheetah4\"\n");
    let e = robot_toml::load(&p).unwrap_err().to_string();
    assert!(e.contains("cheetah4"), "{e}");
    let good = std::fs::read_to_string(common::root().join("scenarios/cheetah3_leg.toml")).unwrap();
    let p = write(
        "mass.toml",
        &good.replacen("pi = [1.6452", "pi = [-1.6452", 1),
    );
    let e = robot_toml::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("mass.toml") && e.contains("body 'abad'") && e.contains("negative mass"),
        "{e}"
    );
    let p = write(
        "parent.toml",
        &good.replacen("parent = \"abad\"", "parent = \"shank\"", 1),
    );
    let e = robot_toml::load(&p).unwrap_err().to_string();
    assert!(e.contains("'thigh'") && e.contains("parent 'shank'"), "{e}");
    // Mass outside its bounding ellipsoid is reported with the margin.
    let p = write(
        "ell.toml",
        &good.replacen(
            "semi_axes = [0.13, 0.13, 0.30]",
            "semi_axes = [0.03, 0.03, 0.1]",
            1,
        ),
    );
    let e = robot_toml::load(&p).unwrap_err().to_string();
    assert!(e.contains("body 'shank'") && e.contains("ellipsoid"), "{e}");
    assert!(matches!(
        io::load_robot("robot.xyz"),
        Err(IoError::UnknownRobot(_))
    ));
    let e = io::load_robot("/nonexistent/r.urdf")
        .unwrap_err()
        .to_string();
    assert!(e.contains("/nonexistent/r.urdf"), "{e}");
}

#[test]
fn sidecar_rotor_on_a_urdf_joint() {
    let dir = tempfile::tempdir().unwrap();
    let toml = format!(
        r#"[robot]
urdf = "{}"
[[robot.rotor]]
joint = "lwr_2_joint"
gear_ratio = 100.0
inertial = {{ mass = 0.3, com = [0.0, 0.0, 0.0], inertia = [2e-5, 0.0, 0.0, 2e-5, 0.0, 3e-5] }}
[[robot.friction]]
joint = "lwr_2_joint"
viscous = 0.5
coulomb = 1.5
"#,
        kuka_path().display()
    );
    let p = dir.path().join("kuka.toml");
    std::fs::write(&p, toml).unwrap();
    let m = robot_toml::load(&p).unwrap();
    assert_eq!(m.rotor_count(), 1);
    let r = m.bodies()[2].rotor.as_ref().unwrap();
    assert_eq!(r.gear_ratio, 100.0);
    assert_eq!(m.bodies()[2].friction.coulomb, 1.5);
    assert_eq!(m.layout().len, 80 + 14);
}

#[test]
fn a_csv_is_read_by_the_columns_used_and_the_first_bad_file_is_named() {
    // The reader decodes only the columns it uses, each trimmed of spaces (as the header's
    // names are); an unused column may hold anything, a used one that is not a number is named
    // with its line and column; files read side by side name the first bad one in their order.
    let dir = tempfile::tempdir().unwrap();
    let model = physid::model::cheetah3::leg();
    let names = model.joint_names();
    let header = |extra: &str| {
        let mut h = vec![" t ".to_string()];
        for g in ["q", "tau"] {
            h.extend(names.iter().map(|n| format!("{g}_{n}")));
        }
        h.push(extra.to_string());
        h.join(",")
    };
    // Angles within the leg's limits (±1.5 rad): positions far outside them that fit as degrees
    // are refused as a log in degrees.
    let row = |k: usize, unused: &[u8]| {
        let mut line = format!(" {} ", k as f64 * 1e-3).into_bytes();
        for j in 0..6 {
            line.extend(format!(", {:.4} ", 0.005 * (k + j) as f64).bytes());
        }
        line.push(b',');
        line.extend(unused);
        line.push(b'\n');
        line
    };
    let write = |name: &str, rows: &dyn Fn(usize) -> Vec<u8>| {
        let mut bytes = format!("{}\n", header("note")).into_bytes();
        for k in 0..200 {
            bytes.extend(rows(k));
        }
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        path
    };
    let good = write("good.csv", &|k| row(k, b"\xff\xfe not text"));
    let (logged, _) = io::samples::read_csv_logged(&good, Some(&names)).unwrap();
    assert_eq!(logged.t.len(), 200);
    assert!((logged.t[3] - 3e-3).abs() < 1e-15 && (logged.q[3 * 3 + 1] - 0.02).abs() < 1e-12);
    let bad_q = write("bad_q.csv", &|k| {
        if k == 7 {
            // The hip's angle is a byte that is not text.
            b" 0.007 , 1.0 , \xff , 1, 1, 1, 1, x\n".to_vec()
        } else {
            row(k, b"x")
        }
    });
    let err = io::samples::read_csv_logged(&bad_q, Some(&names))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("bad_q.csv") && err.contains("line 9, column 'q_hip_joint'"),
        "{err}"
    );
    let bad_t = write("bad_t.csv", &|k| {
        if k == 3 {
            b"oops,1,1,1,1,1,1,x\n".to_vec()
        } else {
            row(k, b"x")
        }
    });
    let paths = [good.as_path(), bad_t.as_path(), bad_q.as_path()];
    let err = io::load_all(&paths, &model, &Default::default())
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("bad_t.csv") && err.contains("'oops' is not a number"),
        "{err}"
    );
}

#[test]
fn a_description_without_geometry_is_bounded_by_its_kinematic_tree() {
    // The SO-ARM100 and UR5 as vendored carry no geometry: each body is bounded by the box of
    // its joint, its children's joints and its centre of mass, plus a margin, grown until the
    // description's own inertia lies inside; one warning names them all.
    for urdf in ["data/so100/so100.urdf", "data/ur5/ur5.urdf"] {
        let path = common::root().join(urdf);
        let (m, warnings) =
            physid::io::load_robot_with(path.to_str().unwrap(), &Default::default()).unwrap();
        let said: Vec<&String> = warnings
            .iter()
            .filter(|w| w.contains("kinematic tree's"))
            .collect();
        assert_eq!(said.len(), 1, "{warnings:?}");
        for (i, b) in m.bodies().iter().enumerate() {
            let e = b
                .bounding
                .as_ref()
                .unwrap_or_else(|| panic!("{urdf}: {} unbounded", b.name));
            assert!(said[0].contains(&format!("'{}'", b.name)));
            let children = m
                .bodies()
                .iter()
                .filter(|c| c.parent == Some(i))
                .map(|c| c.x_tree.r);
            let com = b.inertia.h() / b.inertia.mass();
            for p in std::iter::once(nalgebra::Vector3::zeros())
                .chain(children)
                .chain([com])
            {
                assert!(e.contains(&p), "{urdf}: {} misses {p:?}", b.name);
            }
            let t = b.inertia.consistency(Some(e)).trace_jq_per_mass.unwrap();
            // Inside, and not needlessly loose: a body a tenth of a metre long is not given a
            // metre (the margin is 5 cm plus a quarter of the segment).
            assert!(t >= 0.0, "{urdf}: {} tr(JQ)/m = {t}", b.name);
            let widest = e.semi_axes().max();
            assert!(widest < 1.0, "{urdf}: {} semi-axis {widest} m", b.name);
        }
        // The tightest set the description supports is now the ellipsoid set.
        assert_eq!(
            physid::api::identify::constraint_set(None, &m).set,
            physid::ident::ConstraintSet::Ellipsoid
        );
    }
    // Without geometry and told to ignore it, nothing is bounded.
    let opts = physid::io::robot_spec::RobotOptions {
        geometry_ellipsoids: Some(false),
        ..Default::default()
    };
    let so100 = common::root().join("data/so100/so100.urdf");
    let (m, _) = physid::io::load_robot_with(so100.to_str().unwrap(), &opts).unwrap();
    assert!(m.bodies().iter().all(|b| b.bounding.is_none()));
}

#[test]
fn a_csv_header_with_a_column_twice_or_a_numbered_gap_is_refused_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let model = physid::model::cheetah3::leg();
    let names = model.joint_names();
    for (header, words) in [
        (
            "t,q1,q1,q3,tau1,tau2,tau3",
            "column q1 appears twice (columns 2 and 3, counting from 1)",
        ),
        (
            "t,q1,q3,tau1,tau2,tau3",
            "column q3 without q2: numbered columns run q1..qn without a gap",
        ),
    ] {
        let path = dir.path().join("h.csv");
        std::fs::write(
            &path,
            format!("{header}\n0,0,0,0,0,0,0\n0.001,0,0,0,0,0,0\n"),
        )
        .unwrap();
        let e = physid::io::samples::read_csv(&path, Some(&names)).unwrap_err();
        assert!(e.to_string().contains(words), "{header}: {e}");
        assert!(e.to_string().contains("h.csv"), "{e}");
    }
}

/// A floating robot from URDF: a `floating` joint from a massless "world" link is dropped and
/// its child becomes the trunk, whose inertia is its own plus the links fixed to it (in its
/// frame); read as fixed-base the same file is refused, naming the joint.
#[test]
fn a_floating_urdf_gives_its_trunk_the_root_and_its_fixed_links() {
    let xml = robot(&format!(
        r#"<link name="world"/>
           <joint name="free" type="floating"><parent link="world"/><child link="body"/></joint>
           <link name="body">{LINK}</link>
           <joint name="mount" type="fixed"><parent link="body"/><child link="imu"/><origin xyz="0.2 0 0"/></joint>
           <link name="imu"><inertial><mass value="0.5"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial></link>
           <joint name="hip" type="revolute"><parent link="body"/><child link="leg"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="5" velocity="5"/></joint>
           <link name="leg">{LINK}</link>"#
    ));
    let (robot_, _) =
        urdf::floating_from_str(&xml, Path::new("free.urdf"), &Default::default()).unwrap();
    let trunk = robot_.trunk();
    assert_eq!(trunk.name, "body");
    assert!((trunk.inertia.mass() - 1.5).abs() < 1e-15);
    // Σ m c: the imu's 0.5 kg at x = 0.2 m.
    assert!((trunk.inertia.h() - nalgebra::Vector3::new(0.1, 0.0, 0.0)).norm() < 1e-15);
    // Its parallel-axis term: Iyy = 0.01 + 0.001 + 0.5 · 0.2².
    assert!((trunk.inertia.ibar()[(1, 1)] - 0.031).abs() < 1e-15);
    assert_eq!(robot_.joints(), 1);
    assert!(trunk.bounding.is_some());
    let e = urdf_err(&xml);
    assert!(
        e.contains("joint 'free' is floating") && e.contains("--floating-base"),
        "{e}"
    );
}

/// Solo12 (data/solo12, not built with physid): its root link is the trunk, its feet merge into
/// the lower legs, twelve joints.
#[test]
fn solo12_floats_with_its_base_link_as_the_trunk() {
    let path = common::root().join("data/solo12/solo12.urdf");
    let (solo, warnings) = urdf::load_floating(&path, &Default::default()).unwrap();
    assert_eq!(solo.trunk().name, "base_link");
    assert!((solo.trunk().inertia.mass() - 1.16115091).abs() < 1e-12);
    assert_eq!(solo.joints(), 12);
    assert_eq!(solo.tree().joint_names()[0], "FL_HAA");
    // Its meshes are not in the repository: said, not fatal.
    assert!(
        warnings.iter().any(|w| w.contains("solo_12_base.stl")),
        "{warnings:?}"
    );
    // Read as fixed-base it is the same tree (no floating joint in this file).
    assert_eq!(urdf::load(&path, &Default::default()).unwrap().0.dof(), 12);
}

#[test]
fn a_gazebo_plugins_joint_name_leaves_the_next_joint_its_origin() {
    // Kinova's URDFs put `<jointName>` in a force-torque plugin after each joint. Searched as
    // text, "<joint" matched it, and the next joint's <origin> was dropped as a repeat of the
    // link's inertial origin in between: the arm's kinematics were silently wrong (torques off
    // by 100 % against pinocchio). Read from the document, the plugin is no joint.
    let xml = robot(&format!(
        r#"<link name="base"/><link name="a">{LINK}</link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/><origin xyz="0 0 0.2"/></joint>
  <gazebo><plugin name="ft_sensor" filename="libgazebo_ros_ft_sensor.so"><jointName>j1</jointName></plugin></gazebo>
  <link name="b"><inertial><origin xyz="0 -0.1 0"/><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="j2" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 1 0"/><origin rpy="0 0 0" xyz="0.3 0 0.4"/></joint>"#
    ));
    let (m, warnings) =
        io::urdf::from_str(&xml, std::path::Path::new("arm.urdf"), &Default::default()).unwrap();
    assert!(
        !warnings.iter().any(|w| w.contains("more than one")),
        "{warnings:?}"
    );
    assert_eq!(
        m.bodies()[0].x_tree.r,
        nalgebra::Vector3::new(0.0, 0.0, 0.2)
    );
    assert_eq!(
        m.bodies()[1].x_tree.r,
        nalgebra::Vector3::new(0.3, 0.0, 0.4)
    );
    assert_eq!(
        m.bodies()[1].inertia.h(),
        nalgebra::Vector3::new(0.0, -0.1, 0.0)
    );
}

#[test]
fn mjcf_export_leaves_out_zero_sized_shapes_and_rounding_beyond_the_triangle_inequality() {
    // A placeholder `<box size="0 0 0"/>` (Kinova's, Sawyer's and Atlas's URDFs) and a flat
    // plate whose moments, written in decimals, exceed A + B = C by 4e-18 (ROBOTIS OP2's
    // gripper): MuJoCo refused both files. The inertia goes in principal axes, checked here on
    // the numbers written, as MuJoCo checks them.
    let xml = robot(
        r#"<link name="base"><visual><geometry><box size="0 0 0"/></geometry></visual></link>
  <link name="plate"><inertial><mass value="0.01"/>
    <inertia ixx="8.53333333333e-07" ixy="0" ixz="0" iyy="1.70666666667e-06" iyz="0" izz="8.53333333333e-07"/></inertial>
    <visual><geometry><box size="0.02 0.01 0"/></geometry></visual>
    <visual><geometry><cylinder radius="0.01" length="0.03"/></geometry></visual></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="plate"/><axis xyz="0 0 1"/></joint>"#,
    );
    let (m, _) = urdf::from_str(&xml, Path::new("op2.urdf"), &Default::default()).unwrap();
    let text = io::mjcf::to_string(&m);
    assert!(!text.contains("type=\"box\""), "{text}");
    assert_eq!(text.matches("type=\"cylinder\"").count(), 1, "{text}");
    let diag = text
        .split("diaginertia=\"")
        .nth(1)
        .and_then(|s| s.split('"').next())
        .unwrap();
    let mut l: Vec<f64> = diag.split(' ').map(|x| x.parse().unwrap()).collect();
    l.sort_by(f64::total_cmp);
    assert!(l[0] + l[1] >= l[2], "{l:?}");
    // Moved by no more than its excess and the room it leaves (1e-12 of the sum).
    let excess = 1.70666666667e-06 - 2.0 * 8.53333333333e-07;
    assert!(
        (l[2] - 1.70666666667e-06).abs() <= excess + 2e-12 * l[2],
        "{l:?}"
    );
    assert!((l[0] - 8.53333333333e-07).abs() < 1e-20, "{l:?}");
    // A point mass (URDFs' inertia of zeros under a mass) gets moments of 1e-14 kg m².
    let point = xml.replace(
        r#"ixx="8.53333333333e-07" ixy="0" ixz="0" iyy="1.70666666667e-06" iyz="0" izz="8.53333333333e-07""#,
        r#"ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0""#,
    );
    let (m, _) = urdf::from_str(&point, Path::new("op2.urdf"), &Default::default()).unwrap();
    let text = io::mjcf::to_string(&m);
    let floor = "0.00000000000001";
    assert!(
        text.contains(&format!(
            r#"mass="0.01" diaginertia="{floor} {floor} {floor}""#
        )),
        "{text}"
    );
}
