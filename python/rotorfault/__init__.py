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
from .analysis import (
    RANK_RTOL,
    ZERO_RTOL,
    Airframe,
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
    hover_wrench_distance,
    max_virtual_control,
)
from .control import (
    Allocated,
    Controller,
    HoverTrim,
    IndiController,
    IndiGains,
    LinearFeedback,
    Lti,
    OpenLoop,
    RelaxedHoverFeedback,
    periodic_state,
    TrackingFeedback,
    UniformPassiveFtc,
    hover_trim,
    linearize,
    lqr_hover,
    lqr_hover_allocated,
)
from . import vpp
from .analysis.relaxed_hover import RelaxedHoverAnalysis, RelaxedHoverSettings, RelaxedHoverSolution, relaxed_hover
from .studies.scan import EfficiencyScan, Scan, acai_scan, efficiency_scan, failure_samples, plot_efficiency_scan, read_scan
from .studies.design import Design, DesignSearch, design_search
from .flight import (
    BatchResult,
    Divergence,
    DivergenceLimits,
    Drag,
    FixedPitchActuator,
    MAX_RATE_STEP,
    Noise,
    RotorFault,
    Sensing,
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
#: rotorfault.control), so ``import rotorfault`` stays light (tests/cross/test_architecture.py).
_LAZY_CONTROL = ("LanzonController", "ncfsyn")
#: Modules that moved into the rooms in issue 26: ``rotorfault.<old>`` still resolves, for one
#: release, to a module that warns (``rotorfault/<old>.py``).
_MOVED_MODULES = ("airframe", "campaign", "certify", "controllability", "design", "scan", "scenario", "simulation")


def __getattr__(name: str) -> object:
    if name in _LAZY_CONTROL:
        from . import control

        value = getattr(control, name)
        globals()[name] = value
        return value
    if name == "Event":  # the old name of Divergence: warns (flight.trajectory)
        from .flight import trajectory

        return trajectory.Event
    if name in _MOVED_MODULES:
        import importlib

        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "LanzonController",
    "ncfsyn",
    "vpp",
    "RelaxedHoverAnalysis",
    "RelaxedHoverFeedback",
    "RelaxedHoverSettings",
    "RelaxedHoverSolution",
    "periodic_state",
    "relaxed_hover",
    "Lti",
    "UniformPassiveFtc",
    "IndiController",
    "IndiGains",
    "Controller",
    "Allocated",
    "Allocation",
    "Allocator",
    "DirectionalLimit",
    "HoverMargin",
    "allocate",
    "hover_thrust_margin",
    "hover_wrench_distance",
    "max_virtual_control",
    "lqr_hover_allocated",
    "BatchResult",
    "DivergenceLimits",
    "Drag",
    "Divergence",
    "FixedPitchActuator",
    "LinearFeedback",
    "Noise",
    "OpenLoop",
    "TrackingFeedback",
    "RotorFault",
    "Sensing",
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
