"""Cross-check physid against pinocchio: RNEA torques, the joint-torque regressor and the
inertial parameters read from URDF, on the link-only Cheetah-3 leg (exported by physid as URDF)
and on the real KUKA LWR4+ URDF (read by both); and RNEA of the full leg with its rotors, exported
as URDF mimic joints and loaded with mimic=True; and a KUKA model identified on its real logs,
written into the KUKA's own URDF by `identify --out-urdf`. Exits non-zero on disagreement.

usage: python scripts/check_pinocchio.py [--physid PATH]
"""
import sys
import tempfile

import numpy as np
import pinocchio as pin

from physid_common import KUKA_URDF, PIN_FROM_PAPER, Report, dynamics, export, physid_bin, rel_err, run

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


def main():
    binary = physid_bin(sys.argv)
    report = Report("check_pinocchio")
    with tempfile.TemporaryDirectory() as d:
        leg = ["--robot", "cheetah3", "--no-rotors"]
        urdf = export(binary, leg, "urdf", d)
        check(report, "link-only Cheetah-3 leg", urdf, dynamics(binary, ["--robot", urdf]))
        check_rotors(report, binary, d)
        check_identified_kuka(report, binary, d)
    check(report, "KUKA LWR4+ (data/kuka_lwr4 URDF)", KUKA_URDF, dynamics(binary, ["--robot", KUKA_URDF]))
    report.finish()


if __name__ == "__main__":
    main()
