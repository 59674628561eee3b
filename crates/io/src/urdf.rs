//! URDF import (urdf-rs) for fixed-base and floating robots, and export with inertial tags.
//!
//! Import rules:
//! - the root link and everything fixed to it form the static base; its inertia is ignored,
//!   unless the robot is read as floating ([`load_floating`]): then they form the trunk, whose
//!   inertia is their sum. A `floating` joint from a massless root link with no other joint (the
//!   "world" of many descriptions) marks a floating robot: that link and joint are dropped and
//!   the joint's child is the root; reading such a robot as fixed-base is an error;
//! - `fixed` joints are merged: the child's inertia is added to its parent body, expressed in
//!   the parent's frame; `revolute`, `continuous` and `prismatic` joints become bodies;
//!   other `floating` and `planar` joints are rejected (one-DoF joints only below the root);
//! - a joint with `<mimic>` whose child is a leaf link on the parent of the mimicked joint's
//!   body is a **rotor** of that joint, with gear ratio = multiplier (this is how physid exports
//!   rotors, so URDF round-trips); rotors can also come from a scenario's sidecar (TOML);
//! - `<dynamics damping friction>` become viscous and Coulomb friction;
//! - a link without `<inertial>` is massless (urdf-rs gives it zero mass); a moving joint whose
//!   whole subtree is massless is an error (its mass matrix would be singular);
//! - a joint limit of `effort = 0` or `velocity = 0` means "not given" (infinite), and so does
//!   SDF's −1 for "no limit" (with a warning) or a missing `velocity`; another negative limit
//!   is refused by name;
//! - what physid does not read and urdf-rs would refuse is taken out first (`urdf_text`):
//!   materials, and the axis of a fixed joint;
//! - where an element appears twice (for example two `<origin>` in one joint), urdfdom and
//!   so pinocchio and ROS use the first; physid does the same and reports a warning.

use super::geometry::{self, Lookup};
use super::robot_spec::RobotExtras;
use super::IoError;
use nalgebra::{Matrix3, Vector3};
use physid_core::model::floating::{FloatingModel, Trunk};
use physid_core::model::{Body, Joint, JointFriction, JointLimits, Model, Rotor, STANDARD_GRAVITY};
use physid_core::spatial::bounding::Piece;
use physid_core::spatial::{rpy_to_matrix, InertialParams, Transform};
use std::collections::HashMap;
use std::path::Path;

/// Loads a URDF file, applying the sidecar `extras` (rotors, friction, ellipsoids, how
/// geometry becomes bounding ellipsoids). Returns the model and warnings (elements that appear
/// twice, geometry that gave no bounding ellipsoid). Meshes are found relative to `path`.
pub fn load(path: &Path, extras: &RobotExtras) -> Result<(Model, Vec<String>), IoError> {
    let xml = super::read_to_string(path)?;
    from_str(&xml, path, extras)
}

/// Loads a URDF file as a floating robot: its root link and the links fixed to it are the
/// trunk (their inertias summed, bounded by their geometry or, without it, by the points where
/// the legs attach and the trunk's centre of mass); the rest as [`load`] reads it.
pub fn load_floating(
    path: &Path,
    extras: &RobotExtras,
) -> Result<(FloatingModel, Vec<String>), IoError> {
    let xml = super::read_to_string(path)?;
    floating_from_str(&xml, path, extras)
}

/// [`load_floating`] of URDF text (`path` names it in errors and locates its meshes).
pub fn floating_from_str(
    xml: &str,
    path: &Path,
    extras: &RobotExtras,
) -> Result<(FloatingModel, Vec<String>), IoError> {
    let (model, warnings, trunk) = parse(xml, path, extras, true)?;
    let trunk = trunk.expect("a floating parse gives the trunk");
    let robot = FloatingModel::new(trunk, model).map_err(|source| IoError::Model {
        path: path.to_path_buf(),
        source,
    })?;
    Ok((robot, warnings))
}

/// The inertial parameters of a URDF `<inertial>` in its link frame.
fn link_params(l: &urdf_rs::Link) -> InertialParams {
    let i = &l.inertial;
    let rot = rpy_to_matrix(&Vector3::from(i.origin.rpy.0));
    let t = &i.inertia;
    let ic_local = Matrix3::new(
        t.ixx, t.ixy, t.ixz, t.ixy, t.iyy, t.iyz, t.ixz, t.iyz, t.izz,
    );
    let ic = rot * ic_local * rot.transpose();
    InertialParams::from_mass_com_inertia(i.mass.value, &Vector3::from(i.origin.xyz.0), &ic)
}

fn origin_transform(p: &urdf_rs::Pose) -> Transform {
    Transform::from_pose(
        &rpy_to_matrix(&Vector3::from(p.rpy.0)),
        &Vector3::from(p.xyz.0),
    )
}

/// The name of the document's first element (after the XML declaration, comments and
/// doctype), if any.
fn root_element(xml: &str) -> Option<&str> {
    let mut rest = xml;
    loop {
        let start = rest.find('<')?;
        rest = &rest[start + 1..];
        if let Some(comment) = rest.strip_prefix("!--") {
            rest = &comment[comment.find("-->")? + 3..];
        } else if rest.starts_with('?') || rest.starts_with('!') {
            rest = &rest[rest.find('>')? + 1..];
        } else {
            let end = rest
                .find(|c: char| c.is_whitespace() || c == '>' || c == '/')
                .unwrap_or(rest.len());
            return Some(&rest[..end]);
        }
    }
}

/// The model of `bodies` with the sidecar's gravity and rotor model and the base's shapes,
/// checked physically (its bodies' inertias consistent).
fn physical_model(
    name: String,
    bodies: Vec<Body>,
    (extras, base_shapes): (&RobotExtras, Vec<physid_core::model::Shape>),
    path: &Path,
) -> Result<Model, IoError> {
    let model_err = |source| IoError::Model {
        path: path.to_path_buf(),
        source,
    };
    let gravity = extras
        .gravity
        .map_or(Vector3::new(0.0, 0.0, -STANDARD_GRAVITY), Vector3::from);
    let model = Model::new(name, bodies, gravity)
        .map_err(model_err)?
        .with_rotor_model(extras.rotor_model.unwrap_or_default())
        .with_base_shapes(base_shapes);
    model.check_physical_with(false).map_err(model_err)?;
    Ok(model)
}

