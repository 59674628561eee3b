//! `excite`: design an excitation for a robot or a base scenario ([`excite`] with
//! [`ExciteOptions`]; the optimization itself is [`crate::sim::design`]), write it as a
//! scenario that `simulate` and `experiment` run as is, check it in simulation against the
//! robot's limits ([`check_in_simulation`]), and score a motion designed elsewhere
//! ([`score_motion`]). [`ExciteJson`] is the JSON contract (docs/schemas/excite.schema.json).

use super::data::Notice;
use super::ApiError;
use crate::model::Model;
use crate::sim::design::{self, Design, DesignOptions, Timing};

/// What a design maximizes, and what it tells its caller as it goes.
pub use crate::sim::design::{Objective, Watch};
use crate::sim::scenario::ExcitationSpec;
use crate::trajectory::Trajectory;
use std::path::{Path, PathBuf};

/// The limits as the simulated robot used them (peak over the run / the robot's own limit,
/// no margin).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct SimulatedUse {
    /// Joint name.
    pub joint: String,
    /// Lowest and highest angle reached (rad).
    pub q_range: [f64; 2],
    /// The robot's position limits (rad; null: none).
    pub q_limits: [f64; 2],
    /// Peak speed over the speed limit.
    pub velocity: f64,
    /// Peak acceleration in the motion's band (rad/s²; the true acceleration low-passed at 5×
    /// the highest harmonic).
    pub acceleration: f64,
    /// Peak torque over the effort limit.
    pub torque: f64,
    /// Every peak inside its limit.
    pub within: bool,
}

/// `excite --json` (schema `physid.excite/1`, docs/schemas/).
#[derive(serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct ExciteJson {
    /// The design.
    pub design: Design,
    /// The scenario written, if any.
    pub out: Option<PathBuf>,
    /// The check in simulation (null with --no-check).
    pub simulated: Option<Vec<SimulatedUse>>,
    /// Every simulated peak inside the robot's limits and the acceleration limit.
    pub within_limits: Option<bool>,
}

/// The check of a design in simulation: each joint's peaks against its limits.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct LimitCheck {
    /// Per joint, in the robot's order.
    pub joints: Vec<SimulatedUse>,
    /// Every peak of every joint inside its limit.
    pub within: bool,
}

/// Simulates the scenario `text` (its robot is `model`) and compares each joint's peaks
/// with the robot's limits (position, speed, torque: the true motion) and the acceleration
/// limit (the true acceleration low-passed at `band` Hz, zero phase, without the first and
/// last second: the tracking controller's reaction to encoder quantization adds broadband
/// jitter of a few rad/s² that is not part of the motion, and its start-up a transient).
pub fn check_in_simulation(
    model: &Model,
    text: &str,
    opts: &DesignOptions,
    band: f64,
) -> Result<LimitCheck, ApiError> {
    let designed = |m: String| ApiError::Designed(m);
    let sc: crate::sim::scenario::Scenario =
        toml::from_str(text).map_err(|e| designed(e.to_string()))?;
    sc.validate(model.dof())
        .map_err(|e| designed(e.to_string()))?;
    let rec = crate::sim::run(model, &sc, &mut |_| {})
        .map_err(|source| ApiError::DesignedSimulation { source })?;
    let tr = &rec.truth;
    let rate = sc.simulation.rate;
    let sos = crate::signal::butterworth_lowpass(2, band.min(0.4 * rate), rate)
        .map_err(|e| designed(format!("acceleration band {band} Hz: {e}")))?;
    // The tracking controller's start-up and the filter's ends: the first and last second.
    let settle = (rate as usize).min(tr.len() / 4);
    let mut ok = true;
    let joints = model
        .bodies()
        .iter()
        .enumerate()
        .map(|(j, b)| {
            let col = |f: &dyn Fn(usize) -> f64| (0..tr.len()).map(f).collect::<Vec<f64>>();
            let q = col(&|k| tr.q_at(k)[j]);
            let qd = col(&|k| tr.qd_at(k)[j].abs());
            let qdd: Vec<f64> = sos
                .filtfilt(&col(&|k| tr.qdd_at(k).map_or(0.0, |a| a[j])))
                .iter()
                .skip(settle)
                .take(tr.len().saturating_sub(2 * settle))
                .map(|x| x.abs())
                .collect();
            let tau = col(&|k| tr.tau_at(k)[j].abs());
            let max = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
            let l = &b.limits;
            let ratio = |p: f64, lim: f64| if lim.is_finite() { p / lim } else { 0.0 };
            let mut u = SimulatedUse {
                joint: b.joint_name.clone(),
                q_range: [min(&q), max(&q)],
                q_limits: [l.lower, l.upper],
                velocity: ratio(max(&qd), l.velocity),
                acceleration: max(&qdd),
                torque: ratio(max(&tau), l.effort),
                within: false,
            };
            u.within = u.q_range[0] >= l.lower
                && u.q_range[1] <= l.upper
                && u.velocity <= 1.0
                && u.torque <= 1.0
                && u.acceleration <= opts.acceleration_limit(j);
            ok &= u.within;
            u
        })
        .collect();
    Ok(LimitCheck { joints, within: ok })
}

