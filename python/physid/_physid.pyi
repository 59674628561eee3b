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
        issued as physid.PhysidWarning, once per file and process.

        Keywords:

        robot: The robot: a physid.Robot (as returned by physid.Robot), or "cheetah3" (the built-in
            leg), a URDF or a robot TOML path.
        rotor_model: Override the rotor treatment: full (spinning rotor bodies) or reflected
            (armature). One of: full, reflected.
        no_rotors: Drop the rotors (the link-only model).
        ellipsoid_margin: URDF robots: lengthen every semi-axis of the bounding ellipsoids computed
            from the geometry by this much (m).
        package_dirs: URDF robots: a folder holding ROS packages, for `package://` meshes
            (repeatable; the URDF's own folders and ROS_PACKAGE_PATH are searched first).
        no_geometry_ellipsoids: URDF robots: take no bounding ellipsoids from the geometry (only a
            sidecar's).
        """
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
    mass (links and rotors) within lo..hi kg, as --total-mass.

    Keywords:

    robot: The robot: a physid.Robot (as returned by physid.Robot), or "cheetah3" (the built-in
        leg), a URDF or a robot TOML path.
    data: Samples, one or more runs: physid MCAP logs (their processed signals), other MCAP
        files or rosbag2 directories with JointState, or CSV. Runs are joined without
        differentiating across their seams. Paths, physid.Data held in memory, or a list of
        them.
    validate_data: Validate on other runs (all their samples). Paths, physid.Data held in
        memory, or a list of them.
    train: Training samples, `a:b` (indices, end exclusive); default all. One data file only.
    validate: Validation samples of the same file, `a:b`. One data file only.
    constraints: Constraint set: none, semi, consistent, ellipsoid. Default: the tightest the
        description supports (ellipsoid when every body has a bounding ellipsoid, else
        consistent).
    friction: Friction terms per joint, comma-separated: viscous and coulomb (always; the
        model's own, paper eq. 9), plus any of offset (a torque offset), direction (direction-
        dependent Coulomb), stribeck:<v> (Stribeck excess with velocity v rad/s). Default:
        viscous,coulomb.
    effects: Effect terms from the diagnosis library, comma-separated: torque_offset,
        torque_gain, time_delay, spring, stribeck:<Stribeck velocity, rad/s>,
        asymmetric_coulomb, load_dependent_friction, cogging:<harmonic per rotor revolution>,
        rotor_inertia, tilt, compliance[:<compliance 1/k of the secant, rad/(N m); 0: the
        tangent>], backlash[:<width of the secant, rad: 0.01, 0.02 or 0.04; 0: the tangent>],
        payload[:<body number from 1, default the last>]; see docs/diagnose.md.
    effects_from: Take the effects a diagnosis confirmed: its report.json (`physid diagnose
        out`).
    prior_weight: Weight of the prior term w ‖θ − θ̂‖² (θ̂: the robot description's parameters).
        Default: 0.000001.
    eps: Margin ε of the strict matrix inequalities. Default: 0.000001.
    regularizer: Prior term: euclidean (w ‖θ − θ̂‖², the paper) or logdet (w Σ Bregman
        divergence of −log det between J and the prior's J; Lee, Wensing & Park). Default:
        euclidean.
    topic: The `sensor_msgs/msg/JointState` topic of an MCAP file or rosbag2 directory (default:
        physid's processed signals if the log has them, else /joint_states).
    stamp: Which time stamps a joint state: log (the recorder's receive time) or header (the
        message's header.stamp, when the driver sampled the joints). Default: log.
    cutoff: Low-pass cutoff (Hz) of the signals derived from the log (q̈, and q̇ when not
        logged): zero-phase 2nd-order Butterworth. Default: 20 Hz, at most a tenth of the sample
        rate.
    lock: Joints to hold at their logged position (q̇ = q̈ = 0; their torque is not fitted),
        e.g. a gripper that never moves; comma-separated names.
    only: Fit only these joints' torques; every other joint is locked (comma-separated names).
    allow_few_samples: Accept fewer equations than parameters (the prior then decides the rest).
    mass_bounds: Hold each body's mass within LO..HI times the description's (0 <= LO <= 1 <=
        HI, e.g. 0.5,2): what the data do not determine otherwise goes wherever the constraints
        allow.
    total_mass: Hold the robot's total moving mass (links and rotors) within LO..HI kg (e.g.
        3.5,3.9: the arm weighed on a scale), where the data weigh only some bodies.
    """

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
    sidecar, read unless `description_information=False`.

    Keywords:

    robot: The robot: a physid.Robot (as returned by physid.Robot), or "cheetah3" (the built-in
        leg), a URDF or a robot TOML path.
    data: Training data (CSV with ddq, or MCAP); repeat for several runs. Paths, physid.Data
        held in memory, or a list of them.
    validate: Validation data; without it the last holdout of the data is held out. Paths,
        physid.Data held in memory, or a list of them.
    baseline_data: "What changed": runs of the same robot before the change (a tool change, a
        repair, a new gripper). The description is calibrated on them with their standing
        effects, which are taken out of data; only what differs is attributed. Needs
        description_uncertainty. Paths, physid.Data held in memory, or a list of them.
    constraints: Constraint set of the nominal model. Default: consistent.
    holdout: Fraction held out for validation when no validate is given. Default: 0.3.
    description_uncertainty: How far the description's inertial parameters can be trusted
        (relative, 0.1 = 10 %): tests the identified parameters against it for effects that
        identification absorbs (torque gain, tilt, payload). Off without it.
    payload_any_body: Search a payload over every body, not only the last (with
        description_uncertainty; inner bodies are found only where the motion separates their
        parameters).
    topic: The `sensor_msgs/msg/JointState` topic of an MCAP file or rosbag2 directory (default:
        physid's processed signals if the log has them, else /joint_states).
    stamp: Which time stamps a joint state: log (the recorder's receive time) or header (the
        message's header.stamp, when the driver sampled the joints). Default: log.
    cutoff: Low-pass cutoff (Hz) of the signals derived from the log (q̈, and q̇ when not
        logged): zero-phase 2nd-order Butterworth. Default: 20 Hz, at most a tenth of the sample
        rate.
    lock: Joints to hold at their logged position (q̇ = q̈ = 0; their torque is not fitted),
        e.g. a gripper that never moves; comma-separated names.
    only: Fit only these joints' torques; every other joint is locked (comma-separated names).
    description_information: True unless: ignore the information matrix in the description's
        sidecar (`identify out_urdf` writes it; read from a sidecar given as robot, or beside a
        URDF given as robot). (False is the CLI's no_description_information.)
    """

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
    """Simulate a scenario and log it to MCAP (and CSV), as `physid simulate` does.

    Keywords:

    scenario: A scenario TOML file.
    out: Output MCAP file.
    csv: Also write the processed samples (t, q, dq, ddq, tau) as CSV.
    engine: Override the engine. One of: physid, rapier.
    duration: Override the duration (s).
    seed: Override the seed.
    progress: A callable told the progress (simulate: the fraction of the run done; excite: the
        fraction of the design's evaluations done; experiment, sweep: done, total), on the
        calling thread, in order; an exception in it stops the work.
    """

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
    base_frequency: float | None = None,
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
    """Design an excitation within the robot's limits, as `physid excite` does.

    Keywords:

    robot: The robot: a physid.Robot (as returned by physid.Robot), or "cheetah3" (the built-in
        leg), a URDF or a robot TOML path.
    scenario: Base scenario: its robot, simulation, sensors, processing and experiment are kept
        and its excitation replaced; a Fourier excitation's `offset ± amplitude` narrows the
        joint ranges (the other limits come from the robot).
    duration: Duration of the written scenario (s). Default: 20.
    harmonics: Harmonics per joint. Default: 5.
    base_frequency: Fundamental frequency (Hz): the motion repeats every 1/f s. Default: chosen
        with the limits and the duration: the fastest at which each joint's first harmonic alone
        could sweep its whole range within its speed, acceleration and jerk limits, but at least
        one whole period between the ramps (or over half the run, where ramp leaves less).
    objective: What is maximized. One of: d-optimal, e-optimal, condition. Default: d-optimal.
    seed: Seed of the random starts and steps. Default: 1.
    iterations: Optimization steps per start (0: a random excitation scaled into the limits).
        Default: 1000.
    starts: Random starts (in parallel; the best is kept). Default: 4.
    margin: Fraction of every limit left free. Default: 0.15.
    max_acceleration: Acceleration limit (rad/s²): one for every joint, or one per joint
        separated by commas. Default: the description's (a URDF `<limit acceleration=…>`, a
        robot TOML's `limits.acceleration`), else 3 rad/s², below common arms' limits.
    max_jerk: Jerk limit (rad/s³), as max_acceleration; default the description's, else 30
        rad/s³; `inf`: no jerk limit (the acceleration limit, which bounds the motor current,
        has no such value).
    ramp: Start and end at rest (s): the motion fades in from rest over this long and out to
        rest at the end (velocity, acceleration and jerk zero at both ends). Default: the
        shortest over which a joint's whole range fades in within half its acceleration and jerk
        limits, at most a quarter of the duration; 0 starts mid-motion (periodic).
    samples: Samples per period at which the information is evaluated. Default: 200.
    rate: Sample rate of csv and mcap (Hz; default 1000); needs one of them.
    out: Write the scenario here (TOML); it must not exist as an input of this run.
    csv: Also write the designed trajectory (t, q, q̇, q̈ per joint, named by joint) as CSV, to
        send to a controller.
    mcap: Also write the designed trajectory as MCAP (physid_msgs/msg/JointSample on
        /physid/excitation: position, velocity, acceleration).
    check: True unless: do not simulate the design to check its limits. (False is the CLI's
        no_check.)
    threads: Worker threads (0 = all cores). Results do not depend on it. Default: 0.
    progress: A callable told the progress (simulate: the fraction of the run done; excite: the
        fraction of the design's evaluations done; experiment, sweep: done, total), on the
        calling thread, in order; an exception in it stops the work.
    """

def score_motion(
    scenario: Path,
    *,
    duration: float = 20.0,
    harmonics: int = 5,
    base_frequency: float | None = None,
    objective: str = "d-optimal",
    margin: float = 0.15,
    samples: int = 200,
    rate: float = 1000.0,
    threads: Optional[int] = None,
) -> dict[str, Any]:
    """A scenario's own motion scored as `physid excite --score --json` scores it.

    Keywords:

    scenario: Base scenario: its robot, simulation, sensors, processing and experiment are kept
        and its excitation replaced; a Fourier excitation's `offset ± amplitude` narrows the
        joint ranges (the other limits come from the robot).
    duration: Duration of the written scenario (s). Default: 20.
    harmonics: Harmonics per joint. Default: 5.
    base_frequency: Fundamental frequency (Hz): the motion repeats every 1/f s. Default: chosen
        with the limits and the duration: the fastest at which each joint's first harmonic alone
        could sweep its whole range within its speed, acceleration and jerk limits, but at least
        one whole period between the ramps (or over half the run, where ramp leaves less).
    objective: What is maximized. One of: d-optimal, e-optimal, condition. Default: d-optimal.
    margin: Fraction of every limit left free. Default: 0.15.
    samples: Samples per period at which the information is evaluated. Default: 200.
    rate: Sample rate of csv and mcap (Hz; default 1000); needs one of them.
    threads: Worker threads (0 = all cores). Results do not depend on it. Default: 0.
    """

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
    """Run a parameter sweep (resumable, shardable), as `physid sweep` does.

    Keywords:

    sweep: A sweep TOML file (docs/sweeps.md).
    out: Output directory (default results/<sweep file name>).
    shard: Run only cells with index ≡ K (mod N), e.g. a job array's task: `shard 3/16`.
    threads: Worker threads (default: all cores).
    progress: A callable told the progress (simulate: the fraction of the run done; excite: the
        fraction of the design's evaluations done; experiment, sweep: done, total), on the
        calling thread, in order; an exception in it stops the work.
    """

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
    """Run a scenario's sample-size experiment as `physid experiment` does.

    Keywords:

    scenario: A scenario TOML file.
    seeds: Override the number of seeds.
    threads: Worker threads (default: all cores). Results do not depend on it.
    progress: A callable told the progress (simulate: the fraction of the run done; excite: the
        fraction of the design's evaluations done; experiment, sweep: done, total), on the
        calling thread, in order; an exception in it stops the work.
    """

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
    """Compare results against a baseline folder, or two constraint sets (variant="A<=B").

    Keywords:

    result: A results folder (of physid experiment or physid sweep).
    baseline: Baseline result directory to compare against.
    variant: Two constraint sets within RESULT: `ellipsoid<=consistent` (the first no worse).
    metric: Metric column, lower is better (default val_rms).
    tolerance: Relative tolerance of the median ratio (default 0.05).
    alpha: One-sided level of the signed-rank test (default 0.01).
    min_pairs: Fewest seed pairs a group needs to be able to fail (default 6; raised to what
        alpha needs: the exact test's smallest p on n pairs is 2^-n, so 7 at 0.01).
    allow_too_few: Let groups with too few pairs to reach alpha pass (by default they fail the
        run with exit 2: a group that cannot fail is not a pass).
    max_n_s: Only groups with n_s at most this.
    """

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
    pipeline report and notices.

    Keywords:

    robot: The robot: a physid.Robot (as returned by physid.Robot), or "cheetah3" (the built-in
        leg), a URDF or a robot TOML path.
    data: Samples, one or more runs: physid MCAP logs (their processed signals), other MCAP
        files or rosbag2 directories with JointState, or CSV. Runs are joined without
        differentiating across their seams. Paths, physid.Data held in memory, or a list of
        them.
    topic: The `sensor_msgs/msg/JointState` topic of an MCAP file or rosbag2 directory (default:
        physid's processed signals if the log has them, else /joint_states).
    stamp: Which time stamps a joint state: log (the recorder's receive time) or header (the
        message's header.stamp, when the driver sampled the joints). Default: log.
    cutoff: Low-pass cutoff (Hz) of the signals derived from the log (q̈, and q̇ when not
        logged): zero-phase 2nd-order Butterworth. Default: 20 Hz, at most a tenth of the sample
        rate.
    lock: Joints to hold at their logged position (q̇ = q̈ = 0; their torque is not fitted),
        e.g. a gripper that never moves; comma-separated names.
    only: Fit only these joints' torques; every other joint is locked (comma-separated names).
    """

def version() -> str: ...
def _select_blas_kernels() -> str | None: ...

class FloatingIdentification:
    """A floating robot identified from a log; to_dict() is `physid identify-floating --json`."""

    @property
    def theta(self) -> Array:
        """θ: the trunk's ten parameters, the tree's bodies' and rotors', then friction."""
    @property
    def constraints_hold(self) -> bool: ...
    @property
    def mass(self) -> float:
        """The whole robot's identified mass (kg)."""
    def to_dict(self) -> dict[str, Any]: ...

def simulate_floating(
    out: Path,
    *,
    robot: Optional[Union[Path, "FloatingRobot"]] = None,
    no_rotors: bool = False,
    duration: float = 10.0,
    rate: float = 1000.0,
    seed: int = 1,
    trot: Optional[tuple[float, float]] = None,
    still: bool = False,
    sensors: Union[dict[str, Any], str, None] = None,
) -> dict[str, Any]:
    """Simulate the quadruped standing and log it as its sensors would (CSV), as `physid
    simulate-floating` does; returns its --json summary.

    Keywords:

    out: The log to write: CSV, or MCAP (`.mcap`: /joint_states, /odometry, /foot_forces).
    robot: The robot: a physid.FloatingRobot (as loaded, rotors and all), or "cheetah3" (the
        built-in quadruped), a floating URDF or its sidecar TOML path. Default: cheetah3.
    no_rotors: Drop the rotors (the link-only model).
    duration: Duration (s). Default: 10.
    rate: Control and logging rate (Hz). Default: 1000.
    seed: Seeds the motion and the noise. Default: 1.
    trot: Trot in place instead of standing: `CROUCH,HZ`, each diagonal pair of legs in turn
        crouched by up to CROUCH rad of the hip (its feet swing) at HZ steps per second.
    still: Stand still, holding the standing posture (no weight shifting): how the feet share
        the robot's weight.
    drop: Drop the robot: its lowest foot this high above the ground at the start (m). Default:
        0.
    push: Push the robot: the whole robot's velocity at the start, `VX,VY,VZ` (m/s, world axes).
    ground_friction: The ground's friction coefficient μ. Default: 0.8.
    sensors: The sensors' noise and what they log: a dict over the default sensors' fields
        (torque_noise, force_noise, gyro_noise, gyro_bias, velocity_noise, velocity_bias,
        tilt_noise, position_noise, accel_noise, accel_bias, encoder_step; velocities, forces,
        contacts, accelerometer: True/False), or "exact" for noise-free sensors logging
        everything.
    """

class FloatingRobot:
    """A floating robot (the built-in quadruped "cheetah3", a floating URDF, or its sidecar
    TOML) and its dynamics on arrays in pinocchio's free-flyer layout: q = [x, y, z, qx, qy,
    qz, qw, joints...] (nq = 7 + n), velocities and accelerations [v, w, joints...] (nv = 6 + n,
    trunk axes), generalized forces [f, tau_trunk, joints...]; joints in the robot's order."""

    def __init__(self, robot: Path = "cheetah3", *, no_rotors: bool = False) -> None:
        """Load the floating robot; loader warnings are issued as physid.PhysidWarning.

        Keywords:

        robot: `cheetah3` (built-in leg), a .urdf file, or a .toml file with a [robot] table.
            Default: cheetah3.
        no_rotors: Drop the rotors (the link-only model).
        """
    @property
    def name(self) -> str: ...
    @property
    def trunk(self) -> str: ...
    @property
    def sizes(self) -> tuple[int, int]: ...
    @property
    def joint_names(self) -> list[str]: ...
    @property
    def parameter_names(self) -> list[str]: ...
    @property
    def mass(self) -> float: ...
    def parameters(self) -> Array: ...
    def inverse_dynamics(self, q: ArrayLike, v: ArrayLike, a: ArrayLike) -> Array: ...
    def mass_matrix(self, q: ArrayLike) -> Array: ...
    def regressor(self, q: ArrayLike, v: ArrayLike, a: ArrayLike) -> Array: ...


def identify_floating(
    data: Path,
    *,
    robot: Optional[Union[Path, "FloatingRobot"]] = None,
    no_rotors: bool = False,
    setting: str = "torques-and-contacts",
    constraints: str = "ellipsoid",
    prior_weight: float = 1e-4,
    cutoff: Optional[float] = None,
    foot: Optional[Sequence[Union[str, tuple[str, tuple[float, float, float]]]]] = None,
    contact_force: float = 10.0,
    out_urdf: Optional[Path] = None,
    out_mjcf: Optional[Path] = None,
    truth: Optional[Path] = None,
    baseline: Optional[Path] = None,
    topic: str = "/joint_states",
    odometry_topic: str = "/odometry",
    foot_forces_topic: str = "/foot_forces",
    stamp: str = "log",
) -> FloatingIdentification:
    """Identify a floating robot from one log, its description the prior, as `physid
    identify-floating` does.

    Keywords:

    data: The log: CSV, MCAP or a rosbag2 directory.
    robot: The robot: a physid.FloatingRobot (as loaded, rotors and all), or "cheetah3" (the
        built-in quadruped), a floating URDF or its sidecar TOML path. Default: cheetah3.
    no_rotors: Drop the rotors (the link-only model).
    setting: What the log's quantities are used for: torques-and-contacts (every row), torques-
        only (contact forces projected out: needs contact states or forces), base-only (the
        trunk's six rows from the contact forces; no joint torques). One of: torques-and-
        contacts, torques-only, base-only. Default: torques-and-contacts.
    constraints: Constraint set: none, semi, consistent, ellipsoid. Default: ellipsoid.
    prior_weight: Weight of the pull towards the description. Default: 0.0001.
    cutoff: Low-pass cutoff of the derived signals (Hz); default: chosen from the motion.
    foot: A foot, `BODY:X,Y,Z` (the point in the body's frame, m); repeat for each. Default: the
        built-in quadruped's.
    contact_force: Without contact_<foot> columns, a foot is down where its normal force exceeds
        this (N). Default: 10.
    out_urdf: Write the identified robot as URDF (the trunk its root link; pinocchio: free
        flyer).
    out_mjcf: Write the identified robot as MJCF (a free joint on the trunk).
    truth: The ground truth, a floating URDF of the same robot (`simulate-floating` writes it
        beside its log as <log>.truth.urdf): every body's errors against it are reported.
    baseline: A results folder to compare against.
    topic: MCAP and rosbag2 logs: the joint states' topic (sensor_msgs/msg/JointState). Default:
        /joint_states.
    odometry_topic: MCAP and rosbag2 logs: the trunk's topic (nav_msgs/msg/Odometry: pose in the
        world, twist in trunk coordinates), interpolated to the joint states' times. Default:
        /odometry.
    foot_forces_topic: MCAP and rosbag2 logs: the feet's topic (physid_msgs/msg/FootForces: per
        foot, the ground's force in world coordinates and the contact state). Default:
        /foot_forces.
    imu_topic: MCAP and rosbag2 logs: the IMU's topic (sensor_msgs/msg/Imu at the trunk frame's
        origin), whose accelerometer gives the trunk's linear acceleration where the log has it.
        Default: /imu.
    stamp: MCAP and rosbag2 logs: which time stamps a message, log (the recorder's receive time)
        or header (its header.stamp); every topic alike. Default: log.
    """
