"""``rotorfault.vpp``: variable-pitch quadcopters that lose propellers (Wang et al. 2020).

The implementation lives in :mod:`rotorfault.control.vpp` (it designs controllers, so it sits in
the control layer); this module is its public name."""

from .control.vpp import (
    DEFAULT_DT_S,
    ROUNDOFF_RTOL,
    STATE_NAMES,
    STATE_SCALE,
    ControllabilityResult,
    FeasibleSpeeds,
    VppLinearization,
    VppTrim,
    VppVehicle,
    controllability,
    feasible_speeds,
    fixed_pitch,
    fixed_pitch_trim,
    linearize,
    lqr,
    preset,
    presets,
    trim,
)

__all__ = [
    "DEFAULT_DT_S",
    "ROUNDOFF_RTOL",
    "STATE_NAMES",
    "STATE_SCALE",
    "ControllabilityResult",
    "FeasibleSpeeds",
    "VppLinearization",
    "VppTrim",
    "VppVehicle",
    "controllability",
    "feasible_speeds",
    "fixed_pitch",
    "fixed_pitch_trim",
    "linearize",
    "lqr",
    "preset",
    "presets",
    "trim",
]
