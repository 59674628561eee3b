//! The generalization benchmark: the semi-real benchmark's cases ([`crate::semireal`]) on
//! robots of several makers and sizes, each simulated as a real robot differs from its
//! published description, some robots held out of every tuning decision.
//!
//! For each robot of the benchmark file (`scenarios/generalize.toml`) and seed:
//!
//! - the **real robot** is the published description with each body's inertial parameters
//!   wrong by 10–30 % ([`CAD_ERROR`], drawn per body as [`diagnose::anchor::perturbed_bodies`]
//!   draws them), viscous and Coulomb friction sized by the joint's gravity torque and
//!   simulated as `B_c tanh(q̇ / v_s)` with `v_s` 0.02–0.1 rad/s (not the diagnosis's
//!   `sign q̇`), and a per-joint torque scale of 1 ± 10 % in every log (current sensing,
//!   [`TORQUE_SCALE_ERROR`]);
//! - **two runs of two motions** (finite Fourier series about two centres, at two base
//!   frequencies, [`motion`]) are simulated at the robot's rate with its encoder step and torque
//!   noise, and logged as `t, q, q̇, q̈, τ` (q̇, q̈ the data pipeline's: the semi-real cases
//!   compute injected torques from them and then strip them);
//! - the semi-real benchmark runs on those two runs: each run's description is identified on
//!   the *other* motion from the published description as the prior, then cases are unchanged,
//!   a payload (3–20 % of the robot's mass, [`PAYLOAD_FRACTION`]), the friction changed, or one
//!   library effect, diagnosed from the files a user would give.
//!
//! Scores are kept per robot and pooled separately over the robots used to tune the diagnosis
//! and the robots held out of it ([`RobotEntry::held_out`]).

use crate::semireal::{self, RealCase, RealOptions};
use physid_core::model::Model;
use physid_sim::scenario::{ExcitationSpec, ProcessingSpec, Scenario, SensorSpec, SimulationSpec};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Relative error of each body's inertial parameters in the real robot, uniform in this range.
pub const CAD_ERROR: (f64, f64) = (0.1, 0.3);

/// Each joint's logged torque is the delivered one times a scale uniform in `1 ± this`.
pub const TORQUE_SCALE_ERROR: f64 = 0.1;

/// The real robot's Coulomb regularization velocity `v_s` (rad/s), uniform in this range.
pub const FRICTION_VELOCITY: (f64, f64) = (0.02, 0.1);

/// A payload's mass as a fraction of the robot's total mass, uniform in this range.
pub const PAYLOAD_FRACTION: (f64, f64) = (0.03, 0.2);

/// The benchmark file: the runs' length and the robots.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// Length of each run (s).
    pub duration: f64,
    /// The robots, in report order.
    #[serde(rename = "robot")]
    pub robots: Vec<RobotEntry>,
}

/// One robot of the benchmark.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RobotEntry {
    /// Its name in the tables.
    pub name: String,
    /// Its published description: a URDF path relative to the benchmark file, or a built-in
    /// name (`cheetah3`).
    pub robot: String,
    /// Control and logging rate (Hz).
    pub rate: f64,
    /// Noise on the logged torque (N m, standard deviation).
    pub torque_noise: f64,
    /// Encoder quantization step (rad).
    pub encoder_step: f64,
    /// Kept out of every tuning decision: reported apart.
    pub held_out: bool,
}

/// The benchmark file that could not be read, or a robot that could not be run.
#[derive(Debug, thiserror::Error)]
pub enum GeneralizeError {
    /// Reading a file.
    #[error("{0}")]
    Io(#[from] physid_io::IoError),
    /// A value of the benchmark file out of its range.
    #[error("{path}: {key}: {message}")]
    Invalid {
        /// The benchmark file.
        path: PathBuf,
        /// The key (`robot[2].rate`).
        key: String,
        /// What is wrong.
        message: String,
    },
    /// A robot's run could not be simulated.
    #[error("robot '{robot}', {run}: {source}")]
    Simulation {
        /// The robot.
        robot: String,
        /// Which run.
        run: String,
        /// The failure.
        source: physid_sim::simulate::SimError,
    },
    /// The semi-real machinery on a robot's runs (descriptions, cases, tables).
    #[error("robot '{robot}': {source}")]
    Real {
        /// The robot.
        robot: String,
        /// The failure.
        source: semireal::RealError,
    },
}

impl Spec {
    /// Reads and checks the benchmark file at `path`; robot paths are made relative to it.
    pub fn load(path: &Path) -> Result<Spec, GeneralizeError> {
        let text = physid_io::read_to_string(path)?;
        let mut spec: Spec =
            toml::from_str(&text).map_err(|e| physid_io::IoError::invalid(path, e.to_string()))?;
        spec.validate(path)?;
        let dir = path.parent().unwrap_or(Path::new("."));
        for r in &mut spec.robots {
            if r.robot != "cheetah3" {
                r.robot = dir.join(&r.robot).to_string_lossy().into_owned();
            }
        }
        Ok(spec)
    }