/// The warning that meshes of the links' (`shapes`) or the base's geometry were not found.
fn lost_meshes(shapes: &[Shapes], base: &Shapes) -> Option<String> {
    let lost: Vec<&String> = shapes.iter().chain([base]).flat_map(|s| &s.lost).collect();
    (!lost.is_empty()).then(|| {
        format!(
            "{} meshes of the geometry were not found, and exports (MJCF) will lack them: {} (give --package-dir)",
            lost.len(),
            lost.iter().take(4).map(|s| s.as_str()).collect::<Vec<_>>().join("; ")
        )
    })
}

/// Parses URDF text; `path` names it in errors and locates its meshes. Each body's bounding
/// ellipsoid is the minimum-volume ellipsoid of its geometry (its link's and those fixed to it,
/// [`super::geometry`]) unless the sidecar gives one. Returns the model and warnings
/// (duplicate elements, geometry that gave no bound).
pub fn from_str(
    xml: &str,
    path: &Path,
    extras: &RobotExtras,
) -> Result<(Model, Vec<String>), IoError> {
    let (model, warnings, _) = parse(xml, path, extras, false)?;
    Ok((model, warnings))
}

/// The URDF text as urdf-rs reads it (only the first of each repeated element), the XML
/// document for the attributes urdf-rs does not read, and the repeated elements' warnings.
fn read_robot<'x>(
    xml: &'x str,
    path: &Path,
) -> Result<(urdf_rs::Robot, Option<roxmltree::Document<'x>>, Vec<String>), IoError> {
    if let Some(root) = root_element(xml).filter(|r| *r != "robot") {
        return Err(IoError::Parse {
            path: path.to_path_buf(),
            message: format!("not a URDF: the document's root element is <{root}>, not <robot>"),
        });
    }
    let doc = roxmltree::Document::parse(xml).ok();
    // Not XML to roxmltree: urdf-rs names what is wrong with it.
    let (text, warnings) = match &doc {
        Some(d) => super::urdf_text::readable(xml, d, path)?,
        None => (xml.to_string(), vec![]),
    };
    let robot = urdf_rs::read_from_string(&text).map_err(|e| IoError::Parse {
        path: path.to_path_buf(),
        message: format!("not a valid URDF: {e}"),
    })?;
    Ok((robot, doc, warnings))
}

/// The model of the tree and the warnings, with the trunk when `floating`.
fn parse(
    xml: &str,
    path: &Path,
    extras: &RobotExtras,
    floating: bool,
) -> Result<(Model, Vec<String>, Option<Trunk>), IoError> {
    let (robot, doc, mut warnings) = read_robot(xml, path)?;
    let mut robot = rooted(robot, path, floating)?;
    let tiny = tiny_masses_zeroed(&mut robot);
    warnings.extend(tiny_masses_note(&tiny));
    let rates = doc
        .as_ref()
        .map_or(Ok(HashMap::new()), |d| rate_limits(d, path))?;
    let link_idx = link_index(&robot, path)?;
    let (children, root) = tree(&robot, &link_idx, path)?;
    let lookup = Lookup {
        urdf: path,
        opts: &extras.geometry,
    };
    let Walk {
        mut bodies,
        body_parent_link_x,
        shapes,
        base,
        mimics,
        base_inertia,
        ..
    } = walk(&robot, &link_idx, &children, (root, floating), &lookup)?;
    warnings.extend(doc.as_ref().map_or(vec![], empty_ranges));
    warnings.extend(doc.as_ref().map_or(vec![], sdf_no_limits));
    apply_rate_limits(&mut bodies, &rates);
    warnings.extend(lost_meshes(&shapes, &base));
    bound_bodies(&mut bodies, &shapes, &lookup, &mut warnings);
    attach_rotors(&mut bodies, mimics, &lookup, &mut warnings)?;
    // The sidecar's ellipsoids come last: they override the geometry's (the trunk's, of a
    // floating robot, is its own).
    let (trunk_sidecar, extras) = extras.split_ellipsoid(floating.then_some(root), path)?;
    extras.apply(&mut bodies, &body_parent_link_x, path)?;
    check_subtree_masses(&bodies, &tiny, path)?;
    let trunk = floating.then(|| Trunk {
        name: root.to_string(),
        inertia: base_inertia,
        bounding: trunk_sidecar.or_else(|| {
            trunk_bound(
                &bodies,
                &base,
                (root, &base_inertia),
                &lookup,
                &mut warnings,
            )
        }),
    });
    let model = physical_model(robot.name.clone(), bodies, (&extras, base.shapes), path)?;
    check_bounds(&model, &extras, path, &mut warnings)?;
    Ok((model, warnings, trunk))
}

/// `robot` with a floating joint from a massless world link removed ([`strip_floating_root`]),
/// which only a `floating` read accepts; `Err` for a robot without links.
fn rooted(
    mut robot: urdf_rs::Robot,
    path: &Path,
    floating: bool,
) -> Result<urdf_rs::Robot, IoError> {
    if let Some(joint) = strip_floating_root(&mut robot, path)?.filter(|_| !floating) {
        return Err(IoError::invalid(
            path,
            format!("joint '{joint}' is floating: the robot's root moves, and this reads fixed-base robots; read it as a floating-base robot (`physid dynamics --floating-base`)"),
        ));
    }
    if robot.links.is_empty() {
        return Err(IoError::invalid(path, "the robot has no <link> elements"));
    }
    Ok(robot)
}

/// The acceleration and jerk limits physid reads from the URDF's `<limit>` (urdf-rs does not),
/// by joint name.
fn apply_rate_limits(bodies: &mut [Body], rates: &RateLimits) {
    for b in bodies {
        if let Some(&(acceleration, jerk)) = rates.get(&b.joint_name) {
            b.limits.acceleration = acceleration.unwrap_or(b.limits.acceleration);
            b.limits.jerk = jerk.unwrap_or(b.limits.jerk);
        }
    }
}

/// A `floating` joint whose parent is a massless root link with no other joint: the link and
/// the joint are removed (the joint's child becomes the root) and the joint's name returned.
/// A floating joint anywhere else is an error naming it.
fn strip_floating_root(robot: &mut urdf_rs::Robot, path: &Path) -> Result<Option<String>, IoError> {
    let floating = |jt: &urdf_rs::Joint| matches!(jt.joint_type, urdf_rs::JointType::Floating);
    let Some(j) = robot.joints.iter().position(floating) else {
        return Ok(None);
    };
    let (name, parent) = (
        robot.joints[j].name.clone(),
        robot.joints[j].parent.link.clone(),
    );
    let is_root = !robot.joints.iter().any(|o| o.child.link == parent);
    let alone = robot
        .joints
        .iter()
        .filter(|o| o.parent.link == parent)
        .count()
        == 1;
    let massless = (robot.links.iter()).any(|l| l.name == parent && l.inertial.mass.value == 0.0);
    if !(is_root && alone && massless) {
        return Err(IoError::invalid(
            path,
            format!("joint '{name}' is floating but does not hang the robot from a massless root link of its own (the world): only the root of the tree may float"),
        ));
    }
    robot.joints.remove(j);
    robot.links.retain(|l| l.name != parent);
    Ok(Some(name))
}

