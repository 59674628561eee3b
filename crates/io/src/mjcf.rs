//! MJCF export for MuJoCo cross-checks.
//!
//! MuJoCo has no geared rotor body, so each rotor is exported as physid's
//! [`RotorModel::Reflected`](physid_core::model::RotorModel::Reflected): the rotor's inertia is lumped
//! into its parent body (frozen at zero rotor angle) and its spin inertia becomes the joint's
//! `armature = N² I_axis`; a rotor on the fixed base (the leg's ab/ad rotor) is a static body
//! welded to the world, so the file's total mass is the model's. MuJoCo's `mj_inverse` on this
//! file, with damping and friction loss zeroed, equals physid's RNEA in reflected mode. What it
//! cannot carry: the rotors' gyroscopic coupling (physid's full model), Coulomb friction as
//! physid models it (`frictionloss` is MuJoCo's dry-friction constraint, not `B_c sign(q̇)`),
//! and bounding ellipsoids as constraints (they are drawn as group-3 geoms).
//!
//! Written: inertias (explicit, `inertiafromgeom="false"`, in principal axes; moments at least
//! 1e-14 kg m², a moment beyond the sum of the others by rounding brought 1e-12 inside it, a
//! massless moving body given 1e-12 kg: MuJoCo refuses each as written), joints with `armature`,
//! `damping` (viscous), `frictionloss` (Coulomb), `range` and `actuatorfrcrange` where finite,
//! the description's shapes as visual geoms (group 1, no contacts, so `mj_inverse` never sees a
//! contact force; STL and OBJ meshes by absolute path, other mesh formats and shapes of zero
//! size left out).

use nalgebra::{Rotation3, UnitQuaternion, Vector3};
use physid_core::linalg::principal_axes;
use physid_core::model::{Joint, Model, Rotor, Shape, ShapeKind};
use physid_core::spatial::{Ellipsoid, InertialParams, Transform};
use std::fmt::Write;

fn v3(v: &Vector3<f64>) -> String {
    format!("{} {} {}", v.x, v.y, v.z)
}

/// Each body's inertia with the rotors mounted on it lumped in (body frame).
pub fn lumped_inertias(model: &Model) -> Vec<InertialParams> {
    let mut out: Vec<InertialParams> = model.bodies().iter().map(|b| b.inertia).collect();
    for b in model.bodies() {
        if let (Some(p), Some(r)) = (b.parent, &b.rotor) {
            out[p] = InertialParams(out[p].0 + r.inertia.transformed(&r.x_rot.inverse()).0);
        }
    }
    out
}

/// A rotation as the MJCF `quat` attribute.
fn quat_attr(r: &Rotation3<f64>) -> String {
    let q = UnitQuaternion::from_rotation_matrix(r);
    format!("quat=\"{} {} {} {}\"", q.w, q.i, q.j, q.k)
}

/// A pose as MJCF `pos` and `quat` attributes.
fn pose_attrs(x: &Transform) -> String {
    let (rot, pos) = x.to_pose();
    format!(
        "pos=\"{}\" {}",
        v3(&pos),
        quat_attr(&Rotation3::from_matrix_unchecked(rot))
    )
}

/// An `<inertial>` element, in principal axes (`quat`, `diaginertia`): MuJoCo stores it so,
/// and a `fullinertia` it would decompose itself, with an eigensolver that turns a thin rod's
/// zero moment (1e-9 of the others) negative and refuses the body.
fn inertial(p: &InertialParams) -> String {
    let c = p.com().unwrap_or_default();
    let (axes, moments) = principal_for_mujoco(&p.inertia_about_com().unwrap_or_default());
    format!(
        "<inertial pos=\"{}\" {} mass=\"{}\" diaginertia=\"{}\"/>",
        v3(&c),
        quat_attr(&axes),
        p.mass().max(MASS_FLOOR),
        v3(&moments)
    )
}

/// The smallest mass written (kg): MuJoCo refuses a moving body of no mass, which physid
/// allows where the body carries others (a massless link between two joints: Fetch's base).
const MASS_FLOOR: f64 = 1e-12;

