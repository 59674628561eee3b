//! The semi-real blind benchmark: real logs as the base, one withheld change injected on top.
//!
//! The simulated benchmark ([`crate::blind`]) cannot see what real data bring: a residual with
//! its own structure (the robot's standing friction and offsets, the recording tool's filters,
//! jitter), and a description that is itself an identified model. Here every case starts from
//! a real run:
//!
//! - the **description** is identified on *another* run of the same robot (the nominal fit
//!   of the diagnosis, constraint set `consistent`, viscous and Coulomb friction), and written
//!   as the URDF the user would give;
//! - one **change** is injected into the real run (or none: the untouched run is the clean
//!   case): a payload on a random body (its torque `Y_b(q, q̇, q̈) π_p` from the logged motion,
//!   the inverse dynamics of the payload alone), the friction changed (the description's
//!   viscous and Coulomb terms scaled), a torque gain or offset and a delay
//!   ([`physid_sim::effects::logged_torque`], whole samples), a base tilt (the description's
//!   gravity torque under the tilted gravity minus its own), and compliance or backlash read
//!   on the motor side ([`physid_sim::effects::logged_angle`]);
//! - the case is written as a robot writes it (`t`, `q`, `τ` only: velocities and
//!   accelerations are the pipeline's to derive), diagnosed from those files with the
//!   description's stated uncertainty, and scored on what the ladder from the description
//!   names first.
//!
//! Case `i` takes base run `i mod runs` and slot `i mod 11` ([`slots`]), drawn from
//! `ChaCha8(seed, stream i)`.

use physid_core::model::Model;
use physid_diagnose::{self as diagnose, Diagnosis, Verdict};
use physid_effect::library::Kind;
use physid_experiment::tables;
use physid_io::prepare::Logged;
use physid_sim::effects;
use physid_sim::scenario::EffectSpec;
use polars::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use std::path::{Path, PathBuf};

mod inject;
mod score;
pub use inject::*;
pub use score::*;

/// What a slot injects.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Slot {
    /// The real run untouched.
    Clean,
    /// A payload on a random body.
    Payload,
    /// Every joint's viscous and Coulomb friction scaled.
    Friction,
    /// One effect of the library.
    Effect(Kind),
}

/// The cycle of slots: two clean, two payloads, the friction changed, then one per effect
/// kind injected on real logs (`Kind::semi_real_singles`).
pub fn slots() -> Vec<Slot> {
    let mut out = vec![
        Slot::Clean,
        Slot::Clean,
        Slot::Payload,
        Slot::Payload,
        Slot::Friction,
    ];
    out.extend(Kind::semi_real_singles().into_iter().map(Slot::Effect));
    out
}

impl Slot {
    /// The name in the case table.
    pub fn name(&self) -> &'static str {
        match self {
            Slot::Clean => "clean",
            Slot::Payload => "payload",
            Slot::Friction => "friction_changed",
            Slot::Effect(k) => k.name(),
        }
    }
}

/// A real run the cases start from.
#[derive(Clone, Debug)]
pub struct Base {
    /// Its file (for the case table).
    pub path: PathBuf,
    /// The run as logged: it must carry `q̇` and `q̈` (the injected torques are computed from
    /// the logged motion).
    pub logged: Logged,
    /// The description identified on another run.
    pub description: Model,
    /// Which run the description was identified on.
    pub described_by: PathBuf,
    /// The description's information from that run ([`diagnose::anchor::information`]),
    /// written into each case's sidecar and read back from it.
    pub information: physid_ident::information::Information,
    /// That run's calibration, in the "what changed" mode.
    pub baseline: Option<diagnose::baseline::Baseline>,
    /// The description's torque RMS on the untouched run read as a robot writes it (N m,
    /// [`description_rms`]): the standing gap an injected effect is made visible above.
    pub rms: f64,
    /// The payload masses drawn on this robot (kg, `lo..hi`; the KUKA's
    /// [`physid_effect::PAYLOAD_MASS`] unless the robot's size asks for others).
    pub payload_mass: (f64, f64),
}

/// What a semi-real benchmark is asked for.
#[derive(Clone, Debug, PartialEq)]
pub struct RealOptions {
    /// Number of cases (at least 1).
    pub cases: usize,
    /// Seed of every draw.
    pub seed: u64,
    /// The description's relative uncertainty the diagnosis is told (> 0).
    pub description_uncertainty: f64,
    /// "What changed" mode: the run the description was identified on is also given as the
    /// baseline ([`diagnose::baseline::what_changed`]), so the robot's standing effects cancel.
    pub baseline: bool,
}