    /// Every value in its range, names unique.
    fn validate(&self, path: &Path) -> Result<(), GeneralizeError> {
        let bad = |key: String, message: String| GeneralizeError::Invalid {
            path: path.to_path_buf(),
            key,
            message,
        };
        let d = self.duration;
        if !(d.is_finite() && (5.0..=600.0).contains(&d)) {
            return Err(bad("duration".into(), format!("{d} s: give 5 to 600 s")));
        }
        if self.robots.is_empty() {
            return Err(bad("robot".into(), "no [[robot]] table".into()));
        }
        for (i, r) in self.robots.iter().enumerate() {
            let key = |k: &str| format!("robot[{i}].{k}");
            let checks = [
                (
                    "rate",
                    r.rate,
                    (50.0..=10_000.0).contains(&r.rate),
                    "50 to 10000 Hz",
                ),
                (
                    "torque_noise",
                    r.torque_noise,
                    r.torque_noise >= 0.0,
                    ">= 0 N m",
                ),
                (
                    "encoder_step",
                    r.encoder_step,
                    r.encoder_step >= 0.0,
                    ">= 0 rad",
                ),
            ];
            for (k, v, ok, range) in checks {
                if !(v.is_finite() && ok) {
                    return Err(bad(key(k), format!("{v}: give {range}")));
                }
            }
            if r.name.trim().is_empty() || self.robots[..i].iter().any(|o| o.name == r.name) {
                return Err(bad(key("name"), format!("'{}': empty or repeated", r.name)));
            }
        }
        Ok(())
    }
}

/// The real robot behind a published description: what the simulator runs.
#[derive(Clone, Debug)]
pub struct RealRobot {
    /// Its true inertial parameters and friction.
    pub model: Model,
    /// Its Coulomb regularization velocity `v_s` (rad/s).
    pub friction_velocity: f64,
    /// Each joint's logged torque over the delivered one.
    pub torque_scale: Vec<f64>,
}

/// The real robot of `cad` drawn from `rng`: body errors in [`CAD_ERROR`], friction per joint
/// (Coulomb 3–8 % and viscous 2–6 % per rad/s of the joint's gravity torque scale
/// [`gravity_scale`]), `v_s` in [`FRICTION_VELOCITY`], torque scales in
/// `1 ± TORQUE_SCALE_ERROR`.
pub fn real_robot(cad: &Model, rng: &mut ChaCha8Rng) -> RealRobot {
    let uniform = |rng: &mut ChaCha8Rng, (lo, hi): (f64, f64)| lo + (hi - lo) * rng.random::<f64>();
    let bodies = physid_diagnose::anchor::perturbed_bodies(cad, rng, |r| uniform(r, CAD_ERROR));
    let scale = gravity_scale(cad, &motion(cad, 0));
    let friction: Vec<(f64, f64)> = scale
        .iter()
        .map(|s| {
            (
                uniform(rng, (0.02, 0.06)) * s,
                uniform(rng, (0.03, 0.08)) * s,
            )
        })
        .collect();
    let model = bodies
        .with_bodies_edited(|j, b| {
            (b.friction.viscous, b.friction.coulomb) = friction[j];
        })
        .expect("non-negative friction keeps a valid model valid");
    RealRobot {
        model,
        friction_velocity: uniform(rng, FRICTION_VELOCITY),
        torque_scale: (0..cad.dof())
            .map(|_| uniform(rng, (1.0 - TORQUE_SCALE_ERROR, 1.0 + TORQUE_SCALE_ERROR)))
            .collect(),
    }
}

/// Each joint's gravity torque scale (N m or N): the RMS of `g(q)` over 64 poses spread over
/// the motion's box (`offset ± amplitude`, a fixed quasi-random sequence), at least a tenth of
/// the largest joint's (a vertical first axis carries no gravity, yet has friction).
pub fn gravity_scale(model: &Model, motion: &ExcitationSpec) -> Vec<f64> {
    let ExcitationSpec::Fourier {
        amplitude, offset, ..
    } = motion
    else {
        return vec![1.0; model.dof()];
    };
    let n = model.dof();
    let mut data = physid_core::dynamics::Data::new(model);
    let zero = vec![0.0; n];
    let mut sum = vec![0.0; n];
    const POSES: usize = 64;
    for k in 0..POSES {
        let q: Vec<f64> = (0..n)
            .map(|j| {
                // Additive recurrence with an irrational step per joint: spread, reproducible.
                let u = ((k + 1) as f64 * (2.0f64.sqrt() + j as f64).fract()).fract();
                offset[j] + amplitude[j] * (2.0 * u - 1.0)
            })
            .collect();
        let g = physid_core::dynamics::rnea(model, &mut data, &q, &zero, &zero);
        sum.iter_mut().zip(g.iter()).for_each(|(s, g)| *s += g * g);
    }
    let rms: Vec<f64> = sum.iter().map(|s| (s / POSES as f64).sqrt()).collect();
    let floor = 0.1 * rms.iter().cloned().fold(0.0, f64::max);
    rms.iter().map(|r| r.max(floor).max(1e-3)).collect()
}

/// Motion `which` (0 or 1) of `model`: a finite Fourier series per joint about the middle of its
/// range (motion 1: shifted a tenth of the range up), with an excursion of 30 % of the range at
/// most 0.8 rad (motion 1: 25 %, 0.6 rad; unlimited joints 0.8 / 0.6 rad about 0 / 0.3), five
/// harmonics of 0.1 Hz (motion 1: four of 0.14 Hz), tracked by computed torque.
pub fn motion(model: &Model, which: usize) -> ExcitationSpec {
    let (share, most, shift, harmonics, f0) = if which == 0 {
        (0.3, 0.8, 0.0, 5, 0.1)
    } else {
        (0.25, 0.6, 0.1, 4, 0.14)
    };
    let (mut offset, mut amplitude) = (vec![], vec![]);
    for b in model.bodies() {
        let (lo, hi) = (b.limits.lower, b.limits.upper);
        if lo.is_finite() && hi.is_finite() {
            let range = hi - lo;
            offset.push(0.5 * (lo + hi) + shift * range);
            amplitude.push((share * range).min(most));
        } else {
            offset.push(3.0 * shift);
            amplitude.push(most);
        }
    }
    let n = model.dof();
    ExcitationSpec::Fourier {
        harmonics,
        base_frequency: f0,
        amplitude,
        offset,
        coefficients: None,
        ramp: None,
        friction_feedforward: false,
        kp: vec![150.0; n],
        kd: vec![25.0; n],
        computed_torque: true,
    }
}

/// The scenario of `robot`'s run of motion `which` (seed `seed`) on the real robot `real`.
fn scenario(
    entry: &RobotEntry,
    duration: f64,
    cad: &Model,
    real: &RealRobot,
    (which, seed): (usize, u64),
) -> Scenario {
    Scenario {
        robot: Default::default(),
        simulation: SimulationSpec {
            duration,
            rate: entry.rate,
            substeps: (4000.0 / entry.rate).ceil().max(4.0) as usize,
            engine: Default::default(),
            integrator: None,
            seed,
            friction_velocity: real.friction_velocity,
            initial_q: None,
            max_speed: 200.0,
        },
        excitation: motion(cad, which),
        sensors: SensorSpec {
            encoder_step: entry.encoder_step,
            torque_noise: entry.torque_noise,
            ..Default::default()
        },
        processing: ProcessingSpec {
            cutoff: (0.2 * entry.rate).min(20.0),
            ..Default::default()
        },
        effects: vec![physid_effect::TorqueGain::spec(real.torque_scale.clone())],
        experiment: None,
    }
}

/// The runs of `entry` for `seed`, simulated on its real robot and written into `dir` as
/// `<name>_motion_a.csv` and `<name>_motion_b.csv` (`t`, encoder `q`, the pipeline's `q̇`, `q̈`,
/// logged `τ`).
pub fn simulate_runs(
    entry: &RobotEntry,
    duration: f64,
    cad: &Model,
    seed: u64,
    dir: &Path,
) -> Result<Vec<PathBuf>, GeneralizeError> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let real = real_robot(cad, &mut rng);
    physid_io::create_dir_all(dir)?;
    let mut paths = vec![];
    for (which, label) in ["a", "b"].iter().enumerate() {
        let run_seed = seed.wrapping_mul(1_000_003).wrapping_add(which as u64);
        let sc = scenario(entry, duration, cad, &real, (which, run_seed));
        let sim_err = |source| GeneralizeError::Simulation {
            robot: entry.name.clone(),
            run: format!("motion {label}"),
            source,
        };
        sc.validate(cad.dof()).map_err(|e| sim_err(e.into()))?;
        let rec = physid_sim::run(&real.model, &sc, &mut |_| {}).map_err(sim_err)?;
        let path = dir.join(format!("{}_motion_{label}.csv", entry.name));
        physid_io::samples::write_csv(&path, &as_logged(&rec))?;
        paths.push(path);
    }
    Ok(paths)
}

