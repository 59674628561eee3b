//! **Calibration**: identification of the model extended by effect terms the user chooses
//! (friction beyond viscous + Coulomb, or the effects a diagnosis confirmed), over one or more
//! runs: `τ_k ≈ Y_k θ + E_k c` with the library's columns `E_k` ([`library`]), the inertial
//! parameters under the constraint set, the effect coefficients `c` free (non-negative for the
//! kinds with a physical sign).
//!
//! Effects whose columns are linearized about a nominal model (gain, delay, tilt, compliance,
//! load-dependent friction) use the nominal identification of the same data (no effect terms),
//! as the diagnosis does. Every run keeps its own samples: nothing is differentiated or filtered
//! across the seam between two runs.

use super::rows::for_each_row_in_order;
use nalgebra::DVector;
use physid_core::model::Model;
use physid_core::trajectory::Trajectory;
use physid_effect::library::{self, Context, Kind, Variant};
use physid_ident::{self as ident, IdentError, Identified, NormalEquations};
use serde::Serialize;
use std::ops::Range;

/// One run's samples and the range of them used.
#[derive(Clone, Debug)]
pub struct Run<'a> {
    /// The samples (with q̈).
    pub trajectory: &'a Trajectory,
    /// Sample indices used.
    pub range: Range<usize>,
}

/// Calibration options.
#[derive(Clone, Debug)]
pub struct Options {
    /// The identification's settings (constraint set, prior weight, margin, regularizer).
    pub ident: ident::Options,
    /// The effect terms, each a kind at a grid value (Stribeck velocity, cogging harmonic).
    pub terms: Vec<Variant>,
    /// Low-pass cutoff (Hz) of the data's processing, for the compliance columns.
    pub processing_cutoff: f64,
    /// Joints whose torque rows are not fitted (locked joints).
    pub excluded: Vec<usize>,
}

impl Options {
    /// Checks the values: the identification's, terms unique with a positive grid value where
    /// the kind has a grid, a positive cutoff.
    pub fn validate(&self) -> Result<(), IdentError> {
        self.validate_for(usize::MAX)
    }

    /// [`Options::validate`] for a robot of `n` joints (a payload's body number at most `n`).
    pub fn validate_for(&self, n: usize) -> Result<(), IdentError> {
        self.ident.validate()?;
        let cutoff = self.processing_cutoff;
        if !(cutoff > 0.0 && cutoff.is_finite()) {
            return Err(IdentError::InvalidOption {
                option: "processing_cutoff",
                expected: "> 0 Hz",
                value: cutoff,
            });
        }
        for (i, t) in self.terms.iter().enumerate() {
            let term = || format!("{}:{}", t.kind.name(), t.param);
            if self.terms[..i].iter().any(|u| u.kind == t.kind) {
                return Err(IdentError::InvalidTerm {
                    term: term(),
                    reason: "each kind may be given once",
                });
            }
            if t.kind.gridded() && !t.kind.valid_param(t.param, n) {
                return Err(IdentError::InvalidTerm {
                    term: term(),
                    reason: "needs a valid value (stribeck:<velocity rad/s > 0>, cogging:<harmonic > 0>, payload:<body number 1..n>, compliance:<1/k of the secant >= 0>, backlash:<width 0, 0.01, 0.02 or 0.04 rad>)",
                });
            }
        }
        Ok(())
    }
}

/// One identified effect term.
#[derive(Clone, Debug, Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct TermFit {
    /// The kind.
    pub kind: Kind,
    /// Its grid value (Stribeck velocity in rad/s, cogging harmonic), 0 otherwise.
    pub param: f64,
    /// The coefficients, in column order (physical magnitudes of the injected effect, see
    /// [`library`]).
    pub coefficients: Vec<f64>,
    /// What the magnitudes are, and their unit.
    pub magnitude: (String, String),
    /// The magnitudes per joint (or one for the robot), as the diagnosis reports them.
    pub magnitudes: Vec<f64>,
    /// Per coefficient, the fraction of its column the rigid-body regressor does not explain
    /// on the training data (1: identifiable; near 0: absorbed by the inertial parameters, the
    /// value is then meaningless).
    pub identifiable: Vec<f64>,
}