/// Where a design starts.
#[derive(Clone, Debug)]
pub enum ExciteFrom {
    /// A base scenario file: its robot, simulation, sensors, processing and experiment are
    /// kept and its excitation replaced; a Fourier excitation's `offset ± amplitude` narrows the
    /// joint ranges.
    Scenario(PathBuf),
    /// A robot (`cheetah3`, a .urdf or a robot TOML) under physid's default scenario (0.3 N m
    /// torque noise, 20 Hz Butterworth, computed-torque tracking).
    Robot(String),
}

/// `excite`'s settings, the CLI's flags; [`ExciteOptions::validate`] checks those it can
/// without the robot (the design's own are checked by [`DesignOptions::validate`]).
#[derive(Clone, Debug)]
pub struct ExciteOptions {
    /// Where the design starts.
    pub from: ExciteFrom,
    /// The written scenario's duration (s).
    pub duration: f64,
    /// Harmonics per joint.
    pub harmonics: usize,
    /// Fundamental frequency (Hz); none: chosen with the limits and the duration
    /// ([`design::Timing::chosen`]).
    pub base_frequency: Option<f64>,
    /// What is maximized.
    pub objective: Objective,
    /// Seed of the random starts and steps.
    pub seed: u64,
    /// Optimization steps per start (0: a random excitation scaled into the limits).
    pub iterations: usize,
    /// Random starts (the best is kept).
    pub starts: usize,
    /// Fraction of every limit left free.
    pub margin: f64,
    /// Acceleration limits (rad/s²), one or one per joint; none: the description's, else
    /// [`design::SAFE_ACCELERATION`].
    pub max_acceleration: Option<Vec<f64>>,
    /// Jerk limits (rad/s³), as `max_acceleration`.
    pub max_jerk: Option<Vec<f64>>,
    /// Rest ramps at both ends (s); none: long enough to fade in the joints' whole ranges
    /// within their limits, at most a quarter of the duration ([`design::Timing::chosen`]).
    pub ramp: Option<f64>,
    /// Samples per period at which the information is evaluated.
    pub samples: usize,
    /// Sample rate of the reference trajectory written to `csv` and `mcap` (Hz).
    pub rate: f64,
    /// The scenario written (TOML), if any.
    pub out: Option<PathBuf>,
    /// The reference trajectory (t, q, q̇, q̈ per joint) as CSV, if any.
    pub csv: Option<PathBuf>,
    /// The reference trajectory as MCAP, if any.
    pub mcap: Option<PathBuf>,
    /// Simulate the design and compare its peaks with the robot's limits.
    pub check: bool,
}

