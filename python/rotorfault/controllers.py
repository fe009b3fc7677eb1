"""Controllers for :class:`rotorfault.Simulator`. Design in Python, run in Rust: these classes
hold matrices designed here (python-control, H-infinity synthesis) and hand them to the Rust
loop, which runs them without the GIL. A plain Python callable ``f(t, x) -> commands`` works too
(``x`` the 12-element state vector of :func:`rotorfault.State.vector`): the slow path, for
prototyping.

State vector everywhere: ``x = [north, east, down (m), v_n, v_e, v_d (m/s), roll, pitch, yaw (rad,
Z-Y-X), p, q, r (rad/s, body FRD)]``; yaw errors are wrapped to (-pi, pi].
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.signal import cont2discrete  # type: ignore[import-untyped]

from . import _rfcore
from ._convert import FloatArray, float_array, real

STATE_DIM = 12


class OpenLoop:
    """A piecewise-constant command schedule: ``commands[k]`` (one per actuator channel) holds
    from ``times[k]`` until the next time; the first row also before ``times[0]``."""

    def __init__(self, times: Any, commands: Any) -> None:
        self.times = _frozen("times", times, 1)
        self.commands = _frozen("commands", commands, 2)
        self._core = _rfcore.OpenLoop(self.times, self.commands)

    @property
    def u_trim(self) -> FloatArray:
        """The first scheduled command: where the actuators start by default."""
        first: FloatArray = self.commands[0]
        return first

    @classmethod
    def constant(cls, command: Any) -> OpenLoop:
        """The same commands forever."""
        return cls([0.0], float_array("command", command, 1)[None, :])

    def core(self, dt: float) -> Any:
        return self._core


class LinearFeedback:
    """``u = u_trim - K (x - x_trim)``, e.g. with ``K`` from ``control.lqr`` (see
    :func:`rotorfault.linear.lqr_hover`)."""

    def __init__(self, gain: Any, x_trim: Any, u_trim: Any) -> None:
        self.gain = _frozen("gain", gain, 2)
        self.x_trim = _frozen("x_trim", x_trim, 1)
        self.u_trim = _frozen("u_trim", u_trim, 1)
        self._core = _rfcore.LinearFeedback(self.x_trim, self.u_trim, self.gain)

    def core(self, dt: float) -> Any:
        return self._core


class LTI:
    """A linear controller driven by the state error ``e = x - x_trim``:
    ``xi' = A xi + B e``, ``u = u_trim + C xi + D e``. With ``dt=None`` the matrices are
    continuous-time and are discretised (zero-order hold) at the simulator's control period;
    otherwise they are discrete at period ``dt``, which must equal the simulator's."""

    def __init__(self, A: Any, B: Any, C: Any, D: Any, x_trim: Any, u_trim: Any, dt: float | None = None) -> None:
        self.A = _frozen("A_K", A, 2)
        self.B = _frozen("B_K", B, 2)
        self.C = _frozen("C_K", C, 2)
        self.D = _frozen("D_K", D, 2)
        self.x_trim = _frozen("x_trim", x_trim, 1)
        self.u_trim = _frozen("u_trim", u_trim, 1)
        self.dt = None if dt is None else real("dt", dt)
        if self.dt is not None and not (math.isfinite(self.dt) and self.dt > 0):
            raise ValueError(f"dt: must be > 0 and finite (or None for a continuous controller), got {self.dt}")
        # Validate shapes now (the core checks them), with the matrices as given.
        _rfcore.DiscreteLti(self.A, self.B, self.C, self.D, self.x_trim, self.u_trim)

    def core(self, dt: float) -> Any:
        if self.dt is not None:
            if abs(self.dt - dt) > 1e-12 * dt:
                raise ValueError(f"controller.dt: the discrete controller runs at {self.dt} s, the simulator at {dt} s")
            a, b, c, d = self.A, self.B, self.C, self.D
        elif self.A.shape[0] == 0:
            a, b, c, d = self.A, self.B, self.C, self.D
        else:
            a, b, c, d, _ = cont2discrete((self.A, self.B, self.C, self.D), dt, method="zoh")
        a, b, c, d = (np.ascontiguousarray(m, dtype=np.float64) for m in (a, b, c, d))
        return _rfcore.DiscreteLti(a, b, c, d, self.x_trim, self.u_trim)


class Allocated:
    """A virtual-control law followed by constrained allocation, all in Rust: ``law``
    (:class:`LinearFeedback`, :class:`LTI` or :class:`OpenLoop`) writes the virtual control
    (``allocator.virtual_dimension`` entries, e.g. thrust N and roll/pitch/yaw torques N m), and
    the active-set solver of ``allocator`` (a :class:`rotorfault.allocation.Allocator`) turns it
    into rotor thrusts within their bounds, warm-started from the previous control step.

    The allocator's matrix is what the controller believes; the simulator's rotor health is what
    happens. Pass an allocator built from a degraded airframe to model a known fault."""

    def __init__(self, law: Any, allocator: Any) -> None:
        from .allocation import Allocator

        if not isinstance(law, (OpenLoop, LinearFeedback, LTI)):
            raise TypeError(f"law: expected LinearFeedback, LTI or OpenLoop, got {type(law).__name__}")
        if not isinstance(allocator, Allocator):
            raise TypeError(f"allocator: expected a rotorfault.allocation.Allocator, got {type(allocator).__name__}")
        self.law = law
        self.allocator = allocator
        self.core(1.0)  # checks that the law writes one entry per row of the allocation matrix

    @property
    def u_trim(self) -> FloatArray | None:
        """The rotor commands for the law's trim virtual control: where the actuators start."""
        trim = trim_command(self.law)
        if trim is None:
            return None
        commands: FloatArray = self.allocator.allocate(trim).commands
        return commands

    def core(self, dt: float) -> Any:
        return _rfcore.Allocated(self.law.core(dt), self.allocator._core)


def _frozen(field: str, value: Any, ndim: int) -> FloatArray:
    """A private read-only copy: later changes to the caller's array cannot desynchronise the
    controller from what it reports."""
    array = np.array(float_array(field, value, ndim), dtype=np.float64, copy=True)
    array.setflags(write=False)
    return array


def core_controller(controller: Any, dt: float) -> Any:
    """The object the Rust loop runs for ``controller`` (``None``: all rotors at zero)."""
    if controller is None:
        return None
    if isinstance(controller, (OpenLoop, LinearFeedback, LTI, Allocated)):
        return controller.core(dt)
    if callable(controller):
        return controller
    raise TypeError(
        "controller: expected OpenLoop, LinearFeedback, LTI, Allocated, a callable f(t, x) or None, "
        f"got {type(controller).__name__}"
    )


def trim_command(controller: Any) -> FloatArray | None:
    """The trim command a controller holds, if any (the actuators start there)."""
    u_trim = getattr(controller, "u_trim", None)
    return None if u_trim is None else np.asarray(u_trim, dtype=np.float64)
