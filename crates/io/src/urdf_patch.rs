//! Writing an identified model into the user's own URDF: only `<inertial>` and `<dynamics>`
//! change, every other byte of the file stays as it was (meshes, collision and visual
//! geometry, frame names, transmissions, comments, formatting).
//!
//! - Each body's link gets the identified `<inertial>` (mass, CoM, inertia about the CoM in the
//!   link frame). physid merges links fixed to a body into it, and identifies the merged body:
//!   so the identified inertia goes on the body's own link and the `<inertial>` of every link
//!   fixed to it is replaced by a comment saying where it went (loading the patched file merges
//!   nothing twice).
//! - A rotor written as a mimic joint's link gets its identified `<inertial>`.
//! - Each moving joint's `<dynamics damping friction>` becomes the identified viscous and
//!   Coulomb coefficients, inserted before `</joint>` if the joint had none.
//!
//! Elements are found with roxmltree, which gives each element's byte range in the text, and
//! replaced from the end of the file backwards so earlier ranges stay valid.

use super::IoError;
use nalgebra::Vector3;
use physid_core::model::Model;
use physid_core::spatial::InertialParams;
use std::ops::Range;
use std::path::Path;

/// A number for XML or TOML, exact (shortest round-trip form): plain for ordinary magnitudes,
/// scientific below 1e-4 or from 1e6 on.
fn num(x: f64) -> String {
    if x == 0.0 || (1e-4..1e6).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// The `<inertial>` element of `p` (link frame), indented for a child of `<link>` at `indent`.
fn inertial_xml(p: &InertialParams, indent: &str) -> String {
    let (c, ic) = match (p.com(), p.inertia_about_com()) {
        (Some(c), Some(ic)) => (c, ic),
        _ => (Vector3::zeros(), p.ibar()),
    };
    format!(
        "<inertial>\n{indent}  <origin xyz=\"{} {} {}\" rpy=\"0 0 0\"/>\n{indent}  <mass value=\"{}\"/>\n{indent}  <inertia ixx=\"{}\" ixy=\"{}\" ixz=\"{}\" iyy=\"{}\" iyz=\"{}\" izz=\"{}\"/>\n{indent}</inertial>",
        num(c.x), num(c.y), num(c.z), num(p.mass()),
        num(ic[(0, 0)]), num(ic[(0, 1)]), num(ic[(0, 2)]), num(ic[(1, 1)]), num(ic[(1, 2)]), num(ic[(2, 2)])
    )
}

/// The whitespace before the element starting at `start` on its line.
fn indent_at(xml: &str, start: usize) -> &str {
    let line_start = xml[..start].rfind('\n').map_or(0, |i| i + 1);
    let lead = &xml[line_start..start];
    if lead.chars().all(char::is_whitespace) {
        lead
    } else {
        ""
    }
}

/// What to write where: a byte range of the original text and its replacement.
type Edit = (Range<usize>, String);

/// The edits for one `<link>`: its first `<inertial>` replaced (or inserted) by `new`, or
/// turned into `comment` when `new` is `None`.
fn link_edit(
    xml: &str,
    link: roxmltree::Node,
    new: Option<&InertialParams>,
    comment: &str,
) -> Option<Edit> {
    let inertial = link.children().find(|c| c.has_tag_name("inertial"));
    match (inertial, new) {
        (Some(el), Some(p)) => Some((
            el.range(),
            inertial_xml(p, indent_at(xml, el.range().start)),
        )),
        (Some(el), None) => Some((el.range(), format!("<!-- {comment} -->"))),
        (None, Some(p)) => {
            let close = xml[link.range()]
                .rfind("</link>")
                .map(|i| link.range().start + i)?;
            let outer = indent_at(xml, link.range().start);
            let inner = format!("{outer}  ");
            Some((
                close..close,
                format!("  {}\n{outer}", inertial_xml(p, &inner)),
            ))
        }
        (None, None) => None,
    }
}

/// The edits for one `<joint>`'s `<dynamics>`: an existing element keeps every other attribute
/// (a simulator's `K`, `D`, `mu_coulomb`, …) byte for byte, only the values of `damping` and
/// `friction` replaced (or those attributes added); a joint without one gets a new element.
fn dynamics_edits(xml: &str, joint: roxmltree::Node, damping: f64, friction: f64) -> Vec<Edit> {
    let values = [("damping", num(damping)), ("friction", num(friction))];
    if let Some(el) = joint.children().find(|c| c.has_tag_name("dynamics")) {
        let after_name = el.range().start + "<dynamics".len();
        let mut edits = vec![];
        let mut added = String::new();
        for (name, value) in values {
            match el.attributes().find(|a| a.name() == name) {
                Some(attr) => edits.push((attr.range_value(), value)),
                None => added += &format!(" {name}=\"{value}\""),
            }
        }
        if !added.is_empty() {
            edits.push((after_name..after_name, added));
        }
        return edits;
    }
    let tag = format!(
        "<dynamics damping=\"{}\" friction=\"{}\"/>",
        values[0].1, values[1].1
    );
    let Some(close) = xml[joint.range()]
        .rfind("</joint>")
        .map(|i| joint.range().start + i)
    else {
        return vec![];
    };
    let outer = indent_at(xml, joint.range().start);
    vec![(close..close, format!("  {tag}\n{outer}"))]
}

/// `xml` (the URDF `model` was loaded from, at `path`) with `identified`'s inertial parameters
/// and friction written in (see the module docs). `identified` must have `model`'s structure.
pub fn patch(xml: &str, path: &Path, model: &Model, identified: &Model) -> Result<String, IoError> {
    let bad = |m: String| IoError::invalid(path, m);
    let doc = roxmltree::Document::parse(xml).map_err(|e| IoError::Parse {
        path: path.to_path_buf(),
        message: format!("not valid XML: {e}"),
    })?;
    let root = doc.root_element();
    let named = |tag: &str, name: &str| {
        root.children()
            .find(|n| n.has_tag_name(tag) && n.attribute("name") == Some(name))
    };
    let mut edits: Vec<Edit> = vec![];
    for (b, bi) in model.bodies().iter().zip(identified.bodies()) {
        let link =
            named("link", &b.name).ok_or_else(|| bad(format!("no <link name=\"{}\">", b.name)))?;
        edits.extend(link_edit(xml, link, Some(&bi.inertia), ""));
        let joint = named("joint", &b.joint_name)
            .ok_or_else(|| bad(format!("no <joint name=\"{}\">", b.joint_name)))?;
        edits.extend(dynamics_edits(
            xml,
            joint,
            bi.friction.viscous,
            bi.friction.coulomb,
        ));
        if let (Some(r), Some(ri)) = (&b.rotor, &bi.rotor) {
            if let Some(link) = named("link", &r.name) {
                edits.extend(link_edit(xml, link, Some(&ri.inertia), ""));
            }
        }
        for fixed in fixed_descendants(root, &b.name) {
            let note = format!("inertial merged into link '{}' by physid identify", b.name);
            edits.extend(link_edit(xml, fixed, None, &note));
        }
    }
    edits.sort_by_key(|(r, _)| std::cmp::Reverse(r.start));
    let mut out = xml.to_string();
    for (range, text) in edits {
        out.replace_range(range, &text);
    }
    Ok(out)
}

/// The links attached to `link` through chains of fixed joints.
fn fixed_descendants<'a, 'i>(
    root: roxmltree::Node<'a, 'i>,
    link: &str,
) -> Vec<roxmltree::Node<'a, 'i>> {
    let mut out = vec![];
    let mut stack = vec![link.to_string()];
    while let Some(parent) = stack.pop() {
        for j in root.children().filter(|n| n.has_tag_name("joint")) {
            let child_of = |tag: &str| {
                j.children()
                    .find(|c| c.has_tag_name(tag))
                    .and_then(|c| c.attribute("link"))
            };
            if j.attribute("type") == Some("fixed") && child_of("parent") == Some(parent.as_str()) {
                if let Some(child) = child_of("child") {
                    if let Some(l) = root
                        .children()
                        .find(|n| n.has_tag_name("link") && n.attribute("name") == Some(child))
                    {
                        out.push(l);
                    }
                    stack.push(child.to_string());
                }
            }
        }
    }
    out
}

/// An ellipsoid as a sidecar `[[robot.ellipsoid]]` entry: centre, semi-axes and the
/// roll-pitch-yaw of its principal axes.
pub(crate) fn ellipsoid_toml(
    name: &str,
    e: &physid_core::spatial::Ellipsoid,
    p: &InertialParams,
) -> String {
    let (r, eigenvalues) = physid_core::linalg::principal_axes(&e.qs);
    let (roll, pitch, yaw) = r.euler_angles();
    let a = eigenvalues.map(|l| l.max(0.0).sqrt());
    let c = e.center;
    // A model identified under a looser set may lie outside: it still loads, with a warning.
    let inside = p
        .consistency(Some(e))
        .trace_jq_per_mass
        .is_none_or(|t| t >= 0.0);
    let strict = if inside {
        ""
    } else {
        "strict = false   # the identified inertia lies outside (identified without the ellipsoid set)\n"
    };
    format!(
        "[[robot.ellipsoid]]\nbody = \"{name}\"\ncenter = [{}, {}, {}]\nsemi_axes = [{}, {}, {}]\nrpy = [{}, {}, {}]\n{strict}",
        num(c.x), num(c.y), num(c.z), num(a.x), num(a.y), num(a.z), num(roll), num(pitch), num(yaw)
    )
}

/// A rotor that the URDF does not carry, as a sidecar `[[robot.rotor]]` (origin relative to its
/// parent body's link, inertial as the paper's ten parameters).
fn rotor_toml(joint: &str, r: &physid_core::model::Rotor) -> String {
    let (rot, pos) = r.x_rot.to_pose();
    let (roll, pitch, yaw) = nalgebra::Rotation3::from_matrix_unchecked(rot).euler_angles();
    let pi: Vec<String> = r.inertia.0.iter().map(|x| num(*x)).collect();
    let a = r.joint.axis();
    let kind = match r.joint {
        physid_core::model::Joint::Revolute { .. } => "",
        physid_core::model::Joint::Prismatic { .. } => "type = \"prismatic\"\n",
    };
    format!(
        "[[robot.rotor]]\njoint = \"{joint}\"\nname = \"{}\"\n{kind}gear_ratio = {}\naxis = [{}, {}, {}]\norigin = {{ xyz = [{}, {}, {}], rpy = [{roll}, {pitch}, {yaw}] }}\ninertial = {{ pi = [{}] }}\n",
        r.name, r.gear_ratio, a.x, a.y, a.z, pos.x, pos.y, pos.z, pi.join(", ")
    )
}

/// The sidecar of an exported URDF: a physid robot file (`--robot` takes it) with what URDF
/// cannot carry: the bounding ellipsoids (the exact ones the identification used, so
/// `geometry_ellipsoids = false`), the rotor model and gravity, rotors the URDF does not hold
/// (`urdf_rotors` names those it does, as mimic links), and `extra` tables appended as given
/// (identify's effects as scenario `[[effects]]` tables and its `[information]`; the robot
/// loader ignores them).
pub fn sidecar(
    model: &Model,
    urdf_file: &str,
    urdf_rotors: &[String],
    extra: Option<&str>,
) -> String {
    let g = model.gravity();
    let rotor_model = match model.rotor_model() {
        physid_core::model::RotorModel::Full => "full",
        physid_core::model::RotorModel::Reflected => "reflected",
    };
    let mut s = format!(
        "# physid sidecar of {urdf_file}: what URDF cannot carry. Use it as --robot <this file>.\n[robot]\nurdf = \"{urdf_file}\"\ngeometry_ellipsoids = false\nrotor_model = \"{rotor_model}\"\ngravity = [{}, {}, {}]\n",
        g.x, g.y, g.z
    );
    for b in model.bodies() {
        if let Some(r) = b.rotor.as_ref().filter(|r| !urdf_rotors.contains(&r.name)) {
            s.push('\n');
            s.push_str(&rotor_toml(&b.joint_name, r));
        }
    }
    for b in model.bodies() {
        if let Some(e) = &b.bounding {
            s.push('\n');
            s.push_str(&ellipsoid_toml(&b.name, e, &b.inertia));
        }
        if let Some((r, e)) = b
            .rotor
            .as_ref()
            .and_then(|r| r.bounding.as_ref().map(|e| (r, e)))
        {
            s.push('\n');
            s.push_str(&ellipsoid_toml(&r.name, e, &r.inertia));
        }
    }
    if let Some(fx) = extra {
        s.push_str(fx);
    }
    s
}

/// The names of the links of `xml` that are children of mimic joints (rotors the URDF holds).
pub fn mimic_links(xml: &str) -> Vec<String> {
    let Ok(doc) = roxmltree::Document::parse(xml) else {
        return vec![];
    };
    doc.root_element()
        .children()
        .filter(|j| j.has_tag_name("joint") && j.children().any(|c| c.has_tag_name("mimic")))
        .filter_map(|j| {
            j.children()
                .find(|c| c.has_tag_name("child"))
                .and_then(|c| c.attribute("link"))
                .map(str::to_string)
        })
        .collect()
}
