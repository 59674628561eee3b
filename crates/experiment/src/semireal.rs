//! The semi-real blind benchmark: real logs as the base, one withheld change injected on top.
//!
//! The simulated benchmark ([`super::blind`]) cannot see what real data bring: a residual with
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

use crate::tables;
use physid_core::model::Model;
use physid_diagnose::{self as diagnose, Diagnosis, Verdict};
use physid_effect::library::Kind;
use physid_io::prepare::Logged;
use physid_sim::effects;
use physid_sim::scenario::EffectSpec;
use polars::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// What a slot injects.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
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

/// A change drawn for a case: the slot, its effect (if one of the library's), the payload
/// (body index, mass, centre in the body frame) and the friction factors.
#[derive(Clone, Debug, Serialize)]
pub struct Injection {
    /// The slot.
    pub slot: Slot,
    /// The library effect injected.
    pub spec: Option<EffectSpec>,
    /// True magnitudes in the diagnosis's convention (the payload's mass, kg; the friction's
    /// factors).
    pub magnitudes: Vec<f64>,
    /// The payload's body (index from 0).
    pub body: Option<usize>,
    /// For a library effect: the growth of the description's torque RMS it is scaled up to
    /// at least ([`make_visible`]).
    pub visible: Option<f64>,
}

impl Injection {
    /// Nothing injected.
    pub fn none() -> Self {
        Injection {
            slot: Slot::Clean,
            spec: None,
            magnitudes: vec![],
            body: None,
            visible: None,
        }
    }
}

/// Draws case `i`'s change on `description`.
pub fn draw(i: usize, seed: u64, description: &Model, rate: f64) -> Injection {
    draw_attempt(i, 0, seed, (description, physid_effect::PAYLOAD_MASS), rate)
}

/// Draws case `i`'s change on `description` (payload masses in `payload_mass`, kg), attempt `a`
/// (attempt 0 is [`draw`]; each attempt its own stream: the same seed gives the same draws
/// whatever the thread count).
fn draw_attempt(
    i: usize,
    a: usize,
    seed: u64,
    (description, payload_mass): (&Model, (f64, f64)),
    rate: f64,
) -> Injection {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(i as u64 | ((a as u64) << 32));
    let slots = slots();
    let slot = slots[i % slots.len()];
    let n = description.dof();
    match slot {
        Slot::Clean => Injection::none(),
        Slot::Payload => draw_payload(slot, description, payload_mass, &mut rng),
        Slot::Friction => Injection {
            slot,
            spec: None,
            magnitudes: (0..n).map(|_| 1.5 + rng.random::<f64>()).collect(),
            body: None,
            visible: None,
        },
        Slot::Effect(kind) => {
            let (spec, magnitudes) = kind.draw(description, &mut rng, rate);
            let visible = VISIBLE.0 + (VISIBLE.1 - VISIBLE.0) * rng.random::<f64>();
            Injection {
                slot,
                spec,
                magnitudes,
                body: None,
                visible: Some(visible),
            }
        }
    }
}

/// A payload on a random body ([`physid_effect::payload_on_any_body_within`]).
fn draw_payload(slot: Slot, model: &Model, mass: (f64, f64), rng: &mut ChaCha8Rng) -> Injection {
    let (spec, body, mass) = physid_effect::payload_on_any_body_within(model, rng, mass);
    Injection {
        slot,
        spec: Some(spec),
        magnitudes: vec![mass],
        body: Some(body),
        visible: None,
    }
}

/// The growth of the description's torque RMS a library effect is scaled up to, drawn
/// uniformly per case: the real robot's standing gap from a description identified on another
/// run (0.44–0.47 N m on the KUKA runs) is larger than the signature of several effects at the
/// simulated benchmark's magnitudes (a 15–30 % gain on a wrist joint, compliance at
/// 300–1000 N m/rad on a slow arm raise it by 2–35 %); such a change is not the first thing
/// any diagnosis can name. Payloads and friction changes keep their physical draws.
pub const VISIBLE: (f64, f64) = (1.5, 2.5);

