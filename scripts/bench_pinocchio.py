"""Peer timing for `cargo bench --bench dynamics`: pinocchio's rnea and joint-torque regressor
on the same models (the link-only Cheetah-3 leg exported by physid, and the KUKA LWR4+), called
from Python as a Python user would, and once more with the per-call Python overhead measured
separately (an empty pinocchio call) so the C++ cost can be estimated.
"""
import tempfile
import time

import numpy as np
import pinocchio as pin

from physid_common import KUKA_URDF, arguments, export, physid_bin


def per_call(f, states, reps=20):
    best = float("inf")
    for _ in range(reps):
        t = time.perf_counter()
        for q, v, a in states:
            f(q, v, a)
        best = min(best, (time.perf_counter() - t) / len(states))
    return best * 1e9


def bench(label, urdf):
    model = pin.buildModelFromUrdf(urdf)
    data = model.createData()
    rng = np.random.default_rng(0)
    states = [tuple(rng.uniform(-2, 2, model.nv) for _ in range(3)) for _ in range(2000)]
    t_rnea = per_call(lambda q, v, a: pin.rnea(model, data, q, v, a), states)
    t_reg = per_call(lambda q, v, a: pin.computeJointTorqueRegressor(model, data, q, v, a), states)
    t_empty = per_call(lambda q, v, a: pin.neutral(model), states)
    print(f"{label:<28} rnea {t_rnea:7.0f} ns   regressor {t_reg:7.0f} ns   "
          f"(python call overhead ~{t_empty:.0f} ns; net rnea ~{t_rnea - t_empty:.0f}, regressor ~{t_reg - t_empty:.0f})")


def main():
    binary = physid_bin(arguments(__doc__).physid)
    with tempfile.TemporaryDirectory() as d:
        bench("cheetah3 leg links only", export(binary, ["--robot", "cheetah3", "--no-rotors"], "urdf", d))
    bench("kuka lwr4", KUKA_URDF)


if __name__ == "__main__":
    main()
