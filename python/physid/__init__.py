"""physid: physically-consistent inertial parameter identification of robots.

The Rust library (Wensing, Kim & Slotine, RA-L 2018) in Python, over numpy arrays and files:

    import physid
    robot = physid.Robot("arm.urdf")                 # or "cheetah3", or a robot TOML
    fit = physid.identify(robot, "run1.csv", validate_data="run2.csv",
                          constraints="consistent", friction="viscous,coulomb,offset")
    fit.validation_rms, fit.bodies(), fit.to_dict()  # to_dict() is `physid identify --json`
    fit.write_urdf("identified.urdf")

    tau = robot.inverse_dynamics(q, qd, qdd)         # (samples, n) arrays
    Y = robot.regressor(q, qd, qdd)                  # (samples, n, p), Y @ theta = tau
    runs = physid.load(robot, "run.mcap")            # a file through physid's data pipeline

Errors raise ValueError with the CLI's message (naming the flag, file, sample or joint);
warnings about the data or the answer are issued as PhysidWarning.
"""


class PhysidWarning(UserWarning):
    """A warning about the data or the answer (the CLI prints it as `warning: ...`)."""


from ._physid import Identification, Robot, identify, identify_arrays, load, version  # noqa: E402

__all__ = [
    "Identification",
    "PhysidWarning",
    "Robot",
    "identify",
    "identify_arrays",
    "load",
    "version",
]
__version__ = version()