pub use physid_effect::MAX_GAIN_ERROR;

/// The largest factor [`make_visible`] scales a drawn effect by.
pub const MAX_SCALE: f64 = 4.0;

/// The most draws [`draw_visible`] makes for a case.
pub const MAX_DRAWS: usize = 8;

/// The largest Cramér–Rao bound on a payload's mass ([`payload_mass_bound`], relative) a
/// drawn payload may have: a third of the 15 % the benchmark scores its mass within. On the
/// KUKA runs the payloads fall far either side (0.07–0.5 % on lwr_4..7_link; 15–22 % on
/// lwr_3_link, whose origin lies on the shoulder's axes; lwr_2_link's mass is not in the
/// runs at all).
pub const MAX_MASS_BOUND: f64 = 0.05;

/// Case `i`'s change, drawn until the run can show it: the first draw (made visible where it
/// can be, [`make_visible`]) whose growth of the description's torque RMS reaches
/// `VISIBLE.0` and, for a payload, whose mass the run determines ([`MAX_MASS_BOUND`]); at
/// most [`MAX_DRAWS`] draws (the last is kept when none does). A change the real robot's own
/// gap hides — a payload near a joint axis, a gain on a joint that carries almost no torque,
/// however large within its physical bound — or a mass the motion cannot weigh is a test of
/// the draw, not of a diagnosis; it is drawn again, on another body, joint or magnitude. The
/// rule reads only the truth, the description and the base run, never a diagnosis. Returns
/// the change kept.
pub fn draw_visible(i: usize, seed: u64, base: &Base, rate: f64) -> Drawn {
    let mut last = None;
    for a in 0..MAX_DRAWS {
        let (injection, growth) = make_visible(
            &draw_attempt(i, a, seed, (&base.description, base.payload_mass), rate),
            base,
            rate,
        );
        let drawn = Drawn {
            mass_bound: payload_mass_bound(base, &injection),
            injection,
            growth,
            draws: a + 1,
        };
        if drawn.shows() {
            return drawn;
        }
        last = Some(drawn);
    }
    last.expect("at least one draw")
}

/// A case's change as [`draw_visible`] keeps it.
#[derive(Clone, Debug)]
pub struct Drawn {
    /// The change.
    pub injection: Injection,
    /// The growth of the description's torque RMS it reaches ([`RealCase::growth`]).
    pub growth: f64,
    /// The draws made (1: the first).
    pub draws: usize,
    /// A payload's Cramér–Rao bound on its mass ([`payload_mass_bound`]).
    pub mass_bound: Option<f64>,
}

impl Drawn {
    /// Whether the run shows the change: none drawn, or a growth of at least `VISIBLE.0` and,
    /// for a payload, a mass bound of at most [`MAX_MASS_BOUND`].
    pub fn shows(&self) -> bool {
        self.injection.slot == Slot::Clean
            || (self.growth >= VISIBLE.0 && self.mass_bound.is_none_or(|b| b <= MAX_MASS_BOUND))
    }
}

