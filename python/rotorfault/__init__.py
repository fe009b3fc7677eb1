"""rotorfault: multirotor rotor failures, from controllability to flight.

Controllability under rotor degradation (Du et al., JGCD 2015)::

    >>> import rotorfault as rf
    >>> hexa = rf.Airframe.preset("hexa-ppnnpn")
    >>> round(rf.acai(hexa), 4)
    1.1295
    >>> print(rf.failure_table(hexa, max_failed=1))  # doctest: +SKIP
"""

from typing import TYPE_CHECKING

from ._rfcore import __version__
from .airframe import Airframe
from .controllability import (
    RANK_RTOL,
    ZERO_RTOL,
    ControllabilityReport,
    FailureCase,
    FailureTable,
    acai,
    acai_batch,
    acai_from_matrix,
    controllability,
    failure_table,
)
from .allocation import (
    Allocation,
    Allocator,
    DirectionalLimit,
    HoverMargin,
    allocate,
    hover_thrust_margin,
    max_virtual_control,
)
from .control import (
    Allocated,
    Controller,
    HoverTrim,
    LinearFeedback,
    Lti,
    OpenLoop,
    RelaxedHoverLqr,
    TrackingFeedback,
    UniformPassiveFtc,
    hover_trim,
    linearize,
    lqr_hover,
    lqr_hover_allocated,
)
from . import vpp
from .relaxed_hover import RelaxedHoverAnalysis, RelaxedHoverSettings, RelaxedHoverSolution, periodic_state, relaxed_hover
from .scan import EfficiencyScan, Scan, acai_scan, efficiency_scan, failure_samples, plot_efficiency_scan, read_scan
from .design import Design, DesignSearch, design_search
from .simulation import (
    BatchResult,
    DivergenceLimits,
    Drag,
    Event,
    FixedPitchActuator,
    MAX_RATE_STEP,
    Noise,
    RotorFault,
    Simulator,
    State,
    Trajectory,
    VariablePitchActuator,
    simulate_batch,
)

if TYPE_CHECKING:
    from .control.lanzon import LanzonController
    from .control.robust import ncfsyn

#: Names whose modules import python-control and scipy: loaded on first use (via
#: rotorfault.control), so ``import rotorfault`` stays light (tests/test_architecture.py).
_LAZY_CONTROL = ("LanzonController", "ncfsyn")


def __getattr__(name: str) -> object:
    if name in _LAZY_CONTROL:
        from . import control

        value = getattr(control, name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "LanzonController",
    "ncfsyn",
    "vpp",
    "RelaxedHoverAnalysis",
    "RelaxedHoverLqr",
    "RelaxedHoverSettings",
    "RelaxedHoverSolution",
    "periodic_state",
    "relaxed_hover",
    "Lti",
    "UniformPassiveFtc",
    "Controller",
    "Allocated",
    "Allocation",
    "Allocator",
    "DirectionalLimit",
    "HoverMargin",
    "allocate",
    "hover_thrust_margin",
    "max_virtual_control",
    "lqr_hover_allocated",
    "BatchResult",
    "DivergenceLimits",
    "Drag",
    "Event",
    "FixedPitchActuator",
    "LinearFeedback",
    "Noise",
    "OpenLoop",
    "TrackingFeedback",
    "RotorFault",
    "Simulator",
    "State",
    "Trajectory",
    "VariablePitchActuator",
    "HoverTrim",
    "hover_trim",
    "linearize",
    "lqr_hover",
    "simulate_batch",
    "RANK_RTOL",
    "MAX_RATE_STEP",
    "ZERO_RTOL",
    "Airframe",
    "ControllabilityReport",
    "EfficiencyScan",
    "FailureCase",
    "FailureTable",
    "__version__",
    "acai",
    "acai_batch",
    "acai_from_matrix",
    "controllability",
    "efficiency_scan",
    "failure_table",
    "plot_efficiency_scan",
    "Scan",
    "acai_scan",
    "read_scan",
    "failure_samples",
    "Design",
    "DesignSearch",
    "design_search",
]
