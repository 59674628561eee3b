//! `physid excite`: flags to `physid::api::excite`, the design and its check printed.

use clap::ValueEnum;
use physid::api::data::Notice;
use physid::api::excite::{
    design_kind, excite, score_motion, ExciteFrom, ExciteOptions, MotionScore, SimulatedUse,
};
use physid::sim::design::{Design, Objective};
use std::path::PathBuf;

/// The sample rate of --csv and --mcap when --rate is not given (Hz).
const DEFAULT_RATE: f64 = 1000.0;

/// Design a Fourier excitation that carries the most information about the robot's
/// identifiable parameters within its joint limits, write it as a scenario that `simulate` and
/// `experiment` run as is, and check the limits in simulation.
#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("reference").args(["csv", "mcap"]).multiple(true)))]
pub struct Args {
    /// Base scenario: its robot, simulation, sensors, processing and experiment are kept and
    /// its excitation replaced; a Fourier excitation's `offset ± amplitude` narrows the joint
    /// ranges (the other limits come from the robot).
    #[arg(long, conflicts_with = "robot", required_unless_present = "robot")]
    scenario: Option<PathBuf>,
    /// Robot when no --scenario is given: `cheetah3` or a .urdf file (sensors and processing
    /// then take physid's defaults: 0.3 N m torque noise, 20 Hz Butterworth).
    #[arg(long)]
    robot: Option<String>,
    /// Duration of the written scenario (s).
    #[arg(allow_negative_numbers = true, long, default_value_t = 20.0)]
    duration: f64,
    /// Harmonics per joint.
    #[arg(allow_negative_numbers = true, long, default_value_t = 5)]
    harmonics: usize,
    /// Fundamental frequency (Hz): the motion repeats every 1/f s. Default: chosen with the
    /// limits and the duration: the fastest at which each joint's first harmonic alone could
    /// sweep its whole range within its speed, acceleration and jerk limits, but at least one
    /// whole period between the ramps (or over half the run, where --ramp leaves less).
    #[arg(allow_negative_numbers = true, long)]
    base_frequency: Option<f64>,
    /// What is maximized.
    #[arg(long, value_enum, default_value = "d-optimal")]
    objective: ObjectiveArg,
    /// Seed of the random starts and steps.
    #[arg(allow_negative_numbers = true, long, default_value_t = 1)]
    seed: u64,
    /// Optimization steps per start (0: a random excitation scaled into the limits).
    #[arg(allow_negative_numbers = true, long, default_value_t = 1000)]
    iterations: usize,
    /// Random starts (in parallel; the best is kept).
    #[arg(allow_negative_numbers = true, long, default_value_t = 4)]
    starts: usize,
    /// Fraction of every limit left free.
    #[arg(allow_negative_numbers = true, long, default_value_t = 0.15)]
    margin: f64,
    /// Acceleration limit (rad/s²): one for every joint, or one per joint separated by commas.
    /// Default: the description's (a URDF `<limit acceleration=…>`, a robot TOML's
    /// `limits.acceleration`), else 3 rad/s², below common arms' limits.
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    max_acceleration: Option<Vec<f64>>,
    /// Jerk limit (rad/s³), as --max-acceleration; default the description's, else 30 rad/s³;
    /// `inf`: no jerk limit (the acceleration limit, which bounds the motor current, has no such
    /// value).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    max_jerk: Option<Vec<f64>>,
    /// Start and end at rest (s): the motion fades in from rest over this long and out to rest
    /// at the end (velocity, acceleration and jerk zero at both ends). Default: the shortest
    /// over which a joint's whole range fades in within half its acceleration and jerk limits,
    /// at most a quarter of the duration; 0 starts mid-motion (periodic).
    #[arg(long, allow_negative_numbers = true)]
    ramp: Option<f64>,
    /// Also write the designed trajectory (t, q, q̇, q̈ per joint, named by joint) as CSV, to
    /// send to a controller.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Also write the designed trajectory as MCAP (physid_msgs/msg/JointSample on
    /// /physid/excitation: position, velocity, acceleration).
    #[arg(long)]
    mcap: Option<PathBuf>,
    /// Sample rate of --csv and --mcap (Hz; default 1000); needs one of them.
    #[arg(long, allow_negative_numbers = true, requires = "reference")]
    rate: Option<f64>,
    /// Samples per period at which the information is evaluated.
    #[arg(allow_negative_numbers = true, long, default_value_t = 200)]
    samples: usize,
    /// Write the scenario here (TOML); it must not exist as an input of this run.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Print JSON (schema physid.excite/1) instead of text.
    #[arg(long)]
    json: bool,
    /// Do not simulate the design to check its limits.
    #[arg(long)]
    no_check: bool,
    /// Design nothing: simulate the base scenario's own excitation for --duration and print
    /// its objective values on the true motion (to compare a motion designed elsewhere).
    #[arg(long, requires = "scenario")]
    score: bool,
    /// Worker threads (0 = all cores). Results do not depend on it.
    #[arg(allow_negative_numbers = true, long, default_value_t = 0)]
    threads: usize,
}

#[derive(ValueEnum, Clone, Copy, Debug)]
enum ObjectiveArg {
    DOptimal,
    EOptimal,
    Condition,
}