/// The trunk's bounding ellipsoid: its geometry's (the root link's and those fixed to it);
/// without geometry, the points where the tree attaches and the trunk's centre of mass, as for
/// a body without geometry ([`kinematic_bound`]); none, with a warning, where meshes are
/// missing.
fn trunk_bound(
    bodies: &[Body],
    base: &Shapes,
    (name, inertia): (&str, &InertialParams),
    lookup: &Lookup,
    warnings: &mut Vec<String>,
) -> Option<physid_core::spatial::Ellipsoid> {
    if base.has_no_geometry() || (base.pieces.is_empty() && base.missing.is_empty()) {
        let mut points: Vec<Vector3<f64>> = vec![Vector3::zeros()];
        points.extend(
            bodies
                .iter()
                .filter(|b| b.parent.is_none())
                .map(|b| b.x_tree.r),
        );
        if inertia.mass() > 0.0 {
            points.push(inertia.h() / inertia.mass());
        }
        return Some(grown_to_hold(points, inertia));
    }
    base.bound(name, lookup, warnings).unwrap_or_else(|w| {
        warnings.push(w);
        None
    })
}

/// Each body's shapes and bounding ellipsoid: its geometry's, or the kinematic tree's
/// ([`kinematic_bound`]) where none of its links has geometry (one warning naming them), or
/// none with a warning saying why.
fn bound_bodies(
    bodies: &mut [Body],
    shapes: &[Shapes],
    lookup: &Lookup,
    warnings: &mut Vec<String>,
) {
    // Only the bodies without geometry need the tree's bound (each reads the whole tree).
    let tree_bounds: Vec<Option<physid_core::spatial::Ellipsoid>> = (0..bodies.len())
        .map(|i| {
            (shapes[i].has_no_geometry() && !lookup.opts.ignore_geometry)
                .then(|| kinematic_bound(bodies, i))
        })
        .collect();
    let mut from_tree = vec![];
    for ((b, s), tree) in bodies.iter_mut().zip(shapes).zip(tree_bounds) {
        b.shapes = s.shapes.clone();
        b.bounding = if tree.is_some() {
            from_tree.push(format!("'{}'", b.name));
            tree
        } else {
            s.bound(&b.name, lookup, warnings).unwrap_or_else(|w| {
                warnings.push(w);
                None
            })
        };
    }
    if !from_tree.is_empty() {
        warnings.push(format!(
            "no geometry for {}: their bounding ellipsoids are the kinematic tree's (each body's joint, its children's joints and its centre of mass, {KINEMATIC_MARGIN} m + {KINEMATIC_SHARE} of the segment beyond, grown to hold the description's own inertia); give geometry or sidecar ellipsoids for surer bounds",
            from_tree.join(", ")
        ));
    }
}

/// A bounding ellipsoid's margin beyond the kinematic segment (m) ...
const KINEMATIC_MARGIN: f64 = 0.05;

/// ... plus this share of the segment's length: a link's mass lies around the line between its
/// joints, a housing or a motor's width beside it.
const KINEMATIC_SHARE: f64 = 0.25;

/// Body `i`'s ellipsoid from the kinematic tree alone, for a description without geometry: the
/// box of its joint's origin, its children's joint origins and its centre of mass, enlarged
/// by [`KINEMATIC_MARGIN`] plus [`KINEMATIC_SHARE`] of the segment's length, then scaled until
/// the description's own body lies inside (`tr(JQ) ≥ 0`).
fn kinematic_bound(bodies: &[Body], i: usize) -> physid_core::spatial::Ellipsoid {
    let b = &bodies[i];
    let m = b.inertia.mass();
    let mut points = vec![Vector3::zeros()];
    points.extend(
        (bodies.iter())
            .filter(|c| c.parent == Some(i))
            .map(|c| c.x_tree.r),
    );
    if m > 0.0 {
        points.push(b.inertia.h() / m);
    }
    grown_to_hold(points, &b.inertia)
}

/// The ellipsoid around `points` with [`KINEMATIC_MARGIN`] plus [`KINEMATIC_SHARE`] of their
/// reach, scaled until `inertia` lies inside (`tr(JQ) ≥ 0`).
fn grown_to_hold(
    points: Vec<Vector3<f64>>,
    inertia: &InertialParams,
) -> physid_core::spatial::Ellipsoid {
    let reach = points.iter().map(|p| p.norm()).fold(0.0, f64::max);
    let mut e = physid_core::spatial::Ellipsoid::around_points(
        &points,
        KINEMATIC_MARGIN + KINEMATIC_SHARE * reach,
    );
    for _ in 0..40 {
        match inertia.consistency(Some(&e)).trace_jq_per_mass {
            Some(t) if t < 0.0 => e = e.scaled(1.25),
            _ => break,
        }
    }
    e
}

/// A warning per revolute or prismatic joint whose `<limit>` gives `lower` and `upper` both and
/// equal: a range the joint cannot move in. Both zero is also what URDF readers give when the
/// attributes are left out, and is read as unlimited; other equal values are kept, and the
/// joint should be locked (`--lock`).
fn empty_ranges(doc: &roxmltree::Document) -> Vec<String> {
    let moving =
        |j: &roxmltree::Node| matches!(j.attribute("type"), Some("revolute") | Some("prismatic"));
    let mut out = vec![];
    for (joint, limit) in joint_limits(doc).filter(|(j, _)| moving(j)) {
        let value = |a: &str| {
            limit
                .attribute(a)
                .and_then(|v| v.trim().parse::<f64>().ok())
        };
        let (Some(lower), Some(upper)) = (value("lower"), value("upper")) else {
            continue;
        };
        if lower != upper {
            continue;
        }
        let name = joint.attribute("name").unwrap_or("");
        out.push(if lower == 0.0 {
            format!("joint '{name}': <limit lower=\"0\" upper=\"0\"> is an empty range; read as no range at all (URDF's value when none is given): write type=\"continuous\" for an unlimited joint, or --lock {name} for a joint that does not move")
        } else {
            format!("joint '{name}': <limit lower = upper = {lower}> is a range the joint cannot move in: --lock {name} if it does not move")
        });
    }
    out
}

/// SDF's value of a velocity or effort limit for "no limit".
const SDF_NO_LIMIT: f64 = -1.0;

