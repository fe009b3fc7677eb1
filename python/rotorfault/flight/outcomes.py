"""The verdict on a whole flight: one word, judged over the last ``window_s`` seconds of the run
(not its last sample), with thresholds stated here and shared with the core's per-run summaries
(``VerdictCriteria``: one source, read from the core's ``Default``; the core decides the same
verdict for every campaign run, ``crates/rfcore/src/flight/summary.rs``, tested equal). Every paper,
study and report labels its runs with these functions.

The verdicts (:data:`VERDICTS`, :data:`VERDICT_MEANINGS` states them with their thresholds):

- ``holds``: throughout the window within :data:`HOLD_BAND_M` (2 m horizontally, 1 m in
  altitude) of the setpoint (or the reference it tracks) and moving at most
  :data:`HOLD_SPEED_M_S` (0.5 m/s) relative to it;
- ``circles``: not holding, the mean horizontal speed over the window above 0.5 m/s and the
  direction of travel turning by at least :data:`CIRCLING_TURN_RAD` (90 degrees): a circle or an
  oscillation;
- ``drifts``: airborne to the end but neither: away from the setpoint, sinking, or moving off it
  (a vehicle that falls 9.4 of its 10 m without touching the ground drifts: it is not held);
- ``crashed``: it hit the ground (time and impact speed in the run's event);
- ``diverged``: lost another way (``cause``: ``tilt``, ``altitude-loss``, ``speed``,
  ``body-rate``, ``non-finite-state``, ``non-finite-command``, ``step-size``).

Only ``holds`` is a success. ``FlightMetrics.outcome`` keeps the codes before issue 28
(``holds-position``, ``circling``, ``off-station`` or the divergence kind) for one release; the
verdict is ``verdict`` (and ``cause`` for a lost run). Studies with their own question add their
own codes to the one table (``level`` / ``not-level`` of an attitude-only flight).

This module reads a :class:`~rotorfault.flight.trajectory.Trajectory` without importing it: it is
the one module of a room that ``rotorfault.plotting`` may import (for the words of a verdict).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any, get_args

import numpy as np

from .. import _rfcore
from .._typing import DivergenceKind, FlightOutcome, FlightVerdict
from .._util.convert import FloatArray, real
from .._util.numeric import scaled_norm

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
#: The verdicts, in the order every table counts them (only ``holds`` is a success).
VERDICTS: tuple[FlightVerdict, ...] = get_args(FlightVerdict)
#: Each verdict with its thresholds, in words (the docs, the report page and the CLI state them).
VERDICT_MEANINGS: dict[FlightVerdict, str] = {
    "holds": (
        f"throughout the last {WINDOW_S:g} s within {HOLD_BAND_M[0]:g} m horizontally and {HOLD_BAND_M[1]:g} m in altitude "
        f"of the setpoint (or the reference it tracks), moving at most {HOLD_SPEED_M_S:g} m/s relative to it"
    ),
    "circles": (
        f"not holding; over the last {WINDOW_S:g} s the mean horizontal speed is above {HOLD_SPEED_M_S:g} m/s and the "
        f"direction of travel turns by at least {math.degrees(CIRCLING_TURN_RAD):g} degrees (a circle or an oscillation)"
    ),
    "drifts": (
        "airborne to the end but neither holding nor circling: away from the setpoint, sinking or moving off it "
        "(a vehicle that falls most of its height without touching the ground drifts)"
    ),
    "crashed": "the vehicle hit the ground (the run ends there; its event has the time and the impact speed)",
    "diverged": (
        "lost another way: tilt, altitude loss, speed or body rate beyond the divergence limits, a non-finite state "
        "or command, or a body rate too fast for the step size"
    ),
}


def count_verdicts(verdicts: Iterable[str]) -> dict[FlightVerdict, int]:
    """How many flights got each verdict, every verdict listed in :data:`VERDICTS` order (0s
    included: a table that counts only what occurred hides what did not)."""
    given = list(verdicts)
    unknown = sorted(set(given) - set(VERDICTS))
    if unknown:
        raise ValueError(f"verdicts: {', '.join(map(repr, unknown))} not among {', '.join(VERDICTS)}")
    return {v: given.count(v) for v in VERDICTS}


def verdict_count_text(verdicts: Iterable[str]) -> str:
    """:func:`count_verdicts` in words: ``"holds 1, drifts 4, circles 0, crashed 1, diverged 2"``."""
    return ", ".join(f"{v} {n}" for v, n in count_verdicts(verdicts).items())


#: The outcome code of each flying verdict (the codes before issue 28, kept for one release).
_OUTCOME_OF_VERDICT: dict[str, FlightOutcome] = {"holds": "holds-position", "circles": "circling", "drifts": "off-station"}


def verdict_of(outcome: str) -> FlightVerdict:
    """The verdict of an outcome code (``holds-position`` -> ``holds``, ``circling`` ->
    ``circles``, ``off-station`` -> ``drifts``, ``crashed``, any other divergence kind ->
    ``diverged``); a verdict is returned as it is."""
    if outcome in VERDICTS:
        return outcome
    for verdict, code in _OUTCOME_OF_VERDICT.items():
        if outcome == code:
            return verdict  # type: ignore[return-value]
    if outcome == "crashed":
        return "crashed"
    if outcome in get_args(DivergenceKind):
        return "diverged"
    raise ValueError(f"outcome: {outcome!r} is not a flight outcome code")


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
    #: A crash's impact speed (m/s; the run's ``crashed`` event), else None.
    impact_speed_m_s: float | None = None

    @property
    def verdict(self) -> FlightVerdict:
        """The one verdict on the flight (module docs): ``holds``, ``drifts``, ``circles``,
        ``crashed`` or ``diverged``."""
        return verdict_of(self.outcome)

    @property
    def cause(self) -> str | None:
        """How a lost run was lost (the divergence kind: ``crashed``, ``tilt``, ...); None for a
        run that flew to the end."""
        return self.outcome if self.lost_at_s is not None else None

    @property
    def verdict_label(self) -> str:
        """The verdict with what decided it, for tables: ``"holds"``, ``"drifts (14.4 m off, 0.3 m
        in altitude, 0.05 m/s)"``, ``"crashed at 12.34 s (5.6 m/s)"``, ``"diverged (tilt) at
        1.52 s"``."""
        return verdict_text(self.verdict, cause=self.cause, lost_at_s=self.lost_at_s, impact_speed_m_s=self.impact_speed_m_s,
                            window=None if self.verdict in ("holds", "crashed", "diverged") else self.window_errors)

    @property
    def window_errors(self) -> tuple[float, float, float] | None:
        """(largest horizontal error, largest altitude error, largest speed) over the window, the
        numbers the verdict was judged on (None for a lost run)."""
        if self.window_horizontal_error_m is None or self.window_altitude_error_m is None or self.window_speed_m_s is None:
            return None
        return (self.window_horizontal_error_m, self.window_altitude_error_m, self.window_speed_m_s)

    @property
    def outcome_label(self) -> str:
        """The outcome code in words (``"holds position"``, ``"circling"``, ``"off station"``,
        ``"tilt"``, ...): the wording before issue 28; tables print :attr:`verdict_label`."""
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



