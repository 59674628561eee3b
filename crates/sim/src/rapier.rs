//! An independent engine: the same model simulated in rapier3d (f64) with reduced-coordinate
//! multibody joints, so physid's dynamics can be checked against code it does not share.
//!
//! Mapping: each physid body becomes a dynamic rigid body without colliders whose local frame is
//! the body's joint frame, with mass, CoM and inertia set explicitly. A revolute joint `i` is a
//! rapier generic joint whose free DOF is the local x axis of its two joint frames:
//! `frame1 = (R_tree B, p_tree)` on the parent and `frame2 = (B, 0)` on the child, with `B` a
//! rotation taking x onto the joint axis, so that `child = parent · T(p) R_tree R_axis(q)` as in
//! physid. rapier's default joint damping is removed.
//!
//! A rotor is its own rigid body on the parent, on a revolute multibody joint about its spin
//! axis at `x_rot`, held to `q_rot = N q_i` by rapier's DOF coupling (an equality constraint),
//! which keeps its gyroscopic coupling as physid's full rotor model does. A joint torque `τ_i`
//! is applied as the torque `τ_i a_i` on body `i` and `−τ_i a_i` on its parent (`a_i` the joint
//! axis in world coordinates): an internal torque whose generalized force is `τ_i` on joint `i`
//! alone.

use nalgebra::{Matrix3, Rotation3, Vector3};
use physid_core::model::{Joint, Model};
use physid_core::spatial::InertialParams;
use rapier3d_f64::prelude::*;

/// Why a model cannot be run in rapier.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum RapierError {
    /// A feature not mapped to rapier.
    #[error("rapier engine: {0}")]
    Unsupported(String),
}

/// A model running in rapier's multibody solver.
pub struct RapierSim {
    pub(crate) bodies: RigidBodySet,
    pub(crate) colliders: ColliderSet,
    impulse_joints: ImpulseJointSet,
    multibody_joints: MultibodyJointSet,
    soft_bodies: SoftBodySet,
    islands: IslandManager,
    broad_phase: BroadPhaseBvh,
    pub(crate) narrow_phase: NarrowPhase,
    ccd: CCDSolver,
    pipeline: PhysicsPipeline,
    pub(crate) params: IntegrationParameters,
    gravity: Vector,
    /// The model's bodies and rotors as rapier holds them.
    tree: Hung,
}

/// A model's bodies hung in a rapier multibody: per physid body its joint's handle, its rigid
/// body, its parent's, its joint axis; per rotor its joint index, handle and gear ratio.
struct Hung {
    handles: Vec<MultibodyJointHandle>,
    links: Vec<RigidBodyHandle>,
    parents: Vec<RigidBodyHandle>,
    axes: Vec<Vector3<f64>>,
    rotors: Vec<(usize, MultibodyJointHandle, f64)>,
}

impl Hung {
    /// Inserts `model`'s bodies (and rotors) into `bodies` and `joints`, hung from `base`.
    fn insert(
        model: &Model,
        bodies: &mut RigidBodySet,
        joints: &mut MultibodyJointSet,
        base: RigidBodyHandle,
    ) -> Result<Self, RapierError> {
        let mut hung = Hung {
            handles: vec![],
            links: vec![],
            parents: vec![],
            axes: vec![],
            rotors: vec![],
        };
        for (i, b) in model.bodies().iter().enumerate() {
            let Joint::Revolute { axis } = b.joint else {
                return Err(RapierError::Unsupported(format!(
                    "joint '{}' is prismatic",
                    b.joint_name
                )));
            };
            let body = RigidBodyBuilder::dynamic()
                .additional_mass_properties(mass_properties(&b.inertia))
                .build();
            let h = bodies.insert(body);
            let parent = b.parent.map_or(base, |p| hung.links[p]);
            let joint = revolute(b.x_tree.to_pose(), &axis);
            let jh = joints
                .insert(parent, h, joint, true)
                .ok_or_else(|| RapierError::Unsupported(format!("rapier refused joint {i}")))?;
            if let Some(r) = &b.rotor {
                let jr = RapierSim::add_rotor(bodies, joints, parent, r)?;
                hung.rotors.push((i, jr, r.gear_ratio));
            }
            hung.links.push(h);
            hung.handles.push(jh);
            hung.parents.push(parent);
            hung.axes.push(axis);
        }
        Ok(hung)
    }
}

fn vec3(v: &Vector3<f64>) -> Vector {
    Vector::new(v.x, v.y, v.z)
}