/// A calibrated model: the identification (θ of the model's layout, then the effect
/// coefficients) and each term's fit.
#[derive(Clone, Debug)]
pub struct Calibration {
    /// The identification; `theta` carries the effect coefficients after the model's layout.
    pub identified: Identified,
    /// The nominal parameters the linearized columns were built about.
    pub nominal: DVector<f64>,
    /// The rigid-body model's own normal equations over the runs (no effect columns), for its
    /// identifiability.
    pub rigid: NormalEquations,
    /// Each term's coefficients and magnitudes.
    pub terms: Vec<TermFit>,
}

/// Identifies `model` with `opts.terms` on `runs` (their normal equations summed).
pub fn calibrate(model: &Model, runs: &[Run], opts: &Options) -> Result<Calibration, IdentError> {
    opts.validate_for(model.dof())?;
    if let Some(t) = opts.terms.iter().find(|t| t.kind.needs_rotor()) {
        if model.rotor_count() == 0 {
            return Err(IdentError::InvalidTerm {
                term: format!("{}:{}", t.kind.name(), t.param),
                reason: "acts at the rotor's angle, and this robot has no rotors (give them in the robot's TOML sidecar, docs/robot-format.md)",
            });
        }
    }
    let prior = model.parameters();
    let rigid = runs.iter().fold(
        NormalEquations::new(model.dof(), model.layout().len)
            .excluding(&opts.excluded)
            .finish(),
        |acc, r| {
            acc.merged(&NormalEquations::from_trajectory_excluding(
                model,
                r.trajectory,
                r.range.clone(),
                &opts.excluded,
            ))
        },
    );
    let nominal = if opts.terms.iter().any(|t| t.kind.linearized()) {
        ident::identify(model, &rigid, &prior, &opts.ident)?.theta
    } else {
        prior.clone()
    };
    let mut iopts = opts.ident.clone();
    iopts.nonnegative = nonnegative_columns(model, &opts.terms);
    let extra = columns(&opts.terms, model.dof());
    let full_prior = DVector::from_iterator(
        prior.len() + extra,
        prior.iter().copied().chain(std::iter::repeat_n(0.0, extra)),
    );
    let ne = normal_equations(model, &nominal, runs, opts);
    let identified = ident::identify(
        model,
        &gauge_pinned(&ne, model, &opts.terms),
        &full_prior,
        &iopts,
    )?;
    let absorbed = super::magnitude::Identifiable::new(&ne.yty, prior.len());
    let identifiable: Vec<f64> = (prior.len()..prior.len() + extra)
        .map(|c| absorbed.fraction(c))
        .collect();
    let terms = term_fits(model, &opts.terms, &identified.theta, &identifiable);
    Ok(Calibration {
        identified,
        nominal,
        rigid,
        terms,
    })
}

/// `ne` (`[Y | E]` for `terms`) with each gauge the data do not determine pinned: the mean
/// coefficient of a kind whose common mode lies in the span of `Y` (a torque gain common to
/// every joint is a scale of `θ`).
fn gauge_pinned(ne: &NormalEquations, model: &Model, terms: &[Variant]) -> NormalEquations {
    term_columns(model, terms)
        .filter(|(kind, _)| kind.common_mode_in_span())
        .fold(ne.clone(), |out, (_, cols)| out.with_mean_pinned(cols))
}

/// Each term's kind and its columns after the model's `layout().len`, in order.
fn term_columns<'a>(
    model: &Model,
    terms: &'a [Variant],
) -> impl Iterator<Item = (Kind, Range<usize>)> + 'a {
    let n = model.dof();
    let mut c = model.layout().len;
    terms.iter().map(move |t| {
        let cols = c..c + t.kind.columns(n);
        c = cols.end;
        (t.kind, cols)
    })
}

