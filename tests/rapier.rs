//! Independent simulation cross-check: the link-only Cheetah leg swinging passively for 1 s
//! in rapier3d (reduced-coordinate multibody, f64) and in physid (RK4 on CRBA forward dynamics).
//!
//! rapier integrates with a first-order scheme, so its trajectory error is O(dt) while physid's
//! RK4 at 0.1 ms is exact to ~1e-10 here. The tolerance is justified by convergence, not picked:
//! halving rapier's step must halve the gap (first order, ratio 0.5 ± 0.15), and extrapolating
//! the gap to dt → 0 (Richardson) must leave less than 2% of the smallest gap, i.e. the two
//! engines describe the same dynamics and differ only by rapier's integration error.

mod common;

use nalgebra::DVector;
use physid::dynamics::Data;
use physid::model::{cheetah3, Model};
use physid::sim::rapier::RapierSim;
use physid::sim::rk4_step;

const Q0: [f64; 3] = [0.3, -0.8, 1.5];
const QD0: [f64; 3] = [0.5, -1.0, 1.0];
const T_END: f64 = 1.0;

fn link_only_leg() -> Model {
    cheetah3::leg_with(&cheetah3::LegOptions {
        rotors: false,
        friction: [Default::default(); 3],
        ..Default::default()
    })
    .unwrap()
}

/// physid trajectory sampled every 1 ms.
fn physid_traj(m: &Model) -> Vec<[f64; 3]> {
    let mut d = Data::new(m);
    let (mut q, mut qd) = (Q0.to_vec(), QD0.to_vec());
    let zero = DVector::zeros(3);
    let mut tau = |_t: f64, _q: &[f64], _qd: &[f64]| zero.clone();
    let dt = 1e-4;
    let mut out = vec![[q[0], q[1], q[2]]];
    for k in 0..(T_END / dt).round() as usize {
        rk4_step(m, &mut d, k as f64 * dt, &mut q, &mut qd, dt, &mut tau).unwrap();
        if (k + 1) % 10 == 0 {
            out.push([q[0], q[1], q[2]]);
        }
    }
    out
}

/// Max joint-angle gap (rad) between rapier at step `dt` and the physid trajectory.
fn rapier_gap(m: &Model, reference: &[[f64; 3]], dt: f64) -> f64 {
    let mut sim = RapierSim::new(m, &Q0, &QD0, dt).unwrap();
    let per_ms = (1e-3 / dt).round() as usize;
    let mut gap: f64 = 0.0;
    for (k, r) in reference.iter().enumerate().skip(1) {
        for _ in 0..per_ms {
            sim.step();
        }
        let (q, _) = sim.state();
        for j in 0..3 {
            gap = gap.max((q[j] - r[j]).abs());
        }
        let _ = k;
    }
    gap
}

#[test]
fn rapier_and_physid_agree_on_a_passive_swing() {
    let m = link_only_leg();
    let reference = physid_traj(&m);
    let swing = reference
        .iter()
        .map(|r| (r[1] - Q0[1]).abs())
        .fold(0.0, f64::max);
    assert!(swing > 0.5, "the leg must actually swing ({swing} rad)");
    let gaps: Vec<f64> = [1e-3, 5e-4, 2.5e-4]
        .iter()
        .map(|&dt| rapier_gap(&m, &reference, dt))
        .collect();
    eprintln!("max |q_rapier - q_physid| over 1 s at dt = 1, 0.5, 0.25 ms: {gaps:?} rad (swing {swing:.2} rad)");
    let (r1, r2) = (gaps[1] / gaps[0], gaps[2] / gaps[1]);
    eprintln!("ratios {r1:.3} {r2:.3}");
    assert!(
        (0.35..0.65).contains(&r1) && (0.35..0.65).contains(&r2),
        "not first-order convergence: {gaps:?}"
    );
    let extrapolated = 2.0 * gaps[2] - gaps[1];
    assert!(
        extrapolated.abs() < 0.02 * gaps[2] + 1e-6,
        "gap does not vanish as dt → 0: {extrapolated:e}"
    );
}

#[test]
fn rapier_engine_rejects_what_it_cannot_map() {
    // Prismatic joints are not mapped to rapier: the error names the joint.
    let m = (0..100)
        .map(|seed| physid::model::random::random_tree(seed, 6))
        .find(|m| {
            m.bodies()
                .iter()
                .any(|b| matches!(b.joint, physid::model::Joint::Prismatic { .. }))
        })
        .expect("some random tree has a prismatic joint");
    let zero = vec![0.0; 6];
    let e = RapierSim::new(&m, &zero, &zero, 1e-3)
        .err()
        .expect("prismatic is unsupported");
    assert!(
        e.to_string().contains("prismatic") && e.to_string().contains("joint"),
        "{e}"
    );
}

/// The paper's closed-loop shell experiment on the full leg with geared rotors, run in rapier
/// (rotor bodies held at N q by DOF coupling), explained by physid's inverse dynamics.
#[test]
fn rapier_closed_loop_with_geared_rotors_matches_physid_full_rotor_model() {
    let path = common::root().join("scenarios/cheetah3_shell.toml");
    let (mut sc, m, _) = physid::sim::scenario::load(&path).unwrap();
    sc.simulation.duration = 2.0;
    sc.simulation.engine = physid::sim::scenario::Engine::Rapier;
    let rec = physid::sim::run(&m, &sc, &mut |_| {}).unwrap();
    let (rms_full, max_full) = physid::sim::report::engine_consistency(&m, &rec);
    let refl = m
        .clone()
        .with_rotor_model(physid::model::RotorModel::Reflected);
    let (rms_refl, _) = physid::sim::report::engine_consistency(&refl, &rec);
    let tau_rms: Vec<f64> = (0..3)
        .map(|j| {
            (rec.truth
                .tau
                .iter()
                .skip(j)
                .step_by(3)
                .map(|t| t * t)
                .sum::<f64>()
                / rec.truth.len() as f64)
                .sqrt()
        })
        .collect();
    eprintln!("torque RMS {tau_rms:.3?}; residual of physid full {rms_full:?} (max {max_full:?}), reflected {rms_refl:?}");
    for j in 0..3 {
        // First-order integration in rapier (q̈ from one 0.25 ms step) and constraint
        // regularization of the gears: measured ≈ 2e-4 of the torque RMS; bound at 1e-3.
        assert!(
            rms_full[j] < 1e-3 * tau_rms[j],
            "joint {j}: {} vs torque RMS {}",
            rms_full[j],
            tau_rms[j]
        );
    }
    // The armature model misses the rotors' gyroscopic coupling that rapier resolves.
    assert!(
        rms_refl.iter().zip(&rms_full).all(|(r, f)| *r > 10.0 * f),
        "{rms_refl:?} vs {rms_full:?}"
    );
}