impl RealOptions {
    /// Checks every value against its range.
    pub fn validate(&self) -> Result<(), RealError> {
        if self.cases == 0 || self.cases > MAX_CASES {
            return Err(RealError::InvalidOption {
                option: "cases",
                expected: "in 1..=100000",
                value: self.cases as f64,
            });
        }
        let e = self.description_uncertainty;
        if !(e.is_finite() && e > 0.0) {
            return Err(RealError::InvalidOption {
                option: "description_uncertainty",
                expected: "a positive fraction (0.05 = 5 %)",
                value: e,
            });
        }
        Ok(())
    }

    /// The diagnosis's options for every case.
    pub fn diagnose_options(&self) -> diagnose::Options {
        diagnose::Options {
            description_uncertainty: Some(self.description_uncertainty),
            ..Default::default()
        }
    }
}

/// At most this many cases.
pub const MAX_CASES: usize = 100_000;

/// A semi-real case or its report that could not be made.
#[derive(Debug, thiserror::Error)]
pub enum RealError {
    /// An option out of its range.
    #[error("{option} must be {expected}, got {value}")]
    InvalidOption {
        /// The option.
        option: &'static str,
        /// Its range.
        expected: &'static str,
        /// The value given.
        value: f64,
    },
    /// Fewer than two runs: the description must come from another run.
    #[error("the semi-real benchmark needs at least two runs (the description is identified on another run than the case's), got {0}")]
    TooFewRuns(usize),
    /// A base run without logged velocities or accelerations.
    #[error("{}: the semi-real benchmark computes the injected torques from the logged motion and needs its q̇ and q̈ columns", .0.display())]
    NoAccelerations(PathBuf),
    /// Reading or writing a file.
    #[error("{0}")]
    Io(#[from] physid_io::IoError),
    /// The description's identification or a case's diagnosis.
    #[error("{context}: {source}")]
    Diagnose {
        /// Which case or description.
        context: String,
        /// The failure.
        source: diagnose::DiagnoseError,
    },
    /// Building the case table.
    #[error("case table: {0}")]
    Table(#[from] PolarsError),
    /// Serializing the scores.
    #[error("scores: {0}")]
    Json(#[from] serde_json::Error),
}

physid_core::options::option_error!(RealError);

/// The nominal fit of `robot` on the `runs` of the recording `other` with its information
/// (`at`: the fitted parameters), and the description it makes.
fn described(
    robot: &Model,
    runs: &[physid_core::trajectory::Trajectory],
    other: &Path,
    dopts: &diagnose::Options,
) -> Result<(physid_ident::information::Information, Model), RealError> {
    let data = physid_core::trajectory::Trajectory::concatenate(runs.to_vec())
        .ok_or(RealError::TooFewRuns(0))?;
    let information = diagnose::anchor::information(robot, &data, dopts).map_err(|source| {
        RealError::Diagnose {
            context: format!("the description from {}", other.display()),
            source,
        }
    })?;
    let description = robot
        .with_parameters(&information.at)
        .map_err(|e| RealError::Io(physid_io::IoError::invalid(other, e.to_string())))?;
    Ok((information, description))
}

/// The run at `path` as logged, checked before any work: its q̇ and q̈ logged (the injected
/// torques are computed from them) and at least [`MIN_RUN`] samples.
fn checked_run(robot: &Model, path: &Path) -> Result<physid_io::prepare::Logged, RealError> {
    let (logged, _, _) = physid_io::load_logged(path, robot, &physid_io::DataOptions::default())?;
    if logged.qd.is_none() || logged.qdd.is_none() {
        return Err(RealError::NoAccelerations(path.to_path_buf()));
    }
    if logged.len() < MIN_RUN {
        return Err(RealError::Io(physid_io::IoError::invalid(
            path,
            format!(
                "{} samples: a run of the semi-real benchmark needs at least {MIN_RUN} (each case's diagnosis holds out a part of it and needs {} training samples)",
                logged.len(),
                diagnose::MIN_SAMPLES
            ),
        )));
    }
    Ok(logged)
}

/// The fewest samples a base run may have: ten times what a diagnosis trains on at least,
/// so that its holdout and trimmed ends leave enough.
pub const MIN_RUN: usize = 10 * diagnose::MIN_SAMPLES;

/// The bases of `paths` on `robot`: each run's description identified on the next run
/// (cyclically) by the diagnosis's nominal fit.
pub fn bases(robot: &Model, paths: &[PathBuf], opts: &RealOptions) -> Result<Vec<Base>, RealError> {
    if paths.len() < 2 {
        return Err(RealError::TooFewRuns(paths.len()));
    }
    let roles: Vec<(&str, &Path)> = paths.iter().map(|p| ("--real", p.as_path())).collect();
    physid_io::check_distinct_recordings(&roles)?;
    let dopts = opts.diagnose_options();
    let mut logs = paths
        .iter()
        .map(|path| checked_run(robot, path))
        .collect::<Result<Vec<_>, _>>()?
        .into_iter();
    let mut out = vec![];
    for (k, path) in paths.iter().enumerate() {
        let other = &paths[(k + 1) % paths.len()];
        let loaded = physid_io::load_trajectory(other, robot)?;
        let cutoff = loaded.report.cutoff;
        let runs = loaded.trajectories();
        let (information, description) = described(robot, &runs, other, &dopts)?;
        let logged = logs.next().expect("one log per path");
        let baseline = if opts.baseline {
            Some(calibrated_baseline(
                &description,
                runs,
                (other, cutoff),
                &dopts,
            )?)
        } else {
            None
        };
        let rms = description_rms(
            &inject(&logged, &description, &Injection::none()),
            &description,
        )
        .ok_or_else(|| {
            RealError::Io(physid_io::IoError::invalid(
                path,
                "no sample left after the data pipeline",
            ))
        })?;
        out.push(Base {
            rms,
            path: path.clone(),
            logged,
            description,
            described_by: other.clone(),
            information,
            baseline,
            payload_mass: physid_effect::PAYLOAD_MASS,
        });
    }
    Ok(out)
}

/// One scored case.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct RealCase {
    /// Case index.
    pub case: usize,
    /// The base run's file name.
    pub base: String,
    /// The run its description was identified on.
    pub described_by: String,
    /// What was injected.
    pub injected: String,
    /// The payload's body, when one was injected.
    pub injected_body: Option<String>,
    /// The payload's mass (kg), when one was injected.
    pub injected_mass: Option<f64>,
    /// The ladder's steps from the description, in order (ambiguous ones joined by `|`).
    pub found: Vec<String>,
    /// What the first step was preferred to: the tied explanations with more columns
    /// ([`diagnose::ladder::Rung::also_fit`]), best first. Not scored.
    pub first_also_fit: Vec<String>,
    /// The verdict.
    pub verdict: Verdict,
    /// The first step names the injected change (a payload: on its body, or a body the step
    /// is ambiguous with).
    pub top1: Option<bool>,
    /// A payload or body change was claimed on a clean run.
    pub payload_claimed: bool,
    /// Payload cases: the payload's mass found (kg) on the injected body (chosen by a step:
    /// the mass the diagnosis states, [`diagnose::ladder::BodyChange::stated`]; or tied with
    /// the first step: the mass it would carry in its place).
    pub payload_mass: Option<f64>,
    /// Where a step chose the injected body: its mass with every explanation free (the final
    /// fit), which later steps that trade off with it move.
    pub payload_mass_last: Option<f64>,
    /// Relative magnitude error `‖m̂ − m‖/‖m‖` of the injected kind, when attributed (the
    /// ladder's estimate where it chose the kind; a payload: its mass).
    pub magnitude_error: Option<f64>,
    /// The same, each joint weighted by its estimate's information `1/se²`: the error over
    /// what the data determine.
    pub magnitude_error_weighted: Option<f64>,
    /// The description's and the final validation RMS (N m).
    pub rms: [f64; 2],
    /// Wall time of the diagnosis (s).
    pub seconds: f64,
    /// The description's torque RMS on the changed run over that on the untouched one
    /// ([`description_rms`]): how visible the change is above the robot's standing gap.
    pub growth: f64,
    /// The draws made before the change was visible ([`draw_visible`]; 1: the first).
    pub draws: usize,
    /// A payload's Cramér–Rao bound on its mass from the run, relative to the mass
    /// ([`payload_mass_bound`]).
    pub mass_bound: Option<f64>,
}

/// Runs case `i` on its base, writing its files (`robot.urdf`, `data.csv`) into `dir`.
pub fn run_case(
    i: usize,
    seed: u64,
    bases: &[Base],
    opts: &diagnose::Options,
    dir: &Path,
) -> Result<RealCase, RealError> {
    let base = &bases[i % bases.len()];
    let rate = base.logged.len() as f64 / (base.logged.t[base.logged.len() - 1] - base.logged.t[0]);
    let drawn = draw_visible(i, seed, base, rate);
    let inj = &drawn.injection;
    let data = inject(&base.logged, &base.description, inj);
    physid_io::create_dir_all(dir)?;
    let robot = dir.join("robot.urdf");
    let csv = dir.join("data.csv");
    let urdf = physid_io::urdf::to_string(&base.description);
    physid_io::write_atomic(&robot, urdf.as_bytes())?;
    let table = base.information.sidecar_table();
    let side = physid_io::urdf_patch::sidecar(&base.description, "robot.urdf", &[], Some(&table));
    let sidecar = physid_io::sidecar_path(&robot);
    physid_io::write_atomic(&sidecar, side.as_bytes())?;
    physid_io::write_atomic(&csv, logged_csv(&data).as_bytes())?;
    write_injection(&dir.join("injected.json"), &drawn)?;
    let start = std::time::Instant::now();
    let given = physid_io::load_robot(&robot.to_string_lossy())?;
    let information = described_information(&sidecar, &given)?;
    let loaded = physid_io::load_trajectory(&csv, &given)?;
    let cutoff = loaded.report.cutoff;
    let runs = loaded.trajectories();
    let diag_err = |source| RealError::Diagnose {
        context: format!("case {i}"),
        source,
    };
    // As `physid diagnose` on the case's files: the effect columns processed at the data
    // pipeline's cutoff, in both modes (the "what changed" mode with the compliance and backlash
    // columns at the default 20 Hz, while the pipeline derived q̇, q̈ at the KUKA's 2 Hz, named
    // backlash first on none of its cases).
    let opts = diagnose::Options {
        processing_cutoff: cutoff,
        ..opts.clone()
    };
    let d = if let Some(b) = &base.baseline {
        b.diagnose_change(&given, runs, vec![], HOLDOUT, &opts)
            .map_err(diag_err)?
    } else {
        let opts = diagnose::Options {
            description_information: Some(information),
            ..opts
        };
        diagnose::diagnose_runs(&given, runs, vec![], HOLDOUT, &opts).map_err(diag_err)?
    };
    Ok(RealCase {
        growth: drawn.growth,
        draws: drawn.draws,
        mass_bound: drawn.mass_bound,
        ..score_case(i, base, inj, &given, &d, start.elapsed().as_secs_f64())
    })
}

/// The change injected into a case (`injected.json` beside its files: the truth a kept case
/// is scored against, in the diagnosis's convention), the growth it reached and the draws
/// made ([`draw_visible`]).
fn write_injection(path: &Path, drawn: &Drawn) -> Result<(), RealError> {
    let json = serde_json::json!({
        "schema": "physid.injection/1",
        "injection": drawn.injection,
        "growth": drawn.growth,
        "draws": drawn.draws,
    });
    let text = serde_json::to_string_pretty(&json).expect("an injection serializes");
    physid_io::write_atomic(path, text.as_bytes())?;
    Ok(())
}

/// The baseline calibrated on `runs` of the recording `other`, its effect columns at that
/// recording's data pipeline `cutoff` (Hz), as `physid diagnose --baseline-data` processes
/// them (not at the default 20 Hz: the pipeline derives q̇, q̈ at the KUKA's 2 Hz).
fn calibrated_baseline(
    description: &Model,
    runs: Vec<physid_core::trajectory::Trajectory>,
    (other, cutoff): (&Path, f64),
    dopts: &diagnose::Options,
) -> Result<diagnose::baseline::Baseline, RealError> {
    let opts = diagnose::Options {
        processing_cutoff: cutoff,
        ..dopts.clone()
    };
    diagnose::baseline::Baseline::calibrate(description, runs, HOLDOUT, &opts).map_err(|source| {
        RealError::Diagnose {
            context: format!("the baseline {}", other.display()),
            source,
        }
    })
}

/// The information the case's sidecar carries, read back onto the description as `physid
/// diagnose` reads it (so a kept case re-diagnosed by hand is the benchmark's case).
fn described_information(
    sidecar: &Path,
    given: &Model,
) -> Result<nalgebra::DMatrix<f64>, RealError> {
    let invalid = |m: String| RealError::Io(physid_io::IoError::invalid(sidecar, m));
    let table = physid_ident::information::SidecarInformation::read(sidecar)?
        .ok_or_else(|| invalid("no [information] table".into()))?;
    table.onto(given).map_err(invalid)
}

/// The fraction of each case's data held out for validation.
const HOLDOUT: f64 = 0.3;

/// Whether the ladder's `first` step names the injected change (`None` for a clean case): a
/// payload as a body change on its body (`body`) or with it in the step's ambiguity group, a
/// friction change as friction re-identified, a library effect as its kind or tied with it.
fn first_step_names(
    inj: &Injection,
    body: Option<&str>,
    first: Option<&diagnose::ladder::Rung>,
) -> Option<bool> {
    let names_body = |r: &diagnose::ladder::Rung, b: &str| {
        let on = |s: &str| s.ends_with(&format!(" on {b}")) || s.ends_with(&format!(" of {b}"));
        on(&r.step) || r.ambiguous_with.iter().any(|s| on(s) || s.ends_with(b))
    };
    match inj.slot {
        Slot::Clean => None,
        Slot::Payload => {
            let b = body.expect("a payload has a body");
            Some(
                first.is_some_and(|r| {
                    r.kind.is_some_and(|k| k.is_body_change()) && names_body(r, b)
                }),
            )
        }
        Slot::Friction => Some(first.is_some_and(|r| r.step == "friction re-identified")),
        Slot::Effect(k) => {
            Some(first.is_some_and(|r| {
                r.kind == Some(k) || r.ambiguous_with.iter().any(|s| s == k.name())
            }))
        }
    }
}

/// The mass body `b` carries in the diagnosis: its change where a step chose it (`chosen`),
/// else the mass it would carry in the `first` step's place where the step's ambiguity group
/// holds it.
fn carried_mass(
    b: &str,
    chosen: Option<&diagnose::ladder::BodyChange>,
    first: Option<&diagnose::ladder::Rung>,
) -> Option<f64> {
    let tied_mass = || {
        let r = first?;
        let i = r
            .ambiguous_with
            .iter()
            .position(|s| s.ends_with(&format!(" on {b}")))?;
        r.ambiguous_mass.get(i).copied().flatten()
    };
    chosen.map(|c| c.mass).or_else(tied_mass)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, Matrix3, Vector3};
    use physid_core::spatial::InertialParams;
    use physid_effect::{Compliance, Payload, TimeDelay, TorqueGain, TorqueOffset};

    /// A short logged run of the Cheetah leg: sinusoids with their exact derivatives.
    fn logged(model: &Model) -> Logged {
        let n = model.dof();
        let (mut t, mut q, mut qd, mut qdd, mut tau) = (vec![], vec![], vec![], vec![], vec![]);
        for k in 0..50 {
            let s = k as f64 * 0.01;
            t.push(s);
            for j in 0..n {
                let w = 2.0 + j as f64;
                q.push(0.3 * (w * s).sin());
                qd.push(0.3 * w * (w * s).cos());
                qdd.push(-0.3 * w * w * (w * s).sin());
                tau.push(0.1 * j as f64);
            }
        }
        Logged {
            joint_names: model.joint_names(),
            t,
            q,
            qd: Some(qd),
            qdd: Some(qdd),
            tau,
        }
    }

    #[test]
    fn an_injected_payload_adds_its_body_s_regressor_columns_times_its_parameters() {
        let model = physid_core::model::cheetah3::leg();
        let n = model.dof();
        let log = logged(&model);
        let (mass, com, radius) = (1.3, [0.02, -0.01, -0.15], 0.04);
        let inj = Injection {
            slot: Slot::Payload,
            spec: Some(EffectSpec::Payload(Payload {
                mass,
                com,
                radius,
                body: Some(n),
            })),
            magnitudes: vec![mass],
            body: Some(n - 1),
            visible: None,
        };
        let out = inject(&log, &model, &inj);
        let pi = InertialParams::from_mass_com_inertia(
            mass,
            &Vector3::from(com),
            &(Matrix3::identity() * (0.4 * mass * radius * radius)),
        );
        let mut data = physid_core::dynamics::Data::new(&model);
        let mut y = DMatrix::zeros(n, model.layout().len);
        let mut worst: f64 = 0.0;
        for k in 0..log.len() {
            let r = k * n..(k + 1) * n;
            let (q, qd, qdd) = (
                &log.q[r.clone()],
                &log.qd.as_ref().unwrap()[r.clone()],
                &log.qdd.as_ref().unwrap()[r.clone()],
            );
            physid_core::dynamics::regressor(&model, &mut data, q, qd, qdd, &mut y);
            let added = y.columns(10 * (n - 1), 10) * pi.0;
            for j in 0..n {
                let d = out.tau[k * n + j] - log.tau[k * n + j];
                worst = worst.max((d - added[j]).abs());
            }
        }
        assert!(worst < 1e-10, "{worst}");
        assert!(out.qd.is_none() && out.qdd.is_none());
    }

    #[test]
    fn a_delay_shifts_the_torque_behind_the_motion_and_compliance_the_angle() {
        let model = physid_core::model::cheetah3::leg();
        let n = model.dof();
        let log = logged(&model);
        let delayed = inject(
            &log,
            &model,
            &Injection {
                slot: Slot::Effect(Kind::TimeDelay),
                spec: Some(EffectSpec::TimeDelay(TimeDelay { samples: 3 })),
                magnitudes: vec![3.0],
                body: None,
                visible: None,
            },
        );
        assert_eq!(delayed.len(), log.len() - 3);
        assert_eq!(delayed.t[0], log.t[3]);
        assert_eq!(delayed.q[..n], log.q[3 * n..4 * n]);
        assert_eq!(delayed.tau[..n], log.tau[..n]);
        let k = vec![200.0; n];
        let soft = inject(
            &log,
            &model,
            &Injection {
                slot: Slot::Effect(Kind::Compliance),
                spec: Some(EffectSpec::Compliance(Compliance { stiffness: k })),
                magnitudes: vec![],
                body: None,
                visible: None,
            },
        );
        for i in 0..log.q.len() {
            assert!((soft.q[i] - (log.q[i] + log.tau[i] / 200.0)).abs() < 1e-15);
        }
        assert_eq!(soft.tau, log.tau);
    }

    /// 4 s at 1 kHz of the leg on sinusoids, its torque the model's own (friction included).
    fn exact(model: &Model) -> Logged {
        let n = model.dof();
        let mut log = Logged {
            joint_names: model.joint_names(),
            t: vec![],
            q: vec![],
            qd: Some(vec![]),
            qdd: Some(vec![]),
            tau: vec![],
        };
        let mut data = physid_core::dynamics::Data::new(model);
        for k in 0..4000 {
            let s = k as f64 * 1e-3;
            log.t.push(s);
            let w: Vec<f64> = (0..n)
                .map(|j| std::f64::consts::TAU * (0.7 + 0.4 * j as f64))
                .collect();
            let q: Vec<f64> = (0..n).map(|j| 0.4 * (w[j] * s).sin()).collect();
            let qd: Vec<f64> = (0..n).map(|j| 0.4 * w[j] * (w[j] * s).cos()).collect();
            let qdd: Vec<f64> = (0..n)
                .map(|j| -0.4 * w[j] * w[j] * (w[j] * s).sin())
                .collect();
            let tau = physid_core::dynamics::rnea_with_friction(model, &mut data, &q, &qd, &qdd);
            log.q.extend(&q);
            log.qd.as_mut().unwrap().extend(&qd);
            log.qdd.as_mut().unwrap().extend(&qdd);
            log.tau.extend(tau.iter());
        }
        log
    }

    /// A base of the logged run `logged` described by `model` itself (no information), with
    /// the description's RMS `rms` on it.
    fn exact_base(logged: Logged, model: &Model, rms: f64) -> Base {
        Base {
            path: "exact.csv".into(),
            logged,
            description: model.clone(),
            described_by: "exact.csv".into(),
            information: physid_ident::information::Information {
                names: vec![],
                at: nalgebra::DVector::zeros(0),
                matrix: DMatrix::zeros(0, 0),
                samples: 0,
                residual_rms: 0.0,
                correlation_samples: 1.0,
            },
            baseline: None,
            rms,
            payload_mass: physid_effect::PAYLOAD_MASS,
        }
    }

    /// The leg's exact log, a 0.5 N m offset on every joint, and the description's RMS on the
    /// log without and with it.
    fn offset_case() -> (Logged, Injection, f64, f64) {
        let model = physid_core::model::cheetah3::leg();
        let n = model.dof();
        let log = exact(&model);
        let clean = description_rms(&log, &model).unwrap();
        let offset = Injection {
            slot: Slot::Effect(Kind::TorqueOffset),
            spec: Some(EffectSpec::TorqueOffset(TorqueOffset {
                offset: vec![0.5; n],
            })),
            magnitudes: vec![0.5; n],
            body: None,
            visible: None,
        };
        let shifted = description_rms(&inject(&log, &model, &offset), &model).unwrap();
        (log, offset, clean, shifted)
    }

    #[test]
    fn an_offset_shows_in_the_description_s_rms() {
        let (log, _, clean, shifted) = offset_case();
        // The pipeline's derived q̈ (filtered, ends trimmed) costs under 3 % of the torque on
        // this 4 s run (1.8 % measured); the offset adds its 0.5 N m in quadrature.
        let tau_rms = (log.tau.iter().map(|t| t * t).sum::<f64>() / log.tau.len() as f64).sqrt();
        assert!(clean < 0.03 * tau_rms, "{clean} vs {tau_rms}");
        let expected = (clean * clean + 0.25).sqrt();
        assert!((shifted - expected).abs() < 0.02, "{shifted} vs {expected}");
    }

    #[test]
    fn a_gain_is_scaled_up_to_its_target_and_no_further_than_a_physical_gain() {
        let model = physid_core::model::cheetah3::leg();
        let n = model.dof();
        let (log, offset, _, shifted) = offset_case();
        // A 1 % gain on the knee, asked to raise the RMS by 1 % over a 0.5 N m standing offset.
        let base = exact_base(inject(&log, &model, &offset), &model, shifted);
        let mut gain = vec![1.0; n];
        gain[n - 1] = 1.01;
        let small = Injection {
            slot: Slot::Effect(Kind::TorqueGain),
            spec: Some(EffectSpec::TorqueGain(TorqueGain { gain })),
            magnitudes: vec![0.0, 0.0, 0.01],
            body: None,
            visible: Some(1.01),
        };
        let (scaled, growth) = make_visible(&small, &base, 1000.0);
        assert!((growth - 1.01).abs() < 0.002, "{growth}");
        let Some(EffectSpec::TorqueGain(TorqueGain { gain })) = &scaled.spec else {
            panic!("{:?}", scaled.spec)
        };
        let s = (gain[n - 1] - 1.0) / 0.01;
        assert!(s > 1.0 && s <= MAX_SCALE, "{s}");
        assert!((scaled.magnitudes[2] - 0.01 * s).abs() < 1e-12);
        assert_eq!(gain[0], 1.0);
        // Already visible: left as drawn.
        let (same, _) = make_visible(
            &Injection {
                visible: Some(0.5),
                ..small.clone()
            },
            &base,
            1000.0,
        );
        assert_eq!(same.magnitudes, small.magnitudes);
        // Asked for more than a physical gain gives (a 30 % error cut on the knee, growth 10):
        // scaled to the bound and no further, never a torque read with its sign reversed.
        let mut gain = vec![1.0; n];
        gain[n - 1] = 0.7;
        let large = Injection {
            spec: Some(EffectSpec::TorqueGain(TorqueGain { gain })),
            magnitudes: vec![0.0, 0.0, -0.3],
            visible: Some(10.0),
            ..small.clone()
        };
        let (bounded, growth) = make_visible(&large, &base, 1000.0);
        let Some(EffectSpec::TorqueGain(TorqueGain { gain })) = &bounded.spec else {
            panic!("{:?}", bounded.spec)
        };
        assert!(
            (gain[n - 1] - (1.0 - MAX_GAIN_ERROR)).abs() < 1e-12,
            "{gain:?}"
        );
        assert_eq!(bounded.magnitudes, vec![0.0, 0.0, -MAX_GAIN_ERROR]);
        assert!(growth > 1.0 && growth < 10.0, "{growth}");
    }

    /// A payload of `mass` on body `body` (index from 0) of the leg.
    fn payload_on(body: usize, mass: f64) -> Injection {
        Injection {
            slot: Slot::Payload,
            spec: Some(EffectSpec::Payload(Payload {
                mass,
                com: [0.02, -0.01, -0.1],
                radius: 0.04,
                body: Some(body + 1),
            })),
            magnitudes: vec![mass],
            body: Some(body),
            visible: None,
        }
    }

    #[test]
    fn a_payload_s_mass_bound_is_the_spread_of_its_least_squares_mass_under_white_noise() {
        use rand_distr::{Distribution, StandardNormal};
        let model = physid_core::model::cheetah3::leg();
        let n = model.dof();
        let (sigma, mass, knee) = (0.5, 2.0, n - 1);
        let base = exact_base(exact(&model), &model, sigma);
        let bound = payload_mass_bound(&base, &payload_on(knee, mass)).unwrap();
        // Independently: the knee's four columns stacked, the mass fitted by least squares
        // against white noise of the standing gap, its spread over 400 draws.
        let log = &base.logged;
        let mut y_payload = DMatrix::zeros(n * log.len(), 4);
        let mut data = physid_core::dynamics::Data::new(&model);
        let mut y = DMatrix::zeros(n, model.layout().len);
        for k in 0..log.len() {
            let r = k * n..(k + 1) * n;
            let qd = &log.qd.as_ref().unwrap()[r.clone()];
            let qdd = &log.qdd.as_ref().unwrap()[r.clone()];
            physid_core::dynamics::regressor(&model, &mut data, &log.q[r.clone()], qd, qdd, &mut y);
            let rows = y.fixed_columns::<4>(10 * knee);
            y_payload.rows_mut(k * n, n).copy_from(&rows);
        }
        let solver = y_payload.clone().svd(true, true);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let fitted: Vec<f64> = (0..400)
            .map(|_| {
                let noise = nalgebra::DVector::from_fn(y_payload.nrows(), |_, _| {
                    let z: f64 = StandardNormal.sample(&mut rng);
                    sigma * z
                });
                solver.solve(&noise, 1e-12).unwrap()[0]
            })
            .collect();
        let spread = (fitted.iter().map(|m| m * m).sum::<f64>() / fitted.len() as f64).sqrt();
        let ratio = bound * mass / spread;
        assert!((ratio - 1.0).abs() < 0.1, "bound {bound}, spread {spread}");
        // Twice the mass, half the relative bound; twice the gap, twice the bound.
        let heavier = payload_mass_bound(&base, &payload_on(knee, 2.0 * mass)).unwrap();
        assert!((heavier / bound - 0.5).abs() < 1e-9, "{heavier} vs {bound}");
        // The first body turns about an axis through its origin: a payload on it shows only
        // its first moment and its inertia, never its mass.
        let first = payload_mass_bound(&base, &payload_on(0, mass)).unwrap();
        assert!(first > 1e3 * bound, "{first} vs {bound}");
        assert_eq!(payload_mass_bound(&base, &Injection::none()), None);
    }

    #[test]
    fn a_case_is_drawn_again_until_the_run_shows_its_change_and_weighs_its_payload() {
        let model = physid_core::model::cheetah3::leg();
        let (mut log, _, _, shifted) = offset_case();
        // A 0.5 N m standing offset (q̇, q̈ kept: payloads are injected from them) hides small
        // changes on the leg.
        log.tau.iter_mut().for_each(|t| *t += 0.5);
        let base = exact_base(log, &model, shifted);
        let slots = slots();
        let mut redrawn = 0;
        for i in 0..2 * slots.len() {
            let drawn = draw_visible(i, 3, &base, 1000.0);
            let (inj, growth, draws) = (&drawn.injection, drawn.growth, drawn.draws);
            assert_eq!(inj.slot, slots[i % slots.len()], "case {i}");
            assert!((1..=MAX_DRAWS).contains(&draws), "case {i}: {draws}");
            assert_eq!(drawn.mass_bound, payload_mass_bound(&base, inj), "case {i}");
            let shown = inj.slot == Slot::Clean
                || (growth >= VISIBLE.0 && drawn.mass_bound.is_none_or(|b| b <= MAX_MASS_BOUND));
            assert_eq!(drawn.shows(), shown, "case {i}");
            assert!(shown || draws == MAX_DRAWS, "case {i}: growth {growth}");
            if draws == 1 {
                let first = make_visible(&draw(i, 3, &model, 1000.0), &base, 1000.0).0;
                assert_eq!(inj.magnitudes, first.magnitudes, "case {i}");
            } else {
                redrawn += 1;
            }
            // The same seed, the same case.
            let again = draw_visible(i, 3, &base, 1000.0);
            assert_eq!(
                (&again.injection.magnitudes, again.draws),
                (&inj.magnitudes, draws)
            );
        }
        assert!(redrawn > 0, "no case needed a second draw");
    }

    #[test]
    fn the_weighted_magnitude_error_is_decided_by_the_joints_the_data_determine() {
        use physid_diagnose::{EffectEstimate, Evidence, Magnitude};
        let magnitude = |value: f64, se: f64| Magnitude {
            joint: "j".into(),
            value,
            se,
            unit: "rad/(N m)".into(),
            identifiable: 1.0,
        };
        // A compliance seen on the loaded joint (12 % low, tight), not on the wrist (0.32 ±
        // 0.52 against 0.0017), and a joint without a standard error.
        let e = EffectEstimate {
            kind: Kind::Compliance,
            evidence: Evidence::Description,
            param: 0.0,
            magnitude_name: "compliance 1/k".into(),
            magnitudes: vec![
                magnitude(2.09e-3, 0.16e-3),
                magnitude(0.32, 0.52),
                magnitude(5e-3, 0.0),
            ],
            ambiguous_with: vec![],
            separate_by: None,
            after_later_steps: None,
        };
        let truth = [2.38e-3, 1.7e-3, 1e-3];
        let plain = relative_error(&e, &truth, |_| 1.0).unwrap();
        assert!(plain > 100.0, "{plain}");
        let weighted = relative_error(&e, &truth, information).unwrap();
        // The loaded joint's 12 % and the wrist's error in units of its own standard error.
        let loaded = ((2.09e-3 - 2.38e-3) / 0.16e-3_f64).powi(2);
        let wrist = ((0.32 - 1.7e-3) / 0.52_f64).powi(2);
        let den = (2.38e-3 / 0.16e-3_f64).powi(2) + (1.7e-3 / 0.52_f64).powi(2);
        assert!((weighted - ((loaded + wrist) / den).sqrt()).abs() < 1e-12);
        assert!(weighted > 0.05 && weighted < 0.2, "{weighted}");
        // Nothing the data determine: no error at all.
        assert_eq!(relative_error(&e, &[0.0; 3], information), None);
    }
}
