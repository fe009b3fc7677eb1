"""The verdict on a whole flight: did the vehicle hold its setpoint, circle, stay off station, or
was it lost? A verdict is a property of a flight, judged over the last ``window_s`` seconds of the
run (not its last sample), with thresholds stated here and shared with the core's per-run
summaries (``VerdictCriteria``: one source, read from the core's ``Default``). Every paper, study
and report labels its runs with these functions.

Outcome codes (:data:`OUTCOME_LABELS` gives the words every table prints): ``holds-position``,
``circling``, ``off-station`` (the vehicle flies to the end: :data:`FLYING`), or the divergence
kind that ended the run (``tilt``, ``altitude-loss``, ...: lost). Studies with their own question
add their own codes to the one table (``level`` / ``not-level`` of an attitude-only flight).

This module reads a :class:`~rotorfault.flight.trajectory.Trajectory` without importing it: it is
the one module of a room that ``rotorfault.plotting`` may import (for the words of a verdict).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import _rfcore
from .._typing import FlightOutcome
from .._util.convert import FloatArray, real

_CRITERIA = _rfcore.VerdictCriteria()
#: "holds position": over the last ``window_s`` seconds the horizontal error stays within 2 m
#: and the altitude error within 1 m of the setpoint (m).
HOLD_BAND_M = (_CRITERIA.hold_horizontal_m, _CRITERIA.hold_altitude_m)
#: ... and the speed stays below this (m/s): passing through the setpoint is not holding it.
HOLD_SPEED_M_S = _CRITERIA.hold_speed_m_s
#: "circling": not holding, the mean horizontal speed over the window above
#: :data:`HOLD_SPEED_M_S` and the direction of travel turning by at least this much (rad) within
#: the window: a steady circle, or an oscillation (which reverses, a turn of pi).
CIRCLING_TURN_RAD = _CRITERIA.circling_turn_rad
#: Length of the judging window at the end of a run (s): outcome, steady values, settling.
WINDOW_S = _CRITERIA.window_s
#: Outcomes of a vehicle that flew to the end (every other outcome is a loss).
FLYING: tuple[FlightOutcome, ...] = ("holds-position", "circling", "off-station")


@dataclass(frozen=True)
class FlightMetrics:
    """What Ke reports per flight, judged over the last ``window_s`` seconds of the run (not its
    last sample). Outcome codes (:data:`OUTCOME_LABELS` gives the table text):

    - ``"holds-position"``: no divergence, and throughout the window the horizontal error is
      within ``HOLD_BAND_M[0]`` (2 m), the altitude error within ``HOLD_BAND_M[1]`` (1 m) and
      the speed below :data:`HOLD_SPEED_M_S` (0.5 m/s);
    - ``"circling"``: no divergence, not holding, moving (mean horizontal speed above 0.5 m/s)
      with the direction of travel turning by at least :data:`CIRCLING_TURN_RAD` (90 degrees)
      within the window: a steady circle or oscillation around or near the setpoint;
    - ``"off-station"``: no divergence, neither of the above (e.g. drifting back slowly, or
      parked away from the setpoint);
    - a divergence kind (``"tilt"``, ``"altitude-loss"``, ...): the vehicle was lost at
      ``lost_at_s``.

    Window values (``None`` for a lost run): ``window_horizontal_error_m`` and
    ``window_altitude_error_m`` the largest errors, ``window_speed_m_s`` the largest speed,
    ``window_mean_horizontal_speed_m_s``.

    Steady values, ``None`` unless the run settled: ``r_rad_s`` mean body yaw rate; ``n3z``
    mean vertical component of the primary axis ``n3 = R_eb b_3`` (Fig. 14); ``rotation_axis``
    the mean of ``R_eb^T [0, 0, 1]``, the world vertical in body axes (Section V-B: the axis a
    steady spin turns about). ``spin_settle_s``: time from the last fault that changed an
    efficiency (or from the start) until ``r`` stays within 5 % (at least 0.2 rad/s) and ``n3z``
    within 0.02 of those means to the end of the run; the run counts as settled only if that
    happens no later than ``window_s`` before its end (Ke's "enter into a steady state").

    Position values over the whole run (``None`` for a lost run, whose track stops at the loss:
    tables show "lost at t"): ``max_altitude_loss_m`` the largest drop below the start,
    ``max_horizontal_error_m``, ``final_horizontal_error_m``, ``final_altitude_error_m``
    against the setpoint."""

    outcome: FlightOutcome
    r_rad_s: float | None
    n3z: float | None
    rotation_axis: tuple[float, float, float] | None
    spin_settle_s: float | None
    max_altitude_loss_m: float | None
    max_horizontal_error_m: float | None
    final_horizontal_error_m: float | None
    final_altitude_error_m: float | None
    window_s: float = WINDOW_S
    window_horizontal_error_m: float | None = None
    window_altitude_error_m: float | None = None
    window_speed_m_s: float | None = None
    window_mean_horizontal_speed_m_s: float | None = None
    lost_at_s: float | None = None

    @property
    def outcome_label(self) -> str:
        """The outcome in words, for tables (``"holds position"``, ``"circling"``, ``"off
        station"``, ``"tilt"``, ...)."""
        return OUTCOME_LABELS.get(self.outcome, self.outcome)

    @property
    def settled(self) -> bool:
        return self.spin_settle_s is not None




#: Table text of the outcome codes.
OUTCOME_LABELS: dict[str, str] = {
    "holds-position": "holds position",
    "circling": "circling",
    "off-station": "off station",
    "crashed": "crashed",
    "non-finite-state": "non-finite state",
    "non-finite-command": "non-finite command",
    "tilt": "tilt",
    "altitude-loss": "altitude loss",
    "speed": "speed",
    "body-rate": "body rate",
    "level": "level",
    "not-level": "not level",
}



def outcome_text(code: str, lost_at_s: float | None = None) -> str:
    """An outcome code in words (:data:`OUTCOME_LABELS`); a lost run says when (``"lost (tilt)
    at 1.52 s"``)."""
    if lost_at_s is not None:
        return f"lost ({code}) at {lost_at_s:.2f} s"
    return OUTCOME_LABELS.get(code, code)


def effective_fault_times(trajectory: Any) -> list[float]:
    """Times of the trajectory's own faults that changed a rotor's efficiency within the run (a
    no-op entry, which sets the efficiency a rotor already has, is not an event; nor is a fault
    the run never reached because it ended first)."""
    if not len(trajectory.t):
        return []
    current = np.array(trajectory.efficiency[0], dtype=np.float64)
    times = []
    for f in sorted(trajectory.faults, key=lambda f: f.time):
        if f.time > trajectory.t[-1]:
            break
        if current[f.rotor - 1] != f.efficiency:
            times.append(float(f.time))
            current[f.rotor - 1] = f.efficiency
    return times


def flight_metrics(trajectory: Any, scenario_: Any, *, window_s: float = WINDOW_S) -> FlightMetrics:
    """Scores ``trajectory`` against ``scenario_``'s setpoints (anything with ``setpoints``, a
    sequence of ``(time_s, (north, east, down))``: a :class:`~rotorfault.flight.scenarios.FlightScenario`). Fault times come from the
    trajectory's own faults (what it was flown with), not from the scenario."""
    window_s = real("window_s", window_s)
    if not window_s > 0:
        raise ValueError(f"window_s: must be > 0, got {window_s}")
    t = trajectory.t
    if len(t) < 2:
        raise ValueError(f"trajectory: needs at least 2 samples to be scored, got {len(t)}")
    if trajectory.diverged:
        event = trajectory.events[0]
        return FlightMetrics(event.kind, None, None, None, None, None, None, None, None, window_s, lost_at_s=float(event.time))
    setpoint = _setpoint_track(scenario_, t)
    error = trajectory.position - setpoint
    horizontal = np.hypot(error[:, 0], error[:, 1])
    vertical = np.abs(error[:, 2])
    start_alt = -trajectory.position[0, 2]
    position_errors = (
        float(np.max(start_alt - (-trajectory.position[:, 2]))),
        float(np.max(horizontal)),
        float(horizontal[-1]),
        float(vertical[-1]),
    )
    last = t >= t[-1] - window_s
    speed = np.linalg.norm(trajectory.velocity, axis=1)
    h_speed = np.hypot(trajectory.velocity[:, 0], trajectory.velocity[:, 1])
    window = (
        float(np.max(horizontal[last])),
        float(np.max(vertical[last])),
        float(np.max(speed[last])),
        float(np.mean(h_speed[last])),
    )
    held = window[0] <= HOLD_BAND_M[0] and window[1] <= HOLD_BAND_M[1] and window[2] <= HOLD_SPEED_M_S
    if held:
        outcome: FlightOutcome = "holds-position"
    elif window[3] > HOLD_SPEED_M_S and _turn_rad(trajectory.velocity[last], HOLD_SPEED_M_S / 4) >= CIRCLING_TURN_RAD:
        outcome = "circling"
    else:
        outcome = "off-station"
    r = float(np.mean(trajectory.omega[last, 2]))
    n3z = float(np.mean(trajectory.primary_axis[last, 2]))
    # R_eb^T e_z: the world vertical seen from the body (the rotation axis of a steady spin).
    axis = np.einsum("nji,j->ni", trajectory.rotation[last], np.array([0.0, 0.0, 1.0])).mean(axis=0)
    axis = axis / np.linalg.norm(axis)
    last_fault = max([0.0, *effective_fault_times(trajectory)])
    unsettled = (np.abs(trajectory.omega[:, 2] - r) > max(0.05 * abs(r), 0.2)) | (
        np.abs(trajectory.primary_axis[:, 2] - n3z) > 0.02
    )
    idx = np.nonzero(unsettled & (t >= last_fault))[0]
    settled_from = last_fault if idx.size == 0 else (float(t[idx[-1] + 1]) if idx[-1] + 1 < len(t) else math.inf)
    if settled_from > t[-1] - window_s + 1e-9:
        # Still moving at (or within the window before) the end: no settle time, no steady values.
        return FlightMetrics(outcome, None, None, None, None, *position_errors, window_s, *window)
    return FlightMetrics(
        outcome,
        r,
        n3z,
        (float(axis[0]), float(axis[1]), float(axis[2])),
        settled_from - last_fault,
        *position_errors,
        window_s,
        *window,
    )


def _turn_rad(velocity: FloatArray, min_speed: float) -> float:
    """How far the horizontal direction of travel turns (range of the unwrapped heading, rad),
    over the samples moving faster than ``min_speed``; a reversal counts as pi."""
    moving = np.hypot(velocity[:, 0], velocity[:, 1]) > min_speed
    if moving.sum() < 2:
        return 0.0
    heading = np.unwrap(np.arctan2(velocity[moving, 1], velocity[moving, 0]))
    return float(np.max(heading) - np.min(heading))


def _setpoint_track(scenario_: Any, t: FloatArray) -> FloatArray:
    times = np.array([s for s, _ in scenario_.setpoints])
    points = np.array([p for _, p in scenario_.setpoints])
    k = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 1)
    out: FloatArray = points[k]
    return out



__all__ = [
    "CIRCLING_TURN_RAD",
    "FLYING",
    "HOLD_BAND_M",
    "HOLD_SPEED_M_S",
    "OUTCOME_LABELS",
    "WINDOW_S",
    "FlightMetrics",
    "effective_fault_times",
    "flight_metrics",
    "outcome_text",
]
