//! Identities that the dynamics algorithms must satisfy, each checked against something
//! independent: the regressor against RNEA, CRBA against RNEA columns, forward dynamics against
//! RNEA, RNEA against energy (power balance, gravity as the gradient of potential energy),
//! kinetic energy from body velocities against the mass matrix, and regressor columns against
//! finite differences of RNEA in the parameters. Random trees with rotors, and the Cheetah leg.

use nalgebra::{DMatrix, DVector};
use physid::dynamics::{
    self, crba, forward_dynamics, kinetic_energy, potential_energy, regressor, rnea, Data,
};
use physid::model::random::{random_state, random_tree};
use physid::model::{cheetah3, Model, RotorModel};

/// The models every identity is checked on.
fn models() -> Vec<Model> {
    let mut v = vec![
        cheetah3::leg(),
        cheetah3::leg().with_rotor_model(RotorModel::Reflected),
        cheetah3::leg_with(&cheetah3::LegOptions {
            rotors: false,
            ..Default::default()
        })
        .unwrap(),
    ];
    for seed in 0..6 {
        let n = 2 + (seed as usize * 3) % 7;
        v.push(random_tree(seed, n));
        v.push(random_tree(100 + seed, n).with_rotor_model(RotorModel::Reflected));
    }
    v
}

fn rel(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).norm() / (1.0 + b.norm())
}

#[test]
fn regressor_times_parameters_equals_rnea_plus_friction() {
    for (mi, m) in models().iter().enumerate() {
        let mut d = Data::new(m);
        let theta = m.parameters();
        let mut y = DMatrix::zeros(m.dof(), theta.len());
        for s in 0..20 {
            let [q, qd, qdd] = random_state(1000 * mi as u64 + s, m.dof(), 3.0);
            regressor(m, &mut d, &q, &qd, &qdd, &mut y);
            let tau = dynamics::rnea_with_friction(m, &mut d, &q, &qd, &qdd);
            let err = (&y * &theta - &tau).norm() / tau.norm();
            assert!(err < 1e-10, "{}: relative error {err:e}", m.name());
        }
    }
}

#[test]
fn regressor_times_any_parameters_equals_the_dynamics_of_the_model_carrying_them() {
    // Identified parameters are any vector, physically consistent or not (a body of negative
    // mass, a CoM far outside it): the identification's residuals take `Y θ` as the inverse
    // dynamics with friction of the model carrying `θ`, its own workspace built for it.
    for (mi, m) in models().iter().enumerate() {
        let nominal = m.parameters();
        let mut d = Data::new(m);
        let mut y = DMatrix::zeros(m.dof(), nominal.len());
        for s in 0..5 {
            let seed = 7000 * mi as u64 + s;
            let [q, qd, qdd] = random_state(seed, m.dof(), 3.0);
            let [r, _, _] = random_state(seed + 1, nominal.len(), 2.0);
            let theta = DVector::from_iterator(
                nominal.len(),
                nominal.iter().zip(&r).map(|(t, r)| t * (1.0 + r) + 0.3 * r),
            );
            let carrying = m.with_parameters(&theta).unwrap();
            regressor(m, &mut d, &q, &qd, &qdd, &mut y);
            let tau =
                dynamics::rnea_with_friction(&carrying, &mut Data::new(&carrying), &q, &qd, &qdd);
            let err = (&y * &theta - &tau).norm() / tau.norm();
            assert!(err < 1e-10, "{}: relative error {err:e}", m.name());
        }
    }
}

