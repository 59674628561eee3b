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
    sim = physid.simulate("scenarios/cheetah3_shell.toml", "run.mcap")   # sim.truth["q"], sim.to_dict()
    e = physid.excite(robot, out="designed.toml")    # an excitation within the robot's limits
    d = physid.diagnose(robot, "run3.csv", baseline_data="run2.csv",
                        description_uncertainty=0.05)   # what changed; shows as HTML in a notebook

Errors are physid.Error, each also the built-in of its kind: InputError (a ValueError naming
the keyword, file, sample or joint), MissingFileError (a FileNotFoundError), SolverError (a
RuntimeError); warnings about the data or the answer are issued as PhysidWarning, a robot
description's once per file.
"""


def _openblas_already_loaded() -> bool:
    """Whether this process had loaded the system OpenBLAS before physid (another module then
    shares it, and its kernels are left as they are); True where that cannot be read."""
    try:
        with open("/proc/self/maps") as maps:
            return "/libopenblas.so" in maps.read()
    except OSError:
        return True


_OPENBLAS_SHARED = _openblas_already_loaded()

from .errors import Error, InputError, MissingFileError, PhysidWarning, SolverError  # noqa: E402
from .results import BodyChange  # noqa: E402
from ._physid import (  # noqa: E402
    Comparison,
    Data,
    Diagnosis,
    Excitation,
    Experiment,
    FloatingIdentification,
    FloatingRobot,
    Identification,
    Robot,
    Simulation,
    Sweep,
    compare,
    diagnose,
    excite,
    experiment,
    identify,
    identify_floating,
    load,
    score_motion,
    simulate,
    simulate_floating,
    sweep,
    version,
)
from .arrays import identify_arrays  # noqa: E402

if not _OPENBLAS_SHARED:
    # As the `physid` binary does: OpenBLAS's kernels for the CPU's instruction set where it did
    # not know the CPU, so that results equal the binary's.
    from ._physid import _select_blas_kernels  # noqa: E402

    _select_blas_kernels()

__all__ = [
    "BodyChange",
    "Comparison",
    "Data",
    "Diagnosis",
    "Error",
    "Excitation",
    "Experiment",
    "FloatingIdentification",
    "FloatingRobot",
    "Identification",
    "InputError",
    "MissingFileError",
    "PhysidWarning",
    "Robot",
    "Simulation",
    "SolverError",
    "Sweep",
    "compare",
    "diagnose",
    "excite",
    "experiment",
    "identify",
    "identify_arrays",
    "identify_floating",
    "load",
    "score_motion",
    "simulate",
    "simulate_floating",
    "sweep",
    "version",
]
__version__ = version()