/// The run as a robot logs it with its own derivative estimates: encoder `q`, logged `τ`, the
/// processed `q̇`, `q̈`.
fn as_logged(rec: &physid_core::trajectory::Recording) -> physid_core::trajectory::Trajectory {
    let (m, p) = (&rec.measured, &rec.processed);
    let mut out = physid_core::trajectory::Trajectory::new(m.joint_names.clone(), true);
    for k in 0..m.len().min(p.len()) {
        out.push(m.t[k], m.q_at(k), p.qd_at(k), p.qdd_at(k), m.tau_at(k));
    }
    out
}

/// One case of the benchmark with its robot.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct Case {
    /// The robot's name.
    pub robot: String,
    /// Held out of tuning.
    pub held_out: bool,
    /// The seed of its real robot and runs.
    pub seed: u64,
    /// The semi-real case.
    #[serde(flatten)]
    pub case: RealCase,
}

/// The semi-real bases of one robot and seed: the runs simulated into `dir`, each described by
/// the other, payload masses sized by the robot.
pub fn bases(
    entry: &RobotEntry,
    duration: f64,
    seed: u64,
    opts: &RealOptions,
    dir: &Path,
) -> Result<Vec<semireal::Base>, GeneralizeError> {
    let cad = physid_io::load_robot(&entry.robot)?;
    let paths = simulate_runs(entry, duration, &cad, seed, dir)?;
    let real_err = |source| GeneralizeError::Real {
        robot: entry.name.clone(),
        source,
    };
    let mut bases = semireal::bases(&cad, &paths, opts).map_err(real_err)?;
    let mass = cad.total_mass();
    for b in &mut bases {
        b.payload_mass = (PAYLOAD_FRACTION.0 * mass, PAYLOAD_FRACTION.1 * mass);
    }
    Ok(bases)
}

