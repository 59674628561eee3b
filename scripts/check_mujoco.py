"""Cross-check physid against MuJoCo's mj_inverse and mass matrix on models physid exports to
MJCF: the Cheetah-3 leg with rotors as armature (compared with physid's reflected-inertia
model), the link-only leg, the KUKA LWR4+, and two floating robots with a free joint (the
quadruped with rotors as armature, and Solo12 from its URDF). Also reports how large the rotor gyroscopic
coupling is that the armature model drops (physid's full model minus MuJoCo), and checks
physid's contact model against MuJoCo's on the quadruped standing still (the feet's forces, the
trunk's height and the joints at rest) and in motion: dropped, pushed with its feet sticking, and
pushed on a slippery ground (touchdown, the trunk's height, position and joints, the feet's
loads). Exits non-zero on disagreement.
"""
import csv
import json
import os
import tempfile
import xml.etree.ElementTree as ElementTree

import mujoco
import numpy as np

from physid_common import (KUKA_URDF, SOLO12_URDF, Report, arguments, dynamics, export,
                           identified_quadruped, physid_bin, rel_err, run)

TOL = 1e-9


def physid_model(binary, robot_args):
    return json.loads(run(binary, "model", *robot_args, "--json"))


def mj_compare(report, label, xml_path, dyn, described=None):
    model = mujoco.MjModel.from_xml_path(xml_path)
    if described is not None:
        # The file carries the model's mass (world-mounted rotors included), viscous friction
        # as damping and Coulomb friction as frictionloss; zeroed below so that mj_inverse is
        # the rigid-body torque physid's `dynamics` reports.
        report.add(f"{label}: total mass (world-mounted rotor kept)",
                   abs(model.body_mass.sum() - described["total_mass"]) / described["total_mass"], 1e-12)
        fr = described["joints"]
        want = np.array([[j["friction"]["viscous"], j["friction"]["coulomb"]] for j in fr])
        got = np.stack([model.dof_damping, model.dof_frictionloss], axis=1)
        report.add(f"{label}: damping and frictionloss = physid friction", float(np.abs(got - want).max()), 1e-12)
        lim = np.array([j["limits"][:2] for j in fr], dtype=float)
        finite = np.isfinite(lim).all(axis=1)
        report.add(f"{label}: joint ranges = physid limits",
                   float(np.abs(model.jnt_range[finite] - lim[finite]).max()) if finite.any() else 0.0, 1e-12)
    model.dof_damping[:] = 0
    model.dof_frictionloss[:] = 0
    model.jnt_limited[:] = 0  # random states may lie outside the ranges
    data = mujoco.MjData(model)
    assert model.nv == len(dyn["joint_names"])
    # MuJoCo numbers dofs depth-first; physid's order may differ on a branching tree.
    ids = [model.jnt_dofadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, n)] for n in dyn["joint_names"]]
    e_tau = e_h = 0.0
    taus = []
    for s in dyn["samples"]:
        data.qpos[ids], data.qvel[ids], data.qacc[ids] = s["q"], s["qd"], s["qdd"]
        mujoco.mj_inverse(model, data)
        h = np.zeros((model.nv, model.nv))
        mujoco.mj_fullM(model, data, h)
        e_tau = max(e_tau, rel_err(s["tau"], data.qfrc_inverse[ids]))
        e_h = max(e_h, rel_err(s["H"], h[np.ix_(ids, ids)]))
        taus.append(data.qfrc_inverse[ids].copy())
    report.add(f"{label}: mj_inverse over {len(dyn['samples'])} states", e_tau, TOL)
    report.add(f"{label}: mass matrix (mj_fullM)", e_h, TOL)
    return np.array(taus)


