//! The effect library, injection side: each effect's signature in the simulated data equals its
//! equation (written out here independently), and every run stays exactly consistent with the
//! inverse dynamics of the robot as it really is.

mod common;

use physid::dynamics::{rnea, Data};
use physid::effect::{
    AsymmetricCoulomb, Cogging, Compliance, LoadDependentFriction, Payload, QuadraticDamping,
    Spring, Stribeck, Tilt, TimeDelay, TorqueGain, TorqueOffset,
};
use physid::model::Model;
use physid::sim::scenario::{EffectSpec, Scenario};
use physid::trajectory::Recording;

fn clean() -> (Scenario, Model) {
    let path = common::root().join("scenarios/cheetah3_shell.toml");
    let (mut sc, m, _) = physid::sim::scenario::load(&path).unwrap();
    sc.simulation.duration = 1.5;
    sc.sensors.torque_noise = 0.0;
    (sc, m)
}

fn with(effects: Vec<EffectSpec>) -> (Recording, Model, Scenario) {
    let (mut sc, m) = clean();
    sc.effects = effects;
    sc.validate(m.dof()).unwrap();
    (physid::sim::run(&m, &sc, &mut |_| {}).unwrap(), m, sc)
}

/// Max over samples of |τ_mot + τ_effects − τ_friction − RNEA_model(q, q̇, q̈)|.
fn residual(rec: &Recording, model: &Model) -> f64 {
    let mut d = Data::new(model);
    let tr = &rec.truth;
    let mut worst: f64 = 0.0;
    for k in 0..tr.len() {
        let tau = rnea(
            model,
            &mut d,
            tr.q_at(k),
            tr.qd_at(k),
            tr.qdd_at(k).unwrap(),
        )
        .clone();
        for j in 0..3 {
            let r = tr.tau_at(k)[j] + rec.effects[3 * k + j] - rec.friction[3 * k + j] - tau[j];
            worst = worst.max(r.abs());
        }
    }
    worst
}

/// An effect's expected acting torque at (joint, q, q̇, τ_mot).
type Expected = Box<dyn Fn(usize, f64, f64, f64) -> f64>;

/// Max over samples of |logged effect torque − expected(q, q̇, τ_mot)|.
fn signature(rec: &Recording, expected: impl Fn(usize, f64, f64, f64) -> f64) -> f64 {
    let tr = &rec.truth;
    let mut worst: f64 = 0.0;
    for k in 0..tr.len() {
        for j in 0..3 {
            let e = expected(j, tr.q_at(k)[j], tr.qd_at(k)[j], tr.tau_at(k)[j]);
            worst = worst.max((rec.effects[3 * k + j] - e).abs());
        }
    }
    worst
}

#[test]
fn acting_effects_have_their_equations_and_keep_the_dynamics_consistent() {
    let v = 0.01; // friction_velocity of the scenario
    let cases: Vec<(EffectSpec, Expected)> = vec![
        (
            EffectSpec::Spring(Spring {
                stiffness: vec![2.0, 3.0, 1.0],
                rest: vec![0.1, -0.7, 1.2],
            }),
            Box::new(|j, q, _, _| -[2.0, 3.0, 1.0][j] * (q - [0.1, -0.7, 1.2][j])),
        ),
        (
            EffectSpec::Stribeck(Stribeck {
                static_extra: vec![1.0, 0.8, 0.5],
                velocity: vec![0.1, 0.1, 0.05],
            }),
            Box::new(move |j, _, w, _| {
                -[1.0, 0.8, 0.5][j] * (-(w / [0.1, 0.1, 0.05][j]).powi(2)).exp() * (w / v).tanh()
            }),
        ),
        (
            EffectSpec::AsymmetricCoulomb(AsymmetricCoulomb {
                delta: vec![0.6, 0.4, 0.3],
            }),
            Box::new(move |j, _, w, _| -[0.6, 0.4, 0.3][j] * (w / v).tanh().max(0.0)),
        ),
        (
            EffectSpec::QuadraticDamping(QuadraticDamping {
                coefficient: vec![0.2, 0.1, 0.05],
            }),
            Box::new(|j, _, w, _| -[0.2, 0.1, 0.05][j] * w * w.abs()),
        ),
        (
            EffectSpec::LoadDependentFriction(LoadDependentFriction {
                coefficient: vec![0.05, 0.04, 0.03],
            }),
            Box::new(move |j, _, w, t| -[0.05, 0.04, 0.03][j] * t.abs() * (w / v).tanh()),
        ),
        (
            EffectSpec::Cogging(Cogging {
                amplitude: vec![0.3, 0.2, 0.1],
                harmonic: vec![6.0, 6.0, 12.0],
                phase: vec![],
            }),
            Box::new(|j, q, _, _| -[0.3, 0.2, 0.1][j] * ([6.0, 6.0, 12.0][j] * 10.6 * q).sin()),
        ),
    ];
    for (effect, expected) in cases {
        let (rec, m, _) = with(vec![effect.clone()]);
        let sig = signature(&rec, &expected);
        let res = residual(&rec, &m);
        let size = rec.effects.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        eprintln!("{effect:?}: peak {size:.3} N m, signature error {sig:.1e}, dynamics residual {res:.1e}");
        assert!(size > 0.05, "{effect:?} barely acted");
        assert!(sig < 1e-12 * (1.0 + size), "{effect:?}: signature {sig:e}");
        assert!(res < 1e-9, "{effect:?}: residual {res:e}");
    }
}

