"""Identification from arrays you already have: `identify_arrays`, a `physid.Data` run through
`physid.identify`."""
from __future__ import annotations

from typing import Any, Optional

from ._physid import Data, Identification, Robot, identify


def identify_arrays(
    robot: Robot,
    q: Any,
    qd: Any,
    qdd: Any,
    tau: Any,
    *,
    rate: float = 1000.0,
    t: Optional[Any] = None,
    name: Optional[str] = None,
    **keywords: Any,
) -> Identification:
    """Identifies `robot` from samples held as arrays, exactly as `physid.identify` does from a
    file: `q` (rad or m), `qd` (rad/s), `qdd` (rad/s²) and `tau` (N m or N), each an
    array-like of shape `(samples, n)`, read as a `physid.Data` logged at `rate` Hz (or at the
    time stamps `t`, s). Every keyword of `identify` applies (`constraints`, `friction`,
    `validate_data`, `train`, `validate`, `prior_weight`, `mass_bounds`, …) and so do its
    checks (too few samples for the parameters is refused unless `allow_few_samples=True`).
    Returns an `Identification` (`theta`, `bodies()`, `joints()`, `write_urdf`, …)."""
    if t is not None:
        rate = None  # the time stamps given stand for the rate
    run = Data(q, tau, qd=qd, qdd=qdd, t=t, rate=rate, name=name)
    return identify(robot, run, **keywords)