/// The Cramér–Rao bound on a payload's mass from its base run, relative to the mass: the
/// payload's mass and first moment (the first four columns of its body's regressor over the
/// logged motion, paper eq. 4) fitted against white noise at the base's standing gap
/// (`base.rms`). A payload whose centre of mass lies near the axes of every joint that carries
/// it shows only its first moment `m c` in gravity, and a slow run barely shows `m` in the
/// inertial terms: its mass is not determined by the run, by any diagnosis (infinite where
/// the four columns are dependent). `None` for what is not a payload, or a run without q̇, q̈.
pub fn payload_mass_bound(base: &Base, inj: &Injection) -> Option<f64> {
    let (Slot::Payload, Some(body)) = (inj.slot, inj.body) else {
        return None;
    };
    let mass = *inj.magnitudes.first()?;
    let model = &base.description;
    let logged = &base.logged;
    let n = model.dof();
    let (qd, qdd) = (logged.qd.as_deref()?, logged.qdd.as_deref()?);
    let mut data = physid_core::dynamics::Data::new(model);
    let mut y = nalgebra::DMatrix::zeros(n, model.layout().len);
    let mut gram = nalgebra::Matrix4::<f64>::zeros();
    for k in 0..logged.len() {
        let r = k * n..(k + 1) * n;
        let (q, qd, qdd) = (&logged.q[r.clone()], &qd[r.clone()], &qdd[r]);
        physid_core::dynamics::regressor(model, &mut data, q, qd, qdd, &mut y);
        let y_payload = y.fixed_columns::<4>(10 * body);
        gram += y_payload.transpose() * y_payload;
    }
    let Some(covariance) = gram.try_inverse() else {
        return Some(f64::INFINITY);
    };
    Some(base.rms * covariance[(0, 0)].max(0.0).sqrt() / mass)
}

/// The description's torque residual RMS (N m, over all joints and samples) on `logged`
/// read as a robot writes it: without q̇, q̈, through the data pipeline with its own cutoff.
/// `None` if the pipeline leaves nothing.
pub fn description_rms(logged: &Logged, description: &Model) -> Option<f64> {
    let stripped = Logged {
        qd: None,
        qdd: None,
        ..logged.clone()
    };
    let prepared = physid_io::prepare::prepare(&stripped, &Default::default()).ok()?;
    let mut data = physid_core::dynamics::Data::new(description);
    let (mut sum, mut count) = (0.0, 0usize);
    for run in &prepared.runs {
        let tr = &run.trajectory;
        for k in 0..tr.len() {
            let qdd = tr.qdd_at(k)?;
            let tau_id = physid_core::dynamics::rnea_with_friction(
                description,
                &mut data,
                tr.q_at(k),
                tr.qd_at(k),
                qdd,
            );
            for (t, p) in tr.tau_at(k).iter().zip(tau_id.iter()) {
                sum += (t - p).powi(2);
                count += 1;
            }
        }
    }
    (count > 0 && sum.is_finite()).then(|| (sum / count as f64).sqrt())
}

/// A library effect scaled by `s` about "no effect" (its row's scaling, `Kind::scaled`), with
/// its magnitudes; `None` for what is not scaled.
fn scaled(inj: &Injection, s: f64, rate: f64) -> Option<(EffectSpec, Vec<f64>)> {
    match inj.slot {
        Slot::Effect(k) => k.scaled(inj.spec.as_ref()?, s, rate, &inj.magnitudes),
        _ => None,
    }
}

/// `inj` scaled up (never down, at most [`MAX_SCALE`]) until the description's torque RMS
/// on the changed run is `inj.visible` times `base.rms` (bisection on the factor's
/// logarithm); the growth reached.
pub fn make_visible(inj: &Injection, base: &Base, rate: f64) -> (Injection, f64) {
    let growth_at = |s: f64| -> Option<(Injection, f64)> {
        let (spec, magnitudes) = scaled(inj, s, rate)?;
        let changed = Injection {
            spec: Some(spec),
            magnitudes,
            ..inj.clone()
        };
        let rms = description_rms(
            &inject(&base.logged, &base.description, &changed),
            &base.description,
        )?;
        Some((changed, rms / base.rms))
    };
    let unscaled = || {
        let rms = description_rms(
            &inject(&base.logged, &base.description, inj),
            &base.description,
        );
        (inj.clone(), rms.map_or(f64::NAN, |r| r / base.rms))
    };
    let (Some(target), Some((_, g1))) = (inj.visible, growth_at(1.0)) else {
        return unscaled();
    };
    if g1 >= target {
        return unscaled();
    }
    let (mut lo, mut hi) = (0.0f64, MAX_SCALE.ln());
    if growth_at(MAX_SCALE).is_none_or(|(_, g)| g < target) {
        lo = hi;
    }
    for _ in 0..20 {
        if hi - lo < 0.01 {
            break;
        }
        let mid = 0.5 * (lo + hi);
        match growth_at(mid.exp()) {
            Some((_, g)) if g < target => lo = mid,
            _ => hi = mid,
        }
    }
    growth_at(hi.exp()).unwrap_or_else(unscaled)
}

