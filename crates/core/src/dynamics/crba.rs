//! Composite-rigid-body algorithm for the joint-space mass matrix with rotors (RBDA Table 6.2).

use super::{armature, check_len, update_transforms, Data};
use crate::model::{Model, RotorModel};
use nalgebra::DMatrix;

/// The joint-space mass matrix `H(q)` (kg m²), symmetric positive definite. Returns `&data.h`.
///
/// Composite inertias `I^c_i` include the rotors mounted on body `i` (`X_rotᵀ I_rot X_rot`).
/// Column `i`: `F = I^c_i S_i`, `H_ii = S_iᵀ F`, then `F ← X_up,jᵀ F` up the tree with
/// `H_ij = S_jᵀ F`. Rotor `i` (full model) adds `S_rotᵀ I_rot S_rot` to `H_ii` and, through
/// `F = X_rotᵀ I_rot S_rot` carried up from its parent, the cross terms with every ancestor
/// joint (the gyroscopic-coupling partners). In the reflected model only the armature
/// `N² I_axis` is added to `H_ii`.
pub fn crba<'a>(model: &Model, data: &'a mut Data, q: &[f64]) -> &'a DMatrix<f64> {
    check_len(model, "q", q);
    update_transforms(model, data, q);
    crba_from_transforms(model, data);
    &data.h
}

/// CRBA on the transforms already in `data` (from [`update_transforms`] or an RNEA at the same
/// `q`), filling `data.h`.
pub(crate) fn crba_from_transforms(model: &Model, data: &mut Data) {
    let n = model.dof();
    let full = model.rotor_model() == RotorModel::Full;
    data.ic.copy_from_slice(&data.inertia);
    for (i, b) in model.bodies().iter().enumerate() {
        if let (Some(p), Some(_)) = (b.parent, &b.rotor) {
            let ir = data.inertia_rot[i].expressed_in_parent(&data.x_rot[i]);
            data.ic[p] = data.ic[p].add(&ir);
        }
    }
    data.h.fill(0.0);
    for i in (0..n).rev() {
        let b = &model.bodies()[i];
        if let Some(p) = b.parent {
            let up = data.ic[i].expressed_in_parent(&data.x_up[i]);
            data.ic[p] = data.ic[p].add(&up);
        }
        let mut f = data.ic[i].mul_motion(&data.s[i]);
        data.h[(i, i)] = data.s[i].dot(&f);
        let mut j = i;
        while let Some(p) = model.bodies()[j].parent {
            f = data.x_up[j].inv_apply_force(&f);
            j = p;
            data.h[(i, j)] = data.s[j].dot(&f);
            data.h[(j, i)] = data.h[(i, j)];
        }
        if b.rotor.is_some() {
            if full {
                let ir = &data.inertia_rot[i];
                let f_rot = ir.mul_motion(&data.s_rot[i]);
                data.h[(i, i)] += data.s_rot[i].dot(&f_rot);
                if let Some(p) = b.parent {
                    let mut f = data.x_rot[i].inv_apply_force(&f_rot);
                    let mut j = p;
                    loop {
                        let hij = data.s[j].dot(&f);
                        data.h[(i, j)] += hij;
                        data.h[(j, i)] += hij;
                        match model.bodies()[j].parent {
                            Some(pp) => {
                                f = data.x_up[j].inv_apply_force(&f);
                                j = pp;
                            }
                            None => break,
                        }
                    }
                }
            } else {
                data.h[(i, i)] += armature(model, i);
            }
        }
    }
}
