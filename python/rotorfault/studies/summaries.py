"""Summaries: what one run's row says (:data:`SUMMARY_FIELDS`, computed by the core for every run
of a campaign; :func:`summarize` computes the same in NumPy from a full trajectory, the
independent check) and how rows add up (survival, the share of runs that hold, with its Wilson
interval). The verdict in a row is the flight's own (:mod:`rotorfault.flight.outcomes`), decided
by the core for every campaign run and by :func:`~rotorfault.flight.outcomes.flight_metrics` here:
the tests compare the two."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._util.convert import FloatArray
from .._util.deprecation import renamed_attribute
from ..flight import Trajectory
from ..flight.outcomes import FLYING, WINDOW_S, effective_fault_times, flight_metrics
from ..flight.scenarios import HOVER_M, FlightScenario

#: The summary columns (floats; NaN where a value does not apply, see :func:`summarize`).
SUMMARY_FIELDS: tuple[str, ...] = (
    "lost_at_s",
    "time_to_loss_s",
    "max_altitude_loss_m",
    "max_horizontal_error_m",
    "final_horizontal_error_m",
    "final_altitude_error_m",
    "window_horizontal_error_m",
    "window_altitude_error_m",
    "window_speed_m_s",
    "window_mean_horizontal_speed_m_s",
    "peak_tilt_rad",
    "steady_spin_rad_s",
    "steady_n3z",
    "peak_command",
    "saturated_s",
    "flown_s",
)


def summarize(trajectory: Trajectory, setpoint: Sequence[float] = HOVER_M, *, upper: FloatArray | None = None) -> dict[str, Any]:
    """The summary of a full trajectory, computed in NumPy from its rows: the independent check
    of the core's summaries (window and steady values from
    :func:`rotorfault.flight.outcomes.flight_metrics`). ``upper``: command bounds (default the
    trajectory's airframe is unknown here, so pass ``max_thrust_n``)."""
    scenario = FlightScenario("campaign", "", (), (), float(trajectory.t[-1]), ((0.0, tuple(float(v) for v in setpoint)),))  # type: ignore[arg-type]
    metrics = flight_metrics(trajectory, scenario, window_s=WINDOW_S)
    error = trajectory.position - np.asarray(setpoint)
    horizontal = np.hypot(error[:, 0], error[:, 1])
    command = trajectory.rotor_command
    finite = np.isfinite(command)
    saturated = np.zeros(len(command), dtype=bool)
    if upper is not None:
        saturated = np.any(finite & (command >= np.asarray(upper)), axis=1)
    fault_times = effective_fault_times(trajectory)
    lost = trajectory.events[0].time_s if trajectory.events else math.nan
    nan = math.nan

    def none(v: float | None) -> float:
        return nan if v is None else float(v)

    return {
        "outcome": metrics.outcome,
        "verdict": metrics.verdict,
        "cause": metrics.cause or "",
        "lost_at_s": lost,
        "time_to_loss_s": lost - fault_times[0] if trajectory.events and fault_times else nan,
        "max_altitude_loss_m": float(np.max(trajectory.position[:, 2] - trajectory.position[0, 2])),
        "max_horizontal_error_m": float(np.max(horizontal)),
        "final_horizontal_error_m": float(horizontal[-1]),
        "final_altitude_error_m": float(abs(error[-1, 2])),
        "window_horizontal_error_m": none(metrics.window_horizontal_error_m),
        "window_altitude_error_m": none(metrics.window_altitude_error_m),
        "window_speed_m_s": none(metrics.window_speed_m_s),
        "window_mean_horizontal_speed_m_s": none(metrics.window_mean_horizontal_speed_m_s),
        "peak_tilt_rad": float(np.max(np.arccos(np.clip(trajectory.primary_axis[:, 2], -1, 1)))),
        "steady_spin_rad_s": none(metrics.r_rad_s),
        "steady_n3z": none(metrics.n3z),
        "peak_command": float(np.max(command[finite])) if finite.any() else nan,
        "saturated_s": float(np.sum(np.diff(trajectory.t) * saturated[:-1])),
        "flown_s": float(trajectory.t[-1]),
    }


def wilson_interval(successes: int, trials: int, *, z: float = 1.959963984540054) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion (95 % by default)."""
    if trials <= 0:
        return (math.nan, math.nan)
    p = successes / trials
    denom = 1 + z * z / trials
    centre = (p + z * z / (2 * trials)) / denom
    half = z * math.sqrt(p * (1 - p) / trials + z * z / (4 * trials * trials)) / denom
    return (max(0.0, centre - half), min(1.0, centre + half))


@dataclass(frozen=True)
class Rate:
    """``held`` of ``runs`` in one group (``label``) hold their setpoint (verdict ``holds``), with
    the 95 % Wilson interval ``[low, high]`` of the rate: a campaign's survival."""

    label: str
    held: int
    runs: int
    low: float
    high: float

    @property
    def rate(self) -> float:
        return self.held / self.runs if self.runs else math.nan

    #: The name before issue 28, for one release.
    survived = renamed_attribute("survived", "held")


def rates(held: np.ndarray[Any, np.dtype[np.bool_]], groups: Sequence[tuple[str, np.ndarray[Any, Any]]]) -> list[Rate]:
    """The survival rate (the share of runs that hold) of each group (``(label, mask)``) with its
    Wilson interval."""
    out = []
    for label, mask in groups:
        n, s = int(mask.sum()), int((held & mask).sum())
        out.append(Rate(label, s, n, *wilson_interval(s, n)))
    return out


def numpy_columns(table: Any) -> dict[str, np.ndarray[Any, Any]]:
    """An Arrow table of campaign rows as :func:`run_chunk`-style NumPy columns (strings as
    ``str`` arrays, as in memory)."""
    out: dict[str, np.ndarray[Any, Any]] = {}
    for name in table.column_names:
        values = np.asarray(table.column(name).to_numpy(zero_copy_only=False))
        out[name] = values.astype(str) if values.dtype == object else values
    return out


__all__ = ["FLYING", "SUMMARY_FIELDS", "Rate", "numpy_columns", "rates", "summarize", "wilson_interval"]