/// The run `logged` (with q̇, q̈) with the change injected, as a robot writes it (no q̇, q̈):
/// torques from the logged motion through `description` where the change acts through the
/// dynamics.
pub fn inject(logged: &Logged, description: &Model, inj: &Injection) -> Logged {
    let n = logged.dof();
    let qd = logged.qd.as_deref().unwrap_or(&[]);
    let mut out = Logged {
        qd: None,
        qdd: None,
        ..logged.clone()
    };
    let rows = logged.len();
    match (&inj.slot, &inj.spec) {
        (Slot::Clean, _) => {}
        (Slot::Friction, _) => {
            for k in 0..rows {
                for j in 0..n {
                    let f = &description.bodies()[j].friction;
                    let w = qd[k * n + j];
                    let extra = f.viscous * w + f.coulomb * physid_core::dynamics::sign(w);
                    out.tau[k * n + j] += (inj.magnitudes[j] - 1.0) * extra;
                }
            }
        }
        (_, Some(spec)) => inject_effect(logged, description, spec, &mut out),
        (_, None) => {}
    }
    out
}

/// `spec` injected into `out` (a copy of `logged` without q̇, q̈) the way the simulator makes
/// it (`physid_effect::Physics`): a changed robot's extra torque from the logged motion (the
/// inverse dynamics of the truth less the description's), a delay in whole samples, the
/// encoder's angle (a compliance or a dead zone driven by the logged torque), the logged
/// torque (gains, offsets). A stage the effect does not act through leaves the log as it is.
fn inject_effect(logged: &Logged, description: &Model, spec: &EffectSpec, out: &mut Logged) {
    let n = logged.dof();
    let rows = logged.len();
    let at = |v: &[f64], k: usize| v[k * n..(k + 1) * n].to_vec();
    let physics = spec.physics();
    if let Some(truth) = physics.on_robot(description) {
        let (qd, qdd) = (
            logged.qd.as_deref().unwrap_or(&[]),
            logged.qdd.as_deref().unwrap_or(&[]),
        );
        let mut d0 = physid_core::dynamics::Data::new(description);
        let mut d1 = physid_core::dynamics::Data::new(&truth);
        for k in 0..rows {
            let (q, w, a) = (at(&logged.q, k), at(qd, k), at(qdd, k));
            let t0 = physid_core::dynamics::rnea(description, &mut d0, &q, &w, &a).clone();
            let t1 = physid_core::dynamics::rnea(&truth, &mut d1, &q, &w, &a);
            for j in 0..n {
                out.tau[k * n + j] += t1[j] - t0[j];
            }
        }
        return;
    }
    let delay = physics.delay_samples();
    if delay > 0 {
        let s = delay.min(rows.saturating_sub(1));
        // The torque at sample k is the one of sample k − s: the first s samples go.
        out.tau = logged.tau[..(rows - s) * n].to_vec();
        out.t = logged.t[s..].to_vec();
        out.q = logged.q[s * n..].to_vec();
        return;
    }
    let specs = std::slice::from_ref(spec);
    let mut zone = effects::DeadZone::new(description, specs);
    for k in 0..rows {
        let tau = at(&logged.tau, k);
        let dt = if k + 1 < rows {
            logged.t[k + 1] - logged.t[k]
        } else {
            0.0
        };
        let offsets = zone.as_mut().map(|z| z.step(&tau, dt));
        let q = effects::logged_angle(specs, &at(&logged.q, k), &tau, offsets.as_deref());
        out.q[k * n..(k + 1) * n].copy_from_slice(&q);
        let tau = effects::logged_torque(specs, &tau);
        out.tau[k * n..(k + 1) * n].copy_from_slice(&tau);
    }
}

