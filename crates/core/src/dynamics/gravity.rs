//! Generalized gravity `g(q)`: the RNEA at `q̇ = q̈ = 0` (pinocchio's
//! `computeGeneralizedGravity`), for the controllers' gravity compensation.

use super::rnea::backward_pass;
use super::{base_acceleration, Data};
use crate::model::Model;
use crate::spatial::Motion;
use nalgebra::DVector;

/// `g(q)` at the joints (N m), links and rotors, on the joint transforms already in `data`
/// (from [`super::update_transforms`] or [`super::kinematics::update_world`] at `q`). Returns
/// `&data.tau`; sets `data.v`, `data.v_rot` to zero and `data.a`, `data.a_rot` to the bodies'
/// apparent acceleration `X a_λ`, from the base's `−g`.
///
/// The same numbers as [`super::rnea_from_transforms`] with `q̇ = q̈ = 0`, whose forward pass
/// adds only zeros to `X a_λ` there (`S q̈`, `v × S q̇`), without computing them.
pub fn gravity_from_transforms<'a>(model: &Model, data: &'a mut Data) -> &'a DVector<f64> {
    let a0 = base_acceleration(model);
    for (i, b) in model.bodies().iter().enumerate() {
        let a_p = b.parent.map_or(a0, |p| data.a[p]);
        data.v[i] = Motion::zero();
        data.a[i] = data.x_up[i].apply_motion(&a_p);
        if b.rotor.is_some() {
            data.v_rot[i] = Motion::zero();
            data.a_rot[i] = data.x_rot[i].apply_motion(&a_p);
        }
    }
    let mut zero = std::mem::take(&mut data.zero);
    zero.resize(model.dof(), 0.0);
    backward_pass(model, data, &zero);
    data.zero = zero;
    &data.tau
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::{rnea_from_transforms, update_transforms};

    /// On the leg with its rotors (full and reflected) and on random trees, at random
    /// configurations: the RNEA at zero velocity and acceleration, bit for bit.
    #[test]
    fn gravity_is_the_rnea_at_rest_bit_for_bit() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let leg = crate::model::cheetah3::leg();
        let reflected = leg
            .clone()
            .with_rotor_model(crate::model::RotorModel::Reflected);
        let trees = (1..4).map(|seed| crate::model::random::random_tree(seed, 7));
        for model in [leg, reflected].into_iter().chain(trees) {
            let n = model.dof();
            let (mut a, mut b) = (Data::new(&model), Data::new(&model));
            for _ in 0..50 {
                let q: Vec<f64> = (0..n).map(|_| rng.random_range(-3.0..3.0)).collect();
                update_transforms(&model, &mut a, &q);
                update_transforms(&model, &mut b, &q);
                let g = gravity_from_transforms(&model, &mut a).clone();
                let zero = vec![0.0; n];
                let id = rnea_from_transforms(&model, &mut b, &zero, &zero);
                assert_eq!(&g, id);
                assert!(g.iter().any(|x| x.abs() > 1e-3), "{g}");
            }
        }
    }
}