/// The cases of every robot and seed: each robot's bases first, then `cases` semi-real cases
/// per robot and seed (case `i`: base `i mod 2`, slot `i mod 11`), all in parallel on the
/// current rayon pool; each case's files under `work/<robot>/seed<S>/case<i>`; `done` sees each
/// finished case.
pub fn run(
    spec: &Spec,
    seeds: &[u64],
    cases: usize,
    opts: &RealOptions,
    work: &Path,
    done: &(dyn Fn(&Case) + Sync),
) -> Result<Vec<Case>, GeneralizeError> {
    use rayon::prelude::*;
    let runs: Vec<(&RobotEntry, u64)> = (spec.robots.iter())
        .flat_map(|r| seeds.iter().map(move |&s| (r, s)))
        .collect();
    let folder = |r: &RobotEntry, s: u64| work.join(&r.name).join(format!("seed{s}"));
    let all_bases = runs
        .par_iter()
        .map(|&(r, s)| bases(r, spec.duration, s, opts, &folder(r, s)))
        .collect::<Result<Vec<_>, _>>()?;
    let dopts = opts.diagnose_options();
    let jobs: Vec<(usize, usize)> = (0..runs.len())
        .flat_map(|k| (0..cases).map(move |i| (k, i)))
        .collect();
    jobs.par_iter()
        .map(|&(k, i)| {
            let (r, s) = runs[k];
            let dir = folder(r, s).join(format!("case{i}"));
            let case = semireal::run_case(i, s, &all_bases[k], &dopts, &dir).map_err(|source| {
                GeneralizeError::Real {
                    robot: r.name.clone(),
                    source,
                }
            })?;
            let case = Case {
                robot: r.name.clone(),
                held_out: r.held_out,
                seed: s,
                case,
            };
            done(&case);
            Ok(case)
        })
        .collect()
}