#[test]
fn a_parameter_outside_a_joints_row_columns_leaves_its_torque_untouched() {
    // The joint-by-joint assembly of YᵀY sums each joint's row over `row_columns` only. Checked
    // against RNEA itself: changing any parameter outside joint k's columns leaves τ_k the same
    // bit for bit, and the regressor's entry there is exactly zero.
    for (mi, m) in models().iter().enumerate() {
        let pattern = dynamics::row_columns(m);
        let theta = m.parameters();
        let mut d = Data::new(m);
        let mut y = DMatrix::zeros(m.dof(), theta.len());
        for s in 0..3 {
            let [q, qd, qdd] = random_state(5000 * mi as u64 + s, m.dof(), 2.0);
            regressor(m, &mut d, &q, &qd, &qdd, &mut y);
            let tau = dynamics::rnea_with_friction(m, &mut d, &q, &qd, &qdd);
            for c in 0..theta.len() {
                let mut tp = theta.clone();
                tp[c] *= 1.5;
                tp[c] += 0.1;
                let mp = m.with_parameters(&tp).unwrap();
                let tau_p = dynamics::rnea_with_friction(&mp, &mut Data::new(&mp), &q, &qd, &qdd);
                for (k, cols) in pattern.iter().enumerate() {
                    if !cols.contains(&c) {
                        assert_eq!(tau_p[k], tau[k], "{}: column {c} moved τ_{k}", m.name());
                        assert_eq!(y[(k, c)], 0.0, "{}: Y[{k}, {c}]", m.name());
                    }
                }
            }
        }
    }
    // On the leg (a chain): the abduction's row touches all six bodies and its own two
    // friction terms; the knee's only the knee link, its rotor and its friction.
    let leg = cheetah3::leg();
    let pattern = dynamics::row_columns(&leg);
    assert_eq!(pattern[0].len(), 6 * 10 + 2);
    assert_eq!(pattern[2].len(), 2 * 10 + 2);
}

#[test]
fn regressor_columns_are_derivatives_of_rnea_in_the_parameters() {
    // τ is linear in θ, so a central difference is exact up to round-off.
    for m in models().iter().take(4) {
        let mut d = Data::new(m);
        let theta = m.parameters();
        let [q, qd, qdd] = random_state(7, m.dof(), 2.0);
        let mut y = DMatrix::zeros(m.dof(), theta.len());
        regressor(m, &mut d, &q, &qd, &qdd, &mut y);
        let h = 1e-3;
        for c in 0..theta.len() {
            let mut tp = theta.clone();
            tp[c] += h;
            let mut tm = theta.clone();
            tm[c] -= h;
            let (mp, mm) = (
                m.with_parameters(&tp).unwrap(),
                m.with_parameters(&tm).unwrap(),
            );
            let (mut dp, mut dm) = (Data::new(&mp), Data::new(&mm));
            let fd = (dynamics::rnea_with_friction(&mp, &mut dp, &q, &qd, &qdd)
                - dynamics::rnea_with_friction(&mm, &mut dm, &q, &qd, &qdd))
                / (2.0 * h);
            let col = y.column(c).into_owned();
            assert!(
                (&fd - &col).norm() < 1e-9 * (1.0 + col.norm()),
                "{} column {c}: {fd} vs {col}",
                m.name()
            );
        }
    }
}

#[test]
fn mass_matrix_is_symmetric_positive_definite_and_matches_rnea_columns() {
    for (mi, m) in models().iter().enumerate() {
        let mut d = Data::new(m);
        let n = m.dof();
        let [q, _, _] = random_state(77 + mi as u64, n, 3.0);
        let h = crba(m, &mut d, &q).clone();
        assert!(
            (&h - h.transpose()).norm() < 1e-14 * h.norm(),
            "{}: H not symmetric",
            m.name()
        );
        assert!(
            h.clone().cholesky().is_some(),
            "{}: H not positive definite",
            m.name()
        );
        // Column j of H = τ(q, 0, e_j) − τ(q, 0, 0) without gravity.
        let no_g = m.clone().with_gravity(nalgebra::Vector3::zeros());
        let zero = vec![0.0; n];
        for j in 0..n {
            let mut e = zero.clone();
            e[j] = 1.0;
            let col = rnea(&no_g, &mut d, &q, &zero, &e).clone();
            assert!(
                (col - h.column(j)).norm() < 1e-12 * (1.0 + h.norm()),
                "{}: column {j}",
                m.name()
            );
        }
    }
}