/// A warning per moving joint whose `<limit>` gives `velocity` or `effort` −1: read as not
/// given (SDF's "no limit", which descriptions converted from SDF carry).
fn sdf_no_limits(doc: &roxmltree::Document) -> Vec<String> {
    let moving = |j: &roxmltree::Node| j.attribute("type").is_some_and(|t| t != "fixed");
    let mut out = vec![];
    for (joint, limit) in joint_limits(doc).filter(|(j, _)| moving(j)) {
        for field in ["velocity", "effort"] {
            let value = limit
                .attribute(field)
                .and_then(|v| v.trim().parse::<f64>().ok());
            if value == Some(SDF_NO_LIMIT) {
                out.push(format!(
                    "joint '{}': <limit {field}=\"-1\"> read as not given (SDF's -1 for no limit)",
                    joint.attribute("name").unwrap_or("")
                ));
            }
        }
    }
    out
}

/// Each top-level `<joint>` with its `<limit>` (joints without one left out).
fn joint_limits<'a, 'input>(
    doc: &'a roxmltree::Document<'input>,
) -> impl Iterator<Item = (roxmltree::Node<'a, 'input>, roxmltree::Node<'a, 'input>)> {
    super::urdf_text::top_level_joints(doc).filter_map(|joint| {
        let limit = joint.children().find(|n| n.has_tag_name("limit"))?;
        Some((joint, limit))
    })
}

/// Per joint name, `<limit acceleration jerk>` as given.
type RateLimits = HashMap<String, (Option<f64>, Option<f64>)>;

/// Per joint, the `acceleration` and `jerk` attributes of its `<limit>` (not part of the URDF
/// standard, which urdfdom ignores; some descriptions carry them for planners). A value that
/// is not a number is an error naming the joint.
fn rate_limits(doc: &roxmltree::Document, path: &Path) -> Result<RateLimits, IoError> {
    let mut out = HashMap::new();
    for (joint, limit) in joint_limits(doc) {
        let name = joint.attribute("name").unwrap_or("");
        let read = |attr: &str| -> Result<Option<f64>, IoError> {
            limit
                .attribute(attr)
                .map(|v| {
                    v.trim().parse::<f64>().map_err(|_| {
                        IoError::invalid(
                            path,
                            format!("joint '{name}': <limit {attr}=\"{v}\"> is not a number"),
                        )
                    })
                })
                .transpose()
        };
        let pair = (read("acceleration")?, read("jerk")?);
        if pair != (None, None) {
            out.insert(name.to_string(), pair);
        }
    }
    Ok(out)
}

/// The smallest link mass read as a mass (kg): no part weighs less, and a body that did would
/// make the mass matrix singular in effect. Real URDFs give such masses to frames (1e-10 kg
/// on PR2's camera frames), so a link below it is read as massless, with a warning.
const MIN_MASS: f64 = 1e-9;

/// Each link of `robot` whose mass is positive and below [`MIN_MASS`], made massless (its
/// `<inertial>` zeroed): the links and the masses they had.
fn tiny_masses_zeroed(robot: &mut urdf_rs::Robot) -> Vec<(String, f64)> {
    let mut out = vec![];
    for l in robot.links.iter_mut() {
        let m = l.inertial.mass.value;
        if m > 0.0 && m < MIN_MASS {
            out.push((l.name.clone(), m));
            l.inertial = urdf_rs::Inertial::default();
        }
    }
    out
}

/// The warning (or, in the error of a massless joint, the note) for the links read as massless.
fn tiny_masses_note(tiny: &[(String, f64)]) -> Option<String> {
    let links: Vec<String> = tiny
        .iter()
        .map(|(l, m)| format!("'{l}' ({m:e} kg)"))
        .collect();
    (!tiny.is_empty()).then(|| {
        format!(
            "{} below {MIN_MASS:e} kg, which no part weighs, read as massless: {}",
            if tiny.len() == 1 {
                "a link mass"
            } else {
                "link masses"
            },
            links.join(", ")
        )
    })
}

/// Link name → index; every link defined once with a finite non-negative mass.
fn link_index<'r>(
    robot: &'r urdf_rs::Robot,
    path: &Path,
) -> Result<HashMap<&'r str, usize>, IoError> {
    let bad = |m: String| IoError::invalid(path, m);
    let mut link_idx = HashMap::new();
    for (i, l) in robot.links.iter().enumerate() {
        if link_idx.insert(l.name.as_str(), i).is_some() {
            return Err(bad(format!("link '{}' is defined twice", l.name)));
        }
        let m = l.inertial.mass.value;
        if !m.is_finite() || m < 0.0 {
            return Err(bad(format!(
                "link '{}': mass {m} kg is not a finite non-negative number",
                l.name
            )));
        }
    }
    Ok(link_idx)
}

/// The joint tree: each link's child joints, and the one root link. Every joint names defined
/// links; no link is the child of two joints.
fn tree<'r>(
    robot: &'r urdf_rs::Robot,
    link_idx: &HashMap<&str, usize>,
    path: &Path,
) -> Result<(HashMap<&'r str, Vec<usize>>, &'r str), IoError> {
    let bad = |m: String| IoError::invalid(path, m);
    // Each link has at most one parent joint; every joint names existing links.
    let mut parent_joint: HashMap<&str, usize> = HashMap::new();
    let mut children: HashMap<&str, Vec<usize>> = HashMap::new();
    for (j, jt) in robot.joints.iter().enumerate() {
        for (role, l) in [("parent", &jt.parent.link), ("child", &jt.child.link)] {
            if !link_idx.contains_key(l.as_str()) {
                return Err(bad(format!(
                    "joint '{}' names {role} link '{l}', which is not defined",
                    jt.name
                )));
            }
        }
        if let Some(&other) = parent_joint.get(jt.child.link.as_str()) {
            return Err(bad(format!(
                "link '{}' is the child of two joints ('{}' and '{}'): a closed loop, but URDF describes a tree",
                jt.child.link, robot.joints[other].name, jt.name
            )));
        }
        parent_joint.insert(&jt.child.link, j);
        children.entry(&jt.parent.link).or_default().push(j);
    }
    let roots: Vec<&str> = robot
        .links
        .iter()
        .map(|l| l.name.as_str())
        .filter(|l| !parent_joint.contains_key(l))
        .collect();
    let root = match roots.as_slice() {
        [r] => *r,
        [] => {
            return Err(bad(
                "no root link: the joints form a closed loop".to_string()
            ))
        }
        many => {
            return Err(bad(format!(
                "several root links ({}): the robot is not one connected tree",
                many.join(", ")
            )))
        }
    };

    Ok((children, root))
}