/// The normal equations of `[Y | E]` over the runs (the rows of `opts.excluded` left out).
pub fn normal_equations(
    model: &Model,
    nominal: &DVector<f64>,
    runs: &[Run],
    opts: &Options,
) -> NormalEquations {
    let n = model.dof();
    let p = model.layout().len + columns(&opts.terms, n);
    let mut ne = NormalEquations::new(n, p).excluding(&opts.excluded);
    for r in runs {
        let ctx = Context::new(model, nominal, r.trajectory, opts.processing_cutoff);
        for_each_row_in_order(
            &ctx,
            r.trajectory,
            r.range.clone(),
            &opts.terms,
            0.0,
            &mut |_, z, tau| ne.add(z, tau),
        );
    }
    ne.finish()
}

/// Per-joint and overall RMS of `τ − [Y | E] θ` over the runs (N m), all samples scored.
pub fn rms_error(
    model: &Model,
    calibration: &Calibration,
    runs: &[Run],
    opts: &Options,
) -> (Vec<f64>, f64) {
    let n = model.dof();
    let mut sq = vec![0.0; n];
    let mut count = 0usize;
    for_each_residual(model, calibration, runs, opts, &mut |_, r| {
        for j in 0..n {
            sq[j] += r[j].powi(2);
        }
        count += 1;
    });
    let per: Vec<f64> = sq
        .iter()
        .map(|s| (s / count.max(1) as f64).sqrt())
        .collect();
    let all = (sq.iter().sum::<f64>() / (count.max(1) * n) as f64).sqrt();
    (per, all)
}

/// Passes `(t, τ − Z θ)` (s, N m per joint) of each sample of `runs` to `each`: the residual
/// of the calibrated model, effect columns included.
pub fn for_each_residual(
    model: &Model,
    calibration: &Calibration,
    runs: &[Run],
    opts: &Options,
    each: &mut dyn FnMut(f64, &[f64]),
) {
    let n = model.dof();
    let theta = &calibration.identified.theta;
    let mut r = vec![0.0; n];
    for run in runs {
        let ctx = Context::new(
            model,
            &calibration.nominal,
            run.trajectory,
            opts.processing_cutoff,
        );
        for_each_row_in_order(
            &ctx,
            run.trajectory,
            run.range.clone(),
            &opts.terms,
            0.0,
            &mut |k, z, tau| {
                let pred = z * theta;
                for j in 0..n {
                    r[j] = tau[j] - pred[j];
                }
                each(run.trajectory.t[k], &r);
            },
        );
    }
}

/// Extra columns of `terms` for `n` joints.
pub fn columns(terms: &[Variant], n: usize) -> usize {
    terms.iter().map(|t| t.kind.columns(n)).sum()
}

/// θ's columns that must be non-negative: those of the kinds with a physical sign.
fn nonnegative_columns(model: &Model, terms: &[Variant]) -> Vec<usize> {
    term_columns(model, terms)
        .filter(|(kind, _)| kind.non_negative())
        .flat_map(|(_, cols)| cols)
        .collect()
}

fn term_fits(
    model: &Model,
    terms: &[Variant],
    theta: &DVector<f64>,
    identifiable: &[f64],
) -> Vec<TermFit> {
    let n = model.dof();
    let g = model.gravity().norm();
    let mut c = model.layout().len;
    terms
        .iter()
        .map(|t| {
            let k = t.kind.columns(n);
            let coefficients: Vec<f64> = theta.rows(c, k).iter().copied().collect();
            let p0 = model.layout().len;
            let identifiable = identifiable[c - p0..c - p0 + k].to_vec();
            c += k;
            TermFit {
                kind: t.kind,
                param: t.param,
                magnitude: {
                    let (what, unit) = t.kind.magnitude();
                    (what.to_string(), unit.to_string())
                },
                magnitudes: t.kind.magnitudes(&coefficients, n, g),
                coefficients,
                identifiable,
            }
        })
        .collect()
}