def mj_compare_floating(report, label, binary, robot_args, directory):
    """A floating robot exported as MJCF with a free joint (rotors as armature) against
    physid's floating-base dynamics in the reflected rotor model. MuJoCo's free joint moves
    with qvel = [v_world; ω_body] and pushes with qfrc = [f_world; n_body]; physid uses
    [ω; v] and [n; f] in the trunk frame. With R the trunk's rotation, physid's ν is P ν_mj
    (P maps v_world to Rᵀ v_world), so qfrc_mj = Pᵀ [f_B; τ] and M_mj = Pᵀ M P; the
    free joint's acceleration is d/dt [R v; ω] = [R (v̇ + ω × v); ω̇]."""
    import os
    xml = os.path.join(directory, "floating.xml")
    run(binary, "export", *robot_args, "--floating-base", "--mjcf", xml)
    dyn = dynamics(binary, robot_args + ["--rotor-model", "reflected", "--floating-base"])
    model = mujoco.MjModel.from_xml_path(xml)
    model.dof_damping[:] = 0
    model.dof_frictionloss[:] = 0
    model.jnt_limited[:] = 0
    data = mujoco.MjData(model)
    n = len(dyn["joint_names"])
    assert model.nv == 6 + n, f"MuJoCo has {model.nv} velocities"
    names = [model.joint(j).name for j in range(1, model.njnt)]
    assert names == dyn["joint_names"], f"joint order differs: {names}"
    e_tau = e_m = 0.0
    for s in dyn["samples"]:
        r = np.asarray(s["rotation"])
        w, v = np.asarray(s["v"][:3]), np.asarray(s["v"][3:])
        dw, dv = np.asarray(s["a"][:3]), np.asarray(s["a"][3:])
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, r.flatten())
        data.qpos[:] = np.r_[s["position"], quat, s["q"]]
        data.qvel[:] = np.r_[r @ v, w, s["qd"]]
        data.qacc[:] = np.r_[r @ (dv + np.cross(w, v)), dw, s["qdd"]]
        mujoco.mj_inverse(model, data)
        f_b = np.asarray(s["f_trunk"])
        ours = np.r_[r @ f_b[3:], f_b[:3], s["tau"]]
        e_tau = max(e_tau, rel_err(ours, data.qfrc_inverse))
        p = np.zeros((6 + n, 6 + n))
        p[0:3, 3:6] = np.eye(3)
        p[3:6, 0:3] = r.T
        p[6:, 6:] = np.eye(n)
        h = np.zeros((model.nv, model.nv))
        mujoco.mj_fullM(model, data, h)
        e_m = max(e_m, rel_err(p.T @ np.asarray(s["M"]) @ p, h))
    report.add(f"{label}: mj_inverse with a free joint over {len(dyn['samples'])} states", e_tau, TOL)
    report.add(f"{label}: mass matrix with a free joint (mj_fullM)", e_m, TOL)


def check_identified_quadruped(report, binary, directory):
    """The whole robot identified from a log (`identify-floating --out-mjcf`): MuJoCo loads the
    MJCF with the identified total mass (rotors lumped into their carriers), and the URDF
    written beside it, exported again, has the dynamics physid gives it."""
    found, urdf, xml = identified_quadruped(binary, directory, [])
    model = mujoco.MjModel.from_xml_path(xml)
    total = found["identified_mass"]
    report.add("identified quadruped (identify-floating --out-mjcf): total mass",
               abs(float(model.body_mass.sum()) - total) / total, TOL)
    mj_compare_floating(report, "identified quadruped (its URDF)", binary, ["--robot", urdf], directory)


def mj_standing_quadruped(sim, xml, radius):
    """The exported quadruped in MuJoCo with a floor and a sphere of `radius` at each foot
    point (the only geoms that collide), friction μ of physid's ground, joint friction off
    (physid's smoothed Coulomb friction vanishes at rest), at 0.1 ms steps."""
    text = open(xml).read()
    mu = sim["ground"][2]
    for f in sim["feet"]:
        i = text.index(f'<body name="{f["body"]}"')
        j = text.index("</body>", i)  # a shank carries no other body
        p = " ".join(str(v) for v in f["point"])
        text = (text[:j] + f'<geom name="foot_{f["body"]}" type="sphere" size="{radius}" pos="{p}" '
                f'contype="1" conaffinity="1" friction="{mu} 0.005 0.0001"/>' + text[j:])
    text = text.replace("<worldbody>", '<worldbody><geom name="floor" type="plane" size="10 10 0.1" '
                        f'contype="1" conaffinity="1" friction="{mu} 0.005 0.0001"/>', 1)
    text = text.replace('timestep="0.001" integrator="RK4"', 'timestep="0.0001" integrator="implicitfast"')
    model = mujoco.MjModel.from_xml_string(text)
    model.dof_frictionloss[:] = 0
    model.jnt_limited[:] = 0
    return model


