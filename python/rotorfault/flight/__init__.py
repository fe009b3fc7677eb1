"""Flight: one vehicle flown through time. The simulator wrapper (:mod:`~rotorfault.flight.simulator`:
:class:`Simulator`, :func:`simulate_batch`, the divergence limits), the vehicle state, the actuator,
drag and noise models, rotor faults, the trajectory a run returns, named flight scenarios
(:mod:`~rotorfault.flight.scenarios`) and the verdict on a whole flight
(:mod:`~rotorfault.flight.outcomes`: holds position, circling, off station, or lost). Mirrors the
core's ``flight`` room.

May import: ``rotorfault.analysis`` (the airframe), ``rotorfault._typing``, ``rotorfault._util``
and, on first use, ``rotorfault.plotting``. Never ``control``: the simulator flies anything with
``core(dt_s)`` (the :class:`~rotorfault.control.Controller` protocol in ``_typing``), as the core's
simulator flies any ``Controller``.
"""

from .faults import RotorFault
from .models import Drag, FixedPitchActuator, Noise, VariablePitchActuator
from .simulator import MAX_RATE_STEP, DivergenceLimits, Simulator, simulate_batch
from .state import State
from .trajectory import BatchResult, Event, Trajectory

__all__ = [
    "MAX_RATE_STEP",
    "BatchResult",
    "DivergenceLimits",
    "Drag",
    "Event",
    "FixedPitchActuator",
    "Noise",
    "RotorFault",
    "Simulator",
    "State",
    "Trajectory",
    "VariablePitchActuator",
    "simulate_batch",
]
