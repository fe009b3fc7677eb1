"""Named flights: what happens to the vehicle (rotor faults, in order), where it should be
(setpoints) and for how long. A paper's scenarios are instances (Ke's :class:`KeScenario` adds
what Ke predicts); the verdict on a flown scenario is :func:`rotorfault.flight.outcomes.flight_metrics`."""

from __future__ import annotations

from dataclasses import dataclass

from .faults import RotorFault

#: Where the package's hover flights start and hold: 10 m up (world NED).
HOVER_M = (0.0, 0.0, -10.0)


@dataclass(frozen=True)
class FlightScenario:
    """A named flight: faults applied in order from hover, setpoints (time, NED position).
    ``efficiency`` is the rotor efficiencies after the last fault."""

    name: str
    description: str
    efficiency: tuple[float, ...]
    faults: tuple[RotorFault, ...]
    duration_s: float = 40.0
    setpoints: tuple[tuple[float, tuple[float, float, float]], ...] = ((0.0, HOVER_M),)


__all__ = ["HOVER_M", "FlightScenario"]