/// A mimic joint waiting to become the rotor of the joint it mimics: the joint, its mimic
/// element, the body it is mounted on, its placement on that body, its inertial parameters,
/// its geometry.
type PendingRotor<'r> = (
    &'r urdf_rs::Joint,
    &'r urdf_rs::Mimic,
    Option<usize>,
    Transform,
    InertialParams,
    Shapes,
);

/// The geometry gathered for one body (its link and the links fixed to it) or rotor, in its
/// frame: the pieces, and the links whose geometry could not be used (with why).
#[derive(Default)]
struct Shapes {
    /// The shapes themselves, for export.
    shapes: Vec<physid_core::model::Shape>,
    /// Meshes of the shapes that were not found (left out of every export).
    lost: Vec<String>,
    pieces: Vec<Piece>,
    missing: Vec<String>,
}

impl Shapes {
    /// A link's own geometry, in its frame.
    fn of_link(link: &urdf_rs::Link, lookup: &Lookup) -> Self {
        let mut own = Shapes::default();
        own.add(link, &Transform::identity(), lookup);
        own
    }

    /// Adds a link's geometry, placed in the body frame by `x_link` (link from body). A link
    /// with mass but no usable geometry makes the body's bound unknown.
    fn add(&mut self, link: &urdf_rs::Link, x_link: &Transform, lookup: &Lookup) {
        self.add_shapes(link, x_link, lookup);
        if lookup.opts.ignore_geometry {
            return;
        }
        let (rot, pos) = x_link.to_pose();
        match geometry::link_pieces(link, lookup) {
            Ok(Some(pieces)) => self
                .pieces
                .extend(geometry::into_frame(&pieces, &rot, &pos)),
            Ok(None) if link.inertial.mass.value > 0.0 => self
                .missing
                .push(format!("link '{}' has mass but no geometry", link.name)),
            Ok(None) => {}
            Err(e) => self.missing.push(format!("link '{}': {e}", link.name)),
        }
    }

    /// Adds a link's shapes only (for export: the base's geometry bounds nothing).
    fn add_shapes(&mut self, link: &urdf_rs::Link, x_link: &Transform, lookup: &Lookup) {
        let (shapes, lost) = geometry::link_shapes_and_missing(link, lookup);
        self.shapes
            .extend(shapes.into_iter().map(|s| physid_core::model::Shape {
                pose: s.pose.compose(x_link),
                kind: s.kind,
            }));
        self.lost.extend(
            lost.into_iter()
                .map(|m| format!("link '{}': {m}", link.name)),
        );
    }

    /// Whether every link of the body with mass has no geometry at all (and none has any).
    fn has_no_geometry(&self) -> bool {
        self.pieces.is_empty()
            && !self.missing.is_empty()
            && (self.missing.iter()).all(|m| m.ends_with("has mass but no geometry"))
    }

    /// The bounding ellipsoid, or a warning naming the element and why there is none; a cache
    /// entry that could not bound the geometry is said in `warnings`.
    fn bound(
        &self,
        element: &str,
        lookup: &Lookup,
        warnings: &mut Vec<String>,
    ) -> Result<Option<physid_core::spatial::Ellipsoid>, String> {
        // Without geometry (or with `ignore_geometry`, where `add` collects none): no bound.
        if self.pieces.is_empty() && self.missing.is_empty() {
            return Ok(None);
        }
        if !self.missing.is_empty() {
            return Err(format!(
                "no bounding ellipsoid for '{element}' from geometry: {}",
                self.missing.join("; ")
            ));
        }
        let (e, said) = geometry::bound(&self.pieces, lookup.opts)
            .map_err(|e| format!("no bounding ellipsoid for '{element}' from geometry: {e}"))?;
        warnings.extend(said.map(|s| format!("'{element}': {s}")));
        Ok(Some(e))
    }
}

/// The bodies found by walking the tree from the root.
struct Walk<'r> {
    bodies: Vec<Body>,
    /// Per body: its parent link's frame from its parent body's frame.
    body_parent_link_x: Vec<Transform>,
    /// Per body: its geometry.
    shapes: Vec<Shapes>,
    /// The static base's geometry (the root link and the links fixed to it).
    base: Shapes,
    /// Their summed inertia in the root link's frame (a floating robot's trunk).
    base_inertia: InertialParams,
    /// Whether the base is a floating trunk (its geometry then bounds it).
    floating: bool,
    mimics: Vec<PendingRotor<'r>>,
}

/// Walks the joints in file order, each once its parent link is placed (a topological order
/// that keeps the file's order where it already lists parents first): moving joints become
/// bodies, fixed links are merged into their parent body, mimic joints are set aside as rotors.
fn walk<'r>(
    robot: &'r urdf_rs::Robot,
    link_idx: &HashMap<&str, usize>,
    children: &HashMap<&str, Vec<usize>>,
    (root, floating): (&'r str, bool),
    lookup: &Lookup,
) -> Result<Walk<'r>, IoError> {
    let path = lookup.urdf;
    let bad = |m: String| IoError::invalid(path, m);
    // Joints in file order, each once its parent link is placed (a topological order that keeps
    // the file's order where it already lists parents first). attach[link] = (body index or None
    // for the base, link_X_body).
    let mut attach: HashMap<&str, (Option<usize>, Transform)> = HashMap::new();
    attach.insert(root, (None, Transform::identity()));
    let mut w = Walk::rooted(&robot.links[link_idx[root]], floating, lookup);
    let mut done = vec![false; robot.joints.len()];
    let mut progress = true;
    while progress {
        progress = false;
        for (j, jt) in robot.joints.iter().enumerate() {
            let Some(&(pb, x_p)) = attach.get(jt.parent.link.as_str()).filter(|_| !done[j]) else {
                continue;
            };
            done[j] = true;
            progress = true;
            let child = jt.child.link.as_str();
            let x_origin = origin_transform(&jt.origin).compose(&x_p);
            let child_link = &robot.links[link_idx[child]];
            let child_params = link_params(child_link);
            let Some(joint) = moving_joint(jt, path)? else {
                w.merge_fixed(pb, child_link, &x_origin, child_params, lookup);
                attach.insert(child, (pb, x_origin));
                continue;
            };
            if let Some(mimic) = &jt.mimic {
                if children.get(child).is_some_and(|c| !c.is_empty()) {
                    return Err(bad(format!(
                        "joint '{}' mimics '{}' but its child link '{child}' has children: only a leaf link can be a rotor. {MIMIC_LINKAGE}",
                        jt.name, mimic.joint
                    )));
                }
                let rotor_shapes = Shapes::of_link(child_link, lookup);
                w.mimics
                    .push((jt, mimic, pb, x_origin, child_params, rotor_shapes));
                attach.insert(child, (pb, x_origin));
                continue;
            }
            w.bodies
                .push(moving_body(jt, pb, joint, x_origin, child_params));
            w.body_parent_link_x.push(x_p);
            w.shapes.push(Shapes::of_link(child_link, lookup));
            attach.insert(child, (Some(w.bodies.len() - 1), Transform::identity()));
        }
    }
    check_walked(robot, &attach, &done, w.bodies.len(), root, path)?;
    Ok(w)
}

