//! `physid excite`: design an excitation (library: `physid::sim::design`), write it as a
//! scenario, and check it in simulation.

use anyhow::Context;
use clap::ValueEnum;
use physid::api::excite::{check_in_simulation, ExciteJson, SimulatedUse};
use physid::model::Model;
use physid::sim::design::{self, Design, DesignOptions, Objective};
use physid::sim::scenario::ExcitationSpec;
use std::path::{Path, PathBuf};

/// Design a Fourier excitation that carries the most information about the robot's
/// identifiable parameters within its joint limits, write it as a scenario that `simulate` and
/// `experiment` run as is, and check the limits in simulation.
#[derive(clap::Args, Debug)]
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
    #[arg(long, default_value_t = 20.0)]
    duration: f64,
    /// Harmonics per joint.
    #[arg(long, default_value_t = 5)]
    harmonics: usize,
    /// Fundamental frequency (Hz): the motion repeats every 1/f s.
    #[arg(long, default_value_t = 0.5)]
    base_frequency: f64,
    /// What is maximized.
    #[arg(long, value_enum, default_value = "d-optimal")]
    objective: ObjectiveArg,
    /// Seed of the random starts and steps.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Optimization steps per start (0: a random excitation scaled into the limits).
    #[arg(long, default_value_t = 1000)]
    iterations: usize,
    /// Random starts (in parallel; the best is kept).
    #[arg(long, default_value_t = 4)]
    starts: usize,
    /// Fraction of every limit left free.
    #[arg(long, default_value_t = 0.15)]
    margin: f64,
    /// Acceleration limit (rad/s²): one for every joint, or one per joint separated by commas.
    /// Default: the description's (a URDF `<limit acceleration=…>`, a robot TOML's
    /// `limits.acceleration`), else 3 rad/s², below common arms' limits.
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    max_acceleration: Option<Vec<f64>>,
    /// Jerk limit (rad/s³), as --max-acceleration; default the description's, else 30 rad/s³.
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
    max_jerk: Option<Vec<f64>>,
    /// Start and end at rest (s): the motion fades in from rest over this long and out to rest
    /// at the end (velocity, acceleration and jerk zero at both ends). Default: one period of
    /// the fundamental, at most a quarter of the duration; 0 starts mid-motion (periodic).
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
    /// Sample rate of --csv and --mcap (Hz).
    #[arg(long, default_value_t = 1000.0, allow_negative_numbers = true)]
    rate: f64,
    /// Samples per period at which the information is evaluated.
    #[arg(long, default_value_t = 200)]
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
    #[arg(long, default_value_t = 0)]
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
    if !(a.duration.is_finite() && a.duration > 0.0) {
        anyhow::bail!(
            "--duration must be a positive number of seconds, got {}",
            a.duration
        );
    }
    let base = Base::load(&a)?;
    let (max_acceleration, max_jerk, defaulted) = design::rate_limits(
        &base.model,
        a.max_acceleration.as_deref(),
        a.max_jerk.as_deref(),
    );
    if !defaulted.is_empty() && !a.json {
        eprintln!(
            "note: the description gives no acceleration or jerk limit for {}: designing within {} rad/s² and {} rad/s³ (give --max-acceleration and --max-jerk)",
            defaulted.join(", "),
            design::SAFE_ACCELERATION,
            design::SAFE_JERK
        );
    }
    let ramp = a
        .ramp
        .unwrap_or_else(|| (1.0 / a.base_frequency).min(0.25 * a.duration));
    let opts = DesignOptions {
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
        max_acceleration,
        max_jerk,
        ramp,
        duration: a.duration,
        samples: a.samples,
    };
    opts.validate().map_err(super::option_error)?;
    if !(a.rate.is_finite() && a.rate > 0.0 && a.rate <= 1e5) {
        anyhow::bail!(
            "--rate must be a sample rate in (0, 100000] Hz, got {}",
            a.rate
        );
    }
    if a.score {
        return score_base(&base, &a, &opts);
    }
    let outputs: Vec<&Path> = [&a.out, &a.csv, &a.mcap]
        .into_iter()
        .flatten()
        .map(PathBuf::as_path)
        .collect();
    let inputs: Vec<&Path> = base.inputs.iter().map(PathBuf::as_path).collect();
    physid::io::check_outputs(&outputs, &inputs)?;
    let pool = super::thread_pool(Some(a.threads))?;
    let d = pool
        .install(|| design::design(&base.model, base.range.as_deref(), &opts))
        .map_err(super::option_error)?;
    let text = base.scenario_text(&d, &a)?;
    let (simulated, within) = if a.no_check {
        (None, None)
    } else {
        let band = 5.0 * a.harmonics as f64 * a.base_frequency;
        let check = check_in_simulation(&base.model, &text, &opts, band)?;
        (Some(check.joints), Some(check.within))
    };
    // A design that leaves a limit in simulation is not written.
    if within != Some(false) {
        if let Some(out) = &a.out {
            physid::io::write_atomic(out, text.as_bytes())?;
        }
        write_trajectory(&base.model, &d.series, &a)?;
    }
    if a.json {
        let j = ExciteJson {
            design: d,
            out: a.out.clone(),
            simulated,
            within_limits: within,
        };
        println!(
            "{}",
            serde_json::to_string_pretty(&physid::io::versioned("excite", &j))?
        );
    } else {
        print_design(&d, simulated.as_deref(), &a);
    }
    if within == Some(false) {
        return Err(super::Failed(
            "the simulated run left a limit (see the table above), so the scenario was not written: raise --margin".into(),
        )
        .into());
    }
    Ok(())
}