/// Scores over a group of cases (one robot, or the tuning or held-out robots pooled).
#[derive(Clone, Debug, Default, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct GroupScores {
    /// Cases.
    pub cases: usize,
    /// Unchanged runs (of another motion than the description's).
    pub unchanged: usize,
    /// Fraction of them with no payload or body change named by any step.
    pub unchanged_no_body_claim: f64,
    /// Fraction of them with no step at all.
    pub unchanged_no_claim: f64,
    /// Payload cases.
    pub payload: usize,
    /// Fraction whose first step is a payload on its body.
    pub payload_named_first: f64,
    /// Fraction whose payload mass on that body is within 25 % of the truth.
    pub payload_mass_within_25: f64,
    /// Median relative error of the payload mass, where found.
    pub median_payload_mass_error: f64,
    /// Cases with one library effect injected that the run shows: the description's torque RMS
    /// raised at least `semireal::VISIBLE.0` times ([`RealCase::growth`]; an effect the
    /// robot's own gap hides after [`semireal::MAX_DRAWS`] draws is a test of the draw).
    pub effect: usize,
    /// Fraction of them whose first step names it (or is tied with it).
    pub effect_top1: f64,
    /// Library-effect cases the run does not show (left out of `effect`).
    pub effect_hidden: usize,
    /// Cases with the friction changed.
    pub friction: usize,
    /// Fraction whose first step is friction re-identified.
    pub friction_top1: f64,
    /// Cases without a payload, and the fraction with no step naming a body.
    pub without_payload_no_body_step: f64,
}

/// The scores of `cases`.
pub fn group_scores<'a>(cases: impl IntoIterator<Item = &'a Case>) -> GroupScores {
    let cases: Vec<&RealCase> = cases.into_iter().map(|c| &c.case).collect();
    let of = |name: &str| -> Vec<&RealCase> {
        cases
            .iter()
            .copied()
            .filter(|c| c.injected == name)
            .collect()
    };
    let (unchanged, payload, friction) = (of("clean"), of("payload"), of("friction_changed"));
    let (effect, hidden): (Vec<&RealCase>, Vec<&RealCase>) = (cases.iter().copied())
        .filter(|c| !["clean", "payload", "friction_changed"].contains(&c.injected.as_str()))
        .partition(|c| c.growth >= semireal::VISIBLE.0);
    let names_body = |c: &RealCase| c.found.iter().any(|s| semireal::names_a_body(s));
    let top1 =
        |v: &[&RealCase]| physid_experiment::fraction(v.iter().map(|c| c.top1 == Some(true)));
    let mass_err: Vec<f64> = payload.iter().filter_map(|c| c.magnitude_error).collect();
    GroupScores {
        cases: cases.len(),
        unchanged: unchanged.len(),
        unchanged_no_body_claim: physid_experiment::fraction(
            unchanged.iter().map(|c| !names_body(c)),
        ),
        unchanged_no_claim: physid_experiment::fraction(
            unchanged.iter().map(|c| c.found.is_empty()),
        ),
        payload: payload.len(),
        payload_named_first: top1(&payload),
        payload_mass_within_25: physid_experiment::fraction(
            (payload.iter())
                .map(|c| c.top1 == Some(true) && c.magnitude_error.is_some_and(|e| e <= 0.25)),
        ),
        median_payload_mass_error: physid_experiment::median(&mass_err),
        effect: effect.len(),
        effect_top1: top1(&effect),
        effect_hidden: hidden.len(),
        friction: friction.len(),
        friction_top1: top1(&friction),
        without_payload_no_body_step: physid_experiment::fraction(
            (cases.iter())
                .filter(|c| c.injected != "payload")
                .map(|c| !names_body(c)),
        ),
    }
}

/// One robot's scores.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct RobotScores {
    /// The robot.
    pub robot: String,
    /// Held out of tuning.
    pub held_out: bool,
    /// Its scores.
    #[serde(flatten)]
    pub scores: GroupScores,
}

