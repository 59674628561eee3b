//! Inverse dynamics of one sample with one joint's encoder signals shifted, on a predictor
//! model (`Context::predictors`): the passes behind the encoder-shift columns of compliance and
//! backlash. One whole pass per sample and predictor, kept for every variant of that sample
//! (the grid's secants share it), then one pass from the shifted joint on ([`rnea_after_joint`]):
//! the same numbers, bit for bit, as a whole pass for each variant.

use physid_core::dynamics::{joint_friction, rnea, rnea_after_joint, Data};
use physid_core::model::Model;
use physid_core::spatial::{Force, Motion};

/// One sample's state: its index `k` (the key of the kept pass, and of `shift`'s entries
/// `k · n + j`), joint angles (rad), velocities (rad/s), accelerations (rad/s²).
pub(crate) struct State<'s> {
    pub k: usize,
    pub q: &'s [f64],
    pub qd: &'s [f64],
    pub qdd: &'s [f64],
}

/// A predictor's workspace: its dynamics [`Data`], the unshifted pass of the sample it last
/// ran (the torque, every body's and rotor's velocity and acceleration and own force), and
/// buffers.
pub(crate) struct Predicting {
    data: Data,
    /// The sample whose unshifted pass `tau0` and the saved motions hold.
    sample: Option<usize>,
    /// The unshifted torque `ID(x) + friction` (N m).
    tau0: Vec<f64>,
    /// Bodies' and rotors' spatial velocities and accelerations of the unshifted pass.
    motions: [Vec<Motion>; 4],
    /// Their own terms of its backward pass (`Data::f_body`, `Data::f_rotor`).
    forces: [Vec<Force>; 2],
    /// The shifted state's `q̇`, `q̈`.
    qd: Vec<f64>,
    qdd: Vec<f64>,
}

impl Predicting {
    /// An empty workspace for `model`.
    pub(crate) fn new(model: &Model) -> Self {
        let n = model.dof();
        let data = Data::new(model);
        let motions = [&data.v, &data.a, &data.v_rot, &data.a_rot].map(|m| m.clone());
        let forces = [&data.f_body, &data.f_rotor].map(|f| f.clone());
        Self {
            data,
            sample: None,
            tau0: vec![0.0; n],
            motions,
            forces,
            qd: vec![0.0; n],
            qdd: vec![0.0; n],
        }
    }

    /// The unshifted torque of sample `s` (N m, friction included), the workspace left holding
    /// its transforms and motions: computed on the sample's first call, restored on later ones.
    pub(crate) fn unshifted(&mut self, model: &Model, s: &State) -> &[f64] {
        let d = &mut self.data;
        if self.sample == Some(s.k) {
            for (saved, now) in
                self.motions
                    .iter()
                    .zip([&mut d.v, &mut d.a, &mut d.v_rot, &mut d.a_rot])
            {
                now.copy_from_slice(saved);
            }
            for (saved, now) in self.forces.iter().zip([&mut d.f_body, &mut d.f_rotor]) {
                now.copy_from_slice(saved);
            }
            return &self.tau0;
        }
        let tau = rnea(model, d, s.q, s.qd, s.qdd);
        with_friction(model, tau.as_slice(), s.qd, &mut self.tau0);
        for (saved, now) in self
            .motions
            .iter_mut()
            .zip([&d.v, &d.a, &d.v_rot, &d.a_rot])
        {
            saved.copy_from_slice(now);
        }
        for (saved, now) in self.forces.iter_mut().zip([&d.f_body, &d.f_rotor]) {
            saved.copy_from_slice(now);
        }
        self.sample = Some(s.k);
        &self.tau0
    }

    /// `ID(x) + friction` (N m, into `out`) at sample `s` with joint `j`'s angle, velocity and
    /// acceleration shifted by `−by · shift_j`. The workspace must hold the transforms of `s`
    /// and the motions of the bodies before `j` unshifted or shifted at a later joint
    /// ([`Predicting::unshifted`] first, then the joints from the last to the first).
    pub(crate) fn shifted(
        &mut self,
        model: &Model,
        (j, by): (usize, f64),
        shift: &[Vec<f64>; 3],
        s: &State,
        out: &mut [f64],
    ) {
        let at = s.k * s.q.len() + j;
        self.qd.copy_from_slice(s.qd);
        self.qdd.copy_from_slice(s.qdd);
        let q_j = s.q[j] - by * shift[0][at];
        self.qd[j] -= by * shift[1][at];
        self.qdd[j] -= by * shift[2][at];
        let tau = rnea_after_joint(model, &mut self.data, (j, q_j), &self.qd, &self.qdd);
        with_friction(model, tau.as_slice(), &self.qd, out);
    }
}

/// `τ` plus the joints' friction at speeds `qd` into `out` (N m): the prediction's law, as
/// `rnea_with_friction` adds it.
fn with_friction(model: &Model, tau: &[f64], qd: &[f64], out: &mut [f64]) {
    for (i, b) in model.bodies().iter().enumerate() {
        out[i] = tau[i] + joint_friction(&b.friction, qd[i]);
    }
}
