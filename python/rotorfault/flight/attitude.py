"""The attitude verdict of a flight that is asked to level and spin (Lanzon's Scenario A: roll and
pitch to zero, yaw rate to its set point, no position loop): ``"level"`` or ``"not-level"`` over the
judging window, or the divergence kind, as the windowed verdicts of :mod:`~rotorfault.flight.outcomes`
judge a position hold. :data:`ATTITUDE_VERDICTS` maps the two attitude outcomes to the one flight
verdict (``level`` holds, ``not-level`` drifts); every other outcome is judged by
:func:`~rotorfault.flight.outcomes.verdict_of`."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from .._typing import FlightVerdict
from .._util.convert import FloatArray
from .outcomes import WINDOW_S, scoring_window, verdict_of
from .trajectory import Trajectory

#: "level" in Scenario A: tilt below this (deg) throughout the judging window.
LEVEL_TILT_DEG = 1.0
#: ... and the spin within this fraction of its set point (m g d / k_r).
LEVEL_SPIN_FRACTION = 0.1
#: The flight verdict of each attitude outcome.
ATTITUDE_VERDICTS: dict[str, FlightVerdict] = {"level": "holds", "not-level": "drifts"}

AttitudeOutcome = Literal["level", "not-level"]


@dataclass(frozen=True)
class AttitudeMetrics:
    """What Scenario A asks (roll and pitch to zero, spin to ``m g d / k_r``), judged like Ke's
    flights over the last ``window_s`` seconds: ``"level"`` when the tilt (angle between body and
    world vertical) stays below :data:`LEVEL_TILT_DEG` and the spin within
    :data:`LEVEL_SPIN_FRACTION` of its set point throughout the window, ``"not-level"`` otherwise,
    or the divergence kind (``lost_at_s``). ``level_after_s``: from when the tilt stays below
    :data:`LEVEL_TILT_DEG` to the end (``None``: not level at the end, or lost). Whole-run values:
    ``max_altitude_loss_m`` the largest drop below the start; ``window_*`` the largest tilt and
    the mean spin (paper frame, rad/s) over the window."""

    outcome: str
    level_after_s: float | None
    final_tilt_deg: float | None
    window_tilt_deg: float | None
    window_spin_rad_s: float | None
    max_altitude_loss_m: float | None
    lost_at_s: float | None = None
    window_s: float = WINDOW_S


def tilt_deg(trajectory: Trajectory) -> FloatArray:
    """The angle between the body z axis and the world vertical (deg)."""
    out: FloatArray = np.degrees(np.arccos(np.clip(trajectory.primary_axis[:, 2], -1.0, 1.0)))
    return out


def attitude_metrics(trajectory: Trajectory, spin_setpoint_rad_s: float, *, window_s: float = WINDOW_S) -> AttitudeMetrics:
    """Scores Scenario A's question on ``trajectory`` (see :class:`AttitudeMetrics`)."""
    window_s, t = scoring_window(trajectory, window_s)
    if trajectory.diverged:
        e = trajectory.events[0]
        return AttitudeMetrics(e.kind, None, None, None, None, None, float(e.time_s), window_s)
    tilt = tilt_deg(trajectory)
    spin = -trajectory.omega[:, 2]  # paper frame r (z up)
    last = t >= t[-1] - window_s
    window_tilt = float(np.max(tilt[last]))
    window_spin = float(np.mean(spin[last]))
    level = window_tilt < LEVEL_TILT_DEG and bool(
        np.all(np.abs(spin[last] - spin_setpoint_rad_s) <= LEVEL_SPIN_FRACTION * spin_setpoint_rad_s))
    above = np.nonzero(tilt >= LEVEL_TILT_DEG)[0]
    if above.size == 0:
        level_after: float | None = 0.0
    elif above[-1] + 1 < len(t):
        level_after = float(t[above[-1] + 1])
    else:
        level_after = None
    alt = -trajectory.position[:, 2]
    return AttitudeMetrics("level" if level else "not-level", level_after, float(tilt[-1]), window_tilt, window_spin,
                           float(np.max(alt[0] - alt)), None, window_s)


def attitude_verdict(outcome: str) -> FlightVerdict:
    """The flight verdict of an attitude outcome (:data:`ATTITUDE_VERDICTS`) or of any other
    outcome code (:func:`~rotorfault.flight.outcomes.verdict_of`)."""
    return ATTITUDE_VERDICTS.get(outcome) or verdict_of(outcome)


__all__ = ["ATTITUDE_VERDICTS", "LEVEL_SPIN_FRACTION", "LEVEL_TILT_DEG", "AttitudeMetrics", "AttitudeOutcome", "attitude_metrics",
           "attitude_verdict", "tilt_deg"]
