//! The built-in Cheetah-3-like leg (architecture.md §4): three links (ab/ad, hip/thigh, knee/shank)
//! and three rotors behind 10.6:1 gearboxes, fixed base.
//!
//! Geometry and mass properties follow the open MIT Cheetah-Software `Cheetah3.h` (values about
//! each body's joint frame, architecture.md §4). Because those identified values are degenerate (flat,
//! on the boundary `J ⪰ 0`), the default ground truth **thickens** every body by `d = 1 cm`
//! (`Σ_C ← Σ_C + m d² 1`), see [`Truth`]; the published set remains available.
//!
//! Limits used (all documented here, joint side):
//! - torque: `N × 27.2 N m` (motor peak torque, `ActuatorModel.h`) = 288.3 N m at N = 10.6;
//! - speed: the no-load speed `V / K_T = 65 V / 0.266 N m/A = 244 rad/s` at the motor, i.e.
//!   23.1 rad/s at the joint for N = 10.6 (torque falls linearly towards it through back-EMF);
//! - position: ab/ad ±1.5 rad and hip ±5 rad (the Cheetah-Software simulator's soft stops);
//!   knee ±2.6 rad, which keeps the shank 0.54 rad away from folding onto the thigh (at 0.34 m
//!   link length, more than 0.17 m of clearance against 0.06 m of link thickness).
//!
//! Bounding ellipsoids come from the geometry: motor radius 0.06 m, link radius 0.03 m, link
//! lengths 0.342 m (thigh) and 0.345 m (shank); see [`bounding_ellipsoids`] and the test that
//! reports how much room each truth body has (`tr(J Q)/m`).

use super::{Body, Joint, JointFriction, JointLimits, Model, ModelError, Rotor};
use crate::spatial::{rot_axis_angle, Ellipsoid, InertialParams, Transform};
use nalgebra::Vector3;

/// Gear ratio of every joint in the paper (10.6:1).
pub const GEAR_RATIO: f64 = 10.6;
/// Motor peak torque (N m), Cheetah-Software `ActuatorModel.h`.
pub const MOTOR_TAU_MAX: f64 = 27.2;

/// Acceleration limit of every joint for designed motions (rad/s²): about the peak of the
/// paper's shell motion on this leg (the motors allow far more: 288 N m at the knee against
/// 0.05 kg m² of reflected rotor inertia).
pub const MAX_ACCELERATION: f64 = 65.0;

/// Jerk limit of every joint for designed motions (rad/s³): the acceleration limit reached
/// within about 40 ms.
pub const MAX_JERK: f64 = 1500.0;
/// Motor torque constant (N m/A).
pub const MOTOR_KT: f64 = 0.266;
/// Motor winding resistance (ohm).
pub const MOTOR_R: f64 = 0.45;
/// Battery voltage (V).
pub const BATTERY_V: f64 = 65.0;
/// Thigh length, hip to knee (m).
pub const THIGH_LENGTH: f64 = 0.342;
/// Shank length, knee to foot (m).
pub const SHANK_LENGTH: f64 = 0.345;
/// Ab/ad to hip offset along y (m).
pub const ABAD_TO_HIP: f64 = 0.045;

/// Which mass properties to use as the ground truth.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum Truth {
    /// The published `Cheetah3.h` values, exactly (degenerate, on the boundary of `J ⪰ 0`).
    Published,
    /// Published values with every body thickened by an rms extent `d` (m) along each axis.
    Thickened {
        /// Added rms extent (m).
        d: f64,
    },
}

impl Default for Truth {
    fn default() -> Self {
        Truth::Thickened { d: 0.01 }
    }
}

/// Options of the built-in leg.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LegOptions {
    /// Ground-truth mass properties.
    pub truth: Truth,
    /// Gear ratio of each joint (ab/ad, hip, knee).
    pub gear_ratios: [f64; 3],
    /// Joint friction of each joint.
    pub friction: [JointFriction; 3],
    /// Whether the rotors are part of the model (false: the link-only leg).
    pub rotors: bool,
}