impl Default for ExciteOptions {
    fn default() -> Self {
        let d = DesignOptions::default();
        Self {
            from: ExciteFrom::Robot("cheetah3".into()),
            duration: d.duration,
            harmonics: d.harmonics,
            base_frequency: None,
            objective: d.objective,
            seed: d.seed,
            iterations: d.iterations,
            starts: d.starts,
            margin: d.margin,
            max_acceleration: None,
            max_jerk: None,
            ramp: None,
            samples: d.samples,
            rate: 1000.0,
            out: None,
            csv: None,
            mcap: None,
            check: true,
        }
    }
}

impl ExciteOptions {
    /// The duration and the reference trajectory's rate.
    pub fn validate(&self) -> Result<(), ApiError> {
        if !(self.duration.is_finite() && self.duration > 0.0) {
            return Err(ApiError::invalid_option(
                "duration",
                "a positive number of seconds",
                self.duration,
            ));
        }
        if !(self.rate.is_finite() && self.rate > 0.0 && self.rate <= 1e5) {
            return Err(ApiError::invalid_option(
                "rate",
                "a sample rate in (0, 100000] Hz",
                self.rate,
            ));
        }
        if self.csv.is_some() || self.mcap.is_some() {
            self.check_reference_size()?;
        }
        Ok(())
    }

    /// The reference trajectory `--csv`/`--mcap` would hold: at least [`MIN_REFERENCE`]
    /// samples, and within the memory available (it is built whole before it is written).
    fn check_reference_size(&self) -> Result<(), ApiError> {
        let samples = (self.duration * self.rate).round() + 1.0;
        if samples < MIN_REFERENCE as f64 {
            return Err(ApiError::Options(format!(
                "--rate {} Hz over --duration {} s gives {samples} samples of --csv/--mcap; give a rate of at least {} Hz",
                self.rate,
                self.duration,
                (MIN_REFERENCE as f64 - 1.0) / self.duration
            )));
        }
        // t and q, q̇, q̈, τ per joint (at most a few dozen joints), as numbers and as text.
        let needed = samples * (1.0 + 4.0 * REFERENCE_JOINTS_BOUND) * 8.0 * 3.0;
        match crate::io::available_memory() {
            Some(bytes) if needed > bytes => Err(ApiError::Options(format!(
                "--rate {} Hz over --duration {} s gives {samples:.3e} samples of --csv/--mcap, about {:.1} GB to build, where {:.1} GB are available; lower --rate or --duration",
                self.rate,
                self.duration,
                needed / 1e9,
                bytes / 1e9
            ))),
            _ => Ok(()),
        }
    }

    /// The design's settings for `model` within `range` (the base excitation's, per joint
    /// `(lower, upper)` rad, when it has one), its rate limits defaulted from the description
    /// (the joints defaulted to physid's safe limits are returned, to be told to the user) and
    /// its fundamental and ramps, where not given, chosen with the limits and the duration.
    pub fn design_options(&self, model: &Model, range: Option<&[(f64, f64)]>) -> DesignSettings {
        let (max_acceleration, max_jerk, defaulted) = design::rate_limits(
            model,
            self.max_acceleration.as_deref(),
            self.max_jerk.as_deref(),
        );
        let mut opts = DesignOptions {
            harmonics: self.harmonics,
            base_frequency: self.base_frequency.unwrap_or(FALLBACK_BASE_FREQUENCY),
            objective: self.objective,
            seed: self.seed,
            iterations: self.iterations,
            starts: self.starts,
            margin: self.margin,
            max_acceleration,
            max_jerk,
            ramp: self.ramp.unwrap_or(0.0),
            duration: self.duration,
            samples: self.samples,
        };
        // Limits that cannot be built (a bad option, an empty range) are refused by the
        // design itself, by name, whatever the timing: the placeholders then stay.
        if let Ok(limits) = design::Limits::new(model, range, &opts) {
            let t = Timing::chosen(&limits, self.duration, self.base_frequency, self.ramp);
            (opts.base_frequency, opts.ramp) = (t.base_frequency, t.ramp);
        }
        DesignSettings {
            options: opts,
            defaulted,
        }
    }
}