/// Relative room left below the triangle inequality by [`principal_for_mujoco`].
const TRIANGLE_ROOM: f64 = 1e-12;

/// The smallest principal moment written (kg m²): MuJoCo refuses moments below 1e-15, which a
/// point mass (URDFs' `<inertia>` of zeros under a mass) has; 1e-14 kg m² is a gram at 3 µm.
const MOMENT_FLOOR: f64 = 1e-14;

/// The principal axes (a proper rotation, body frame) and moments (kg m²) of the rotational
/// inertia `ic` about the CoM, as MuJoCo takes them: moments at least [`MOMENT_FLOOR`], and
/// any that exceeds the sum of the other two by rounding (a flat plate's `A + B = C` written
/// in decimals: 8.53e-7 + 8.53e-7 against 1.70666666667e-6 in ROBOTIS OP2's URDF) brought to
/// `(1 − 10⁻¹²)` times that sum. MuJoCo refuses any excess, and physid has read the body as
/// consistent, so the excess is below `10⁻¹²` of its pseudo-inertia.
fn principal_for_mujoco(ic: &nalgebra::Matrix3<f64>) -> (Rotation3<f64>, Vector3<f64>) {
    let (axes, moments) = principal_axes(ic);
    let mut moments = moments.map(|m| m.max(MOMENT_FLOOR));
    let total = moments.sum();
    for k in 0..3 {
        let limit = (total - moments[k]) * (1.0 - TRIANGLE_ROOM);
        moments[k] = moments[k].min(limit);
    }
    (axes, moments)
}

/// Whether MuJoCo reads this mesh file (STL, OBJ).
fn mujoco_reads(path: &std::path::Path) -> bool {
    let ext = path.extension().map(|e| e.to_string_lossy().to_lowercase());
    matches!(ext.as_deref(), Some("stl" | "obj"))
}

/// Every body's shapes by the name their geoms take (`world` for the static base's).
fn named_shapes(model: &Model) -> Vec<(&str, &[Shape])> {
    std::iter::once(("world", model.base_shapes()))
        .chain(
            model
                .bodies()
                .iter()
                .map(|b| (b.name.as_str(), &b.shapes[..])),
        )
        .collect()
}

/// The description's meshes an MJCF cannot carry (a format MuJoCo does not read), by body, for
/// a warning: the export shows those bodies without them.
pub fn unwritten(model: &Model) -> Vec<String> {
    named_shapes(model)
        .into_iter()
        .flat_map(|(body, shapes)| {
            shapes.iter().filter_map(move |sh| match &sh.kind {
                ShapeKind::Mesh { path, .. } if !mujoco_reads(path) => {
                    Some(format!("{body}: {}", path.display()))
                }
                _ => None,
            })
        })
        .collect()
}

/// Mesh files MuJoCo reads: asset name → file, scale.
fn mesh_assets(model: &Model) -> Vec<(String, String, [f64; 3])> {
    let mut out = vec![];
    for (body, shapes) in named_shapes(model) {
        for (k, sh) in shapes.iter().enumerate() {
            if let ShapeKind::Mesh { path, scale } = &sh.kind {
                if mujoco_reads(path) {
                    let file = std::fs::canonicalize(path).unwrap_or(path.clone());
                    out.push((
                        format!("{body}_mesh{k}"),
                        file.display().to_string(),
                        *scale,
                    ));
                }
            }
        }
    }
    out
}