impl Default for LegOptions {
    fn default() -> Self {
        Self {
            truth: Truth::default(),
            gear_ratios: [GEAR_RATIO; 3],
            // Coulomb: the paper's identified values; viscous: of the order of 0.1 N m s/rad,
            // deliberately unequal so that a permuted joint order shows up in tests.
            friction: [
                JointFriction {
                    viscous: 0.12,
                    coulomb: 3.12,
                },
                JointFriction {
                    viscous: 0.10,
                    coulomb: 1.25,
                },
                JointFriction {
                    viscous: 0.08,
                    coulomb: 0.95,
                },
            ],
            rotors: true,
        }
    }
}

/// `Cheetah3.h` parameters in Cheetah-Software order `[m, hx, hy, hz, Ixx, Iyy, Izz, Iyz, Ixz,
/// Ixy]`, about each body's joint frame (architecture.md §4). Digits are kept verbatim as published,
/// trailing zeros included.
#[allow(clippy::excessive_precision)]
pub mod published {
    /// Ab/ad link.
    pub const ABAD: [f64; 10] = [
        1.645278752937798,
        0.0,
        1.050694793045323e-1,
        -7.248117018543008e-3,
        6.871761154771191e-3,
        2.715028710162546e-4,
        6.820782113449669e-3,
        4.545198314447007e-4,
        0.0,
        0.0,
    ];
    /// Thigh (hip link).
    pub const HIP: [f64; 10] = [
        1.071200401412615,
        -7.564034441661159e-4,
        -3.180527291037499e-2,
        -1.047496808654130e-1,
        2.020976253260794e-2,
        1.856851411013688e-2,
        3.115448656660994e-3,
        1.294666102054298e-4,
        1.217274116646696e-3,
        -4.116533457993085e-4,
    ];
    /// Shank (knee link).
    pub const KNEE: [f64; 10] = [
        9.019384095786234e-1,
        2.215928611851693e-2,
        3.623331361414656e-3,
        -4.411934868569409e-2,
        2.269554734974269e-2,
        2.714252268535285e-2,
        5.566745484613744e-3,
        -3.238036214456428e-4,
        -2.194717054345885e-3,
        1.274627163554897e-3,
    ];
    /// Ab/ad rotor.
    pub const ABAD_ROTOR: [f64; 10] = [
        4.999939189070923e-1,
        0.0,
        1.976769699734076e-3,
        -3.681440077402916e-4,
        9.908339941420835e-4,
        4.955917167197880e-4,
        4.956200895280653e-4,
        3.533262919985919e-8,
        0.0,
        0.0,
    ];
    /// Hip rotor.
    pub const HIP_ROTOR: [f64; 10] = [
        5.405045213157799e-1,
        -3.164547557293410e-3,
        -6.776800604201722e-3,
        7.158586831736347e-4,
        4.352341568156850e-4,
        1.015373256571613e-3,
        9.126776037286181e-4,
        -3.097121515937353e-5,
        -2.154046949222089e-4,
        1.306997274233568e-4,
    ];
    /// Knee rotor.
    pub const KNEE_ROTOR: [f64; 10] = [
        5.398676189202086e-1,
        -2.571556872957194e-4,
        -7.550002224983261e-3,
        1.125959428120149e-3,
        7.035267590972641e-4,
        8.693209041255046e-4,
        4.122075637011218e-4,
        -3.986925582339967e-5,
        -2.295396403157565e-4,
        2.324567952553503e-5,
    ];
}

/// Bounding ellipsoids from the geometry, in each body's frame:
/// `[abad, thigh, shank, abad_rotor, hip_rotor, knee_rotor]`.
///
/// - ab/ad link: it carries the hip motor housing; a sphere of radius 0.08 m (motor radius
///   0.06 m plus housing) centred at the hip motor, (0, 0.05, 0).
/// - thigh: carries the knee motor at its origin and reaches the knee: centred at
///   (0, 0, −0.15) with semi-axes (0.09, 0.09, 0.25) m, covering z from +0.10 to −0.40 m.
/// - shank: from the knee (0, 0, 0) to the foot (0, 0, −0.345) plus a 0.03 m link radius, and the
///   knee linkage, which puts mass well off-axis in x (the published CoM is 2.5 cm forward):
///   centred at (0, 0, −0.17) with semi-axes (0.13, 0.13, 0.30) m.
/// - rotors: discs of radius about 0.06 m: oblate ellipsoids centred at the rotor frame
///   origin, 0.045 m along the spin axis and 0.085 m across it.
pub fn bounding_ellipsoids() -> [Ellipsoid; 6] {
    let v = Vector3::new;
    let disc = |axis: Vector3<f64>| {
        let semi = axis * 0.045 + (Vector3::repeat(1.0) - axis) * 0.085;
        Ellipsoid::axis_aligned(Vector3::zeros(), semi)
    };
    [
        Ellipsoid::sphere(v(0.0, 0.05, 0.0), 0.08),
        Ellipsoid::axis_aligned(v(0.0, 0.0, -0.15), v(0.09, 0.09, 0.25)),
        Ellipsoid::axis_aligned(v(0.0, 0.0, -0.17), v(0.13, 0.13, 0.30)),
        disc(Vector3::x()),
        disc(Vector3::y()),
        disc(Vector3::y()),
    ]
}

