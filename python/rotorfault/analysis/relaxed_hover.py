"""Relaxed hover (Mueller and D'Andrea, IJRR 2016; ICRA 2014): every way a multirotor can stay in
place with constant rotor thrusts, static or spinning at a constant rate about a vertical axis,
once static hover is lost (a quadrotor without a rotor, a hexacopter whose ACAI is 0).

:func:`relaxed_hover` returns every strategy's best solution (a strategy: which rotors carry the
vehicle, static or spinning, the spin direction), each checked against the equations and with its
linear model; ``analysis.best`` is the one with the most thrust margin (headroom: the smallest
distance of a carrying rotor's thrust to its upper bound) among those a linear feedback can hold.
The equations, the margin and the search are documented in the core
(``crates/rfcore/src/analysis/relaxed_hover/mod.rs``)::

    >>> import rotorfault as rf
    >>> quad = rf.Airframe.preset("ke-quadcopter").with_failed_rotors([1])
    >>> best = rf.relaxed_hover(quad, drag=rf.Drag(rotational_n_m_s=2.8e-3)).best
    >>> round(best.spin_rate_rad_s, 2), best.carrying
    (15.22, [2, 3, 4])

:func:`circle_offsets` gives the circle the centre of mass describes;
:func:`rotorfault.control.periodic_state` the state on the periodic solution (where to start a
flight; the solution's ``command_n`` held constant flies it), and
:class:`rotorfault.control.RelaxedHoverFeedback` holds it with an LQR.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import numpy.typing as npt

from .. import _rfcore
from .._util.convert import FloatArray, float_array, real
from .airframe import Airframe, require_airframe

class FixedPitchActuatorLike(Protocol):
    """What the analysis reads of :class:`rotorfault.FixedPitchActuator`."""

    @property
    def thrust_coefficient_n_s2(self) -> float: ...


RelaxedHoverSettings = _rfcore.RelaxedHoverSettings
RelaxedHoverSolution = _rfcore.RelaxedHoverSolution
RelaxedHoverAnalysis = _rfcore.RelaxedHoverAnalysis

_DEFAULT = _rfcore.RelaxedHoverSettings()
#: The settings that describe the vehicle (the simulator's drag and actuator), not the search.
_PHYSICAL = ("rotational_drag_n_m_s", "rotor_inertia_kg_m2", "thrust_coefficient_n_s2")
_FIELDS = (*_PHYSICAL, "max_spin_rate_rad_s", "max_circle_radius_m", "max_idle_rotors", "grid_points")


def relaxed_hover(
    airframe: Airframe,
    settings: RelaxedHoverSettings | None = None,
    *,
    drag: _rfcore.Drag | None = None,
    actuator: FixedPitchActuatorLike | None = None,
    best_only: bool = False,
) -> RelaxedHoverAnalysis:
    """Every relaxed hover solution of ``airframe`` (its efficiencies: a failed rotor has 0),
    best first. The rotational damping ``k_r``, rotor inertia ``I_R`` and thrust coefficient
    ``k_f`` are the simulator's: pass its ``drag`` and ``actuator`` (they fill those settings) or
    set them in ``settings``, not both. ``best_only``: only what decides ``.best`` (the same
    solution, several times faster on quadrotors): carrying sets whose thrust margin cannot reach
    the best holdable one already found are not searched, so ``solutions`` may list fewer
    strategies.

    Examples:

        >>> import rotorfault as rf
        >>> quad = rf.Airframe.preset("ke-quadcopter").with_failed_rotors([1])
        >>> settings = rf.RelaxedHoverSettings(rotational_drag_n_m_s=2.8e-3, grid_points=21)
        >>> best = rf.relaxed_hover(quad, settings).best
        >>> round(best.spin_rate_rad_s, 2), best.carrying
        (15.22, [2, 3, 4])
    """
    airframe = require_airframe(airframe)
    if not isinstance(best_only, bool):
        raise TypeError(f"best_only: expected True or False, got {type(best_only).__name__}")
    settings = _vehicle_settings(settings, drag, actuator)
    return _rfcore.relaxed_hover(airframe._core, settings, best_only)


def _vehicle_settings(
    settings: RelaxedHoverSettings | None, drag: _rfcore.Drag | None, actuator: FixedPitchActuatorLike | None
) -> RelaxedHoverSettings:
    """``settings`` (default :class:`RelaxedHoverSettings`) with the vehicle's rotor parameters from
    ``drag`` and ``actuator`` (given once), each checked by type first."""
    if settings is None:
        settings = _DEFAULT
    if not isinstance(settings, RelaxedHoverSettings):
        raise TypeError(f"settings: expected rotorfault.RelaxedHoverSettings, got {type(settings).__name__}")
    if drag is not None and not isinstance(drag, _rfcore.Drag):
        raise TypeError(f"drag: expected rotorfault.Drag, got {type(drag).__name__}")
    # The actuator is read, not built (rotorfault.FixedPitchActuator lives in the flight room,
    # above this one): anything with a thrust coefficient; a variable-pitch actuator has none.
    if actuator is not None and not isinstance(getattr(actuator, "thrust_coefficient_n_s2", None), (int, float)):
        raise TypeError(
            f"actuator: expected rotorfault.FixedPitchActuator (relaxed hover is for rotors commanded in thrust), "
            f"got {type(actuator).__name__}"
        )
    if drag is not None or actuator is not None:
        given = [name for name in _PHYSICAL if getattr(settings, name) != getattr(_DEFAULT, name)]
        if given:
            raise ValueError(
                f"settings: {', '.join(given)} given both in settings and through drag/actuator; give the vehicle's "
                "rotor parameters once"
            )
        values = {name: getattr(settings, name) for name in _FIELDS}
        if drag is not None:
            values["rotational_drag_n_m_s"] = real("drag.rotational_n_m_s", drag.rotational_n_m_s)
            values["rotor_inertia_kg_m2"] = real("drag.rotor_inertia_kg_m2", drag.rotor_inertia_kg_m2)
        if actuator is not None:
            values["thrust_coefficient_n_s2"] = real("actuator.thrust_coefficient_n_s2", actuator.thrust_coefficient_n_s2)
        settings = RelaxedHoverSettings(**values)
    return settings


def relaxed_hover_residual(
    airframe: Airframe,
    body_rate_rad_s: npt.ArrayLike,
    up: npt.ArrayLike,
    thrust_n: npt.ArrayLike,
    settings: RelaxedHoverSettings | None = None,
) -> float:
    """The scaled residual of the relaxed hover equations at a proposed body rate (zero, or
    parallel to ``up``), up axis (unit, body FRD) and produced rotor thrusts: the check every
    solution passes (below ``1e-9``), usable on a flight's steady state."""
    airframe = require_airframe(airframe)
    settings = _DEFAULT if settings is None else settings
    rate = _three("body_rate_rad_s", body_rate_rad_s)
    axis = _three("up", up)
    thrust = float_array("thrust_n", thrust_n, 1)
    return float(_rfcore.relaxed_hover_residual(airframe._core, settings, rate, axis, thrust))