/// The `<geom>` of a shape: visual only (`contype = conaffinity = 0`, group 1), so that
/// contacts never enter `mj_inverse`; `None` for a mesh MuJoCo cannot read and for a shape
/// with a size of zero (URDFs' placeholder `<box size="0 0 0"/>`), which MuJoCo refuses.
fn shape_geom(body: &str, k: usize, sh: &Shape) -> Option<String> {
    let (kind, size) = match &sh.kind {
        ShapeKind::Box { size } => ("box", vec![size[0] / 2.0, size[1] / 2.0, size[2] / 2.0]),
        ShapeKind::Cylinder { radius, length } => ("cylinder", vec![*radius, length / 2.0]),
        ShapeKind::Capsule { radius, length } => ("capsule", vec![*radius, length / 2.0]),
        ShapeKind::Sphere { radius } => ("sphere", vec![*radius]),
        ShapeKind::Mesh { path, .. } => {
            if !mujoco_reads(path) {
                return None;
            }
            return Some(format!(
                "<geom type=\"mesh\" mesh=\"{body}_mesh{k}\" {} contype=\"0\" conaffinity=\"0\" group=\"1\"/>",
                pose_attrs(&sh.pose)
            ));
        }
    };
    if !size.iter().all(|s| s.is_finite() && *s > 0.0) {
        return None;
    }
    let size: Vec<String> = size.iter().map(f64::to_string).collect();
    Some(format!(
        "<geom type=\"{kind}\" size=\"{}\" {} contype=\"0\" conaffinity=\"0\" group=\"1\"/>",
        size.join(" "),
        pose_attrs(&sh.pose)
    ))
}

/// The bounding ellipsoid as a geom (group 3, visual only).
fn ellipsoid_geom(e: &Ellipsoid) -> String {
    let (r, eigenvalues) = principal_axes(&e.qs);
    let a = eigenvalues.map(|l| l.max(0.0).sqrt());
    format!(
        "<geom type=\"ellipsoid\" size=\"{}\" pos=\"{}\" {} contype=\"0\" conaffinity=\"0\" group=\"3\" rgba=\"0.2 0.6 1 0.15\"/>",
        v3(&a),
        v3(&e.center),
        quat_attr(&r)
    )
}

/// A joint with its armature, friction and limits.
fn joint(b: &physid_core::model::Body) -> String {
    let (kind, axis) = match b.joint {
        Joint::Revolute { axis } => ("hinge", axis),
        Joint::Prismatic { axis } => ("slide", axis),
    };
    let l = &b.limits;
    let range = if l.lower.is_finite() && l.upper.is_finite() {
        format!(" limited=\"true\" range=\"{} {}\"", l.lower, l.upper)
    } else {
        " limited=\"false\"".into()
    };
    let effort = if l.effort.is_finite() {
        format!(
            " actuatorfrclimited=\"true\" actuatorfrcrange=\"{} {}\"",
            -l.effort, l.effort
        )
    } else {
        String::new()
    };
    format!(
        "<joint name=\"{}\" type=\"{kind}\" axis=\"{}\" armature=\"{}\" damping=\"{}\" frictionloss=\"{}\"{range}{effort}/>",
        b.joint_name,
        v3(&axis),
        b.rotor.as_ref().map_or(0.0, Rotor::armature),
        b.friction.viscous,
        b.friction.coulomb
    )
}

fn body(model: &Model, inertias: &[InertialParams], i: usize, depth: usize, s: &mut String) {
    let b = &model.bodies()[i];
    let pad = "  ".repeat(depth + 2);
    let _ = writeln!(
        s,
        "{pad}<body name=\"{}\" {}>",
        b.name,
        pose_attrs(&b.x_tree)
    );
    let _ = writeln!(s, "{pad}  {}", inertial(&inertias[i]));
    let _ = writeln!(s, "{pad}  {}", joint(b));
    for (k, sh) in b.shapes.iter().enumerate() {
        if let Some(g) = shape_geom(&b.name, k, sh) {
            let _ = writeln!(s, "{pad}  {g}");
        }
    }
    if let Some(e) = &b.bounding {
        let _ = writeln!(s, "{pad}  {}", ellipsoid_geom(e));
    }
    for c in (0..model.dof()).filter(|&c| model.bodies()[c].parent == Some(i)) {
        body(model, inertias, c, depth + 1, s);
    }
    let _ = writeln!(s, "{pad}</body>");
}