/// `physid excite`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let opts = options(&a);
    let json = a.json;
    let mut notify = |n: Notice| {
        if n.warning {
            eprintln!("warning: {}", n.text);
        } else if !json {
            eprintln!("note: {}", n.text);
        }
    };
    if a.score {
        let s = score_motion(&opts, &mut notify).map_err(super::option_error)?;
        return print_score(&s, &a);
    }
    let pool = super::thread_pool(Some(a.threads))?;
    let e = pool
        .install(|| excite(&opts, &mut notify))
        .map_err(super::option_error)?;
    let within = e.within_limits();
    if json {
        println!(
            "{}",
            serde_json::to_string_pretty(&physid::io::versioned("excite", &e.json(a.out.clone())))?
        );
    } else {
        print_design(&e.design, e.check.as_ref().map(|c| c.joints.as_slice()), &a);
    }
    if within == Some(false) {
        return Err(super::Failed(
            "the simulated run left a limit (see the table above), so the scenario was not written: raise --margin".into(),
        )
        .into());
    }
    Ok(())
}

/// The library's options from the flags.
fn options(a: &Args) -> ExciteOptions {
    ExciteOptions {
        from: match (&a.scenario, &a.robot) {
            (Some(path), _) => ExciteFrom::Scenario(path.clone()),
            (None, robot) => ExciteFrom::Robot(
                robot
                    .clone()
                    .expect("clap requires --robot without --scenario"),
            ),
        },
        duration: a.duration,
        harmonics: a.harmonics,
        base_frequency: a.base_frequency,
        objective: match a.objective {
            ObjectiveArg::DOptimal => Objective::DOptimal,
            ObjectiveArg::EOptimal => Objective::EOptimal,
            ObjectiveArg::Condition => Objective::Condition,
        },
        seed: a.seed,
        iterations: a.iterations,
        starts: a.starts,
        margin: a.margin,
        max_acceleration: a.max_acceleration.clone(),
        max_jerk: a.max_jerk.clone(),
        ramp: a.ramp,
        samples: a.samples,
        rate: a.rate.unwrap_or(DEFAULT_RATE),
        out: a.out.clone(),
        csv: a.csv.clone(),
        mcap: a.mcap.clone(),
        check: !a.no_check,
    }
}

/// `--score`: the base scenario's own motion's information measures.
fn print_score(s: &MotionScore, a: &Args) -> anyhow::Result<()> {
    if a.json {
        let v = serde_json::json!({
            "d_optimal": s.d_optimal, "e_optimal": s.e_optimal, "condition": s.condition, "samples": s.samples,
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!(
            "{} s of the scenario's own motion ({} samples, true states): log det F / r = {:.4}, log λ_min(F) = {:.4}, condition number {:.3e}",
            a.duration, s.samples, s.d_optimal, s.e_optimal, s.condition
        );
    }
    Ok(())
}

/// Each joint's peaks in the check in simulation against the robot's own limits.
fn print_simulated_use(sim: &[SimulatedUse]) {
    println!("in simulation (peak / the robot's own limit): joint, q range [limits] rad, speed, acceleration rad/s², torque");
    for u in sim {
        println!(
            "  {:<14} [{:.3}, {:.3}] in [{:.3}, {:.3}]  {:>5.2}  {:>7.2}  {:>5.2}{}",
            u.joint,
            u.q_range[0],
            u.q_range[1],
            u.q_limits[0],
            u.q_limits[1],
            u.velocity,
            u.acceleration,
            u.torque,
            if u.within { "" } else { "  LEFT A LIMIT" }
        );
    }
}

fn print_design(d: &Design, simulated: Option<&[SimulatedUse]>, a: &Args) {
    println!(
        "{} Fourier excitation: {} harmonics at {} Hz (period {:.2} s), objective {} = {:.4} (best random start {:.4}); log det F / r = {:.4}; condition number {:.3e}; {} of {} parameter combinations identifiable; {} evaluations in {:.2} s",
        design_kind(d, a.starts),
        a.harmonics,
        format!("{:.4}", d.series.base_frequency)
            .trim_end_matches('0')
            .trim_end_matches('.'),
        d.series.period(),
        physid::io::serde_name(&d.objective),
        d.value,
        d.start_value,
        d.d_value,
        d.condition,
        d.identifiable,
        d.parameters,
        d.evaluations,
        d.seconds
    );
    println!(
        "limits used (peak / limit with the {:.0} % margin, ramps included): joint, position, speed, acceleration, jerk, torque",
        100.0 * a.margin
    );
    for u in &d.limit_use {
        println!(
            "  {:<14} {:>5.2} {:>5.2} {:>5.2} {:>5.2} {:>5.2}",
            u.joint, u.position, u.velocity, u.acceleration, u.jerk, u.torque
        );
    }
    if let Some(w) = d.series.window {
        println!(
            "starts and ends at rest: {:.2} s ramps at both ends of the {} s run",
            w.ramp, a.duration
        );
    }
    if let Some(sim) = simulated {
        print_simulated_use(sim);
    }
    if let Some(out) = &a.out {
        if simulated.is_some_and(|s| !s.iter().all(|u| u.within)) {
            println!(
                "not written: {} (a limit was left in simulation)",
                out.display()
            );
        } else {
            println!("wrote {}", out.display());
        }
    }
}