def verdict_text(
    verdict: FlightVerdict,
    *,
    cause: str | None = None,
    lost_at_s: float | None = None,
    impact_speed_m_s: float | None = None,
    window: tuple[float, float, float] | None = None,
) -> str:
    """A verdict in words with what decided it: ``"crashed at 12.34 s (5.6 m/s)"``, ``"diverged
    (tilt) at 1.52 s"``, ``"drifts (window: 14.4 m off, 0.3 m in altitude, up to 0.05 m/s)"``."""
    if verdict == "crashed":
        speed = "" if impact_speed_m_s is None else f" ({impact_speed_m_s:.1f} m/s)"
        return f"crashed at {lost_at_s:.2f} s{speed}" if lost_at_s is not None else "crashed"
    if verdict == "diverged":
        what = f" ({OUTCOME_LABELS.get(cause, cause)})" if cause else ""
        return f"diverged{what} at {lost_at_s:.2f} s" if lost_at_s is not None else f"diverged{what}"
    if window is not None:
        return f"{verdict} (window: {window[0]:.2f} m off, {window[1]:.2f} m in altitude, up to {window[2]:.2f} m/s)"
    return verdict


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


def scoring_window(trajectory: Any, window_s: Any) -> tuple[float, FloatArray]:
    """``(window_s, t)`` of a flight about to be scored: the window (s) a real number > 0, the
    trajectory's times at least 2 samples (``ValueError`` naming the field otherwise); every
    scoring of a whole flight (:func:`flight_metrics`, a paper's own metrics) checks them here."""
    window = real("window_s", window_s)
    if not window > 0:
        raise ValueError(f"window_s: must be > 0, got {window}")
    t: FloatArray = trajectory.t
    if len(t) < 2:
        raise ValueError(f"trajectory: needs at least 2 samples to be scored, got {len(t)}")
    return window, t


