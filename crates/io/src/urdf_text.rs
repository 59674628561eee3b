//! The URDF text urdf-rs is given: the user's file with what physid does not read and urdf-rs
//! would refuse taken out, and what URDF leaves optional filled in with its meaning.
//!
//! - Every `<material>` goes (colours and textures: physid never reads them, and urdf-rs
//!   refuses a `<visual>` with two, which xacro output has).
//! - A `fixed` joint's `<axis>` goes: no reader uses it (urdfdom does not read it), so a
//!   malformed one (`<axis xzy="0 0 1"/>`) does not stop the robot from loading.
//! - A moving joint's `<axis>` without `xyz` is an error naming the joint: urdf-rs would say
//!   only "missing field `xyz`", and urdfdom would give it a zero axis.
//! - A `<limit>` without `velocity` gets `velocity="0"`, URDF's "not given" (physid reads 0 as
//!   unknown, as it does a missing `effort`); urdf-rs requires the attribute.
//! - Where a joint repeats an element URDF allows once (`<origin>`, `<axis>`, `<limit>`,
//!   `<dynamics>`, `<mimic>`), the first is kept, as urdfdom (and so pinocchio and ROS) reads
//!   it, with a warning.
//!
//! Elements are found in the parsed document, never by searching the text: a Gazebo plugin's
//! `<jointName>` is not a `<joint>`. Only these elements change; the file on disk is never
//! touched.

use super::IoError;
use std::ops::Range;
use std::path::Path;

/// The elements a joint has at most once.
const ONCE_PER_JOINT: [&str; 5] = ["origin", "axis", "limit", "dynamics", "mimic"];

/// `xml` with the edits of the module docs and the warnings for repeated elements, or the
/// error naming a moving joint whose axis has no direction. `doc` is `xml` parsed.
pub(crate) fn readable(
    xml: &str,
    doc: &roxmltree::Document,
    path: &Path,
) -> Result<(String, Vec<String>), IoError> {
    let (mut edits, warnings) = repeated_in_joints(doc);
    let materials = doc.descendants().filter(|n| n.has_tag_name("material"));
    edits.extend(materials.map(|m| (m.range(), "")));
    for joint in top_level_joints(doc) {
        let fixed = joint.attribute("type") == Some("fixed");
        for node in joint.children() {
            if node.has_tag_name("axis") && fixed {
                edits.push((node.range(), ""));
            } else if node.has_tag_name("axis") && node.attribute("xyz").is_none() {
                return Err(IoError::invalid(path, axis_without_xyz(&joint, &node)));
            } else if node.has_tag_name("limit") && node.attribute("velocity").is_none() {
                let at = node.range().start + "<limit".len();
                edits.push((at..at, " velocity=\"0\""));
            }
        }
    }
    Ok((apply(xml, edits), warnings))
}

/// The robot's own `<joint>` elements, children of `<robot>` (not a `<transmission>`'s
/// `<joint>` or a plugin's `<jointName>`).
pub(crate) fn top_level_joints<'a, 'input>(
    doc: &'a roxmltree::Document<'input>,
) -> impl Iterator<Item = roxmltree::Node<'a, 'input>> {
    doc.root_element()
        .children()
        .filter(|n| n.has_tag_name("joint"))
}