/// The foot position in the shank frame (m).
pub fn foot_in_shank() -> Vector3<f64> {
    Vector3::new(0.0, 0.0, -SHANK_LENGTH)
}

fn params(cheetah: &[f64; 10], truth: Truth) -> InertialParams {
    let p = InertialParams::from_cheetah(cheetah).expect("published values are finite");
    match truth {
        Truth::Published => p,
        Truth::Thickened { d } => p.thickened(d),
    }
}

/// The Cheetah-3-like leg with the default options (rotors, thickened truth, paper friction).
pub fn leg() -> Model {
    leg_with(&LegOptions::default()).expect("the built-in leg is valid")
}

/// One joint of the leg: its body, the rotor that drives it, and its travel (rad).
struct LegJoint {
    body: &'static str,
    joint: &'static str,
    parent: Option<usize>,
    axis: Vector3<f64>,
    x_tree: Transform,
    link: &'static [f64; 10],
    rotor: &'static str,
    x_rot: Transform,
    rotor_link: &'static [f64; 10],
    travel: f64,
}

/// The leg with the given options.
pub fn leg_with(o: &LegOptions) -> Result<Model, ModelError> {
    let rz_pi = rot_axis_angle(&Vector3::z(), std::f64::consts::PI);
    let hip_origin = Transform::from_pose(&rz_pi, &Vector3::new(0.0, ABAD_TO_HIP, 0.0));
    let joints = [
        LegJoint {
            body: "abad",
            joint: "abad_joint",
            parent: None,
            axis: Vector3::x(),
            x_tree: Transform::identity(),
            link: &published::ABAD,
            rotor: "abad_rotor",
            x_rot: Transform::translation(&Vector3::new(0.0, -0.128, 0.0)),
            rotor_link: &published::ABAD_ROTOR,
            travel: 1.5,
        },
        LegJoint {
            body: "thigh",
            joint: "hip_joint",
            parent: Some(0),
            axis: Vector3::y(),
            x_tree: hip_origin,
            link: &published::HIP,
            rotor: "hip_rotor",
            x_rot: hip_origin,
            rotor_link: &published::HIP_ROTOR,
            travel: 5.0,
        },
        LegJoint {
            body: "shank",
            joint: "knee_joint",
            parent: Some(1),
            axis: Vector3::y(),
            x_tree: Transform::translation(&Vector3::new(0.0, 0.0, -THIGH_LENGTH)),
            link: &published::KNEE,
            rotor: "knee_rotor",
            x_rot: Transform::identity(),
            rotor_link: &published::KNEE_ROTOR,
            travel: 2.6,
        },
    ];
    let ell = bounding_ellipsoids();
    let bodies = joints
        .iter()
        .enumerate()
        .map(|(i, j)| leg_body(o, i, j, ell[i], ell[i + 3]))
        .collect();
    let model = Model::new(
        "cheetah3_leg",
        bodies,
        Vector3::new(0.0, 0.0, -super::STANDARD_GRAVITY),
    )?;
    if o.truth != Truth::Published {
        model.check_physical()?;
    }
    Ok(model)
}