/// The model as MJCF text (see the module docs).
pub fn to_string(model: &Model) -> String {
    let inertias = lumped_inertias(model);
    let mut s = header(model);
    let _ = writeln!(s, "  <worldbody>");
    for (k, sh) in model.base_shapes().iter().enumerate() {
        if let Some(g) = shape_geom("world", k, sh) {
            let _ = writeln!(s, "    {g}");
        }
    }
    // Rotors on the fixed base: static bodies welded to the world, so that the model's mass
    // is complete; their spin inertia acts through their joint's armature.
    for b in model.bodies().iter().filter(|b| b.parent.is_none()) {
        if let Some(r) = &b.rotor {
            let _ = writeln!(s, "    <body name=\"{}\" {}>", r.name, pose_attrs(&r.x_rot));
            let _ = writeln!(s, "      {}", inertial(&r.inertia));
            let _ = writeln!(s, "    </body>");
        }
    }
    for i in (0..model.dof()).filter(|&i| model.bodies()[i].parent.is_none()) {
        body(model, &inertias, i, 0, &mut s);
    }
    let _ = writeln!(s, "  </worldbody>");
    let _ = writeln!(s, "</mujoco>");
    s
}

/// A floating robot as MJCF: the trunk a body with a `<freejoint>` (at the world origin, axes
/// aligned), its inertia with the rotors mounted on it lumped in, the tree's shapes on it and
/// the tree below as [`to_string`] writes it. MuJoCo's free joint orders its velocity as the
/// trunk origin's linear velocity in world coordinates, then the angular velocity in the trunk
/// frame; physid's `v_B = [ω; v]` is in the trunk frame throughout.
pub fn floating_to_string(robot: &physid_core::model::floating::FloatingModel) -> String {
    let model = robot.tree();
    let inertias = lumped_inertias(model);
    let mut trunk = robot.trunk().inertia;
    for b in model.bodies().iter().filter(|b| b.parent.is_none()) {
        if let Some(r) = &b.rotor {
            trunk = InertialParams(trunk.0 + r.inertia.transformed(&r.x_rot.inverse()).0);
        }
    }
    let name = &robot.trunk().name;
    let mut s = header(model);
    let _ = writeln!(s, "  <worldbody>");
    let _ = writeln!(s, "    <body name=\"{name}\" pos=\"0 0 0\">");
    let _ = writeln!(s, "      <freejoint name=\"{name}_free\"/>");
    let _ = writeln!(s, "      {}", inertial(&trunk));
    for (k, sh) in model.base_shapes().iter().enumerate() {
        if let Some(g) = shape_geom(name, k, sh) {
            let _ = writeln!(s, "      {g}");
        }
    }
    if let Some(e) = &robot.trunk().bounding {
        let _ = writeln!(s, "      {}", ellipsoid_geom(e));
    }
    for i in (0..model.dof()).filter(|&i| model.bodies()[i].parent.is_none()) {
        body(model, &inertias, i, 1, &mut s);
    }
    let _ = writeln!(s, "    </body>");
    let _ = writeln!(s, "  </worldbody>");
    let _ = writeln!(s, "</mujoco>");
    s
}

/// The file's opening: the model's name, the compiler, gravity and the mesh assets.
fn header(model: &Model) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "<mujoco model=\"{}\">", model.name());
    let _ = writeln!(
        s,
        "  <compiler angle=\"radian\" inertiafromgeom=\"false\"/>"
    );
    let _ = writeln!(
        s,
        "  <option gravity=\"{}\" timestep=\"0.001\" integrator=\"RK4\"/>",
        v3(&model.gravity())
    );
    let meshes = mesh_assets(model);
    if !meshes.is_empty() {
        let _ = writeln!(s, "  <asset>");
        for (name, file, sc) in &meshes {
            let _ = writeln!(
                s,
                "    <mesh name=\"{name}\" file=\"{file}\" scale=\"{} {} {}\"/>",
                sc[0], sc[1], sc[2]
            );
        }
        let _ = writeln!(s, "  </asset>");
    }
    s
}