impl Walk<'_> {
    /// No body yet; the static base's geometry and inertia those of the `root` link.
    fn rooted(root: &urdf_rs::Link, floating: bool, lookup: &Lookup) -> Self {
        let mut base = Shapes::default();
        if floating {
            base.add(root, &Transform::identity(), lookup);
        } else {
            base.add_shapes(root, &Transform::identity(), lookup);
        }
        Walk {
            bodies: vec![],
            body_parent_link_x: vec![],
            shapes: vec![],
            base,
            base_inertia: link_params(root),
            floating,
            mimics: vec![],
        }
    }

    /// Merges a link fixed to body `pb` (or to the base, `None`) at `x_origin` (its frame from
    /// the body's): its inertial parameters `params` (about its own frame) and its shapes.
    fn merge_fixed(
        &mut self,
        pb: Option<usize>,
        link: &urdf_rs::Link,
        x_origin: &Transform,
        params: InertialParams,
        lookup: &Lookup,
    ) {
        if let Some(b) = pb {
            let merged = params.transformed(&x_origin.inverse());
            self.bodies[b].inertia = InertialParams(self.bodies[b].inertia.0 + merged.0);
            self.shapes[b].add(link, x_origin, lookup);
        } else {
            let merged = params.transformed(&x_origin.inverse());
            self.base_inertia = InertialParams(self.base_inertia.0 + merged.0);
            if self.floating {
                self.base.add(link, x_origin, lookup);
            } else {
                self.base.add_shapes(link, x_origin, lookup);
            }
        }
    }
}

/// A URDF joint's motion: `None` for a fixed joint (its child link is merged into the parent
/// body); an error naming the joint for a type with more than one degree of freedom.
fn moving_joint(jt: &urdf_rs::Joint, path: &Path) -> Result<Option<Joint>, IoError> {
    let axis = Vector3::from(jt.axis.xyz.0);
    use urdf_rs::JointType as T;
    match jt.joint_type {
        T::Fixed => Ok(None),
        T::Revolute | T::Continuous => Ok(Some(Joint::Revolute { axis })),
        T::Prismatic => Ok(Some(Joint::Prismatic { axis })),
        ref other => Err(IoError::invalid(
            path,
            format!(
                "joint '{}' has type {other:?}: physid models fixed-base robots with one-DoF joints (revolute, continuous, prismatic, fixed)",
                jt.name
            ),
        )),
    }
}

/// What a mimic joint that is not a rotor is, and what to do with it (errors end with it).
const MIMIC_LINKAGE: &str = "physid reads a <mimic> joint as a rotor only (a leaf link on the parent body of the joint it mimics); a linkage coupled by <mimic> (a gripper's fingers, a parallel link or piston) is not modelled: if it holds still in the data, make its joints and the joint they mimic type=\"fixed\" in a copy of the URDF (their links' mass then counts in the body they hang from)";

/// After the walk: every joint was reached from the root, and some joint moves.
fn check_walked(
    robot: &urdf_rs::Robot,
    attach: &HashMap<&str, (Option<usize>, Transform)>,
    done: &[bool],
    bodies: usize,
    root: &str,
    path: &Path,
) -> Result<(), IoError> {
    let bad = |m: String| IoError::invalid(path, m);
    if done.iter().any(|d| !d) {
        let lost: Vec<&str> = robot
            .links
            .iter()
            .map(|l| l.name.as_str())
            .filter(|l| !attach.contains_key(l))
            .collect();
        return Err(bad(format!(
            "links {} are not reachable from the root '{root}': they form a closed loop",
            lost.join(", ")
        )));
    }
    if bodies == 0 {
        return Err(bad("the robot has no moving joints".to_string()));
    }
    Ok(())
}

/// A moving joint's body: its child link's inertia, the joint's limits (0/0 or continuous:
/// unlimited; a velocity or effort limit of 0 or SDF's −1: unknown) and friction.
fn moving_body(
    jt: &urdf_rs::Joint,
    parent: Option<usize>,
    joint: Joint,
    x_tree: Transform,
    inertia: InertialParams,
) -> Body {
    use urdf_rs::JointType as T;
    let lim = &jt.limit;
    // 0 means "not given" in URDF, and −1 "no limit" in SDF, which descriptions converted from
    // SDF carry (`sdf_no_limits` warns); any other negative limit is kept for the model to
    // refuse by name.
    let infinite_if_not_given = |v: f64| {
        if v == 0.0 || v == SDF_NO_LIMIT {
            f64::INFINITY
        } else {
            v
        }
    };
    let (lower, upper) = match jt.joint_type {
        T::Continuous => (f64::NEG_INFINITY, f64::INFINITY),
        _ if lim.lower == 0.0 && lim.upper == 0.0 => (f64::NEG_INFINITY, f64::INFINITY),
        _ => (lim.lower, lim.upper),
    };
    let friction = jt
        .dynamics
        .as_ref()
        .map_or(JointFriction::default(), |d| JointFriction {
            viscous: d.damping,
            coulomb: d.friction,
        });
    Body {
        name: jt.child.link.clone(),
        joint_name: jt.name.clone(),
        parent,
        joint,
        x_tree,
        inertia,
        bounding: None,
        shapes: vec![],
        rotor: None,
        friction,
        limits: JointLimits {
            lower,
            upper,
            velocity: infinite_if_not_given(lim.velocity),
            effort: infinite_if_not_given(lim.effort),
            ..Default::default()
        },
    }
}

