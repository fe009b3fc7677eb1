"""Rotor faults: rotor ``i`` (numbered from 1, as in the papers and the CLI) changes efficiency
at a time of the run. The controller never sees them."""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from .._util.convert import real


@dataclass(frozen=True)
class RotorFault:
    """Rotor ``rotor`` (1-based) has efficiency ``efficiency`` (0 failed, 1 healthy) from ``time``
    (s) on. The controller never sees it.

    Examples:

        >>> import rotorfault as rf
        >>> fault = rf.RotorFault(rotor=1, time=2.0, efficiency=0.5)
        >>> fault
        RotorFault(rotor=1, time=2.0, efficiency=0.5)
    """

    rotor: int
    time: float
    efficiency: float = 0.0

    def __post_init__(self) -> None:
        if isinstance(self.rotor, bool) or not isinstance(self.rotor, (int, np.integer)):
            raise TypeError(f"rotor: expected a 1-based rotor number, got {self.rotor!r}")
        if not 1 <= self.rotor <= 2**31:
            raise ValueError(f"rotor: rotor numbers run from 1 to the airframe's rotor count, got {self.rotor}")
        real("time", self.time)
        real("efficiency", self.efficiency)

    def _packed(self) -> tuple[int, float, float]:
        return (int(self.rotor) - 1, float(self.time), float(self.efficiency))


def _faults(faults: Iterable[RotorFault] | None, duration_s: float, field_name: str = "faults") -> tuple[RotorFault, ...]:
    """The fault list, each fault inside the run: ``0 <= time < duration_s`` (a fault the run
    would never apply is refused, not silently dropped)."""
    if faults is None:
        return ()
    items = tuple(faults)
    for k, f in enumerate(items):
        if not isinstance(f, RotorFault):
            raise TypeError(f"{field_name}: expected rotorfault.RotorFault items, got {type(f).__name__}")
        if math.isfinite(f.time) and not 0.0 <= f.time < duration_s:  # (the core reports non-finite times)
            raise ValueError(
                f"{field_name}[{k}].time: must lie in [0, duration_s) = [0, {duration_s:g}) s, the run's span, got {f.time:g}"
            )
    return items


__all__ = ["RotorFault"]
