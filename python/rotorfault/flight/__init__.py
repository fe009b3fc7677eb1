"""Flight: one vehicle flown through time. The simulator wrapper (:mod:`~rotorfault.flight.simulator`:
:class:`Simulator`, :func:`simulate_batch`, the divergence limits), the vehicle state, the actuator,
drag and noise models, the sensors a controller may fly on (:data:`Sensing`), rotor faults, the trajectory a run returns, named flight scenarios
(:mod:`~rotorfault.flight.scenarios`) and the verdict on a whole flight
(:mod:`~rotorfault.flight.outcomes`: holds position, circling, off station, or lost;
:mod:`~rotorfault.flight.attitude`: level and spinning, for a flight without a position loop). Mirrors the
core's ``flight`` room.

May import: ``rotorfault.analysis`` (the airframe), ``rotorfault._typing``, ``rotorfault._util``
and, on first use, ``rotorfault.plotting``. Never ``control``: the simulator flies anything with
``core(dt_s)`` (the :class:`~rotorfault.control.Controller` protocol in ``_typing``), as the core's
simulator flies any ``Controller``.
"""

from .faults import RotorFault
from .models import Drag, FixedPitchActuator, Noise, Sensing, VariablePitchActuator
from .simulator import MAX_RATE_STEP, DivergenceLimits, Simulator, simulate_batch
from .state import State
from .trajectory import BatchResult, Divergence, Estimates, Trajectory


def __getattr__(name: str) -> object:
    if name == "Event":  # the old name of Divergence: warns (flight.trajectory)
        from . import trajectory

        return trajectory.Event
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "MAX_RATE_STEP",
    "BatchResult",
    "DivergenceLimits",
    "Drag",
    "Divergence",
    "Estimates",
    "FixedPitchActuator",
    "Noise",
    "RotorFault",
    "Sensing",
    "Simulator",
    "State",
    "Trajectory",
    "VariablePitchActuator",
    "simulate_batch",
]