/// Mimic joints become the rotors of the joints they mimic: mounted on that joint's parent
/// body, no offset, one rotor per joint.
fn attach_rotors(
    bodies: &mut [Body],
    mimics: Vec<PendingRotor>,
    lookup: &Lookup,
    warnings: &mut Vec<String>,
) -> Result<(), IoError> {
    let mut from_tree = vec![];
    for (jt, mimic, pb, x_rot, params, shapes) in mimics {
        let k = rotor_host(bodies, jt, mimic, pb, lookup.urdf)?;
        bodies[k].rotor = Some(Rotor {
            name: jt.child.link.clone(),
            x_rot,
            // The mimic joint's own type: a prismatic mimic slides (a gripper's second finger,
            // as pinocchio models it), a revolute or continuous one spins.
            joint: match jt.joint_type {
                urdf_rs::JointType::Prismatic => Joint::Prismatic {
                    axis: Vector3::from(jt.axis.xyz.0),
                },
                _ => Joint::Revolute {
                    axis: Vector3::from(jt.axis.xyz.0),
                },
            },
            gear_ratio: mimic.multiplier.unwrap_or(1.0),
            inertia: params,
            bounding: rotor_bounding(&shapes, (&jt.child.link, &params), lookup, warnings)
                .inspect(|(_, kinematic)| {
                    if *kinematic {
                        from_tree.push(format!("'{}'", jt.child.link));
                    }
                })
                .map(|(e, _)| e),
        });
    }
    if !from_tree.is_empty() {
        warnings.push(format!(
            "no geometry for the rotors {}: their bounding ellipsoids are about each rotor's frame and centre of mass ({KINEMATIC_MARGIN} m), grown to hold the description's own inertia; give geometry or sidecar ellipsoids for surer bounds",
            from_tree.join(", ")
        ));
    }
    Ok(())
}

/// The body whose joint the mimic joint `jt` drives as its rotor; `Err` where it is not a
/// rotor (no such moving joint, on another body, with an offset, or a second rotor).
fn rotor_host(
    bodies: &[Body],
    jt: &urdf_rs::Joint,
    mimic: &urdf_rs::Mimic,
    pb: Option<usize>,
    path: &Path,
) -> Result<usize, IoError> {
    let bad = |m: String| IoError::invalid(path, m);
    let k = bodies
        .iter()
        .position(|b| b.joint_name == mimic.joint)
        .ok_or_else(|| {
            bad(format!(
                "joint '{}' mimics '{}', which is not a moving joint",
                jt.name, mimic.joint
            ))
        })?;
    if bodies[k].parent != pb {
        return Err(bad(format!(
            "joint '{}' mimics '{}' but is not mounted on that joint's parent body: not a rotor. {MIMIC_LINKAGE}",
            jt.name, mimic.joint
        )));
    }
    if mimic.offset.unwrap_or(0.0) != 0.0 {
        return Err(bad(format!(
            "joint '{}': a rotor's mimic offset must be 0",
            jt.name
        )));
    }
    if bodies[k].rotor.is_some() {
        return Err(bad(format!("joint '{}' drives two rotors", mimic.joint)));
    }
    Ok(k)
}

/// A rotor's bounding ellipsoid and whether it is [`rotor_bound`]'s (the rotor has no
/// geometry): its geometry's, or none with a warning saying why.
fn rotor_bounding(
    shapes: &Shapes,
    (link, inertia): (&str, &InertialParams),
    lookup: &Lookup,
    warnings: &mut Vec<String>,
) -> Option<(physid_core::spatial::Ellipsoid, bool)> {
    if shapes.has_no_geometry() && !lookup.opts.ignore_geometry {
        return Some((rotor_bound(inertia), true));
    }
    let bound = shapes.bound(link, lookup, warnings).unwrap_or_else(|w| {
        warnings.push(w);
        None
    });
    bound.map(|e| (e, false))
}

/// A rotor's ellipsoid without geometry: its frame's origin and its centre of mass, enlarged by
/// [`KINEMATIC_MARGIN`], scaled until its own inertia lies inside.
fn rotor_bound(inertia: &InertialParams) -> physid_core::spatial::Ellipsoid {
    let m = inertia.mass();
    let mut points = vec![Vector3::zeros()];
    if m > 0.0 {
        points.push(inertia.h() / m);
    }
    grown_to_hold(points, inertia)
}

/// The description's inertia of each body and rotor against its bounding ellipsoid: outside a
/// sidecar's ellipsoid is an error (the user stated both); outside the ellipsoid of the body's
/// own geometry a warning (the description's inertial tags are often rough, while the
/// geometry bounds where mass can be; identification then holds the estimate to the geometry).
fn check_bounds(
    model: &Model,
    extras: &RobotExtras,
    path: &Path,
    warnings: &mut Vec<String>,
) -> Result<(), IoError> {
    let given = |name: &str| {
        extras
            .ellipsoid
            .iter()
            .any(|e| e.body.as_deref() == Some(name) && e.strict)
    };
    let elements = model.bodies().iter().flat_map(|b| {
        std::iter::once((&b.name, &b.inertia, b.bounding.as_ref())).chain(
            b.rotor
                .as_ref()
                .map(|r| (&r.name, &r.inertia, r.bounding.as_ref())),
        )
    });
    for (name, p, e) in elements {
        let Some(t) = e.and_then(|e| p.consistency(Some(e)).trace_jq_per_mass) else {
            continue;
        };
        if t >= 0.0 || p.mass() == 0.0 {
            continue;
        }
        if given(name) {
            return Err(IoError::invalid(
                path,
                format!("'{name}': the inertia lies outside the sidecar's bounding ellipsoid (tr(JQ)/m = {t:.4})"),
            ));
        }
        warnings.push(format!(
            "'{name}': the description's own inertia is not inside the bounding ellipsoid of its geometry (tr(JQ)/m = {t:.4}); the ellipsoid is kept for identification"
        ));
    }
    Ok(())
}

/// A joint whose subtree (and rotor) has no mass cannot be accelerated.
fn check_subtree_masses(
    bodies: &[Body],
    tiny: &[(String, f64)],
    path: &Path,
) -> Result<(), IoError> {
    let bad = |m: String| IoError::invalid(path, m);
    let n = bodies.len();
    let mut subtree_mass: Vec<f64> = bodies
        .iter()
        .map(|b| b.inertia.mass() + b.rotor.as_ref().map_or(0.0, |r| r.inertia.mass()))
        .collect();
    for i in (0..n).rev() {
        if let Some(p) = bodies[i].parent {
            subtree_mass[p] += subtree_mass[i];
        }
    }
    if let Some(i) = (0..n).find(|&i| subtree_mass[i] <= 0.0) {
        return Err(bad(format!(
            "joint '{}' moves only massless links (no <inertial> or zero mass from link '{}' on): its mass matrix would be singular{}",
            bodies[i].joint_name,
            bodies[i].name,
            tiny_masses_note(tiny).map_or(String::new(), |n| format!(" ({n})"))
        )));
    }
    Ok(())
}

fn pose(x: &Transform) -> urdf_rs::Pose {
    let (rot, pos) = x.to_pose();
    let (r, p, y) = nalgebra::Rotation3::from_matrix_unchecked(rot).euler_angles();
    urdf_rs::Pose {
        xyz: urdf_rs::Vec3([pos.x, pos.y, pos.z]),
        rpy: urdf_rs::Vec3([r, p, y]),
    }
}