/// A CSV of `t`, `q1..qn`, `tau1..taun` (the physid format without q̇, q̈).
pub fn logged_csv(logged: &Logged) -> String {
    let n = logged.dof();
    let mut s = String::from("t");
    (1..=n).for_each(|j| s += &format!(",q{j}"));
    (1..=n).for_each(|j| s += &format!(",tau{j}"));
    s.push('\n');
    for k in 0..logged.len() {
        s += &format!("{}", logged.t[k]);
        for v in &logged.q[k * n..(k + 1) * n] {
            s += &format!(",{v}");
        }
        for v in &logged.tau[k * n..(k + 1) * n] {
            s += &format!(",{v}");
        }
        s.push('\n');
    }
    s
}

/// One scored case.
#[derive(Clone, Debug, Serialize)]
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
    // pipeline's cutoff (in both modes: until 2026-11-27 the "what changed" mode processed the
    // logged torque of the compliance and backlash columns at the default 20 Hz while the
    // pipeline derived q̇, q̈ at the KUKA's 2 Hz, and named backlash first on none of its cases).
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
/// them (until 2026-11-27 at the default 20 Hz, while the pipeline derived q̇, q̈ at the
/// KUKA's 2 Hz).
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

/// A case's marks.
fn score_case(
    i: usize,
    base: &Base,
    inj: &Injection,
    model: &Model,
    d: &Diagnosis,
    seconds: f64,
) -> RealCase {
    let ladder = d.ladder.as_ref();
    let steps: Vec<&diagnose::ladder::Rung> =
        ladder.map_or(vec![], |l| l.rungs[2..l.rungs.len() - 1].iter().collect());
    let found = found_steps(&steps);
    let bodies = ladder.map_or(&[][..], |l| &l.bodies[..]);
    let body_name = inj.body.map(|b| model.bodies()[b].name.clone());
    let first = steps.first();
    let top1 = first_step_names(inj, body_name.as_deref(), first.copied());
    // The injected body's change, where a step chose it.
    let chosen = body_name
        .as_deref()
        .and_then(|b| bodies.iter().find(|c| c.body == b));
    let payload_mass = body_name
        .as_deref()
        .and_then(|b| carried_mass(b, chosen, first.copied()));
    let mass_error = payload_mass.map(|m| (m - inj.magnitudes[0]).abs() / inj.magnitudes[0]);
    let payload_mass_last = chosen.map(|c| c.last.mass);
    let (magnitude_error, magnitude_error_weighted) = match inj.slot {
        Slot::Payload => (mass_error, mass_error),
        Slot::Effect(k) => (
            magnitude_error(d, k, &inj.magnitudes),
            weighted_magnitude_error(d, k, &inj.magnitudes),
        ),
        _ => (None, None),
    };
    RealCase {
        case: i,
        base: file_name(&base.path),
        described_by: file_name(&base.described_by),
        injected: inj.slot.name().into(),
        injected_body: body_name,
        injected_mass: (inj.slot == Slot::Payload).then(|| inj.magnitudes[0]),
        found,
        first_also_fit: first.map_or(vec![], |r| {
            r.also_fit.iter().map(|a| a.name.clone()).collect()
        }),
        verdict: d.verdict,
        top1,
        payload_claimed: bodies.iter().any(|b| b.payload),
        payload_mass,
        payload_mass_last,
        magnitude_error,
        magnitude_error_weighted,
        rms: [d.overall[0], d.overall[d.overall.len() - 1]],
        seconds,
        growth: f64::NAN,
        draws: 1,
        mass_bound: None,
    }
}