def flight_metrics(
    trajectory: Any,
    scenario_: Any = None,
    *,
    window_s: float = WINDOW_S,
    reference: tuple[Any, Any] | None = None,
) -> FlightMetrics:
    """Scores ``trajectory`` against ``scenario_``'s setpoints (anything with ``setpoints``, a
    sequence of ``(time_s, (north, east, down))``: a :class:`~rotorfault.flight.scenarios.FlightScenario`),
    or against a moving ``reference``: ``(positions, velocities)``, each N x 3 (NED) at the
    trajectory's times, the speed then judged relative to the reference's velocity (a setpoint
    is a reference at rest: the same verdict). Fault times come from the trajectory's own faults
    (what it was flown with), not from the scenario."""
    window_s, t = scoring_window(trajectory, window_s)
    if (scenario_ is None) == (reference is None):
        raise ValueError("reference: give a scenario with setpoints or a reference (positions, velocities), not both or neither")
    if trajectory.diverged:
        event = trajectory.events[0]
        return FlightMetrics(event.kind, None, None, None, None, None, None, None, None, window_s, lost_at_s=float(event.time_s),
                             impact_speed_m_s=getattr(event, "impact_speed_m_s", None))
    if reference is None:
        setpoint = _setpoint_track(scenario_, t)
        reference_velocity = np.zeros_like(setpoint)
    else:
        setpoint, reference_velocity = (np.asarray(r, dtype=np.float64) for r in reference)
        if setpoint.shape != (len(t), 3) or reference_velocity.shape != (len(t), 3):
            raise ValueError(f"reference: expected two arrays of shape ({len(t)}, 3), got {setpoint.shape} and {reference_velocity.shape}")
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
    relative = trajectory.velocity - reference_velocity
    speed = scaled_norm(relative, axis=1)
    h_speed = np.hypot(relative[:, 0], relative[:, 1])
    window = (
        float(np.max(horizontal[last])),
        float(np.max(vertical[last])),
        float(np.max(speed[last])),
        float(np.mean(h_speed[last])),
    )
    held = window[0] <= HOLD_BAND_M[0] and window[1] <= HOLD_BAND_M[1] and window[2] <= HOLD_SPEED_M_S
    if held:
        outcome: FlightOutcome = "holds-position"
    elif window[3] > HOLD_SPEED_M_S and _turn_rad(relative[last], HOLD_SPEED_M_S / 4) >= CIRCLING_TURN_RAD:
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
    "VERDICTS",
    "VERDICT_MEANINGS",
    "count_verdicts",
    "verdict_count_text",
    "HOLD_SPEED_M_S",
    "OUTCOME_LABELS",
    "WINDOW_S",
    "FlightMetrics",
    "effective_fault_times",
    "flight_metrics",
    "outcome_text",
    "verdict_of",
    "verdict_text",
]