#[test]
fn rnea_on_the_transforms_of_the_kinematics_is_rnea() {
    for m in models() {
        let mut d = Data::new(&m);
        for seed in 0..3 {
            let [q, qd, qdd] = random_state(10 + seed, m.dof(), 2.0);
            let full = rnea(&m, &mut d, &q, &qd, &qdd).clone();
            let mut e = Data::new(&m);
            dynamics::kinematics::update_world(&m, &mut e, &q);
            let reused = dynamics::rnea_from_transforms(&m, &mut e, &qd, &qdd);
            // The same operations on the same numbers: equal bit for bit.
            assert_eq!(reused, &full);
        }
    }
}

#[test]
fn forward_dynamics_inverts_rnea() {
    for (mi, m) in models().iter().enumerate() {
        let mut d = Data::new(m);
        for s in 0..10 {
            let [q, qd, qdd] = random_state(500 + 50 * mi as u64 + s, m.dof(), 3.0);
            let tau = rnea(m, &mut d, &q, &qd, &qdd).clone();
            let got = forward_dynamics(m, &mut d, &q, &qd, tau.as_slice())
                .unwrap()
                .clone();
            let want = DVector::from_vec(qdd.clone());
            assert!(rel(&got, &want) < 1e-9, "{}: {got} vs {want}", m.name());
        }
    }
}

#[test]
fn kinetic_energy_from_body_velocities_equals_half_qd_h_qd() {
    for (mi, m) in models().iter().enumerate() {
        let mut d = Data::new(m);
        let [q, qd, _] = random_state(900 + mi as u64, m.dof(), 3.0);
        let t = kinetic_energy(m, &mut d, &q, &qd);
        let h = crba(m, &mut d, &q).clone();
        let v = DVector::from_vec(qd);
        let t2 = 0.5 * v.dot(&(&h * &v));
        assert!(
            (t - t2).abs() < 1e-12 * (1.0 + t.abs()),
            "{}: {t} vs {t2}",
            m.name()
        );
    }
}

/// Total energy along the curve q(t) = q + q̇ t + ½ q̈ t², q̇(t) = q̇ + q̈ t.
fn energy_on_curve(m: &Model, d: &mut Data, q: &[f64], qd: &[f64], qdd: &[f64], t: f64) -> f64 {
    let qt: Vec<f64> = (0..q.len())
        .map(|i| q[i] + qd[i] * t + 0.5 * qdd[i] * t * t)
        .collect();
    let vt: Vec<f64> = (0..q.len()).map(|i| qd[i] + qdd[i] * t).collect();
    kinetic_energy(m, d, &qt, &vt) + potential_energy(m, d, &qt)
}

#[test]
fn power_balance_tau_dot_qd_equals_energy_rate() {
    // For τ = ID(q, q̇, q̈) without friction, dE/dt = τ · q̇ exactly; checked by a central
    // difference of E along the motion (truncation O(h²) with h = 1e-4 s).
    for (mi, m) in models().iter().enumerate() {
        let mut d = Data::new(m);
        for s in 0..5 {
            let [q, qd, qdd] = random_state(3000 + 10 * mi as u64 + s, m.dof(), 2.0);
            let tau = rnea(m, &mut d, &q, &qd, &qdd).clone();
            let power = tau.dot(&DVector::from_vec(qd.clone()));
            let h = 1e-4;
            let de = (energy_on_curve(m, &mut d, &q, &qd, &qdd, h)
                - energy_on_curve(m, &mut d, &q, &qd, &qdd, -h))
                / (2.0 * h);
            let scale = 1.0 + tau.norm() * DVector::from_vec(qd.clone()).norm();
            assert!(
                (de - power).abs() < 1e-6 * scale,
                "{}: dE/dt {de} vs τ·q̇ {power}",
                m.name()
            );
        }
    }
}