/// The fundamental (Hz) where the limits cannot choose one.
const FALLBACK_BASE_FREQUENCY: f64 = 0.5;

/// The design's settings for a robot, and which joints' rate limits were defaulted.
#[derive(Clone, Debug)]
pub struct DesignSettings {
    /// The settings.
    pub options: DesignOptions,
    /// Joints without an acceleration or jerk limit in the description, designed within
    /// [`design::SAFE_ACCELERATION`] and [`design::SAFE_JERK`].
    pub defaulted: Vec<String>,
}

/// A designed excitation: the design, the scenario that runs it, its check in simulation.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Excitation {
    /// The robot it was designed for.
    pub model: Model,
    /// The design.
    pub design: Design,
    /// The settings it was made with (rate limits as used).
    pub options: DesignOptions,
    /// The scenario's text: the base's tables as they were, the design as its excitation.
    pub scenario: String,
    /// The check in simulation (none when not asked for).
    pub check: Option<LimitCheck>,
    /// The scenario written to (none when not asked for, or when the check failed: a design
    /// that leaves a limit in simulation is not written, nor is its trajectory).
    pub written: Option<PathBuf>,
}

impl Excitation {
    /// Every simulated peak inside the robot's limits (none: not checked).
    pub fn within_limits(&self) -> Option<bool> {
        self.check.as_ref().map(|c| c.within)
    }

    /// The JSON contract (`excite --json`, schema `physid.excite/1`); `out` is the scenario
    /// asked for, written or not.
    pub fn json(&self, out: Option<PathBuf>) -> ExciteJson {
        ExciteJson {
            design: self.design.clone(),
            out,
            simulated: self.check.as_ref().map(|c| c.joints.clone()),
            within_limits: self.within_limits(),
        }
    }
}

/// Designs an excitation (in the current rayon pool), checks it in simulation when asked and
/// writes the scenario and trajectory when it stays within the limits. Each notice (the
/// loader's warnings, rate limits defaulted) is handed to `notify` as it arises.
pub fn excite(
    opts: &ExciteOptions,
    notify: &mut dyn FnMut(Notice),
) -> Result<Excitation, ApiError> {
    excite_until(opts, notify, &design::Watch::NONE)
}

/// [`excite`], the design telling `watch` of its progress (evaluations of the objective done
/// of their total), ending with [`ApiError::Cancelled`] and nothing written once `watch.stop`
/// returns true (asked between the design's evaluations, which then end, and before anything
/// is written).
pub fn excite_until(
    opts: &ExciteOptions,
    notify: &mut dyn FnMut(Notice),
    watch: &design::Watch<'_>,
) -> Result<Excitation, ApiError> {
    let stop = watch.stop;
    opts.validate()?;
    let base = ExciteBase::load(&opts.from, notify)?;
    let DesignSettings {
        options: design_opts,
        defaulted,
    } = opts.design_options(&base.model, base.range.as_deref());
    if !defaulted.is_empty() {
        notify(Notice::note(format!(
            "the description gives no acceleration or jerk limit for {}: designing within {} rad/s² and {} rad/s³ (give --max-acceleration and --max-jerk)",
            defaulted.join(", "),
            design::SAFE_ACCELERATION,
            design::SAFE_JERK
        )));
    }
    design_opts.validate()?;
    let outputs: Vec<&Path> = [&opts.out, &opts.csv, &opts.mcap]
        .into_iter()
        .flatten()
        .map(PathBuf::as_path)
        .collect();
    let inputs: Vec<&Path> = base.inputs.iter().map(PathBuf::as_path).collect();
    crate::io::check_outputs(&outputs, &inputs)?;
    let d = design::design_watched(&base.model, base.range.as_deref(), &design_opts, watch)?;
    let scenario = base.scenario_text(&d, &design_opts, opts.out.as_deref())?;
    let check = if opts.check {
        let band = 5.0 * opts.harmonics as f64 * design_opts.base_frequency;
        Some(check_in_simulation(
            &base.model,
            &scenario,
            &design_opts,
            band,
        )?)
    } else {
        None
    };
    if stop() {
        return Err(ApiError::Cancelled);
    }
    let written = if check.as_ref().is_none_or(|c| c.within) {
        write_design(opts, &base.model, &d, &scenario)?
    } else {
        None
    };
    Ok(Excitation {
        model: base.model,
        design: d,
        options: design_opts,
        scenario,
        check,
        written,
    })
}

