"""physid: physically-consistent inertial parameter identification of robots.

The Rust library (Wensing, Kim & Slotine, RA-L 2018) over numpy arrays:

    import numpy as np, physid
    robot = physid.Robot("cheetah3")            # or a URDF / robot TOML path
    tau = robot.inverse_dynamics(q, qd, qdd)    # (samples, n) arrays
    Y = robot.regressor(q, qd, qdd)             # (samples, n, p), Y @ theta = tau
    fit = physid.identify_arrays(robot, q, qd, qdd, tau, constraints="consistent")
    fit["theta"], fit["constraints_hold"]

Errors raise ValueError with the library's message, naming the array, sample and joint.
"""

from ._physid import Robot, identify_arrays, version

__all__ = ["Robot", "identify_arrays", "version"]
__version__ = version()