BASE = ["base_x", "base_y", "base_z", "base_qw", "base_qx", "base_qy", "base_qz"]


def log_qpos(row, names):
    """MuJoCo's qpos (free joint, then the hinges `names`) of one row of a floating log."""
    return [float(row[k]) for k in BASE] + [float(row["q_" + n]) for n in names]


def mj_feet_forces(model, data):
    """The ground's force on each foot (world frame), by foot body name."""
    out = {}
    for c in range(data.ncon):
        con = data.contact[c]
        f6 = np.zeros(6)
        mujoco.mj_contactForce(model, data, c, f6)
        names = {model.geom(con.geom1).name, model.geom(con.geom2).name} - {"floor"}
        out[names.pop().removeprefix("foot_")] = con.frame.reshape(3, 3).T @ f6[:3]
    return out


def check_contact_standing_still(report, binary, directory, seconds=4.0):
    """physid's ground (a spring-damper under each point foot, regularized Coulomb friction)
    against MuJoCo's soft contacts: the quadruped standing still under the same PD law from the
    same initial state (`simulate-floating --still --sensors exact`). The robot is symmetric left
    to right, so statics fix how its feet share the weight from where the feet and the centre of
    mass are: this tests the ground's equilibrium and the loaded legs, not the contact's
    dynamics. After `seconds` the feet's normal forces must agree within 0.5 % of the weight. The trunk's height above its feet must
    agree within 1 mm (each engine's own penetration removed: physid's foot sinks F/k, MuJoCo's
    sphere centre is read). The joints agree within 0.01 rad: the feet's small tangential forces
    (a few N, set by how each engine's friction sticks during the settling) bend the legs by
    parts of a hundredth of a radian through the PD gains."""
    log = os.path.join(directory, "still.csv")
    sim = json.loads(run(binary, "simulate-floating", "--still", "--sensors", "exact", "--duration",
                         str(seconds), "--out", log, "--json"))
    xml = os.path.join(directory, "still.xml")
    run(binary, "export", "--floating-base", "--robot", sim["truth"], "--mjcf", xml)
    radius = 0.001
    model = mj_standing_quadruped(sim, xml, radius)
    data = mujoco.MjData(model)
    names = [model.joint(j).name for j in range(1, model.njnt)]
    assert names == sim["joints"], f"joint order differs: {names}"
    with open(log) as f:
        rows = list(csv.DictReader(f))
    data.qpos[:] = log_qpos(rows[0], names)
    data.qpos[2] += radius  # the sphere's bottom where physid's point foot is
    (kp, kd), q_star = sim["gains"], np.tile(sim["posture"], 4)
    for _ in range(int(round(float(rows[-1]["t"]) / model.opt.timestep))):
        data.qfrc_applied[6:] = kp * (q_star - data.qpos[7:]) - kd * data.qvel[6:]
        mujoco.mj_step(model, data)
    mujoco.mj_kinematics(model, data)
    theirs, last = mj_feet_forces(model, data), rows[-1]
    weight = float(model.body_mass.sum()) * 9.81
    ours = {f["body"]: np.array([float(last[f"force_{f['body']}_{a}"]) for a in "xyz"]) for f in sim["feet"]}
    report.add("quadruped standing still: each foot's normal force against MuJoCo, share of the weight",
               max(abs(ours[b][2] - theirs.get(b, np.zeros(3))[2]) for b in ours) / weight, 5e-3)
    k = sim["ground"][0]
    our_feet_z = np.mean([-ours[b][2] / k for b in ours])
    their_feet_z = np.mean([data.geom_xpos[model.geom("foot_" + b).id][2] for b in ours])
    report.add("quadruped standing still: the trunk's height above its feet against MuJoCo (m)",
               abs((float(last["base_z"]) - our_feet_z) - (data.qpos[2] - their_feet_z)), 1e-3)
    q_ours = np.array([float(last["q_" + n]) for n in names])
    report.add("quadruped standing still: joint angles at rest against MuJoCo (rad)",
               float(np.abs(q_ours - data.qpos[7:]).max()), 1e-2)
    tangential = max(np.linalg.norm(f[:2]) / f[2] for f in list(ours.values()) + list(theirs.values()))
    report.add("quadruped standing still: the feet stick (tangential / normal force, both engines, "
               f"below μ = {sim['ground'][2]})", tangential, sim["ground"][2])