/// Each step's name with its ambiguity group, joined by `|`.
fn found_steps(steps: &[&diagnose::ladder::Rung]) -> Vec<String> {
    steps
        .iter()
        .map(|r| {
            std::iter::once(r.step.clone())
                .chain(r.ambiguous_with.iter().cloned())
                .collect::<Vec<_>>()
                .join(" | ")
        })
        .collect()
}

fn file_name(p: &Path) -> String {
    p.file_name()
        .map_or_else(|| p.display().to_string(), |f| f.to_string_lossy().into())
}

/// The estimate of `kind` the case is scored on: the ladder's (anchored at the description, as
/// the case's steps are) where the ladder chose the kind, else the cross-validated one.
fn estimate_of(d: &Diagnosis, kind: Kind) -> Option<&diagnose::EffectEstimate> {
    (d.described_effects.iter())
        .chain(&d.effects)
        .find(|e| e.kind == kind)
}

/// Relative error `‖m̂ − m‖/‖m‖` of the estimate of `kind` over the joints whose estimate is
/// identifiable.
fn magnitude_error(d: &Diagnosis, kind: Kind, truth: &[f64]) -> Option<f64> {
    let e = estimate_of(d, kind)?;
    relative_error(e, truth, |_| 1.0)
}

/// The same error with each joint weighted by its estimate's information `1/se²` (joints
/// without a finite positive standard error left out): what the data determine. A joint the
/// data do not see (a compliance on a wrist joint whose torque is a tenth of a newton metre)
/// has an estimate whose standard error exceeds it a hundredfold, and would decide the
/// unweighted error alone.
fn weighted_magnitude_error(d: &Diagnosis, kind: Kind, truth: &[f64]) -> Option<f64> {
    let e = estimate_of(d, kind)?;
    relative_error(e, truth, information)
}

/// A magnitude's information `1/se²` (0 without a finite positive standard error).
fn information(m: &diagnose::Magnitude) -> f64 {
    if m.se.is_finite() && m.se > 0.0 {
        1.0 / (m.se * m.se)
    } else {
        0.0
    }
}

/// `sqrt(Σ w (m̂ − m)² / Σ w m²)` over the identifiable joints, `w` per magnitude.
fn relative_error(
    e: &diagnose::EffectEstimate,
    truth: &[f64],
    weight: impl Fn(&diagnose::Magnitude) -> f64,
) -> Option<f64> {
    let (mut num, mut den) = (0.0, 0.0);
    for (m, t) in e.magnitudes.iter().zip(truth) {
        if m.is_identifiable() {
            let w = weight(m);
            num += w * (m.value - t).powi(2);
            den += w * t * t;
        }
    }
    (den > 0.0).then(|| (num / den).sqrt())
}

/// The semi-real benchmark's scores.
#[derive(Clone, Debug, Serialize, schemars::JsonSchema)]
pub struct RealScores {
    /// Cases run.
    pub cases: usize,
    /// Cases whose first draw the run did not show (hidden by the base's standing gap, or a
    /// payload's mass it cannot weigh) and were drawn again ([`draw_visible`]).
    pub redrawn: usize,
    /// Payload cases.
    pub payload: usize,
    /// Fraction whose first step is the payload on its body.
    pub payload_found: f64,
    /// Fraction whose payload mass on that body is within 15 % of the truth.
    pub payload_mass_within_15: f64,
    /// Median relative error of the payload mass.
    pub median_payload_mass_error: f64,
    /// Payload cases whose payload raised the description's torque RMS by at least
    /// `VISIBLE.0` (a payload near the base barely moves the torque).
    pub payload_visible: usize,
    /// Fraction of those whose first step is the payload on its body.
    pub payload_found_visible: f64,
    /// Untouched real runs.
    pub clean: usize,
    /// Fraction of them with no payload or body change claimed.
    pub clean_no_payload: f64,
    /// Fraction of them with no step at all.
    pub clean_no_claim: f64,
    /// Cases without a payload injected (untouched runs and every other change).
    pub without_payload: usize,
    /// Fraction of them in which no step of the ladder names a body (`+ payload on …`, `+
    /// change of …`), first or later.
    pub without_payload_no_body_step: f64,
    /// Cases with one injected change (payload and friction included).
    pub single: usize,
    /// Fraction whose first step names it.
    pub top1: f64,
    /// Of them, the cases whose change raised the description's torque RMS by at least
    /// `VISIBLE.0` (1.5 times: [`RealCase::growth`]).
    pub visible_single: usize,
    /// Fraction of those whose first step names it.
    pub top1_visible: f64,
    /// Median relative magnitude error over them, where attributed.
    pub median_magnitude_error: f64,
    /// Median of the information-weighted error ([`RealCase::magnitude_error_weighted`]).
    pub median_magnitude_error_weighted: f64,
}