/// The fewest samples a reference trajectory (`--csv`, `--mcap`) is written with.
pub const MIN_REFERENCE: usize = 10;

/// Joints the reference's memory check allows for (the design's robot is not loaded yet when
/// the options are checked; a robot with more joints is still written, at a proportionally
/// larger size).
const REFERENCE_JOINTS_BOUND: f64 = 12.0;

/// Writes the designed `scenario` (`--out`) and its reference trajectory (`--csv`, `--mcap`,
/// sampled once for both, before anything is written); the scenario's path when written.
fn write_design(
    opts: &ExciteOptions,
    model: &Model,
    d: &design::Design,
    scenario: &str,
) -> Result<Option<PathBuf>, ApiError> {
    let reference = (opts.csv.is_some() || opts.mcap.is_some())
        .then(|| reference_trajectory(model, &d.series, opts.duration, opts.rate));
    if let Some(reference) = &reference {
        if let Some(p) = &opts.csv {
            crate::io::samples::write_reference_csv(p, reference)?;
        }
        if let Some(p) = &opts.mcap {
            crate::io::mcap_log::write_reference(p, reference)?;
        }
    }
    let mut written = None;
    if let Some(out) = &opts.out {
        crate::io::write_atomic(out, scenario.as_bytes())?;
        written = Some(out.clone());
    }
    Ok(written)
}

/// The designed reference trajectory (t, q, q̇, q̈ per joint, named by joint; zero torque)
/// sampled at `rate` Hz over `duration` s (an [`Excitation`]'s: its `model`,
/// `design.series` and `options.duration`).
pub fn reference_trajectory(
    model: &Model,
    series: &design::FourierSeries,
    duration: f64,
    rate: f64,
) -> Trajectory {
    let names: Vec<String> = model.joint_names();
    let samples = (duration * rate).round() as usize + 1;
    let mut tr = Trajectory::new(names.clone(), true);
    let zero = vec![0.0; names.len()];
    for k in 0..samples {
        let t = k as f64 / rate;
        let [q, qd, qdd] = series.at(t);
        tr.push(t, &q, &qd, Some(&qdd), &zero);
    }
    tr
}

/// A motion's information measures (`excite --score`): the design's three objectives on the
/// true states of a simulated run.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct MotionScore {
    /// `log det F / r`.
    pub d_optimal: f64,
    /// `log λ_min(F)`.
    pub e_optimal: f64,
    /// The condition number `κ(F)`.
    pub condition: f64,
    /// Samples scored.
    pub samples: usize,
}

/// Simulates the base scenario's own excitation for `opts.duration` s and scores its true
/// states (to compare a motion designed elsewhere); only a scenario has its own excitation.
pub fn score_motion(
    opts: &ExciteOptions,
    notify: &mut dyn FnMut(Notice),
) -> Result<MotionScore, ApiError> {
    opts.validate()?;
    if !matches!(opts.from, ExciteFrom::Scenario(_)) {
        return Err(ApiError::Options(
            "scoring a motion needs a base scenario (its excitation is what is scored)".into(),
        ));
    }
    let base = ExciteBase::load(&opts.from, notify)?;
    let design_opts = opts
        .design_options(&base.model, base.range.as_deref())
        .options;
    design_opts.validate()?;
    let mut sc: crate::sim::scenario::Scenario =
        toml::from_str(&base.text).map_err(|e| ApiError::Options(e.to_string()))?;
    sc.simulation.duration = opts.duration;
    let rec = crate::sim::run(&base.model, &sc, &mut |_| {})
        .map_err(|source| ApiError::DesignedSimulation { source })?;
    let tr = &rec.truth;
    let states = (0..tr.len()).filter_map(|k| Some([tr.q_at(k), tr.qd_at(k), tr.qdd_at(k)?]));
    let [d, e, c] = design::score_states(&base.model, base.range.as_deref(), &design_opts, states)?;
    Ok(MotionScore {
        d_optimal: d,
        e_optimal: e,
        condition: (-c).exp(),
        samples: tr.len(),
    })
}