def mj_follow(binary, directory, name, args, radius=0.001):
    """physid's run of `simulate-floating <args> --sensors exact` and MuJoCo's from the same
    start (the log's first sample, with `--push`'s velocity) under the same PD law, updated at
    the log's rate and held between updates, and the same joint friction (physid's law,
    `b q̇ + B_c tanh(q̇ / v_f)`, applied as a force; MuJoCo's own damping and dry friction off).
    Per logged sample, for each engine: the trunk's height above its feet (physid's feet placed
    by MuJoCo's kinematics at physid's state), its horizontal position, the joints and each
    foot's normal force."""
    log = os.path.join(directory, f"{name}.csv")
    sim = json.loads(run(binary, "simulate-floating", "--sensors", "exact", "--out", log, "--json", *args))
    xml = os.path.join(directory, f"{name}.xml")
    run(binary, "export", "--floating-base", "--robot", sim["truth"], "--mjcf", xml)
    model = mj_standing_quadruped(sim, xml, radius)
    model.dof_damping[:] = 0
    data = mujoco.MjData(model)
    names = [model.joint(j).name for j in range(1, model.njnt)]
    friction = np.array([[float(a) for a in (j.get("damping"), j.get("frictionloss"))]
                         for j in _mjcf_joints(xml, names)])
    with open(log) as f:
        rows = list(csv.DictReader(f))
    feet = [f["body"] for f in sim["feet"]]
    foot_ids = [model.geom("foot_" + b).id for b in feet]

    def above_feet(d):
        mujoco.mj_kinematics(model, d)
        return d.qpos[2] - np.mean([d.geom_xpos[i][2] for i in foot_ids]) - radius

    data.qpos[:] = log_qpos(rows[0], names)
    data.qpos[2] += radius  # the sphere's bottom where physid's point foot is
    data.qvel[0:3] = sim["push"]
    (kp, kd), q_star = sim["gains"], np.tile(sim["posture"], 4)
    per_sample = int(round((float(rows[1]["t"]) - float(rows[0]["t"])) / model.opt.timestep))
    probe = mujoco.MjData(model)
    ours, theirs = [], []
    for row in rows:
        probe.qpos[:] = log_qpos(row, names)
        ours.append((above_feet(probe), probe.qpos[0:2].copy(), probe.qpos[7:].copy(),
                     [float(row[f"force_{b}_z"]) for b in feet]))
        forces = mj_feet_forces(model, data)
        theirs.append((above_feet(data), data.qpos[0:2].copy(), data.qpos[7:].copy(),
                       [forces.get(b, np.zeros(3))[2] for b in feet]))
        motor = kp * (q_star - data.qpos[7:]) - kd * data.qvel[6:]
        for _ in range(per_sample):
            w = data.qvel[6:]
            data.qfrc_applied[6:] = motor - friction[:, 0] * w - friction[:, 1] * np.tanh(w / sim["friction_speed"])
            mujoco.mj_step(model, data)
    weight = float(model.body_mass.sum()) * 9.81
    return ours, theirs, weight


def _mjcf_joints(xml, names):
    """The exported MJCF's hinge joints' attributes, in `names` order."""
    joints = {j.get("name"): j for j in ElementTree.parse(xml).iter("joint")}
    return [joints[n] for n in names]


def contact_gaps(ours, theirs, weight, settle=200, window=50):
    """The largest differences between two runs: the trunk's height above its feet (m), its
    horizontal position (m), the joints (rad), and each foot's normal force over `window`-sample
    means from sample `settle` on (after the landing), over the weight."""
    height = max(abs(a[0] - b[0]) for a, b in zip(ours, theirs))
    horizontal = max(float(np.linalg.norm(a[1] - b[1])) for a, b in zip(ours, theirs))
    joints = max(float(np.abs(a[2] - b[2]).max()) for a, b in zip(ours, theirs))
    normal = 0.0
    for k in range(settle, len(ours) - window + 1, window):
        a = np.mean([o[3] for o in ours[k:k + window]], axis=0)
        b = np.mean([t[3] for t in theirs[k:k + window]], axis=0)
        normal = max(normal, float(np.abs(a - b).max()) / weight)
    return height, horizontal, joints, normal


