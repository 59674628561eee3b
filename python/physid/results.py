"""Findings of a diagnosis as plain Python values (they pickle, compare and print as data)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional


@dataclass(frozen=True)
class BodyChange:
    """A change of one body's inertial parameters found by the diagnosis, in the body's frame.

    `mass` (kg) and `mass_se` (its standard error, kg; None where no joint torque feels the
    mass) are as weighed at the body's own step of the ladder, `com` (m, body frame; None
    unless the added mass is positive and determined) likewise; `final_mass`, `final_mass_se`
    and `final_com` with every explanation of the ladder free (`moved`: the later steps moved
    the mass by more than its standard error allows, they trade off with it). `payload`: the
    change reads as a payload (added mass beyond three standard errors, its centre of mass
    near the body). `pi`: the ten parameters of the change (m, hx, hy, hz, Ixx, Ixy, Ixz, Iyy,
    Iyz, Izz; kg, kg m, kg m²) in the final fit.
    """

    body: str
    payload: bool
    mass: float
    mass_se: Optional[float]
    com: Optional[tuple[float, float, float]]
    moved: bool
    final_mass: float
    final_mass_se: Optional[float]
    final_com: Optional[tuple[float, float, float]]
    pi: tuple[float, ...]


def _point(v: Any) -> Optional[tuple[float, float, float]]:
    return None if v is None else (float(v[0]), float(v[1]), float(v[2]))


def body_changes(found: list[dict[str, Any]]) -> list[BodyChange]:
    """The ladder's `bodies` of a diagnosis report (its JSON) as BodyChange values."""
    return [
        BodyChange(
            body=b["body"],
            payload=bool(b["payload"]),
            mass=float(b["mass"]),
            mass_se=b["mass_se"],
            com=_point(b["com"]),
            moved=bool(b["moved"]),
            final_mass=float(b["last"]["mass"]),
            final_mass_se=b["last"]["mass_se"],
            final_com=_point(b["last"]["com"]),
            pi=tuple(float(x) for x in b["pi"]),
        )
        for b in found
    ]
