"""physid on a robot it was not built around, with logs as robots write them.

Ground truth for the Franka Panda (data/panda) is made with pinocchio (scripts/panda_truth.py:
each link a uniform solid of its collision hull, masses scaled, viscous + Coulomb friction,
0.08 N m torque noise, small position and velocity noise), over 40 s at 1 kHz with a 0.5 s
dropout and 2 % of the samples dropped at random. It is written as ROS 2 bags (rosbags; MCAP and
SQLite storage) and as a CSV, without accelerations, joints shuffled, the gripper fingers still
with zero effort (as franka_gripper publishes), and a joint the robot does not have.

Checked:
- the reported held-out RMS is within 10 % of the same identified model scored by pinocchio on
  the true states (q, q̇, q̈ of the truth, the logged torque);
- the identified friction is within 15 % of the truth on every arm joint;
- the MCAP bag, the SQLite bag and the CSV identify the same model;
- `physid diagnose` on this clean case says no effect;
- the gap splits the run, the dropped samples are counted, the finger is locked;
- physid's model of the mimic finger (a sliding rotor) is pinocchio's with mimic=True: mass
  matrix and torques at random states.
"""
import json
import os
import tempfile

import numpy as np
import pinocchio as pin

import panda_truth as P
from physid_common import Report, arguments, dynamics, physid_bin, run

SEED = 1


def identify(binary, data, directory, name, extra=()):
    out = os.path.join(directory, f"{name}.json")
    urdf = os.path.join(directory, f"{name}.urdf")
    text = run(binary, "identify", "--data", data, "--robot", P.URDF, "--json", "--out-urdf", urdf, *extra)
    with open(out, "w") as f:
        f.write(text)
    return json.loads(text), urdf


def true_state_rms(exp, urdf, ident, rows):
    """RMS of the logged torque minus the identified model's prediction on the true states."""
    model = pin.buildModelFromUrdf(urdf)
    data = model.createData()
    viscous = np.array(ident["friction"]["viscous"][:7])
    coulomb = np.array(ident["friction"]["coulomb"][:7])
    pred = P.arm_torques(model, data, exp["q"][rows], exp["qd"][rows], exp["qdd"][rows], viscous, coulomb)
    return float(np.sqrt(((exp["tau"][rows] - pred) ** 2).mean()))


def check_mimic(report, binary):
    """The mimic finger: physid's sliding rotor against pinocchio's mimic joint."""
    model = pin.buildModelFromUrdf(P.URDF, mimic=True)
    data = model.createData()
    dyn = dynamics(binary, ["--robot", P.URDF], samples=12, seed=5)
    report.check(f"pinocchio (mimic=True) has physid's {len(dyn['joint_names'])} degrees of freedom", model.nv == len(dyn["joint_names"]))
    e_tau = e_h = 0.0
    for s in dyn["samples"]:
        q, v, a = (np.asarray(s[k]) for k in ("q", "qd", "qdd"))
        tau = pin.rnea(model, data, q, v, a)
        h = pin.crba(model, data, q)
        h = np.triu(h) + np.triu(h, 1).T
        e_tau = max(e_tau, float(np.max(np.abs(tau - s["tau"])) / (1 + np.max(np.abs(tau)))))
        e_h = max(e_h, float(np.max(np.abs(h - np.asarray(s["H"]))) / (1 + np.max(np.abs(h)))))
    report.add("Panda with its mimic finger: rnea vs pinocchio mimic=True", e_tau, 1e-9)
    report.add("Panda with its mimic finger: mass matrix vs pinocchio", e_h, 1e-9)


def main():
    binary = physid_bin(arguments(__doc__).physid)
    report = Report("Panda (pinocchio truth, logs as robots write them)")
    check_mimic(report, binary)
    with tempfile.TemporaryDirectory() as d:
        exp = P.experiment(SEED, workdir=d)
        q, qd = P.logged(exp, SEED)
        bag, bag_sql, csv_path = (os.path.join(d, x) for x in ("bag", "bag_sql", "data.csv"))
        P.write_bag(bag, exp, q, qd)
        P.write_bag(bag_sql, exp, q, qd, storage="sqlite3")
        P.write_csv(csv_path, exp, q, qd)
        m = len(exp["t"])
        cut = int(0.7 * m)
        split = ["--train", f"0:{cut}", "--validate", f"{cut}:{m}"]
        ident, urdf = identify(binary, bag, d, "bag", [*split, "--stamp", "header"])
        pipe = ident["data_pipeline"][0]["pipeline"]
        report.check(f"the 0.5 s dropout splits the bag into 2 runs (got {pipe['runs']})", pipe["runs"] == 2 and len(pipe["gaps"]) == 1)
        dropped = int(round(40_000 - 500 - m))
        report.check(f"the {dropped} samples dropped at random are counted as bridged ({pipe['missing_bridged']})", abs(pipe["missing_bridged"] - dropped) <= 2)
        report.check("q̈ derived, the finger locked (its effort is never measured)", pipe["derived_qdd"] and not pipe["derived_qd"] and pipe["locked"] == ["panda_finger_joint1"])
        reported = ident["validation"]["rms_overall"]
        truth_rms = true_state_rms(exp, urdf, ident, slice(cut, m))
        floor = float(np.sqrt(((exp["tau"][cut:] - exp["tau_true"][cut:]) ** 2).mean()))
        print(f"     held-out RMS: reported {reported:.4f} N m, the same model on the true states {truth_rms:.4f}, noise {floor:.4f}")
        report.add("reported held-out RMS against the true-state score (relative)", abs(reported / truth_rms - 1), 0.10)
        b, bc = np.array(ident["friction"]["viscous"][:7]), np.array(ident["friction"]["coulomb"][:7])
        report.add("viscous friction against the truth (relative, worst joint)", float(np.max(np.abs(b / P.VISCOUS - 1))), 0.15)
        report.add("Coulomb friction against the truth (relative, worst joint)", float(np.max(np.abs(bc / P.COULOMB - 1))), 0.15)
        theta = np.array(ident["theta"])
        for label, data, extra in (("SQLite bag", bag_sql, ["--stamp", "header"]), ("CSV", csv_path, [])):
            other, _ = identify(binary, data, d, label.replace(" ", "_"), [*split, *extra])
            err = float(np.max(np.abs(np.array(other["theta"]) - theta)) / (1 + np.max(np.abs(theta))))
            report.add(f"the {label} identifies the MCAP bag's model", err, 1e-6)
        diag = json.loads(run(binary, "diagnose", "--data", bag, "--robot", P.URDF, "--stamp", "header", "--json"))
        print(f"     diagnose: {diag['verdict']}: {diag['summary'][:160]}")
        report.check(f"diagnose on the clean case: no effect (verdict {diag['verdict']}, {len(diag['effects'])} effects)", diag["verdict"] == "no_effect" and not diag["effects"])
    report.finish()


if __name__ == "__main__":
    main()