def check_contact_dynamics(report, binary, directory):
    """physid's contact in motion against MuJoCo's: the quadruped holding its posture, dropped
    3 cm (touchdown and landing), pushed sideways at 0.5 m/s (its feet stick) and pushed
    forwards at 1 m/s on a ground of μ = 0.15 (its feet slide). The contacts differ (physid's
    spring and damper under a point foot, MuJoCo's soft constraint under a 1 mm sphere), so the
    runs agree to what that difference leaves: bounds of a few millimetres, hundredths of a
    radian and percent of the weight, as for rapier (crates/sim/src/rapier_floating_tests.rs)."""
    cases = [
        ("dropped 3 cm", "drop", ["--drop", "0.03"]),
        ("pushed sideways, feet sticking", "push", ["--push", "0,0.5,0"]),
        ("pushed on a slippery ground (μ 0.15)", "slip", ["--push", "1,0,0", "--ground-friction", "0.15"]),
    ]
    for label, name, args in cases:
        ours, theirs, weight = mj_follow(binary, directory, name, ["--still", "--duration", "1.2", *args])
        height, horizontal, joints, normal = contact_gaps(ours, theirs, weight)
        report.add(f"quadruped {label}: the trunk's height above its feet against MuJoCo (m)", height, 5e-3)
        report.add(f"quadruped {label}: the trunk's horizontal position against MuJoCo (m)", horizontal, 1e-2)
        report.add(f"quadruped {label}: joint angles against MuJoCo (rad)", joints, 2e-2)
        report.add(f"quadruped {label}: each foot's normal force (50 ms means after 0.2 s) against MuJoCo, "
                   "share of the weight", normal, 5e-2)
        if name == "drop":
            fall = (2 * 0.03 / 9.81) ** 0.5
            first = [next(k for k, s in enumerate(run) if sum(s[3]) > 0) * 1e-3 for run in (ours, theirs)]
            report.add("quadruped dropped 3 cm: touchdown after the free fall sqrt(2h/g), both engines (s)",
                       max(abs(t - fall) for t in first), 2e-3)
        if name == "slip":
            travel = [float(run[-1][1][0]) for run in (ours, theirs)]
            report.check(f"quadruped pushed on a slippery ground: its feet slide in both engines (the trunk "
                         f"travels {travel[0]:.3f} and {travel[1]:.3f} m, over 0.2)", min(travel) > 0.2)


# An arm as URDFs are written (not any one robot's): a placeholder <box size="0 0 0"/>, a flat
# plate whose moments, in decimals, exceed A + B = C by 4e-18, a point mass (inertia zeros),
# a massless link between two joints, a thin rod turned off the axes (MuJoCo refuses all five
# if exported as they are, the rod from its own eigendecomposition of a full inertia), on a tree whose branches have branches (MuJoCo numbers dofs depth-first,
# physid need not).
PLACEHOLDER_ARM = """<robot name="placeholder_arm">
  <link name="base"><visual><geometry><box size="0 0 0"/></geometry></visual></link>
  <link name="upper"><inertial><origin xyz="0.1 0 0.02"/><mass value="1.2"/>
    <inertia ixx="0.004" ixy="0.0002" ixz="0" iyy="0.006" iyz="0" izz="0.005"/></inertial>
    <visual><geometry><box size="0 0 0"/></geometry></visual></link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/></joint>
  <link name="plate"><inertial><mass value="0.01"/>
    <inertia ixx="8.53333333333e-07" ixy="0" ixz="0" iyy="1.70666666667e-06" iyz="0" izz="8.53333333333e-07"/></inertial></link>
  <joint name="gripper" type="revolute"><parent link="upper"/><child link="plate"/><origin xyz="0.2 0 0"/><axis xyz="0 1 0"/></joint>
  <link name="tool"><inertial><origin xyz="0 0 0.05"/><mass value="0.3"/>
    <inertia ixx="0.0004" ixy="0" ixz="0" iyy="0.0004" iyz="0" izz="0.0002"/></inertial></link>
  <joint name="wrist" type="revolute"><parent link="upper"/><child link="tool"/><origin xyz="0.2 0 0.05" rpy="0.3 0 0"/><axis xyz="1 0 0"/></joint>
  <link name="finger"><inertial><origin xyz="0.01 0 0"/><mass value="0.05"/>
    <inertia ixx="1e-5" ixy="0" ixz="0" iyy="2e-5" iyz="0" izz="2e-5"/></inertial></link>
  <joint name="finger" type="prismatic"><parent link="plate"/><child link="finger"/><axis xyz="0 1 0"/></joint>
  <link name="camera"><inertial><origin xyz="0.02 0 0"/><mass value="0.2"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>
  <link name="tilt_link"/>
  <joint name="tilt" type="revolute"><parent link="base"/><child link="tilt_link"/><origin xyz="0.3 0 0.1"/><axis xyz="0 1 0"/></joint>
  <joint name="pan" type="continuous"><parent link="tilt_link"/><child link="camera"/><axis xyz="0 0 1"/></joint>
  <link name="rod"><inertial><origin xyz="0 0 0.1"/><mass value="0.4"/><inertia ixx="0.0013" ixy="0" ixz="0" iyy="0.0013" iyz="0" izz="0"/></inertial></link>
  <joint name="rod_joint" type="revolute"><parent link="tool"/><child link="rod"/><origin xyz="0 0 0.1" rpy="0.2 0.7 -0.4"/><axis xyz="0 1 0"/></joint>
</robot>"""


