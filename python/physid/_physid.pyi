"""Type stubs of the extension module physid._physid."""

from typing import Any, Optional

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]

class Robot:
    """A robot: "cheetah3" (the built-in leg), a URDF file, or a robot TOML file."""

    def __init__(self, robot: str) -> None: ...
    @property
    def name(self) -> str: ...
    @property
    def dof(self) -> int: ...
    @property
    def joint_names(self) -> list[str]: ...
    @property
    def parameter_names(self) -> list[str]: ...
    def parameters(self) -> Array:
        """The description's parameter vector theta."""
    def inverse_dynamics(self, q: Array, qd: Array, qdd: Array) -> Array:
        """tau = RNEA + friction (N m), shape (samples, n)."""
    def mass_matrix(self, q: Array) -> Array:
        """H(q) (kg m^2), shape (samples, n, n)."""
    def regressor(self, q: Array, qd: Array, qdd: Array) -> Array:
        """Y(q, qd, qdd) with Y @ theta = tau, shape (samples, n, p)."""
    def describe(self) -> dict[str, Any]:
        """The JSON of `physid model --json`."""

def identify_arrays(
    robot: Robot,
    q: Array,
    qd: Array,
    qdd: Array,
    tau: Array,
    constraints: Optional[str] = None,
    prior_weight: float = 1e-6,
) -> dict[str, Any]:
    """Identify theta from arrays under a constraint set (none, semi, consistent, ellipsoid)."""

def version() -> str: ...
