"""What the Python package adds, side by side in one run:

- `physid.identify` called from Python against the library's own time for the same call
  (`Identification.seconds`, measured inside the extension): the real KUKA runs 1 and 2, run 3
  held out, consistent set with a torque offset (median of 9 calls);
- the regressor of 10,000 KUKA samples: one `Robot.regressor` call on numpy arrays against
  pinocchio's `computeJointTorqueRegressor` called from Python in a loop over the same samples,
  best of 5: written plainly (each sample's configuration assembled in new arrays) and written
  as fast as a Python loop goes (the samples' rows passed as they are, the joints being in
  pinocchio's order, into one preallocated array): the fair ratio is the second.

The package folder (`--package DIR`, default $PHYSID_PYTHON) holds physid/ with the extension
built, as scripts/test.sh makes it.
"""
import os
import statistics
import time
import warnings

import numpy as np
import pinocchio as pin

from physid_common import KUKA_URDF, PACKAGE_OPTION, ROOT, arguments, on_path

on_path(arguments(__doc__, PACKAGE_OPTION, binary=False).package)
import physid  # noqa: E402

warnings.simplefilter("ignore", physid.PhysidWarning)
runs = [os.path.join(ROOT, "data", "kuka_lwr4", f"measurements_{k}.csv") for k in (1, 2, 3)]
robot = physid.Robot(KUKA_URDF)

wall, own = [], []
for _ in range(9):
    t = time.perf_counter()
    fit = physid.identify(robot, runs[:2], validate_data=runs[2], constraints="consistent",
                          friction="viscous,coulomb,offset")
    wall.append(time.perf_counter() - t)
    own.append(fit.seconds)
w, o = statistics.median(wall), statistics.median(own)
print(f"identify, KUKA runs 1+2, run 3 held out: Python {w * 1e3:.1f} ms, library {o * 1e3:.1f} ms, "
      f"Python adds {100 * (w - o) / o:.1f} %")

rng = np.random.default_rng(1)
n, count = robot.dof, 10_000
q, qd, qdd = (rng.uniform(-1.5, 1.5, (count, n)) for _ in range(3))
model = pin.buildModelFromUrdf(KUKA_URDF)
data = model.createData()
idx = [model.joints[model.getJointId(j)].idx_v for j in robot.joint_names]


def physid_regressor():
    return robot.regressor(q, qd, qdd)


def pinocchio_regressor():
    out = np.empty((count, model.nv, 10 * (model.njoints - 1)))
    for k in range(count):
        Q, V, A = (np.zeros(model.nq) for _ in range(3))
        Q[idx], V[idx], A[idx] = q[k], qd[k], qdd[k]
        out[k] = pin.computeJointTorqueRegressor(model, data, Q, V, A)
    return out


def pinocchio_regressor_preallocated():
    assert idx == list(range(model.nv)) and model.nq == model.nv  # rows passed as they are
    out = np.empty((count, model.nv, 10 * (model.njoints - 1)))
    regressor = pin.computeJointTorqueRegressor
    for k in range(count):
        out[k] = regressor(model, data, q[k], qd[k], qdd[k])
    return out


def best(f, reps=5):
    times = []
    for _ in range(reps):
        t = time.perf_counter()
        f()
        times.append(time.perf_counter() - t)
    return min(times)


assert np.allclose(pinocchio_regressor(), pinocchio_regressor_preallocated())
tp, tq, tf = best(physid_regressor), best(pinocchio_regressor), best(pinocchio_regressor_preallocated)
print(f"regressor of {count} samples: physid {tp * 1e3:.1f} ms (one call); pinocchio in a Python loop "
      f"{tq * 1e3:.1f} ms written plainly ({tq / tp:.2f}x physid), {tf * 1e3:.1f} ms into a "
      f"preallocated array ({tf / tp:.2f}x physid, the fair ratio)")