/// Whether a ladder step (`+ payload on lwr_5_link | payload or change on lwr_6_link`) names a
/// body change.
pub(crate) fn names_a_body(step: &str) -> bool {
    step.starts_with("+ payload on") || step.starts_with("+ change of")
}

/// Scores of a set of cases.
pub fn score(results: &[RealCase]) -> RealScores {
    let payload: Vec<&RealCase> = results.iter().filter(|r| r.injected == "payload").collect();
    let clean: Vec<&RealCase> = results.iter().filter(|r| r.injected == "clean").collect();
    let mass_err: Vec<f64> = payload.iter().filter_map(|r| r.magnitude_error).collect();
    let visible: Vec<bool> = results
        .iter()
        .filter(|r| r.growth >= VISIBLE.0)
        .filter_map(|r| r.top1)
        .collect();
    RealScores {
        cases: results.len(),
        redrawn: results.iter().filter(|r| r.draws > 1).count(),
        payload: payload.len(),
        payload_found: super::fraction(payload.iter().map(|r| r.top1 == Some(true))),
        payload_mass_within_15: super::fraction(
            payload
                .iter()
                .map(|r| r.magnitude_error.is_some_and(|e| e <= 0.15)),
        ),
        median_payload_mass_error: super::median(&mass_err),
        payload_visible: payload.iter().filter(|r| r.growth >= VISIBLE.0).count(),
        payload_found_visible: super::fraction(
            payload
                .iter()
                .filter(|r| r.growth >= VISIBLE.0)
                .map(|r| r.top1 == Some(true)),
        ),
        clean: clean.len(),
        clean_no_payload: super::fraction(clean.iter().map(|r| !r.payload_claimed)),
        clean_no_claim: super::fraction(clean.iter().map(|r| r.found.is_empty())),
        without_payload: results.len() - payload.len(),
        without_payload_no_body_step: super::fraction(
            (results.iter())
                .filter(|r| r.injected != "payload")
                .map(|r| !r.found.iter().any(|s| names_a_body(s))),
        ),
        single: results.iter().filter(|r| r.top1.is_some()).count(),
        top1: super::fraction(results.iter().filter_map(|r| r.top1)),
        visible_single: visible.len(),
        top1_visible: super::fraction(visible),
        median_magnitude_error: super::median(
            &results
                .iter()
                .filter_map(|r| r.magnitude_error)
                .collect::<Vec<_>>(),
        ),
        median_magnitude_error_weighted: super::median(
            &results
                .iter()
                .filter_map(|r| r.magnitude_error_weighted)
                .collect::<Vec<_>>(),
        ),
    }
}