fn inertial(p: &InertialParams) -> urdf_rs::Inertial {
    let (c, ic) = match (p.com(), p.inertia_about_com()) {
        (Some(c), Some(ic)) => (c, ic),
        _ => (Vector3::zeros(), p.ibar()),
    };
    urdf_rs::Inertial {
        origin: urdf_rs::Pose {
            xyz: urdf_rs::Vec3([c.x, c.y, c.z]),
            rpy: urdf_rs::Vec3([0.0; 3]),
        },
        mass: urdf_rs::Mass { value: p.mass() },
        inertia: urdf_rs::Inertia {
            ixx: ic[(0, 0)],
            ixy: ic[(0, 1)],
            ixz: ic[(0, 2)],
            iyy: ic[(1, 1)],
            iyz: ic[(1, 2)],
            izz: ic[(2, 2)],
        },
    }
}

fn link(name: &str, p: &InertialParams) -> urdf_rs::Link {
    urdf_rs::Link {
        name: name.into(),
        inertial: inertial(p),
        visual: vec![],
        collision: vec![],
    }
}

/// A rotor's `<mimic>` joint on its body's parent link (`parent_link`), for a body whose own
/// joint is of type `jt`. The rotor's joint moves as the rotor does (a sliding rotor is
/// prismatic); a spinning one is `continuous` only on a `continuous` joint (pinocchio's mimic
/// needs equal configuration sizes: a `continuous` rotor on a `revolute` joint is refused). Its
/// limits are its joint's scaled by the gear ratio.
fn rotor_joint(
    b: &Body,
    r: &Rotor,
    jt: &urdf_rs::JointType,
    parent_link: String,
) -> urdf_rs::Joint {
    let finite_or = |v: f64, d: f64| if v.is_finite() { v } else { d };
    let rotor_type = match (r.joint, jt) {
        (Joint::Prismatic { .. }, _) => urdf_rs::JointType::Prismatic,
        (Joint::Revolute { .. }, urdf_rs::JointType::Continuous) => urdf_rs::JointType::Continuous,
        (Joint::Revolute { .. }, _) => urdf_rs::JointType::Revolute,
    };
    let n = r.gear_ratio;
    let (lo, hi) = (n * b.limits.lower, n * b.limits.upper);
    urdf_rs::Joint {
        name: format!("{}_joint", r.name),
        joint_type: rotor_type,
        limit: urdf_rs::JointLimit {
            lower: finite_or(lo.min(hi), 0.0),
            upper: finite_or(lo.max(hi), 0.0),
            effort: finite_or(b.limits.effort / n.abs(), 0.0),
            velocity: finite_or(b.limits.velocity * n.abs(), 0.0),
            ..Default::default()
        },
        origin: pose(&r.x_rot),
        parent: urdf_rs::LinkName { link: parent_link },
        child: urdf_rs::LinkName {
            link: r.name.clone(),
        },
        axis: urdf_rs::Axis {
            xyz: urdf_rs::Vec3(r.joint.axis().into()),
        },
        calibration: None,
        dynamics: None,
        mimic: Some(urdf_rs::Mimic {
            joint: b.joint_name.clone(),
            multiplier: Some(r.gear_ratio),
            offset: None,
        }),
        safety_controller: None,
    }
}

/// The model as URDF text: one link per body with its inertial, one joint per joint with its
/// limits and friction (`<dynamics damping friction>`), and each rotor as a leaf link on the
/// parent body driven by a `<mimic>` joint with `multiplier = N` (read back by [`from_str`]).
/// The base link is `base`. Numbers are written with full precision.
pub fn to_string(model: &Model) -> String {
    rooted_to_string(model, "base", &InertialParams::zero())
}

/// A floating robot as URDF: its trunk the root link (with the trunk's inertia), the tree
/// below it as [`to_string`] writes it. pinocchio reads it with a free flyer at the root
/// (`buildModel(path, JointModelFreeFlyer())`), and [`floating_from_str`] reads it back.
pub fn floating_to_string(robot: &physid_core::model::floating::FloatingModel) -> String {
    let trunk = robot.trunk();
    rooted_to_string(robot.tree(), &trunk.name, &trunk.inertia)
}

/// `model` as URDF below a root link `root` of inertia `root_inertia`.
fn rooted_to_string(model: &Model, root: &str, root_inertia: &InertialParams) -> String {
    let mut links = vec![link(root, root_inertia)];
    let mut joints = vec![];
    let parent_link =
        |p: Option<usize>| p.map_or(root.to_string(), |p| model.bodies()[p].name.clone());
    let finite_or = |v: f64, d: f64| if v.is_finite() { v } else { d };
    for b in model.bodies() {
        links.push(link(&b.name, &b.inertia));
        let (jt, axis) = match b.joint {
            Joint::Revolute { axis } if b.limits.lower.is_finite() => {
                (urdf_rs::JointType::Revolute, axis)
            }
            Joint::Revolute { axis } => (urdf_rs::JointType::Continuous, axis),
            Joint::Prismatic { axis } => (urdf_rs::JointType::Prismatic, axis),
        };
        joints.push(urdf_rs::Joint {
            name: b.joint_name.clone(),
            joint_type: jt.clone(),
            origin: pose(&b.x_tree),
            parent: urdf_rs::LinkName {
                link: parent_link(b.parent),
            },
            child: urdf_rs::LinkName {
                link: b.name.clone(),
            },
            axis: urdf_rs::Axis {
                xyz: urdf_rs::Vec3([axis.x, axis.y, axis.z]),
            },
            limit: urdf_rs::JointLimit {
                lower: finite_or(b.limits.lower, 0.0),
                upper: finite_or(b.limits.upper, 0.0),
                effort: finite_or(b.limits.effort, 0.0),
                velocity: finite_or(b.limits.velocity, 0.0),
                ..Default::default()
            },
            calibration: None,
            dynamics: Some(urdf_rs::Dynamics {
                damping: b.friction.viscous,
                friction: b.friction.coulomb,
            }),
            mimic: None,
            safety_controller: None,
        });
        if let Some(r) = &b.rotor {
            links.push(link(&r.name, &r.inertia));
            joints.push(rotor_joint(b, r, &jt, parent_link(b.parent)));
        }
    }
    let robot = urdf_rs::Robot {
        name: model.name().to_string(),
        version: None,
        links,
        joints,
        materials: vec![],
    };
    urdf_rs::write_to_string(&robot).expect("serializing a URDF built in memory cannot fail")
}
