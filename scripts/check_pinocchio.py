"""Cross-check physid against pinocchio: RNEA torques, the joint-torque regressor and the
inertial parameters read from URDF, on the link-only Cheetah-3 leg (exported by physid as URDF)
and on the real KUKA LWR4+ URDF (read by both); and RNEA of the full leg with its rotors, exported
as URDF mimic joints and loaded with mimic=True; and a KUKA model identified on its real logs,
written into the KUKA's own URDF by `identify --out-urdf`. Exits non-zero on disagreement.
"""
import os
import sys
import tempfile

import numpy as np
import pinocchio as pin

from physid_common import (KUKA_URDF, SOLO12_URDF, PIN_FROM_PAPER, Report, arguments, dynamics,
                           export, identified_quadruped, physid_bin, rel_err, run)

TOL = 1e-9


def check(report, label, urdf_path, dyn):
    model = pin.buildModelFromUrdf(urdf_path)
    data = model.createData()
    assert model.nq == model.nv == len(dyn["joint_names"]), "joint count differs"
    names = list(model.names)[1:]
    if names != dyn["joint_names"]:
        sys.exit(f"{label}: joint order differs: pinocchio {names} vs physid {dyn['joint_names']}")
    n = model.nv
    # Inertial parameters as each reads them from the URDF.
    theta = np.asarray(dyn["theta"])
    pin_theta = np.concatenate([model.inertias[i + 1].toDynamicParameters()[PIN_FROM_PAPER] for i in range(n)])
    report.add(f"{label}: inertial parameters from URDF", rel_err(theta[: 10 * n], pin_theta), TOL)
    perm = np.concatenate([10 * i + np.array(PIN_FROM_PAPER) for i in range(n)])
    e_tau = e_y = 0.0
    for s in dyn["samples"]:
        q, v, a = (np.asarray(s[k]) for k in ("q", "qd", "qdd"))
        tau = pin.rnea(model, data, q, v, a)
        y = pin.computeJointTorqueRegressor(model, data, q, v, a)
        e_tau = max(e_tau, rel_err(s["tau"], tau))
        e_y = max(e_y, rel_err(np.asarray(s["Y"])[:, : 10 * n], y[:, perm]))
    report.add(f"{label}: rnea over {len(dyn['samples'])} random states", e_tau, TOL)
    report.add(f"{label}: joint torque regressor (link columns)", e_y, TOL)


def check_rotors(report, binary, directory):
    """The full leg exported as URDF (rotors as revolute joints mimicking theirs with the gear
    ratio as multiplier), loaded by pinocchio with mimic=True: its RNEA is physid's full rotor
    model (rotor bodies spinning at N q', gyroscopic coupling kept)."""
    urdf = export(binary, ["--robot", "cheetah3"], "urdf", directory)
    model = pin.buildModelFromUrdf(urdf, mimic=True)
    data = model.createData()
    dyn = dynamics(binary, ["--robot", "cheetah3"])
    assert model.nv == len(dyn["joint_names"]), f"pinocchio has {model.nv} velocities"
    e_tau = 0.0
    for s in dyn["samples"]:
        q, v, a = (np.asarray(s[k]) for k in ("q", "qd", "qdd"))
        e_tau = max(e_tau, rel_err(s["tau"], pin.rnea(model, data, q, v, a)))
    report.add("Cheetah-3 leg with rotors (URDF mimic=True): rnea", e_tau, TOL)


def check_identified_kuka(report, binary, directory):
    """`identify --out-urdf` on the KUKA logs patches the KUKA's own URDF (geometry, meshes,
    transmissions kept): pinocchio reads exactly the identified inertias from it, and its RNEA
    equals physid's on the exported pair (URDF + sidecar)."""
    import json
    import os
    out = os.path.join(directory, "kuka_identified.urdf")
    data = os.path.join(os.path.dirname(KUKA_URDF), "measurements_1.csv")
    stdout = run(binary, "identify", "--robot", KUKA_URDF, "--data", data, "--json",
                 "--friction", "viscous,coulomb,offset", "--out-urdf", out)
    pi = np.concatenate([b["pi"] for b in json.loads(stdout)["bodies"]])
    model = pin.buildModelFromUrdf(out)
    n = model.nv
    pin_pi = np.concatenate([model.inertias[i + 1].toDynamicParameters()[PIN_FROM_PAPER] for i in range(n)])
    report.add("identified KUKA, patched URDF: pinocchio's inertias = identify's", rel_err(pi, pin_pi), 1e-12)
    sidecar = os.path.join(directory, "kuka_identified.physid.toml")
    check(report, "identified KUKA (patched URDF + sidecar)", out, dynamics(binary, ["--robot", sidecar]))