/// Body `i` of the leg from its joint `j`, with the link's and the rotor's bounding ellipsoids;
/// the joint's speed and torque limits from the motor through the gear ratio.
fn leg_body(o: &LegOptions, i: usize, j: &LegJoint, link: Ellipsoid, rotor: Ellipsoid) -> Body {
    let n = o.gear_ratios[i];
    Body {
        name: j.body.into(),
        joint_name: j.joint.into(),
        parent: j.parent,
        joint: Joint::Revolute { axis: j.axis },
        x_tree: j.x_tree,
        inertia: params(j.link, o.truth),
        bounding: Some(link),
        shapes: vec![],
        rotor: o.rotors.then(|| Rotor {
            name: j.rotor.into(),
            x_rot: j.x_rot,
            joint: Joint::Revolute { axis: j.axis },
            gear_ratio: n,
            inertia: params(j.rotor_link, o.truth),
            bounding: Some(rotor),
        }),
        friction: o.friction[i],
        limits: JointLimits {
            lower: -j.travel,
            upper: j.travel,
            velocity: BATTERY_V / MOTOR_KT / n,
            effort: n * MOTOR_TAU_MAX,
            acceleration: MAX_ACCELERATION,
            jerk: MAX_JERK,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn published_values_are_flat_and_thickened_truth_is_not() {
        // architecture.md §4, trap 1: every published body has a zero eigenvalue of Σ_C (rms < 1 mm).
        let all = [
            published::ABAD,
            published::HIP,
            published::KNEE,
            published::ABAD_ROTOR,
            published::HIP_ROTOR,
            published::KNEE_ROTOR,
        ];
        for p in &all {
            let pub_p = params(p, Truth::Published);
            let thick = params(p, Truth::default());
            let m = pub_p.mass();
            let flat = pub_p.min_eig_pseudo() / m;
            assert!(
                flat.abs() < 1e-6,
                "published body not flat: λmin(J)/m = {flat}"
            );
            // Thickening by 1 cm lifts λmin(J)/m to about d² = 1e-4 m².
            let lam = thick.min_eig_pseudo() / m;
            assert!(lam > 0.5e-4 && lam < 1.0e-4 + 1e-6, "{lam}");
        }
    }

    #[test]
    fn truth_lies_inside_every_bounding_ellipsoid_with_margin() {
        let m = leg();
        let mut margins = vec![];
        for b in m.bodies() {
            let r = b.inertia.consistency(b.bounding.as_ref());
            margins.push((
                b.name.clone(),
                r.trace_jq_per_mass.unwrap(),
                r.min_eig_com.unwrap(),
            ));
            let rr = b.rotor.as_ref().unwrap();
            let r2 = rr.inertia.consistency(rr.bounding.as_ref());
            margins.push((
                rr.name.clone(),
                r2.trace_jq_per_mass.unwrap(),
                r2.min_eig_com.unwrap(),
            ));
        }
        for (name, t, c) in &margins {
            eprintln!("{name:>11}: tr(JQ)/m = {t:.3}, min eig C = {c:.2e}");
            assert!(*t > 0.1, "{name}: ellipsoid margin {t} too small");
            assert!(
                *t < 0.9,
                "{name}: ellipsoid so loose it does not matter ({t})"
            );
            assert!(*c > 0.0, "{name}: CoM outside");
        }
    }

    #[test]
    fn published_shank_escapes_the_matlab_ellipsoid() {
        // architecture.md §4, trap 2, reproduced: semi-axes (0.042, 0.042, 0.290) at (0, 0, -0.1725).
        let e = Ellipsoid::axis_aligned(
            Vector3::new(0.0, 0.0, -0.1725),
            Vector3::new(0.042, 0.042, 0.29),
        );
        let r = params(&published::KNEE, Truth::Published).consistency(Some(&e));
        assert!((r.trace_jq_per_mass.unwrap() + 2.9).abs() < 0.05, "{r:?}");
    }

    #[test]
    fn leg_structure() {
        let m = leg();
        assert_eq!(m.dof(), 3);
        assert_eq!(m.rotor_count(), 3);
        assert_eq!(m.layout().len, 66);
        assert_eq!(m.layout().rotor_col, vec![Some(30), Some(40), Some(50)]);
        assert!((m.bodies()[0].limits.effort - 288.32).abs() < 1e-9);
        let names = m.parameter_names();
        assert_eq!(names[17], "thigh.Iyy");
        assert_eq!(names[59], "knee_rotor.Izz");
        assert_eq!(names[61], "hip_joint.B");
        assert_eq!(names[65], "knee_joint.Bc");
        assert!((m.total_mass() - 5.1989).abs() < 1e-3, "{}", m.total_mass());
    }
}