#[test]
fn sensor_effects_change_only_the_log() {
    let (base, _, _) = with(vec![]);
    let (rec, _, _) = with(vec![
        EffectSpec::TorqueGain(TorqueGain {
            gain: vec![1.1, 0.9, 1.05],
        }),
        EffectSpec::TorqueOffset(TorqueOffset {
            offset: vec![0.5, -0.3, 0.2],
        }),
        EffectSpec::TimeDelay(TimeDelay { samples: 3 }),
    ]);
    assert_eq!(rec.truth, base.truth, "sensor effects must not act");
    let n = rec.truth.len();
    for k in 0..n {
        let src = k.saturating_sub(3);
        for (j, (g, o)) in [(1.1, 0.5), (0.9, -0.3), (1.05, 0.2)].iter().enumerate() {
            let want = g * rec.truth.tau_at(src)[j] + o;
            assert!(
                (rec.measured.tau_at(k)[j] - want).abs() < 1e-12,
                "sample {k} joint {j}"
            );
        }
    }
}

#[test]
fn tilt_and_payload_change_the_robot_not_the_model() {
    for effect in [
        EffectSpec::Tilt(Tilt {
            roll: 0.05,
            pitch: -0.08,
        }),
        EffectSpec::Payload(Payload {
            mass: 0.5,
            com: [0.0, 0.0, -0.345],
            radius: 0.03,
            body: None,
        }),
    ] {
        let (rec, nominal, sc) = with(vec![effect.clone()]);
        let real = physid::sim::effects::true_robot(&nominal, &sc.effects);
        let (r_real, r_nominal) = (residual(&rec, &real), residual(&rec, &nominal));
        eprintln!("{effect:?}: residual with the true robot {r_real:.1e}, with the nominal model {r_nominal:.3} N m");
        assert!(r_real < 1e-9 && r_nominal > 0.1, "{effect:?}");
    }
}

#[test]
fn bad_effects_are_rejected_with_the_key() {
    let (mut sc, m) = clean();
    sc.effects = vec![EffectSpec::TorqueGain(TorqueGain {
        gain: vec![1.0, -1.0, 1.0],
    })];
    assert!(sc
        .validate(3)
        .unwrap_err()
        .to_string()
        .contains("effects[0].gain"));
    sc.effects = vec![EffectSpec::Stribeck(Stribeck {
        static_extra: vec![1.0; 2],
        velocity: vec![0.1; 3],
    })];
    assert!(sc
        .validate(3)
        .unwrap_err()
        .to_string()
        .contains("effects[0].static_extra"));
    sc.effects = vec![EffectSpec::TimeDelay(TimeDelay { samples: 0 })];
    assert!(sc
        .validate(m.dof())
        .unwrap_err()
        .to_string()
        .contains("effects[0].samples"));
}

#[test]
fn compliance_shifts_only_the_logged_angle_by_the_deflection() {
    let (base, _, _) = with(vec![]);
    let k = [400.0, 300.0, f64::INFINITY];
    let (rec, _, _) = with(vec![EffectSpec::Compliance(Compliance {
        stiffness: k.to_vec(),
    })]);
    assert_eq!(rec.truth, base.truth, "a sensor effect must not act");
    let mut peak = 0.0f64;
    for s in 0..rec.truth.len() {
        for (j, kj) in k.iter().enumerate() {
            let defl = rec.measured.q_at(s)[j] - base.measured.q_at(s)[j];
            let want = if kj.is_finite() {
                rec.truth.tau_at(s)[j] / kj
            } else {
                0.0
            };
            peak = peak.max(want.abs());
            assert!(
                (defl - want).abs() < 1e-15,
                "sample {s} joint {j}: {defl} vs {want}"
            );
        }
    }
    assert!(peak > 1e-3, "deflection {peak} rad too small to test");
}
