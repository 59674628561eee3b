//! Property tests (proptest, shrinking counterexamples): spatial-algebra identities for
//! arbitrary transforms and bodies, and `Y θ = τ` for arbitrary random trees and states.

use nalgebra::{DMatrix, Vector3};
use physid::dynamics::{regressor, rnea_with_friction, Data};
use physid::model::random::{random_body, random_tree};
use physid::spatial::{rot_axis_angle, InertialParams, Motion, Transform};
use proptest::prelude::*;
use rand::SeedableRng;

fn vec3() -> impl Strategy<Value = Vector3<f64>> {
    (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64).prop_map(|(x, y, z)| Vector3::new(x, y, z))
}

fn transform() -> impl Strategy<Value = Transform> {
    (vec3(), -3.1..3.1f64, vec3()).prop_map(|(a, ang, p)| {
        let axis = if a.norm() < 1e-3 {
            Vector3::z()
        } else {
            a.normalize()
        };
        Transform::from_pose(&rot_axis_angle(&axis, ang), &p)
    })
}

fn body() -> impl Strategy<Value = InertialParams> {
    (any::<u64>(), vec3()).prop_map(|(seed, c)| {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        random_body(&mut rng, &(c * 0.3), 0.2)
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn moving_a_body_keeps_its_pseudo_inertia_spectrum_sign(p in body(), x in transform()) {
        // J transforms by a congruence, so positive definiteness (physical consistency) and the
        // mass are frame independent.
        let q = p.transformed(&x);
        prop_assert!((q.mass() - p.mass()).abs() < 1e-12);
        prop_assert!(q.min_eig_pseudo() > 0.0);
        let back = q.transformed(&x.inverse());
        prop_assert!((back.0 - p.0).norm() < 1e-12 * (1.0 + p.0.norm()));
    }

    #[test]
    fn kinetic_energy_is_frame_independent(p in body(), x in transform(), w in vec3(), v in vec3()) {
        let m = Motion::new(w, v);
        let e_a = m.dot(&p.rigid().mul_motion(&m));
        let mb = x.apply_motion(&m);
        let e_b = mb.dot(&p.transformed(&x).rigid().mul_motion(&mb));
        prop_assert!((e_a - e_b).abs() < 1e-12 * (1.0 + e_a.abs()));
    }

    #[test]
    fn pi_and_pseudo_inertia_are_inverse(p in body()) {
        let q = InertialParams::from_pseudo_inertia(&p.pseudo_inertia());
        prop_assert!((q.0 - p.0).norm() < 1e-14 * (1.0 + p.0.norm()));
    }

    #[test]
    fn regressor_is_exact_on_any_tree(seed in 0u64..10_000, n in 1usize..9, s in 0u64..1000) {
        let m = random_tree(seed, n);
        let mut d = Data::new(&m);
        let [q, qd, qdd] = physid::model::random::random_state(s, n, 3.0);
        let mut y = DMatrix::zeros(n, m.layout().len);
        regressor(&m, &mut d, &q, &qd, &qdd, &mut y);
        let tau = rnea_with_friction(&m, &mut d, &q, &qd, &qdd);
        prop_assert!((&y * m.parameters() - &tau).norm() <= 1e-10 * (1.0 + tau.norm()));
    }
}
