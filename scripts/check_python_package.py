"""The Python package `physid` (python/: PyO3 over the library's entry points) against the CLI
and against pinocchio.

Checked:
- `Robot(...).describe()` equals `physid model --json` (KUKA, the leg);
- the batch dynamics over numpy arrays equal pinocchio's RNEA, CRBA and its regressor-free
  torque on random KUKA states, and `Y @ theta = tau`;
- `identify_arrays` on torques pinocchio computes for a KUKA whose links are not the
  description's (masses scaled, centres of mass moved: a robot the repository does not hold)
  predicts held-out torques of that robot (relative RMS below 1e-9 by least squares, 1e-5
  under the consistent set's LMI margin), and equals `physid identify`
  on the same samples written as CSV (theta to 1e-9);
- bad arrays raise ValueError naming the array, sample and joint;
- python/examples/identify_from_arrays.py runs.

The package folder (`--package DIR`, default $PHYSID_PYTHON) holds physid/ with the extension
built, as scripts/test.sh makes it.
"""
import json
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

from physid_common import KUKA_URDF, PACKAGE_OPTION, arguments, on_path, physid_bin, run

args = arguments(__doc__, PACKAGE_OPTION)
package = args.package
on_path(package)
import physid  # noqa: E402

passed, failed = 0, 0


def check(name, ok, detail=""):
    global passed, failed
    print(f"{'ok  ' if ok else 'FAIL'} {name} {detail}")
    passed, failed = passed + ok, failed + (not ok)


binary = physid_bin(args.physid)

# describe() is the CLI's model JSON.
for robot in [KUKA_URDF, "cheetah3"]:
    cli = json.loads(run(binary, "model", "--robot", robot, "--json"))
    check(f"describe() == model --json ({os.path.basename(robot)})", physid.Robot(robot).describe() == cli)

# Batch dynamics against pinocchio on the KUKA.
robot = physid.Robot(KUKA_URDF)
n = robot.dof
model = pin.buildModelFromUrdf(KUKA_URDF)
data = model.createData()
idx = [model.joints[model.getJointId(j)].idx_v for j in robot.joint_names]
rng = np.random.default_rng(5)
q, qd, qdd = (rng.uniform(-1.5, 1.5, size=(40, n)) for _ in range(3))
tau = robot.inverse_dynamics(q, qd, qdd)
H = robot.mass_matrix(q)
Y = robot.regressor(q, qd, qdd)
friction = np.array([[b["friction"]["viscous"], b["friction"]["coulomb"]] for b in robot.describe()["joints"]])


def pin_full(v):
    out = np.zeros(model.nv)
    out[idx] = v
    return out


tau_pin = np.array([pin.rnea(model, data, pin_full(a), pin_full(b), pin_full(c))[idx]
                    for a, b, c in zip(q, qd, qdd)]) + friction[:, 0] * qd + friction[:, 1] * np.sign(qd)
H_pin = np.array([pin.crba(model, data, pin_full(a))[np.ix_(idx, idx)] for a in q])
check("inverse_dynamics == pinocchio RNEA + friction", np.abs(tau - tau_pin).max() < 1e-9,
      f"(max {np.abs(tau - tau_pin).max():.1e} N m)")
H_pin = np.triu(H_pin) + np.transpose(np.triu(H_pin, 1), (0, 2, 1))
check("mass_matrix == pinocchio CRBA", np.abs(H - H_pin).max() < 1e-9, f"(max {np.abs(H - H_pin).max():.1e})")
check("regressor @ theta == inverse_dynamics", np.abs(Y @ robot.parameters() - tau).max() < 1e-9)
check("shapes", tau.shape == (40, n) and H.shape == (40, n, n) and Y.shape == (40, n, len(robot.parameter_names)))