/// The case table.
pub fn case_table(results: &[RealCase]) -> PolarsResult<DataFrame> {
    let s = |f: &dyn Fn(&RealCase) -> String| results.iter().map(f).collect::<Vec<_>>();
    df!(
        "case" => results.iter().map(|r| r.case as u64).collect::<Vec<_>>(),
        "base" => s(&|r| r.base.clone()),
        "described_by" => s(&|r| r.described_by.clone()),
        "injected" => s(&|r| r.injected.clone()),
        "injected_body" => results.iter().map(|r| r.injected_body.clone()).collect::<Vec<_>>(),
        "injected_mass" => results.iter().map(|r| r.injected_mass).collect::<Vec<_>>(),
        "found" => s(&|r| r.found.join(", ")),
        "verdict" => s(&|r| physid_io::serde_name(&r.verdict)),
        "top1" => results.iter().map(|r| r.top1).collect::<Vec<_>>(),
        "payload_claimed" => results.iter().map(|r| r.payload_claimed).collect::<Vec<_>>(),
        "payload_mass" => results.iter().map(|r| r.payload_mass).collect::<Vec<_>>(),
        "payload_mass_last" => results.iter().map(|r| r.payload_mass_last).collect::<Vec<_>>(),
        "magnitude_error" => results.iter().map(|r| r.magnitude_error).collect::<Vec<_>>(),
        "magnitude_error_weighted" => results.iter().map(|r| r.magnitude_error_weighted).collect::<Vec<_>>(),
        "rms_description" => results.iter().map(|r| r.rms[0]).collect::<Vec<_>>(),
        "rms_final" => results.iter().map(|r| r.rms[1]).collect::<Vec<_>>(),
        "growth" => results.iter().map(|r| r.growth).collect::<Vec<_>>(),
        "draws" => results.iter().map(|r| r.draws as u64).collect::<Vec<_>>(),
        "mass_bound" => results.iter().map(|r| r.mass_bound).collect::<Vec<_>>(),
        "first_also_fit" => s(&|r| r.first_also_fit.join(" | ")),
    )
}

/// Writes `cases.csv`, `README.md` (command, scores, per-kind table, cases) and `scores.json`
/// into `dir`.
pub fn write(
    dir: &Path,
    results: &[RealCase],
    scores: &RealScores,
    command: &str,
    wall: f64,
) -> Result<(), RealError> {
    physid_io::write_result_dir(dir, physid_io::SCORES_MARK, |staged| {
        write_files(staged, results, scores, command, wall)
    })
}

/// The files of [`write`] written into `dir`.
fn write_files(
    dir: &Path,
    results: &[RealCase],
    scores: &RealScores,
    command: &str,
    wall: f64,
) -> Result<(), RealError> {
    let mut df = case_table(results)?;
    tables::write_csv(&dir.join("cases.csv"), &mut df)?;
    use tables::Stat::{Count, Mean, Median};
    let per_kind = tables::Groups::of(&df, &["injected"])?
        .agg(
            &df,
            &[
                ("", Count, "cases"),
                ("top1", Mean, "top1"),
                ("growth", Median, "median_growth"),
                ("payload_claimed", Mean, "payload_claimed"),
                ("magnitude_error", Median, "median_magnitude_error"),
                (
                    "magnitude_error_weighted",
                    Median,
                    "median_magnitude_error_weighted",
                ),
            ],
        )?
        .sort(["injected"], Default::default())?;
    let md = format!(
        "# Semi-real blind benchmark\n\n`{command}` ({wall:.0} s wall).\n\nReal runs as the base, the description identified on another run, one change injected per case (docs/diagnose.md, \"Semi-real benchmark\").\n\n## Scores\n\n```json\n{}\n```\n\n## By injected change\n\n{}\n## Cases\n\n{}",
        serde_json::to_string_pretty(scores)?,
        tables::markdown(&per_kind),
        tables::markdown(&df)
    );
    physid_io::write_atomic(&dir.join("README.md"), md.as_bytes())?;
    physid_io::write_atomic(
        &dir.join("scores.json"),
        serde_json::to_string_pretty(&physid_io::versioned("blind_real_scores", scores))?
            .as_bytes(),
    )?;
    Ok(())
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
