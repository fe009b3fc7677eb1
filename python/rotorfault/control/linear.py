"""Linear controllers for :class:`rotorfault.Simulator`. Design in Python, run in Rust: these
classes hold matrices designed here (python-control, H-infinity synthesis) and hand them to the
Rust loop, which runs them without the GIL. A plain Python callable ``f(t, x) -> commands`` works
too (``x`` the 12-element state vector of :func:`rotorfault.State.vector`): the slow path, for
prototyping.

State vector everywhere: ``x = [north, east, down (m), v_n, v_e, v_d (m/s), roll, pitch, yaw (rad,
Z-Y-X), p, q, r (rad/s, body FRD)]``; yaw errors are wrapped to (-pi, pi].
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from .. import _rfcore
from .._util.convert import FloatArray, float_array, frozen_array, real

if TYPE_CHECKING:
    from .riccati import LqrDesign

STATE_DIM = 12

#: Short names of the 12 states, in order (Wang's symbols; NED position and velocity, Euler
#: angles, body rates): errors and reports name a state by these.
STATE_NAMES = ("x", "y", "z", "u", "v", "w", "phi", "theta", "psi", "p", "q", "r")

#: What each state is, for the lead state of a named mode ("yaw rate r together with p and q").
STATE_LABELS = (
    "north position x", "east position y", "down position z", "north velocity u", "east velocity v",
    "down velocity w", "roll phi", "pitch theta", "yaw psi", "roll rate p", "pitch rate q", "yaw rate r",
)


class OpenLoop:
    """A piecewise-constant command schedule: ``commands[k]`` (one per actuator channel) holds
    from ``times[k]`` until the next time; the first row also before ``times[0]``.

    Examples:

        >>> import rotorfault as rf
        >>> sim = rf.Simulator(rf.Airframe.preset("quad-x"))
        >>> hover = rf.hover_trim(sim).command
        >>> schedule = rf.OpenLoop([0.0, 0.5], [hover, 1.1 * hover])
        >>> run = sim.run(rf.State(position=(0, 0, -1)), 1.0, controller=schedule)
        >>> bool(run.position[-1, 2] < -1)
        True
    """

    def __init__(self, times: npt.ArrayLike, commands: npt.ArrayLike) -> None:
        self.times = frozen_array("times", times, 1)
        self.commands = frozen_array("commands", commands, 2)
        self._core = _rfcore.OpenLoop(self.times, self.commands)

    @property
    def u_trim(self) -> FloatArray:
        """The first scheduled command: where the actuators start by default."""
        first: FloatArray = self.commands[0]
        return first

    @classmethod
    def constant(cls, command: npt.ArrayLike) -> OpenLoop:
        """The same commands forever."""
        return cls([0.0], float_array("command", command, 1)[None, :])

    def core(self, dt_s: float) -> _rfcore.OpenLoop:
        return self._core


class LinearFeedback:
    """``u = u_trim - K (x - x_trim)``, e.g. with ``K`` from
    :func:`rotorfault.control.riccati.design_lqr` (see :func:`rotorfault.control.lqr.lqr_hover`).
    ``design``: the checked design the gain came from (an ``LqrDesign`` with its evidence:
    Riccati residual, closed-loop and sampled-loop eigenvalues, PBH tests), None for a gain given
    by hand.

    Examples:

        >>> import numpy as np
        >>> import rotorfault as rf
        >>> sim = rf.Simulator(rf.Airframe.preset("quad-x"))
        >>> trim = rf.hover_trim(sim, position=(0, 0, -1))
        >>> feedback = rf.LinearFeedback(np.zeros((4, 12)), trim.state, trim.command)
        >>> run = sim.run(rf.State(position=(0, 0, -1)), 0.5, controller=feedback)
        >>> round(float(abs(run.position[-1] - (0, 0, -1)).max()), 6)
        0.0
    """

    def __init__(self, gain: npt.ArrayLike, x_trim: npt.ArrayLike, u_trim: npt.ArrayLike, *, design: LqrDesign | None = None) -> None:
        self.gain = frozen_array("gain", gain, 2)
        self.x_trim = frozen_array("x_trim", x_trim, 1)
        self.u_trim = frozen_array("u_trim", u_trim, 1)
        self.design = design
        self._core = _rfcore.LinearFeedback(self.x_trim, self.u_trim, self.gain)

    def core(self, dt_s: float) -> _rfcore.LinearFeedback:
        return self._core


class Lti:
    """A linear controller driven by the state error ``e = x - x_trim``:
    ``xi' = A xi + B e``, ``u = u_trim + C xi + D e``. With ``dt_s=None`` the matrices are
    continuous-time and are discretised (zero-order hold) at the simulator's control period;
    otherwise they are discrete at period ``dt_s``, which must equal the simulator's.

    Examples:

        >>> import numpy as np
        >>> import rotorfault as rf
        >>> sim = rf.Simulator(rf.Airframe.preset("quad-x"))
        >>> k = rf.lqr_hover(sim, position=(0, 0, -1))
        >>> static = rf.Lti(np.zeros((1, 1)), np.zeros((1, 12)), np.zeros((4, 1)), -k.gain, k.x_trim, k.u_trim)
        >>> run = sim.run(rf.State(position=(0.2, 0, -1)), 3.0, controller=static)
        >>> round(float(run.position[-1, 0]), 3)
        0.036
    """

    def __init__(
        self,
        A: npt.ArrayLike,
        B: npt.ArrayLike,
        C: npt.ArrayLike,
        D: npt.ArrayLike,
        x_trim: npt.ArrayLike,
        u_trim: npt.ArrayLike,
        *,
        dt_s: float | None = None,
    ) -> None:
        self.A = frozen_array("A_K", A, 2)
        self.B = frozen_array("B_K", B, 2)
        self.C = frozen_array("C_K", C, 2)
        self.D = frozen_array("D_K", D, 2)
        self.x_trim = frozen_array("x_trim", x_trim, 1)
        self.u_trim = frozen_array("u_trim", u_trim, 1)
        self.dt_s = None if dt_s is None else real("dt_s", dt_s)
        if self.dt_s is not None and not (math.isfinite(self.dt_s) and self.dt_s > 0):
            raise ValueError(f"dt_s: must be > 0 and finite (or None for a continuous controller), got {self.dt_s}")
        # Validate shapes now (the core checks them), with the matrices as given.
        _rfcore.Lti(self.A, self.B, self.C, self.D, self.x_trim, self.u_trim)

    def core(self, dt_s: float) -> _rfcore.Lti:
        if self.dt_s is not None:
            if abs(self.dt_s - dt_s) > 1e-12 * dt_s:
                raise ValueError(f"controller.dt_s: the discrete controller runs at {self.dt_s} s, the simulator at {dt_s} s")
            a, b, c, d = self.A, self.B, self.C, self.D
        elif self.A.shape[0] == 0:
            a, b, c, d = self.A, self.B, self.C, self.D
        else:
            # scipy.signal costs ~0.5 s to import: only continuous designs pay it.
            from scipy.signal import cont2discrete  # type: ignore[import-untyped]

            a, b, c, d, _ = cont2discrete((self.A, self.B, self.C, self.D), dt_s, method="zoh")
        a, b, c, d = (np.ascontiguousarray(m, dtype=np.float64) for m in (a, b, c, d))
        return _rfcore.Lti(a, b, c, d, self.x_trim, self.u_trim)


__all__ = ["STATE_DIM", "STATE_LABELS", "STATE_NAMES", "LinearFeedback", "Lti", "OpenLoop"]
