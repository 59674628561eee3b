"""Type stubs of the extension module physid._physid."""

import os
from typing import Any, Callable, Optional, Sequence, Union
from .results import BodyChange

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]
# Joint values as numpy arrays of any integer or float dtype, nested lists, or pandas/polars
# frames: (samples, n), or one sample (n,).
ArrayLike = npt.ArrayLike
Path = Union[str, os.PathLike[str]]
# Runs: data files (CSV, MCAP, rosbag2 directories) or physid.Data held in memory.
Paths = Union[Path, "Data", Sequence[Union[Path, "Data"]]]
Names = Union[str, Sequence[str]]
SampleRange = Union[str, tuple[Optional[int], Optional[int]], range]

class Robot:
    """A robot: "cheetah3" (the built-in leg), a URDF file, or a robot TOML file."""

    def __init__(
        self,
        robot: Path,
        *,
        rotor_model: Optional[str] = None,
        no_rotors: bool = False,
        ellipsoid_margin: Optional[float] = None,
        package_dirs: Optional[Paths] = None,
        no_geometry_ellipsoids: bool = False,
    ) -> None:
        """Load the robot; the keyword arguments are the CLI's robot flags. Loader warnings are
        issued as physid.PhysidWarning, once per file and process."""
    @property
    def name(self) -> str: ...
    @property
    def dof(self) -> int: ...
    @property
    def joint_names(self) -> list[str]: ...
    @property
    def parameter_names(self) -> list[str]: ...
    @property
    def notices(self) -> list[str]:
        """The loader's notes and warnings; its warnings are raised as PhysidWarning the
        first time a file is loaded in a process."""
    def parameters(self) -> Array:
        """The description's parameter vector theta."""
    def inverse_dynamics(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> Array:
        """tau = RNEA + friction (N m), shape (samples, n); (n,) for one sample given as (n,)."""
    def mass_matrix(self, q: ArrayLike) -> Array:
        """H(q) (kg m^2), shape (samples, n, n); (n, n) for one sample given as (n,)."""
    def regressor(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> Array:
        """Y(q, qd, qdd) with Y @ theta = tau, shape (samples, n, p); (n, p) for one sample."""
    def describe(self) -> dict[str, Any]:
        """The JSON of `physid model --json`."""
    def write_mjcf(self, path: Path) -> None:
        """The robot as MJCF (rotors as armature), as `physid export --mjcf`."""
    def write_urdf(self, path: Path) -> None:
        """The robot as URDF with its sidecar, as `physid export --urdf`."""

class Data:
    """A run held in memory, read through physid's data pipeline as a logged file is, and
    taken wherever a data file is (identify, diagnose, load)."""

    def __init__(
        self,
        q: ArrayLike,
        tau: ArrayLike,
        *,
        qd: Optional[ArrayLike] = None,
        qdd: Optional[ArrayLike] = None,
        t: Optional[ArrayLike] = None,
        rate: Optional[float] = None,
        name: Optional[str] = None,
    ) -> None:
        """q (rad or m) and tau (N m or N) as (samples, n); qd (rad/s), qdd (rad/s²) where
        logged (else derived as for a file); t the time stamps (s) or rate (Hz), one of
        them; name what messages call it (default <arrays K>)."""
    @property
    def name(self) -> str:
        """What names the run in options and messages."""
    def __len__(self) -> int: ...

class Identification:
    """What identify found; to_dict() is `physid identify --json`."""

    @property
    def theta(self) -> Array:
        """The identified parameters: the model's, then the effect terms' coefficients."""
    @property
    def parameter_names(self) -> list[str]: ...
    @property
    def constraints(self) -> str:
        """The constraint set identified under."""
    @property
    def constraints_hold(self) -> bool: ...
    @property
    def train_rms(self) -> float:
        """RMS torque error on the training samples (N m)."""
    @property
    def validation_rms(self) -> Optional[float]:
        """RMS torque error on the held-out samples (N m), None when nothing was held out."""
    @property
    def seconds(self) -> float:
        """Wall time of the library's own identify call (s)."""
    @property
    def notices(self) -> list[str]:
        """Notes and warnings as the CLI prints them."""
    def bodies(self, backend: str = "pandas") -> Any:
        """pandas DataFrame: name, m, hx, ..., Izz, min_eig_I, min_eig_J, tr_JQ, consistent."""
    def joints(self, backend: str = "pandas") -> Any:
        """pandas DataFrame: joint, viscous, coulomb, train_rms, validation_rms."""
    def to_dict(self) -> dict[str, Any]:
        """The report as `physid identify --json` prints it."""
    def write_mjcf(self, path: Path) -> None:
        """The identified model as MJCF (rotors as armature); never over an input."""
    def write_urdf(self, path: Path) -> None:
        """Write the identified model as URDF plus its sidecar; never over an input."""

def identify(
    robot: Robot,
    data: Paths,
    *,
    validate_data: Optional[Paths] = None,
    train: Optional[SampleRange] = None,
    validate: Optional[SampleRange] = None,
    constraints: Optional[str] = None,
    friction: Optional[Names] = None,
    effects: Optional[Names] = None,
    effects_from: Optional[Path] = None,
    prior_weight: float = 1e-6,
    eps: float = 1e-6,
    regularizer: str = "euclidean",
    topic: Optional[str] = None,
    stamp: str = "log",
    cutoff: Optional[float] = None,
    lock: Optional[Names] = None,
    only: Optional[Names] = None,
    allow_few_samples: bool = False,
    mass_bounds: Optional[tuple[float, float]] = None,
    total_mass: Optional[tuple[float, float]] = None,
) -> Identification:
    """Identify from data files (CSV, MCAP, rosbag2) as `physid identify` does.
    mass_bounds=(lo, hi) holds each body's mass within lo..hi times the description's
    (0 <= lo <= 1 <= hi), as --mass-bounds; total_mass=(lo, hi) holds the robot's moving
    mass (links and rotors) within lo..hi kg, as --total-mass."""

class Diagnosis:
    """A diagnosis of the gap between a description and its runs; to_dict() is
    `physid diagnose --json`; shows itself as the HTML report in a notebook."""

    @property
    def verdict(self) -> str: ...
    @property
    def summary(self) -> str: ...
    @property
    def effect_kinds(self) -> list[str]:
        """The effects found, in the order they were selected (kind names)."""
    def effects(self, backend: str = "pandas") -> Any:
        """DataFrame, one row per effect and joint: effect, evidence, param, magnitude, joint,
        value, se, unit, identifiable, ambiguous_with; the selection's effects, then the
        ladder's (a payload as `payload` rows)."""
    def ladder(self, backend: str = "pandas") -> Any:
        """DataFrame, one row per rung of the ladder from the description: step, kind, param,
        overall (held-out RMS, N m), reduction, t, mass (kg, a body change's), alternatives,
        then the held-out RMS per joint (N m). No rows without a ladder."""
    @property
    def bodies(self) -> list[BodyChange]:
        """The body changes the ladder found, in order (empty without a ladder)."""
    @property
    def payload(self) -> Optional[BodyChange]:
        """The payload named (body, mass in kg, mass_se, com in m, body frame), or None."""
    @property
    def standing(self) -> Optional[list[str]]:
        """What-changed mode: the baseline's standing effects taken out of the data."""
    @property
    def notices(self) -> list[str]: ...
    def gap(self, backend: str = "pandas") -> Any:
        """pandas DataFrame: per joint the validation RMS of the description, the nominal
        model, after each effect, and the noise floor (N m)."""
    def to_dict(self) -> dict[str, Any]: ...
    def text(self) -> str:
        """The report as `physid diagnose` prints it (the Markdown's sections, condensed)."""
    def markdown(self) -> str: ...
    def html(self) -> str:
        """The self-contained HTML report, plots inline."""
    def _repr_html_(self) -> str: ...
    def write_report(self, path: Path) -> None:
        """report.html, report.md, report.json and SVG plots into a folder (never an input's)."""

def diagnose(
    robot: Robot,
    data: Paths,
    *,
    validate: Optional[Paths] = None,
    baseline_data: Optional[Paths] = None,
    constraints: str = "consistent",
    holdout: float = 0.3,
    description_uncertainty: Optional[float] = None,
    payload_any_body: bool = False,
    topic: Optional[str] = None,
    stamp: str = "log",
    cutoff: Optional[float] = None,
    lock: Optional[Names] = None,
    only: Optional[Names] = None,
    description_information: bool = True,
) -> Diagnosis:
    """Diagnose the gap between the description and its runs as `physid diagnose` does; a
    description written by `Identification.write_urdf` carries its information matrix in its
    sidecar, read unless `description_information=False`."""

class Simulation:
    """A simulated excitation experiment, its log written; to_dict() is `physid simulate --json`."""

    @property
    def truth(self) -> dict[str, Array]:
        """t, q, qd, qdd, tau (the actuators' torque), friction and effects (its parts)."""
    @property
    def measured(self) -> dict[str, Array]:
        """What the robot logs: t, q, qd, qdd, tau."""
    @property
    def processed(self) -> dict[str, Array]:
        """The identification input (what csv= writes): t, q, qd, qdd, tau."""
    @property
    def robot(self) -> Robot:
        """The scenario's robot, the ground truth."""
    def to_dict(self) -> dict[str, Any]: ...

def simulate(
    scenario: Path,
    out: Path,
    *,
    csv: Optional[Path] = None,
    engine: Optional[str] = None,
    duration: Optional[float] = None,
    seed: Optional[int] = None,
    progress: Optional[Callable[[float], None]] = None,
) -> Simulation:
    """Simulate a scenario and log it to MCAP (and CSV), as `physid simulate` does."""

class Excitation:
    """A designed excitation; to_dict() is `physid excite --json`."""

    @property
    def scenario(self) -> str:
        """The scenario's TOML text, the design as its [excitation]."""
    @property
    def within_limits(self) -> Optional[bool]:
        """Every simulated peak inside the robot's limits (None: not checked)."""
    @property
    def written(self) -> Optional[Path]:
        """The scenario file written (None: none asked for, or the check failed)."""
    @property
    def design(self) -> dict[str, Any]:
        """The design: series, objective value, condition, identifiable, limits, limit_use."""
    @property
    def notices(self) -> list[str]:
        """Notes and warnings, also raised as PhysidWarning."""
    def reference(self, rate: float = 1000.0) -> dict[str, Array]:
        """The reference trajectory t, q, qd, qdd (tau zero) at `rate` Hz."""
    def limits(self, backend: str = "pandas") -> Any:
        """Per joint, peaks over the robot's limits in simulation (pandas DataFrame)."""
    def to_dict(self) -> dict[str, Any]: ...

def excite(
    robot: Union[Robot, Path, None] = None,
    *,
    scenario: Optional[Path] = None,
    duration: float = 20.0,
    harmonics: int = 5,
    base_frequency: float = 0.5,
    objective: str = "d-optimal",
    seed: int = 1,
    iterations: int = 1000,
    starts: int = 4,
    margin: float = 0.15,
    max_acceleration: Optional[Sequence[float]] = None,
    max_jerk: Optional[Sequence[float]] = None,
    ramp: Optional[float] = None,
    samples: int = 200,
    rate: float = 1000.0,
    out: Optional[Path] = None,
    csv: Optional[Path] = None,
    mcap: Optional[Path] = None,
    check: bool = True,
    threads: Optional[int] = None,
    progress: Optional[Callable[[float], None]] = None,
) -> Excitation:
    """Design an excitation within the robot's limits, as `physid excite` does."""

def score_motion(
    scenario: Path,
    *,
    duration: float = 20.0,
    harmonics: int = 5,
    base_frequency: float = 0.5,
    objective: str = "d-optimal",
    margin: float = 0.15,
    samples: int = 200,
    rate: float = 1000.0,
    threads: Optional[int] = None,
) -> dict[str, Any]:
    """A scenario's own motion scored as `physid excite --score --json` scores it."""

class Sweep:
    """A parameter sweep's result: its folder, what ran, the merged tables once complete."""

    @property
    def out(self) -> Path: ...
    @property
    def cells(self) -> dict[str, int]:
        """total, shard, ran, missing, stale."""
    @property
    def merged(self) -> bool: ...
    @property
    def markdown(self) -> str:
        """summary.md (physid.InputError while cells are missing)."""
    def rows(self, backend: str = "pandas") -> Any:
        """rows.csv as a pandas DataFrame (physid.InputError while cells are missing)."""
    def summary(self, backend: str = "pandas") -> Any:
        """summary.csv as a pandas DataFrame."""

def sweep(
    sweep: Path,
    *,
    out: Optional[Path] = None,
    shard: Optional[tuple[int, int]] = None,
    threads: Optional[int] = None,
    progress: Optional[Callable[[int, int], None]] = None,
) -> Sweep:
    """Run a parameter sweep (resumable, shardable), as `physid sweep` does."""

class Experiment:
    """The sample-size experiment: every (seed, n_s, constraint set) cell."""

    def rows(self, backend: str = "pandas") -> Any:
        """pandas DataFrame: the CLI's rows.csv."""
    def summary(self, backend: str = "pandas") -> Any:
        """pandas DataFrame: median and quartiles over seeds (the CLI's summary.csv)."""
    @property
    def constraints(self) -> list[str]: ...
    @property
    def seconds(self) -> float: ...

def experiment(
    scenario: Path,
    *,
    seeds: Optional[int] = None,
    threads: Optional[int] = None,
    progress: Optional[Callable[[int, int], None]] = None,
) -> Experiment:
    """Run a scenario's sample-size experiment as `physid experiment` does."""

class Comparison:
    """A comparison of results (`physid compare`): per group medians, ratio, p-value, outcome."""

    @property
    def regressions(self) -> int: ...
    @property
    def too_few(self) -> int: ...
    def groups(self, backend: str = "pandas") -> Any:
        """pandas DataFrame: point, n_s, set, pairs, medians, median_ratio, p_value, outcome."""
    def markdown(self) -> str: ...
    def junit(self) -> str: ...
    def to_dict(self) -> dict[str, Any]: ...

def compare(
    result: Path,
    *,
    baseline: Optional[Path] = None,
    variant: Optional[str] = None,
    metric: Optional[str] = None,
    tolerance: Optional[float] = None,
    alpha: Optional[float] = None,
    min_pairs: Optional[int] = None,
    allow_too_few: bool = False,
    max_n_s: Optional[int] = None,
) -> Comparison:
    """Compare results against a baseline folder, or two constraint sets (variant="A<=B")."""

def load(
    robot: Robot,
    data: Paths,
    *,
    topic: Optional[str] = None,
    stamp: str = "log",
    cutoff: Optional[float] = None,
    lock: Optional[Names] = None,
    only: Optional[Names] = None,
) -> list[dict[str, Any]]:
    """Read files through physid's pipeline: per file its runs (t, q, qd, qdd, tau, index),
    pipeline report and notices."""

def version() -> str: ...