def check_floating(report, binary, directory, rotors, urdf=None):
    """The Cheetah-3-like quadruped on a floating trunk (`dynamics --floating-base`): its tree
    exported as URDF, loaded under pinocchio's free flyer (rotors as mimic joints) with the
    trunk's inertia set from physid's; RNEA (trunk wrench and joint torques), CRBA, the
    regressor's inertial columns (link-only) and the feet's Jacobians on random trunk and joint
    states. pinocchio orders the free flyer's velocity and wrench linear first, physid angular
    first: swapped here."""
    import os
    if urdf is None:
        args = ["--robot", "cheetah3"] + ([] if rotors else ["--no-rotors"])
        dyn = dynamics(binary, args + ["--floating-base"])
        path = os.path.join(directory, f"quadruped_{int(rotors)}.urdf")
        with open(path, "w") as f:
            f.write(dyn["tree_urdf"])
        model = pin.buildModelFromUrdf(path, pin.JointModelFreeFlyer(), rotors)
        # physid's export of the tree has no trunk inertia: set it from physid's.
        pin_pi = np.zeros(10)
        pin_pi[PIN_FROM_PAPER] = dyn["trunk_pi"]
        model.inertias[1] = pin.Inertia.FromDynamicParameters(pin_pi)
        label = "quadruped " + ("with rotors (mimic)" if rotors else "link-only")
    else:
        # Both read the same URDF: pinocchio's free flyer carries the root link and the links
        # fixed to it, as physid's trunk does.
        dyn = dynamics(binary, ["--robot", urdf, "--floating-base"])
        model = pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer())
        label = os.path.basename(urdf) + " (floating URDF)"
        pin_trunk = model.inertias[1].toDynamicParameters()[PIN_FROM_PAPER]
        report.add(f"{label}: trunk inertia read from URDF", rel_err(dyn["trunk_pi"], pin_trunk), TOL)
    data = model.createData()
    n = len(dyn["joint_names"])
    # pinocchio orders sibling links by name; map physid's joints by theirs.
    jids = [model.getJointId(name) for name in dyn["joint_names"]]
    if any(j >= model.njoints for j in jids) or model.nv != 6 + n:
        sys.exit(f"quadruped: pinocchio's joints {list(model.names)} do not match {dyn['joint_names']}")
    vi = np.array([model.joints[j].idx_v for j in jids])
    nu = np.r_[3, 4, 5, 0, 1, 2, vi]  # physid's ν entry i is pinocchio's nu[i]
    e_tau = e_m = e_y = e_j = 0.0
    for s in dyn["samples"]:
        q = np.zeros(model.nq)
        q[:3] = s["position"]
        q[3:7] = pin.Quaternion(np.asarray(s["rotation"])).coeffs()
        q[vi + 1] = s["q"]
        v, a = np.zeros(model.nv), np.zeros(model.nv)
        v[nu] = np.r_[s["v"], s["qd"]]
        a[nu] = np.r_[s["a"], s["qdd"]]
        ours = np.r_[s["f_trunk"], s["tau"]]
        e_tau = max(e_tau, rel_err(ours, pin.rnea(model, data, q, v, a)[nu]))
        m = pin.crba(model, data, q)
        m = np.triu(m) + np.triu(m, 1).T
        e_m = max(e_m, rel_err(np.asarray(s["M"]), m[np.ix_(nu, nu)]))
        if not rotors:
            y = pin.computeJointTorqueRegressor(model, data, q, v, a)
            bodies = [1] + jids  # the trunk, then physid's bodies
            cols = np.concatenate([10 * (j - 1) + np.array(PIN_FROM_PAPER) for j in bodies])
            e_y = max(e_y, rel_err(np.asarray(s["Y"])[:, : 10 * (n + 1)], y[np.ix_(nu, cols)]))
        pin.computeJointJacobians(model, data, q)
        for body, point, jac in zip(dyn["feet"], dyn["foot_points"], s["foot_jacobians"]):
            jid = jids[body]
            j6 = pin.getJointJacobian(model, data, jid, pin.LOCAL_WORLD_ALIGNED)
            r = data.oMi[jid].rotation @ np.asarray(point)
            j_point = j6[:3] - pin.skew(r) @ j6[3:]
            e_j = max(e_j, rel_err(np.asarray(jac), j_point[:, nu]))
    count = len(dyn["samples"])
    report.add(f"{label}: rnea (trunk wrench, joint torques) over {count} random states", e_tau, TOL)
    report.add(f"{label}: mass matrix", e_m, TOL)
    if not rotors:
        report.add(f"{label}: regressor (trunk and link columns)", e_y, TOL)
    report.add(f"{label}: feet Jacobians", e_j, TOL)


