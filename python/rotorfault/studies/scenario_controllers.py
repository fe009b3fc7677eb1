"""The controllers a scenario file can fly, by the registry's names
(:mod:`rotorfault.control.registry`): one builder per registered Rust controller turns the
``[controller]`` table of a scenario file into the controller, designed for the scenario's
simulator (``tests/studies/test_scenario_files.py`` checks that every registered controller has
one, so a controller added to the registry is selectable in a file once its builder is here).

Keys every position-holding controller reads: ``setpoint_m = [north, east, down]`` (default: the
initial position) or ``setpoints = [[time_s, north, east, down], ...]`` (Ke's moving setpoint).
The keys of each controller are listed in :data:`BUILDERS` (``keys``) and in the schema of
:mod:`rotorfault.studies.scenario_file`; an unknown key is an error naming the allowed ones.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, get_args

import numpy as np

from .._typing import VppInputs
from .._util.convert import FloatArray, float_array, real
from ..control import Allocated, IndiController, IndiGains, LinearFeedback, Lti, OpenLoop, TrackingFeedback, UniformPassiveFtc
from ..control import hover_trim, lqr_hover, lqr_hover_allocated
from ..allocation import Allocator
from ..flight import FixedPitchActuator, RotorFault, Simulator

Setpoint = tuple[float, tuple[float, float, float]]


@dataclass(frozen=True)
class Context:
    """What a builder knows of the scenario: the simulator, the paper vehicle it was built from
    (``vehicle_kind``: ``"airframe"``, ``"ke"``, ``"lanzon"`` or ``"vpp"``; ``vehicle``: the
    :class:`~rotorfault.control.ke.FtcPreset`, :class:`~rotorfault.control.lanzon.LanzonVehicle`
    or :class:`~rotorfault.vpp.VppVehicle`, None for a plain airframe), the setpoints, the faults
    and the reference table (``[reference]``, None without one)."""

    simulator: Simulator
    vehicle_kind: str
    vehicle: Any
    setpoints: tuple[Setpoint, ...]
    faults: tuple[RotorFault, ...]
    reference: tuple[FloatArray, FloatArray] | None

    @property
    def setpoint(self) -> tuple[float, float, float]:
        return self.setpoints[0][1]


@dataclass(frozen=True)
class Builder:
    """How a scenario file builds one registered controller: its keys (name -> what it is) and
    the function ``build(context, parameters)``."""

    keys: Mapping[str, str]
    build: Callable[[Context, dict[str, Any]], Any]
    #: The vehicle kinds it flies (empty: any).
    vehicles: tuple[str, ...] = ()


def _vector(name: str, value: Any, length: int | None = None) -> FloatArray:
    array = float_array(f"controller.{name}", value, 1)
    if length is not None and array.shape != (length,):
        raise ValueError(f"controller.{name}: expected {length} entries, got {array.shape[0]}")
    return array


def _weights(p: dict[str, Any], m: int) -> tuple[FloatArray | None, FloatArray | None]:
    q = None if "q_diag" not in p else np.diag(_vector("q_diag", p["q_diag"], 12))
    r = None if "r_diag" not in p else np.diag(_vector("r_diag", p["r_diag"], m))
    return q, r


def _fixed_pitch(context: Context, kind: str) -> None:
    if context.simulator.command_count != context.simulator.airframe.rotor_count:
        raise ValueError(f"controller.kind: {kind} designs for fixed-pitch rotors; this vehicle has variable pitch (use tracking-feedback)")


def _open_loop(context: Context, p: dict[str, Any]) -> OpenLoop:
    if "commands" in p:
        return OpenLoop.constant(_vector("commands", p["commands"], context.simulator.command_count))
    _fixed_pitch(context, "open-loop (without commands)")
    return OpenLoop.constant(hover_trim(context.simulator, position=context.setpoint).command)


def _linear_feedback(context: Context, p: dict[str, Any]) -> LinearFeedback:
    _fixed_pitch(context, "linear-feedback")
    q, r = _weights(p, context.simulator.command_count)
    return lqr_hover(context.simulator, q=q, r=r, position=context.setpoint)


def _lti(context: Context, p: dict[str, Any]) -> Lti:
    _fixed_pitch(context, "lti")
    for key in ("a", "b", "c", "d"):
        if key not in p:
            raise ValueError(f"controller.{key}: required for an lti controller (xi' = a xi + b e, u = u_trim + c xi + d e)")
    trim = hover_trim(context.simulator, position=context.setpoint)
    a, b, c, d = (float_array(f"controller.{key}", p[key], 2) for key in ("a", "b", "c", "d"))
    dt_s = None if "dt_s" not in p else real("controller.dt_s", p["dt_s"])
    return Lti(a, b, c, d, trim.state, trim.command, dt_s=dt_s)


def _allocated(context: Context, p: dict[str, Any]) -> Allocated:
    _fixed_pitch(context, "allocated")
    weights = None if "weights" not in p else _vector("weights", p["weights"], 4)
    q, r = _weights(p, context.simulator.command_count)
    return lqr_hover_allocated(context.simulator, Allocator(context.simulator.airframe, weights=weights), q=q, r=r, position=context.setpoint)


def _uniform_passive_ftc(context: Context, p: dict[str, Any]) -> UniformPassiveFtc:
    from ..control import ke

    gains = p.get("gains", context.vehicle.name if context.vehicle_kind == "ke" else "ke-hil")
    if not isinstance(gains, str):
        raise TypeError(f"controller.gains: expected a gains preset name ({', '.join(ke.presets())}), got {type(gains).__name__}")
    values = ke.preset(gains).gains
    overrides = p.get("gain_values", {})
    if not isinstance(overrides, dict):
        raise ValueError("controller.gain_values: expected a table of KeGains fields")
    if overrides:
        values = values.replace(**overrides)
    return UniformPassiveFtc(context.simulator.airframe, gains=values, law=p.get("law", "feedforward"), setpoints=context.setpoints)


def _lanzon_controller(context: Context, p: dict[str, Any]) -> Any:
    from ..control.lanzon import LanzonController, OuterLoopGains, design

    options = {k: p[k] for k in ("crossover_rad_s", "low_gain_db", "rolloff_factor", "channel_gain", "factor") if k in p}
    designed = design(context.vehicle, **options)
    outer = p.get("outer_loop", True)
    if not isinstance(outer, bool):
        raise TypeError(f"controller.outer_loop: expected true or false, got {type(outer).__name__}")
    gains = p.get("outer_loop_gains", {})
    if not isinstance(gains, dict):
        raise ValueError("controller.outer_loop_gains: expected a table of OuterLoopGains fields")
    return LanzonController(designed, position=context.setpoint if outer else None, outer_loop=OuterLoopGains(**gains))


def _tracking_feedback(context: Context, p: dict[str, Any]) -> TrackingFeedback:
    if context.reference is None:
        raise ValueError("reference: a tracking-feedback controller needs a [reference] table (circle or steps)")
    times, references = context.reference
    limit = np.full(12, math.inf)
    limit[:3] = real("controller.error_limit_m", p.get("error_limit_m", math.inf))
    if context.vehicle_kind == "vpp":
        from ..control import vpp

        speeds_raw = p.get("trim_speeds", {})
        if not isinstance(speeds_raw, dict):
            raise ValueError("controller.trim_speeds: expected a table {rotor = speed}")
        speeds = {int(k): real(f"controller.trim_speeds.{k}", v) for k, v in speeds_raw.items()} or None
        failed = tuple(int(k) + 1 for k in np.flatnonzero(context.simulator.airframe.efficiency == 0.0))
        trim = vpp.trim(context.vehicle, failed=failed, speeds=speeds)
        inputs = p.get("inputs", "every-channel")
        if inputs not in get_args(VppInputs):
            raise ValueError(f"controller.inputs: must be one of {', '.join(get_args(VppInputs))}, got {inputs!r}")
        feedback = vpp.lqr(context.vehicle, trim, dt_s=context.simulator.dt_s, inputs=inputs)
    else:
        q, r = _weights(p, context.simulator.command_count)
        feedback = lqr_hover(context.simulator, q=q, r=r, position=tuple(references[0, :3]))
    return TrackingFeedback.from_feedback(feedback, times_s=times, references=references, error_limit=limit)


def _indi_controller(context: Context, p: dict[str, Any]) -> IndiController:
    told = p.get("told", True)
    if not isinstance(told, bool):
        raise TypeError(f"controller.told: expected true or false, got {type(told).__name__}")
    gains = p.get("gain_values", {})
    if not isinstance(gains, dict):
        raise ValueError("controller.gain_values: expected a table of IndiGains fields")
    velocity = _vector("velocity_m_s", p.get("velocity_m_s", (0.0, 0.0, 0.0)), 3)
    return IndiController(context.simulator.airframe, failures=list(context.faults) if told else [], gains=IndiGains(**gains),
                          setpoints=list(context.setpoints), velocity=velocity)


def _relaxed_hover_feedback(context: Context, p: dict[str, Any]) -> Any:
    from ..analysis.relaxed_hover import relaxed_hover
    from ..control.relaxed_hover import RelaxedHoverFeedback

    _fixed_pitch(context, "relaxed-hover-feedback")
    sim = context.simulator
    actuator = sim.actuator
    assert isinstance(actuator, FixedPitchActuator)  # _fixed_pitch above
    # The relaxed hover after the file's total failures (the vehicle it will fly once they happen).
    failed = sorted({f.rotor for f in context.faults if f.efficiency == 0.0})
    airframe = sim.airframe.with_failed_rotors(failed) if failed else sim.airframe
    best = relaxed_hover(airframe, drag=sim.drag, actuator=actuator).best
    if best is None:
        lost = f"rotor(s) {', '.join(map(str, failed))} failed" if failed else "no rotor failed"
        raise ValueError(f"controller.kind: relaxed-hover-feedback: {airframe.name} with {lost} has no relaxed hover a linear feedback can hold")
    return RelaxedHoverFeedback(best, airframe, position=context.setpoint, linear_drag_n_s_m=sim.drag.linear_n_s_m)


_WEIGHTS = {"q_diag": "LQR state weights, 12 diagonal entries (default Bryson's rule)",
            "r_diag": "LQR input weights, one per rotor (default Bryson's rule)"}

#: The builders by registry name (:func:`rotorfault.control.registry.entries`).
BUILDERS: dict[str, Builder] = {
    "open-loop": Builder({"commands": "constant commands, one per channel (default: the hover trim)"}, _open_loop),
    "linear-feedback": Builder(dict(_WEIGHTS), _linear_feedback),
    "lti": Builder({"a": "matrix", "b": "matrix", "c": "matrix", "d": "matrix (xi' = a xi + b e, u = u_trim + c xi + d e, e = x - x_trim)",
                    "dt_s": "the matrices' sampling period (default: continuous)"}, _lti),
    "allocated": Builder({"weights": "allocation weights of thrust, roll, pitch, yaw", **_WEIGHTS}, _allocated),
    "uniform-passive-ftc": Builder({"gains": "a gains preset (ke-hil, ke-experiment)", "gain_values": "table of KeGains fields overriding it",
                                    "law": "feedforward, literal, full-compensation or baseline"}, _uniform_passive_ftc),
    "lanzon-controller": Builder({"crossover_rad_s": "loop-shape crossover (the paper: 100; ours: 30)", "low_gain_db": "low-frequency gain",
                                  "rolloff_factor": "roll-off above the crossover", "channel_gain": "[phi, theta, r]",
                                  "factor": "gamma / gamma_min", "outer_loop": "hold setpoint_m (default true)",
                                  "outer_loop_gains": "table of OuterLoopGains fields"}, _lanzon_controller, ("lanzon",)),
    "tracking-feedback": Builder({"trim_speeds": "VPP: {rotor = speed} of the trim (default: middle of the feasible range)",
                                  "inputs": "VPP: the design's inputs, wang (omega_3 held, Wang's) or every-channel (default)",
                                  "error_limit_m": "clip of each position error (default: none)", **_WEIGHTS}, _tracking_feedback),
    "relaxed-hover-feedback": Builder({}, _relaxed_hover_feedback),
    "indi-controller": Builder({"told": "the controller is told the failures (default true)", "gain_values": "table of IndiGains fields",
                                "velocity_m_s": "velocity setpoint"}, _indi_controller),
}
#: Keys every controller table may have besides its own.
COMMON_KEYS = {"kind": "the controller (a registry name, none, or an alias)", "setpoint_m": "the position held (default: the start)",
               "setpoints": "[[time_s, north, east, down], ...]: a moving setpoint"}
#: The scenario files of the first release named two designs: still accepted.
ALIASES = {"lqr-hover": "linear-feedback", "open-loop-hover": "open-loop"}


def check(kind: str, vehicle_kind: str, parameters: Mapping[str, Any]) -> None:
    """What :func:`build` refuses without designing anything, so that a scenario file is refused
    when it is read: unknown keys, a controller for another kind of vehicle, and a number that is
    not finite anywhere in the table (no controller parameter is NaN or infinite)."""
    if kind == "none":
        if parameters:
            raise ValueError(f"controller: kind none takes no parameters, got {', '.join(sorted(parameters))}")
        return
    builder = BUILDERS[ALIASES.get(kind, kind)]
    unknown = set(parameters) - set(builder.keys)
    if unknown:
        allowed = ", ".join(sorted({*builder.keys, *COMMON_KEYS})) or "none"
        raise ValueError(f"controller: unknown key(s) {', '.join(sorted(unknown))} for {kind}; allowed: {allowed}")
    if builder.vehicles and vehicle_kind not in builder.vehicles:
        raise ValueError(f"controller.kind: {kind} flies a [vehicle] of kind {' or '.join(builder.vehicles)} (its design needs that model)")
    for key, value in parameters.items():
        _require_finite(f"controller.{key}", value)


def _require_finite(field: str, value: Any) -> None:
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"{field}: must be a finite number, got {value}")
    if isinstance(value, dict):
        for k, v in value.items():
            _require_finite(f"{field}.{k}", v)
    elif isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            _require_finite(f"{field}[{i}]", v)


def build(kind: str, context: Context, parameters: Mapping[str, Any]) -> Any:
    """The controller ``kind`` (a registry name or an alias; ``"none"``: None) for ``context``,
    with ``parameters`` (the ``[controller]`` table without the common keys)."""
    check(kind, context.vehicle_kind, parameters)
    if kind == "none":
        return None
    return BUILDERS[ALIASES.get(kind, kind)].build(context, dict(parameters))


def kinds() -> tuple[str, ...]:
    """Every ``kind`` a scenario file accepts."""
    return ("none", *BUILDERS, *ALIASES)


def check_registry(names: Sequence[str]) -> list[str]:
    """The registered controller names without a builder (empty: every one is selectable)."""
    return [n for n in names if n not in BUILDERS]


__all__ = ["ALIASES", "BUILDERS", "COMMON_KEYS", "Builder", "Context", "build", "check", "check_registry", "kinds"]