/// `--csv` and `--mcap`: the designed reference trajectory (t, q, q̇, q̈) at `a.rate` over the
/// run, written atomically.
fn write_trajectory(model: &Model, series: &design::FourierSeries, a: &Args) -> anyhow::Result<()> {
    if a.csv.is_none() && a.mcap.is_none() {
        return Ok(());
    }
    let names: Vec<String> = model.bodies.iter().map(|b| b.joint_name.clone()).collect();
    let samples = (a.duration * a.rate).round() as usize + 1;
    let mut tr = physid::trajectory::Trajectory::new(names.clone(), true);
    for k in 0..samples {
        let t = k as f64 / a.rate;
        let [q, qd, qdd] = series.at(t);
        tr.push(t, &q, &qd, Some(&qdd), &vec![0.0; names.len()]);
    }
    if let Some(p) = &a.csv {
        physid::io::samples::write_reference_csv(p, &tr)?;
    }
    if let Some(p) = &a.mcap {
        physid::io::mcap_log::write_reference(p, &tr)?;
    }
    Ok(())
}

/// `--score`: the base scenario's own motion, simulated for `a.duration`, scored on its true
/// states.
fn score_base(base: &Base, a: &Args, opts: &DesignOptions) -> anyhow::Result<()> {
    let mut sc: physid::sim::scenario::Scenario = toml::from_str(&base.text)?;
    sc.simulation.duration = a.duration;
    let rec =
        physid::sim::run(&base.model, &sc, &mut |_| {}).context("simulating the base scenario")?;
    let tr = &rec.truth;
    let states = (0..tr.len()).filter_map(|k| Some([tr.q_at(k), tr.qd_at(k), tr.qdd_at(k)?]));
    let [d, e, c] = design::score_states(&base.model, base.range.as_deref(), opts, states)?;
    if a.json {
        let v = serde_json::json!({
            "d_optimal": d, "e_optimal": e, "condition": (-c).exp(), "samples": tr.len(),
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!(
            "{} s of the scenario's own motion ({} samples, true states): log det F / r = {d:.4}, log λ_min(F) = {e:.4}, condition number {:.3e}",
            a.duration,
            tr.len(),
            (-c).exp()
        );
    }
    Ok(())
}

/// What the design starts from: the robot, the scenario table it goes into, the joint ranges.
struct Base {
    model: Model,
    /// The scenario's text (the base file's, or physid's defaults for a robot).
    text: String,
    /// The base file's directory (relative robot paths resolve against it).
    dir: PathBuf,
    /// Per joint `(lower, upper)` from a base Fourier excitation.
    range: Option<Vec<(f64, f64)>>,
    /// Gains of the tracking controller.
    gains: (Vec<f64>, Vec<f64>, bool),
    /// Files read.
    inputs: Vec<PathBuf>,
}

impl Base {
    fn load(a: &Args) -> anyhow::Result<Self> {
        if let Some(path) = &a.scenario {
            let (sc, model, text) = physid::sim::scenario::load(path)?;
            let n = model.dof();
            let (range, gains) = match &sc.excitation {
                ExcitationSpec::Fourier {
                    amplitude,
                    offset,
                    coefficients,
                    kp,
                    kd,
                    computed_torque,
                    ..
                } => (
                    coefficients.is_none().then(|| {
                        offset
                            .iter()
                            .zip(amplitude)
                            .map(|(o, a)| (o - a, o + a))
                            .collect()
                    }),
                    (kp.clone(), kd.clone(), *computed_torque),
                ),
                _ => (None, default_gains(n)),
            };
            let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
            Ok(Self {
                model,
                text,
                dir,
                range,
                gains,
                inputs: physid::io::scenario_files(path),
            })
        } else {
            let robot = a
                .robot
                .clone()
                .expect("clap requires --robot without --scenario");
            let (model, warnings) = physid::io::load_robot_with(&robot, &Default::default())?;
            for w in warnings {
                eprintln!("warning: {robot}: {w}");
            }
            let n = model.dof();
            let robot_table = if robot == "cheetah3" {
                "builtin = \"cheetah3\"".to_string()
            } else {
                format!("urdf = {}", toml::Value::String(robot.clone()))
            };
            let text = format!(
                "[robot]\n{robot_table}\n\n[simulation]\nduration = 1.0\nrate = 1000.0\nsubsteps = 4\nseed = 1\nfriction_velocity = 0.01\n\n[excitation]\nkind = \"passive\"\n\n[sensors]\ntorque_noise = 0.3\nvelocity_feedback = \"finite_difference\"\n\n[processing]\nmethod = \"butterworth\"\ncutoff = 20.0\norder = 2\n"
            );
            Ok(Self {
                model,
                text,
                dir: std::env::current_dir()?,
                range: None,
                gains: default_gains(n),
                inputs: physid::io::robot_files(&robot, &[]),
            })
        }
    }

    /// The scenario text with the design as its excitation and `a.duration` (the base file's
    /// other tables, comments included, as they were); a relative URDF path rewritten
    /// relative to `a.out`'s folder.
    fn scenario_text(&self, d: &Design, a: &Args) -> anyhow::Result<String> {
        use toml_edit::{value, Array, DocumentMut, Item, Table};
        let s = &d.series;
        let (kp, kd, computed_torque) = self.gains.clone();
        let list = |v: &[f64]| Array::from_iter(v.iter().copied());
        let rows = |m: &[Vec<f64>]| Array::from_iter(m.iter().map(|r| list(r)));
        let mut ex = Table::new();
        ex["kind"] = value("fourier");
        ex["harmonics"] = value(s.sin.first().map_or(0, |r| r.len()) as i64);
        ex["base_frequency"] = value(s.base_frequency);
        ex["offset"] = value(list(&s.offset));
        ex["kp"] = value(list(&kp));
        ex["kd"] = value(list(&kd));
        ex["computed_torque"] = value(computed_torque);
        if let Some(w) = s.window {
            ex["ramp"] = value(w.ramp);
        }
        if computed_torque {
            ex["friction_feedforward"] = value(true);
        }
        let mut c = Table::new();
        c["sin"] = value(rows(&s.sin));
        c["cos"] = value(rows(&s.cos));
        ex["coefficients"] = Item::Table(c);
        let mut doc: DocumentMut = self.text.parse().context("re-reading the base scenario")?;
        let header = format!(
            "# Designed by `physid excite` (physid {}): {} Fourier excitation, {} harmonics at {} Hz,\n# objective {} = {:.4} (best random start {:.4}), condition number {:.3e}, seed {}, margin {},\n# acceleration limit {:?} rad/s², jerk limit {:?} rad/s³, ramp {} s. {} of {} parameter combinations identifiable. Limits kept and used: `physid excite --json`.\n",
            env!("CARGO_PKG_VERSION"),
            if d.evaluations > a.starts { "optimized" } else { "random" },
            a.harmonics,
            a.base_frequency,
            physid::io::serde_name(&d.objective),
            d.value,
            d.start_value,
            d.condition,
            a.seed,
            a.margin,
            d.limits.acceleration.iter().map(|x| x / (1.0 - a.margin)).collect::<Vec<_>>(),
            d.limits.jerk.iter().map(|x| x / (1.0 - a.margin)).collect::<Vec<_>>(),
            s.window.map_or(0.0, |w| w.ramp),
            d.identifiable,
            d.parameters,
        );
        ex.decor_mut().set_prefix(format!("\n{header}"));
        doc["excitation"] = Item::Table(ex);
        doc["simulation"]["duration"] = value(a.duration);
        if let Some(u) = doc["robot"].get("urdf").and_then(|v| v.as_str()) {
            let urdf = self.dir.join(u);
            let urdf = urdf.canonicalize().unwrap_or(urdf);
            let out_dir = a
                .out
                .as_ref()
                .and_then(|o| o.parent())
                .filter(|p| !p.as_os_str().is_empty())
                .unwrap_or(Path::new("."))
                .canonicalize()?;
            let rel = pathdiff::diff_paths(&urdf, &out_dir).unwrap_or(urdf);
            doc["robot"]["urdf"] = value(rel.display().to_string());
        }
        Ok(doc.to_string())
    }
}

/// Computed-torque gains for a robot without a base excitation (1/s², 1/s).
fn default_gains(n: usize) -> (Vec<f64>, Vec<f64>, bool) {
    (vec![400.0; n], vec![40.0; n], true)
}

fn print_design(d: &Design, simulated: Option<&[SimulatedUse]>, a: &Args) {
    println!(
        "{} Fourier excitation: {} harmonics at {} Hz (period {:.2} s), objective {} = {:.4} (best random start {:.4}); log det F / r = {:.4}; condition number {:.3e}; {} of {} parameter combinations identifiable; {} evaluations in {:.2} s",
        if d.evaluations > a.starts { "optimized" } else { "random" },
        a.harmonics,
        a.base_frequency,
        1.0 / a.base_frequency,
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