def _three(name: str, value: npt.ArrayLike) -> tuple[float, float, float]:
    v = float_array(name, value, 1)
    if v.shape != (3,):
        raise ValueError(f"{name}: expected 3 entries, got {v.shape[0]}")
    return (float(v[0]), float(v[1]), float(v[2]))


@dataclass(frozen=True)
class CircleOffsets:
    """Where the centre of mass is relative to the centre of the circle it describes, and its
    velocity, in body axes (constant along the periodic solution, m and m/s)."""

    position_m: FloatArray
    velocity_m_s: FloatArray


def circle_offsets(solution: RelaxedHoverSolution, airframe: Airframe, *, linear_drag_n_s_m: float = 0.0) -> CircleOffsets:
    """The periodic motion of the centre of mass: the force's horizontal part ``F_perp`` turns
    with the body at the spin rate ``s`` about the up axis ``u``, so ``m v' = F_perp - k v`` has
    the periodic solution ``v = alpha F + beta u x F``, ``r = (beta F - alpha u x F) / s`` with
    ``alpha = k / (m^2 s^2 + k^2)``, ``beta = -m s / (m^2 s^2 + k^2)`` (``k``: the linear
    translational drag; quadratic drag has no closed form and is not accepted here)."""
    if not isinstance(solution, RelaxedHoverSolution):
        raise TypeError(f"solution: expected rotorfault.RelaxedHoverSolution, got {type(solution).__name__}")
    airframe = require_airframe(airframe)
    k = real("linear_drag_n_s_m", linear_drag_n_s_m)
    if not (math.isfinite(k) and k >= 0):
        raise ValueError(f"linear_drag_n_s_m: must be finite and >= 0, got {k}")
    s = solution.spin_rate_rad_s
    if s == 0.0:
        return CircleOffsets(np.zeros(3), np.zeros(3))
    n = np.asarray(solution.spin_axis)
    force = np.asarray(solution.thrust_direction) * solution.total_thrust_n
    perp = force - n * (n @ force)
    m = airframe.mass_kg
    denominator = m * m * s * s + k * k
    alpha, beta = k / denominator, -m * s / denominator
    turned = np.cross(n, perp)
    return CircleOffsets(position_m=(beta * perp - alpha * turned) / s, velocity_m_s=alpha * perp + beta * turned)


__all__ = [
    "CircleOffsets",
    "FixedPitchActuatorLike",
    "RelaxedHoverAnalysis",
    "RelaxedHoverSettings",
    "RelaxedHoverSolution",
    "circle_offsets",
    "relaxed_hover",
    "relaxed_hover_residual",
]