# A robot the repository does not hold: the KUKA's links with other masses and centres of mass.
with tempfile.TemporaryDirectory() as d:
    tree = ET.parse(KUKA_URDF)
    prng = np.random.default_rng(11)
    for link in tree.getroot().findall("link"):
        inertial = link.find("inertial")
        if inertial is None:
            continue
        mass = inertial.find("mass")
        mass.set("value", repr(float(mass.get("value")) * prng.uniform(0.8, 1.25)))
        origin = inertial.find("origin")
        xyz = np.array([float(x) for x in (origin.get("xyz") or "0 0 0").split()]) + prng.normal(scale=0.01, size=3)
        origin.set("xyz", " ".join(repr(float(x)) for x in xyz))
    truth_path = os.path.join(d, "truth.urdf")
    tree.write(truth_path)
    truth = pin.buildModelFromUrdf(truth_path)
    tdata = truth.createData()
    t = np.arange(4000) / 1000.0
    w = 2 * np.pi * np.array([0.3, 0.5, 0.7, 0.4, 0.6, 0.8, 0.9])
    phase = rng.uniform(0, 2 * np.pi, size=n)
    q = 1.0 * np.sin(w * t[:, None] + phase) + 0.3 * np.sin(3 * w * t[:, None])
    qd = 1.0 * w * np.cos(w * t[:, None] + phase) + 0.9 * w * np.cos(3 * w * t[:, None])
    qdd = -1.0 * w**2 * np.sin(w * t[:, None] + phase) - 2.7 * w**2 * np.sin(3 * w * t[:, None])
    tau = np.array([pin.rnea(truth, tdata, pin_full(a), pin_full(b), pin_full(c))[idx] for a, b, c in zip(q, qd, qdd)])
    train, held = slice(0, 3000), slice(3000, 4000)
    # Least squares recovers what the data determine to round-off; the consistent set to the
    # LMI margin (J ⪰ ε·1, ε = 1e-6) and the conic solver's tolerance.
    for constraints, tol in [("none", 1e-9), ("consistent", 1e-5)]:
        fit = physid.identify_arrays(robot, q[train], qd[train], qdd[train], tau[train],
                                      constraints=constraints, prior_weight=1e-10)
        pred = robot.regressor(q[held], qd[held], qdd[held]) @ fit.theta
        rel = np.sqrt(np.mean((pred - tau[held]) ** 2)) / np.sqrt(np.mean(tau[held] ** 2))
        check(f"identify_arrays ({constraints}) predicts the unseen robot's held-out torque",
              rel < tol and fit.constraints_hold,
              f"(relative RMS {rel:.1e} < {tol:.0e}, constraints hold: {fit.constraints_hold})")
    # The same samples through the CLI.
    csv = os.path.join(d, "samples.csv")
    cols = (["t"] + [f"q{i + 1}" for i in range(n)] + [f"dq{i + 1}" for i in range(n)]
            + [f"ddq{i + 1}" for i in range(n)] + [f"tau{i + 1}" for i in range(n)])
    np.savetxt(csv, np.column_stack([t[train], q[train], qd[train], qdd[train], tau[train]]), delimiter=",",
               header=",".join(cols), comments="", fmt="%.17g")
    cli = json.loads(run(binary, "identify", "--robot", KUKA_URDF, "--data", csv, "--constraints", "consistent",
                         "--prior-weight", "1e-10", "--json"))
    diff = np.abs(np.array(cli["theta"]) - fit.theta).max() / np.abs(fit.theta).max()
    check("identify_arrays == physid identify on the same samples", diff < 1e-9, f"(θ differ by {diff:.1e} relative)")

# Bad arrays.
for name, args, words in [
    ("wrong width", (np.zeros((3, n - 1)), np.zeros((3, n)), np.zeros((3, n))), "q has shape"),
    ("NaN", (np.zeros((3, n)), np.zeros((3, n)), np.where(np.arange(3 * n).reshape(3, n) == n + 2, np.nan, 0.0)),
     "qdd: sample 1, joint 2 is NaN"),
    ("sample counts", (np.zeros((3, n)), np.zeros((2, n)), np.zeros((3, n))), "qd has 2 samples, q has 3"),
]:
    try:
        robot.inverse_dynamics(*args)
        check(f"bad input ({name}) raises", False, "(no error)")
    except ValueError as e:
        check(f"bad input ({name}) raises ValueError naming it", words in str(e), f"({e})")
z, nan_at = np.zeros((3, n)), np.where(np.arange(3 * n).reshape(3, n) == n + 2, np.nan, 0.0)
for name, args, words in [
    # As the data pipeline names a value of a logged file: sample and column (tau3: joint 2 of 0..n-1).
    ("NaN torque", (z, z, z, nan_at), "sample 1 (t = 0.001 s): tau3 is NaN"),
    ("sample counts", (z, np.zeros((2, n)), z, z), f"qd has shape (2, {n}): q has shape (3, {n})"),
]:
    try:
        physid.identify_arrays(robot, *args)
        check(f"identify_arrays bad input ({name}) raises", False, "(no error)")
    except ValueError as e:
        check(f"identify_arrays bad input ({name}) raises ValueError naming it", words in str(e), f"({e})")
try:
    physid.Robot("/nonexistent/arm.urdf")
    check("a missing robot file raises", False)
except FileNotFoundError as e:
    check("a missing robot file raises FileNotFoundError naming it", e.filename == "/nonexistent/arm.urdf", f"({e})")

# The example a user copies runs as shipped.
example = os.path.join(os.path.dirname(KUKA_URDF), "..", "..", "python", "examples", "identify_from_arrays.py")
res = subprocess.run([sys.executable, example], capture_output=True, text=True,
                     cwd=os.path.join(os.path.dirname(KUKA_URDF), "..", ".."),
                     env={**os.environ, "PYTHONPATH": package})
check("python/examples/identify_from_arrays.py runs", res.returncode == 0 and "constraints hold: True" in res.stdout,
      res.stderr[-300:])

print(f"{passed} passed, {failed} failed")
sys.exit(1 if failed else 0)