/// The removal of every repeat of an element a top-level joint has once, and a warning per
/// joint and element.
fn repeated_in_joints<'d>(
    doc: &roxmltree::Document,
) -> (Vec<(Range<usize>, &'d str)>, Vec<String>) {
    let (mut edits, mut warnings) = (vec![], vec![]);
    for joint in top_level_joints(doc) {
        for tag in ONCE_PER_JOINT {
            let repeats: Vec<_> = joint
                .children()
                .filter(|c| c.has_tag_name(tag))
                .skip(1)
                .collect();
            if repeats.is_empty() {
                continue;
            }
            warnings.push(format!(
                "joint '{}' has more than one <{tag}>; the first is used",
                joint.attribute("name").unwrap_or("?")
            ));
            edits.extend(repeats.iter().map(|r| (r.range(), "")));
        }
    }
    (edits, warnings)
}

/// The error for a moving joint's `<axis>` that gives no `xyz`, naming what it does give.
fn axis_without_xyz(joint: &roxmltree::Node, axis: &roxmltree::Node) -> String {
    let given: Vec<String> = axis
        .attributes()
        .map(|a| format!("{}=\"{}\"", a.name(), a.value()))
        .collect();
    format!(
        "joint '{}' ({}): its <axis> has no xyz attribute (it gives {}): write the axis as <axis xyz=\"x y z\"/>",
        joint.attribute("name").unwrap_or("?"),
        joint.attribute("type").unwrap_or("no type"),
        if given.is_empty() {
            "none".to_string()
        } else {
            given.join(" ")
        }
    )
}

/// `xml` with each range replaced by its text; the ranges do not overlap, except that a range
/// inside one that is removed goes with it.
fn apply(xml: &str, mut edits: Vec<(Range<usize>, &str)>) -> String {
    edits.sort_by_key(|(r, _)| (r.start, std::cmp::Reverse(r.end)));
    let mut out = String::with_capacity(xml.len() + 16 * edits.len());
    let mut at = 0;
    for (range, text) in edits {
        if range.start < at {
            continue; // inside an element already removed
        }
        out.push_str(&xml[at..range.start]);
        out.push_str(text);
        at = range.end;
    }
    out.push_str(&xml[at..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn readable_of(xml: &str) -> Result<String, String> {
        let doc = roxmltree::Document::parse(xml).expect("XML");
        readable(xml, &doc, Path::new("r.urdf"))
            .map(|(text, _)| text)
            .map_err(|e| e.to_string())
    }

    #[test]
    fn materials_and_fixed_axes_go_and_a_missing_velocity_is_not_given() {
        let xml = r#"<robot name="r">
  <material name="red"><color rgba="1 0 0 1"/></material>
  <link name="a"><visual><geometry><box size="1 1 1"/></geometry><material name=""/><material name="red"/></visual></link>
  <joint name="f" type="fixed"><parent link="a"/><child link="b"/><axis xzy="0 0 1"/></joint>
  <joint name="m" type="revolute"><axis xyz="0 0 1"/><limit lower="-1" upper="1"/></joint>
  <gazebo reference="a"><material>Gazebo/Black</material></gazebo>
</robot>"#;
        let out = readable_of(xml).unwrap();
        assert!(!out.contains("material"), "{out}");
        assert!(!out.contains("xzy"), "{out}");
        assert!(out.contains(r#"<axis xyz="0 0 1"/>"#), "{out}");
        assert!(
            out.contains(r#"<limit velocity="0" lower="-1" upper="1"/>"#),
            "{out}"
        );
        assert!(out.contains(r#"<box size="1 1 1"/>"#), "{out}");
        roxmltree::Document::parse(&out).expect("still XML");
    }

    #[test]
    fn a_moving_joint_whose_axis_has_no_xyz_is_named() {
        let xml = r#"<robot name="r"><joint name="elbow" type="revolute"><axis xzy="0 0 1"/></joint></robot>"#;
        let err = readable_of(xml).unwrap_err();
        assert!(
            err.contains("joint 'elbow' (revolute)") && err.contains(r#"xzy="0 0 1""#),
            "{err}"
        );
        let bare =
            r#"<robot name="r"><joint name="slide" type="prismatic"><axis/></joint></robot>"#;
        assert!(readable_of(bare).unwrap_err().contains("it gives none"));
    }

    #[test]
    fn a_joints_repeated_elements_go_but_a_plugins_joint_name_is_no_joint() {
        // A Gazebo plugin's <jointName> (Kinova's URDFs) or a transmission's self-closing
        // <joint/> (Drake's Allegro hand) between two joints: searched as text, "<joint"
        // matched them and the next joint lost its <origin> to a link's.
        let xml = r#"<robot name="r">
  <joint name="a" type="revolute"><origin xyz="1 0 0"/><origin xyz="2 0 0"/><axis xyz="0 0 1"/><axis xyz="1 0 0"/></joint>
  <gazebo><plugin name="ft"><jointName>a</jointName></plugin></gazebo>
  <transmission name="t"><actuator name="m"/><joint name="a"/></transmission>
  <link name="l"><inertial><origin xyz="0 -0.2 0"/><mass value="1"/></inertial></link>
  <joint name="b" type="revolute"><origin xyz="0 0 3"/><axis xyz="0 0 1"/></joint>
</robot>"#;
        let doc = roxmltree::Document::parse(xml).unwrap();
        let (out, warnings) = readable(xml, &doc, Path::new("r.urdf")).unwrap();
        assert!(
            !out.contains(r#"<origin xyz="2 0 0"/>"#) && !out.contains(r#"<axis xyz="1 0 0"/>"#)
        );
        assert!(out.contains(r#"<origin xyz="1 0 0"/>"#), "{out}");
        assert!(
            out.contains(r#"<origin xyz="0 -0.2 0"/>"#) && out.contains(r#"<origin xyz="0 0 3"/>"#)
        );
        assert_eq!(
            warnings,
            [
                "joint 'a' has more than one <origin>; the first is used",
                "joint 'a' has more than one <axis>; the first is used"
            ]
        );
    }

    #[test]
    fn a_text_without_edits_is_given_back_unchanged() {
        let xml = r#"<robot name="r"><link name="a"/><joint name="m" type="continuous"><axis xyz="1 0 0"/><limit effort="1" velocity="2"/></joint></robot>"#;
        assert_eq!(readable_of(xml).unwrap(), xml);
    }
}