#[test]
fn gravity_torque_is_the_gradient_of_potential_energy() {
    for (mi, m) in models().iter().enumerate() {
        let mut d = Data::new(m);
        let n = m.dof();
        let [q, _, _] = random_state(4000 + mi as u64, n, 3.0);
        let zero = vec![0.0; n];
        let g = rnea(m, &mut d, &q, &zero, &zero).clone();
        for i in 0..n {
            let h = 1e-5;
            let (mut qp, mut qm) = (q.clone(), q.clone());
            qp[i] += h;
            qm[i] -= h;
            let du =
                (potential_energy(m, &mut d, &qp) - potential_energy(m, &mut d, &qm)) / (2.0 * h);
            assert!(
                (du - g[i]).abs() < 1e-7 * (1.0 + g.norm()),
                "{} joint {i}: {du} vs {}",
                m.name(),
                g[i]
            );
        }
    }
}

#[test]
fn coriolis_matrix_satisfies_the_skew_symmetry_of_h_dot_minus_2c() {
    // q̇ᵀ (Ḣ − 2C) q̇ = 0, i.e. q̇ · (C q̇) = ½ q̇ᵀ Ḣ q̇ with Ḣ by central differences.
    for (mi, m) in models().iter().enumerate() {
        let mut d = Data::new(m);
        let n = m.dof();
        let [q, qd, _] = random_state(5000 + mi as u64, n, 2.0);
        let zero = vec![0.0; n];
        let no_g = m.clone().with_gravity(nalgebra::Vector3::zeros());
        let cqd = rnea(&no_g, &mut d, &q, &qd, &zero).clone();
        let h = 1e-5;
        let shift = |s: f64| -> Vec<f64> { q.iter().zip(&qd).map(|(a, b)| a + s * b).collect() };
        let hd =
            (crba(m, &mut d, &shift(h)).clone() - crba(m, &mut d, &shift(-h)).clone()) / (2.0 * h);
        let v = DVector::from_vec(qd.clone());
        let lhs = v.dot(&cqd);
        let rhs = 0.5 * v.dot(&(&hd * &v));
        assert!(
            (lhs - rhs).abs() < 1e-6 * (1.0 + lhs.abs()),
            "{}: {lhs} vs {rhs}",
            m.name()
        );
    }
}

#[test]
fn frictionless_passive_simulation_conserves_energy() {
    // RK4 at 0.5 ms for 2 s: the relative energy drift must stay below 1e-6 (it is O(dt⁴)).
    let m = cheetah3::leg_with(&cheetah3::LegOptions {
        friction: [Default::default(); 3],
        ..Default::default()
    })
    .unwrap();
    let mut d = Data::new(&m);
    let (mut q, mut qd) = (vec![0.8, -1.0, 1.9], vec![1.0, -2.0, 3.0]);
    let e0 = kinetic_energy(&m, &mut d, &q, &qd) + potential_energy(&m, &mut d, &q);
    let zero = DVector::zeros(3);
    let mut tau = |_t: f64, _q: &[f64], _qd: &[f64]| zero.clone();
    let dt = 5e-4;
    let mut worst: f64 = 0.0;
    let scale = kinetic_energy(&m, &mut d, &q, &qd) + 10.0;
    for k in 0..4000 {
        physid::sim::rk4_step(&m, &mut d, k as f64 * dt, &mut q, &mut qd, dt, &mut tau).unwrap();
        let e = kinetic_energy(&m, &mut d, &q, &qd) + potential_energy(&m, &mut d, &q);
        worst = worst.max((e - e0).abs() / scale);
    }
    assert!(worst < 1e-6, "energy drift {worst:e}");
    assert!(
        qd.iter().any(|v| v.abs() > 0.5),
        "the leg should still be moving"
    );
}

#[test]
fn rotor_gyroscopic_coupling_is_what_the_reflected_model_drops() {
    // With rotors, the full and reflected models share the armature diagonal term but differ
    // off the diagonal by the rotor cross terms N S_rotᵀ I_rot X_rot S_j; for the Cheetah leg
    // those are of order N I_axis ≈ 10 × 5e-4 kg m².
    let full = cheetah3::leg();
    let refl = cheetah3::leg().with_rotor_model(RotorModel::Reflected);
    let q = [0.3, -0.7, 1.4];
    let hf = crba(&full, &mut Data::new(&full), &q).clone();
    let hr = crba(&refl, &mut Data::new(&refl), &q).clone();
    let diff = &hf - &hr;
    // Knee rotor sits on the thigh: its coupling with the hip joint is N I_axis (both about y).
    let r = full.bodies()[2].rotor.as_ref().unwrap();
    let a = r.joint.axis();
    let i_axis = a.dot(&(r.inertia.ibar() * a));
    assert!(
        (diff[(2, 1)] - r.gear_ratio * i_axis).abs() < 1e-12,
        "{diff}"
    );
    for i in 0..3 {
        assert!(diff[(i, i)].abs() < 0.2 * hf[(i, i)], "{diff}");
    }
}