/// The terms [`parse_term`] reads, from the effect table: each kind's name, with `:<value>` for
/// a kind searched over a grid (`[:<value>]` where it has a default), e.g. for a command's help.
pub fn term_syntax() -> String {
    Kind::ALL
        .into_iter()
        .map(|k| match (k.gridded(), k.default_param().is_some()) {
            (false, _) => k.name().to_string(),
            (true, true) => format!("{}[:<{}>]", k.name(), k.grid_meaning()),
            (true, false) => format!("{}:<{}>", k.name(), k.grid_meaning()),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Parses a term: a kind's name (`torque_offset`, `tilt`, …), or one of the friction aliases
/// `offset`, `direction` (direction-dependent Coulomb), `stribeck:<v rad/s>`; kinds with a grid
/// take their value after `:` (`cogging:<harmonic>`).
pub fn parse_term(s: &str) -> Result<Variant, String> {
    let (name, value) = match s.split_once(':') {
        Some((n, v)) => (
            n,
            Some(
                v.parse::<f64>()
                    .map_err(|_| format!("'{s}': '{v}' is not a number"))?,
            ),
        ),
        None => (s, None),
    };
    let name = match name {
        "offset" => "torque_offset",
        "direction" | "direction_coulomb" => "asymmetric_coulomb",
        other => other,
    };
    let kind = Kind::ALL
        .into_iter()
        .find(|k| k.name() == name)
        .ok_or_else(|| {
            format!(
                "unknown term '{s}' (one of {}, or offset, direction)",
                library::names(&Kind::ALL)
            )
        })?;
    match (kind.gridded(), value) {
        (true, Some(v)) => Ok(Variant { kind, param: v }),
        (true, None) if kind.default_param().is_some() => Ok(Variant {
            kind,
            param: kind.default_param().unwrap_or(0.0),
        }),
        (true, None) => Err(format!(
            "'{s}' needs its value: {}:<{}>",
            kind.name(),
            kind.grid_meaning()
        )),
        (false, Some(_)) => Err(format!("'{s}': {} takes no value", kind.name())),
        (false, None) => Ok(Variant { kind, param: 0.0 }),
    }
}

/// The calibrated effects as a scenario's `[[effects]]` tables (docs/scenario-format.md), so
/// `physid simulate` replays the calibrated robot; kinds without a scenario form (reflected rotor
/// inertia, a payload, a tilt under a gravity not along −z) are left as comments. `dt` is the
/// data's sample period (s), for a delay in samples.
pub fn scenario_snippet(model: &Model, terms: &[TermFit], dt: f64) -> String {
    let mut out = String::new();
    for t in terms {
        match t.kind.replay(model, &t.coefficients, t.param, dt) {
            Some(effect) => out.push_str(&format!(
                "[[effects]]\nkind = \"{}\"\n{}\n\n",
                t.kind.name(),
                effect.toml_body()
            )),
            None => out.push_str(&format!(
                "# {} ({}: {}) has no scenario form here\n\n",
                t.kind.name(),
                t.magnitude.0,
                physid_sim::scenario::toml_list(&t.magnitudes)
            )),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn terms_parse_with_aliases_and_values() {
        assert_eq!(parse_term("offset").unwrap().kind, Kind::TorqueOffset);
        assert_eq!(
            parse_term("direction").unwrap().kind,
            Kind::AsymmetricCoulomb
        );
        let s = parse_term("stribeck:0.1").unwrap();
        assert_eq!((s.kind, s.param), (Kind::Stribeck, 0.1));
        assert!(parse_term("stribeck").unwrap_err().contains("stribeck:<"));
        assert!(parse_term("tilt:3").unwrap_err().contains("takes no value"));
        assert!(parse_term("windage").unwrap_err().contains("unknown term"));
    }
}
