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
from ._convert import FloatArray, float_array, frozen_array, real

STATE_DIM = 12

#: The Rust controller objects :func:`core_controller` can return (all can run in a batch).
CORE_TYPES: tuple[type, ...] = (
    _rfcore.OpenLoop,
    _rfcore.LinearFeedback,
    _rfcore.DiscreteLti,
    _rfcore.Allocated,
    _rfcore.UniformPassiveFtc,
)


class OpenLoop:
    """A piecewise-constant command schedule: ``commands[k]`` (one per actuator channel) holds
    from ``times[k]`` until the next time; the first row also before ``times[0]``."""

    def __init__(self, times: Any, commands: Any) -> None:
        self.times = frozen_array("times", times, 1)
        self.commands = frozen_array("commands", commands, 2)
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
        self.gain = frozen_array("gain", gain, 2)
        self.x_trim = frozen_array("x_trim", x_trim, 1)
        self.u_trim = frozen_array("u_trim", u_trim, 1)
        self._core = _rfcore.LinearFeedback(self.x_trim, self.u_trim, self.gain)

    def core(self, dt: float) -> Any:
        return self._core


class LTI:
    """A linear controller driven by the state error ``e = x - x_trim``:
    ``xi' = A xi + B e``, ``u = u_trim + C xi + D e``. With ``dt=None`` the matrices are
    continuous-time and are discretised (zero-order hold) at the simulator's control period;
    otherwise they are discrete at period ``dt``, which must equal the simulator's."""

    def __init__(self, A: Any, B: Any, C: Any, D: Any, x_trim: Any, u_trim: Any, dt: float | None = None) -> None:
        self.A = frozen_array("A_K", A, 2)
        self.B = frozen_array("B_K", B, 2)
        self.C = frozen_array("C_K", C, 2)
        self.D = frozen_array("D_K", D, 2)
        self.x_trim = frozen_array("x_trim", x_trim, 1)
        self.u_trim = frozen_array("u_trim", u_trim, 1)
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
        # The law's trim has one entry per output: it must match the allocation's rows. (Building
        # the core here would need the simulator's period, which a discrete LTI insists on.)
        outputs = np.asarray(law.u_trim).shape[0]
        if outputs != allocator.virtual_dimension:
            raise ValueError(
                f"law: writes {outputs} outputs, the allocation matrix has {allocator.virtual_dimension} rows"
            )

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


class UniformPassiveFTC:
    """Ke et al.'s uniform passive fault-tolerant controller, run in Rust at the simulator's
    control rate (Ke: 400 Hz). One controller, one set of gains, fault-free and through one, two
    and three rotor failures; it never reads rotor health (see :mod:`rotorfault.ftc`).

    ``gains``: a :class:`rotorfault.ftc.KeGains` or a controller preset name (``"ke-hil"``,
    default; ``"ke-experiment"``). ``law``: ``"feedforward"`` (default, the documented remedy for
    the steady deficit of eq. (18)), ``"literal"`` (eq. (18) as printed), ``"full-compensation"``
    (Remark 5, eq. (29)) or ``"baseline"`` (conventional: desired virtual control straight into
    the pseudo-inverse, no estimation, no QP). ``setpoints``: ``[(time_s, (north, east, down))]``
    held from their time on, or give one ``position``."""

    LAWS = ("feedforward", "literal", "full-compensation", "baseline")

    def __init__(
        self,
        airframe: Any,
        gains: Any = "ke-hil",
        law: str = "feedforward",
        position: Any = (0.0, 0.0, 0.0),
        setpoints: Any = None,
    ) -> None:
        from .airframe import require_airframe
        from .ftc import KeGains, preset

        self.airframe = require_airframe(airframe)
        if isinstance(gains, str):
            gains = preset(gains).gains
        if not isinstance(gains, KeGains):
            raise TypeError(f"gains: expected rotorfault.ftc.KeGains or a preset name, got {type(gains).__name__}")
        if not isinstance(law, str):
            raise TypeError(f"law: expected a string, got {type(law).__name__}")
        if law not in self.LAWS:
            raise ValueError(f"law: expected one of {', '.join(map(repr, self.LAWS))}, got {law!r}")
        self.gains = gains
        self.law = law
        if setpoints is None:
            setpoints = [(0.0, position)]
        if isinstance(setpoints, (str, bytes)) or not hasattr(setpoints, "__iter__"):
            raise TypeError("setpoints: expected a sequence of (time_s, (north, east, down))")
        parsed = []
        for k, item in enumerate(setpoints):
            if not hasattr(item, "__len__") or len(item) != 2:
                raise TypeError(f"setpoints[{k}]: expected (time_s, (north, east, down))")
            point = float_array(f"setpoints[{k}].position", item[1], 1)
            if point.shape != (3,):
                raise ValueError(f"setpoints[{k}].position: expected 3 entries (north, east, down), got {point.shape[0]}")
            parsed.append((real(f"setpoints[{k}].time", item[0]), (float(point[0]), float(point[1]), float(point[2]))))
        self.setpoints = tuple(parsed)
        self.core(1.0 / 400.0)  # validates gains, airframe and setpoints now

    @property
    def u_trim(self) -> FloatArray:
        """Hover thrusts on the nominal matrix: where the actuators start."""
        from .allocation import Allocator

        nominal = self.airframe.with_efficiency(np.ones(self.airframe.rotor_count))
        hover = np.array([nominal.hover_thrust_n, 0.0, 0.0, 0.0])
        commands: FloatArray = Allocator(nominal, weights=self.gains.weights).allocate(hover).commands
        return commands

    def core(self, dt: float) -> Any:
        return _rfcore.UniformPassiveFtc(
            self.airframe._core, self.law, list(self.setpoints), float(dt), **self.gains._packed()
        )

    def replay(self, times: Any, states: Any, dt: float = 1.0 / 400.0) -> FloatArray:
        """The commands this controller (from its reset state) gives for a recorded history:
        ``times`` (N), ``states`` (N x 13: position, velocity, quaternion w x y z, body rates),
        e.g. ``np.hstack([tr.position, tr.velocity, tr.quaternion, tr.omega])``. No rotor health
        enters: the passivity check."""
        t = float_array("times", times, 1)
        x = float_array("states", states, 2)
        period = real("dt", dt)
        # The filters assume one call per control period: a thinned recording (record_every > 1)
        # would replay with the wrong dynamics.
        if t.size > 1 and np.abs(np.diff(t) - period).max() > 1e-9 * max(period, 1.0):
            raise ValueError(f"times: must be spaced by the control period dt = {period} s (record with record_every=1)")
        out: FloatArray = _rfcore.replay(self.core(period), t, x, 4)
        return out


def core_controller(controller: Any, dt: float) -> Any:
    """The object the Rust loop runs for ``controller`` (``None``: all rotors at zero)."""
    if controller is None:
        return None
    if isinstance(controller, (OpenLoop, LinearFeedback, LTI, Allocated, UniformPassiveFTC)):
        return controller.core(dt)
    if callable(controller):
        return controller
    raise TypeError(
        "controller: expected OpenLoop, LinearFeedback, LTI, Allocated, UniformPassiveFTC, a callable f(t, x) "
        "or None, "
        f"got {type(controller).__name__}"
    )


def trim_command(controller: Any) -> FloatArray | None:
    """The trim command a controller holds, if any (the actuators start there)."""
    u_trim = getattr(controller, "u_trim", None)
    return None if u_trim is None else np.asarray(u_trim, dtype=np.float64)
