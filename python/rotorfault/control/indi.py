"""Incremental nonlinear dynamic inversion (INDI) fault-tolerant control, after Sun, Wang, Chu and de
Visser (IEEE T-RO 2021, "Incremental nonlinear fault-tolerant control of a quadrotor with complete
loss of two opposing rotors"), for any planar multirotor and any set of failed rotors. It runs in
Rust (:class:`IndiController` hands the core a ``rotorfault._rfcore.IndiController``); the law,
its equations and decisions are documented in ``crates/rfcore/src/control/indi/mod.rs``.

- Reduced attitude of the primary axis (the thrust direction, the vehicle free to spin about it when
  yaw is given up), an outer position loop giving the desired acceleration, and the INDI inner loop:
  angular acceleration from the filtered gyro (a second-order low-pass, differentiated), the same
  filter on the rotor thrusts actually produced and on the accelerometer, and an incremental
  allocation over the remaining rotors.
- **An active controller**: it is told which rotors failed and when (``failures``: the time a
  detector reports it). Partial losses it is not told of reach it through the measurements.
- Priorities once the rotors saturate (``yaw="auto"``, the default): thrust and reduced attitude
  first, yaw with what is left (Sun et al.), so a nearly dead rotor it is not told of makes it spin
  rather than sink; ``yaw="hold"`` keeps yaw's weight (the law before that rule).
- With two opposing rotors of a quadrotor gone, only one attitude output can be controlled; Sun's
  output redefinition keeps the rest (the zero dynamics) stable when ``J_z > J_xy``
  (:meth:`IndiController.failure_modes` reports their damping for the nominal inertia; in flight
  the side of the output angle follows the inertia coupling measured from the gyro, since an
  inertia error of 10-20 % can turn the sign of ``1 + a = (2 J_xy - J_z) / J_xy``, which is small
  on a quadrotor).
- A relaxed hover (``spin_axis``): a primary axis tilted from body z and a spin-rate loop about it,
  for a vehicle without rotational drag whose spin otherwise grows without bound once yaw is given up.

The simulator gives it the gyro, the specific force and the rotor thrusts each control step (truth,
or the noisy body rates with sensor noise).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from .. import _rfcore
from .._util.convert import FloatArray, float_array, real
from ..analysis.airframe import Airframe, require_airframe

#: The gains (keyword-only; defaults are Sun's printed values where he prints them, from the core's
#: ``IndiGains::default``; values are checked there, naming the gain).
IndiGains = _rfcore.IndiGains



#: How the controller flies one set of failed rotors (rotors numbered from 1), decided at
#: construction: the core's class, used directly (its fields: ``failed``, ``healthy``,
#: ``yaw_controlled``, ``single_axis``, ``output_direction``, ``primary_axis``,
#: ``zero_dynamics_a``, ``zero_dynamics_damping``, ``hover_thrust_n`` in N).
IndiFailureMode = _rfcore.IndiFailureMode


def _vector(field: str, value: npt.ArrayLike) -> tuple[float, float, float]:
    arr = float_array(field, value, 1)
    if arr.shape != (3,):
        raise ValueError(f"{field}: expected 3 entries (north, east, down), got {arr.shape[0]}")
    return (float(arr[0]), float(arr[1]), float(arr[2]))


def _body_axis(field: str, value: npt.ArrayLike) -> tuple[float, float, float]:
    arr = float_array(field, value, 1)
    if arr.shape != (3,):
        raise ValueError(f"{field}: expected 3 entries (body x, y, z), got {arr.shape[0]}")
    return (float(arr[0]), float(arr[1]), float(arr[2]))


def _failure(k: int, item: Any, rotor_count: int) -> tuple[int, float]:
    """``(rotor, time_s)`` with a 1-based rotor, or a :class:`rotorfault.RotorFault` of a complete
    loss: the (1-based) rotor and the time the controller is told."""
    efficiency = getattr(item, "efficiency", None)
    if efficiency is not None:
        if real(f"failures[{k}].efficiency", efficiency) != 0.0:
            raise ValueError(
                f"failures[{k}].efficiency: INDI is told of complete losses only (efficiency 0); a partial "
                f"loss reaches it through the measurements, got {efficiency}"
            )
        rotor, time = item.rotor, item.time
    elif isinstance(item, (str, bytes)) or not isinstance(item, Sequence) or len(item) != 2:
        raise TypeError(f"failures[{k}]: expected (rotor, time_s) or a RotorFault, got {item!r}")
    else:
        rotor, time = item
    if isinstance(rotor, bool) or not isinstance(rotor, (int, np.integer)):
        raise TypeError(f"failures[{k}].rotor: expected a 1-based rotor number, got {rotor!r}")
    if not 1 <= int(rotor) <= rotor_count:
        raise ValueError(f"failures[{k}].rotor: rotor numbers run from 1 to {rotor_count}, got {rotor}")
    return int(rotor), real(f"failures[{k}].time", time)


def _weaker_of(value: Any, rotor_count: int) -> tuple[int, int]:
    """``spin_axis_weaker_of`` checked: two 1-based rotor numbers of this vehicle."""
    if isinstance(value, (str, bytes)) or not isinstance(value, Sequence) or len(value) != 2:
        raise TypeError(f"spin_axis_weaker_of: expected two rotor numbers (1-based), got {value!r}")
    rotors = []
    for k, rotor in enumerate(value):
        if isinstance(rotor, bool) or not isinstance(rotor, (int, np.integer)):
            raise TypeError(f"spin_axis_weaker_of[{k}]: expected a 1-based rotor number, got {rotor!r}")
        if not 1 <= int(rotor) <= rotor_count:
            raise ValueError(f"spin_axis_weaker_of[{k}]: rotor numbers run from 1 to {rotor_count}, got {rotor}")
        rotors.append(int(rotor))
    # Two different rotors, and the rest of the choice's rules: the core's (RelaxedSpin, with_relaxed_spin).
    return rotors[0], rotors[1]


class IndiController:
    """INDI fault-tolerant control (Sun et al.), run in Rust at the simulator's control rate.

    ``failures``: the rotors it is told have failed, ``(rotor, time_s)`` (1-based rotor, the time it
    learns of it) or :class:`rotorfault.RotorFault` objects of complete losses (told at the fault's
    time). ``gains``: :class:`IndiGains`. The reference: ``setpoints`` ``[(time_s, position)]`` or
    ``[(time_s, position, velocity)]`` (NED; from each time on the position moves at the velocity),
    or one ``position`` (NED, m) and ``velocity`` (NED, m/s; ``velocity=(2, 0, 0)`` is forward flight at 2 m/s).
    ``spin_axis``: a relaxed hover to fly from ``spin_axis_time_s`` (s) on: this axis (body FRD,
    unit or not, within 60 degrees of body z either way) becomes the primary axis and a spin-rate
    loop about it (``IndiGains.k_spin``, 1/s; weight ``spin_weight``, after thrust and attitude)
    aims at ``spin_rate_rad_s`` (rad/s, its magnitude, in the direction the vehicle spins; 0: the
    slowest spin the rotors allow). What a vehicle without rotational drag needs, whose spin
    otherwise grows without bound once yaw is given up (``crates/rfcore/src/control/indi/relaxed.rs``).
    The given axis takes precedence over ``IndiGains.given_up_yaw_axis_tilt``; refused (``ValueError``
    naming ``spin_axis``) when a failure set flown from its time on leaves one torque axis (the spin
    about body z keeps that vehicle stable), and ``spin_axis_time_s`` / ``spin_rate_rad_s`` other than
    0 without ``spin_axis`` are refused naming the field.
    ``spin_axis_weaker_of``: two rotors (1-based) mounted opposite each other that both lost thrust
    by amounts not told (two opposing rotors of a quadrotor): ``spin_axis`` is the axis for the first
    being the weaker and its mirror ``(-x, -y, z)`` the one for the second; for 0.25 s from
    ``spin_axis_time_s`` the law flies as without a spin axis and measures each one's produced over
    commanded thrust (from the rotor thrust samples; without them at any step of the 0.25 s it keeps
    the given axis), then flies the axis of the weaker and keeps that choice: on the x500 a relaxed
    hover after two opposing rotors partly lost exists only on the weaker's side (``relaxed.rs``,
    module docs). Refused naming the field: rotors not opposite each other, one told failed by the
    end of the 0.25 s, or a control period of 0.25 s or more.

    Examples:

        >>> import rotorfault as rf
        >>> quad = rf.Airframe.preset("quad-x")
        >>> sim = rf.Simulator(quad)
        >>> indi = rf.IndiController(quad, position=(0, 0, -1))
        >>> run = sim.run(rf.State(position=(0, 0, -1)), 1.0, controller=indi)
        >>> round(float(abs(run.position[-1] - (0, 0, -1)).max()), 3)
        0.0
    """

    def __init__(
        self,
        airframe: Airframe,
        *,
        failures: Sequence[Any] = (),
        gains: Any = None,
        position: npt.ArrayLike = (0.0, 0.0, 0.0),
        velocity: npt.ArrayLike = (0.0, 0.0, 0.0),
        setpoints: Sequence[Any] | None = None,
        spin_axis: npt.ArrayLike | None = None,
        spin_axis_time_s: float = 0.0,
        spin_rate_rad_s: float = 0.0,
        spin_axis_weaker_of: Sequence[int] | None = None,
    ) -> None:
        self.airframe = require_airframe(airframe)
        if gains is None:
            gains = IndiGains()
        if not isinstance(gains, IndiGains):
            raise TypeError(f"gains: expected rotorfault.IndiGains, got {type(gains).__name__}")
        self.gains = gains
        if isinstance(failures, (str, bytes)) or not isinstance(failures, Sequence):
            raise TypeError(f"failures: expected a sequence of (rotor, time_s) or RotorFault, got {type(failures).__name__}")
        #: ``(rotor, time_s)``, 1-based rotors as given.
        self.failures = tuple(_failure(k, item, airframe.rotor_count) for k, item in enumerate(failures))
        if setpoints is None:
            setpoints = [(0.0, position, velocity)]
        if isinstance(setpoints, (str, bytes)) or not isinstance(setpoints, Sequence):
            raise TypeError("setpoints: expected a sequence of (time_s, position) or (time_s, position, velocity)")
        parsed = []
        for k, item in enumerate(setpoints):
            if isinstance(item, (str, bytes)) or not isinstance(item, Sequence) or len(item) not in (2, 3):
                raise TypeError(f"setpoints[{k}]: expected (time_s, position) or (time_s, position, velocity)")
            moving = item[2] if len(item) == 3 else (0.0, 0.0, 0.0)
            parsed.append(
                (real(f"setpoints[{k}].time", item[0]), _vector(f"setpoints[{k}].position", item[1]),
                 _vector(f"setpoints[{k}].velocity", moving))
            )
        self.setpoints = tuple(parsed)
        #: The relaxed hover's spin axis (body frame) flown from ``spin_axis_time_s`` on, or ``None``.
        self.spin_axis = None if spin_axis is None else _body_axis("spin_axis", spin_axis)
        self.spin_axis_time_s = real("spin_axis_time_s", spin_axis_time_s)
        self.spin_rate_rad_s = real("spin_rate_rad_s", spin_rate_rad_s)
        if self.spin_axis is None:
            # Without a spin axis no relaxed hover is flown: a time or rate for it would be ignored.
            for field, value in (("spin_axis_time_s", self.spin_axis_time_s), ("spin_rate_rad_s", self.spin_rate_rad_s)):
                if value != 0.0:
                    raise ValueError(f"{field}: given ({value}) without spin_axis, the relaxed hover it belongs to; "
                                     "give spin_axis too or leave it at its default 0")
        #: The two rotors (1-based) whose weaker, as measured, the spin axis tilts toward, or ``None``.
        self.spin_axis_weaker_of = None if spin_axis_weaker_of is None else _weaker_of(spin_axis_weaker_of, airframe.rotor_count)
        if self.spin_axis_weaker_of is not None and self.spin_axis is None:
            raise ValueError("spin_axis_weaker_of: given without spin_axis, the spin whose side it chooses")
        # Validates everything now.
        self._modes = self.core(1.0 / 400.0).failure_modes()

    def core(self, dt_s: float) -> _rfcore.IndiController:
        return _rfcore.IndiController(
            self.airframe._core,
            gains=self.gains,
            failures=[(rotor - 1, time) for rotor, time in self.failures],
            setpoints=[(t, list(p), list(v)) for t, p, v in self.setpoints],
            dt_s=real("dt_s", dt_s),
            relaxed_spin=None if self.spin_axis is None else (self.spin_axis_time_s, list(self.spin_axis), self.spin_rate_rad_s),
            spin_axis_weaker_of=None if self.spin_axis_weaker_of is None else (self.spin_axis_weaker_of[0] - 1, self.spin_axis_weaker_of[1] - 1),
        )

    @property
    def u_trim(self) -> FloatArray:
        """The healthy vehicle's hover thrusts: where the actuators start."""
        return np.array(self._modes[0].hover_thrust_n)

    def failure_modes(self) -> list[IndiFailureMode]:
        """How each failure set is flown: ``[0]`` the healthy vehicle, then one per detection time
        (the failures told then and before; failures told at once are flown together)."""
        return list(self._modes)


__all__ = ["IndiController", "IndiFailureMode", "IndiGains"]