/// Rotors frozen into the bodies they sit on are the reflected-inertia model minus its
/// armature: `H_reflected(q) = H_frozen(q) + diag(N² I_axis)`, and gravity is the same.
#[test]
fn frozen_rotors_are_the_reflected_model_without_its_armature() {
    for model in models() {
        if model.rotor_count() == 0 {
            continue;
        }
        let reflected = model.clone().with_rotor_model(RotorModel::Reflected);
        let frozen = model.with_rotors_frozen();
        assert_eq!(frozen.rotor_count(), 0);
        let n = model.dof();
        let (mut dr, mut df) = (Data::new(&reflected), Data::new(&frozen));
        for seed in 0..5 {
            let [q, _, _] = random_state(seed, n, 1.0);
            let hr = crba(&reflected, &mut dr, &q).clone();
            let hf = crba(&frozen, &mut df, &q).clone();
            let arm =
                DMatrix::from_diagonal(&DVector::from_fn(n, |i, _| dynamics::armature(&model, i)));
            let err = (&hr - &hf - &arm).norm();
            assert!(
                err < 1e-10 * hr.norm(),
                "{}: H differs by {err}",
                model.name()
            );
            let zero = vec![0.0; n];
            let gr = rnea(&reflected, &mut dr, &q, &zero, &zero).clone();
            let gf = rnea(&frozen, &mut df, &q, &zero, &zero).clone();
            assert!(
                (&gr - &gf).norm() < 1e-10 * (1.0 + gr.norm()),
                "{}",
                model.name()
            );
        }
    }
}

#[test]
fn a_singular_mass_matrix_names_the_joint_that_moves_no_inertia() {
    // A low-cost arm of point masses (the AL5D's URDF: every <inertia> zero, each mass at its
    // link's origin): the wrist's body sits on its own axis, so nothing turns with it. Before,
    // simulation said only that the mass matrix was not positive definite.
    let point = |m: f64, x: f64| {
        format!(
            r#"<inertial><origin xyz="{x} 0 0"/><mass value="{m}"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial>"#
        )
    };
    let xml = format!(
        r#"<robot name="points"><link name="base"/>
  <link name="upper">{}</link><link name="hand">{}</link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/><axis xyz="0 0 1"/></joint>
  <joint name="wrist" type="revolute"><parent link="upper"/><child link="hand"/><origin xyz="0.2 0 0"/><axis xyz="1 0 0"/></joint>
</robot>"#,
        point(0.3, 0.1),
        point(0.1, 0.05)
    );
    // Forward dynamics of the arm at rest, at one configuration.
    let at_rest = |xml: &str| {
        let path = std::path::Path::new("points.urdf");
        let (m, _) = physid::io::urdf::from_str(xml, path, &Default::default()).unwrap();
        let mut d = Data::new(&m);
        forward_dynamics(&m, &mut d, &[0.3, 0.2], &[0.0, 0.0], &[0.0, 0.0])
            .map(|_| ())
            .map_err(|e| e.to_string())
    };
    let e = at_rest(&xml).unwrap_err();
    assert!(e.contains("joint 'wrist'"), "{e}");
    // Off its axis, the hand's mass turns with the wrist: the matrix is positive definite.
    let off_axis = xml.replace(
        r#"<origin xyz="0.05 0 0"/>"#,
        r#"<origin xyz="0.05 0.02 0"/>"#,
    );
    assert_eq!(at_rest(&off_axis), Ok(()));
}