/// The tracking controller's gains (1/s², 1/s) and whether it feeds the inverse dynamics
/// forward.
#[derive(Clone, Debug)]
struct Gains {
    kp: Vec<f64>,
    kd: Vec<f64>,
    computed_torque: bool,
}

impl Gains {
    /// Computed-torque gains for a robot without a base excitation.
    fn default_for(n: usize) -> Self {
        Gains {
            kp: vec![400.0; n],
            kd: vec![40.0; n],
            computed_torque: true,
        }
    }
}

/// What a design starts from: the robot, the scenario table it goes into, the joint ranges.
struct ExciteBase {
    model: Model,
    /// The scenario's text (the base file's, or physid's defaults for a robot).
    text: String,
    /// The base file's directory (relative robot paths resolve against it).
    dir: PathBuf,
    /// Per joint `(lower, upper)` from a base Fourier excitation.
    range: Option<Vec<(f64, f64)>>,
    /// Gains of the tracking controller.
    gains: Gains,
    /// Files read (no output may replace them).
    inputs: Vec<PathBuf>,
}

impl ExciteBase {
    fn load(from: &ExciteFrom, notify: &mut dyn FnMut(Notice)) -> Result<Self, ApiError> {
        match from {
            ExciteFrom::Scenario(path) => Self::from_scenario(path),
            ExciteFrom::Robot(robot) => Self::from_robot(robot, notify),
        }
    }