/// The benchmark's scores: per robot, and pooled over the tuning and the held-out robots.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct Scores {
    /// Per robot, in the benchmark file's order.
    pub robots: Vec<RobotScores>,
    /// The robots the diagnosis was tuned on, pooled.
    pub tuning: GroupScores,
    /// The robots held out of tuning, pooled.
    pub held_out: GroupScores,
}

/// The scores of `cases` of the robots of `spec`.
pub fn score(spec: &Spec, cases: &[Case]) -> Scores {
    let robots = (spec.robots.iter())
        .map(|r| RobotScores {
            robot: r.name.clone(),
            held_out: r.held_out,
            scores: group_scores(cases.iter().filter(|c| c.robot == r.name)),
        })
        .collect();
    Scores {
        robots,
        tuning: group_scores(cases.iter().filter(|c| !c.held_out)),
        held_out: group_scores(cases.iter().filter(|c| c.held_out)),
    }
}

/// The per-robot table: one row per robot, then the tuning and held-out pools.
pub fn score_table(scores: &Scores) -> polars::prelude::PolarsResult<polars::prelude::DataFrame> {
    use polars::prelude::*;
    let rows: Vec<(String, &GroupScores)> = (scores.robots.iter())
        .map(|r| {
            let tag = if r.held_out { " (held out)" } else { "" };
            (format!("{}{tag}", r.robot), &r.scores)
        })
        .chain([
            ("all tuning robots".to_string(), &scores.tuning),
            ("all held-out robots".to_string(), &scores.held_out),
        ])
        .collect();
    let col = |f: &dyn Fn(&GroupScores) -> f64| rows.iter().map(|(_, s)| f(s)).collect::<Vec<_>>();
    let count = |f: &dyn Fn(&GroupScores) -> usize| {
        rows.iter().map(|(_, s)| f(s) as u64).collect::<Vec<_>>()
    };
    df!(
        "robot" => rows.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>(),
        "cases" => count(&|s| s.cases),
        "unchanged: no body claimed" => col(&|s| s.unchanged_no_body_claim),
        "unchanged: nothing claimed" => col(&|s| s.unchanged_no_claim),
        "payload named first" => col(&|s| s.payload_named_first),
        "payload mass within 25 %" => col(&|s| s.payload_mass_within_25),
        "effect top-1" => col(&|s| s.effect_top1),
        "effects hidden" => count(&|s| s.effect_hidden),
        "friction top-1" => col(&|s| s.friction_top1),
        "no payload: no body step" => col(&|s| s.without_payload_no_body_step),
    )
}

/// Writes `cases.csv`, `README.md` (command, the per-robot table, the cases) and `scores.json`
/// into `dir`.
pub fn write(
    dir: &Path,
    cases: &[Case],
    scores: &Scores,
    command: &str,
    wall: f64,
) -> Result<(), semireal::RealError> {
    physid_io::write_result_dir(dir, physid_io::SCORES_MARK, |staged| {
        write_files(staged, cases, scores, command, wall)
    })
}