fn rot3(m: &Matrix3<f64>) -> Rotation {
    let c = |j: usize| Vector::new(m[(0, j)], m[(1, j)], m[(2, j)]);
    Rotation::from_mat3(&rapier3d_f64::math::Matrix::from_cols(c(0), c(1), c(2))).normalize()
}

/// A rotation taking the x axis onto the unit vector `a`.
fn x_onto(a: &Vector3<f64>) -> Matrix3<f64> {
    Rotation3::rotation_between(&Vector3::x(), a)
        .unwrap_or_else(|| Rotation3::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI))
        .into_inner()
}

pub(crate) fn mass_properties(p: &InertialParams) -> MassProperties {
    let c = p.com().unwrap_or_default();
    let ic = p.inertia_about_com().unwrap_or_default();
    let col = |j: usize| Vector::new(ic[(0, j)], ic[(1, j)], ic[(2, j)]);
    MassProperties::with_inertia_matrix(
        vec3(&c),
        p.mass(),
        rapier3d_f64::math::Matrix::from_cols(col(0), col(1), col(2)),
    )
}

impl RapierSim {
    /// Builds the multibody at `(q0, q̇0)` with time step `dt` (s).
    pub fn new(model: &Model, q0: &[f64], qd0: &[f64], dt: f64) -> Result<Self, RapierError> {
        let mut bodies = RigidBodySet::new();
        let base = bodies.insert(RigidBodyBuilder::fixed().build());
        let mut sim = Self::hung_from(model, bodies, base, dt)?;
        sim.set_state(q0, qd0, None);
        Ok(sim)
    }

    /// `model`'s bodies (and rotors) inserted into `bodies` as one multibody hung from `base`
    /// (a fixed body, or a floating trunk), gravity the model's; the joints at zero.
    pub(crate) fn hung_from(
        model: &Model,
        mut bodies: RigidBodySet,
        base: RigidBodyHandle,
        dt: f64,
    ) -> Result<Self, RapierError> {
        let mut multibody_joints = MultibodyJointSet::new();
        let tree = Hung::insert(model, &mut bodies, &mut multibody_joints, base)?;
        let mut sim = Self {
            bodies,
            colliders: ColliderSet::new(),
            impulse_joints: ImpulseJointSet::new(),
            multibody_joints,
            soft_bodies: SoftBodySet::new(),
            islands: IslandManager::new(),
            broad_phase: BroadPhaseBvh::new(),
            narrow_phase: NarrowPhase::new(),
            ccd: CCDSolver::new(),
            pipeline: PhysicsPipeline::new(),
            params: IntegrationParameters {
                dt,
                ..Default::default()
            },
            gravity: vec3(&model.gravity()),
            tree,
        };
        sim.couple_rotors();
        Ok(sim)
    }

    /// The multibody link id of each physid joint.
    fn link_ids(&self) -> Vec<usize> {
        self.tree
            .handles
            .iter()
            .map(|&h| self.multibody_joints.get(h).expect("joint exists").1)
            .collect()
    }

    /// Adds the gear constraints `q_rot = N q_i`.
    fn couple_rotors(&mut self) {
        let ids = self.link_ids();
        let couplings: Vec<MultibodyDofCoupling> = self
            .tree
            .rotors
            .iter()
            .map(|&(i, jr, n)| MultibodyDofCoupling {
                link1: ids[i],
                dof1: 0,
                axis1: 3,
                link2: self.multibody_joints.get(jr).expect("rotor exists").1,
                dof2: 0,
                axis2: 3,
                coeff: n,
                offset: 0.0,
            })
            .collect();
        let (mb, _) = self
            .multibody_joints
            .get_mut(self.tree.handles[0])
            .expect("joint exists");
        for c in couplings {
            mb.add_dof_coupling(c);
        }
    }

