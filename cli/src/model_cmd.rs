//! `physid model`: a robot's bodies, rotors, mass properties and consistency margins.

use super::RobotArgs;
use physid::dynamics::{crba, Data};
use physid::model::Model;
use physid::spatial::{ConsistencyReport, Ellipsoid, InertialParams};

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
    let v = physid::api::model::describe(m);
    if as_json {
        println!(
            "{}",
            serde_json::to_string_pretty(&physid::io::versioned("model", &v))?
        );
        return Ok(());
    }
    let (q0, g) = (&v.q0, &v.gravity_torque_q0);
    let h = crba(m, &mut Data::new(m), q0).clone();
    println!(
        "{}: {} joints, {} rotors ({:?} model), {:.4} kg, {} parameters",
        m.name(),
        m.dof(),
        m.rotor_count(),
        m.rotor_model(),
        m.total_mass(),
        m.layout().len
    );
    let mut rows = vec![];
    for b in m.bodies() {
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
    for b in m.bodies() {
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
    println!("\nat q = {q0:?}: gravity torque g(q) = {:.4?} N m", g);
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
    for b in m.bodies() {
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