def check_identified_quadruped(report, binary, directory):
    """The whole robot identified from a log (`identify-floating --out-urdf`, link-only):
    pinocchio reads the URDF under a free flyer with the identified trunk and total mass, and
    its dynamics equal physid's of the same file (`check_floating`)."""
    found, urdf, _ = identified_quadruped(binary, directory, ["--no-rotors"])
    model = pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer())
    label = "identified quadruped (identify-floating --out-urdf)"
    trunk = model.inertias[1].toDynamicParameters()[PIN_FROM_PAPER]
    report.add(f"{label}: trunk as identified", rel_err(np.asarray(found["bodies"][0]["pi"]), trunk), TOL)
    total = found["identified_mass"]
    report.add(f"{label}: total mass", abs(pin.computeTotalMass(model) - total) / total, TOL)
    check_floating(report, binary, directory, rotors=False, urdf=urdf)


# An arm written the way ROS descriptions are (not any one robot's): a Gazebo plugin's
# <jointName> after each joint, a joint with two <origin> (urdfdom reads the first), a visual
# with two <material>, a fixed joint whose <axis> is misspelt (urdfdom, and so pinocchio,
# refuses a <limit> without velocity, which physid reads as not given).
ROS_STYLE_ARM = """<robot name="ros_style_arm">
  <material name="grey"><color rgba="0.5 0.5 0.5 1"/></material>
  <link name="world_base"/>
  <link name="base"><visual><geometry><box size="0.1 0.1 0.1"/></geometry><material name=""/><material name="grey"/></visual></link>
  <joint name="mount" type="fixed"><parent link="world_base"/><child link="base"/><axis xzy="0 0 1"/><origin xyz="0 0 0.05"/></joint>
{links}
</robot>"""
ROS_STYLE_LINK = """  <link name="l{i}"><inertial><origin xyz="{cx} 0.01 -0.02" rpy="0.1 0 0.2"/><mass value="{m}"/>
    <inertia ixx="0.004" ixy="0.0003" ixz="0" iyy="0.005" iyz="0.0001" izz="0.003"/></inertial></link>
  <joint name="j{i}" type="revolute"><parent link="{parent}"/><child link="l{i}"/>
    <origin xyz="0.{i} 0 0.3" rpy="{rpy}"/><origin xyz="9 9 9"/><axis xyz="{axis}"/>
    <limit lower="-2" upper="2" effort="30" velocity="2"/><dynamics damping="0" friction="0"/></joint>
  <gazebo><plugin name="ft{i}" filename="libgazebo_ros_ft_sensor.so"><jointName>j{i}</jointName></plugin></gazebo>"""


def check_ros_style_arm(report, binary, directory):
    links = "\n".join(
        ROS_STYLE_LINK.format(i=i, parent="base" if i == 1 else f"l{i - 1}", cx=0.05 * i, m=1.5 - 0.3 * i,
                              rpy=f"{0.3 * i} -0.2 0.1", axis=["0 0 1", "0 1 0", "1 0 0"][i - 1])
        for i in (1, 2, 3))
    urdf = os.path.join(directory, "ros_style_arm.urdf")
    with open(urdf, "w") as f:
        f.write(ROS_STYLE_ARM.format(links=links))
    check(report, "arm as ROS descriptions write it (plugins' <jointName>, repeated <origin>)", urdf,
          dynamics(binary, ["--robot", urdf]))


def main():
    binary = physid_bin(arguments(__doc__).physid)
    report = Report("check_pinocchio")
    with tempfile.TemporaryDirectory() as d:
        leg = ["--robot", "cheetah3", "--no-rotors"]
        urdf = export(binary, leg, "urdf", d)
        check(report, "link-only Cheetah-3 leg", urdf, dynamics(binary, ["--robot", urdf]))
        check_rotors(report, binary, d)
        check_identified_kuka(report, binary, d)
        check_floating(report, binary, d, rotors=False)
        check_floating(report, binary, d, rotors=True)
        check_floating(report, binary, d, rotors=False, urdf=SOLO12_URDF)
        check_identified_quadruped(report, binary, d)
        check_ros_style_arm(report, binary, d)
    check(report, "KUKA LWR4+ (data/kuka_lwr4 URDF)", KUKA_URDF, dynamics(binary, ["--robot", KUKA_URDF]))
    report.finish()


if __name__ == "__main__":
    main()
