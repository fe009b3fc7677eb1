"""State feedback on a moving reference with a saturated error (reference shaping):
``u = u_trim - K sat(x - x_ref(t))``, run in Rust (``crates/rfcore/src/control/tracking.rs``).

A gain designed about hover answers a 5 m step with commands far outside the linear model (Wang's
scenario 2 is lost by a plain LQR); clipping each error component to ``error_limit`` turns a
step into a bounded approach. The reference is a table of 12-state rows at non-decreasing
``times_s``: linear between distinct times, held outside, and a repeated time is a jump (the
later row holds from then), so one table holds setpoint steps and a sampled path alike.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import get_args

import numpy as np
import numpy.typing as npt

from .. import _rfcore
from .._typing import CircleTurn
from .._util.convert import FloatArray, float_array, frozen_array, real
from .linear import STATE_DIM, LinearFeedback


class TrackingFeedback:
    """``u = u_trim - K sat(x - x_ref(t))`` (module docs). ``error_limit``: 12 entries > 0 or
    ``inf`` (no limit); ``None``: no limit anywhere (plain feedback on the reference).

    Examples:

        >>> import numpy as np
        >>> import rotorfault as rf
        >>> sim = rf.Simulator(rf.Airframe.preset("quad-x"))
        >>> k = rf.lqr_hover(sim, position=(0, 0, -1))
        >>> references = np.tile(k.x_trim, (2, 1))
        >>> references[1, 0] = 1.0
        >>> tracking = rf.TrackingFeedback(k.gain, k.u_trim, times_s=[0.0, 1.0], references=references)
        >>> run = sim.run(rf.State(position=(0, 0, -1)), 4.0, controller=tracking)
        >>> round(float(run.position[-1, 0]), 2)
        0.89
    """

    def __init__(
        self,
        gain: npt.ArrayLike,
        u_trim: npt.ArrayLike,
        *,
        times_s: npt.ArrayLike,
        references: npt.ArrayLike,
        error_limit: npt.ArrayLike | None = None,
    ) -> None:
        self.gain = frozen_array("gain", gain, 2)
        self.u_trim = frozen_array("u_trim", u_trim, 1)
        self.times_s = frozen_array("times_s", times_s, 1)
        self.references = frozen_array("references", references, 2)
        limit = np.full(STATE_DIM, math.inf) if error_limit is None else float_array("error_limit", error_limit, 1)
        self.error_limit = frozen_array("error_limit", limit, 1)
        self._core = _rfcore.TrackingFeedback(
            u_trim=self.u_trim, gain=self.gain, times_s=self.times_s, references=self.references, error_limit=self.error_limit,
        )

    @classmethod
    def from_feedback(
        cls,
        feedback: LinearFeedback,
        *,
        times_s: npt.ArrayLike,
        references: npt.ArrayLike,
        error_limit: npt.ArrayLike | None = None,
    ) -> TrackingFeedback:
        """``feedback``'s gain and trim command on a reference table (its ``x_trim`` is unused:
        the references replace it)."""
        if not isinstance(feedback, LinearFeedback):
            raise TypeError(f"feedback: expected a LinearFeedback, got {type(feedback).__name__}")
        return cls(feedback.gain, feedback.u_trim, times_s=times_s, references=references, error_limit=error_limit)

    def reference(self, t_s: float) -> FloatArray:
        """The reference state at ``t_s`` (as the Rust loop sees it)."""
        return np.array(self._core.reference(float(t_s)))

    def core(self, dt_s: float) -> _rfcore.TrackingFeedback:
        return self._core


def _steps(events: list[tuple[float, FloatArray]]) -> tuple[FloatArray, FloatArray]:
    """A reference table from ``(time, row)`` events: each row holds from its time (a repeated
    time is the jump)."""
    times: list[float] = []
    rows: list[FloatArray] = []
    for t, row in events:
        if rows:
            times.append(t)
            rows.append(rows[-1])
        times.append(t)
        rows.append(row)
    return np.array(times), np.array(rows)


def step_reference(
    waypoints: Sequence[tuple[float, Sequence[float]]], yaw_steps: Sequence[tuple[float, float]] = ()
) -> tuple[FloatArray, FloatArray]:
    """``(times_s, references)`` for :class:`TrackingFeedback`: position steps ``waypoints``
    (``(time_s, (north, east, down))``, m) and heading steps ``yaw_steps`` (``(time_s, yaw_rad)``;
    0 before the first), each held until the next (zero velocity and rates), jumps at repeated
    times. The first waypoint holds from time 0."""
    moves = [(float(t), np.asarray(p, dtype=np.float64)) for t, p in waypoints]
    turns = [(float(t), float(y)) for t, y in yaw_steps]
    if not moves:
        raise ValueError("waypoints: give at least one (time_s, (north, east, down))")
    for name, times in (("waypoints", [t for t, _ in moves]), ("yaw_steps", [t for t, _ in turns])):
        for k, t_s in enumerate(times):
            if not (math.isfinite(t_s) and t_s >= 0.0):
                raise ValueError(f"{name}[{k}]: the time must be >= 0 and finite, got {t_s}")
    for k, (_, y) in enumerate(turns):
        if not math.isfinite(y):
            raise ValueError(f"yaw_steps[{k}]: the heading must be finite, got {y}")
    for k, (_, p) in enumerate(moves):
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise ValueError(f"waypoints[{k}]: expected a finite (north, east, down), got {p.tolist()}")
    events: list[tuple[float, FloatArray]] = []
    for t_s in sorted({t for t, _ in moves} | {0.0} | {t for t, _ in turns}):
        row = np.zeros(STATE_DIM)
        reached = [p for s, p in moves if s <= t_s]
        row[:3] = reached[-1] if reached else moves[0][1]
        headings = [y for s, y in turns if s <= t_s]
        row[8] = headings[-1] if headings else 0.0
        events.append((t_s, row))
    return _steps(events)


def circle_reference(
    *, radius_m: float, period_s: float, climb_m_s: float = 0.0, yaw_amplitude_rad: float = 0.0, duration_s: float,
    sample_s: float = 0.05, turn: CircleTurn = "clockwise",
) -> tuple[FloatArray, FloatArray]:
    """``(times_s, references)`` for :class:`TrackingFeedback`: a circle of ``radius_m`` flown once
    per ``period_s`` from the origin (north ``R (1 - cos wt)``, east ``R sin wt``), climbing at
    ``climb_m_s``, the heading ``yaw_amplitude_rad sin wt``, with the matching velocities and yaw
    rate, sampled every ``sample_s`` over ``duration_s``. ``turn``: seen from above, ``"clockwise"``
    (north, then east: ``w = 2 pi / period_s``) or ``"counterclockwise"`` (north, then west, the
    heading mirrored too: ``w`` negated; Wang's scenario 1, whose y axis points left)."""
    if turn not in get_args(CircleTurn):
        raise ValueError(f"turn: must be one of {', '.join(get_args(CircleTurn))}, got {turn!r}")
    # Checked before any arithmetic: a period of 0 divided by zero, a NaN radius gave NaN rows.
    for name, value in (("radius_m", radius_m), ("period_s", period_s), ("duration_s", duration_s), ("sample_s", sample_s)):
        if not (math.isfinite(real(name, value)) and value > 0.0):
            raise ValueError(f"{name}: must be > 0 and finite, got {value}")
    for name, value in (("climb_m_s", climb_m_s), ("yaw_amplitude_rad", yaw_amplitude_rad)):
        if not math.isfinite(real(name, value)):
            raise ValueError(f"{name}: must be finite, got {value}")
    if duration_s / sample_s > 1e7:
        raise ValueError(f"sample_s: {duration_s:g} s / {sample_s:g} s exceeds 10,000,000 reference rows")
    t = np.arange(0.0, duration_s + sample_s, sample_s)
    w = (1.0 if turn == "clockwise" else -1.0) * 2 * math.pi / period_s
    refs = np.zeros((len(t), STATE_DIM))
    refs[:, 0] = radius_m * (1 - np.cos(w * t))
    refs[:, 1] = radius_m * np.sin(w * t)
    refs[:, 2] = -climb_m_s * t
    refs[:, 3] = radius_m * w * np.sin(w * t)
    refs[:, 4] = radius_m * w * np.cos(w * t)
    refs[:, 5] = -climb_m_s
    refs[:, 8] = yaw_amplitude_rad * np.sin(w * t)
    refs[:, 11] = yaw_amplitude_rad * w * np.cos(w * t)
    return t, refs


__all__ = ["TrackingFeedback", "circle_reference", "step_reference"]
