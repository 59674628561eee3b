"""Cross-check physid against MuJoCo's mj_inverse and mass matrix on models physid exports to
MJCF: the Cheetah-3 leg with rotors as armature (compared with physid's reflected-inertia
model), the link-only leg, and the KUKA LWR4+. Also reports how large the rotor gyroscopic
coupling is that the armature model drops (physid's full model minus MuJoCo). Exits non-zero
on disagreement.

usage: python scripts/check_mujoco.py [--physid PATH]
"""
import json
import sys
import tempfile

import mujoco
import numpy as np

from physid_common import KUKA_URDF, Report, dynamics, export, physid_bin, rel_err, run

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
    e_tau = e_h = 0.0
    taus = []
    for s in dyn["samples"]:
        data.qpos[:], data.qvel[:], data.qacc[:] = s["q"], s["qd"], s["qdd"]
        mujoco.mj_inverse(model, data)
        h = np.zeros((model.nv, model.nv))
        mujoco.mj_fullM(model, data, h)
        e_tau = max(e_tau, rel_err(s["tau"], data.qfrc_inverse))
        e_h = max(e_h, rel_err(s["H"], h))
        taus.append(data.qfrc_inverse.copy())
    report.add(f"{label}: mj_inverse over {len(dyn['samples'])} states", e_tau, TOL)
    report.add(f"{label}: mass matrix (mj_fullM)", e_h, TOL)
    return np.array(taus)


def main():
    binary = physid_bin(sys.argv)
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
    report.finish()


if __name__ == "__main__":
    main()
