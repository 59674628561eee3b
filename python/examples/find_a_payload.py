"""The whole loop in a notebook's cells: read a robot's log, identify its description, then
find a payload in a later run, plot the diagnosis's ladder, and hand the results to worker
processes (they pickle).

The later run is the KUKA's real run 3 with a 2 kg payload, 5 cm out on the flange, added to its
logged torques through the robot's own regressor: the change is known, the rest is real.

usage: python python/examples/find_a_payload.py [OUT_DIR]   (from the repository root)
"""
import multiprocessing
import sys
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import physid  # noqa: E402


def payload_torque(robot, q, qd, qdd, body, mass, com):
    """τ of a point mass (kg) at `com` (m, body frame) on `body`, through the regressor."""
    c = np.asarray(com, dtype=float)
    inertia = mass * (c @ c * np.eye(3) - np.outer(c, c))  # about the body's frame origin
    pi = [mass, *(mass * c), inertia[0, 0], inertia[0, 1], inertia[0, 2], inertia[1, 1], inertia[1, 2], inertia[2, 2]]
    columns = [robot.parameter_names.index(f"{body}.{k}")
               for k in ("m", "hx", "hy", "hz", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz")]
    return robot.regressor(q, qd, qdd)[:, :, columns] @ np.asarray(pi)


def what_it_found(result):
    """Runs in a worker process: the result arrived pickled."""
    if isinstance(result, physid.Diagnosis):
        return f"diagnosis: {result.payload.body} carries {result.payload.mass:.2f} ± {result.payload.mass_se:.2f} kg"
    return f"identification: validation RMS {result.validation_rms:.3f} N m"


if __name__ == "__main__":
    out = Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    warnings.simplefilter("ignore", physid.PhysidWarning)   # the bundled URDF's; see robot.notices
    robot = physid.Robot("data/kuka_lwr4/kuka_lwr4.urdf")

    # 1. The description, identified from the robot's own log (run 1; run 2 held out).
    fit = physid.identify(robot, "data/kuka_lwr4/measurements_1.csv",
                          validate_data="data/kuka_lwr4/measurements_2.csv", constraints="consistent")
    fit.write_urdf(out / "identified.urdf")   # the URDF and its sidecar with the fit's information
    described = physid.Robot(out / "identified.urdf")

    # 2. A later run, as arrays: run 3 read through the data pipeline, 2 kg added on the flange.
    run3 = physid.load(robot, "data/kuka_lwr4/measurements_3.csv")[0]["runs"][0]
    q, qd, qdd, tau = run3["q"], run3["qd"], run3["qdd"], run3["tau"]
    loaded = tau + payload_torque(robot, q, qd, qdd, "lwr_7_link", 2.0, [0.0, 0.0, 0.05])
    later = physid.Data(q, loaded, qd=qd, qdd=qdd, t=run3["t"], name="run 3 with 2 kg")

    # 3. What changed, read against the identified description.
    d = physid.diagnose(described, later)
    print(d.verdict, "-", d.payload)
    ladder = d.ladder()
    print(ladder[["step", "overall", "reduction", "mass"]].round(3).to_string(index=False))
    fig, ax = plt.subplots(figsize=(7, 3))
    ax.barh(ladder["step"][::-1], ladder["overall"][::-1])
    ax.set(xlabel="held-out RMS torque error (N m)", title="the diagnosis's ladder")
    fig.tight_layout()
    fig.savefig(out / "ladder.png", dpi=100)

    # 4. Results pickle: hand them to worker processes.
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        for line in pool.map(what_it_found, [fit, d]):
            print(line)
