//! `physid model`: a robot's bodies, rotors, mass properties and consistency margins.

use super::RobotArgs;
use physid::dynamics::{crba, rnea, Data};
use physid::model::Model;
use physid::spatial::{ConsistencyReport, Ellipsoid, InertialParams};

/// An ellipsoid: centre (m), semi-axes (m, ascending), `Q_s` (m²).
#[derive(serde::Serialize, schemars::JsonSchema)]
pub struct EllipsoidJson {
    center: Vec<f64>,
    semi_axes: Vec<f64>,
    qs: Vec<Vec<f64>>,
}

/// One body or rotor: its ten parameters (paper order, own frame), mass (kg), CoM (m),
/// principal moments about the CoM (kg m²), consistency margins, bounding ellipsoid.
#[derive(serde::Serialize, schemars::JsonSchema)]
pub struct BodyJson {
    ellipsoid: Option<EllipsoidJson>,
    name: String,
    pi: Vec<f64>,
    mass: f64,
    com: Option<Vec<f64>>,
    principal_moments: Option<Vec<f64>>,
    consistency: ConsistencyReport,
}

/// One joint: friction and limits `[lower, upper, velocity, effort]`.
#[derive(serde::Serialize, schemars::JsonSchema)]
pub struct JointJson {
    name: String,
    friction: physid::model::JointFriction,
    limits: [f64; 4],
}

/// `model --json` (schema `physid.model/1`, docs/schemas/).
#[derive(serde::Serialize, schemars::JsonSchema)]
pub struct ModelJson {
    name: String,
    dof: usize,
    rotors: usize,
    rotor_model: physid::model::RotorModel,
    /// kg.
    total_mass: f64,
    parameters: usize,
    bodies: Vec<BodyJson>,
    joints: Vec<JointJson>,
    /// The reference configuration (rad): zero clamped into the limits.
    q0: Vec<f64>,
    /// Gravity torque at `q0` (N m).
    gravity_torque_q0: Vec<f64>,
}

fn ellipsoid_json(e: &Ellipsoid) -> EllipsoidJson {
    EllipsoidJson {
        center: e.center.as_slice().to_vec(),
        semi_axes: e.semi_axes().as_slice().to_vec(),
        qs: (0..3)
            .map(|i| (0..3).map(|j| e.qs[(i, j)]).collect())
            .collect(),
    }
}

fn body_json(name: &str, p: &InertialParams, e: Option<&Ellipsoid>) -> BodyJson {
    BodyJson {
        ellipsoid: e.map(ellipsoid_json),
        name: name.to_string(),
        pi: p.0.as_slice().to_vec(),
        mass: p.mass(),
        com: p.com().map(|c| c.as_slice().to_vec()),
        principal_moments: p.principal_moments().map(|(v, _)| v.as_slice().to_vec()),
        consistency: p.consistency(e),
    }
}

/// Describe a robot: bodies, rotors, mass properties, consistency margins, and its dynamics at
/// a reference configuration.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    robot: RobotArgs,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// `physid model`.
pub fn run(a: Args) -> anyhow::Result<()> {
    describe(&a.robot.load()?, a.json)
}