/// The files of [`write`] written into `dir`.
fn write_files(
    dir: &Path,
    cases: &[Case],
    scores: &Scores,
    command: &str,
    wall: f64,
) -> Result<(), semireal::RealError> {
    use polars::prelude::*;
    let real: Vec<RealCase> = cases.iter().map(|c| c.case.clone()).collect();
    let mut df = semireal::case_table(&real)?;
    df.insert_column(
        0,
        Column::new(
            "robot".into(),
            cases.iter().map(|c| c.robot.clone()).collect::<Vec<_>>(),
        ),
    )?;
    df.insert_column(
        1,
        Column::new(
            "held_out".into(),
            cases.iter().map(|c| c.held_out).collect::<Vec<_>>(),
        ),
    )?;
    df.insert_column(
        2,
        Column::new(
            "seed".into(),
            cases.iter().map(|c| c.seed).collect::<Vec<_>>(),
        ),
    )?;
    physid_experiment::tables::write_csv(&dir.join("cases.csv"), &mut df)?;
    let md = format!(
        "# Generalization benchmark\n\n`{command}` ({wall:.0} s wall).\n\nEach robot simulated as a real robot differs from its published description (docs/diagnose.md, \"Generalization benchmark\"); the description identified on one motion, the case on the other. Robots marked held out were kept out of every tuning decision.\n\n## Scores by robot\n\n{}\n## Scores\n\n```json\n{}\n```\n\n## Cases\n\n{}",
        physid_experiment::tables::markdown(&score_table(scores)?),
        serde_json::to_string_pretty(scores)?,
        physid_experiment::tables::markdown(&df)
    );
    physid_io::write_atomic(&dir.join("README.md"), md.as_bytes())?;
    physid_io::write_atomic(
        &dir.join("scores.json"),
        serde_json::to_string_pretty(&physid_io::versioned("generalize_scores", scores))?
            .as_bytes(),
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec_text(robot: &str) -> String {
        format!("duration = 10.0\n[[robot]]\nname = \"leg\"\nrobot = \"cheetah3\"\n{robot}held_out = true\n")
    }

    fn load(text: &str) -> Result<Spec, GeneralizeError> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bench.toml");
        std::fs::write(&path, text).unwrap();
        Spec::load(&path)
    }

    #[test]
    fn the_benchmark_file_s_values_are_checked_by_key() {
        let ok = "rate = 1000.0\ntorque_noise = 0.3\nencoder_step = 0.0\n";
        assert_eq!(load(&spec_text(ok)).unwrap().robots[0].robot, "cheetah3");
        let cases = [
            (spec_text(ok).replace("10.0", "1e9"), "duration"),
            (spec_text(&ok.replace("1000.0", "10.0")), "robot[0].rate"),
            (
                spec_text(&ok.replace("0.3", "nan")),
                "robot[0].torque_noise",
            ),
            (
                spec_text(&ok.replace("step = 0.0", "step = -1.0")),
                "robot[0].encoder_step",
            ),
            (spec_text(&format!("{ok}colour = 1\n")), "colour"),
            ("duration = 10.0\n".into(), "robot"),
            (
                format!(
                    "{}{}",
                    spec_text(ok),
                    spec_text(ok).replace("duration = 10.0\n", "")
                ),
                "robot[1].name",
            ),
        ];
        for (text, key) in cases {
            let err = load(&text).expect_err(key).to_string();
            assert!(
                err.contains("bench.toml") && err.contains(key),
                "{key}: {err}"
            );
        }
    }

    #[test]
    fn a_real_robot_differs_from_its_description_within_the_stated_ranges() {
        let cad = physid_core::model::cheetah3::leg();
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let real = real_robot(&cad, &mut rng);
        for (c, r) in cad.bodies().iter().zip(real.model.bodies()) {
            let ratio = r.inertia.mass() / c.inertia.mass();
            // J + ε J^½ G J^½ at ε ≤ 0.3: the mass moves by ε times a unit Gaussian.
            assert!(
                ratio != 1.0 && (ratio - 1.0).abs() < 1.5,
                "mass ratio {ratio}"
            );
            assert!(r.inertia.pseudo_inertia().symmetric_eigenvalues().min() > 0.0);
            assert!(r.friction.coulomb > 0.0 && r.friction.viscous > 0.0);
        }
        assert!(real
            .torque_scale
            .iter()
            .all(|s| (s - 1.0).abs() <= TORQUE_SCALE_ERROR));
        let v = real.friction_velocity;
        assert!((FRICTION_VELOCITY.0..=FRICTION_VELOCITY.1).contains(&v));
        // Same seed, same robot.
        let again = real_robot(&cad, &mut ChaCha8Rng::seed_from_u64(7));
        assert_eq!(again.model.parameters(), real.model.parameters());
    }

    #[test]
    fn the_two_motions_stay_within_the_joint_limits_and_differ() {
        let urdf = physid_io::load_robot(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../../data/so100/so100.urdf")
                .to_string_lossy(),
        )
        .unwrap();
        let (a, b) = (motion(&urdf, 0), motion(&urdf, 1));
        assert_ne!(a, b);
        for m in [a, b] {
            let ExcitationSpec::Fourier {
                amplitude, offset, ..
            } = m
            else {
                panic!("a Fourier motion")
            };
            for (j, body) in urdf.bodies().iter().enumerate() {
                let l = body.limits;
                assert!(offset[j] - amplitude[j] >= l.lower && offset[j] + amplitude[j] <= l.upper);
            }
        }
        // Gravity scales: positive, the vertical first axis floored at a tenth of the largest.
        let g = gravity_scale(&urdf, &motion(&urdf, 0));
        let most = g.iter().cloned().fold(0.0, f64::max);
        assert!(
            g.iter().all(|&x| x >= 0.1 * most - 1e-12) && most > 0.05,
            "{g:?}"
        );
    }
}