def check_placeholder_arm(report, binary, directory):
    urdf = os.path.join(directory, "placeholder_arm.urdf")
    with open(urdf, "w") as f:
        f.write(PLACEHOLDER_ARM)
    xml = export(binary, ["--robot", urdf], "mjcf", directory)
    dyn = dynamics(binary, ["--robot", urdf])
    mj_compare(report, "arm with placeholder shapes, a flat plate, a point mass, a massless link and a thin rod", xml, dyn)


def main():
    binary = physid_bin(arguments(__doc__).physid)
    report = Report("check_mujoco")
    with tempfile.TemporaryDirectory() as d:
        xml = export(binary, ["--robot", "cheetah3"], "mjcf", d)
        refl = dynamics(binary, ["--robot", "cheetah3", "--rotor-model", "reflected"])
        mj_tau = mj_compare(report, "Cheetah-3 leg, rotors as armature", xml, refl,
                            physid_model(binary, ["--robot", "cheetah3"]))
        full = dynamics(binary, ["--robot", "cheetah3"])
        gyro = np.abs(np.array([s["tau"] for s in full["samples"]]) - mj_tau).max(axis=0)
        print(f"     rotor coupling dropped by the armature model: max |tau_full - tau_mujoco| = {np.round(gyro, 4)} N m")
        if not np.all(gyro > 1e-3):
            report.add("full rotor model differs from armature (expected)", 1.0, 0.0)
        xml = export(binary, ["--robot", "cheetah3", "--no-rotors"], "mjcf", d)
        mj_compare(report, "link-only Cheetah-3 leg", xml, dynamics(binary, ["--robot", "cheetah3", "--no-rotors"]))
        xml = export(binary, ["--robot", KUKA_URDF], "mjcf", d)
        kuka = mujoco.MjModel.from_xml_path(xml)
        n_geoms = int((kuka.geom_group == 1).sum())
        report.add(f"KUKA LWR4+: {n_geoms} shape geoms from the URDF (spheres, cylinders, the wrist mesh)",
                   0.0 if n_geoms >= 17 else 1.0, 0.0)
        mj_compare(report, "KUKA LWR4+ (physid import -> MJCF)", xml, dynamics(binary, ["--robot", KUKA_URDF]),
                   physid_model(binary, ["--robot", KUKA_URDF]))
        mj_compare_floating(report, "quadruped, rotors as armature", binary, ["--robot", "cheetah3"], d)
        mj_compare_floating(report, "Solo12 (floating URDF)", binary, ["--robot", SOLO12_URDF], d)
        check_identified_quadruped(report, binary, d)
        check_contact_standing_still(report, binary, d)
        check_contact_dynamics(report, binary, d)
        check_placeholder_arm(report, binary, d)
    report.finish()


if __name__ == "__main__":
    main()