    /// Sets joint positions (rad) and velocities (rad/s), rotors at `N q`, `N q̇`, and a
    /// floating root's six coordinates and velocities (`root`: its free joint's, linear then
    /// angular, world axes); assumes the current coordinates are zero (called once, after
    /// [`RapierSim::hung_from`]).
    pub(crate) fn set_state(&mut self, q: &[f64], qd: &[f64], root: Option<([f64; 6], [f64; 6])>) {
        let ids = self.link_ids();
        let rotor_ids: Vec<(usize, usize, f64)> = self
            .tree
            .rotors
            .iter()
            .map(|&(i, jr, n)| (i, self.multibody_joints.get(jr).expect("rotor exists").1, n))
            .collect();
        let (mb, _) = self
            .multibody_joints
            .get_mut(self.tree.handles[0])
            .expect("joint exists");
        mb.damping_mut().fill(0.0);
        let mut disp = vec![0.0; mb.ndofs()];
        let mut vel = vec![0.0; mb.ndofs()];
        if let Some((x, v)) = root {
            disp[..6].copy_from_slice(&x);
            vel[..6].copy_from_slice(&v);
        }
        for (i, &l) in ids.iter().enumerate() {
            let d = mb.link(l).expect("link exists").assembly_id();
            disp[d] = q[i];
            vel[d] = qd[i];
        }
        for &(i, l, n) in &rotor_ids {
            let d = mb.link(l).expect("rotor link exists").assembly_id();
            disp[d] = n * q[i];
            vel[d] = n * qd[i];
        }
        mb.apply_displacements(&disp);
        for (d, v) in vel.iter().enumerate() {
            mb.generalized_velocity_mut()[d] = *v;
        }
        mb.forward_kinematics(&self.bodies, false);
        mb.update_rigid_bodies(&mut self.bodies, true);
    }

    /// The rigid body of physid body `b`.
    pub(crate) fn link(&self, b: usize) -> RigidBodyHandle {
        self.tree.links[b]
    }

    /// Advances one time step with the joint torques `tau` (N m) held.
    pub fn step_with_torque(&mut self, tau: &[f64]) {
        for h in self.tree.links.iter().chain(&self.tree.parents) {
            if let Some(b) = self.bodies.get_mut(*h) {
                b.reset_torques(true);
            }
        }
        for (i, &h) in self.tree.links.iter().enumerate() {
            let rot = self.bodies[h].position().rotation;
            let a = rot * vec3(&self.tree.axes[i]);
            self.bodies[h].add_torque(a * tau[i], true);
            let p = self.tree.parents[i];
            if self.bodies[p].is_dynamic() {
                self.bodies[p].add_torque(-a * tau[i], true);
            }
        }
        self.step();
    }

    /// Advances one time step without applied torque.
    pub fn step(&mut self) {
        self.pipeline.step(
            self.gravity,
            &self.params,
            &mut self.islands,
            &mut self.broad_phase,
            &mut self.narrow_phase,
            &mut self.bodies,
            &mut self.colliders,
            &mut self.impulse_joints,
            &mut self.multibody_joints,
            &mut self.soft_bodies,
            &mut self.ccd,
            &(),
            &(),
        );
    }

    /// Inserts rotor `r` as a body of its own, hinged on `parent` (the body carrying it): its
    /// multibody joint's handle.
    fn add_rotor(
        bodies: &mut RigidBodySet,
        joints: &mut MultibodyJointSet,
        parent: RigidBodyHandle,
        r: &physid_core::model::Rotor,
    ) -> Result<MultibodyJointHandle, RapierError> {
        let body = RigidBodyBuilder::dynamic()
            .additional_mass_properties(mass_properties(&r.inertia))
            .build();
        let hr = bodies.insert(body);
        let physid_core::model::Joint::Revolute { axis } = r.joint else {
            return Err(RapierError::Unsupported(format!(
            "rotor '{}' slides (a prismatic mimic); the rapier engine models spinning rotors only",
            r.name
        )));
        };
        let joint = revolute(r.x_rot.to_pose(), &axis);
        joints
            .insert(parent, hr, joint, true)
            .ok_or_else(|| RapierError::Unsupported(format!("rapier refused rotor '{}'", r.name)))
    }

    /// Joint positions (rad) and velocities (rad/s).
    pub fn state(&self) -> (Vec<f64>, Vec<f64>) {
        let (mb, _) = self
            .multibody_joints
            .get(self.tree.handles[0])
            .expect("joint exists");
        let mut q = vec![];
        let mut qd = vec![];
        for l in self.link_ids() {
            let link = mb.link(l).expect("link exists");
            q.push(link.joint().coords()[3]);
            qd.push(mb.generalized_velocity()[link.assembly_id()]);
        }
        (q, qd)
    }
}
/// A revolute joint about `axis` (its own frame) placed by `(rotation, position)` in the
/// parent's frame: rapier turns about the x axis of its joint frames, so both are rotated by
/// the rotation taking x onto the axis.
fn revolute(
    (rotation, position): (Matrix3<f64>, Vector3<f64>),
    axis: &Vector3<f64>,
) -> GenericJoint {
    let onto = x_onto(axis);
    GenericJointBuilder::new(JointAxesMask::LOCKED_REVOLUTE_AXES)
        .local_frame1(Pose::from_parts(vec3(&position), rot3(&(rotation * onto))))
        .local_frame2(Pose::from_parts(Vector::ZERO, rot3(&onto)))
        .build()
}