    fn from_scenario(path: &Path) -> Result<Self, ApiError> {
        let (sc, model, text) = crate::sim::scenario::load(path)?;
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
                Gains {
                    kp: kp.clone(),
                    kd: kd.clone(),
                    computed_torque: *computed_torque,
                },
            ),
            _ => (None, Gains::default_for(n)),
        };
        Ok(Self {
            model,
            text,
            dir: path.parent().unwrap_or(Path::new("")).to_path_buf(),
            range,
            gains,
            inputs: crate::io::scenario_files(path),
        })
    }

    fn from_robot(robot: &str, notify: &mut dyn FnMut(Notice)) -> Result<Self, ApiError> {
        let (model, warnings) = crate::io::load_robot_with(robot, &Default::default())?;
        for w in warnings {
            notify(Notice::warning(format!("{robot}: {w}")));
        }
        let n = model.dof();
        let robot_table = if robot == "cheetah3" {
            "builtin = \"cheetah3\"".to_string()
        } else {
            format!("urdf = {}", toml::Value::String(robot.to_string()))
        };
        let text = format!(
            "[robot]\n{robot_table}\n\n[simulation]\nduration = 1.0\nrate = 1000.0\nsubsteps = 4\nseed = 1\nfriction_velocity = 0.01\n\n[excitation]\nkind = \"passive\"\n\n[sensors]\ntorque_noise = 0.3\nvelocity_feedback = \"finite_difference\"\n\n[processing]\nmethod = \"butterworth\"\ncutoff = 20.0\norder = 2\n"
        );
        let dir = std::env::current_dir().map_err(|source| crate::io::IoError::Fs {
            path: PathBuf::from("."),
            source,
        })?;
        Ok(Self {
            model,
            text,
            dir,
            range: None,
            gains: Gains::default_for(n),
            inputs: crate::io::robot_files(robot, &[]),
        })
    }

    /// The scenario text with the design as its excitation and `opts.duration` (the base
    /// file's other tables, comments included, as they were); a relative URDF path rewritten
    /// relative to `out`'s folder.
    fn scenario_text(
        &self,
        d: &Design,
        opts: &DesignOptions,
        out: Option<&Path>,
    ) -> Result<String, ApiError> {
        use toml_edit::{value, Item};
        let mut doc: toml_edit::DocumentMut = self
            .text
            .parse()
            .map_err(|e| ApiError::Designed(format!("re-reading the base scenario: {e}")))?;
        let mut ex = self.excitation_table(d);
        ex.decor_mut()
            .set_prefix(format!("\n{}", design_header(d, opts)));
        doc["excitation"] = Item::Table(ex);
        doc["simulation"]["duration"] = value(opts.duration);
        if let Some(u) = doc["robot"].get("urdf").and_then(|v| v.as_str()) {
            let urdf = self.dir.join(u);
            let urdf = urdf.canonicalize().unwrap_or(urdf);
            let out_dir = out
                .and_then(Path::parent)
                .filter(|p| !p.as_os_str().is_empty())
                .unwrap_or(Path::new("."));
            let out_dir = out_dir
                .canonicalize()
                .map_err(|source| crate::io::IoError::Fs {
                    path: out_dir.to_path_buf(),
                    source,
                })?;
            let rel = pathdiff::diff_paths(&urdf, &out_dir).unwrap_or(urdf);
            doc["robot"]["urdf"] = value(rel.display().to_string());
        }
        Ok(doc.to_string())
    }

    /// The `[excitation]` table of a design: its Fourier coefficients and the tracking gains.
    fn excitation_table(&self, d: &Design) -> toml_edit::Table {
        use toml_edit::{value, Array, Item, Table};
        let s = &d.series;
        let list = |v: &[f64]| Array::from_iter(v.iter().copied());
        let rows = |m: &[Vec<f64>]| Array::from_iter(m.iter().map(|r| list(r)));
        let mut ex = Table::new();
        ex["kind"] = value("fourier");
        ex["harmonics"] = value(s.sin.first().map_or(0, |r| r.len()) as i64);
        ex["base_frequency"] = value(s.base_frequency);
        ex["offset"] = value(list(&s.offset));
        ex["kp"] = value(list(&self.gains.kp));
        ex["kd"] = value(list(&self.gains.kd));
        ex["computed_torque"] = value(self.gains.computed_torque);
        if let Some(w) = s.window {
            ex["ramp"] = value(w.ramp);
        }
        if self.gains.computed_torque {
            ex["friction_feedforward"] = value(true);
        }
        let mut c = Table::new();
        c["sin"] = value(rows(&s.sin));
        c["cos"] = value(rows(&s.cos));
        ex["coefficients"] = Item::Table(c);
        ex
    }
}

/// Whether the design was optimized (more evaluations than random starts) or is the best
/// random start.
pub fn design_kind(d: &Design, starts: usize) -> &'static str {
    if d.evaluations > starts {
        "optimized"
    } else {
        "random"
    }
}

/// The comment above a written `[excitation]`: how it was designed and how good it is.
fn design_header(d: &Design, opts: &DesignOptions) -> String {
    let s = &d.series;
    format!(
        "# Designed by `physid excite` (physid {}): {} Fourier excitation, {} harmonics at {} Hz,\n# objective {} = {:.4} (best random start {:.4}), condition number {:.3e}, seed {}, margin {},\n# acceleration limit {:?} rad/s², jerk limit {:?} rad/s³, ramp {} s. {} of {} parameter combinations identifiable. Limits kept and used: `physid excite --json`.\n",
        env!("CARGO_PKG_VERSION"),
        design_kind(d, opts.starts),
        opts.harmonics,
        opts.base_frequency,
        crate::io::serde_name(&d.objective),
        d.value,
        d.start_value,
        d.condition,
        opts.seed,
        opts.margin,
        d.limits.acceleration.iter().map(|x| x / (1.0 - opts.margin)).collect::<Vec<_>>(),
        d.limits.jerk.iter().map(|x| x / (1.0 - opts.margin)).collect::<Vec<_>>(),
        s.window.map_or(0.0, |w| w.ramp),
        d.identifiable,
        d.parameters,
    )
}