/// Prints the model summary.
pub fn describe(m: &Model, as_json: bool) -> anyhow::Result<()> {
    let mut bodies = vec![];
    for b in &m.bodies {
        bodies.push(body_json(&b.name, &b.inertia, b.bounding.as_ref()));
        if let Some(r) = &b.rotor {
            bodies.push(body_json(&r.name, &r.inertia, r.bounding.as_ref()));
        }
    }
    let q0: Vec<f64> = m
        .bodies
        .iter()
        .map(|b| 0.0f64.clamp(b.limits.lower, b.limits.upper))
        .collect();
    let mut d = Data::new(m);
    let zero = vec![0.0; m.dof()];
    let g = rnea(m, &mut d, &q0, &zero, &zero).clone();
    let h = crba(m, &mut d, &q0).clone();
    if as_json {
        let v = ModelJson {
            name: m.name.clone(),
            dof: m.dof(),
            rotors: m.rotor_count(),
            rotor_model: m.rotor_model,
            total_mass: m.total_mass(),
            parameters: m.layout().len,
            bodies,
            joints: m
                .bodies
                .iter()
                .map(|b| JointJson {
                    name: b.joint_name.clone(),
                    friction: b.friction,
                    limits: [
                        b.limits.lower,
                        b.limits.upper,
                        b.limits.velocity,
                        b.limits.effort,
                    ],
                })
                .collect(),
            q0: q0.clone(),
            gravity_torque_q0: g.as_slice().to_vec(),
        };
        println!(
            "{}",
            serde_json::to_string_pretty(&physid::io::versioned("model", &v))?
        );
        return Ok(());
    }
    println!(
        "{}: {} joints, {} rotors ({:?} model), {:.4} kg, {} parameters",
        m.name,
        m.dof(),
        m.rotor_count(),
        m.rotor_model,
        m.total_mass(),
        m.layout().len
    );
    let mut rows = vec![];
    for b in &m.bodies {
        rows.push((
            b.name.clone(),
            b.inertia,
            b.inertia.consistency(b.bounding.as_ref()),
        ));
        if let Some(r) = &b.rotor {
            rows.push((
                r.name.clone(),
                r.inertia,
                r.inertia.consistency(r.bounding.as_ref()),
            ));
        }
    }
    print_bodies(&rows);
    print_ellipsoids(m);
    println!(
        "\n{:<14} {:>8} {:>12} {:>12} {:>22}",
        "joint", "N", "B [Nms/rad]", "Bc [Nm]", "limits [rad]"
    );
    for b in &m.bodies {
        println!(
            "{:<14} {:>8} {:>12.3} {:>12.3} {:>22}",
            b.joint_name,
            b.rotor
                .as_ref()
                .map_or("-".into(), |r| format!("{}", r.gear_ratio)),
            b.friction.viscous,
            b.friction.coulomb,
            format!("[{}, {}]", b.limits.lower, b.limits.upper)
        );
    }
    println!(
        "\nat q = {q0:?}: gravity torque g(q) = {:.4?} N m",
        g.as_slice()
    );
    println!("mass matrix H(q) [kg m^2]:{h:.5}");
    Ok(())
}

/// Prints each body's and rotor's bounding ellipsoid (centre and semi-axes, body frame), or
/// that it has none.
fn print_ellipsoids(m: &Model) {
    println!(
        "\n{:<12} {:>30} {:>30}",
        "ellipsoid", "centre [m]", "semi-axes [m]"
    );
    let row = |name: &str, e: Option<&Ellipsoid>| match e {
        Some(e) => {
            let (c, a) = (e.center, e.semi_axes());
            println!(
                "{name:<12} {:>30} {:>30}",
                format!("({:.4}, {:.4}, {:.4})", c.x, c.y, c.z),
                format!("({:.4}, {:.4}, {:.4})", a.x, a.y, a.z)
            );
        }
        None => println!("{name:<12} {:>30}", "none"),
    };
    for b in &m.bodies {
        row(&b.name, b.bounding.as_ref());
        if let Some(r) = &b.rotor {
            row(&r.name, r.bounding.as_ref());
        }
    }
}

/// Prints one line per body: mass, CoM, principal moments about the CoM and the consistency
/// margins (`λ_min I`, `λ_min J`, `tr(JQ)/m`).
pub fn print_bodies(rows: &[(String, InertialParams, ConsistencyReport)]) {
    print_bodies_marked(rows, &vec![' '; rows.len()]);
}

/// [`print_bodies`] with a mark after each body's mass (e.g. `~` for a mass the data do not
/// determine).
pub fn print_bodies_marked(rows: &[(String, InertialParams, ConsistencyReport)], marks: &[char]) {
    let width = rows
        .iter()
        .map(|(n, _, _)| n.len())
        .max()
        .unwrap_or(4)
        .max(12);
    println!(
        "\n{:<width$} {:>9} {:>28} {:>30} {:>11} {:>11} {:>9}",
        "body", "m [kg]", "CoM [m]", "principal I_C [kg m^2]", "min eig I", "min eig J", "tr(JQ)/m"
    );
    for ((name, p, r), mark) in rows.iter().zip(marks) {
        let c = p.com().unwrap_or_default();
        let pm = p.principal_moments().map(|x| x.0).unwrap_or_default();
        println!(
            "{:<width$} {:>8.4}{mark} {:>28} {:>30} {:>11.3e} {:>11.3e} {:>9}",
            name,
            p.mass(),
            format!("({:.4}, {:.4}, {:.4})", c.x, c.y, c.z),
            format!("({:.2e}, {:.2e}, {:.2e})", pm.x, pm.y, pm.z),
            r.min_eig_spatial,
            r.min_eig_pseudo,
            r.trace_jq_per_mass
                .map_or("-".into(), |t| format!("{t:.3}"))
        );
    }
}
